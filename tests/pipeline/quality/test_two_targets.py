"""The Quality sheet marks an aircraft whose reports from one sensor switch between two places (two targets
under one identity, pipeline.model.mixed): its row on that sensor and the sensor's pooled row, nothing else.
The two targets are made by hand: AXM123's ADS-B reports given MAS72's identity."""

from __future__ import annotations

from dataclasses import asdict

import pandas as pd
import pytest

from fixtures.scenario import default_scenario
from fixtures.simulate import simulate
from msdc.pipeline.model.measurements import build_measurements
from msdc.pipeline.model.sensors import REQUIRED_COLUMNS as SENSOR_COLUMNS
from msdc.pipeline.quality.tables import ALL, quality_tables


@pytest.fixture(scope="module")
def meas() -> pd.DataFrame:
    sc = default_scenario()
    sensors = pd.DataFrame([asdict(sc.radar)])[SENSOR_COLUMNS]
    sim = simulate(sc, seed=7)
    return build_measurements(sim.radar, sim.adsb, sensors)


def _marked(quality: pd.DataFrame) -> set[tuple[str, str]]:
    return {(r.callsign, r.sensor) for r in quality.itertuples() if r.two_targets}


def test_one_flight_per_identity_marks_nothing(meas):
    assert _marked(quality_tables(meas)["Quality"]) == set()


def test_a_readdressed_aircraft_is_marked_on_that_sensor_alone(meas):
    axm = (meas["aircraft_id"].astype(str) == "75008A") & (meas["sensor_kind"] == "adsb")
    mixed = meas.copy()
    for column, value in (("aircraft_id", "750312"), ("address", "750312"), ("callsign", "MAS72")):
        mixed[column] = mixed[column].astype(object).where(~axm, value).astype(meas[column].dtype)
    quality = quality_tables(mixed)["Quality"]
    assert _marked(quality) == {("MAS72", "adsb"), (ALL, "adsb")}  # the radar's MAS72 is one target
    assert "AXM123" in set(quality.loc[quality["sensor"] == "radar", "callsign"])


def test_pairs_found_before_are_used_as_given(meas):
    """The jobs pass the pairs they found (pipeline.jobs.common.marked_measurements): those mark, not a
    search of its own."""
    quality = quality_tables(meas, mixed=[("7503A0", "048:25/201")])["Quality"]
    assert _marked(quality) == {("MAS136", "radar"), (ALL, "radar")}
    assert _marked(quality_tables(meas, mixed=[("7503A0", "021:9/9")])["Quality"]) == set()  # another sensor
