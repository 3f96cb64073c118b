"""``correlate --fill predict``: empty slots take the tracker's prediction. The default (hold) is left
exactly as it was; predicted fills change only the empty slots and sit closer to the simulator's truth
during ADS-B dropouts than the held previous slot."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from pyproj import Geod

from fixtures.simulate import simulate
from msdc.pipeline.cli import main
from msdc.pipeline.correlate.correlation import correlate
from msdc.pipeline.model.load import load
from msdc.pipeline.model.measurements import build_measurements
from msdc.pipeline.model.sensors import read_sensors

# one worker runs the module: the runs made once, not on each worker
pytestmark = pytest.mark.xdist_group("fill")

FIX = Path(__file__).resolve().parents[3] / "fixtures"
BASE = [str(FIX / "radar.ast"), str(FIX / "adsb.ast"), "--sensors", str(FIX / "sensors.toml"),
        "--date", "2019-03-01", "--all"]
GEOD = Geod(ellps="WGS84")


@pytest.fixture(scope="module")
def runs():
    data = load([FIX / "radar.ast", FIX / "adsb.ast"], date="2019-03-01")
    meas = build_measurements(data.frames[48], data.frames[21], read_sensors(FIX / "sensors.toml"),
                              date=data.date)
    return correlate(meas, all_aircraft=True), correlate(meas, all_aircraft=True, fill="predict")


def test_default_json_is_unchanged_by_the_option(tmp_path, capsys):
    """--fill hold (explicit) and no --fill give the same document: the thesis numbers are untouched (the
    truth tests pin those numbers themselves)."""
    for name, extra in (("default", []), ("hold", ["--fill", "hold"])):
        assert main(["correlate", *BASE, "--json", str(tmp_path / f"{name}.json"), *extra]) == 0
    capsys.readouterr()
    a, b = (json.loads((tmp_path / f"{n}.json").read_text()) for n in ("default", "hold"))
    for doc in (a, b):
        for k in ("run_utc", "run_time_s", "command"):
            doc["parameters"].pop(k, None)
        assert "fill" not in doc["parameters"]
    assert a == b


def test_predict_changes_only_empty_slots(runs):
    hold, pred = runs
    assert len(hold.windows) == len(pred.windows)
    changed = empty = 0
    for wh, wp in zip(hold.windows, pred.windows, strict=True):
        for side in ("radar", "adsb"):
            sh, sp = wh.slots, wp.slots
            assert (sh[f"{side}_count"] == sp[f"{side}_count"]).all()
            full = ~sh[f"{side}_filled"].to_numpy(bool)
            for c in ("lat", "lon"):  # bit for bit where the slot had reports
                assert np.array_equal(sh[f"{side}_{c}"].to_numpy()[full], sp[f"{side}_{c}"].to_numpy()[full])
            changed += int((sh[f"{side}_lat"].to_numpy() != sp[f"{side}_lat"].to_numpy()).sum())
            empty += int((~full).sum())
    # on the fixtures no window starts with an empty slot, and every empty one is within the coast limit
    assert changed == empty >= 15


def test_predicted_fills_are_closer_to_truth_in_dropouts(runs):
    """Against the simulator's true position at each empty ADS-B slot's centre (the instant the
    prediction is for; the held value is a position from 10 s or more before)."""
    hold, pred = runs
    sim = simulate()
    truth = {ac.spec.callsign: ac for ac in sim.aircraft}
    err_hold, err_pred = [], []
    for wh, wp in zip(hold.windows, pred.windows, strict=True):
        ac = truth[wh.summary["callsign"]]
        s_h, s_p = wh.slots, wp.slots
        counts = s_h["adsb_count"].to_numpy()
        after_first = np.arange(len(counts)) > np.argmax(counts > 0)
        empty = s_h["adsb_filled"].to_numpy(bool) & after_first
        if not empty.any():
            continue
        t = s_h["time_of_day"].to_numpy(float)[empty] + 5.0
        st = ac.truth(t)
        for frame, out in ((s_h, err_hold), (s_p, err_pred)):
            out += list(GEOD.inv(frame["adsb_lon"].to_numpy()[empty], frame["adsb_lat"].to_numpy()[empty],
                                 st.longitude, st.latitude)[2])
    err_hold, err_pred = np.array(err_hold), np.array(err_pred)
    assert len(err_hold) >= 15
    # at 250-480 kt an aircraft moves 1.3-2.5 km per 10 s slot: holding is kilometres off; the prediction
    # (coasting at most the 180 s gap rule) stays within hundreds of metres on average
    assert np.median(err_hold) > 1000.0
    assert np.median(err_pred) < 0.2 * np.median(err_hold)
    assert np.mean(err_pred < err_hold) > 0.9


# --- the fast predictor against the tracker's own route (track(), state_at, predict) ---------------------

T0 = pd.Timestamp("2024-05-10T23:58:00Z")  # the flight crosses midnight: the filter's epoch is the 10th


def _old_route(reports: pd.DataFrame, reference: pd.Timestamp, max_coast_s: float, seconds: np.ndarray):
    """What --fill predict computed before: the full track() with filter histories, then per time the state
    after the last update at or before it, propagated by predict() (1 s steps) and read at its last row."""
    from msdc.pipeline.track import predict, track

    result = track(reports.assign(aircraft_id="A"), max_coast_s=max_coast_s, keep_states=True)
    lat, lon = np.full(len(seconds), np.nan), np.full(len(seconds), np.nan)
    for i, s in enumerate(seconds):
        when = reference + pd.to_timedelta(s, unit="s")
        try:
            state = result.state_at("A", when)
        except ValueError:
            continue
        ahead = (when - state.time).total_seconds()
        if ahead > max_coast_s:
            continue
        if ahead <= 1e-9:
            la, lo = state.plane.inverse(np.array([state.mu @ state.x[:, 0]]),
                                         np.array([state.mu @ state.x[:, 3]]))
        else:
            p = predict(state, ahead, step_s=min(1.0, ahead))
            la, lo = p["latitude"].to_numpy()[-1:], p["longitude"].to_numpy()[-1:]
        lat[i], lon[i] = la[0], lo[0]
    return lat, lon


def _frame(seed: int = 3) -> pd.DataFrame:
    from fixtures.track_scenarios import fly

    rng = np.random.default_rng(seed)
    truth = fly((0.0, 0.0), 60.0, 210.0, [(120, 0, 0), (40, -3.0, 0), (100, 0, 0), (80, 0, -1.0), (60, 0, 0)])
    t = np.concatenate([np.arange(0.25, 250.0, 1.0), np.arange(320.5, 399.0, 1.0)])  # 70 s dropout
    station = np.where(rng.random(len(t)) < 0.5, "021:0/108", "021:0/107")
    both = rng.choice(len(t), 40, replace=False)  # the other station at the same instant
    t = np.concatenate([t, t[both]])
    station = np.concatenate([station, np.where(station[both] == "021:0/107", "021:0/108", "021:0/107")])
    e, n = truth.at(t)
    e, n = e + rng.normal(0, 15.0, len(t)), n + rng.normal(0, 15.0, len(t))
    ve, vn = truth.velocity_at(t)
    k = np.ones(len(t))
    lon, lat, _ = GEOD.fwd(2.0 * k, 41.0 * k, np.degrees(np.arctan2(e, n)), np.hypot(e, n))
    frame = pd.DataFrame({
        "time": T0 + pd.to_timedelta(t, unit="s"), "sensor_id": pd.Categorical(station),
        "sensor_kind": "adsb", "latitude": lat, "longitude": lon, "flight_level": 350.0 - t / 60.0,
        "cov_ee_m2": 225.0, "cov_en_m2": 0.0, "cov_nn_m2": 225.0,
        "ground_speed_kt": np.hypot(ve, vn) / 0.514444, "heading_deg": np.degrees(np.arctan2(ve, vn)) % 360.0,
        "nucr_nacv": pd.array(rng.integers(0, 4, len(t)), dtype="Int8")})
    frame.loc[frame.index[100], "latitude"] += 0.2  # a jump the gate rejects
    frame.loc[frame.index[[5, 200]], "cov_nn_m2"] = np.nan  # untracked
    return frame


@pytest.mark.parametrize("sensors", ["categories", "reversed categories", "text"])
def test_fast_predictor_equals_track_then_predict(sensors):
    """Bit for bit against the old route, at slot-like centres, at every third report time (an update
    exactly: its posterior), just after one, through the dropout up to and past max_coast_s, before the
    first report; for a reference on the filter's own midnight and one a day earlier. Reports of the two
    stations at one instant go in track()'s order: by the sensor's category order, or alphabetically."""
    from msdc.pipeline.correlate.fill import track_predictor

    frame = _frame()
    if sensors == "reversed categories":
        frame["sensor_id"] = frame["sensor_id"].cat.reorder_categories(["021:0/108", "021:0/107"])
    elif sensors == "text":
        frame["sensor_id"] = frame["sensor_id"].astype(str)
    max_coast_s = 45.0
    for reference in (T0.floor("D"), T0.floor("D") - pd.Timedelta(days=1)):
        off = (T0 - reference).total_seconds()
        first = off + 0.25
        seconds = np.concatenate([
            off + np.arange(-20.0, 420.0, 10.0) + 5.0,  # slot centres, some before the first report
            off + np.sort(np.unique((frame["time"] - T0).dt.total_seconds().to_numpy()))[::3],
            off + np.array([0.25 + 1e-6, 249.25, 249.25 + 44.0, 249.25 + 45.0, 249.25 + 45.5, 300.0,
                            249.25 + 0.4, 249.25 + 7.9999999, 249.25 + 8.0, 249.25 + 8.0000000004]),
            [first - 1e-3, first]])
        new = track_predictor(frame, reference, max_coast_s)(seconds)
        old = _old_route(frame, reference, max_coast_s, seconds)
        for a, b in zip(new, old, strict=True):
            assert np.array_equal(a, b, equal_nan=True), seconds[~((a == b) | (np.isnan(a) & np.isnan(b)))]
        lat = new[0]
        assert np.isnan(lat[seconds < first]).all() and np.isfinite(lat[seconds == first]).all()
        gap = (seconds > off + 249.25 + 45.0) & (seconds < off + 320.5)
        assert gap.any() and np.isnan(lat[gap]).all()  # past max_coast_s after the last update
        assert np.isfinite(lat[(seconds > off + 249.25) & (seconds <= off + 249.25 + 45.0)]).sum() >= 5


def test_fast_predictor_in_any_order_and_without_covariances():
    """The kernel continues one chain of 1 s steps between queries; queries out of order, repeated or of
    another row restart it and must give the same numbers as the sorted ones."""
    from msdc.pipeline.correlate.fill import track_predictor

    frame = _frame(seed=5)
    reference = T0.floor("D")
    off = (T0 - reference).total_seconds()
    seconds = off + np.array([260.0, 259.0, 255.5, 280.25, 255.5, 30.2, 262.0, 31.0, 250.0, 290.0, 10.7])
    at = track_predictor(frame, reference, 60.0)
    order = np.argsort(seconds, kind="stable")
    lat, lon = at(seconds)
    lat_s, lon_s = at(seconds[order])
    assert np.array_equal(lat[order], lat_s) and np.array_equal(lon[order], lon_s)
    assert np.array_equal(np.stack(at(seconds)), np.stack(_old_route(frame, reference, 60.0, seconds)),
                          equal_nan=True)
    assert track_predictor(frame.assign(cov_ee_m2=np.nan), reference, 60.0) is None
