"""Losses measured only where both aircraft are reported (issue 26): the reported intervals and the
positions interpolated between reports, by hand; a coasted stretch never a loss; the closest point of a
loss between its grid samples in closed form; losses that began inside the minimum."""

import numpy as np
import pandas as pd
import pytest

from msdc.pipeline.conflict.events import losses_by_pairs
from msdc.pipeline.conflict.grid import grid_rows
from msdc.pipeline.conflict.loss_minimum import loss_minima
from msdc.pipeline.conflict.reported import report_rows, reported_intervals, reported_samples

A = 6378137.0
T0 = pd.Timestamp("2024-05-01 10:00:00", tz="UTC")
KT = 1.0 / 3600.0  # NM/s per kt


def lon_at(distance_nm):
    """Longitude on the equator whose chord from (0, 0) is distance_nm: 2 A sin(dlon / 2) = d (a signed
    distance gives a signed longitude)."""
    d = np.asarray(distance_nm, float)
    return np.sign(d) * np.degrees(2 * np.arcsin(np.abs(d) * 1852 / (2 * A)))


def tracker_rows(name, report_s, grid_s, east_nm, fl, end_s=None):
    """A tracker-like frame for one aircraft on the equator: a row at each report (coasted False) and at
    each grid time up to end_s (coasted True unless a report falls on it); east_nm(t) and fl(t) give the
    position and level at any time, so coasted rows carry the extrapolation the tracker would."""
    times = sorted(set(report_s) | {t for t in grid_s if end_s is None or t <= end_s})
    return pd.DataFrame({"aircraft_id": name, "time": [T0 + pd.Timedelta(seconds=t) for t in times],
                         "latitude": 0.0, "longitude": [float(lon_at(east_nm(t))) for t in times],
                         "flight_level": [float(fl(t)) for t in times],
                         "coasted": [t not in report_s for t in times], "on_surface": False})


def losses_on_reports(frames, step_s=5.0, max_gap_s=15.0):
    """What the conflicts job does: losses on the reported grid samples, their closest points."""
    tracks = pd.concat(frames, ignore_index=True)
    reports = report_rows(tracks)
    samples = reported_samples(grid_rows(tracks, step_s), reports, max_gap_s)
    losses = losses_by_pairs(samples, 5.0, 1000.0, 25.0, kinds=("airborne",), step_s=step_s)["airborne"]
    return loss_minima(losses, reports, 5.0, 975.0, max_gap_s), samples


def test_reported_intervals_by_hand():
    ns = (np.array([0.0, 4.0, 8.0, 20.0, 40.0]) * 1e9).astype(np.int64)
    interval, starts = reported_intervals(ns, 15.0)  # gaps 4, 4, 12 linked; 20 is not
    assert interval.tolist() == [0, 0, 0, 0, 1] and starts.tolist() == [0, 4, 5]
    interval, starts = reported_intervals(ns, 10.0)  # 12 s is more than 10
    assert interval.tolist() == [0, 0, 0, 1, 2] and starts.tolist() == [0, 3, 4, 5]


def test_grid_samples_between_reports_are_interpolated_and_coasted_ones_left_out():
    # reports at 0, 4, 8, 20 and 40 s, the grid every 5 s to 60 s (coasted after 40 s); the position moves
    # 0.1 NM/s east and the level 0.5 FL/s, so interpolation between any two reports is exact
    grid = range(0, 61, 5)
    rows = tracker_rows("A", [0, 4, 8, 20, 40], grid, lambda t: 0.1 * t, lambda t: 100 + 0.5 * t)
    samples = reported_samples(grid_rows(rows, 5.0), report_rows(rows), 15.0)
    seconds = ((samples["time"] - T0).dt.total_seconds()).tolist()
    assert seconds == [0, 5, 10, 15, 20, 40]  # 25-35 s: 20 s between reports; 45-60 s: coasted
    assert samples["interval"].tolist() == [0, 0, 0, 0, 0, 1]
    assert np.allclose(samples["longitude"], lon_at(0.1 * np.array(seconds)), atol=1e-12)
    assert np.allclose(samples["flight_level"], 100 + 0.5 * np.array(seconds))
    shorter = reported_samples(grid_rows(rows, 5.0), report_rows(rows), 10.0)  # 8 -> 20 s is 12 s
    assert ((shorter["time"] - T0).dt.total_seconds()).tolist() == [0, 5, 20, 40]


def test_a_coasted_stretch_is_never_a_loss():
    # head-on on the equator at 360 kt each, 500 ft apart, meeting at 41 s: B's reports stop at 20 s and
    # its track coasts on through A. On the coasted samples the old tables had a loss down to 0.2 NM at
    # 40 s; on the reported ones the loss ends at 20 s, where B was 8.2 - 2 x 0.1 x 20 = 4.2 NM from A
    grid = range(0, 61, 5)
    a = tracker_rows("A", list(range(0, 61, 4)), grid, lambda t: -4.1 + 0.1 * t, lambda t: 350.0)
    b = tracker_rows("B", list(range(0, 21, 4)), grid, lambda t: 4.1 - 0.1 * t, lambda t: 355.0, end_s=60)
    losses, _ = losses_on_reports([a, b])
    assert len(losses) == 1
    loss = losses.iloc[0]
    # under 5 NM from 16 s: the first grid sample inside is at 20 s, B's last report
    assert loss["start"] == loss["end"] == T0 + pd.Timedelta(seconds=20)
    assert loss["min_horizontal_nm"] == pytest.approx(4.2, abs=1e-6)
    assert loss["time_of_min"] == T0 + pd.Timedelta(seconds=20)


def test_the_closest_point_between_grid_samples_in_closed_form():
    # head-on on the equator at 360 kt each, meeting at 22 s: the 5 s grid has them 0.4 NM apart at 20 s
    # and 0.6 NM at 25 s; the reports (every 4 s) put the meeting between 20 and 24 s, at 0 NM. B climbs
    # from FL345.6 at 0.2 FL/s through A's FL350 at 22 s as well, so the vertical minimum is 0 there
    grid = range(0, 61, 5)
    a = tracker_rows("A", list(range(0, 61, 4)), grid, lambda t: -2.2 + 0.1 * t, lambda t: 350.0)
    b = tracker_rows("B", list(range(0, 61, 4)), grid, lambda t: 2.2 - 0.1 * t, lambda t: 345.6 + 0.2 * t)
    losses, _ = losses_on_reports([a, b])
    assert len(losses) == 1
    loss = losses.iloc[0]
    assert loss["min_horizontal_nm"] == pytest.approx(0.0, abs=1e-6)
    assert loss["time_of_min"] == T0 + pd.Timedelta(seconds=22)
    assert loss["vertical_at_min_ft"] == pytest.approx(0.0, abs=1e-6)
    assert loss["min_vertical_ft"] == pytest.approx(0.0, abs=1e-6)
    assert loss["flight_level_a"] == pytest.approx(350.0) and loss["flight_level_b"] == pytest.approx(350.0)
    assert loss["latitude"] == pytest.approx(0.0) and loss["longitude"] == pytest.approx(0.0, abs=1e-9)
    # in loss while under 5 NM (from 22 - 25 s to 22 + 25 s) and 975 ft (B from FL340.25 to FL359.75:
    # -28.75 s to 70.75 s): the grid samples 0..45 s
    assert loss["start"] == T0 and loss["end"] == T0 + pd.Timedelta(seconds=45)


def test_a_loss_that_begins_inside_the_minimum_is_marked():
    # B's track starts at 10 s 3 NM west of A (already inside); C closes on A from 8.2 NM east at 0.1 NM/s
    # and is inside from 32 s: the grid sample before the first inside, 35 s, had C outside (5.2 NM at
    # 30 s). B and C stay more than 5 NM apart (11.2 - 0.1 t NM) up to 60 s
    grid = range(0, 61, 5)
    a = tracker_rows("A", list(range(0, 61, 4)), grid, lambda t: 0.0, lambda t: 350.0)
    b = tracker_rows("B", list(range(10, 61, 4)), [t for t in grid if t >= 10], lambda t: -3.0,
                     lambda t: 352.0)
    c = tracker_rows("C", list(range(0, 61, 4)), grid, lambda t: 8.2 - 0.1 * t, lambda t: 348.0)
    losses, _ = losses_on_reports([a, b, c])
    assert sorted(by for by in zip(losses["aircraft_a"], losses["aircraft_b"], strict=True)) == [
        ("A", "B"), ("A", "C")]
    by_pair = {(r.aircraft_a, r.aircraft_b): r for r in losses.itertuples()}
    assert by_pair[("A", "B")].began_inside and not by_pair[("A", "C")].began_inside
    assert by_pair[("A", "C")].start == T0 + pd.Timedelta(seconds=35)


def test_report_positions_come_from_the_accepted_measurements():
    # the tracker's estimate at a report lags the plot; the report's own position is used, a rejected
    # plot at the same time from another sensor is not
    rows = tracker_rows("A", [0, 4], range(0, 6, 5), lambda t: 0.1 * t, lambda t: 100.0)
    meas = pd.DataFrame({"aircraft_id": ["A", "A", "A"], "sensor_id": ["r1", "r1", "r2"],
                         "time": [T0, T0 + pd.Timedelta(seconds=4), T0 + pd.Timedelta(seconds=4)],
                         "latitude": [0.001, 0.002, 0.5], "longitude": [0.0, 0.01, 0.5]})
    rejected = meas.iloc[[2]]
    reports = report_rows(rows, meas, rejected)
    assert reports["latitude"].tolist() == [0.001, 0.002] and reports["longitude"].tolist() == [0.0, 0.01]
    assert reports["flight_level"].tolist() == [100.0, 100.0]  # the tracker's level


def test_a_departure_flagged_as_it_becomes_airborne_inside_the_minimum_began_inside():
    # two simultaneous departures from parallel runways 0.7 NM apart: each on the surface until 20 s; the
    # airborne pair is first counted at 20 s, already inside the minimum: no alert could have warned
    grid = range(0, 61, 5)
    a = tracker_rows("A", list(range(0, 61, 4)), grid, lambda t: 0.0, lambda t: 0.0)
    b = tracker_rows("B", list(range(0, 61, 4)), grid, lambda t: 0.7, lambda t: 0.0)
    for f in (a, b):
        f["on_surface"] = (f["time"] - T0).dt.total_seconds() < 20
    losses, _ = losses_on_reports([a, b])
    assert len(losses) == 1 and losses.iloc[0]["began_inside"]
    assert losses.iloc[0]["start"] == T0 + pd.Timedelta(seconds=20)


def test_a_coarser_sensor_counts_only_where_the_finest_is_silent():
    """Aircraft A: ADS-B (sigma 5 m) every 2 s over 0-10 s and 40-50 s, radar (sigma 300 m, 60 times
    coarser) every 4 s from 1 s; reports 10 s apart at most bracket one another (max_gap_s 10). The radar
    plots at 1, 5 and 9 s lie between ADS-B reports 2 s apart, and 41, 45, 49 s too: left out; 13-37 s have
    ADS-B reports 30 s apart around them, 53 and 57 s none after: kept. Aircraft B: ADS-B (5 m) and
    multilateration (8 m, less than twice as coarse): both kept. Aircraft C: no sigma given: every report
    kept."""
    adsb_s = [0, 2, 4, 6, 8, 10, 40, 42, 44, 46, 48, 50]
    radar_s = list(range(1, 61, 4))
    times = sorted(set(adsb_s) | set(radar_s))
    rows = tracker_rows("A", times, [], lambda t: 0.1 * t, lambda t: 100.0)
    rows_b = tracker_rows("B", [0, 1, 2, 3], [], lambda t: 0.1 * t, lambda t: 200.0)
    rows_c = tracker_rows("C", [0, 4], [], lambda t: 0.1 * t, lambda t: 300.0)
    meas = pd.DataFrame({
        "aircraft_id": ["A"] * (len(adsb_s) + len(radar_s)) + ["B"] * 4 + ["C"] * 2,
        "sensor_id": ["adsb"] * len(adsb_s) + ["radar"] * len(radar_s) + ["adsb", "mlat"] * 2 + ["r", "r"],
        "time": [T0 + pd.Timedelta(seconds=t) for t in [*adsb_s, *radar_s, 0, 1, 2, 3, 0, 4]],
        "latitude": 0.0, "longitude": 0.0,
        "sigma_major_m": [5.0] * len(adsb_s) + [300.0] * len(radar_s) + [5.0, 8.0] * 2 + [np.nan] * 2})
    tracks = pd.concat([rows, rows_b, rows_c], ignore_index=True)
    got = report_rows(tracks, meas, max_gap_s=10.0)
    seconds = lambda name: [(t - T0).total_seconds() for t in got.loc[got["aircraft_id"] == name, "time"]]  # noqa: E731
    kept_radar = [13, 17, 21, 25, 29, 33, 37, 53, 57]
    assert seconds("A") == sorted(set(adsb_s) | set(kept_radar))
    assert seconds("B") == [0, 1, 2, 3] and seconds("C") == [0, 4]
