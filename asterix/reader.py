"""``read``: a recording in, one typed DataFrame per category out, with an account of what was skipped."""

from __future__ import annotations

import datetime as dt
import mmap
import os
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from . import kernel
from .containers import Segments, read_segments
from .errors import REASONS, DecodeError, UnreadableInput
from .frames import empty_column, typed_column
from .layout import Layout, compile_layout
from .tables import resolve_edition
from .timeline import assign_days, timestamp_index

DECODABLE = (21, 34, 48)
# Decoded when categories=None. CAT034 (service messages) is decoded on request (categories=DECODABLE):
# until the pipeline handles its frames, its blocks are stepped over and counted as ignored.
DEFAULT_CATEGORIES = (21, 48)
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
    wanted = set(DEFAULT_CATEGORIES if categories is None else categories)
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
            errors += [(int(o), int(n), cat, f"unknown category {cat} (msdc decodes CAT021, 034, 048)")
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
    first_day = assign_days(columns, seg, b_seg)
    if first_day is not None and seg.dated:
        date = dt.date(1970, 1, 1) + dt.timedelta(days=first_day)
    frames: dict[int, pd.DataFrame] = {}
    for cat in list(columns):
        cols = columns.pop(cat)
        cols["timestamp"] = timestamp_index(cols["day"], cols["time_of_day"], date)
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
    """Decode a recording file (raw, pcap/pcapng, final, gps or oradis) into typed frames by category."""
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


def categories_in(path, *, format: str | None = None) -> dict[int, int]:
    """Data blocks per category in a recording, from framing alone (fast: no record is walked)."""
    with _mapped(path) as buf:
        seg = read_segments(buf, format)
        known = np.zeros(256, np.uint8)
        known[list(DECODABLE)] = 1
        cats = kernel.frame_blocks(buf, seg.start, seg.stop, seg.exact, known)[2]
        values, counts = np.unique(cats, return_counts=True)
        return {int(v): int(n) for v, n in zip(values, counts, strict=True)}
