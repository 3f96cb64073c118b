"""update_times.aircraft_updates: one aircraft's expected updates, compiled, against the numpy formulation it
replaced (written out below, stretch by stretch) on random trajectories, and by hand."""

from __future__ import annotations

import numpy as np
import pytest

from msdc.pipeline.evaluate.update_times import EDGE_SLACK, aircraft_updates


def _missed_times(times, start_s, end_s, period_s):
    if not times.size:
        k = int(np.floor((end_s - start_s) / period_s + EDGE_SLACK))
        return start_s + period_s * (np.arange(k) + 0.5)
    before = int(np.floor((times[0] - start_s) / period_s + EDGE_SLACK))
    after = int(np.floor((end_s - times[-1]) / period_s + EDGE_SLACK))
    out = [times[0] - period_s * np.arange(before, 0, -1), times[-1] + period_s * np.arange(1, after + 1)]
    for a, g in zip(times[:-1], np.diff(times), strict=True):
        m = int(round(g / period_s)) - 1
        if m > 0:
            out.append(a + g * np.arange(1, m + 1) / (m + 1))
    return np.sort(np.concatenate(out))


def _window_updates(times, start_s, end_s, interval_s):
    k = int(np.floor((end_s - start_s) / interval_s + 1e-9))
    edges = start_s + interval_s * np.arange(k + 1)
    held = np.zeros(k, dtype=bool)
    if k and times.size:
        idx = np.searchsorted(edges, times, side="right") - 1
        held[np.unique(idx[(idx >= 0) & (idx < k)])] = True
    return edges[:-1] + 0.5 * interval_s, held


def _numpy(t_ref, mine, max_gap_s, step_s, by_interval):
    cut = np.flatnonzero(np.diff(t_ref) > max_gap_s)
    starts, ends = np.concatenate([[0], cut + 1]), np.concatenate([cut, [t_ref.size - 1]])
    out = {"stretch": [], "t": [], "held": [], "clipped": []}
    for s, (a, b) in enumerate(zip(t_ref[starts], t_ref[ends], strict=True)):
        times = mine[(mine >= a) & (mine <= b)]
        if by_interval:
            t_exp, held = _window_updates(times, a, b, step_s)
        else:
            first = times[np.concatenate([[True], np.diff(times) > 0.5 * step_s])] if times.size else times
            missed = _missed_times(first, a, b, step_s)
            t_exp = np.concatenate([first, missed])
            held = np.concatenate([np.ones(first.size, bool), np.zeros(missed.size, bool)])
        out["stretch"].append(np.full(t_exp.size, s))
        out["t"].append(t_exp)
        out["held"].append(held)
        out["clipped"].append(np.clip(t_exp, a, b))
    return tuple(np.concatenate(v) for v in out.values())


@pytest.mark.parametrize("by_interval", [False, True])
def test_the_same_updates_as_the_numpy_formulation_to_the_bit(by_interval):
    rng = np.random.default_rng(8 + by_interval)
    for _ in range(400):
        n = int(rng.integers(1, 400))
        t_ref = np.sort(rng.uniform(0, 900, n)) + rng.uniform(-1e5, 1e5)
        t_ref = np.unique(np.round(t_ref, int(rng.integers(0, 4))))  # equal times made apart, some rounded
        period = float(rng.choice([1.0, 4.0, 4.7, 12.0, rng.uniform(0.5, 20)]))
        # reports: most scans, some missed, split plots, some outside every stretch
        scans = np.arange(t_ref[0] - 30, t_ref[-1] + 30, period) + rng.normal(0, 0.05 * period, 1)
        mine = scans[rng.uniform(size=scans.size) < rng.uniform(0.3, 1.0)]
        mine = np.sort(np.concatenate([mine, mine[:: int(rng.integers(3, 9))] + 0.1 * period]))
        gap = float(rng.choice([5.0, 30.0, 60.0]))
        got = aircraft_updates(t_ref, mine, gap, period, by_interval)
        want = _numpy(t_ref, mine, gap, period, by_interval)
        for g, w in zip(got, want, strict=True):
            assert np.array_equal(g, w), (g, w)


def test_by_hand_scans():
    # one stretch 0-40 s, scans of 4 s: reports at 4, 4.5 (split: the same update), 8, then a gap to 20
    t_ref = np.arange(0.0, 41.0, 1.0)
    stretch, t, held, clipped = aircraft_updates(t_ref, np.array([4.0, 4.5, 8.0, 20.0]), 30.0, 4.0, False)
    # detected: 4, 8, 20; missed: before 4 one, at 0 (floor(4/4 + 0.05) = 1); between 8 and 20 (12 s, 3
    # periods) two, at 12 and 16; after 20: 24, 28, 32, 36, 40 (floor(20/4 + 0.05) = 5)
    assert t.tolist() == [4.0, 8.0, 20.0, 0.0, 12.0, 16.0, 24.0, 28.0, 32.0, 36.0, 40.0]
    assert held.tolist() == [True] * 3 + [False] * 8 and set(stretch.tolist()) == {0}
    assert clipped.tolist() == t.tolist()


def test_by_hand_a_gap_cuts_two_stretches_and_intervals():
    t_ref = np.array([0.0, 1.0, 2.0, 100.0, 101.0, 111.0])  # a gap over 30 s: stretches 0-2 and 100-111
    stretch, t, held, _ = aircraft_updates(t_ref, np.array([1.5, 104.0]), 30.0, 5.0, True)
    # intervals of 5 s: none fits 0-2; 100-105 (holds 104) and 105-110, middles 102.5 and 107.5
    assert stretch.tolist() == [1, 1] and t.tolist() == [102.5, 107.5] and held.tolist() == [True, False]
    # no report in a stretch: every period from half a period after its start
    stretch, t, held, _ = aircraft_updates(np.array([0.0, 10.0]), np.zeros(0), 30.0, 4.0, False)
    assert t.tolist() == [2.0, 6.0] and not held.any()  # floor(10/4 + 0.05) = 2 updates
