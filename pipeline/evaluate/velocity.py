"""``velocity_correct``: a report's velocity (ground speed and heading, or vx/vy) against the reference's,
differenced from the reference positions around the report's time. As a position, a velocity is judged
against an independent reference only: a sensor's own smoothed track would judge its own velocity."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
import pandas as pd

from msdc.pipeline.evaluate.outcome import Outcome, share, withheld
from msdc.pipeline.evaluate.reference import (
    DEFAULT_REFERENCE_GAP_S,
    associated,
    checked_trajectories,
    parameter,
    reference_values,
    rows_by_index,
)
from msdc.pipeline.model.geodesy import M_PER_S_PER_KT, east_north_m

STEP_S = 1.0  # the reference velocity is the displacement from t - STEP_S to t + STEP_S over 2 STEP_S
SELF_LEFT_OUT = "independent reference only"  # opens the note of the reports left out on the own track


def report_velocity(rep: pd.DataFrame) -> tuple[np.ndarray, np.ndarray]:
    """East and north velocity (m/s) of each report: vx_ms/vy_ms where given, else from ground speed and
    heading (NaN where neither)."""
    def column(name: str) -> np.ndarray:
        return (pd.to_numeric(rep[name], errors="coerce").to_numpy(float) if name in rep
                else np.full(len(rep), np.nan))

    vx, vy = column("vx_ms"), column("vy_ms")
    if {"ground_speed_kt", "heading_deg"} <= set(rep.columns):
        gs = pd.to_numeric(rep["ground_speed_kt"], errors="coerce").to_numpy(float) * M_PER_S_PER_KT
        hdg = np.radians(pd.to_numeric(rep["heading_deg"], errors="coerce").to_numpy(float))
        missing = ~np.isfinite(vx) | ~np.isfinite(vy)
        vx = np.where(missing, gs * np.sin(hdg), vx)
        vy = np.where(missing, gs * np.cos(hdg), vy)
    return vx, vy


def reference_velocity(rep: pd.DataFrame, reference: pd.DataFrame,
                       parameters: Mapping | None) -> tuple[np.ndarray, np.ndarray]:
    """East and north velocity (m/s) of each associated report's reference aircraft at its time, from the
    reference positions STEP_S before and after (NaN where either is unknown)."""
    max_gap_s = float(parameter(parameters, "reference_max_gap_s", DEFAULT_REFERENCE_GAP_S))
    vx, vy = np.full(len(rep), np.nan), np.full(len(rep), np.nan)
    t, idx = rep["t_s"].to_numpy(float), rep["ref_index"].to_numpy()
    trajs = checked_trajectories(reference)[1]
    groups = rows_by_index(idx, len(trajs))
    for k, tr in enumerate(trajs):
        rows = groups[k]
        if not len(rows):
            continue
        lat0, lon0, _, _ = tr.at(t[rows] - STEP_S, max_gap_s)
        lat1, lon1, _, _ = tr.at(t[rows] + STEP_S, max_gap_s)
        de, dn = east_north_m(lat0, lon0, lat1, lon1)
        vx[rows], vy[rows] = de / (2 * STEP_S), dn / (2 * STEP_S)
    return vx, vy


def velocity_correct(reports: pd.DataFrame, reference: pd.DataFrame, parameters: Mapping | None = None,
                     sensor=None) -> Outcome:
    """Of the associated reports with a velocity where an independent reference's is known, those whose
    velocity vector lies within the larger of tolerance_mps and tolerance_fraction x the reference speed;
    the reports on the sensor's own track are left out and counted in a note."""
    tol_mps = parameter(parameters, "tolerance_mps", None)
    if tol_mps is None:
        raise ValueError("velocity_correct needs the parameter tolerance_mps")
    fraction = float(parameter(parameters, "tolerance_fraction", 0.0))
    rep = associated(reports, reference, parameters)
    rep = rep[rep["ref_index"].to_numpy() >= 0].reset_index(drop=True)
    own = np.zeros(len(rep), bool)
    if "self_reference" in reference.columns and len(rep):
        own = np.array([bool(x) if x is not None else False
                        for x in reference_values(rep, reference, "self_reference", parameters)], bool)
    vx, vy = report_velocity(rep)
    rx, ry = reference_velocity(rep, reference, parameters)
    known = np.isfinite(vx) & np.isfinite(vy)
    left = int((known & own).sum())
    note = (f"{SELF_LEFT_OUT}: {left:,} of {int(known.sum()):,} reports with a velocity were on "
            "the sensor's own track") if left else ""
    known &= ~own & np.isfinite(rx) & np.isfinite(ry)
    if not known.any():
        return withheld("velocity_correct", "no associated report has a velocity where an independent "
                        "reference's is known" + (f" ({note})" if note else ""))
    error = np.hypot(vx - rx, vy - ry)[known]
    tol = np.maximum(float(tol_mps), fraction * np.hypot(rx, ry)[known])
    return share("velocity_correct", int((error <= tol).sum()), int(known.sum()), (note,) if note else ())
