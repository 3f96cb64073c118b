"""End-to-end validation of the correlation pipeline against the scenario simulator's truth.

Every case goes through real bytes: simulate -> asterix.encode (``write_fixtures``) -> ``asterix.read`` ->
``pipeline.model.measurements`` -> ``pipeline.correlate.correlation.correlate``, and the
results are compared with what
the simulator injected (``Simulation.truth`` / ``truth.json`` and ``truth_tracks``). The bundled fixtures
(fixtures/radar.ast, adsb.ast, sensors.toml, truth.json) are checked the same way, through
``pipeline.model.load`` and the ``msdc correlate`` command as a user would run them.

Data sets:

* ``bundled``: the committed fixtures (default scenario, seed 2019), with every effect injected:
  duplicates, missing/zero radar speeds, ADS-B position jumps, short and long dropouts, low-quality
  ADS-B episodes, and MAS136 coming back 2 h 25 min after leaving.
* ``quiet``: the default scenario without ADS-B jumps, short dropouts and low-quality episodes, seeds
  1, 3 and 7 (duplicates, bad radar speeds and long dropouts kept, so windows and dedup are still tested);
  this is where the correlation coefficients and separations are held to the noise model.
* ``near_gap``: ADS-B short dropouts of 170-176 s (gaps that must NOT split a period) and long dropouts
  of 181-186 s (gaps that must), seed 11.
* ``midnight``: the midnight preset (23:50 to 00:20 UTC) decoded from raw blocks with ``date=``, and the
  same scenario moved to noon.
* ``late_radar``: the quiet scenario with radar times reported 30 s late, for the lag sign.
* ``antimeridian``: quiet seed 1 seen from a radar at 17.75 S 179.9 E: the same flights relative to the
  site, with tracks and slots across +-180 deg.
"""

from __future__ import annotations

import json
import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from fixtures import geodesy as geo
from fixtures.scenario import RadarSite, Scenario, midnight_scenario
from fixtures.simulate import DEFAULT_SEED, TOD_LSB_S, Simulation, simulate, write_fixtures
from msdc.pipeline.cli import main as msdc
from msdc.pipeline.correlate.correlation import correlate
from msdc.pipeline.correlate.slots import slot_index
from msdc.pipeline.model.dedup import deduplicate
from msdc.pipeline.model.geodesy import M_PER_NM
from msdc.pipeline.model.load import load
from msdc.pipeline.model.measurements import build_measurements, radar_measurements, select
from msdc.pipeline.model.sensors import read_sensors
from msdc.pipeline.model.time import with_clock

# one worker runs the module: the simulated cases made once, not on each worker
pytestmark = pytest.mark.xdist_group("truth")

FIX = Path(__file__).resolve().parents[3] / "fixtures"
SLOT_S = 10.0
QUIET = dict(adsb_jump_fraction=0.0, adsb_short_dropouts_per_hour=0.0, adsb_low_quality_episodes=0)
QUIET_SEEDS = (1, 3, 7)
MIDNIGHT_SEED = 5
NEAR_GAP = Scenario(name="near-gap", adsb_short_dropout_s=(170.0, 176.0), adsb_long_dropout_s=(181.0, 186.0),
                    radar_long_dropout_s=(181.0, 186.0), radar_long_dropouts=2)
NEAR_GAP_SEED = 11
FIJI = RadarSite(name="Nadi", sac=30, sic=1, latitude=-17.75, longitude=179.9, altitude_m=20.0)
DAY0 = "2019-06-30"
KT_MS = M_PER_NM / 3600.0

# Slot-timing mismatch (RMS, s) between the radar and the ADS-B slot means. The radar reports every
# T = 4.8 s, so a 10-s slot holds two reports at u and u + T (u uniform in [0.4, 4.8) s from the slot
# start) or three (u < 0.4): their mean time u + T/2 lies in [2.8, 7.2] s, up to 2.2 s from mid-slot,
# with RMS sqrt(4.4/4.8 * 2.2^2/3) = 1.22 s. ADS-B reports every 0.5-1.5 s average to within ~0.3 s of
# mid-slot. The two slot means therefore describe the aircraft ~1.25 s apart (RMS), i.e. v * 1.25 s
# along track (190-300 m at 300-465 kt): a property of the thesis's plain per-slot mean, as large as
# the radar noise itself.
SLOT_TIMING_RMS_S = 1.25


# ----------------------------------------------------------------------------------------------------------
# Data sets


class Case:
    """One decoded data set: its simulation (truth), measurements and the all-aircraft correlation."""

    def __init__(self, sim: Simulation, truth: dict, radar: pd.DataFrame, adsb: pd.DataFrame, date=None):
        self.sim, self.truth, self.radar, self.adsb = sim, truth, radar, adsb
        self.run = correlate(pd.concat([radar, adsb], ignore_index=True), all_aircraft=True)

    def windows(self, callsign: str | None = None) -> list[dict]:
        return [w.summary for w in self.run.windows if callsign in (None, w.summary["callsign"])]

    def results(self):
        return self.run.windows

    def truth_windows(self, callsign: str | None = None) -> list[dict]:
        return [w for w in self.truth["overlap_windows"] if callsign in (None, w["callsign"])]

    def track(self, callsign: str, sensor: str, start_s: float, end_s: float) -> pd.DataFrame:
        """Truth rows of one aircraft and sensor inside [start, end], duplicates left out."""
        tt = self.sim.truth_tracks
        m = ((tt["callsign"] == callsign) & (tt["sensor"] == sensor) & tt["t_s"].between(start_s, end_s)
             & ~tt["duplicate"])
        return tt[m]


def decode_dir(directory: Path, date=None) -> tuple[pd.DataFrame, pd.DataFrame]:
    """Radar and ADS-B measurements of radar.ast / adsb.ast / sensors.toml in a directory, loaded as ``msdc``
    does, with the thesis clock (``time_of_day`` from the first midnight) for the checks."""
    loaded = load([directory / "radar.ast", directory / "adsb.ast"], date=date)
    assert loaded.errors.empty
    sensors = read_sensors(directory / "sensors.toml")
    meas = with_clock(build_measurements(loaded.frames[48], loaded.frames[21], sensors, date=loaded.date))
    is_radar = (meas["sensor_kind"] == "radar").to_numpy(bool)
    return meas[is_radar].reset_index(drop=True), meas[~is_radar].reset_index(drop=True)


def simulated_case(tmp: Path, scenario: Scenario, seed: int, date=None) -> Case:
    write_fixtures(tmp, seed, scenario)
    sim = simulate(scenario, seed)
    truth = json.loads((tmp / "truth.json").read_text())
    radar, adsb = decode_dir(tmp, date)
    return Case(sim, truth, radar, adsb)


@pytest.fixture(scope="module")
def bundled() -> Case:
    radar, adsb = decode_dir(FIX)
    return Case(simulate(seed=DEFAULT_SEED), json.loads((FIX / "truth.json").read_text()), radar, adsb)


@pytest.fixture(scope="module")
def quiet(tmp_path_factory) -> list[Case]:
    return [simulated_case(tmp_path_factory.mktemp(f"quiet{seed}"), Scenario(name="quiet", **QUIET), seed)
            for seed in QUIET_SEEDS]


@pytest.fixture(scope="module")
def near_gap(tmp_path_factory) -> Case:
    return simulated_case(tmp_path_factory.mktemp("near_gap"), NEAR_GAP, NEAR_GAP_SEED)


@pytest.fixture(scope="module")
def late_radar(tmp_path_factory) -> Case:
    return simulated_case(tmp_path_factory.mktemp("late"), Scenario(time_bias_s=30.0, **QUIET), 1)


@pytest.fixture(scope="module")
def antimeridian(tmp_path_factory) -> Case:
    return simulated_case(tmp_path_factory.mktemp("fiji"), Scenario(radar=FIJI, **QUIET), QUIET_SEEDS[0])


@pytest.fixture(scope="module")
def midnight(tmp_path_factory) -> Case:
    return simulated_case(tmp_path_factory.mktemp("midnight"), midnight_scenario(), MIDNIGHT_SEED, DAY0)


@pytest.fixture(scope="module")
def noon(tmp_path_factory) -> Case:
    sc = replace(midnight_scenario(), start_tod_s=12 * 3600.0 - 600.0)
    return simulated_case(tmp_path_factory.mktemp("noon"), sc, MIDNIGHT_SEED, DAY0)


@pytest.fixture(params=["bundled", "quiet", "near_gap", "midnight", "antimeridian"])
def cases(request) -> list[Case]:
    got = request.getfixturevalue(request.param)
    return got if isinstance(got, list) else [got]


def turn_deg(track: pd.DataFrame) -> float:
    """Total heading change (deg) of a truth track."""
    return float(np.degrees(np.abs(np.diff(np.unwrap(np.radians(track["track_deg"].to_numpy())))).sum()))


def slot_sigma_m(sc: Scenario, rho_nm, v_ms, n_radar: int = 2):
    """RMS radar-minus-ADS-B separation of one slot expected from the noise model (see SLOT_TIMING_RMS_S).

    radar: range sigma and azimuth sigma * R (cross range), averaged over ``n_radar`` reports;
    ADS-B: sigma per axis over >= 5 reports; slot timing: v * SLOT_TIMING_RMS_S.
    """
    cross_m = np.asarray(rho_nm) * M_PER_NM * math.radians(sc.sigma_azimuth_deg)
    return np.sqrt((sc.sigma_range_m**2 + cross_m**2) / n_radar + 2 * sc.adsb_sigma_position_m**2 / 5
                   + (np.asarray(v_ms) * SLOT_TIMING_RMS_S) ** 2)


# ----------------------------------------------------------------------------------------------------------
# The bundled fixtures are the default scenario


def test_bundled_fixtures_are_the_default_scenario(tmp_path):
    """The committed recordings and truth are what the simulator writes today (else the truth is stale).

    Regenerate with: python -m fixtures.simulate fixtures --seed 2019 --scenario default
    """
    write_fixtures(tmp_path, DEFAULT_SEED, "default")
    for name in ("radar.ast", "adsb.ast", "sensors.toml"):
        assert (tmp_path / name).read_bytes() == (FIX / name).read_bytes(), f"fixtures/{name} is stale"
    fresh = json.loads((tmp_path / "truth.json").read_text())
    committed = json.loads((FIX / "truth.json").read_text())
    # Floats may differ in the last digit between numpy builds (libm); the recordings above are exact.
    assert _close(fresh, committed)


def _close(a, b, path="truth") -> bool:
    """Deep equality with floats compared to 1e-12 relative (numpy builds differ in the last ulp)."""
    if isinstance(a, dict):
        assert isinstance(b, dict) and a.keys() == b.keys(), path
        return all(_close(a[k], b[k], f"{path}/{k}") for k in a)
    if isinstance(a, list):
        assert isinstance(b, list) and len(a) == len(b), path
        return all(_close(x, y, f"{path}[{i}]") for i, (x, y) in enumerate(zip(a, b, strict=True)))
    if isinstance(a, float) or isinstance(b, float):
        assert math.isclose(a, b, rel_tol=1e-12, abs_tol=1e-12), f"{path}: {a} != {b}"
        return True
    assert a == b, f"{path}: {a!r} != {b!r}"
    return True


def test_decoded_frames_equal_the_simulated_ones(bundled):
    """The encode/decode round trip returns the simulator's values exactly (all are multiples of the LSBs)."""
    loaded = load([FIX / "radar.ast", FIX / "adsb.ast"])
    for cat, sim_frame in ((48, bundled.sim.radar), (21, bundled.sim.adsb)):
        got = loaded.frames[cat]
        assert len(got) == len(sim_frame)
        for col in sim_frame.columns:
            a, b = got[col].to_numpy(), sim_frame[col].to_numpy()
            if sim_frame[col].dtype.kind == "f":
                np.testing.assert_array_equal(a.astype(float), b, err_msg=f"CAT{cat:03d} {col}")
            else:
                assert (pd.Series(a).astype(str) == pd.Series(b).astype(str)).all(), f"CAT{cat:03d} {col}"


# ----------------------------------------------------------------------------------------------------------
# Windows, duplicates and slot counts against truth


def test_windows_are_the_truth_overlap_windows(cases):
    """Per aircraft, the windows found are the truth's overlap windows (from emitted report times) within one
    ToD LSB; degenerate ones (shorter than a slot) are skipped with a reason, none is lost or invented."""
    for case in cases:
        found = sorted([(w["callsign"], w["start_tod"], w["end_tod"]) for w in case.windows()]
                       + [(s.callsign, s.start_tod, s.end_tod) for s in case.run.skipped])
        want = sorted((w["callsign"], w["start_s"], w["end_s"]) for w in case.truth_windows())
        assert [f[0] for f in found] == [w[0] for w in want]
        for f, w in zip(found, want, strict=True):
            assert f[1] == pytest.approx(w[1], abs=TOD_LSB_S) and f[2] == pytest.approx(w[2], abs=TOD_LSB_S)
        for s in case.run.skipped:
            assert s.end_tod - s.start_tod < SLOT_S and "shorter than one slot" in s.reason


def test_windows_split_at_the_injected_gaps(cases):
    """Consecutive windows of an aircraft are separated by truth gaps (dropouts, absences) of more than G."""
    for case in cases:
        gaps = case.truth["adsb_gaps"] + case.truth["radar_gaps"]
        for cs in {w["callsign"] for w in case.windows()}:
            ws = case.windows(cs)
            for a, b in zip(ws[:-1], ws[1:], strict=True):
                between = [g for g in gaps if g["callsign"] == cs and a["end_tod"] <= g["start_s"]
                           and g["end_s"] <= b["start_tod"]]
                assert between, f"{cs}: windows {a['window']} and {b['window']} are not separated by a gap"
                assert all(g["duration_s"] > case.truth["gap_rule_s"] for g in between)


def test_gap_rule_near_the_threshold(near_gap):
    """Gaps of 170-178 s stay inside a window, gaps of more than 180 s end it (G = 180 s, "more than")."""
    inside = 0
    for w in near_gap.windows():
        for meas in (near_gap.radar, near_gap.adsb):
            t = np.sort(meas.loc[(meas["callsign"] == w["callsign"])
                                 & meas["time_of_day"].between(w["start_tod"], w["end_tod"]), "time_of_day"])
            gaps = np.diff(t)
            assert gaps.max() <= 180.0
            inside += int((gaps > 170.0).sum())
    assert inside >= 10
    assert sum(g["duration_s"] < 190.0 for g in near_gap.truth["adsb_gaps"]) >= 3


def test_duplicates_per_aircraft_and_per_window(cases):
    """Dedup drops exactly the injected duplicates, per aircraft and sensor (at the injected times), and the
    window counts equal the truth duplicates inside each window."""
    for case in cases:
        truth_dups = case.truth["duplicates"]
        for cs in truth_dups["radar"]["by_aircraft"]:
            for sensor, meas in (("radar", case.radar), ("adsb", case.adsb)):
                ordered = select(meas, callsign=cs).sort_values("time_of_day", kind="stable")
                _, dropped = deduplicate(ordered)
                want = truth_dups[sensor]["by_aircraft"][cs]
                assert dropped == want["count"], (cs, sensor)
                dropped_t = np.sort(ordered["time_of_day"].to_numpy()[ordered.duplicated(
                    ["time_of_day", "latitude", "longitude", "ground_speed_kt", "heading_deg"]).to_numpy()])
                np.testing.assert_allclose(dropped_t, np.sort(want["t_s"]), atol=TOD_LSB_S)
        truth_w = {(w["callsign"], round(w["start_s"] * 128)): w for w in case.truth_windows()}
        for w in case.windows():
            t = truth_w[(w["callsign"], round(w["start_tod"] * 128))]
            assert w["radar_duplicates"] == t["radar_duplicates"]
            assert w["adsb_duplicates"] == t["adsb_duplicates"]
            assert w["radar_before"] == t["radar_rows"] - t["radar_duplicates"]
            assert w["adsb_before"] == t["adsb_rows"] - t["adsb_duplicates"]


def test_missing_speed_duplicates_are_dropped(bundled):
    """The bundled data holds radar duplicates whose speed and heading are missing (and zero): missing
    compares equal, so each such pair loses its copy."""
    tt = bundled.sim.truth_tracks
    for flag in ("missing", "zero"):
        dup = tt[tt["duplicate"] & (tt["speed_flag"] == flag)]
        assert len(dup) >= 1
        for row in dup.itertuples():
            rows = bundled.radar[(bundled.radar["callsign"] == row.callsign)
                                 & (bundled.radar["time_of_day"] == row.t_s)]
            assert len(rows) == 2 and rows["ground_speed_kt"].isna().all() == (flag == "missing")
            kept, dropped = deduplicate(rows)
            assert dropped == 1 and len(kept) == 1


def test_slot_counts(cases):
    """Both sensors get N = floor((end - start) / 10) + 1 slots, computed here in integer ToD LSBs; every
    report in the window lands in a slot, and empty slots repeat the previous (leading: first) value."""
    filled_slots = edges = 0
    for case in cases:
        for res in case.results():
            w = res.summary
            start, end = round(w["start_tod"] * 128), round(w["end_tod"] * 128)
            assert start == w["start_tod"] * 128 and end == w["end_tod"] * 128  # exact LSB multiples
            n = (end - start) // 1280 + 1
            assert w["slots"] == w["radar_after"] == w["adsb_after"] == len(res.slots) == n
            s = res.slots
            assert s["slot"].tolist() == list(range(n))
            np.testing.assert_array_equal(s["time_of_day"].to_numpy(), w["start_tod"] + SLOT_S * np.arange(n))
            assert s["radar_count"].sum() == w["radar_before"] and s["adsb_count"].sum() == w["adsb_before"]
            for sensor, meas in (("radar", case.radar), ("adsb", case.adsb)):
                # slot k holds start + kD <= t < start + (k+1)D: in integer LSBs, k = (t - start) // 1280
                t = deduplicate(select(meas, callsign=w["callsign"]))[0]["time_of_day"].to_numpy() * 128
                t = t[(t >= start) & (t <= end)].astype(np.int64)
                np.testing.assert_array_equal(np.bincount((t - start) // 1280, minlength=n),
                                              s[f"{sensor}_count"].to_numpy())
                edges += int(np.sum(((t - start) % 1280 == 0) & (t > start)))
            assert len(res.lags) == 2 * n - 1
            for sensor in ("radar", "adsb"):
                filled = s[f"{sensor}_filled"].to_numpy()
                assert ((s[f"{sensor}_count"] == 0).to_numpy() == filled).all()
                # an empty slot takes the previous slot's value; leading empty ones the first non-empty
                src = np.maximum.accumulate(np.where(filled, 0, np.arange(n)))
                src = np.where(np.arange(n) < np.argmin(filled), np.argmin(filled), src)
                for col in ("lat", "lon"):
                    v = s[f"{sensor}_{col}"].to_numpy()
                    np.testing.assert_array_equal(v, v[src])
            filled_slots += int(s["radar_filled"].sum() + s["adsb_filled"].sum())
    assert edges > 0  # reports exactly on an inner slot edge are exercised
    if any(c.sim.scenario.adsb_short_dropouts_per_hour > 0 for c in cases):
        assert filled_slots > 0  # ADS-B short dropouts leave empty slots


# ----------------------------------------------------------------------------------------------------------
# Correlation coefficients


def test_ncc_peaks_at_zero_and_is_one_to_six_places(quiet, bundled):
    """NCC peaks at lag 0 in every window (the overlap length N - |d| in its numerator makes it a tent around
    0), and where ADS-B has no position jumps r(0) > 0.999999 for longitude, and for latitude wherever the
    RMS latitude is >= 2 deg (> 0.99999 everywhere).

    r(0) = x.y / (|x| |y|) is the cosine of the angle between the two series seen as vectors. The thesis
    normalisation keeps the mean, so |x| is dominated by the mean latitude (0.8-4 deg here) and longitude
    (~102 deg), whereas x - y is the ~200-300 m = 0.002-0.003 deg separation: 1 - r(0) ~ mean((x - y)^2) /
    mean(x^2) / 2, i.e. ~5e-7 at 3 deg latitude but 2.4e-6 at 0.8 deg (the equator lowers it, not the data),
    and ~2e-10 for longitude. Exactly, 1 - r(0) <= 2 |x - y|^2 / |x|^2. NCC at lag 0 therefore says almost
    nothing about agreement; the Pearson coefficient (mean removed) is the discriminating one.
    """
    for case in [*quiet, bundled]:
        jumps = pd.DataFrame(case.truth["jumps"], columns=["callsign", "t_s"])
        for res in case.results():
            w = res.summary
            assert w["ncc_peak_lag_lat"] == 0 and w["ncc_peak_lag_lon"] == 0
            for ax in ("lat", "lon"):
                x, y = res.slots[f"radar_{ax}"].to_numpy(), res.slots[f"adsb_{ax}"].to_numpy()
                assert 1 - w[f"ncc0_{ax}"] <= 2 * np.sum((x - y) ** 2) / np.sum(x**2) + 1e-15
            jumped = (jumps["callsign"] == w["callsign"]) & jumps["t_s"].between(w["start_tod"], w["end_tod"])
            if jumped.any():
                continue
            rms_lat = math.sqrt(np.mean(res.slots["radar_lat"] ** 2))
            assert w["ncc0_lon"] > 0.999999 and w["ncc0_lat"] > 0.99999, w
            if rms_lat >= 2.0:
                assert w["ncc0_lat"] > 0.999999, w


def test_lag_tables_follow_the_formulas(late_radar):
    """r(d) = sum_i x[i] y[i-d] / sqrt(sum x^2 sum y^2) and the Pearson coefficient of the pairs
    (x[i], y[i-d]), recomputed here from the slot series at d = -4..4 (x radar, y ADS-B)."""
    for res in late_radar.results():
        s, lags = res.slots, res.lags.set_index("lag")
        n = len(s)
        for ax in ("lat", "lon"):
            x, y = s[f"radar_{ax}"].to_numpy(), s[f"adsb_{ax}"].to_numpy()
            for d in range(-4, 5):
                i = np.arange(max(d, 0), min(n, n + d))
                ncc = np.sum(x[i] * y[i - d]) / math.sqrt(np.sum(x**2) * np.sum(y**2))
                assert lags.loc[d, f"ncc_{ax}"] == pytest.approx(ncc, abs=1e-12)
                pearson = np.corrcoef(x[i], y[i - d])[0, 1]
                assert lags.loc[d, f"pearson_{ax}"] == pytest.approx(pearson, abs=1e-9)


def test_pearson_peaks_at_zero_where_the_track_curves(quiet):
    """Pearson (mean removed) peaks at lag 0 for lat and lon in every clean window of >= 30 slots whose
    track turns by >= 30 deg, where the lag is identified (an axis whose velocity barely changes in the
    turn may leave it unidentified: null, never another lag), and r(0) > 0.99 along every axis the aircraft
    moves along by >= 5 km RMS (expected r(0) ~ 1 - (sigma_slot / sigma_motion)^2 with sigma_slot <~ 400 m:
    >= 0.9936)."""
    checked_lag = checked_r0 = 0
    for case in quiet:
        for res in case.results():
            w = res.summary
            if w["slots"] < 30:
                continue
            track = case.track(w["callsign"], "radar", w["start_tod"], w["end_tod"])
            if turn_deg(track) >= 30.0:
                for ax in ("lat", "lon"):
                    if w[f"pearson_lag_unidentified_{ax}"]:
                        assert w[f"pearson_peak_lag_{ax}"] is None, w
                    else:
                        assert w[f"pearson_peak_lag_{ax}"] == 0, w
                        checked_lag += 1
            centre = case.sim.aircraft_by_callsign(w["callsign"]).truth(res.slots["time_of_day"] + SLOT_S / 2)
            motion_m = {"lat": np.std(centre.latitude) * math.radians(1) * geo.WGS84_A_M,
                        "lon": np.std(centre.longitude) * math.radians(1) * geo.WGS84_A_M
                        * math.cos(math.radians(np.mean(centre.latitude)))}
            for ax, m in motion_m.items():
                if m >= 5000.0:
                    assert w[f"pearson0_{ax}"] > 0.99, (w, ax, m)
                    checked_r0 += 1
    assert checked_lag >= 20 and checked_r0 >= 30  # axes with the lag identified, of 16 turning windows


def test_pearson_lag_is_not_identifiable_on_straight_legs(quiet):
    """On a straight constant-velocity leg both series are linear in time, and a shifted line correlates
    perfectly with a line: r(d) is flat, and only noise decides the peak. Over |d| <= 5 slots the Pearson
    curve then varies by less than twice its own noise level 1 - r(0) (by less than once, in fact), so a
    non-zero peak lag there is no finding (several such windows in these seeds peak at +-1..23)."""
    straight = 0
    for case in quiet:
        for res in case.results():
            w = res.summary
            track = case.track(w["callsign"], "radar", w["start_tod"], w["end_tod"])
            if w["slots"] < 30 or turn_deg(track) >= 1.0:
                continue
            straight += 1
            lags = res.lags.set_index("lag")
            for ax in ("lat", "lon"):
                near = lags.loc[-5:5, f"pearson_{ax}"]
                assert near.max() - near.min() < 2.0 * (1.0 - w[f"pearson0_{ax}"]), (w, ax)
    assert straight >= 5


def test_time_offset_is_found_by_pearson_not_by_ncc(late_radar):
    """Radar times reported 30 s late: the radar series repeats the ADS-B one 3 slots later, x[i] ~ y[i - 3],
    so Pearson peaks at lag +3 (radar lags ADS-B) in every window of >= 30 slots that turns by >= 30 deg.
    NCC still peaks at 0 everywhere: with the mean kept, r(d) ~ (N - |d|) / N, a tent that no offset of a
    few slots can move, so the NCC peak lag carries no timing information."""
    checked = 0
    for res in late_radar.results():
        w = res.summary
        assert w["ncc_peak_lag_lat"] == 0 and w["ncc_peak_lag_lon"] == 0
        track = late_radar.track(w["callsign"], "radar", w["start_tod"], w["end_tod"])
        if w["slots"] >= 30 and turn_deg(track) >= 30.0:
            assert w["pearson_peak_lag_lat"] == 3 and w["pearson_peak_lag_lon"] == 3, w
            checked += 1
    assert checked >= 5


# ----------------------------------------------------------------------------------------------------------
# Separations against the noise model


def test_separation_rms_within_the_noise_bounds(quiet):
    """sep_rms of every quiet window lies between bounds derived from the injected noise.

    Upper: per slot, radar range sigma 70 m and cross-range R * 0.08 deg (R the largest slant range in the
    window: 260 m at 100 NM, 520 m at 200 NM), averaged over >= 2 reports (/sqrt 2); ADS-B 5 m per axis
    over >= 5 reports; plus the slot-timing term v_max * 1.25 s (SLOT_TIMING_RMS_S). The window RMS of
    N >= 30 slots fluctuates by <~ 1/sqrt(2N) <= 13 %, so the bound is 1.35 x that. No ADS-B jumps,
    short dropouts or low-quality episodes are injected here (the bundled data is treated slot by slot in
    the next test).
    Lower: radar noise alone at the smallest range over <= 3 reports per slot (timing only adds to it),
    halved for fluctuation: a few tens of metres, i.e. the separations are not zero.
    """
    sc = Scenario(**QUIET)
    for case in quiet:
        for res in case.results():
            w = res.summary
            if w["slots"] < 30:
                continue
            track = case.track(w["callsign"], "radar", w["start_tod"], w["end_tod"])
            upper = 1.35 * slot_sigma_m(sc, track["rho_true_nm"].max(),
                                        track["ground_speed_kt"].max() * KT_MS)
            cross_min_m = track["rho_true_nm"].min() * M_PER_NM * math.radians(sc.sigma_azimuth_deg)
            lower = 0.5 * math.sqrt((sc.sigma_range_m**2 + cross_min_m**2) / 3)
            assert lower < w["sep_rms_m"] < upper, (w, lower, upper)
            assert w["sep_mean_m"] <= w["sep_rms_m"] <= w["sep_max_m"] and w["sep_p95_m"] <= w["sep_max_m"]


def test_separation_is_explained_by_noise_and_slot_timing(quiet):
    """Slot by slot, the expected squared separation is the radar noise of that slot's reports (their count
    and range) plus the distance between the TRUE positions averaged at the radar and at the ADS-B report
    times of the slot. The observed window RMS matches that prediction within -20/+25 % (it does within
    -10/+15 % over 80 windows of 8 seeds): nothing else (geodesy, slotting, longitude averaging) adds
    error."""
    sc = Scenario(**QUIET)
    for case in quiet:
        ac = case.sim.aircraft_by_callsign
        for res in case.results():
            w = res.summary
            means = []
            for sensor in ("radar", "adsb"):
                tr = case.track(w["callsign"], sensor, w["start_tod"], w["end_tod"])
                t = tr["t_s"].to_numpy()
                st = ac(w["callsign"]).truth(t)
                means.append(pd.DataFrame({"k": slot_index(t, w["start_tod"], SLOT_S), "lat": st.latitude,
                                           "lon": st.longitude, "rho": tr["rho_true_nm"].to_numpy()})
                             .groupby("k").agg(lat=("lat", "mean"), lon=("lon", "mean"), n=("lat", "size"),
                                               rho=("rho", "mean")))
            both = means[0].merge(means[1], left_index=True, right_index=True, how="inner",
                                  suffixes=("", "_a"))
            e_r, n_r = geo_offsets(both["lat"], both["lon"], both["lat_a"], both["lon_a"])
            cross = both["rho"] * M_PER_NM * math.radians(sc.sigma_azimuth_deg)
            noise2 = ((sc.sigma_range_m**2 + cross**2) / both["n"]
                      + 2 * sc.adsb_sigma_position_m**2 / both["n_a"])
            predicted = math.sqrt(float(np.mean(e_r**2 + n_r**2 + noise2)))
            observed = math.sqrt(float(np.mean(res.slots["sep_m"].to_numpy()[both.index] ** 2)))
            assert 0.8 < observed / predicted < 1.25, (w, observed, predicted)


def geo_offsets(lat1, lon1, lat2, lon2) -> tuple[np.ndarray, np.ndarray]:
    """East and north (m) of point 2 from point 1, on the local tangent plane (fine for < 10 km)."""
    lat1, lon1, lat2, lon2 = (np.asarray(v, dtype=float) for v in (lat1, lon1, lat2, lon2))
    rot = geo.enu_rotation(lat1, lon1)
    diff = geo.geodetic_to_ecef(lat2, lon2, 0.0) - geo.geodetic_to_ecef(lat1, lon1, 0.0)
    return (np.einsum("...j,...j->...", rot[..., 0, :], diff),
            np.einsum("...j,...j->...", rot[..., 1, :], diff))


def test_bundled_separations_slot_by_slot(bundled):
    """On the bundled data every large separation is accounted for by an injected effect.

    * A slot holding ADS-B jump reports has its ADS-B mean moved by sum(jump)/count (0.1-6 deg / ~10
      reports: 1-60 km); its separation equals that displacement within 3 slot sigmas.
    * Slots with no report of a sensor (filled from the previous slot: ~v * 10 s per slot) or overlapping
      an injected ADS-B short dropout or low-quality episode are left out.
    * The remaining slots of each window obey the quiet-window bound (1.35 x slot_sigma at R_max, v_max).
    """
    sc = bundled.sim.scenario
    jumps = pd.DataFrame(bundled.truth["jumps"])
    episodes = pd.DataFrame(bundled.truth["injected_dropouts"]["adsb"]
                            + bundled.truth["low_quality"]["episodes"])
    n_jump_slots = 0
    for res in bundled.results():
        w, s = res.summary, res.slots
        track = bundled.track(w["callsign"], "radar", w["start_tod"], w["end_tod"])
        sigma = slot_sigma_m(sc, track["rho_true_nm"].max(), track["ground_speed_kt"].max() * KT_MS)
        t0 = s["time_of_day"].to_numpy()
        k = slot_index(jumps["t_s"], w["start_tod"], SLOT_S)
        mine = ((jumps["callsign"] == w["callsign"])
                & jumps["t_s"].between(w["start_tod"], w["end_tod"])).to_numpy()
        jump_slot = np.zeros(len(s), bool)
        for kk in np.unique(k[mine]):
            sel = mine & (k == kk)
            n = s["adsb_count"].iloc[kk]
            lat, lon = s["adsb_lat"].iloc[kk], s["adsb_lon"].iloc[kk]
            de, dn = geo_offsets(lat, lon, lat - jumps["dlat_deg"][sel].sum() / n,
                                 lon - jumps["dlon_deg"][sel].sum() / n)
            assert abs(s["sep_m"].iloc[kk] - math.hypot(de, dn)) < 3 * sigma, (w, kk)
            jump_slot[kk] = True
        dirty = np.array(s["radar_filled"] | s["adsb_filled"], dtype=bool)
        for iv in episodes[episodes["callsign"] == w["callsign"]].itertuples():
            dirty |= (t0 <= iv.end_s) & (t0 + SLOT_S > iv.start_s)
        clean = ~jump_slot & ~dirty
        assert clean.sum() >= 0.8 * len(s)
        assert math.sqrt(np.mean(s["sep_m"].to_numpy()[clean] ** 2)) < 1.35 * sigma, w
        n_jump_slots += int(jump_slot.sum())
    assert n_jump_slots >= 30  # the bundled windows hold 37 of the 38 injected jumps


# ----------------------------------------------------------------------------------------------------------
# Polar plots to WGS-84


def horizontal_error_m(lat, lon, lat_true, lon_true, h_m) -> np.ndarray:
    """Horizontal distance (m) between two positions at the true height, independent of pipeline.geodesy."""
    rot = geo.enu_rotation(lat_true, lon_true)
    diff = geo.geodetic_to_ecef(lat, lon, h_m) - geo.geodetic_to_ecef(lat_true, lon_true, h_m)
    return np.hypot(np.einsum("...j,...j->...", rot[..., 0, :], diff),
                    np.einsum("...j,...j->...", rot[..., 1, :], diff))


def cat048(sac, sic, rho_nm, theta_deg, fl) -> pd.DataFrame:
    n = np.broadcast(rho_nm, theta_deg, fl, sic).size
    return pd.DataFrame({"sac": np.broadcast_to(sac, n), "sic": np.broadcast_to(sic, n), "day": 0,
                         "time_of_day": 0.0, "rho_nm": np.broadcast_to(rho_nm, n),
                         "theta_deg": np.broadcast_to(theta_deg, n), "flight_level": np.broadcast_to(fl, n)})


def test_polar_to_wgs84_on_the_truth_tracks(bundled):
    """The exact, unquantised slant range/azimuth of every radar report and its true FL (alt_ft / 100, the
    ellipsoid height here) give back the true position within 1 mm (up to ~180 NM in this scenario)."""
    tt = bundled.sim.truth_tracks
    tt = tt[tt["sensor"] == "radar"]
    site = bundled.sim.scenario.radar
    sensors = read_sensors(FIX / "sensors.toml")
    meas = radar_measurements(cat048(site.sac, site.sic, tt["rho_true_nm"].to_numpy(),
                                     tt["theta_true_deg"].to_numpy(), tt["alt_ft"].to_numpy() / 100.0),
                              sensors)
    err = horizontal_error_m(meas["latitude"], meas["longitude"], tt["latitude"], tt["longitude"],
                             tt["height_m"])
    assert tt["rho_true_nm"].max() > 150.0
    assert err.max() < 1e-3


def test_polar_to_wgs84_at_250_nm():
    """A noise-free case built with the simulator's own WGS-84 code: points at slant ranges 1-250 NM, every
    15 deg of azimuth and elevations -5..+10 deg, kept where the height is FL0-FL500, seen from three sites
    (tropics, 60 N at 500 m, 45 S next to the antimeridian). The pipeline puts each within 1 m (it does to
    well under a millimetre)."""
    sites = pd.DataFrame({"name": ["KLIA", "North", "Antimeridian"], "sac": 1, "sic": [1, 2, 3],
                          "latitude": [2.7456, 60.0, -45.0], "longitude": [101.7099, 10.0, 179.95],
                          "altitude_m": [40.0, 500.0, 0.0]})
    rho, az, el = np.meshgrid([1.0, 60.0, 150.0, 230.0, 250.0], np.arange(0.0, 360.0, 15.0) + 0.3,
                              np.linspace(-5.0, 10.0, 61), indexing="ij")
    rows = []
    for site in sites.itertuples():
        r_m, a, e = rho.ravel() * M_PER_NM, np.radians(az.ravel()), np.radians(el.ravel())
        enu = np.stack([r_m * np.cos(e) * np.sin(a), r_m * np.cos(e) * np.cos(a), r_m * np.sin(e)], axis=-1)
        ecef = geo.enu_to_ecef(enu, site.latitude, site.longitude, site.altitude_m)
        lat, lon, h = geo.ecef_to_geodetic(ecef)
        keep = (h >= 0.0) & (h <= 50000 * geo.M_PER_FT)
        rows.append(pd.DataFrame({"sic": site.sic, "rho": rho.ravel()[keep], "az": az.ravel()[keep],
                                  "lat": lat[keep], "lon": lon[keep], "h": h[keep]}))
    pts = pd.concat(rows, ignore_index=True)
    meas = radar_measurements(cat048(1, pts["sic"].to_numpy(), pts["rho"].to_numpy(), pts["az"].to_numpy(),
                                     pts["h"].to_numpy() / geo.M_PER_FT / 100.0), sites)
    err = horizontal_error_m(meas["latitude"], meas["longitude"], pts["lat"], pts["lon"], pts["h"])
    assert (pts["rho"] == 250.0).sum() > 100 and set(pts["sic"]) == {1, 2, 3}
    assert err.max() < 1.0
    assert err.max() < 1e-3  # in fact


def test_antimeridian_site_gives_the_same_results(antimeridian, quiet):
    """The same flights (same seed, same positions relative to the site) seen from a radar next to the
    antimeridian: ADS-B and radar longitudes on both sides of +-180, slots averaged across it, and the same
    windows, counts and lags as from KLIA, coefficients within 1e-4 and separations within 1 %."""
    for meas in (antimeridian.radar, antimeridian.adsb):
        lon = meas["longitude"]
        assert lon.between(-180.0, 180.0, inclusive="left").all()
        assert (lon > 179.9).any() and (lon < -179.9).any()
    crossing = [r for r in antimeridian.results() if np.ptp(r.slots["radar_lon"]) > 180.0]
    assert len(crossing) >= 3
    for a, b in zip(antimeridian.windows(), quiet[0].windows(), strict=True):
        for key in ("callsign", "window", "start_tod", "end_tod", "slots", "radar_before", "adsb_before",
                    "ncc_peak_lag_lat", "ncc_peak_lag_lon", "pearson_peak_lag_lat", "pearson_peak_lag_lon"):
            assert a[key] == b[key], key
        for key in ("ncc0_lat", "ncc0_lon", "pearson0_lat", "pearson0_lon"):
            assert a[key] == pytest.approx(b[key], abs=1e-4), key
        for key in ("sep_mean_m", "sep_rms_m", "sep_p95_m", "sep_max_m"):
            assert a[key] == pytest.approx(b[key], rel=0.01), key


# ----------------------------------------------------------------------------------------------------------
# Midnight


def test_midnight_windows_span_the_day_change(midnight):
    """Raw blocks carry no date: decoded with date=, reports after midnight get day 1, windows run across
    86400 s with ISO start/end on consecutive days, and the slots are continuous through midnight."""
    spanning = [r for r in midnight.results() if r.summary["start_tod"] < 86400.0 < r.summary["end_tod"]]
    assert len(spanning) >= 3
    for res in spanning:
        w, s = res.summary, res.slots
        assert str(w["start"].tz) == str(w["end"].tz) == "UTC"  # real UTC date-times, not text
        assert w["start"].strftime("%Y-%m-%dT%H") == f"{DAY0}T23"
        assert w["end"].strftime("%Y-%m-%dT%H") == "2019-07-01T00"
        span = (w["end"] - w["start"]).total_seconds()
        assert span == pytest.approx(w["end_tod"] - w["start_tod"], abs=1e-6)
        assert (np.diff(s["time_of_day"]) == SLOT_S).all()
        k = int(slot_index(86400.0, w["start_tod"], SLOT_S))
        near = s.iloc[max(k - 2, 0): k + 3]
        assert (near["radar_count"] > 0).all() and (near["adsb_count"] > 0).all(), w
        assert (s["timestamp"].dt.date.astype(str).iloc[[0, -1]] == [DAY0, "2019-07-01"]).all()
    # the day change itself is in the decoded measurements
    assert midnight.radar["time_of_day"].max() > 86400.0 > midnight.radar["time_of_day"].min()


def test_midnight_same_results_as_noon(midnight, noon):
    """The same scenario 12 h earlier (same seed and geometry) gives the same windows shifted by 43200 s,
    the same slot counts and the same coefficients and separations: midnight creates no gap and no error."""
    a, b = midnight.windows(), noon.windows()
    assert [(w["callsign"], w["window"]) for w in a] == [(w["callsign"], w["window"]) for w in b]
    for x, y in zip(a, b, strict=True):
        assert x["start_tod"] - y["start_tod"] == pytest.approx(43200.0, abs=TOD_LSB_S)
        assert x["end_tod"] - y["end_tod"] == pytest.approx(43200.0, abs=TOD_LSB_S)
        for key in ("slots", "radar_before", "adsb_before", "radar_duplicates", "adsb_duplicates",
                    "ncc_peak_lag_lat", "ncc_peak_lag_lon", "pearson_peak_lag_lat", "pearson_peak_lag_lon"):
            assert x[key] == y[key], key
        for key in ("ncc0_lat", "ncc0_lon", "pearson0_lat", "pearson0_lon"):
            assert x[key] == pytest.approx(y[key], abs=1e-9), key
        for key in ("sep_mean_m", "sep_rms_m", "sep_p95_m", "sep_max_m"):
            assert x[key] == pytest.approx(y[key], abs=1e-3), key
    assert pd.Timestamp(b[0]["start"]).date().isoformat() == DAY0


def test_midnight_without_a_date(tmp_path, midnight):
    """Without date= the days still come from the time-of-day wrap: same windows, no ISO times."""
    write_fixtures(tmp_path, MIDNIGHT_SEED, "midnight")
    radar, adsb = decode_dir(tmp_path)
    run = correlate(pd.concat([radar, adsb], ignore_index=True), all_aircraft=True)
    got = [(w.summary["callsign"], w.summary["start_tod"], w.summary["end_tod"], w.summary["slots"])
           for w in run.windows]
    assert got == [(w["callsign"], w["start_tod"], w["end_tod"], w["slots"]) for w in midnight.windows()]
    assert all(w.summary["start"] is None and w.summary["end"] is None for w in run.windows)


# ----------------------------------------------------------------------------------------------------------
# The returning call sign and the bundled MAS72


def test_returning_callsign_gets_separate_windows(bundled):
    """MAS136 leaves after 25 min and is back 2 h 25 min later: two windows, numbered 1 and 2 within the call
    sign, each inside one of its flights, the absence between them a truth gap of cause "absent"."""
    ws = bundled.windows("MAS136")
    flights = next(a for a in bundled.truth["aircraft"] if a["callsign"] == "MAS136")["flights"]
    assert [w["window"] for w in ws] == [1, 2] and len(flights) == 2
    for w, f in zip(ws, flights, strict=True):
        assert f["start_s"] <= w["start_tod"] < w["end_tod"] <= f["end_s"]
    assert ws[1]["start_tod"] - ws[0]["end_tod"] > 2 * 3600
    assert any(g["callsign"] == "MAS136" and g["cause"] == "absent" and g["start_s"] >= ws[0]["end_tod"]
               and g["end_s"] <= ws[1]["start_tod"] for g in bundled.truth["adsb_gaps"])
    assert {w["address"] for w in ws} == {"7503A0"}
    # every call sign numbers its windows 1..n in time order
    for cs in {w["callsign"] for w in bundled.windows()}:
        ws = bundled.windows(cs)
        assert [w["window"] for w in ws] == list(range(1, len(ws) + 1))
        assert all(a["end_tod"] < b["start_tod"] for a, b in zip(ws[:-1], ws[1:], strict=True))


def test_bundled_mas72_and_the_command_line(bundled, tmp_path):
    """What the README's first command runs: MAS72 alone gives the same windows as the all-aircraft run and
    the truth; ``msdc correlate --all --json`` writes exactly the summaries validated above."""
    one = correlate(pd.concat([bundled.radar, bundled.adsb], ignore_index=True), callsign="MAS72")
    assert [w.summary for w in one.windows] == bundled.windows("MAS72")
    assert [(w["start_tod"], w["end_tod"]) for w in bundled.windows("MAS72")] == [
        (w["start_s"], w["end_s"]) for w in bundled.truth_windows("MAS72")]
    out = tmp_path / "all.json"
    assert msdc(["correlate", str(FIX / "radar.ast"), str(FIX / "adsb.ast"), "--sensors",
                 str(FIX / "sensors.toml"), "--all", "--json", str(out)]) == 0
    written = json.loads(out.read_text())["windows"]
    assert len(written) == len(bundled.windows())
    for got, want in zip(written, bundled.windows(), strict=True):
        assert list(got) == [*want, "note"]  # the JSON adds the window's plain-language note
        for key, value in want.items():
            assert got[key] == (pytest.approx(value, rel=1e-12) if isinstance(value, float) else value), key
