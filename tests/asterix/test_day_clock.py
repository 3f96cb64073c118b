"""Counting midnights in file order (asterix.timeline): damaged records that walk count no midnight and
date no other report; real midnights, late reports and gaps across midnight are dated as before; any
cut into chunks (DayClock carried) or windows (stream.WindowClock) gives the same days. Times of day are
worked out by hand; the damaged run is benchmarks/fuzz_reader.py's seed 99 case 79 (the ADS-B fixture, a
block's tail overwritten with random bytes that walked as CAT021 records)."""

from __future__ import annotations

import numpy as np
import pytest

from msdc.asterix.stream import WindowClock
from msdc.asterix.timeline import DayClock, count_days, file_order_days

# the case's times of day in file order, in range 0-86400 s (those above 86400 are no times): real reports
# up to 29404 s, the walked garbage, the real reports again from 29427 s
REAL_BEFORE = [29396.977, 29398.117, 29398.867, 29399.945, 29400.727, 29401.352, 29402.164, 29402.227,
               29403.320, 29403.422, 29403.859, 29404.102, 29404.641]
GARBAGE = [31069.531, 51410.930, 52431.563, 82759.117, 16579.148, 34888.773, 37812.5, 53043.195, 38104.453]
REAL_AFTER = [29427.313, 29427.727, 29428.727, 29428.914, 29429.531, 29429.742, 29430.117, 29430.781]


def _days(tods, clock=None) -> np.ndarray:
    frames = {21: {"offset": np.arange(len(tods)), "time_of_day": np.asarray(tods, float)}}
    file_order_days(frames, clock)
    return frames[21]["day"]


def test_garbage_times_count_no_midnight():
    days = _days(REAL_BEFORE + GARBAGE + REAL_AFTER)
    real = np.r_[np.arange(len(REAL_BEFORE)), len(REAL_BEFORE) + len(GARBAGE) + np.arange(len(REAL_AFTER))]
    assert (days[real] == 0).all()  # a plain drop-count put the reports after 82759 -> 16579 on day 1


def test_a_real_midnight_a_late_report_and_a_gap_across_midnight():
    # 23:59:50 .. 23:59:59, then 00:00:00 .. 00:00:09: day 1 from midnight
    assert _days(list(86390.0 + np.arange(10)) + list(np.arange(10.0))).tolist() == [0] * 10 + [1] * 10
    # a report stamped 23:59:58 arriving after 00:00:05 is a late one from the day before
    assert _days([86395.0, 86397.0, 1.0, 3.0, 5.0, 86398.0, 7.0, 9.0]).tolist() == [0, 0, 1, 1, 1, 0, 1, 1]
    # a recording stopped at 22:00 and resumed at 02:00: every report after the gap on day 1, the first ones
    # too (dated against the last report before the gap, whom they do not agree with yet)
    before, after = 79200.0 + np.arange(12.0), 7200.0 + np.arange(12.0)
    assert _days(list(before) + list(after)).tolist() == [0] * 12 + [1] * 12


def test_invalid_times_take_the_day_of_the_valid_one_before():
    tods = [86398.0, 86399.0, np.nan, 0.5, np.nan, 1.5]
    assert _days(tods).tolist() == [0, 0, 0, 1, 1, 1]
    assert _days([np.nan, np.nan, 100.0, 101.0]).tolist() == [0, 0, 0, 0]  # at the start: the one after


def _sequence(seed: int) -> np.ndarray:
    """Two days of reports every 0.37 s with a real midnight, late reports, a gap, runs of random garbage
    and invalid times, in file order."""
    rng = np.random.default_rng(seed)
    t = (80000.0 + 0.37 * np.arange(60_000)) % 86400.0
    late = rng.choice(len(t), 40, replace=False)
    t[late] = (t[late] - rng.uniform(1, 30, 40)) % 86400.0
    for at in rng.choice(len(t) - 20, 30, replace=False):
        n = int(rng.integers(1, 15))
        t[at:at + n] = rng.uniform(0, 86400, n)
    t[rng.choice(len(t), 200, replace=False)] = np.nan
    return np.r_[t[:30_000], t[40_000:]]  # and an hour's gap


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_chunks_and_windows_continue_the_count_exactly(seed):
    t = _sequence(seed)
    whole = _days(t)
    assert set(np.unique(whole)) == {0, 1}
    rng = np.random.default_rng(seed)
    cuts = np.sort(rng.choice(np.arange(1, len(t)), 25, replace=False))
    clock, parts = None, []
    for piece in np.split(t, cuts):  # iter_read's chunks: each dated from the clock before it
        frames = {48: {"offset": np.arange(len(piece)), "time_of_day": piece}}
        clock = file_order_days(frames, clock)
        parts.append(frames[48]["day"])
    assert (np.concatenate(parts) == whole).all()
    # plan_windows' windows: the clock before each from the windows' summaries alone, as file_order_days
    valid = t[np.isfinite(t)]
    start = DayClock(0)
    _, want = count_days(valid, start)
    clock = start
    for piece in np.split(valid, cuts[cuts < len(valid)]):
        clock = WindowClock.of(piece, 0).after(clock)
    assert (clock.day, clock.ref_tod_s, clock.last_day) == (want.day, want.ref_tod_s, want.last_day)
    assert (clock.recent_s == want.recent_s).all()
