"""``read`` and ``iter_read``: recordings in, one typed DataFrame per category out."""

from __future__ import annotations

import datetime as dt
import mmap
import os
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from . import kernel
from .containers import Segments, read_segments
from .errors import REASONS, DecodeError, UnreadableInput
from .frames import empty_column, typed_column
from .layout import Layout, compile_layout
from .tables import resolve_edition

DECODABLE = (21, 48)
AUTO_CANDIDATES = {21: ("2.7", "0.26", "0.23")}
ERROR_COLUMNS = ["file", "offset", "length", "category", "reason"]


@dataclass
class Recording:
    """Decoded recording: frames by category, the error account, and how it was read."""

    frames: dict[int, pd.DataFrame]
    errors: pd.DataFrame
    editions: dict[int, str]
    path: str = ""
    format: str = ""
    date: dt.date | None = None
    size_bytes: int = 0
    container_bytes: int = 0
    decoded_bytes: int = 0
    ignored_blocks: dict[int, int] = field(default_factory=dict)  # blocks of unselected categories
    ignored_bytes: int = 0
    edition_choice: dict[int, str] = field(default_factory=dict)  # how 'auto' chose, in words
    day0: int | None = None  # container day number of day 0: capture day (pcap), day byte (final); raw None

    def __getitem__(self, category: int) -> pd.DataFrame:
        return self.frames[category]


def _parse_date(date) -> dt.date | None:
    if date is None or isinstance(date, dt.date):
        return date
    return dt.date.fromisoformat(str(date))


@contextmanager
def _mapped(path) -> Iterator[np.ndarray]:
    """The file as a read-only uint8 array, memory-mapped while the block runs."""
    try:
        with open(path, "rb") as fh:
            size = os.fstat(fh.fileno()).st_size
            mm = mmap.mmap(fh.fileno(), 0, access=mmap.ACCESS_READ) if size else None
    except OSError as exc:
        raise UnreadableInput(f"{path}: cannot read: {exc.strerror or exc}") from exc
    buf = np.frombuffer(mm, np.uint8) if mm is not None else np.zeros(0, np.uint8)
    try:
        yield buf
    finally:
        del buf
        if mm is not None:
            try:
                mm.close()
            except BufferError:  # frames still view the map: the OS unmaps it when they go
                pass


def _scan(buf, starts, lens, lay: Layout):
    """One walk over the blocks: records per block (minus an error code for a bad block), where
    bad walks failed, and where each part of each good record lies (arrays sized by numpy)."""
    cap = int(lens.sum()) // 40 + 16  # a first guess at the record count, doubled until it fits
    slots = max(lay.n_slots, 1)
    while True:
        rel_off = np.full((cap, slots), 0xFFFF, np.uint16)
        rel_len = np.zeros((cap, slots), np.uint16)
        rec_off, rec_blk = np.empty(cap, np.int64), np.empty(cap, np.int64)
        counts, fail_at, n = kernel.scan(buf, starts, lens, lay.P, lay.ext_sizes, lay.sub_parts, lay.n_frn,
                                         lay.n_slots, rel_off, rel_len, rec_off, rec_blk)
        if n >= 0:
            return counts, fail_at, rel_off, rel_len, rec_off, rec_blk, n
        cap *= 2


def choose_edition(buf: np.ndarray, starts: np.ndarray, lens: np.ndarray, category: int,
                   sample: int = 400) -> tuple[str, str]:
    """Pick the edition family under which a sample of blocks walks exactly with plausible values."""
    idx = np.unique(np.linspace(0, len(starts) - 1, min(sample, len(starts))).astype(np.int64))
    s, n = starts[idx], lens[idx]
    scores = []
    for ed in AUTO_CANDIDATES[category]:
        lay = compile_layout(category, ed)
        scanned = _scan(buf, s, n, lay)
        counts = scanned[0]
        good = counts > 0
        plausible = 0.0
        if good.any():
            fl, _, _, _ = _extract(buf, scanned, lay)
            cols = {nm: fl[i] for i, nm in enumerate(lay.out_names_float)}
            lat, lon, tod = cols["latitude"], cols["longitude"], cols["time_of_day"]
            ok = (np.abs(lat) <= 90) & (np.abs(lon) <= 180) & (tod >= 0) & (tod < 86400)
            plausible = float(np.mean(ok)) if len(ok) else 0.0
        scores.append((float(good.mean()) if len(good) else 0.0, plausible, ed))
    best = max(scores, key=lambda t: (t[0], t[1]))
    words = "; ".join(f"{ed}: {w:.0%} of sampled blocks walk, {p:.0%} plausible" for w, p, ed in scores)
    return best[2], f"chose {best[2]} ({words})"


def _extract(buf, scanned, lay: Layout):
    """Gather every field of the scanned records into column matrices."""
    _, _, rel_off, rel_len, rec_off, rec_blk, n = scanned
    fl = np.full((len(lay.out_names_float), n), np.nan)
    it = np.full((len(lay.out_names_int), n), -1, np.int32)
    wd = np.full((len(lay.out_names_wide), n), -1, np.int64)
    kernel.gather(buf, rec_off[:n], rel_off[:n], rel_len[:n], lay.F, lay.f_mult, fl, it, wd)
    return fl, (it, wd), rec_off[:n].copy(), rec_blk[:n].copy()


def _columns(lay: Layout, fl, ints, rec_off, rec_blk) -> dict[str, object]:
    """The typed columns of one category from kernel arrays, in schema order."""
    n = rec_off.shape[0]
    it, wd = ints
    where = {nm: (fl, i) for i, nm in enumerate(lay.out_names_float)}
    where |= {nm: (it, i) for i, nm in enumerate(lay.out_names_int)}
    where |= {nm: (wd, i) for i, nm in enumerate(lay.out_names_wide)}
    data: dict[str, object] = {}
    for col in lay.columns:
        if not any(src[0] in lay.item_frn for src in col.sources):
            data[col.name] = empty_column(col, n)
            continue
        matrix, row = where[col.name]
        data[col.name] = matrix[row] if matrix is fl else typed_column(col, matrix[row])
    data["block"] = rec_blk
    data["offset"] = rec_off
    return data


def _days(frames: dict[int, dict], seg: Segments, blk_seg: np.ndarray) -> int | None:
    """Add the ``day`` column (days after the first) to each category's columns; return the
    container's day number of day 0 (days since 1970 when ``seg.dated``), None for raw streams."""
    parts = [(c, f) for c, f in frames.items() if len(f["offset"])]
    if not parts:
        for f in frames.values():
            f["day"] = np.zeros(0, np.int64)
        return None
    if seg.format in ("raw",) or not len(seg.start):
        # file order across categories; a drop of more than 12 h is a new day, a rise of more
        # than 12 h a late report from the day before
        off = np.concatenate([np.asarray(f["offset"]) for _, f in parts])
        tod = np.concatenate([np.asarray(f["time_of_day"]) for _, f in parts])
        order = np.argsort(off, kind="stable")
        t = pd.Series(tod[order]).ffill().bfill().to_numpy()
        d = np.diff(t, prepend=t[:1] if len(t) else t)
        day_sorted = np.cumsum(d < -43200) - np.cumsum(d > 43200)
        day = np.empty_like(day_sorted)
        day[order] = day_sorted
        first = int(day.min())
        i = 0
        for _, f in parts:
            n = len(f["offset"])
            f["day"] = (day[i:i + n] - first).astype(np.int64)
            i += n
        first_day = None
    else:
        # container capture time: the day that puts the report nearest its capture
        all_days = []
        for _, f in parts:
            s = blk_seg[np.asarray(f["block"])]
            cday, ctod = seg.capture_day[s], seg.capture_tod[s]
            tod = np.asarray(f["time_of_day"])
            tod = np.where(np.isnan(tod), ctod, tod)
            all_days.append(cday + np.rint((ctod - tod) / 86400.0).astype(np.int64))
        first_day = int(min(a.min() for a in all_days))
        for (_, f), a in zip(parts, all_days, strict=True):
            f["day"] = a - first_day
    for f in frames.values():
        if "day" not in f:
            f["day"] = np.zeros(len(f["offset"]), np.int64)
    return first_day


def _timestamp(day, tod, date: dt.date | None) -> pd.DatetimeIndex:
    """UTC timestamps from day offsets and times of day (NaT when the date or the time is unknown)."""
    day, tod = np.asarray(day), np.asarray(tod)
    if date is None:
        return pd.DatetimeIndex(np.full(len(day), np.datetime64("NaT"), "datetime64[ns]")).tz_localize("UTC")
    ns = np.rint((day * 86400.0 + tod) * 1e9)
    missing = np.isnan(ns)
    vals = np.datetime64(date, "ns") + np.where(missing, 0, ns).astype("timedelta64[ns]")
    vals[missing] = np.datetime64("NaT")
    return pd.DatetimeIndex(vals).tz_localize("UTC")


def _timestamps(frames: dict[int, pd.DataFrame], date: dt.date | None) -> None:
    """Recompute the timestamp column of finished frames (after a day shift)."""
    for f in frames.values():
        f["timestamp"] = _timestamp(f["day"], f["time_of_day"], date)


LEADING = ("sac", "sic", "time_of_day", "day", "timestamp")


def _build(cols: dict[str, object]) -> pd.DataFrame:
    """One DataFrame in schema order (identity and time first, provenance last), built once."""
    order = [*LEADING, *(c for c in cols if c not in LEADING and c not in ("block", "offset")), "block",
             "offset"]
    return pd.DataFrame({c: cols[c] for c in order}, copy=False)


def decode_buffer(buf: np.ndarray, seg: Segments, *, path: str = "", editions: dict | None = None,
                  categories=None, date=None, strict: bool = False) -> Recording:
    """Decode an in-memory recording whose container segments are already known."""
    editions = dict(editions or {})
    wanted = set(DECODABLE if categories is None else categories)
    known = np.zeros(256, np.uint8)
    known[list(DECODABLE)] = 1
    b_start, b_len, b_cat, b_seg, e_off, e_len, e_cat, e_code = kernel.frame_blocks(
        buf, seg.start, seg.stop, seg.exact, known)
    errors: list[tuple[int, int, int, str]] = [
        (int(o), int(n), int(c), REASONS[int(code)])
        for o, n, c, code in zip(e_off, e_len, e_cat, e_code, strict=True)]
    errors += [(o, n, -1, f"container: {why}") for o, n, why in seg.problems]
    columns: dict[int, dict] = {}
    chosen: dict[int, str] = {}
    choice: dict[int, str] = {}
    ignored: dict[int, int] = {}
    decoded_bytes = ignored_bytes = 0
    for cat in (int(c) for c in np.unique(b_cat)):
        sel = np.flatnonzero(b_cat == cat)
        if cat not in DECODABLE:
            errors += [(int(o), int(n), cat, f"unknown category {cat} (msdc decodes CAT021 and CAT048)")
                       for o, n in zip(b_start[sel], b_len[sel], strict=True)]
            continue
        if cat not in wanted:
            ignored[cat] = len(sel)
            ignored_bytes += int(b_len[sel].sum())
            continue
        starts, lens = b_start[sel], b_len[sel]
        ed = editions.get(cat)
        if ed == "auto":
            ed, choice[cat] = choose_edition(buf, starts, lens, cat)
        lay = compile_layout(cat, ed)
        chosen[cat] = lay.edition
        scanned = _scan(buf, starts, lens, lay)
        counts, fail_at = scanned[0], scanned[1]
        for j in np.flatnonzero(counts < 0):
            reason = f"{REASONS[int(-counts[j])]} (record at offset {int(fail_at[j])})"
            errors.append((int(starts[j]), int(lens[j]), cat, reason))
        decoded_bytes += int(lens[counts > 0].sum())
        fl, ints, rec_off, rec_blk = _extract(buf, scanned, lay)
        del scanned
        columns[cat] = _columns(lay, fl, ints, rec_off, sel[rec_blk])
        del fl, ints
    errors.sort()
    if strict and errors:
        o, _, c, why = errors[0]
        raise DecodeError(path, o, why, c)
    date = _parse_date(date)
    first_day = _days(columns, seg, b_seg)
    if first_day is not None and seg.dated:
        date = dt.date(1970, 1, 1) + dt.timedelta(days=first_day)
    frames: dict[int, pd.DataFrame] = {}
    for cat in list(columns):
        cols = columns.pop(cat)
        cols["timestamp"] = _timestamp(cols["day"], cols["time_of_day"], date)
        frames[cat] = _build(cols)
        del cols
    err = pd.DataFrame(errors, columns=["offset", "length", "category", "reason"])
    err.insert(0, "file", path)
    err["category"] = err["category"].astype("Int16").where(err["category"] >= 0)
    return Recording(frames, err, chosen, path, seg.format, date, int(len(buf)), int(seg.container_bytes),
                     decoded_bytes, ignored, ignored_bytes, choice, first_day)


def _parse_editions(editions) -> dict[int, str]:
    """Accept {21: "0.26"} or ["21=0.26", ...] or "21=0.26"."""
    if editions is None:
        return {}
    if isinstance(editions, str):
        editions = [editions]
    if isinstance(editions, dict):
        return {int(k): str(v) for k, v in editions.items()}
    out = {}
    for item in editions:
        cat, _, ed = str(item).partition("=")
        out[int(cat)] = ed
    return out


def read(path, *, editions=None, date=None, categories=None, format: str | None = None,
         strict: bool = False) -> Recording:
    """Decode a recording file (raw blocks, pcap/pcapng or final) into typed frames by category."""
    eds = _parse_editions(editions)
    for cat, ed in eds.items():
        if ed != "auto":
            resolve_edition(cat, ed)
    with _mapped(path) as buf:
        try:
            seg = read_segments(buf, format)
        except ValueError as exc:
            raise UnreadableInput(f"{path}: {exc}") from exc
        return decode_buffer(buf, seg, path=str(path), editions=eds, categories=categories, date=date,
                             strict=strict)


def iter_read(path, *, chunk: int = 1_000_000, editions=None, date=None, categories=None,
              format: str | None = None, strict: bool = False) -> Iterator[Recording]:
    """Stream a recording in chunks of about ``chunk`` bytes of payload, yielding a Recording each.

    Days and timestamps continue across chunks; memory stays bounded by the chunk size.
    """
    eds = _parse_editions(editions)
    with _mapped(path) as buf:
        seg = read_segments(buf, format)
        bounds = _chunk_bounds(buf, seg, chunk)
        carry_day = 0
        last_tod = np.nan
        first_date = _parse_date(date)
        day0 = None  # container day number of the first chunk's day 0
        for sub in bounds:
            rec = decode_buffer(buf, sub, path=str(path), editions=eds, categories=categories,
                                date=first_date, strict=strict)
            if seg.format == "raw":
                carry_day, last_tod = _continue_days(rec, carry_day, last_tod, first_date)
            elif rec.day0 is not None and day0 is None:
                day0, first_date = rec.day0, rec.date  # a dated container's date wins over date=
            elif rec.day0 is not None and rec.day0 != day0:
                # each chunk counts days from its own first: count them from the first chunk's
                for f in rec.frames.values():
                    f["day"] += rec.day0 - day0
                _timestamps(rec.frames, first_date)
                rec.date, rec.day0 = first_date, day0
            eds = {**eds, **{c: e for c, e in rec.editions.items() if eds.get(c) == "auto"}}
            yield rec


def _continue_days(rec: Recording, carry_day: int, last_tod: float, date) -> tuple[int, float]:
    """Carry the midnight count of a raw stream from one chunk to the next."""
    firsts = [(f["offset"].iloc[0], f["time_of_day"].iloc[0]) for f in rec.frames.values() if len(f)]
    if not firsts:
        return carry_day, last_tod
    first_tod = min(firsts)[1]
    if not np.isnan(last_tod) and not np.isnan(first_tod) and first_tod < last_tod - 43200:
        carry_day += 1
    for f in rec.frames.values():
        f["day"] += carry_day
    _timestamps(rec.frames, date)
    lasts = [(f["offset"].iloc[-1], f["time_of_day"].iloc[-1], f["day"].iloc[-1])
             for f in rec.frames.values() if len(f)]
    _, tod, day = max(lasts)
    return int(day), float(tod)


def _chunk_bounds(buf: np.ndarray, seg: Segments, chunk: int):
    """Split the segments into groups of about ``chunk`` bytes, cutting raw streams at block starts."""
    out = []
    if seg.format == "raw" and len(seg.start):
        known = np.zeros(256, np.uint8)
        known[list(DECODABLE)] = 1
        b_start, _, _, _, _, _, _, _ = kernel.frame_blocks(buf, seg.start, seg.stop, False, known)
        cuts = [int(seg.start[0])]
        for s in b_start:
            if s - cuts[-1] >= chunk:
                cuts.append(int(s))
        cuts.append(int(seg.stop[0]))
        for lo, hi in zip(cuts[:-1], cuts[1:], strict=True):
            sub = _sub_segments(seg, np.array([lo]), np.array([hi]), np.array([0]))
            out.append(sub)
        return out
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


def categories_in(path, *, format: str | None = None) -> dict[int, int]:
    """Data blocks per category in a recording, from framing alone (fast: no record is walked)."""
    with _mapped(path) as buf:
        seg = read_segments(buf, format)
        known = np.zeros(256, np.uint8)
        known[list(DECODABLE)] = 1
        cats = kernel.frame_blocks(buf, seg.start, seg.stop, seg.exact, known)[2]
        values, counts = np.unique(cats, return_counts=True)
        return {int(v): int(n) for v, n in zip(values, counts, strict=True)}


def read_path_list(paths, **kw) -> list[Recording]:
    """Read several recordings with the same options."""
    return [read(Path(p), **kw) for p in paths]
