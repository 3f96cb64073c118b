"""A span's percentile, its interval and its error bands pooled in passes over parts, against the same
figures on the values together: statistics.clustered_interval and accuracy.error_bands on one frame. Small
ranges and bins force many passes."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

import msdc.pipeline.evaluate.streamed as streamed
from msdc.pipeline.evaluate.accuracy import error_bands
from msdc.pipeline.evaluate.statistics import clustered_interval


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


def test_values_read_whole_in_one_range_take_two_passes_the_point_with_the_replicates():
    """Fewer values than a range reads whole: one pass counts the aircraft (and the values' range), one more
    sorts them and finds the percentile and every replicate together."""
    windows = _windows(np.random.default_rng(7))
    passes = []

    def parts():
        passes.append(1)
        return iter(windows)

    streamed.streamed_interval(parts, "p95")
    assert len(passes) == 2


def test_error_bands_refuse_values_they_cannot_order():
    frame = pd.DataFrame({"range_nm": [5.0, 15.0], "aircraft": ["a", "b"], "error_m": [3.0, np.nan]})
    with pytest.raises(ValueError, match="1 NaN or infinite"):
        streamed.streamed_error_bands(lambda: iter([frame]), 10.0)
