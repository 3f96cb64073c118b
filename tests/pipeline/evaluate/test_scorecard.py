"""The scorecard's assembly (pipeline/evaluate/scorecard.py) on hand-made reports and references: the verdict
of a signed bias by its magnitude, the parameters text, the sigma gate of false reports, and the cut of
reports and reference into a region by the reference's position."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

from msdc.pipeline.evaluate.coverage import Sensor
from msdc.pipeline.evaluate.outcome import Outcome
from msdc.pipeline.evaluate.presets import Preset, Requirement
from msdc.pipeline.evaluate.scorecard import Region, judge, measure, parameters_text, score_sensor

M_PER_DEG_LAT = 111_320.0  # near the equator, where these cases lie: good to 0.5 %


def requirement(ident: str, threshold: float, direction: str = "<=", **parameters) -> Requirement:
    return Requirement(ident, threshold, direction, "clause", True, "hand", "stated", parameters=parameters)


def preset(*requirements: Requirement) -> Preset:
    return Preset("hand", "hand", "none", ("ssr",), "hand", tuple(requirements))


def track(n: int = 21, sigma_m: float = 5.0, label: str = "A") -> pd.DataFrame:
    """An aircraft flying north along longitude 0 at 100 m/s, sampled every second, its sigma given."""
    t = np.arange(float(n))
    return pd.DataFrame({"aircraft": label, "t_s": t, "latitude": 100.0 * t / M_PER_DEG_LAT, "longitude": 0.0,
                         "altitude_ft": 10_000.0, "sigma_m": sigma_m, "self_reference": False})


def test_a_signed_bias_is_judged_by_its_magnitude():
    req = requirement("range_bias_m", 100.0)
    inside = Outcome("range_bias_m", -40.0, -60.0, -20.0, 5000, 5000)
    row = judge(inside, req, preset(req), "R", "global")
    assert (row["value"], row["ci_low"], row["verdict"]) == (-40.0, -60.0, "pass")  # |x| in [20, 60]
    beyond = Outcome("range_bias_m", -150.0, -170.0, -130.0, 5000, 5000)
    assert judge(beyond, req, preset(req), "R", "global")["verdict"] == "fail"
    across = Outcome("range_bias_m", 10.0, -120.0, 140.0, 5000, 5000)  # |x| in [0, 140]
    assert judge(across, req, preset(req), "R", "global")["verdict"] == "inconclusive"


def test_a_maximum_above_its_threshold_fails_and_one_below_stays_open():
    """The largest error judged is a lower bound of the true maximum: above a '<=' threshold it fails for
    sure; below it, more reports could still exceed it."""
    req = requirement("max_m", 1000.0)
    above = Outcome("max_m", 1296.8, math.nan, math.nan, 3046, 3046)
    below = Outcome("max_m", 800.0, math.nan, math.nan, 3046, 3046)
    assert judge(above, req, preset(req), "R", "global")["verdict"] == "fail"
    assert judge(below, req, preset(req), "R", "global")["verdict"] == "inconclusive"


def test_parameters_are_written_as_the_preset_gives_them():
    assert parameters_text(requirement("pd", 0.97, ">=", interval_s=5.0, scope="global")) == \
        "interval_s = 5, scope = global"
    assert parameters_text(requirement("mode3a_correct", 0.98, ">=")) == ""


def test_false_reports_leave_out_reports_near_an_uncertain_reference():
    """Three reports against a 60 m tolerance: one on an aircraft whose reference sigma is 5 m (judged, not
    false), one 100 m off an aircraft whose sigma is 50 m, above a third of 60 m (left out), one 5 km from
    any aircraft (false, whatever the reference's accuracy)."""
    ref = pd.concat([track(sigma_m=5.0, label="A"),
                     track(sigma_m=50.0, label="B").assign(longitude=0.1)], ignore_index=True)
    rep = pd.DataFrame({"t_s": [5.0, 5.0, 5.0],
                        "latitude": [500.0 / M_PER_DEG_LAT, 500.0 / M_PER_DEG_LAT, 5500.0 / M_PER_DEG_LAT],
                        "longitude": [0.0, 0.1 + 100.0 / M_PER_DEG_LAT, 0.0]})
    out = measure(requirement("false_reports", 0.01, distance_m=60.0), rep, ref, Sensor(0.0, 0.0, 0.0))
    assert (out.count, out.n) == (1, 2)
    assert "1 of 3 reports left out" in " ".join(out.notes)


def test_a_region_takes_the_reports_where_their_aircraft_is():
    """A region north of latitude 1000 m holds the aircraft's second half: its reports there (even one 30 m
    south of the line, its aircraft being north of it) and only the reference's samples there."""
    ref = track()  # 0 to 2000 m north in 20 s
    t = np.arange(0.0, 21.0, 4.0)  # 0, 4, ..., 20 s: 0, 400, ..., 2000 m
    lat = 100.0 * t / M_PER_DEG_LAT
    lat[3] = (1200.0 - 230.0) / M_PER_DEG_LAT  # the report at 12 s (aircraft at 1200 m) lies at 970 m
    rep = pd.DataFrame({"t_s": t, "latitude": lat, "longitude": 0.0})
    north = Region("north", lambda la, lo, fl, g: la * M_PER_DEG_LAT > 1000.0)
    score = score_sensor(preset(requirement("pd", 0.5, ">=", interval_s=4.0)), "R", rep, ref,
                         Sensor(0.0, 0.0, 0.0, max_range_nm=100.0), [north])
    rows = {r["sector"]: r for r in score.rows}
    assert rows["global"]["n"] == 5  # 20 s of reference: five whole 4 s intervals
    # north of 1000 m the reference runs from 11 s to 20 s: two whole intervals, both with a report
    assert (rows["north"]["n"], rows["north"]["value"]) == (2, 1.0)
    assert not math.isnan(rows["north"]["ci_low"])


def test_the_preset_association_gate_decides_which_reports_an_aircraft_has():
    """A report 500 m east of the aircraft is its report under the default gate (2 NM), judged 500 m off;
    beyond an airport preset's 150 m gate it is no aircraft's, and no error is judged."""
    ref = track()
    rep = pd.DataFrame({"t_s": [5.0], "latitude": [500.0 / M_PER_DEG_LAT],
                        "longitude": [500.0 / M_PER_DEG_LAT]})
    req = requirement("max_m", 1000.0)
    wide = score_sensor(preset(req), "R", rep, ref, Sensor(0.0, 0.0, 0.0))
    narrow = Preset("hand", "hand", "none", ("mlat",), "hand", (req,), gate_m=150.0)
    tight = score_sensor(narrow, "R", rep, ref, Sensor(0.0, 0.0, 0.0))
    assert wide.rows[0]["value"] == pytest.approx(500.0, rel=0.01)
    assert math.isnan(tight.rows[0]["value"])


def flight(label: str, t_end: float = 200.0, east_m: float = 0.0, north_m_per_s: float = 100.0
           ) -> pd.DataFrame:
    """A reference aircraft flying north from latitude 0, ``east_m`` east of the site, sampled each second."""
    ref = track(int(t_end) + 1, label=label)
    return ref.assign(latitude=north_m_per_s * ref["t_s"] / M_PER_DEG_LAT, longitude=east_m / M_PER_DEG_LAT)


def plots(ref: pd.DataFrame, times) -> pd.DataFrame:
    """Reports exactly on the reference at the given times (whole seconds, so on its samples)."""
    at = ref.set_index("t_s").loc[np.asarray(times, float)]
    return pd.DataFrame({"t_s": at.index.to_numpy(float), "latitude": at["latitude"].to_numpy(),
                         "longitude": at["longitude"].to_numpy()})


def sector_rows(rep, ref, *regions, **parameters) -> dict:
    score = score_sensor(preset(requirement("pd", 0.5, ">=", **parameters)), "R", rep, ref,
                         Sensor(0.0, 0.0, 0.0), list(regions))
    return {r["sector"]: r for r in score.rows}


SCANS = np.arange(0.0, 201.0, 4.0)  # a 4 s radar seeing the aircraft at 0, 4, ..., 200 s: 51 scans


def test_an_aircraft_briefly_out_of_a_region_is_expected_there_only_while_inside():
    """The aircraft leaves the region for 20 s (10,000-12,000 m north: 100-120 s), less than the reference's
    30 s gap, and every scan sees it. Inside, 51 scans less the six at 100, 104, ..., 120 s: 45, all
    detected (a reference cut to the region would bridge the 20 s and count those six as missed)."""
    ref = flight("A")
    out = Region("out of the band", lambda la, lo, fl, g: np.abs(la * M_PER_DEG_LAT - 11_000.0) > 1_000.0)
    rows = sector_rows(plots(ref, SCANS), ref, out)
    assert (rows["global"]["n"], rows["global"]["value"]) == (51, 1.0)
    assert (rows["out of the band"]["n"], rows["out of the band"]["value"]) == (45, 1.0)
    # gaps between successive updates inside: 0-96 s and 124-200 s, 24 and 19 of 4 s, none long (the
    # 28 s from 96 to 124 s passes outside)
    gaps = score_sensor(preset(requirement("long_gaps", 0.5, min_gap_s=12.0)), "R", plots(ref, SCANS), ref,
                        Sensor(0.0, 0.0, 0.0), [out]).outcomes[("out of the band", "long_gaps", 0)]
    assert (gaps.count, gaps.n) == (0, 43)


def test_a_region_is_judged_with_the_sensors_coverage_and_scan_period():
    """A is seen on every scan out to 30 km (150 m/s for 200 s); B, 11 km east, only up to 100 s and then
    never, while the reference follows it to 200 s, well inside the range A was seen at. The east region
    holds B alone: 26 of its 51 scans detected (coverage estimated from B's plots alone would end at its
    last one and call it 26 of 26). A region of A's first 20 s holds five plots, too few to estimate a scan
    period of their own: the sensor's 4 s counts five updates there."""
    a, b = flight("A", north_m_per_s=150.0), flight("B", east_m=11_000.0)
    rep = pd.concat([plots(a, SCANS), plots(b, SCANS[SCANS <= 100.0])], ignore_index=True)
    east = Region("east", lambda la, lo, fl, g: lo * M_PER_DEG_LAT > 5_000.0)
    start = Region("start",
                   lambda la, lo, fl, g: (lo * M_PER_DEG_LAT < 5_000.0) & (la * M_PER_DEG_LAT < 3_000.0))
    rows = sector_rows(rep, pd.concat([a, b], ignore_index=True), east, start)
    assert (rows["global"]["n"], rows["global"]["value"]) == (102, pytest.approx(77 / 102))
    assert (rows["east"]["n"], rows["east"]["value"]) == (51, pytest.approx(26 / 51))
    assert (rows["start"]["n"], rows["start"]["value"]) == (5, 1.0)  # 0, 4, ..., 16 s: below 3,000 m
    assert "scan period 4 s" in rows["start"]["notes"]


def test_a_report_near_the_edge_of_a_region_is_judged_against_the_samples_either_side():
    """South of 1,000 m the reference's samples run from 0 to 9 s; a report at 9.5 s (the aircraft at 950 m,
    inside) lies between the samples at 9 and 10 s: judged 30 m off, as the one at 5 s is judged 10 m off
    (a reference cut to its samples inside would end at 9 s and leave the report unjudged)."""
    ref = track()
    rep = pd.DataFrame({"t_s": [5.0, 9.5], "latitude": [500.0 / M_PER_DEG_LAT, 950.0 / M_PER_DEG_LAT],
                        "longitude": [10.0 / M_PER_DEG_LAT, 30.0 / M_PER_DEG_LAT]})
    south = Region("south", lambda la, lo, fl, g: la * M_PER_DEG_LAT < 1000.0)
    score = score_sensor(preset(requirement("max_m", 1000.0)), "R", rep, ref, Sensor(0.0, 0.0, 0.0), [south])
    rows = {r["sector"]: r for r in score.rows}
    assert rows["south"]["n"] == 2
    assert rows["south"]["value"] == pytest.approx(30.0, rel=0.01)


def test_a_row_resting_partly_on_the_sensors_own_track_says_how_much():
    """A is known only from the sensor's own track (self_reference), B from another sensor: of the five
    reports, three lie on A; the code row says so of its trials, the accuracy and velocity rows (which never
    use A) do not, the velocity row judging B's two reports and counting A's three it left out."""
    ref = pd.concat([track(label="A").assign(self_reference=True),
                     track(label="B").assign(longitude=0.1, self_reference=False)], ignore_index=True)
    rep = pd.DataFrame({"t_s": [2.0, 6.0, 10.0, 4.0, 8.0],
                        "latitude": [200.0, 600.0, 1000.0, 400.0, 800.0] / np.float64(M_PER_DEG_LAT),
                        "longitude": [0.0, 0.0, 0.0, 0.1, 0.1], "mode3a": [0o1234] * 5,
                        "ground_speed_kt": 100.0 * 3600.0 / 1852.0, "heading_deg": 0.0})
    ref["mode3a"] = 0o1234
    score = score_sensor(preset(requirement("mode3a_correct", 0.5, ">="), requirement("rms_m", 100.0),
                                requirement("velocity_correct", 0.5, ">=", tolerance_mps=5.0)), "R",
                         rep, ref, Sensor(0.0, 0.0, 0.0))
    codes, rms, velocity = score.rows
    assert "self-reference: 3 of 5 trials judged against the sensor's own track" in codes["notes"]
    assert "associated reports" not in codes["notes"]
    assert "self-reference" not in rms["notes"]
    assert (velocity["n"], velocity["value"]) == (2, 1.0)
    assert "self-reference" not in velocity["notes"]
    assert "3 of 5 reports with a velocity were on the sensor's own track" in velocity["notes"]


def test_a_code_row_counts_its_own_trials_on_the_sensors_own_track_not_the_regions_reports():
    """Only A's track (the sensor's own) knows a Mode 3/A code, B's (another sensor's) none: the three
    reports on A are all the code row's trials, all on the own track (the region's 3 of 5 associated
    reports would understate it); the detection row keeps the region's count."""
    ref = pd.concat([track(label="A").assign(self_reference=True, mode3a="1234"),
                     track(label="B").assign(longitude=0.1, self_reference=False, mode3a=None)],
                    ignore_index=True)
    rep = pd.DataFrame({"t_s": [2.0, 6.0, 10.0, 4.0, 8.0],
                        "latitude": [200.0, 600.0, 1000.0, 400.0, 800.0] / np.float64(M_PER_DEG_LAT),
                        "longitude": [0.0, 0.0, 0.0, 0.1, 0.1], "mode3a": ["1234"] * 5})
    codes = preset(requirement("mode3a_correct", 0.5, ">="), requirement("mode3a_present", 0.5, ">="))
    score = score_sensor(codes, "R", rep, ref, Sensor(0.0, 0.0, 0.0))
    correct, present = score.rows
    assert (correct["n"], correct["value"]) == (3, 1.0)
    assert "self-reference: 3 of 3 trials judged against the sensor's own track" in correct["notes"]
    assert (present["n"], present["value"]) == (5, 1.0)
    assert "self-reference: 3 of 5 trials judged against the sensor's own track" in present["notes"]


def test_a_field_monitor_is_judged_in_its_own_row_and_left_out_of_the_others():
    """A fixed transponder (field_monitor) at 5 km east, seen every 4 s for 200 s, 51 of 51, beside an
    aircraft seen on 26 of its 51 scans: the monitor's row holds its 51 updates alone, the global row the
    aircraft's 51 alone (pooled, the global PD would read 77 of 102)."""
    aircraft = flight("A")
    monitor = flight("M", east_m=5_000.0, north_m_per_s=0.0).assign(field_monitor=True, on_ground=True)
    ref = pd.concat([aircraft.assign(field_monitor=False, on_ground=False), monitor], ignore_index=True)
    rep = pd.concat([plots(aircraft, SCANS[::2]), plots(monitor, SCANS)], ignore_index=True)
    rows = sector_rows(rep, ref)
    assert (rows["field monitors"]["n"], rows["field monitors"]["value"]) == (51, 1.0)
    assert (rows["global"]["n"], rows["global"]["value"]) == (51, pytest.approx(26 / 51))


def test_every_requirement_of_a_sensor_reads_one_coverage_estimate():
    """Estimated once from the reference at the sensor's associated reports: A's last, 30 km north at
    10,000 ft (3,048 m), is sqrt(30,000^2 + 3,048^2) = 30,154 m = 16.28 NM away (to the 0.5 % of
    M_PER_DEG_LAT), whether PD counts scans or 8 s intervals (each counted its own, from its detected
    updates' places)."""
    a, b = flight("A", north_m_per_s=150.0), flight("B", east_m=11_000.0)
    rep = pd.concat([plots(a, SCANS), plots(b, SCANS[SCANS <= 100.0])], ignore_index=True)
    score = score_sensor(preset(requirement("pd", 0.5, ">="), requirement("pd", 0.5, ">=", interval_s=8.0)),
                         "R", rep, pd.concat([a, b], ignore_index=True), Sensor(0.0, 0.0, 0.0))
    said = {row["notes"].split("max_range_nm ")[1].split(",")[0] for row in score.rows}
    assert len(said) == 1 and float(said.pop()) == pytest.approx(16.28, rel=0.01)


def test_a_requirement_on_an_area_no_sector_provides_keeps_its_row():
    req = Requirement("pd", 0.9, ">=", "clause", True, "hand", "stated", area="stands")
    score = score_sensor(preset(req), "R", plots(flight("A"), SCANS), flight("A"), Sensor(0.0, 0.0, 0.0))
    (row,) = score.rows
    assert (row["sector"], row["requirement"], row["verdict"]) == ("stands", "pd", "inconclusive")
    assert row["n"] == 0
    assert math.isnan(row["value"])
    assert "not measured on area 'stands': no sector of that area in the sector file" in row["notes"]


def test_a_report_is_on_the_surface_while_the_latest_reference_sample_says_so():
    """The reference says 'on the ground' at 0 s and 'airborne' at 10 s: a report at 6 s is a surface
    report (the latest sample's state, as the bins' surface class takes it; the nearest sample would say
    airborne), one at 12 s an airborne one."""
    t = np.array([0.0, 10.0, 20.0])
    ref = pd.DataFrame({"aircraft": "A", "t_s": t, "latitude": 100.0 * t / M_PER_DEG_LAT, "longitude": 0.0,
                        "altitude_ft": 0.0, "sigma_m": 5.0, "on_ground": [True, False, False]})
    rep = pd.DataFrame({"t_s": [6.0, 12.0], "latitude": [600.0 / M_PER_DEG_LAT, 1200.0 / M_PER_DEG_LAT],
                        "longitude": 0.0})
    rows = {r["sector"]: r for r in score_sensor(preset(requirement("max_m", 1000.0)), "R", rep, ref,
                                                 Sensor(0.0, 0.0, 0.0)).rows}
    assert (rows["surface"]["n"], rows["airborne"]["n"], rows["global"]["n"]) == (1, 1, 2)


def test_a_false_report_is_on_the_surface_or_airborne_as_it_says_itself():
    """Three reports 4 km from an airborne aircraft and 11 km from one on the ground: one saying 'on the
    ground', one 'airborne', one nothing. With no aircraft to place them, the surface row counts the first
    false, the airborne row the second (beside the airborne aircraft's own report, not false), the global row
    all three; the third is in neither sector row, and both say so."""
    ref = pd.concat([track().assign(on_ground=False),
                     track(label="B").assign(latitude=0.0, longitude=0.1, on_ground=True)], ignore_index=True)
    far = 5_000.0 / M_PER_DEG_LAT
    rep = pd.DataFrame({"t_s": [5.0, 5.0, 6.0, 7.0], "latitude": [500.0 / M_PER_DEG_LAT, far, far, far],
                        "longitude": 0.0,
                        "on_ground": pd.array([False, True, False, pd.NA], dtype="boolean")})
    score = score_sensor(preset(requirement("false_reports", 0.01, distance_m=100.0)), "R", rep, ref,
                         Sensor(0.0, 0.0, 0.0))
    rows = {r["sector"]: r for r in score.rows}
    assert (rows["global"]["value"] * rows["global"]["n"], rows["global"]["n"]) == (3, 4)
    assert (rows["surface"]["value"] * rows["surface"]["n"], rows["surface"]["n"]) == (1, 1)
    assert (rows["airborne"]["value"] * rows["airborne"]["n"], rows["airborne"]["n"]) == (1, 2)
    for sector in ("surface", "airborne"):
        assert "1 reports of no reference aircraft that do not say whether" in rows[sector]["notes"]
    assert "do not say whether" not in rows["global"]["notes"]
