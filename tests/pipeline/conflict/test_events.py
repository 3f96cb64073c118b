"""Losses of separation, alert events, warning times and false alerts on hand-worked traffic."""

import numpy as np
import pandas as pd
import pytest

from msdc.pipeline.conflict import alert_events, classify_alerts, losses_of_separation, warning_times

A = 6378137.0
T0 = pd.Timestamp("2024-05-01 10:00:00", tz="UTC")


def lon_at(distance_nm):
    """Longitude on the equator whose chord from (0, 0) is distance_nm: 2 A sin(dlon / 2) = d."""
    return np.degrees(2 * np.arcsin(np.asarray(distance_nm) * 1852 / (2 * A)))


def tracks_from(distances_nm, fl_b=355.0, extra=None):
    """A fixed at (0, 0) FL350; B on the equator at the given distance from A, one per second."""
    rows = []
    for k, dist in enumerate(distances_nm):
        t = T0 + pd.Timedelta(seconds=k)
        rows.append(("A", t, 0.0, 0.0, 350.0))
        if dist is not None:
            rows.append(("B", t, 0.0, float(lon_at(dist)), fl_b))
        if extra:
            rows.extend((name, t, 0.0, lon, fl) for name, lon, fl in extra)
    return pd.DataFrame(rows, columns=["aircraft_id", "time", "latitude", "longitude", "flight_level"])


def test_one_loss_by_hand():
    tracks = tracks_from([7, 6, 4.9, 3.0, 2.5, 4.0, 5.01, 6])  # in loss at 2..5 s, closest 2.5 NM at 4 s
    losses = losses_of_separation(tracks)
    assert len(losses) == 1
    loss = losses.iloc[0]
    assert (loss.aircraft_a, loss.aircraft_b) == ("A", "B")
    assert loss.start == T0 + pd.Timedelta(seconds=2) and loss.end == T0 + pd.Timedelta(seconds=5)
    assert loss.duration_s == 3.0
    assert loss.min_horizontal_nm == pytest.approx(2.5, abs=1e-9)
    assert loss.time_of_min == T0 + pd.Timedelta(seconds=4)
    assert loss.min_vertical_ft == pytest.approx(500.0) and loss.vertical_at_min_ft == pytest.approx(500.0)


def test_vertical_separation_of_1000_ft_is_kept_and_gaps_split_losses():
    # C sits 1 NM east of A at FL360: exactly 1000 ft above A (separated), 500 ft above B (a loss
    # whenever B is within 5 NM of C, i.e. B within 6 NM of A on the same side)
    c_lon = float(lon_at(1.0))
    tracks = tracks_from([3, 3, None, 3, 9], extra=[("C", c_lon, 360.0)])
    losses = losses_of_separation(tracks)
    got = [(r.aircraft_a, r.aircraft_b, (r.start - T0).seconds, (r.end - T0).seconds)
           for r in losses.itertuples()]
    # B absent at 2 s: each pair's loss splits in two; A-C never (1000 ft)
    assert sorted(got) == [("A", "B", 0, 1), ("A", "B", 3, 3), ("B", "C", 0, 1), ("B", "C", 3, 3)]
    bc = losses[losses.aircraft_a == "B"].iloc[0]
    assert bc.min_horizontal_nm == pytest.approx(2.0, abs=1e-6)  # on the equator: 3 NM - 1 NM (to 1e-6)


def test_vertical_tolerance_boundary_by_hand():
    # B 3 NM from A; reported levels are quantised to 25 ft, so with the default 25 ft tolerance a loss
    # needs a vertical distance below 1000 - 25 = 975 ft
    def loss_at(fl_b, dist_nm=3.0, **kw):
        return not losses_of_separation(tracks_from([dist_nm], fl_b=fl_b), **kw).empty

    assert not loss_at(359.999)  # 999.9 ft: within the quantum of 1000 ft, separated
    assert loss_at(359.999, vertical_tolerance_ft=0.0)  # the strict rule counts it
    assert not loss_at(359.75)  # 975 ft exactly: the edge of the quantum, separated
    assert loss_at(359.74)  # 974 ft
    assert not loss_at(359.74, vertical_tolerance_ft=50.0)  # 974 ft >= 1000 - 50
    assert not loss_at(360.0, 4.9)  # 1000 ft apart at 4.9 NM: separated vertically
    assert loss_at(359.0, 4.9)  # 900 ft at 4.9 NM
    loss = losses_of_separation(tracks_from([4.9], fl_b=359.0)).iloc[0]
    assert loss.min_horizontal_nm == pytest.approx(4.9, abs=1e-9)
    assert loss.vertical_at_min_ft == pytest.approx(900.0)
    for bad in (-1.0, 1000.0, float("nan")):
        with pytest.raises(ValueError, match="vertical_tolerance_ft: must be from 0"):
            losses_of_separation(tracks_from([3.0]), vertical_tolerance_ft=bad)


def test_no_loss_gives_typed_empty_frame():
    losses = losses_of_separation(tracks_from([8, 7, 6]))
    assert losses.empty and list(losses.columns)[:4] == ["aircraft_a", "aircraft_b", "start", "end"]


def pc_frame(values, horizon=60, pair=("A", "B")):
    rows = [(T0 + pd.Timedelta(seconds=k), pair[0], pair[1], horizon, v) for k, v in values if v is not None]
    return pd.DataFrame(rows, columns=["time", "aircraft_a", "aircraft_b", "horizon_s", "pc"])


def test_alert_events_by_hand():
    pc = pd.concat([
        pc_frame([(0, 0.1), (1, 0.3), (2, 0.5), (3, 0.15), (4, 0.25), (5, 0.21), (7, 0.4)]),
        pc_frame([(1, 0.9)], horizon=20, pair=("B", "A")),  # written the other way round
    ])
    events = alert_events(pc, threshold=0.2)
    got = [(r.aircraft_a, r.aircraft_b, r.horizon_s, (r.start - T0).seconds, (r.end - T0).seconds, r.peak_pc,
            (r.time_of_peak - T0).seconds) for r in events.itertuples()]
    # 60 s: above at 1-2 (peak 0.5 at 2), 4-5 (0.25 at 4), 7 (after a missing sample at 6: a new event)
    assert got == [("A", "B", 20, 1, 1, 0.9, 1), ("A", "B", 60, 1, 2, 0.5, 2), ("A", "B", 60, 4, 5, 0.25, 4),
                   ("A", "B", 60, 7, 7, 0.4, 7)]
    assert len(alert_events(pc, threshold=0.2, step_s=2.0)) == 3  # gaps of 2 s bridged
    with pytest.raises(ValueError, match="threshold: a probability in"):
        alert_events(pc, threshold=1.5)
    with pytest.raises(ValueError, match="pc: missing column"):
        alert_events(pc.drop(columns="pc"))


def test_warning_times_and_false_alerts_by_hand():
    s = pd.Timedelta(seconds=1)
    losses = pd.DataFrame({"aircraft_a": ["A", "C"], "aircraft_b": ["B", "D"],
                           "start": [T0 + 100 * s, T0 + 300 * s], "end": [T0 + 130 * s, T0 + 310 * s]})
    alerts = pd.DataFrame({
        "aircraft_a": ["A", "A", "A", "A", "C", "E"], "aircraft_b": ["B", "B", "B", "B", "D", "F"],
        "horizon_s": [60, 60, 120, 20, 60, 60],
        "start": [T0 + 30 * s, T0 + 50 * s, T0 + 10 * s, T0 + 105 * s, T0 + 100 * s, T0 + 0 * s],
        "end": [T0 + 35 * s, T0 + 95 * s, T0 + 20 * s, T0 + 110 * s, T0 + 120 * s, T0 + 10 * s],
        "peak_pc": 0.5, "time_of_peak": T0})
    classified = classify_alerts(alerts, losses)
    # A-B at 60 s from 30-35 s reaches 95 s (< loss at 100 s): false; 50-95 s warns of the loss at 100 s;
    # 120 s horizon, 10-20 s reaches 140 s: true; 20 s horizon during the loss: true (late);
    # C-D 100-120 s reaches 180 s, before the loss at 300 s: false; E-F has no loss: false
    assert classified["false_alert"].tolist() == [True, False, False, False, True, True]
    assert classified["loss_start"].iloc[1] == T0 + 100 * s
    warn = warning_times(losses, alerts, horizons_s=[20, 60, 120])
    got = {(r.aircraft_a, r.horizon_s): r.warning_s for r in warn.itertuples()}
    assert got[("A", 20)] == -5.0 and got[("A", 60)] == 50.0 and got[("A", 120)] == 90.0
    assert all(np.isnan(got[("C", h)]) for h in (20, 60, 120))  # missed at every horizon


def chord_nm(lat1, lon1, lat2, lon2):
    """Straight line between two points on the WGS-84 surface, from the ellipsoid's own formulas."""
    e2 = (1 / 298.257223563) * (2 - 1 / 298.257223563)

    def ecef(lat, lon):
        la, lo = np.radians(lat), np.radians(lon)
        n = A / np.sqrt(1 - e2 * np.sin(la) ** 2)
        return np.array([n * np.cos(la) * np.cos(lo), n * np.cos(la) * np.sin(lo), n * (1 - e2) * np.sin(la)])

    return float(np.linalg.norm(ecef(lat1, lon1) - ecef(lat2, lon2))) / 1852.0


def test_losses_of_separation_equal_brute_force():
    """Every pair at every time tested (O(n^2)), the runs walked grid time by grid time."""
    rng = np.random.default_rng(11)
    n_aircraft, n_steps = 14, 30
    lat = rng.uniform(-0.15, 0.15, n_aircraft)
    lon = rng.uniform(-0.15, 0.15, n_aircraft)
    rows = []
    for k in range(n_steps):
        lat, lon = lat + rng.normal(0, 0.004, n_aircraft), lon + rng.normal(0, 0.004, n_aircraft)
        fl = rng.choice([330.0, 339.8, 340.0, 340.2, 350.0], n_aircraft)  # 1000 ft apart, or wobbling
        for a in range(n_aircraft):
            if rng.random() > 0.1:  # some aircraft absent at some times
                rows.append((f"AC{a:02d}", T0 + pd.Timedelta(seconds=k), lat[a], lon[a], fl[a]))
    tracks = pd.DataFrame(rows, columns=["aircraft_id", "time", "latitude", "longitude", "flight_level"])
    tracks = tracks.sample(frac=1.0, random_state=3).reset_index(drop=True)  # any row order
    got = losses_of_separation(tracks, 5.0, 1000.0, 25.0)

    grid = sorted(tracks["time"].unique())
    at = {(r.time, r.aircraft_id): r for r in tracks.itertuples()}
    ids = sorted(tracks["aircraft_id"].unique())
    expected = []
    for ia, a in enumerate(ids):
        for b in ids[ia + 1:]:
            run = []
            for t in grid + [None]:
                ra, rb = at.get((t, a)), at.get((t, b))
                inside = False
                if ra is not None and rb is not None:
                    h = chord_nm(ra.latitude, ra.longitude, rb.latitude, rb.longitude)
                    v = abs(ra.flight_level - rb.flight_level) * 100
                    inside = h < 5.0 and v < 975.0
                if inside:
                    run.append((t, h, v))
                elif run:
                    t_min, h_min, v_min = min(run, key=lambda s: s[1])
                    expected.append((a, b, run[0][0], run[-1][0], (run[-1][0] - run[0][0]).total_seconds(),
                                     h_min, t_min, v_min, min(s[2] for s in run)))
                    run = []
    expected.sort(key=lambda e: (e[2], e[0], e[1]))
    assert len(expected) >= 10 and any(e[4] > 0 for e in expected)  # several losses, some lasting
    assert len(got) == len(expected)
    for row, exp in zip(got.itertuples(index=False), expected, strict=True):
        assert (row.aircraft_a, row.aircraft_b, row.start, row.end, row.duration_s) == exp[:5]
        assert row.min_horizontal_nm == pytest.approx(exp[5], rel=1e-9) and row.time_of_min == exp[6]
        assert row.vertical_at_min_ft == pytest.approx(exp[7], rel=1e-9)
        assert row.min_vertical_ft == pytest.approx(exp[8], rel=1e-9)


def _grid_and_report_rows(offset_a_s: float, offset_b_s: float) -> pd.DataFrame:
    """track()-like output: A fixed at (0, 0), B on the equator |10 - 0.2 t| NM from it, each with a row
    at every whole second (the grid) and one at a report time offset_s after it."""
    rows = []
    for k in range(101):
        for name, offset in (("A", offset_a_s), ("B", offset_b_s)):
            for t in (k, k + offset):
                lon = 0.0 if name == "A" else float(lon_at(abs(10 - 0.2 * t)))
                rows.append((name, T0 + pd.Timedelta(seconds=t), 0.0, lon, 350.0))
    return pd.DataFrame(rows, columns=["aircraft_id", "time", "latitude", "longitude", "flight_level"])


@pytest.mark.parametrize("offsets", [(0.3, 0.55), (0.25, 0.5)])  # not multiples; multiples, seldom 0.25 apart
def test_report_rows_off_the_grid_are_refused_or_left_out(offsets):
    from msdc.pipeline.conflict import grid_rows

    tracks = _grid_and_report_rows(*offsets)
    with pytest.raises(ValueError, match=r"tracks: the rows are not on one common time grid .*grid_rows"):
        losses_of_separation(tracks)
    # by hand: |10 - 0.2 t| < 5 for 25 < t < 75: grid times 26..74, closest (0 NM) at 50 s
    for losses in (losses_of_separation(tracks, step_s=1.0), losses_of_separation(grid_rows(tracks, 1.0))):
        assert len(losses) == 1
        loss = losses.iloc[0]
        assert (loss.start - T0).total_seconds() == 26 and (loss.end - T0).total_seconds() == 74
        assert loss.duration_s == 48.0 and loss.time_of_min == T0 + pd.Timedelta(seconds=50)
        assert loss.min_horizontal_nm == pytest.approx(0.0, abs=1e-9)


def test_aircraft_at_different_steps_are_refused():
    # C and D every second, A and B every 5 s: a loss run of A-B would end at every second
    tracks = tracks_from([3.0] * 30, extra=[("C", 1.0, 200.0), ("D", 1.0, 200.0)])
    tracks = tracks[tracks["aircraft_id"].isin(["C", "D"]) | ((tracks["time"] - T0).dt.seconds % 5 == 0)]
    with pytest.raises(ValueError, match=r"aircraft 'A' is never 1 s \(the smallest step\)"):
        losses_of_separation(tracks)
    losses = losses_of_separation(tracks, step_s=5.0)  # the 5 s grid: one run each, 0..25 s
    assert sorted(zip(losses.aircraft_a, losses.aircraft_b, losses.duration_s, strict=True)) == [
        ("A", "B", 25.0), ("C", "D", 25.0)]


def test_alert_events_step_is_each_pair_and_horizons_own():
    t = pd.date_range(T0, periods=301, freq="1s")
    a = pd.DataFrame({"aircraft_a": "A", "aircraft_b": "B", "horizon_s": 60, "time": t[0:300:5], "pc": 0.5})
    other_pair = pd.DataFrame({"aircraft_a": "C", "aircraft_b": "D", "horizon_s": 60, "time": t[0:2],
                               "pc": 0.0})
    other_horizon = a.assign(horizon_s=20, time=t[:60])
    assert len(alert_events(a)) == 1  # 5 s samples, PC 0.5 throughout: one event
    assert len(alert_events(pd.concat([a, other_pair]))) == 1
    events = alert_events(pd.concat([a, other_horizon]))
    assert events[["horizon_s", "start", "end"]].values.tolist() == [[20, t[0], t[59]], [60, t[0], t[295]]]
    assert len(alert_events(a, step_s=1.0)) == 60  # a step given is used as given


def test_classifying_twice_and_chaining_give_the_same_tables():
    s = pd.Timedelta(seconds=1)
    losses = pd.DataFrame({"aircraft_a": ["A"], "aircraft_b": ["B"], "start": [T0 + 100 * s],
                           "end": [T0 + 130 * s]})
    alerts = pd.DataFrame({"aircraft_a": ["A", "B"], "aircraft_b": ["B", "A"], "horizon_s": [60, 60],
                           "start": [T0 + 50 * s, T0 + 200 * s], "end": [T0 + 95 * s, T0 + 210 * s],
                           "peak_pc": 0.5, "time_of_peak": T0})
    once = classify_alerts(alerts, losses)
    assert once["false_alert"].tolist() == [False, True]  # 50-95 s reaches 155 s; 200-210 s is after the loss
    pd.testing.assert_frame_equal(classify_alerts(once, losses), once)
    warn = warning_times(losses, once)
    pd.testing.assert_frame_equal(warn, warning_times(losses, alerts))
    assert warn["warning_s"].tolist() == [50.0]


def test_times_must_be_time_zone_aware_and_are_compared_in_utc():
    s = pd.Timedelta(seconds=1)
    losses = pd.DataFrame({"aircraft_a": ["A"], "aircraft_b": ["B"], "start": [T0 + 100 * s],
                           "end": [T0 + 130 * s]})
    alerts = pd.DataFrame({"aircraft_a": ["A"], "aircraft_b": ["B"], "horizon_s": [60],
                           "start": [T0 + 50 * s], "end": [T0 + 95 * s], "peak_pc": 0.5, "time_of_peak": T0})
    naive = alerts.assign(start=alerts["start"].dt.tz_localize(None),
                          end=alerts["end"].dt.tz_localize(None))
    with pytest.raises(TypeError, match=r"alerts: column 'start' must hold time-zone-aware UTC datetimes, "
                                        r"got naive datetimes"):
        classify_alerts(naive, losses)
    with pytest.raises(TypeError, match=r"alerts: column 'start'"):
        warning_times(losses, naive)
    pc = pc_frame([(0, 0.5), (1, 0.5)])
    with pytest.raises(TypeError, match=r"pc: column 'time' .* dtype (object|str): convert"):
        alert_events(pc.assign(time=pc["time"].astype(str)))
    with pytest.raises(TypeError, match=r"tracks: column 'time' .* naive"):
        losses_of_separation(tracks_from([3.0, 3.0]).assign(time=lambda f: f["time"].dt.tz_localize(None)))
    # 12:00 in Madrid (CEST, UTC+2) is 10:00 UTC: the same loss and the same warning, in UTC
    madrid = losses.assign(start=losses["start"].dt.tz_convert("Europe/Madrid"),
                           end=losses["end"].dt.tz_convert("Europe/Madrid"))
    assert classify_alerts(alerts, madrid)["loss_start"].tolist() == [T0 + 100 * s]
    assert warning_times(madrid, alerts)["warning_s"].tolist() == [50.0]
    events = alert_events(pc.assign(time=pc["time"].dt.tz_convert("Europe/Madrid")))
    assert events["start"].tolist() == [T0] and str(events["start"].dt.tz) == "UTC"
