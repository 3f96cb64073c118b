"""The evaluation's workbook: a Scorecard sheet first (human headers, each row's unit in words, verdicts
coloured, unchecked thresholds marked "no" as the presets mark them), the coverage figures when given (a
Coverage sheet, one figure per printed page), then one sheet per table (proportions as percentages, as the
scorecard: evaluation_formats); every sheet A4 landscape, fitted to the page width, its header row repeated
on every printed page."""

from __future__ import annotations

import math
import os
from collections.abc import Mapping

import pandas as pd
from openpyxl import Workbook
from openpyxl.cell import WriteOnlyCell
from openpyxl.styles import Alignment, Font, PatternFill
from openpyxl.utils import get_column_letter
from openpyxl.worksheet._write_only import WriteOnlyWorksheet

from msdc.pipeline.correlate.results import CorrelationRun
from msdc.pipeline.evaluate.catalogue import CATALOGUE
from msdc.pipeline.evaluate.scorecard_schema import (
    SCORECARD_COLUMNS,
    validate_images,
    validate_scorecard,
    validate_tables,
)
from msdc.pipeline.report.cells import (
    BODY_FONT,
    BOLD,
    GAP_CHARS,
    MAX_WIDTH,
    ROW_HEIGHT_PT,
    aligned_right,
    clean_text,
    column_width,
    header_cells,
    header_height,
    indented,
    left_space,
    make_column,
    note_lines,
    note_text_cell,
    page_setup,
    set_widths,
    text_cell,
    wrapped_lines,
    write_table,
)
from msdc.pipeline.report.evaluation_formats import (
    PROPORTION_FORMAT,
    percent_decimals,
    percent_format,
    proportion_columns,
)
from msdc.pipeline.report.excel import _discard, _write_figures, sheet_name, write_parameters
from msdc.pipeline.report.headers import workbook_header
from msdc.pipeline.report.saving import save

SCORECARD_SHEET = "Scorecard"
COVERAGE_SHEET = "Coverage"
# the scorecard's printed columns: (schema column or 'unit', header)
SCORECARD_HEADERS: tuple[tuple[str, str], ...] = (
    ("sensor", "Sensor"), ("sector", "Sector"), ("requirement", "Requirement"), ("parameters", "Parameters"),
    ("value", "Value"),
    ("ci_low", "95 % interval, low"), ("ci_high", "95 % interval, high"), ("unit", "Unit"),
    ("threshold", "Threshold"), ("verdict", "Verdict"), ("n", "Sample size"), ("clause", "Clause"),
    ("checked", "Threshold checked against the standard"), ("notes", "Notes"))
# a requirement's unit (catalogue.RequirementType.unit) in words, and the number format of its values
UNIT_WORDS: dict[str, str] = {"fraction": "percent", "m": "metres", "s": "seconds", "deg": "degrees",
                              "ppm": "parts per million", "per scan": "per antenna scan",
                              "per aircraft": "per aircraft"}
UNIT_FORMATS: dict[str, str] = {"fraction": "0.00%", "m": "0.0", "s": "0.000", "deg": "0.0000",
                                "ppm": "0.0", "per scan": "0.000", "per aircraft": "0.000"}
VERDICT_FILLS: dict[str, PatternFill] = {  # Excel's own good / bad / neutral colours
    "pass": PatternFill("solid", fgColor="C6EFCE"), "fail": PatternFill("solid", fgColor="FFC7CE"),
    "inconclusive": PatternFill("solid", fgColor="FFEB9C")}
VERDICT_FONTS: dict[str, Font] = {
    "pass": Font(name=BODY_FONT, bold=True, color="006100"),
    "fail": Font(name=BODY_FONT, bold=True, color="9C0006"),
    "inconclusive": Font(name=BODY_FONT, bold=True, color="9C5700")}
UNCHECKED_NOTE = ("Threshold checked against the standard 'no': the preset marks the figure as not checked "
                  "against the standard's own text (checked = false); it is a configurable default, and a "
                  "pass against it is not compliance with the standard.")
# long text wraps inside these widths (characters)
_WRAP_COLUMNS = {"clause": 28, "notes": 44, "parameters": 22}
# a cell's alignment by (wraps, indented: cells.indented, a text column right of a numeric one)
_ALIGN = {(wrap, indent): Alignment(horizontal="left" if indent else None, indent=int(indent), vertical="top",
                                    wrap_text=wrap or None)
          for wrap in (False, True) for indent in (False, True)}


def unit_words(requirement: str) -> str:
    """A requirement's unit in words (a proportion is shown as a percentage)."""
    return UNIT_WORDS[CATALOGUE[requirement].unit]


def _cell(ws: WriteOnlyWorksheet, value, number_format: str | None = None, *, font: Font | None = None,
          fill: PatternFill | None = None, wrap: bool = False, indent: bool = False) -> WriteOnlyCell | None:
    """One scorecard cell: text never a formula, NaN an empty cell, numbers in the row's unit format; text
    of an ``indent``-ed column indented (cells.indented)."""
    if isinstance(value, str):
        cell = text_cell(ws, clean_text(value), font=font, fill=fill)
    elif value is None or (isinstance(value, float) and math.isnan(value)):
        cell = WriteOnlyCell(ws, None)
    else:
        cell = WriteOnlyCell(ws, value)
        if number_format:
            cell.number_format = number_format
        if font is not None:
            cell.font = font
    cell.alignment = _ALIGN[wrap, indent and isinstance(value, str)]
    return cell


def _number_format(row: dict, value) -> str:
    """A scorecard number's format: its row's unit's, a proportion's decimals by its size (percent_format)."""
    fmt = str(row["_format"])
    if fmt.endswith("%") and isinstance(value, float) and not math.isnan(value):
        return percent_format(value)
    return fmt


def _display(value, number_format: str | None) -> str:
    """The text a number shows under the scorecard's formats (for the column widths)."""
    if isinstance(value, str):
        return value
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return ""
    if number_format and number_format.endswith("%"):
        return f"{100 * value:.{percent_decimals(value)}f}%"
    decimals = len(number_format.split(".")[1]) if number_format and "." in number_format else 0
    return f"{value:,.{decimals}f}"


def _scorecard_rows(card: pd.DataFrame) -> list[dict[str, object]]:
    """The scorecard's printed values per row: the schema's, the unit in words, 'yes'/'no' for checked."""
    rows = []
    for rec in card.to_dict("records"):
        unit = CATALOGUE[rec["requirement"]].unit
        rows.append({**rec, "unit": UNIT_WORDS[unit], "checked": "yes" if rec["checked"] else "no",
                     "n": int(rec["n"]) if float(rec["n"]).is_integer() else rec["n"],
                     "_format": UNIT_FORMATS[unit]})
    return rows


def _widths(rows: list[dict[str, object]], headers: tuple[tuple[str, str], ...] = SCORECARD_HEADERS
            ) -> list[float]:
    """Each column's width: cells.column_width of its header and the text of its values, the wrapped
    columns capped (their indent on top)."""
    indents = _indents(rows, headers)
    widths = []
    for (key, header), indent in zip(headers, indents, strict=True):
        numeric = key in ("value", "ci_low", "ci_high", "threshold")
        texts = [_display(r[key], r["_format"] if numeric else "#,##0.0" if key == "n" else None)
                 for r in rows]
        width = column_width(header, texts, None, indent=indent)
        cap = _WRAP_COLUMNS.get(key, MAX_WIDTH) + left_space(indent) - GAP_CHARS
        widths.append(min(cap, width))
    return widths


def _indents(rows: list[dict[str, object]], headers: tuple[tuple[str, str], ...]) -> list[bool]:
    """The indented columns (cells.indented) of the scorecard's ``rows`` under ``headers``."""
    return indented([aligned_right([r[key] for r in rows]) for key, _ in headers])


def _write_scorecard(wb: Workbook, card: pd.DataFrame, title: str = SCORECARD_SHEET,
                     leading: tuple[str, ...] = ()) -> None:
    """The Scorecard sheet (or another table of scorecard rows, its ``leading`` columns first, e.g. each
    row's window): one row per sensor, sector and requirement, the values in the row's unit, the verdict
    cell coloured."""
    ws = wb.create_sheet(title)
    keys = (*((c, workbook_header(c)) for c in leading), *SCORECARD_HEADERS)
    rows = _scorecard_rows(card)
    widths = _widths(rows, keys)
    headers = [h for _, h in keys]
    set_widths(ws, widths)
    ws.freeze_panes = f"{get_column_letter(len(leading) + 4)}2"
    page_setup(ws)  # one page wide, header row repeated on every page
    right = [aligned_right([r[k] for r in rows]) for k, _ in keys]
    ws.row_dimensions[1].height = header_height(headers, widths, right)
    indents = _indents(rows, keys)
    room = [w - left_space(indent) - GAP_CHARS for w, indent in zip(widths, indents, strict=True)]
    for i, row in enumerate(rows, start=2):
        lines = max([1, *(wrapped_lines(str(row[k]), room[j])
                          for j, (k, _) in enumerate(keys) if k in _WRAP_COLUMNS)])
        if lines > 1:
            ws.row_dimensions[i].height = lines * ROW_HEIGHT_PT
    ws.append(header_cells(ws, headers, right=right))
    for row in rows:
        cells = []
        for (key, _), indent in zip(keys, indents, strict=True):
            value = row[key]
            if key in ("value", "ci_low", "ci_high"):
                cells.append(_cell(ws, value, _number_format(row, value)))
            elif key == "threshold":
                italic = None if row["checked"] == "yes" else Font(name=BODY_FONT, italic=True)
                cells.append(_cell(ws, value, _number_format(row, value), font=italic))
            elif key == "verdict":
                cells.append(_cell(ws, value, font=VERDICT_FONTS[value], fill=VERDICT_FILLS[value],
                                   indent=indent))
            elif key == "n":  # a count with thousands separated; an exposure (a rate's) to one decimal
                cells.append(_cell(ws, value, "#,##0" if isinstance(value, int) else "#,##0.0"))
            elif key == "checked":
                cells.append(_cell(ws, value, font=BOLD if value == "no" else None, indent=indent))
            else:
                cells.append(_cell(ws, value, wrap=key in _WRAP_COLUMNS, indent=indent))
        ws.append(cells)
    notes = ["Values, intervals and thresholds are in the row's unit; a proportion is shown as a "
             "percentage. Verdict: pass when the whole 95 % interval meets the threshold, fail when the "
             "whole interval misses it, inconclusive otherwise (or below the standard's minimum sample)."]
    if any(r["checked"] == "no" for r in rows):
        notes.append(UNCHECKED_NOTE)
    ws.append([])
    for note in notes:
        _, lines = note_lines(note, widths, [True] * len(widths), len(rows))
        for line in lines:
            ws.append([note_text_cell(ws, line)])


def _write_table(wb: Workbook, title: str, frame: pd.DataFrame) -> None:
    """One table on its own sheet, under the workbooks' common rules (headers with units, formats)."""
    ws = wb.create_sheet(title)
    if not isinstance(frame.index, pd.RangeIndex) or any(n is not None for n in frame.index.names):
        frame = frame.reset_index()
    columns = [make_column(ws, str(h), frame.iloc[:, j]) for j, h in enumerate(frame.columns)]
    proportions = proportion_columns(frame)
    for column in columns:
        if column.header in proportions and not column.text:  # a percentage, as on the scorecard
            column.number_format = PROPORTION_FORMAT
            column.styled = WriteOnlyCell(ws, 0.0)
            column.styled.number_format = PROPORTION_FORMAT
    if not columns:
        page_setup(ws)
        ws.append([text_cell(ws, "No columns.", font=BOLD)])
        return
    note = frame.attrs.get("note") if isinstance(frame.attrs.get("note"), str) else ""
    write_table(ws, columns, note=note or ("No rows." if frame.empty else ""))


def write_evaluation_xlsx(scorecard: pd.DataFrame, path: str | os.PathLike[str],
                          tables: Mapping[str, pd.DataFrame] | None = None,
                          images: Mapping[str, bytes] | None = None, run: Mapping | None = None) -> None:
    """The evaluation workbook at ``path``: the scorecard (validated: scorecard_schema), the Coverage sheet
    of ``images`` (title -> PNG bytes, e.g. coverage_figures.coverage_images) when given, the tables in
    their order, one sheet each, and the Parameters sheet of ``run`` (its inputs and parameters)."""
    card = validate_scorecard(scorecard)
    extra = validate_tables(tables)
    figures = validate_images(images)
    wb = Workbook(write_only=True)
    taken = {SCORECARD_SHEET.lower()}
    try:
        _write_scorecard(wb, card)
        if figures:
            _write_figures(wb, sheet_name(COVERAGE_SHEET, taken), figures)
        for name, frame in extra.items():
            if set(SCORECARD_COLUMNS) <= set(frame.columns):  # scorecard rows (per window): as the scorecard
                leading = tuple(str(c) for c in frame.columns if c not in SCORECARD_COLUMNS)
                _write_scorecard(wb, frame, sheet_name(name, taken), leading)
            else:
                _write_table(wb, sheet_name(name, taken), frame)
        if run is not None:
            write_parameters(wb, CorrelationRun(inputs=list(run.get("inputs", [])),
                                                parameters=dict(run.get("parameters", {}))),
                             windows=False, title=sheet_name("Parameters", taken))
    except BaseException:
        _discard(wb)
        raise
    save(wb, path)
