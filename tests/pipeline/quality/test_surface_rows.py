"""Surface and airborne are separate pooled rows: a field monitor or a parked aircraft goes to "(all
surface)", never into the radar's "(all)" row. Expected rows are pooled by hand from the per-aircraft rows
and the simulator's reports."""

from __future__ import annotations

from dataclasses import asdict

import numpy as np
import pandas as pd
import pytest

from fixtures.scenario import default_scenario
from fixtures.simulate import simulate
from msdc.pipeline.model.measurements import build_measurements
from msdc.pipeline.model.sensors import REQUIRED_COLUMNS as SENSOR_COLUMNS
from msdc.pipeline.quality import surface
from msdc.pipeline.quality.accuracy import error_stats, radar_errors
from msdc.pipeline.quality.surface import SURFACE_ALL, on_surface
from msdc.pipeline.quality.tables import quality_tables


def test_the_threshold_is_the_conflicts_one():
    from msdc.pipeline.track.noise import SURFACE_SPEED_KT

    assert surface.SURFACE_SPEED_KT == SURFACE_SPEED_KT


def test_the_rule_per_report():
    reports = pd.DataFrame({
        "on_ground": pd.array([True, False, None, None, None, False], dtype="boolean"),
        "ground_speed_kt": [300.0, 10.0, 20.0, 120.0, np.nan, np.nan]})
    # said on the ground; said airborne (a helicopter at 10 kt); unsaid: slow, fast, no speed; said airborne
    assert on_surface(reports).tolist() == [True, False, True, False, False, False]
    assert on_surface(reports.drop(columns="on_ground")).tolist() == [False, True, True, False, False, False]


@pytest.fixture(scope="module")
def parked():
    """The default simulation with MAS72's radar plots marked on the ground, as a field monitor's or a
    parked aircraft's are (I048/230 STAT or RAB), and the callsign picked."""
    sc = default_scenario()
    sim = simulate(sc, seed=7)
    sensors = pd.DataFrame([asdict(sc.radar)])[SENSOR_COLUMNS]
    meas = build_measurements(sim.radar, sim.adsb, sensors)
    mas72 = (meas["callsign"].astype(str) == "MAS72") & (meas["sensor_kind"] == "radar")
    ids = meas.loc[mas72, "aircraft_id"].dropna().unique()
    radar = (meas["sensor_kind"] == "radar").to_numpy(bool)
    ground = meas["aircraft_id"].isin(ids).fillna(False).to_numpy(bool) & radar
    meas = meas.assign(on_ground=pd.array(np.where(ground, True, False), dtype="boolean"))
    return meas, sensors


def test_quality_pools_surface_and_airborne_apart(parked):
    meas, _ = parked
    q = quality_tables(meas)["Quality"]
    radar = q[q["sensor"] == "radar"]
    per_aircraft = radar[~radar["callsign"].isin(["(all)", SURFACE_ALL])]
    surface = per_aircraft[per_aircraft["on_surface"]]
    airborne = per_aircraft[~per_aircraft["on_surface"]]
    assert surface["callsign"].tolist() == ["MAS72"] and len(airborne) == 4
    for label, rows in (("(all)", airborne), (SURFACE_ALL, surface)):
        pooled = radar[radar["callsign"] == label].iloc[0]
        assert bool(pooled["on_surface"]) == (label == SURFACE_ALL)
        for column in ("reports", "duplicates_removed", "reports_after_dedup", "intervals", "gaps"):
            assert pooled[column] == rows[column].sum(), (label, column)
        assert pooled["interval_max_s"] == rows["interval_max_s"].max()
        assert pooled["first_tod"] == rows["first_tod"].min()
    # ADS-B says nothing of the ground (on_ground False, the simulator's GBS): its rows stay airborne
    adsb = q[q["sensor"] == "adsb"]
    assert not (adsb["callsign"] == SURFACE_ALL).any() and not adsb["on_surface"].any()


def test_accuracy_pools_surface_and_airborne_apart(parked):
    meas, sensors = parked
    errors = radar_errors(meas, sensors)
    stats = error_stats(errors)
    mas72 = errors["callsign"].astype(str) == "MAS72"
    for label, rows in (("(all)", errors[~mas72]), (SURFACE_ALL, errors[mas72])):
        pooled = stats[stats["callsign"] == label].iloc[0]
        assert pooled["n_reports"] == len(rows)
        assert pooled["range_error_mean_m"] == pytest.approx(rows["range_error_m"].mean())
        rms_m = np.sqrt(np.mean(rows["horizontal_error_m"] ** 2))
        assert pooled["horizontal_error_rms_m"] == pytest.approx(rms_m)
