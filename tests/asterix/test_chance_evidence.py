"""What counts as evidence when framing resumes after damage in a recording of categories not decoded (a
tracker's CAT062 blocks, read with the default categories): a chain of such blocks hidden inside a false
header's LEN is real blocks, whether their category was met or not.
Found by benchmarks/fuzz_undecoded.py (seed 1: 107 records made of track bytes, 258 intact blocks lost over
200 damaged slices). The streams are built with msdc's encoder; what is expected follows from how they are
built (the blocks written and where the damage is), not from the decoder."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
from live_bytes import raw_blocks

import msdc.asterix as asterix
from msdc.asterix.encode import encode_frame

RECORDS_PER_BLOCK = 25


def _tracker_blocks(n: int, seed: int) -> list[bytes]:
    """n CAT062 blocks of 25 system track messages (the decode benchmark's track items)."""
    import importlib.util

    path = Path(__file__).resolve().parents[2] / "benchmarks" / "decode.py"
    spec = importlib.util.spec_from_file_location("msdc_bench_decode", path)
    bench = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(bench)
    frame = bench.cat062_frame(n * RECORDS_PER_BLOCK, np.random.default_rng(seed))
    return raw_blocks(encode_frame(62, frame, records_per_block=RECORDS_PER_BLOCK))


def _read(path: Path, **kw) -> asterix.Recording:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return asterix.read(path, **kw)


def test_a_false_header_does_not_swallow_a_trackers_blocks_not_met_yet(tmp_path):
    """Damage at the start of a tracker's recording: 8 bytes whose header (category 162, met nowhere) has a
    LEN running over the first 20 real blocks and landing exactly on the 21st; the last block cut short by
    7 bytes (so that it is framed carefully). CAT062 is not met yet, so no chain of met categories shows
    the blocks inside; twelve blocks of one category not decoded in a row there do (a chance header lands
    on a chain with a chance of 1/65,536, never on twelve). Before, the false block was kept and the 20
    blocks lost inside it."""
    blocks = _tracker_blocks(40, 3)
    swallowed = sum(len(b) for b in blocks[:20])
    junk = bytes([162]) + (8 + swallowed).to_bytes(2, "big") + bytes([1, 2, 3, 4, 5])
    last = len(junk) + sum(len(b) for b in blocks[:39])
    path = tmp_path / "tracks.ast"
    path.write_bytes((junk + b"".join(blocks))[:-7])
    rec = _read(path)
    assert not any(len(f) for f in rec.frames.values())
    assert rec.errors[["offset", "length"]].values.tolist() == [[0, len(junk)], [last, len(blocks[39]) - 7]]
    assert rec.ignored_blocks == {62: 39}
