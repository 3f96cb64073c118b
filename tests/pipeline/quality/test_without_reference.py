"""Quality without a reference: a radar-only aircraft gets what its own reports give, and an empty radar
accuracy or bias table always says why (no ADS-B, none left after the filters, no overlap in time, no
aircraft seen by both)."""

from __future__ import annotations

from dataclasses import asdict
from pathlib import Path

import pandas as pd
import pytest

import msdc.asterix as asterix
from fixtures.scenario import default_scenario
from fixtures.simulate import simulate
from msdc.pipeline.jobs.common import JobError
from msdc.pipeline.jobs.quality import QualityOptions, quality_job, text
from msdc.pipeline.model.measurements import build_measurements
from msdc.pipeline.model.sensors import REQUIRED_COLUMNS as SENSOR_COLUMNS
from msdc.pipeline.quality.quality_run import quality_run

# one worker runs the module: the measurements made once, not on each worker
pytestmark = pytest.mark.xdist_group("without_reference")

FIX = Path(__file__).resolve().parents[3] / "fixtures"
RADAR, SENSORS = str(FIX / "radar.ast"), str(FIX / "sensors.toml")
NEEDS = "the Radar accuracy and Radar biases sheets need a reference (ADS-B)"


def test_a_radar_only_aircraft_gets_its_own_figures():
    result = quality_job(QualityOptions(inputs=(RADAR,), sensors=SENSORS, callsign="MAS72"))
    q = result.quality.sheets["Quality"]
    row = q[(q["callsign"] == "MAS72") & (q["sensor"] == "radar")].iloc[0]
    decoded = asterix.read(RADAR).frames[48]
    assert row["reports"] == int((decoded["address"] == "750312").sum())  # the decoder's count of its plots
    assert row["intervals"] > 0 and row["interval_median_s"] > 0
    assert result.quality.sheets["Radar biases"].empty and result.quality.sheets["Radar accuracy"].empty
    (note,) = result.quality.notes
    assert "no ADS-B report" in note and NEEDS in note and note in result.parameters["notes"]
    assert result.quality.sheets["Radar accuracy"].attrs["note"] == note
    assert f"Radar biases:\n  none. {note}" in text(result)


def test_an_aircraft_no_sensor_saw_is_still_refused():
    with pytest.raises(JobError, match="ZZZ999 not seen by radar or ADS-B"):
        quality_job(QualityOptions(inputs=(RADAR,), sensors=SENSORS, callsign="ZZZ999"))


@pytest.fixture(scope="module")
def meas_and_sensors():
    sc = default_scenario()
    sim = simulate(sc, seed=11)
    sensors = pd.DataFrame([asdict(sc.radar)])[SENSOR_COLUMNS]
    return build_measurements(sim.radar, sim.adsb, sensors), sensors


def _reason(meas: pd.DataFrame, sensors: pd.DataFrame, **kw) -> str:
    result = quality_run(meas, sensors, **kw)
    assert result.sheets["Radar biases"].empty
    (note,) = result.notes
    assert result.sheets["Radar biases"].attrs["note"].startswith(note)
    return note


def test_radar_and_adsb_that_never_overlap_in_time(meas_and_sensors):
    meas, sensors = meas_and_sensors
    adsb = (meas["sensor_kind"] == "adsb").to_numpy()
    later = meas.copy()
    later.loc[adsb, "time"] = later.loc[adsb, "time"] + pd.Timedelta(hours=6)  # after the last radar plot
    assert "never overlap in time" in _reason(later, sensors)


def test_no_aircraft_seen_by_both(meas_and_sensors):
    meas, sensors = meas_and_sensors
    adsb = (meas["sensor_kind"] == "adsb").to_numpy()
    apart = meas.copy()
    apart["aircraft_id"] = apart["aircraft_id"].astype(object)
    apart.loc[adsb, "aircraft_id"] = "other:" + apart.loc[adsb, "aircraft_id"].astype(str)
    assert "no aircraft is seen by both radar and ADS-B" in _reason(apart, sensors)


def test_filters_that_left_no_adsb(meas_and_sensors):
    meas, sensors = meas_and_sensors
    radar_only = meas[(meas["sensor_kind"] == "radar").to_numpy()].reset_index(drop=True)
    note = _reason(meas, sensors, reference_meas=radar_only)
    assert "the ADS-B filters removed every ADS-B report" in note and NEEDS in note
