"""PC time series for every close pair of predicted positions, per prediction time and horizon.

predictions: `aircraft_id, time, horizon_s, east_m, north_m, var_east_m2, cov_east_north_m2,
var_north_m2, flight_level`, optionally `sigma_alt_ft`: the position each aircraft is predicted to have
`horizon_s` after `time`, in one local east-north plane, with its covariance.

Output (the `pc` schema of `pipeline.conflict.events`): `time, aircraft_a, aircraft_b, horizon_s, pc,
horizontal_nm, vertical_ft` (the predicted mean distances). Every pair left out has PC <= eps.

Memory: the predictions are not copied; only their row order by (horizon, time, aircraft) is kept, the
pairs are searched in chunks of whole (horizon, time) groups of about `chunk_rows` rows, and the exact PC
of the pairs the bound leaves is computed as they come, in the batches of `_CHUNK` pairs one pass over
all of them would make (the quadrature's panels depend on the batch), so what is held beyond the
predictions grows with the chunk and the pairs kept, not with the rows.
"""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np
import pandas as pd
from scipy.special import ndtr

from msdc.pipeline.conflict.geometry import FT_PER_FL, M_PER_NM, VERTICAL_TOLERANCE_FT, vertical_limit_ft
from msdc.pipeline.conflict.pairs import _require, time_key
from msdc.pipeline.conflict.probability import conflict_probability, pc_margin, pc_upper_bound
from msdc.pipeline.conflict.sweep import grouped_box_pairs
from msdc.pipeline.model.arguments import finite_number

PREDICTION_COLUMNS = ["aircraft_id", "time", "horizon_s", "east_m", "north_m", "var_east_m2",
                      "cov_east_north_m2", "var_north_m2", "flight_level"]
PC_COLUMNS = ["time", "aircraft_a", "aircraft_b", "horizon_s", "pc", "horizontal_nm", "vertical_ft"]
CHUNK_ROWS = 1 << 18  # prediction rows searched for pairs at once (whole (horizon, time) groups)
_CHUNK = 20_000  # pairs whose exact PC is computed at once
_SLACK = 1e-6  # the sweep's box is this much wider (relatively) than the exact test that follows


def pair_probabilities(predictions: pd.DataFrame, radius_nm: float = 5.0, vertical_ft: float = 1000.0,
                       method: str = "exact", eps: float = 1e-6, pairs: pd.DataFrame | None = None,
                       vertical_tolerance_ft: float = VERTICAL_TOLERANCE_FT,
                       chunk_rows: int = CHUNK_ROWS) -> pd.DataFrame:
    """PC of every pair at every (time, horizon) whose PC can exceed eps.

    Pairs come from a sort and sweep of the predicted positions, the radius widened by `pc_margin`; or, given
    `pairs` (`time, aircraft_a, aircraft_b`, e.g. from `pairs_per_step` on current positions with the
    closing distance as margin), exactly those pairs at every horizon.

    Horizontally, PC against a disc of radius_nm. Vertically, against vertical_ft less
    vertical_tolerance_ft (as `losses_of_separation`): with `sigma_alt_ft`, PC is multiplied by the
    probability that the altitude difference is below it (independent Gaussian errors); without it, a
    pair counts only when its predicted altitudes differ by less. chunk_rows bounds the rows searched
    at once (memory only: the result does not depend on it).
    """
    _require(predictions, PREDICTION_COLUMNS, "predictions")
    finite_number("radius_nm", radius_nm, "NM")
    vertical_ft = vertical_limit_ft(vertical_ft, vertical_tolerance_ft)
    radius_m = radius_nm * M_PER_NM
    cols = _Columns(predictions)
    keys = predictions[["horizon_s", "time", "aircraft_id"]].reset_index(drop=True)
    ordered = keys.sort_values(["horizon_s", "time", "aircraft_id"], kind="stable")
    order = ordered.index.to_numpy()
    if pairs is not None:
        given = _given_pairs(ordered, pairs)
        step = max(int(chunk_rows), 1)
        found: Iterator[np.ndarray] = (given[s:s + step] for s in range(0, len(given), step))
    else:
        key_h, key_t = ordered["horizon_s"].to_numpy(), time_key(ordered["time"])
        bounds = np.r_[np.flatnonzero(np.r_[True, (key_h[1:] != key_h[:-1]) | (key_t[1:] != key_t[:-1])]),
                       len(order)]
        found = _near_pairs(cols, order, bounds, radius_m, vertical_ft, eps, max(int(chunk_rows), 1))
        del key_h, key_t
    del keys, ordered

    any_pair = False
    pending: list[tuple] = []  # pairs the bound leaves, their exact PC not yet computed
    kept: list[tuple] = []
    seq = 0
    for ij in found:
        if not len(ij):
            continue
        any_pair = True
        a, b = order[ij[:, 0]], order[ij[:, 1]]
        rel, rel_cov, dz, vertical = cols.relative(a, b, vertical_ft)
        ok = pc_upper_bound(rel, rel_cov, radius_m) * vertical > eps
        number = np.arange(seq, seq + len(ij))
        seq += len(ij)
        if 0.0 > eps:  # a pair the bound rules out has PC 0, kept only below a negative eps
            kept.append((number[~ok], a[~ok], b[~ok], np.zeros((~ok).sum()), rel[~ok], dz[~ok]))
        pending.append((number[ok], a[ok], b[ok], rel[ok], rel_cov[ok], dz[ok], vertical[ok]))
        if sum(len(p[0]) for p in pending) >= _CHUNK:
            pending = _exact_batches(pending, False, radius_m, method, eps, kept)
    if pending:
        _exact_batches(pending, True, radius_m, method, eps, kept)
    if not any_pair or not kept:
        return pd.DataFrame({c: pd.Series(dtype=_dtype(c, predictions)) for c in PC_COLUMNS})
    number, a, b, pc, rel, dz = (np.concatenate(p) for p in zip(*kept, strict=True))
    first = np.argsort(number, kind="stable")
    a, b, pc, rel, dz = a[first], b[first], pc[first], rel[first], dz[first]
    ids, horizon = predictions["aircraft_id"], predictions["horizon_s"].to_numpy()
    out = pd.DataFrame({"time": predictions["time"].array.take(a), "aircraft_a": ids.take(a).to_numpy(),
                        "aircraft_b": ids.take(b).to_numpy(), "horizon_s": horizon[a],
                        "pc": pc, "horizontal_nm": np.hypot(rel[:, 0], rel[:, 1]) / M_PER_NM,
                        "vertical_ft": np.abs(dz)})
    return out[out["pc"] > eps].reset_index(drop=True)


class _Columns:
    """The predictions' numeric columns as float arrays (views, not copies, when already float64)."""

    def __init__(self, frame: pd.DataFrame):
        self.east, self.north = frame["east_m"].to_numpy(float), frame["north_m"].to_numpy(float)
        self.var_e = frame["var_east_m2"].to_numpy(float)
        self.cov_en = frame["cov_east_north_m2"].to_numpy(float)
        self.var_n = frame["var_north_m2"].to_numpy(float)
        self.fl = frame["flight_level"].to_numpy(float)
        self.sig_alt = frame["sigma_alt_ft"].to_numpy(float) if "sigma_alt_ft" in frame.columns else None
        if self.sig_alt is not None:
            bad = np.isfinite(self.fl) & ~(np.isfinite(self.sig_alt) & (self.sig_alt >= 0))
            if bad.any():
                k = int(np.flatnonzero(bad)[0])
                raise ValueError(f"predictions: sigma_alt_ft {float(self.sig_alt[k])!r} at a flight level "
                                 f"(aircraft {frame['aircraft_id'].iloc[k]!r}, {frame['time'].iloc[k]}, "
                                 f"horizon {frame['horizon_s'].iloc[k]!r} s): must be a finite non-negative "
                                 "sigma")

    def cov(self, rows: np.ndarray) -> np.ndarray:
        out = np.empty((len(rows), 2, 2))
        out[:, 0, 0] = self.var_e[rows]
        out[:, 0, 1] = out[:, 1, 0] = self.cov_en[rows]
        out[:, 1, 1] = self.var_n[rows]
        return out

    def relative(self, a: np.ndarray, b: np.ndarray, vertical_ft: float):
        """Relative position (k, 2) and covariance (k, 2, 2), altitude difference (ft) and vertical
        factor of the row pairs (a, b)."""
        rel = np.column_stack([self.east[a] - self.east[b], self.north[a] - self.north[b]])
        rel_cov = self.cov(a) + self.cov(b)
        dz = self.fl[a] * FT_PER_FL - self.fl[b] * FT_PER_FL
        if self.sig_alt is None:
            vertical = (np.abs(dz) < vertical_ft).astype(float)
        else:
            s = np.hypot(self.sig_alt[a], self.sig_alt[b])
            vertical = ndtr((vertical_ft - dz) / s) - ndtr((-vertical_ft - dz) / s)
        return rel, rel_cov, dz, vertical


def _exact_batches(pending: list[tuple], last: bool, radius_m: float, method: str, eps: float,
                   kept: list[tuple]) -> list[tuple]:
    """Exact PC of the pending pairs in batches of _CHUNK in the order they came (the batches of one pass
    over all pairs: the quadrature's panels depend on the batch), the last one shorter only when `last`;
    the pairs above eps appended to kept; returns the pairs left pending."""
    number, a, b, rel, rel_cov, dz, vertical = (np.concatenate(p) for p in zip(*pending, strict=True))
    n = len(number) if last else len(number) // _CHUNK * _CHUNK
    for s in range(0, n, _CHUNK):
        k = slice(s, min(s + _CHUNK, n))
        pc = conflict_probability(rel[k], rel_cov[k], radius_m, method) * vertical[k]
        above = pc > eps
        kept.append((number[k][above], a[k][above], b[k][above], pc[above], rel[k][above], dz[k][above]))
    rest = slice(n, None)
    return [(number[rest], a[rest], b[rest], rel[rest], rel_cov[rest], dz[rest], vertical[rest])] \
        if n < len(number) else []


def _near_pairs(cols: _Columns, order: np.ndarray, bounds: np.ndarray, radius_m: float, vertical_ft: float,
                eps: float, chunk_rows: int) -> Iterator[np.ndarray]:
    """Pairs of sorted positions within one (horizon, time) group whose PC can exceed eps, sorted, in
    chunks of whole groups of about chunk_rows rows: those `candidate_pairs` finds group by group within
    the group's radius (radius_m plus the PC margin of its largest variance) and vertical limit."""
    n_groups = len(bounds) - 1
    g0 = 0
    while g0 < n_groups:
        g1 = max(int(np.searchsorted(bounds, bounds[g0] + chunk_rows, side="right")) - 1, g0 + 1)
        lo, hi = int(bounds[g0]), int(bounds[g1])
        yield _chunk_pairs(cols, order[lo:hi], bounds[g0:g1 + 1] - lo, radius_m, vertical_ft, eps) + lo
        g0 = g1


def _chunk_pairs(cols: _Columns, rows: np.ndarray, edges: np.ndarray, radius_m: float, vertical_ft: float,
                 eps: float) -> np.ndarray:
    """Local index pairs (i < j, sorted) within the groups [edges[g], edges[g + 1]) of `rows`."""
    size = np.diff(edges)
    multi = np.flatnonzero(size >= 2)
    if not len(multi):
        return np.empty((0, 2), dtype=np.int64)
    ve, vn, cen = cols.var_e[rows], cols.var_n[rows], cols.cov_en[rows]
    lam = 0.5 * (ve + vn) + np.hypot(0.5 * (ve - vn), cen)
    # relative covariance: largest eigenvalue at most the sum of the two largest
    group_r = radius_m + pc_margin(np.sqrt(2.0 * np.maximum.reduceat(lam, edges[:-1])[multi]), eps)
    if cols.sig_alt is None:
        group_v = np.full(len(multi), vertical_ft)
    else:
        # a row without a level (NaN, no sigma either) is never paired: it widens no group's limit
        sig = np.where(np.isfinite(cols.fl[rows]), cols.sig_alt[rows], 0.0)
        sig_max = np.maximum.reduceat(sig, edges[:-1])[multi]
        group_v = vertical_ft + pc_margin(np.sqrt(2.0) * sig_max, eps)
    _check_limits(group_r, group_v)
    # the groups' rows: group number, radius and vertical limit of each
    gid = np.repeat(np.arange(len(multi)), size[multi])
    local = np.flatnonzero(np.repeat(size >= 2, size))
    r = rows[local]
    x, y, alt = cols.east[r], cols.north[r], cols.fl[r] * FT_PER_FL
    finite = np.isfinite(x) & np.isfinite(y) & np.isfinite(alt)
    local, gid, x, y, alt = local[finite], gid[finite], x[finite], y[finite], alt[finite]
    vg = group_v[gid]
    # the box |dx|, |dy| <= radius, |d alt| <= vertical, a little wider, holds every wanted pair; the exact
    # cylinder test follows
    edges_kept = np.searchsorted(gid, np.arange(len(multi) + 1))
    box = np.column_stack([group_r, group_r, group_v]) * (1.0 + _SLACK)
    found = grouped_box_pairs(np.column_stack([x, y, alt]), edges_kept, box)
    i, j = found[:, 0], found[:, 1]
    r2 = np.array([float(v) ** 2 for v in group_r])[gid[i]]  # as candidate_pairs: radius_m**2
    near = ((x[i] - x[j]) ** 2 + (y[i] - y[j]) ** 2 <= r2) & (np.abs(alt[i] - alt[j]) <= vg[i])
    i, j = local[i[near]], local[j[near]]
    out = np.column_stack([np.minimum(i, j), np.maximum(i, j)])
    return out[np.lexsort((out[:, 1], out[:, 0]))]


def _check_limits(group_r: np.ndarray, group_v: np.ndarray) -> None:
    """ValueError, as `candidate_pairs`, for the first group whose radius or vertical limit is not a
    finite non-negative distance (a NaN variance)."""
    bad_r = ~(np.isfinite(group_r) & (group_r >= 0))
    bad_v = ~(np.isfinite(group_v) & (group_v >= 0))
    if (bad_r | bad_v).any():
        g = int(np.flatnonzero(bad_r | bad_v)[0])
        name, value = ("radius_m", group_r[g]) if bad_r[g] else ("vertical_ft", group_v[g])
        raise ValueError(f"{name}: must be a finite non-negative distance, got {float(value)!r}")


def _given_pairs(ordered: pd.DataFrame, pairs: pd.DataFrame) -> np.ndarray:
    """Positions in the sorted keys (`horizon_s, time, aircraft_id`) of each given (time, a, b) at every
    horizon both have."""
    _require(pairs, ["time", "aircraft_a", "aircraft_b"], "pairs")
    index = pd.MultiIndex.from_arrays([ordered["horizon_s"], time_key(ordered["time"]),
                                       ordered["aircraft_id"]])
    when = time_key(pairs["time"])
    rows = []
    for h in ordered["horizon_s"].unique():
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
