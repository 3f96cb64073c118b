"""``read``: a recording in, one typed DataFrame per category out, with an account of what was skipped."""

from __future__ import annotations

import datetime as dt
import mmap
import os
import warnings
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from functools import cache

import numpy as np
import pandas as pd

from . import bds, kernel
from .cat001_time import PLOT_CATEGORY, UNTIMED_COLUMNS, SectorClock, time_cat001, untimed_advice
from .categories import DECODABLE, MEASUREMENT_CATEGORIES, REGISTRY
from .columns import FAMILIES
from .containers import Segments, read_segments
from .errors import REASONS, DecodeError, EditionWarning, UnreadableInput, UntimedWarning
from .frames import code_list_column, empty_columns, icao_columns, typed_column
from .layout import OUT_FLOAT, OUT_INT, OUT_WIDE, Layout, compile_layout
from .tables import available, resolve_edition
from .timeline import assign_days, timestamp_index

# Decoded when categories=None: the measurement categories. CAT034 (service messages) is decoded on
# request (categories=DECODABLE): until the pipeline handles its frames, its blocks are stepped over and
# counted as ignored.
DEFAULT_CATEGORIES = MEASUREMENT_CATEGORIES
WRONG_EDITION_MIN_BLOCKS = 10  # failed blocks, all walking under another edition, proving the edition wrong
AUTO_SAMPLE_BLOCKS = 20_000  # blocks walked per candidate edition by editions={cat: "auto"}
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
    ignored_blocks: dict[int, int] = field(default_factory=dict)  # blocks per category not decoded
    ignored_bytes: int = 0
    edition_choice: dict[int, str] = field(default_factory=dict)  # how 'auto' chose, in words
    day0: int | None = None  # container day number of day 0: capture day (pcap), day byte (final); raw None
    ignored_category_bytes: dict[int, int] = field(default_factory=dict)  # bytes per category not decoded
    # a category most of whose blocks fail under its edition: the other editions under which every one
    # of them sampled walks (a likely wrong edition; it is said, not switched: nothing on the wire says)
    edition_fits: dict[int, tuple[str, ...]] = field(default_factory=dict)
    blocks: int = 0  # data blocks framed, of every category (the ``block`` column numbers them)
    # CAT001 records whose truncated time of day no CAT002 message made whole (cat001_time): offset,
    # category, sac, sic, reason; their time_of_day is NaN
    untimed: pd.DataFrame = field(default_factory=lambda: pd.DataFrame(columns=UNTIMED_COLUMNS))

    @property
    def ignored(self) -> pd.DataFrame:
        """Blocks of categories not decoded (other categories, or not selected): category, blocks, bytes."""
        return pd.DataFrame({"category": list(self.ignored_blocks),
                             "blocks": list(self.ignored_blocks.values()),
                             "bytes": [self.ignored_category_bytes.get(c, 0) for c in self.ignored_blocks]},
                            columns=["category", "blocks", "bytes"])

    def __getitem__(self, category: int) -> pd.DataFrame:
        return self.frames[category]


_ALWAYS = ("day", "timestamp", "block", "offset")  # built for every frame


def selected_columns(columns) -> tuple[str, ...] | None:
    """Decoded column names to compile (sorted; ``NAME_hex`` asks for ``NAME``), or None for all;
    ValueError naming a column no category has."""
    if columns is None:
        return None
    known = {c.name for family in FAMILIES.values() for c in family}
    names = set()
    for name in ([columns] if isinstance(columns, str) else columns):
        base = name[:-4] if name.endswith("_hex") and name[:-4] in known else name
        if base not in known and base not in _ALWAYS:
            raise ValueError(f"columns: no decoded column is named {name!r} (see docs/columns.md)")
        if base not in _ALWAYS:
            names.add(base)
    return tuple(sorted(names))


# Timestamps are datetime64[ns] (1677-09-21 .. 2262-04-11): a day outside these years, or its
# neighbours (late reports from the day before, a recording past midnight), would wrap silently.
FIRST_DATE, LAST_DATE = dt.date(1678, 1, 1), dt.date(2261, 12, 31)


def parse_date(date, name: str = "date") -> dt.date | None:
    """The UTC calendar day ``date`` names (FIRST_DATE .. LAST_DATE): a datetime.date, an ISO text
    ("2019-03-01"), or a datetime or pandas Timestamp at midnight (naive or UTC). One with a time of day
    or another time zone would shift every timestamp, and a day outside the nanosecond timestamps' span
    would wrap them, so they are refused (ValueError), and so is an integer (nanoseconds or YYYYMMDD?: it
    says neither) or any other type (TypeError); ``name`` is the argument the message names."""
    day = _calendar_day(date, name)
    if day is not None and not FIRST_DATE <= day <= LAST_DATE:
        raise ValueError(f"{name} {day.isoformat()}: outside the days msdc can time ({FIRST_DATE} to "
                         f"{LAST_DATE}: nanosecond UTC timestamps); give the UTC day of the recording")
    return day


def _calendar_day(date, name: str) -> dt.date | None:
    """The day ``date`` names, any year (parse_date's rules but the range)."""
    if date is None:
        return None
    if isinstance(date, np.datetime64):
        date = pd.Timestamp(date)
    if isinstance(date, str):
        text = date.strip()
        try:
            return dt.date.fromisoformat(text)
        except ValueError:
            try:
                date = dt.datetime.fromisoformat(text)
            except ValueError:
                raise ValueError(f"{name} {date!r}: not a date; give the UTC day as YYYY-MM-DD") from None
    if isinstance(date, dt.datetime):
        if pd.isna(date):
            raise ValueError(f"{name} {date!r}: not a date; give the UTC day as YYYY-MM-DD")
        offset = date.utcoffset()
        if offset is not None and offset != dt.timedelta(0):
            raise ValueError(f"{name} {date!s}: a time in zone {date.tzname()}, not a UTC calendar day; "
                             f"ASTERIX times are UTC: give the UTC day as YYYY-MM-DD")
        if date.time() != dt.time(0):
            raise ValueError(f"{name} {date!s}: carries a time of day ({date.time()}), which would shift "
                             f"every timestamp; give the UTC day alone (YYYY-MM-DD)")
        return date.date()
    if isinstance(date, dt.date):
        return date
    why = ("an integer says neither YYYYMMDD nor nanoseconds" if isinstance(date, int | np.integer)
           else f"{type(date).__name__} is not a date type")
    raise TypeError(f"{name} {date!r}: {why}; give the UTC day as a 'YYYY-MM-DD' text or a datetime.date")



def check_categories(categories) -> tuple[int, ...] | None:
    """``categories`` as a tuple of the categories msdc decodes (one int is one category; None: the
    default); TypeError for what is not an int or a sequence of ints, ValueError for a category msdc does
    not decode (asking for it would return no frame, silently)."""
    if categories is None:
        return None
    items = (categories,) if isinstance(categories, int | np.integer) else categories
    if isinstance(items, str | bytes) or not hasattr(items, "__iter__"):
        raise TypeError(f"categories {categories!r}: give a category number or a sequence of them, "
                        f"e.g. (21, 48)")
    out = []
    for c in items:
        if isinstance(c, bool) or not isinstance(c, int | np.integer):
            raise TypeError(f"categories {categories!r}: {c!r} is not a category number (an int)")
        if int(c) not in DECODABLE:
            raise ValueError(f"categories {categories!r}: msdc does not decode CAT{int(c):03d}; it decodes "
                             f"{', '.join(f'CAT{d:03d}' for d in DECODABLE)} (other categories' blocks are "
                             f"counted in Recording.ignored)")
        out.append(int(c))
    return tuple(out)


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


def release_pages(buf: np.ndarray, start: int, stop: int) -> None:
    """Drop the pages of a memory-mapped file between two offsets from this process (the data stay in the
    page cache and fault back in if read again), so a file read in chunks is not held in memory whole."""
    mm = getattr(getattr(buf, "base", None), "obj", None)
    if not isinstance(mm, mmap.mmap) or not hasattr(mmap, "MADV_DONTNEED") or stop <= start:
        return
    lo = start // mmap.PAGESIZE * mmap.PAGESIZE
    hi = min(stop, len(mm))
    if hi > lo:
        mm.madvise(mmap.MADV_DONTNEED, lo, hi - lo)


SIZE_SAMPLE_BLOCKS = 64  # blocks walked, spread over the recording, to guess the record count
SIZE_SAMPLE_BYTES = 1 << 18  # at most this many bytes of them


def _record_guess(buf, starts, lens, lay: Layout) -> int:
    """A first guess at the record count of these blocks (5 % over), from the records per byte of up to
    SIZE_SAMPLE_BLOCKS blocks spread over them (SIZE_SAMPLE_BYTES at most); the category's typical record
    size when none of those walks. A guess short of the count walks everything twice (records of about 30
    bytes, the real CAT010 and CAT021 0.23 recordings, did with 1 per 40 bytes)."""
    k = _spread(len(starts), SIZE_SAMPLE_BLOCKS)
    k = k[:max(1, int(np.searchsorted(np.cumsum(lens[k]), SIZE_SAMPLE_BYTES, side="right")))]
    cap = int(lens[k].sum()) // 8 + 16  # records past it: the blocks walked before are enough to judge
    slots = max(lay.n_slots, 1)
    rel_off = np.full((cap, slots), 0xFFFF, np.uint16)
    counts, _, _ = kernel.scan(buf, starts[k], lens[k], lay.parts, lay.n_frn, lay.n_slots, rel_off,
                               np.zeros((cap, slots), np.uint16), np.empty(cap, np.int64),
                               np.empty(cap, np.int64))
    good = counts > 0
    if not good.any():
        return int(lens.sum()) // REGISTRY[lay.category].record_bytes + 16
    per_byte = counts[good].sum() / lens[k][good].sum()
    return int(per_byte * int(lens.sum()) * 1.05) + 16


def _scan(buf, starts, lens, lay: Layout):
    """One walk over the blocks: records per block (minus an error code for a bad block), where
    bad walks failed, and where each part of each good record lies (arrays sized by numpy)."""
    cap = _record_guess(buf, starts, lens, lay)  # doubled until it fits
    slots = max(lay.n_slots, 1)
    while True:
        rel_off = np.full((cap, slots), 0xFFFF, np.uint16)
        rel_len = np.zeros((cap, slots), np.uint16)
        rec_off, rec_blk = np.empty(cap, np.int64), np.empty(cap, np.int64)
        counts, fail_at, n = kernel.scan(buf, starts, lens, lay.parts, lay.n_frn, lay.n_slots, rel_off,
                                         rel_len, rec_off, rec_blk)
        if n >= 0:
            return counts, fail_at, rel_off, rel_len, rec_off, rec_blk, n
        cap *= 2


def _editions_oldest_first(category: int) -> list[str]:
    """The category's editions in version order."""
    return sorted(available()[category], key=lambda e: tuple(int(x) for x in e.split(".")))


def _spread(n: int, sample: int) -> np.ndarray:
    """Positions of ``sample`` of ``n`` items spread evenly (all of them when there are no more)."""
    return np.unique(np.linspace(0, n - 1, min(sample, n)).astype(np.int64))


def _walk_flags(buf: np.ndarray, starts: np.ndarray, lens: np.ndarray, category: int, ed: str) -> np.ndarray:
    """For each block, whether it walks exactly under one edition of the category (kernel.walk_flags)."""
    framing = _framing_tables(((category, ed),))
    return kernel.walk_flags(buf, starts, lens, framing.base[category], framing.nfrn[category],
                             framing.parts).astype(bool)


def choose_edition(buf: np.ndarray, starts: np.ndarray, lens: np.ndarray, category: int,
                   sample: int = AUTO_SAMPLE_BLOCKS) -> tuple[str, str]:
    """Pick the edition under which every sampled block walks exactly (the newest of those, as they read
    the sample alike), values plausible; say which blocks told the editions apart, or that none walks all.

    The sample is every block, or AUTO_SAMPLE_BLOCKS spread evenly over a longer recording: a walk costs
    no memory, so rare blocks that tell editions apart (I021/271 with an odd LW) are seen.
    """
    idx = _spread(len(starts), sample)
    s, n = starts[idx], lens[idx]
    eds = _editions_oldest_first(category)
    flags = {ed: _walk_flags(buf, s, n, category, ed) for ed in eds}
    share = {ed: float(f.mean()) for ed, f in flags.items()}
    best = max(share.values())
    tied = [ed for ed in eds if share[ed] == best]
    plaus = {ed: _plausible_share(buf, s, n, category, ed) for ed in tied} if len(tied) > 1 else {}
    top = max(plaus.values()) if plaus else None
    chosen = [ed for ed in tied if not plaus or plaus[ed] == top][-1]
    # blocks that told the contenders (editions walking at least half the sample) apart
    contenders = [ed for ed in eds if share[ed] >= 0.5] or [chosen]
    stack = np.array([flags[ed] for ed in contenders])
    apart = np.flatnonzero(stack.min(axis=0) != stack.max(axis=0))
    words = [f"{ed}: {share[ed]:.0%}" for ed in eds]
    told = ", ".join(f"offset {int(s[j])} walks under {'/'.join(ed for ed in contenders if flags[ed][j])}"
                     for j in apart[:3]) or "none"
    if best < 1:
        verdict = f"no edition walks every sampled block; best {chosen}"
    else:
        verdict = f"editions walking every sampled block: {', '.join(tied)}; newest {chosen}"
    if plaus:
        verdict += " (" + ", ".join(f"{ed} {p:.0%} plausible" for ed, p in plaus.items()) + ")"
    apart_words = (f"{len(apart)} blocks told {'/'.join(contenders)} apart: {told}" if len(contenders) > 1
                   else "no other edition walks half the sample, so none needed telling apart")
    return chosen, (f"chose {chosen} ({len(idx)} of {len(starts)} blocks sampled; blocks walking: "
                    f"{'; '.join(words)}; {verdict}; {apart_words})")


def walking_editions(buf: np.ndarray, starts: np.ndarray, lens: np.ndarray, category: int, *,
                     besides: str = "", sample: int = AUTO_SAMPLE_BLOCKS) -> tuple[str, ...]:
    """The editions (oldest first, ``besides`` left out) under which every one of these blocks walks
    exactly, or of ``sample`` of them spread evenly over a longer list."""
    idx = _spread(len(starts), sample)
    s, n = starts[idx], lens[idx]
    return tuple(ed for ed in _editions_oldest_first(category)
                 if ed != besides and _walk_flags(buf, s, n, category, ed).all())


def framing_edition(buf: np.ndarray, seg: Segments, walked: dict, category: int) -> str:
    """For an 'auto' category of a stream whose block chain breaks: the edition under which careful
    framing loses the fewest bytes (most of its blocks found on a tie, then the newest). Framing cannot
    walk a category without an edition, and would otherwise lose every block of it after the damage."""
    best: tuple | None = None
    for ed in _editions_oldest_first(category):
        framed = frame(buf, seg, {**walked, category: ed}, True)
        key = (int(framed[5].sum()), -int((framed[2] == category).sum()))
        if best is None or key <= best[0]:
            best = (key, ed)
    return best[1]


def _plausible_share(buf, s, n, category: int, ed: str, limit: int = 400) -> float:
    """Share of records of up to ``limit`` sampled blocks with a plausible position and time of day."""
    k = _spread(len(s), limit)
    lay = compile_layout(category, ed)
    scanned = _scan(buf, s[k], n[k], lay)
    if not (scanned[0] > 0).any():
        return 0.0
    where, _, _, _ = _extract(buf, scanned, lay)
    absent = np.full(int(scanned[-1]), np.nan)
    lat, lon, tod = (where[nm][0][where[nm][1]] if nm in where else absent
                     for nm in ("latitude", "longitude", "time_of_day"))
    ok = (np.abs(lat) <= 90) & (np.abs(lon) <= 180) & (tod >= 0) & (tod < 86400)
    return float(np.mean(ok)) if len(ok) else 0.0


def _extract(buf, scanned, lay: Layout):
    """Gather every field of the scanned records into column matrices: only the fields of parts some
    record carries, into rows for their columns alone (a wide edition's other columns, absent from every
    record, cost neither a pass nor memory here: ``_columns`` builds them empty)."""
    _, _, rel_off, rel_len, rec_off, rec_blk, n = scanned
    F, mult = lay.F, lay.f_mult
    if len(F):
        carried = (rel_off[:n] != 0xFFFF).any(axis=0) if n else np.zeros(rel_off.shape[1], bool)
        keep = carried[F[:, 0]]
        if not keep.all():
            F, mult = F[keep], mult[keep]
    F = np.array(F, np.int64, copy=True)
    names = {OUT_INT: lay.out_names_int, OUT_FLOAT: lay.out_names_float, OUT_WIDE: lay.out_names_wide}
    rows = {k: sorted(set(F[F[:, 5] == k, 4].tolist())) for k in names}
    for k in names:  # the kept columns' rows, numbered afresh per output kind
        renumber = np.full(len(names[k]) + 1, -1, np.int64)
        renumber[rows[k]] = np.arange(len(rows[k]))
        sel = F[:, 5] == k
        F[sel, 4] = renumber[F[sel, 4]]
    it = np.full((len(rows[OUT_INT]), n), -1, np.int32)
    fl = np.full((len(rows[OUT_FLOAT]), n), np.nan)
    wd = np.full((len(rows[OUT_WIDE]), n), -1, np.int64)
    kernel.gather(buf, rec_off[:n], rel_off[:n], rel_len[:n], np.ascontiguousarray(F),
                  np.ascontiguousarray(mult), fl, it, wd)
    matrices = {OUT_INT: it, OUT_FLOAT: fl, OUT_WIDE: wd}
    where = {names[k][r]: (matrices[k], i) for k in names for i, r in enumerate(rows[k])}
    texts = {name: code_list_column(buf, rec_off[:n], rel_off[:n, s], rel_len[:n, s])
             for name, s in lay.code_slots}
    for s in sorted({s for _, s, _ in lay.bds_slots}):  # Mode S register fields, one pass per item
        texts |= bds.decode(buf, rec_off[:n], rel_off[:n, s], rel_len[:n, s],
                            {name: path for name, slot, path in lay.bds_slots if slot == s})
    return where, texts, rec_off[:n].copy(), rec_blk[:n].copy()


def _columns(lay: Layout, where: dict, texts: dict, rec_off, rec_blk) -> dict[str, object]:
    """The typed columns of one category from kernel arrays, in schema order (``where``: the matrix and
    row of each gathered column; the others are absent from every record)."""
    n = rec_off.shape[0]
    empty = empty_columns([c for c in lay.columns if c.name not in where and c.name not in texts], n)
    data: dict[str, object] = {}
    for col in lay.columns:
        if col.name in texts:
            data[col.name] = texts[col.name]
            continue
        if col.name not in where:
            data[col.name] = empty[col.name]
            if col.kind == "icao":
                data[f"{col.name}_hex"] = empty[f"{col.name}_hex"]
            continue
        matrix, row = where[col.name]
        if col.kind == "icao":  # the raw identification beside its text (codes outside the ICAO set)
            data[col.name], data[f"{col.name}_hex"] = icao_columns(matrix[row])
            continue
        data[col.name] = matrix[row] if col.kind == "float" else typed_column(col, matrix[row])
    data["block"] = rec_blk
    data["offset"] = rec_off
    return data


LEADING = ("sac", "sic", "time_of_day", "day", "timestamp")


def _build(cols: dict[str, object]) -> pd.DataFrame:
    """One DataFrame in schema order (identity and time first, provenance last), built once."""
    order = [*LEADING, *(c for c in cols if c not in LEADING and c not in ("block", "offset")), "block",
             "offset"]
    return pd.DataFrame({c: cols[c] for c in order}, copy=False)


@cache
def _framing_tables(walked: tuple[tuple[int, str], ...]) -> kernel.Framing:
    """The layouts framing walks blocks with, packed into one part table (base[cat] = first row, -1 if
    the category is not walked), for kernel.frame_blocks."""
    base = np.full(256, -1, np.int64)
    nfrn = np.zeros(256, np.int64)
    parts, ext_sizes, ext_fx, sub_parts = [np.zeros((1, kernel.N_PART_COLUMNS), np.int64)], [], [], []
    n_parts, n_ext, n_sub = 1, 0, 0  # row 0 is a dummy: P is never empty
    for cat, ed in walked:
        lay = compile_layout(cat, ed)
        P = lay.P.copy()
        P[:, kernel.K_EXT_START] += n_ext
        P[:, kernel.K_SUB_START] += n_sub
        sub = lay.sub_parts.astype(np.int64)
        sub_parts.append(np.where(sub >= 0, sub + n_parts, -1))
        ext_sizes.append(lay.ext_sizes.astype(np.int64))
        ext_fx.append(lay.ext_fx.astype(np.int8))
        base[cat], nfrn[cat] = n_parts, lay.n_frn
        parts.append(P)
        n_parts, n_ext, n_sub = n_parts + len(P), n_ext + len(lay.ext_sizes), n_sub + len(sub)
    packed = kernel.Parts(np.ascontiguousarray(np.concatenate(parts)), _cat_or(ext_sizes, 1, np.int64),
                          _cat_or(ext_fx, 1, np.int8), _cat_or(sub_parts, -1, np.int64))
    return kernel.Framing(base, nfrn, packed)


def _cat_or(arrays: list[np.ndarray], fill: int, dtype) -> np.ndarray:
    """The arrays end to end, or a one-element placeholder (numba wants no empty tables)."""
    return np.concatenate(arrays) if arrays else np.array([fill], dtype)


def frame(buf: np.ndarray, seg: Segments, walked: dict[int, str | None] | None = None,
          careful: bool = False):
    """Data blocks of every category in the segments (kernel.frame_blocks); ``walked`` gives the
    categories (and editions) whose blocks must walk exactly where framing has to resynchronise."""
    key = tuple(sorted((c, compile_layout(c, e).edition) for c, e in (walked or {}).items()))
    return kernel.frame_blocks(buf, seg.start, seg.stop, seg.exact, careful, _framing_tables(key))


def _lone_category(b_cat: np.ndarray, walked: dict) -> bool:
    """A category not walked that has a single block: a possible false header, worth careful framing."""
    counts = np.bincount(b_cat.astype(np.int64), minlength=256)
    counts[list(walked)] = 0
    return bool((counts == 1).any())


def walked_editions(editions: dict, categories) -> dict[int, str | None]:
    """Categories whose blocks framing may walk, with their edition: the decoded ones and, when not
    selected, CAT048 (1.32 walks every edition) and those whose edition is given; never 'auto' ones."""
    wanted = set(DEFAULT_CATEGORIES if categories is None else categories)
    return {c: editions.get(c) for c in DECODABLE
            if (c in wanted or c == 48 or c in editions)
            and editions.get(c) != "auto"}


def framing_walk(buf: np.ndarray, seg: Segments, editions: dict, categories) -> dict[int, str | None]:
    """walked_editions, plus, on a stream whose block chain breaks, each decoded 'auto' category with the
    edition framing_edition finds for it (its blocks are found before its edition is chosen)."""
    walked = walked_editions(editions, categories)
    wanted = set(DEFAULT_CATEGORIES if categories is None else categories)
    auto = [c for c in DECODABLE if c in wanted and editions.get(c) == "auto"]
    if auto and not seg.exact and len(frame(buf, seg, walked, False)[4]):
        for cat in auto:
            walked[cat] = framing_edition(buf, seg, walked, cat)
    return walked


def _walking_bytes(buf: np.ndarray, framed, framing: kernel.Framing, among=None) -> int:
    """Bytes in the framed blocks of walked categories (of ``among`` only, when given) that walk exactly
    (kernel.walk_flags)."""
    b_start, b_len, b_cat = framed[:3]
    total = 0
    for cat in np.unique(b_cat):
        if framing.base[cat] < 0 or (among is not None and cat not in among):
            continue
        sel = b_cat == cat
        ok = kernel.walk_flags(buf, b_start[sel], b_len[sel], framing.base[cat], framing.nfrn[cat],
                               framing.parts).astype(bool)  # 0/1 flags: as a mask, not as indices
        total += int(b_len[sel][ok].sum())
    return total


def frame_checked(buf: np.ndarray, seg: Segments, walked: dict[int, str | None], plain=None):
    """Framing as decode_buffer settles it: the chain as it is (``plain``, framed here when not given)
    when it holds and every walked block walks, else careful framing; but a chain that holds from end
    to end is kept when careful framing walks no more bytes (blocks that do not walk are then of another
    edition, not damaged: cutting them up would lose the blocks and misreport them as framing errors)."""
    key = tuple(sorted((c, compile_layout(c, e).edition) for c, e in walked.items()))
    framing = _framing_tables(key)
    framed = plain if plain is not None else kernel.frame_blocks(buf, seg.start, seg.stop, seg.exact, False,
                                                                 framing)
    if seg.exact or (not len(framed[4]) and not _lone_category(framed[2], walked)
                     and kernel.all_walk(buf, framed[0], framed[1], framed[2], framing)):
        return framed
    careful = kernel.frame_blocks(buf, seg.start, seg.stop, seg.exact, True, framing)
    # only the categories of the holding chain count: blocks of another category that careful framing finds
    # inside them (random bytes walk as a short CAT010 or CAT020 block now and then) prove nothing
    among = set(np.unique(framed[2]).tolist())
    if not len(framed[4]) and (_walking_bytes(buf, careful, framing, among)
                               <= _walking_bytes(buf, framed, framing, among)):
        return framed
    return careful


def _scan_decoded(buf: np.ndarray, framed, decoded: list[int], editions: dict, choice: dict,
                  selected) -> dict[int, tuple]:
    """Walk the framed blocks of each decoded category: {cat: (block indices, layout, scan)}; an 'auto'
    edition is chosen on its first framing (``editions`` and ``choice`` are updated)."""
    b_start, b_len, b_cat = framed[:3]
    scans: dict[int, tuple] = {}
    for cat in decoded:
        sel = np.flatnonzero(b_cat == cat)
        if not len(sel):
            continue
        starts, lens = b_start[sel], b_len[sel]
        ed = editions.get(cat)
        if ed == "auto" and cat not in choice:
            ed, choice[cat] = choose_edition(buf, starts, lens, cat)
            editions[cat] = ed
        lay = compile_layout(cat, ed, selected)
        scans[cat] = (sel, lay, _scan(buf, starts, lens, lay))
    return scans


def decode_buffer(buf: np.ndarray, seg: Segments, *, path: str = "", editions: dict | None = None,
                  categories=None, date=None, strict: bool = False, columns=None,
                  sector_clock: SectorClock | None = None) -> Recording:
    """Decode an in-memory recording whose container segments are already known (``columns``: see
    ``read``; ``sector_clock``: the CAT002 times of the data before it, which ``iter_read`` carries)."""
    editions = dict(editions or {})
    selected = selected_columns(columns)
    date = parse_date(date)
    categories = check_categories(categories)
    decoded = [c for c in DECODABLE if c in set(DEFAULT_CATEGORIES if categories is None else categories)]
    walked = framing_walk(buf, seg, editions, categories)
    choice: dict[int, str] = {}
    # Framing first follows the block chain as it is. If it breaks, or a decoded block does not walk
    # (a LEN may be damaged), the raw stream is framed again carefully, walking the decoded blocks, and
    # frame_checked settles which framing stands.
    framed = frame(buf, seg, walked, False)
    scans = _scan_decoded(buf, framed, decoded, editions, choice, selected)
    failed = any((sc[2][0] < 0).any() for sc in scans.values())
    if not seg.exact and (failed or _lone_category(framed[2], walked)):
        settled = frame_checked(buf, seg, walked_editions(editions, categories), plain=framed)
        if settled is not framed:
            framed = settled
            scans = _scan_decoded(buf, framed, decoded, editions, choice, selected)
    b_start, b_len, b_cat, b_seg, e_off, e_len, e_cat, e_code = framed
    errors: list[tuple[int, int, int, str]] = [
        (int(o), int(n), int(c), framing_reason(buf, seg, int(o), int(code)))
        for o, n, c, code in zip(e_off, e_len, e_cat, e_code, strict=True)]
    errors += [(o, n, -1, f"container: {why}") for o, n, why in seg.problems]
    columns: dict[int, dict] = {}
    chosen: dict[int, str] = {}
    fits: dict[int, tuple[str, ...]] = {}
    ignored: dict[int, int] = {}
    ignored_by_cat: dict[int, int] = {}
    decoded_bytes = ignored_bytes = 0
    for cat in (int(c) for c in np.unique(b_cat)):
        if cat not in scans:  # a category not decoded: stepped over, accounted per category
            sel = b_cat == cat
            ignored[cat] = int(sel.sum())
            ignored_by_cat[cat] = int(b_len[sel].sum())
            ignored_bytes += ignored_by_cat[cat]
            continue
        sel, lay, scanned = scans.pop(cat)
        starts, lens = b_start[sel], b_len[sel]
        chosen[cat] = lay.edition
        counts, fail_at = scanned[0], scanned[1]
        for j in np.flatnonzero(counts < 0):
            reason = f"{REASONS[int(-counts[j])]} (record at offset {int(fail_at[j])})"
            errors.append((int(starts[j]), int(lens[j]), cat, reason))
        failed = counts < 0
        if failed.any() and 2 * int(failed.sum()) >= len(counts):
            fits[cat] = walking_editions(buf, starts[failed], lens[failed], cat, besides=lay.edition)
            if fits[cat] and failed.sum() >= WRONG_EDITION_MIN_BLOCKS:
                # the edition is wrong: blocks that walk under it anyway would give wrong values
                others = " or ".join(fits[cat])
                why = (f"walks under edition {lay.edition}, but most CAT{cat:03d} blocks do not and every "
                       f"one of those sampled walks under {others}: withheld (a wrong edition)")
                errors += [(int(starts[j]), int(lens[j]), cat, why) for j in np.flatnonzero(~failed)]
                scanned = (*scanned[:-1], 0)
                counts = np.full_like(counts, -1)
        decoded_bytes += int(lens[counts > 0].sum())
        where, texts, rec_off, rec_blk = _extract(buf, scanned, lay)
        del scanned
        columns[cat] = _columns(lay, where, texts, rec_off, sel[rec_blk])
        del where, texts
    untimed = (time_cat001(columns, buf, framed, editions, sector_clock or SectorClock())
               if PLOT_CATEGORY in decoded else pd.DataFrame(columns=UNTIMED_COLUMNS))
    errors.sort()
    if strict and errors:
        o, _, c, why = errors[0]
        raise DecodeError(path, o, why, c)
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
    return Recording(frames=frames, errors=err, editions=chosen, path=path, format=seg.format, date=date,
                     size_bytes=int(len(buf)), container_bytes=int(seg.container_bytes),
                     decoded_bytes=decoded_bytes, ignored_blocks=ignored, ignored_bytes=ignored_bytes,
                     edition_choice=choice, day0=first_day, ignored_category_bytes=ignored_by_cat,
                     edition_fits=fits, blocks=int(len(b_start)), untimed=untimed)


def framing_reason(buf: np.ndarray, seg: Segments, offset: int, code: int) -> str:
    """A framing error's reason; for a bad data block LEN, which way it is bad, its numbers in a trailing
    parenthesis (``msdc stats`` groups the reasons without them)."""
    if code != kernel.E_BAD_LEN or offset + 3 > len(buf):
        return REASONS[code]
    n = int(buf[offset + 1]) << 8 | int(buf[offset + 2])
    i = int(np.searchsorted(seg.start, offset, side="right")) - 1
    end = int(seg.stop[i]) if i >= 0 else len(buf)  # the end of the payload the block is in
    if n < 3:
        return f"data block LEN below 3 (LEN {n})"
    if offset + n > end:
        return f"data block runs past the end of the data (LEN {n}, {offset + n - end} bytes past the end)"
    return f"data block LEN does not fit the block chain (LEN {n})"


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
         strict: bool = False, columns=None) -> Recording:
    """Decode a recording file (raw, pcap/pcapng, final, gps or oradis) into typed frames by category.

    ``columns`` (names, any category) decodes only those columns besides ``sac``, ``sic``,
    ``time_of_day``, ``day``, ``timestamp``, ``block`` and ``offset``: a job that needs a few columns
    of a large recording holds only them. Every block is still walked and accounted alike.
    """
    eds = _parse_editions(editions)
    selected_columns(columns)
    date, categories = parse_date(date), check_categories(categories)
    for cat, ed in eds.items():
        if ed != "auto":
            resolve_edition(cat, ed)
    with _mapped(path) as buf:
        try:
            seg = read_segments(buf, format)
        except ValueError as exc:
            raise UnreadableInput(f"{path}: {exc}") from exc
        rec = decode_buffer(buf, seg, path=str(path), editions=eds, categories=categories, date=date,
                            strict=strict, columns=columns)
    for text in edition_advice(rec):
        warnings.warn(text, EditionWarning, stacklevel=2)
    for text in untimed_advice(rec.path, rec.untimed):
        warnings.warn(text, UntimedWarning, stacklevel=2)
    return rec


def edition_advice(rec: Recording) -> list[str]:
    """Per category whose blocks mostly failed under its edition (``Recording.edition_fits``): how many, and
    the edition(s) every one sampled walks under, as ``read``'s ``editions=`` argument."""
    out = []
    for cat, fits in rec.edition_fits.items():
        if not fits:
            continue
        failed = int((rec.errors["category"] == cat).sum())
        pin = (f"pin it with editions={{{cat}: {fits[0]!r}}}" if len(fits) == 1 else
               f"pin the right one, or try editions={{{cat}: 'auto'}}")
        out.append(f"{rec.path}: {failed} CAT{cat:03d} block(s) could not be decoded under edition "
                   f"{rec.editions.get(cat)}; every one sampled decodes under {', '.join(fits)}: {pin}")
    return out


def categories_in(path, *, format: str | None = None) -> dict[int, int]:
    """Data blocks per category in a recording, from framing alone (fast: no record is walked)."""
    with _mapped(path) as buf:
        seg = read_segments(buf, format)
        cats = frame(buf, seg)[2]
        values, counts = np.unique(cats, return_counts=True)
        return {int(v): int(n) for v, n in zip(values, counts, strict=True)}
