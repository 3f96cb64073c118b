"""The sensor file's optional coverage keys: read as declared, refused with the file, entry and value named,
and carried into the evaluation's Sensor so that ``pd`` says the coverage was declared."""

from __future__ import annotations

import math

import pytest

from msdc.pipeline.evaluate.coverage import coverage, sensor_from_entry
from msdc.pipeline.model.sensors import read_sensors

RADAR = """
[[sensor]]
name = "Hill"
sac = 20
sic = 1
latitude = 41.0
longitude = 2.0
altitude_m = 600
"""
SMR = """
[[sensor]]
name = "Ground"
category = 10
kind = "smr"
sac = 20
sic = 9
latitude = 41.3
longitude = 2.08
altitude_m = 30
"""
MLAT = SMR.replace('kind = "smr"', 'kind = "mlat"').replace("sic = 9", "sic = 8")


def read(tmp_path, text: str):
    path = tmp_path / "sensors.toml"
    path.write_text(text)
    return path, read_sensors(path)


def test_declared_limits_are_read_and_absent_ones_are_nan(tmp_path):
    text = RADAR + "max_range_nm = 200\nmax_elevation_deg = 40.5\n" + SMR + "max_range_nm = 3.5\n"
    _, table = read(tmp_path, text)
    radar, smr = table.iloc[0], table.iloc[1]
    assert (radar["max_range_nm"], radar["max_elevation_deg"]) == (200.0, 40.5)
    assert math.isnan(radar["min_range_nm"]) and math.isnan(radar["min_elevation_deg"])
    assert smr["max_range_nm"] == 3.5 and math.isnan(smr["max_elevation_deg"])


def test_all_four_limits_are_read(tmp_path):
    text = RADAR + "min_range_nm = 0.5\nmax_range_nm = 250\nmin_elevation_deg = -2\nmax_elevation_deg = 45\n"
    _, table = read(tmp_path, text)
    row = table.iloc[0]
    assert [row[k] for k in ("min_range_nm", "max_range_nm", "min_elevation_deg", "max_elevation_deg")] \
        == [0.5, 250.0, -2.0, 45.0]


@pytest.mark.parametrize(("extra", "words"), [
    ("max_range_nm = -5", ["max_range_nm", "-5", "outside 0.0..1000.0"]),
    ("max_range_nm = 1e6", ["max_range_nm", "outside"]),
    ("max_range_nm = nan", ["max_range_nm", "nan", "outside"]),
    ("max_range_nm = inf", ["max_range_nm", "inf", "outside"]),
    ("max_elevation_deg = 95", ["max_elevation_deg", "95", "outside -90.0..90.0"]),
    ("min_elevation_deg = -91", ["min_elevation_deg", "outside"]),
    ('max_range_nm = "200"', ["max_range_nm", "'200'", "integer or float"]),
    ("max_range_nm = true", ["max_range_nm = true should be"]),  # as TOML writes it
    ("min_range_nm = 50\nmax_range_nm = 50", ["'Hill'", "min_range_nm = 50", "not below max_range_nm = 50"]),
    ("min_elevation_deg = 10\nmax_elevation_deg = 5", ["min_elevation_deg = 10", "max_elevation_deg = 5"]),
    ("max_rang_nm = 200", ["unknown key 'max_rang_nm'", "did you mean max_range_nm"]),
    ("max_range_nm = 0", ["'Hill'", "max_range_nm = 0", "no position would be inside the coverage"]),
])
def test_bad_limits_are_refused_naming_file_entry_and_value(tmp_path, extra, words):
    path = tmp_path / "sensors.toml"
    path.write_text(RADAR + extra + "\n")
    with pytest.raises(ValueError) as info:
        read_sensors(path)
    message = str(info.value)
    for word in [str(path), "entry 1", *words]:
        assert word in message, (word, message)


def test_a_multilateration_entry_takes_no_coverage_limits(tmp_path):
    path = tmp_path / "sensors.toml"
    path.write_text(MLAT + "max_range_nm = 20\n")
    with pytest.raises(ValueError, match="max_range_nm does not apply to a multilateration entry"):
        read_sensors(path)


def test_the_evaluation_sensor_uses_the_declared_limits(tmp_path):
    _, table = read(tmp_path, RADAR + "max_range_nm = 200\nmax_elevation_deg = 40\n")
    sensor = sensor_from_entry(table.iloc[0])
    assert (sensor.name, sensor.latitude, sensor.altitude_m) == ("Hill", 41.0, 600.0)
    assert (sensor.max_range_nm, sensor.max_elevation_deg) == (200.0, 40.0)
    assert sensor.min_range_nm is None and sensor.min_elevation_deg is None
    # the plot noise the bias fit's goodness of fit is judged by: the file's
    _, noisy = read(tmp_path, RADAR + "sigma_range_m = 55.0\nsigma_azimuth_deg = 0.05\n")
    given = sensor_from_entry(noisy.iloc[0])
    assert (given.sigma_range_m, given.sigma_azimuth_deg) == (55.0, 0.05)
    # detections out to 120 NM and 30 deg: the declared limits stand, the absent minimums are none
    cov = coverage(sensor, [10.0, 120.0], [1.0, 30.0])
    assert (cov.max_range_nm, cov.max_elevation_deg, cov.min_range_nm, cov.min_elevation_deg) \
        == (200.0, 40.0, 0.0, -90.0)
    assert "declared: max_range_nm 200, max_elevation_deg 40" in cov.source
    assert "estimated" not in cov.source
    # without the keys, the maximums are the detections' largest
    _, plain = read(tmp_path, RADAR)
    cov = coverage(sensor_from_entry(plain.iloc[0]), [10.0, 120.0], [1.0, 30.0])
    assert (cov.max_range_nm, cov.max_elevation_deg) == (120.0, 30.0)
    assert "estimated from the sensor's own detections: max_range_nm 120, max_elevation_deg 30" in cov.source
