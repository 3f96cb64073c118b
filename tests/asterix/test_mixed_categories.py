"""Mixed-category raw streams (several radars; CAT001/002/008/019/020/034/048 interleaved, hand-built):
every block framed by its LEN, other categories accounted per category, damage localised."""

from __future__ import annotations

import pandas as pd
import pytest
from asterix_bytes import block, decode_bytes, fspec, mutate
from budget import examples
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import msdc.asterix as asterix

RADARS = [(20, 129), (20, 130), (21, 7)]  # SAC/SIC of three radars


def rec048(sac: int, sic: int, i: int) -> bytes:
    """CAT048 record: FSPEC (2), I048/010 (2), I048/140 ToD = 128*i/128 = i s (3), I048/161 track i (2)."""
    return fspec(1, 2, 11) + bytes([sac, sic]) + (128 * i).to_bytes(3, "big") + (i & 0xFFF).to_bytes(2, "big")


def rec034(sac: int, sic: int, i: int) -> bytes:
    """CAT034 sector crossing: FSPEC F0 (FRNs 1-4), I034/010, /000 = 2, /030 ToD, /020 sector i."""
    return bytes([0xF0, sac, sic, 2]) + (128 * i).to_bytes(3, "big") + bytes([i & 0xFF])


# Blocks of categories msdc does not decode: FSPEC-led bodies with arbitrary item bytes.
OTHER = {1: bytes([0xC0, 20, 129, 0x22]), 2: bytes([0xE0, 20, 129, 1, 0, 0x10, 0x00]),
         8: bytes([0x80, 20, 129]), 19: bytes([0xE0, 0, 50, 1, 0x01, 0x02, 0x03]),
         20: bytes([0xC0, 0, 50, 0x41, 0x00])}


def mixed_stream(rounds: int = 3) -> tuple[bytes, list[tuple[int, int, list[int]]]]:
    """Raw stream and its blocks: (start offset, category, CAT048 track numbers in it)."""
    out = b""
    blocks: list[tuple[int, int, list[int]]] = []
    track = 1

    def add(cat: int, body: bytes, tracks: list[int]) -> None:
        nonlocal out
        blocks.append((len(out), cat, tracks))
        out += block(cat, body)

    for r in range(rounds):
        for k, (sac, sic) in enumerate(RADARS):
            tracks = [track, track + 1]
            add(48, rec048(sac, sic, tracks[0]) + rec048(sac, sic, tracks[1]), tracks)
            track += 2
            # two blocks of other categories in a row (the case that derailed the old framer)
            add(1, OTHER[1], [])
            add(2, OTHER[2], [])
            add(34, rec034(sac, sic, 3 * r + k), [])
        for cat in (8, 19, 20):
            add(cat, OTHER[cat], [])
    return out, blocks


def accounted(rec: asterix.Recording) -> int:
    return rec.decoded_bytes + int(rec.errors["length"].sum()) + rec.container_bytes + rec.ignored_bytes


def blocks_of(rec: asterix.Recording, cat: int) -> int:
    """Blocks of a category decoded or stepped over (CAT034 may be either, depending on the build)."""
    decoded = rec.frames[cat]["block"].nunique() if cat in rec.frames else 0
    return decoded + rec.ignored_blocks.get(cat, 0)


def test_mixed_stream_every_block_framed_and_accounted():
    data, blocks = mixed_stream()
    rec = decode_bytes(data)
    assert rec.errors.empty, rec.errors
    f = rec.frames[48]
    # 3 rounds x 3 radars x 2 records, in file order, each radar's SAC/SIC kept
    assert list(f.track_number) == list(range(1, 19))
    assert list(zip(f.sac, f.sic, strict=True))[:6] == [(20, 129)] * 2 + [(20, 130)] * 2 + [(21, 7)] * 2
    for cat in (1, 2, 8, 19, 20, 34):
        assert blocks_of(rec, cat) == sum(1 for _, c, _ in blocks if c == cat), cat
    # bytes per category: block = 3 header bytes + body
    assert rec.ignored_category_bytes[1] == 9 * (3 + 4) and rec.ignored_category_bytes[2] == 9 * (3 + 7)
    assert rec.ignored_category_bytes[8] == 3 * 6 and rec.ignored_category_bytes[19] == 3 * 10
    # CAT048 blocks: 3 + 2 records x 9 bytes; CAT034 blocks (3 + 8) count as decoded once msdc decodes them,
    # and so do the CAT020 ones (3 + 5: FSPEC C0, I020/010, I020/020 of two octets, a record that walks)
    assert rec.ignored_category_bytes.get(20, 0) + len(rec.frames.get(20, [])) * 8 == 3 * 8
    assert rec.decoded_bytes == (9 * (3 + 2 * 9) + (9 * (3 + 8) if 34 in rec.frames else 0)
                                 + (3 * 8 if 20 in rec.frames else 0))
    assert accounted(rec) == len(data)


def test_categories_not_selected_are_accounted_like_other_categories():
    data, _ = mixed_stream(1)
    rec = decode_bytes(data, categories=[21])
    assert rec.frames == {} and rec.errors.empty
    assert rec.ignored_blocks[48] == 3 and rec.ignored_category_bytes[48] == 3 * 21
    assert accounted(rec) == len(data)


def test_garbage_between_other_category_blocks():
    data, blocks = mixed_stream(2)
    at = blocks[2][0]  # between the CAT001 and the CAT002 block of radar 1
    junk = bytes([0x00, 0xFF, 0x13, 0x37, 0x00])  # category 0 cannot start a block
    rec = decode_bytes(data[:at] + junk + data[at:])
    assert list(rec.frames[48].track_number) == list(range(1, 13))
    assert rec.errors[["offset", "length"]].values.tolist() == [[at, 5]]
    assert rec.errors["category"].isna().all()  # garbage names no category (its first byte is 0x00)
    assert accounted(rec) == len(data) + 5


def test_text_is_garbage_of_no_category():
    text = b"# msdc\n\nNot a recording: a README.\n" * 20  # '#' is 35, a category byte if read as one
    rec = decode_bytes(text)
    assert not rec.frames or all(f.empty for f in rec.frames.values())
    assert rec.errors["length"].sum() == len(text) and rec.errors["category"].isna().all()
    assert set(rec.errors["reason"]) == {"bytes that do not start a plausible ASTERIX data block"}


def test_cut_inside_an_other_category_block_keeps_the_decoded_ones():
    data, blocks = mixed_stream(2)
    cut = blocks[-2][0] + 4  # inside the CAT019 block, 1 byte of its body
    rec = decode_bytes(data[:cut])
    assert list(rec.frames[48].track_number) == list(range(1, 13))
    assert rec.errors[["offset", "length"]].values.tolist() == [[blocks[-2][0], 4]]
    assert accounted(rec) == cut


@pytest.mark.fuzz
@settings(max_examples=examples(300), deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.data())
def test_mutated_mixed_stream_accounted_and_far_blocks_survive(data):
    stream, blocks = mixed_stream(2)
    buf = bytearray(stream)
    pos, action = mutate(buf, data)
    rec = decode_bytes(bytes(buf))
    assert accounted(rec) == len(buf)
    starts = [s for s, _, _ in blocks]
    hit = max(i for i, s in enumerate(starts) if s <= pos)
    tracks = set(rec.frames[48].track_number) if 48 in rec.frames else set()
    # damage in a header can make the previous block's end ambiguous: that one may go too
    first_lost = hit - 1 if pos - starts[hit] < 3 else hit
    before = {t for _, _, ts in blocks[:max(first_lost, 0)] for t in ts}
    assert before <= tracks
    if action != "truncate":
        after = {t for _, _, ts in blocks[hit + 2:] for t in ts}
        assert after <= tracks
    for frame in rec.frames.values():
        assert frame["offset"].between(0, len(buf) - 1).all()


def test_stats_show_other_categories(tmp_path):
    from msdc.pipeline.quality.inventory import format_stats, stats_tables

    data, _ = mixed_stream(1)
    path = tmp_path / "mixed.ast"
    path.write_bytes(data)
    rec = asterix.read(path)
    tables = stats_tables(rec.frames, rec.errors, rec.ignored)
    other = tables["other"].set_index("category")
    assert other.loc[1, "blocks"] == 3 and other.loc[1, "bytes"] == 21
    text = format_stats(tables)
    assert "not decoded" in text and pd.notna(other.loc[19, "bytes"])
