"""The evaluation's HTML report: one self-contained file that works offline (Bokeh's scripts written inside
it, no request to any server): the scorecard as a table (verdicts coloured, unchecked thresholds marked),
the coverage figures (PNGs inside the file as data URIs), the tables (numbers as evaluation_formats shows
them), and an interactive map of the reports and the reference per aircraft (legend click hides an
aircraft or a source; hover names the point; pan and wheel zoom)."""

from __future__ import annotations

import base64
import html
import json
import math
import os
import re
from collections.abc import Mapping
from pathlib import Path

import numpy as np
import pandas as pd

from msdc.pipeline.evaluate.catalogue import CATALOGUE
from msdc.pipeline.evaluate.scorecard_schema import (
    validate_images,
    validate_map,
    validate_scorecard,
    validate_tables,
)
from msdc.pipeline.evaluate.verdicts import VERDICTS, sensor_verdicts
from msdc.pipeline.report.evaluation_formats import number_text, proportion_columns, sample_text
from msdc.pipeline.report.evaluation_xlsx import SCORECARD_HEADERS, UNCHECKED_NOTE, UNIT_WORDS
from msdc.pipeline.report.files import named
from msdc.pipeline.report.headers import workbook_header

# one colour per aircraft, repeating past twenty: ten strong ones, then their light tints
PALETTE = ("#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b", "#e377c2", "#17becf",
           "#7f7f7f", "#bcbd22", "#aec7e8", "#ff9896", "#98df8a", "#c5b0d5", "#ffbb78", "#c49c94", "#f7b6d2",
           "#9edae5", "#c7c7c7", "#dbdb8d")
LEGEND_COLUMNS = 8  # the map's legend below it: one entry per aircraft, this many to a row
LEGEND_ROW_PX = 24  # the height a row of the legend takes
LONG_TABLE_ROWS = 60  # a table longer than this is folded under its heading (a click shows it)
_STYLE = """
body { font-family: sans-serif; margin: 1.5em; color: #222; }
table { border-collapse: collapse; margin: 0.5em 0 1.5em; font-size: 0.9em; }
th, td { border: 1px solid #bbb; padding: 0.25em 0.5em; vertical-align: top; }
th { background: #d9e1f2; text-align: left; }
td.num { text-align: right; font-variant-numeric: tabular-nums; white-space: nowrap; }
span.kv { white-space: nowrap; }
td.pass { background: #c6efce; color: #006100; font-weight: bold; }
td.fail { background: #ffc7ce; color: #9c0006; font-weight: bold; }
td.inconclusive { background: #ffeb9c; color: #9c5700; font-weight: bold; }
td.unchecked { font-weight: bold; }
tbody.result tr.has-notes td { border-bottom: none; }
tr.notes td { border-top: none; padding: 0 0.5em 0.4em 2em; color: #444; font-size: 0.95em; }
tr.notes td::before { content: "Notes: "; font-weight: bold; color: #595959; }
nav#contents { margin: -0.5em 0 1em; line-height: 1.6; }
details > summary { cursor: pointer; color: #1f4e79; margin: 0.3em 0; }
p.note { font-style: italic; color: #595959; max-width: 60em; }
figure.coverage { margin: 0.5em 0 1.5em; }
figure.coverage img { max-width: 100%; height: auto; border: 1px solid #ddd; }
figure.coverage figcaption { font-weight: bold; margin-bottom: 0.3em; }
@media (max-width: 1250px) {  /* a laptop's 1,024-1,250 px: the scorecard's 13 columns without scrolling */
  body { margin: 1em; } table { font-size: 0.8em; } th, td { padding: 0.2em 0.3em; }
}
"""


def _scorecard_table(card: pd.DataFrame) -> str:
    """The scorecard as an HTML table, a body per sensor, sector and requirement: its figures in a row, its
    notes (the longest text) in a row below across the whole width, so that the table fits a screen and
    the notes read as lines, not a word a line in a last column pushed out of view."""
    columns = [(key, title) for key, title in SCORECARD_HEADERS if key != "notes"]
    head = "".join(f"<th>{html.escape(h)}</th>" for _, h in columns)
    bodies = []
    for i, rec in enumerate(card.to_dict("records")):
        unit = CATALOGUE[rec["requirement"]].unit
        cells = {
            "unit": html.escape(UNIT_WORDS[unit]),
            "checked": "yes" if rec["checked"] else "no",
            "n": sample_text(rec["n"]),
            "parameters": ", ".join(f'<span class="kv">{html.escape(kv)}</span>'
                                    for kv in str(rec.get("parameters") or "").split(", ") if kv),
            "clause": " ".join(f'<span class="kv">{html.escape(word)}</span>'  # not "Table 3-" / "1"
                               for word in str(rec["clause"]).split()),
        }
        out = []
        for key, _ in columns:
            if key in ("value", "ci_low", "ci_high", "threshold"):
                out.append(f'<td class="num">{number_text(float(rec[key]), key, set(), unit)}</td>')
            elif key == "n":
                out.append(f'<td class="num">{cells["n"]}</td>')
            elif key == "verdict":
                out.append(f'<td class="{rec[key]}">{html.escape(rec[key])}</td>')
            elif key == "checked":
                cls = "" if rec["checked"] else ' class="unchecked"'
                out.append(f"<td{cls}>{cells['checked']}</td>")
            else:
                out.append(f"<td>{cells[key] if key in cells else html.escape(str(rec[key]))}</td>")
        notes = str(rec.get("notes") or "")
        if notes:
            bodies.append(f'<tbody class="result" id="row{i}"><tr class="has-notes">{"".join(out)}</tr>'
                          f'<tr class="notes"><td colspan="{len(columns)}">{html.escape(notes)}</td></tr>'
                          "</tbody>")
        else:
            bodies.append(f'<tbody class="result" id="row{i}"><tr>{"".join(out)}</tr></tbody>')
    return f'<table id="scorecard"><thead><tr>{head}</tr></thead>{"".join(bodies)}</table>'


def _verdicts_table(card: pd.DataFrame) -> str:
    """Per sensor, its verdicts counted (the inconclusive ones without a value apart: nothing measured) and
    its failed requirements with their sectors, each linked to its scorecard row: what a reader acts on
    first (evaluate.verdicts)."""
    rows = []
    for s in sensor_verdicts(card):
        failed = "; ".join(
            f"{html.escape(requirement)}: "
            + ", ".join(f'<a href="#row{i}">{html.escape(sector)}</a>' for sector, i in where)
            for requirement, where in s.failed.items())
        rows.append(f"<tr><td>{html.escape(s.sensor)}</td>"
                    + "".join(f'<td class="num">{s.counts[v]:,}</td>' for v in VERDICTS)
                    + f'<td class="num">{s.not_measured:,}</td><td>{failed or "none"}</td></tr>')
    head = "".join(f"<th>{h}</th>" for h in ("Sensor", "Pass", "Fail", "Inconclusive",
                                              "Of which not measured (no value)", "Failed requirements"))
    return f'<table id="verdicts"><thead><tr>{head}</tr></thead><tbody>{"".join(rows)}</tbody></table>'


def _frame_table(name: str, frame: pd.DataFrame) -> str:
    """A table as HTML: headers as the workbook prints them, numbers as evaluation_formats shows them
    (a requirement's values in its unit when the table has a ``requirement`` column), NaN as an empty
    cell."""
    if not isinstance(frame.index, pd.RangeIndex):
        frame = frame.reset_index()
    head = "".join(f"<th>{html.escape(workbook_header(str(c)))}</th>" for c in frame.columns)
    proportions = proportion_columns(frame)
    columns = [str(c) for c in frame.columns]
    body = []
    for row in frame.itertuples(index=False):
        ident = row[columns.index("requirement")] if "requirement" in columns else None
        row_unit = CATALOGUE[ident].unit if isinstance(ident, str) and ident in CATALOGUE else None
        cells = []
        for column, value in zip(columns, row, strict=True):
            if isinstance(value, bool | np.bool_):
                cells.append(f"<td>{'yes' if value else 'no'}</td>")
            elif isinstance(value, float | np.floating):
                text = number_text(float(value), column, proportions, row_unit)
                cells.append(f'<td class="num">{text}</td>')
            elif isinstance(value, int | np.integer):
                cells.append(f'<td class="num">{int(value)}</td>')
            else:
                cells.append(f"<td>{html.escape(str(value))}</td>")
        body.append("<tr>" + "".join(cells) + "</tr>")
    table = (f"<table class=\"evaluation-table\"><thead><tr>{head}</tr></thead>"
             f"<tbody>{''.join(body)}</tbody></table>")
    if len(body) > LONG_TABLE_ROWS:  # folded: a bin table of hundreds of rows is pages of scrolling
        table = f"<details><summary>{len(body):,} rows: show them</summary>{table}</details>"
    return f"<h2>{html.escape(name)}</h2>{table}"


def _figures(images: Mapping[str, bytes]) -> str:
    """The coverage figures, each a PNG inside the page as a data URI under its title."""
    parts = []
    for title, png in images.items():
        uri = "data:image/png;base64," + base64.b64encode(png).decode("ascii")
        text = html.escape(title)
        parts.append(f'<figure class="coverage"><figcaption>{text}</figcaption>'
                     f'<img src="{uri}" alt="{text}"></figure>')
    return "".join(parts)


def _source(frame: pd.DataFrame):
    """A Bokeh data source of the map's columns, given as arrays (a DataFrame would be copied with an index
    column, and pandas warns of Bokeh's reset_index(inplace=True))."""
    from bokeh.models import ColumnDataSource

    return ColumnDataSource(data={c: frame[c].to_numpy() for c in frame.columns})


def _map(points: pd.DataFrame):
    """The Bokeh map: per aircraft its reference as a line and its reports as dots, in one colour; the
    legend, below the map in columns (one entry per aircraft, whatever their number), hides an aircraft on
    click. Axes in degrees, scaled so that a degree of longitude and of latitude show their true ground
    lengths at the mean latitude."""
    from bokeh.models import HoverTool, Legend, LegendItem
    from bokeh.plotting import figure

    mean_lat = float(points["latitude"].mean())
    fig = figure(title="Reports and reference per aircraft", x_axis_label="Longitude (deg)",
                 y_axis_label="Latitude (deg)", width=900, height=650, match_aspect=True,
                 aspect_scale=max(0.05, math.cos(math.radians(mean_lat))),
                 tools="pan,wheel_zoom,box_zoom,reset,save", active_scroll="wheel_zoom",
                 output_backend="canvas")
    items = []
    for i, (aircraft, group) in enumerate(points.groupby("aircraft", sort=True)):
        colour = PALETTE[i % len(PALETTE)]
        ref = group[group["source"] == "reference"]
        rep = group[group["source"] == "report"]
        drawn = []
        if not ref.empty:
            drawn.append(fig.line("longitude", "latitude", source=_source(ref), color=colour, line_width=2))
        if not rep.empty:
            drawn.append(fig.scatter("longitude", "latitude", source=_source(rep), color=colour, size=6,
                                     fill_alpha=0.6))
        items.append(LegendItem(label=str(aircraft), renderers=drawn))
    fig.add_tools(HoverTool(tooltips=[
        ("aircraft", "@aircraft"), ("source", "@source"), ("sensor", "@sensor"),
        ("latitude", "@latitude{0.00000}"), ("longitude", "@longitude{0.00000}")]))
    legend = Legend(items=items, ncols=LEGEND_COLUMNS, click_policy="hide",
                    title="aircraft (line: reference, dots: reports; click to hide)")
    fig.add_layout(legend, "below")
    fig.height += LEGEND_ROW_PX * (math.ceil(len(items) / LEGEND_COLUMNS) + 1)  # the map keeps its height
    return fig


def evaluation_html(scorecard: pd.DataFrame, tables: Mapping[str, pd.DataFrame] | None = None,
                    map_points: pd.DataFrame | None = None, title: str = "msdc evaluation",
                    images: Mapping[str, bytes] | None = None, run: Mapping | None = None) -> str:
    """The report's HTML text (inputs validated by scorecard_schema); ``images`` (title -> PNG bytes, e.g.
    coverage_figures.coverage_images) make its Coverage section, ``run`` (inputs and parameters) its last,
    Run."""
    card = validate_scorecard(scorecard)
    frames = validate_tables(tables)
    points = validate_map(map_points)
    figures = validate_images(images)
    parts = [f"<h1>{html.escape(title)}</h1>", "<h2>Verdicts</h2>", _verdicts_table(card),
             "<h2>Scorecard</h2>", _scorecard_table(card),
             "<p class=\"note\">Values, intervals and thresholds are in the row's unit. Verdict: pass when "
             "the "
             "whole 95 % interval meets the threshold, fail when the whole interval misses it, inconclusive "
             "otherwise (or below the standard's minimum sample).</p>"]
    if not card["checked"].all():
        parts.append(f'<p class="note">{html.escape(UNCHECKED_NOTE)}</p>')
    if figures:
        parts += ['<h2>Coverage</h2><div id="coverage">', _figures(figures), "</div>"]
    head = ""
    if points is not None and not points.empty:
        try:
            from bokeh.embed import components
            from bokeh.resources import Resources
        except ImportError:
            raise ValueError("the HTML report's map needs Bokeh, which is not installed: pip install bokeh "
                             "(or msdc[html])") from None

        script, div = components(_map(points))
        head = Resources(mode="inline", components=["bokeh"]).render_js() + script
        parts += ["<h2>Map</h2>", f'<div id="map">{div}</div>']
    else:
        parts.append('<h2>Map</h2><p class="note">No map points were given.</p>')
    parts += [_frame_table(name, frame) for name, frame in frames.items()]
    if run is not None:
        parts.append(_run_table(run))
    return ("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
            f"<title>{html.escape(title)}</title><style>{_STYLE}</style>{head}</head>"
            f"<body>{_with_contents(parts[0], ''.join(parts[1:]))}</body></html>\n")


def _with_contents(heading: str, body: str) -> str:
    """The page's heading, a line of links to its sections (each h2 given an id), then the sections."""
    titles: list[str] = []

    def anchored(match: re.Match) -> str:
        titles.append(match.group(1))
        return f'<h2 id="section{len(titles)}">{match.group(1)}</h2>'

    body = re.sub(r"<h2>(.*?)</h2>", anchored, body)
    links = " · ".join(f'<a href="#section{k}">{t}</a>' for k, t in enumerate(titles, start=1))
    return f'{heading}<nav id="contents">{links}</nav>{body}'


def _run_table(run: Mapping) -> str:
    """The Run section: what was read (paths, SHA-256) and how, a row per item as the JSON has it."""
    from msdc.pipeline.correlate.results import CorrelationRun
    from msdc.pipeline.report.excel import run_rows

    rows = run_rows(CorrelationRun(inputs=list(run.get("inputs", [])),
                                   parameters=dict(run.get("parameters", {}))), windows=False)
    def text(v) -> str:
        return "" if v is None else json.dumps(v) if isinstance(v, Mapping | list | tuple) else str(v)

    body = "".join("<tr>" + "".join(f"<td>{html.escape(text(v))}</td>" for v in row) + "</tr>"
                   for row in rows)
    return ('<h2>Run</h2><table id="run"><tr><th>Section</th><th>Key</th><th>Value</th></tr>'
            f"{body}</table>")


def write_evaluation_html(scorecard: pd.DataFrame, path: str | os.PathLike[str],
                          tables: Mapping[str, pd.DataFrame] | None = None,
                          map_points: pd.DataFrame | None = None, title: str = "msdc evaluation",
                          images: Mapping[str, bytes] | None = None, run: Mapping | None = None) -> Path:
    """evaluation_html written to ``path`` as UTF-8 (an error names it); returns ``path``."""
    text = evaluation_html(scorecard, tables, map_points, title, images, run)
    path = Path(path)
    with named(path):
        path.write_text(text, encoding="utf-8", errors="backslashreplace")  # a lone surrogate: its escape
    return path
