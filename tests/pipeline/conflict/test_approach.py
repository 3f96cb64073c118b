"""Predicted closest approach per alert, against geometry worked by hand (positions placed on the WGS-84
ellipsoid by pyproj's geodesic, an independent library)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from pyproj import Geod

from msdc.pipeline.conflict.approach import APPROACH_COLUMNS, closest_approach

GEOD = Geod(ellps="WGS84")
NM = 1852.0
T = pd.Timestamp("2026-01-01 12:00:00", tz="UTC")


def _offset(lat, lon, east_nm, north_nm):
    lon1, lat1, _ = GEOD.fwd(lon, lat, 90.0, east_nm * NM)
    lon2, lat2, _ = GEOD.fwd(lon1, lat1, 0.0, north_nm * NM)
    return lat2, lon2


def _tracks(rows):
    return pd.DataFrame([{"time": T, **r} for r in rows])


def _head_on(b_vertical_rate_fpm: float) -> pd.DataFrame:
    """A east at 360 kt at FL350 from (0, 0); B 20 NM east and 3 NM north at FL370, west at 360 kt."""
    lat_b, lon_b = _offset(0.0, 0.0, 20.0, 3.0)
    return _tracks([
        {"aircraft_id": "A", "latitude": 0.0, "longitude": 0.0, "flight_level": 350.0, "speed_kt": 360.0,
         "track_deg": 90.0, "vertical_rate_fpm": 0.0},
        {"aircraft_id": "B", "latitude": lat_b, "longitude": lon_b, "flight_level": 370.0, "speed_kt": 360.0,
         "track_deg": 270.0, "vertical_rate_fpm": b_vertical_rate_fpm}])


def _alert(a="A", b="B"):
    return pd.DataFrame({"aircraft_a": [a], "aircraft_b": [b], "horizon_s": [60.0], "start": [T]})


def test_head_on_offset_pair_closes_in_100_s_at_3_nm_and_1000_ft():
    # A flies east at 360 kt; B, 20 NM east and 3 NM north, flies west at 360 kt: closing at 0.2 NM/s,
    # closest after 20 / 0.2 = 100 s at 3 NM; B descends at 600 ft/min from FL370 to 36,000 ft by then
    tracks = _head_on(-600.0)
    out = closest_approach(_alert(), tracks)
    assert list(out.columns[-4:]) == APPROACH_COLUMNS
    row = out.iloc[0]
    assert row["time_to_cpa_s"] == pytest.approx(100.0, abs=0.2)
    assert row["cpa_time"] == T + pd.Timedelta(seconds=row["time_to_cpa_s"])
    assert row["cpa_horizontal_nm"] == pytest.approx(3.0, abs=0.005)
    assert row["cpa_vertical_ft"] == pytest.approx(1000.0, abs=2.0)
    # written the other way round (b before a), the same approach
    swapped = closest_approach(_alert("B", "A"), tracks).iloc[0]
    assert swapped["time_to_cpa_s"] == pytest.approx(row["time_to_cpa_s"], abs=1e-3)
    assert swapped["cpa_horizontal_nm"] == pytest.approx(row["cpa_horizontal_nm"], abs=1e-4)


def test_converging_at_50_north_and_a_diverging_pair():
    # A heads 045 and B, 10 NM north of A, heads 135, both at 400 kt: B - A velocity is 400 sqrt(2) kt
    # due south, so they meet after 10 / (400 sqrt(2) / 3600) = 63.6 s at 0 NM
    lat_b, lon_b = _offset(50.0, 5.0, 0.0, 10.0)
    tracks = _tracks([
        {"aircraft_id": "A", "latitude": 50.0, "longitude": 5.0, "flight_level": 300.0, "speed_kt": 400.0,
         "track_deg": 45.0, "vertical_rate_fpm": 0.0},
        {"aircraft_id": "B", "latitude": lat_b, "longitude": lon_b, "flight_level": 300.0, "speed_kt": 400.0,
         "track_deg": 135.0, "vertical_rate_fpm": 0.0},
        {"aircraft_id": "C", "latitude": lat_b, "longitude": lon_b, "flight_level": 310.0, "speed_kt": 400.0,
         "track_deg": 0.0, "vertical_rate_fpm": 0.0}])
    row = closest_approach(_alert(), tracks).iloc[0]
    assert row["time_to_cpa_s"] == pytest.approx(10.0 / (400.0 * np.sqrt(2) / 3600.0), abs=0.2)
    assert row["cpa_horizontal_nm"] == pytest.approx(0.0, abs=0.01)
    # C flies north away from A (A's northward speed 283 kt < 400 kt): closest now, 10 NM and 1000 ft
    row = closest_approach(_alert("A", "C"), tracks).iloc[0]
    assert row["time_to_cpa_s"] == 0.0 and row["cpa_time"] == T
    assert row["cpa_horizontal_nm"] == pytest.approx(10.0, abs=0.005)
    assert row["cpa_vertical_ft"] == pytest.approx(1000.0)
    # a pair without a track at the alert's start: NaN, not a guess
    row = closest_approach(_alert("A", "D"), tracks).iloc[0]
    assert np.isnan(row["time_to_cpa_s"]) and np.isnan(row["cpa_horizontal_nm"])


def test_times_in_another_zone_match_and_naive_ones_are_refused():
    # an alert time in Kuala Lumpur time is the same instant as the tracks' UTC time: the same approach
    tracks = _head_on(0.0)
    alert = _alert().assign(start=[T.tz_convert("Asia/Kuala_Lumpur")])
    row = closest_approach(alert, tracks).iloc[0]
    assert row["time_to_cpa_s"] == pytest.approx(100.0, abs=0.2)
    with pytest.raises(TypeError, match=r"alerts: column 'start' must hold time-zone-aware UTC datetimes"):
        closest_approach(_alert().assign(start=[T.tz_localize(None)]), tracks)
