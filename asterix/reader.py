"""``read``: a recording in, one typed DataFrame per category out, with an account of what was skipped."""

from __future__ import annotations

import datetime as dt
import mmap
import os
import warnings
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass, field
from functools import cache, partial

import numpy as np
import pandas as pd

from . import bds, kernel, sampling, threads
from .cat001_time import PLOT_CATEGORY, UNTIMED_COLUMNS, SectorClock, time_cat001, untimed_advice
from .categories import DECODABLE, MEASUREMENT_CATEGORIES, REGISTRY
from .columns import FAMILIES
from .containers import Segments, read_segments, readonly
from .errors import REASONS, ContentWarning, DecodeError, EditionWarning, UnreadableInput, UntimedWarning
from .families import AUTO, edition_families, edition_span, family_name, family_of, with_defaults
from .frames import code_list_column, empty_columns, frame_of, icao_columns, typed_column
from .framing import Progress, alike_framings, held, release_pages, segment_modes, survey
from .layout import OUT_FLAG, OUT_FLOAT, OUT_INT, OUT_WIDE, Layout, compile_layout
from .plausible import BOUNDS, Implausible, count_implausible, count_odd_sources, implausible
from .stretches import Stretch, describe, foreign_spans
from .tables import available, resolve_edition
from .timeline import assign_days, timestamp_index
from .verdict import Tally, head_of

# Decoded when categories=None: the measurement categories. CAT034 (service messages) is decoded on
# request (categories=DECODABLE): until the pipeline handles its frames, its blocks are stepped over and
# counted as ignored.
DEFAULT_CATEGORIES = MEASUREMENT_CATEGORIES
WRONG_EDITION_MIN_BLOCKS = 10  # failed blocks, all walking under another edition, proving the edition wrong
AUTO_SAMPLE_BLOCKS = 20_000  # blocks walked per candidate edition by editions={cat: "auto"}
AUTO_SAMPLE_BYTES = 2 << 20  # at most about this many bytes of them (20,000 one-record blocks fit)
# a raw stream whose chain breaks (choose_editions): blocks before the break enough to choose the edition
# that frames the rest; else framing_edition over the stream's first FRAMING_EDITION_BYTES; then windows
AUTO_PREFIX_BLOCKS = 100
FRAMING_EDITION_BYTES = 1 << 22
AUTO_WINDOWS, AUTO_WINDOW_BYTES = 16, 1 << 18
ERROR_COLUMNS = ["file", "offset", "length", "category", "reason"]
OVERSIZED_BLOCK_BYTES = 8192  # a longer block of a category not decoded counts as unlike a recording's


@dataclass(eq=False)  # two Recordings are equal when they are the same one: frames have no truth value
class Recording:
    """Decoded recording: frames by category, the error account, and how it was read.

    - ``frames``: one DataFrame per decoded category (``rec[48]`` is ``rec.frames[48]``); ``errors``: what
      was skipped (file, offset, length, category, reason); ``editions``: the edition each category was
      decoded under; ``edition_choice``: how ``'auto'`` chose it, in words.
    - ``path``, ``format`` (raw, pcap, pcapng, final, gps, oradis), ``date`` (the UTC day of day 0, None
      when unknown), ``day0`` (the container's day number of day 0: days since 1970 for a pcap, the day
      byte for a final file; None for a raw stream).
    - The byte account, ``size_bytes = decoded_bytes + errors.length.sum() + container_bytes +
      ignored_bytes``: ``ignored_bytes`` in blocks of categories not decoded, per category
      ``ignored_category_bytes`` and ``ignored_blocks`` (``ignored``: the three as a table), of them
      ``oversized_bytes`` in blocks over 8 KB (unlike a recording's: text and random bytes).
    - ``blocks``: data blocks framed, of every category (the ``block`` column numbers them);
      ``decoded_blocks``: per category, the blocks whose records decoded.
    - ``edition_fits``: a category most of whose blocks fail under its edition, and the editions every
      one sampled walks under; ``edition_stretches``: stretches of another edition family, withheld;
      ``implausible``: per category, the records holding values no real report carries; ``odd_sources``:
      per category, the records naming another data source than the rest of their block; ``untimed``:
      CAT001 records no CAT002 message timed (offset, category, sac, sic, reason).
    """

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
    # a category holding stretches of blocks that walk under another edition family than the rest: each
    # stretch, withheld (recordings of different editions laid end to end)
    edition_stretches: dict[int, list[Stretch]] = field(default_factory=dict)
    decoded_blocks: dict[int, int] = field(default_factory=dict)  # blocks per category whose records decoded
    # per category, the decoded records holding a value no real report carries (plausible.BOUNDS)
    implausible: dict[int, Implausible] = field(default_factory=dict)
    # per category, the records naming another data source (SAC/SIC) than most of their block's (damage
    # inside a block that still walks: plausible.odd_sources)
    odd_sources: dict[int, Implausible] = field(default_factory=dict)
    # bytes in blocks of categories not decoded longer than OVERSIZED_BLOCK_BYTES: what text and random bytes
    # frame into (printable text makes every LEN at least 0x2020 = 8224), rarely what a recorder writes
    oversized_bytes: int = 0

    @property
    def ignored(self) -> pd.DataFrame:
        """Blocks of categories not decoded (other categories, or not selected): category, blocks, bytes."""
        return pd.DataFrame({"category": list(self.ignored_blocks),
                             "blocks": list(self.ignored_blocks.values()),
                             "bytes": [self.ignored_category_bytes.get(c, 0) for c in self.ignored_blocks]},
                            columns=["category", "blocks", "bytes"])

    def __getitem__(self, category: int) -> pd.DataFrame:
        """The frame of a category; KeyError naming the categories decoded (and why not this one)."""
        try:
            return self.frames[category]
        except (KeyError, TypeError):
            pass
        held = ", ".join(f"CAT{c:03d}" for c in sorted(self.frames)) or "none"
        why = ("a category is a number (an int)" if not isinstance(category, int | np.integer) else
               "its blocks were not decoded (give categories=)" if category in self.ignored_blocks else
               "the recording holds none")
        raise KeyError(f"{category!r}: no frame of this category ({why}); frames: {held}") from None


_ALWAYS = ("day", "timestamp", "block", "offset")  # built for every frame
KNOWN_COLUMNS = frozenset(c.name for family in FAMILIES.values() for c in family)


def selected_columns(columns) -> tuple[str, ...] | None:
    """Decoded column names to compile (sorted; ``NAME_hex`` asks for ``NAME``), or None for all;
    ValueError naming a column no category has."""
    if columns is None:
        return None
    if not isinstance(columns, str) and not hasattr(columns, "__iter__"):
        raise TypeError(f"columns {columns!r}: give a column name or a sequence of them, e.g. "
                        f"('address', 'callsign')")
    known = KNOWN_COLUMNS
    names = set()
    for name in ([columns] if isinstance(columns, str) else columns):
        if not isinstance(name, str):
            raise TypeError(f"columns {columns!r:.80}: {name!r} is not a column name (a str; see "
                            f"docs/columns.md)")
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
            asked = f"CAT{int(c):03d}" if c >= 0 else f"category {int(c)}"  # not CAT-01
            raise ValueError(f"categories {categories!r}: msdc does not decode {asked}; it decodes "
                             f"{', '.join(f'CAT{d:03d}' for d in DECODABLE)} (other categories' blocks are "
                             f"counted in Recording.ignored)")
        out.append(int(c))
    return tuple(out)


def check_strict(strict) -> bool:
    """``strict`` as a bool; TypeError for anything else (the text "False" is true, and turned it on)."""
    if not isinstance(strict, bool | np.bool_):
        raise TypeError(f"strict {strict!r}: must be True or False (a bool), not {type(strict).__name__}")
    return bool(strict)


def check_path(path) -> None:
    """TypeError unless ``path`` names a file (str or os.PathLike): open() takes an int as a descriptor,
    which it reads and then closes (the caller's, stdout for 1 or True), and bytes as a path."""
    if isinstance(path, str | os.PathLike):
        return
    hint = (" (bytes in memory: msdc.asterix.decode_buffer decodes them)"
            if isinstance(path, bytes | bytearray | memoryview) else "")
    raise TypeError(f"path: a file path (str or os.PathLike), not {type(path).__name__} {path!r:.40}{hint}")


def check_readable(path) -> None:
    """check_path, then UnreadableInput unless the file opens for reading (missing, a folder, no
    permission)."""
    check_path(path)
    try:
        with open(path, "rb"):
            pass
    except OSError as exc:
        raise UnreadableInput(f"{path}: cannot read: {exc.strerror or exc}") from exc


@contextmanager
def _mapped(path) -> Iterator[np.ndarray]:
    """The file as a read-only uint8 array, memory-mapped while the block runs."""
    check_path(path)
    try:
        with open(path, "rb") as fh:
            size = os.fstat(fh.fileno()).st_size
            mm = mmap.mmap(fh.fileno(), 0, access=mmap.ACCESS_READ) if size else None
    except OSError as exc:
        raise UnreadableInput(f"{path}: cannot read: {exc.strerror or exc}") from exc
    buf = np.frombuffer(mm, np.uint8) if mm is not None else np.frombuffer(b"", np.uint8)  # read-only alike
    try:
        yield buf
    finally:
        del buf
        if mm is not None:
            try:
                mm.close()
            except BufferError:  # frames still view the map: the OS unmaps it when they go
                pass


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
    counts, _, _ = kernel.scan(buf, starts[k], lens[k], lay.parts, lay.n_frn, lay.n_slots,
                               np.empty((cap, slots), np.uint16), np.zeros((cap, slots), np.uint16),
                               np.empty(cap, np.int64), np.empty(cap, np.int64), np.zeros(slots, np.uint8))
    good = counts > 0
    if not good.any():
        return int(lens.sum()) // REGISTRY[lay.category].record_bytes + 16
    per_byte = counts[good].sum() / lens[k][good].sum()
    return int(per_byte * int(lens.sum()) * 1.05) + 16


@dataclass
class _Piece:
    """The part table of one group of blocks' good records (rows 0..n), the first of them being record
    ``first`` of all the groups'."""

    first: int
    n: int
    rel_off: np.ndarray
    rel_len: np.ndarray
    rec_off: np.ndarray


@dataclass
class _Scanned:
    """One walk over a category's blocks: records per block (minus an error code for a bad block), where bad
    walks failed, the good records' offsets and block indices, the parts some good record carries, and
    where each part of each record lies, in pieces walked side by side (rel_len 0 where a record lacks it)."""

    counts: np.ndarray
    fail_at: np.ndarray
    rec_off: np.ndarray
    rec_blk: np.ndarray
    carried: np.ndarray
    pieces: list[_Piece]

    @property
    def n(self) -> int:
        return len(self.rec_off)

    def part(self, slot: int) -> tuple[np.ndarray, np.ndarray]:
        """Offsets and lengths of one part in every record, in record order."""
        if not self.pieces:
            return np.zeros(0, np.uint16), np.zeros(0, np.uint16)
        if len(self.pieces) == 1:
            p = self.pieces[0]
            return p.rel_off[:p.n, slot], p.rel_len[:p.n, slot]
        return (np.concatenate([p.rel_off[:p.n, slot] for p in self.pieces]),
                np.concatenate([p.rel_len[:p.n, slot] for p in self.pieces]))

    def none_kept(self) -> _Scanned:
        """The same walk with no record kept."""
        return _Scanned(self.counts, self.fail_at, self.rec_off[:0], self.rec_blk[:0], self.carried, [])


def _walk_arrays(cap: int, slots: int) -> tuple[np.ndarray, ...]:
    """kernel.scan's output arrays for up to cap records (made on the calling thread: memory a decode
    thread allocates stays in its own heap when freed, which held 20-80 MB more after small-record
    decodes)."""
    return (np.empty((cap, slots), np.uint16), np.zeros((cap, slots), np.uint16), np.empty(cap, np.int64),
            np.empty(cap, np.int64), np.zeros(slots, np.uint8))


def _scan(buf, starts, lens, lay: Layout) -> _Scanned:
    """One walk over the blocks (all or nothing per block), in groups of blocks walked side by side on the
    decode's threads when they hold enough records; each group's arrays sized from a guess, doubled for a
    group they are too small for, which is walked again."""
    groups = threads.byte_groups(lens, int(lens.sum()) // REGISTRY[lay.category].record_bytes)
    slots = max(lay.n_slots, 1)
    arrays: list = [_walk_arrays(_record_guess(buf, starts[g], lens[g], lay), slots) for g in groups]
    walked: list = [None] * len(groups)
    while todo := [i for i, w in enumerate(walked) if w is None]:
        done = threads.run_all([partial(kernel.scan, buf, starts[groups[i]], lens[groups[i]], lay.parts,
                                        lay.n_frn, lay.n_slots, *arrays[i]) for i in todo])
        for i, (counts, fail_at, n) in zip(todo, done, strict=True):
            if n < 0:
                arrays[i] = _walk_arrays(2 * len(arrays[i][2]), slots)
                continue
            rel_off, rel_len, rec_off, rec_blk, carried = arrays[i]
            if (counts <= 0).any():  # a bad block's records set slots too: only the good ones count
                carried = (rel_len[:n] != 0).any(axis=0)
            walked[i] = (counts, fail_at, rec_off[:n], rec_blk[:n] + groups[i].start, carried.astype(bool))
    pieces, first = [], 0
    for (_, _, rec_off, _, _), (rel_off, rel_len, *_) in zip(walked, arrays, strict=True):
        pieces.append(_Piece(first, len(rec_off), rel_off, rel_len, rec_off))
        first += len(rec_off)
    if len(walked) == 1:
        return _Scanned(*walked[0], pieces)
    return _Scanned(*(np.concatenate([w[k] for w in walked]) for k in range(4)),
                    np.logical_or.reduce([w[4] for w in walked]), pieces)


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


def _family_flags(buf: np.ndarray, starts: np.ndarray, lens: np.ndarray, category: int
                  ) -> dict[str, np.ndarray]:
    """_walk_flags under every edition, walked once per family (its editions walk every block alike)."""
    flags: dict[str, np.ndarray] = {}
    for family in edition_families(category):
        walked = _walk_flags(buf, starts, lens, category, family[-1])
        flags |= {ed: walked for ed in family}
    return {ed: flags[ed] for ed in _editions_oldest_first(category)}


def choose_edition(buf: np.ndarray, starts: np.ndarray, lens: np.ndarray, category: int,
                   sample: int = AUTO_SAMPLE_BLOCKS, total: int | None = None, source: str = "",
                   offsets: np.ndarray | None = None) -> tuple[str, str]:
    """Pick the edition under which every sampled block walks exactly (the newest of those, as they read
    the sample alike), values plausible; say which blocks told the editions apart, or that none walks all.

    The sample is every block, or AUTO_SAMPLE_BLOCKS spread evenly over a longer recording, or fewer spread
    alike where they would hold more than AUTO_SAMPLE_BYTES: a walk costs no memory, so rare blocks that
    tell editions apart (I021/271 with an odd LW) are seen. ``total``:
    the blocks the given ones were sampled from (choose_editions samples the whole recording first), or
    ``source``: where they come from, in words. ``offsets``: the blocks' offsets in the file, when ``buf``
    holds copies of them (``_gathered``).
    """
    idx = _spread(len(starts), sample)
    if len(idx) and int(lens[idx].sum()) > AUTO_SAMPLE_BYTES:  # long blocks: spread over fewer
        idx = idx[_spread(len(idx), max(1, AUTO_SAMPLE_BYTES * len(idx) // int(lens[idx].sum())))]
    s, n = starts[idx], lens[idx]
    where = s if offsets is None else offsets[idx]
    total = len(starts) if total is None else total
    eds = _editions_oldest_first(category)
    flags = _family_flags(buf, s, n, category)
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
    # per family (its editions walk every block alike, so their shares are one)
    words = [f"{family_name(f)}: {share[f[0]]:.0%}" for f in edition_families(category)]
    told = ", ".join(f"offset {int(where[j])} walks under {'/'.join(ed for ed in contenders if flags[ed][j])}"
                     for j in apart[:3]) or "none"
    if best < 1:
        verdict = f"no edition walks every sampled block; best {chosen}"
    else:
        walking = edition_span(category, tuple(tied))
        verdict = f"editions walking every sampled block: {walking}; newest {chosen}"
    if plaus and len(set(plaus.values())) == 1:
        verdict += f" (all {next(iter(plaus.values())):.0%} plausible)"
    elif plaus:
        verdict += " (" + ", ".join(f"{ed} {p:.0%} plausible" for ed, p in plaus.items()) + ")"
    apart_words = (f"{len(apart)} blocks told {'/'.join(contenders)} apart: {told}" if len(contenders) > 1
                   else "no other edition walks half the sample, so none needed telling apart")
    sampled = f"{len(idx)} {source}" if source else f"{len(idx)} of {total} blocks sampled"
    return chosen, (f"chose {chosen} ({sampled}; blocks walking: "
                    f"{'; '.join(words)}; {verdict}; {apart_words})")


def walking_editions(buf: np.ndarray, starts: np.ndarray, lens: np.ndarray, category: int, *,
                     besides: str = "", sample: int = AUTO_SAMPLE_BLOCKS) -> tuple[str, ...]:
    """The editions (oldest first, ``besides`` left out) under which every one of these blocks walks
    exactly, or of ``sample`` of them spread evenly over a longer list."""
    idx = _spread(len(starts), sample)
    flags = _family_flags(buf, starts[idx], lens[idx], category)
    return tuple(ed for ed, f in flags.items() if ed != besides and f.all())


def _other_family_spans(buf: np.ndarray, starts: np.ndarray, lens: np.ndarray, failed: np.ndarray,
                        category: int, edition: str) -> list[tuple[int, int]]:
    """Block spans of stretches of another edition family (asterix.stretches), when at least
    WRONG_EDITION_MIN_BLOCKS blocks failed, that many walk under one other family, and at least as many
    blocks outside the stretches are evidence for ``edition``; else none (a wrong edition throughout is
    the rule of decode_buffer, a few failed blocks are damage)."""
    if failed.sum() < WRONG_EDITION_MIN_BLOCKS:
        return []
    idx = np.flatnonzero(failed)[_spread(int(failed.sum()), AUTO_SAMPLE_BLOCKS)]
    own = family_of(category, compile_layout(category, edition).edition)
    counts = {f[-1]: int(_walk_flags(buf, starts[idx], lens[idx], category, f[-1]).sum())
              for f in edition_families(category) if f != own}
    if not counts or max(counts.values()) < WRONG_EDITION_MIN_BLOCKS:
        return []
    other = max(counts, key=lambda ed: counts[ed])
    spans, used = foreign_spans(~failed, _walk_flags(buf, starts, lens, category, other),
                                WRONG_EDITION_MIN_BLOCKS)
    return spans if used >= WRONG_EDITION_MIN_BLOCKS else []


def framing_edition(buf: np.ndarray, seg: Segments, walked: dict, category: int,
                    progress: Progress | None = None) -> str:
    """For an 'auto' category of a stream whose block chain breaks: the edition under which careful
    framing loses the fewest bytes (most of its blocks found on a tie, then the newest). Framing cannot
    walk a category without an edition, and would otherwise lose every block of it after the damage.
    One edition per family is tried, the newest: the editions of a family frame alike (and families that
    walk every block framing meets alike are framed once: framing.alike_framings)."""
    careful = np.full(len(seg.start), kernel.MODE_CAREFUL, np.int8)
    eds = [family[-1] for family in edition_families(category)]
    framed = alike_framings(buf, seg, careful, {ed: tables_for({**walked, category: ed}) for ed in eds},
                            category, progress, what=f"framing under CAT{category:03d}")
    best: tuple | None = None
    for ed in eds:
        key = (framed[ed].error_bytes, -int(framed[ed].blocks[category]))
        if best is None or key <= best[0]:
            best = (key, ed)
    return best[1]


PLAUSIBLE_SAMPLE_BYTES = 1 << 18  # at most about this many bytes of blocks decoded per tied edition


def _plausible_share(buf, s, n, category: int, ed: str, limit: int = 400) -> float:
    """Share of records of up to ``limit`` sampled blocks (PLAUSIBLE_SAMPLE_BYTES at most) whose values are
    plausible (plausible.mask: positions on the Earth, times of day within 24 h; the columns the category
    has), only those columns decoded."""
    k = _spread(len(s), limit)
    if len(k) and int(n[k].sum()) > PLAUSIBLE_SAMPLE_BYTES:
        k = k[_spread(len(k), max(1, PLAUSIBLE_SAMPLE_BYTES * len(k) // int(n[k].sum())))]
    lay = compile_layout(category, ed, _scanned_columns(()))
    scanned = _scan(buf, s[k], n[k], lay)
    if not (scanned.counts > 0).any():
        return 0.0
    where, _, _, _ = _extract(buf, scanned, lay)
    bounded = {nm: where[nm][0][where[nm][1]] for nm in BOUNDS if nm in where}
    ok = ~implausible(bounded) if bounded else np.ones(scanned.n, bool)
    return float(np.mean(ok)) if len(ok) else 0.0


def _extract(buf, scanned: _Scanned, lay: Layout):
    """Gather every field of the scanned records into column matrices: only the fields of parts some
    record carries, into rows for their columns alone (a wide edition's other columns, absent from every
    record, cost neither a pass nor memory here: ``_columns`` builds them empty)."""
    n = scanned.n
    F, mult = lay.F, lay.f_mult
    if len(F):
        keep = scanned.carried[F[:, 0]] if n else np.zeros(len(F), bool)
        if not keep.all():
            F, mult = F[keep], mult[keep]
    F = np.array(F, np.int64, copy=True)
    names = {OUT_INT: lay.out_names_int, OUT_FLOAT: lay.out_names_float, OUT_WIDE: lay.out_names_wide,
             OUT_FLAG: lay.out_names_flag}
    rows = {k: sorted(set(F[F[:, 5] == k, 4].tolist())) for k in names}
    for k in names:  # the kept columns' rows, numbered afresh per output kind
        renumber = np.full(len(names[k]) + 1, -1, np.int64)
        renumber[rows[k]] = np.arange(len(rows[k]))
        sel = F[:, 5] == k
        F[sel, 4] = renumber[F[sel, 4]]
    it = np.full((len(rows[OUT_INT]), n), -1, np.int32)
    fl = np.full((len(rows[OUT_FLOAT]), n), np.nan)
    wd = np.full((len(rows[OUT_WIDE]), n), -1, np.int64)
    fg = np.full((len(rows[OUT_FLAG]), n), -1, np.int8)
    F, mult = np.ascontiguousarray(F), np.ascontiguousarray(mult)

    def gather(p: _Piece, a: int, b: int) -> None:
        kernel.gather(buf, p.rec_off, p.rel_off, p.rel_len, F, mult, fl, it, wd, fg, a, b, p.first)

    # each piece's records in ranges, the decode's threads shared among the pieces (one range each when the
    # blocks were walked side by side, one per thread when in one piece)
    share = max(1, threads.decode_threads() // max(len(scanned.pieces), 1))
    threads.run_all([partial(gather, p, a, b) for p in scanned.pieces for a, b in threads.ranges(p.n, share)])
    matrices = {OUT_INT: it, OUT_FLOAT: fl, OUT_WIDE: wd, OUT_FLAG: fg}
    where = {names[k][r]: (matrices[k], i) for k in names for i, r in enumerate(rows[k])}
    rec_off = scanned.rec_off
    texts = {name: code_list_column(buf, rec_off, *scanned.part(s)) for name, s in lay.code_slots}
    for s in sorted({s for _, s, _ in lay.bds_slots}):  # Mode S register fields, one pass per item
        texts |= bds.decode(buf, rec_off, *scanned.part(s),
                            {name: path for name, slot, path in lay.bds_slots if slot == s})
    return where, texts, rec_off, scanned.rec_blk


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
    return frame_of({c: cols[c] for c in order})


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


def tables_for(walked: dict[int, str | None]) -> kernel.Framing:
    """The framing tables walking these categories under these editions (None: the default); the same
    object for the same editions."""
    return _framing_tables(tuple(sorted((c, compile_layout(c, e).edition) for c, e in walked.items())))


def frame(buf: np.ndarray, seg: Segments, walked: dict[int, str | None] | None = None,
          careful: bool = False):
    """Data blocks of every category in the segments, in one piece (kernel.frame_blocks); ``walked`` gives
    the categories (and editions) whose blocks must walk exactly where framing has to resynchronise."""
    return kernel.frame_blocks(buf, seg.start, seg.stop, seg.exact, careful, tables_for(walked or {}))


def walked_editions(editions: dict, categories) -> dict[int, str | None]:
    """Categories whose blocks framing may walk, with their edition: the decoded ones and, when not
    selected, CAT048 (1.32 walks every edition) and those whose edition is given; never 'auto' ones."""
    wanted = set(DEFAULT_CATEGORIES if categories is None else categories)
    return {c: editions.get(c) for c in DECODABLE
            if (c in wanted or c == 48 or c in editions)
            and editions.get(c) != AUTO}


def _raw_part(lo: int, hi: int) -> Segments:
    """Bytes [lo, hi) of a file as a raw stream of their own."""
    return Segments("raw", np.array([lo]), np.array([hi]), np.array([-1]), np.array([np.nan]), False, False,
                    0, [])


def _broken_chain_sample(buf: np.ndarray, seg: Segments, cat: int, walked: dict) -> tuple[np.ndarray, str]:
    """For a raw stream whose chain breaks: the starts of the sampled blocks of ``cat``, and where they come
    from. Framing such a stream needs an edition for ``cat`` (careful framing finds blocks by walking
    them): one is chosen from the blocks before the chain's first break, or, with too few there, the one
    under which careful framing of the stream's start loses the fewest bytes (framing_edition); the
    sample is then the blocks before the break and those careful framing under it finds in
    AUTO_WINDOWS windows spread over the stream (the whole stream when it is no longer)."""
    start, stop = int(seg.start[0]), int(seg.stop[0])
    prefix = sampling.prefix_starts(buf, start, stop, cat, AUTO_SAMPLE_BLOCKS)
    if len(prefix) >= AUTO_PREFIX_BLOCKS:
        ed = choose_edition(buf, prefix, sampling.block_lengths(buf, prefix), cat)[0]
    else:
        ed = framing_edition(buf, _raw_part(start, min(stop, start + FRAMING_EDITION_BYTES)), walked, cat)
    span = AUTO_WINDOWS * AUTO_WINDOW_BYTES
    windows = ([(start, stop)] if stop - start <= span else
               [(int(lo), int(lo) + AUTO_WINDOW_BYTES)
                for lo in np.linspace(start, stop - AUTO_WINDOW_BYTES, AUTO_WINDOWS).astype(np.int64)])
    found = [prefix]
    for lo, hi in windows:
        framed = frame(buf, _raw_part(lo, hi), {**walked, cat: ed}, True)
        found.append(framed[0][framed[2] == cat])
    found = np.unique(np.concatenate(found))
    starts = found[_spread(len(found), AUTO_SAMPLE_BLOCKS)]  # clustered: spread by count, not by offset
    where = ("the stream framed" if len(windows) == 1 else f"{len(windows)} windows of the stream framed")
    return starts, (f"blocks sampled from the chain before its first break and {where} under {ed} (its "
                    "chain breaks)")


def choose_editions(buf: np.ndarray, seg: Segments, editions: dict, categories
                    ) -> tuple[dict, dict[int, str]]:
    """Each 'auto' edition of a decoded category chosen over the whole recording before it is decoded
    (``read`` decodes with the result whole, ``iter_read`` in chunks: they choose alike): the editions
    with each 'auto' replaced, and how each was chosen in words. A category with no block stays 'auto'.

    The sample follows the block chain (asterix.sampling), at no cost in memory and next to none in time;
    a raw stream whose chain breaks is sampled as _broken_chain_sample says."""
    wanted = set(DEFAULT_CATEGORIES if categories is None else categories)
    auto = [c for c in DECODABLE if c in wanted and editions.get(c) == AUTO]
    chosen, why = dict(editions), {}
    for cat in auto:
        source = ""
        release = partial(release_pages, buf)  # pages behind each window walked: not held
        if seg.exact or sampling.all_chains_hold(buf, seg.start, seg.stop, release):
            starts, total = sampling.sample_starts(buf, seg.start, seg.stop, cat, AUTO_SAMPLE_BLOCKS, release,
                                                   AUTO_SAMPLE_BYTES)
        else:
            starts, source = _broken_chain_sample(buf, seg, cat, walked_editions(editions, categories))
            total = len(starts)
        if total:
            data, at, lens = _gathered(buf, starts, release)
            chosen[cat], why[cat] = choose_edition(data, at, lens, cat, total=total, source=source,
                                                   offsets=starts)
    return chosen, why


def _gathered(buf: np.ndarray, starts: np.ndarray, release, batch: int = 256
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The blocks at ``starts`` (ascending) copied out end to end, a batch at a time, each copied before its
    pages are released: (their bytes, their starts in them, their lengths). Each page fault maps about
    64 kB of the file around it, so walking 4,000 blocks spread over 1 GB in place held 400 MB of it."""
    pieces: list[np.ndarray] = []
    lens: list[np.ndarray] = []
    for i in range(0, len(starts), batch):
        part = starts[i:i + batch]
        n = np.minimum(sampling.block_lengths(buf, part), len(buf) - part)
        pieces.append(np.concatenate([buf[a:a + k] for a, k in zip(part.tolist(), n.tolist(), strict=True)]))
        lens.append(n.astype(np.int64))
        release(int(part[0]), int(part[-1] + n[-1]))
    length = np.concatenate(lens) if lens else np.zeros(0, np.int64)
    data = readonly(np.concatenate(pieces) if pieces else np.zeros(0, np.uint8))
    return data, np.concatenate([[0], np.cumsum(length)[:-1]]).astype(np.int64), length


def _scan_decoded(buf: np.ndarray, framed, plan, selected) -> dict[int, tuple[np.ndarray, Layout, _Scanned]]:
    """Walk the framed blocks of each decoded category under the plan's edition: {cat: (block indices,
    layout, scan)}."""
    b_start, b_len, b_cat = framed[:3]
    scans: dict[int, tuple] = {}
    for cat in plan.decoded:
        sel = np.flatnonzero(b_cat == cat)
        if not len(sel):
            continue
        lay = compile_layout(cat, plan.editions.get(cat), selected)
        scans[cat] = (sel, lay, _scan(buf, b_start[sel], b_len[sel], lay))
    return scans


@dataclass
class _Judged:
    """What the walk of one category's blocks says about its edition: the errors (each failed block, and
    blocks withheld), the blocks kept (None: all), and the stretches of another edition among them."""

    errors: list[tuple[int, int, int, str]]
    keep: np.ndarray | None = None
    stretches: list[Stretch] = field(default_factory=list)


def find_stretches(buf: np.ndarray, starts: np.ndarray, lens: np.ndarray, failed: np.ndarray, cat: int,
                   edition: str) -> list[Stretch]:
    """The stretches of another edition family among all of a category's blocks (``failed``: those that do
    not walk under ``edition``), found over the whole recording (asterix.plan): _other_family_spans."""
    out = []
    for lo, hi in _other_family_spans(buf, starts, lens, failed, cat, edition):
        inside = slice(lo, hi)
        eds = walking_editions(buf, starts[inside][failed[inside]], lens[inside][failed[inside]], cat,
                               besides=edition)
        end = int(starts[hi - 1] + lens[hi - 1])
        out.append(Stretch(int(starts[lo]), end, hi - lo, eds, edition, lo == 0, hi == len(starts)))
    return out


def _judge_edition(starts: np.ndarray, lens: np.ndarray, scanned: _Scanned, cat: int, edition: str, plan
                   ) -> _Judged:
    """Report the blocks that failed to walk, and apply the plan's judgement of the edition (settled over
    the whole recording): blocks in stretches of another edition family are withheld, each reported as such
    (the part of a stretch among these blocks is reported as a Stretch of them, ``opens``/``closes`` saying
    it goes on before or after); a wrong edition throughout withholds the blocks that walk under it anyway
    (they would give wrong values)."""
    counts, fail_at = scanned.counts, scanned.fail_at
    failed = counts < 0
    why_failed = {int(j): f"{REASONS[int(-counts[j])]} (record at offset {int(fail_at[j])})"
                  for j in np.flatnonzero(failed)}
    judged = _Judged([])
    for whole in plan.stretches.get(cat, ()):
        inside = np.flatnonzero((starts >= whole.first_offset) & (starts < whole.stop_offset))
        if not len(inside):
            continue
        lo, hi = int(inside[0]), int(inside[-1]) + 1
        first, end = int(starts[lo]), int(starts[hi - 1] + lens[hi - 1])
        judged.stretches.append(Stretch(first, end, hi - lo, whole.editions, edition,
                                        (lo == 0 and first > whole.first_offset) or whole.opens,
                                        (hi == len(counts) and end < whole.stop_offset) or whole.closes))
        among = (f"CAT{cat:03d} blocks at offsets {whole.first_offset}-{whole.stop_offset - 1} that walk "
                 f"under {edition_span(cat, whole.editions) or 'another edition'} and not under {edition}")
        for j in inside:
            why_failed[int(j)] = (f"does not walk under edition {edition}; lies among {among}: skipped "
                                  f"(another edition)" if failed[j] else
                                  f"walks under edition {edition}, but lies among {among}: withheld "
                                  f"(another edition)")
        if judged.keep is None:
            judged.keep = np.ones(len(counts), bool)
        judged.keep[inside] = False
    if cat in plan.withheld:
        others = " or ".join(plan.fits[cat])
        why = (f"walks under edition {edition}, but most CAT{cat:03d} blocks do not and every one of "
               f"those sampled walks under {others}: withheld (a wrong edition)")
        why_failed |= {int(j): why for j in np.flatnonzero(~failed)}
        judged.keep = np.zeros(len(counts), bool)
    judged.errors = [(int(starts[j]), int(lens[j]), cat, why) for j, why in sorted(why_failed.items())]
    return judged


def decode_buffer(buf: np.ndarray, seg: Segments, *, path: str = "", editions: dict | None = None,
                  categories=None, date=None, strict: bool = False, columns=None,
                  sector_clock: SectorClock | None = None) -> Recording:
    """Decode an in-memory recording whose container segments are already known (``columns``: see
    ``read``; ``sector_clock``: the CAT002 times of the data before it): the plan settled over the whole
    recording (asterix.plan), then every block at once."""
    from .plan import plan_recording  # the plan chooses editions with this module's functions

    buf = readonly(buf)
    selected = selected_columns(columns)
    strict = check_strict(strict)
    date = parse_date(date)
    categories = check_categories(categories)
    editions = _parse_editions(editions)
    plan = plan_recording(buf, seg, dict(editions), categories, assume_walking=True)
    framed = plan.framer(buf).window()
    scans = _scan_decoded(buf, framed, plan, _scanned_columns(selected))
    if plan.assumed and any((scan[2].counts < 0).any() for scan in scans.values()):
        del scans  # a decoded block does not walk: the plan is settled again, walking every block
        plan = plan_recording(buf, seg, dict(editions), categories)
        framed, scans = plan.framer(buf).window(), None
    return decode_framed(buf, plan, framed, path=path, date=date, strict=strict, selected=selected,
                         sector_clock=sector_clock, scans=scans)


def _scanned_columns(asked) -> tuple[str, ...] | None:
    """The columns decoded for ``asked`` (None: all): those plausibility is judged on too (dropped after)."""
    return None if asked is None else tuple(sorted({*asked, *(c for c in BOUNDS if c in KNOWN_COLUMNS)}))


def decode_framed(buf: np.ndarray, plan, framed, *, path: str = "", date: dt.date | None = None,
                  strict: bool = False, selected=None, part: Segments | None = None,
                  first_segment: int = 0, sector_clock: SectorClock | None = None,
                  scans: dict[int, tuple] | None = None) -> Recording:
    """Decode framed blocks (all of a recording's, or one window's: kernel.frame_window) by the plan
    (asterix.plan), into a Recording of them. ``selected``: the columns asked for (None: all); ``part``:
    the segments they lie in, the first being the plan's segment ``first_segment`` (days are counted, and
    container bytes and problems told, by it), the plan's segments when None; ``sector_clock``: the CAT002
    times of the data before (``iter_read`` carries it from window to window); ``scans``: the framed
    blocks' walks (_scan_decoded), when already made."""
    seg = plan.seg
    part = seg if part is None else part
    asked = selected
    selected = _scanned_columns(asked)
    if scans is None:
        scans = _scan_decoded(buf, framed, plan, selected)
    b_start, b_len, b_cat, b_seg, e_off, e_len, e_cat, e_code = framed
    errors: list[tuple[int, int, int, str]] = [
        (int(o), int(n), int(c), framing_reason(buf, seg, int(o), int(code)))
        for o, n, c, code in zip(e_off, e_len, e_cat, e_code, strict=True)]
    errors += [(o, n, -1, f"container: {why}") for o, n, why in part.problems]
    columns: dict[int, dict] = {}
    chosen: dict[int, str] = {}
    stretches: dict[int, list[Stretch]] = {}
    decoded_blocks: dict[int, int] = {}
    ignored: dict[int, int] = {}
    ignored_by_cat: dict[int, int] = {}
    decoded_bytes = ignored_bytes = oversized_bytes = 0
    for cat in (int(c) for c in np.unique(b_cat)):
        if cat not in scans:  # a category not decoded: stepped over, accounted per category
            sel = b_cat == cat
            ignored[cat] = int(sel.sum())
            ignored_by_cat[cat] = int(b_len[sel].sum())
            oversized_bytes += int(b_len[sel][b_len[sel] > OVERSIZED_BLOCK_BYTES].sum())
            ignored_bytes += ignored_by_cat[cat]
            continue
        sel, lay, scanned = scans.pop(cat)
        starts, lens = b_start[sel], b_len[sel]
        chosen[cat] = lay.edition
        judged = _judge_edition(starts, lens, scanned, cat, lay.edition, plan)
        errors += judged.errors
        if judged.stretches:
            stretches[cat] = judged.stretches
        counts = scanned.counts
        if judged.keep is not None and not judged.keep.any():
            scanned = scanned.none_kept()
            counts = np.full_like(counts, -1)
        elif judged.keep is not None:  # stretches withheld: the rest walked again on its own
            sel, starts, lens = sel[judged.keep], starts[judged.keep], lens[judged.keep]
            scanned = _scan(buf, starts, lens, lay)
            counts = scanned.counts
        decoded_bytes += int(lens[counts > 0].sum())
        decoded_blocks[cat] = int((counts > 0).sum())
        where, texts, rec_off, rec_blk = _extract(buf, scanned, lay)
        del scanned
        columns[cat] = _columns(lay, where, texts, rec_off, sel[rec_blk])
        del where, texts
    untimed = (time_cat001(columns, buf, framed, plan.editions, sector_clock or SectorClock())
               if PLOT_CATEGORY in plan.decoded else pd.DataFrame(columns=UNTIMED_COLUMNS))
    errors.sort()
    if strict and errors:
        o, _, c, why = errors[0]
        raise DecodeError(path, o, why, c)
    first_day = assign_days(columns, part, b_seg - first_segment)
    if first_day is not None and seg.dated:
        date = dt.date(1970, 1, 1) + dt.timedelta(days=first_day)
    frames: dict[int, pd.DataFrame] = {}
    odd: dict[int, Implausible] = {}
    mixed: dict[int, Implausible] = {}
    for cat in list(columns):
        cols = columns.pop(cat)
        odd[cat] = count_implausible(cols, cols["offset"])
        mixed[cat] = count_odd_sources(cols)
        for extra in () if asked is None else set(selected) - set(asked) - set(LEADING):
            cols.pop(extra, None)
        cols["timestamp"] = timestamp_index(cols["day"], cols["time_of_day"], date)
        frames[cat] = _build(cols)
        del cols
    err = pd.DataFrame(errors, columns=["offset", "length", "category", "reason"])
    # object, not pandas' str: a file name that is not UTF-8 (surrogate escapes) is kept as given
    err.insert(0, "file", pd.Series([path] * len(err), index=err.index, dtype=object))
    err["category"] = err["category"].astype("Int16").where(err["category"] >= 0)
    return Recording(frames=frames, errors=err, editions=chosen, path=path, format=seg.format, date=date,
                     size_bytes=int(len(buf)), container_bytes=int(part.container_bytes),
                     decoded_bytes=decoded_bytes, ignored_blocks=ignored, ignored_bytes=ignored_bytes,
                     edition_choice=dict(plan.choice), day0=first_day, ignored_category_bytes=ignored_by_cat,
                     edition_fits=dict(plan.fits), blocks=int(len(b_start)), untimed=untimed,
                     edition_stretches=stretches,
                     decoded_blocks=decoded_blocks, implausible={c: v for c, v in odd.items() if v.records},
                     odd_sources={c: v for c, v in mixed.items() if v.records},
                     oversized_bytes=oversized_bytes)


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
    """Accept {21: "0.26"} or ["21=0.26", ...] or "21=0.26"; TypeError for another form, or an edition that
    is not text (a float cannot hold 1.30), ValueError for a text that is not CAT=EDITION."""
    if editions is None:
        return {}
    if isinstance(editions, str):
        editions = [editions]
    if isinstance(editions, Mapping):
        pairs = list(editions.items())
    elif isinstance(editions, bytes | bytearray) or not hasattr(editions, "__iter__"):
        raise TypeError(f"editions {editions!r:.80}: give a mapping such as {{21: '0.26'}} or 'CAT=EDITION' "
                        f"texts such as '21=0.26'")
    else:
        pairs = []
        for item in editions:
            if not isinstance(item, str):
                raise TypeError(f"editions {editions!r:.80}: {item!r} is not a 'CAT=EDITION' text; give a "
                                f"mapping such as {{21: '0.26'}} or texts such as '21=0.26'")
            cat, eq, ed = item.partition("=")
            if not eq or not cat.strip().isdigit():
                raise ValueError(f"editions {editions!r:.80}: {item!r} is not 'CAT=EDITION' text such as "
                                 f"'21=0.26'")
            pairs.append((int(cat), ed.strip()))
    out = {}
    for cat, ed in pairs:
        if isinstance(cat, str) and cat.strip().isdigit():  # {"21": "0.26"}, as the texts give it
            cat = int(cat)
        if isinstance(cat, bool) or not isinstance(cat, int | np.integer):
            raise TypeError(f"editions {editions!r:.80}: category {cat!r} is not a category number (an int)")
        if not isinstance(ed, str):
            tables = ", ".join(available().get(int(cat), [])) or "none"
            raise TypeError(f"editions {editions!r:.80}: CAT{int(cat):03d} edition {ed!r} is a "
                            f"{type(ed).__name__}; give it as text, as the tables name it ('1.30': a float "
                            f"cannot hold 1.30; tables: {tables})")
        out[int(cat)] = ed
    return out


def reading_editions(editions, categories) -> dict[int, str]:
    """The editions a recording is read with: those given (``read``'s forms; a pinned one must name a
    shipped table), and for each other decoded category its reading default ('auto' for a category whose
    editions walk differently: asterix.families)."""
    eds = _parse_editions(editions)
    for cat, ed in eds.items():
        if ed != AUTO:
            resolve_edition(cat, ed)
    return with_defaults(eds, DEFAULT_CATEGORIES if categories is None else categories)


def read(path, *, editions=None, date=None, categories=None, format: str | None = None,
         strict: bool = False, columns=None) -> Recording:
    """Decode a recording file (raw, pcap/pcapng, final, gps or oradis) into typed frames by category.

    ``columns`` (names, any category) decodes only those columns besides ``sac``, ``sic``,
    ``time_of_day``, ``day``, ``timestamp``, ``block`` and ``offset``: a job that needs a few columns
    of a large recording holds only them. Every block is still walked and accounted alike.
    """
    selected_columns(columns)
    strict = check_strict(strict)
    date, categories = parse_date(date), check_categories(categories)
    eds = reading_editions(editions, categories)
    with _mapped(path) as buf:
        try:
            seg = read_segments(buf, format)
        except ValueError as exc:
            raise UnreadableInput(f"{path}: {exc}") from exc
        rec = decode_buffer(held(buf), seg, path=str(path), editions=eds, categories=categories, date=date,
                            strict=strict, columns=columns)
    if date is not None and rec.format in ("pcap", "pcapng") and rec.day0 is not None and rec.date != date:
        warnings.warn(f"{path}: date={date.isoformat()} ignored, the capture time dates a {rec.format} file "
                      f"(day 0 {rec.date})", UserWarning, stacklevel=2)
    for text in edition_advice(rec):
        warnings.warn(text, EditionWarning, stacklevel=2)
    for text in untimed_advice(rec.path, rec.untimed):
        warnings.warn(text, UntimedWarning, stacklevel=2)
    content = Tally(str(path))
    content.add(rec)
    for text in content.warnings(head_of(path), detected=format is None) + content.notes():
        warnings.warn(text, ContentWarning, stacklevel=2)
    return rec


def edition_advice(rec: Recording) -> list[str]:
    """Per category whose blocks mostly failed under its edition (``Recording.edition_fits``): how many, and
    the edition(s) every one sampled walks under, as ``read``'s ``editions=`` argument; per category holding
    stretches of another edition family (``Recording.edition_stretches``): where, and how to decode them."""
    out = [describe(rec.path, cat, found, lambda ed, c=cat: f"editions={{{c}: {ed!r}}}", rec.format == "raw")
           for cat, found in rec.edition_stretches.items()]
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
    """Data blocks per category in a recording, from framing alone (fast: no record is walked; counted a
    window at a time)."""
    with _mapped(path) as buf:
        seg = read_segments(buf, format)
        tables = tables_for({})
        counted = survey(buf, seg, segment_modes(buf, seg, tables), tables)
        return {int(c): int(counted.blocks[c]) for c in np.flatnonzero(counted.blocks)}
