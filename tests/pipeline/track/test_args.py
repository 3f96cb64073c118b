"""track()'s arguments: times in any zone read as UTC, bad numbers and covariances named, every report
counted (audit findings A4, A7, A-C1, A-B2/B9)."""

import warnings

import numpy as np
import pandas as pd
import pytest

from msdc.pipeline.track import track

T0 = pd.Timestamp("2024-05-10T07:00:00.25Z")


def _adsb(n=120, sensor="021:0/107", aircraft="A1", dt=1.0):
    """An aircraft flying north at 100 m/s (0.000904 deg of latitude a second, near 41 N) with no noise."""
    t = np.arange(n) * dt
    return pd.DataFrame({"time": T0 + pd.to_timedelta(t, unit="s"), "sensor_id": sensor,
                         "sensor_kind": "adsb", "aircraft_id": aircraft,
                         "latitude": 41.0 + t * 100.0 / 111_000.0, "longitude": 2.0,
                         "flight_level": 300.0, "cov_ee_m2": 100.0, "cov_en_m2": 0.0, "cov_nn_m2": 100.0})


def test_a_time_column_in_another_zone_is_read_as_utc():
    m = _adsb()
    local = m.assign(time=m["time"].dt.tz_convert("Asia/Kuala_Lumpur"))
    got = track(local, step_s=7.0).tracks
    assert str(got["time"].dt.tz) == "UTC"
    # 07:00:00.25 UTC is 25200.25 s after UTC midnight (15:00 in Kuala Lumpur, UTC+8)
    assert got["time_of_day"].iloc[0] == pytest.approx(25200.25)
    grid = got[got["coasted"]]
    since_midnight = (grid["time"] - pd.Timestamp("2024-05-10T00:00Z")).dt.total_seconds()
    assert len(grid) > 10 and np.allclose(since_midnight % 7.0, 0.0)
    pd.testing.assert_frame_equal(got, track(m, step_s=7.0).tracks)


def test_naive_times_are_refused_with_the_fix():
    m = _adsb()
    with pytest.raises(TypeError, match=r"measurements: column 'time' must hold time-zone-aware UTC "
                                        r"datetimes, got naive datetimes: localise them, "
                                        r"\.dt\.tz_localize\('UTC'\)"):
        track(m.assign(time=m["time"].dt.tz_localize(None)))
    res = track(m, keep_states=True)
    with pytest.raises(ValueError, match="time '2024-05-10 07:01': a naive time"):
        res.state_at("A1", "2024-05-10 07:01")
    # an aware time in another zone is the same instant: 15:01 in Kuala Lumpur is 07:01 UTC
    kl = res.state_at("A1", pd.Timestamp("2024-05-10 15:01", tz="Asia/Kuala_Lumpur"))
    assert kl.time == pd.Timestamp("2024-05-10T07:00:59.25Z")
    with pytest.raises(KeyError, match="'NOPE': not tracked in this result \\(1 aircraft: 'A1'\\)"):
        res.state_at("NOPE", T0)
    with pytest.raises(KeyError, match="keep_states=True"):
        track(m).state_at("A1", T0)


@pytest.mark.parametrize("kwargs, error, message", [
    ({"step_s": "1"}, TypeError, "step_s '1': must be a number of seconds, not str"),
    ({"step_s": True}, TypeError, "step_s True"),
    ({"step_s": np.nan}, ValueError, "step_s nan: must be a finite number"),
    ({"step_s": 10.0, "max_coast_s": 5.0}, ValueError, r"max_coast_s 5.0: .* >= step_s \(10\)"),
    ({"max_coast_s": -1}, ValueError, "max_coast_s -1"),
    ({"epoch": "2024-05-10"}, ValueError, "epoch '2024-05-10': a naive time"),
])
def test_bad_numbers_are_named(kwargs, error, message):
    with pytest.raises(error, match=message):
        track(_adsb(10), **kwargs)


def test_a_covariance_that_is_not_positive_definite_is_refused():
    m = _adsb(10)
    m.loc[3, "cov_ee_m2"] = -100.0
    with pytest.raises(ValueError, match=r"1 row\(s\) with a covariance that is not positive definite.*"
                                         r"index 3: cov_ee_m2 -100"):
        track(m)
    m.loc[3, ["cov_ee_m2", "cov_en_m2"]] = (100.0, 100.0)  # correlation 1: singular
    with pytest.raises(ValueError, match="index 3"):
        track(m)


def test_every_report_is_counted():
    adsb = _adsb(120)
    radar = _adsb(30, sensor="048:25/201", dt=4.0).assign(sensor_kind="radar", cov_ee_m2=np.nan)
    far = _adsb(2).assign(latitude=-41.0)  # 9000 km from the others: out of range
    bad = _adsb(3).assign(latitude=95.0)  # no such latitude: invalid
    anon = _adsb(5, sensor="048:25/201").assign(sensor_kind="radar", aircraft_id=None)
    m = pd.concat([adsb, radar, far, bad, anon], ignore_index=True)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        res = track(m)
    said = "5 report(s) without an aircraft_id not tracked (048:25/201: 5"
    assert any(said in str(w.message) for w in caught)
    assert res.parameters["unidentified_reports"] == {"048:25/201": 5}
    s = res.sensors.set_index("sensor_id")
    assert s.loc["048:25/201", ["reports", "updates", "gated", "invalid", "out_of_range"]].tolist() == [
        30, 0, 0, 30, 0]
    assert s.loc["048:25/201", "sensor_kind"] == "radar"
    assert s.loc["021:0/107", ["reports", "updates", "invalid", "out_of_range"]].tolist() == [125, 120, 3, 2]
    counts = res.sensors[["updates", "gated", "invalid", "out_of_range"]].sum(axis=1)
    assert (res.sensors["reports"] == counts).all()
    a = res.aircraft.iloc[0]
    assert (a["reports"], a["invalid"], a["out_of_range"]) == (155, 33, 2)
    none = track(radar)
    assert none.tracks.empty
    assert none.sensors[["reports", "invalid", "updates"]].values.tolist() == [[30, 30, 0]]


def _with_radar():
    radar = _adsb(30, sensor="048:25/201", dt=4.0).assign(sensor_kind="radar")
    return pd.concat([_adsb(120), radar], ignore_index=True)


@pytest.mark.parametrize("sites, message", [
    ({"048:25/202": (41.2, 2.1)}, r"'048:25/202' not a radar of the measurements, while '048:25/201' has no "
                                  r"site \(a misspelt key\?\)"),
    ({"048:25/201": (2.1, 101.7)}, r"latitude 2.1 / longitude 101.7|km from its plots"),
    ({"048:25/201": (101.7, 2.1)}, r"sites\['048:25/201'\] \(101.7, 2.1\): latitude 101.7 / longitude 2.1 "
                                   r"out of range"),
    ({"048:25/201": (2.0, 41.2)}, r"sites\['048:25/201'\] \(2.0, 41.2\): 5,8[0-9]{2} km from its plots"),
    ({"048:25/201": 41.2}, r"sites\['048:25/201'\] 41.2: expected \(latitude, longitude\)"),
])
def test_bad_radar_sites_are_named(sites, message):
    """estimate_noise dropped a misspelt key or a (longitude, latitude) site and gave the radar one isotropic
    factor without a word (audit A10); (2.0, 41.2) is the site (41.2, 2.0) swapped: 5,850 km from the
    plots by the haversine (R 6371 km)."""
    from msdc.pipeline.track.noise import estimate_noise

    with pytest.raises(ValueError, match=message):
        estimate_noise(_with_radar(), sites=sites)


def test_a_sensor_file_radar_absent_from_the_measurements_is_left_out():
    from msdc.pipeline.track.noise import check_sites

    sites = {"048:25/201": (41.2, 2.1), "048:25/999": (40.0, 3.0)}
    assert check_sites(_with_radar(), sites) == {"048:25/201": (41.2, 2.1)}


def test_a_turn_rate_means_the_same_sign_in_the_modes_and_the_table():
    """Positive turn_rate_dps = right turn (track angle increasing) in the table, in Mode and in the
    parameters (the JSON said turn_left +3, turn_right -3 against the table's right = + (audit B7))."""
    from msdc.pipeline.track import default_modes

    modes = {m.name: m.turn_rate_dps for m in default_modes(3.0)}
    assert modes["turn_left"] == -3.0 and modes["turn_right"] == 3.0
    # a clockwise circle: heading 3t deg (north, then east), 100 m/s, 1 Hz reports
    t = np.arange(0.0, 90.0)
    psi = np.radians(np.where(t < 30, 0.0, 3.0 * (t - 30)))
    e, n = np.cumsum(100.0 * np.sin(psi)), np.cumsum(100.0 * np.cos(psi))
    m = _adsb(90).assign(latitude=41.0 + n / 111_000.0,
                         longitude=2.0 + e / (111_000.0 * np.cos(np.radians(41.0))))
    res = track(m)
    params = {p["name"]: p["turn_rate_dps"] for p in res.parameters["modes"]}
    assert params["turn_left"] == -3.0 and params["turn_right"] == 3.0
    turning = res.tracks[(res.tracks.time_of_day > 25200.25 + 45) & (res.tracks.time_of_day < 25200.25 + 88)]
    assert (turning["mode_turn_right"] > 0.8).mean() > 0.8
    assert turning["turn_rate_dps"].median() > 2.0
    # the mode that dominates turns the way the table's turn rate says
    dominant = turning[["mode_turn_left", "mode_turn_right"]].idxmax(axis=1).str.removeprefix("mode_")
    dominant = dominant.map(params)
    assert (np.sign(dominant) == np.sign(turning["turn_rate_dps"])).mean() > 0.9


def test_coasted_time_is_time_beyond_the_update_interval():
    """tracked_s spans first to last update; coasted_s is the time without any update beyond the slowest
    sensor's interval (audit B10: a radar-only track at 4 s read ~75 % coasted with no scan missed, and a
    one-report track 'tracked 60, coasted 60')."""
    from msdc.pipeline.track.tracker import coasted_time

    t = np.array([0.0, 4.0, 8.0, 16.0, 20.0])  # the 12 s scan missed: 4 s coasted
    assert coasted_time(t, np.zeros(5, int), np.full(5, "r")) == (4.0, 4.0)
    # ADS-B each second from 0 to 40 s but 10-29 s; a 4 s radar throughout but 20-35 s
    adsb = np.r_[np.arange(0.0, 10.0), np.arange(30.0, 41.0)]
    radar = np.r_[np.arange(0.0, 20.0, 4.0), np.arange(36.0, 41.0, 4.0)]
    times = np.r_[adsb, radar]
    order = np.argsort(times, kind="stable")
    sensors = np.r_[np.full(len(adsb), "a"), np.full(len(radar), "r")][order]
    # gaps without any update: 16 -> 30 s (14 s, 10 beyond the radar's 4 s), all others <= 4 s
    assert coasted_time(times[order], np.zeros(len(times), int), sensors) == (4.0, 10.0)
    # a 60 s gap that ends a segment is not coasting
    two = coasted_time(np.array([0.0, 4.0, 64.0, 68.0]), np.array([0, 0, 1, 1]), np.full(4, "r"))
    assert two == (4.0, 0.0)
    assert np.isnan(coasted_time(np.array([5.0]), np.zeros(1, int), np.array(["a"]))[0])

    radar = _adsb(30, sensor="048:25/201", dt=4.0).assign(sensor_kind="radar")
    radar = radar.drop(index=[10, 11])  # two scans missed: 40 and 44 s
    one = _adsb(1, aircraft="B")
    a = track(pd.concat([radar, one], ignore_index=True), max_coast_s=60.0).aircraft.set_index("aircraft_id")
    assert a.loc["A1", ["tracked_s", "update_interval_s", "coasted_s"]].tolist() == [116.0, 4.0, 8.0]
    assert a.loc["B", ["tracked_s", "coasted_s"]].tolist() == [0.0, 0.0]


@pytest.mark.parametrize(("kwargs", "error", "said"), [
    ({"turn_rate_dps": float("nan")}, ValueError, "turn_rate_dps nan: must be a finite number of degrees per "
                                                  "second > 0"),
    ({"turn_rate_dps": float("inf")}, ValueError, "turn_rate_dps inf"),
    ({"turn_rate_dps": -5.0}, ValueError, "turn_rate_dps -5.0"),
    ({"config": "x"}, TypeError, "config 'x': a TrackerConfig, not str"),
    ({"columns": ("time", "nosuch")}, ValueError, "columns: 'nosuch' not in the tracks table"),
])
def test_bad_model_arguments_are_named(kwargs, error, said):
    """turn_rate_dps was taken as given (nan: a turn-rate column of NaN; inf: fewer rows, NaN positions;
    negative: the turn modes swapped); config 'x' and an unknown column failed deep inside (AttributeError,
    KeyError)."""
    with pytest.raises(error) as caught:
        track(_adsb(), **kwargs)
    assert str(caught.value).startswith(said)
