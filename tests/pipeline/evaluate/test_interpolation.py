"""A reference aircraft's samples at report times (evaluate.reference.Trajectory.at, its numba kernel):
checked against numpy's own linear interpolation and by hand."""

import numpy as np
import pytest

from msdc.pipeline.evaluate.reference import Trajectory


def _trajectory(t, lat, lon, h, alt) -> Trajectory:
    arrays = [np.asarray(v, float) for v in (t, lat, lon, h, alt)]
    return Trajectory("a", *arrays, np.arange(len(arrays[0])))


def test_between_samples_the_values_are_numpys_linear_interpolation():
    rng = np.random.default_rng(7)
    t = np.sort(rng.choice(np.arange(0.0, 500.0, 0.25), 60, replace=False))
    lat, lon = rng.uniform(40, 41, 60), rng.uniform(2, 3, 60)
    h, alt = rng.uniform(0, 1e4, 60), rng.uniform(0, 4e4, 60)
    q = rng.uniform(t[0], t[-1], 500)
    got = _trajectory(t, lat, lon, h, alt).at(q, 1e9)
    for v, g in zip((lat, lon, h, alt), got, strict=True):
        np.testing.assert_allclose(g, np.interp(q, t, v), rtol=0, atol=1e-9)


def test_outside_the_samples_across_a_long_gap_and_without_a_time_nothing_is_known():
    tr = _trajectory([0, 10, 100, 110], [1, 2, 3, 4], [1, 2, 3, 4], [0, 0, 0, 0], [0, 0, 0, 0])
    lat = tr.at(np.array([-1.0, 5.0, 50.0, 105.0, 111.0, np.nan]), 30.0)[0]
    np.testing.assert_array_equal(lat, [np.nan, 1.5, np.nan, 3.5, np.nan, np.nan])


def test_on_a_sample_its_own_value_even_beside_a_long_gap_and_at_the_last():
    tr = _trajectory([0, 10, 100], [1, 2, 3], [5, 6, 7], [8, 9, 10], [11, np.nan, 13])
    lat, lon, h, alt = tr.at(np.array([10.0, 100.0]), 30.0)
    np.testing.assert_array_equal(lat, [2, 3])
    np.testing.assert_array_equal(lon, [6, 7])
    np.testing.assert_array_equal(h, [9, 10])
    np.testing.assert_array_equal(alt, [np.nan, 13])


def test_a_longitude_goes_the_short_way_round_across_the_antimeridian():
    tr = _trajectory([0, 10], [0, 0], [179.0, -179.0], [0, 0], [0, 0])
    lon = tr.at(np.array([5.0, 2.5]), 30.0)[1]
    assert lon[0] == pytest.approx(180.0)  # 179 + 0.5 * 2, not 179 - 0.5 * 358
    assert lon[1] == pytest.approx(179.5)


def test_a_single_sample_is_known_at_its_time_only():
    tr = _trajectory([5.0], [1.0], [2.0], [3.0], [4.0])
    lat = tr.at(np.array([4.0, 5.0, 6.0]), 30.0)[0]
    np.testing.assert_array_equal(lat, [np.nan, 1.0, np.nan])
