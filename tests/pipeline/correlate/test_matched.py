"""The numbers a correlate report leads with (pipeline.correlate.matched) and its verdict, against the
simulator's truth: each radar report's distance from the reference at its own time is the radar's own
error (the truth's, at the report's time), whatever the slot fill and the ADS-B jumps; a radar 30 s late
shows as an along-track offset of 30 s of flight; injected range and azimuth biases show as the mean
offsets the truth gives.

The truth side is worked out here from the simulator alone (fixtures.simulate): the true position at the
report's time, the true track direction, and the truth's own duplicate, jump and low-quality flags.
"""

from __future__ import annotations

import math
import re
import warnings
from dataclasses import replace
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from fixtures import geodesy as geo
from fixtures.scenario import Scenario, bias_scenario
from fixtures.simulate import DEFAULT_SEED, simulate, write_fixtures
from msdc.pipeline.correlate.correlation import correlate
from msdc.pipeline.correlate.matched import matched_pairs, matched_summary, mean_and_se, window_accuracy
from msdc.pipeline.correlate.verdict import MIN_MATCHED_REPORTS, window_verdict
from msdc.pipeline.model.load import load
from msdc.pipeline.model.measurements import OutOfCoverageWarning, build_measurements
from msdc.pipeline.model.sensors import read_sensors
from msdc.pipeline.model.time import with_clock

FIX = Path(__file__).resolve().parents[3] / "fixtures"
SLOT_S = 10.0
QUIET = dict(adsb_jump_fraction=0.0, adsb_short_dropouts_per_hour=0.0, adsb_low_quality_episodes=0)


class Data:
    """One simulated recording decoded from its bytes, its truth, and the all-aircraft correlation."""

    def __init__(self, directory: Path, sim, **correlate_kw):
        loaded = load([directory / "radar.ast", directory / "adsb.ast"])
        with warnings.catch_warnings():  # an ADS-B jump of 6 deg lands out of coverage: said, and left out
            warnings.simplefilter("ignore", OutOfCoverageWarning)
            meas = with_clock(build_measurements(loaded.frames[48], loaded.frames[21],
                                                 read_sensors(directory / "sensors.toml"), date=loaded.date))
        radar = (meas["sensor_kind"] == "radar").to_numpy(bool)
        self.sim, self.meas = sim, meas
        self.radar, self.adsb = meas[radar].reset_index(drop=True), meas[~radar].reset_index(drop=True)
        self.run = correlate(meas, all_aircraft=True, **correlate_kw)

    def truth_rows(self, sensor: str, callsign: str, start_s: float, end_s: float) -> pd.DataFrame:
        """The truth rows of one sensor and aircraft in [start, end], duplicates (and ADS-B jumps) out."""
        tt = self.sim.truth_tracks
        keep = ((tt["sensor"] == sensor) & (tt["callsign"] == callsign) & tt["t_s"].between(start_s, end_s)
                & ~tt["duplicate"] & ~tt["jump"])
        return tt[keep]

    def reports(self, sensor: str, callsign: str, start_s: float, end_s: float) -> tuple[np.ndarray, ...]:
        """The decoded reports of those truth rows: time of day, latitude, longitude."""
        rows = self.truth_rows(sensor, callsign, start_s, end_s)["row"].to_numpy()
        frame = (self.radar if sensor == "radar" else self.adsb).iloc[rows]
        return tuple(frame[c].to_numpy(float) for c in ("time_of_day", "latitude", "longitude"))

    def truth_errors(self, callsign: str, t_s: np.ndarray, lat: np.ndarray, lon: np.ndarray
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Distance, along- and cross-track offset (m) of reported positions from the true position at
        their reported times, on the true track's direction (fixtures.geodesy, not msdc's)."""
        st = self.sim.aircraft_by_callsign(callsign).truth(t_s)
        rot = geo.enu_rotation(st.latitude, st.longitude)
        d = geo.geodetic_to_ecef(lat, lon, 0.0) - geo.geodetic_to_ecef(st.latitude, st.longitude, 0.0)
        east = np.einsum("...j,...j->...", rot[..., 0, :], d)
        north = np.einsum("...j,...j->...", rot[..., 1, :], d)
        trk = np.radians(st.track_deg)
        along = east * np.sin(trk) + north * np.cos(trk)
        cross = east * np.cos(trk) - north * np.sin(trk)
        return np.hypot(east, north), along, cross


def _data(tmp: Path, scenario: Scenario | str, seed: int, **kw) -> Data:
    write_fixtures(tmp, seed, scenario)
    return Data(tmp, simulate(scenario if isinstance(scenario, Scenario) else None, seed), **kw)


@pytest.fixture(scope="module")
def bundled() -> Data:
    return Data(FIX, simulate(seed=DEFAULT_SEED))


@pytest.fixture(scope="module")
def late(tmp_path_factory) -> Data:
    return _data(tmp_path_factory.mktemp("late"), Scenario(time_bias_s=30.0, **QUIET), 1)


@pytest.fixture(scope="module")
def biased(tmp_path_factory) -> Data:
    return _data(tmp_path_factory.mktemp("bias"), replace(bias_scenario(), time_bias_s=0.0), 2)


def _in_episodes(data: Data, callsign: str, t_s: np.ndarray) -> np.ndarray:
    """Report times inside an injected low-quality ADS-B episode of the aircraft (ADS-B sigma 100 m)."""
    out = np.zeros(t_s.size, bool)
    for ep in data.sim.truth["low_quality"]["episodes"]:
        if ep["callsign"] == callsign:
            out |= (t_s >= ep["start_s"] - 2.0) & (t_s <= ep["end_s"] + 2.0)
    return out


def test_each_matched_report_is_the_radar_error_at_its_time(bundled):
    """Bundled fixtures (ADS-B jumps, duplicates, dropouts, low-quality episodes): every radar report
    matched to the truth's clean ADS-B reports is as far from them as from the true position at its time,
    within 20 m (ADS-B noise 5 m a report, interpolation over ~1 s), outside low-quality episodes; and the
    windows' lead RMS, with the pipeline's own duplicate and jump detection, is within 3 % of the truth's
    radar error over the same reports. The thesis RMS of the same windows runs to kilometres."""
    checked = 0
    for res in bundled.run.windows:
        w = res.summary
        radar = bundled.reports("radar", w["callsign"], w["start_tod"], w["end_tod"])
        adsb = bundled.reports("adsb", w["callsign"], w["start_tod"], w["end_tod"])
        pairs = matched_pairs(radar, adsb, w["start_tod"], w["end_tod"], SLOT_S)
        at = np.isin(radar[0], pairs["time_of_day"])
        truth_sep, _, _ = bundled.truth_errors(w["callsign"], radar[0][at], radar[1][at], radar[2][at])
        clean = ~_in_episodes(bundled, w["callsign"], pairs["time_of_day"])
        assert np.abs(pairs["sep_m"] - truth_sep)[clean].max() < 20.0, w["callsign"]
        assert pairs["sep_m"].size >= 0.9 * radar[0].size  # nearly every radar report has a reference
        truth_rms = math.sqrt(np.mean(truth_sep**2))
        assert w["matched_reports"] == pytest.approx(pairs["sep_m"].size, abs=2)
        assert w["matched_sep_rms_m"] == pytest.approx(truth_rms, rel=0.03), (w["callsign"], w["window"])
        checked += 1
    assert checked == len(bundled.run.windows) == 10
    thesis = [w.summary["sep_rms_m"] for w in bundled.run.windows]
    assert max(thesis) > 5000.0 and max(w.summary["matched_sep_rms_m"] for w in bundled.run.windows) < 400.0


def test_the_lead_numbers_do_not_depend_on_the_fill_or_on_dropping_jumps(bundled):
    """Filled slots are never read and jumps are left out either way: --fill predict and --drop-jumps give
    the same lead numbers and verdicts as the thesis defaults."""
    from msdc.pipeline.quality.filters import apply_filters

    keys = ["matched_reports", "matched_sep_median_m", "matched_sep_rms_m", "matched_along_mean_m",
            "matched_cross_mean_m", "matched_time_offset_s", "verdict"]
    base = [[w.summary[k] for k in keys] for w in bundled.run.windows]
    mas72 = [row for row, w in zip(base, bundled.run.windows, strict=True)
             if w.summary["callsign"] == "MAS72"]
    predicted = correlate(bundled.meas, callsign="MAS72", fill="predict")  # (the tracker: one aircraft)
    assert [[w.summary[k] for k in keys] for w in predicted.windows] == mas72
    assert any(w.summary["adsb_filled_slots"] for w in predicted.windows)
    dropped, removed = apply_filters(bundled.meas, drop_jumps=True)
    assert removed["jumps"] > 0
    without = correlate(dropped, all_aircraft=True)
    for got, want in zip(without.windows, bundled.run.windows, strict=True):
        assert got.summary["matched_reports"] == want.summary["matched_reports"]
        assert got.summary["matched_sep_rms_m"] == pytest.approx(want.summary["matched_sep_rms_m"], rel=1e-12)
        assert got.summary["sep_rms_m"] != pytest.approx(want.summary["sep_rms_m"], rel=0.1) or \
            want.summary["adsb_jumps"] == 0


def test_a_late_radar_shows_as_a_time_offset(late):
    """Radar times 30 s late (quiet ADS-B): in every window of at least 30 matched reports the radar plots
    trail ADS-B by 30 s of flight and the verdict says so. The time offset is -along / speed: 30 s where
    the last 30 s were flown straight at constant speed, less on a turn (the chord is shorter than the
    arc) or after accelerating. It equals the truth's -along / speed of the same reports within 0.2 s, and
    30 s within 1.5 s."""
    checked = 0
    for res in late.run.windows:
        w = res.summary
        if w["matched_reports"] < 30:
            continue
        radar = late.reports("radar", w["callsign"], w["start_tod"], w["end_tod"])
        _, along, _ = late.truth_errors(w["callsign"], *radar)
        speed_ms = late.sim.aircraft_by_callsign(w["callsign"]).truth(radar[0]).ground_speed_kt * 1852 / 3600
        assert w["matched_time_offset_s"] == pytest.approx(float(np.mean(-along / speed_ms)), abs=0.2), w
        assert w["matched_time_offset_s"] == pytest.approx(30.0, abs=1.5), w
        assert w["verdict"].startswith("systematic offset: ") and "behind ADS-B along track" in w["verdict"]
        said = re.search(r"behind ADS-B along track \(([0-9.]+) s of flight\)", w["verdict"])
        assert said and float(said.group(1)) == pytest.approx(w["matched_time_offset_s"], abs=0.05)
        checked += 1
    assert checked >= 5


def test_injected_biases_show_as_the_truths_mean_offsets(biased):
    """Range bias 150 m, gain 100 ppm, azimuth bias 0.12 deg: each window's mean along- and cross-track
    offsets are the truth's mean offsets of the same reports within 3 standard errors + 10 m, and a mean
    the truth puts beyond 6 standard errors is named by the verdict."""
    named = 0
    for res in biased.run.windows:
        w = res.summary
        if w["matched_reports"] < MIN_MATCHED_REPORTS:
            continue
        radar = biased.reports("radar", w["callsign"], w["start_tod"], w["end_tod"])
        _, along, cross = biased.truth_errors(w["callsign"], *radar)
        for key, truth in (("along", along), ("cross", cross)):
            mean, se = w[f"matched_{key}_mean_m"], w[f"matched_{key}_se_m"]
            assert mean == pytest.approx(float(np.mean(truth)), abs=3 * se + 10.0), (w["callsign"], key)
            if abs(np.mean(truth)) > 6 * se:
                side = ("ADS-B along track" if key == "along" else "of the ADS-B track")
                assert side in w["verdict"], w["verdict"]
                named += 1
    assert named >= 3


def test_mean_and_se_allow_for_correlated_reports():
    """White noise: the plain standard error sigma / sqrt(n). A random walk's steps are correlated (lag-1
    near 1): its standard error is at least 5 times the white-noise formula."""
    rng = np.random.default_rng(3)
    white = rng.normal(10.0, 2.0, 4000)
    mean, se = mean_and_se(white)
    assert mean == pytest.approx(10.0, abs=4 * 2.0 / math.sqrt(4000))
    assert se == pytest.approx(2.0 / math.sqrt(4000), rel=0.1)
    walk = np.cumsum(rng.normal(0.0, 1.0, 4000))
    assert mean_and_se(walk)[1] > 5 * walk.std(ddof=1) / math.sqrt(4000)
    assert math.isnan(mean_and_se(np.array([1.0, 2.0]))[1])


def test_matched_pairs_by_hand():
    """A reference flying east at 100 m/s along the equator, reported every second; radar reports 50 m
    north of it at 2.5 s and 7.25 s, and one in a slot the reference did not report (no match). The
    distances are 50 m, the along-track offset 0, the cross-track offset -50 m (left of an eastbound
    track) and the speed 100 m/s; a gap longer than a slot is not bridged."""
    m_per_deg = 6378137.0 * math.pi / 180.0  # on the equator: east along the equator, north along a meridian
    t_ref = np.arange(0.0, 11.0)
    ref = (t_ref, np.zeros(t_ref.size), 100.0 * t_ref / m_per_deg)
    north_deg = math.degrees(50.0 / 6335439.327)  # 50 m north at the equator (meridian radius of curvature)
    t_radar = np.array([2.5, 7.25, 25.0])
    radar = (t_radar, np.full(3, north_deg), 100.0 * t_radar / m_per_deg)
    pairs = matched_pairs(radar, ref, 0.0, 30.0, SLOT_S)
    assert pairs["time_of_day"].tolist() == [2.5, 7.25]
    assert pairs["sep_m"] == pytest.approx([50.0, 50.0], abs=0.01)
    assert pairs["along_m"] == pytest.approx([0.0, 0.0], abs=0.01)
    assert pairs["cross_m"] == pytest.approx([-50.0, -50.0], abs=0.01)
    assert pairs["speed_ms"] == pytest.approx([100.0, 100.0], rel=1e-3)
    s = matched_summary(pairs)
    assert s["matched_reports"] == 2 and s["matched_sep_rms_m"] == pytest.approx(50.0, abs=0.01)
    assert s["matched_time_offset_s"] == pytest.approx(0.0, abs=1e-4)
    # a 20 s hole in the reference: the report at 9 s sits in a slot the reference reported (at 0-3 s) but
    # the reference reports around it are 20 s apart
    t_holed = np.r_[0.0, 1.0, 2.0, 3.0, 23.0, 24.0, 25.0]
    holed = (t_holed, np.zeros(t_holed.size), 100.0 * t_holed / m_per_deg)
    lone = (np.array([9.0]), np.zeros(1), np.array([900.0 / m_per_deg]))
    assert matched_pairs(lone, holed, 0.0, 30.0, SLOT_S)["sep_m"].size == 0
    assert matched_pairs(lone, ref, 0.0, 30.0, SLOT_S)["sep_m"] == pytest.approx([0.0], abs=0.01)


def test_verdict_wording():
    """Too few reports: no verdict. Offsets within 3 standard errors: none named. Beyond: named with their
    side and, along track, the seconds of flight, but not their cause (one window cannot tell a time-stamp
    error from a range or azimuth bias); ADS-B jumps left out are counted."""
    few = window_verdict({"matched_reports": 4})
    assert few.startswith("no verdict: 4 radar reports matched")
    quiet = {"matched_reports": 200, "matched_sep_rms_m": 312.4, "matched_along_mean_m": 20.0,
             "matched_along_se_m": 10.0, "matched_cross_mean_m": -25.0, "matched_cross_se_m": 10.0,
             "matched_time_offset_s": -0.1, "adsb_jumps": 2}
    assert window_verdict(quiet) == ("no systematic offset beyond the noise; 312 m RMS from ADS-B over 200 "
                                     "reports; 2 ADS-B position jumps left out")
    parked = {**quiet, "matched_along_mean_m": None, "matched_along_se_m": None, "matched_cross_mean_m": None,
              "matched_cross_se_m": None, "matched_time_offset_s": None, "adsb_jumps": 0}
    assert window_verdict(parked).startswith("offsets not judged (too few reports moving faster than 20")
    late = {**quiet, "matched_along_mean_m": -6900.0, "matched_time_offset_s": 30.04, "adsb_jumps": 0,
            "matched_cross_mean_m": 45.0}
    assert window_verdict(late, "048:25/202") == (
        "systematic offset: 6,900 m behind 048:25/202 along track (30.0 s of flight); 45 m right of the "
        "048:25/202 track; 312 m RMS from 048:25/202 over 200 reports; a time-stamp, range or azimuth "
        "error: the radar's biases (--quality) tell which")
    # multilateration against ADS-B: --quality fits no bias of it, so the verdict does not point there
    assert window_verdict(late, "ADS-B", "010:0/107:mlat").endswith(
        "312 m RMS from ADS-B over 200 reports; a time-stamp or position error of either sensor (--quality "
        "fits biases for CAT048 radars only)")
    assert window_verdict({"matched_reports": 4}, "ADS-B", "010:0/107:mlat") == (
        "no verdict: 4 reports of 010:0/107:mlat matched to ADS-B at their own time (at least 10 needed)")
    # no mean offset stands out, but a 55 km RMS is no sensor's noise (four times ESASSP R3's 500 m is 2 km)
    far = {**quiet, "matched_sep_rms_m": 55281.0, "matched_along_se_m": 4000.0, "matched_cross_se_m": 3000.0,
           "adsb_jumps": 0}
    assert window_verdict(far) == (
        "no constant offset along or across track; 55,281 m RMS from ADS-B over 200 reports, far beyond "
        "any sensor's noise (past 2,000 m): an error that changes along the flight, such as a wrong sensor "
        "site or a bias seen from a turning flight; the radar's site and biases are to be checked (--quality "
        "fits the biases)")
    assert window_verdict({**far, "matched_sep_rms_m": 1999.0}).startswith("no systematic offset beyond the "
                                                                            "noise; 1,999 m RMS")
    assert "either sensor's site and biases are to be checked; " in window_verdict(
        {**far, "adsb_jumps": 1}, "ADS-B", "010:0/107:mlat")
    # parked far away: offsets not judged, and the distance still said to be no noise
    assert window_verdict({**parked, "matched_sep_rms_m": 55281.0}).startswith(
        "offsets not judged (too few reports moving faster than 20 m/s for a direction of travel); 55,281 m "
        "RMS from ADS-B over 200 reports, far beyond any sensor's noise")


def test_a_radar_placed_55_km_off_is_never_said_to_agree_within_the_noise(tmp_path):
    """The bundled recordings with the radar's site given 0.5 deg north of where it is (55.6 km on the
    ellipsoid: the plots land about that far from the aircraft): every window names a systematic offset or
    says the distance is far beyond any sensor's noise; none says it is noise (a turning flight's along and
    cross offsets average out: MAS72's second window did)."""
    site = (FIX / "sensors.toml").read_text()
    moved = tmp_path / "moved.toml"
    moved.write_text(site.replace("latitude = 2.7456", "latitude = 3.2456"))
    assert moved.read_text() != site
    loaded = load([FIX / "radar.ast", FIX / "adsb.ast"])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", OutOfCoverageWarning)
        meas = with_clock(build_measurements(loaded.frames[48], loaded.frames[21], read_sensors(moved),
                                             date=loaded.date))
    verdicts = [w.summary["verdict"] for w in correlate(meas, all_aircraft=True).windows]
    assert len(verdicts) == 10
    for v in verdicts:
        rms = float(re.search(r"([\d,]+) m RMS", v).group(1).replace(",", ""))
        assert 50_000 < rms < 60_000, v
        assert v.startswith("systematic offset: ") or "far beyond any sensor's noise" in v, v
    assert sum("far beyond any sensor's noise" in v for v in verdicts) >= 1


def test_window_accuracy_takes_the_radar_errors_of_its_radar_aircraft_and_time():
    """The quality step's errors of the window's radar (SAC/SIC from "048:25/201"), aircraft (call sign and
    address) and span only: of the six rows below, the first three (range errors 10, 20, 60 m: mean 30,
    SD sqrt(((-20)^2 + (-10)^2 + 30^2) / 2) = sqrt(700)); another radar, aircraft or a later time is not
    the window's."""
    errors = pd.DataFrame({
        "sac": [25, 25, 25, 25, 25, 30], "sic": [201, 201, 201, 201, 201, 201],
        "callsign": ["MAS72", "MAS72", "MAS72", "MAS72", "SIA305", "MAS72"],
        "address": ["750312"] * 6, "time_of_day": [100.0, 110.0, 120.0, 500.0, 110.0, 110.0],
        "range_error_m": [10.0, 20.0, 60.0, 999.0, 999.0, 999.0],
        "azimuth_error_deg": [0.1, 0.0, -0.1, 9.0, 9.0, 9.0]})
    window = {"radar_sensor": "048:25/201", "callsign": "MAS72", "address": "750312", "start_tod": 100.0,
              "end_tod": 200.0}
    (got,) = window_accuracy([window], errors)
    assert got["quality_reports"] == 3
    assert got["range_error_mean_m"] == pytest.approx(30.0)
    assert got["range_error_std_m"] == pytest.approx(math.sqrt(700.0))
    assert got["azimuth_error_mean_deg"] == pytest.approx(0.0, abs=1e-12)
    assert got["azimuth_error_std_deg"] == pytest.approx(0.1)
    (none,) = window_accuracy([{**window, "radar_sensor": "048:25/202"}], errors)
    assert none["quality_reports"] == 0 and none["range_error_mean_m"] is None
    # an aircraft without a call sign: the quality step's errors carry <NA>, the window ""
    anonymous = errors.assign(callsign=pd.array([pd.NA] * 6, dtype="string"),
                              address=["750312"] * 4 + ["76CDA3", "750312"])
    (got,) = window_accuracy([{**window, "callsign": ""}], anonymous)
    assert got["quality_reports"] == 3


def test_a_window_of_an_aircraft_with_two_targets_says_so():
    import pandas as pd

    from msdc.pipeline.correlate.verdict import mention_mixed
    from msdc.pipeline.model.mixed import mixed_pairs

    mixed = mixed_pairs(pd.DataFrame({"aircraft_id": ["750312", "CS:ABC"],
                                      "sensor_id": ["021:0/1", "048:25/201"]}))
    windows = [{"address": "750312", "callsign": "MAS72", "radar_sensor": "048:25/201",
                "reference_sensor": "021:0/1", "verdict": "no systematic offset beyond the noise"},
               {"address": None, "callsign": "ABC", "radar_sensor": "048:25/201",
                "reference_sensor": "021:0/1", "verdict": "v"},
               {"address": "750312", "callsign": "MAS72", "radar_sensor": "048:25/202",
                "reference_sensor": "021:0/2", "verdict": "v"}]
    assert mention_mixed(windows, mixed) == 2
    assert windows[0]["verdict"] == ("no systematic offset beyond the noise; two targets may share this "
                                     "identity on 021:0/1 (its reports switch between two places): these "
                                     "numbers mix both")
    assert "on 048:25/201 (" in windows[1]["verdict"] and windows[2]["verdict"] == "v"
    # the pairs as written by hand say the same
    again = [{**w, "verdict": "v"} for w in windows]
    assert mention_mixed(again, (("750312", "021:0/1"), ("CS:ABC", "048:25/201"))) == 2
    assert [w["verdict"] == "v" for w in again] == [False, False, True]
