"""Report rules of issue 9: the figure's peak rule, the window note, unit formats, formula-injection guards,
``stats`` grouping, and openpyxl writing through lxml. Expected values are worked by hand."""

from __future__ import annotations

import math
import shutil
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from msdc.pipeline.cli import main
from msdc.pipeline.quality.inventory import reason_kind, stats_tables
from msdc.pipeline.report.figures import figure_peak
from msdc.pipeline.report.formats import column_unit, decimals, excel_format
from msdc.pipeline.report.quality_figures import histogram_range_s
from msdc.pipeline.report.summary import SEP_DOMINATED_RATIO, window_note
from msdc.pipeline.report.textguard import guard_frame, neutralise

FIX = Path(__file__).resolve().parents[3] / "fixtures"


# ------------------------------------------------------------------------------------- figure peak rule

LAGS = np.arange(-23, 24)  # N = 24 slots: Pearson peak searched over |lag| <= min(24 // 2, 24 - 10) = 12


def _r(values: dict[int, float]) -> np.ndarray:
    """A coefficient per lag of LAGS: 0 but at the lags given."""
    r = np.zeros(LAGS.size)
    for lag, v in values.items():
        r[lag + 23] = v
    return r


R = _r({-20: 0.99, -2: 0.5, 1: 0.6, 20: 0.95})


def test_pearson_peak_ignores_lags_beyond_half():
    # lags -20 and +20 (0.99, 0.95) overlap on 4 slots only; among -12..12 the largest is 0.6 at lag +1
    k, at_limit = figure_peak(LAGS, R, "pearson")
    assert LAGS[k] == 1 and not at_limit


def test_ncc_peak_searches_every_lag():
    assert LAGS[figure_peak(LAGS, R, "ncc")[0]] == -20


def test_peak_ties_nan_and_empty():
    tie = _r({-2: 0.7, 2: 0.7})
    assert LAGS[figure_peak(LAGS, tie, "pearson")[0]] == -2  # first of the equal maxima
    only_outside = _r({-20: 0.9, 20: 0.8})
    only_outside[np.abs(LAGS) <= 12] = np.nan
    assert figure_peak(LAGS, only_outside, "pearson") == (None, False)
    assert LAGS[figure_peak(LAGS, only_outside, "ncc")[0]] == -20


def test_a_peak_at_the_search_limit_is_marked_as_such():
    k, at_limit = figure_peak(LAGS, _r({-12: 0.9, 0: 0.5}), "pearson")
    assert LAGS[k] == -12 and at_limit
    # a window of 10 slots: only lag 0 has 10 slots overlapping, no lag can be estimated; of 11, lag +-1
    assert figure_peak(np.arange(-9, 10), np.linspace(0, 1, 19), "pearson") == (None, False)
    assert figure_peak(np.arange(-10, 11), np.linspace(0, 1, 21), "pearson") == (11, True)


def test_peak_matches_the_summary_rule():
    """The lag the figure marks is the summary's pearson_peak_lag for a window built by correlate."""
    from msdc.pipeline.correlate.correlation import PEARSON_MIN_OVERLAP, pearson_by_lag, pearson_peak

    t = np.arange(40.0)
    x = np.sin(t / 5.0)
    y = np.roll(x, -3) + 0.01 * np.cos(t)
    lags, r = pearson_by_lag(x, y, PEARSON_MIN_OVERLAP)
    expected, _ = pearson_peak(lags, r, 40)
    assert expected is not None and lags[figure_peak(lags, r, "pearson")[0]] == expected


# ------------------------------------------------------------------------------------------ window note

def _s(rms, median, jumps=0):
    return {"sep_rms_m": rms, "sep_median_m": median, "adsb_jumps": jumps}


def test_note_appears_exactly_above_three_times_the_median():
    assert SEP_DOMINATED_RATIO == 3.0
    assert window_note(_s(300.0, 100.0, 7)) is None  # equal to 3 x median: not dominated
    assert window_note(_s(299.9, 100.0, 7)) is None
    note = window_note(_s(300.1, 100.0, 7))
    assert note.startswith("7 ADS-B position jumps in this window; rerun with --drop-jumps")
    assert "300.1 m" in note and "100.0 m" in note


def test_note_wording_without_jumps_and_missing_values():
    assert window_note(_s(10371.7, 231.5, 1)).startswith("1 ADS-B position jump in this window;")
    note = window_note(_s(900.0, 200.0, 0))
    assert note.startswith("a few slots dominate the separation") and "--drop-jumps" not in note
    assert window_note(_s(math.nan, 200.0, 3)) is None
    assert window_note(_s(900.0, None, 3)) is None
    assert window_note(_s(5.0, 0.0, 0)) is not None  # median 0, RMS 5: a few slots carry everything


def test_note_in_json_and_stdout_from_the_fixtures(tmp_path, capsys):
    """MAS72 window 1 of the bundled fixtures: RMS separation ~10 km from ADS-B jumps, median ~230 m."""
    import json

    out = tmp_path / "s.json"
    assert main(["correlate", str(FIX / "radar.ast"), str(FIX / "adsb.ast"), "--sensors",
                 str(FIX / "sensors.toml"), "--callsign", "MAS72", "--json", str(out)]) == 0
    stdout = capsys.readouterr().out
    first = json.loads(out.read_text())["windows"][0]
    assert first["sep_rms_m"] > SEP_DOMINATED_RATIO * first["sep_median_m"]
    assert first["adsb_jumps"] >= 1 and "rerun with --drop-jumps" in first["note"]
    pair = "048:25/201 vs 021:0/1"
    assert f"Note: MAS72 window 1 ({pair}): {first['adsb_jumps']} ADS-B position jump" in stdout
    assert first["radar_filled_slots"] + first["radar_after"] >= first["slots"]


# ------------------------------------------------------------------------------------------------ units

@pytest.mark.parametrize(("name", "unit", "fmt", "places"), [
    ("azimuth_bias_deg", "deg", "0.0000", 4), ("radar_lat", "deg", "0.0000", 4),
    ("latitude", "deg", "0.0000", 4),
    ("ncc0_lat", "coef", "0.000000", 6), ("pearson_lon", "coef", "0.000000", 6),
    ("sep_rms_m", "m", "0.0", 1), ("range_bias_m", "m", "0.0", 1), ("range_gain_ppm", "ppm", "0.0", 1),
    ("lag_s", "s", "0.000", 3), ("lag", "count", "0", 0), ("pearson_peak_lag_lat", "count", "0", 0),
    ("start_tod", "tod", "[hh]:mm:ss.000", 3), ("gap_start_tod_s", "tod", "[hh]:mm:ss.000", 3),
    ("time_of_day", "tod", "[hh]:mm:ss.000", 3), ("speed_missing_or_zero_pct", "pct", "0.0", 1),
    ("ground_speed_kt", "kt", "0.0", 1),
    # a reference point is typed into the sensor file to the centimetre (1e-7 deg is 1.1 cm); "corrected"
    # is not a correlation coefficient
    ("corrected_latitude", "point_deg", "0.0000000", 7), ("point_longitude", "point_deg", "0.0000000", 7),
])
def test_unit_table(name, unit, fmt, places):
    assert column_unit(name) == unit
    assert excel_format(name) == fmt
    assert decimals(name) == places


def test_unknown_column_has_no_unit():
    assert column_unit("callsign") is None and excel_format("mops_versions") is None


# ---------------------------------------------------------------------------------- formula injection

def test_neutralise_and_guard_frame():
    assert neutralise("=1+1") == "'=1+1" and neutralise("+A1") == "'+A1" and neutralise("-2") == "'-2"
    assert neutralise("@SUM(A1)") == "'@SUM(A1)" and neutralise("\t=x") == "'\t=x"
    assert neutralise("MAS72") == "MAS72" and neutralise(-2.5) == -2.5
    frame = pd.DataFrame({"callsign": pd.Categorical(["=cmd", "MAS72", None]), "file": ["@x", "a.ast", None],
                          "rho_nm": [-1.0, 2.0, 3.0]})
    out = guard_frame(frame)
    assert out["callsign"].tolist()[:2] == ["'=cmd", "MAS72"] and pd.isna(out["callsign"].iloc[2])
    assert out["file"].tolist()[:2] == ["'@x", "a.ast"]
    assert out["rho_nm"].tolist() == [-1.0, 2.0, 3.0]  # numbers untouched
    assert frame["file"].iloc[0] == "@x"  # the input is not modified
    # text none of which is formula-like, and values that cannot be hashed (each then looked at)
    lists = pd.DataFrame({"plain": ["MAS72", "a-b", None], "parts": [["=x"], "-1", None]})
    out = guard_frame(lists)
    assert out["plain"].tolist()[:2] == ["MAS72", "a-b"] and out["parts"].tolist()[:2] == [["=x"], "'-1"]


def test_decode_csv_file_column_is_protected(tmp_path, capsys):
    evil = tmp_path / "=1+1.ast"
    shutil.copy(FIX / "radar.ast", evil)
    out = tmp_path / "out.csv"
    assert main(["decode", str(evil), "-o", str(out)]) == 0
    frame = pd.read_csv(out, dtype=str)
    assert set(frame["file"]) == {"'=1+1.ast"}
    assert not frame["callsign"].dropna().str.startswith(("=", "+", "-", "@")).any()


# ------------------------------------------------------------------------------------------------ stats

def test_skipped_blocks_group_by_reason_without_offset():
    assert reason_kind("a data block with no record (record at offset 1234)") == "a data block with no record"
    assert reason_kind("unknown category") == "unknown category"
    past = "an FSPEC or item runs past the end of its data block"
    errors = pd.DataFrame({"file": ["f"] * 3, "offset": [10, 500, 90], "length": [5, 7, 3],
                           "category": [48] * 3,
                           "reason": [f"{past} (record at offset 12)", f"{past} (record at offset 503)",
                                      "unknown category"]})
    skipped = stats_tables({}, errors)["skipped"]
    assert skipped.to_dict("records") == [
        {"file": "f", "category": 48, "reason": "an FSPEC or item runs past the end of its data block",
         "blocks": 2, "bytes": 12, "first_offset": 10},
        {"file": "f", "category": 48, "reason": "unknown category", "blocks": 1, "bytes": 3,
         "first_offset": 90}]


def test_stats_lists_aircraft_with_utc_spans(capsys):
    assert main(["stats", str(FIX / "radar.ast"), str(FIX / "adsb.ast"), "--date", "2019-03-01"]) == 0
    out = capsys.readouterr().out
    assert "Aircraft per sensor" in out and "Skipped blocks by reason" in out
    line = next(x for x in out.splitlines() if "MAS136" in x and " 25 " in x)
    assert "2019-03-01 08:10:01" in line and "11:19:55" in line  # radar 08:10 to 11:19 (back hours later)
    assert "29401" not in out  # never seconds of day


def test_stats_without_date_prints_clock_times(capsys):
    assert main(["stats", str(FIX / "radar.ast")]) == 0
    out = capsys.readouterr().out
    assert "08:00:02" in out and "2019" not in out.split("Aircraft")[0]


# --------------------------------------------------------------------------------------------- speed

def test_openpyxl_writes_through_lxml():
    """openpyxl streams write-only sheets through lxml only when it is importable and not switched off by
    OPENPYXL_LXML; without it workbooks are written about twice as slowly."""
    from openpyxl.xml import LXML

    assert LXML


def test_histogram_range_keeps_the_bulk():
    h = pd.DataFrame({"bin_start_s": [0.0, 0.5, 1.0, 1.5, 9.5], "bin_end_s": [0.5, 1.0, 1.5, 2.0, 10.0],
                      "intervals": [0, 600, 399, 0, 1]})
    assert histogram_range_s(h) == 1.5  # 999 of 1000 intervals end by 1.5 s; the single 9.7 s one is a note
    assert histogram_range_s(h, share=1.0) == 10.0


def test_slotting_panel_range_follows_the_radar():
    """ADS-B jumps of degrees would flatten the track: the raw-report panels take the radar's range,
    padded by 8 % of it, at least 0.01 deg."""
    from msdc.pipeline.report.quality_figures import track_span

    assert track_span(np.array([1.0, np.nan, 2.0])) == pytest.approx((0.92, 2.08))
    assert track_span(np.array([5.0, 5.0])) == pytest.approx((4.99, 5.01))
    assert track_span(np.array([np.nan])) is None
