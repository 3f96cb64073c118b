"""Slot assignment, per-slot means (latitude and longitude across +-180) and filling of empty slots."""

import numpy as np
import pandas as pd
import pytest

from msdc.pipeline.correlate.slots import slot_count, slot_index, slot_window


def meas(times, lat, lon):
    return pd.DataFrame({"time_of_day": np.asarray(times, float), "latitude": np.asarray(lat, float),
                         "longitude": np.asarray(lon, float)})


def test_slot_count_formula():
    # N = floor((end - start) / D) + 1: 95 s / 10 s -> floor 9.5 = 9 -> 10 slots; 100 s -> 11; 0 s -> 1
    assert slot_count(1000.0, 1095.0, 10.0) == 10
    assert slot_count(1000.0, 1100.0, 10.0) == 11
    assert slot_count(1000.0, 1000.0, 10.0) == 1


def test_slot_edges():
    # start + k D <= t < start + (k+1) D
    assert slot_index([0.0, 9.999, 10.0, 19.0, 20.0], 0.0, 10.0).tolist() == [0, 0, 1, 1, 2]
    # the defining inequality holds exactly as evaluated in floating point, even for awkward values
    rng = np.random.default_rng(0)
    start, d = 0.1, 0.2
    t = start + rng.integers(0, 1000, 2000) * d + rng.choice([0.0, 1e-12, -1e-12], 2000)
    t = t[t >= start]
    k = slot_index(t, start, d)
    assert np.all(start + k * d <= t) and np.all(t < start + (k + 1) * d)


def test_slot_means_counts_and_filling():
    # window [100, 150], D = 10 -> N = 6 slots starting 100, 110, ..., 150
    m = meas([112.0, 115.0, 118.0, 131.0, 150.0], [1.0, 2.0, 6.0, 4.0, 5.0], [10.0, 20.0, 30.0, 40.0, 50.0])
    out = slot_window(m, 100.0, 150.0, 10.0)
    assert out["slot"].tolist() == [0, 1, 2, 3, 4, 5]
    assert out["time_of_day"].tolist() == [100.0, 110.0, 120.0, 130.0, 140.0, 150.0]
    assert out["count"].tolist() == [0, 3, 0, 1, 0, 1]  # t = end falls in the last slot
    assert out["filled"].tolist() == [True, False, True, False, True, False]
    # slot 1: mean(1, 2, 6) = 3, mean(10, 20, 30) = 20; slot 0 takes slot 1 (first non-empty),
    # slot 2 repeats slot 1, slot 4 repeats slot 3
    assert out["latitude"].tolist() == pytest.approx([3.0, 3.0, 3.0, 4.0, 4.0, 5.0])
    assert out["longitude"].tolist() == pytest.approx([20.0, 20.0, 20.0, 40.0, 40.0, 50.0])


def test_measurements_outside_the_window_are_ignored():
    m = meas([95.0, 100.0, 120.0, 120.5], [9.0, 1.0, 3.0, 9.0], [0.0, 0.0, 0.0, 0.0])
    out = slot_window(m, 100.0, 120.0, 10.0)
    assert out["count"].tolist() == [1, 0, 1]
    assert out["latitude"].tolist() == [1.0, 1.0, 3.0]


def test_longitude_mean_across_antimeridian():
    # mean of 179.9 and -179.9 is the antimeridian, not 0
    out = slot_window(meas([0.0, 1.0], [0.0, 0.0], [179.9, -179.9]), 0.0, 5.0, 10.0)
    assert abs(out.loc[0, "longitude"]) == pytest.approx(180.0)
    # 179.8 and -179.6 -> 180.1 -> -179.9
    out = slot_window(meas([0.0, 1.0], [0.0, 0.0], [179.8, -179.6]), 0.0, 5.0, 10.0)
    assert out.loc[0, "longitude"] == pytest.approx(-179.9)


def test_window_across_midnight():
    # times past 86400 (day 1) continue the same window: [86395, 86415] -> 3 slots
    times = np.array([0, 1, 1]) * 86400 + np.array([86396.0, 6.0, 15.0])
    out = slot_window(meas(times, [1.0, 2.0, 3.0], [0.0, 0.0, 0.0]), 86395.0, 86415.0, 10.0)
    assert out["count"].tolist() == [1, 1, 1]
    assert out["latitude"].tolist() == [1.0, 2.0, 3.0]
