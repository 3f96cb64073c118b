"""What counts as evidence when framing resumes after damage in a recording of categories not decoded (a
tracker's CAT062 blocks, read with the default categories): a chain of such blocks hidden inside a false
header's LEN is real blocks, whether their category was met or not; a short walking block of a decoded
category is evidence only when every record names one data source (I0xx/010, mandatory in every category),
as a sensor's block does.
Found by benchmarks/fuzz_undecoded.py (seed 1: 107 records made of track bytes, 258 intact blocks lost over
200 damaged slices). The streams are built with msdc's encoder; what is expected follows from how they are
built (the blocks written and where the damage is), not from the decoder."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest
from asterix_bytes import block
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


# Bytes that walk as a short block of a decoded category: three CAT010 records with no I010/010 (FSPEC 0x40:
# I010/000 message type alone); two CAT020 records, each I020/010 alone (FSPEC 0x80), naming 54/212 and
# 117/0, bytes met in the decode benchmark's track messages (its aircraft addresses are 0x7500xx): what was
# left of the made-up records of fuzz_undecoded seeds 1 and 2 once every record had to name a source.
CHANCE_BLOCKS = {"no data source": bytes([10, 0, 9, 0x40, 1, 0x40, 1, 0x40, 1]),
                 "two data sources": bytes([20, 0, 9, 0x80, 54, 212, 0x80, 117, 0])}


@pytest.mark.parametrize("kind", list(CHANCE_BLOCKS))
def test_a_short_walking_block_not_naming_one_source_anchors_nothing(tmp_path, kind):
    """Damage between two blocks of a tracker's recording: bytes that read as a header of a category met
    nowhere (CAT237) whose LEN lands on a short walking block (CHANCE_BLOCKS), then zeros to the next real
    block. Before, that chain of two anchored framing: CAT010 or CAT020 'reports' made of damage. The data
    source is mandatory in every record of every category, and a sensor's block names its own: a walking
    block whose records do not name one source is no evidence; the inserted bytes are the error and every
    real block is stepped over."""
    chance = CHANCE_BLOCKS[kind]
    assert chance[:3] == block(chance[0], chance[3:])[:3]  # the header's LEN counts the records given
    blocks = _tracker_blocks(24, 5)
    false = bytes([237]) + (3 + 20).to_bytes(2, "big") + bytes(range(20))
    damage = false + chance + bytes(50)
    at = sum(len(b) for b in blocks[:11])
    path = tmp_path / "tracks.ast"
    path.write_bytes(b"".join(blocks[:11]) + damage + b"".join(blocks[11:]))
    rec = _read(path)
    assert not any(len(f) for f in rec.frames.values()), {c: len(f) for c, f in rec.frames.items()}
    assert rec.ignored_blocks == {62: 24}
    assert rec.errors[["offset", "length"]].values.tolist() == [[at, len(damage)]]


def test_a_damaged_recording_whose_records_lack_the_data_source_still_decodes(tmp_path):
    """The other side of the rule: a CAT048 recording whose records carry no I048/010 (FSPEC 0x40: the
    time of day alone; not as the standard asks, as a simulator may write it), 500 random bytes inserted
    after its 200th block. Its blocks walk and its category is met, which anchors framing: every one of its
    1,200 records decodes, the inserted bytes the one error (a walking block without sources is no
    evidence on its own, but it is not damage either)."""
    rng = np.random.default_rng(3)
    blocks, tod = [], 0
    for _ in range(400):
        records = []
        for _ in range(3):
            tod += 128  # I048/140 in 1/128 s: one second a record
            records.append(bytes([0x40]) + tod.to_bytes(3, "big"))
        blocks.append(block(48, *records))
    at = sum(len(b) for b in blocks[:200])
    path = tmp_path / "radar.ast"
    path.write_bytes(b"".join(blocks[:200]) + rng.integers(0, 256, 500, dtype=np.uint8).tobytes()
                     + b"".join(blocks[200:]))
    rec = _read(path)
    assert rec.errors[["offset", "length"]].values.tolist() == [[at, 500]]
    got = rec.frames[48]
    assert len(got) == 1200 and got["sac"].isna().all()
    assert np.array_equal(got["time_of_day"].to_numpy(), np.arange(1, 1201, dtype=float))


def _two_radar_blocks(n: int) -> list[bytes]:
    """n CAT048 blocks of four plots each, the records naming 20/1 and 20/2 in turn (a block of two sources:
    not what a radar sends, but nothing forbids it); I048/010 and I048/040 (FSPEC 0x90), RHO 10 + i/256
    NM."""
    out = []
    for i in range(n):
        body = b"".join(bytes([0x90, 20, 1 + k % 2, 10, i % 256, 0x40, k]) for k in range(4))
        out.append(bytes([48]) + (3 + len(body)).to_bytes(2, "big") + body)
    return out


def test_blocks_naming_two_sources_still_frame_after_damage(tmp_path):
    """Blocks whose records name two sources are no evidence, but no damage either: 400 of them with 500
    random bytes inserted before the first, after the 200th or before the last, and with a false header
    (category 162) whose LEN swallows five of them, decode every plot, the inserted bytes the errors."""
    blocks = _two_radar_blocks(400)
    junk = np.random.default_rng(3).integers(0, 256, 500, dtype=np.uint8).tobytes()
    path = tmp_path / "radar.ast"
    for at in (0, 200, 399):
        path.write_bytes(b"".join(blocks[:at]) + junk + b"".join(blocks[at:]))
        rec = _read(path)
        assert len(rec.frames[48]) == 1600, at
        assert rec.errors[["offset", "length"]].values.tolist() == [[31 * at, 500]], at
    swallowed = sum(len(b) for b in blocks[200:205])
    false = bytes([162]) + (8 + swallowed).to_bytes(2, "big") + bytes(5)
    path.write_bytes(b"".join(blocks[:200]) + false + b"".join(blocks[200:]) + blocks[0][:10])
    rec = _read(path)
    assert len(rec.frames[48]) == 1600
    assert rec.errors[["offset", "length"]].values.tolist() == [[31 * 200, 8], [31 * 400 + 8, 10]]


def test_a_real_block_hiding_chance_headers_that_jump_onto_later_blocks_is_kept(tmp_path):
    """A tracker's block right after damage (5 zeros after the 15th block) whose last record (I062/SP, FRN
    35) holds bytes that read as a header of CAT182 (LEN 16) and then one of CAT115 whose LEN jumps to the
    start of a real block four blocks later: a chain of three categories not decoded that runs on over the
    eleven real blocks after it. Such chance headers lie inside 2,051 of the decode benchmark's 40,000
    CAT062 blocks; only two of the chain's blocks are inside this one, and the real blocks a false LEN
    swallows are four or more, so the block is kept where framing resumes (the first version of the rule
    took it for a false header and lost it)."""
    blocks = _tracker_blocks(30, 7)
    zeros, k = 5, 15
    start = sum(len(b) for b in blocks[:k]) + zeros  # where the block after the damage starts
    grown = len(blocks[k]) + 8 + 40  # the SP record: FSPEC 0x81 01 01 01 02, I062/010, length byte, 40
    first = start + len(blocks[k]) + 8  # the chance headers, at the start of the SP data
    target = start + grown + sum(len(b) for b in blocks[k + 1:k + 4])  # the start of the 4th block after
    sp = bytes([182, 0, 16]) + bytes(13) + bytes([115]) + (target - (first + 16)).to_bytes(2, "big")
    sp += bytes(40 - len(sp))
    body = blocks[k][3:] + bytes([0x81, 1, 1, 1, 0x02, 9, 9, 1 + len(sp)]) + sp
    blocks[k] = bytes([62]) + (3 + len(body)).to_bytes(2, "big") + body
    assert len(blocks[k]) == grown
    path = tmp_path / "tracks.ast"
    path.write_bytes(b"".join(blocks[:k]) + bytes(zeros) + b"".join(blocks[k:]))
    rec = _read(path)
    assert not any(len(f) for f in rec.frames.values())
    assert rec.errors[["offset", "length"]].values.tolist() == [[start - zeros, zeros]]
    assert rec.ignored_blocks == {62: 30}
    assert len(_read(path, categories=[62]).frames[62]) == 30 * RECORDS_PER_BLOCK + 1
