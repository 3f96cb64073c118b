"""The conflict alert figure's PC panel (gaps drawn as gaps, the time range fitted to the pair's samples) and
the conflicts workbook's cells (UTC labelled, seconds as given, an empty table on one page)."""

import numpy as np
import pandas as pd

from msdc.pipeline.report.conflict_figures import pc_line, pc_window
from msdc.pipeline.report.headers import column_name

T0 = pd.Timestamp("2016-05-10 22:04:25", tz="UTC")


def at(*seconds):
    return pd.Series([T0 + pd.Timedelta(seconds=s) for s in seconds])


def test_pc_line_breaks_where_a_sample_is_missing():
    # samples at 0, 5, 10 s, then 100 s and 195-200 s (the 120 s horizon of 344548/4CA5F7 on the real
    # ADS-B recording: the predicted levels 975 ft or more apart in between, so no PC there)
    t, v = pc_line(at(0, 5, 10, 100, 195, 200), [0.1, 0.2, 0.3, 0.34, 0.24, 0.21], 5.0)
    assert np.isnan(v).tolist() == [False, False, False, True, False, True, False, False]
    assert np.isnat(t).tolist() == np.isnan(v).tolist()
    assert v[~np.isnan(v)].tolist() == [0.1, 0.2, 0.3, 0.34, 0.24, 0.21]
    assert len(pc_line(at(0, 5, 10), [0.5] * 3, 5.0)[1]) == 3  # no gap: nothing added


def test_pc_window_fits_the_samples_not_the_whole_map_window():
    alert = pd.Series({"start": T0 + pd.Timedelta(seconds=80), "end": T0 + pd.Timedelta(seconds=85),
                       "loss_start": T0 + pd.Timedelta(seconds=80)})
    t0, t1 = T0 - pd.Timedelta(seconds=40), T0 + pd.Timedelta(seconds=205)  # 120 s before, 120 s after
    lo, hi = pc_window(at(80, 85), alert, 5.0, t0, t1)
    assert (lo, hi) == (T0 + pd.Timedelta(seconds=75), T0 + pd.Timedelta(seconds=90))  # a step either side
    lo, hi = pc_window(at(0, 200), alert, 5.0, t0, t1)  # 200 s of samples: 10 s (5 %) either side, clipped
    assert (lo, hi) == (T0 - pd.Timedelta(seconds=10), t1)


def test_conflict_workbook_labels_utc_and_shows_seconds_as_given(tmp_path):
    from openpyxl import load_workbook

    from msdc.pipeline.conflict.events import ALERT_COLUMNS, LOSS_COLUMNS, WARNING_COLUMNS
    from msdc.pipeline.report.conflict_excel import write_conflict_workbook

    losses = pd.DataFrame({"aircraft_a": ["A"], "aircraft_b": ["B"], "start": at(100), "end": at(130),
                           "duration_s": [30.0], "began_inside": [False], "min_horizontal_nm": [2.0],
                           "time_of_min": at(110),
                           "vertical_at_min_ft": [500.0], "min_vertical_ft": [400.0]})[LOSS_COLUMNS]
    warnings = pd.DataFrame({"aircraft_a": ["A", "A"], "aircraft_b": ["B", "B"], "loss_start": at(100, 100),
                             "horizon_s": [20.0, 120.0], "alert_start": at(97.5, 100),
                             "warning_s": [2.5, 0.0]})[WARNING_COLUMNS]
    alerts = pd.DataFrame({c: pd.Series(dtype="datetime64[ns, UTC]" if c in ("start", "end", "time_of_peak")
                                        else float) for c in ALERT_COLUMNS})
    path = tmp_path / "c.xlsx"
    parameters = {"step_s": 5.0, "run_utc": "2026-11-23T16:49:34Z"}
    write_conflict_workbook(alerts, losses, warnings, parameters, path)
    wb = load_workbook(path)
    ws = wb["Losses"]
    fmt = {column_name(ws.cell(1, j).value): ws.cell(2, j).number_format for j in range(1, ws.max_column + 1)}
    assert fmt["start"] == fmt["end"] == fmt["time_of_min"] == 'yyyy-mm-dd hh:mm:ss "UTC"'
    assert fmt["duration_s"] == "General" and ws.cell(2, 5).value == 30
    # wide enough for "2019-03-01 00:01:50 UTC" (23 characters; narrower, a spreadsheet shows ###)
    width = {column_name(ws.cell(1, j).value): ws.column_dimensions[ws.cell(1, j).column_letter].width
             for j in range(1, ws.max_column + 1)}
    assert width["time_of_min"] >= 23 and width["start"] >= 23
    ws = wb["Warning times"]
    fmt = {column_name(ws.cell(1, j).value): ws.cell(2, j).number_format for j in range(1, ws.max_column + 1)}
    assert fmt["loss_start"] == 'yyyy-mm-dd hh:mm:ss "UTC"'
    assert fmt["alert_start"] == 'yyyy-mm-dd hh:mm:ss.000 "UTC"'  # 97.5 s: the fraction shown
    assert fmt["horizon_s"] == fmt["warning_s"] == "General"
    assert wb["Alerts"].page_setup.fitToWidth == 1 and wb["Alerts"].max_row == 1  # headers alone: one page
    sections = {wb["Parameters"].cell(r, 1).value for r in range(2, wb["Parameters"].max_row + 1)}
    assert sections == {"parameters"}  # no correlation report's "report windows"


def test_figure_titles_name_each_aircraft_as_atc_does():
    from msdc.pipeline.report.conflict_figures import aircraft_label, place_label

    alert = pd.Series({"aircraft_a": "4CA216", "callsign_a": "EIN56P", "mode3a_a": "2011",
                       "flight_level_a": 95.4, "aircraft_b": "M3A:7052", "callsign_b": "", "mode3a_b": "7052",
                       "flight_level_b": float("nan"), "latitude": 41.5856, "longitude": -2.5982})
    assert aircraft_label(alert, "a") == "EIN56P 2011 (4CA216) FL 95"
    assert aircraft_label(alert, "b") == "7052 (M3A:7052)"  # no call sign, no level: left out
    assert place_label(alert) == ", at 41.586 N 2.598 W"
    bare = pd.Series({"aircraft_a": "A", "aircraft_b": "B"})  # a table without the labels
    assert aircraft_label(bare, "a") == "(A)" and place_label(bare) == ""
