"""The blocks of one category that ``editions={cat: "auto"}`` judges an edition by, taken from the whole
recording before it is decoded (whole or in chunks: ``read`` and ``iter_read`` see the same sample).

Every block when there are at most ``size`` of them; else the first block at or after each of ``size``
offsets spread evenly over the recording's payload. Following the block chain costs no memory: a
recording of any length is sampled in one pass (a raw stream whose chain breaks is framed first, as the
decoder frames it).
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True, nogil=True)
def chain_holds(buf, q, stop):
    """The bytes [q, stop) are data blocks end to end (the chain of an exact payload or a raw stream)."""
    while q < stop:
        if q + 3 > stop or buf[q] == 0:
            return False
        n = (np.int64(buf[q + 1]) << 8) | buf[q + 2]
        if n < 3 or q + n > stop:
            return False
        q += n
    return True


@njit(cache=True, nogil=True)
def chain_end(buf, q, stop):
    """Where the block chain from q stops: the end of its last whole block before ``stop`` (q if none)."""
    while q + 3 <= stop and buf[q] != 0:
        n = (np.int64(buf[q + 1]) << 8) | buf[q + 2]
        if n < 3 or q + n > stop:
            break
        q += n
    return q


@njit(cache=True, nogil=True)
def sample_chain(buf, seg_start, seg_stop, cat, targets, kept, picks):
    """Follow the block chain of every payload (one that does not tile into blocks is left out, as framing
    skips it) and note blocks of ``cat``: the first ``len(kept)`` of them in ``kept`` and, in ``picks``,
    the first at or after each target offset (-1 when none). Returns the number of blocks of ``cat``."""
    count = 0
    t = 0
    for s in range(seg_start.shape[0]):
        q, stop = seg_start[s], seg_stop[s]
        if not chain_holds(buf, q, stop):
            continue
        while q < stop:
            n = (np.int64(buf[q + 1]) << 8) | buf[q + 2]
            if buf[q] == cat:
                if count < kept.shape[0]:
                    kept[count] = q
                while t < targets.shape[0] and targets[t] <= q:
                    picks[t] = q
                    t += 1
                count += 1
            q += n
    return count


@njit(cache=True, nogil=True)
def prefix_chain(buf, q, stop, cat, kept):
    """Follow a raw stream's block chain from q while each header is a possible one (a category, a LEN of
    at least 3 within the data), noting the first ``len(kept)`` blocks of ``cat``: how many it noted."""
    count = 0
    while count < kept.shape[0] and q + 3 <= stop and buf[q] != 0:
        n = (np.int64(buf[q + 1]) << 8) | buf[q + 2]
        if n < 3 or q + n > stop:
            break
        if buf[q] == cat:
            kept[count] = q
            count += 1
        q += n
    return count


def prefix_starts(buf: np.ndarray, start: int, stop: int, cat: int, size: int) -> np.ndarray:
    """Starts of the first ``size`` blocks of ``cat`` on a raw stream's chain before it breaks."""
    kept = np.zeros(size, np.int64)
    return kept[:prefix_chain(buf, np.int64(start), np.int64(stop), np.uint8(cat), kept)]


def spread_offsets(lo: int, hi: int, size: int) -> np.ndarray:
    """``size`` offsets spread evenly over [lo, hi)."""
    return np.unique(np.linspace(lo, max(hi - 1, lo), size).astype(np.int64))


def sample_starts(buf: np.ndarray, seg_start: np.ndarray, seg_stop: np.ndarray, cat: int,
                  size: int) -> tuple[np.ndarray, int]:
    """(starts of the sampled blocks of ``cat``, its blocks in all) over chaining payloads (module doc)."""
    if not len(seg_start):
        return np.zeros(0, np.int64), 0
    targets = spread_offsets(int(seg_start.min()), int(seg_stop.max()), size)
    kept = np.zeros(size, np.int64)
    picks = np.full(len(targets), -1, np.int64)
    count = sample_chain(buf, seg_start.astype(np.int64), seg_stop.astype(np.int64), np.uint8(cat), targets,
                         kept, picks)
    if count <= size:
        return kept[:count], count
    return np.unique(picks[picks >= 0]), count


def sample_of(cat_starts: np.ndarray, lo: int, hi: int, size: int) -> np.ndarray:
    """The same choice over block starts already framed (``cat_starts``, ascending), for a stream framed
    carefully: all of them when there are at most ``size``, else the first at or after each offset."""
    if len(cat_starts) <= size:
        return cat_starts
    at = np.searchsorted(cat_starts, spread_offsets(lo, hi, size))
    return np.unique(cat_starts[at[at < len(cat_starts)]])


def block_lengths(buf: np.ndarray, starts: np.ndarray) -> np.ndarray:
    """The LEN of the data blocks at ``starts``."""
    return (buf[starts + 1].astype(np.int64) << 8) | buf[starts + 2]
