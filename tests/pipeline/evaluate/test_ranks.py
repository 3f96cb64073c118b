"""Order statistics found in passes (ranks), against numpy's own percentiles and against sorting every value
and adding the weights up by hand. Small ranges and bins force many passes."""

from __future__ import annotations

import numpy as np
import pytest

from msdc.pipeline.evaluate import ranks


def test_keys_order_floats_as_the_floats_and_give_them_back():
    tiny = np.nextafter(0.0, 1.0)
    x = np.array([-np.finfo(float).max, -1e300, -2.5, -tiny, -0.0, 0.0, tiny, 1e-310, 1.0,
                  np.nextafter(1.0, 2.0), 7.25e12, np.finfo(float).max])
    keys = ranks.float_keys(x)
    assert np.all(np.diff(keys[x != 0]) > 0) and keys[4] == keys[5]  # -0.0 and 0.0 are one value
    back = ranks.key_values(keys)
    assert back.view(np.int64).tolist() == (x + 0.0).view(np.int64).tolist()
    rng = np.random.default_rng(2)
    y = rng.standard_cauchy(5000) * 10.0 ** rng.integers(-300, 300, 5000)
    assert np.array_equal(np.sort(y), ranks.key_values(np.sort(ranks.float_keys(y))))


@pytest.mark.parametrize("level", [1.0, 33.3, 50.0, 90.0, 95.0, 99.0, 99.9])
def test_the_rank_of_an_inverted_cdf_is_numpys(level):
    for n in range(1, 1200):
        q = np.true_divide(level, 100)
        assert ranks.inverted_cdf_rank(n, q) == np.percentile(np.arange(n), level, method="inverted_cdf")


def test_the_linear_percentile_from_its_two_ranks_is_numpys():
    rng = np.random.default_rng(3)
    for n in range(1, 600):
        x = np.sort(rng.gamma(2.0, 40.0, n))
        a, b, t = ranks.linear_ranks(n, np.true_divide(95, 100))
        assert ranks.interpolated(x[a], x[b], t) == np.percentile(x, 95)


def _parts(rng, sizes, n_groups, ties):
    out = []
    for size in sizes:
        values = rng.standard_t(3, size) * 40.0
        if ties:
            values = np.round(values / 10.0) * 10.0
        out.append((values, rng.integers(0, n_groups, size)))
    return out


def _by_sorting(parts, weights, targets):
    """Every value sorted, each row's weights added along them: where they first reach its target."""
    values = np.concatenate([v for v, _ in parts])
    groups = np.concatenate([g for _, g in parts])
    order = np.argsort(values, kind="stable")
    out = []
    for w, t in zip(weights, targets, strict=True):
        cum = np.cumsum(w[groups[order]])
        out.append(values[order][np.searchsorted(cum, t)])
    return np.array(out)


@pytest.mark.parametrize("ties", [False, True], ids=["distinct", "ties"])
def test_each_rows_value_is_where_its_weights_reach_the_target(cuts, ties):
    rng = np.random.default_rng(11)
    parts = _parts(rng, [300, 0, 1, 450, 200], 7, ties)
    counts = np.bincount(np.concatenate([g for _, g in parts]), minlength=7)
    weights = rng.integers(0, 4, (30, 7)).astype(float)
    weights[0], weights[1] = 1.0, np.eye(7)[3]  # every value alike; one group's values only
    totals = weights @ counts
    targets = np.array([rng.integers(1, t + 1) for t in totals], dtype=float)
    targets[2:4] = 1.0, totals[3]  # the smallest and the largest of a row's values
    blocks = lambda: iter([weights[:11], weights[11:12], weights[12:]])  # noqa: E731
    got = ranks.lowest_reaching(lambda: iter(parts), 7, blocks, targets)
    assert got.tolist() == _by_sorting(parts, weights, targets).tolist()


def test_one_value_many_times_is_that_value_and_no_value_is_an_error(cuts):
    parts = [(np.full(500, 12.5), np.zeros(500, dtype=int))]
    assert ranks.lowest_reaching(lambda: iter(parts), 1, lambda: iter([np.ones((2, 1))]),
                                 np.array([1.0, 500.0])).tolist() == [12.5, 12.5]
    with pytest.raises(ValueError, match="no values"):
        ranks.lowest_reaching(lambda: iter([]), 1, lambda: iter([np.ones((1, 1))]), np.array([1.0]))
