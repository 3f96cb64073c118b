"""Whether the radar bias fit can be trusted: goodness of fit against the declared sigmas, the site-offset
check and the reference height, on the simulator with a known site offset and a known geometric-minus-
pressure height difference."""

from __future__ import annotations

import functools
from dataclasses import asdict, replace
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from bias_fleet import FLEET, INJECTED

from fixtures.scenario import Scenario
from fixtures.simulate import simulate
from msdc.pipeline.model.measurements import build_measurements
from msdc.pipeline.model.sensors import REQUIRED_COLUMNS as SENSOR_COLUMNS
from msdc.pipeline.quality.accuracy import estimate_biases, fit_biases, radar_errors
from msdc.pipeline.quality.fit_checks import CHI2_TRUST_MAX, chi2_per_dof

M_PER_DEG_LAT = 110_574.0  # WGS-84 near the equator (the simulated site is at 2.7 deg N)
M_PER_DEG_LON = 111_320.0 * np.cos(np.radians(2.7456))


@functools.cache
def _simulation(geometric_minus_baro_ft: float = 0.0, biased: bool = True):
    sc = Scenario(name="fit-check", aircraft=FLEET, geometric_minus_baro_ft=geometric_minus_baro_ft,
                  **(INJECTED if biased else {}))
    return sc, simulate(sc, seed=42)


def _errors(east_m: float = 0.0, north_m: float = 0.0, *, geometric_minus_baro_ft: float = 0.0,
            biased: bool = True, keep_geometric: bool = True) -> pd.DataFrame:
    """Radar errors of the simulated radar whose declared site is east_m, north_m from the true one."""
    sc, sim = _simulation(geometric_minus_baro_ft, biased)
    site = replace(sc.radar, latitude=sc.radar.latitude + north_m / M_PER_DEG_LAT,
                   longitude=sc.radar.longitude + east_m / M_PER_DEG_LON)
    sensors = pd.DataFrame([asdict(site)])[SENSOR_COLUMNS]
    meas = build_measurements(sim.radar, sim.adsb, sensors)
    if not keep_geometric:
        meas = meas.drop(columns=["height_source"])
    return radar_errors(meas, sensors)


def _biases(*args, **kw) -> pd.DataFrame:
    return estimate_biases(_errors(*args, **kw))


def test_an_exact_site_is_never_flagged_and_the_fit_matches_the_declared_sigmas():
    errors = _errors()
    b, fit = estimate_biases(errors).iloc[0], fit_biases(errors)
    assert not fit["offset_flagged"] and b["fit_trusted"] == "yes"
    assert b["site_offset_m"] == pytest.approx(np.hypot(*fit["offset"]))
    assert b["site_offset_m"] < 4.0 * fit["offset_se"]
    assert "not flagged" in b["note"]
    # the simulator draws 70 m and 0.08 deg, as the sensor file declares, and ADS-B at 5 m per axis (NACp 9
    # declares 30 / 2.45 = 12 m): the normalised chi-square per degree of freedom is close to 1
    assert 0.85 < b["chi2_per_dof"] < 1.15
    assert "NOT TO BE TRUSTED" not in b["note"]


@pytest.mark.parametrize(("east_m", "north_m"), [(-1100.0, 0.0), (0.0, 1100.0)])
def test_a_site_1_1_km_off_is_flagged(east_m, north_m):
    # the declared site is (east_m, north_m) from the true one: the radar is (-east_m, -north_m) from it
    errors = _errors(east_m, north_m)
    biases, fit = estimate_biases(errors), fit_biases(errors)
    b = biases.iloc[0]
    assert fit["offset_flagged"] and b["fit_trusted"] == "no"
    assert fit["offset"] == pytest.approx([-east_m, -north_m], abs=60.0)
    assert b["site_offset_m"] == pytest.approx(1100.0, abs=60.0)
    assert b["note"].startswith("NOT TO BE TRUSTED") and "check the site in the sensor file" in b["note"]
    assert "the bias fit is not to be trusted" in biases.attrs["note"]


def test_the_quality_command_warns_of_a_fit_not_to_be_trusted(tmp_path):
    # the fixtures' radar declared 1.1 km west of where the simulator put it
    from fixtures.scenario import RadarSite
    from msdc.pipeline.jobs.quality import QualityOptions, quality_job

    fix = Path(__file__).resolve().parents[3] / "fixtures"
    site = RadarSite()
    sensors = tmp_path / "off.toml"
    sensors.write_text(f'[[sensor]]\nname = "off"\nsac = {site.sac}\nsic = {site.sic}\n'
                       f"latitude = {site.latitude}\nlongitude = {site.longitude - 1100.0 / M_PER_DEG_LON}\n"
                       f"altitude_m = {site.altitude_m}\n")
    result = quality_job(QualityOptions(inputs=(str(fix / "radar.ast"), str(fix / "adsb.ast")),
                                        sensors=str(sensors), all_aircraft=True))
    (said,) = [w for w in result.warnings if "not to be trusted" in w]
    assert said.startswith("off: the bias fit is not to be trusted") and said in result.parameters["notes"]


def test_geometric_height_is_the_reference_and_the_note_says_so():
    # ellipsoid height = pressure altitude + 1000 ft; no bias injected: with the geometric height the range
    # bias is nothing, with the pressure altitude the slant ranges are wrong by up to 1000 ft x sin(elevation)
    geo = _biases(geometric_minus_baro_ft=1000.0, biased=False)
    assert geo.iloc[0]["range_bias_m"] == pytest.approx(0.0, abs=15.0)
    assert "Reference height: the ADS-B geometric height (I021/140) at all" in geo.attrs["note"]
    baro = _biases(geometric_minus_baro_ft=1000.0, biased=False, keep_geometric=False)
    assert "Reference height: the ADS-B pressure altitude" in baro.attrs["note"]
    assert "no geometric height was used" in baro.attrs["note"]
    moved = abs(baro.iloc[0]["range_bias_m"] - geo.iloc[0]["range_bias_m"]) + abs(
        baro.iloc[0]["range_gain_ppm"] - geo.iloc[0]["range_gain_ppm"]) * 0.1
    assert moved > 15.0  # the pressure altitude moves the fit where geometric height is the truth


def _noisy_errors(noise_factor: float, n: int = 2000, seed: int = 3) -> pd.DataFrame:
    """Errors of an unbiased radar declared at 70 m and 0.08 deg whose noise is noise_factor times that,
    aircraft all round the radar at 20-200 km, FL330, NACp unknown (no reference sigma)."""
    rng = np.random.default_rng(seed)
    ground = rng.uniform(20e3, 200e3, n)
    return pd.DataFrame({
        "radar": "R", "sac": 1, "sic": 2, "callsign": [f"A{i % 20}" for i in range(n)], "address": "",
        "adsb_nacp": np.nan, "ground_range_m": ground, "slant_range_m": np.hypot(ground, 10e3),
        "azimuth_deg": rng.uniform(0.0, 360.0, n),
        "range_rate_ms": rng.uniform(-200.0, 200.0, n), "tangential_speed_ms": rng.uniform(-200.0, 200.0, n),
        "range_error_m": rng.normal(0.0, 70.0 * noise_factor, n),
        "azimuth_error_deg": rng.normal(0.0, 0.08 * noise_factor, n),
        "sigma_range_m": 70.0, "sigma_azimuth_deg": 0.08})


@pytest.mark.parametrize(("factor", "trusted"), [(1.0, "yes"), (3.0, "no")])
def test_residuals_against_the_declared_sigmas(factor, trusted):
    b = estimate_biases(_noisy_errors(factor)).iloc[0]
    assert b["chi2_per_dof"] == pytest.approx(factor**2, rel=0.1)  # E[chi2/dof] = (noise / declared)^2
    assert b["fit_trusted"] == trusted and "site offset" in b["note"] and "not flagged" in b["note"]
    assert ("times the declared sigmas" in b["note"]) == (factor**2 > CHI2_TRUST_MAX)


def test_chi2_per_dof_by_hand():
    assert chi2_per_dof(np.array([1.0, -2.0, 2.0, 0.0, 3.0]), np.array([1.0, 1.0, 2.0, 1.0, 3.0]), 2) == \
        pytest.approx((1 + 4 + 1 + 0 + 1) / 3)
    assert np.isnan(chi2_per_dof(np.ones(3), None, 2))
    assert np.isnan(chi2_per_dof(np.ones(2), np.ones(2), 2))
