"""Radar accuracy reference from the smoothed ADS-B-only track (``msdc quality --reference track``).

Instead of interpolating linearly between ADS-B reports, the aircraft's ADS-B reports (jumps removed, no
radar: the radar under test never enters its own reference) are tracked by the IMM and smoothed (RTS);
the reference at a radar time is that smoothed track, sampled every ``STEP_S`` and interpolated between
samples (at most 0.4 m from the arc in a 3 deg/s turn at 450 kt). The same gap rule as the ADS-B reference
applies: a radar time counts only between two ADS-B reports at most ``max_gap_s`` apart.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from msdc.pipeline.model.geodesy import M_PER_FT, M_PER_S_PER_KT, wrap180

STEP_S = 0.5
# the measurement columns read here besides the tracker's (pipeline.track.tracker REQUIRED and FILTER_INPUTS)
TRACK_REFERENCE_INPUTS = ["time", "nacp"]
_FPM_TO_MS = M_PER_FT / 60.0


def track_reference(adsb: pd.DataFrame, t_s: np.ndarray, max_gap_s: float) -> dict[str, np.ndarray]:
    """The reference state at the radar times t_s (seconds on adsb's ``time_of_day`` clock): lat, lon,
    h (m, from the filtered flight level), ve/vn/vu (m/s), gap (s between the bracketing ADS-B reports)
    and nacp (the worse of the two), NaN outside the gap rule; the keys of accuracy._interpolate."""
    from msdc.pipeline.track import track

    t_s = np.asarray(t_s, float)
    out = {k: np.full(t_s.size, np.nan) for k in ("lat", "lon", "h", "ve", "vn", "vu", "gap", "nacp")}
    a = adsb.sort_values("time_of_day", kind="stable")
    ta = a["time_of_day"].to_numpy(float)
    if ta.size < 2:
        return out
    k = np.clip(np.searchsorted(ta, t_s, side="right") - 1, 0, ta.size - 2)
    k = np.where(t_s == ta[-1], ta.size - 2, k)
    gap = ta[k + 1] - ta[k]
    ok = (t_s >= ta[0]) & (t_s <= ta[-1]) & (gap <= max_gap_s)
    if not ok.any():
        return out
    res = track(a.assign(aircraft_id="A"), step_s=STEP_S, smooth=True, max_coast_s=max(max_gap_s, STEP_S))
    tr = res.tracks
    if tr.empty:
        return out
    # the track's clock: seconds since the first report's UTC midnight; adsb's time_of_day: since its own
    offset = float(np.median(ta - (a["time"] - tr["time"].iloc[0].floor("D")).dt.total_seconds()))
    tt = tr["time_of_day"].to_numpy(float) + offset
    lon_unwrapped = np.unwrap(tr["longitude"].to_numpy(float), period=360.0)
    trk = np.radians(tr["track_deg"].to_numpy(float))
    speed = tr["speed_kt"].to_numpy(float) * M_PER_S_PER_KT
    series = {"lat": tr["latitude"].to_numpy(float), "lon": lon_unwrapped,
              "h": tr["flight_level"].to_numpy(float) * 100.0 * M_PER_FT,
              "ve": speed * np.sin(trk), "vn": speed * np.cos(trk),
              "vu": np.nan_to_num(tr["vertical_rate_fpm"].to_numpy(float) * _FPM_TO_MS)}
    inside = ok & (t_s >= tt[0]) & (t_s <= tt[-1])
    for name, v in series.items():
        out[name][inside] = np.interp(t_s[inside], tt, v)
    out["lon"] = wrap180(out["lon"])
    nacp = pd.to_numeric(a["nacp"], errors="coerce").to_numpy(float) if "nacp" in a else np.full(ta.size,
                                                                                                 np.nan)
    out["gap"] = np.where(inside, gap, np.nan)
    out["nacp"] = np.where(inside, np.fmin(nacp[k], nacp[k + 1]), np.nan)
    return out
