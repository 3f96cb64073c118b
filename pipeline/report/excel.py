"""Excel workbook of a CorrelationRun: Summary, Map, Lag charts, Slot charts, Correlation, Slots, extra
sheets and Parameters.

Written with openpyxl in write-only (streaming) mode, lxml underneath, so long recordings stay within
memory. Cell rules: times are real Excel date-times in UTC (clock times when the date is unknown, never
seconds of day), numbers are numbers (NaN -> empty cell) with the format of their unit
(``pipeline.report.formats``), all text is stored as text (never as a formula), headers are bold and
frozen, widths fit the content. Every sheet prints landscape, fitted to the page width, with its header
rows repeated; charts sit on their own sheets, on a grid of whole pages.
"""

from __future__ import annotations

import datetime as dt
import json
import math
import os
import re
from collections.abc import Iterable, Iterator, Mapping
from dataclasses import dataclass
from itertools import islice
from numbers import Integral, Real
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
from openpyxl import Workbook
from openpyxl.cell import WriteOnlyCell
from openpyxl.cell.cell import ILLEGAL_CHARACTERS_RE
from openpyxl.chart import Reference, ScatterChart, Series
from openpyxl.chart.marker import Marker
from openpyxl.chart.shapes import GraphicalProperties
from openpyxl.drawing.image import Image
from openpyxl.drawing.line import LineProperties
from openpyxl.drawing.spreadsheet_drawing import AbsoluteAnchor
from openpyxl.drawing.xdr import XDRPoint2D, XDRPositiveSize2D
from openpyxl.styles import Alignment, Border, Font, PatternFill, Side
from openpyxl.utils import get_column_letter
from openpyxl.utils.datetime import to_excel
from openpyxl.utils.units import cm_to_EMU
from openpyxl.worksheet._write_only import WriteOnlyWorksheet
from openpyxl.worksheet.pagebreak import Break
from openpyxl.xml import LXML

from pipeline.correlate.correlation import pearson_max_lag
from pipeline.correlate.results import LAG_COLUMNS, SLOT_COLUMNS, SUMMARY_KEYS, CorrelationRun, WindowResult
from pipeline.report.formats import UNITS, column_unit, excel_format
from pipeline.report.summary import (
    SKIPPED_KEYS,
    is_missing,
    json_value,
    slot_seconds,
    utc_naive,
    window_note,
    write_atomically,
)
from pipeline.report.textguard import FORMULA_START

if not LXML:  # pragma: no cover - lxml is a dependency; OPENPYXL_LXML=False would halve the write speed
    import warnings

    warnings.warn("openpyxl is not using lxml (is OPENPYXL_LXML set?): workbooks will be written slowly",
                  stacklevel=1)

DATETIME_FORMAT = "yyyy-mm-dd hh:mm:ss.000"
SUMMARY_DATETIME_FORMAT = "yyyy-mm-dd hh:mm:ss"
DATE_FORMAT = "yyyy-mm-dd"
TIME_FORMAT = "hh:mm:ss.000"
CLOCK_FORMAT = UNITS["tod"].excel  # seconds of day shown as a clock time ([hh] runs past 24 h)
MAX_CORRELATION_CHARTS = 20
MAX_SLOT_CHART_WINDOWS = 10
EXCEL_MAX_ROWS = 1_048_576
EXCEL_MAX_TEXT = 32_767
MIN_WIDTH, MAX_WIDTH = 6.0, 66.0
_WIDTH_SAMPLE_ROWS = 5000
_ISO_DATE = re.compile(r"\d{4}-\d{2}-\d{2}\Z")
_ISO_DATETIME = re.compile(r"\d{4}-\d{2}-\d{2}[T ]\d{2}:\d{2}(:\d{2}(\.\d{1,9})?)?(Z|[+-]\d{2}:?\d{2})?\Z")
_DATETIME_HEADERS = {"time_utc", "start", "end", "timestamp", "run_time"}

# Summary: stacked blocks that each fit a landscape page; every block starts with call sign and window
SUMMARY_BLOCKS: list[tuple[str, list[str]]] = [
    ("Windows and measurements (thesis table 6.1: before = reports in the window, after = slots)",
     ["callsign", "window", "start", "end", "address", "slots", "radar_before", "radar_after", "adsb_before",
      "adsb_after", "radar_duplicates", "adsb_duplicates", "adsb_jumps", "radar_filled_slots",
      "adsb_filled_slots"]),
    ("Coefficients (thesis table 6.2: r(0) by NCC; Pearson peak searched over |lag| <= N/2)",
     ["callsign", "window", "start", "end", "ncc0_lat", "ncc0_lon", "ncc_peak_lag_lat", "ncc_peak_lag_lon",
      "pearson0_lat", "pearson0_lon", "pearson_peak_lag_lat", "pearson_peak_lag_lon"]),
    ("Separation between slotted radar and ADS-B positions (m)",
     ["callsign", "window", "start", "end", "sep_mean_m", "sep_median_m", "sep_rms_m", "sep_p95_m",
      "sep_max_m"]),
]
SUMMARY_TITLE_ROWS = "1:1"
CORRELATION_HEADERS = ["window", "callsign", "address", "lag", "lag_s", *LAG_COLUMNS[1:]]
SLOTS_HEADERS = ["window", "callsign", "address", "slot", "time_utc", *SLOT_COLUMNS[3:]]
_CORE_SHEETS = ("Summary", "Map", "Lag charts", "Slot charts", "Correlation", "Slots", "Parameters")

_BOLD = Font(bold=True)
_TITLE_FONT = Font(bold=True, size=12)
_NOTE_FONT = Font(italic=True, color="595959")
_HEADER_FILL = PatternFill("solid", fgColor="D9E1F2")
_BLOCK_FILLS = ["EDEDED", "E2EFDA", "DDEBF7", "FCE4D6"]
_HEADER_BORDER = Border(bottom=Side(style="thin", color="808080"))
_HEADER_ALIGN = Alignment(vertical="center", wrap_text=True)

RADAR_RGB, ADSB_RGB, ADSB_EDGE_RGB = "D62728", "E6B800", "3D3000"
LAT_RGB, LON_RGB = "1F77B4", "2CA02C"

CHART_HEADING_ROWS = 2  # rows 1-2 of a chart sheet: its heading, repeated on every printed page
# Page grid (A4 landscape, margins below, rows of 15 pt): a chart sheet holds 2 x 2 charts per page
PAPER_A4 = 9
MARGIN_IN = 0.4
ROW_HEIGHT_PT = 15.0
CHART_COL_WIDTH = 9.5  # characters; 7 columns per chart slot
CHART_SLOT_COLS, CHART_SLOT_ROWS, CHARTS_PER_ROW, CHART_ROWS_PER_PAGE = 7, 15, 2, 2
CHART_W_CM, CHART_H_CM = 12.6, 7.4
CHART_SLOT_W_CM = 13.3  # two slots (26.6 cm) inside the 27.7 cm between A4 landscape margins
IMAGE_MAX_W_PX, IMAGE_MAX_H_PX = 1000, 620  # one figure per printed page


# ----------------------------------------------------------------------------------------------- values

def excel_value(value: Any) -> Any:
    """A value openpyxl stores natively: None for missing, naive-UTC datetime, int, float, bool or text."""
    if is_missing(value):
        return None
    if isinstance(value, bool | np.bool_):
        return bool(value)
    if isinstance(value, pd.Timestamp | dt.datetime | np.datetime64):
        return utc_naive(value)
    if isinstance(value, dt.date | dt.time):
        return value
    if isinstance(value, pd.Timedelta | dt.timedelta | np.timedelta64):  # before Integral: timedelta64 is one
        return pd.Timedelta(value).total_seconds()
    if isinstance(value, Integral):
        return int(value)
    if isinstance(value, Real):
        number = float(value)
        return number if math.isfinite(number) else ("inf" if number > 0 else "-inf")
    if isinstance(value, str):
        return iso_time(value) or clean_text(value)
    if isinstance(value, Path):
        return clean_text(str(value))
    if isinstance(value, Mapping | list | tuple | set | frozenset | np.ndarray):
        return clean_text(json.dumps(json_value(value), ensure_ascii=False))
    return clean_text(str(value))


def iso_time(text: str) -> dt.datetime | dt.date | None:
    """A naive-UTC datetime (or a date) when ``text`` is an ISO 8601 date-time (or date), else None."""
    if not (10 <= len(text) <= 40 and text[:1].isdigit()):
        return None
    try:
        if _ISO_DATE.match(text):
            return dt.date.fromisoformat(text)
        if _ISO_DATETIME.match(text):
            return utc_naive(pd.Timestamp(text))
    except ValueError:
        pass
    return None


def clean_text(text: str) -> str:
    """Text Excel can hold: XML-illegal control characters replaced, cut at Excel's cell limit."""
    return ILLEGAL_CHARACTERS_RE.sub("\ufffd", text)[:EXCEL_MAX_TEXT]


def text_cell(ws: WriteOnlyWorksheet, text: str, *, font: Font | None = None,
              fill: PatternFill | None = None) -> WriteOnlyCell:
    """A string cell that can never become a formula (type "s"; quote prefix on formula-like text)."""
    cell = WriteOnlyCell(ws, text)
    cell.data_type = "s"
    if text.startswith(FORMULA_START):
        cell.quotePrefix = True
    if font is not None:
        cell.font = font
    if fill is not None:
        cell.fill = fill
    return cell


def _is_number(value: Any) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool)


def _cell(ws: WriteOnlyWorksheet, value: Any, number_format: str | None) -> Any:
    """The cell (or plain value) for an excel_value() result under a column number format."""
    if value is None or isinstance(value, bool):
        return value
    if isinstance(value, str):
        return text_cell(ws, value)
    if isinstance(value, dt.datetime):
        number_format = DATETIME_FORMAT
    elif isinstance(value, dt.date):
        number_format = DATE_FORMAT
    elif isinstance(value, dt.time):
        number_format = TIME_FORMAT
    elif number_format is None or (isinstance(value, int) and number_format == "0"):
        return value
    elif number_format == CLOCK_FORMAT:
        value = value / 86400.0
    cell = WriteOnlyCell(ws, value)
    cell.number_format = number_format
    return cell


# ------------------------------------------------------------------------------------ column writing

@dataclass
class Column:
    """One output column: its header, cell values (already Excel-ready) and, for numbers that need it, a
    template cell carrying the column's number format, reused for every value (styling by column)."""

    header: str
    values: list[Any]
    number_format: str | None
    styled: WriteOnlyCell | None = None
    text: bool = False  # values may hold text, which must be checked for formula-like starts


def _datetime_serials(series: pd.Series) -> list[Any]:
    """Excel serial days (UTC wall clock) of a datetime column, None where missing."""
    stamps = series.dt.tz_convert("UTC").dt.tz_localize(None) if series.dt.tz is not None else series
    days = (stamps - pd.Timestamp("1899-12-30")) / pd.Timedelta(days=1)
    return [None if v != v else v for v in days.round(11).to_numpy(dtype=float, na_value=np.nan).tolist()]


def column_values(series: pd.Series) -> list[Any]:
    """excel_value() of every entry, with fast paths for plain float, integer and bool columns."""
    dtype = series.dtype
    if dtype.kind == "f" and isinstance(dtype, np.dtype):
        values = series.to_numpy()
        if np.isinf(values).any():
            return [excel_value(v) for v in values.tolist()]
        return [None if v != v else v for v in values.tolist()]  # v != v: NaN
    if dtype.kind in "iub" and isinstance(dtype, np.dtype):
        return series.to_numpy().tolist()
    return [excel_value(v) for v in series.tolist()]


def _fallback_format(values: Iterable[Any]) -> str | None:
    numbers = [v for v in values if _is_number(v)]
    if not numbers or all(float(v).is_integer() for v in numbers):
        return None
    return "0.000000" if max(abs(v) for v in numbers) < 1 else "0.000"


def number_format_for(name: str, values: Iterable[Any]) -> str | None:
    """Number format of a column: from the unit table by name, else from sample values (None = General)."""
    return excel_format(name) or _fallback_format(values)


def make_column(ws: WriteOnlyWorksheet, header: str, data: pd.Series | list[Any], *,
                general: bool = False) -> Column:
    """A Column from a pandas Series (fast paths for numbers and datetimes) or a list of raw values.

    Seconds-of-day columns become clock times; datetimes become Excel date-times; numbers take the format
    of their unit. ``general`` keeps numbers in General format (columns mixing unrelated values)."""
    series = data if isinstance(data, pd.Series) else pd.Series(list(data), dtype=object)
    unit = None if general else column_unit(header)
    if isinstance(series.dtype, pd.DatetimeTZDtype) or series.dtype.kind == "M":
        column = Column(header, _datetime_serials(series), DATETIME_FORMAT)
    else:
        values = column_values(series)
        if unit == "tod" and all(v is None or _is_number(v) for v in values):
            values = [None if v is None else v / 86400.0 for v in values]
            column = Column(header, values, CLOCK_FORMAT)
        else:
            kinds = {type(v) for v in values[:_WIDTH_SAMPLE_ROWS] if v is not None}
            mixed = bool(kinds - {int, float, bool})
            fmt = None if general else number_format_for(header, values[:_WIDTH_SAMPLE_ROWS])
            if mixed:  # text, dates, mixed types: one cell at a time
                return Column(header, values, fmt, text=True)
            if fmt == "0" and kinds <= {int, bool}:
                fmt = None  # integers read the same in General
            column = Column(header, values, fmt)
    if column.number_format is not None:
        column.styled = WriteOnlyCell(ws, 0.0)
        column.styled.number_format = column.number_format
    return column


def _rows(ws: WriteOnlyWorksheet, columns: list[Column], start: int = 0,
          stop: int | None = None) -> Iterator[list[Any]]:
    """Rows of cells for ws.append: plain values where General will do, the column's styled cell (value
    swapped in) for formatted numbers, text cells for text."""
    styled = [(j, c.styled) for j, c in enumerate(columns) if c.styled is not None and not c.text]
    texts = [(j, c.number_format) for j, c in enumerate(columns) if c.text]
    for row in islice(zip(*(c.values for c in columns), strict=True), start, stop):
        out = list(row)
        for j, cell in styled:
            value = out[j]
            if value is not None and value.__class__ is not bool:
                cell.value = value
                out[j] = cell
        for j, fmt in texts:
            value = out[j]
            if value is not None and not (value.__class__ is str and not value.startswith(FORMULA_START)):
                out[j] = _cell(ws, value, fmt)
        yield out


def _display_len(value: Any, number_format: str | None) -> int:
    if value is None:
        return len(SUMMARY_DATETIME_FORMAT) if number_format == SUMMARY_DATETIME_FORMAT else 0
    if isinstance(value, str):
        return max(len(line) for line in value.split("\n"))
    if isinstance(value, bool):
        return 5
    if number_format == SUMMARY_DATETIME_FORMAT:
        return len(SUMMARY_DATETIME_FORMAT)
    if isinstance(value, dt.datetime) or number_format == DATETIME_FORMAT:
        return len(DATETIME_FORMAT)
    if isinstance(value, dt.date | dt.time) or number_format == CLOCK_FORMAT:
        return 12
    if number_format and "." in number_format:
        return len(f"{value:,.{number_format.count('0', number_format.index('.'))}f}")
    if number_format and number_format.startswith("#,"):
        return len(f"{value:,.0f}")
    if isinstance(value, float) and not number_format:
        return min(len(repr(value)), 12)
    return len(f"{value:.0f}") if isinstance(value, float) else len(str(value))


def _width(header: str, values: Iterable[Any], number_format: str | None) -> float:
    longest = max([max(len(word) for word in header.split(" ")), *(_display_len(v, number_format)
                                                                   for v in values)])
    if header in _DATETIME_HEADERS:
        longest = max(longest, _display_len(None, number_format) or len(DATETIME_FORMAT))
    return min(MAX_WIDTH, max(MIN_WIDTH, longest + 2.0))


def _set_widths(ws: WriteOnlyWorksheet, widths: list[float]) -> None:
    for i, width in enumerate(widths, start=1):
        ws.column_dimensions[get_column_letter(i)].width = round(width, 1)


def _header_cells(ws: WriteOnlyWorksheet, headers: list[str], fill: PatternFill = _HEADER_FILL) -> list[Any]:
    cells = []
    for header in headers:
        cell = text_cell(ws, clean_text(str(header)), font=_BOLD, fill=fill)
        cell.border = _HEADER_BORDER
        cell.alignment = _HEADER_ALIGN
        cells.append(cell)
    return cells


def _note(ws: WriteOnlyWorksheet, text: str) -> WriteOnlyCell:
    return text_cell(ws, clean_text(text), font=_NOTE_FONT)


def page_setup(ws: WriteOnlyWorksheet, title_rows: str | None = "1:1", *, fit_height: int = 0) -> None:
    """A4 landscape, fitted to one page wide (``fit_height`` pages tall, 0 = as many as needed), narrow
    margins, header rows repeated on every page, sheet name and page number in the footer."""
    ws.page_setup.orientation = "landscape"
    ws.page_setup.paperSize = PAPER_A4
    ws.page_setup.fitToWidth = 1
    ws.page_setup.fitToHeight = fit_height
    ws.sheet_properties.pageSetUpPr.fitToPage = True
    for side in ("left", "right"):
        setattr(ws.page_margins, side, MARGIN_IN)
    ws.page_margins.top = ws.page_margins.bottom = 0.5
    ws.page_margins.header = ws.page_margins.footer = 0.25
    if title_rows:
        ws.print_title_rows = title_rows
    ws.oddFooter.center.text = "&A, page &P of &N"


PAGE_WIDTH_CHARS = 170  # characters of column width a landscape page shows legibly


def wide_pages(ws: WriteOnlyWorksheet, widths: list[float], text: list[bool]) -> int:
    """For a table wider than one legible landscape page: fit it to 2 or 3 pages wide instead of 1 and
    repeat its leading text columns (identity: call sign, address, sensor) on every page. Returns the
    number of pages wide."""
    pages = min(3, math.ceil(sum(widths) / PAGE_WIDTH_CHARS)) if widths else 1
    if pages > 1:
        ws.page_setup.fitToWidth = pages
        lead = 0
        while lead < min(3, len(text)) and text[lead]:
            lead += 1
        if lead:
            ws.print_title_cols = f"A:{get_column_letter(lead)}"
    return max(pages, 1)


def fixed_rows(ws: WriteOnlyWorksheet) -> None:
    """Every row ROW_HEIGHT_PT high in Excel and LibreOffice alike (their defaults differ), so a grid of
    charts or images lands on the same pages in both."""
    ws.sheet_format.defaultRowHeight = ROW_HEIGHT_PT
    ws.sheet_format.customHeight = True


def _write_table(ws: WriteOnlyWorksheet, columns: list[Column], *, freeze: str = "A2",
                 note: str = "") -> int:
    """Header row, the rows and an optional note under them; returns the number of rows kept."""
    n_rows = len(columns[0].values) if columns else 0
    sample = [c.values[:_WIDTH_SAMPLE_ROWS] for c in columns]
    widths = [_width(c.header, v, c.number_format) for c, v in zip(columns, sample, strict=True)]
    _set_widths(ws, widths)
    ws.freeze_panes = freeze
    page_setup(ws)
    wide_pages(ws, widths, [c.text for c in columns])
    kept = min(n_rows, EXCEL_MAX_ROWS - 1)
    if kept < n_rows:
        note = f"{note} Rows cut at Excel's limit: {kept} of {n_rows} written.".strip()
    ws.append(_header_cells(ws, [c.header for c in columns]))
    for row in _rows(ws, columns, 0, kept):
        ws.append(row)
    if note:  # below the table, so the printed width stays the table's
        ws.append([])
        ws.append([_note(ws, note)])
    return kept


# ------------------------------------------------------------------------------------------------ charts

def pt_to_EMU(points: float) -> int:
    """Points (1/72 inch) to EMU (914400 per inch)."""
    return int(round(points * 12700))


def _scatter(title: str, x_title: str, y_title: str) -> ScatterChart:
    chart = ScatterChart()
    chart.title = clean_text(title)
    chart.style = 2
    chart.width, chart.height = CHART_W_CM, CHART_H_CM
    chart.x_axis.title, chart.y_axis.title = x_title, y_title
    chart.x_axis.delete = False  # openpyxl 3.1 hides axes unless told otherwise
    chart.y_axis.delete = False
    chart.x_axis.crosses = "min"  # axes on the lower-left edges, not through zero
    chart.y_axis.crosses = "min"
    chart.legend.position = "b"
    return chart


def _xy_series(ws: WriteOnlyWorksheet, x_col: int, y_col: int, rows: tuple[int, int], title: str,
               line_rgb: str, *, dash: str | None = None, width_pt: float = 1.5,
               marker: str | None = None) -> Series:
    xs = Reference(ws, min_col=x_col, min_row=rows[0], max_row=rows[1])
    ys = Reference(ws, min_col=y_col, min_row=rows[0], max_row=rows[1])
    series = Series(ys, xs, title=title)
    series.graphicalProperties = GraphicalProperties(
        ln=LineProperties(solidFill=line_rgb, w=int(width_pt * 12700), prstDash=dash))
    if marker:
        series.marker = Marker(symbol=marker, size=4, spPr=GraphicalProperties(
            solidFill=line_rgb, ln=LineProperties(solidFill=line_rgb, w=6350)))
    else:
        series.marker = Marker(symbol="none")
    series.smooth = False
    return series


def _limits(values: Iterable[Any], pad: float = 0.05) -> tuple[float, float] | None:
    numbers = [v for v in values if _is_number(v) and math.isfinite(v)]
    if not numbers:
        return None
    low, high = min(numbers), max(numbers)
    span = (high - low) or max(abs(high) * 1e-6, 1e-9)
    return low - pad * span, high + pad * span


def chart_anchor(index: int, chart: ScatterChart | None = None) -> AbsoluteAnchor:
    """Where chart ``index`` sits on a chart sheet: CHARTS_PER_ROW across, CHART_SLOT_ROWS rows of
    ROW_HEIGHT_PT each down, below the heading rows. Absolute (EMU from the sheet's corner), so the grid
    does not depend on column widths, which differ between spreadsheet programs and their fonts."""
    grid_row, grid_col = divmod(index, CHARTS_PER_ROW)
    x_cm = grid_col * CHART_SLOT_W_CM
    y_pt = (CHART_HEADING_ROWS + grid_row * CHART_SLOT_ROWS) * ROW_HEIGHT_PT + 4.0
    width, height = (chart.width, chart.height) if chart is not None else (CHART_W_CM, CHART_H_CM)
    return AbsoluteAnchor(pos=XDRPoint2D(cm_to_EMU(x_cm), pt_to_EMU(y_pt)),
                          ext=XDRPositiveSize2D(cm_to_EMU(width), cm_to_EMU(height)))


def _chart_sheet(wb: Workbook, title: str, heading: tuple[str, str], n_charts: int) -> WriteOnlyWorksheet:
    """A sheet for charts: column grid, two heading rows (repeated on every page), a page break every
    CHART_ROWS_PER_PAGE rows of charts."""
    ws = wb.create_sheet(title)
    for i in range(CHART_SLOT_COLS * CHARTS_PER_ROW):
        ws.column_dimensions[get_column_letter(i + 1)].width = CHART_COL_WIDTH
    page_setup(ws, f"1:{CHART_HEADING_ROWS}")
    fixed_rows(ws)
    ws.append([text_cell(ws, clean_text(heading[0]), font=_TITLE_FONT)])
    ws.append([_note(ws, heading[1])])
    grid_rows = math.ceil(n_charts / CHARTS_PER_ROW)
    for page in range(1, math.ceil(grid_rows / CHART_ROWS_PER_PAGE)):
        ws.row_breaks.append(Break(id=CHART_HEADING_ROWS + page * CHART_ROWS_PER_PAGE * CHART_SLOT_ROWS))
    # rows under the charts exist (empty) so the print range covers every chart
    for _ in range(grid_rows * CHART_SLOT_ROWS):
        ws.append([])
    return ws


# ------------------------------------------------------------------------------------------------ sheets

def _window_id(window: WindowResult, index: int) -> Any:
    value = excel_value(window.summary.get("window"))
    return index if value is None else value


def _window_title(window: WindowResult, index: int) -> str:
    summary = window.summary
    callsign = excel_value(summary.get("callsign")) or excel_value(summary.get("address")) or "?"
    return f"{callsign} window {_window_id(window, index)}"


def _summary_value(window: WindowResult, key: str) -> Any:
    """A Summary cell value; start/end fall back to the clock time (seconds of day) when undated."""
    value = excel_value(window.summary.get(key))
    if value is None and key in ("start", "end"):
        tod = excel_value(window.summary.get(f"{key}_tod"))
        return ("tod", tod) if _is_number(tod) else None
    return value


def summary_header(key: str) -> str:
    """A Summary header: the JSON key with spaces, so it wraps onto two lines ("radar duplicates")."""
    return key.replace("_", " ")


_INDENT = Alignment(horizontal="left", indent=1)


def _summary_time_cell(ws: WriteOnlyWorksheet, value: Any) -> Any:
    """A Summary start/end: UTC date-time to the second, or ("tod", seconds) as a clock time."""
    if isinstance(value, tuple):
        return _cell(ws, value[1], CLOCK_FORMAT)
    if isinstance(value, dt.datetime):
        cell = WriteOnlyCell(ws, value)
        cell.number_format = SUMMARY_DATETIME_FORMAT
        return cell
    return _cell(ws, value, None)


def _summary_block(ws: WriteOnlyWorksheet, run: CorrelationRun, title: str, keys: list[str],
                   fill: str, row: int) -> int:
    """One Summary block (title, header, one row per window, blank) from sheet row ``row``; returns the
    next free row."""
    keys = [k for k in keys if k in SUMMARY_KEYS]
    ws.append([text_cell(ws, title, font=_BOLD)])
    ws.row_dimensions[row + 1].height = 3 * ROW_HEIGHT_PT  # "radar filled slots" wraps onto 3 lines
    ws.append(_header_cells(ws, [summary_header(k) for k in keys], PatternFill("solid", fgColor=fill)))
    rows = [[_summary_value(w, k) for k in keys] for w in run.windows]
    formats = [number_format_for(k, [r[j] for r in rows]) for j, k in enumerate(keys)]
    for values in rows:
        cells = []
        for value, fmt in zip(values, formats, strict=True):
            if isinstance(value, tuple | dt.datetime):
                cells.append(_summary_time_cell(ws, value))
            elif isinstance(value, str):  # indented: never glued to the number on its left
                cell = _cell(ws, value, None)
                cell.alignment = _INDENT
                cells.append(cell)
            else:
                cells.append(_cell(ws, value, fmt))
        ws.append(cells)
    if not rows:
        ws.append([_note(ws, "no correlated window")])
    ws.append([])
    return row + 2 + max(len(rows), 1) + 1


def _write_summary(wb: Workbook, run: CorrelationRun) -> None:
    ws = wb.create_sheet("Summary")
    skipped = [[excel_value(getattr(s, k)) for k in SKIPPED_KEYS] for s in run.skipped]
    widths: dict[int, float] = {}

    def widen(headers: list[str], rows: list[list[Any]], formats: list[str | None]) -> None:
        for j, header in enumerate(headers):
            values = [r[j] for r in rows]
            widths[j] = max(widths.get(j, 0.0), _width(header, values, formats[j]))

    for _title, keys in SUMMARY_BLOCKS:  # widths first: write-only sheets take them before any row
        keys = [k for k in keys if k in SUMMARY_KEYS]
        rows = [[excel_value(w.summary.get(k)) for k in keys] for w in run.windows]
        formats = [SUMMARY_DATETIME_FORMAT if k in ("start", "end") else
                   number_format_for(k, [r[j] for r in rows]) for j, k in enumerate(keys)]
        widen([summary_header(k) for k in keys], rows, formats)
    widen(SKIPPED_KEYS[:-1], [r[:-1] for r in skipped], [CLOCK_FORMAT] * 4)  # the reason overflows
    _set_widths(ws, [widths[j] for j in sorted(widths)])
    ws.freeze_panes = "C2"
    page_setup(ws, SUMMARY_TITLE_ROWS)
    date = run.parameters.get("date")
    ws.append([text_cell(ws, f"Correlation summary: {len(run.windows)} window(s), {len(run.skipped)} skipped"
                         + (f", {date} UTC" if date else ", date unknown (clock times)"), font=_TITLE_FONT)])
    row = 2
    for (title, keys), fill in zip(SUMMARY_BLOCKS, _BLOCK_FILLS, strict=False):
        row = _summary_block(ws, run, title, keys, fill, row)

    notes = [(w, window_note(w.summary)) for w in run.windows]
    notes = [(w, n) for w, n in notes if n]
    ws.append([text_cell(ws, f"Notes ({len(notes)})", font=_BOLD)])
    for w, note in notes:
        start = _summary_value(w, "start")
        note_cell = _note(ws, note)
        note_cell.alignment = _INDENT
        ws.append([_cell(ws, excel_value(w.summary.get("callsign")), None),
                   _cell(ws, excel_value(w.summary.get("window")), None),
                   _summary_time_cell(ws, start), note_cell])
    if not notes:
        ws.append([_note(ws, "none: in every window the RMS separation is within 3 x the median")])
    ws.append([])
    ws.append([text_cell(ws, f"Skipped windows ({len(skipped)})", font=_BOLD)])
    if skipped:
        ws.append(_header_cells(ws, ["callsign", "address", "start", "end", "reason"],
                                PatternFill("solid", fgColor=_BLOCK_FILLS[3])))
        for row in skipped:
            ws.append([_cell(ws, row[0], None), _cell(ws, row[1], None),
                       *(_cell(ws, v, CLOCK_FORMAT if _is_number(v) else None) for v in row[2:4]),
                       _cell(ws, row[4], None)])
    else:
        ws.append([_note(ws, "none")])


def _scaled_image(png: str | os.PathLike[str]) -> Image:
    """The PNG as an openpyxl Image, scaled down to fit one printed landscape page."""
    image = Image(str(png))
    if image.width and image.height:
        scale = min(1.0, IMAGE_MAX_W_PX / image.width, IMAGE_MAX_H_PX / image.height)
        image.width, image.height = int(image.width * scale), int(image.height * scale)
    return image


def _write_map(wb: Workbook, figure_png: str | os.PathLike[str]) -> None:
    ws = wb.create_sheet("Map")
    page_setup(ws, None, fit_height=1)
    fixed_rows(ws)
    ws.append([text_cell(ws, "Slotted tracks: radar (red) and ADS-B (yellow), every correlated window",
                         font=_TITLE_FONT)])
    ws.add_image(_scaled_image(figure_png), "A2")


def _lag_frame(window: WindowResult) -> pd.DataFrame:
    lags = window.lags
    return lags.sort_values("lag", kind="stable") if "lag" in lags.columns else lags


def _concat_columns(ws: WriteOnlyWorksheet, headers: list[str],
                    per_window: list[dict[str, pd.Series | list[Any]]]) -> list[Column]:
    """Columns built from each window's pieces, concatenated (one Column per header)."""
    columns = []
    for h in headers:
        parts = [p[h] for p in per_window]
        if parts and all(isinstance(p, pd.Series) for p in parts):
            data = pd.concat(parts, ignore_index=True) if len(parts) > 1 else parts[0].reset_index(drop=True)
        else:
            data = pd.Series([v for p in parts for v in (p.tolist() if isinstance(p, pd.Series) else p)],
                             dtype=object)
        columns.append(make_column(ws, h, data))
    return columns


def _ident(window: WindowResult, index: int, n: int) -> dict[str, list[Any]]:
    return {"window": [_window_id(window, index)] * n,
            "callsign": [excel_value(window.summary.get("callsign"))] * n,
            "address": [excel_value(window.summary.get("address"))] * n}


def _write_correlation(wb: Workbook, run: CorrelationRun) -> None:
    ws = wb.create_sheet("Correlation")
    extra = _extra_columns((w.lags for w in run.windows), LAG_COLUMNS)
    headers = CORRELATION_HEADERS + extra
    pieces = []
    for i, w in enumerate(run.windows):
        lags = _lag_frame(w)
        piece: dict[str, Any] = _ident(w, i, len(lags))
        for c in [*LAG_COLUMNS, *extra]:
            piece[c] = lags[c] if c in lags.columns else [None] * len(lags)
        lag = pd.to_numeric(lags["lag"], errors="coerce") if "lag" in lags.columns else pd.Series(
            [np.nan] * len(lags))
        piece["lag_s"] = (lag * slot_seconds(w, run.parameters)).astype(float)
        pieces.append(piece)
    _write_table(ws, _concat_columns(ws, headers, pieces), freeze="D2",
                 note="All lags d = -(N-1)..N-1 of every window; charts of |d| <= N/2: Lag charts sheet.")


def _write_lag_charts(wb: Workbook, run: CorrelationRun, data_sheet: str = "Correlation") -> None:
    """One chart per window of coefficient against lag, |lag| <= N/2 only, on a page grid."""
    frames = [_lag_frame(w) for w in run.windows]
    charted = [i for i, f in enumerate(frames) if len(f)]
    shown = charted[:MAX_CORRELATION_CHARTS]
    more = _first_of(len(shown), len(charted))
    heading = ("Coefficient against lag for |lag| <= N/2 (at least half the slots overlap)",
               "Wider lags are left out (all lags: Correlation sheet). NCC solid, Pearson dashed; "
               f"latitude blue, longitude green{more}.")
    ws = _chart_sheet(wb, "Lag charts", heading, len(shown))
    ref = _SheetRef(data_sheet)
    starts = np.concatenate([[2], 2 + np.cumsum([len(f) for f in frames])]).astype(int)
    col = {h: i + 1 for i, h in enumerate(CORRELATION_HEADERS)}
    for n, i in enumerate(shown):
        w, lags = run.windows[i], frames[i]
        n_slots = (len(lags) + 1) // 2
        half = pearson_max_lag(n_slots)
        lag = pd.to_numeric(lags["lag"], errors="coerce").to_numpy(dtype=float)
        inside = np.flatnonzero(np.abs(lag) <= half)
        if inside.size == 0:
            continue
        first, last = int(starts[i] + inside[0]), int(starts[i] + inside[-1])
        if last > EXCEL_MAX_ROWS:
            break
        chart = _scatter(f"{_window_title(w, i)}, N = {n_slots}", f"lag (slots, |lag| <= {half})",
                         "coefficient")
        values = []
        for name, rgb, dash, label in (("ncc_lat", LAT_RGB, None, "NCC lat"),
                                       ("ncc_lon", LON_RGB, None, "NCC lon"),
                                       ("pearson_lat", LAT_RGB, "dash", "Pearson lat"),
                                       ("pearson_lon", LON_RGB, "dash", "Pearson lon")):
            chart.series.append(_xy_series(ref, col["lag"], col[name], (first, last), label, rgb, dash=dash,
                                           width_pt=1.5))
            if name in lags.columns:
                values += pd.to_numeric(lags[name], errors="coerce").to_numpy(dtype=float)[inside].tolist()
        chart.x_axis.scaling.min, chart.x_axis.scaling.max = -half, half
        y_span = coefficient_axis(values)
        chart.y_axis.scaling.min, chart.y_axis.scaling.max = y_span
        chart.y_axis.number_format = "0.0"
        chart.x_axis.number_format = "0"
        ws.add_chart(chart, chart_anchor(n, chart))


def coefficient_axis(values: Iterable[float]) -> tuple[float, float]:
    """y range of a coefficient chart: 0.1 steps around the finite values, within [-1, 1]."""
    finite = [v for v in values if v == v and math.isfinite(v)]
    if not finite:
        return -1.0, 1.0
    low = max(-1.0, math.floor(min(finite) * 10 - 1e-9) / 10)
    high = min(1.0, math.ceil(max(finite) * 10 + 1e-9) / 10)
    return (low, high) if high > low else (low - 0.1, high + 0.1)


def _first_of(shown: int, total: int) -> str:
    return f"; charts for the first {shown} of {total} windows" if total > shown else ""


class _SheetRef:
    """Stands in for a worksheet in chart References (only its title is used)."""

    def __init__(self, title: str):
        self.title = title


def _extra_columns(frames: Iterable[pd.DataFrame], known: list[str]) -> list[str]:
    extra: dict[str, None] = {}
    for frame in frames:
        extra.update((str(c), None) for c in frame.columns if c not in known and str(c) not in extra)
    return [c for c in extra if c not in known]


def _slot_times(window: WindowResult) -> pd.Series:
    """The slots' UTC times (all known: the caller checked)."""
    return pd.to_datetime(window.slots["timestamp"], utc=True).reset_index(drop=True)


def _write_slots(wb: Workbook, run: CorrelationRun) -> None:
    ws = wb.create_sheet("Slots")
    extra = _extra_columns((w.slots for w in run.windows), SLOT_COLUMNS)
    headers = SLOTS_HEADERS + extra
    pieces = []
    dated = all("timestamp" in w.slots and w.slots["timestamp"].notna().all() for w in run.windows)
    for i, w in enumerate(run.windows):
        piece: dict[str, Any] = _ident(w, i, len(w.slots))
        for c in [h for h in headers[3:] if h != "time_utc"]:
            piece[c] = w.slots[c].reset_index(drop=True) if c in w.slots.columns else [None] * len(w.slots)
        if dated:
            piece["time_utc"] = _slot_times(w)
        else:  # clock times for every window, so the column has one format
            tod = w.slots["time_of_day"] if "time_of_day" in w.slots else pd.Series([np.nan] * len(w.slots))
            piece["time_utc"] = pd.to_numeric(tod, errors="coerce").reset_index(drop=True)
        pieces.append(piece)
    columns = _concat_columns(ws, headers, pieces)
    if not dated:
        index = headers.index("time_utc")
        values = [None if v is None else v / 86400.0 for v in columns[index].values]
        columns[index] = Column("time_utc", values, CLOCK_FORMAT, WriteOnlyCell(ws, 0.0))
        columns[index].styled.number_format = CLOCK_FORMAT
    _write_table(ws, columns, freeze="D2",
                 note="time_utc: slot start, UTC" + ("" if dated else " clock time (date unknown)")
                 + "; charts on the Slot charts sheet.")


def _write_slot_charts(wb: Workbook, run: CorrelationRun, data_sheet: str = "Slots") -> None:
    lengths = [len(w.slots) for w in run.windows]
    charted = [i for i, n in enumerate(lengths) if n]
    shown = charted[:MAX_SLOT_CHART_WINDOWS]
    more = _first_of(len(shown), len(charted))
    heading = ("Slotted latitude and longitude against time (UTC)",
               f"ADS-B yellow (solid, wide), radar red (dashed, on top); data on the Slots sheet{more}.")
    ws = _chart_sheet(wb, "Slot charts", heading, 2 * len(shown))
    ref = _SheetRef(data_sheet)
    starts = np.concatenate([[2], 2 + np.cumsum(lengths)]).astype(int)
    col = {h: i + 1 for i, h in enumerate(SLOTS_HEADERS)}
    dated = all("timestamp" in w.slots and w.slots["timestamp"].notna().all() for w in run.windows)
    for n, i in enumerate(shown):
        w = run.windows[i]
        first, last = int(starts[i]), int(starts[i + 1]) - 1
        if last > EXCEL_MAX_ROWS:
            break
        if dated:
            times = [to_excel(utc_naive(t)) for t in w.slots["timestamp"]]
        else:
            times = [v / 86400.0 for v in pd.to_numeric(w.slots["time_of_day"], errors="coerce").tolist()]
        x_span = _limits(times, pad=0.0)
        markers = len(w.slots) <= 40
        for k, (axis, name) in enumerate((("lat", "latitude"), ("lon", "longitude"))):
            chart = _scatter(f"{_window_title(w, i)}: {name}", "time (UTC)", f"{name} (deg)")
            # LibreOffice draws the first series on top: radar first, so the wide ADS-B line never hides it
            chart.series.append(_xy_series(ref, col["time_utc"], col[f"radar_{axis}"], (first, last), "Radar",
                                           RADAR_RGB, dash="dash", width_pt=1.5,
                                           marker="triangle" if markers else None))
            chart.series.append(_xy_series(ref, col["time_utc"], col[f"adsb_{axis}"], (first, last), "ADS-B",
                                           ADSB_RGB, width_pt=3.0, marker="circle" if markers else None))
            chart.x_axis.number_format = "hh:mm"
            chart.y_axis.number_format = "0.00"
            if x_span:
                chart.x_axis.scaling.min, chart.x_axis.scaling.max = x_span
                chart.x_axis.majorUnit = _time_step_days(x_span[1] - x_span[0])
            y_values = [*column_values(w.slots[f"radar_{axis}"]), *column_values(w.slots[f"adsb_{axis}"])]
            y_span = _limits(y_values)
            if y_span:
                chart.y_axis.scaling.min, chart.y_axis.scaling.max = y_span
            ws.add_chart(chart, chart_anchor(2 * n + k, chart))


def _time_step_days(span_days: float) -> float:
    """A round tick step (1 min .. 2 h) giving at most 6 ticks over ``span_days``."""
    for minutes in (1, 2, 5, 10, 15, 30, 60, 120):
        if span_days * 1440 / minutes <= 6:
            return minutes / 1440
    return 240 / 1440


def _flatten(prefix: str, value: Any) -> Iterator[tuple[str, Any]]:
    if isinstance(value, Mapping) and value:
        for key, item in value.items():
            yield from _flatten(f"{prefix}.{key}" if prefix else str(key), item)
    else:
        yield prefix, value


def parameter_rows(run: CorrelationRun) -> list[list[Any]]:
    """Key/value rows of the Parameters sheet: section, key, value."""
    rows: list[list[Any]] = []
    for i, item in enumerate(run.inputs, start=1):
        order = ["path", "format", "bytes", "sha256"]
        for key in [*(k for k in order if k in item), *(k for k in item if k not in order)]:
            rows.append([f"input {i}", key, item[key]])
    for key, value in run.parameters.items():
        if isinstance(value, Mapping):
            rows += [[str(key), k, v] for k, v in _flatten("", value)]
        else:
            rows.append(["parameters", str(key), value])
    rows += [["filters", str(k), v] for k, v in run.filters.items()]
    rows += [["report", "windows", len(run.windows)], ["report", "skipped windows", len(run.skipped)]]
    return [[excel_value(v) for v in row] for row in rows]


def _write_parameters(wb: Workbook, run: CorrelationRun) -> None:
    ws = wb.create_sheet("Parameters")
    rows = parameter_rows(run)
    headers = ["section", "key", "value"]
    columns = [make_column(ws, h, [r[j] for r in rows], general=True) for j, h in enumerate(headers)]
    _write_table(ws, columns)


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
    _write_table(ws, columns, note=note)


def _write_figures(wb: Workbook, title: str, images: dict[str, str | os.PathLike[str]]) -> None:
    """A sheet of PNG figures, one per printed page, each under its caption."""
    ws = wb.create_sheet(title)
    page_setup(ws, None)
    fixed_rows(ws)
    row = 1
    rows_per_page = int((IMAGE_MAX_H_PX + 40) / (ROW_HEIGHT_PT * 4 / 3)) + 2
    for caption, png in images.items():
        image = _scaled_image(png)
        ws.append([text_cell(ws, clean_text(caption), font=_TITLE_FONT)])
        ws.add_image(image, f"A{row + 1}")
        for _ in range(rows_per_page - 1):
            ws.append([])
        row += rows_per_page
        ws.row_breaks.append(Break(id=row - 1))


def write_report(run: CorrelationRun, path_xlsx: str | os.PathLike[str], *,
                 figure_png: str | os.PathLike[str] | None = None,
                 images: dict[str, str | os.PathLike[str]] | None = None) -> None:
    """Write the run's workbook to ``path_xlsx``; embed ``figure_png`` on a Map sheet when given and
    further ``images`` (caption -> PNG) on a Figures sheet."""
    wb = Workbook(write_only=True)
    taken = {name.lower() for name in _CORE_SHEETS}
    _write_summary(wb, run)
    if figure_png is not None:
        _write_map(wb, figure_png)
    _write_lag_charts(wb, run)
    _write_slot_charts(wb, run)
    _write_correlation(wb, run)
    _write_slots(wb, run)
    for name, frame in run.extra_sheets.items():
        _write_frame(wb, sheet_name(name, taken), frame)
    if images:
        _write_figures(wb, sheet_name("Figures", taken), images)
    _write_parameters(wb, run)
    write_atomically(path_xlsx, wb.save)


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
        _write_parameters(wb, CorrelationRun(parameters=parameters))
    write_atomically(path_xlsx, wb.save)

