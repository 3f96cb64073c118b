"""PC time series for every close pair of predicted positions, per prediction time and horizon.

predictions: `aircraft_id, time, horizon_s, east_m, north_m, var_east_m2, cov_east_north_m2,
var_north_m2, flight_level`, optionally `sigma_alt_ft`: the position each aircraft is predicted to have
`horizon_s` after `time`, in one local east-north plane, with its covariance.

Output (the `pc` schema of `pipeline.conflict.events`): `time, aircraft_a, aircraft_b, horizon_s, pc,
horizontal_nm, vertical_ft` (the predicted mean distances). Every pair left out has PC <= eps.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
from scipy.special import ndtr

from pipeline.conflict.geometry import FT_PER_FL, M_PER_NM
from pipeline.conflict.pairs import _require, candidate_pairs
from pipeline.conflict.probability import conflict_probability, pc_margin

PREDICTION_COLUMNS = ["aircraft_id", "time", "horizon_s", "east_m", "north_m", "var_east_m2",
                      "cov_east_north_m2", "var_north_m2", "flight_level"]
PC_COLUMNS = ["time", "aircraft_a", "aircraft_b", "horizon_s", "pc", "horizontal_nm", "vertical_ft"]
_CHUNK = 20_000


def pair_probabilities(predictions: pd.DataFrame, radius_nm: float = 5.0, vertical_ft: float = 1000.0,
                       method: str = "exact", eps: float = 1e-6) -> pd.DataFrame:
    """PC of every pair at every (time, horizon) whose PC can exceed eps.

    Horizontally, PC against a disc of radius_nm. Vertically, with `sigma_alt_ft`, PC is multiplied by
    the probability that the altitude difference is below vertical_ft (independent Gaussian errors);
    without it, a pair counts only when its predicted altitudes differ by less than vertical_ft.
    """
    _require(predictions, PREDICTION_COLUMNS, "predictions")
    frame = predictions.sort_values(["horizon_s", "time", "aircraft_id"], kind="stable")
    east, north = frame["east_m"].to_numpy(float), frame["north_m"].to_numpy(float)
    cov = np.empty((len(frame), 2, 2))
    cov[:, 0, 0] = frame["var_east_m2"].to_numpy(float)
    cov[:, 0, 1] = cov[:, 1, 0] = frame["cov_east_north_m2"].to_numpy(float)
    cov[:, 1, 1] = frame["var_north_m2"].to_numpy(float)
    alt = frame["flight_level"].to_numpy(float) * FT_PER_FL
    sig_alt = frame["sigma_alt_ft"].to_numpy(float) if "sigma_alt_ft" in frame.columns else None
    lam = 0.5 * (cov[:, 0, 0] + cov[:, 1, 1]) + np.hypot(0.5 * (cov[:, 0, 0] - cov[:, 1, 1]), cov[:, 0, 1])
    radius_m = radius_nm * M_PER_NM

    key_h, key_t = frame["horizon_s"].to_numpy(), frame["time"].to_numpy()
    starts = np.flatnonzero(np.r_[True, (key_h[1:] != key_h[:-1]) | (key_t[1:] != key_t[:-1])])
    bounds = np.r_[starts, len(frame)]
    pos = np.column_stack([east, north])
    found = []
    for lo, hi in zip(bounds[:-1], bounds[1:], strict=True):
        if hi - lo < 2:
            continue
        # relative covariance: largest eigenvalue at most the sum of the two largest
        margin = float(pc_margin(np.sqrt(2.0 * lam[lo:hi].max()), eps))
        v_margin = 0.0 if sig_alt is None else float(pc_margin(np.sqrt(2.0) * sig_alt[lo:hi].max(), eps))
        pairs = candidate_pairs(pos[lo:hi], alt[lo:hi], radius_m + margin, vertical_ft + v_margin)
        if len(pairs):
            found.append(pairs + lo)
    if not found:
        return pd.DataFrame({c: pd.Series(dtype=_dtype(c, frame)) for c in PC_COLUMNS})
    ij = np.concatenate(found)
    i, j = ij[:, 0], ij[:, 1]
    rel = pos[i] - pos[j]
    rel_cov = cov[i] + cov[j]
    pc = np.concatenate([conflict_probability(rel[s:s + _CHUNK], rel_cov[s:s + _CHUNK], radius_m, method)
                         for s in range(0, len(ij), _CHUNK)])
    dz = alt[i] - alt[j]
    if sig_alt is None:
        pc = np.where(np.abs(dz) < vertical_ft, pc, 0.0)
    else:
        s = np.hypot(sig_alt[i], sig_alt[j])
        pc = pc * (ndtr((vertical_ft - dz) / s) - ndtr((-vertical_ft - dz) / s))
    ids = frame["aircraft_id"].to_numpy()
    out = pd.DataFrame({"time": key_t[i], "aircraft_a": ids[i], "aircraft_b": ids[j], "horizon_s": key_h[i],
                        "pc": pc, "horizontal_nm": np.hypot(rel[:, 0], rel[:, 1]) / M_PER_NM,
                        "vertical_ft": np.abs(dz)})
    return out[out["pc"] > eps].reset_index(drop=True)


def _dtype(column: str, frame: pd.DataFrame):
    ids = frame["aircraft_id"].dtype
    known = {"time": frame["time"].dtype, "aircraft_a": ids, "aircraft_b": ids,
             "horizon_s": frame["horizon_s"].dtype}
    return known.get(column, float)
