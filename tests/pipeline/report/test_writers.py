"""Report writers: Excel workbook, JSON summary, stdout table and PNG figures from a hand-built run."""

from __future__ import annotations

import datetime as dt
import json
import math
import zipfile
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from openpyxl import load_workbook

from msdc.pipeline.correlate.results import (
    MATCHED_KEYS,
    SLOT_COLUMNS,
    SUMMARY_KEYS,
    WINDOW_QUALITY_KEYS,
    CorrelationRun,
    SkippedWindow,
    WindowResult,
)
from msdc.pipeline.report.excel import sheet_name, write_report
from msdc.pipeline.report.figures import lag_figure, latlon_time_figure, track_figure
from msdc.pipeline.report.files import write_json
from msdc.pipeline.report.headers import column_name
from msdc.pipeline.report.summary import LEAD_WINDOW_KEYS, run_to_json, summary_table

# one worker runs the module: the outputs made once, not on each worker
pytestmark = pytest.mark.xdist_group("writers")

EVIL = "=cmd|' /C calc'!A0"
T0 = pd.Timestamp("2019-03-01 10:00:00.500", tz="UTC")
PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def _slots(n: int, t0: pd.Timestamp | None, lat0: float, lon0: float) -> pd.DataFrame:
    k = np.arange(n)
    tod = 36000.5 + 4.0 * k
    stamps = (pd.Series([t0 + pd.Timedelta(seconds=4 * i) for i in k]) if t0 is not None
              else pd.Series([pd.NaT] * n, dtype="datetime64[ns, UTC]"))
    frame = pd.DataFrame({
        "slot": k, "time_of_day": tod, "timestamp": stamps,
        "radar_lat": lat0 + 0.01 * k + 0.0004, "radar_lon": lon0 + 0.012 * k - 0.0003,
        "adsb_lat": lat0 + 0.01 * k, "adsb_lon": lon0 + 0.012 * k,
        "radar_count": np.ones(n, dtype=int), "adsb_count": np.full(n, 2),
        "radar_filled": np.zeros(n, dtype=bool), "adsb_filled": np.zeros(n, dtype=bool),
        "sep_m": np.linspace(40.0, 60.0, n),
    })
    return frame[SLOT_COLUMNS]


def _lags(lags: range) -> pd.DataFrame:
    x = np.array(list(lags), dtype=float)
    return pd.DataFrame({"lag": list(lags), "ncc_lat": 0.99998 - 1e-4 * x**2,
                         "ncc_lon": 0.99990 - 1e-4 * x**2, "pearson_lat": 0.98 - 0.05 * x**2,
                         "pearson_lon": 0.97 - 0.05 * np.abs(x)})


def _summary(**values: object) -> dict:
    summary = {key: math.nan for key in SUMMARY_KEYS}
    summary.update(values)
    return summary


@pytest.fixture(scope="module")
def run() -> CorrelationRun:
    slots1 = _slots(6, T0, 1.30, 103.90)
    slots1.loc[2, "radar_lat"] = math.nan
    slots1.loc[2, "radar_filled"] = True
    w1 = WindowResult(
        summary=_summary(callsign="SIA321", address="76CD01", window=0, start_tod=36000.5, end_tod=36020.5,
                         start=T0, end=T0 + pd.Timedelta(seconds=20), slots=6, radar_before=7, radar_after=5,
                         adsb_before=13, adsb_after=6, radar_duplicates=0, adsb_duplicates=1,
                         ncc0_lat=0.99998, ncc0_lon=0.9999, ncc_peak_lag_lat=0, ncc_peak_lag_lon=0,
                         pearson0_lat=0.98, pearson0_lon=0.97, pearson_peak_lag_lat=0, pearson_peak_lag_lon=0,
                         sep_mean_m=50.0, sep_rms_m=50.8, sep_p95_m=59.0, sep_max_m=60.0),
        slots=slots1, lags=_lags(range(-2, 3)))
    w2 = WindowResult(
        summary=_summary(callsign=EVIL, address="ABC123", window=1, start_tod=36100.0, end_tod=36112.0,
                         start=pd.NaT, end=None, slots=4, radar_before=4, radar_after=4, adsb_before=8,
                         adsb_after=4, ncc0_lat=np.float64(0.9991), ncc0_lon=0.9992, pearson0_lon=0.5,
                         ncc_peak_lag_lat=np.int64(1), sep_rms_m=np.float32(12.5)),
        slots=_slots(4, None, 1.40, 104.00), lags=_lags(range(-1, 2)))
    return CorrelationRun(
        windows=[w1, w2],
        skipped=[SkippedWindow("-1+1", "=HYPERLINK(\"http://x\")", 37000.0, 37010.0, "fewer than 10 slots")],
        parameters={"options": {"slot_s": 4.0, "max_lag": 2}, "editions": {"cat048": "1.23", "cat021": "2.1"},
                    "software_version": "0.1.0", "date": "2019-03-01",
                    "run_time": pd.Timestamp("2024-05-01 12:00:00", tz="UTC")},
        inputs=[{"path": "rec.ast", "sha256": "ab" * 32, "bytes": 12345, "format": "ast"}],
        filters={"ground": 3, "no_position": 0},
        extra_sheets={"Quality": pd.DataFrame({"sensor": ["radar", "adsb"], "score": [0.5, math.nan],
                                               "when": [T0, pd.NaT]})},
    )


@pytest.fixture(scope="module")
def outputs(run: CorrelationRun, tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    out = tmp_path_factory.mktemp("report")
    png = track_figure(run, out / "tracks.png")
    xlsx = out / "run.xlsx"
    write_report(run, xlsx, figure_png=png)
    return {"png": png, "xlsx": xlsx, "json": write_json(run_to_json(run), out / "run.json")}


def _header_index(row: tuple) -> dict[str, int]:
    """Column index by snake_case name of a header row (the workbook prints headers with units)."""
    return {column_name(c.value): c.column for c in row if c.value is not None}


def _block(ws, title_start: str) -> tuple[int, dict[str, int]]:
    """Row of a Summary block's header and its column index by key (headers.workbook_header's)."""
    row = next(c.row for c in ws["A"] if isinstance(c.value, str) and c.value.startswith(title_start))
    row = next(r for r in range(row + 1, row + 4) if ws.cell(r, 1).value in ("Aircraft", "Radar"))
    return row, _header_index(ws[row])


def test_sheets_headers_and_freeze(outputs: dict[str, Path]) -> None:
    wb = load_workbook(outputs["xlsx"])
    assert wb.sheetnames == ["Summary", "Map", "Lag charts", "Slot charts", "Correlation", "Slots", "Quality",
                             "Parameters"]
    summary = wb["Summary"]
    titles = [c.value for c in summary["A"] if isinstance(c.value, str) and c.font.b and " " in c.value]
    # the lead first (what each window shows, its verdicts), then the thesis's measures, each with its limit
    order = ["What each window shows: ", "Verdicts (", "The thesis's measures (", "Thesis table 6.1: ",
             "Thesis table 6.2: ", "Separation between the slot means, "]
    assert [next(i for i, t in enumerate(titles) if t.startswith(o)) for o in order] == sorted(
        next(i for i, t in enumerate(titles) if t.startswith(o)) for o in order)
    assert titles[1].startswith(order[0])
    keys = set()
    for start in ("What each window shows", "Thesis table 6.1", "Thesis table 6.2",
                  "Separation between the slot means"):
        row, col = _block(summary, start)
        # every block names its window: aircraft, number and sensor pair (numbers restart for every pair)
        assert list(col)[:5] == ["aircraft", "window", "sensors", "start", "end"]
        assert all(summary.cell(row, c).font.b for c in col.values())
        keys |= set(col)
    # clock times live in start/end, the sensor pair in "sensors"; the verdict has its own rows, and the
    # quality step's numbers a block of their own with --quality only
    # ... and the call sign in "aircraft" (else the address, which has its own column too)
    shown_apart = {"start_tod", "end_tod", "radar_sensor", "reference_sensor", "verdict", "callsign"}
    assert keys == (set(SUMMARY_KEYS) - shown_apart - set(WINDOW_QUALITY_KEYS)) | {"sensors", "aircraft"}
    assert summary.freeze_panes == "C2"
    assert [c.value for c in wb["Correlation"][1]][:11] == [
        "Window", "Call sign", "Address", "Radar sensor", "Reference sensor", "Lag (slots)", "Lag (s)",
        "NCC latitude", "NCC longitude", "Pearson latitude", "Pearson longitude"]
    assert wb["Correlation"].freeze_panes == "F2"
    slot_headers = _header_index(wb["Slots"][1])
    assert {"slot", "time_utc", "radar_lat", "adsb_lon", "radar_filled", "sep_m"} <= set(slot_headers)
    assert "time_of_day" not in slot_headers  # never seconds of day: time_utc carries the time
    assert [c.value for c in wb["Quality"][1]] == ["Sensor", "score", "when"]  # (no labels of their own)
    assert wb["Parameters"].freeze_panes == "A2"
    assert 6 <= summary.column_dimensions["A"].width <= 66


def test_values_numbers_datetimes_and_blanks(outputs: dict[str, Path]) -> None:
    wb = load_workbook(outputs["xlsx"])
    summary = wb["Summary"]
    row, col = _block(summary, "Thesis table 6.2")
    assert summary.cell(row + 1, col["ncc0_lat"]).value == 0.99998
    assert summary.cell(row + 1, col["ncc0_lat"]).data_type == "n"
    assert summary.cell(row + 2, col["pearson0_lat"]).value is None  # NaN
    assert summary.cell(row + 2, col["ncc_peak_lag_lat"]).value == 1
    row, col = _block(summary, "Thesis table 6.1")
    assert summary.cell(row + 1, col["radar_after"]).value == 5
    assert summary.cell(row + 1, col["start"]).value == dt.datetime(2019, 3, 1, 10, 0, 0, 500000)
    assert summary.cell(row + 1, col["start"]).number_format == 'yyyy-mm-dd hh:mm:ss "UTC"'
    assert summary.cell(row + 1, col["end"]).value == dt.datetime(2019, 3, 1, 10, 0, 20, 500000)
    # window 2 has no date: its start is the clock time of start_tod 36100 s = 10:01:40, never 36100
    assert summary.cell(row + 2, col["start"]).value == dt.timedelta(seconds=36100)
    assert summary.cell(row + 2, col["start"]).number_format == "[hh]:mm:ss.000"
    row, col = _block(summary, "Separation between the slot means")
    assert summary.cell(row + 2, col["sep_rms_m"]).value == 12.5

    slots = wb["Slots"]
    col = _header_index(slots[1])
    # window 2 has no timestamps, so the whole column is clock times (one format per column)
    assert slots.cell(2, col["time_utc"]).value == dt.timedelta(seconds=36000.5)
    assert slots.cell(3, col["time_utc"]).value == dt.timedelta(seconds=36004.5)
    assert slots.cell(4, col["radar_lat"]).value is None  # NaN slot
    assert slots.cell(4, col["radar_filled"]).value is True
    assert slots.cell(4, col["adsb_lat"]).value == pytest.approx(1.32)
    assert slots.cell(8, col["callsign"]).value == EVIL  # first slot of window 2
    assert slots.cell(8, col["time_utc"]).value == dt.timedelta(seconds=36000.5)

    corr = wb["Correlation"]
    col = _header_index(corr[1])
    assert corr.cell(2, col["lag"]).value == -2
    assert corr.cell(2, col["lag_s"]).value == -8.0
    assert corr.cell(4, col["ncc_lat"]).value == 0.99998

    quality = wb["Quality"]
    assert quality["C2"].value == dt.datetime(2019, 3, 1, 10, 0, 0, 500000)
    assert quality["B3"].value is None and quality["C3"].value is None

    params = {(r[0], r[1]): r[2] for r in wb["Parameters"].iter_rows(min_row=2, values_only=True)}
    assert params[("input 1", "sha256")] == "ab" * 32
    assert params[("input 1", "bytes")] == 12345
    assert params[("editions", "cat048")] == "1.23"
    assert params[("options", "slot_s")] == 4.0
    assert params[("parameters", "run_time")] == dt.datetime(2024, 5, 1, 12, 0)
    assert params[("parameters", "date")] == dt.datetime(2019, 3, 1)  # ISO date text -> Excel date
    assert params[("filters", "ground")] == 3


def test_dated_slots_are_utc_datetimes(run: CorrelationRun, tmp_path: Path) -> None:
    dated = CorrelationRun(windows=run.windows[:1], parameters=run.parameters)
    write_report(dated, tmp_path / "dated.xlsx")
    slots = load_workbook(tmp_path / "dated.xlsx")["Slots"]
    col = _header_index(slots[1])
    assert slots.cell(2, col["time_utc"]).value == dt.datetime(2019, 3, 1, 10, 0, 0, 500000)
    assert slots.cell(3, col["time_utc"]).value == dt.datetime(2019, 3, 1, 10, 0, 4, 500000)
    assert slots.cell(2, col["time_utc"]).number_format == "yyyy-mm-dd hh:mm:ss.000"


def test_number_formats_follow_units(outputs: dict[str, Path]) -> None:
    """Degrees to 4 decimals, coefficients to 6, metres to 1 (issue 9: one table of unit -> format)."""
    wb = load_workbook(outputs["xlsx"])
    slots = wb["Slots"]
    col = _header_index(slots[1])
    assert slots.cell(2, col["radar_lat"]).number_format == "0.0000"
    assert slots.cell(2, col["sep_m"]).number_format == "0.0"
    corr = wb["Correlation"]
    col = _header_index(corr[1])
    assert corr.cell(2, col["pearson_lat"]).number_format == "0.000000"
    assert corr.cell(2, col["ncc_lon"]).number_format == "0.000000"
    assert corr.cell(2, col["lag_s"]).number_format == "0.000"
    summary = wb["Summary"]
    row, col = _block(summary, "Separation between the slot means")
    assert summary.cell(row + 1, col["sep_mean_m"]).number_format == "0.0"


def test_quality_tables_formats(tmp_path: Path) -> None:
    """An azimuth bias of 0.0036 deg shows as 0.0036 (it printed 0.00), ppm to 0.1, seconds of day as
    times."""
    from msdc.pipeline.report.excel import write_tables

    biases = pd.DataFrame({"radar": ["R"], "azimuth_bias_deg": [0.0036], "range_gain_ppm": [-27.0021],
                           "range_bias_m": [6.26], "time_bias_s": [-0.0192], "gap_start_tod": [29401.25]})
    write_tables({"Radar biases": biases}, tmp_path / "q.xlsx")
    ws = load_workbook(tmp_path / "q.xlsx")["Radar biases"]
    col = _header_index(ws[1])
    assert ws.cell(2, col["azimuth_bias_deg"]).number_format == "0.0000"
    assert ws.cell(2, col["range_gain_ppm"]).number_format == "0.0"
    assert ws.cell(2, col["range_bias_m"]).number_format == "0.0"
    assert ws.cell(2, col["time_bias_s"]).number_format == "0.000"
    assert ws.cell(2, col["gap_start_tod"]).value == dt.timedelta(seconds=29401.25)  # 08:10:01.250
    assert ws.print_title_rows == "$1:$1" and ws.page_setup.orientation == "landscape"


def test_every_sheet_prints_landscape_fitted_with_titles(outputs: dict[str, Path]) -> None:
    wb = load_workbook(outputs["xlsx"])
    titles = {"Summary": "$1:$1", "Lag charts": "$1:$2", "Slot charts": "$1:$2", "Correlation": "$1:$1",
              "Slots": "$1:$1", "Quality": "$1:$1", "Parameters": "$1:$1", "Map": None}
    for ws in wb.worksheets:
        assert ws.page_setup.orientation == "landscape", ws.title
        assert ws.page_setup.paperSize == 9, ws.title  # A4
        assert ws.sheet_properties.pageSetUpPr.fitToPage, ws.title
        # every table here is short (at most SHORT_TABLE_ROWS rows): one page wide, the 17 Slots columns too
        assert ws.page_setup.fitToWidth == 1, ws.title
        assert ws.page_setup.fitToHeight == (1 if ws.title == "Map" else 0), ws.title
        assert ws.print_title_rows == titles[ws.title], ws.title


def _chart_boxes_cm(ws) -> list[tuple[float, float, float, float]]:
    """(left, top, right, bottom) of every chart in cm, from its absolute anchor (EMU, 360000 per cm)."""
    boxes = []
    for chart in ws._charts:
        pos, ext = chart.anchor.pos, chart.anchor.ext
        boxes.append((pos.x / 360000, pos.y / 360000, (pos.x + ext.width) / 360000,
                      (pos.y + ext.height) / 360000))
    return boxes


def _page_rows_cm(ws) -> float:
    return ws.sheet_format.defaultRowHeight / 72 * 2.54


def test_charts_on_their_own_grid(outputs: dict[str, Path]) -> None:
    """Charts on a grid of 2 across, none overlapping another, each inside the printable width of an A4
    landscape page and inside its grid slot; data sheets carry no chart."""
    from msdc.pipeline.report.charts import CHART_HEADING_ROWS, CHART_SLOT_ROWS

    wb = load_workbook(outputs["xlsx"])
    assert len(wb["Lag charts"]._charts) == 2
    assert len(wb["Slot charts"]._charts) == 4  # latitude and longitude for each window
    assert not wb["Correlation"]._charts and not wb["Slots"]._charts  # data sheets stay data
    for name in ("Lag charts", "Slot charts"):
        ws = wb[name]
        assert ws.sheet_format.customHeight and ws.sheet_format.defaultRowHeight == 15
        row_cm = _page_rows_cm(ws)
        boxes = _chart_boxes_cm(ws)
        for i, a in enumerate(boxes):
            for b in boxes[i + 1:]:
                assert a[2] <= b[0] or b[2] <= a[0] or a[3] <= b[1] or b[3] <= a[1], (name, a, b)
            assert a[0] >= 0 and a[2] <= 29.7 - 2 * 0.4 * 2.54  # inside the margins of landscape A4
            slot = int((a[1] / row_cm - CHART_HEADING_ROWS) // CHART_SLOT_ROWS)
            slot_top = (CHART_HEADING_ROWS + slot * CHART_SLOT_ROWS) * row_cm
            assert slot_top <= a[1] and a[3] <= slot_top + CHART_SLOT_ROWS * row_cm  # inside its slot
        lefts = sorted({round(b[0], 3) for b in boxes})
        assert len(lefts) == 2  # two columns of charts
    assert "Wider lags are left out" in wb["Lag charts"]["A2"].value


def test_page_breaks_fall_between_chart_rows(tmp_path: Path) -> None:
    """Seven windows: 7 lag charts, 4 rows of 2, 2 rows per page: one break, after the first page's
    charts, and no chart crosses it."""
    from msdc.pipeline.report.charts import CHART_HEADING_ROWS, CHART_ROWS_PER_PAGE, CHART_SLOT_ROWS

    windows = [WindowResult(summary=_summary(callsign=f"C{i}", window=1, slots=5),
                            slots=_slots(5, T0, 1.0, 100.0), lags=_lags(range(-4, 5))) for i in range(7)]
    write_report(CorrelationRun(windows=windows), tmp_path / "seven.xlsx")
    ws = load_workbook(tmp_path / "seven.xlsx")["Lag charts"]
    assert len(ws._charts) == 7
    breaks = [b.id for b in ws.row_breaks.brk]
    assert breaks == [CHART_HEADING_ROWS + CHART_ROWS_PER_PAGE * CHART_SLOT_ROWS]  # after row 32
    break_cm = breaks[0] * _page_rows_cm(ws)
    boxes = _chart_boxes_cm(ws)
    assert all(b[3] <= break_cm or b[1] >= break_cm for b in boxes)
    assert sum(b[3] <= break_cm for b in boxes) == 4  # the first page holds 2 x 2 charts
    # the page below the repeated heading rows is taller than its two chart rows
    page_cm = (21.0 - 2 * 0.5 * 2.54) - CHART_HEADING_ROWS * _page_rows_cm(ws)
    assert CHART_ROWS_PER_PAGE * CHART_SLOT_ROWS * _page_rows_cm(ws) < page_cm


def test_lag_charts_cover_half_the_lags(outputs: dict[str, Path]) -> None:
    """Window 1's lag table holds lags -2..2 (N = 3): its chart spans the rows of |lag| <= 1 only and its
    x axis is fixed to +-1."""
    wb = load_workbook(outputs["xlsx"])
    chart = wb["Lag charts"]._charts[0]
    assert chart.x_axis.scaling.min == -1 and chart.x_axis.scaling.max == 1  # N = 3, N // 2 = 1
    refs = {s.xVal.numRef.f for s in chart.series}
    assert refs == {"'Correlation'!$F$3:$F$5"}  # lags -1, 0, 1 of window 1 (rows 2..6 hold -2..2)
    assert all(s.marker is not None and s.marker.symbol is None for s in chart.series)  # symbol "none"


def test_formula_looking_text_stays_text(outputs: dict[str, Path]) -> None:
    wb = load_workbook(outputs["xlsx"])
    summary = wb["Summary"]
    row, _ = _block(summary, "Thesis table 6.1")
    evil = summary.cell(row + 2, 1)
    assert evil.value == EVIL and evil.data_type == "s"
    assert evil.quotePrefix  # Excel keeps it text even when the cell is edited
    rows = list(summary.iter_rows())
    skip_header = next(i for i, r in enumerate(rows) if r[0].value == "Skipped windows (1)")
    skipped = rows[skip_header + 2]
    assert skipped[0].value == "-1+1" and skipped[0].data_type == "s" and skipped[0].quotePrefix
    assert skipped[1].value == "=HYPERLINK(\"http://x\")" and skipped[1].data_type == "s"
    assert skipped[5].value == "fewer than 10 slots"
    corr = wb["Correlation"]
    assert any(c.value == EVIL and c.data_type == "s" and c.quotePrefix for c in corr["B"])
    with zipfile.ZipFile(outputs["xlsx"]) as zf:
        sheets = [n for n in zf.namelist() if n.startswith("xl/worksheets/sheet")]
        assert sheets
        for name in sheets:
            xml = zf.read(name).decode("utf-8")
            assert "<f>" not in xml and "<f " not in xml


def test_map_image(outputs: dict[str, Path]) -> None:
    assert len(load_workbook(outputs["xlsx"])["Map"]._images) == 1


def test_without_figure_there_is_no_map(run: CorrelationRun, tmp_path: Path) -> None:
    write_report(run, tmp_path / "plain.xlsx")
    assert "Map" not in load_workbook(tmp_path / "plain.xlsx").sheetnames


def test_json_round_trip(outputs: dict[str, Path]) -> None:
    with open(outputs["json"], encoding="utf-8") as fh:
        data = json.load(fh)
    # the lead first
    assert list(data) == ["summary", "windows", "skipped", "parameters", "inputs", "filters"]
    lead = data["summary"]
    assert lead["about"].startswith("What each window shows: every radar report against the reference's")
    assert list(lead["windows"][0]) == [*LEAD_WINDOW_KEYS[:7], *MATCHED_KEYS, "verdict"]  # no --quality keys
    assert lead["radars"] == [] and list(lead["thesis_measures"]) == ["counts", "coefficients", "separation"]
    assert lead["thesis_measures"]["coefficients"].startswith("Thesis table 6.2: r(0) by NCC")
    assert [list(w) for w in data["windows"]] == [[*SUMMARY_KEYS, "note"]] * 2
    first, second = data["windows"]
    assert first["ncc0_lat"] == 0.99998 and first["radar_after"] == 5
    assert first["start"] == "2019-03-01T10:00:00.500Z" and first["end"] == "2019-03-01T10:00:20.500Z"
    assert second["pearson0_lat"] is None and second["start"] is None and second["end"] is None
    assert second["callsign"] == EVIL and second["ncc_peak_lag_lat"] == 1
    assert data["skipped"] == [{"callsign": "-1+1", "address": "=HYPERLINK(\"http://x\")",
                                "radar_sensor": "", "reference_sensor": "", "start_tod": 37000.0,
                                "end_tod": 37010.0, "reason": "fewer than 10 slots"}]
    assert data["parameters"]["run_time"] == "2024-05-01T12:00:00.000Z"  # every time to the millisecond
    assert data["inputs"][0]["bytes"] == 12345 and data["filters"]["ground"] == 3


def test_run_to_json_is_strict_json(run: CorrelationRun) -> None:
    json.dumps(run_to_json(run), allow_nan=False)


def test_summary_table(run: CorrelationRun) -> None:
    text = summary_table(run)
    lead = text.splitlines()
    # the lead: what the numbers are, header, rule, windows, a verdict per window, a blank line
    assert lead[0].startswith("What each window shows: ") and lead[1].split()[:6] == [
        "call", "sign", "win", "sensors", "start", "(UTC)"]
    assert "reports" in lead[1] and "RMS m" in lead[1] and "range SD m" not in lead[1]  # no --quality
    assert [line.split(":")[0] for line in lead[5:7]] == ["Verdict", "Verdict"] and lead[7] == ""
    assert lead[8] == "The thesis's measures (kept as the thesis computes them; each with its limit):"
    limits = [line for line in lead if line.startswith("  Thesis table") or line.startswith("  Separation")]
    assert len(limits) == 3
    lines = [line for line in lead[9:] if line not in limits]
    # header, rule, windows, count, one skipped window, what the separations are taken over
    assert len(lines) == 2 + len(run.windows) + 3
    assert lines[0].split()[:6] == ["call", "sign", "win", "sensors", "start", "(UTC)"]
    assert "SIA321" in lines[2] and "0.999980" in lines[2] and "0.9999800000" not in lines[2]  # 6 decimals
    assert "50.8" in lines[2] and "2019-03-01 10:00:00" in lines[2] and " 10:00:20 " in lines[2]
    assert EVIL in lines[3] and "10:01:40" in lines[3] and "36100" not in lines[3]  # clock time, undated
    assert "1 skipped" in lines[4]
    assert lines[5] == "  skipped -1+1 10:16:40-10:16:50: fewer than 10 slots"
    assert lines[6].startswith("sep: ") and "both sensors reported" in lines[6]


def _assert_png(path: Path, min_bytes: int = 10_000) -> None:
    data = path.read_bytes()
    assert data[:8] == PNG_MAGIC and len(data) > min_bytes


def test_figures_are_png(run: CorrelationRun, outputs: dict[str, Path], tmp_path: Path) -> None:
    _assert_png(outputs["png"], 30_000)
    _assert_png(lag_figure(run.windows[0], tmp_path / "lag.png"))
    _assert_png(latlon_time_figure(run.windows[0], tmp_path / "t0.png"))
    _assert_png(latlon_time_figure(run.windows[1], tmp_path / "t1.png"))  # time-of-day axis


def test_empty_run(tmp_path: Path) -> None:
    empty = CorrelationRun()
    png = track_figure(empty, tmp_path / "empty.png")
    write_report(empty, tmp_path / "empty.xlsx", figure_png=png)
    wb = load_workbook(tmp_path / "empty.xlsx")
    assert wb.sheetnames == ["Summary", "Map", "Lag charts", "Slot charts", "Correlation", "Slots",
                             "Parameters"]
    assert any(c.value == "Skipped windows (0)" for c in wb["Summary"]["A"])
    assert run_to_json(empty)["windows"] == []
    assert summary_table(empty).splitlines()[-1] == "0 window(s) correlated, 0 skipped"


def test_sheet_names_are_valid_and_unique() -> None:
    taken = {"summary", "slots"}
    assert sheet_name("Slots", taken) == "Slots (2)"
    assert sheet_name("Radar accuracy [m]: a/b?", taken) == "Radar accuracy _m__ a_b_"
    assert len(sheet_name("x" * 40, taken)) == 31
    assert sheet_name("history", taken) == "History_"


def test_summary_clock_text():
    from msdc.pipeline.report.summary import clock_text

    # undated: HH:MM:SS of the time of day (seconds cut, not rounded), +Nd past the first day
    assert clock_text(None, 59.96) == "00:00:59"
    assert clock_text(None, 86400 + 3661.04) == "01:01:01+1d"
    assert clock_text(None, 28802.984375) == "08:00:02"
    assert clock_text(None, None) == "-"
    # dated: the UTC date-time wins over the time of day
    assert clock_text("2019-03-01T08:00:02.984Z", 28802.984) == "2019-03-01 08:00:02"
    assert clock_text(pd.Timestamp("2019-03-02 00:00:01", tz="UTC"), None, date=False) == "00:00:01"


def test_wide_tables_span_pages_with_identity_repeated(tmp_path: Path) -> None:
    """29 columns, 27 of them 22 characters wide (header + 2), are over 600 characters: far more than one
    legible landscape page (170), so the sheet is fitted to the cap of 3 pages wide and repeats its leading
    text columns (call sign, address) on each; a narrow sheet stays one page wide."""
    from msdc.pipeline.report.excel import write_tables

    wide = pd.DataFrame({"callsign": ["MAS72"], "address": ["750312"],
                         **{f"interval_{i:02d}_median_s": [4.8] for i in range(27)}})
    narrow = pd.DataFrame({"callsign": ["MAS72"], "interval_median_s": [4.8]})
    write_tables({"Quality": wide, "Small": narrow}, tmp_path / "wide.xlsx")
    wb = load_workbook(tmp_path / "wide.xlsx")
    assert wb["Quality"].page_setup.fitToWidth == 3 and wb["Quality"].print_title_cols == "$A:$B"
    assert wb["Small"].page_setup.fitToWidth == 1 and wb["Small"].print_title_cols is None


def test_a_short_wide_table_prints_one_page_wide_and_a_long_one_across_pages(tmp_path: Path) -> None:
    """A call sign (7 characters: MAS72 and 2) and 10 columns of 20 (18 and 2) are 207 wide: over a legible
    page of 170 and its slack (187), under 1.5 pages (255). One row prints on one page wide, smaller,
    rather than a few columns a page; 41 rows (over SHORT_TABLE_ROWS = 40) print 2 wide with the leading
    text columns (3 at most) on each, the two halves of a band of rows on consecutive pages."""
    from msdc.pipeline.report.excel import write_tables

    def table(rows: int) -> pd.DataFrame:
        return pd.DataFrame({"callsign": ["MAS72"] * rows, **{f"c{i}": ["x" * 18] * rows for i in range(10)}})

    write_tables({"Short": table(1), "Long": table(41)}, tmp_path / "t.xlsx")
    wb = load_workbook(tmp_path / "t.xlsx")
    assert sum(wb["Short"].column_dimensions[c].width for c in "ABCDEFGHIJK") == 207.0
    assert wb["Short"].page_setup.fitToWidth == 1 and wb["Short"].print_title_cols is None
    assert wb["Long"].page_setup.fitToWidth == 2 and wb["Long"].print_title_cols == "$A:$C"
    assert wb["Long"].page_setup.pageOrder == "overThenDown"  # a band of rows across its 2 pages, then on


def test_window_start_is_a_utc_date_in_the_workbook(tmp_path: Path) -> None:
    """On the fixtures, MAS72's first window starts where the simulator's truth says (its first overlap of
    radar and ADS-B reports, ToD to one LSB): the workbook cell read back is that UTC date-time, a real
    Excel date labelled UTC, and the JSON keeps ISO text."""
    from msdc.pipeline.jobs import correlate

    root = Path(__file__).resolve().parents[3]
    truth = json.loads((root / "fixtures" / "truth.json").read_text())
    first = min((w for w in truth["overlap_windows"] if w["callsign"] == "MAS72"), key=lambda w: w["start_s"])
    want = dt.datetime(2019, 3, 1) + dt.timedelta(seconds=first["start_s"])  # truth: UTC s since midnight
    result = correlate.correlate_job(correlate.CorrelateOptions(
        inputs=(str(root / "fixtures" / "radar.ast"), str(root / "fixtures" / "adsb.ast")),
        sensors=str(root / "fixtures" / "sensors.toml"), callsign="MAS72", date=dt.date(2019, 3, 1)))
    write_report(result.run, tmp_path / "r.xlsx")
    summary = load_workbook(tmp_path / "r.xlsx")["Summary"]
    row, col = _block(summary, "Thesis table 6.1")
    cell = summary.cell(row + 1, col["start"])
    assert isinstance(cell.value, dt.datetime) and cell.is_date
    assert abs((cell.value - want).total_seconds()) <= 1 / 128
    assert cell.number_format.endswith('"UTC"')
    text = run_to_json(result.run)["windows"][0]["start"]
    assert text.endswith("Z") and abs(pd.Timestamp(text).tz_localize(None) - want).total_seconds() <= 1 / 128


def test_text_that_looks_like_a_date_stays_text() -> None:
    """Times reach the workbook as datetimes; text is never parsed back into a date (a call sign, file name
    or parameter that happens to read as ISO 8601 stays what it was)."""
    from msdc.pipeline.report.cells import excel_value

    assert excel_value("2019-03-01T10:00:20.500Z") == "2019-03-01T10:00:20.500Z"
    assert excel_value("2024-05-01") == "2024-05-01"
    assert excel_value(T0) == dt.datetime(2019, 3, 1, 10, 0, 0, 500000)


def test_plain_tables_parameters_have_no_correlation_window_rows(tmp_path):
    # the quality workbook's Parameters: its own parameters, not the correlation report's window counts
    from openpyxl import load_workbook

    from msdc.pipeline.report.excel import write_tables

    write_tables({"T": pd.DataFrame({"a": [1, 2]})}, tmp_path / "q.xlsx", parameters={"gap_s": 180})
    rows = list(load_workbook(tmp_path / "q.xlsx")["Parameters"].iter_rows(min_row=2, values_only=True))
    assert [r[:3] for r in rows] == [("parameters", "gap_s", 180)]


def test_every_boolean_reads_true_or_false(outputs: dict[str, Path]) -> None:
    """LibreOffice showed unstyled boolean cells as 0/1 or TRUE/FALSE depending on their neighbours (both
    in one Summary row): every boolean, in the Summary's blocks and the Slots sheet's streamed rows alike,
    carries the format that reads TRUE or FALSE."""
    from msdc.pipeline.report.rows import BOOL_FORMAT

    wb = load_workbook(outputs["xlsx"])
    flags = [c for name in ("Summary", "Slots") for row in wb[name].iter_rows() for c in row
             if c.data_type == "b"]
    assert len([c for c in flags if c.parent.title == "Slots"]) == 2 * (6 + 4)  # radar/adsb filled per slot
    assert flags and all(c.number_format == BOOL_FORMAT for c in flags)


def test_quality_numbers_lead_the_summary(run: CorrelationRun, tmp_path: Path) -> None:
    """With --quality (a radar's accuracy and biases, the radar's errors in each window) the lead block
    gains the window's range and azimuth errors, a block of radars follows the verdicts with each radar's
    note under it, and the JSON's summary carries both; the terminal adds both tables."""
    radar = {"radar": "KLIA MSSR", "radar_sensor": "048:25/201", "n_reports": 2922,
             "horizontal_error_rms_m": 275.3, "range_error_std_m": 70.4, "azimuth_error_std_deg": 0.079,
             "range_bias_m": 6.3, "range_bias_se_m": 4.3, "range_gain_ppm": -27.0, "range_gain_se_ppm": 22.4,
             "azimuth_bias_deg": 0.0036, "azimuth_bias_se_deg": 0.0015, "time_bias_s": -0.019,
             "time_bias_se_s": 0.015, "note": "the standard errors rest on 5 aircraft"}
    windows = [WindowResult({**w.summary, "quality_reports": 7, "range_error_mean_m": 2.5,
                             "range_error_std_m": 66.0, "azimuth_error_mean_deg": -0.01,
                             "azimuth_error_std_deg": 0.08, "matched_reports": 7, "matched_sep_rms_m": 250.7,
                             "verdict": "no verdict: 7 radar reports matched"}, w.slots, w.lags)
               for w in run.windows]
    quality = CorrelationRun(windows=windows, parameters=run.parameters, radars=[radar])
    write_report(quality, tmp_path / "q.xlsx")
    summary = load_workbook(tmp_path / "q.xlsx")["Summary"]
    row, col = _block(summary, "What each window shows")
    assert list(col)[-5:] == WINDOW_QUALITY_KEYS
    # quality_reports counts the radar reports compared with ADS-B, as the Radar biases sheet's count
    assert summary.cell(row, col["quality_reports"]).value == "Reports compared with ADS-B"
    assert summary.cell(row + 1, col["range_error_std_m"]).value == 66.0
    assert summary.cell(row + 1, col["matched_sep_rms_m"]).value == 250.7
    verdicts = next(c.row for c in summary["A"] if c.value == "Verdicts (2)")
    assert summary.cell(verdicts + 1, 5).value == "no verdict: 7 radar reports matched"
    row, col = _block(summary, "Radars against ADS-B over the run")
    assert summary.cell(row + 1, col["range_bias_m"]).value == 6.3 and "note" not in col
    assert summary.cell(row + 3, 1).value == "KLIA MSSR: the standard errors rest on 5 aircraft"
    lead = run_to_json(quality)["summary"]
    assert list(lead["windows"][0])[-6:] == [*WINDOW_QUALITY_KEYS, "verdict"]
    assert lead["radars"][0]["time_bias_s"] == -0.019
    text = summary_table(quality)
    assert "range SD m" in text and "KLIA MSSR  048:25/201" in text and "6.3 +- 4.3" in text


def test_a_window_of_an_aircraft_without_a_call_sign_is_named_by_its_address(tmp_path) -> None:
    """Two LEBL vehicles without call signs were two rows of blank call sign in the Summary's blocks and its
    Verdicts; their Aircraft cell is the address, as the terminal names them."""
    from msdc.pipeline.correlate.results import CorrelationRun, WindowResult

    def window(callsign, address, number):
        summary = {"callsign": callsign, "address": address, "window": number,
                   "radar_sensor": "010:0/107:mlat", "reference_sensor": "021:0/107",
                   "verdict": f"verdict {number}"}
        return WindowResult(summary, pd.DataFrame(), pd.DataFrame())

    run = CorrelationRun(windows=[window(None, "4CA1C3", 1), window("AFL2513", "4242AA", 2)])
    write_report(run, tmp_path / "r.xlsx")
    ws = load_workbook(tmp_path / "r.xlsx")["Summary"]
    row, col = _block(ws, "What each window shows")
    assert [ws.cell(row + k, col["aircraft"]).value for k in (1, 2)] == ["4CA1C3", "AFL2513"]
    verdicts = next(c.row for c in ws["A"] if isinstance(c.value, str) and c.value.startswith("Verdicts ("))
    assert [ws.cell(verdicts + k, 1).value for k in (1, 2)] == ["4CA1C3", "AFL2513"]


def test_headers_titles_and_notes_print_in_the_cells_face(outputs: dict[str, Path]) -> None:
    """A bold or italic font without a name printed in LibreOffice's default serif face, headers and notes
    unlike the cells under them: every styled cell names the face the workbook's plain cells have."""
    wb = load_workbook(outputs["xlsx"])
    plain = wb["Correlation"].cell(2, 1).font.name  # a number cell, in the workbook's default face
    styled = [(ws.title, c.coordinate, c.font.name) for ws in wb.worksheets for row in ws.iter_rows()
              for c in row if c.value is not None and (c.font.b or c.font.i)]
    assert len(styled) > 50 and {name for *_, name in styled} == {plain}, styled[:5]
