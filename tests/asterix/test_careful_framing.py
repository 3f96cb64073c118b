"""Careful framing does not let a cut block that walks by chance swallow the real block after it (issue
#27, found by benchmarks/fuzz_reader.py on the real CAT021 and CAT010 files). Streams built by hand from
the CAT048 fixture's blocks and the I048 layout of the spec (I048/010 2 bytes, I048/140 3, I048/020 1 with
FX, I048/040 4: RHO in 1/256 NM, THETA in 360/2^16 degrees)."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np

import msdc.asterix as asterix


def _stream(tmp_path: Path, pieces: list[bytes]) -> asterix.Recording:
    path = tmp_path / "stream.ast"
    path.write_bytes(b"".join(pieces))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return asterix.read(path, categories=[48])


def plot(sac: int, sic: int, rho: int, theta: int) -> bytes:
    """A CAT048 block of one record: I048/010 and I048/040 (FSPEC 0x90), raw RHO and THETA."""
    return bytes([48, 0, 10, 0x90, sac, sic, rho >> 8, rho & 255, theta >> 8, theta & 255])


def _real_blocks(n: int) -> list[bytes]:
    return [plot(1, 2 * i, 2560 + i, 1000 * i) for i in range(n)]


def _junk_header(real: list[bytes], category: int, into: int) -> tuple[list[bytes], int]:
    """The real blocks with a 3-byte junk header of ``category`` inserted after the third, its LEN landing
    four bytes into real[into] (counted after the inserted bytes); the pieces and the junk's offset."""
    junk_at = sum(len(p) for p in real[:3])
    land = sum(len(p) for p in real[:into]) + 3 + 4
    junk = bytes([category]) + (land - junk_at).to_bytes(2, "big")
    return [*real[:3], junk, *real[3:]], junk_at


def test_a_cut_block_ending_a_byte_into_the_next_does_not_swallow_it(tmp_path):
    """The cut block: header, FSPEC of I048/010 alone, one byte of its own, and for its last byte the real
    block's category: it walks exactly and ends one byte into the real block, where a zero follows."""
    real = _real_blocks(6)
    cut = bytes([48, 0, 6, 0x80, 7])  # + the real block's first byte (48) as I048/010's SIC
    pieces = [*real[:3], cut, *real[3:]]
    rec = _stream(tmp_path, pieces)
    start = sum(len(p) for p in pieces[:4])  # the real block after the cut one
    assert start + 3 in set(rec.frames[48]["offset"]), "the real block after the cut one is lost"
    # every real block's records, none of the cut one's
    whole = _stream(tmp_path, real)
    assert len(rec.frames[48]) == len(whole.frames[48])
    assert rec.errors["offset"].min() == sum(len(p) for p in real[:3])


def test_a_cut_block_whose_tail_lands_far_on_a_real_block_does_not_swallow_the_next(tmp_path):
    """The cut block (header and FSPEC of I048/010, I048/140, I048/020) walks over the next block's first
    six bytes; the bytes it ends on read as a CAT096 header (the next block's RHO 96.0 NM) whose LEN (the
    THETA's first byte) jumps to a real block two blocks on: a chain that lands on a real block by chance
    is no evidence, and the next block is decoded with its values."""
    real = _real_blocks(6)
    after = real[2]
    jump = 4 + len(after)  # from the CAT096 'header' (RHO's first byte) to the block after ``after``
    assert jump < 256
    sic = 8  # even: I048/020's one byte ends (FX clear) on it
    nxt = bytes([48, 0, 10, 0x90, 5, sic, 96, 0, jump, 64])  # I048/010 and I048/040
    cut = bytes([48, 0, 10, 0xE0])  # + nxt's first 6 bytes: I048/010 (2), I048/140 (3), I048/020 (1)
    pieces = [*real[:2], cut, nxt, after, *real[3:]]
    rec = _stream(tmp_path, pieces)
    at = sum(len(p) for p in pieces[:3])
    got = rec.frames[48].set_index("offset")
    assert at + 3 in got.index, "the block after the cut one is lost"
    row = got.loc[at + 3]
    assert (int(row["sac"]), int(row["sic"])) == (5, sic)
    assert np.isclose(row["rho_nm"], (96 * 256) / 256)
    assert np.isclose(row["theta_deg"], (jump * 256 + 64) * 360 / 65536)
    assert len(rec.frames[48]) == len(_stream(tmp_path, real).frames[48]) + 1  # every real block's, and nxt's
    assert rec.errors["offset"].tolist() == [sum(len(p) for p in pieces[:2])]



def test_a_len_landing_on_a_chance_block_inside_a_real_one_does_not_swallow_the_real_ones(tmp_path):
    """Three junk bytes, a header of a category met nowhere else (0x77), whose LEN lands four bytes into a
    real block whose SAC, SIC and RHO read 48, 0, 10, 0x90: a CAT048 block header and FSPEC that walk
    exactly (I048/010, I048/040, ten bytes, into the next real block). One chance block that walks is no
    proof of that LEN: the real blocks after the junk decode (benchmarks/fuzz_reader.py found it on the real
    surface radar file: 1,707 records lost after 2,852 inserted bytes)."""
    real = _real_blocks(10)
    real[6] = plot(48, 0, (10 << 8) | 0x90, 4321)
    pieces, junk_at = _junk_header(real, 0x77, 6)  # four bytes into real[6]
    rec = _stream(tmp_path, pieces)
    whole = _stream(tmp_path, real)
    assert len(rec.frames[48]) == len(whole.frames[48])
    assert rec.errors[["offset", "length"]].values.tolist() == [[junk_at, 3]]


def test_a_len_proven_by_chance_headers_inside_real_data_does_not_swallow_the_real_ones(tmp_path):
    """A junk header of a category met nowhere else (0x77) whose LEN lands four bytes into a real block
    whose SAC, SIC and RHO read 0x77, 0, 20: the header of a 0x77 'block' of 20 bytes, landing four bytes
    into the block two on, which reads the same, and so on: a chain of its own category, as the junk
    header's LEN would need. Ten real blocks walk between the junk and that landing: they are what the junk
    hides, wherever its LEN lands (benchmarks/fuzz_reader.py found it on a slice of the real Barcelona radar
    hour: 244 of 3,315 records lost after 2,920 inserted bytes)."""
    real = _real_blocks(22)
    for i in (12, 14, 16, 18, 20):
        real[i] = plot(0x77, 0, (20 << 8) | 7, 1000 * i)
    pieces, junk_at = _junk_header(real, 0x77, 12)  # four bytes into real[12]
    rec = _stream(tmp_path, pieces)
    assert len(rec.frames[48]) == len(_stream(tmp_path, real).frames[48]) == 22
    assert rec.errors[["offset", "length"]].values.tolist() == [[junk_at, 3]]


def test_a_len_landing_on_one_chance_header_of_its_own_category_does_not_swallow_the_real_ones(tmp_path):
    """A junk header of a category met nowhere else (0x16) whose LEN lands four bytes into a real block
    whose SAC, SIC and RHO read 0x16, 0, 16: a 0x16 'block' of 16 bytes, which lands on the start of the
    real block two on, and real blocks follow. One header of its own category, met by chance, is no proof of
    the junk's LEN: the two real blocks it would swallow decode (benchmarks/fuzz_reader.py found it on a
    slice of the ADS-B fixture: 20 of 4,540 records lost after two deletions). The real blocks are one
    radar's (1/2), as a recording's blocks are: the chain here holds from end to end, and a walking block
    hidden in another block makes it framed carefully when it names a data source of the chain's."""
    real = [plot(1, 2, 2560 + i, 1000 * i) for i in range(12)]
    real[5] = plot(0x16, 0, (16 << 8) | 7, 4321)
    pieces, junk_at = _junk_header(real, 0x16, 5)  # four bytes into real[5]
    rec = _stream(tmp_path, pieces)
    assert len(rec.frames[48]) == len(_stream(tmp_path, real).frames[48]) == 12
    assert rec.errors[["offset", "length"]].values.tolist() == [[junk_at, 3]]


def test_a_cut_block_landing_on_a_false_truncated_tail_does_not_swallow_the_next(tmp_path):
    """The cut block (header, FSPEC of I048/010 and I048/040, one byte) walks over the next block's first
    five bytes and lands on its SIC and RHO, which read 48, 0xF0, 0x00: a CAT048 header whose LEN (61,440)
    runs past the end of the data, as a file's truncated last block would. Real blocks follow it, so it is
    no truncated tail and proves nothing: the next block decodes with its values (benchmarks/fuzz_reader.py
    found it on the real ADS-B 0.23 file, seed 99: one record lost after a copied stretch)."""
    real = _real_blocks(8)
    nxt = plot(3, 48, 0xF000, 0x4000)
    cut = bytes([48, 0, 10, 0x90, 1])  # + nxt's first five bytes: I048/010 (1, 48), I048/040 (0, 10, 0x90, 3)
    pieces = [*real[:4], cut, nxt, *real[4:]]
    rec = _stream(tmp_path, pieces)
    at = sum(len(p) for p in pieces[:5])
    got = rec.frames[48].set_index("offset")
    assert at + 3 in got.index, "the block after the cut one is lost"
    row = got.loc[at + 3]
    assert (int(row["sac"]), int(row["sic"])) == (3, 48)
    assert np.isclose(row["rho_nm"], 0xF000 / 256) and np.isclose(row["theta_deg"], 90.0)
    assert len(rec.frames[48]) == 9  # the eight real blocks' plots and nxt's, none of the cut one's
    assert rec.errors[["offset", "length"]].values.tolist() == [[sum(len(p) for p in pieces[:4]), 5]]
