"""Damage inside data blocks: how often it is refused, walks into other records, and is told.

Run by hand: ``python benchmarks/damage.py [--trials 400] [--seed 2] [FILE:CATEGORY ...]`` (default: the
bundled fixtures, 20 records a block). Each trial overwrites 4-32 random bytes inside one block (its header
kept) and decodes that block alone under the undamaged block's edition. Outcomes: refused (a decode error),
the same number of records (other values: no check can tell them without a checksum, which ASTERIX lacks),
or another number of records (the walk past the damage made records of misaligned bytes); of the last, how
many ``Recording.odd_sources`` (records naming another data source than their block) and
``Recording.implausible`` (a position off the Earth, a time outside 0-24 h) tell.
"""

from __future__ import annotations

import argparse
import warnings
from pathlib import Path

import numpy as np

import msdc.asterix as asterix
from msdc.asterix.containers import read_segments
from msdc.asterix.reader import decode_buffer

FIXTURES = Path(__file__).resolve().parents[1] / "fixtures"


def decode_block(data: bytes, editions: dict | None = None) -> asterix.Recording:
    """One data block decoded on its own (a raw stream of it)."""
    buf = np.frombuffer(data, np.uint8)
    return decode_buffer(buf, read_segments(buf, "raw"), editions=editions)


def blocks_of(data: bytes, category: int) -> list[tuple[int, int]]:
    """(offset, LEN) of the category's blocks of more than one record's bytes, along the raw chain."""
    out, q = [], 0
    while q + 3 <= len(data):
        n = int.from_bytes(data[q + 1:q + 3], "big")
        if n < 3:
            break
        if data[q] == category and n > 40:
            out.append((q, n))
        q += n
    return out


def run(path: Path, category: int, trials: int, seed: int) -> dict[str, int]:
    """The outcomes of ``trials`` overwrites of one file's blocks."""
    data = path.read_bytes()
    blocks = blocks_of(data, category)
    rng = np.random.default_rng(seed)
    out = dict.fromkeys(("refused", "same_records", "other_records", "told_by_source", "told_by_value",
                         "told_by_either"), 0)
    for _ in range(trials):
        q, n = blocks[rng.integers(len(blocks))]
        blk = bytearray(data[q:q + n])
        k = int(rng.integers(4, 33))
        at = 3 + int(rng.integers(max(1, n - 3 - k)))
        blk[at:at + k] = rng.integers(0, 256, k, dtype=np.uint8).tobytes()[:len(blk[at:at + k])]
        good = decode_block(data[q:q + n])
        bad = decode_block(bytes(blk), dict(good.editions))
        if len(bad.errors):
            out["refused"] += 1
            continue
        if len(bad.frames[category]) == len(good.frames[category]):
            out["same_records"] += 1
            continue
        out["other_records"] += 1
        source, value = category in bad.odd_sources, category in bad.implausible
        out["told_by_source"] += source
        out["told_by_value"] += value
        out["told_by_either"] += source or value
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("inputs", nargs="*", help="FILE:CATEGORY (default: the bundled fixtures)")
    parser.add_argument("--trials", type=int, default=400)
    parser.add_argument("--seed", type=int, default=2)
    args = parser.parse_args()
    cases = [(Path(a.rsplit(":", 1)[0]), int(a.rsplit(":", 1)[1])) for a in args.inputs] or [
        (FIXTURES / "adsb.ast", 21), (FIXTURES / "radar.ast", 48)]
    warnings.simplefilter("ignore", asterix.ContentWarning)
    for path, category in cases:
        outcomes = run(path, category, args.trials, args.seed)
        print(f"{path.name} CAT{category:03d}, {args.trials} overwrites: {outcomes}")


if __name__ == "__main__":
    main()
