"""Order statistics found in passes over parts, against the other ways to the same figures: numpy's own
percentiles, sorting every value and adding the weights up by hand, statistics.clustered_interval on the
values together (its weighted CDFs over every value sorted) and accuracy.error_bands on one frame. Small
ranges and bins force many passes."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

import msdc.pipeline.evaluate.streamed as streamed
from msdc.pipeline.evaluate.accuracy import error_bands
from msdc.pipeline.evaluate.statistics import clustered_interval

# (values read whole at most, bins a range is cut into): the module's own, then small enough for many passes
CUTS = [(streamed.COLLECT_VALUES, streamed.BINS), (40, 4), (3, 2)]


@pytest.fixture(params=CUTS, ids=["as-built", "small", "bisection"])
def cuts(request, monkeypatch):
    collect, bins = request.param
    monkeypatch.setattr(streamed, "COLLECT_VALUES", collect)
    monkeypatch.setattr(streamed, "BINS", bins)
    return request.param


def test_keys_order_floats_as_the_floats_and_give_them_back():
    tiny = np.nextafter(0.0, 1.0)
    x = np.array([-np.finfo(float).max, -1e300, -2.5, -tiny, -0.0, 0.0, tiny, 1e-310, 1.0,
                  np.nextafter(1.0, 2.0), 7.25e12, np.finfo(float).max])
    keys = streamed.float_keys(x)
    assert np.all(np.diff(keys[x != 0]) > 0) and keys[4] == keys[5]  # -0.0 and 0.0 are one value
    back = streamed.key_values(keys)
    assert back.view(np.int64).tolist() == (x + 0.0).view(np.int64).tolist()
    rng = np.random.default_rng(2)
    y = rng.standard_cauchy(5000) * 10.0 ** rng.integers(-300, 300, 5000)
    assert np.array_equal(np.sort(y), streamed.key_values(np.sort(streamed.float_keys(y))))


@pytest.mark.parametrize("level", [1.0, 33.3, 50.0, 90.0, 95.0, 99.0, 99.9])
def test_the_rank_of_an_inverted_cdf_is_numpys(level):
    for n in range(1, 1200):
        q = np.true_divide(level, 100)
        assert streamed.inverted_cdf_rank(n, q) == np.percentile(np.arange(n), level, method="inverted_cdf")


def test_the_linear_percentile_from_its_two_ranks_is_numpys():
    rng = np.random.default_rng(3)
    for n in range(1, 600):
        x = np.sort(rng.gamma(2.0, 40.0, n))
        a, b, t = streamed.linear_ranks(n, np.true_divide(95, 100))
        assert streamed.interpolated(x[a], x[b], t) == np.percentile(x, 95)


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
    got = streamed.lowest_reaching(lambda: iter(parts), 7, blocks, targets)
    assert got.tolist() == _by_sorting(parts, weights, targets).tolist()


def test_one_value_many_times_is_found_in_one_pass_and_no_value_is_an_error(cuts):
    parts = [(np.full(500, 12.5), np.zeros(500, dtype=int))]
    assert streamed.lowest_reaching(lambda: iter(parts), 1, lambda: iter([np.ones((2, 1))]),
                                    np.array([1.0, 500.0])).tolist() == [12.5, 12.5]
    with pytest.raises(ValueError, match="no values"):
        streamed.lowest_reaching(lambda: iter([]), 1, lambda: iter([np.ones((1, 1))]), np.array([1.0]))


def _windows(rng, ties=False):
    """Errors and aircraft of five windows: text in some, categoricals with categories unused in others."""
    names = [f"A{k:03d}" for k in range(45)]
    out = []
    for size in (700, 0, 350, 900, 40):
        values = rng.gamma(2.0, 40.0, size)
        if ties:
            values = np.round(values)
        aircraft = rng.choice(names[: rng.integers(30, 45)], size)
        out.append((values, aircraft if size % 2 else pd.Categorical(aircraft, categories=names[::-1])))
    return out


@pytest.mark.parametrize("statistic", ["p95", "p99", "p50"])
@pytest.mark.parametrize("ties", [False, True], ids=["distinct", "ties"])
def test_a_percentile_and_its_interval_in_passes_are_those_of_every_value_together(cuts, statistic, ties):
    windows = _windows(np.random.default_rng(7), ties)
    values = np.concatenate([v for v, _ in windows])
    aircraft = np.concatenate([np.asarray(a, dtype=object) for _, a in windows])
    direct = clustered_interval(values, aircraft, statistic, seed=4)
    got = streamed.streamed_interval(lambda: iter(windows), statistic, seed=4)
    assert got == direct
    assert direct.n == 1990 and math.isfinite(direct.ci_low) and direct.ci_low < direct.ci_high


def test_one_aircraft_no_values_and_bad_values_as_together():
    one = [(np.array([3.0, 1.0, 2.0]), np.array(["K1"] * 3))]
    assert streamed.streamed_interval(lambda: iter(one), "p95") == clustered_interval(
        one[0][0], one[0][1], "p95")
    empty = [(np.zeros(0), np.array([], dtype=object))]
    assert streamed.streamed_interval(lambda: iter(empty), "p95") == clustered_interval([], [], "p95")
    with pytest.raises(ValueError, match="1 NaN or infinite"):
        streamed.streamed_interval(lambda: iter([(np.array([1.0, np.inf]), np.array(["a", "b"]))]), "p95")
    with pytest.raises(ValueError, match="only a percentile"):
        streamed.streamed_interval(lambda: iter(one), "rms")


def test_error_bands_in_passes_are_those_of_one_frame(cuts):
    rng = np.random.default_rng(9)
    frames = []
    for values, aircraft in _windows(rng):
        frames.append(pd.DataFrame({"range_nm": rng.uniform(0.0, 95.0, values.size),
                                    "aircraft": pd.Categorical(np.asarray(aircraft, dtype=object)),
                                    "error_m": values}))
    direct = error_bands(pd.concat(frames, ignore_index=True))
    got = streamed.streamed_error_bands(lambda: iter(frames), 10.0)
    exact = ["low_nm", "high_nm", "reports", "aircraft", "p95_m", "max_m"]
    pd.testing.assert_frame_equal(got[exact], direct[exact], check_exact=True)
    assert np.allclose(got["rms_m"], direct["rms_m"], rtol=1e-13, atol=0.0)  # summed in another order
    assert len(direct) == 10
