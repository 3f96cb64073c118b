"""Pair pre-filter: which aircraft are close enough, horizontally and vertically, to need a closer look.

A sort and sweep (`pipeline.conflict.sweep`: the times of a chunk in one kernel call) finds the pairs
without testing all n(n-1)/2 of a time. Callers widen the radius by a margin: the largest closing
distance within the look-ahead for current positions (`closing_margin_m`), or a probability bound for
predicted positions (`pipeline.conflict.pc_margin`).
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from msdc.pipeline.conflict.geometry import M_PER_NM, surface_ecef_m
from msdc.pipeline.conflict.sweep import grouped_box_pairs

PAIR_COLUMNS = ["time", "aircraft_a", "aircraft_b"]
CHUNK_ROWS = 1 << 16  # track rows searched for pairs at once (whole times)


def candidate_pairs(position_m, altitude_ft, radius_m: float, vertical_ft: float) -> np.ndarray:
    """Index pairs (i, j), i < j, sorted, with straight-line distance <= radius_m and altitude
    difference <= vertical_ft. position_m is (n, 2) plane or (n, 3) earth-centred coordinates."""
    pos = np.asarray(position_m, dtype=float)
    alt = np.asarray(altitude_ft, dtype=float)
    if pos.ndim != 2 or pos.shape[1] not in (2, 3):
        raise ValueError(f"position_m: expected shape (n, 2) or (n, 3), got {pos.shape}")
    if alt.shape != (len(pos),):
        raise ValueError(f"altitude_ft: expected shape ({len(pos)},) to match position_m, got {alt.shape}")
    _check_limits(radius_m, vertical_ft)
    return _grouped_pairs(pos, alt, np.array([0, len(pos)]), radius_m, vertical_ft)


def _check_limits(radius_m: float, vertical_ft: float) -> None:
    for name, value in (("radius_m", radius_m), ("vertical_ft", vertical_ft)):
        if not np.isfinite(value) or value < 0:
            raise ValueError(f"{name}: must be a finite non-negative distance, got {value!r}")


def _grouped_pairs(pos: np.ndarray, alt: np.ndarray, edges: np.ndarray, radius_m: float,
                   vertical_ft: float) -> np.ndarray:
    """`candidate_pairs` of each group of rows [edges[g], edges[g + 1]) at once: row pairs (i, j), i < j,
    sorted, rows with a non-finite coordinate left out."""
    keep = np.flatnonzero(np.isfinite(pos).all(axis=1) & np.isfinite(alt))
    if len(keep) < 2:
        return np.empty((0, 2), dtype=np.int64)
    # the box |dx|, |dy|, |dz| <= radius, |d alt| <= vertical, a little wider, holds every wanted pair;
    # the exact cylinder test follows
    box = np.array([radius_m] * pos.shape[1] + [vertical_ft]) * (1 + 1e-9)
    found = grouped_box_pairs(np.column_stack([pos[keep], alt[keep]]), np.searchsorted(keep, edges),
                              np.broadcast_to(box, (len(edges) - 1, len(box))))
    i, j = keep[found[:, 0]], keep[found[:, 1]]
    near = (((pos[i] - pos[j]) ** 2).sum(axis=1) <= radius_m**2) & (np.abs(alt[i] - alt[j]) <= vertical_ft)
    pairs = np.column_stack([i, j])[near]
    return pairs[np.lexsort((pairs[:, 1], pairs[:, 0]))]


def closing_margin_m(max_speed_kt: float, horizon_s: float) -> float:
    """Largest possible decrease of the distance between two aircraft within the horizon: both flying
    head-on at the largest speed."""
    for name, value in (("max_speed_kt", max_speed_kt), ("horizon_s", horizon_s)):
        if not np.isfinite(value) or value < 0:
            raise ValueError(f"{name}: must be finite and not negative, got {value!r}")
    return 2.0 * max_speed_kt * M_PER_NM / 3600.0 * horizon_s


def pairs_per_step(tracks: pd.DataFrame, radius_nm: float = 5.0, vertical_ft: float = 1000.0,
                   margin_nm: float = 0.0, vertical_margin_ft: float = 0.0,
                   chunk_rows: int = CHUNK_ROWS) -> pd.DataFrame:
    """Candidate pairs at each time of a track frame: `time, aircraft_a, aircraft_b` (a < b).

    tracks: `aircraft_id, time, latitude, longitude, flight_level` (one row per aircraft and time).
    Horizontal distance is the chord between the points on the WGS-84 surface (never more than the
    geodesic), so no pair within radius_nm + margin_nm of each other is missed. The times are searched
    in chunks of whole times of about chunk_rows rows (memory only: the result does not depend on it).
    """
    _require(tracks, ["aircraft_id", "time", "latitude", "longitude", "flight_level"], "tracks")
    frame = tracks.sort_values(["time", "aircraft_id"], kind="stable")
    radius_m = (radius_nm + margin_nm) * M_PER_NM
    if len(frame):
        _check_limits(radius_m, vertical_ft + vertical_margin_ft)
    xyz = surface_ecef_m(frame["latitude"].to_numpy(float), frame["longitude"].to_numpy(float))
    alt = frame["flight_level"].to_numpy(float) * 100.0
    ids = frame["aircraft_id"].to_numpy()
    times = time_key(frame["time"])
    bounds = np.r_[np.flatnonzero(np.r_[True, times[1:] != times[:-1]]), len(frame)]
    found = []
    g0 = 0
    while g0 < len(bounds) - 1:  # chunks of whole times
        g1 = max(int(np.searchsorted(bounds, bounds[g0] + max(int(chunk_rows), 1), side="right")) - 1, g0 + 1)
        lo, hi = int(bounds[g0]), int(bounds[g1])
        found.append(_grouped_pairs(xyz[lo:hi], alt[lo:hi], bounds[g0:g1 + 1] - lo, radius_m,
                                    vertical_ft + vertical_margin_ft) + lo)
        g0 = g1
    pairs = np.concatenate(found) if found else np.empty((0, 2), dtype=np.int64)
    if not len(pairs):
        return pd.DataFrame({c: pd.Series(dtype=tracks[s].dtype) for c, s in
                             zip(PAIR_COLUMNS, ["time", "aircraft_id", "aircraft_id"], strict=True)})
    return pd.DataFrame({"time": frame["time"].array.take(pairs[:, 0]), "aircraft_a": ids[pairs[:, 0]],
                         "aircraft_b": ids[pairs[:, 1]]})


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
