"""Pair pre-filter: which aircraft are close enough, horizontally and vertically, to need a closer look.

A k-d tree (scipy's cKDTree) finds the pairs in O(n log n) rather than testing all n(n-1)/2. Callers
widen the radius by a margin: the largest closing distance within the look-ahead when the tree holds
current positions (`closing_margin_m`), or a probability bound when it holds predicted positions
(`pipeline.conflict.pc_margin`).
"""

from __future__ import annotations

import numpy as np
import pandas as pd
from scipy.spatial import cKDTree

from pipeline.conflict.geometry import M_PER_NM, surface_ecef_m

PAIR_COLUMNS = ["time", "aircraft_a", "aircraft_b"]


def candidate_pairs(position_m, altitude_ft, radius_m: float, vertical_ft: float) -> np.ndarray:
    """Index pairs (i, j), i < j, sorted, with straight-line distance <= radius_m and altitude
    difference <= vertical_ft. position_m is (n, 2) plane or (n, 3) earth-centred coordinates."""
    pos = np.asarray(position_m, dtype=float)
    alt = np.asarray(altitude_ft, dtype=float)
    if pos.ndim != 2 or pos.shape[1] not in (2, 3):
        raise ValueError(f"position_m: expected shape (n, 2) or (n, 3), got {pos.shape}")
    if alt.shape != (len(pos),):
        raise ValueError(f"altitude_ft: expected shape ({len(pos)},) to match position_m, got {alt.shape}")
    for name, value in (("radius_m", radius_m), ("vertical_ft", vertical_ft)):
        if not np.isfinite(value) or value < 0:
            raise ValueError(f"{name}: must be a finite non-negative distance, got {value!r}")
    finite = np.isfinite(pos).all(axis=1) & np.isfinite(alt)
    if len(pos) < 2 or not finite.any():
        return np.empty((0, 2), dtype=np.int64)
    keep = np.flatnonzero(finite)
    # the box |dx|, |dy|, |dz| <= radius, |d alt| <= vertical (altitude scaled to the radius) holds
    # every wanted pair; the exact cylinder test follows
    scale = radius_m / vertical_ft if vertical_ft > 0 else 1e12
    points = np.column_stack([pos[keep], alt[keep] * scale])
    found = cKDTree(points).query_pairs(radius_m * (1 + 1e-12), p=np.inf, output_type="ndarray")
    i, j = keep[found[:, 0]], keep[found[:, 1]]
    near = (((pos[i] - pos[j]) ** 2).sum(axis=1) <= radius_m**2) & (np.abs(alt[i] - alt[j]) <= vertical_ft)
    pairs = np.column_stack([np.minimum(i, j), np.maximum(i, j)])[near]
    return pairs[np.lexsort((pairs[:, 1], pairs[:, 0]))]


def closing_margin_m(max_speed_kt: float, horizon_s: float) -> float:
    """Largest possible decrease of the distance between two aircraft within the horizon: both flying
    head-on at the largest speed."""
    return 2.0 * max_speed_kt * M_PER_NM / 3600.0 * horizon_s


def pairs_per_step(tracks: pd.DataFrame, radius_nm: float = 5.0, vertical_ft: float = 1000.0,
                   margin_nm: float = 0.0, vertical_margin_ft: float = 0.0) -> pd.DataFrame:
    """Candidate pairs at each time of a track frame: `time, aircraft_a, aircraft_b` (a < b).

    tracks: `aircraft_id, time, latitude, longitude, flight_level` (one row per aircraft and time).
    Horizontal distance is the chord between the points on the WGS-84 surface (never more than the
    geodesic), so no pair within radius_nm + margin_nm of each other is missed.
    """
    _require(tracks, ["aircraft_id", "time", "latitude", "longitude", "flight_level"], "tracks")
    frame = tracks.sort_values(["time", "aircraft_id"], kind="stable")
    xyz = surface_ecef_m(frame["latitude"].to_numpy(float), frame["longitude"].to_numpy(float))
    alt = frame["flight_level"].to_numpy(float) * 100.0
    ids = frame["aircraft_id"].to_numpy()
    times = time_key(frame["time"])
    starts = np.flatnonzero(np.r_[True, times[1:] != times[:-1]])
    bounds = np.r_[starts, len(frame)]
    radius_m = (radius_nm + margin_nm) * M_PER_NM
    out_t, out_a, out_b = [], [], []
    rows = np.arange(len(frame))
    for lo, hi in zip(bounds[:-1], bounds[1:], strict=True):
        found = candidate_pairs(xyz[lo:hi], alt[lo:hi], radius_m, vertical_ft + vertical_margin_ft)
        if len(found):
            out_t.append(np.repeat(rows[lo], len(found)))
            out_a.append(ids[lo:hi][found[:, 0]])
            out_b.append(ids[lo:hi][found[:, 1]])
    if not out_t:
        return pd.DataFrame({c: pd.Series(dtype=tracks[s].dtype) for c, s in
                             zip(PAIR_COLUMNS, ["time", "aircraft_id", "aircraft_id"], strict=True)})
    return pd.DataFrame({"time": frame["time"].array.take(np.concatenate(out_t)),
                         "aircraft_a": np.concatenate(out_a),
                         "aircraft_b": np.concatenate(out_b)})


def time_key(times: pd.Series) -> np.ndarray:
    """Times as int64 nanoseconds (datetimes, with or without time zone) or as they are (numbers), for
    fast grouping; converting time-zone-aware datetimes with to_numpy() builds Python objects."""
    array = times.array
    return array.as_unit("ns").asi8 if hasattr(array, "asi8") else times.to_numpy()


def _require(frame: pd.DataFrame, columns: list[str], name: str) -> None:
    missing = [c for c in columns if c not in frame.columns]
    if missing:
        raise ValueError(f"{name}: missing column(s) {', '.join(missing)}; "
                         f"has {', '.join(map(str, frame.columns))}")
