"""``msdc quality --reference track``: radar accuracy against the smoothed ADS-B-only IMM track. The
biases the simulator injects are still recovered (same fleet, seed and tolerances as test_accuracy)."""

from __future__ import annotations

import functools
from dataclasses import asdict
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from bias_fleet import FLEET, INJECTED, TOLERANCE, se_name

from fixtures.scenario import Scenario
from fixtures.simulate import simulate
from msdc.pipeline.cli import main
from msdc.pipeline.jobs import quality
from msdc.pipeline.jobs.common import OptionError
from msdc.pipeline.model.measurements import build_measurements
from msdc.pipeline.model.sensors import REQUIRED_COLUMNS as SENSOR_COLUMNS
from msdc.pipeline.quality.accuracy import estimate_biases, radar_errors

FIX = Path(__file__).resolve().parents[3] / "fixtures"


@functools.cache
def case(name: str) -> tuple[dict, pd.DataFrame, pd.DataFrame, pd.DataFrame]:
    injected = dict(INJECTED) if name == "all" else {}
    sc = Scenario(name="bias-test", aircraft=FLEET, **injected)
    sim = simulate(sc, seed=42)
    sensors = pd.DataFrame([asdict(sc.radar)])[SENSOR_COLUMNS]
    meas = build_measurements(sim.radar, sim.adsb, sensors)
    track_err = radar_errors(meas, sensors, reference="track")
    adsb_err = radar_errors(meas, sensors)
    return injected, track_err, estimate_biases(track_err), adsb_err


@pytest.mark.parametrize("name", ["none", "all"])
def test_biases_recovered_against_the_track(name):
    injected, errors, biases, adsb_errors = case(name)
    b = biases.iloc[0]
    # the same radar reports are matched as with the interpolated reference (same gap rule)
    assert len(errors) == len(adsb_errors) and b["n_reports"] > 4000 and b["aircraft"] == len(FLEET)
    for key, tol in TOLERANCE.items():
        expected = injected.get(key, 0.0)
        assert b[key] == pytest.approx(expected, abs=tol), (name, key)
        assert abs(b[key] - expected) < 4.0 * b[se_name(key)], (name, key)
    # the residuals are the simulator's radar noise (70 m, 0.08 deg), the reference adding almost nothing
    assert b["range_residual_rms_m"] == pytest.approx(70.0, rel=0.1)
    assert b["azimuth_residual_rms_deg"] == pytest.approx(0.08, rel=0.1)


def test_track_reference_is_closer_to_truth_than_interpolation():
    """Reference position error against the simulator's truth at each radar time: the smoothed track
    averages the ADS-B noise that linear interpolation passes through."""
    sc = Scenario(name="bias-test", aircraft=FLEET)
    sim = simulate(sc, seed=42)
    _, track_err, _, adsb_err = case("none")
    truth = {a.spec.callsign: a for a in sim.aircraft}
    from pyproj import Geod

    geod = Geod(ellps="WGS84")

    def ref_error(errors: pd.DataFrame) -> np.ndarray:
        out = []
        for cs, g in errors.groupby("callsign"):
            st = truth[cs].truth(g["time_of_day"].to_numpy(float))
            out.append(geod.inv(g["adsb_longitude"].to_numpy(), g["adsb_latitude"].to_numpy(),
                                st.longitude, st.latitude)[2])
        return np.concatenate(out)

    e_track, e_adsb = ref_error(track_err), ref_error(adsb_err)
    assert np.sqrt(np.nanmean(e_track**2)) < 0.7 * np.sqrt(np.nanmean(e_adsb**2))


def test_reference_option(tmp_path, capsys):
    with pytest.raises(OptionError, match="--reference 'smooth': must be adsb or track"):
        quality.validate(quality.QualityOptions(inputs=(str(FIX / "radar.ast"),),
                                                sensors=str(FIX / "sensors.toml"), all_aircraft=True,
                                                reference="smooth"))
    out = tmp_path / "q.json"
    assert main(["quality", str(FIX / "radar.ast"), str(FIX / "adsb.ast"), "--sensors",
                 str(FIX / "sensors.toml"), "--callsign", "MAS72", "--date", "2019-03-01",
                 "--reference", "track", "--json", str(out)]) == 0
    assert "Radar biases" in capsys.readouterr().out and out.exists()
