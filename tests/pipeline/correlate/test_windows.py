"""Tracking segments, overlap windows and the short-window rule."""

import numpy as np

from msdc.pipeline.correlate.windows import in_window, overlap_windows, segments, short_window_reason


def test_gap_of_180_s_keeps_one_segment_181_splits():
    assert segments([0.0, 180.0, 190.0], gap_s=180) == [(0.0, 190.0)]
    assert segments([0.0, 181.0, 190.0], gap_s=180) == [(0.0, 0.0), (181.0, 190.0)]


def test_segments_sort_and_skip_nan():
    assert segments([50.0, np.nan, 10.0, 400.0, 30.0]) == [(10.0, 50.0), (400.0, 400.0)]
    assert segments([]) == []


def test_segments_span_midnight():
    # day 0 at 86390 s, then day 1 at 00:00:05 -> 86405: 15 s apart, one segment across 86400
    times = np.array([0, 0, 1, 1]) * 86400 + np.array([86380.0, 86390.0, 5.0, 20.0])
    assert segments(times) == [(86380.0, 86420.0)]


def test_overlap_windows_every_pair():
    radar = [0.0, 50.0, 100.0, 400.0, 450.0, 500.0]  # segments [0, 100], [400, 500]
    adsb = [50.0, 200.0, 300.0, 450.0, 1000.0]  # segments [50, 450], [1000, 1000]
    assert overlap_windows(radar, adsb, 180) == [(50.0, 100.0), (400.0, 450.0)]
    assert overlap_windows([0.0, 10.0], [20.0, 30.0], 180) == []
    assert overlap_windows([0.0, 10.0], [10.0, 30.0], 180) == [(10.0, 10.0)]


def test_short_window_and_truncation():
    assert short_window_reason(0.0, 9.9, 10.0) is not None
    assert short_window_reason(0.0, 10.0, 10.0) is None
    assert in_window([4.0, 5.0, 7.0, 9.0, 9.5], 5.0, 9.0).tolist() == [False, True, True, True, False]
