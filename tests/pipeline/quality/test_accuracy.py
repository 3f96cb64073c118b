"""Radar accuracy against ADS-B: hand-worked error decomposition, statistics, bias recovery in simulation."""

from __future__ import annotations

import functools
from dataclasses import asdict

import numpy as np
import pandas as pd
import pytest
from bias_fleet import CASES, FLEET, INJECTED, TOLERANCE, se_name
from measurement_frames import meas_frame

from fixtures.scenario import Scenario
from fixtures.simulate import simulate
from msdc.pipeline.model.geodesy import (
    A_M,
    E2,
    M_PER_NM,
    ecef_to_geodetic,
    enu_to_ecef,
    geodetic_to_ecef,
    slant_range_azimuth,
)
from msdc.pipeline.model.measurements import build_measurements
from msdc.pipeline.model.sensors import REQUIRED_COLUMNS as SENSOR_COLUMNS
from msdc.pipeline.quality.accuracy import (
    BIAS_COLUMNS,
    ERROR_COLUMNS,
    LIMITATION_NOTE,
    _cluster_cov,
    error_stats,
    estimate_biases,
    nacp_bound_m,
    radar_errors,
)
from msdc.pipeline.report.quality_figures import radar_error_figure

SITE = {"name": "TEST", "sac": 25, "sic": 1, "latitude": 0.0, "longitude": 0.0, "altitude_m": 0.0}
SENSORS = pd.DataFrame([SITE])[SENSOR_COLUMNS]
FL = 100.0
H_M = FL * 100 * 0.3048
SPEED_MS = 200.0


def errors_of(radar: pd.DataFrame, adsb: pd.DataFrame, sensors: pd.DataFrame, **kw) -> pd.DataFrame:
    """radar_errors of hand-made radar and ADS-B reports (radar first, so radar_row is the radar row)."""
    return radar_errors(meas_frame(pd.concat([radar, adsb], ignore_index=True)), sensors, **kw)


# ---------------------------------------------------------------------------------------------------------
# Hand-worked geometry: radar at (0, 0), target 0.5 deg north of it


def _m_per_deg_lon(lat_deg: float) -> float:
    n = A_M / np.sqrt(1.0 - E2 * np.sin(np.radians(lat_deg)) ** 2)
    return (n + H_M) * np.cos(np.radians(lat_deg)) * np.pi / 180.0


def _m_per_deg_lat(lat_deg: float) -> float:
    s2 = np.sin(np.radians(lat_deg)) ** 2
    return (A_M * (1 - E2) / (1 - E2 * s2) ** 1.5 + H_M) * np.pi / 180.0


def adsb_track(t_s, track_deg: float, lat0: float = 0.5, lon0: float = 0.0, *, velocity=True) -> pd.DataFrame:
    """ADS-B reports of a target at FL 100 flying a constant track through (lat0, lon0) at t = 10 s."""
    t = np.asarray(t_s, dtype=float)
    d_m = SPEED_MS * (t - 10.0)
    lat = lat0 + d_m * np.cos(np.radians(track_deg)) / _m_per_deg_lat(lat0)
    lon = lon0 + d_m * np.sin(np.radians(track_deg)) / _m_per_deg_lon(lat0)
    return pd.DataFrame({
        "sensor": "adsb", "time_of_day": t, "timestamp": pd.NaT, "latitude": lat, "longitude": lon,
        "flight_level": FL, "ground_speed_kt": SPEED_MS * 3600 / 1852 if velocity else np.nan,
        "heading_deg": track_deg if velocity else np.nan, "callsign": "HAND1", "address": "ABCDEF",
        "sac": 0, "sic": 1, "nucp_nic": 8, "nacp": 9})


def radar_plot(t_s: float, lat: float, lon: float, d_east_m: float,
               d_north_m: float) -> tuple[pd.DataFrame, float]:
    """A radar report at t of the point (east, north) metres from (lat, lon, FL 100); also the true
    slant-range difference plot - target (m) computed directly from ECEF."""
    plot = enu_to_ecef(d_east_m, d_north_m, 0.0, lat, lon, H_M)
    p_lat, p_lon, p_h = ecef_to_geodetic(*plot)
    rho_nm, theta, _ = slant_range_azimuth(0.0, 0.0, 0.0, p_lat, p_lon, p_h)
    site = np.array(geodetic_to_ecef(0.0, 0.0, 0.0))
    target = np.array(geodetic_to_ecef(lat, lon, H_M))
    drange = np.linalg.norm(np.array(plot) - site) - np.linalg.norm(target - site)
    frame = pd.DataFrame({
        "sensor": ["radar"], "time_of_day": [t_s], "timestamp": [pd.NaT], "latitude": [float(p_lat)],
        "longitude": [float(p_lon)], "flight_level": [FL], "ground_speed_kt": [np.nan],
        "heading_deg": [np.nan],
        "callsign": ["HAND1"], "address": ["ABCDEF"], "sac": [25], "sic": [1], "rho_nm": [float(rho_nm)],
        "theta_deg": [float(theta)], "position_item": ["040"], "height_assumed": [False]})
    return frame, float(drange)


def one_error(track_deg: float, d_east_m: float, d_north_m: float, *, velocity=True, t_radar=10.0,
              lat0=0.5, lon0=0.0) -> tuple[pd.Series, float]:
    adsb = adsb_track(np.arange(0.0, 21.0), track_deg, lat0, lon0, velocity=velocity)
    row = adsb[adsb["time_of_day"] == t_radar].iloc[0]
    radar, drange = radar_plot(t_radar, row["latitude"], row["longitude"], d_east_m, d_north_m)
    errors = errors_of(radar, adsb, SENSORS)
    assert list(errors.columns) == ERROR_COLUMNS and len(errors) == 1
    return errors.iloc[0], drange


@pytest.mark.parametrize("velocity", [True, False])
def test_target_flying_east_radar_due_south(velocity):
    e, drange = one_error(90.0, 100.0, 50.0, velocity=velocity)
    assert e["along_track_m"] == pytest.approx(100.0, abs=0.2)  # along = east component
    assert e["cross_track_m"] == pytest.approx(-50.0, abs=0.2)  # north is left of an eastbound track
    assert e["horizontal_error_m"] == pytest.approx(np.hypot(100.0, 50.0), abs=0.2)
    assert e["range_error_m"] == pytest.approx(drange, abs=0.05)
    assert e["range_error_m"] == pytest.approx(50.0, abs=0.5)  # north is radial here
    ground = e["ground_range_m"]
    assert e["azimuth_error_deg"] == pytest.approx(np.degrees(np.arctan2(100.0, ground)), abs=2e-4)
    assert e["adsb_track_deg"] == pytest.approx(90.0, abs=0.05)
    assert e["range_rate_ms"] == pytest.approx(0.0, abs=0.5)
    assert e["tangential_speed_ms"] == pytest.approx(SPEED_MS, abs=0.5)  # clockwise = eastward at north
    assert e["azimuth_deg"] == pytest.approx(0.0, abs=1e-6)
    assert e["slant_range_m"] == pytest.approx(e["rho_nm"] * M_PER_NM - e["range_error_m"], abs=1e-6)


def test_target_flying_west_and_north():
    e, _ = one_error(270.0, 100.0, 50.0)
    assert e["along_track_m"] == pytest.approx(-100.0, abs=0.2)
    assert e["cross_track_m"] == pytest.approx(50.0, abs=0.2)  # north is right of a westbound track
    assert e["tangential_speed_ms"] == pytest.approx(-SPEED_MS, abs=0.5)
    e, _ = one_error(0.0, 30.0, -80.0)  # flying north, straight away from the radar
    assert e["along_track_m"] == pytest.approx(-80.0, abs=0.2)
    assert e["cross_track_m"] == pytest.approx(30.0, abs=0.2)
    assert e["range_rate_ms"] == pytest.approx(SPEED_MS, rel=0.01)
    assert e["tangential_speed_ms"] == pytest.approx(0.0, abs=0.5)
    assert e["range_error_m"] == pytest.approx(-80.0, abs=0.5)


def test_azimuth_error_wraps_at_north():
    e, _ = one_error(90.0, -100.0, 0.0)  # plot just west of north: theta near 360
    assert e["theta_deg"] > 359.0
    expected = -np.degrees(np.arctan2(100.0, e["ground_range_m"]))
    assert e["azimuth_error_deg"] == pytest.approx(expected, abs=2e-4)


def test_interpolation_between_reports_and_only_across_short_gaps():
    adsb = adsb_track(np.arange(0.0, 41.0, 2.0), 90.0)
    adsb = adsb[(adsb["time_of_day"] < 20) | (adsb["time_of_day"] > 31)]  # gap 18 -> 32 s
    truth = adsb_track([13.0, 25.0, 40.0], 90.0)
    radar = pd.concat([radar_plot(t, r["latitude"], r["longitude"], 0.0, 0.0)[0]
                       for t, (_, r) in zip([13.0, 25.0, 40.0], truth.iterrows(), strict=True)])
    radar = pd.concat([radar, radar_plot(60.0, 0.5, 0.0, 0.0, 0.0)[0]], ignore_index=True)  # after ADS-B ends
    errors = errors_of(radar, adsb, SENSORS)
    assert errors["time_of_day"].tolist() == [13.0, 40.0]  # 25 s falls in the 14 s gap; 60 s is beyond
    assert errors["radar_row"].tolist() == [0, 2]
    np.testing.assert_allclose(errors["horizontal_error_m"], 0.0, atol=0.05)
    np.testing.assert_allclose(errors["adsb_gap_s"], 2.0)
    assert errors_of(radar, adsb, SENSORS, max_gap_s=20.0)["time_of_day"].tolist() == [13.0, 25.0, 40.0]


def test_jumps_and_duplicates_in_adsb_do_not_disturb_the_reference():
    adsb = adsb_track(np.arange(0.0, 60.0), 45.0)
    adsb.loc[30, "latitude"] += 0.3  # a 33 km jump next to the radar time
    adsb = pd.concat([adsb, adsb.iloc[[10, 29]]]).sort_values("time_of_day", kind="stable")
    truth = adsb_track([30.5], 45.0).iloc[0]
    radar, _ = radar_plot(30.5, truth["latitude"], truth["longitude"], 0.0, 0.0)
    radar = pd.concat([radar, radar], ignore_index=True)  # a duplicated radar report counts once
    e = errors_of(radar, adsb, SENSORS)
    assert len(e) == 1
    assert e["horizontal_error_m"].iloc[0] < 1.0


def test_unknown_radar_and_no_common_aircraft():
    adsb = adsb_track(np.arange(0.0, 21.0), 90.0)
    radar, _ = radar_plot(10.0, 0.5, 0.0, 0.0, 0.0)
    with pytest.raises(ValueError, match="SAC 25 SIC 1"):
        errors_of(radar, adsb, SENSORS.assign(sic=2))
    empty = errors_of(radar.assign(address="000001", callsign="OTHER"), adsb, SENSORS)
    assert empty.empty and list(empty.columns) == ERROR_COLUMNS
    assert estimate_biases(empty).empty and error_stats(empty).empty


def test_error_stats_by_radar_and_aircraft():
    errors = pd.DataFrame({
        "radar": "R", "sac": 1, "sic": 2, "callsign": ["A", "A", "B", "B", "B"],
        "address": ["000001", "000001", "000002", "000002", "000002"],
        "range_error_m": [10.0, 30.0, -5.0, 5.0, 15.0], "azimuth_error_deg": [0.1, 0.3, 0.0, 0.0, 0.3],
        "along_track_m": 1.0, "cross_track_m": -2.0, "horizontal_error_m": [3.0, 4.0, 5.0, 6.0, 7.0]})
    stats = error_stats(errors).set_index("callsign")
    assert stats.loc["(all)", "n_reports"] == 5 and stats.loc["B", "n_reports"] == 3
    assert stats.loc["A", "range_error_mean_m"] == pytest.approx(20.0)
    assert stats.loc["A", "range_error_std_m"] == pytest.approx(np.std([10.0, 30.0], ddof=1))
    assert stats.loc["A", "range_error_rms_m"] == pytest.approx(np.sqrt((100 + 900) / 2))
    assert stats.loc["(all)", "azimuth_error_mean_deg"] == pytest.approx(0.14)
    assert stats.loc["B", "horizontal_error_rms_m"] == pytest.approx(np.sqrt((25 + 36 + 49) / 3))
    assert stats.loc["(all)", "cross_track_rms_m"] == pytest.approx(2.0)


def test_nacp_bounds_and_too_few_reports():
    assert [nacp_bound_m(n) for n in (8, 9, 10, 11)] == [92.6, 30.0, 10.0, 3.0]
    assert np.isnan(nacp_bound_m(0)) and np.isnan(nacp_bound_m(None))
    e, _ = one_error(90.0, 0.0, 0.0)
    b = estimate_biases(pd.DataFrame([e]))
    assert list(b.columns) == BIAS_COLUMNS
    assert np.isnan(b["range_bias_m"].iloc[0]) and "too few reports" in b["note"].iloc[0]
    assert b["adsb_nacp_95_m"].iloc[0] == 30.0 and "within 30 m" in b["note"].iloc[0]
    # the general limitation, then the height the reference had: this frame says no geometric height
    assert b.attrs["note"].startswith(LIMITATION_NOTE + " Reference height: the ADS-B pressure altitude")


# ---------------------------------------------------------------------------------------------------------
# Bias recovery in simulation: 12 aircraft for 40 min at random ranges, azimuths, turns and levels


def _simulated_errors(injected: dict) -> pd.DataFrame:
    sc = Scenario(name="bias-test", aircraft=FLEET, **injected)
    sim = simulate(sc, seed=42)
    sensors = pd.DataFrame([asdict(sc.radar)])[SENSOR_COLUMNS]
    return radar_errors(build_measurements(sim.radar, sim.adsb, sensors), sensors)


@functools.cache
def simulated_case(name: str) -> tuple[str, dict, pd.DataFrame, pd.DataFrame]:
    """Injected biases, radar errors and the bias estimates of one case (cached across tests)."""
    injected = {k: INJECTED[k] for k in CASES[name]}
    errors = _simulated_errors(injected)
    return name, injected, errors, estimate_biases(errors)


# the default run injects none and all four biases at once; the one-bias cases (no cross-talk between the
# four estimates) are the validation run's (pytest -m validation)
@pytest.fixture(params=[pytest.param(name, marks=() if name in ("none", "all") else pytest.mark.validation)
                        for name in CASES])
def bias_case(request):
    return simulated_case(request.param)


def test_biases_are_recovered(bias_case):
    name, injected, errors, biases = bias_case
    assert len(biases) == 1
    b = biases.iloc[0]
    assert b["n_reports"] > 4000 and b["aircraft"] == len(FLEET)
    assert b["n_rejected"] < 0.01 * 2 * b["n_reports"]
    for key, tol in TOLERANCE.items():
        expected = injected.get(key, 0.0)
        assert b[key] == pytest.approx(expected, abs=tol), (name, key)
        se = b[se_name(key)]
        assert 0 < se < tol / 2, (name, key)
        assert abs(b[key] - expected) < 4.0 * se, (name, key)
    assert b["range_residual_rms_m"] == pytest.approx(70.0, rel=0.1)  # the simulator's radar noise
    assert b["azimuth_residual_rms_deg"] == pytest.approx(0.08, rel=0.1)
    assert b["adsb_nacp_median"] == 9 and b["adsb_nacp_95_m"] == 30.0
    print(name, {k: round(float(b[k]), 4) for k in TOLERANCE})



def test_error_stats_and_figure_on_simulation(tmp_path):
    _, _, errors, biases = simulated_case("all")
    stats = error_stats(errors)
    overall = stats[stats["callsign"] == "(all)"].iloc[0]
    assert overall["n_reports"] == len(errors)
    assert overall["azimuth_error_mean_deg"] == pytest.approx(errors["azimuth_error_deg"].mean())
    assert len(stats) == len(FLEET) + 1
    assert errors["adsb_gap_s"].max() <= 10.0
    path = radar_error_figure(errors, tmp_path / "errors.png", biases)
    assert path.exists() and path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_cartesian_plots_are_evaluated_from_their_position():
    adsb = adsb_track(np.arange(0.0, 21.0), 90.0)
    row = adsb[adsb["time_of_day"] == 10.0].iloc[0]
    radar, _ = radar_plot(10.0, row["latitude"], row["longitude"], 100.0, 50.0)
    polar = errors_of(radar, adsb, SENSORS).iloc[0]
    cart = errors_of(radar.assign(rho_nm=np.nan, theta_deg=np.nan, position_item="042"), adsb,
                     SENSORS).iloc[0]
    for c in ("range_error_m", "along_track_m", "cross_track_m", "horizontal_error_m"):
        assert cart[c] == pytest.approx(polar[c], abs=0.01), c
    assert cart["azimuth_error_deg"] == pytest.approx(polar["azimuth_error_deg"], abs=1e-6)


# ---------------------------------------------------------------------------------------------------------
# Plots that decide a bias alone: nearly overhead (cone of silence), or a high-leverage azimuth row


def _unbiased_errors(n: int = 400, seed: int = 7) -> pd.DataFrame:
    """Errors of an unbiased radar (70 m, 0.08 deg noise) at 20-200 km ground range and FL330."""
    rng = np.random.default_rng(seed)
    ground = rng.uniform(20e3, 200e3, n)
    return pd.DataFrame({
        "radar": "R", "sac": 1, "sic": 2, "callsign": "A", "address": "000001", "adsb_nacp": 9,
        "ground_range_m": ground, "slant_range_m": np.hypot(ground, 10e3),
        "range_rate_ms": rng.uniform(-200.0, 200.0, n), "tangential_speed_ms": rng.uniform(-200.0, 200.0, n),
        "range_error_m": rng.normal(0.0, 70.0, n), "azimuth_error_deg": rng.normal(0.0, 0.08, n)})


def _with_plot(errors: pd.DataFrame, ground_m: float, height_m: float, tangential_ms: float,
               azimuth_error_deg: float) -> pd.DataFrame:
    row = errors.iloc[[0]].assign(ground_range_m=ground_m, slant_range_m=np.hypot(ground_m, height_m),
                                  range_rate_ms=0.0, tangential_speed_ms=tangential_ms, range_error_m=0.0,
                                  azimuth_error_deg=azimuth_error_deg)
    return pd.concat([errors, row], ignore_index=True)


def test_a_plot_overhead_does_not_decide_the_time_bias():
    # the audit's plot: 119 m from the site at 10.36 km, -157.75 m/s across the line of sight (azimuth
    # rate -75.9 deg/s), 3.34 deg azimuth error: alone it is fitted exactly by a 3.34/75.9 = 0.044 s time bias
    errors = _with_plot(_unbiased_errors(), 119.0, 10360.0, -157.75, 3.34)
    b = estimate_biases(errors).iloc[0]
    assert b["n_overhead"] == 1 and b["n_rejected"] == 0
    # the truth is no bias: the estimate is within 3 of its standard errors of it and the SE is that of
    # the 400 ordinary plots (0.08 deg / ~0.1 deg/s azimuth rates: centiseconds, not milliseconds)
    assert abs(b["time_bias_s"]) < 3 * b["time_bias_se_s"]
    assert b["time_bias_se_s"] > 0.01
    alone = estimate_biases(errors.iloc[:-1]).iloc[0]
    assert b["time_bias_s"] == pytest.approx(alone["time_bias_s"], abs=1e-3)


def test_a_high_leverage_plot_gets_an_honest_standard_error():
    # a low plot (16.7 deg elevation, outside the cone) 1 km from the site crossing at 200 m/s: 11.5 deg/s
    # of azimuth rate against ~0.1 deg/s for the rest, with 17 m across the line of sight (1 deg)
    errors = _with_plot(_unbiased_errors(), 1000.0, 300.0, 200.0, 1.0)
    b = estimate_biases(errors).iloc[0]
    assert b["n_overhead"] == 0
    # leaving that plot out moves the time bias by about the plot's own pull; the SE must be of that size
    # (the textbook SE of the weighted fit is a few times smaller: the plot looks like information)
    shift = abs(b["time_bias_s"] - estimate_biases(errors.iloc[:-1]).iloc[0]["time_bias_s"])
    assert shift > 0.05
    assert b["time_bias_se_s"] > 0.5 * shift


# ---------------------------------------------------------------------------------------------------------
# Errors shared by all plots of an aircraft (transponder reply delay: Mode S +-0.25 us = +-37 m of range;
# an aircraft's ADS-B offset): the standard errors count aircraft, not plots


def test_delete_one_aircraft_covariance_by_hand():
    # the mean of three aircraft's plots {1, 1}, {3, 3}, {5, 5}: 3; without each aircraft 4, 3, 2, so the
    # jackknife variance is (3 - 1) / 3 * (1 + 0 + 1) = 4/3
    x, y = np.ones((6, 1)), np.array([1.0, 1.0, 3.0, 3.0, 5.0, 5.0])
    cov = _cluster_cov(x, y, np.array([3.0]), np.array([7, 7, 2, 2, 9, 9]))
    assert cov[0, 0] == pytest.approx(4.0 / 3.0)
    assert np.isnan(_cluster_cov(x, y, np.array([3.0]), np.zeros(6))).all()  # one aircraft: no estimate


def _fleet_errors(rng: np.random.Generator, n_aircraft: int, sd_aircraft_m: float, n_plots: int = 60
                  ) -> pd.DataFrame:
    """Errors of a radar without bias (70 m, 0.08 deg plot noise), each aircraft at its own range band and
    velocity, every plot of an aircraft offset in range by the same N(0, sd_aircraft_m) draw."""
    parts = []
    for k in range(n_aircraft):
        ground = rng.uniform(20e3, 200e3) + rng.uniform(-10e3, 10e3, n_plots)
        parts.append(pd.DataFrame({
            "radar": "R", "sac": 1, "sic": 2, "callsign": f"A{k}", "address": f"{k:06X}", "adsb_nacp": 9,
            "ground_range_m": ground, "slant_range_m": np.hypot(ground, 10e3),
            "range_rate_ms": rng.uniform(-200.0, 200.0) + rng.normal(0.0, 20.0, n_plots),
            "tangential_speed_ms": rng.uniform(-200.0, 200.0) + rng.normal(0.0, 20.0, n_plots),
            "range_error_m": rng.normal(0.0, 70.0, n_plots) + rng.normal(0.0, sd_aircraft_m),
            "azimuth_error_deg": rng.normal(0.0, 0.08, n_plots)}))
    return pd.concat(parts, ignore_index=True)


def _coverage(n_aircraft: int, sd_aircraft_m: float, runs: int) -> dict[str, tuple[float, float]]:
    """Per bias: the share of runs whose +-1.96 SE interval holds the truth (0), and sd(estimate)/mean SE."""
    rows = [estimate_biases(_fleet_errors(np.random.default_rng(seed), n_aircraft, sd_aircraft_m)).iloc[0]
            for seed in range(runs)]
    b = pd.DataFrame(rows)
    return {key: (float(np.mean(np.abs(b[key]) < 1.96 * b[se_name(key)])),
                  float(b[key].std() / b[se_name(key)].mean())) for key in INJECTED}


def test_standard_errors_hold_under_errors_shared_by_an_aircraft():
    # 20 aircraft with a 40 m range offset each: the range bias's true sd is about 40 / sqrt(20) = 9 m,
    # against 70 / sqrt(1200) = 2 m if the 1200 plots were independent (the old SE: about 30 % coverage)
    result = _coverage(20, 40.0, 100)
    for key in ("range_bias_m", "range_gain_ppm", "azimuth_bias_deg", "time_bias_s"):
        covered, ratio = result[key]
        assert covered >= 0.88, (key, result[key])
        assert 0.75 < ratio < 1.25, (key, result[key])


def test_standard_errors_of_independent_plots_stay_right_or_conservative():
    result = _coverage(12, 0.0, 60)
    for key, (covered, ratio) in result.items():
        assert covered >= 0.88, (key, covered)
        assert 0.7 < ratio < 1.15, (key, ratio)


def test_few_aircraft_are_named_in_the_note():
    b = estimate_biases(_fleet_errors(np.random.default_rng(1), 8, 40.0)).iloc[0]
    assert "rest on 8 aircraft" in b["note"] and "+-2.36 standard errors" in b["note"]
    # also under the table (sheet and terminal): 2.36 is t(0.975) with 7 degrees of freedom
    assert estimate_biases(_fleet_errors(np.random.default_rng(1), 8, 40.0)).attrs["note"].endswith(
        "R: the standard errors rest on 8 aircraft (fewer than 10): for a 95 % interval use +-2.36 standard "
        "errors (Student t, 7 degrees of freedom).")
    one = estimate_biases(_unbiased_errors()).iloc[0]
    assert "rest on one aircraft" in one["note"]
    many = estimate_biases(_fleet_errors(np.random.default_rng(1), 10, 40.0)).iloc[0]
    assert "rest on" not in many["note"]


def test_adsb_latency_enters_the_time_bias_with_the_opposite_sign():
    # a perfect radar, ADS-B stamped 1 s after its time of applicability: radar time - ADS-B time = -1 s
    fleet = FLEET[:6]
    sc = Scenario(name="latency", aircraft=fleet, adsb_jump_fraction=0.0, adsb_low_quality_episodes=0)
    sim = simulate(sc, seed=11)
    adsb = sim.adsb.assign(time_of_day=sim.adsb["time_of_day"] + 1.0)
    sensors = pd.DataFrame([asdict(sc.radar)])[SENSOR_COLUMNS]
    b = estimate_biases(radar_errors(build_measurements(sim.radar, adsb, sensors), sensors)).iloc[0]
    assert b["time_bias_s"] == pytest.approx(-1.0, abs=max(0.05, 3 * b["time_bias_se_s"]))
    assert "radar time minus ADS-B time" in LIMITATION_NOTE and "opposite sign" in LIMITATION_NOTE


# ---------------------------------------------------------------------------------------------------------
# Bad arguments: a clear error naming the argument and the value, before any work


def _hand_meas() -> pd.DataFrame:
    adsb = adsb_track(np.arange(0.0, 21.0), 90.0)
    row = adsb[adsb["time_of_day"] == 10.0].iloc[0]
    radar, _ = radar_plot(10.0, row["latitude"], row["longitude"], 100.0, 50.0)
    return meas_frame(pd.concat([radar, adsb], ignore_index=True))


@pytest.mark.parametrize(("kw", "error", "words"), [
    ({"reference": "trak"}, ValueError, ["reference", "'trak'", "'adsb', 'track'"]),
    ({"reference": "TRACK"}, ValueError, ["reference", "'TRACK'"]),
    ({"reference": None}, ValueError, ["reference", "None"]),
    ({"max_gap_s": -1}, ValueError, ["max_gap_s", "-1", "> 0"]),
    ({"max_gap_s": 0.0}, ValueError, ["max_gap_s", "> 0"]),
    ({"max_gap_s": float("nan")}, ValueError, ["max_gap_s", "nan", "finite"]),
    ({"max_gap_s": "10"}, TypeError, ["max_gap_s", "'10'"]),
    ({"jump_kw": 3}, TypeError, ["jump_kw", "int"]),
])
def test_radar_errors_rejects_bad_arguments(kw, error, words):
    meas = _hand_meas()
    with pytest.raises(error) as exc:
        radar_errors(meas, SENSORS, **kw)
    assert all(w in str(exc.value) for w in words), str(exc.value)


def test_the_radar_name_is_one_categorical_value_not_a_copy_per_plot():
    """Each error row names its radar through the sensor table's categorical name (issue 27 item 8: a name
    copied per plot took 3.4 GB for a 1 MB name)."""
    long_name = "N" * 50_000
    errors = radar_errors(_hand_meas(), SENSORS.assign(name=long_name))
    assert len(errors) == 1 and isinstance(errors["radar"].dtype, pd.CategoricalDtype)
    assert errors["radar"].cat.categories.tolist() == [long_name]


def test_radar_errors_needs_the_sensor_table_for_radar_reports():
    meas = _hand_meas()
    with pytest.raises(TypeError, match="sensors: expected the sensor table .* got NoneType"):
        radar_errors(meas, None)
    with pytest.raises(TypeError, match="meas: expected a pandas DataFrame, got list"):
        radar_errors([], SENSORS)
    with pytest.raises(ValueError, match="meas: lacks the column.s. flight_level"):
        radar_errors(meas.drop(columns="flight_level"), SENSORS)
    adsb_only = meas[meas["sensor_kind"] == "adsb"]
    assert radar_errors(adsb_only, None).empty  # ADS-B alone needs no sensor table
    assert len(radar_errors(meas, SENSORS, max_gap_s=1)) == 1  # the reports are 1 s apart


def test_quality_run_rejects_bad_arguments_before_the_tables():
    from msdc.pipeline.quality.quality_run import quality_run

    meas = _hand_meas()
    with pytest.raises(ValueError, match="reference: 'TRACK' is not one of 'adsb', 'track'"):
        quality_run(meas, SENSORS, reference="TRACK")
    with pytest.raises(ValueError, match="gap_s -5: must be a finite number of seconds > 0"):
        quality_run(meas, SENSORS, gap_s=-5)
    with pytest.raises(TypeError, match="errors: expected a pandas DataFrame, got NoneType"):
        estimate_biases(None)
    with pytest.raises(ValueError, match="errors: lacks the column.s. radar"):
        error_stats(pd.DataFrame({"x": [1]}))


@pytest.mark.parametrize("span_s", [600.0, 12000.0, 40000.0])
def test_radar_error_time_labels_stand_apart(tmp_path, monkeypatch, span_s):
    """The time panels are half the figure wide: their clock labels ran into one string
    ('08:00:0008:30:00...', 2-3 px apart) over the fixtures' 08:00-11:20. On the drawn canvas, for 10 min,
    3 h 20 min and 11 h of reports, at least three labels show and each two stand at least half their
    height apart (half an em: a character's room)."""
    from msdc.pipeline.report import quality_figures

    n = 400
    errors = pd.DataFrame({"radar": "R", "sac": 1, "sic": 2, "callsign": [f"AC{i % 3}" for i in range(n)],
                           "address": None, "time_of_day": 28800.0 + np.linspace(0.0, span_s, n),
                           "slant_range_m": np.linspace(20e3, 300e3, n),
                           "range_error_m": np.sin(np.arange(n)), "azimuth_error_deg": 0.0})
    errors["ground_range_m"] = errors["slant_range_m"] * 0.99
    captured = {}
    monkeypatch.setattr(quality_figures, "save_png", lambda fig, path: captured.setdefault("fig", fig))
    quality_figures.radar_error_figure(errors, tmp_path / "e.png")
    fig = captured["fig"]
    fig.draw_without_rendering()
    renderer = fig.canvas.get_renderer()
    for ax in (fig.axes[1], fig.axes[3]):  # the two panels against time
        low, high = ax.get_xlim()
        labels = [t for t, x in zip(ax.get_xticklabels(), ax.get_xticks(), strict=True)
                  if t.get_visible() and t.get_text() and low <= x <= high]  # (the ones drawn)
        boxes = sorted((t.get_window_extent(renderer) for t in labels), key=lambda b: b.x0)
        assert len(boxes) >= 3, [t.get_text() for t in labels]
        assert all(b.x0 - a.x1 >= 0.5 * a.height for a, b in zip(boxes, boxes[1:], strict=False)), [
            t.get_text() for t in labels]
