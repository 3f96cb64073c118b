"""``iter_read``: decode a recording in bounded chunks, days and timestamps continuing across them."""

from __future__ import annotations

import dataclasses
from collections.abc import Iterator

import numpy as np

from .cat001_time import SectorClock
from .containers import UNTIMED, Segments, read_segments
from .errors import UnreadableInput
from .reader import (
    Recording,
    _mapped,
    check_categories,
    choose_editions,
    decode_buffer,
    frame_checked,
    framing_walk,
    parse_date,
    reading_editions,
    release_pages,
    selected_columns,
)
from .timeline import ANCHOR_REPORTS, file_order_days, first_report_day, known_captures, restamp, valid_times

HOLD_BYTES = 1 << 22  # a raw stream's first chunks held at most until day 0 is anchored (payload bytes)


def iter_read(path, *, chunk: int = 1_000_000, editions=None, date=None, categories=None,
              format: str | None = None, strict: bool = False, columns=None) -> Iterator[Recording]:
    """Stream a recording in chunks of about ``chunk`` bytes of payload, yielding a Recording each
    (``columns``: only those decoded columns, as in ``read``).

    Days, timestamps and the ``block`` index continue across chunks; memory stays bounded by the chunk
    size.
    """
    if isinstance(chunk, bool) or not isinstance(chunk, int | np.integer):
        raise TypeError(f"chunk {chunk!r}: must be a whole number of bytes (an int), not a "
                        f"{type(chunk).__name__}")
    if chunk <= 0:
        raise ValueError(f"chunk {chunk!r}: must be a positive number of bytes")
    selected_columns(columns)
    first_date, categories = parse_date(date), check_categories(categories)
    eds = reading_editions(editions, categories)
    with _mapped(path) as buf:
        try:
            seg = read_segments(buf, format)
        except ValueError as exc:  # as read() says it
            raise UnreadableInput(f"{path}: {exc}") from exc
        eds, choice = choose_editions(buf, seg, eds, categories)  # over the whole file, as read() does
        bounds = _chunk_bounds(buf, seg, chunk, eds, categories)
        release_pages(buf, 0, len(buf))  # planning the chunks read the whole file
        clock = None  # a raw stream's (day, time of day) at the end of the chunks before; None: not anchored
        pending: list[Recording] = []  # a raw stream's first chunks, held until day 0 is anchored
        seen = np.zeros(0)  # their valid times of day in file order (the first ANCHOR_REPORTS)
        held = 0  # their payload bytes
        day0 = None  # container day number of the first chunk's day 0
        blocks = 0  # data blocks framed in the chunks before: each chunk numbers its own from 0
        sectors = SectorClock()  # each radar's last CAT002 time: CAT001 times continue across chunks
        for sub in bounds:
            rec = decode_buffer(buf, sub, path=str(path), editions=eds, categories=categories,
                                date=first_date, strict=strict, columns=columns, sector_clock=sectors)
            rec.edition_choice = {**choice, **rec.edition_choice}
            for f in rec.frames.values():
                f["block"] += blocks
            blocks += rec.blocks
            eds = {**eds, **{c: e for c, e in rec.editions.items() if eds.get(c) == "auto"}}
            if len(sub.start):
                release_pages(buf, int(sub.start.min()), int(sub.stop.max()))
            if seg.format in UNTIMED and clock is None:
                pending.append(rec)
                seen = np.concatenate([seen, valid_times(rec.frames)])[:ANCHOR_REPORTS]
                held += int((sub.stop - sub.start).sum())
                if len(seen) < ANCHOR_REPORTS and held < HOLD_BYTES:
                    continue
                clock = (first_report_day(seen), np.nan)
                for held_rec in pending:
                    clock = file_order_days(held_rec.frames, *clock)
                    restamp(held_rec.frames, first_date)
                    yield held_rec
                pending = []
                continue
            if seg.format in UNTIMED:
                clock = file_order_days(rec.frames, *clock)
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
        clock = (first_report_day(seen), np.nan)
        for held_rec in pending:  # a short file: fewer valid times of day than settle day 0
            clock = file_order_days(held_rec.frames, *clock)
            restamp(held_rec.frames, first_date)
            yield held_rec


def _chunk_bounds(buf: np.ndarray, seg: Segments, chunk: int, eds: dict, categories):
    """Split the segments into groups of about ``chunk`` bytes, cutting raw streams at block starts."""
    out = []
    if seg.format == "raw" and len(seg.start):
        b_start = frame_checked(buf, seg, framing_walk(buf, seg, eds, categories))[0]
        cuts = [int(seg.start[0])]
        for s in b_start:
            if s - cuts[-1] >= chunk:
                cuts.append(int(s))
        cuts.append(int(seg.stop[0]))
        for lo, hi in zip(cuts[:-1], cuts[1:], strict=True):
            sub = _sub_segments(seg, np.array([lo]), np.array([hi]), np.array([0]))
            out.append(sub)
        return out
    day, tod = known_captures(seg)  # untimed packets (pcapng SPB) take their neighbour's capture time
    if day is not None:
        seg = dataclasses.replace(seg, capture_day=day, capture_tod=tod)
    sizes = np.cumsum(seg.stop - seg.start)
    group = (sizes // max(chunk, 1)).astype(np.int64)
    for g in np.unique(group):
        idx = np.flatnonzero(group == g)
        sub = _sub_segments(seg, seg.start[idx], seg.stop[idx], idx)
        out.append(sub)
    if not len(seg.start):
        out.append(seg)
    return out


def _sub_segments(seg: Segments, start, stop, idx) -> Segments:
    first = len(idx) and idx[0] == 0
    return Segments(seg.format, np.asarray(start, np.int64), np.asarray(stop, np.int64),
                    seg.capture_day[idx] if len(seg.capture_day) else np.full(len(idx), -1, np.int64),
                    seg.capture_tod[idx] if len(seg.capture_tod) else np.full(len(idx), np.nan),
                    seg.dated, seg.exact, seg.container_bytes if first else 0,
                    seg.problems if first else [])
