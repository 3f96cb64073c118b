"""Continuous tracking segments of one sensor, and the windows where radar and ADS-B both track."""

from __future__ import annotations

import numpy as np


def segments(times_s, gap_s: float = 180.0) -> list[tuple[float, float]]:
    """(start, end) of runs of measurement times, split where consecutive times are MORE than gap_s apart."""
    t = np.sort(np.asarray(times_s, dtype=float))
    t = t[np.isfinite(t)]
    if t.size == 0:
        return []
    breaks = np.flatnonzero(np.diff(t) > gap_s)
    starts = np.concatenate([[0], breaks + 1])
    ends = np.concatenate([breaks, [t.size - 1]])
    return [(float(t[s]), float(t[e])) for s, e in zip(starts, ends, strict=True)]


def overlap_windows(radar_times_s, adsb_times_s, gap_s: float = 180.0) -> list[tuple[float, float]]:
    """Sorted non-empty intersections [max(starts), min(ends)] of every radar with every ADS-B segment."""
    out = []
    for r_start, r_end in segments(radar_times_s, gap_s):
        for a_start, a_end in segments(adsb_times_s, gap_s):
            start, end = max(r_start, a_start), min(r_end, a_end)
            if start <= end:
                out.append((start, end))
    return sorted(out)


def short_window_reason(start_s: float, end_s: float, slot_s: float) -> str | None:
    """Why a window is too short to correlate (shorter than one slot), or None if it is usable."""
    if end_s - start_s < slot_s:
        return f"window of {end_s - start_s:g} s is shorter than one slot ({slot_s:g} s)"
    return None


def in_window(times_s, start_s: float, end_s: float) -> np.ndarray:
    """Boolean mask of times inside [start, end] (everything else is truncated)."""
    t = np.asarray(times_s, dtype=float)
    return (t >= start_s) & (t <= end_s)
