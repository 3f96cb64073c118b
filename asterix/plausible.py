"""Values no real report carries: a position off the Earth, a time of day outside 0-24 h; and records
naming another data source than the rest of their data block.

Bytes that are not what they are read as (garbage framed as blocks, a wrong edition) decode into such
values far more often than real reports do; ``auto`` breaks ties with them, and the reader counts the
records that carry one. A real recording's data block holds one sensor's records (I0xx/010 alike in every
record); damage inside a block that still walks to its end makes records out of the bytes after it, and
those name made-up data sources.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
import pandas as pd
from numba import njit

# column -> (lowest, highest) plausible value; time of day: highest excluded (86400 s is the next day)
BOUNDS: dict[str, tuple[float, float]] = {
    "latitude": (-90.0, 90.0),
    "longitude": (-180.0, 180.0),
    "time_of_day": (0.0, 86400.0),
}
EXCLUSIVE_TOP = ("time_of_day",)
SHOWN_OFFSETS = 5  # offsets of implausible records a Recording keeps


class Implausible(NamedTuple):
    """Records of one category holding an implausible value: how many, and the first ones' offsets."""

    records: int
    offsets: tuple[int, ...]

    def __add__(self, other: Implausible) -> Implausible:  # type: ignore[override]
        return Implausible(self.records + other.records, (self.offsets + other.offsets)[:SHOWN_OFFSETS])


def implausible(columns: dict[str, np.ndarray]) -> np.ndarray:
    """True for each record one of whose bounded columns (``BOUNDS``, those present) holds a value outside
    its bounds; an absent value (NaN) is no evidence either way."""
    n = len(next(iter(columns.values()))) if columns else 0
    out = np.zeros(n, bool)
    for name, (lo, hi) in BOUNDS.items():
        values = columns.get(name)
        if values is None:
            continue
        values = np.asarray(values, np.float64)
        high = values >= hi if name in EXCLUSIVE_TOP else values > hi
        out |= (values < lo) | high  # NaN compares False: absent values pass
    return out


def count_implausible(columns: dict[str, np.ndarray], offsets: np.ndarray) -> Implausible:
    """The records of one category's decoded columns that hold an implausible value (``implausible``)."""
    bad = implausible({name: columns[name] for name in BOUNDS if name in columns})
    return Implausible(int(bad.sum()), tuple(int(o) for o in offsets[bad][:SHOWN_OFFSETS]))


@njit(cache=True, nogil=True)
def _majority(source, i, j):
    """The most common source among records i..j-1 (the first met wins a tie)."""
    best, best_count = source[i], 0
    for a in range(i, j):
        count = 0
        for b in range(i, j):
            if source[b] == source[a]:
                count += 1
        if count > best_count:
            best, best_count = source[a], count
    return best


@njit(cache=True, nogil=True)
def _odd_sources(sac, sic, block):
    """True for each record whose source (SAC << 8 | SIC; -1 when absent, a value like any other: every
    category's FRN 1 is its data source) differs from the most common one of its run of records of one
    block and is no block's most common one (a feed mixing sensors in its blocks names each of them as
    some block's; bytes after damage name made-up ones); one pass unless a block mixes."""
    n = sac.shape[0]
    out = np.zeros(n, np.bool_)
    mixed = False
    head = np.int64(-2)  # the source of the first record of the run
    for r in range(n):
        here = np.int64(-1) if sac[r] < 0 or sic[r] < 0 else (np.int64(sac[r]) << 8) | sic[r]
        if r == 0 or block[r] != block[r - 1]:
            head = here
        elif here != head:
            mixed = True
            break
    if not mixed:  # nearly every input: one pass, nothing held
        return out
    source = np.empty(n, np.int64)
    for r in range(n):
        source[r] = -1 if sac[r] < 0 or sic[r] < 0 else (np.int64(sac[r]) << 8) | sic[r]
    starts = np.empty(n + 1, np.int64)  # each run's first record, then n
    runs = 0
    i = 0
    while i < n:
        starts[runs] = i
        runs += 1
        j = i + 1
        while j < n and block[j] == block[i]:
            j += 1
        i = j
    starts[runs] = n
    majority = np.empty(runs, np.int64)
    for k in range(runs):
        majority[k] = _majority(source, starts[k], starts[k + 1])
    known = np.unique(majority)
    for k in range(runs):
        for a in range(starts[k], starts[k + 1]):
            if source[a] != majority[k]:
                at = np.searchsorted(known, source[a])
                out[a] = source[a] < 0 or at == known.shape[0] or known[at] != source[a]
    return out


def odd_sources(sac, sic, block) -> np.ndarray:
    """True for each record naming a data source (SAC/SIC) other than the most common one of its data block
    and than any block's, or none beside records that name one (``block``: the block index of each record,
    a block's records one after another)."""
    sac, sic = (pd.array(v).to_numpy(dtype=np.int16, na_value=-1) for v in (sac, sic))
    return _odd_sources(sac, sic, np.asarray(block))


def count_odd_sources(columns: dict[str, np.ndarray]) -> Implausible:
    """The records of one category's decoded columns naming another data source than their block
    (``odd_sources``; none when the columns carry no data source)."""
    if "sac" not in columns or "sic" not in columns:
        return Implausible(0, ())
    odd = odd_sources(columns["sac"], columns["sic"], columns["block"])
    offsets = np.asarray(columns["offset"])[odd][:SHOWN_OFFSETS]
    return Implausible(int(odd.sum()), tuple(int(o) for o in offsets))
