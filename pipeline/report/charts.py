"""Chart sheets of the correlation workbook: coefficient against lag and slotted positions against time,
native Excel scatter charts placed on a grid of whole printed pages (two across, two down)."""

from __future__ import annotations

import functools
import math
from collections.abc import Iterable
from typing import Any

import numpy as np
import pandas as pd
from openpyxl import Workbook
from openpyxl.chart import Reference, ScatterChart, Series
from openpyxl.chart.marker import Marker
from openpyxl.chart.shapes import GraphicalProperties
from openpyxl.chart.text import RichText
from openpyxl.chart.text import Text as ChartText
from openpyxl.chart.title import Title, title_maker
from openpyxl.drawing.line import LineProperties
from openpyxl.drawing.spreadsheet_drawing import AbsoluteAnchor
from openpyxl.drawing.text import CharacterProperties, Paragraph, ParagraphProperties, RegularTextRun
from openpyxl.drawing.xdr import XDRPoint2D, XDRPositiveSize2D
from openpyxl.utils import get_column_letter
from openpyxl.utils.datetime import to_excel
from openpyxl.utils.units import cm_to_EMU
from openpyxl.worksheet._write_only import WriteOnlyWorksheet
from openpyxl.worksheet.pagebreak import Break

from msdc.pipeline.correlate.correlation import pearson_max_lag
from msdc.pipeline.correlate.results import LAG_COLUMNS, SLOT_COLUMNS, CorrelationRun, WindowResult
from msdc.pipeline.report.cells import (
    EXCEL_MAX_ROWS,
    ROW_HEIGHT_PT,
    TITLE_FONT,
    clean_text,
    column_values,
    excel_value,
    fixed_rows,
    is_number,
    note_text_cell,
    page_setup,
    text_cell,
)
from msdc.pipeline.report.summary import pair_nouns, side_words, utc_naive, window_label
from msdc.pipeline.report.tables import lag_frame

# every row names its window: number, aircraft and sensor pair (numbers restart for every pair)
WINDOW_HEADERS = ["window", "callsign", "address", "radar_sensor", "reference_sensor"]
CORRELATION_HEADERS = [*WINDOW_HEADERS, "lag", "lag_s", *LAG_COLUMNS[1:]]
SLOTS_HEADERS = [*WINDOW_HEADERS, "slot", "time_utc", *SLOT_COLUMNS[3:]]
# the columns of the excerpts a workbook keeps for its charts when the tables went to Parquet
LAG_CHART_HEADERS = [*WINDOW_HEADERS, "lag", "ncc_lat", "ncc_lon", "pearson_lat", "pearson_lon"]
SLOT_CHART_HEADERS = [*WINDOW_HEADERS, "time_utc", "radar_lat", "radar_lon", "adsb_lat", "adsb_lon"]
MAX_CORRELATION_CHARTS = 20
MAX_SLOT_CHART_WINDOWS = 10
RADAR_RGB, ADSB_RGB = "D62728", "E6B800"
CHART_TITLE_PT = 10.0
LAT_RGB, LON_RGB = "1F77B4", "2CA02C"

CHART_HEADING_ROWS = 2  # rows 1-2 of a chart sheet: its heading, repeated on every printed page
CHART_COL_WIDTH = 9.5  # characters; 7 columns per chart slot
CHART_SLOT_COLS, CHART_SLOT_ROWS, CHARTS_PER_ROW, CHART_ROWS_PER_PAGE = 7, 15, 2, 2
CHART_W_CM, CHART_H_CM = 12.6, 7.4
CHART_SLOT_W_CM = 13.3  # two slots (26.6 cm) inside the 27.7 cm between A4 landscape margins


def pt_to_EMU(points: float) -> int:
    """Points (1/72 inch) to EMU (914400 per inch)."""
    return int(round(points * 12700))


@functools.lru_cache(maxsize=64)
def _axis_title(text: str) -> Title:
    """An axis title, made once per text: the same titles recur on every chart of a sheet (openpyxl builds
    each from text through a dozen validated objects); charts only read them."""
    return title_maker(text)


@functools.lru_cache(maxsize=64)
def _line(rgb: str, width_emu: int, dash: str | None) -> GraphicalProperties:
    """A series' line, made once per look and shared by the series that have it (read, never changed)."""
    return GraphicalProperties(ln=LineProperties(solidFill=rgb, w=width_emu, prstDash=dash))


@functools.lru_cache(maxsize=64)
def _marker(symbol: str | None, rgb: str) -> Marker:
    """A series' markers (``symbol`` None: none), made once per look and shared like _line."""
    if symbol is None:
        return Marker(symbol="none")
    return Marker(symbol=symbol, size=4, spPr=GraphicalProperties(solidFill=rgb,
                                                                  ln=LineProperties(solidFill=rgb, w=6350)))


def chart_title(text: str, size_pt: float = CHART_TITLE_PT) -> Title:
    """A bold chart title of ``size_pt`` points: a window's title (call sign, number, sensor pair, N) stays
    on one line above the plot instead of three at Excel's default 14 pt."""
    font = CharacterProperties(sz=int(size_pt * 100), b=True)
    paragraph = Paragraph(pPr=ParagraphProperties(defRPr=font), r=[RegularTextRun(rPr=font, t=text)])
    return Title(tx=ChartText(rich=RichText(p=[paragraph])), overlay=False)


def scatter_chart(title: str, x_title: str, y_title: str) -> ScatterChart:
    """An empty Excel scatter chart with its title, axis titles and the report's size and axes."""
    chart = ScatterChart()
    chart.title = chart_title(clean_text(title))
    chart.style = 2
    chart.width, chart.height = CHART_W_CM, CHART_H_CM
    chart.x_axis.title, chart.y_axis.title = _axis_title(x_title), _axis_title(y_title)
    chart.x_axis.delete = False  # openpyxl 3.1 hides axes unless told otherwise
    chart.y_axis.delete = False
    chart.x_axis.crosses = "min"  # axes on the lower-left edges, not through zero
    chart.y_axis.crosses = "min"
    chart.legend.position = "b"
    return chart


def xy_series(ws: WriteOnlyWorksheet, x_col: int, y_col: int, rows: tuple[int, int], title: str,
               line_rgb: str, *, dash: str | None = None, width_pt: float = 1.5,
               marker: str | None = None) -> Series:
    """A line series of sheet columns x_col / y_col over rows (first, last), drawn in line_rgb."""
    xs = Reference(ws, min_col=x_col, min_row=rows[0], max_row=rows[1])
    ys = Reference(ws, min_col=y_col, min_row=rows[0], max_row=rows[1])
    series = Series(ys, xs, title=title)
    series.graphicalProperties = _line(line_rgb, int(width_pt * 12700), dash)
    series.marker = _marker(marker, line_rgb)
    series.smooth = False
    return series


def axis_limits(values: Iterable[Any], pad: float = 0.05) -> tuple[float, float] | None:
    """Axis minimum and maximum padded by pad of the span of the finite numbers; None if there are none."""
    numbers = [v for v in values if is_number(v) and math.isfinite(v)]
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


def chart_sheet(wb: Workbook, title: str, heading: tuple[str, str], n_charts: int) -> WriteOnlyWorksheet:
    """A sheet for charts: column grid, two heading rows (repeated on every page), a page break every
    CHART_ROWS_PER_PAGE rows of charts."""
    ws = wb.create_sheet(title)
    for i in range(CHART_SLOT_COLS * CHARTS_PER_ROW):
        ws.column_dimensions[get_column_letter(i + 1)].width = CHART_COL_WIDTH
    page_setup(ws, f"1:{CHART_HEADING_ROWS}")
    fixed_rows(ws)
    ws.append([text_cell(ws, clean_text(heading[0]), font=TITLE_FONT)])
    ws.append([note_text_cell(ws, heading[1])])
    grid_rows = math.ceil(n_charts / CHARTS_PER_ROW)
    for page in range(1, math.ceil(grid_rows / CHART_ROWS_PER_PAGE)):
        ws.row_breaks.append(Break(id=CHART_HEADING_ROWS + page * CHART_ROWS_PER_PAGE * CHART_SLOT_ROWS))
    # rows under the charts exist (empty) so the print range covers every chart
    for _ in range(grid_rows * CHART_SLOT_ROWS):
        ws.append([])
    return ws



def window_id(window: WindowResult, index: int) -> Any:
    """The window's number as its summary gives it, else its position in the run."""
    value = excel_value(window.summary.get("window"))
    return index if value is None else value


def window_title(window: WindowResult, index: int) -> str:
    """Call sign (else address), window number and sensor pair (summary.window_label)."""
    return window_label({**window.summary, "window": window_id(window, index)})


def charted_windows(run: CorrelationRun, kind: str) -> list[int]:
    """Indices of the windows that get charts: the first MAX_CORRELATION_CHARTS with lags (``lags``) or
    the first MAX_SLOT_CHART_WINDOWS with slots (``slots``)."""
    if kind == "lags":
        return [i for i, w in enumerate(run.windows) if len(w.lags)][:MAX_CORRELATION_CHARTS]
    return [i for i, w in enumerate(run.windows) if len(w.slots)][:MAX_SLOT_CHART_WINDOWS]


def write_lag_charts(wb: Workbook, run: CorrelationRun, data_sheet: str = "Correlation",
                     frames: list[pd.DataFrame] | None = None, headers: list[str] | None = None) -> None:
    """One chart per window of coefficient against lag, |lag| <= N/2 only, on a page grid. ``frames``: each
    window's rows as ``data_sheet`` holds them, in order under ``headers`` (default: every lag of every
    window, CORRELATION_HEADERS)."""
    full = [lag_frame(w) for w in run.windows]
    where = "Correlation sheet" if frames is None else "the Parquet file the Correlation sheet names"
    frames = full if frames is None else frames
    charted = [i for i, f in enumerate(full) if len(f)]
    shown = charted[:MAX_CORRELATION_CHARTS]
    more = _first_of(len(shown), len(charted))
    heading = ("Coefficient against lag for |lag| <= N/2 (at least half the slots overlap)",
               f"Wider lags are left out (all lags: {where}). NCC solid, Pearson dashed; "
               f"latitude blue, longitude green{more}.")
    ws = chart_sheet(wb, "Lag charts", heading, len(shown))
    ref = _SheetRef(data_sheet)
    starts = np.concatenate([[2], 2 + np.cumsum([len(f) for f in frames])]).astype(int)
    col = {h: i + 1 for i, h in enumerate(headers or CORRELATION_HEADERS)}
    for n, i in enumerate(shown):
        w, lags = run.windows[i], frames[i]
        n_slots = (len(full[i]) + 1) // 2
        half = pearson_max_lag(n_slots)
        lag = pd.to_numeric(lags["lag"], errors="coerce").to_numpy(dtype=float)
        inside = np.flatnonzero(np.abs(lag) <= half)
        if inside.size == 0:
            continue
        first, last = int(starts[i] + inside[0]), int(starts[i] + inside[-1])
        if last > EXCEL_MAX_ROWS:
            break
        chart = scatter_chart(f"{window_title(w, i)}, N = {n_slots}", f"lag (slots, |lag| <= {half})",
                         "coefficient")
        values = []
        for name, rgb, dash, label in (("ncc_lat", LAT_RGB, None, "NCC lat"),
                                       ("ncc_lon", LON_RGB, None, "NCC lon"),
                                       ("pearson_lat", LAT_RGB, "dash", "Pearson lat"),
                                       ("pearson_lon", LON_RGB, "dash", "Pearson lon")):
            chart.series.append(xy_series(ref, col["lag"], col[name], (first, last), label, rgb, dash=dash,
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



def write_slot_charts(wb: Workbook, run: CorrelationRun, data_sheet: str = "Slots",
                      frames: list[pd.DataFrame] | None = None, headers: list[str] | None = None) -> None:
    """Two charts per window (latitude, longitude against time). ``frames``: each window's slots as
    ``data_sheet`` holds them, in order under ``headers`` (default: every slot of every window,
    SLOTS_HEADERS)."""
    frames = [w.slots for w in run.windows] if frames is None else frames
    lengths = [len(f) for f in frames]
    charted = [i for i, w in enumerate(run.windows) if len(w.slots)]
    shown = charted[:MAX_SLOT_CHART_WINDOWS]
    more = _first_of(len(shown), len(charted))
    tested, reference = pair_nouns(run.parameters.get("pairs"))
    heading = ("Slotted latitude and longitude against time (UTC)",
               f"{reference[:1].upper()}{reference[1:]} yellow (solid, wide), {tested} red (dashed, on top); "
               f"data on the {data_sheet} sheet{more}.")
    ws = chart_sheet(wb, "Slot charts", heading, 2 * len(shown))
    ref = _SheetRef(data_sheet)
    starts = np.concatenate([[2], 2 + np.cumsum(lengths)]).astype(int)
    col = {h: i + 1 for i, h in enumerate(headers or SLOTS_HEADERS)}
    dated = all("timestamp" in w.slots and w.slots["timestamp"].notna().all() for w in run.windows)
    for n, i in enumerate(shown):
        w, slots = run.windows[i], frames[i]
        first, last = int(starts[i]), int(starts[i + 1]) - 1
        if last > EXCEL_MAX_ROWS or last < first:
            break
        if dated:  # only the axis limits are needed: the first and last instant, converted as cells are
            stamps = slots["timestamp"]
            times = [to_excel(utc_naive(t)) for t in (stamps.min(), stamps.max())] if len(stamps) else []
        else:
            times = [v / 86400.0 for v in pd.to_numeric(slots["time_of_day"], errors="coerce").tolist()]
        x_span = axis_limits(times, pad=0.0)
        markers = len(slots) <= 40
        words = side_words(w.summary)  # "Surface radar" and "Multilateration" for --pairs smr-mlat
        for k, (axis, name) in enumerate((("lat", "latitude"), ("lon", "longitude"))):
            chart = scatter_chart(f"{window_title(w, i)}: {name}", "time (UTC)", f"{name} (deg)")
            # LibreOffice draws the first series on top: radar first, so the wide ADS-B line never hides it
            chart.series.append(xy_series(ref, col["time_utc"], col[f"radar_{axis}"], (first, last),
                                           words["radar"], RADAR_RGB, dash="dash", width_pt=1.5,
                                           marker="triangle" if markers else None))
            chart.series.append(xy_series(ref, col["time_utc"], col[f"adsb_{axis}"], (first, last),
                                           words["adsb"], ADSB_RGB, width_pt=3.0,
                                           marker="circle" if markers else None))
            chart.x_axis.number_format = "hh:mm"
            if x_span:
                chart.x_axis.scaling.min, chart.x_axis.scaling.max = x_span
                chart.x_axis.majorUnit = _time_step_days(x_span[1] - x_span[0])
            y_values = [*column_values(slots[f"radar_{axis}"]), *column_values(slots[f"adsb_{axis}"])]
            y_span = axis_limits(y_values)
            chart.y_axis.number_format = degree_format(y_span)
            if y_span:
                chart.y_axis.scaling.min, chart.y_axis.scaling.max = y_span
            ws.add_chart(chart, chart_anchor(2 * n + k, chart))


def degree_format(limits: tuple[float, float] | None) -> str:
    """A coordinate axis's number format with the decimals that tell its ticks apart (about five over the
    span): 0.00 deg for an airborne track, 0.0000 for an aircraft taxiing 300 m (0.00 printed 41.30 twice)."""
    span = (limits[1] - limits[0]) if limits else 0.0
    places = math.ceil(-math.log10(span / 5.0)) if span > 0 else 2
    return "0." + "0" * min(6, max(2, places))


def _time_step_days(span_days: float) -> float:
    """A round tick step (1 min .. 2 h) giving at most 6 ticks over ``span_days``."""
    for minutes in (1, 2, 5, 10, 15, 30, 60, 120):
        if span_days * 1440 / minutes <= 6:
            return minutes / 1440
    return 240 / 1440


