"""The ADS-B filters apply to the reference of radar accuracy and biases, in msdc quality and in correlate
--quality alike, and the quality sheets still describe every report. Expected differences come from the
fixtures' truth: SIA305 flies with NACp 8 (every ADS-B report of it goes under --min-nacp 9), three aircraft
have a low-quality episode at NACp 6 (its reports go), AXM123 has NACp 9 throughout (nothing goes)."""

from __future__ import annotations

import functools
import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import msdc.asterix as asterix
from msdc.pipeline.jobs.correlate import CorrelateOptions, correlate_job
from msdc.pipeline.jobs.quality import QualityOptions, quality_job, text

FIX = Path(__file__).resolve().parents[3] / "fixtures"
RADAR, ADSB, SENSORS = str(FIX / "radar.ast"), str(FIX / "adsb.ast"), str(FIX / "sensors.toml")
TRUTH = json.loads((FIX / "truth.json").read_text())
ADSB_MAX_INTERVAL_S = TRUTH["parameters"]["adsb_interval_s"][1]  # the longest ADS-B update interval


def _nacp_of(callsign: str) -> int:
    (ac,) = [a for a in TRUTH["aircraft"] if a["callsign"] == callsign]
    return int(ac["adsb_quality"]["nacp"])


EPISODES = TRUTH["low_quality"]["episodes"]  # every report in one has NACp 6


@functools.cache
def _run(command: str, min_nacp: int | None):
    if command == "quality":
        result = quality_job(QualityOptions(inputs=(RADAR, ADSB), sensors=SENSORS, all_aircraft=True,
                                            min_nacp=min_nacp))
        return result, result.quality
    result = correlate_job(CorrelateOptions(inputs=(RADAR, ADSB), sensors=SENSORS, all_aircraft=True,
                                            quality=True, min_nacp=min_nacp))
    return result, result.quality


def _accuracy(quality) -> pd.DataFrame:
    return quality.sheets["Radar accuracy"].set_index("callsign")


@pytest.mark.parametrize("command", ["quality", "correlate"])
def test_min_nacp_removes_from_the_reference_what_the_truth_says(command):
    _, before = _run(command, None)
    _, after = _run(command, 9)
    dropped = {a["callsign"] for a in TRUTH["aircraft"] if _nacp_of(a["callsign"]) < 9}
    untouched = {a["callsign"] for a in TRUTH["aircraft"]} - dropped - {e["callsign"] for e in EPISODES}
    assert dropped == {"SIA305"} and untouched == {"AXM123"}  # what the fixture was built with
    acc_before, acc_after = _accuracy(before), _accuracy(after)
    # an aircraft whose every ADS-B report goes has no reference: its row goes
    assert dropped <= set(acc_before.index) and not dropped & set(acc_after.index)
    # an aircraft the filter leaves alone keeps its very numbers
    for cs in untouched:
        pd.testing.assert_series_equal(acc_before.loc[cs], acc_after.loc[cs])
    # per aircraft with an episode: the radar reports inside it lose their reference (the ADS-B gap across
    # it is longer than 10 s), those more than an ADS-B interval away from it keep theirs, unchanged
    e0, e1 = before.errors, after.errors
    for episode in EPISODES:
        cs = episode["callsign"]
        b, a = e0[e0["callsign"] == cs], e1[e1["callsign"] == cs]
        t_b = b["time_of_day"].to_numpy()
        inside = (t_b >= episode["start_s"]) & (t_b <= episode["end_s"])
        far = (t_b < episode["start_s"] - 2 * ADSB_MAX_INTERVAL_S) | (t_b > episode["end_s"]
                                                                     + 2 * ADSB_MAX_INTERVAL_S)
        assert inside.sum() > 5
        kept = set(a["radar_row"])
        assert not kept & set(b["radar_row"][inside])
        assert set(b["radar_row"][far]) <= kept
        common = b[far].set_index("radar_row")["range_error_m"]
        np.testing.assert_allclose(a.set_index("radar_row").loc[common.index, "range_error_m"], common)
    # the bias fit rests on those reports: one aircraft and every removed report fewer
    b_before, b_after = before.sheets["Radar biases"].iloc[0], after.sheets["Radar biases"].iloc[0]
    assert b_after["aircraft"] == b_before["aircraft"] - len(dropped)
    assert b_after["n_reports"] == len(e1) < len(e0) - acc_before.loc["SIA305", "n_reports"]
    assert b_after["range_bias_m"] != b_before["range_bias_m"]
    # the quality sheets describe every report, filtered or not
    pd.testing.assert_frame_equal(before.sheets["Quality"], after.sheets["Quality"])
    pd.testing.assert_frame_equal(before.sheets["ADS-B quality"], after.sheets["ADS-B quality"])


def test_quality_records_and_says_what_the_filters_removed():
    result, _ = _run("quality", 9)
    assert result.parameters["filters"]["min_nacp"] == 9
    # every decoded CAT021 record below NACp 9 (SIA305's, the episodes', duplicates included): the
    # decoder's count, not the filter's (the 3,038)
    below = int((asterix.read(ADSB).frames[21]["nacp"] < 9).sum())
    assert result.parameters["filters"]["removed"]["nacp_below_min"] == below == 3038
    said = text(result)
    assert "ADS-B filters (radar accuracy and biases use what they leave): nacp_below_min 3038" in said


def test_correlate_all_names_an_aircraft_the_filter_removed_whole():
    """SIA305 flies with NACp 8 (the truth): under --min-nacp 9 every ADS-B report of it goes, and --all
    left it out of every table in silence (--callsign SIA305 says it as an error). Its count, by the truth's
    reports: those of SIA305's address in the ADS-B fixture."""
    truth = json.loads((FIX / "truth.json").read_text())
    sia = next(a for a in truth["aircraft"] if a["callsign"] == "SIA305")
    assert sia["adsb_quality"]["nacp"] < 9
    frame = asterix.read(ADSB).frames[21]
    n = int((frame["address"] == sia["address"]).sum())
    result = correlate_job(CorrelateOptions(inputs=(RADAR, ADSB), sensors=SENSORS, all_aircraft=True,
                                            min_nacp=9))
    said = ("--min-nacp 9 removed all ADS-B reports of 1 aircraft seen by radar and ADS-B, which are not "
            f"correlated: SIA305 ({sia['address']}, {n:,} reports)")
    assert said in result.warnings and said in result.run.parameters["notes"]
    assert "SIA305" not in {w.summary["callsign"] for w in result.run.windows}
