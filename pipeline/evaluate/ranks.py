"""Order statistics found in passes over values given in parts: the smallest value at which each of many
weighted counts (rows of whole-number weights per group of values) reaches its target. A bootstrap's
percentiles over aircraft are such rows (each aircraft's draws its weight), and a long span's values need
not be held together to find them (streamed)."""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator

import numpy as np
from scipy import sparse

# a range of keys holding at most this many values is read whole and sorted; a larger one is cut into BINS
# ranges counted for the next pass: a pass holds BINS counts per group and range, and this many values a range
COLLECT_VALUES = 1 << 16
BINS = 256
_CODES_HELD = 2_000_000  # (bin, group) counts gathered before they are added up
_CELLS = 4_000_000  # rows x values weighed at once among a range's values read whole
_LOW_BITS = np.int64(0x7FFF_FFFF_FFFF_FFFF)

# one pass over the values: their parts in order, each as (values, group of each value from 0)
Parts = Callable[[], Iterator[tuple[np.ndarray, np.ndarray]]]
# one pass over the weights: blocks of rows (rows x groups, whole numbers as floats), the rows in order
Weights = Callable[[], Iterator[np.ndarray]]


class KeyRange:
    """The smallest and largest key of values seen part by part, and how many there were."""

    def __init__(self) -> None:
        self.low, self.high, self.n = 0, 0, 0

    def add(self, values: np.ndarray) -> None:
        if len(values):
            keys = float_keys(values)
            low, high = int(keys.min()), int(keys.max())
            self.low, self.high = (low, high) if not self.n else (min(self.low, low), max(self.high, high))
            self.n += len(values)


def float_keys(values: np.ndarray) -> np.ndarray:
    """Whole numbers ordered as the finite floats ``values`` are (-0.0 as 0.0): their bits, the negative
    ones' magnitude bits flipped."""
    bits = (np.asarray(values, dtype=np.float64) + 0.0).view(np.int64)
    return np.where(bits < 0, bits ^ _LOW_BITS, bits)


def key_values(keys: np.ndarray) -> np.ndarray:
    """The floats of float_keys' keys."""
    keys = np.asarray(keys, dtype=np.int64)
    return np.where(keys < 0, keys ^ _LOW_BITS, keys).view(np.float64)


def lowest_reaching(parts: Parts, n_groups: int, weights: Weights, targets: np.ndarray,
                    keys: KeyRange | None = None) -> np.ndarray:
    """Per row r of the weights, the smallest value v of the parts' at which the weights of the values up to
    v (W[r, group of the value]) add up to targets[r] (> 0, at most the row's total): the order statistic
    an inverted CDF picks. Each pass cuts every row's range of keys into BINS and keeps the bin it ends in,
    until the range holds one value or at most COLLECT_VALUES, then sorts those. ``keys``, when the caller
    has read them, saves the first pass."""
    targets = np.asarray(targets, dtype=float)
    rows = targets.size
    if keys is None:
        keys = KeyRange()
        for values, _ in parts():
            keys.add(values)
    low, high, n = keys.low, keys.high, keys.n
    if n == 0:
        raise ValueError("no values to take an order statistic of")
    lo = np.full(rows, low, dtype=np.int64)
    hi = np.full(rows, high, dtype=np.int64)
    base = np.zeros(rows)          # each row's weight below its range
    count = np.full(rows, n, dtype=np.int64)  # the values in its range
    answer = np.zeros(rows, dtype=np.int64)
    done = lo == hi
    answer[done] = lo[done]
    while not done.all():
        jobs = _Jobs(lo[~done], hi[~done], count[~done])
        held = jobs.read(parts, n_groups)
        offset = 0
        for block in weights():
            r = np.arange(offset, offset + block.shape[0])
            offset += block.shape[0]
            todo = r[~done[r]]
            job_of = jobs.job_of(lo[todo])
            for job in np.unique(job_of):
                mine = todo[job_of == job]
                w = block[mine - r[0]]
                if jobs.collect[job]:
                    answer[mine] = _collected(held[job], w, base[mine], targets[mine], lo[mine[0]])
                    done[mine] = True
                else:
                    _narrowed(jobs, held[job], job, w, mine, targets, lo, hi, base, count)
                    ends = mine[lo[mine] == hi[mine]]
                    answer[ends], done[ends] = lo[ends], True
        if offset != rows:
            raise ValueError(f"the weights have {offset} rows, the targets {rows}")
    return key_values(answer)


class _Jobs:
    """The distinct key ranges the rows are in (disjoint: each is a bin of the pass before), each either
    counted in BINS bins per group or, when small, read whole."""

    def __init__(self, lo: np.ndarray, hi: np.ndarray, count: np.ndarray) -> None:
        pairs = np.unique(np.stack([lo, hi], axis=1), axis=0)
        self.lo, self.hi = pairs[:, 0], pairs[:, 1]
        counts = {(a, b): c for a, b, c in zip(lo.tolist(), hi.tolist(), count.tolist(), strict=True)}
        self.collect = np.array([counts[(a, b)] <= COLLECT_VALUES for a, b in pairs.tolist()], dtype=bool)
        lowers, uppers, self.first = [], [], []
        for a, b, whole in zip(self.lo.tolist(), self.hi.tolist(), self.collect.tolist(), strict=True):
            self.first.append(len(lowers))
            edges = [a, b + 1] if whole else _edges(a, b)
            lowers += edges[:-1]
            uppers += [e - 1 for e in edges[1:]]
        self.first.append(len(lowers))
        self.lowers = np.array(lowers, dtype=np.int64)
        self.uppers = np.array(uppers, dtype=np.int64)
        self.job_of_bin = np.repeat(np.arange(self.lo.size), np.diff(self.first))

    def job_of(self, lo: np.ndarray) -> np.ndarray:
        """The job of rows whose range starts at lo."""
        return np.searchsorted(self.lo, lo)

    def read(self, parts: Parts, n_groups: int) -> list:
        """One pass: per job, its bins' counts per group (sparse, bins x groups; ``in_bin`` the values of
        each bin) or its values whole (keys sorted, with their groups)."""
        codes: list[tuple[np.ndarray, np.ndarray]] = []
        kept: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []
        collect_bin = self.collect[self.job_of_bin]
        for values, groups in parts():
            keys = float_keys(values)
            b = np.searchsorted(self.lowers, keys, side="right") - 1
            inside = b >= 0
            inside[inside] = keys[inside] <= self.uppers[b[inside]]
            keys, b, groups = keys[inside], b[inside], np.asarray(groups)[inside]
            whole = collect_bin[b]
            if whole.any():
                kept.append((self.job_of_bin[b[whole]], keys[whole], groups[whole]))
            code = b[~whole].astype(np.int64) * n_groups + groups[~whole]
            code, counted = np.unique(code, return_counts=True)
            codes.append((code, counted))
            if sum(c.size for c, _ in codes) > _CODES_HELD:
                codes = [_merged(codes)]
        code, counted = _merged(codes)
        row = code // n_groups
        self.in_bin = np.bincount(row, weights=counted, minlength=self.lowers.size).astype(np.int64)
        bins = sparse.csr_matrix((counted.astype(float), (row, code % n_groups)),
                                 shape=(self.lowers.size, n_groups))
        out: list = [None] * self.lo.size
        for job in np.flatnonzero(~self.collect):
            out[job] = bins[self.first[job]:self.first[job + 1]]
        empty = np.zeros(0, dtype=np.int64)
        job = np.concatenate([empty, *(k[0] for k in kept)])
        keys = np.concatenate([empty, *(k[1] for k in kept)])
        groups = np.concatenate([empty, *(k[2] for k in kept)])
        order = np.lexsort((keys, job))
        job, keys, groups = job[order], keys[order], groups[order]
        cuts = np.searchsorted(job, np.arange(self.lo.size + 1))
        for j in np.flatnonzero(self.collect):
            out[j] = (keys[cuts[j]:cuts[j + 1]], groups[cuts[j]:cuts[j + 1]])
        return out


def _edges(lo: int, hi: int) -> list[int]:
    """At most BINS + 1 edges cutting the keys lo..hi (inclusive) into ranges of near equal width."""
    width = hi - lo + 1
    return sorted({lo + (i * width) // BINS for i in range(BINS)} | {hi + 1})


def _merged(codes: list[tuple[np.ndarray, np.ndarray]]) -> tuple[np.ndarray, np.ndarray]:
    """Counts of the same code added."""
    if not codes:
        return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64)
    code = np.concatenate([c for c, _ in codes])
    counted = np.concatenate([n for _, n in codes])
    unique, inverse = np.unique(code, return_inverse=True)
    return unique, np.bincount(inverse, weights=counted, minlength=unique.size).astype(np.int64)


def _collected(held: tuple[np.ndarray, np.ndarray], w: np.ndarray, base: np.ndarray, targets: np.ndarray,
               lo: int) -> np.ndarray:
    """Each row's answer among a range's values read whole (sorted by key)."""
    keys, groups = held
    if keys.size == 0:
        raise RuntimeError(f"no value in the key range from {lo} where the targets end: a bug in msdc")
    index = np.zeros(targets.size, dtype=np.int64)
    step = max(1, _CELLS // keys.size)
    for start in range(0, targets.size, step):
        part = slice(start, start + step)
        cum = base[part, None] + np.cumsum(w[part][:, groups], axis=1)
        index[part] = [np.searchsorted(row, t) for row, t in zip(cum, targets[part], strict=True)]
    if np.any(index >= keys.size):
        raise RuntimeError(f"a target beyond the values of the key range from {lo}: a bug in msdc")
    return keys[index]


def _narrowed(jobs: _Jobs, counts: sparse.csr_matrix, job: int, w: np.ndarray, mine: np.ndarray,
              targets: np.ndarray, lo: np.ndarray, hi: np.ndarray, base: np.ndarray,
              count: np.ndarray) -> None:
    """The rows ``mine`` of a counted job moved to the bin where their weight reaches the target."""
    reach = np.asarray(counts @ w.T)                       # bins x rows: each bin's weight per row
    cum = base[mine][None, :] + np.cumsum(reach, axis=0)
    ends = cum >= targets[mine][None, :]
    if not ends[-1].all():
        raise RuntimeError(f"a target beyond the values of the key range from {jobs.lo[job]}: a bug in msdc")
    at = np.argmax(ends, axis=0)
    base[mine] = cum[at, np.arange(mine.size)] - reach[at, np.arange(mine.size)]
    first = jobs.first[job]
    lo[mine], hi[mine] = jobs.lowers[first + at], jobs.uppers[first + at]
    count[mine] = jobs.in_bin[first + at]


def inverted_cdf_rank(n: int, q: float) -> int:
    """The 0-based order statistic numpy's percentile with method='inverted_cdf' takes of n values at the
    share q: the smallest k with (k + 1) / n >= q, in numpy's floating-point arithmetic."""
    index = n * q - 1
    previous = math.floor(index)
    return max(0, previous if index - previous == 0 else previous + 1)


def linear_ranks(n: int, q: float) -> tuple[int, int, float]:
    """The two order statistics (0-based) numpy's default ('linear') percentile of n values at share q
    interpolates between, and the weight of the second."""
    index = (n - 1) * q
    if index >= n - 1:
        return n - 1, n - 1, 0.0  # both the largest
    previous = math.floor(index)
    return previous, previous + 1, index - previous


def interpolated(a: float, b: float, t: float) -> float:
    """a + (b - a) t, computed from the nearer end (as numpy's percentile does, so the figures agree)."""
    diff = b - a
    return b - diff * (1 - t) if t >= 0.5 else a + diff * t


__all__ = ["BINS", "COLLECT_VALUES", "KeyRange", "Parts", "Weights", "float_keys", "interpolated",
           "inverted_cdf_rank", "key_values", "linear_ranks", "lowest_reaching"]
