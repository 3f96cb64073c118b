"""pipeline.model.mixed: two targets under one identity, from report sequences worked out by hand."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from pyproj import Geod

from msdc.pipeline.model.mixed import mixed_identities, mixed_warnings

GEOD = Geod(ellps="WGS84")
T0 = pd.Timestamp("2016-05-10T22:00:00Z")


def _reports(aircraft: str, sensor: str, t_s, east_m, north_m, sigma_m: float = 3.0) -> pd.DataFrame:
    """Reports at east/north metres from (41.3, 2.08), placed with pyproj's geodesic."""
    east_m, north_m = np.asarray(east_m, float), np.asarray(north_m, float)
    az = np.degrees(np.arctan2(east_m, north_m))
    lon, lat, _ = GEOD.fwd(np.full(len(az), 2.08), np.full(len(az), 41.3), az, np.hypot(east_m, north_m))
    return pd.DataFrame({"time": T0 + pd.to_timedelta(np.asarray(t_s, float), unit="s"),
                         "aircraft_id": aircraft, "sensor_id": sensor, "latitude": lat, "longitude": lon,
                         "sigma_major_m": sigma_m})


def test_two_targets_reporting_in_turn_switch_at_every_report():
    # A at the origin, B 2 km north, reporting in turn every 0.5 s under one address for 100 s: from the
    # third report on each lies 2 km from the last and next to the one before it: 199 judged, 199 switches
    t = np.arange(201) * 0.5
    north = np.where(np.arange(201) % 2 == 0, 0.0, 2000.0)
    found = mixed_identities(_reports("4CA1C3", "021:0/107", t, 10.0 * t, north))
    assert found[["aircraft_id", "sensor_id", "reports", "judged", "switches"]].values.tolist() == [
        ["4CA1C3", "021:0/107", 201, 199, 199]]
    assert found["share"].iloc[0] == 1.0
    assert found["separation_m"].iloc[0] == pytest.approx(np.hypot(2000.0, 5.0), rel=1e-5)  # 0.5 s at 10 m/s


def test_isolated_jumps_are_not_two_targets(monkeypatch):
    # 450 kt (231.5 m/s) every 4 s, 926 m between plots, 5 jumps of 3 km: the plot after a jump is 3.1 km
    # from it but 1,852 m from the one before it (over a quarter of 3.1 km): no switch at all. A parked
    # target (3 m noise) with 9 jumps of 500 m: each return lies ~4 m from the report before the jump,
    # 9 switches of 598 judged, under MIN_SWITCHES (10) and MIN_SHARE (0.1)
    import msdc.pipeline.model.mixed as mixed

    rng = np.random.default_rng(4)
    t = np.arange(600) * 4.0
    east = np.zeros(600)
    east[[50, 150, 250, 350, 450]] = 3000.0
    parked_east = rng.normal(0.0, 3.0, 600)
    parked_east[np.arange(1, 10) * 60] += 500.0
    frame = pd.concat([_reports("A", "048:25/201", t, east, 231.5 * t, sigma_m=100.0),
                       _reports("P", "021:0/107", t, parked_east, rng.normal(0.0, 3.0, 600))])
    assert mixed_identities(frame).empty
    monkeypatch.setattr(mixed, "MIN_SWITCHES", 1)
    monkeypatch.setattr(mixed, "MIN_SHARE", 0.0)
    found = mixed_identities(frame)
    assert found[["aircraft_id", "judged", "switches"]].values.tolist() == [["P", 598, 9]]


def test_what_is_not_judged_or_too_close_to_tell():
    rng = np.random.default_rng(2)
    t = np.arange(300.0)
    parts = [
        # a parked aircraft's noise (3 m): never far from the last report
        _reports("P", "010:0/107:mlat", t, rng.normal(0, 3, 300), rng.normal(0, 3, 300)),
        # a surface radar's split echoes of one aircraft, 35 m apart in turn: under MIN_SEPARATION_M
        _reports("S", "010:0/7:smr", t, np.zeros(300), np.where(np.arange(300) % 2 == 0, 0.0, 35.0)),
        # two targets 5 km apart in turn, but 61 s between reports: the aircraft may have moved
        _reports("G", "021:0/107", 61.0 * t, np.zeros(300), np.where(np.arange(300) % 2 == 0, 0.0, 5000.0)),
        # a radar whose plots' sigma is 500 m: 2 km apart is not over 6 combined sigmas (4.2 km)
        _reports("R", "048:25/201", 4.0 * t, np.zeros(300), np.where(np.arange(300) % 2 == 0, 0.0, 2000.0),
                 sigma_m=500.0),
    ]
    frame = pd.concat(parts, ignore_index=True)
    assert mixed_identities(frame).empty and mixed_warnings(frame) == []
    # two sensors' reports of one aircraft are never compared with each other
    both = pd.concat([_reports("X", "021:0/107", t, 8.0 * t, np.zeros(300)),
                      _reports("X", "010:0/107:mlat", t + 0.5, 8.0 * t + 4.0, np.full(300, 400.0))])
    assert mixed_identities(both).empty


def test_the_warning_names_aircraft_sensor_and_figures():
    t = np.arange(41) * 1.0
    north = np.where(np.arange(41) % 2 == 0, 0.0, 1000.0)
    frame = pd.concat([_reports("4CA1C3", "021:0/107", t, np.zeros(41), north),
                       _reports("UNKNOWN", "021:0/107", t, np.zeros(41), north).assign(aircraft_id=pd.NA)])
    (said,) = mixed_warnings(frame)
    assert said.startswith("1 aircraft's reports switch back and forth between two places: 4CA1C3 on "
                           "021:0/107 (39 of 39 reports, 1,000 m apart). Two targets may share the identity")


def test_short_distances_agree_with_the_geodesic():
    rng = np.random.default_rng(1)
    lat, lon = rng.uniform(-80.0, 80.0, 10_000), rng.uniform(-180.0, 180.0, 10_000)
    d = rng.uniform(1.0, 5000.0, 10_000)
    lon2, lat2, _ = GEOD.fwd(lon, lat, rng.uniform(0.0, 360.0, 10_000), d)
    from msdc.pipeline.model.mixed import short_distance_m

    np.testing.assert_allclose(short_distance_m(lat, lon, lat2, lon2), d, rtol=1e-6)
