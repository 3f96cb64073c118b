"""Damaged CAT010/CAT020 streams keep the decoder's byte properties: no crash, every byte accounted for
exactly once, and damage stays local (blocks before it and from the second after it decode)."""

from __future__ import annotations

import pytest
from asterix_bytes import SHARED, block, decode_bytes, mutate
from budget import examples
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import msdc.asterix as asterix

N_BLOCKS = 8


def rec010(i: int) -> bytes:
    """CAT010 MLAT report: FSPEC F3 20 (FRNs 1 2 3 4 7 | 10), I010/010 0/107, /000 1, /020 0x2C (TYP 1),
    /140 i s, /042 x = i m, y = -i m, /161 track i."""
    return (bytes.fromhex("F320") + bytes([0, 107, 1, 0x2C]) + (128 * i).to_bytes(3, "big")
            + i.to_bytes(2, "big", signed=True) + (-i).to_bytes(2, "big", signed=True) + i.to_bytes(2, "big"))


def rec020(i: int) -> bytes:
    """CAT020 report: FSPEC E4 (FRNs 1 2 3 6), I020/010 25/10, /020 0x40 (one octet), /140 i s, /161 i."""
    return bytes([0xE4, 25, 10, 0x40]) + (128 * i).to_bytes(3, "big") + i.to_bytes(2, "big")


def stream() -> tuple[bytes, list[int]]:
    """Blocks of three records, CAT010 and CAT020 in turn (tracks 1-3 in block 0, ...), and block starts."""
    out, starts = b"", []
    for b in range(N_BLOCKS):
        make, cat = (rec010, 10) if b % 2 == 0 else (rec020, 20)
        starts.append(len(out))
        out += block(cat, *(make(3 * b + k) for k in (1, 2, 3)))
    return out, starts


def accounted(rec: asterix.Recording) -> int:
    return rec.decoded_bytes + int(rec.errors["length"].sum()) + rec.container_bytes + rec.ignored_bytes


def tracks(rec: asterix.Recording) -> set[int]:
    return {int(t) for cat in (10, 20) if cat in rec.frames for t in rec.frames[cat].track_number.dropna()}


def test_the_clean_stream_decodes_whole():
    data, _ = stream()
    rec = decode_bytes(data)
    assert rec.errors.empty and accounted(rec) == rec.decoded_bytes == len(data)
    assert tracks(rec) == set(range(1, 3 * N_BLOCKS + 1))
    f10 = rec.frames[10]
    assert f10.x_m.tolist()[:3] == [1.0, 2.0, 3.0] and f10.y_m.tolist()[:3] == [-1.0, -2.0, -3.0]


@pytest.mark.fuzz
@settings(max_examples=examples(300), deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.data())
def test_mutated_stream_accounted_and_far_blocks_survive(data):
    clean, starts = stream()
    buf = bytearray(clean)
    pos, action = mutate(buf, data)
    rec = decode_bytes(bytes(buf), editions={20: data.draw(st.sampled_from(["1.9", "1.10", "1.11", "auto"]))})
    assert accounted(rec) == len(buf)
    hit = max(i for i, s in enumerate(starts) if s <= pos)
    got = tracks(rec)
    first_lost = hit - 1 if pos - starts[hit] < 3 else hit  # a damaged header can take the block before
    assert {t for b in range(max(first_lost, 0)) for t in range(3 * b + 1, 3 * b + 4)} <= got
    if action != "truncate":
        assert {t for b in range(hit + 2, N_BLOCKS) for t in range(3 * b + 1, 3 * b + 4)} <= got


REAL = SHARED / "real"
REAL_HEADS = [(p.name, p.read_bytes()[:4000]) for p in sorted(REAL.glob("*lebl*.ast"))
              if p.name.startswith(("mlat", "smr"))] if REAL.is_dir() else []


@pytest.mark.fuzz
@pytest.mark.skipif(not REAL_HEADS, reason=f"{REAL} not present: no real CAT010 bytes to damage")
@settings(max_examples=examples(100), deadline=None)
@given(st.data())
def test_bit_flipped_and_truncated_real_cat010(data):
    """The first 4000 bytes of the real MLAT and surface radar files, bits flipped and cut: never a crash,
    every byte accounted, every decoded record placed inside the data."""
    _, head = data.draw(st.sampled_from(REAL_HEADS))
    buf = bytearray(head)
    for _ in range(data.draw(st.integers(1, 3))):
        at = data.draw(st.integers(0, len(buf) - 1))
        buf[at] ^= 1 << data.draw(st.integers(0, 7))
    cut = data.draw(st.integers(0, len(buf)))
    rec = decode_bytes(bytes(buf[:cut]))
    assert accounted(rec) == cut
    for frame in rec.frames.values():
        assert frame["offset"].between(0, cut - 1).all()
