"""Radar systematic and random errors against an independent reference: ``range_bias_m``,
``range_gain_ppm``, ``azimuth_bias_deg``, ``time_bias_s`` (the four biases of quality.accuracy.fit_biases,
fitted on the associated plots) and ``range_sd_m``, ``azimuth_sd_deg`` (the standard deviation of the fit's
residuals, bootstrap interval over aircraft). Reference rows marked ``self_reference`` are never used, and
a fit that its checks do not trust (a site offset, residuals far beyond the declared sigmas) gives no
figure: the requirement is withheld with the fit's reason and its estimate in words."""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np
import pandas as pd

from msdc.pipeline.evaluate.coverage import Sensor
from msdc.pipeline.evaluate.outcome import ErrorEvidence, FitEvidence, Outcome, withheld
from msdc.pipeline.evaluate.reference import (
    DEFAULT_REFERENCE_GAP_S,
    associated,
    checked_trajectories,
    parameter,
    rows_by_index,
)
from msdc.pipeline.evaluate.reference_gates import reference_at, self_referenced
from msdc.pipeline.evaluate.statistics import cluster_sums, clustered_interval
from msdc.pipeline.model.geodesy import M_PER_NM, east_north_m, wrap180
from msdc.pipeline.quality.accuracy import (
    MIN_BIAS_REPORTS,
    MIN_SE_AIRCRAFT,
    T975,
    aircraft_codes,
    fit_biases,
    fit_trust,
    site_geometry,
)

STEP_S = 1.0  # the reference velocity: its displacement from t - STEP_S to t + STEP_S
Z975 = 1.959964  # the normal 97.5 % point: the 95 % interval from MIN_SE_AIRCRAFT aircraft on
# requirement id -> (index in fit_biases' params, unit, what)
SIGNED = {"range_bias_m": (0, "m", "range bias"), "range_gain_ppm": (1, "ppm", "range gain"),
          "azimuth_bias_deg": (2, "deg", "azimuth bias"), "time_bias_s": (3, "s", "time bias")}
RANDOM = {"range_sd_m": (True, "m", "range"), "azimuth_sd_deg": (False, "deg", "azimuth")}
_CACHE: list = []  # the last (reports, reference, sensor, parameters key, fit): six ids share one fit


def bias_errors(reports: pd.DataFrame, reference: pd.DataFrame, parameters: Mapping | None,
                sensor: Sensor) -> pd.DataFrame:
    """Per associated plot with a slant range and azimuth, judged against an independent reference (never a
    self-reference row): its errors and the reference geometry seen from the sensor's declared site, in the
    columns ``fit_biases`` reads (``callsign`` is the reference aircraft, so the fit clusters by it). The
    reference is interpolated at the plot's time, its velocity differenced over +-STEP_S; the declared
    sigmas are the sensor's plot noise and the reference's ``sigma_m`` added in quadrature."""
    max_gap_s = float(parameter(parameters, "reference_max_gap_s", DEFAULT_REFERENCE_GAP_S))
    rep = associated(reports, reference, parameters)
    linked = rep["ref_index"].to_numpy() >= 0
    rep = rep[linked & ~self_referenced(rep, reference, parameters)].reset_index(drop=True)
    for col in ("rho_nm", "theta_deg"):
        if col not in rep.columns:
            raise ValueError(f"the radar reports lack the column {col}: biases need slant range and azimuth")
    t, idx = rep["t_s"].to_numpy(float), rep["ref_index"].to_numpy()
    state = {k: np.full(len(rep), np.nan) for k in ("lat", "lon", "h", "ve", "vn", "vu")}
    trajs = checked_trajectories(reference)[1]
    groups = rows_by_index(idx, len(trajs))
    for k, tr in enumerate(trajs):
        rows = groups[k]
        if not rows.size:
            continue
        lat, lon, h, _ = tr.at(t[rows], max_gap_s)
        lat0, lon0, h0, _ = tr.at(t[rows] - STEP_S, max_gap_s)
        lat1, lon1, h1, _ = tr.at(t[rows] + STEP_S, max_gap_s)
        de, dn = east_north_m(lat0, lon0, lat1, lon1)
        for key, v in (("lat", lat), ("lon", lon), ("h", h), ("ve", de / (2 * STEP_S)),
                       ("vn", dn / (2 * STEP_S)), ("vu", (h1 - h0) / (2 * STEP_S))):
            state[key][rows] = v
    known = np.all([np.isfinite(v) for v in state.values()], axis=0)
    rep, state = rep[known].reset_index(drop=True), {k: v[known] for k, v in state.items()}
    e, n, slant_m, ground_m, range_rate, tangential = site_geometry(
        state["lat"], state["lon"], state["h"], state["ve"], state["vn"], state["vu"],
        sensor.latitude, sensor.longitude, sensor.altitude_m)
    azimuth = np.degrees(np.arctan2(e, n)) % 360.0
    rho_m = pd.to_numeric(rep["rho_nm"], errors="coerce").to_numpy(float) * M_PER_NM
    theta = pd.to_numeric(rep["theta_deg"], errors="coerce").to_numpy(float)
    out = pd.DataFrame({
        "callsign": rep["ref_aircraft"].astype(str).to_numpy(object), "address": "", "t_s": rep["t_s"],
        "slant_range_m": slant_m, "ground_range_m": ground_m, "azimuth_deg": azimuth,
        "range_rate_ms": range_rate, "tangential_speed_ms": tangential,
        "range_error_m": rho_m - slant_m, "azimuth_error_deg": wrap180(theta - azimuth),
        "adsb_nacp": np.nan})
    if sensor.sigma_range_m is not None and sensor.sigma_azimuth_deg is not None:
        ref_m = np.nan_to_num(reference_at(rep, reference, "sigma_m", parameters))
        out["sigma_range_m"] = np.hypot(sensor.sigma_range_m, ref_m)
        out["sigma_azimuth_deg"] = np.hypot(sensor.sigma_azimuth_deg, np.degrees(ref_m / ground_m))
    return out


def _parameters_key(parameters: Mapping | None) -> tuple | None:
    """A hashable form of the parameters (None when a value cannot be hashed: no caching then)."""
    try:
        key = tuple(sorted((parameters or {}).items()))
        hash(key)
    except TypeError:
        return None
    return key


def sensor_fit(reports: pd.DataFrame, reference: pd.DataFrame, parameters: Mapping | None,
               sensor: Sensor) -> tuple[pd.DataFrame, dict]:
    """The errors (bias_errors) and their fit (fit_biases), computed once for the six ids of one sensor."""
    key = _parameters_key(parameters)
    if _CACHE and key is not None:
        c_rep, c_ref, c_sensor, c_key, errors, fit = _CACHE[0]
        if c_rep is reports and c_ref is reference and c_sensor is sensor and c_key == key:
            return errors, fit
    errors = bias_errors(reports, reference, parameters, sensor)
    fit = fit_biases(errors)
    _CACHE[:] = [(reports, reference, sensor, key, errors, fit)] if key is not None else []
    return errors, fit


def _refusal(fit: dict) -> str:
    """Why a fit gives no figure ("" when it gives one)."""
    if fit["n_reports"] < MIN_BIAS_REPORTS:
        return (f"{fit['n_reports']:,} plots judged against an independent reference: fewer than "
                f"{MIN_BIAS_REPORTS}, too few to fit the radar biases")
    if not np.all(np.isfinite(fit["params"])):
        return ("the plots do not separate range bias, gain, azimuth bias and time bias (too little "
                "diversity of range, azimuth rate or range rate)")
    if fit["aircraft"] < 2:
        return ("the fit rests on one aircraft: an error shared by all its plots (transponder delay, its "
                "reference's own offset) cannot be told from a radar bias")
    trusted, warning = fit_trust(fit)
    if trusted == "no":
        return f"the bias fit is not to be trusted: {warning}"
    return ""


def _fit_notes(fit: dict) -> tuple[str, ...]:
    """What the fit rests on: plots, aircraft, goodness of fit, site-offset check."""
    trusted, _ = fit_trust(fit)
    notes = [f"{fit['n_reports']:,} plots ({fit['n_rejected']:,} clipped as outliers, {fit['n_overhead']:,} "
             f"azimuths overhead left out) of {fit['aircraft']:,} aircraft"]
    chi2 = fit["chi2_per_dof"]
    notes.append(f"chi-square per degree of freedom {chi2:.2f} against the declared sigmas"
                 if np.isfinite(chi2)
                 else "goodness of fit unchecked: the sensor declares no sigma_range_m / sigma_azimuth_deg")
    if fit["offset_checked"]:
        east, north = fit["offset"]
        notes.append(f"site offset {np.hypot(east, north):.0f} m ({east:+.0f} m east, {north:+.0f} m "
                     f"north): not flagged")
    else:
        notes.append("site offset not checked: the plots do not surround the radar enough to separate it")
    if trusted == "unchecked":
        notes.append("fit trusted: unchecked (a check could not be made)")
    return tuple(notes)


def _interval_factor(n_aircraft: int) -> tuple[float, str]:
    """The multiple of the standard error giving a 95 % interval: the normal one from MIN_SE_AIRCRAFT
    aircraft, below that Student t with (aircraft - 1) degrees of freedom (the errors cluster by aircraft)."""
    if n_aircraft >= MIN_SE_AIRCRAFT:
        return Z975, "95 % interval: estimate +- 1.96 cluster-robust standard errors"
    q = T975[n_aircraft - 1]
    return q, (f"95 % interval: estimate +- {q:.2f} cluster-robust standard errors (Student t, "
               f"{n_aircraft - 1} degrees of freedom: {n_aircraft} aircraft)")


def _signed(requirement: str):
    """The requirement function of one fitted bias."""
    index, unit, what = SIGNED[requirement]

    def fn(reports: pd.DataFrame, reference: pd.DataFrame, parameters: Mapping | None = None,
           sensor: Sensor | None = None) -> Outcome:
        if sensor is None:
            raise ValueError(f"{requirement} needs the sensor under test (its site)")
        _, fit = sensor_fit(reports, reference, parameters, sensor)
        why = _refusal(fit)
        value, se = float(fit["params"][index]), float(fit["se"][index])
        if why:
            said = f"; the fit gave {what} {value:.4g} {unit} (SE {se:.2g})" if math.isfinite(value) else ""
            return withheld(requirement, why + said)
        q, said = _interval_factor(fit["aircraft"])
        return Outcome(requirement, value, value - q * se, value + q * se, int(fit["n_reports"]),
                       int(fit["n_reports"]), (f"standard error {se:.3g} {unit}", said, *_fit_notes(fit)),
                       evidence=FitEvidence(value, se, unit, int(fit["n_reports"]), int(fit["aircraft"])))
    fn.__name__ = requirement
    fn.__doc__ = f"``{requirement}``: the fitted radar {what} (docs/methods/evaluate.md)."
    return fn


def _random(requirement: str):
    """The requirement function of one random error: the SD of the fit's residuals over aircraft."""
    is_range, unit, what = RANDOM[requirement]

    def fn(reports: pd.DataFrame, reference: pd.DataFrame, parameters: Mapping | None = None,
           sensor: Sensor | None = None) -> Outcome:
        if sensor is None:
            raise ValueError(f"{requirement} needs the sensor under test (its site)")
        errors, fit = sensor_fit(reports, reference, parameters, sensor)
        why = _refusal(fit)
        if why:
            return withheld(requirement, why)
        n = fit["rows"].size
        part = slice(0, n) if is_range else slice(n, 2 * n)
        kept = fit["kept"][part]
        values = fit["residuals"][part][kept]
        clusters = aircraft_codes(errors.iloc[fit["rows"]])[kept]
        seed = int(parameter(parameters, "seed", 0))
        ci = clustered_interval(values, clusters, "sd", seed=seed)
        notes = (f"{what} residuals after removing the four fitted biases: {ci.n:,} plots of "
                 f"{ci.n_clusters:,} aircraft (outliers clipped by the fit left out); the reference's own "
                 "error is in them",
                 *((ci.reason,) if ci.reason else ()), *_fit_notes(fit)[1:])
        labels = aircraft_labels(errors.iloc[fit["rows"]])[kept]
        return Outcome(requirement, ci.value, ci.ci_low, ci.ci_high, ci.n, ci.n, notes,
                       evidence=ErrorEvidence("sd", seed, sums=cluster_sums(values, labels)))
    fn.__name__ = requirement
    fn.__doc__ = f"``{requirement}``: SD of the radar's {what} residuals (docs/methods/evaluate.md)."
    return fn


def aircraft_labels(errors: pd.DataFrame) -> np.ndarray:
    """Per row, its aircraft as text (call sign and address), the same in every window of a span (the fit's
    integer codes number the aircraft of one window)."""
    if not {"callsign", "address"} <= set(errors.columns):
        return np.full(len(errors), "all", dtype=object)
    return (errors["callsign"].astype(object).fillna("").astype(str).to_numpy(object) + "|"
            + errors["address"].astype(object).fillna("").astype(str).to_numpy(object))


BIAS_REQUIREMENTS = {**{rid: _signed(rid) for rid in SIGNED}, **{rid: _random(rid) for rid in RANDOM}}
