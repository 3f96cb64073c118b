"""Reference point offsets: a multilateration system shifted from ADS-B, a surface radar (no identity) shifted
from the multilateration, recovered from the reports; the corrected point checked with pyproj's geodesic."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest
from measurement_frames import meas_frame
from pyproj import Geod

from msdc.pipeline.quality.reference_offset import reference_offsets

GEOD = Geod(ellps="WGS84")
REF = (45.0, 5.0)
ENTRIES = pd.DataFrame({"name": ["MLAT", "SMR"], "sac": [0, 0], "sic": [107, 7], "latitude": [REF[0]] * 2,
                        "longitude": [REF[1]] * 2, "altitude_m": [0.0, 0.0], "category": [10, 10],
                        "kind": ["mlat", "smr"], "sigma_m": [3.0, 3.0], "sigma_range_m": np.nan,
                        "sigma_azimuth_deg": np.nan})


def at(east_m, north_m):
    east_m, north_m = np.broadcast_arrays(np.asarray(east_m, float), np.asarray(north_m, float))
    lon, lat, _ = GEOD.fwd(np.full(east_m.shape, REF[1]), np.full(east_m.shape, REF[0]),
                           np.degrees(np.arctan2(east_m, north_m)), np.hypot(east_m, north_m))
    return np.asarray(lat), np.asarray(lon)


def rows(kind, sensor, t, east, north, **cols):
    lat, lon = at(east, north)
    return pd.DataFrame({"time_of_day": t, "latitude": lat, "longitude": lon, "sensor_kind": kind,
                         "sensor_id": sensor, "ground_speed_kt": 10.0, **cols})


def test_offsets_of_multilateration_and_surface_radar():
    rng = np.random.default_rng(7)
    t = np.arange(200.0)
    north = 5.14 * t - 500.0  # 10 kt due north, on the surface
    parts = []
    for address, east in (("4CA1B2", 0.0), ("4CA1B3", 400.0)):
        parts.append(rows("adsb", "021:0/107", t, east, north, address=address))
        # the multilateration puts the aircraft 3 m east and 20 m south of ADS-B (2 m noise per axis)
        parts.append(rows("mlat", "010:0/107:mlat", t, east + 3.0 + rng.normal(0, 2, t.size),
                          north - 20.0 + rng.normal(0, 2, t.size), address=address))
        # the surface radar 100 m west and 50 m north of the multilateration, no identity (two aircraft:
        # each radar report pairs with both; only the true offset lines most of them up)
        parts.append(rows("smr", "010:0/7:smr", t, east + 3.0 - 100.0 + rng.normal(0, 3, t.size),
                          north - 20.0 + 50.0 + rng.normal(0, 3, t.size), track_number=5))
    meas = meas_frame(pd.concat(parts, ignore_index=True))
    table = reference_offsets(meas, ENTRIES).set_index("sensor_id")
    mlat, smr = table.loc["010:0/107:mlat"], table.loc["010:0/7:smr"]
    assert mlat["reference"] == "adsb" and smr["reference"] == "mlat"
    assert mlat["pairs"] == 400  # each report with the one ADS-B report of its aircraft at its time
    # medians of 400 draws of 2 m noise: within 0.3 m (2.5 standard errors of a median, 1.25 sqrt(pi/2)/20)
    assert (mlat["east_offset_m"], mlat["north_offset_m"]) == pytest.approx((3.0, -20.0), abs=0.3)
    assert (smr["east_offset_m"], smr["north_offset_m"]) == pytest.approx((-100.0, 50.0), abs=0.6)
    assert abs(smr["rotation_deg"]) < 0.1 and smr["scatter_m"] < 6.0
    # the corrected point: the entry's moved by minus the offset, 3 m west and 20 m north for the MLAT
    az, _, dist = GEOD.inv(REF[1], REF[0], mlat["corrected_longitude"], mlat["corrected_latitude"])
    e, n = -mlat["east_offset_m"], -mlat["north_offset_m"]
    assert dist == pytest.approx(math.hypot(e, n), abs=0.01)
    assert az == pytest.approx(math.degrees(math.atan2(e, n)), abs=0.01)


def test_too_few_pairs_measure_nothing():
    t = np.arange(10.0)
    meas = meas_frame(pd.concat([rows("adsb", "021:0/107", t, 0.0, 5.0 * t, address="4CA1B2"),
                                 rows("mlat", "010:0/107:mlat", t, 3.0, 5.0 * t, address="4CA1B2")],
                                ignore_index=True))
    row = reference_offsets(meas, ENTRIES).iloc[0]
    assert row["sensor_id"] == "010:0/107:mlat" and np.isnan(row["east_offset_m"])
    assert row["point_latitude"] == REF[0] and np.isnan(row["corrected_latitude"])
