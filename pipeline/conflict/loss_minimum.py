"""The closest point of each loss of separation between its grid samples, where both aircraft are reported.

A loss run is found on grid times (`--step` apart); its minimum is not. Between reports each aircraft's
position is the straight line between its estimates at two reports (`pipeline.conflict.reported`), so the
horizontal and vertical distances are those of piecewise-linear paths: the minimum over [start, end]
lies at a report time of either aircraft, at the closest point of one piece (closed form), or where the
two levels cross. Those candidate times in loss (horizontal below the radius and vertical below the
limit) give the minimum, its time, and the pair's position there; on a 5 s grid the grid minimum can lie
up to half a step of closing speed above it (0.35 NM at 500 kt).
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from msdc.pipeline.conflict.geometry import FT_PER_FL, horizontal_distance_nm, surface_ecef_m
from msdc.pipeline.conflict.pairs import time_key
from msdc.pipeline.conflict.reported import MAX_GAP_S, positions_at

MINIMUM_COLUMNS = ["min_horizontal_nm", "time_of_min", "latitude", "longitude", "flight_level_a",
                   "flight_level_b", "vertical_at_min_ft", "min_vertical_ft"]


def loss_minima(losses: pd.DataFrame, reports: pd.DataFrame, radius_nm: float, limit_ft: float,
                max_gap_s: float = MAX_GAP_S) -> pd.DataFrame:
    """losses (`aircraft_a, aircraft_b, start, end`) with MINIMUM_COLUMNS worked out between their grid
    samples from the aircraft's reports (`report_rows`): latitude and longitude of the pair's midpoint and
    each aircraft's flight level at the time of the minimum. A loss whose span an aircraft's reports do
    not cover (not found on `reported_samples`) keeps its grid values."""
    out = losses.copy()
    if out.empty:
        for c in MINIMUM_COLUMNS:
            if c not in out.columns:
                out[c] = pd.Series(dtype=out["start"].dtype if c == "time_of_min" else float)
        return out
    involved = set(out["aircraft_a"].astype(str)) | set(out["aircraft_b"].astype(str))
    mine = reports[reports["aircraft_id"].astype(str).isin(involved).to_numpy(bool)]
    by_aircraft = {str(a): r.sort_values("time", kind="stable")
                   for a, r in mine.groupby("aircraft_id", sort=False, observed=True)}
    values = {c: np.full(len(out), np.nan) for c in MINIMUM_COLUMNS if c != "time_of_min"}
    when = np.full(len(out), np.iinfo(np.int64).min, dtype=np.int64)
    start, end = time_key(out["start"]), time_key(out["end"])
    for i, (a, b) in enumerate(zip(out["aircraft_a"], out["aircraft_b"], strict=True)):
        ra, rb = by_aircraft.get(str(a)), by_aircraft.get(str(b))
        if ra is None or rb is None:
            continue
        found = _closest(ra, rb, int(start[i]), int(end[i]), radius_nm, limit_ft, max_gap_s)
        if found is None:
            continue
        when[i] = found.pop("time_ns")
        for c, v in found.items():
            values[c][i] = v
    done = when != np.iinfo(np.int64).min
    for c, v in values.items():
        out[c] = np.where(done, v, out[c]) if c in out.columns else v
    tz = out["start"].dt.tz
    found_times = pd.to_datetime(when[done], unit="ns", utc=True)
    times = out["time_of_min"].copy() if "time_of_min" in out.columns else out["start"].copy()
    times[done] = found_times.tz_convert(tz) if tz is not None else found_times.tz_localize(None)
    out["time_of_min"] = times
    return out


def _closest(ra: pd.DataFrame, rb: pd.DataFrame, start_ns: int, end_ns: int, radius_nm: float,
             limit_ft: float, max_gap_s: float) -> dict | None:
    """The closest point in loss of one pair over [start, end] (None when either is not reported over
    the whole span)."""
    inner = [time_key(r["time"]) for r in (ra, rb)]
    breaks = np.unique(np.concatenate([[start_ns, end_ns]] + [t[(t > start_ns) & (t < end_ns)]
                                                              for t in inner]))
    pa, pb = (_at(r, breaks, max_gap_s) for r in (ra, rb))
    if pa is None or pb is None:
        return None
    # candidates within each piece: the closest point of the chords (relative motion is linear on a piece)
    # and the time the levels cross
    r = surface_ecef_m(pb[0], pb[1]) - surface_ecef_m(pa[0], pa[1])
    d = np.diff(r, axis=0)
    dd = (d * d).sum(axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        s = np.clip(np.where(dd > 0, -(r[:-1] * d).sum(axis=1) / dd, 0.0), 0.0, 1.0)
        dz = pb[2] - pa[2]
        cross = dz[:-1] / (dz[:-1] - dz[1:])
    cross = np.where((dz[:-1] * dz[1:] < 0) & np.isfinite(cross), cross, 0.0)
    span = np.diff(breaks).astype(float)
    # whole nanoseconds added to the integer times (as floats, times since 1970 would lose 256 ns)
    extra = np.concatenate([breaks[:-1] + np.round(s * span).astype(np.int64),
                            breaks[:-1] + np.round(cross * span).astype(np.int64)])
    times = np.unique(np.concatenate([breaks, np.clip(extra, start_ns, end_ns)]))
    pa, pb = (_at(r, times, max_gap_s) for r in (ra, rb))
    if pa is None or pb is None:
        return None
    horizontal = horizontal_distance_nm(pa[0], pa[1], pb[0], pb[1])
    vertical = np.abs(pb[2] - pa[2]) * FT_PER_FL
    in_loss = (horizontal < radius_nm) & (vertical < limit_ft)
    if not in_loss.any():
        return None
    k = np.flatnonzero(in_loss)[np.argmin(horizontal[in_loss])]
    mid_lat, mid_lon = _midpoint(pa[0][k], pa[1][k], pb[0][k], pb[1][k])
    return {"time_ns": int(times[k]), "min_horizontal_nm": float(horizontal[k]), "latitude": mid_lat,
            "longitude": mid_lon, "flight_level_a": float(pa[2][k]), "flight_level_b": float(pb[2][k]),
            "vertical_at_min_ft": float(vertical[k]), "min_vertical_ft": float(vertical[in_loss].min())}


def _at(reports: pd.DataFrame, times_ns: np.ndarray, max_gap_s: float):
    """Latitude, longitude and flight level of one aircraft at every time, or None when a time is not
    within one reported interval with the others."""
    inside, interval, lat, lon, fl = positions_at(reports, times_ns, max_gap_s)
    if not inside.all() or len(np.unique(interval)) > 1:
        return None
    return lat, lon, fl


def _midpoint(lat_a: float, lon_a: float, lat_b: float, lon_b: float) -> tuple[float, float]:
    """The point halfway between two nearby positions (degrees)."""
    dlon = (lon_b - lon_a + 180.0) % 360.0 - 180.0
    return (lat_a + lat_b) / 2.0, (lon_a + dlon / 2.0 + 180.0) % 360.0 - 180.0
