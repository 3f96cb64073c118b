"""A track's expected update interval and coasted time from its updates (numpy only: the figure workers
import it without the tracker)."""

from __future__ import annotations

import math

import numpy as np

# a gap between updates counts as coasting once it exceeds this many update intervals (a missed radar scan
# doubles the interval; scan-to-scan jitter of a few percent never reaches it)
MISSED_UPDATE_FACTOR = 1.5


def coasted_time(t: np.ndarray, segment: np.ndarray, sensor: np.ndarray) -> tuple[float, float]:
    """The track's expected update interval and its coasted time, from its accepted updates (times sorted,
    their segments and sensors). The interval is the slowest sensor's median interval between its own
    consecutive updates in a segment (a 4 s radar fused with 1 s ADS-B: 4 s; NaN with no such pair). Coasted
    is the time without any update beyond that interval, summed over the gaps within segments that exceed
    MISSED_UPDATE_FACTOR intervals: a missed 4 s scan counts 4 s, a regular scan 0; the coast after a
    segment's last update is not counted (nor in tracked_s)."""
    medians = []
    for s in np.unique(sensor):
        i = sensor == s
        d = np.diff(t[i])[np.diff(segment[i]) == 0]
        d = d[d > 0.0]
        if len(d):
            medians.append(float(np.median(d)))
    if not medians:
        return math.nan, 0.0
    interval = max(medians)
    gaps = np.diff(t)[np.diff(segment) == 0]
    missed = gaps > MISSED_UPDATE_FACTOR * interval
    return interval, float((gaps[missed] - interval).sum())
