"""The numbers a correlate report leads with: each radar report against the reference at its own time.

Over the slots where both sensors reported (the reference's ADS-B position jumps left out, so a slot
holding only jumps is not one of them), every radar report is compared with the reference's position
interpolated linearly to the report's time between the reference reports on either side of it. The
result does not depend on how empty slots are filled (no filled slot is read) nor on when in a slot
the reports fell (no slot mean is taken): the distance is the sensors' disagreement, not the slotting's.

Besides the horizontal distance (median, RMS, 95th percentile) the offset is split along and across the
reference's direction of travel: a mean along-track offset is what a time-stamp error or latency leaves
(``matched_time_offset_s`` = -along / speed, positive when the radar's times are late), a mean
cross-track offset what an azimuth or site error leaves. Their standard errors allow for the correlation
of successive reports (AR(1): n_eff = n (1 - rho) / (1 + rho)), so the verdict (pipeline.correlate.verdict)
can say whether a mean offset stands out of the noise.
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from msdc.pipeline.correlate.results import MATCHED_KEYS, WINDOW_QUALITY_KEYS
from msdc.pipeline.correlate.slots import slot_count, slot_index
from msdc.pipeline.model.geodesy import distance_m, ecef_to_enu, geodetic_to_ecef, wrap180

# the reference is interpolated across gaps of at most one slot, or of 1.5 of its median update interval
# when that is longer (a radar of 10 s scans as the reference at 10 s slots: a missed scan is not bridged)
GAP_UPDATE_FACTOR = 1.5
# below this speed the direction of travel over one slot is noise: no along/cross split for such a report
MIN_SPEED_MS = 20.0
MAX_AR1 = 0.95  # the lag-1 correlation used for the standard errors is capped here (n_eff >= n / 39)


def reference_gap_s(ref_t: np.ndarray, slot_s: float) -> float:
    """The longest reference gap interpolated across: one slot, or GAP_UPDATE_FACTOR of the reference's
    median update interval when that is longer."""
    d = np.diff(np.unique(ref_t))
    return max(slot_s, GAP_UPDATE_FACTOR * float(np.median(d))) if d.size else slot_s


def _by_time(t: np.ndarray, lat: np.ndarray, lon: np.ndarray) -> tuple[np.ndarray, ...]:
    """Reports at one time averaged (longitudes unwrapped first), in time order."""
    order = np.argsort(t, kind="stable")
    t, lat, lon = t[order], lat[order], np.unwrap(lon[order], period=360.0)
    times, inverse = np.unique(t, return_inverse=True)
    n = np.bincount(inverse).astype(float)
    return times, np.bincount(inverse, lat) / n, np.bincount(inverse, lon) / n


def matched_pairs(radar: tuple[np.ndarray, np.ndarray, np.ndarray],
                  reference: tuple[np.ndarray, np.ndarray, np.ndarray],
                  start_s: float, end_s: float, slot_s: float) -> dict[str, np.ndarray]:
    """The radar reports (time of day, latitude, longitude arrays) inside [start, end] matched to the
    reference reports (the same arrays, jumps already left out): per matched report its time, the
    reference position at that time, the distance (m), the offsets along and across the reference's
    direction of travel (m, NaN below MIN_SPEED_MS; across positive to the right) and that speed (m/s).

    A report is matched when its slot holds a reference report and the reference reports on either side
    of it are at most ``reference_gap_s`` apart (or one is at its very time)."""
    rt, rlat, rlon = (np.asarray(v, float) for v in radar)
    at, alat, alon = (np.asarray(v, float) for v in reference)
    empty = {k: np.zeros(0) for k in ("time_of_day", "ref_lat", "ref_lon", "sep_m", "along_m", "cross_m",
                                      "speed_ms")}
    keep = (rt >= start_s) & (rt <= end_s) & np.isfinite(rt) & np.isfinite(rlat) & np.isfinite(rlon)
    rt, rlat, rlon = rt[keep], rlat[keep], rlon[keep]
    inside = (at >= start_s) & (at <= end_s) & np.isfinite(at) & np.isfinite(alat) & np.isfinite(alon)
    if not rt.size or not inside.any():
        return empty
    ut, ulat, ulon = _by_time(at[inside], alat[inside], alon[inside])
    n_slots = slot_count(start_s, end_s, slot_s)
    reported = np.zeros(n_slots, bool)
    reported[np.clip(slot_index(ut, start_s, slot_s), 0, n_slots - 1)] = True
    both = reported[np.clip(slot_index(rt, start_s, slot_s), 0, n_slots - 1)]
    j = np.searchsorted(ut, rt, side="right") - 1
    jc = np.clip(j, 0, ut.size - 1)
    exact = (j >= 0) & (ut[jc] == rt)
    nxt = np.clip(j + 1, 0, ut.size - 1)
    bridged = (j >= 0) & (j < ut.size - 1) & (ut[nxt] - ut[jc] <= reference_gap_s(ut, slot_s))
    ok = both & (exact | bridged)
    if not ok.any():
        return empty
    rt, rlat, rlon, jc, nxt, exact = rt[ok], rlat[ok], rlon[ok], jc[ok], nxt[ok], exact[ok]
    span = ut[nxt] - ut[jc]
    f = np.where(exact | (span <= 0), 0.0, (rt - ut[jc]) / np.where(span > 0, span, 1.0))
    ref_lat = ulat[jc] + f * (ulat[nxt] - ulat[jc])
    ref_lon_unwrapped = ulon[jc] + f * (ulon[nxt] - ulon[jc])
    ref_lon = wrap180(ref_lon_unwrapped)
    sep = distance_m(rlat, rlon, ref_lat, ref_lon)
    # direction of travel: the reference from half a slot before to half a slot after (within its reports)
    t0 = np.clip(rt - slot_s / 2, ut[0], ut[-1])
    t1 = np.clip(rt + slot_s / 2, ut[0], ut[-1])
    lat0, lon0 = np.interp(t0, ut, ulat), wrap180(np.interp(t0, ut, ulon))
    lat1, lon1 = np.interp(t1, ut, ulat), wrap180(np.interp(t1, ut, ulon))
    ve, vn, _ = _enu(lat1, lon1, ref_lat, ref_lon)
    we, wn, _ = _enu(lat0, lon0, ref_lat, ref_lon)
    dt = t1 - t0
    de_, dn_ = ve - we, vn - wn
    norm = np.hypot(de_, dn_)
    speed = np.where(dt > 0, norm / np.where(dt > 0, dt, 1.0), np.nan)
    moving = speed >= MIN_SPEED_MS
    ue, un = np.where(moving, de_ / np.where(norm > 0, norm, 1.0), np.nan), np.where(
        moving, dn_ / np.where(norm > 0, norm, 1.0), np.nan)
    de, dn, _ = _enu(rlat, rlon, ref_lat, ref_lon)
    return {"time_of_day": rt, "ref_lat": ref_lat, "ref_lon": ref_lon, "sep_m": sep,
            "along_m": de * ue + dn * un, "cross_m": de * un - dn * ue, "speed_ms": speed}


def _enu(lat: np.ndarray, lon: np.ndarray, lat0: np.ndarray, lon0: np.ndarray) -> tuple[np.ndarray, ...]:
    """East, north, up (m) of points from origins, both on the ellipsoid's surface."""
    return ecef_to_enu(*geodetic_to_ecef(lat, lon, 0.0), lat0, lon0, 0.0)


def mean_and_se(values: np.ndarray) -> tuple[float, float]:
    """Mean of a time-ordered series and its standard error, the sample's lag-1 autocorrelation rho
    (0 to MAX_AR1) shrinking the count to n (1 - rho) / (1 + rho); NaN where fewer than 3 values."""
    v = np.asarray(values, float)
    v = v[np.isfinite(v)]
    if v.size < 3:
        return (float(v.mean()) if v.size else math.nan), math.nan
    d = v - v.mean()
    ss = float(d @ d)
    rho = min(max(float(d[1:] @ d[:-1]) / ss, 0.0), MAX_AR1) if ss > 0 else 0.0
    n_eff = v.size * (1.0 - rho) / (1.0 + rho)
    return float(v.mean()), float(v.std(ddof=1)) / math.sqrt(n_eff)


__all__ = ["MATCHED_KEYS", "WINDOW_QUALITY_KEYS", "matched_pairs", "matched_summary", "mean_and_se",
           "reference_gap_s", "window_accuracy"]


def matched_summary(pairs: dict[str, np.ndarray]) -> dict[str, float | int]:
    """MATCHED_KEYS of a window from its matched_pairs: count, distance median/RMS/95th percentile, mean
    along- and cross-track offsets with their standard errors, and the time offset -along / speed (s,
    positive: the radar's times are late) over the reports with a direction of travel."""
    sep = pairs["sep_m"]
    n = int(sep.size)
    along_mean, along_se = mean_and_se(pairs["along_m"])
    cross_mean, cross_se = mean_and_se(pairs["cross_m"])
    moving = np.isfinite(pairs["along_m"])
    offset = (float(np.mean(-pairs["along_m"][moving] / pairs["speed_ms"][moving])) if moving.any()
              else math.nan)
    return {"matched_reports": n,
            "matched_sep_median_m": float(np.median(sep)) if n else math.nan,
            "matched_sep_rms_m": float(np.sqrt(np.mean(sep**2))) if n else math.nan,
            "matched_sep_p95_m": float(np.percentile(sep, 95)) if n else math.nan,
            "matched_along_mean_m": along_mean, "matched_along_se_m": along_se,
            "matched_cross_mean_m": cross_mean, "matched_cross_se_m": cross_se,
            "matched_time_offset_s": offset}


def _label(value) -> str:
    """A call sign or address label as text ("" for a missing one)."""
    return "" if value is None or (not isinstance(value, str) and bool(pd.isna(value))) else str(value)


def window_accuracy(summaries: list[dict], errors: pd.DataFrame) -> list[dict]:
    """Per window summary, WINDOW_QUALITY_KEYS from the quality step's radar errors against ADS-B
    (pipeline.quality.accuracy.radar_errors rows: sac, sic, callsign, address, time_of_day, range_error_m,
    azimuth_error_deg) of its radar (``radar_sensor`` "CAT:SAC/SIC") and aircraft inside the window: the
    reports, mean and standard deviation of the range and azimuth errors. None where nothing matched."""
    keys = {"sac": errors["sac"].to_numpy(), "sic": errors["sic"].to_numpy(),
            "who": (errors["callsign"].map(_label) + "\x00" + errors["address"].map(_label)).to_numpy()}
    t = errors["time_of_day"].to_numpy(float)
    out = []
    for s in summaries:
        try:
            sac, sic = (int(v) for v in str(s.get("radar_sensor", "")).split(":")[1].split("/"))
        except (IndexError, ValueError):
            out.append(dict.fromkeys(WINDOW_QUALITY_KEYS))
            continue
        mine = ((keys["sac"] == sac) & (keys["sic"] == sic)
                & (keys["who"] == _label(s.get("callsign")) + "\x00" + _label(s.get("address")))
                & (t >= s["start_tod"]) & (t <= s["end_tod"]))
        rng = errors["range_error_m"].to_numpy(float)[mine]
        az = errors["azimuth_error_deg"].to_numpy(float)[mine]
        n = int(mine.sum())
        out.append({"quality_reports": n,
                    "range_error_mean_m": float(np.mean(rng)) if n else None,
                    "range_error_std_m": float(np.std(rng, ddof=1)) if n > 1 else None,
                    "azimuth_error_mean_deg": float(np.mean(az)) if n else None,
                    "azimuth_error_std_deg": float(np.std(az, ddof=1)) if n > 1 else None})
    return out
