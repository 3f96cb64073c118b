"""CAT010/CAT020 reports as measurements: the sensor file's reference points, positions from x/y and polar
coordinates checked with pyproj's geodesic (an independent method), covariances, kinds, sensor ids."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pandas as pd
import pytest
from pyproj import Geod

from msdc.pipeline.model.measurements import LeftOutWarning, build_measurements, local_measurement_rows
from msdc.pipeline.model.schema import MEASUREMENT_COLUMNS
from msdc.pipeline.model.sensors import (
    UnknownReferencePoint,
    radar_entries,
    read_sensors,
    reference_entries,
    reference_toml_snippet,
)

GEOD = Geod(ellps="WGS84")
REF = (45.0, 5.0)  # the reference point of the test's systems
# 7.5 m at 95 % of a circular Gaussian: 95 % lie within sqrt(-2 ln 0.05) sigma (Rayleigh), 2.4477
SMGCS_SIGMA_M = 7.5 / 2.447746830680816

SENSORS = f"""
[[sensor]]
name = "radar"
sac = 0
sic = 107
latitude = 44.0
longitude = 4.0
altitude_m = 100.0

[[sensor]]
name = "MLAT"
category = 10
kind = "mlat"
sac = 0
sic = 107
latitude = {REF[0]}
longitude = {REF[1]}
altitude_m = 0.0

[[sensor]]
name = "SMR"
category = 10
kind = "smr"
sac = 0
sic = 7
latitude = {REF[0]}
longitude = {REF[1]}
altitude_m = 0.0
sigma_m = 4.0

[[sensor]]
name = "WAM"
category = 20
sac = 25
sic = 10
latitude = {REF[0]}
longitude = {REF[1]}
altitude_m = 0.0
"""


@pytest.fixture
def sensors(tmp_path):
    path = tmp_path / "sensors.toml"
    path.write_text(SENSORS)
    return read_sensors(path)


def test_reference_points_beside_radars(sensors):
    assert sensors["kind"].tolist() == ["radar", "mlat", "smr", "mlat"]
    assert sensors["category"].tolist() == [48, 10, 10, 20]
    radar = radar_entries(sensors)
    assert radar["name"].tolist() == ["radar"] and radar["sigma_range_m"].tolist() == [70.0]
    points = reference_entries(sensors)
    assert points["name"].tolist() == ["MLAT", "SMR", "WAM"]
    # CAT010's default is the A-SMGCS requirement as a per-axis sigma; CAT020 has none
    assert points["sigma_m"].iloc[0] == pytest.approx(SMGCS_SIGMA_M, rel=1e-12)
    assert points["sigma_m"].iloc[1] == 4.0 and np.isnan(points["sigma_m"].iloc[2])
    assert "sigma_range_m" not in points


@pytest.mark.parametrize(("edit", "words"), [
    (lambda t: t.replace('kind = "smr"\n', ""), ["entry 3", "no kind", "'mlat' or 'smr'", "TYP"]),
    (lambda t: t.replace('category = 20\n', 'category = 20\nkind = "smr"\n'), ["entry 4", "'smr'", "'mlat'"]),
    (lambda t: t.replace("category = 20", "category = 62"), ["entry 4", "category = 62"]),
    (lambda t: t.replace("sigma_m = 4.0", "sigma_range_m = 4.0"), ["entry 3", "sigma_range_m", "sigma_m"]),
    (lambda t: t.replace("altitude_m = 100.0", "altitude_m = 100.0\nsigma_m = 3"), ["entry 1", "sigma_m"]),
    (lambda t: t.replace("sic = 7\n", "sic = 107\n").replace('kind = "smr"', 'kind = "mlat"'),
     ["CAT010 mlat SAC 0 SIC 107", "twice"]),
    (lambda t: t.replace(f"latitude = {REF[0]}\nlongitude = {REF[1]}", "latitude = 0\nlongitude = 0", 1),
     ["entry 2", "no multilateration reference point"]),
])
def test_bad_reference_entries_name_the_file_and_entry(tmp_path, edit, words):
    path = tmp_path / "s.toml"
    path.write_text(edit(SENSORS))
    with pytest.raises(ValueError) as info:
        read_sensors(path)
    for word in [str(path), *words]:
        assert word in str(info.value)


def test_the_snippet_for_a_missing_point_reads_back(tmp_path):
    text = reference_toml_snippet(10, "smr", 0, 9).replace("latitude = 0.0", "latitude = 1.0")
    path = tmp_path / "s.toml"
    path.write_text(text)
    entry = read_sensors(path).iloc[0]
    assert (entry["category"], entry["kind"], entry["sac"], entry["sic"]) == (10, "smr", 0, 9)


def cat010(rows: list[dict]) -> pd.DataFrame:
    """A decoded CAT010 frame with the columns the decoder gives (absent: NaN / <NA>)."""
    columns = {"sac": "Int32", "sic": "Int32", "message_type": "Int32", "typ": "Int32",
               "track_number": "Int32", "gbs": "Int8"}
    floats = ["time_of_day", "latitude", "longitude", "rho_m", "theta_deg", "x_m", "y_m", "ground_speed_kt",
              "track_angle_deg", "vx_ms", "vy_ms", "flight_level", "sigma_x_m", "sigma_y_m",
              "geometric_height_ft"]
    frame = pd.DataFrame(rows)
    out = {c: frame[c].astype(d) if c in frame else pd.array([pd.NA] * len(frame), dtype=d)
           for c, d in columns.items()}
    out |= {c: frame[c].astype(float) if c in frame else np.full(len(frame), np.nan) for c in floats}
    out |= {c: pd.Categorical(frame[c]) if c in frame else pd.Categorical([None] * len(frame))
            for c in ("address", "callsign", "mode3a")}
    out["day"] = np.zeros(len(frame), np.int64)
    out["timestamp"] = pd.Series(pd.NaT, index=range(len(frame)), dtype="datetime64[ns, UTC]")
    out["offset"] = np.arange(len(frame), dtype=np.int64) * 40
    return pd.DataFrame(out)


def geodesic_from_ref(meas: pd.DataFrame) -> tuple[np.ndarray, np.ndarray]:
    """Azimuth (deg) and distance (m) from the reference point to each row, by pyproj's geodesic."""
    n = len(meas)
    az, _, dist = GEOD.inv(np.full(n, REF[1]), np.full(n, REF[0]), meas["longitude"].to_numpy(float),
                           meas["latitude"].to_numpy(float))
    return np.asarray(az) % 360.0, np.asarray(dist)


def test_cat010_reports_placed_from_the_reference_point(sensors):
    frame = cat010([
        # MLAT 1000 m east (I010/042), its own sigmas (I010/500), velocity due west 10 m/s, no I010/200
        {"sac": 0, "sic": 107, "message_type": 1, "typ": 1, "time_of_day": 10.0, "x_m": 1000.0, "y_m": 0.0,
         "sigma_x_m": 2.5, "sigma_y_m": 5.0, "vx_ms": -10.0, "vy_ms": 0.0, "address": "4CA1B2", "gbs": 1},
        # SMR from I010/040 alone: 500 m at azimuth 180 (due south), no sigma: the entry's 4 m
        {"sac": 0, "sic": 7, "message_type": 1, "typ": 3, "time_of_day": 11.0, "rho_m": 500.0,
         "theta_deg": 180.0, "track_number": 12, "ground_speed_kt": 5.0, "track_angle_deg": 90.0, "gbs": 0},
        # MLAT 300 m north: no sigma: the CAT010 default
        {"sac": 0, "sic": 107, "message_type": 1, "typ": 0, "time_of_day": 12.0, "x_m": 0.0, "y_m": 300.0},
        # an ADS-B report in CAT010 (TYP 2), a status message, a TYP 4 report: no measurement
        {"sac": 0, "sic": 107, "message_type": 1, "typ": 2, "time_of_day": 13.0, "x_m": 1.0, "y_m": 1.0},
        {"sac": 0, "sic": 107, "message_type": 2, "time_of_day": 14.0},
        {"sac": 0, "sic": 107, "message_type": 1, "typ": 4, "time_of_day": 15.0, "x_m": 1.0, "y_m": 1.0},
    ])
    local = local_measurement_rows(frame, None, sensors)
    assert local.other_kinds == {2: 1, 4: 1} and local.unplaced.empty
    (rows,) = local.parts
    assert set(rows.columns) <= set(MEASUREMENT_COLUMNS)
    assert rows["sensor_id"].astype(str).tolist() == ["010:0/107:mlat", "010:0/7:smr", "010:0/107:mlat"]
    assert rows["sensor_kind"].astype(str).tolist() == ["mlat", "smr", "mlat"]
    az, dist = geodesic_from_ref(rows)
    # on the plane tangent at the point, 1000 m east and 500 m south: the geodesic agrees within a centimetre
    assert dist == pytest.approx([1000.0, 500.0, 300.0], abs=0.01)
    assert np.abs((az - [90.0, 180.0, 0.0] + 180.0) % 360.0 - 180.0).max() < 1e-4
    assert rows["position_item"].astype(str).tolist() == ["042", "040", "042"]
    assert rows["cov_ee_m2"].tolist() == pytest.approx([6.25, 16.0, SMGCS_SIGMA_M**2])
    assert rows["cov_nn_m2"].tolist() == pytest.approx([25.0, 16.0, SMGCS_SIGMA_M**2])
    assert rows["cov_en_m2"].tolist() == [0.0, 0.0, 0.0]
    # heading: the velocity vector's direction (due west), else I010/200's track angle; speed 10 m/s in kt
    assert rows["heading_deg"].tolist()[:2] == pytest.approx([270.0, 90.0])
    assert rows["ground_speed_kt"].tolist()[:2] == pytest.approx([10.0 * 3600 / 1852, 5.0])
    # GBS: on the ground for the MLAT report; a primary radar's GBS says nothing
    assert rows["on_ground"].iloc[0] == True and pd.isna(rows["on_ground"].iloc[1])  # noqa: E712


def test_cat010_without_its_reference_point_is_listed_not_placed(sensors):
    frame = cat010([{"sac": 0, "sic": 9, "message_type": 1, "typ": 1, "time_of_day": 1.0, "x_m": 5.0,
                     "y_m": 5.0} for _ in range(3)]
                   + [{"sac": 0, "sic": 9, "message_type": 1, "typ": 1, "time_of_day": 2.0,
                       "latitude": 45.5, "longitude": 5.5}])
    local = local_measurement_rows(frame, None, sensors)
    assert local.unplaced[["category", "kind", "sac", "sic", "records", "offset"]].values.tolist() == [
        [10, "mlat", 0, 9, 3, 0]]
    (rows,) = local.parts  # the WGS-84 report needs no point; its sigma is CAT010's default
    assert rows["latitude"].tolist() == [45.5] and rows["position_item"].astype(str).tolist() == ["041"]
    assert rows["cov_ee_m2"].tolist() == pytest.approx([SMGCS_SIGMA_M**2])
    with pytest.raises(UnknownReferencePoint, match="CAT010 multilateration SAC 0 SIC 9") as info:
        build_measurements(cat010=frame, sensors=sensors)
    assert 'kind = "mlat"' in str(info.value) and "sic = 9" in str(info.value)


def test_one_report_without_its_point_is_taken_for_damage(sensors):
    good = [{"sac": 0, "sic": 107, "message_type": 1, "typ": 1, "time_of_day": float(t), "x_m": 1.0,
             "y_m": 2.0, "address": "4CA1B2"} for t in range(10)]
    frame = cat010(good + [{"sac": 0, "sic": 99, "message_type": 1, "typ": 1, "time_of_day": 3.0,
                            "x_m": 1.0, "y_m": 2.0}])
    with warnings.catch_warnings(record=True) as said:
        warnings.simplefilter("always")
        meas = build_measurements(cat010=frame, sensors=sensors)
    assert len(meas) == 10
    texts = [str(w.message) for w in said if issubclass(w.category, LeftOutWarning)]
    assert len(texts) == 1 and "SAC/SIC 0/99" in texts[0] and "damaged" in texts[0]


def test_cat020_wgs84_cartesian_and_sigmas(sensors):
    frame = cat010([
        {"sac": 25, "sic": 10, "time_of_day": 1.0, "latitude": 45.01, "longitude": 5.02, "sigma_x_m": 20.0,
         "sigma_y_m": 10.0, "geometric_height_ft": 10000.0, "address": "4CA1B2"},
        {"sac": 25, "sic": 10, "time_of_day": 2.0, "x_m": -2000.0, "y_m": 0.0, "flight_level": 50.0},
    ]).drop(columns=["message_type", "typ"])
    (rows,) = local_measurement_rows(None, frame, sensors).parts
    assert rows["sensor_id"].astype(str).tolist() == ["020:25/10", "020:25/10"]
    assert rows["latitude"].iloc[0] == 45.01
    assert rows["height_source"].astype(str).tolist() == ["geometric", "flight_level"]
    assert rows["height_m"].tolist() == pytest.approx([3048.0, 1524.0])
    az, dist = geodesic_from_ref(rows.iloc[1:])
    # x/y on the tangent plane, raised to 1524 m along the reference point's up axis, which leans toward the
    # point by 2000 m / R from the vertical 2 km west of it: the footprint moves 1524 x 2000 / R = 0.478 m
    # back toward the point (R = 6378 km within 0.5 % at 45 deg: 3 mm of it)
    assert dist[0] == pytest.approx(2000.0 - 1524.0 * 2000.0 / 6.378e6, abs=0.01)
    assert az[0] == pytest.approx(270.0, abs=1e-3)
    # CAT020 has no default sigma: the second report's covariance is unknown
    assert rows["cov_ee_m2"].iloc[0] == 400.0 and rows["cov_nn_m2"].iloc[0] == 100.0
    assert np.isnan(rows["cov_ee_m2"].iloc[1])


def test_build_measurements_orders_and_validates(sensors):
    frame = cat010([{"sac": 0, "sic": 107, "message_type": 1, "typ": 1, "time_of_day": float(t),
                     "x_m": 10.0 * t, "y_m": 0.0, "address": "4CA1B2"} for t in range(5)])
    meas = build_measurements(None, None, sensors, cat010=frame)
    assert list(meas.columns) == MEASUREMENT_COLUMNS
    assert meas["aircraft_id"].astype(str).unique().tolist() == ["4CA1B2"]
    assert math.isclose(meas["sigma_major_m"].iloc[0], SMGCS_SIGMA_M)
