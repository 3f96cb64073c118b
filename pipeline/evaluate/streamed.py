"""A long span's percentiles, their bootstrap over aircraft and its error bands from the parts its windows
wrote to disk, in passes over them (ranks.lowest_reaching), with the figures that sorting every value at
once gives: memory bounded by a part, whatever the span (docs/guide/evaluate.md, "A long span")."""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator

import numpy as np
import pandas as pd

from msdc.pipeline.evaluate.ranks import (
    KeyRange,
    interpolated,
    inverted_cdf_rank,
    linear_ranks,
    lowest_reaching,
)
from msdc.pipeline.evaluate.statistics import (
    N_BOOT,
    ClusteredInterval,
    _check_boot,
    _check_confidence,
    _finished,
    _percentile_level,
    percentile_replicates,
)


def streamed_interval(parts: Callable[[], Iterator[tuple[np.ndarray, np.ndarray]]], statistic: str,
                      confidence: float = 0.95, n_boot: int = N_BOOT, seed: int = 0) -> ClusteredInterval:
    """statistics.clustered_interval of a percentile over every part's values (each part: values and their
    aircraft's labels) without holding them together: the same value and interval, bit for bit, from the
    aircraft's counts and passes of ranks.lowest_reaching."""
    alpha = _check_confidence(confidence)
    level = _percentile_level(statistic)
    if level is None:
        raise ValueError(f"{statistic}: only a percentile is pooled in passes (a mean, RMS or SD from each "
                         "aircraft's sums)")
    _check_boot(n_boot)
    per_label = pd.Series(dtype=float)
    keys = KeyRange()
    for values, labels in parts():
        x = np.asarray(values, dtype=float)
        if not np.all(np.isfinite(x)):
            raise ValueError(f"values hold {int(np.sum(~np.isfinite(x)))} NaN or infinite errors: drop them "
                             "first")
        keys.add(x)
        c = pd.Categorical(labels)
        counted = pd.Series(np.bincount(c.codes, minlength=len(c.categories)).astype(float),
                            index=pd.Index(np.asarray(c.categories, dtype=object), dtype=object))
        per_label = per_label.add(counted, fill_value=0)
    per_label = per_label[per_label > 0].sort_index()
    n, n_clusters = int(per_label.sum()), per_label.size
    if n == 0:
        return ClusteredInterval(statistic, math.nan, math.nan, math.nan, 0, 0, "no reports")
    index = pd.Index(per_label.index)
    counts = per_label.to_numpy(float)

    def grouped() -> Iterator[tuple[np.ndarray, np.ndarray]]:
        for values, labels in parts():
            c = pd.Categorical(labels)
            known = index.get_indexer(np.asarray(c.categories, dtype=object))
            yield np.asarray(values, dtype=float), known[c.codes]

    if n_clusters < 2:
        point = lowest_reaching(grouped, 1, lambda: iter([np.ones((1, 1))]),
                                np.array([inverted_cdf_rank(n, np.true_divide(level, 100)) + 1.0]), keys)
        return ClusteredInterval(statistic, float(point[0]), math.nan, math.nan, n, 1,
                                 "one aircraft: no interval over aircraft")
    found = percentile_replicates(grouped, counts, level, n_boot, seed, keys, with_point=True)
    return _finished(statistic, float(found[0]), found[1:], alpha, n, n_clusters)


def streamed_error_bands(parts: Callable[[], Iterator[pd.DataFrame]], step_nm: float) -> pd.DataFrame:
    """accuracy.error_bands of every part's judged errors (range_nm, aircraft, error_m) without holding
    them together: reports, aircraft, 95th percentile and maximum as error_bands gives them; the RMS summed
    part by part (equal to within the order of summation)."""
    columns = ["low_nm", "high_nm", "reports", "aircraft", "rms_m", "p95_m", "max_m"]
    reports: dict[int, int] = {}
    squares: dict[int, float] = {}
    largest: dict[int, float] = {}
    seen: set[tuple[int, str]] = set()
    keys = KeyRange()
    for frame in parts():
        band = np.floor(frame["range_nm"].to_numpy(float) / step_nm).astype(np.int64)
        error = frame["error_m"].to_numpy(float)
        if not np.all(np.isfinite(error)):
            raise ValueError(f"judged errors hold {int(np.sum(~np.isfinite(error)))} NaN or infinite values")
        keys.add(error)
        by = pd.DataFrame({"band": band, "square": error**2, "error": error})
        summed = by.groupby("band").agg(n=("error", "size"), square=("square", "sum"), top=("error", "max"))
        for k, row in summed.iterrows():
            reports[k] = reports.get(k, 0) + int(row["n"])
            squares[k] = squares.get(k, 0.0) + float(row["square"])
            largest[k] = max(largest.get(k, -math.inf), float(row["top"]))
        pairs = pd.DataFrame({"band": band, "aircraft": frame["aircraft"].astype(str).to_numpy(object)})
        seen |= set(pairs.drop_duplicates().itertuples(index=False, name=None))
    if not reports:
        return pd.DataFrame(columns=columns)
    bands = np.array(sorted(reports), dtype=np.int64)
    ranks = [linear_ranks(reports[k], np.true_divide(95, 100)) for k in bands.tolist()]

    def grouped() -> Iterator[tuple[np.ndarray, np.ndarray]]:
        for frame in parts():
            band = np.floor(frame["range_nm"].to_numpy(float) / step_nm).astype(np.int64)
            yield frame["error_m"].to_numpy(float), np.searchsorted(bands, band)

    one_hot = np.repeat(np.eye(bands.size), 2, axis=0)
    targets = np.array([r + 1.0 for a, b, _ in ranks for r in (a, b)])
    ends = lowest_reaching(grouped, bands.size, lambda: iter([one_hot]), targets, keys).reshape(-1, 2)
    aircraft = pd.Series([b for b, _ in seen]).value_counts()
    rows = [(k * step_nm, (k + 1) * step_nm, reports[k], int(aircraft[k]),
             math.sqrt(squares[k] / reports[k]), interpolated(a, b, t), largest[k])
            for k, (a, b), (_, _, t) in zip(bands.tolist(), ends.tolist(), ranks, strict=True)]
    return pd.DataFrame(rows, columns=columns)


__all__ = ["streamed_error_bands", "streamed_interval"]
