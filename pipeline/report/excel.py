"""Excel workbook of a CorrelationRun: Summary, Map, Lag charts, Slot charts, Correlation, Slots, extra
sheets and Parameters.

Written with openpyxl in write-only (streaming) mode, lxml underneath, so long recordings stay within
memory; cells, columns and page setup come from ``pipeline.report.cells``, the chart sheets from
``pipeline.report.charts``. Cell rules: times are real Excel date-times in UTC (clock times when the
date is unknown, never seconds of day), numbers are numbers (NaN -> empty cell) with the format of their unit
(``pipeline.report.formats``), all text is stored as text (never as a formula), headers are bold and
frozen, widths fit the content. Every sheet prints landscape, fitted to the page width, with its header
rows repeated; charts sit on their own sheets, on a grid of whole pages.
"""

from __future__ import annotations

import contextlib
import datetime as dt
import io
import os
import re
import textwrap
from collections.abc import Callable, Collection, Iterator, Mapping
from pathlib import Path
from typing import Any

import pandas as pd
from openpyxl import Workbook
from openpyxl.cell import WriteOnlyCell
from openpyxl.drawing.image import Image
from openpyxl.styles import PatternFill
from openpyxl.worksheet._write_only import WriteOnlyWorksheet
from openpyxl.worksheet.pagebreak import Break

from msdc.pipeline.correlate.correlation import PEARSON_MIN_OVERLAP, pearson_max_lag
from msdc.pipeline.correlate.results import (
    MATCHED_KEYS,
    RADAR_KEYS,
    WINDOW_QUALITY_KEYS,
    CorrelationRun,
    WindowResult,
)
from msdc.pipeline.report.cells import (
    BOLD,
    CLOCK_FORMAT,
    INDENTED,
    NOTE_FONT,
    ROW_HEIGHT_PT,
    SUMMARY_DATETIME_FORMAT,
    TITLE_FONT,
    Column,
    aligned_right,
    cell_for,
    clean_text,
    column_width,
    excel_value,
    fixed_rows,
    header_cells,
    header_height,
    indented,
    is_number,
    iso_time,
    make_column,
    note_text_cell,
    number_format_for,
    page_setup,
    set_widths,
    text_cell,
    write_table,
)
from msdc.pipeline.report.charts import (
    CORRELATION_HEADERS,
    LAG_CHART_HEADERS,
    SLOT_CHART_HEADERS,
    SLOTS_HEADERS,
    charted_windows,
    write_lag_charts,
    write_slot_charts,
)
from msdc.pipeline.report.headers import workbook_header
from msdc.pipeline.report.saving import get_ready, save
from msdc.pipeline.report.summary import (
    LEAD_TITLE,
    RADARS_TEXT,
    RADARS_TITLE,
    THESIS_LIMITS,
    THESIS_TEXT,
    THESIS_TITLE,
    aircraft_name,
    has_quality,
    lead_text,
    map_nouns,
    sensor_pair,
    window_notes,
)
from msdc.pipeline.report.tables import (
    AUTO_MAX_ROWS,
    CHART_MAX_POINTS,
    COLUMN_NOTES,
    IDENT_COLUMNS,
    correlation_table,
    lag_frame,
    parquet_path,
    parquet_tables,
    slot_table,
    table_length,
    write_table_parquet,
)

# Summary: stacked blocks that each fit a landscape page; every window block starts with the aircraft (call
# sign, else address), window and sensor pair ("048:25/201 vs 021:0/1": window numbers restart for every
# pair of an aircraft). The lead block comes first (what each window shows, then with --quality the radar's
# errors in it), then the thesis's
LEAD_BLOCK_KEYS = ["aircraft", "window", "sensors", "start", "end", *MATCHED_KEYS]
SUMMARY_BLOCKS: list[tuple[str, list[str]]] = [
    (f"{THESIS_LIMITS['counts'][0]} ({THESIS_LIMITS['counts'][1]})",
     ["aircraft", "window", "sensors", "start", "end", "address", "slots",
      "radar_before", "radar_after", "adsb_before", "adsb_after", "radar_duplicates", "adsb_duplicates",
      "adsb_jumps", "radar_filled_slots", "adsb_filled_slots"]),
    (f"{THESIS_LIMITS['coefficients'][0]} ({THESIS_LIMITS['coefficients'][1]}; Pearson where at least "
     f"{PEARSON_MIN_OVERLAP} slots overlap, its peak searched over |lag| <= N/2)",
     ["aircraft", "window", "sensors", "start", "end", "ncc0_lat", "ncc0_lon", "ncc_peak_lag_lat",
      "ncc_peak_lag_lon", "pearson0_lat", "pearson0_lon", "pearson_peak_lag_lat", "pearson_peak_lag_lon",
      "pearson_peak_at_limit_lat", "pearson_peak_at_limit_lon", "pearson_lag_unidentified_lat",
      "pearson_lag_unidentified_lon"]),
    (f"{THESIS_LIMITS['separation'][0]} (m; {THESIS_LIMITS['separation'][1]}); "
     f"{workbook_header('sep_rms_all_m')}: filled slots included",
     ["aircraft", "window", "sensors", "start", "end", "sep_mean_m", "sep_median_m", "sep_rms_m", "sep_p95_m",
      "sep_max_m", "sep_slots", "sep_rms_all_m"]),
]
SKIPPED_HEADERS = ["callsign", "address", "sensors", "start", "end", "reason"]
SUMMARY_TITLE_ROWS = "1:1"
_CORE_SHEETS = ("Summary", "Map", "Lag charts", "Slot charts", "Correlation", "Slots", "Parameters")
_BLOCK_FILLS = ["EDEDED", "E2EFDA", "DDEBF7", "FCE4D6"]
_LEAD_FILL = "FFF2CC"
IMAGE_MAX_W_PX, IMAGE_MAX_H_PX = 1000, 620  # one figure per printed page


def _summary_values(run: CorrelationRun) -> list[dict[str, Any]]:
    """Each window's summary as Excel values (excel_value), worked out once for the Summary's passes."""
    return [{**{key: excel_value(value) for key, value in w.summary.items()},
             "aircraft": aircraft_name(w.summary, "") or None, "sensors": sensor_pair(w.summary) or None}
            for w in run.windows]


def _summary_value(values: dict[str, Any], key: str) -> Any:
    """A Summary cell value from a window's _summary_values; start/end fall back to the clock time (seconds
    of day) when undated."""
    value = values.get(key)
    if value is None and key in ("start", "end"):
        tod = values.get(f"{key}_tod")
        return ("tod", tod) if is_number(tod) else None
    return value


def summary_header(key: str) -> str:
    """A Summary header: the workbooks' header of the JSON key (headers.workbook_header), wrapped at its
    spaces."""
    return workbook_header(key)


def _summary_time_cell(ws: WriteOnlyWorksheet, value: Any) -> Any:
    """A Summary start/end: UTC date-time to the second, or ("tod", seconds) as a clock time."""
    if isinstance(value, tuple):
        return cell_for(ws, value[1], CLOCK_FORMAT)
    if isinstance(value, dt.datetime):
        cell = WriteOnlyCell(ws, value)
        cell.number_format = SUMMARY_DATETIME_FORMAT
        return cell
    return cell_for(ws, value, None)


def _wrapped(ws: WriteOnlyWorksheet, text: str, chars: int, font=BOLD) -> int:
    """``text`` on as many rows as it needs at ``chars`` characters a row (a row running far past the
    tables would shrink the printed page: it is fitted to the widest row); returns the rows written."""
    lines = textwrap.wrap(text, width=chars) or [text]
    for line in lines:
        ws.append([text_cell(ws, line, font=font)])
    return len(lines)


def _summary_block(ws: WriteOnlyWorksheet, summaries: list[dict[str, Any]], title: str, keys: list[str],
                   fill: str, row: int, chars: int, widths: list[float],
                   empty: str = "no correlated window") -> int:
    """One Summary block (title cut into rows of ``chars`` characters, header, one row per entry of
    ``summaries``: _summary_values, or the radars' Excel values, blank) from sheet row ``row``; returns the
    next free row. ``widths``: the sheet's column widths, which the header row's height is made for."""
    row += _wrapped(ws, title, chars) - 1
    headers = [summary_header(k) for k in keys]
    rows = [[_summary_value(values, k) for k in keys] for values in summaries]
    formats = [number_format_for(k, [r[j] for r in rows]) for j, k in enumerate(keys)]
    right = [aligned_right([r[j] for r in rows], formats[j]) for j in range(len(keys))]
    ws.row_dimensions[row + 1].height = header_height(headers, widths, right)
    ws.append(header_cells(ws, headers, PatternFill("solid", fgColor=fill), right))
    for values in rows:
        cells = []
        for value, fmt, indent in zip(values, formats, indented(right), strict=True):
            if isinstance(value, tuple | dt.datetime):
                cells.append(_summary_time_cell(ws, value))
            elif isinstance(value, str):  # indented right of a number: never glued to it
                cell = cell_for(ws, value, None)
                if indent:
                    cell.alignment = INDENTED
                cells.append(cell)
            else:
                cells.append(cell_for(ws, value, fmt))
        ws.append(cells)
    if not rows:
        ws.append([note_text_cell(ws, empty)])
    ws.append([])
    return row + 2 + max(len(rows), 1) + 1


def _lead_keys(run: CorrelationRun) -> list[str]:
    """The lead block's columns: with --quality the radar's errors in the window too."""
    return LEAD_BLOCK_KEYS + (WINDOW_QUALITY_KEYS if has_quality(run) else [])


def _text_rows(ws: WriteOnlyWorksheet, title: str, lines: list[tuple[dict[str, Any], str]],
               none: str) -> int:
    """A titled list of one text per window (its call sign, number, sensors and start first): the verdicts,
    the notes. Returns the rows written."""
    ws.append([text_cell(ws, title, font=BOLD)])
    for values, text in lines:
        cell = note_text_cell(ws, text)
        cell.alignment = INDENTED
        pair = cell_for(ws, values.get("sensors"), None)
        if pair is not None:
            pair.alignment = INDENTED
        ws.append([cell_for(ws, values.get("aircraft"), None), cell_for(ws, values.get("window"), None), pair,
                   _summary_time_cell(ws, _summary_value(values, "start")), cell])
    if not lines:
        ws.append([note_text_cell(ws, none)])
    ws.append([])
    return 1 + max(len(lines), 1) + 1


def _write_summary(wb: Workbook, run: CorrelationRun) -> None:
    ws = wb.create_sheet("Summary")
    summaries = _summary_values(run)
    radars = [{k: excel_value(r.get(k)) for k in RADAR_KEYS} for r in run.radars]
    radar_keys = [k for k in RADAR_KEYS if k != "note"]  # (each radar's note on rows of its own)
    skipped = [[excel_value(s.callsign), excel_value(s.address), sensor_pair(vars(s)) or None,
                excel_value(s.start_tod), excel_value(s.end_tod), excel_value(s.reason)] for s in run.skipped]
    blocks = [(f"{LEAD_TITLE}: {lead_text(run)}", _lead_keys(run)), *SUMMARY_BLOCKS]
    widths: dict[int, float] = {}

    def widen(headers: list[str], rows: list[list[Any]], formats: list[str | None]) -> None:
        columns = [[r[j] for r in rows] for j in range(len(headers))]
        indents = indented([aligned_right(v, fmt) for v, fmt in zip(columns, formats, strict=True)])
        for j, header in enumerate(headers):
            width = column_width(header, columns[j], formats[j], indent=indents[j])
            widths[j] = max(widths.get(j, 0.0), width)

    for _title, keys in blocks:  # widths first: write-only sheets take them before any row
        rows = [[values.get(k) for k in keys] for values in summaries]
        formats = [SUMMARY_DATETIME_FORMAT if k in ("start", "end") else
                   number_format_for(k, [r[j] for r in rows]) for j, k in enumerate(keys)]
        widen([summary_header(k) for k in keys], rows, formats)
    if radars:
        rows = [[r.get(k) for k in radar_keys] for r in radars]
        widen([summary_header(k) for k in radar_keys], rows, [number_format_for(k, [r[j] for r in rows])
                                                               for j, k in enumerate(radar_keys)])
    widen([summary_header(k) for k in SKIPPED_HEADERS[:-1]], [r[:-1] for r in skipped],
          [None, None, None, CLOCK_FORMAT, CLOCK_FORMAT])  # (the reason overflows)
    set_widths(ws, [widths[j] for j in sorted(widths)])
    col_widths = [widths[j] for j in sorted(widths)]
    ws.freeze_panes = "C2"
    page_setup(ws, SUMMARY_TITLE_ROWS)
    date = run.parameters.get("date")
    ws.append([text_cell(ws, f"Correlation summary: {len(run.windows)} window(s), {len(run.skipped)} skipped"
                         + (f", {date} UTC" if date else ", date unknown (clock times)"), font=TITLE_FONT)])
    chars = max(60, int(0.9 * sum(widths.values())))  # a title's row: about the tables' width
    row = 2
    row = _summary_block(ws, summaries, blocks[0][0], blocks[0][1], _LEAD_FILL, row, chars,
                         col_widths)
    row += _text_rows(ws, f"Verdicts ({len(summaries)})", [(values, str(values.get("verdict") or "-"))
                                                           for values in summaries], "none")
    if radars:
        row = _summary_block(ws, radars, f"{RADARS_TITLE} ({RADARS_TEXT})", radar_keys, _LEAD_FILL, row,
                             chars, col_widths)
        for radar in run.radars:
            if radar.get("note"):
                row += _wrapped(ws, f"{radar.get('radar')}: {radar['note']}", chars, NOTE_FONT)
        ws.append([])
        row += 1
    ws.append([text_cell(ws, f"{THESIS_TITLE} ({THESIS_TEXT})", font=TITLE_FONT)])
    row += 1
    for (title, keys), fill in zip(SUMMARY_BLOCKS, _BLOCK_FILLS, strict=False):
        row = _summary_block(ws, summaries, title, keys, fill, row, chars, col_widths)

    # one row per note, so that no row runs far past the tables (the page is fitted to its widest row)
    notes = [(values, n) for w, values in zip(run.windows, summaries, strict=True)
             for n in window_notes(w.summary)]
    row += _text_rows(ws, f"Notes on the thesis's measures ({len(notes)})", notes,
                      "none: in every window the RMS separation is within 3 x the median and no Pearson peak "
                      "needs a warning")
    ws.append([text_cell(ws, f"Skipped windows ({len(skipped)})", font=BOLD)])
    if skipped:
        right = [aligned_right([r[j] for r in skipped]) for j in range(len(SKIPPED_HEADERS))]
        ws.append(header_cells(ws, [summary_header(k) for k in SKIPPED_HEADERS],
                               PatternFill("solid", fgColor=_BLOCK_FILLS[3]), right))
        for row in skipped:
            cells = [*(cell_for(ws, v, None) for v in row[:3]),
                     *(cell_for(ws, v, CLOCK_FORMAT if is_number(v) else None) for v in row[3:5]),
                     cell_for(ws, row[5], None)]
            for cell, value, indent in zip(cells, row, indented(right), strict=True):
                if indent and isinstance(value, str):
                    cell.alignment = INDENTED
            ws.append(cells)
    else:
        ws.append([note_text_cell(ws, "none")])


def _scaled_image(png: str | os.PathLike[str] | bytes) -> Image:
    """The PNG (a file, or its bytes) as an openpyxl Image, scaled down to fit one printed landscape page."""
    image = Image(io.BytesIO(png) if isinstance(png, bytes) else str(png))
    if image.width and image.height:
        scale = min(1.0, IMAGE_MAX_W_PX / image.width, IMAGE_MAX_H_PX / image.height)
        image.width, image.height = int(image.width * scale), int(image.height * scale)
    return image


def _write_map(wb: Workbook, pairs: str | None) -> WriteOnlyWorksheet:
    """The Map sheet's title in the words of ``pairs``; its figure is added just before saving (it may still
    be being drawn)."""
    ws = wb.create_sheet("Map")
    page_setup(ws, None, fit_height=1)
    fixed_rows(ws)
    tested, reference = map_nouns(pairs)
    title = f"Slotted tracks: {tested} (red) and {reference} (yellow), every correlated window"
    ws.append([text_cell(ws, title, font=TITLE_FONT)])
    return ws



def _sheet_columns(ws: WriteOnlyWorksheet, frame: pd.DataFrame, headers: list[str]) -> list[Column]:
    """Columns of a Slots or Correlation sheet from its table (pipeline.report.tables): the sheet's
    headers in order, undated slot times as clock times under ``time_utc``."""
    columns = []
    for h in headers:
        if h == "time_utc" and "time_utc" not in frame:
            seconds = frame["time_of_day"].to_numpy(dtype=float)
            column = Column("time_utc", [None if v != v else v / 86400.0 for v in seconds.tolist()],
                            CLOCK_FORMAT, WriteOnlyCell(ws, 0.0))
            column.styled.number_format = CLOCK_FORMAT
            columns.append(column)
        else:
            columns.append(make_column(ws, h, frame[h].reset_index(drop=True)))
    return columns


def _write_correlation(wb: Workbook, run: CorrelationRun, title: str = "Correlation", note: str = "",
                       headers: list[str] | None = None) -> None:
    ws = wb.create_sheet(title)
    frame = correlation_table(run)
    headers = headers or CORRELATION_HEADERS + [c for c in frame.columns if c not in CORRELATION_HEADERS
                                                and c not in IDENT_COLUMNS]
    write_table(ws, _sheet_columns(ws, frame, headers), freeze="F2", note=note or
                "All lags d = -(N-1)..N-1 of every window; charts of |d| <= N/2: Lag charts sheet.")


def _write_slots(wb: Workbook, run: CorrelationRun, title: str = "Slots", note: str = "",
                 headers: list[str] | None = None) -> None:
    ws = wb.create_sheet(title)
    frame = slot_table(run)
    dated = "time_utc" in frame
    headers = headers or SLOTS_HEADERS + [c for c in frame.columns if c not in SLOTS_HEADERS
                                          and c not in IDENT_COLUMNS and c != "time_of_day"]
    write_table(ws, _sheet_columns(ws, frame, headers), freeze="F2", note=note or
                "time_utc: slot start, UTC" + ("" if dated else " clock time (date unknown)")
                + "; charts on the Slot charts sheet.")


def _write_parquet_note(wb: Workbook, title: str, rows: int, schema, path: Path, mode: str,
                        chart_sheet: str) -> WriteOnlyWorksheet:
    """The sheet of a table written to Parquet: the file, its rows and columns, where the charts' data is.
    With ``schema`` None the column rows are left for _parquet_columns (the table is written elsewhere)."""
    ws = wb.create_sheet(title)
    set_widths(ws, [20.0, 12.0, 60.0])
    page_setup(ws)
    why = (f"it has more than {AUTO_MAX_ROWS:,} rows (--tables auto; --tables xlsx keeps it in the workbook)"
           if mode == "auto" else "--tables parquet")
    ws.append([text_cell(ws, f"{title}: {rows:,} rows in {path.name}, beside this workbook",
                         font=TITLE_FONT)])
    ws.append([note_text_cell(ws, f"Written as Parquet because {why}. The charts use an excerpt of it: "
                                  f"{chart_sheet} sheet.")])
    ws.append([])
    ws.append(header_cells(ws, ["Column", "Type", "Meaning"]))  # of the Parquet file: its own names
    if schema is not None:
        _parquet_columns(ws, schema)
    return ws


def _parquet_columns(ws: WriteOnlyWorksheet, schema) -> None:
    """A Parquet table's columns, one row each: name, type, meaning."""
    for field in schema:
        ws.append([text_cell(ws, field.name), text_cell(ws, str(field.type)),
                   text_cell(ws, COLUMN_NOTES.get(field.name, ""))])


def _excerpt(run: CorrelationRun, shown: list[int], rows) -> CorrelationRun:
    """The run with only the charted windows' rows kept (``rows(window)`` gives the kept window)."""
    windows = [rows(w) if i in shown else WindowResult(w.summary, w.slots.iloc[:0], w.lags.iloc[:0])
               for i, w in enumerate(run.windows)]
    return CorrelationRun(windows=windows, parameters=run.parameters)


def _step(n: int) -> int:
    return max(1, -(-n // CHART_MAX_POINTS))


def _slot_excerpt(window: WindowResult) -> WindowResult:
    return WindowResult(window.summary, window.slots.iloc[::_step(len(window.slots))], window.lags.iloc[:0])


def _lag_excerpt(window: WindowResult) -> WindowResult:
    lags = lag_frame(window)
    half = pearson_max_lag((len(lags) + 1) // 2)
    inside = lags[(pd.to_numeric(lags["lag"], errors="coerce").abs() <= half).to_numpy(bool)]
    return WindowResult(window.summary, window.slots, inside.iloc[::_step(len(inside))])


def _write_tables(wb: Workbook, run: CorrelationRun, parquet: dict[str, tuple[int, object, Path]],
                  mode: str) -> dict[str, WriteOnlyWorksheet]:
    """Lag and slot charts, then the Correlation and Slots sheets: the tables themselves, or for a table
    written to Parquet a sheet naming the file and a sheet of the charts' excerpt (every k-th row of the
    charted windows, at most CHART_MAX_POINTS per chart). Returns the Parquet sheets still waiting for
    their column rows (schema None: the table is being written elsewhere)."""
    waiting = {}
    lag_frames = slot_frames = None
    lag_data, slot_data = "Correlation", "Slots"
    if "correlation" in parquet:
        lag_run = _excerpt(run, charted_windows(run, "lags"), _lag_excerpt)
        lag_frames, lag_data = [lag_frame(w) for w in lag_run.windows], "Lag chart data"
    if "slots" in parquet:
        slot_run = _excerpt(run, charted_windows(run, "slots"), _slot_excerpt)
        slot_frames, slot_data = [w.slots for w in slot_run.windows], "Slot chart data"
    write_lag_charts(wb, run, lag_data, lag_frames, None if lag_frames is None else LAG_CHART_HEADERS)
    write_slot_charts(wb, run, slot_data, slot_frames, None if slot_frames is None else SLOT_CHART_HEADERS)
    excerpt_note = ("Excerpt for the charts: every k-th row (at most {n} a chart) of the charted windows; "
                    "the whole table: {file}.")
    if "correlation" in parquet:
        rows, schema, path = parquet["correlation"]
        waiting["correlation"] = _write_parquet_note(wb, "Correlation", rows, schema, path, mode, lag_data)
        _write_correlation(wb, lag_run, lag_data, excerpt_note.format(n=CHART_MAX_POINTS, file=path.name),
                           LAG_CHART_HEADERS)
    else:
        _write_correlation(wb, run)
    if "slots" in parquet:
        rows, schema, path = parquet["slots"]
        waiting["slots"] = _write_parquet_note(wb, "Slots", rows, schema, path, mode, slot_data)
        _write_slots(wb, slot_run, slot_data, excerpt_note.format(n=CHART_MAX_POINTS, file=path.name),
                     SLOT_CHART_HEADERS)
    else:
        _write_slots(wb, run)
    return {name: ws for name, ws in waiting.items() if parquet[name][1] is None}


def _flatten(prefix: str, value: Any) -> Iterator[tuple[str, Any]]:
    if isinstance(value, Mapping) and value:
        for key, item in value.items():
            yield from _flatten(f"{prefix}.{key}" if prefix else str(key), item)
    else:
        yield prefix, value


def parameter_rows(run: CorrelationRun, windows: bool = True) -> list[list[Any]]:
    """Key/value rows of the Parameters sheet: section, key, value (ISO 8601 text, as the JSON has it, shown
    as an Excel date); ``windows``: with the correlation report's window counts."""
    return [[(iso_time(v) if isinstance(v, str) else None) or excel_value(v) for v in row]
            for row in run_rows(run, windows)]


def run_rows(run: CorrelationRun, windows: bool = True) -> list[list[Any]]:
    """The run's record as section, key, value rows (values as the JSON has them): each input, the
    parameters (a mapping's items under its name; a list of texts, such as the notes and warnings, a row
    per text under its key, not one cell of JSON), the filters; ``windows``: the window counts."""
    rows: list[list[Any]] = []
    for i, item in enumerate(run.inputs, start=1):
        order = ["path", "format", "bytes", "sha256"]
        for key in [*(k for k in order if k in item), *(k for k in item if k not in order)]:
            rows.append([f"input {i}", key, item[key]])
    for key, value in run.parameters.items():
        if isinstance(value, Mapping):
            rows += [[str(key), k, v] for k, v in _flatten("", value)]
        elif isinstance(value, list | tuple) and value and all(isinstance(v, str) for v in value):
            rows += [["parameters", str(key), v] for v in value]
        else:
            rows.append(["parameters", str(key), value])
    rows += [["filters", str(k), v] for k, v in run.filters.items()]
    if windows:
        rows += [["report", "windows", len(run.windows)], ["report", "skipped windows", len(run.skipped)]]
    return rows


def write_parameters(wb: Workbook, run: CorrelationRun, windows: bool = True, title: str = "Parameters"
                     ) -> None:
    """The Parameters sheet: parameter_rows under the headers section, key, value."""
    ws = wb.create_sheet(title)
    rows = parameter_rows(run, windows)
    headers = ["section", "key", "value"]
    columns = [make_column(ws, h, [r[j] for r in rows], general=True) for j, h in enumerate(headers)]
    write_table(ws, columns)


def sheet_name(name: str, taken: set[str]) -> str:
    """A valid, unused Excel sheet name (31 chars, no []:*?/\\, not "History"); adds it to ``taken``."""
    base = re.sub(r"[\[\]:*?/\\]", "_", clean_text(str(name))).strip().strip("'")[:31] or "Sheet"
    if base.lower() == "history":
        base = "History_"
    candidate, n = base, 2
    while candidate.lower() in taken:
        suffix = f" ({n})"
        candidate, n = base[: 31 - len(suffix)] + suffix, n + 1
    taken.add(candidate.lower())
    return candidate


def _write_frame(wb: Workbook, title: str, frame: pd.DataFrame | pd.Series) -> None:
    ws = wb.create_sheet(title)
    if isinstance(frame, pd.Series):
        frame = frame.to_frame()
    if not isinstance(frame.index, pd.RangeIndex) or any(n is not None for n in frame.index.names):
        frame = frame.reset_index()
    headers = [" / ".join(map(str, c)) if isinstance(c, tuple) else str(c) for c in frame.columns]
    columns = [make_column(ws, h, frame.iloc[:, j]) for j, h in enumerate(headers)]
    note = frame.attrs.get("note") if isinstance(frame.attrs.get("note"), str) else ""
    write_table(ws, columns, note=note)


def _write_figures(wb: Workbook, title: str, images: Mapping[str, str | os.PathLike[str] | bytes],
                   note: str = "") -> None:
    """A sheet of PNG figures, one per printed page, each under its caption; ``note`` (what the figures
    leave out) on the first row."""
    ws = wb.create_sheet(title)
    page_setup(ws, None)
    fixed_rows(ws)
    row = 1
    if note:
        ws.append([text_cell(ws, clean_text(note[:1].upper() + note[1:]), font=BOLD)])
        row += 1
    rows_per_page = int((IMAGE_MAX_H_PX + 40) / (ROW_HEIGHT_PT * 4 / 3)) + 2
    for caption, png in images.items():
        image = _scaled_image(png)
        ws.append([text_cell(ws, clean_text(caption), font=TITLE_FONT)])
        ws.add_image(image, f"A{row + 1}")
        for _ in range(rows_per_page - 1):
            ws.append([])
        row += rows_per_page
        ws.row_breaks.append(Break(id=row - 1))


def write_parquet_tables(run: CorrelationRun, path_xlsx: str | os.PathLike[str], tables: str = "auto",
                         names: Collection[str] | None = None) -> dict[str, tuple[int, object, Path]]:
    """The run's tables that go to Parquet under ``tables`` (pipeline.report.tables), or those ``names``,
    written beside the workbook one table at a time, in batches of whole windows (write_table_parquet):
    name -> (rows, schema, path)."""
    parquet = {}
    for name in parquet_tables(run, tables) if names is None else names:  # built and written one at a time
        path = parquet_path(path_xlsx, name)
        parquet[name] = (*write_table_parquet(run, name, path), path)
    return parquet


def write_report(run: CorrelationRun, path_xlsx: str | os.PathLike[str], *,
                 figure_png: str | os.PathLike[str] | None = None,
                 images: dict[str, str | os.PathLike[str]] | None = None, images_note: str = "",
                 tables: str = "auto",
                 figure_ready: Callable[[], object] | None = None,
                 tables_written: Callable[[], dict[str, tuple[int, object, Path]]] | None = None,
                 elsewhere: Collection[str] | None = None) -> list[Path]:
    """Write the run's workbook to ``path_xlsx``; embed ``figure_png`` on a Map sheet when given and
    further ``images`` (caption -> PNG) on a Figures sheet, under ``images_note`` (what they leave out).
    The slot and lag tables go to Parquet beside
    it as ``tables`` says (pipeline.report.tables); returns the Parquet files written. ``figure_ready``
    is called before ``figure_png`` is first read (the figure may be drawn meanwhile elsewhere). With
    ``tables_written`` the Parquet tables named in ``elsewhere`` (all of them when None) are being written
    elsewhere (write_parquet_tables in another process), the others here first: it is called before the
    workbook is saved and returns what write_parquet_tables returned for them."""
    names = parquet_tables(run, tables)
    away = [] if tables_written is None else [n for n in names if elsewhere is None or n in elsewhere]
    parquet = write_parquet_tables(run, path_xlsx, names=[n for n in names if n not in away])
    for name in away:  # the sheets name the file and its rows now, its columns once written
        parquet[name] = (table_length(run, name), None, parquet_path(path_xlsx, name))
    parquet = {name: parquet[name] for name in names}  # in table order, wherever written
    wb = Workbook(write_only=True)
    taken = {name.lower() for name in _CORE_SHEETS}
    _write_summary(wb, run)
    try:
        map_sheet = _write_map(wb, run.parameters.get("pairs")) if figure_png is not None else None
        waiting = _write_tables(wb, run, parquet, tables)
        for name, frame in run.extra_sheets.items():
            _write_frame(wb, sheet_name(name, taken), frame)
        if images:
            _write_figures(wb, sheet_name("Figures", taken), images, images_note)
        write_parameters(wb, run)
        get_ready(wb)  # while the tables and the figure may still be written elsewhere
        if away:
            parquet.update(tables_written())
            for name, ws in waiting.items():
                _parquet_columns(ws, parquet[name][1])
        if map_sheet is not None:
            if figure_ready is not None:
                figure_ready()
            map_sheet.add_image(_scaled_image(figure_png), "A2")
    except BaseException:
        _discard(wb)
        raise
    save(wb, path_xlsx)
    return [path for _, _, path in parquet.values()]


def _discard(wb: Workbook) -> None:
    """End the streamed sheets of a workbook that will not be saved, so their writers close cleanly
    (otherwise they complain on stderr when collected)."""
    for ws in wb.worksheets:
        with contextlib.suppress(Exception):
            ws.close()


def write_tables(tables: dict[str, pd.DataFrame], path_xlsx: str | os.PathLike[str], *,
                 images: dict[str, str | os.PathLike[str]] | None = None,
                 parameters: dict | None = None) -> None:
    """A workbook of plain tables (one sheet each, same formatting rules), figures and parameters."""
    wb = Workbook(write_only=True)
    taken: set[str] = set()
    for name, frame in tables.items():
        _write_frame(wb, sheet_name(name, taken), frame)
    if images:
        _write_figures(wb, sheet_name("Figures", taken), images)
    if parameters is not None:
        write_parameters(wb, CorrelationRun(parameters=parameters), windows=False)  # not a correlation
    save(wb, path_xlsx)

