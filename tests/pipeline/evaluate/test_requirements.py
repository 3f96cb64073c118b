"""The requirement functions (pipeline/evaluate/detection.py, codes.py, plots.py): hand-worked tiny frames for
the counting rules, and a seeded simulation whose injected rates each function recovers."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from fixtures.radar_effects import RadarEffects, expected_rates, simulate_effects
from msdc.pipeline.evaluate.coverage import Sensor
from msdc.pipeline.evaluate.reference import associate
from msdc.pipeline.evaluate.requirements import REQUIREMENTS, radar_reports
from msdc.pipeline.model.geodesy import polar_to_geodetic

# one worker runs the module: the simulated recording made once, not on each worker
pytestmark = pytest.mark.xdist_group("requirements")

MARKERS = -2.0 + 4.0 * np.arange(40)  # north markers every 4 s
NEAR = Sensor(0.0, 0.0, 0.0, name="hand", max_range_nm=100.0, north_markers_s=MARKERS)


def position(t_s, start_nm: float = 30.0, nm_per_s: float = 0.1, azimuth_deg: float = 0.0):
    """Latitude and longitude of an aircraft on the ground flying out from the site (0, 0) along an azimuth,
    at start_nm + nm_per_s * t slant range."""
    t = np.asarray(t_s, float)
    lat, lon, _ = polar_to_geodetic(0.0, 0.0, 0.0, start_nm + nm_per_s * t, azimuth_deg, 0.0)
    return lat, lon


def reference(t_end: float = 20.0, label: str = "A", azimuth_deg: float = 0.0, times=None, **ident):
    """A reference sampled every second from 0 to t_end, at height 0, with the given identity columns."""
    t = np.arange(0.0, t_end + 0.5, 1.0) if times is None else np.asarray(times, float)
    lat, lon = position(t, azimuth_deg=azimuth_deg)
    return pd.DataFrame({"aircraft": label, "t_s": t, "latitude": lat, "longitude": lon, "height_m": 0.0,
                         **{k: v for k, v in ident.items()}})


def reports(times, azimuth_deg: float = 0.0, **columns):
    """Reports exactly on the aircraft's path at the given times, with extra columns."""
    lat, lon = position(times, azimuth_deg=azimuth_deg)
    return pd.DataFrame({"t_s": np.asarray(times, float), "latitude": lat, "longitude": lon, **columns})


def run(requirement: str, rep, ref, sensor=NEAR, **parameters):
    return REQUIREMENTS[requirement](rep, ref, parameters, sensor)


def counts(outcome) -> tuple[int, int]:
    return outcome.count, int(outcome.n)


# ---------------------------------------------------------------------------------------------------------
# Detection


def test_a_missed_scan_is_one_expected_update_without_report():
    out = run("pd", reports([0, 4, 8, 16, 20]), reference())
    assert counts(out) == (5, 6)
    assert out.value == pytest.approx(5 / 6)
    assert "from 40 north markers" in out.notes[0] and "scan period 4 s" in out.notes[0]


def test_an_aircraft_leaving_coverage_is_not_expected_outside():
    # 30 NM + 0.1 NM/s: beyond the declared 31 NM after 10 s; the updates at 12, 16, 20 s are not expected
    leaving = Sensor(0.0, 0.0, 0.0, max_range_nm=31.0, north_markers_s=MARKERS)
    out = run("pd", reports([0, 4, 8]), reference(), leaving)
    assert counts(out) == (3, 3)
    assert "declared: max_range_nm 31" in out.notes[1]
    # with no declared range the coverage ends at the farthest detection (30.8 NM, at 8 s): the same
    estimated = Sensor(0.0, 0.0, 0.0, north_markers_s=MARKERS)
    out = run("pd", reports([0, 4, 8]), reference(), estimated)
    assert counts(out) == (3, 3)
    assert "estimated from the sensor's own detections: max_range_nm 30.8" in out.notes[1]
    # a sensor that declares more range misses those three updates
    assert counts(run("pd", reports([0, 4, 8]), reference())) == (3, 6)


def test_missed_updates_below_every_detection_are_said_when_no_minimum_elevation_is_declared():
    # flying out at height 0 the aircraft sinks below the site's horizon: the three missed updates (12, 16,
    # 20 s) lie lower than the lowest detection (30.8 NM, 8 s). On the ellipsoid along the equator's
    # meridian, a surface point at chord c is at elevation -asin(c / 2M), M = a (1 - e^2) = 6,335,439 m:
    # -0.258 deg at 30.8 NM
    lowest = -np.degrees(np.arcsin(30.8 * 1852.0 / (2 * 6_335_439.0)))
    out = run("pd", reports([0, 4, 8]), reference())
    assert counts(out) == (3, 6)
    said = [n for n in out.notes if "below the lowest elevation" in n]
    assert said == [f"3 expected updates inside coverage (50.0 %) lie below the lowest elevation the sensor "
                    f"detected ({lowest:.2f} deg), all missed: no min_elevation_deg is declared; if that is "
                    "the radar's horizon, declare it in the sensor file"]
    # declared, the minimum is the user's: nothing said; a missed update above the lowest detection: nothing
    declared = Sensor(0.0, 0.0, 0.0, max_range_nm=100.0, min_elevation_deg=-5.0, north_markers_s=MARKERS)
    assert not [n for n in run("pd", reports([0, 4, 8]), reference(), declared).notes if "lowest" in n]
    assert not [n for n in run("pd", reports([0, 4, 8, 16, 20]), reference()).notes if "lowest" in n]


def test_two_plots_in_one_scan_are_one_update():
    times = [0, 4, 4, 8]
    rep = reports(times)
    rep.loc[2, "longitude"] += 300.0 / 111_320.0  # the split plot, 300 m east
    assert counts(run("pd", rep, reference(8))) == (3, 3)
    assert counts(run("multiple_reports", rep, reference(8))) == (1, 3)
    assert counts(run("split_reports", rep, reference(8))) == (1, 3)
    # an exact repeat (same time and position) is a multiple report, not a split one
    twin = reports(times)
    assert counts(run("multiple_reports", twin, reference(8))) == (1, 3)
    assert counts(run("split_reports", twin, reference(8))) == (0, 3)
    # a lone plot the radar marks split (I048/030 code 3) counts in both
    flagged = reports([0, 4, 8], warning_codes=[None, "1,3", None])
    assert counts(run("split_reports", flagged, reference(8))) == (1, 3)
    assert counts(run("multiple_reports", flagged, reference(8))) == (1, 3)
    assert counts(run("split_reports", reports([0, 4, 8], warning_codes=["13", None, None]),
                      reference(8))) == (0, 3)


def test_update_intervals_tile_the_reference():
    # 5 s intervals over [0, 20]: [0,5) [5,10) [10,15) [15,20); the one of 10-15 s holds no report
    out = run("pd", reports([0, 4, 8, 16]), reference(), interval_s=5.0)
    assert counts(out) == (3, 4)
    assert out.notes[0] == "intervals of 5 s"


def test_scan_period_from_the_plots_without_markers():
    times = [t for t in range(0, 101, 4) if t not in (12, 40)]
    out = run("pd", reports(times), reference(100), Sensor(0.0, 0.0, 0.0, max_range_nm=100.0))
    assert counts(out) == (24, 26)
    assert out.notes[0] == "scan period 4 s estimated from the plots (no north markers)"


def test_no_update_is_expected_where_the_reference_has_a_hole():
    ref = reference(times=[*range(0, 21), *range(80, 101)])
    rep = reports([*range(0, 21, 4), *range(80, 101, 4)])
    assert counts(run("pd", rep, ref)) == (12, 12)
    # bridged by a longer reference gap, the 60 s hole holds 60 / 4 - 1 = 14 missed updates
    assert counts(run("pd", rep, ref, reference_max_gap_s=100.0)) == (12, 26)


def test_per_target_scope_gives_the_weakest_aircraft():
    ref = pd.concat([reference(label="A"), reference(label="B", azimuth_deg=90.0)])
    rep = pd.concat([reports([0, 4, 8, 16, 20]), reports([0, 4, 8, 12, 16, 20], azimuth_deg=90.0)])
    out = run("pd", rep, ref, scope="per_target")
    assert counts(out) == (5, 6)
    assert out.per_aircraft["expected"].tolist() == [6, 6] and out.per_aircraft["detected"].tolist() == [5, 6]
    assert counts(run("pd", rep, ref)) == (11, 12)


def test_long_gaps_inside_coverage():
    # gaps 4, 4, 12 s: one of three is at least 10 s
    assert counts(run("long_gaps", reports([0, 4, 8, 20]), reference(), min_gap_s=10.0)) == (1, 3)
    assert counts(run("long_gaps", reports([0, 4, 8, 20]), reference(), min_gap_s=10.0,
                      max_gap_s=12.0)) == (0, 3)
    # the 12 s gap spans updates outside a 31 NM coverage (after 10 s): not a gap the sensor answers for
    leaving = Sensor(0.0, 0.0, 0.0, max_range_nm=31.0, north_markers_s=MARKERS)
    assert counts(run("long_gaps", reports([0, 4, 8, 20]), reference(), leaving, min_gap_s=10.0)) == (0, 2)
    with pytest.raises(ValueError, match="min_gap_s"):
        run("long_gaps", reports([0, 4]), reference())


# ---------------------------------------------------------------------------------------------------------
# Codes and identity


def test_mode3a_present_valid_correct_false():
    # right; garbled (G and V set, wrong code); wrong but not flagged; absent
    rep = reports([0, 4, 8, 12], mode3a=["1234", "1274", "1235", None], mode3a_v=[0, 1, 0, pd.NA],
                  mode3a_g=[0, 1, 0, pd.NA])
    ref = reference(mode3a="1234")
    assert counts(run("mode3a_present", rep, ref)) == (3, 4)
    assert counts(run("mode3a_valid", rep, ref)) == (2, 3)
    correct = run("mode3a_correct", rep, ref)
    assert counts(correct) == (1, 4)
    # the three misses, one for each reason
    assert ("of the 3 misses: 1 carries no code; 1 carries a code not validated or garbled; 1 carries a "
            "different code") in correct.notes
    assert counts(run("mode3a_false", rep, ref)) == (1, 2)


def test_update_numbers_run_over_every_aircraft_at_once():
    """Reports of B at 0 and 5 s and of A at 0, 1.5 and 4.5 s, a 4 s scan: A's first two are one update
    (1.5 s apart, under half a scan), its third the next (3 s on); B's two are two updates, numbered
    after A's."""
    from msdc.pipeline.evaluate.scans import update_numbers

    got = update_numbers(np.array(["B", "A", "A", "B", "A"], object), np.array([0, 0, 1.5, 5, 4.5]), 4.0)
    assert got.tolist() == [2, 0, 0, 3, 1]
    assert update_numbers(np.array([], object), np.array([]), 4.0).tolist() == []


def test_a_split_repeating_its_plots_code_widens_the_interval_by_the_design_effect():
    """One report a 4 s scan, right, wrong, right, right, wrong, right, and a split at 4 s and at 12 s
    repeating its plot's code: 5 correct of 8. The updates (reports, correct) are (1, 1), (2, 0), (1, 1),
    (2, 2), (1, 0), (1, 1); with p = 5/8 the squares of y - p m sum to 2.9375, over n p (1 - p) = 1.875 a
    design effect of 1.5667, and the interval is Clopper-Pearson's of 5 / 1.5667 in 8 / 1.5667 trials.
    Without the splits, 4 of 6 with the plain interval and no note."""
    from scipy import stats

    ref = reference(mode3a="1234")
    codes = {0: "1234", 4: "1235", 8: "1234", 12: "1234", 16: "1235", 20: "1234"}
    times = [0, 4, 4, 8, 12, 12, 16, 20]
    out = run("mode3a_correct", reports(times, mode3a=[codes[t] for t in times]), ref)
    assert counts(out) == (5, 8)
    deff = 2.9375 / 1.875
    assert out.ci_low == pytest.approx(stats.beta.ppf(0.025, 5 / deff, 3 / deff + 1), rel=1e-9)
    assert out.ci_high == pytest.approx(stats.beta.ppf(0.975, 5 / deff + 1, 3 / deff), rel=1e-9)
    assert "8 in 6 groups that are not independent (design effect 1.567)" in out.notes[-1]
    alone = run("mode3a_correct", reports(list(codes), mode3a=list(codes.values())), ref)
    assert counts(alone) == (4, 6)
    assert (alone.ci_low, alone.ci_high) == (pytest.approx(stats.beta.ppf(0.025, 4, 3), rel=1e-12),
                                             pytest.approx(stats.beta.ppf(0.975, 5, 2), rel=1e-12))
    assert not any("design effect" in n for n in alone.notes)


def test_mode3a_follows_a_code_change_in_the_reference():
    ref = reference(mode3a=["1234"] * 10 + ["7000"] * 11)
    rep = reports([0, 4, 8, 12, 16], mode3a=["1234", "1234", "1234", "7000", "1234"])
    assert counts(run("mode3a_correct", rep, ref)) == (4, 5)


def test_validity_is_withheld_without_the_bits():
    rep = reports([0, 4], mode3a=["1234", "1234"])
    out = run("mode3a_valid", rep, reference(mode3a="1234"))
    assert np.isnan(out.value) and "mode3a_v" in out.notes[0]
    out = run("mode3a_correct", rep, reference(mode3a="1234"))
    assert counts(out) == (2, 2) and "taken as validated" in out.notes[0]


def test_modec_within_the_tolerance():
    # 0, 250 and 400 ft off; the last is garbled
    rep = reports([0, 4, 8, 12], flight_level=[100.0, 102.5, 104.0, 100.0], flight_level_v=[0, 0, 0, 1],
                  flight_level_g=[0, 0, 0, 1])
    ref = reference(altitude_ft=10_000.0)
    assert counts(run("modec_present", rep, ref)) == (4, 4)
    assert counts(run("modec_valid", rep, ref)) == (3, 4)
    correct = run("modec_correct", rep, ref, tolerance_ft=300.0)
    assert counts(correct) == (2, 4)
    assert ("of the 2 misses: 1 carries a Mode C not validated or garbled; 1 carries a Mode C outside the "
            "tolerance") in correct.notes
    assert counts(run("modec_false", rep, ref, tolerance_ft=300.0)) == (1, 3)
    assert counts(run("modec_correct", rep, ref, tolerance_ft=500.0)) == (3, 4)
    with pytest.raises(ValueError, match="tolerance_ft"):
        run("modec_correct", rep, ref)


def test_address_and_callsign():
    rep = reports([0, 4, 8, 12], address=["ABC123", "ABC124", None, "abc123"],
                  callsign=["AFR12 ", "AFR12", "AFR21", None])
    ref = reference(address="ABC123", callsign="AFR12")
    address = run("address_correct", rep, ref)
    assert counts(address) == (2, 4)
    assert "of the 2 misses: 1 carries no address; 1 carries a different address" in address.notes
    assert counts(run("address_false", rep, ref)) == (1, 3)
    assert counts(run("callsign_correct", rep, ref)) == (2, 4)
    assert counts(run("callsign_false", rep, ref)) == (1, 3)
    assert np.isnan(run("callsign_correct", rep, reference()).value)


def test_a_reference_call_sign_unread_judges_nothing():
    """The reference's call sign with characters outside the ICAO set (decoded "?", a damaged CAT021 item):
    the sensor's right call sign counted wrong (the LEBL hour with one aircraft's ADS-B call sign damaged:
    the multilateration's airborne callsign_correct fell from 100 % to 78 %). Those reports are not judged;
    a report whose own call sign is unread is still wrong against a readable reference."""
    from msdc.pipeline.evaluate.identification import identification_false

    ref = reference(times=range(9), callsign=["?????YA"] * 4 + ["RYR75YA"] * 5)  # unread for 0-3 s
    rep = reports([0, 1, 2, 5, 6, 7], callsign=["RYR75YA", "RYR75YA", "RYR75YA", "RYR75YA", "RYR75YA",
                                                "??R75YA"])
    out = run("callsign_correct", rep, ref)
    assert counts(out) == (2, 3)  # the 3 reports while the reference read ?????YA not judged
    assert ("3 reports whose reference call sign holds a character outside the ICAO set (shown '?'), not "
            "judged") in out.notes
    assert counts(run("callsign_false", rep, ref)) == (1, 3)
    ident = identification_false(rep, ref)
    assert (ident.count, ident.n) == (1, 3)


def test_an_address_is_not_judged_on_the_sensors_own_track_keyed_by_it():
    """Two aircraft on the sensor's own track: ABC123 is keyed by its address (whatever address the sensor
    reports, its track carries it), CS:AFR34 by its call sign. Of the four reports on ABC123 none is judged
    for its address (counted in a note); the two on AFR34's track are (one right, one wrong). The call sign
    is judged on both, its note counting the six own-track trials. All on ABC123's track: withheld."""
    keyed = reference(label="ABC123", address="ABC123", callsign="AFR12").assign(self_reference=True)
    by_cs = reference(label="CS:AFR34", azimuth_deg=90.0, address="DEF456", callsign="AFR34").assign(
        self_reference=True)
    ref = pd.concat([keyed, by_cs], ignore_index=True)
    rep = pd.concat([reports([0, 4, 8, 12], address="ABC123", callsign="AFR12"),
                     reports([2, 6], azimuth_deg=90.0, address=["DEF456", "DEF457"], callsign="AFR34")],
                    ignore_index=True)
    out = run("address_correct", rep, ref)
    assert counts(out) == (1, 2)
    assert any(n.startswith("4 reports on the sensor's own track, which is keyed by the address")
               for n in out.notes)
    assert "self-reference: 2 of 2 trials judged against the sensor's own track" in " ".join(out.notes)
    assert counts(run("address_false", rep, ref)) == (1, 2)
    call = run("callsign_correct", rep, ref)
    assert counts(call) == (6, 6)
    assert "self-reference: 6 of 6 trials" in " ".join(call.notes)
    one = run("address_correct", rep.iloc[[0, 4, 5]], ref)
    assert counts(one) == (1, 2)
    assert ("1 report on the sensor's own track, which is keyed by the address it reports, not judged"
            in one.notes)
    alone = run("address_correct", rep.iloc[:4], keyed)
    assert np.isnan(alone.value) and "keyed by the address it reports" in alone.notes[0]


# ---------------------------------------------------------------------------------------------------------
# False reports, association, bad input


def test_false_reports_beyond_the_distance():
    rep = reports([0, 4, 4, 8])
    rep.loc[2, "longitude"] += 5000.0 / 111_320.0  # 5 km east of the aircraft
    ref = reference(8)
    assert counts(run("false_reports", rep, ref, distance_m=2100.0)) == (1, 4)
    assert counts(run("false_reports", rep, ref, distance_m=6000.0)) == (0, 4)
    out = run("false_reports_per_scan", rep, ref, distance_m=2100.0)
    assert (out.count, out.n) == (1, 2.0)  # 8 s of reports over a 4 s scan
    # the far plot is associated with nobody, so the aircraft's updates are unchanged
    assert counts(run("pd", rep, ref)) == (3, 3)
    # without distance_m (the PSR standard gives none) a report is false beyond the association gate, 2 NM
    # (3704 m): 5 km east is, 3 km east is not
    assert run("false_reports_per_scan", rep, ref).count == 1
    near = rep.copy()
    near.loc[2, "longitude"] -= 2000.0 / 111_320.0
    assert run("false_reports_per_scan", near, ref).count == 0
    # a report when no reference aircraft is known is false whatever the distance
    late = reports([0, 4, 30])
    assert counts(run("false_reports", late, reference(8), distance_m=1e9)) == (1, 3)


def test_association_is_by_position_to_the_nearest_aircraft():
    ref = pd.concat([reference(label="A"), reference(label="B", azimuth_deg=1.0)])
    rep = reports([4, 4], azimuth_deg=0.0)
    rep.loc[1, ["latitude", "longitude"]] = position(4.0, azimuth_deg=0.9)
    out = associate(rep, ref)
    assert out["ref_aircraft"].tolist() == ["A", "B"]
    # 0.1 deg at 30.4 NM is 99 m, the distance to B
    assert out["ref_distance_m"].iloc[1] == pytest.approx(30.4 * 1852 * np.radians(0.1), rel=0.01)
    assert associate(rep, ref, {"gate_m": 50.0})["ref_aircraft"].tolist() == ["A", None]


def test_crossing_aircraft_keep_their_plots_by_level():
    # B is 0.1 deg (99 m) beside A but 20,000 ft above it
    a_ref, b_ref = reference(label="A", altitude_ft=10_000.0), reference(label="B", azimuth_deg=0.1,
                                                                           altitude_ft=30_000.0)
    rep = reports([4, 4, 4], azimuth_deg=0.1, flight_level=[100.0, 300.0, np.nan])
    both = pd.concat([a_ref, b_ref])
    assert associate(rep, both)["ref_aircraft"].tolist() == ["A", "B", "B"]
    # a Mode C far from the only aircraft in the gate still goes to it (a code error, judged apart)
    assert associate(rep, b_ref)["ref_aircraft"].tolist() == ["B", "B", "B"]
    assert associate(rep, both, {"vertical_gate_ft": 1e6})["ref_aircraft"].tolist() == ["B", "B", "B"]


def test_bad_input_is_named():
    with pytest.raises(ValueError, match="missing column.* in the reference: longitude"):
        run("pd", reports([0]), reference().drop(columns="longitude"))
    with pytest.raises(ValueError, match="missing column.* in the test reports: t_s"):
        run("pd", reports([0]).drop(columns="t_s"), reference())
    with pytest.raises(ValueError, match="no update interval"):
        run("pd", reports([0, 4]), reference(), Sensor(0.0, 0.0, 0.0))
    with pytest.raises(ValueError, match="max_range_nm must be a finite number"):
        Sensor(0.0, 0.0, 0.0, name="x", max_range_nm=float("nan"))
    with pytest.raises(ValueError, match="altitude_m must be a finite number, got True"):
        Sensor(0.0, 0.0, True)
    assert Sensor(np.float32(1.0), np.int64(2), 0).longitude == 2  # numpy numbers are numbers


# ---------------------------------------------------------------------------------------------------------
# A seeded simulation: every injected rate inside its 95 % interval

INJECTED = RadarEffects(pd=0.9, full_range_nm=140.0, max_range_nm=180.0, cone_elevation_deg=40.0,
                        mode3a_garble=0.03, mode3a_error=0.01, modec_garble=0.02, modec_error=0.015,
                        false_per_scan=2.0, split=0.03)
PARAMETERS = {"tolerance_ft": 300.0, "distance_m": 2100.0}


def evaluate_all(sim) -> tuple[dict, pd.DataFrame]:
    """Every requirement on the simulated radar against the simulator's truth as reference."""
    site, m = sim.declared_site, sim.north_markers
    sensor = Sensor(site.latitude, site.longitude, site.altitude_m, max_range_nm=sim.effects.full_range_nm,
                    max_elevation_deg=sim.effects.cone_elevation_deg,
                    north_markers_s=(m["day"] * 86400.0 + m["time_of_day"]).to_numpy())
    ref = sim.reference()
    rep = associate(radar_reports(sim.radar, sensor), ref)
    out = {}
    for name, (_, extra) in expected_rates(sim.effects, sim.scan_period_s).items():
        out[name] = REQUIREMENTS[name](rep, ref, {**PARAMETERS, **extra}, sensor)
    out["false_reports"] = REQUIREMENTS["false_reports"](rep, ref, PARAMETERS, sensor)
    return out, rep


@pytest.fixture(scope="module")
def simulated():
    sim = simulate_effects(effects=INJECTED, seed=2028)
    return sim, *evaluate_all(sim)


@pytest.mark.parametrize("name", list(expected_rates(INJECTED, 4.8)))
def test_simulation_recovers_the_injected_rate(simulated, name):
    sim, out, _ = simulated
    truth = expected_rates(sim.effects, sim.scan_period_s)[name][0]
    o = out[name]
    assert o.ci_low <= truth <= o.ci_high, (name, o)
    assert o.n > 500


def test_simulation_counts_match_the_truth(simulated):
    sim, out, rep = simulated
    p = sim.plots
    shown = p[p["row"] >= 0].sort_values("row")
    # every plot of an aircraft is associated with it, every false plot with nobody
    assert np.array_equal(rep["ref_index"].to_numpy(), shown["aircraft"].to_numpy())
    assert out["false_reports"].count == (p["kind"] == "false").sum()
    assert out["split_reports"].count == (p["kind"] == "split").sum()
    assert out["mode3a_valid"].n - out["mode3a_valid"].count == (shown["mode3a_error"] == "garbled").sum()
    assert out["modec_false"].count == (shown["modec_error"] == "wrong").sum()
    # detections inside coverage: the truth's crossings at their true range and elevation
    crossings = p[p["kind"].isin(["target", "missed"])]
    inside = crossings[(crossings["rho_true_nm"] <= INJECTED.full_range_nm)
                       & (crossings["elevation_deg"] <= INJECTED.cone_elevation_deg)]
    assert abs(out["pd"].count - int(inside["detected"].sum())) <= 2
    assert abs(out["pd"].n - len(inside)) <= 4
