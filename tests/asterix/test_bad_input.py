"""Bad input: clear account of what was skipped, nothing decodable lost, no bytes ever crash."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from asterix_bytes import block, decode_bytes, fspec, mutate
from budget import examples
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import msdc.asterix as asterix


def rec048(i: int) -> bytes:
    """A CAT048 record: I048/010 (SAC 7, SIC i), I048/140 ToD = i seconds, I048/161 track i."""
    tod, track = (128 * i).to_bytes(3, "big"), (i & 0xFFF).to_bytes(2, "big")
    return fspec(1, 2, 11) + bytes([7, i & 0xFF]) + tod + track


def good_stream(n_blocks: int = 6, per_block: int = 3) -> tuple[bytes, list[int]]:
    """Raw data blocks and the offset at which each block starts."""
    out, starts = b"", []
    for b in range(n_blocks):
        starts.append(len(out))
        out += block(48, *(rec048(b * per_block + k + 1) for k in range(per_block)))
    return out, starts


def accounted(rec: asterix.Recording) -> int:
    """Bytes in decoded blocks, error entries, container headers and ignored blocks."""
    return rec.decoded_bytes + int(rec.errors["length"].sum()) + rec.container_bytes + rec.ignored_bytes


def test_good_stream_has_no_errors():
    data, _ = good_stream()
    rec = decode_bytes(data)
    assert rec.errors.empty and len(rec.frames[48]) == 18
    assert list(rec.frames[48].track_number) == list(range(1, 19))
    assert accounted(rec) == len(data)


def test_truncated_file_keeps_every_complete_block():
    data, starts = good_stream()
    cut = starts[-1] + 7  # last block cut inside its first record
    rec = decode_bytes(data[:cut])
    assert len(rec.frames[48]) == 15
    assert list(rec.errors.offset) == [starts[-1]]
    assert "past the end" in rec.errors.reason.iloc[0]
    assert accounted(rec) == cut


def test_len_past_end_and_fspec_past_block():
    data, starts = good_stream()
    # block 2 claims one byte less than it has: its last record's item runs past the block end
    bad = bytearray(data)
    n = int.from_bytes(bad[starts[2] + 1:starts[2] + 3], "big")
    bad[starts[2] + 1:starts[2] + 3] = (n - 1).to_bytes(2, "big")
    rec = decode_bytes(bytes(bad))
    assert not rec.errors.empty and rec.errors.offset.iloc[0] == starts[2]
    tracks = set(rec.frames[48].track_number)
    assert {1, 2, 3, 4, 5, 6}.issubset(tracks)  # blocks before
    assert {13, 14, 15, 16, 17, 18}.issubset(tracks)  # blocks after the damage
    assert accounted(rec) == len(data)


def test_an_fspec_past_the_end_names_its_record():
    """A block ending inside a record's FSPEC (an FX bit set on its last byte) names that record: it said
    'record at offset -1' before."""
    data, starts = good_stream(2)
    cut = block(48, rec048(1), b"\x01")  # record 2 is one FSPEC byte with FX set, then the block ends
    rec = decode_bytes(data + cut)
    assert list(rec.errors.offset) == [len(data)]
    first_record_end = len(data) + 3 + len(rec048(1))
    assert rec.errors.reason.iloc[0] == ("an FSPEC or item runs past the end of its data block "
                                         f"(record at offset {first_record_end})")


def adsb_blocks(n: int, edition: str) -> bytes:
    """n CAT021 blocks of one record each (position, time, address, call sign) in the given edition."""
    from msdc.asterix.encode import encode_frame

    frame = pd.DataFrame({"sac": 0, "sic": 107, "time_of_day": 79200 + 0.5 * np.arange(n),
                          "latitude": 41.3 + 1e-4 * np.arange(n), "longitude": 2.08 + 1e-4 * np.arange(n),
                          "address": 0x3443D2, "callsign": "VLG836M"})
    return encode_frame(21, frame, edition=edition, records_per_block=1)


def test_a_wrong_edition_keeps_a_chain_that_holds(tmp_path):
    """Blocks whose chain tiles the file but that do not walk under the edition asked for are of another
    edition, not damaged: each is reported at its own offset as a walk error. Careful framing used to
    cut them up and report bytes of valid blocks as framing errors ('data block LEN below 3')."""
    n = 40
    data = adsb_blocks(n, "0.23")
    starts, q = [], 0
    while q < len(data):  # the block starts, from the LEN fields
        starts.append(q)
        q += int.from_bytes(data[q + 1:q + 3], "big")
    assert len(decode_bytes(data, editions={21: "0.23"}).frames[21]) == n
    rec = decode_bytes(data, editions={21: "2.7"})
    assert list(rec.errors.offset) == starts
    assert (rec.errors.category == 21).all()
    assert not rec.errors.reason.str.contains("data block LEN|plausible").any()
    assert accounted(rec) == len(data)
    # I021/130 is 6 bytes in 0.23 and 8 from 0.24 (specs): no other edition walks these blocks
    assert rec.edition_fits == {21: ("0.23",)}
    path = tmp_path / "adsb.ast"  # read in chunks (msdc stats, decode and the jobs): cut at the same blocks
    path.write_bytes(data)
    chunks = list(asterix.iter_read(path, editions={21: "2.7"}, chunk=200))
    assert len(chunks) > 1
    assert [int(o) for c in chunks for o in c.errors.offset] == starts


@pytest.mark.parametrize(("n_wrong", "withheld"), [(12, True), (9, False)])
def test_blocks_that_walk_under_a_wrong_edition_are_withheld(n_wrong, withheld):
    """Most blocks fail under 2.7 and every one of them walks under 0.23: the edition is wrong, and a block
    that walks under 2.7 anyway would give wrong values, so it is withheld and reported (from 10 failed
    blocks on; fewer prove too little, and the block is decoded, the likely edition still named)."""
    good = adsb_blocks(1, "2.7")
    data = adsb_blocks(n_wrong, "0.23") + good
    rec = decode_bytes(data, editions={21: "2.7"})
    assert rec.edition_fits == {21: ("0.23",)}
    assert len(rec.errors) == n_wrong + withheld
    assert len(rec.frames[21]) == (0 if withheld else 1)
    last = rec.errors.iloc[-1]
    assert (last.offset == len(data) - len(good) and "withheld" in last.reason) == withheld
    assert accounted(rec) == len(data)


def test_one_block_of_another_category_beside_one_plot():
    """A lone block of a category not decoded makes framing check the chain carefully; comparing what
    each framing walks read the 0/1 walk flags as indices (IndexError on these two blocks)."""
    plot = fspec(1, 2) + bytes([7, 1]) + (128).to_bytes(3, "big")  # I048/010 and I048/140 (1 s)
    rec = decode_bytes(block(48, plot) + block(34, bytes([0x80, 25, 201])))
    assert len(rec.frames[48]) == 1 and rec.frames[48]["time_of_day"].iloc[0] == 1.0
    assert rec.errors.empty and rec.ignored_blocks == {34: 1}


def test_other_category_is_stepped_over_and_accounted():
    data, starts = good_stream(3)
    alien = block(62, bytes([0x80, 1, 2]))  # 62 06 00 80 01 02: six bytes
    rec = decode_bytes(data[:starts[1]] + alien + data[starts[1]:])
    assert len(rec.frames[48]) == 9 and rec.errors.empty
    assert rec.ignored_blocks == {62: 1} and rec.ignored_category_bytes == {62: 6}
    assert rec.ignored.to_dict("records") == [{"category": 62, "blocks": 1, "bytes": 6}]
    assert accounted(rec) == len(data) + 6


def test_garbage_between_blocks_is_one_entry():
    data, starts = good_stream(4)
    junk = bytes([0x00, 0xFF, 0x13, 0x37, 0x00])
    rec = decode_bytes(data[:starts[2]] + junk + data[starts[2]:])
    assert len(rec.frames[48]) == 12
    assert list(rec.errors.offset) == [starts[2]] and list(rec.errors.length) == [len(junk)]


def test_not_asterix_at_all():
    data = bytes(range(256)) * 4
    rec = decode_bytes(data)
    assert sum(len(f) for f in rec.frames.values()) == 0
    assert accounted(rec) == len(data)


def test_strict_raises_with_file_offset_reason():
    data, starts = good_stream()
    with pytest.raises(asterix.DecodeError) as exc:
        decode_bytes(data[: starts[-1] + 7], strict=True)
    assert exc.value.offset == starts[-1] and "<test>" in str(exc.value)
    assert f"offset {starts[-1]}" in str(exc.value)


def test_block_is_all_or_nothing():
    # second record of the block has an FRN the edition does not define (FRN 29+ does not exist)
    bad_record = fspec(1, 35) + bytes([7, 1, 0])
    rec = decode_bytes(block(48, rec048(1), bad_record) + block(48, rec048(2)))
    assert list(rec.frames[48].track_number) == [2]
    assert "FRN" in rec.errors.reason.iloc[0]


@pytest.mark.fuzz
@settings(max_examples=examples(300), deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.binary(max_size=600))
def test_random_bytes_never_crash_and_are_accounted(data):
    rec = decode_bytes(data)
    assert accounted(rec) == len(data)


@pytest.mark.fuzz
@settings(max_examples=examples(300), deadline=None)
@given(st.data())
def test_mutated_stream_accounted_and_far_blocks_survive(data):
    stream, starts = good_stream(8, 3)
    buf = bytearray(stream)
    pos, action = mutate(buf, data)
    rec = decode_bytes(bytes(buf))
    assert accounted(rec) == len(buf)
    hit = max(i for i, s in enumerate(starts) if s <= pos)
    tracks = set(rec.frames[48].track_number) if 48 in rec.frames else set()
    # Damage inside a block header can make the previous block's end ambiguous (e.g. its last byte
    # 0x15 followed by the next LEN reads as a CAT021 header): framing does not walk records, so
    # that one block may be lost too. Every block before it must decode.
    first_lost = hit - 1 if pos - starts[hit] < 3 else hit
    before = {t for b in range(max(first_lost, 0)) for t in range(b * 3 + 1, b * 3 + 4)}
    assert before <= tracks  # every block before the damage decodes
    if action != "truncate":
        after = {t for b in range(hit + 2, 8) for t in range(b * 3 + 1, b * 3 + 4)}
        assert after <= tracks  # and every block from the second after it


def test_unreadable_input_message(tmp_path):
    with pytest.raises(asterix.UnreadableInput) as exc:
        asterix.read(tmp_path / "missing.ast")
    assert "missing.ast" in str(exc.value)


def test_empty_file(tmp_path):
    p = tmp_path / "empty.ast"
    p.write_bytes(b"")
    rec = asterix.read(p)
    assert rec.frames == {} and rec.errors.empty


def test_record_values_independent_of_block_grouping():
    recs = [rec048(i) for i in range(1, 10)]
    a = decode_bytes(b"".join(block(48, r) for r in recs)).frames[48]
    b = decode_bytes(block(48, *recs)).frames[48]
    assert np.array_equal(a.track_number.to_numpy(), b.track_number.to_numpy())
    assert list(a.block) == list(range(9)) and set(b.block) == {0}


def _real_streams() -> list[tuple[str, bytes]]:
    """Real recordings: the conformance records (when ../shared is there) and the fixtures' first blocks."""
    from pathlib import Path

    from asterix_bytes import SHARED

    fixtures = Path(__file__).resolve().parents[2] / "fixtures"
    out = [(p.name, p.read_bytes()[:3000]) for p in (fixtures / "radar.ast", fixtures / "adsb.ast")]
    conf = SHARED / "conformance"
    if conf.is_dir():
        out += [(p.name, p.read_bytes()) for p in sorted(conf.iterdir())
                if not p.name.endswith((".json", ".md"))]
    return out


REAL = _real_streams()


@pytest.mark.fuzz
@settings(max_examples=examples(200), deadline=None)
@given(st.sampled_from(REAL), st.data())
def test_bit_flipped_and_truncated_real_blocks(named, data):
    _, stream = named
    buf = bytearray(stream)
    for _ in range(data.draw(st.integers(1, 3))):
        pos = data.draw(st.integers(0, len(buf) - 1))
        buf[pos] ^= 1 << data.draw(st.integers(0, 7))
    cut = data.draw(st.integers(0, len(buf)))
    rec = decode_bytes(bytes(buf[:cut]), editions={21: data.draw(st.sampled_from(["2.1", "0.26", "auto"]))})
    assert accounted(rec) == cut
    for frame in rec.frames.values():  # whatever decodes comes with a place in the file
        assert frame["offset"].between(0, cut - 1).all()


@pytest.mark.parametrize("bad", [1, True, None, 3.5, b"\x30\x00\x03"])
def test_a_path_that_is_no_path_is_a_type_error_and_closes_nothing(bad, tmp_path):
    """open() takes an int as a file descriptor: read(1) decoded nothing and closed the caller's stdout
    (read(fd) read the file and closed the caller's descriptor); bytes were taken for a path ('embedded
    null byte'). Each is a TypeError naming the argument; a descriptor stays open."""
    import os

    with pytest.raises(TypeError, match=r"^path: a file path \(str or os\.PathLike\), not "):
        asterix.read(bad)
    path = tmp_path / "r.ast"
    path.write_bytes(block(48, rec048(1)))
    fd = os.open(path, os.O_RDONLY)
    try:
        with pytest.raises(TypeError, match="not int"):
            asterix.read(fd)
        os.fstat(fd)  # still open: raises OSError (EBADF) if read closed it
    finally:
        os.close(fd)
    assert len(asterix.read(path).frames[48]) == 1
