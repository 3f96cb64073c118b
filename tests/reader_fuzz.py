"""Damage drawn at random in a clean recording, and what the reader must still do with it (issue #27):
account for every byte, return the same records and errors from ``read`` and from ``iter_read`` at any
chunk size, and lose no record of a block the damage did not touch (its values unchanged).

Shared by the seeded fuzz tests (tests/asterix/test_fuzz_reader.py) and the full run in
benchmarks/fuzz_reader.py. The damage is tracked byte by byte (where each byte of the damaged file came
from in the clean one), so which blocks are intact is known independently of the decoder.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

import msdc.asterix as asterix

DAMAGES = ("flip", "insert", "insert at a block start", "delete", "duplicate", "zeros", "overwrite",
           "truncate")
IDENTITY = ("block", "offset")  # columns that move with the damage
CHUNKS = (1_000, 20_000, 100_000, 1_000_000)  # chunk sizes drawn around (bytes of payload)


@dataclass
class Damaged:
    """A damaged copy of a clean recording: its bytes, where each came from in the clean one (-1: new or
    changed), and what was done."""

    data: bytes
    origin: np.ndarray
    done: list[str] = field(default_factory=list)


def clean_blocks(data: bytes) -> tuple[np.ndarray, np.ndarray]:
    """Data block starts and lengths of a clean raw stream, read from its headers (the chain must hold)."""
    starts, lens, q = [], [], 0
    while q < len(data):
        n = int.from_bytes(data[q + 1:q + 3], "big")
        assert n >= 3 and q + n <= len(data), f"not a clean stream at offset {q}"
        starts.append(q)
        lens.append(n)
        q += n
    return np.array(starts, np.int64), np.array(lens, np.int64)


def damage(data: bytes, rng: np.random.Generator, blocks: np.ndarray, n_damages: int = 1) -> Damaged:
    """Apply ``n_damages`` damages drawn from DAMAGES at random places: bits flipped, 1-3000 random bytes
    inserted (anywhere or at a block start), 1-3000 bytes deleted, 1-3000 bytes of the file copied in
    elsewhere, a stretch zeroed or overwritten with random bytes, the tail cut."""
    buf = np.frombuffer(data, np.uint8).copy()
    origin = np.arange(len(buf), dtype=np.int64)
    done = []
    for _ in range(n_damages):
        if len(buf) < 2:
            break
        kind = DAMAGES[int(rng.integers(len(DAMAGES)))]
        pos = int(rng.integers(0, len(buf)))
        size = int(rng.integers(1, 3001))
        if kind == "insert at a block start":
            inside = blocks[blocks < len(buf)]
            pos = int(rng.choice(inside)) if len(inside) else pos
            size = int(rng.integers(1, 9))
        if kind == "flip":
            for _ in range(int(rng.integers(1, 4))):
                at = int(rng.integers(max(pos - 8, 0), min(pos + 8, len(buf))))
                buf[at] ^= np.uint8(1 << int(rng.integers(8)))
                origin[at] = -1
        elif kind in ("insert", "insert at a block start"):
            new = rng.integers(0, 256, size, dtype=np.uint8)
            buf = np.concatenate([buf[:pos], new, buf[pos:]])
            origin = np.concatenate([origin[:pos], np.full(size, -1), origin[pos:]])
        elif kind == "delete":
            buf = np.concatenate([buf[:pos], buf[pos + size:]])
            origin = np.concatenate([origin[:pos], origin[pos + size:]])
        elif kind == "duplicate":  # a stretch of the file itself: blocks and pieces of blocks
            src = int(rng.integers(0, max(len(buf) - size, 1)))
            buf = np.concatenate([buf[:pos], buf[src:src + size], buf[pos:]])
            origin = np.concatenate([origin[:pos], np.full(len(buf) - len(origin), -1), origin[pos:]])
        elif kind in ("zeros", "overwrite"):
            stop = min(pos + size, len(buf))
            buf[pos:stop] = 0 if kind == "zeros" else rng.integers(0, 256, stop - pos, dtype=np.uint8)
            origin[pos:stop] = -1
        else:  # truncate
            buf, origin = buf[:pos], origin[:pos]
        done.append(f"{kind} at {pos}" + (f" ({size} bytes)" if kind not in ("flip", "truncate") else ""))
    return Damaged(buf.tobytes(), origin, done)


def intact_blocks(damaged: Damaged, starts: np.ndarray, lens: np.ndarray) -> dict[int, int]:
    """Clean block start -> its start in the damaged file, for each clean block whose bytes all survive
    unchanged and in one piece."""
    where = np.full(int(starts[-1] + lens[-1]) if len(starts) else 0, -1, np.int64)
    keep = damaged.origin >= 0
    where[damaged.origin[keep]] = np.flatnonzero(keep)
    out = {}
    for s, n in zip(starts.tolist(), lens.tolist(), strict=True):
        at = where[s:s + n]
        if at[0] >= 0 and (np.diff(at) == 1).all() and (at >= 0).all():
            out[s] = int(at[0])
    return out


def account(rec: asterix.Recording) -> int:
    """Bytes in decoded blocks, skipped blocks and bytes, container headers and blocks not decoded."""
    return rec.decoded_bytes + int(rec.errors["length"].sum()) + rec.container_bytes + rec.ignored_bytes


def _plain(frame: pd.DataFrame) -> pd.DataFrame:
    """A frame with categoricals as objects (each chunk has its own categories)."""
    out = frame.reset_index(drop=True)
    for name in out.columns:  # chunks of different categories concatenate to objects (NaN for absent)
        if isinstance(out[name].dtype, pd.CategoricalDtype) or out[name].dtype == object:
            out[name] = out[name].astype(object).where(out[name].notna(), None)
    return out


def check_chunks(path: Path, whole: asterix.Recording, chunk: int, **kw) -> list[str]:
    """What differs between ``read`` (``whole``) and ``iter_read`` at this chunk size: records, errors, the
    byte account; [] when nothing."""
    parts = list(asterix.iter_read(path, chunk=chunk, **kw))
    problems = []
    for cat in sorted(set(whole.frames) | {c for p in parts for c in p.frames}):
        pieces = [p.frames[cat] for p in parts if cat in p.frames]
        joined = pd.concat(pieces, ignore_index=True) if pieces else whole.frames[cat].iloc[:0]
        frame = whole.frames.get(cat, joined.iloc[:0])
        if len(joined) != len(frame):
            problems.append(f"chunk {chunk}: CAT{cat:03d} {len(joined)} records, read gives {len(frame)}")
            continue
        try:
            pd.testing.assert_frame_equal(_plain(joined), _plain(frame), check_dtype=False)
        except AssertionError as exc:
            problems.append(f"chunk {chunk}: CAT{cat:03d} records differ from read's: {str(exc)[:300]}")
    errors = pd.concat([p.errors for p in parts], ignore_index=True) if parts else whole.errors.iloc[:0]
    mine = [tuple(e) for e in errors[["offset", "length", "reason"]].itertuples(index=False)]
    theirs = [tuple(e) for e in whole.errors[["offset", "length", "reason"]].itertuples(index=False)]
    if sorted(mine) != sorted(theirs):
        diff = sorted(set(mine) ^ set(theirs))
        problems.append(f"chunk {chunk}: errors differ from read's: {diff[:4]}")
    got = sum(account(p) for p in parts)
    if got != whole.size_bytes:
        problems.append(f"chunk {chunk}: {got} bytes accounted for of {whole.size_bytes}")
    return problems


def check_kept(clean: asterix.Recording, damaged: asterix.Recording, moved: dict[int, int],
               starts: np.ndarray) -> list[str]:
    """Records of the clean recording's intact blocks (``moved``: clean block start -> damaged start) that
    the damaged decode lost or changed; [] when none."""
    problems = []
    now = np.full(len(starts), -1, np.int64)  # each clean block's start in the damaged file, -1 if damaged
    now[np.searchsorted(starts, np.fromiter(moved, np.int64, len(moved)))] = list(moved.values())
    for cat, frame in clean.frames.items():
        off = frame["offset"].to_numpy()
        blk = np.searchsorted(starts, off, side="right") - 1
        keep = now[blk] >= 0
        if not keep.any():
            continue
        want = frame[keep].assign(offset=off[keep] - starts[blk[keep]] + now[blk[keep]]).drop(columns="block")
        got = damaged.frames.get(cat)
        got = got.drop(columns="block") if got is not None else want.iloc[:0]
        both = want.merge(got[["offset"]].assign(found=True), on="offset", how="left")
        lost = both[both["found"].isna()]
        if len(lost):
            problems.append(f"CAT{cat:03d}: {len(lost)} of {len(want)} records of intact blocks lost, the "
                            f"first at damaged offset {int(lost['offset'].iloc[0])}")
            continue
        mine = _plain(got[got["offset"].isin(want["offset"])].sort_values("offset"))
        theirs = _plain(want.sort_values("offset"))
        try:
            pd.testing.assert_frame_equal(mine[theirs.columns], theirs, check_dtype=False)
        except AssertionError as exc:
            problems.append(f"CAT{cat:03d}: records of intact blocks changed: {str(exc)[:300]}")
    return problems
