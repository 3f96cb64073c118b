"""Statistics that decide: exact binomial intervals for proportions, a bootstrap over aircraft for error
statistics, and the three-valued verdict (pass / fail / inconclusive) of an interval against a threshold."""

from __future__ import annotations

import math
import numbers
import re
from dataclasses import dataclass

import numpy as np
from scipy.special import betaincinv, chdtrc, gammaincinv, ndtri

from msdc.pipeline.evaluate.ranks import KeyRange, Parts, inverted_cdf_rank, lowest_reaching

DIRECTIONS = (">=", ">", "<=", "<")
VERDICTS = ("pass", "fail", "inconclusive")
N_BOOT = 2000
# below this many aircraft the bootstrap's 95 % intervals hold the truth clearly less often than 95 %
# (benchmarks/evaluate_statistics.py: RMS 0.88-0.92 over 10-20 aircraft, tail percentiles far less)
FEW_AIRCRAFT = 30
_PERCENTILE = re.compile(r"p(\d{1,2}(?:\.\d+)?)")
_CHUNK_CELLS = 4_000_000  # bootstrap replicates x aircraft drawn at once
_DRAWS_HELD = 64_000_000  # replicates x aircraft of a percentile's draws kept between passes (2 bytes each)


@dataclass(frozen=True)
class Proportion:
    """A proportion (successes / trials) with its exact two-sided interval; arrays when vectorised."""

    value: np.ndarray | float
    ci_low: np.ndarray | float
    ci_high: np.ndarray | float
    n: np.ndarray | int


@dataclass(frozen=True)
class ClusteredInterval:
    """An error statistic over reports, its bootstrap interval over clusters (aircraft), and the counts."""

    statistic: str
    value: float
    ci_low: float
    ci_high: float
    n: int
    n_clusters: int
    reason: str = ""


@dataclass(frozen=True)
class Verdict:
    """The verdict of an interval against a threshold, and why when it is not pass or fail outright."""

    verdict: str
    reason: str = ""


def _check_confidence(confidence: float) -> float:
    """The two-sided tail probability alpha of a confidence level strictly between 0 and 1."""
    if not isinstance(confidence, numbers.Real) or not 0.0 < float(confidence) < 1.0:
        raise ValueError(f"confidence must be a number strictly between 0 and 1, got {confidence!r}")
    return 1.0 - float(confidence)


def proportion(successes, trials, confidence: float = 0.95) -> Proportion:
    """Proportion successes/trials with its Clopper-Pearson interval (beta quantiles; lower bound exactly 0
    at 0 successes, upper exactly 1 at all successes); trials of 0 give NaN. Vectorised over arrays."""
    alpha = _check_confidence(confidence)
    k = np.asarray(successes)
    n = np.asarray(trials)
    for name, arr in (("successes", k), ("trials", n)):
        if arr.dtype.kind not in "iuf" or not np.all(np.isfinite(arr)) or np.any(arr < 0) \
                or np.any(arr != np.floor(arr)):
            raise ValueError(f"{name} must be whole numbers >= 0, got {arr!r}")
    if np.any(k > n):
        raise ValueError(f"successes must not exceed trials, got {k!r} of {n!r}")
    k, n = np.broadcast_arrays(k.astype(float), n.astype(float))
    with np.errstate(divide="ignore", invalid="ignore"):
        value = np.where(n > 0, k / np.where(n > 0, n, 1.0), np.nan)
        low = np.where(k > 0, betaincinv(np.maximum(k, 1), n - k + 1, alpha / 2), 0.0)
        high = np.where(k < n, betaincinv(k + 1, np.maximum(n - k, 1), 1 - alpha / 2), 1.0)
    low = np.where(n > 0, low, np.nan)
    high = np.where(n > 0, high, np.nan)
    if value.ndim == 0:
        return Proportion(float(value), float(low), float(high), int(n))
    return Proportion(value, low, high, n.astype(np.int64))


@dataclass(frozen=True)
class ShareClusters:
    """Sums over the clusters (groups of trials that are not independent: the reports of one aircraft in one
    update) that a proportion's design effect needs, additive over disjoint sets of clusters: the sums of
    m_c^2, y_c * m_c and y_c^2 (m_c trials and y_c successes of cluster c) and the number of clusters."""

    sum_m2: float
    sum_ym: float
    sum_y2: float
    clusters: int

    def __add__(self, other: ShareClusters) -> ShareClusters:
        return ShareClusters(self.sum_m2 + other.sum_m2, self.sum_ym + other.sum_ym,
                             self.sum_y2 + other.sum_y2, self.clusters + other.clusters)


def share_clusters(success: np.ndarray, cluster: np.ndarray) -> ShareClusters:
    """The ShareClusters of trials (``success``: bool per trial) grouped by ``cluster`` (a key per trial)."""
    if not len(success):
        return ShareClusters(0.0, 0.0, 0.0, 0)
    _, inverse = np.unique(np.asarray(cluster), return_inverse=True)
    m = np.bincount(inverse).astype(float)
    y = np.bincount(inverse, weights=np.asarray(success, float))
    return ShareClusters(float(m @ m), float(y @ m), float(y @ y), len(m))


def design_effect(successes: int, trials: int, sums: ShareClusters) -> float:
    """How much more a proportion varies over these clusters than over independent trials: the sum over
    clusters of (y_c - p m_c)^2 over that of the trials (n p (1 - p)), at least 1 (1 for single-trial
    clusters, 2 when every trial is doubled; 1 at p = 0 or 1)."""
    if trials <= 0 or successes <= 0 or successes >= trials or sums.clusters >= trials:
        return 1.0  # (as many clusters as trials: each of one trial, where rounding gave 1 + 1e-15)
    p = successes / trials
    spread = sums.sum_y2 - 2.0 * p * sums.sum_ym + p * p * sums.sum_m2
    return max(1.0, spread / (trials * p * (1.0 - p)))


def effective_proportion(successes: int, trials: int, deff: float, confidence: float = 0.95) -> Proportion:
    """successes/trials with the Clopper-Pearson interval of the effective sample (successes / deff of
    trials / deff: Korn and Graubard 1998), exactly ``proportion``'s at a design effect of 1."""
    if deff == 1.0:
        return proportion(successes, trials, confidence)
    alpha = _check_confidence(confidence)
    base = proportion(successes, trials, confidence)  # checks the counts
    k, n = successes / deff, trials / deff
    low = float(betaincinv(k, n - k + 1, alpha / 2)) if successes > 0 else 0.0
    high = float(betaincinv(k + 1, n - k, 1 - alpha / 2)) if successes < trials else 1.0
    return Proportion(base.value, low, high, base.n)


# The quantiles and tail below are scipy.special's functions that scipy.stats' beta.ppf, chi2.ppf, chi2.sf and
# norm.ppf evaluate (the same values, checked to the bit): scipy.stats costs 0.5-1 s to import in every
# process, a restarted worker's too.
Z975 = float(ndtri(0.975))  # the standard normal's 97.5 % point


def chi2_sf(q: float, dof: int) -> float:
    """P(chi-square with ``dof`` degrees of freedom > q), as scipy.stats.chi2.sf gives it (NaN for no
    degree of freedom)."""
    return float(chdtrc(dof, q)) if dof > 0 else math.nan


@dataclass(frozen=True)
class Rate:
    """Events per unit of exposure (e.g. false reports per antenna scan) with its exact Poisson interval."""

    value: np.ndarray | float
    ci_low: np.ndarray | float
    ci_high: np.ndarray | float
    n: np.ndarray | int


def inverse_variance(values, se, tau2: float = 0.0) -> tuple[float, float, float]:
    """Estimates with standard errors ``se`` combined by inverse variance: their mean, its standard error
    1 / sqrt(sum of weights), and Cochran's Q of their agreement; ``tau2`` (a variance between them, random
    effects) is added to each one's."""
    v = np.asarray(values, float)
    w = 1.0 / (np.square(np.asarray(se, float)) + tau2)
    mean = float(np.sum(w * v) / np.sum(w))
    return mean, float(1.0 / np.sqrt(np.sum(w))), float(np.sum(w * (v - mean) ** 2))


def poisson_rate(events, exposure, confidence: float = 0.95) -> Rate:
    """Rate events/exposure with the exact (Garwood) Poisson interval from chi-square quantiles: lower end
    exactly 0 at no events; an exposure of 0 gives NaN. For counts such as false reports per scan, where
    the events are many independent rare ones. Vectorised over arrays."""
    alpha = _check_confidence(confidence)
    k = np.asarray(events)
    t = np.asarray(exposure, dtype=float)
    if k.dtype.kind not in "iuf" or not np.all(np.isfinite(k)) or np.any(k < 0) or np.any(k != np.floor(k)):
        raise ValueError(f"events must be whole numbers >= 0, got {k!r}")
    if not np.all(np.isfinite(t)) or np.any(t < 0):
        raise ValueError(f"exposure must be finite and >= 0, got {t!r}")
    k, t = np.broadcast_arrays(k.astype(float), t)
    with np.errstate(divide="ignore", invalid="ignore"):
        safe = np.where(t > 0, t, 1.0)
        value = np.where(t > 0, k / safe, np.nan)
        low = np.where(k > 0, gammaincinv(np.maximum(k, 1), alpha / 2), 0.0) / safe  # chi2(2k) quantile / 2
        high = gammaincinv(k + 1, 1 - alpha / 2) / safe
    low, high = np.where(t > 0, low, np.nan), np.where(t > 0, high, np.nan)
    if value.ndim == 0:
        return Rate(float(value), float(low), float(high), int(k))
    return Rate(value, low, high, k.astype(np.int64))


def _percentile_level(statistic: str) -> float | None:
    """The percentile (0-100) a statistic name like 'p95' asks for; None for 'rms' and 'mean'."""
    if statistic in ("rms", "mean", "sd"):
        return None
    match = _PERCENTILE.fullmatch(statistic)
    if match is None or not 0.0 < float(match.group(1)) < 100.0:
        raise ValueError(f"statistic must be 'rms', 'mean', 'sd' or a percentile such as 'p95', "
                         f"got {statistic!r}")
    return float(match.group(1))


def _point(values: np.ndarray, statistic: str, level: float | None) -> float:
    """The statistic on the whole sample (percentiles by the inverted-CDF definition, as the bootstrap)."""
    if statistic == "rms":
        return float(np.sqrt(np.mean(values**2)))
    if statistic == "mean":
        return float(np.mean(values))
    if statistic == "sd":
        return float(np.std(values))
    return float(np.percentile(values, level, method="inverted_cdf"))


def clustered_interval(values, clusters, statistic: str, confidence: float = 0.95, n_boot: int = N_BOOT,
                       seed: int = 0) -> ClusteredInterval:
    """RMS, mean, SD (population form) or a percentile ('p95', 'p99') of per-report errors with a
    percentile bootstrap interval over clusters. Whole aircraft are resampled with replacement, because
    the reports of one aircraft share its errors (transponder delay, its own bias, its geometry) and are
    not independent samples: resampling single reports gives intervals far too narrow. Reproducible for a
    given seed; one cluster gives the value with a NaN interval, no values a NaN value, and fewer than
    FEW_AIRCRAFT aircraft an interval marked as too narrow (``reason`` says which)."""
    alpha = _check_confidence(confidence)
    level = _percentile_level(statistic)
    _check_boot(n_boot)
    x = np.asarray(values, dtype=float).ravel()
    groups = np.asarray(clusters).ravel()
    if x.size != groups.size:
        raise ValueError(f"values and clusters differ in length: {x.size} values, {groups.size} clusters")
    if not np.all(np.isfinite(x)):
        bad = int(np.sum(~np.isfinite(x)))
        raise ValueError(f"values hold {bad} NaN or infinite errors: drop them first")
    if x.size == 0:
        return ClusteredInterval(statistic, math.nan, math.nan, math.nan, 0, 0, "no reports")
    labels, cluster_of = np.unique(groups, return_inverse=True)
    n_clusters = labels.size
    value = _point(x, statistic, level)
    if n_clusters < 2:
        return ClusteredInterval(statistic, value, math.nan, math.nan, int(x.size), 1,
                                 "one aircraft: no interval over aircraft")
    counts = np.bincount(cluster_of, minlength=n_clusters).astype(float)
    if level is None:
        sums = np.bincount(cluster_of, weights=x, minlength=n_clusters)
        squares = np.bincount(cluster_of, weights=x**2, minlength=n_clusters)
        replicates = _moment_replicates(np.random.default_rng(seed), counts, sums, squares, statistic, n_boot)
        return _finished(statistic, value, replicates, alpha, int(x.size), n_clusters)
    replicates = percentile_replicates(lambda: iter([(x, cluster_of)]), counts, level, n_boot, seed)
    return _finished(statistic, value, replicates, alpha, int(x.size), n_clusters)


def percentile_replicates(parts: Parts, counts: np.ndarray, level: float, n_boot: int, seed: int,
                          keys: KeyRange | None = None, with_point: bool = False) -> np.ndarray:
    """A percentile's bootstrap replicates over clusters (``counts`` values each; ``parts`` give the values
    and their cluster's index): each replicate draws as many clusters as there are, with replacement, and
    takes the inverted-CDF percentile of the values so weighted (ranks.lowest_reaching, passing the draws
    in chunks). ``with_point``: the percentile of the values themselves first, found in the same passes."""
    n_clusters = counts.size
    rows = max(1, _CHUNK_CELLS // n_clusters)

    def drawn():
        rng = np.random.default_rng(seed)
        for start in range(0, n_boot, rows):
            yield cluster_draws(rng, n_clusters, min(rows, n_boot - start))

    # the draws kept between passes when they fit _DRAWS_HELD (as 16-bit counts: an aircraft is drawn at
    # most n_clusters times), else made again for each pass
    small = n_boot * n_clusters <= _DRAWS_HELD and n_clusters < 2**16
    kept = [d.astype(np.uint16) for d in drawn()] if small else None

    def draws():
        if with_point:
            yield np.ones((1, n_clusters))
        for d in kept if kept is not None else drawn():
            yield d.astype(float)

    total = np.concatenate([d @ counts for d in draws()])
    # the smallest value whose weight reaches the share q of the total (q * total within rounding of a whole
    # number is that number); the point's as numpy's percentile takes it
    q = level / 100.0
    targets = np.ceil(q * total - 1e-9 * total)
    if with_point:
        targets[0] = inverted_cdf_rank(int(counts.sum()), np.true_divide(level, 100)) + 1
    return lowest_reaching(parts, n_clusters, draws, targets, keys)


def cluster_draws(rng: np.random.Generator, n_clusters: int, rows: int) -> np.ndarray:
    """Bootstrap draws over clusters (rows, n_clusters): per row, how often each cluster is drawn when
    n_clusters are drawn uniformly with replacement (a uniform multinomial, counted from the draws
    themselves: five times faster than numpy's multinomial for hundreds of aircraft)."""
    picks = rng.integers(0, n_clusters, size=(rows, n_clusters))
    picks += np.arange(rows)[:, None] * n_clusters
    return np.bincount(picks.ravel(), minlength=rows * n_clusters).reshape(rows, n_clusters)


def _check_boot(n_boot: int) -> None:
    """ValueError unless n_boot is a whole number of at least 100 replicates."""
    if not isinstance(n_boot, int | np.integer) or n_boot < 100:
        raise ValueError(f"n_boot must be a whole number >= 100, got {n_boot!r}")


def _moment_replicates(rng: np.random.Generator, counts: np.ndarray, sums: np.ndarray, squares: np.ndarray,
                       statistic: str, n_boot: int) -> np.ndarray:
    """The bootstrap replicates of an RMS, mean or SD from each cluster's count, sum and sum of squares:
    whole clusters drawn with replacement, in chunks so that the draws stay bounded."""
    n_clusters = counts.size
    rows = max(1, _CHUNK_CELLS // n_clusters)
    replicates = []
    for start in range(0, n_boot, rows):
        draws = cluster_draws(rng, n_clusters, min(rows, n_boot - start)).astype(float)
        n = draws @ counts
        mean, square = (draws @ sums) / n, (draws @ squares) / n
        replicates.append({"mean": mean, "rms": np.sqrt(square),
                           "sd": np.sqrt(np.maximum(square - mean**2, 0.0))}[statistic])
    return np.concatenate(replicates)


def _finished(statistic: str, value: float, replicates: np.ndarray, alpha: float, n: int,
              n_clusters: int) -> ClusteredInterval:
    """The interval from the replicates' quantiles, marked too narrow below FEW_AIRCRAFT clusters."""
    low, high = np.quantile(replicates, [alpha / 2, 1 - alpha / 2])
    few = (f"with fewer than {FEW_AIRCRAFT} aircraft the interval over aircraft is too narrow (covers "
           "clearly less than 95 %)") if n_clusters < FEW_AIRCRAFT else ""
    return ClusteredInterval(statistic, value, float(low), float(high), n, int(n_clusters), few)


@dataclass(frozen=True)
class ClusterSums:
    """Per cluster (labels sorted): its reports, the sum and the sum of squares of their values: all an RMS,
    mean or SD and its bootstrap over clusters need, and what the windows of a span add up exactly."""

    labels: np.ndarray
    counts: np.ndarray
    sums: np.ndarray
    squares: np.ndarray

    @property
    def n(self) -> int:
        """The reports summed."""
        return int(self.counts.sum())


def cluster_sums(values, clusters) -> ClusterSums:
    """Each cluster's count, sum and sum of squares of ``values`` (finite), labels as text, sorted."""
    x = np.asarray(values, dtype=float).ravel()
    labels, cluster_of = np.unique(np.asarray(clusters).astype(str).ravel(), return_inverse=True)
    k = labels.size
    return ClusterSums(labels, np.bincount(cluster_of, minlength=k).astype(float),
                       np.bincount(cluster_of, weights=x, minlength=k),
                       np.bincount(cluster_of, weights=x**2, minlength=k))


def pooled_sums(parts) -> ClusterSums:
    """The cluster sums of several samples taken together (a cluster in several: its sums added)."""
    parts = list(parts)
    if not parts:
        return cluster_sums(np.zeros(0), np.zeros(0, dtype=str))
    labels, index = np.unique(np.concatenate([p.labels for p in parts]), return_inverse=True)

    def total(attr: str) -> np.ndarray:
        return np.bincount(index, weights=np.concatenate([getattr(p, attr) for p in parts]),
                           minlength=labels.size)

    return ClusterSums(labels, total("counts"), total("sums"), total("squares"))


def interval_from_sums(sums: ClusterSums, statistic: str, confidence: float = 0.95, n_boot: int = N_BOOT,
                       seed: int = 0) -> ClusteredInterval:
    """As clustered_interval for an RMS, mean or SD, from the clusters' sums alone: the same draws for the
    same seed and clusters, so equal to it on the same reports up to the order of summation."""
    alpha = _check_confidence(confidence)
    if _percentile_level(statistic) is not None:
        raise ValueError(f"a percentile ({statistic}) needs every value, not the clusters' sums")
    _check_boot(n_boot)
    n, n_clusters = sums.n, int(sums.labels.size)
    if n == 0:
        return ClusteredInterval(statistic, math.nan, math.nan, math.nan, 0, 0, "no reports")
    mean, square = float(sums.sums.sum()) / n, float(sums.squares.sum()) / n
    value = {"mean": mean, "rms": math.sqrt(square), "sd": math.sqrt(max(square - mean**2, 0.0))}[statistic]
    if n_clusters < 2:
        return ClusteredInterval(statistic, value, math.nan, math.nan, n, 1,
                                 "one aircraft: no interval over aircraft")
    replicates = _moment_replicates(np.random.default_rng(seed), sums.counts, sums.sums, sums.squares,
                                    statistic, n_boot)
    return _finished(statistic, value, replicates, alpha, n, n_clusters)


def magnitude_interval(ci_low: float, ci_high: float) -> tuple[float, float]:
    """The interval of |x| when x lies in [ci_low, ci_high]: for a signed bias judged by its size."""
    if math.isnan(ci_low) or math.isnan(ci_high):
        return math.nan, math.nan
    if ci_low > ci_high:
        raise ValueError(f"interval bounds reversed: low {ci_low!r} > high {ci_high!r}")
    if ci_low <= 0.0 <= ci_high:
        return 0.0, max(-ci_low, ci_high)
    return min(abs(ci_low), abs(ci_high)), max(abs(ci_low), abs(ci_high))


def _meets(x: float, threshold: float, direction: str) -> bool:
    """Whether the single value x meets the threshold in the given direction."""
    return {">=": x >= threshold, ">": x > threshold, "<=": x <= threshold, "<": x < threshold}[direction]


def verdict(ci_low: float, ci_high: float, threshold: float, direction: str, n: int | None = None,
            min_sample: int | None = None) -> Verdict:
    """'pass' when every value of the interval meets the threshold, 'fail' when none does, 'inconclusive'
    otherwise, and also when the interval is undefined or n is below the preset's minimum sample."""
    if direction not in DIRECTIONS:
        raise ValueError(f"direction must be one of {', '.join(DIRECTIONS)}, got {direction!r}")
    if not isinstance(threshold, numbers.Real) or isinstance(threshold, bool) or not math.isfinite(threshold):
        raise ValueError(f"threshold must be a finite number, got {threshold!r}")
    if ci_low is None or ci_high is None or math.isnan(ci_low) or math.isnan(ci_high):
        return Verdict("inconclusive", "interval undefined (no sample, or one aircraft)")
    if ci_low > ci_high:
        raise ValueError(f"interval bounds reversed: low {ci_low!r} > high {ci_high!r}")
    # the interval is convex, so its two ends decide for all its values
    low_meets, high_meets = _meets(ci_low, threshold, direction), _meets(ci_high, threshold, direction)
    outcome = "pass" if low_meets and high_meets else "fail" if not (low_meets or high_meets) else ""
    if min_sample is not None and (n is None or n < min_sample):
        said = {"pass": "meets", "fail": "misses", "": "straddles"}[outcome]
        said = f"interval {said} the threshold"
        return Verdict("inconclusive", f"n = {n} below the minimum sample {min_sample} ({said})")
    if not outcome:
        return Verdict("inconclusive", f"interval [{ci_low:.6g}, {ci_high:.6g}] straddles {threshold:g}")
    return Verdict(outcome)
