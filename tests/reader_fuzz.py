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


def _block(cat: int, body: bytes) -> bytes:
    """A data block: CAT, LEN (counting the 3 header bytes), records."""
    return bytes([cat]) + (len(body) + 3).to_bytes(2, "big") + body


def multilateration_stream(n_blocks: int = 2_000) -> bytes:
    """CAT010 (MLAT target reports, 1.1) and CAT020 (1.9-1.11) blocks in turn, three records each, laid out by
    hand as in tests/asterix/test_cat010_cat020_damage.py: report i has time of day i s, track number i, and
    (CAT010) x = i m, y = -i m. CAT010: FSPEC F3 20 (FRNs 1 2 3 4 7 | 10), I010/010 0/107, /000 1, /020 0x2C
    (TYP 1), /140, /042, /161; CAT020: FSPEC E4 (FRNs 1 2 3 6), I020/010 25/10, /020 0x40, /140, /161."""
    out, i = [], 1
    for b in range(n_blocks):
        records = []
        for _ in range(3):
            if b % 2 == 0:
                records.append(bytes.fromhex("F320") + bytes([0, 107, 1, 0x2C]) + (128 * i).to_bytes(3, "big")
                               + i.to_bytes(2, "big", signed=True) + (-i).to_bytes(2, "big", signed=True)
                               + i.to_bytes(2, "big"))
            else:
                records.append(bytes([0xE4, 25, 10, 0x40]) + (128 * i).to_bytes(3, "big")
                               + i.to_bytes(2, "big"))
            i += 1
        out.append(_block(10 if b % 2 == 0 else 20, b"".join(records)))
    return b"".join(out)


def cat001_stream(rounds: int = 1_500) -> bytes:
    """A CAT001 radar (SAC/SIC 25/201) as in tests/asterix/test_cat001.py's radar_stream: per round r a CAT002
    sector crossing at 100 + r s (FSPEC F0: I002/010, /000 2, /020 sector, /030), then a CAT001 block of two
    tracks (FSPEC E1 40: I001/010, /020 0x80 TYP 1, /161 track number, /141 the truncated time 100 + r s,
    made whole by the CAT002 before it) and one plot (FSPEC E2: /010, /020 0x00, /040, /141 0: undated)."""
    out, n = [], 1
    for r in range(rounds):
        sector = bytes([0xF0, 25, 201, 2, (16 * r) % 256]) + (128 * (100 + r)).to_bytes(3, "big")
        out.append(_block(2, sector))
        tracks = [bytes([0xE1, 0x40, 25, 201, 0x80]) + ((n + k) % 65536).to_bytes(2, "big")
                  + (128 * (100 + r) % 65536).to_bytes(2, "big") for k in range(2)]
        plot = bytes([0xE2, 25, 201, 0x00]) + bytes.fromhex("0A000100") + bytes(2)
        out.append(_block(1, b"".join(tracks) + plot))
        n += 2
    return b"".join(out)


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


TIMES = ("time_of_day", "day", "timestamp")


def check_kept(clean: asterix.Recording, damaged: asterix.Recording, moved: dict[int, int],
               starts: np.ndarray, copied: bool = False) -> list[str]:
    """Records of the clean recording's intact blocks (``moved``: clean block start -> damaged start) that
    the damaged decode lost or changed; [] when none. A CAT001 record's time of day is made whole from the
    CAT002 messages before it, which damage may destroy: it may then be undated (NaN, and listed in
    ``damaged.untimed``), never dated otherwise; unless the damage copied bytes of the file itself in
    (``copied``): a real CAT002 message copied in dates what follows it, as it would on the wire."""
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
        if cat == 1:  # time made whole from other blocks (docstring)
            untimed = set(damaged.untimed["offset"].tolist())
            excused = mine["offset"].isin(untimed).to_numpy() & mine["time_of_day"].isna().to_numpy()
            if copied:
                excused |= mine["time_of_day"].notna().to_numpy()
            for name in TIMES:
                theirs.loc[excused, name] = mine.loc[excused, name]
        try:
            pd.testing.assert_frame_equal(mine[theirs.columns], theirs, check_dtype=False)
        except AssertionError as exc:
            problems.append(f"CAT{cat:03d}: records of intact blocks changed: {str(exc)[:300]}")
    return problems
