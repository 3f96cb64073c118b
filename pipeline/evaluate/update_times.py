"""The updates a sensor should have made of one reference aircraft (detection.expected_updates), in one
compiled pass over every stretch of the aircraft: the arithmetic of the numpy formulation it replaced,
operation for operation (kept as the reference of tests/pipeline/evaluate/test_update_times.py), without a
numpy call per stretch (some 5,000 a window at the peak)."""

from __future__ import annotations

import math

import numpy as np
from numba import njit

EDGE_SLACK = 0.05  # of a period: a missed update this close outside a reference stretch still counts


@njit(cache=True, nogil=True)
def _stretch_bounds(t_ref: np.ndarray, max_gap_s: float) -> tuple[np.ndarray, np.ndarray]:
    """First and last sample time of each stretch (cut where samples are more than max_gap_s apart)."""
    n_cut = 0
    for i in range(1, t_ref.size):
        if t_ref[i] - t_ref[i - 1] > max_gap_s:
            n_cut += 1
    lo, hi = np.empty(n_cut + 1), np.empty(n_cut + 1)
    s, lo[0] = 0, t_ref[0]
    for i in range(1, t_ref.size):
        if t_ref[i] - t_ref[i - 1] > max_gap_s:
            hi[s] = t_ref[i - 1]
            s += 1
            lo[s] = t_ref[i]
    hi[s] = t_ref[t_ref.size - 1]
    return lo, hi


@njit(cache=True, nogil=True)
def _scan_updates(mine: np.ndarray, i0: int, i1: int, a: float, b: float, period_s: float, t_out: np.ndarray,
                  held: np.ndarray, at: int, count_only: bool) -> int:
    """One stretch's updates by scans (its reports ``mine[i0:i1]``): the first report of each update (a
    report less than half a period after the previous one is the same update), then the missed ones sorted
    (in a gap g, round(g / T) - 1 evenly spaced; before the first and after the last, every T back to the
    stretch's start and on to its end; with none, every T from T/2); written from ``at`` unless
    ``count_only``; returns how many."""
    n = i1 - i0
    if n == 0:
        k = int(math.floor((b - a) / period_s + EDGE_SLACK))
        if not count_only:
            for i in range(k):
                t_out[at + i] = a + period_s * (i + 0.5)
                held[at + i] = False
        return k
    first = np.empty(n)
    nf = 1
    first[0] = mine[i0]
    for i in range(i0 + 1, i1):
        if mine[i] - mine[i - 1] > 0.5 * period_s:
            first[nf] = mine[i]
            nf += 1
    before = int(math.floor((first[0] - a) / period_s + EDGE_SLACK))
    after = int(math.floor((b - first[nf - 1]) / period_s + EDGE_SLACK))
    n_missed = max(before, 0) + max(after, 0)
    for i in range(nf - 1):
        m = int(np.rint((first[i + 1] - first[i]) / period_s)) - 1
        if m > 0:
            n_missed += m
    if count_only:
        return nf + n_missed
    for i in range(nf):
        t_out[at + i] = first[i]
        held[at + i] = True
    # the missed ones in ascending order as they are made (no sort): those before the first update, those
    # of each gap (inside it, gap after gap), those after the last
    j = at + nf
    for r in range(before, 0, -1):
        t_out[j] = first[0] - period_s * r
        j += 1
    for i in range(nf - 1):
        g = first[i + 1] - first[i]
        m = int(np.rint(g / period_s)) - 1
        for r in range(1, m + 1):
            t_out[j] = first[i] + g * r / (m + 1)
            j += 1
    for r in range(1, after + 1):
        t_out[j] = first[nf - 1] + period_s * r
        j += 1
    for i in range(at + nf, j):
        held[i] = False
    return nf + n_missed


@njit(cache=True, nogil=True)
def _interval_updates(mine: np.ndarray, i0: int, i1: int, a: float, b: float, interval_s: float,
                      t_out: np.ndarray, held: np.ndarray, at: int, count_only: bool) -> int:
    """One stretch's whole intervals from its start (its reports ``mine[i0:i1]``; a last partial one left
    out), each one's middle time and whether it holds a report; written from ``at`` unless ``count_only``;
    returns how many."""
    k = int(math.floor((b - a) / interval_s + 1e-9))
    if count_only:
        return k
    edges = np.empty(k + 1)
    for i in range(k + 1):
        edges[i] = a + interval_s * i
    for i in range(k):
        t_out[at + i] = edges[i] + 0.5 * interval_s
        held[at + i] = False
    if k:
        j = 0  # the reports are sorted: each one's interval (edges up to and including it, less one)
        for i in range(i0, i1):
            while j <= k and edges[j] <= mine[i]:
                j += 1
            if 0 <= j - 1 < k:
                held[at + j - 1] = True
    return k


@njit(cache=True, nogil=True)
def aircraft_updates(t_ref: np.ndarray, mine: np.ndarray, max_gap_s: float, step_s: float, by_interval: bool
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Per expected update of one aircraft (its reference's sorted sample times ``t_ref``, the sensor's
    sorted report times ``mine``): its stretch, its time, whether the sensor made it, and its time clipped
    to the stretch (where the reference is read), stretch by stretch as detection's table lists them."""
    lo, hi = _stretch_bounds(t_ref, max_gap_s)
    empty_t, empty_h = np.empty(0), np.empty(0, np.bool_)
    spans = np.zeros((lo.size, 2), np.int64)  # each stretch's reports: mine[spans[s, 0]:spans[s, 1]]
    total = 0  # the flags and start passed as numpy scalars: numba compiles a copy per literal argument
    for s in range(lo.size):  # mine sorted (a missing time last): those within the stretch are a run
        spans[s, 0] = np.searchsorted(mine, lo[s], side="left")
        spans[s, 1] = max(np.searchsorted(mine, hi[s], side="right"), spans[s, 0])
        if by_interval:
            total += _interval_updates(mine, spans[s, 0], spans[s, 1], lo[s], hi[s], step_s, empty_t,
                                       empty_h, np.int64(0), np.bool_(True))
        else:
            total += _scan_updates(mine, spans[s, 0], spans[s, 1], lo[s], hi[s], step_s, empty_t, empty_h,
                                   np.int64(0), np.bool_(True))
    stretch = np.empty(total, np.int64)
    t_out, held, clipped = np.empty(total), np.empty(total, np.bool_), np.empty(total)
    at = np.int64(0)
    for s in range(lo.size):
        if by_interval:
            n = _interval_updates(mine, spans[s, 0], spans[s, 1], lo[s], hi[s], step_s, t_out, held, at,
                                  np.bool_(False))
        else:
            n = _scan_updates(mine, spans[s, 0], spans[s, 1], lo[s], hi[s], step_s, t_out, held, at,
                              np.bool_(False))
        for i in range(at, at + n):
            stretch[i] = s
            clipped[i] = min(max(t_out[i], lo[s]), hi[s])
        at += n
    return stretch, t_out, held, clipped
