"""Surface radar tracks join the aircraft whose multilateration reports they follow (positions made with
pyproj's geodesic, not msdc's geodesy)."""

from __future__ import annotations

import numpy as np
import pandas as pd
from measurement_frames import meas_frame
from pyproj import Geod

from msdc.pipeline.model.primary_tracks import join_primary_tracks

GEOD = Geod(ellps="WGS84")
REF = (45.0, 5.0)


def at(east_m, north_m) -> tuple[np.ndarray, np.ndarray]:
    """Latitude and longitude of points east/north (m) of REF, by the geodesic from it."""
    east_m, north_m = np.broadcast_arrays(np.asarray(east_m, float), np.asarray(north_m, float))
    az = np.degrees(np.arctan2(east_m, north_m))
    lon, lat, _ = GEOD.fwd(np.full(east_m.shape, REF[1]), np.full(east_m.shape, REF[0]), az,
                           np.hypot(east_m, north_m))
    return np.asarray(lat), np.asarray(lon)


def rows(kind: str, sensor: str, t: np.ndarray, east: np.ndarray, north: np.ndarray, **cols) -> pd.DataFrame:
    lat, lon = at(east, north)
    return pd.DataFrame({"time_of_day": t, "latitude": lat, "longitude": lon, "sensor_kind": kind,
                         "sensor_id": sensor, **cols})


def test_tracks_join_the_aircraft_they_follow():
    t = np.arange(60.0)
    mlat = rows("mlat", "010:0/107:mlat", t, 10.0 * t, 0.0, address="4CA1B2", track_number=1)
    # SMR track 7 follows it 0.3 s late and 5 m north (the aircraft is then 3 m further east); track 8 is a
    # vehicle 500 m north of it; track 7 is used again 100 s after its first use, far from any aircraft
    follow = rows("smr", "010:0/7:smr", t + 0.3, 10.0 * t + 3.0, 5.0, track_number=7)
    vehicle = rows("smr", "010:0/7:smr", t + 0.5, 10.0 * t, 500.0, track_number=8)
    reused = rows("smr", "010:0/7:smr", t + 160.0, 10.0 * t, 0.0, track_number=7)
    meas = meas_frame(pd.concat([mlat, follow, vehicle, reused], ignore_index=True))
    assert meas["aircraft_id"].isna().sum() == 180  # identity leaves every primary report unidentified
    ident, joined = join_primary_tracks(meas)
    assert joined == 60
    kinds = meas["sensor_kind"].astype(str).to_numpy()
    number = meas["track_number"].to_numpy()
    first = (kinds == "smr") & (number == 7) & (meas["time"] < meas["time"].min() + pd.Timedelta(seconds=100))
    assert (ident[first] == "4CA1B2").all()
    assert ident[(kinds == "smr") & ~first].isna().all()
    assert (ident[kinds == "mlat"] == "4CA1B2").all()


def test_a_track_split_between_two_aircraft_joins_neither():
    """A track whose votes no aircraft holds the majority of stays unidentified (two aircraft 40 m apart,
    the track between them, nearer the first half the time and the second the other half)."""
    t = np.arange(40.0)
    one = rows("mlat", "010:0/107:mlat", t, 10.0 * t, 0.0, address="4CA1B2")
    two = rows("mlat", "010:0/107:mlat", t, 10.0 * t, 40.0, address="4CA1B3")
    between = rows("smr", "010:0/7:smr", t, 10.0 * t, np.where(t < 20, 15.0, 25.0), track_number=3)
    meas = meas_frame(pd.concat([one, two, between], ignore_index=True))
    ident, joined = join_primary_tracks(meas)
    assert joined == 0 and ident[(meas["sensor_kind"] == "smr").to_numpy()].isna().all()


def test_a_vehicle_crossing_an_aircraft_is_not_joined_to_it():
    """A vehicle drives north across the taxiway 0.3 s after each of the aircraft's multilateration
    reports: within 50 m of it for t = 17..23 s only (14.1 m per second from the crossing at t = 20 s), so
    those 7 reports all vote for the aircraft; but where the aircraft's reports bracket the vehicle's, 45 of
    them lie beyond 100 m of its interpolated position (|t - 20.3| > 7.07 s) against 7 within 50 m."""
    t = np.arange(60.0)
    mlat = rows("mlat", "010:0/107:mlat", t, 10.0 * t, 0.0, address="4CA1B2")
    vehicle = rows("smr", "010:0/7:smr", t + 0.3, 203.0, 10.0 * (t + 0.3 - 20.3), track_number=9)
    meas = meas_frame(pd.concat([mlat, vehicle], ignore_index=True))
    ident, joined = join_primary_tracks(meas)
    assert joined == 0 and ident[(meas["sensor_kind"] == "smr").to_numpy()].isna().all()


def test_two_echoes_of_one_aircraft_both_join_it():
    """A long aircraft's two echoes, tracked at once 5 m north and 30 m south of its multilateration
    position, agree with it (within 50 m): both tracks join."""
    t = np.arange(40.0)
    mlat = rows("mlat", "010:0/107:mlat", t, 8.0 * t, 0.0, address="4CA1B2")
    nose = rows("smr", "010:0/7:smr", t + 0.5, 8.0 * (t + 0.5), 5.0, track_number=3)
    tail = rows("smr", "010:0/7:smr", t + 0.5, 8.0 * (t + 0.5), -30.0, track_number=4)
    meas = meas_frame(pd.concat([mlat, nose, tail], ignore_index=True))
    ident, joined = join_primary_tracks(meas)
    assert joined == 80 and (ident == "4CA1B2").all()
