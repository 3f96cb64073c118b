"""A reference aircraft's samples interpolated at given times, in one numba pass: the same arithmetic as
the array expression it replaced (the requirements call it some 30,000 times a window, each on a few
reports, where numpy's per-call overhead was most of the cost)."""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True, nogil=True)
def interpolate(t_ref: np.ndarray, latitude: np.ndarray, longitude: np.ndarray, height_m: np.ndarray,
                altitude_ft: np.ndarray, t: np.ndarray, max_gap_s: float) -> np.ndarray:  # pragma: no cover
    """Rows of latitude, longitude, height and altitude (each sampled at the sorted ``t_ref``) at ``t``:
    the sample itself on a sample time, else linear between the samples around it when they are at most
    ``max_gap_s`` apart (longitude the short way round), else NaN (before the first sample, after the last,
    a missing time)."""
    last = t_ref.size - 1
    out = np.empty((4, t.size))
    for q in range(t.size):
        x = t[q]
        i = np.searchsorted(t_ref, x, side="right") - 1
        j = min(max(i, 0), max(last - 1, 0))
        k = min(j + 1, last)
        at = min(max(i, 0), last)
        if i >= 0 and x == t_ref[at]:  # on a sample: its value, whatever the gaps around it
            out[0, q], out[1, q] = latitude[at], longitude[at]
            out[2, q], out[3, q] = height_m[at], altitude_ft[at]
            continue
        span = t_ref[k] - t_ref[j]
        if not (i >= 0 and i < last and span <= max_gap_s):
            out[:, q] = np.nan
            continue
        w = (x - t_ref[j]) / (span if span > 0 else 1.0)
        out[0, q] = latitude[j] + w * (latitude[k] - latitude[j])
        out[1, q] = longitude[j] + w * ((longitude[k] - longitude[j] + 180.0) % 360.0 - 180.0)
        out[2, q] = height_m[j] + w * (height_m[k] - height_m[j])
        out[3, q] = altitude_ft[j] + w * (altitude_ft[k] - altitude_ft[j])
    return out
