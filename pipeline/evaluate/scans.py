"""The update interval of a sensor (a radar's scan period, from north markers when present, else estimated
from the plots of each aircraft) and the grouping of one aircraft's reports into updates."""

from __future__ import annotations

import numpy as np

MIN_DIFFS = 10  # fewer successive-report intervals than this cannot give a scan period


def _whole_periods(d: np.ndarray) -> float:
    """The period of which intervals d are mostly one and sometimes several: the median interval, refined
    as the summed intervals over their summed whole numbers of periods (those within 10 % of a whole
    number), which averages out time stamps quantised to 1/128 s."""
    first = float(np.median(d))
    m = np.round(d / first)
    keep = (m >= 1) & (np.abs(d / np.maximum(m, 1) - first) < 0.1 * first)
    return float(d[keep].sum() / m[keep].sum())


def period_from_markers(north_marker_t_s: np.ndarray) -> float:
    """The antenna period from successive north markers (CAT034/CAT002 message type 1); a missing marker
    makes an interval of two periods, counted as such. NaN with fewer than two markers."""
    t = np.unique(np.asarray(north_marker_t_s, dtype=float))
    d = np.diff(t[np.isfinite(t)])
    d = d[d > 0]
    return _whole_periods(d) if d.size else float("nan")


def period_from_plots(t_s: np.ndarray, aircraft: np.ndarray) -> float:
    """The scan period estimated from the intervals between successive reports of each aircraft: their
    median (most intervals are one scan while the probability of detection is above one half), refined
    as the summed intervals over their whole numbers of scans. NaN with too few intervals."""
    t, a = np.asarray(t_s, float), np.asarray(aircraft)
    order = np.lexsort((t, a))
    t, a = t[order], a[order]
    d = np.diff(t)[a[1:] == a[:-1]]
    d = d[d > 0.5]
    if d.size < MIN_DIFFS:
        return float("nan")
    return _whole_periods(d)


def update_numbers(aircraft: np.ndarray, t_s: np.ndarray, period_s: float) -> np.ndarray:
    """Each report's update, numbered over every aircraft (in the aircraft's sorted order, then by time): a
    report less than half a period after its aircraft's previous one belongs to the same update (a split
    plot, a duplicate), a later one starts the next."""
    t = np.asarray(t_s, float)
    if not t.size:
        return np.zeros(0, dtype=np.int64)
    key = np.unique(np.asarray(aircraft), return_inverse=True)[1].ravel()
    order = np.lexsort((t, key))
    new = np.ones(t.size, bool)
    new[1:] = (np.diff(key[order]) != 0) | (np.diff(t[order]) > 0.5 * period_s)
    out = np.empty(t.size, np.int64)
    out[order] = np.cumsum(new) - 1
    return out
