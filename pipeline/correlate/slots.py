"""Resampling one sensor's measurements in a window onto fixed time slots."""

from __future__ import annotations

import numpy as np
import pandas as pd

from msdc.pipeline.model.geodesy import wrap180

SLOTTED_COLUMNS = ["slot", "time_of_day", "latitude", "longitude", "count", "filled"]


def slot_count(start_s: float, end_s: float, slot_s: float) -> int:
    """N = floor((end - start) / D) + 1 slots cover [start, end]."""
    return int(np.floor((end_s - start_s) / slot_s)) + 1


def slot_index(times_s, start_s: float, slot_s: float) -> np.ndarray:
    """k with start + k*D <= t < start + (k+1)*D, exact at slot edges despite floating point."""
    t = np.asarray(times_s, dtype=float)
    k = np.floor((t - start_s) / slot_s)
    k = np.where(start_s + (k + 1) * slot_s <= t, k + 1, k)
    k = np.where(start_s + k * slot_s > t, k - 1, k)
    return k.astype(np.int64)


def slot_window(meas: pd.DataFrame, start_s: float, end_s: float, slot_s: float = 10.0) -> pd.DataFrame:
    """Mean position per slot of measurements in [start, end]; empty slots copy the previous (or first) slot.

    Longitudes are averaged relative to the window's first longitude, so slots straddling +-180 deg
    average correctly; results are wrapped into [-180, 180). Columns: SLOTTED_COLUMNS, where
    time_of_day is the slot start and ``filled`` marks slots that had no measurement.
    """
    return pd.DataFrame(slot_arrays(meas, start_s, end_s, slot_s), columns=SLOTTED_COLUMNS)


def slot_arrays(meas: pd.DataFrame, start_s: float, end_s: float,
                slot_s: float = 10.0) -> dict[str, np.ndarray]:
    """slot_window's columns as arrays (no frame: the correlation builds its own per window)."""
    return slot_series(meas["time_of_day"].to_numpy(float), meas["latitude"].to_numpy(float),
                       meas["longitude"].to_numpy(float), start_s, end_s, slot_s)


def slot_series(t: np.ndarray, lat: np.ndarray, lon: np.ndarray, start_s: float, end_s: float,
                slot_s: float = 10.0) -> dict[str, np.ndarray]:
    """slot_arrays of reports given as arrays of time of day (s), latitude and longitude (deg)."""
    n = slot_count(start_s, end_s, slot_s)
    inside = (t >= start_s) & (t <= end_s)
    lat, lon = lat[inside], lon[inside]
    k = slot_index(t[inside], start_s, slot_s)
    count = np.bincount(k, minlength=n)[:n]
    with np.errstate(invalid="ignore", divide="ignore"):
        lat_mean = np.bincount(k, lat, minlength=n)[:n] / count
        ref = lon[0] if lon.size else 0.0
        rel = wrap180(lon - ref)
        lon_mean = np.bincount(k, rel, minlength=n)[:n] / count + ref
    lat_mean, lon_mean = _fill(lat_mean), wrap180(_fill(lon_mean))
    return {"slot": np.arange(n), "time_of_day": start_s + np.arange(n) * slot_s, "latitude": lat_mean,
            "longitude": lon_mean, "count": count.astype(np.int64), "filled": count == 0}


def _fill(values: np.ndarray) -> np.ndarray:
    """NaN entries take the previous value, leading ones the first value (forward, then backward fill)."""
    valid = ~np.isnan(values)
    if valid.all() or not valid.any():
        return values
    index = np.maximum.accumulate(np.where(valid, np.arange(values.size), -1))
    index[index < 0] = int(np.argmax(valid))
    return values[index]
