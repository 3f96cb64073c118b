"""Per-job column selection: a job builds only the measurement columns it reads (pipeline.model.schema
schema_columns / validate(frame, columns)), the same values as in the whole frame."""

from __future__ import annotations

from pathlib import Path

import pandas as pd
import pytest

from pipeline.model.load import load_measurements
from pipeline.model.schema import MEASUREMENT_COLUMNS, SchemaError, column_names, validate
from pipeline.model.sensors import read_sensors

FIX = Path(__file__).resolve().parents[1] / "fixtures"
INPUTS = [FIX / "radar.ast", FIX / "adsb.ast"]


@pytest.fixture(scope="module")
def sensors() -> pd.DataFrame:
    return read_sensors(FIX / "sensors.toml")


def test_column_names_are_checked_and_in_schema_order():
    assert column_names(["longitude", "time", "latitude"]) == ["time", "latitude", "longitude"]
    assert column_names(None) == MEASUREMENT_COLUMNS
    with pytest.raises(SchemaError, match="'speed' is not a measurement column"):
        column_names(["time", "speed"])


def test_a_narrow_frame_is_validated_on_its_own_columns(sensors):
    columns = ["time", "sensor_kind", "aircraft_id", "latitude", "longitude"]
    _, narrow = load_measurements(INPUTS, sensors, columns=columns)
    assert list(narrow.columns) == columns
    assert validate(narrow, columns) is narrow
    with pytest.raises(SchemaError, match="'sensor_id' is missing"):  # not the whole model
        validate(narrow)
    with pytest.raises(SchemaError, match="'latitude' is missing"):
        validate(narrow.drop(columns="latitude"), columns)
    with pytest.raises(SchemaError, match="'longitude' has values missing or outside"):  # still checked
        validate(narrow.assign(longitude=200.0), columns)
    with pytest.raises(SchemaError, match="'sensor_kind'.*allowed: radar, adsb"):
        validate(narrow.assign(sensor_kind=pd.Series("lidar", index=narrow.index, dtype="string")
                               .astype("category")), columns)


def test_narrow_measurements_are_the_full_ones_columns(sensors):
    """The identity rule reads address, call sign and Mode 3/A, and sigma_major_m the covariance: asked
    for alone, they come out as in the whole frame, without their inputs."""
    _, full = load_measurements(INPUTS, sensors)
    for columns in (["time", "aircraft_id", "sigma_major_m"], ["sensor_id", "rho_nm", "nacp"]):
        _, narrow = load_measurements(INPUTS, sensors, columns=columns, chunk=40_000)  # many chunks joined
        pd.testing.assert_frame_equal(narrow, full[columns])
