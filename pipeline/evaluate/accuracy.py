"""Position accuracy against an independent reference: per report the horizontal error to the reference
interpolated at its time, split along and across the reference's track; RMS, mean, percentiles and maximum
with a bootstrap interval over aircraft (statistics.clustered_interval). Reference rows marked
``self_reference`` (a sensor's own track) are never used: a sensor cannot judge its own position."""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np
import pandas as pd

from msdc.pipeline.evaluate.outcome import ErrorEvidence, Outcome, withheld
from msdc.pipeline.evaluate.reference import (
    DEFAULT_REFERENCE_GAP_S,
    associated,
    checked_trajectories,
    parameter,
    reference_values,
    rows_by_index,
)
from msdc.pipeline.evaluate.statistics import cluster_sums, clustered_interval
from msdc.pipeline.evaluate.timing import timing_note
from msdc.pipeline.evaluate.velocity import reference_velocity
from msdc.pipeline.model.geodesy import east_north_m

THRESHOLD_PARAMETER = "threshold_m"  # the requirement's tolerance, given by the scorecard to the timing note
MIN_SPEED_MPS = 5.0  # below this the reference has no track direction: along/across and latency not judged


def position_errors(reports: pd.DataFrame, reference: pd.DataFrame, parameters: Mapping | None = None
                    ) -> pd.DataFrame:
    """Per associated report judged against an independent reference: ``aircraft``, ``error_m`` (horizontal),
    ``along_m`` (positive ahead of the reference), ``across_m`` (positive to the right of its track),
    ``latency_s`` (-along / speed: positive when the report lags), the reference's ``speed_mps``, and the
    report's ``latitude`` and ``longitude``; NaN along/across/latency/speed where the reference moves slower
    than MIN_SPEED_MPS."""
    max_gap_s = float(parameter(parameters, "reference_max_gap_s", DEFAULT_REFERENCE_GAP_S))
    rep = associated(reports, reference, parameters)
    rep = rep[rep["ref_index"].to_numpy() >= 0].reset_index(drop=True)
    if "self_reference" in reference.columns and len(rep):
        own = reference_values(rep, reference, "self_reference", parameters)
        rep = rep[~np.array([bool(x) if x is not None else False for x in own])].reset_index(drop=True)
    t, idx = rep["t_s"].to_numpy(float), rep["ref_index"].to_numpy()
    de, dn = np.full(len(rep), np.nan), np.full(len(rep), np.nan)
    lat, lon = rep["latitude"].to_numpy(float), rep["longitude"].to_numpy(float)
    trajs = checked_trajectories(reference)[1]
    groups = rows_by_index(idx, len(trajs))
    for k, tr in enumerate(trajs):
        rows = groups[k]
        if len(rows):
            r_lat, r_lon, _, _ = tr.at(t[rows], max_gap_s)
            de[rows], dn[rows] = east_north_m(r_lat, r_lon, lat[rows], lon[rows])
    vx, vy = reference_velocity(rep, reference, parameters)
    speed = np.hypot(vx, vy)
    moving = speed >= MIN_SPEED_MPS
    safe = np.where(moving, speed, 1.0)
    ux, uy = np.where(moving, vx / safe, np.nan), np.where(moving, vy / safe, np.nan)
    along = de * ux + dn * uy
    across = de * uy - dn * ux  # to the right of the track is positive
    out = pd.DataFrame({"aircraft": rep["ref_aircraft"].to_numpy(object), "t_s": t,
                        "error_m": np.hypot(de, dn), "along_m": along, "across_m": across,
                        "latency_s": -along / safe, "speed_mps": np.where(moving, speed, np.nan),
                        "latitude": lat, "longitude": lon})
    return out[np.isfinite(out["error_m"].to_numpy())].reset_index(drop=True)


def _statistic(requirement: str, column: str, statistic: str):
    """The requirement function of one error statistic."""
    def fn(reports: pd.DataFrame, reference: pd.DataFrame, parameters: Mapping | None = None,
           sensor=None) -> Outcome:
        errors = position_errors(reports, reference, parameters)
        values = errors[column].to_numpy(float)
        keep = np.isfinite(values)
        if not keep.any():
            return withheld(requirement, "no report judged against an independent reference"
                            + ("" if column == "error_m" else " while the reference moves"))
        values, clusters = values[keep], errors["aircraft"].to_numpy(object)[keep].astype(str)
        seed = int(parameter(parameters, "seed", 0))
        if statistic == "max":
            return Outcome(requirement, float(values.max()), math.nan, math.nan, int(values.size),
                           int(values.size), ("a maximum has no interval",),
                           evidence=ErrorEvidence(statistic, seed, values=values.max(keepdims=True)))
        ci = clustered_interval(values, clusters, statistic, seed=seed)
        notes = error_notes(ci)
        if column == "error_m":  # a clock, not the sensor's scatter, can make the errors at speed
            threshold = parameter(parameters, THRESHOLD_PARAMETER, None)
            notes = (*notes, timing_note(errors, None if threshold is None else float(threshold),
                                         adsb=is_adsb(reports)))
        return Outcome(requirement, ci.value, ci.ci_low, ci.ci_high, ci.n, ci.n, tuple(n for n in notes if n),
                       evidence=error_evidence(values, clusters, statistic, seed))
    fn.__name__ = requirement
    fn.__doc__ = f"``{requirement}``: {statistic} of {column} over aircraft (docs/methods/evaluate.md)."
    return fn


def is_adsb(reports: pd.DataFrame) -> bool:
    """Whether the reports are an ADS-B sensor's (each aircraft then keeps its own clock)."""
    return ("sensor_kind" in reports.columns and len(reports) > 0
            and str(reports["sensor_kind"].iloc[0]) == "adsb")


def error_notes(ci) -> tuple[str, ...]:
    """An error statistic's notes: the aircraft it rests on, and why its interval is marked."""
    return (f"{ci.n_clusters} aircraft",) + ((ci.reason,) if ci.reason else ())


def error_evidence(values: np.ndarray, clusters: np.ndarray, statistic: str, seed: int) -> ErrorEvidence:
    """What the statistic rests on for pooling windows: a percentile keeps every value, the others the
    aircraft's sums."""
    if statistic in ("rms", "mean", "sd"):
        return ErrorEvidence(statistic, seed, sums=cluster_sums(values, clusters))
    return ErrorEvidence(statistic, seed, values=np.asarray(values, float),
                         clusters=pd.Categorical(np.asarray(clusters, str)))


ACCURACY_REQUIREMENTS = {
    "rms_m": _statistic("rms_m", "error_m", "rms"),
    "mean_m": _statistic("mean_m", "error_m", "mean"),
    "p95_m": _statistic("p95_m", "error_m", "p95"),
    "p99_m": _statistic("p99_m", "error_m", "p99"),
    "max_m": _statistic("max_m", "error_m", "max"),
    "along_rms_m": _statistic("along_rms_m", "along_m", "rms"),
    "across_rms_m": _statistic("across_rms_m", "across_m", "rms"),
    "latency_p95_s": _statistic("latency_p95_s", "latency_s", "p95"),
}


ERROR_RANGE_BAND_NM = 10.0


def errors_by_range(reports: pd.DataFrame, reference: pd.DataFrame, sensor, parameters: Mapping | None = None,
                    step_nm: float = ERROR_RANGE_BAND_NM) -> pd.DataFrame:
    """Horizontal position error against range from the sensor's site (on the ground, NM): per band of
    step_nm, the reports judged (position_errors: an independent reference only), the aircraft, and the
    RMS, 95th percentile and maximum error (m). Empty when no report is judged."""
    return error_bands(range_errors(reports, reference, sensor, parameters), step_nm)


def range_errors(reports: pd.DataFrame, reference: pd.DataFrame, sensor, parameters: Mapping | None = None
                 ) -> pd.DataFrame:
    """Per report judged (position_errors): its ground range from the sensor's site (``range_nm``), its
    ``aircraft`` (categorical) and ``error_m``: what error_bands counts, and what windows of a span pool."""
    errors = position_errors(reports, reference, parameters)
    if errors.empty:
        return pd.DataFrame({"range_nm": [], "aircraft": pd.Categorical([]), "error_m": []})
    rho, _ = sensor.polar(errors["latitude"].to_numpy(float), errors["longitude"].to_numpy(float),
                          np.zeros(len(errors)))
    return pd.DataFrame({"range_nm": rho, "aircraft": pd.Categorical(errors["aircraft"].astype(str)),
                         "error_m": errors["error_m"].to_numpy(float)})


def error_bands(errors: pd.DataFrame, step_nm: float = ERROR_RANGE_BAND_NM) -> pd.DataFrame:
    """The table of errors_by_range from range_errors' rows (of one window or several pooled)."""
    columns = ["low_nm", "high_nm", "reports", "aircraft", "rms_m", "p95_m", "max_m"]
    if errors.empty:
        return pd.DataFrame(columns=columns)
    band = np.floor(errors["range_nm"].to_numpy(float) / step_nm).astype(int)
    aircraft = errors["aircraft"].astype(str).to_numpy(object)
    rows = []
    for k in np.unique(band):
        e = errors["error_m"].to_numpy(float)[band == k]
        rows.append((k * step_nm, (k + 1) * step_nm, e.size, len(set(aircraft[band == k])),
                     float(np.sqrt(np.mean(e ** 2))), float(np.percentile(e, 95)), float(e.max())))
    return pd.DataFrame(rows, columns=columns)
