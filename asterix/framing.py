"""Framing a recording window by window: its data blocks and errors in the order of one pass over the whole
file, in memory bounded by the window (``Framer``), and counts over a whole framing (``survey``).

The kernel's framing state (kernel.frame_window) is carried from one window to the next, so the blocks and
errors do not depend on the window size; the pages of the memory-mapped file behind each window are dropped
from the process once framing has passed them (``release_pages``).
"""

from __future__ import annotations

import mmap
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field

import numpy as np

from . import kernel
from .containers import Segments

WINDOW_BYTES = 8 << 20  # payload bytes framed per window of a survey (memory: that window's blocks)
RELEASE_BEHIND = 1 << 21  # bytes before a released range released again (more than any fault-around)
KEEP_ENTRIES = 1 << 20  # blocks and errors of a careful framing kept for decoding (26 bytes each), at most
SAMPLE_BLOCKS = 20_000  # blocks a survey keeps of a sampled category: between this and twice as many

Framed = tuple[np.ndarray, ...]  # (blk_start, blk_len, blk_cat, blk_seg, err_off, err_len, err_cat, err_code)
Progress = Callable[[int, int, str], None]  # (bytes done, bytes in all, what is being done)


def release_pages(buf: np.ndarray, start: int, stop: int) -> None:
    """Drop the pages of a memory-mapped file between two offsets from this process (the data stay in the
    page cache and fault back in if read again), so a file read in chunks is not held in memory whole.
    RELEASE_BEHIND bytes before ``start`` are dropped again: a page fault maps the cached pages around it
    too (fault-around), some of them behind the part already dropped, which stayed mapped (issue 27:
    0.1 MB a window, 50 MB over a 2 GB file)."""
    mm = getattr(getattr(buf, "base", None), "obj", None)
    if not isinstance(mm, mmap.mmap) or not hasattr(mmap, "MADV_DONTNEED") or stop <= start:
        return
    lo = max(start - RELEASE_BEHIND, 0) // mmap.PAGESIZE * mmap.PAGESIZE
    hi = min(stop, len(mm))
    if hi > lo:
        mm.madvise(mmap.MADV_DONTNEED, lo, hi - lo)


def held(buf: np.ndarray) -> np.ndarray:
    """The same bytes as an array release_pages leaves alone: for a decoder that holds the whole file
    (``read``), where dropping pages between the passes that plan it only faults them back (5 ms a pass
    over 57 MB)."""
    return np.frombuffer(memoryview(buf), np.uint8)


def segment_modes(buf: np.ndarray, seg: Segments, tables: kernel.Framing,
                  progress: Progress | None = None) -> np.ndarray:
    """Each segment's framing mode, as kernel.frame_blocks settles it without ``careful``: container
    payloads exact, a raw stream taken as a chain when its chain holds from start to end and no block of a
    category not walked hides a walking block naming a data source of the chain (checked a window at a
    time, its pages dropped behind), else framed carefully."""
    if seg.exact:
        return np.full(len(seg.start), kernel.MODE_EXACT, np.int8)
    modes = np.full(len(seg.start), kernel.MODE_CAREFUL, np.int8)
    total = int(len(buf))
    sources = kernel.new_chain_sources()
    for s, (start, stop) in enumerate(zip(seg.start.tolist(), seg.stop.tolist(), strict=True)):
        q, status = start, 0
        while status == 0:
            at = q
            q, status = kernel.chain_step(buf, start, stop, tables, q, q + WINDOW_BYTES, sources)
            release_pages(buf, at, q)
            if progress:
                progress(q, total, "checking the block chain")
        modes[s] = kernel.settled_mode(status, sources)
    return modes


class Framer:
    """One framing of a recording (modes per segment, the tables it walks with), produced window by window."""

    def __init__(self, buf: np.ndarray, seg: Segments, modes: np.ndarray, tables: kernel.Framing,
                 log_cat: int = -1):
        self.buf, self.seg, self.modes, self.tables = buf, seg, modes, tables
        self.careful = np.flatnonzero(modes == kernel.MODE_CAREFUL)  # segments framed with the search
        self.state, self.seen = kernel.new_state()
        self.memo = kernel.new_memo(log_cat)
        self.released = 0  # pages below this offset were dropped

    @property
    def done(self) -> bool:
        """Every segment framed."""
        return int(self.state[kernel.ST_SEG]) >= len(self.seg.start)

    @property
    def position(self) -> int:
        """The file offset framing has settled up to (the next decision or the resumption search's front)."""
        st = self.state
        if self.done:
            return int(self.seg.stop.max()) if len(self.seg.stop) else 0
        if st[kernel.ST_PENDING]:
            return int(st[kernel.ST_SCAN])
        return int(st[kernel.ST_POS]) if st[kernel.ST_POS] >= 0 else int(self.seg.start[st[kernel.ST_SEG]])

    @property
    def segment(self) -> int:
        """The segment framing is in (len(seg.start) when done)."""
        return int(self.state[kernel.ST_SEG])

    def window(self, byte_limit: int = kernel.NO_LIMIT, seg_limit: int | None = None) -> Framed:
        """The blocks and errors settled before ``byte_limit`` (and segment ``seg_limit``): at least one
        decision's worth, none once done. The pages of the windows before (their blocks read by now) are
        dropped first."""
        seg = self.seg
        self.release(self.position)
        limit = len(seg.start) if seg_limit is None else seg_limit
        first = np.searchsorted(self.careful, self.state[kernel.ST_SEG])
        if first == len(self.careful) or self.careful[first] >= limit:  # frame_plain: a smaller kernel
            return kernel.frame_plain(self.buf, seg.start, seg.stop, self.modes, self.state, limit,
                                      byte_limit)
        return kernel.frame_window(self.buf, seg.start, seg.stop, self.modes, self.tables, self.state,
                                   self.seen, self.memo, limit, byte_limit)

    def release(self, upto: int) -> None:
        """Drop the mapped pages below ``upto`` (framing no longer reads them)."""
        if upto > self.released:
            release_pages(self.buf, self.released, upto)
            self.released = upto

    def drain(self) -> tuple[np.ndarray, np.ndarray] | None:
        """The blocks of the logged category walked since the last drain: (starts, walked exactly), emptying
        the log; None if an entry was lost (no room: see kernel.LOG_RESERVE)."""
        memo = self.memo
        count = int(memo[kernel.LOG_COUNT])
        memo[kernel.LOG_COUNT] = 0
        if count == kernel.LOG_OVERFLOW:
            return None
        entries = memo[kernel.LOG_COUNT + 1:kernel.LOG_COUNT + 1 + count]
        return entries >> 1, (entries & 1).astype(np.int8)

    def windows(self, window_bytes: int = WINDOW_BYTES, progress: Progress | None = None,
                what: str = "framing") -> Iterable[Framed]:
        """Every window of ``window_bytes`` to the end."""
        total = int(len(self.buf))
        while not self.done:
            yield self.window(self.position + window_bytes)
            if progress:
                progress(self.position, total, what)
        self.release(total)


class Replay:
    """A framing kept from a survey (Survey.framed), handed out window by window as Framer does: careful
    framing costs a pass over the file, and a short list of blocks (non-ASTERIX bytes) is cheaper kept."""

    def __init__(self, buf: np.ndarray, seg: Segments, framed: Framed):
        self.buf, self.seg, self.framed = buf, seg, framed
        self.block, self.error = 0, 0  # the next block and error handed out
        self.at = int(seg.start[0]) if len(seg.start) else 0  # offset handed out up to
        self.released = 0

    @property
    def done(self) -> bool:
        """Every block and error handed out."""
        return self.block >= len(self.framed[0]) and self.error >= len(self.framed[4])

    @property
    def position(self) -> int:
        """The offset handed out up to (the end of the payload once done)."""
        return int(self.seg.stop.max()) if self.done and len(self.seg.stop) else self.at

    def window(self, byte_limit: int = kernel.NO_LIMIT, seg_limit: int | None = None) -> Framed:
        """The blocks and errors starting before ``byte_limit`` (at least the next one; raw streams only:
        ``seg_limit`` is not used)."""
        b_start, e_off = self.framed[0], self.framed[4]
        nxt = min(int(b_start[self.block]) if self.block < len(b_start) else kernel.NO_LIMIT,
                  int(e_off[self.error]) if self.error < len(e_off) else kernel.NO_LIMIT)
        limit = max(byte_limit, nxt + 1)
        b1 = self.block + int(np.searchsorted(b_start[self.block:], limit))
        e1 = self.error + int(np.searchsorted(e_off[self.error:], limit))
        out = (*(a[self.block:b1] for a in self.framed[:4]), *(a[self.error:e1] for a in self.framed[4:]))
        self.block, self.error, self.at = b1, e1, max(self.at, min(limit, int(self.seg.stop.max())))
        self.release(self.at)
        return out

    def release(self, upto: int) -> None:
        """Drop the mapped pages below ``upto``."""
        if upto > self.released:
            release_pages(self.buf, self.released, upto)
            self.released = upto


class Sample:
    """Every k-th block of a category in framing order, k doubling whenever more than 2 x SAMPLE_BLOCKS
    are kept: an even spread over the file, the same whatever the windows."""

    def __init__(self) -> None:
        self.k = 1
        self.seen = 0  # blocks offered so far
        self.index: list[np.ndarray] = []
        self.start: list[np.ndarray] = []
        self.length: list[np.ndarray] = []

    def add(self, start: np.ndarray, length: np.ndarray) -> None:
        """Offer the next blocks of the category (in framing order)."""
        idx = self.seen + np.arange(len(start), dtype=np.int64)
        self.seen += len(start)
        keep = idx % self.k == 0
        self.index.append(idx[keep])
        self.start.append(start[keep])
        self.length.append(length[keep])
        if sum(len(i) for i in self.index) > 2 * SAMPLE_BLOCKS:
            idx, start, length = self.arrays(with_index=True)
            while len(idx) > 2 * SAMPLE_BLOCKS:
                self.k *= 2
                keep = idx % self.k == 0
                idx, start, length = idx[keep], start[keep], length[keep]
            self.index, self.start, self.length = [idx], [start], [length]

    def arrays(self, with_index: bool = False):
        """(starts, lengths) of the kept blocks (with their indices first when asked)."""
        out = [np.concatenate(p) if p else np.zeros(0, np.int64)
               for p in (self.index, self.start, self.length)]
        return tuple(out) if with_index else (out[1], out[2])


@dataclass
class Survey:
    """What one framing of a recording holds, counted window by window (no memory per block): blocks and
    bytes per category, blocks of walked categories that do not walk, bytes of those that do, framing errors,
    and samples of some categories' blocks and of the failed blocks of others."""

    blocks: np.ndarray = field(default_factory=lambda: np.zeros(256, np.int64))
    bytes: np.ndarray = field(default_factory=lambda: np.zeros(256, np.int64))
    failed: np.ndarray = field(default_factory=lambda: np.zeros(256, np.int64))
    walking_bytes: int = 0
    walking: np.ndarray = field(default_factory=lambda: np.zeros(256, np.int64))  # those bytes per category
    errors: int = 0
    error_bytes: int = 0
    samples: dict[int, Sample] = field(default_factory=dict)
    failed_samples: dict[int, Sample] = field(default_factory=dict)
    framed: Framed | None = None  # the whole framing, when kept (survey's ``keep``)

    def walking_among(self, cats: Iterable[int]) -> int:
        """Bytes of walking blocks of these categories."""
        return int(self.walking[list(cats)].sum())

    def lone(self, walked: Iterable[int]) -> bool:
        """A category not walked has a single block: a possible false header (worth careful framing)."""
        counts = self.blocks.copy()
        counts[list(walked)] = 0
        return bool((counts == 1).any())


def alike_framings(buf: np.ndarray, seg: Segments, modes: np.ndarray, tables: dict[str, kernel.Framing],
                   cat: int, progress: Progress | None = None, what: str = "framing") -> dict[str, Survey]:
    """Blocks per category and framing errors of the recording framed under each of several tables that
    differ only in how blocks of ``cat`` walk (its editions), by key. The first is framed, logging every
    block of ``cat`` its framing walks; tables that walk each of those alike frame alike, decision for
    decision, and share its counts; the others are framed in turn the same way (framing once per group of
    editions that agree, instead of once per edition)."""
    out: dict[str, Survey] = {}
    remaining = list(tables)
    while remaining:
        lead, rest = remaining[0], remaining[1:]
        alike = set(rest)
        counted = Survey()
        framer = Framer(buf, seg, modes, tables[lead], log_cat=cat)
        for framed in framer.windows(progress=progress, what=f"{what} {lead}"):
            cats = framed[2].astype(np.int64)
            counted.blocks += np.bincount(cats, minlength=256)
            counted.bytes += np.bincount(cats, weights=framed[1], minlength=256).astype(np.int64)
            counted.errors += len(framed[4])
            counted.error_bytes += int(framed[5].sum())
            log = framer.drain()
            if log is None:
                alike.clear()
            elif len(log[0]) and alike:
                starts = log[0]
                lens = (buf[starts + 1].astype(np.int64) << 8) | buf[starts + 2]
                for key in list(alike):
                    t = tables[key]
                    walked = kernel.walk_flags(buf, starts, lens, t.base[cat], t.nfrn[cat], t.parts)
                    if (walked != log[1]).any():
                        alike.discard(key)
        for key in (lead, *alike):
            out[key] = counted
        remaining = [k for k in rest if k not in alike]
    return out


def survey(buf: np.ndarray, seg: Segments, modes: np.ndarray, tables: kernel.Framing,
           walk: kernel.Framing | None = None, *, sample: Iterable[int] = (),
           sample_failed: Iterable[int] = (), progress: Progress | None = None,
           what: str = "framing", keep: int = 0, walk_blocks: bool = True) -> Survey:
    """Frame the recording window by window (with ``tables``), walk each block of a category ``walk``
    walks (default: ``tables``), and count (Survey); ``sample``: categories whose blocks are sampled,
    ``sample_failed``: those whose failed blocks are. A careful framing of at most ``keep`` blocks and
    errors is kept (Survey.framed), for decoding to replay instead of framing again. Without
    ``walk_blocks`` no block is walked: none counts as failed or walking (the plan assumes they walk)."""
    walk = tables if walk is None else walk
    out = Survey(samples={c: Sample() for c in sample}, failed_samples={c: Sample() for c in sample_failed})
    kept: list[Framed] | None = [] if keep and (modes == kernel.MODE_CAREFUL).any() else None
    entries = 0
    for framed in Framer(buf, seg, modes, tables).windows(progress=progress, what=what):
        if kept is not None:
            entries += len(framed[0]) + len(framed[4])
            if entries <= keep:
                kept.append(framed)
            else:
                kept = None  # too long to keep: decoding frames it again
        b_start, b_len, b_cat = framed[:3]
        cats = b_cat.astype(np.int64)
        out.blocks += np.bincount(cats, minlength=256)
        out.bytes += np.bincount(cats, weights=b_len, minlength=256).astype(np.int64)
        out.errors += len(framed[4])
        out.error_bytes += int(framed[5].sum())
        for cat, smp in out.samples.items():
            sel = cats == cat
            smp.add(b_start[sel], b_len[sel])
        if not walk_blocks:
            continue
        flags = kernel.block_walks(buf, b_start, b_len, b_cat, walk)
        bad = flags == 0
        out.failed += np.bincount(cats[bad], minlength=256)
        good = flags == 1
        out.walking_bytes += int(b_len[good].sum())
        out.walking += np.bincount(cats[good], weights=b_len[good], minlength=256).astype(np.int64)
        for cat, smp in out.failed_samples.items():
            sel = bad & (cats == cat)
            smp.add(b_start[sel], b_len[sel])
    if kept:
        out.framed = tuple(np.concatenate([w[i] for w in kept]) for i in range(8))
    return out
