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

from pipeline.conflict.geometry import FT_PER_FL, M_PER_NM, VERTICAL_TOLERANCE_FT, vertical_limit_ft
from pipeline.conflict.pairs import _require, candidate_pairs, time_key
from pipeline.conflict.probability import conflict_probability, pc_margin, pc_upper_bound

PREDICTION_COLUMNS = ["aircraft_id", "time", "horizon_s", "east_m", "north_m", "var_east_m2",
                      "cov_east_north_m2", "var_north_m2", "flight_level"]
PC_COLUMNS = ["time", "aircraft_a", "aircraft_b", "horizon_s", "pc", "horizontal_nm", "vertical_ft"]
_CHUNK = 20_000


def pair_probabilities(predictions: pd.DataFrame, radius_nm: float = 5.0, vertical_ft: float = 1000.0,
                       method: str = "exact", eps: float = 1e-6, pairs: pd.DataFrame | None = None,
                       vertical_tolerance_ft: float = VERTICAL_TOLERANCE_FT) -> pd.DataFrame:
    """PC of every pair at every (time, horizon) whose PC can exceed eps.

    Pairs come from a k-d tree on the predicted positions, the radius widened by `pc_margin`; or, given
    `pairs` (`time, aircraft_a, aircraft_b`, e.g. from `pairs_per_step` on current positions with the
    closing distance as margin), exactly those pairs at every horizon.

    Horizontally, PC against a disc of radius_nm. Vertically, against vertical_ft less
    vertical_tolerance_ft (as `losses_of_separation`): with `sigma_alt_ft`, PC is multiplied by the
    probability that the altitude difference is below it (independent Gaussian errors); without it, a
    pair counts only when its predicted altitudes differ by less.
    """
    _require(predictions, PREDICTION_COLUMNS, "predictions")
    vertical_ft = vertical_limit_ft(vertical_ft, vertical_tolerance_ft)
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

    key_h, key_t = frame["horizon_s"].to_numpy(), time_key(frame["time"])
    starts = np.flatnonzero(np.r_[True, (key_h[1:] != key_h[:-1]) | (key_t[1:] != key_t[:-1])])
    bounds = np.r_[starts, len(frame)]
    pos = np.column_stack([east, north])
    if pairs is not None:
        ij = _given_pairs(frame, pairs)
    else:
        ij = _tree_pairs(pos, alt, lam, sig_alt, bounds, radius_m, vertical_ft, eps)
    if len(ij) == 0:
        return pd.DataFrame({c: pd.Series(dtype=_dtype(c, frame)) for c in PC_COLUMNS})
    i, j = ij[:, 0], ij[:, 1]
    rel = pos[i] - pos[j]
    rel_cov = cov[i] + cov[j]
    dz = alt[i] - alt[j]
    if sig_alt is None:
        vertical = (np.abs(dz) < vertical_ft).astype(float)
    else:
        s = np.hypot(sig_alt[i], sig_alt[j])
        vertical = ndtr((vertical_ft - dz) / s) - ndtr((-vertical_ft - dz) / s)
    # the exact PC only where the cheap bound leaves it possibly above eps
    todo = np.flatnonzero(pc_upper_bound(rel, rel_cov, radius_m) * vertical > eps)
    pc = np.zeros(len(ij))
    for s in range(0, len(todo), _CHUNK):
        k = todo[s:s + _CHUNK]
        pc[k] = conflict_probability(rel[k], rel_cov[k], radius_m, method) * vertical[k]
    ids = frame["aircraft_id"].to_numpy()
    out = pd.DataFrame({"time": frame["time"].array.take(i), "aircraft_a": ids[i], "aircraft_b": ids[j],
                        "horizon_s": key_h[i],
                        "pc": pc, "horizontal_nm": np.hypot(rel[:, 0], rel[:, 1]) / M_PER_NM,
                        "vertical_ft": np.abs(dz)})
    return out[out["pc"] > eps].reset_index(drop=True)


def _tree_pairs(pos, alt, lam, sig_alt, bounds, radius_m, vertical_ft, eps) -> np.ndarray:
    """Row pairs within one (horizon, time) group whose PC can exceed eps."""
    found = [np.empty((0, 2), dtype=np.int64)]
    for lo, hi in zip(bounds[:-1], bounds[1:], strict=True):
        if hi - lo < 2:
            continue
        # relative covariance: largest eigenvalue at most the sum of the two largest
        margin = float(pc_margin(np.sqrt(2.0 * lam[lo:hi].max()), eps))
        v_margin = 0.0 if sig_alt is None else float(pc_margin(np.sqrt(2.0) * sig_alt[lo:hi].max(), eps))
        found.append(candidate_pairs(pos[lo:hi], alt[lo:hi], radius_m + margin, vertical_ft + v_margin) + lo)
    return np.concatenate(found)


def _given_pairs(frame: pd.DataFrame, pairs: pd.DataFrame) -> np.ndarray:
    """Row pairs of the sorted predictions for each given (time, a, b) at every horizon both have."""
    _require(pairs, ["time", "aircraft_a", "aircraft_b"], "pairs")
    index = pd.MultiIndex.from_arrays([frame["horizon_s"], time_key(frame["time"]), frame["aircraft_id"]])
    when = time_key(pairs["time"])
    rows = []
    for h in frame["horizon_s"].unique():
        hh = np.full(len(pairs), h)
        ia = index.get_indexer(pd.MultiIndex.from_arrays([hh, when, pairs["aircraft_a"]]))
        ib = index.get_indexer(pd.MultiIndex.from_arrays([hh, when, pairs["aircraft_b"]]))
        ok = (ia >= 0) & (ib >= 0)
        rows.append(np.column_stack([np.minimum(ia, ib), np.maximum(ia, ib)])[ok])
    return np.concatenate(rows) if rows else np.empty((0, 2), dtype=np.int64)


def _dtype(column: str, frame: pd.DataFrame):
    ids = frame["aircraft_id"].dtype
    known = {"time": frame["time"].dtype, "aircraft_a": ids, "aircraft_b": ids,
             "horizon_s": frame["horizon_s"].dtype}
    return known.get(column, float)
