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

from pipeline.correlate.results import SLOT_COLUMNS, SUMMARY_KEYS, CorrelationRun, SkippedWindow, WindowResult
from pipeline.report.excel import sheet_name, write_report
from pipeline.report.figures import lag_figure, latlon_time_figure, track_figure
from pipeline.report.summary import run_to_json, summary_table, write_json

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
                         start=T0, end="2019-03-01T10:00:20.500Z", slots=6, radar_before=7, radar_after=5,
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
    return {"png": png, "xlsx": xlsx, "json": write_json(run, out / "run.json")}


def _header_index(row: tuple) -> dict[str, int]:
    return {c.value: c.column for c in row if c.value is not None}


def test_sheets_headers_and_freeze(outputs: dict[str, Path]) -> None:
    wb = load_workbook(outputs["xlsx"])
    assert wb.sheetnames == ["Summary", "Map", "Correlation", "Slots", "Quality", "Parameters"]
    summary = wb["Summary"]
    groups = [c.value for c in summary[1] if c.value]
    assert groups == ["Window", "Table 6.1 counts", "Table 6.2 coefficients", "Added measures"]
    headers = [c.value for c in summary[2]]
    assert sorted(headers) == sorted(SUMMARY_KEYS)
    assert headers[10:16] == [
        "radar_before", "radar_after", "adsb_before", "adsb_after", "ncc0_lat", "ncc0_lon"]
    assert all(c.font.b for c in summary[2])
    assert summary.freeze_panes == "C3"
    assert [c.value for c in wb["Correlation"][1]][:9] == [
        "window", "callsign", "address", "lag", "lag_s", "ncc_lat", "ncc_lon", "pearson_lat", "pearson_lon"]
    assert wb["Correlation"].freeze_panes == "D2"
    slot_headers = _header_index(wb["Slots"][1])
    expected = {"slot", "time_utc", "time_of_day", "radar_lat", "adsb_lon", "radar_filled", "sep_m"}
    assert expected <= set(slot_headers)
    assert [c.value for c in wb["Quality"][1]] == ["sensor", "score", "when"]
    assert wb["Parameters"].freeze_panes == "A2"
    assert 6 <= summary.column_dimensions["A"].width <= 66


def test_values_numbers_datetimes_and_blanks(outputs: dict[str, Path]) -> None:
    wb = load_workbook(outputs["xlsx"])
    summary = wb["Summary"]
    col = _header_index(summary[2])
    assert summary.cell(3, col["ncc0_lat"]).value == 0.99998
    assert summary.cell(3, col["ncc0_lat"]).data_type == "n"
    assert summary.cell(3, col["radar_after"]).value == 5
    assert summary.cell(3, col["start"]).value == dt.datetime(2019, 3, 1, 10, 0, 0, 500000)
    assert summary.cell(3, col["start"]).number_format == "yyyy-mm-dd hh:mm:ss.000"
    assert summary.cell(3, col["end"]).value == dt.datetime(2019, 3, 1, 10, 0, 20, 500000)  # ISO text in
    assert summary.cell(4, col["start"]).value is None  # NaT
    assert summary.cell(4, col["pearson0_lat"]).value is None  # NaN
    assert summary.cell(4, col["sep_rms_m"]).value == 12.5
    assert summary.cell(4, col["ncc_peak_lag_lat"]).value == 1

    slots = wb["Slots"]
    col = _header_index(slots[1])
    assert slots.cell(2, col["time_utc"]).value == dt.datetime(2019, 3, 1, 10, 0, 0, 500000)
    assert slots.cell(3, col["time_utc"]).value == dt.datetime(2019, 3, 1, 10, 0, 4, 500000)
    assert slots.cell(2, col["time_of_day"]).value == 36000.5
    assert slots.cell(4, col["radar_lat"]).value is None  # NaN slot
    assert slots.cell(4, col["radar_filled"]).value is True
    assert slots.cell(4, col["adsb_lat"]).value == pytest.approx(1.32)
    assert slots.cell(8, col["callsign"]).value == EVIL  # first slot of window 2
    assert slots.cell(8, col["time_utc"]).value is None  # timestamps unknown
    assert slots.cell(8, col["time_of_day"]).value == 36000.5

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


def test_formula_looking_text_stays_text(outputs: dict[str, Path]) -> None:
    wb = load_workbook(outputs["xlsx"])
    summary = wb["Summary"]
    assert summary["A4"].value == EVIL and summary["A4"].data_type == "s"
    assert summary["A4"].quotePrefix  # Excel keeps it text even when the cell is edited
    rows = list(summary.iter_rows())
    skip_header = next(i for i, r in enumerate(rows) if r[0].value == "Skipped windows (1)")
    skipped = rows[skip_header + 2]
    assert skipped[0].value == "-1+1" and skipped[0].data_type == "s"
    assert skipped[1].value == "=HYPERLINK(\"http://x\")" and skipped[1].data_type == "s"
    assert skipped[4].value == "fewer than 10 slots"
    corr = wb["Correlation"]
    assert any(c.value == EVIL and c.data_type == "s" for c in corr["B"])
    with zipfile.ZipFile(outputs["xlsx"]) as zf:
        sheets = [n for n in zf.namelist() if n.startswith("xl/worksheets/sheet")]
        assert sheets
        for name in sheets:
            xml = zf.read(name).decode("utf-8")
            assert "<f>" not in xml and "<f " not in xml


def test_charts_and_image(outputs: dict[str, Path]) -> None:
    wb = load_workbook(outputs["xlsx"])
    assert len(wb["Correlation"]._charts) == 2
    assert len(wb["Slots"]._charts) == 4  # latitude and longitude for each window
    assert len(wb["Map"]._images) == 1
    assert "NCC solid" in str(wb["Correlation"].cell(1, 11).value)


def test_without_figure_there_is_no_map(run: CorrelationRun, tmp_path: Path) -> None:
    write_report(run, tmp_path / "plain.xlsx")
    assert "Map" not in load_workbook(tmp_path / "plain.xlsx").sheetnames


def test_json_round_trip(outputs: dict[str, Path]) -> None:
    with open(outputs["json"], encoding="utf-8") as fh:
        data = json.load(fh)
    assert set(data) == {"windows", "skipped", "parameters", "inputs", "filters"}
    assert [list(w) for w in data["windows"]] == [SUMMARY_KEYS, SUMMARY_KEYS]
    first, second = data["windows"]
    assert first["ncc0_lat"] == 0.99998 and first["radar_after"] == 5
    assert first["start"] == "2019-03-01T10:00:00.500000Z" and first["end"] == "2019-03-01T10:00:20.500Z"
    assert second["pearson0_lat"] is None and second["start"] is None and second["end"] is None
    assert second["callsign"] == EVIL and second["ncc_peak_lag_lat"] == 1
    assert data["skipped"] == [{"callsign": "-1+1", "address": "=HYPERLINK(\"http://x\")",
                                "start_tod": 37000.0, "end_tod": 37010.0, "reason": "fewer than 10 slots"}]
    assert data["parameters"]["run_time"] == "2024-05-01T12:00:00Z"
    assert data["inputs"][0]["bytes"] == 12345 and data["filters"]["ground"] == 3


def test_run_to_json_is_strict_json(run: CorrelationRun) -> None:
    json.dumps(run_to_json(run), allow_nan=False)


def test_summary_table(run: CorrelationRun) -> None:
    text = summary_table(run)
    lines = text.splitlines()
    assert len(lines) == 2 + len(run.windows) + 1
    assert lines[0].split()[:4] == ["callsign", "window", "sensors", "start"]
    assert "SIA321" in lines[2] and "0.9999800000" in lines[2]
    assert "50.8" in lines[2] and "10:00:00.5" in lines[2]
    assert EVIL in lines[3] and "-" in lines[3].split()
    assert "1 skipped" in lines[-1]


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
    assert wb.sheetnames == ["Summary", "Map", "Correlation", "Slots", "Parameters"]
    assert wb["Summary"]["A4"].value == "Skipped windows (0)"
    assert run_to_json(empty)["windows"] == []
    assert summary_table(empty).splitlines()[-1] == "0 window(s) correlated, 0 skipped"


def test_sheet_names_are_valid_and_unique() -> None:
    taken = {"summary", "slots"}
    assert sheet_name("Slots", taken) == "Slots (2)"
    assert sheet_name("Radar accuracy [m]: a/b?", taken) == "Radar accuracy _m__ a_b_"
    assert len(sheet_name("x" * 40, taken)) == 31
    assert sheet_name("history", taken) == "History_"


def test_summary_clock_rounds_whole_time():
    from pipeline.report.summary import _clock

    # 59.96 s rounds to 00:01:00.0 (not 00:00:60.0); 86400 + 3661.04 s is 01:01:01.0 on the next day
    assert _clock(None, 59.96) == "00:01:00.0"
    assert _clock(None, 86400 + 3661.04) == "01:01:01.0+1d"
    assert _clock(None, 28802.984375) == "08:00:03.0"
    assert _clock(None, None) == "-"
