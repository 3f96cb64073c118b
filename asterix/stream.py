"""``iter_read``: decode a recording in bounded chunks, days and timestamps continuing across them."""

from __future__ import annotations

import dataclasses
import datetime as dt
from collections.abc import Iterator
from concurrent.futures import Executor
from dataclasses import dataclass

import numpy as np

from .cat001_time import PLOT_CATEGORY, SectorClock
from .containers import UNTIMED, Segments, check_format, read_segments
from .errors import UnreadableInput
from .framing import Progress, release_pages
from .plan import Plan, plan_recording
from .reader import (
    Recording,
    _mapped,
    check_categories,
    check_readable,
    check_strict,
    decode_framed,
    parse_date,
    reading_editions,
    selected_columns,
)
from .timeline import (
    ANCHOR_FOLLOWERS,
    ANCHOR_REPORTS,
    DayClock,
    _file_order,
    _steps,
    agreed_run,
    count_days,
    file_order_days,
    first_report_day,
    known_captures,
    restamp,
    valid_times,
)

HOLD_BYTES = 1 << 22  # a raw stream's first chunks held at most until day 0 is anchored (payload bytes)
MAX_CHUNK = 1 << 62  # bytes: any file is smaller, and a position plus a chunk still fits an int64


def iter_read(path, *, chunk: int = 1_000_000, editions=None, date=None, categories=None,
              format: str | None = None, strict: bool = False, columns=None,
              progress: Progress | None = None, pool: Executor | None = None) -> Iterator[Recording]:
    """Stream a recording in chunks of about ``chunk`` bytes of payload, yielding a Recording each
    (``columns``: only those decoded columns, as in ``read``); ``progress(done, total, what)`` is called
    as the passes that plan the decoding (asterix.plan) and the decoding itself go through the file.

    The records, errors, days, timestamps and ``block`` index are those ``read`` gives, whatever the chunk
    size: the framing, the editions and the verdicts on them are settled over the whole file first. Memory
    follows the chunk size, not the file (but for a container's table of packets, 32 bytes a packet).
    The arguments, and that the file can be read, are checked when iter_read is called, not at the first
    chunk.
    """
    if isinstance(chunk, bool) or not isinstance(chunk, int | np.integer):
        raise TypeError(f"chunk {chunk!r}: must be a whole number of bytes (an int), not a "
                        f"{type(chunk).__name__}")
    if not 0 < chunk <= MAX_CHUNK:
        raise ValueError(f"chunk {chunk!r}: must be a positive number of bytes, at most {MAX_CHUNK} (2**62; "
                         f"a chunk the size of the file decodes it at once)")
    if progress is not None and not callable(progress):
        raise TypeError(f"progress {progress!r:.60}: must be a function progress(done, total, what) or "
                        f"None, not {type(progress).__name__}")
    if pool is not None and not callable(getattr(pool, "submit", None)):
        raise TypeError(f"pool {pool!r:.60}: must be a concurrent.futures.Executor (a ProcessPoolExecutor) "
                        f"or None, not {type(pool).__name__}")
    selected = selected_columns(columns)
    strict = check_strict(strict)
    first_date, categories = parse_date(date), check_categories(categories)
    eds = reading_editions(editions, categories)
    check_readable(path)
    try:
        check_format(format)
    except ValueError as exc:  # as read() says it
        raise UnreadableInput(f"{path}: {exc}") from exc
    return _iter_read(path, chunk, eds, first_date, categories, format, strict, selected, progress, pool)


def _iter_read(path, chunk: int, eds: dict[int, str], first_date: dt.date | None, categories,
               format: str | None, strict: bool, selected, progress: Progress | None,
               pool: Executor | None) -> Iterator[Recording]:
    """iter_read's chunks, from its arguments checked."""
    with _mapped(path) as buf:
        try:
            seg = read_segments(buf, format)
        except ValueError as exc:  # as read() says it
            raise UnreadableInput(f"{path}: {exc}") from exc
        release_pages(buf, 0, len(buf))  # finding the payloads of a container read the whole file
        plan = plan_recording(buf, seg, eds, categories, progress)  # 'auto' chosen over the whole file
        clock = None  # a raw stream's DayClock after the chunks before; None: day 0 not anchored yet
        pending: list[Recording] = []  # a raw stream's first chunks, held until day 0 is anchored
        seen = np.zeros(0)  # their valid times of day in file order (the first ANCHOR_REPORTS)
        held = 0  # their payload bytes
        day0 = None  # container day number of the first chunk's day 0
        blocks = 0  # data blocks framed in the chunks before: each chunk numbers its own from 0
        sectors = SectorClock()  # each radar's last CAT002 time: CAT001 times continue across chunks
        pooled = pool if pool is not None and can_pool(plan) else None
        for rec, covered in _chunks(buf, plan, chunk, path=str(path), date=first_date, strict=strict,
                                    selected=selected, sector_clock=sectors, progress=progress,
                                    pool=pooled):
            for f in rec.frames.values():
                f["block"] += blocks
            blocks += rec.blocks
            if seg.format in UNTIMED and clock is None:
                pending.append(rec)
                seen = np.concatenate([seen, valid_times(rec.frames)])[:ANCHOR_REPORTS]
                held += covered
                if len(seen) < ANCHOR_REPORTS and held < HOLD_BYTES:
                    continue
                clock = DayClock(first_report_day(seen))
                for held_rec in pending:
                    clock = file_order_days(held_rec.frames, clock)
                    restamp(held_rec.frames, first_date)
                    yield held_rec
                pending = []
                continue
            if seg.format in UNTIMED:
                clock = file_order_days(rec.frames, clock)
                restamp(rec.frames, first_date)
            elif rec.day0 is not None and day0 is None:
                day0, first_date = rec.day0, rec.date  # a dated container's date wins over date=
            elif rec.day0 is not None and rec.day0 != day0:
                # each chunk counts days from its own first: count them from the first chunk's
                for f in rec.frames.values():
                    f["day"] += rec.day0 - day0
                restamp(rec.frames, first_date)
                rec.date, rec.day0 = first_date, day0
            yield rec
        clock = DayClock(first_report_day(seen))
        for held_rec in pending:  # a short file: fewer valid times of day than settle day 0
            clock = file_order_days(held_rec.frames, clock)
            restamp(held_rec.frames, first_date)
            yield held_rec


def can_pool(plan: Plan) -> bool:
    """Whether a recording's chunks may decode apart: a raw stream (one payload, framed here) without
    CAT001 plots, whose times come from the CAT002 messages of the chunks before."""
    return bool(len(plan.seg.start)) and not plan.seg.exact and PLOT_CATEGORY not in plan.decoded


def _chunks(buf: np.ndarray, plan: Plan, chunk: int, *, progress: Progress | None = None,
            pool: Executor | None = None, **decode) -> Iterator[tuple[Recording, int]]:
    """The recording decoded by the plan in chunks of about ``chunk`` payload bytes, each with the payload
    bytes it covers: a raw stream cut at block starts as framing goes, a container's payloads in groups
    (chunks holding nothing at all are not yielded, but for a file without payload). ``pool``: a raw
    stream's chunks decoded in its processes (can_pool), in order, at most POOL_AHEAD per process ahead."""
    seg = plan.seg
    framer = plan.framer(buf)
    total = int(len(buf))
    if not len(seg.start):
        yield decode_framed(buf, plan, framer.window(), **decode), 0
        return
    if not seg.exact:
        windows = _raw_windows(framer, chunk, total, progress)
        if pool is None:
            for framed, covered in windows:
                yield decode_framed(buf, plan, framed, **decode), covered
        else:
            yield from _pooled(pool, plan, windows, decode)
        framer.release(total)
        return
    day, tod = known_captures(seg)  # untimed packets (pcapng SPB) take their neighbour's capture time
    if day is not None:
        seg = dataclasses.replace(seg, capture_day=day, capture_tod=tod)
    sizes = np.cumsum(seg.stop - seg.start)
    group = (sizes // max(chunk, 1)).astype(np.int64)
    ends = np.flatnonzero(np.diff(group, append=group[-1] + 1)) + 1  # one past each group's last segment
    first = 0
    for end in ends.tolist():
        idx = np.arange(first, end)
        part = _sub_segments(seg, seg.start[idx], seg.stop[idx], idx)
        framed = framer.window(seg_limit=end)
        if progress:
            progress(int(seg.stop[end - 1]), total, "decoding")
        covered = int(sizes[end - 1] - (sizes[first - 1] if first else 0))
        yield decode_framed(buf, plan, framed, part=part, first_segment=first, **decode), covered
        first = end
    framer.release(total)


def _raw_windows(framer, chunk: int, total: int, progress: Progress | None
                 ) -> Iterator[tuple[tuple, int]]:
    """A raw stream's framed windows of about ``chunk`` bytes, cut at block starts, each with the bytes it
    covers (windows holding no block and no framing error are passed over)."""
    while not framer.done:
        at = framer.position
        framed = framer.window(at + chunk)
        if progress:
            progress(framer.position, total, "decoding")
        if len(framed[0]) or len(framed[4]):
            yield framed, framer.position - at


POOL_AHEAD = 2  # windows in flight per pool process: the next is ready when one is taken


def _pooled(pool: Executor, plan: Plan, windows: Iterator[tuple[tuple, int]], decode: dict
            ) -> Iterator[tuple[Recording, int]]:
    """Each window decoded in ``pool`` (_decode_window), yielded in file order as it comes back."""
    from collections import deque

    ahead = POOL_AHEAD * max(getattr(pool, "_max_workers", 1), 1)
    path = decode.pop("path")
    decode.pop("sector_clock", None)  # no CAT001 plots here (can_pool): the clock is never read
    pending: deque = deque()
    for framed, covered in windows:
        pending.append((pool.submit(_decode_window, path, plan, framed, decode), covered))
        if len(pending) >= ahead:
            future, n = pending.popleft()
            yield future.result(), n
    while pending:
        future, n = pending.popleft()
        yield future.result(), n


def _decode_window(path: str, plan: Plan, framed: tuple, decode: dict) -> Recording:
    """One framed window of the file at ``path`` decoded in a pool process (the file mapped again there)."""
    with _mapped(path) as buf:
        return decode_framed(buf, plan, framed, path=path, **decode)


def _sub_segments(seg: Segments, start, stop, idx) -> Segments:
    first = len(idx) and idx[0] == 0
    return Segments(seg.format, np.asarray(start, np.int64), np.asarray(stop, np.int64),
                    seg.capture_day[idx] if len(seg.capture_day) else np.full(len(idx), -1, np.int64),
                    seg.capture_tod[idx] if len(seg.capture_tod) else np.full(len(idx), np.nan),
                    seg.dated, seg.exact, seg.container_bytes if first else 0,
                    seg.problems if first else [])


@dataclass(frozen=True)
class Window:
    """One chunk of a raw stream, framed and clocked in file order, to decode on its own (decode_window):
    its framed blocks, the data blocks before it, and the DayClock the reports before it leave, on the
    recording's ``date``."""

    index: int
    framed: tuple
    blocks_before: int
    clock: DayClock
    date: dt.date | None


def plan_windows(path, pool: Executor, *, chunk: int, editions=None, date=None, categories=None,
                 format: str | None = None) -> tuple[Plan, list[Window]] | None:
    """A raw stream cut into windows of about ``chunk`` bytes that decode apart, in ``pool``'s processes,
    into the records, days and block numbers iter_read gives: the windows' times of day are decoded first
    (in the pool; the time of day alone, about a third of a whole decode) and the clocks settled from them
    in file order as iter_read settles them. None when the recording is not a raw stream or holds CAT001
    plots (can_pool): iter_read decodes it."""
    first_date, categories = parse_date(date), check_categories(categories)
    eds = reading_editions(editions, categories)
    with _mapped(path) as buf:
        try:
            seg = read_segments(buf, format)
        except ValueError as exc:
            raise UnreadableInput(f"{path}: {exc}") from exc
        release_pages(buf, 0, len(buf))
        plan = plan_recording(buf, seg, eds, categories, None)
        if seg.format != "raw" or not can_pool(plan):
            return None
        framer = plan.framer(buf)
        framed = list(_raw_windows(framer, chunk, int(len(buf)), None))
        framer.release(int(len(buf)))
    timed = list(pool.map(_window_times, [(str(path), plan, f) for f, _ in framed]))
    seen = np.zeros(0)  # the first valid times of day, as iter_read anchors day 0 on them
    held = 0
    for (_, covered), clock in zip(framed, timed, strict=True):
        seen = np.concatenate([seen, clock.head])[:ANCHOR_REPORTS]
        held += covered
        if len(seen) >= ANCHOR_REPORTS or held >= HOLD_BYTES:
            break
    day_clock = DayClock(first_report_day(seen))
    windows, blocks = [], 0
    for i, ((f, _), clock) in enumerate(zip(framed, timed, strict=True)):
        windows.append(Window(i, f, blocks, day_clock, first_date))
        day_clock = clock.after(day_clock)
        blocks += clock.blocks
    return plan, windows


@dataclass(frozen=True)
class WindowClock:
    """What a window's valid times of day (file order) tell the windows after it, a few numbers whatever the
    window: its first ANCHOR_REPORTS and last ANCHOR_FOLLOWERS times, how many; and of its reports after the
    first ANCHOR_FOLLOWERS (whose agreeing depends on no earlier window) those that agree with the ones
    before them: the first and last time and the midnights between them; its last time; its data blocks."""

    head: np.ndarray
    tail: np.ndarray
    count: int
    agreed_first_s: float
    agreed_last_s: float
    midnights: int
    last_s: float
    blocks: int

    @classmethod
    def of(cls, valid: np.ndarray, blocks: int) -> WindowClock:
        """The WindowClock of a window's valid times of day (file order) and its data blocks."""
        first_s, last_s, midnights = agreed_run(valid[ANCHOR_FOLLOWERS:], valid[:ANCHOR_FOLLOWERS])
        return cls(valid[:ANCHOR_REPORTS].copy(), valid[-ANCHOR_FOLLOWERS:].copy(), len(valid), first_s,
                   last_s, midnights, float(valid[-1]) if len(valid) else np.nan, blocks)

    def after(self, clock: DayClock) -> DayClock:
        """The clock after the window from the clock before it: timeline.file_order_days's, exactly."""
        if not self.count:
            return clock
        _, clock = count_days(self.head[:ANCHOR_FOLLOWERS], clock)
        if self.count <= ANCHOR_FOLLOWERS:
            return clock
        day, ref_s = clock.day, clock.ref_tod_s
        if np.isfinite(self.agreed_first_s):
            step = np.array([self.agreed_first_s - ref_s])
            day, ref_s = day + int(_steps(step)[0]) + self.midnights, self.agreed_last_s
        return DayClock(day, ref_s, self.tail, day + int(_steps(np.array([self.last_s - ref_s]))[0]))


def _window_times(args: tuple) -> WindowClock:
    """A window's WindowClock (in a pool process): its times of day decoded alone."""
    path, plan, framed = args
    with _mapped(path) as buf:
        rec = decode_framed(buf, plan, framed, path=path, selected=selected_columns(["time_of_day"]))
    parts = [f for f in rec.frames.values() if len(f["offset"])]
    t = _file_order(parts)[1] if parts else np.zeros(0)
    return WindowClock.of(t[np.isfinite(t)], rec.blocks)


def decode_window(path, plan: Plan, window: Window, *, strict: bool = False, columns=None) -> Recording:
    """One window of plan_windows decoded: the records, days, timestamps and block numbers iter_read gives
    them."""
    strict = check_strict(strict)
    with _mapped(path) as buf:
        rec = decode_framed(buf, plan, window.framed, path=str(path), date=window.date, strict=strict,
                            selected=selected_columns(columns))
    for f in rec.frames.values():
        f["block"] += window.blocks_before
    file_order_days(rec.frames, window.clock)
    restamp(rec.frames, window.date)
    return rec
