"""The blocks of one category that ``editions={cat: "auto"}`` judges an edition by, taken from the whole
recording before it is decoded (whole or in chunks: ``read`` and ``iter_read`` see the same sample).

Every block when there are at most ``size`` of them; else the first block at or after each of ``size``
offsets spread evenly over the recording's payload; either thinned evenly to about ``max_bytes`` of blocks
when they hold more (blocks of many records: each edition family walks every sampled record). Following
the block chain costs no memory: a recording of any length is sampled in one pass (a raw stream whose
chain breaks is framed first, as the decoder frames it), a window of WINDOW_BYTES at a time with the pages
behind each window released (a walk over the whole mapped file at once kept all of it resident: 1.08 GB
of a 1 GB file, issue #27 item 6).
"""

from __future__ import annotations

import numpy as np
from numba import njit

WINDOW_BYTES = 8 << 20  # payload bytes walked between page releases


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
def chain_walk(buf, q, stop, limit):
    """Follow the block chain from q until it reaches ``limit`` (or ``stop``): the offset reached, -1 where
    the chain breaks before."""
    while q < stop and q < limit:
        if q + 3 > stop or buf[q] == 0:
            return -1
        n = (np.int64(buf[q + 1]) << 8) | buf[q + 2]
        if n < 3 or q + n > stop:
            return -1
        q += n
    return q


@njit(cache=True, nogil=True)
def chains_hold(buf, seg_start, seg_stop):
    """Every payload of the arrays is data blocks end to end."""
    for s in range(seg_start.shape[0]):
        if not chain_holds(buf, seg_start[s], seg_stop[s]):
            return False
    return True


@njit(cache=True, nogil=True)
def sample_walk(buf, q, stop, limit, cat, targets, kept, picks, count, t, nbytes):
    """Along a chain known to hold, from q until ``limit`` (or ``stop``): note blocks of ``cat``, the first
    ``len(kept)`` in ``kept`` and, in ``picks``, the first at or after each target offset; returns the
    offset reached, the blocks of ``cat`` counted so far, the next target and their bytes so far."""
    while q < stop and q < limit:
        n = (np.int64(buf[q + 1]) << 8) | buf[q + 2]
        if buf[q] == cat:
            nbytes += n
            if count < kept.shape[0]:
                kept[count] = q
            while t < targets.shape[0] and targets[t] <= q:
                picks[t] = q
                t += 1
            count += 1
        q += n
    return q, count, t, nbytes


@njit(cache=True, nogil=True)
def sample_chain(buf, seg_start, seg_stop, cat, targets, kept, picks, count, t, nbytes):
    """sample_walk over every payload of the arrays that tiles into blocks (one that does not is left out,
    as framing skips it); returns the blocks of ``cat`` counted so far, the next target and their bytes."""
    for s in range(seg_start.shape[0]):
        q, stop = seg_start[s], seg_stop[s]
        if chain_holds(buf, q, stop):
            q, count, t, nbytes = sample_walk(buf, q, stop, stop, cat, targets, kept, picks, count, t, nbytes)
    return count, t, nbytes


def _batches(seg_start: np.ndarray, seg_stop: np.ndarray):
    """The payloads in batches of about WINDOW_BYTES: (first, end) index ranges, a payload longer than a
    window alone in its batch (walked window by window)."""
    sizes = (seg_stop - seg_start).astype(np.int64)
    ends = np.cumsum(sizes)
    i, n = 0, len(sizes)
    while i < n:
        if sizes[i] > WINDOW_BYTES:
            yield i, i + 1
            i += 1
            continue
        j = int(np.searchsorted(ends, (ends[i - 1] if i else 0) + WINDOW_BYTES, side="right"))
        j = max(j, i + 1)
        long = np.flatnonzero(sizes[i:j] > WINDOW_BYTES)
        j = i + int(long[0]) if len(long) else j
        yield i, j
        i = j


def all_chains_hold(buf: np.ndarray, seg_start: np.ndarray, seg_stop: np.ndarray, release=None) -> bool:
    """Every payload tiles into data blocks, walked a window at a time; ``release(lo, hi)`` drops the pages
    of each window walked."""
    starts, stops = seg_start.astype(np.int64), seg_stop.astype(np.int64)
    for i, j in _batches(starts, stops):
        if j == i + 1 and stops[i] - starts[i] > WINDOW_BYTES:
            q, stop = int(starts[i]), int(stops[i])
            while q < stop:
                reached = chain_walk(buf, np.int64(q), np.int64(stop), np.int64(min(q + WINDOW_BYTES, stop)))
                if release is not None:
                    release(q, reached if reached >= 0 else min(q + WINDOW_BYTES, stop))
                if reached < 0:
                    return False
                q = reached
            continue
        held = chains_hold(buf, starts[i:j], stops[i:j])
        if release is not None:
            release(int(starts[i]), int(stops[j - 1]))
        if not held:
            return False
    return True


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
                  size: int, release=None, max_bytes: int | None = None) -> tuple[np.ndarray, int]:
    """(starts of the sampled blocks of ``cat``, its blocks in all) over chaining payloads (module doc),
    walked a window at a time; ``release(lo, hi)`` drops the pages of each window walked. ``max_bytes``:
    the sample thinned evenly to about that many bytes of blocks of the category's mean size."""
    if not len(seg_start):
        return np.zeros(0, np.int64), 0
    targets = spread_offsets(int(seg_start.min()), int(seg_stop.max()), size)
    kept = np.zeros(size, np.int64)
    picks = np.full(len(targets), -1, np.int64)
    starts, stops = seg_start.astype(np.int64), seg_stop.astype(np.int64)
    count, t, code, nbytes = 0, 0, np.uint8(cat), np.int64(0)
    for i, j in _batches(starts, stops):
        if j == i + 1 and stops[i] - starts[i] > WINDOW_BYTES:
            lo, stop = int(starts[i]), int(stops[i])
            if not all_chains_hold(buf, starts[i:j], stops[i:j], release):
                continue
            q = lo
            while q < stop:
                before = q
                limit = np.int64(min(q + WINDOW_BYTES, stop))
                q, count, t, nbytes = sample_walk(buf, np.int64(q), np.int64(stop), limit, code, targets,
                                                  kept, picks, count, t, nbytes)
                if release is not None:
                    release(before, int(q))
            continue
        count, t, nbytes = sample_chain(buf, starts[i:j], stops[i:j], code, targets, kept, picks, count, t,
                                        nbytes)
        if release is not None:
            release(int(starts[i]), int(stops[j - 1]))
    sample = kept[:count] if count <= size else np.unique(picks[picks >= 0])
    if max_bytes is not None and count:
        fit = max(1, int(max_bytes * count // int(nbytes)))  # blocks of the mean size in max_bytes
        if len(sample) > fit:
            sample = sample[np.unique(np.linspace(0, len(sample) - 1, fit).astype(np.int64))]
    return sample, count


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
