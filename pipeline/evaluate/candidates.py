"""Which (reference aircraft, report) pairs the association measures: those whose report the aircraft's box
of samples may hold within a limit, found in one numba pass over every aircraft's time span instead of a
numpy pass per aircraft (a window's radar has some 10,000 reports and 470 aircraft to try)."""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from msdc.pipeline.model.geodesy import A_M, E2

_MERIDIAN_MIN_M = A_M * (1.0 - E2)  # the least meridian radius of curvature (at the equator)


@njit(cache=True, nogil=True)
def _may_hold(lat: float, lon: float, south: float, north: float, west: float, east: float, bounded: bool,
              limit_m: float) -> bool:  # pragma: no cover - compiled; tested through candidate_pairs
    """Whether the box may hold a point within limit_m of (lat, lon): its latitude and longitude gaps on the
    least radii of curvature, less a thousandth and a millimetre, are no more than the limit (a lower bound
    of local_distance_m to any point of the box); a box that cannot bound (across the antimeridian) may hold
    any point. False without a position."""
    if not (math.isfinite(lat) and math.isfinite(lon)):
        return False
    if not bounded:
        return True
    dlat = max(max(south - lat, lat - north), 0.0)
    if 0.999 * math.radians(dlat) * _MERIDIAN_MIN_M - 0.001 > limit_m:
        return False  # the latitude gap alone rules it out
    gap = max(max(west - lon, lon - east), 0.0)  # along the line, to the nearer edge
    dlon = max(min(gap, 360.0 - gap - (east - west)), 0.0)  # or round the other way
    top = min(max(abs(lat), max(abs(south), abs(north))), 90.0)
    bound = math.hypot(math.radians(dlat) * _MERIDIAN_MIN_M,
                       math.radians(dlon) * A_M * math.cos(math.radians(top)))
    return max(0.999 * bound - 0.001, 0.0) <= limit_m


@njit(cache=True, nogil=True)
def candidate_pairs(aircraft: np.ndarray, order: np.ndarray, first: np.ndarray, stop: np.ndarray,
                    t_first: np.ndarray, t_last: np.ndarray, boxes: np.ndarray, bounded: np.ndarray,
                    t: np.ndarray, lat: np.ndarray, lon: np.ndarray, limit_m: np.ndarray
                    ) -> tuple[np.ndarray, np.ndarray]:  # pragma: no cover - compiled
    """For each aircraft k of ``aircraft``, the reports among ``order[first[k]:stop[k]]`` within its time
    span (t_first[k] <= t <= t_last[k]) that its box (``boxes[k]``: south, north, west, east; ``bounded[k]``)
    may hold within ``limit_m`` of the report: the pairs as (k, row) arrays, k in the order given."""
    size = 0
    for k in aircraft:
        size += max(stop[k] - first[k], 0)
    ks = np.empty(size, np.int64)
    rows = np.empty(size, np.int64)
    n = 0
    for k in aircraft:
        south, north, west, east = boxes[k, 0], boxes[k, 1], boxes[k, 2], boxes[k, 3]
        for p in range(first[k], stop[k]):
            r = order[p]
            if t[r] >= t_first[k] and t[r] <= t_last[k] and _may_hold(
                    lat[r], lon[r], south, north, west, east, bounded[k], limit_m[r]):
                ks[n] = k
                rows[n] = r
                n += 1
    return ks[:n], rows[:n]


def latitude_reach_deg(limit_m: float) -> float:
    """A latitude gap (deg) beyond which _may_hold rules a point out for ``limit_m`` (with room for
    rounding): the reports worth trying lie within it of a box's south and north."""
    return math.degrees((limit_m + 0.001) / 0.999 / _MERIDIAN_MIN_M) * (1.0 + 1e-9) + 1e-9
