"""Prediction without measurements: an IMM state propagated to a look-ahead.

Each step is an IMM cycle with every likelihood 1 (the conflict paper's trajectory prediction): mixing,
mode-matched prediction, mode probabilities by the Markov chain (mu <- PI^T mu) and the mixture
covariance including the spread of the mode means.
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from .imm import NX, propagate, propagate_ends
from .plane import PlaneRun
from .tracker import ImmState


def predict(state: ImmState, horizon_s: float, *, step_s: float = 1.0) -> pd.DataFrame:
    """One row per step up to horizon_s: time, latitude, longitude, east_m/north_m (the track's plane),
    ve_mps/vn_mps, the position covariance cov_ee_m2/cov_en_m2/cov_nn_m2 (plane frame) and mode_<name>."""
    if not horizon_s > 0.0 or not step_s > 0.0:
        raise ValueError(f"horizon_s {horizon_s!r} and step_s {step_s!r} must be > 0")
    args = state.config.kernel_args()
    n = math.ceil(horizon_s / step_s - 1e-9)
    r = len(state.mu)
    mu_out = np.empty((n, r))
    x_out = np.empty((n, r, NX))
    P_out = np.empty((n, r, NX, NX))
    xc = np.empty((n, NX))
    Pc = np.empty((n, NX, NX))
    propagate(args["kinds"], args["omegas"], args["qs"], args["tpm_kind"], args["tpm_param"],
              args["tpm_param2"], np.asarray(state.mu, float), np.asarray(state.x, float),
              np.asarray(state.P, float), float(horizon_s), float(step_s), mu_out, x_out, P_out, xc, Pc)
    ahead = np.minimum(np.arange(1, n + 1) * step_s, horizon_s)
    lat, lon = state.plane.inverse(xc[:, 0], xc[:, 3])
    out = {"time": state.time + pd.to_timedelta(ahead, unit="s"), "ahead_s": ahead,
           "latitude": lat, "longitude": lon, "east_m": xc[:, 0], "north_m": xc[:, 3],
           "ve_mps": xc[:, 1], "vn_mps": xc[:, 4], "cov_ee_m2": Pc[:, 0, 0], "cov_en_m2": Pc[:, 0, 3],
           "cov_nn_m2": Pc[:, 3, 3]}
    for j, mode in enumerate(state.config.modes):
        out[f"mode_{mode.name}"] = mu_out[:, j]
    return pd.DataFrame(out)


def predict_ends(run: PlaneRun, rows: np.ndarray, horizon_s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Combined states (n, 6) and covariances (n, 6, 6) that ``predict`` ends at (its last row, default
    step) from the posterior after each run row ``rows[i]``, ``horizon_s[i]`` > 0 s ahead, all in one
    kernel call without a frame per prediction; sorted by row, then horizon, is the cheapest order."""
    rows = np.ascontiguousarray(rows, np.int64)
    horizon = np.ascontiguousarray(horizon_s, float)
    if rows.shape != horizon.shape:
        raise ValueError(f"rows {rows.shape} and horizon_s {horizon.shape} must have the same shape")
    if not (horizon > 0.0).all():
        raise ValueError("horizon_s must be > 0")
    args = run.config.kernel_args()
    xc = np.empty((len(rows), NX))
    Pc = np.empty((len(rows), NX, NX))
    propagate_ends(rows, horizon, args["kinds"], args["omegas"], args["qs"], args["tpm_kind"],
                   args["tpm_param"], args["tpm_param2"], run.mu, run.x, run.P, xc, Pc)
    return xc, Pc
