"""Excel workbook of a CorrelationRun: Summary, Map, Correlation, Slots, extra sheets and Parameters.

Written with openpyxl in write-only (streaming) mode so long recordings stay within memory. Cell rules:
times are real Excel date-times in UTC, numbers are numbers (NaN -> empty cell), all text is stored as
text (never as a formula), headers are bold and frozen, widths fit the content.
"""

from __future__ import annotations

import datetime as dt
import json
import math
import os
import re
from collections.abc import Callable, Iterable, Iterator, Mapping
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
from openpyxl.styles import Alignment, Border, Font, PatternFill, Side
from openpyxl.utils import get_column_letter
from openpyxl.utils.datetime import to_excel
from openpyxl.worksheet._write_only import WriteOnlyWorksheet

from pipeline.correlate.results import LAG_COLUMNS, SLOT_COLUMNS, SUMMARY_KEYS, CorrelationRun, WindowResult
from pipeline.report.summary import (
    SKIPPED_KEYS,
    is_missing,
    json_value,
    slot_seconds,
    utc_naive,
    write_atomically,
)

DATETIME_FORMAT = "yyyy-mm-dd hh:mm:ss.000"
DATE_FORMAT = "yyyy-mm-dd"
TIME_FORMAT = "hh:mm:ss.000"
MAX_CORRELATION_CHARTS = 20
MAX_SLOT_CHART_WINDOWS = 6
EXCEL_MAX_ROWS = 1_048_576
EXCEL_MAX_TEXT = 32_767
MIN_WIDTH, MAX_WIDTH = 6.0, 66.0
_WIDTH_SAMPLE_ROWS = 5000
_FORMULA_START = ("=", "+", "-", "@", "\t", "\r")
_ISO_DATE = re.compile(r"\d{4}-\d{2}-\d{2}\Z")
_ISO_DATETIME = re.compile(r"\d{4}-\d{2}-\d{2}[T ]\d{2}:\d{2}(:\d{2}(\.\d{1,9})?)?(Z|[+-]\d{2}:?\d{2})?\Z")
_DATETIME_HEADERS = {"time_utc", "start", "end", "timestamp", "run_time"}

SUMMARY_GROUPS: list[tuple[str, list[str]]] = [
    ("Window", ["callsign", "address", "window", "radar_sensor", "reference_sensor", "start", "end",
                "start_tod", "end_tod", "slots"]),
    ("Table 6.1 counts", ["radar_before", "radar_after", "adsb_before", "adsb_after"]),
    ("Table 6.2 coefficients", ["ncc0_lat", "ncc0_lon"]),
    ("Added measures", []),  # every other SUMMARY_KEYS entry, in SUMMARY_KEYS order
]
CORRELATION_HEADERS = ["window", "callsign", "address", "lag", "lag_s", *LAG_COLUMNS[1:]]
SLOTS_HEADERS = ["window", "callsign", "address", "slot", "time_utc", *SLOT_COLUMNS[1:2], *SLOT_COLUMNS[3:]]
_SLOT_SOURCE = {"time_utc": "timestamp"}
_CORE_SHEETS = ("Summary", "Map", "Correlation", "Slots", "Parameters")

_BOLD = Font(bold=True)
_NOTE_FONT = Font(italic=True, color="595959")
_HEADER_FILL = PatternFill("solid", fgColor="D9E1F2")
_GROUP_FILLS = ["EDEDED", "FCE4D6", "E2EFDA", "DDEBF7"]
_HEADER_BORDER = Border(bottom=Side(style="thin", color="808080"))
_HEADER_ALIGN = Alignment(vertical="center")

RADAR_RGB, ADSB_RGB, ADSB_EDGE_RGB = "D62728", "FFD400", "3D3000"
LAT_RGB, LON_RGB = "1F77B4", "2CA02C"
_CHART_W_CM, _CHART_H_CM, _CHART_ROWS, _CHART_COLS = 15.0, 7.5, 16, 10


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
    if text.startswith(_FORMULA_START):
        cell.quotePrefix = True
    if font is not None:
        cell.font = font
    if fill is not None:
        cell.fill = fill
    return cell


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
    cell = WriteOnlyCell(ws, value)
    cell.number_format = number_format
    return cell


def _series_values(frame: pd.DataFrame, column: str) -> list[Any]:
    """excel_value() of every entry of ``frame[column]`` (all None when the column is absent)."""
    if column not in frame.columns:
        return [None] * len(frame)
    return column_values(frame[column])


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


# ------------------------------------------------------------------------------------- formats, widths

def _is_number(value: Any) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool)


def number_format_for(name: str, values: Iterable[Any]) -> str | None:
    """Number format for a column from its name (units, coordinates, coefficients) and sample values."""
    numbers = [v for v in values if _is_number(v)]
    if not numbers:
        return None
    key = name.lower()
    if re.search(r"(^|_)lag($|_)", key):
        return "0.000" if key.endswith("_s") else "0"
    if re.search(r"ncc", key):  # NCC of raw coordinates sits very close to 1: show the digits that differ
        return "0.0000000000"
    if re.search(r"pearson|corr|coef", key):
        return "0.000000"
    if re.search(r"(^|_)(lat|lon|latitude|longitude)($|_|\d)", key):
        return "0.000000"
    if key in {"bytes", "size", "size_bytes"}:
        return "#,##0"
    for suffix, fmt in (("_m", "0.0"), ("_nm", "0.000"), ("_deg", "0.00"), ("_kt", "0.0"), ("_ft", "0"),
                        ("_s", "0.000"), ("_tod", "0.000"), ("time_of_day", "0.000")):
        if key.endswith(suffix):
            return fmt
    if all(float(v).is_integer() for v in numbers):
        return "0"
    return "0.000000" if max(abs(v) for v in numbers) < 1 else "0.000"


def _display_len(value: Any, number_format: str | None) -> int:
    if value is None:
        return 0
    if isinstance(value, str):
        return max(len(line) for line in value.split("\n"))
    if isinstance(value, bool):
        return 5
    if isinstance(value, dt.datetime):
        return len(DATETIME_FORMAT)
    if isinstance(value, dt.date | dt.time):
        return 12
    if number_format and "." in number_format:
        return len(f"{value:,.{number_format.count('0', number_format.index('.'))}f}")
    if number_format and number_format.startswith("#,"):
        return len(f"{value:,.0f}")
    if isinstance(value, float) and not number_format:
        return min(len(repr(value)), 12)
    return len(f"{value:.0f}") if isinstance(value, float) else len(str(value))


def _width(header: str, values: Iterable[Any], number_format: str | None) -> float:
    longest = max([len(header), *(_display_len(v, number_format) for v in values)])
    if header in _DATETIME_HEADERS:
        longest = max(longest, len(DATETIME_FORMAT))
    return min(MAX_WIDTH, max(MIN_WIDTH, longest + 2.0))


def _plan(headers: list[str], sample: list[list[Any]],
          general: bool = False) -> tuple[list[str | None], list[float]]:
    """Number format (None = General when ``general``) and width of each column, from a sample of rows."""
    columns = list(zip(*sample, strict=True)) if sample else [()] * len(headers)
    pairs = zip(headers, columns, strict=True)
    formats = [None if general else number_format_for(h, col) for h, col in pairs]
    widths = [_width(h, col, f) for h, col, f in zip(headers, columns, formats, strict=True)]
    return formats, widths


def _set_widths(ws: WriteOnlyWorksheet, widths: list[float]) -> None:
    for i, width in enumerate(widths, start=1):
        ws.column_dimensions[get_column_letter(i)].width = round(width, 1)


def _header_cells(ws: WriteOnlyWorksheet, headers: list[str], fills: list[str] | None = None) -> list[Any]:
    cells = []
    for i, header in enumerate(headers):
        cell = text_cell(ws, clean_text(str(header)), font=_BOLD,
                         fill=PatternFill("solid", fgColor=fills[i]) if fills else _HEADER_FILL)
        cell.border = _HEADER_BORDER
        cell.alignment = _HEADER_ALIGN
        cells.append(cell)
    return cells


def _note(ws: WriteOnlyWorksheet, text: str) -> WriteOnlyCell:
    return text_cell(ws, clean_text(text), font=_NOTE_FONT)


def _write_table(ws: WriteOnlyWorksheet, headers: list[str], rows: Callable[[], Iterator[list[Any]]],
                 n_rows: int, *, freeze: str = "A2", note: str = "", note_column: int | None = None,
                 per_cell_formats: bool = False) -> tuple[list[str | None], int]:
    """Header row (with an optional note to the right) and streamed data rows; returns formats, rows kept.

    ``per_cell_formats`` leaves numbers in General format, for columns that mix unrelated values."""
    formats, widths = _plan(headers, list(islice(rows(), _WIDTH_SAMPLE_ROWS)), general=per_cell_formats)
    _set_widths(ws, widths)
    ws.freeze_panes = freeze
    kept = min(n_rows, EXCEL_MAX_ROWS - 1)
    if kept < n_rows:
        note = f"{note} Rows cut at Excel's limit: {kept} of {n_rows} written.".strip()
    header = _header_cells(ws, headers)
    if note:
        column = note_column or len(headers) + 2
        header += [None] * (column - len(header) - 1) + [_note(ws, note)]
    ws.append(header)
    for row in islice(rows(), kept):
        ws.append([_cell(ws, v, f) for v, f in zip(row, formats, strict=True)])
    return formats, kept


# ------------------------------------------------------------------------------------------------ charts

def _scatter(title: str, x_title: str, y_title: str) -> ScatterChart:
    chart = ScatterChart()
    chart.title = clean_text(title)
    chart.style = 2
    chart.width, chart.height = _CHART_W_CM, _CHART_H_CM
    chart.x_axis.title, chart.y_axis.title = x_title, y_title
    chart.x_axis.delete = False  # openpyxl 3.1 hides axes unless told otherwise
    chart.y_axis.delete = False
    chart.x_axis.crosses = "min"  # axes on the lower-left edges, not through zero
    chart.y_axis.crosses = "min"
    chart.legend.position = "b"
    return chart


def _xy_series(ws: WriteOnlyWorksheet, x_col: int, y_col: int, rows: tuple[int, int], title: str,
               line_rgb: str, *, dash: str | None = None, marker: str = "circle",
               marker_rgb: str | None = None, edge_rgb: str | None = None, width_pt: float = 1.5) -> Series:
    xs = Reference(ws, min_col=x_col, min_row=rows[0], max_row=rows[1])
    ys = Reference(ws, min_col=y_col, min_row=rows[0], max_row=rows[1])
    series = Series(ys, xs, title=title)
    series.graphicalProperties = GraphicalProperties(
        ln=LineProperties(solidFill=line_rgb, w=int(width_pt * 12700), prstDash=dash))
    series.marker = Marker(symbol=marker, size=5, spPr=GraphicalProperties(
        solidFill=marker_rgb or line_rgb, ln=LineProperties(solidFill=edge_rgb or line_rgb, w=9525)))
    series.smooth = False
    return series


def _limits(values: Iterable[Any], pad: float = 0.05) -> tuple[float, float] | None:
    numbers = [v for v in values if _is_number(v) and math.isfinite(v)]
    if not numbers:
        return None
    low, high = min(numbers), max(numbers)
    span = (high - low) or max(abs(high) * 1e-6, 1e-9)
    return low - pad * span, high + pad * span


def _anchor(column: int, index: int, per_row: int, first_row: int = 2) -> str:
    row = first_row + (index // per_row) * _CHART_ROWS
    return f"{get_column_letter(column + (index % per_row) * _CHART_COLS)}{row}"


# ------------------------------------------------------------------------------------------------ sheets

def _window_id(window: WindowResult, index: int) -> Any:
    value = excel_value(window.summary.get("window"))
    return index if value is None else value


def _window_title(window: WindowResult, index: int) -> str:
    summary = window.summary
    callsign = excel_value(summary.get("callsign")) or excel_value(summary.get("address")) or "?"
    return f"{callsign} window {_window_id(window, index)}"


def _summary_columns() -> tuple[list[str], list[str], list[str]]:
    """Summary headers in sheet order, with each column's group label and fill."""
    named = {key for _, keys in SUMMARY_GROUPS for key in keys}
    headers, groups, fills = [], [], []
    for (label, keys), fill in zip(SUMMARY_GROUPS, _GROUP_FILLS, strict=True):
        keys = [k for k in keys if k in SUMMARY_KEYS] if keys else [k for k in SUMMARY_KEYS if k not in named]
        if not keys:
            continue
        headers += keys
        groups += [label] + [""] * (len(keys) - 1)
        fills += [fill] * len(keys)
    return headers, groups, fills


def _write_summary(wb: Workbook, run: CorrelationRun) -> None:
    ws = wb.create_sheet("Summary")
    headers, groups, fills = _summary_columns()
    rows = [[excel_value(w.summary.get(k)) for k in headers] for w in run.windows]
    skipped = [[excel_value(getattr(s, k)) for k in SKIPPED_KEYS] for s in run.skipped]
    formats, widths = _plan(headers, rows)
    skip_formats, skip_widths = _plan(SKIPPED_KEYS, [r[:-1] + [None] for r in skipped])  # reason overflows
    _set_widths(ws, [max(a, b) for a, b in zip(widths, skip_widths + [0.0] * len(widths), strict=False)])
    ws.freeze_panes = "C3"
    ws.append([text_cell(ws, g, font=_BOLD, fill=PatternFill("solid", fgColor=f)) if g else
               _filled(ws, f) for g, f in zip(groups, fills, strict=True)])
    ws.append(_header_cells(ws, headers, fills))
    for row in rows:
        ws.append([_cell(ws, v, f) for v, f in zip(row, formats, strict=True)])
    ws.append([])
    ws.append([text_cell(ws, f"Skipped windows ({len(skipped)})", font=_BOLD)])
    if skipped:
        ws.append(_header_cells(ws, SKIPPED_KEYS))
        for row in skipped:
            ws.append([_cell(ws, v, f) for v, f in zip(row, skip_formats, strict=True)])
    else:
        ws.append([_note(ws, "none")])


def _filled(ws: WriteOnlyWorksheet, rgb: str) -> WriteOnlyCell:
    cell = WriteOnlyCell(ws, None)
    cell.fill = PatternFill("solid", fgColor=rgb)
    return cell


def _write_map(wb: Workbook, figure_png: str | os.PathLike[str]) -> None:
    ws = wb.create_sheet("Map")
    ws.append([text_cell(ws, "Slotted tracks: radar (red) and ADS-B (yellow), every correlated window",
                         font=Font(bold=True, size=12))])
    image = Image(str(figure_png))
    scale = min(1.0, 1100 / image.width) if image.width else 1.0
    image.width, image.height = int(image.width * scale), int(image.height * scale)
    ws.add_image(image, "A3")


def _lag_frame(window: WindowResult) -> pd.DataFrame:
    lags = window.lags
    return lags.sort_values("lag", kind="stable") if "lag" in lags.columns else lags


def _write_correlation(wb: Workbook, run: CorrelationRun) -> None:
    ws = wb.create_sheet("Correlation")
    extra = _extra_columns((w.lags for w in run.windows), LAG_COLUMNS)
    headers = CORRELATION_HEADERS + extra
    frames = [_lag_frame(w) for w in run.windows]

    def rows() -> Iterator[list[Any]]:
        for i, (w, lags) in enumerate(zip(run.windows, frames, strict=True)):
            ident = [_window_id(w, i), excel_value(w.summary.get("callsign")),
                     excel_value(w.summary.get("address"))]
            step = slot_seconds(w, run.parameters)
            lag = _series_values(lags, "lag")
            lag_s = [excel_value(v * step) if _is_number(v) else None for v in lag]
            columns = [lag, lag_s, *(_series_values(lags, c) for c in [*LAG_COLUMNS[1:], *extra])]
            for values in zip(*columns, strict=True):
                yield [*ident, *values]

    total = sum(len(f) for f in frames)
    charted = [i for i, f in enumerate(frames) if len(f)]
    capped = len(charted) > MAX_CORRELATION_CHARTS
    note = ("One chart per window: NCC solid, Pearson dashed; latitude blue, longitude green."
            + (f" Charts shown for the first {MAX_CORRELATION_CHARTS} of {len(charted)} windows." if capped
               else ""))
    chart_col = len(headers) + 2
    _, kept = _write_table(ws, headers, rows, total, freeze="D2", note=note, note_column=chart_col)
    starts = np.concatenate([[2], 2 + np.cumsum([len(f) for f in frames])]).astype(int)
    col = {h: i + 1 for i, h in enumerate(headers)}
    for n, i in enumerate(charted[:MAX_CORRELATION_CHARTS]):
        first, last = int(starts[i]), min(int(starts[i + 1]) - 1, kept + 1)
        if last < first:
            break
        chart = _scatter(f"{_window_title(run.windows[i], i)}: coefficient vs lag", "lag (slots)",
                         "coefficient")
        for name, rgb, dash, label in (("ncc_lat", LAT_RGB, None, "NCC lat"),
                                       ("ncc_lon", LON_RGB, None, "NCC lon"),
                                       ("pearson_lat", LAT_RGB, "dash", "Pearson lat"),
                                       ("pearson_lon", LON_RGB, "dash", "Pearson lon")):
            chart.series.append(_xy_series(ws, col["lag"], col[name], (first, last), label, rgb, dash=dash,
                                           marker="circle" if dash is None else "square"))
        span = _limits(_series_values(frames[i], "lag"), pad=0.0)
        if span:
            chart.x_axis.scaling.min, chart.x_axis.scaling.max = span
        chart.y_axis.number_format = "0.0000"
        ws.add_chart(chart, _anchor(chart_col, n, per_row=2))


def _extra_columns(frames: Iterable[pd.DataFrame], known: list[str]) -> list[str]:
    extra: dict[str, None] = {}
    for frame in frames:
        extra.update((str(c), None) for c in frame.columns if c not in known and str(c) not in extra)
    return [c for c in extra if c not in known]


def _write_slots(wb: Workbook, run: CorrelationRun) -> None:
    ws = wb.create_sheet("Slots")
    extra = _extra_columns((w.slots for w in run.windows), SLOT_COLUMNS)
    headers = SLOTS_HEADERS + extra
    sources = [_SLOT_SOURCE.get(h, h) for h in headers[3:]]

    def rows() -> Iterator[list[Any]]:
        for i, w in enumerate(run.windows):
            ident = [_window_id(w, i), excel_value(w.summary.get("callsign")),
                     excel_value(w.summary.get("address"))]
            for values in zip(*(_series_values(w.slots, c) for c in sources), strict=True):
                yield [*ident, *values]

    lengths = [len(w.slots) for w in run.windows]
    charted = [i for i, n in enumerate(lengths) if n][:MAX_SLOT_CHART_WINDOWS]
    n_charted = sum(1 for n in lengths if n)
    capped = f", for the first {len(charted)} of {n_charted} windows." if n_charted > len(charted) else "."
    note = "Charts: latitude and longitude against time, radar red, ADS-B yellow" + capped
    chart_col = len(headers) + 2
    _, kept = _write_table(ws, headers, rows, sum(lengths), freeze="D2", note=note, note_column=chart_col)
    starts = np.concatenate([[2], 2 + np.cumsum(lengths)]).astype(int)
    col = {h: i + 1 for i, h in enumerate(headers)}
    for n, i in enumerate(charted):
        w = run.windows[i]
        first, last = int(starts[i]), min(int(starts[i + 1]) - 1, kept + 1)
        if last < first:
            break
        times = [utc_naive(t) for t in (w.slots["timestamp"] if "timestamp" in w.slots else [None])]
        if all(t is not None for t in times):
            x_col, x_title, x_format = col["time_utc"], "time (UTC)", "hh:mm:ss"
            x_span = _limits([to_excel(t) for t in times], pad=0.0)
        else:
            x_col, x_title, x_format = col["time_of_day"], "time of day (s)", "0"
            x_span = _limits(_series_values(w.slots, "time_of_day"), pad=0.0)
        for k, (axis, name) in enumerate((("lat", "latitude"), ("lon", "longitude"))):
            chart = _scatter(f"{_window_title(w, i)}: {name}", x_title, f"{name} (deg)")
            chart.series.append(_xy_series(ws, x_col, col[f"adsb_{axis}"], (first, last), "ADS-B", ADSB_RGB,
                                           marker_rgb=ADSB_RGB, edge_rgb=ADSB_EDGE_RGB, width_pt=2.0))
            chart.series.append(_xy_series(ws, x_col, col[f"radar_{axis}"], (first, last), "Radar", RADAR_RGB,
                                           width_pt=1.25))
            chart.x_axis.number_format = x_format
            chart.y_axis.number_format = "0.0000"
            if x_span:
                chart.x_axis.scaling.min, chart.x_axis.scaling.max = x_span
            y_values = _series_values(w.slots, f"radar_{axis}") + _series_values(w.slots, f"adsb_{axis}")
            y_span = _limits(y_values)
            if y_span:
                chart.y_axis.scaling.min, chart.y_axis.scaling.max = y_span
            ws.add_chart(chart, _anchor(chart_col, 2 * n + k, per_row=2))


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
    _write_table(ws, headers, lambda: iter(rows), len(rows), per_cell_formats=True)


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
    values = [column_values(frame.iloc[:, j]) for j in range(frame.shape[1])]
    _write_table(ws, headers, lambda: (list(r) for r in zip(*values, strict=True)), len(frame))


def _write_figures(wb: Workbook, title: str, images: dict[str, str | os.PathLike[str]]) -> None:
    """A sheet of PNG figures stacked vertically, each under its caption."""
    ws = wb.create_sheet(title)
    row = 1
    for caption, png in images.items():
        image = Image(str(png))
        scale = min(1.0, 1000 / image.width) if image.width else 1.0
        image.width, image.height = int(image.width * scale), int(image.height * scale)
        ws.append([text_cell(ws, caption, font=Font(bold=True, size=12))])
        ws.add_image(image, f"A{row + 1}")
        rows_used = int(image.height / 20) + 3
        for _ in range(rows_used):
            ws.append([])
        row += rows_used + 1


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
