"""Framing a window at a time (asterix.framing, kernel.frame_window) gives what one pass over the whole
stream gives, whatever the windows; the shortcuts of planning (a kept framing replayed, editions framing
alike framed once) give what framing each time gives."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from reader_fuzz import clean_blocks

from msdc.asterix import kernel
from msdc.asterix.containers import read_segments
from msdc.asterix.framing import Framer, Replay, Sample, alike_framings, survey
from msdc.asterix.reader import _editions_oldest_first, tables_for

FIXTURES = Path(__file__).resolve().parents[2] / "fixtures"


def damaged_stream(seed: int) -> np.ndarray:
    """The first 30 kB of each fixture end to end, with random bytes inserted, bytes deleted and a bit
    flipped at seeded places, then 5 kB of random bytes."""
    rng = np.random.default_rng(seed)
    data = b""
    for name in ("radar.ast", "adsb.ast"):  # whole blocks only
        whole = (FIXTURES / name).read_bytes()
        starts, _ = clean_blocks(whole)
        data += whole[:int(starts[np.searchsorted(starts, 30_000)])]
    buf = bytearray(data)
    at = np.sort(rng.integers(0, len(buf) - 400, 3))[::-1].tolist()  # from the end: offsets stay valid
    buf[at[0]:at[0]] = rng.integers(0, 256, int(rng.integers(1, 300)), np.uint8).tobytes()
    del buf[at[1]:at[1] + int(rng.integers(1, 300))]
    buf[at[2]] ^= 1 << int(rng.integers(8))
    return np.frombuffer(bytes(buf) + rng.integers(0, 256, 5_000, np.uint8).tobytes(), np.uint8)


CAREFUL = np.array([kernel.MODE_CAREFUL], np.int8)


@pytest.mark.parametrize("seed", range(4))
def test_windows_of_any_size_frame_as_one_pass(seed: int) -> None:
    buf = damaged_stream(seed)
    seg = read_segments(buf, "raw")
    tables = tables_for({48: None, 21: None})
    whole = kernel.frame_blocks(buf, seg.start, seg.stop, False, True, tables)
    assert len(whole[4])  # the damage broke the chain somewhere: resynchronisation was exercised
    rng = np.random.default_rng(seed)
    framer = Framer(buf, seg, CAREFUL, tables)
    parts = []
    while not framer.done:
        parts.append(framer.window(framer.position + int(rng.integers(1, 4_000))))
    assert len(parts) > 10
    for i in range(8):
        assert np.array_equal(np.concatenate([p[i] for p in parts]), whole[i])
    replay = Replay(buf, seg, whole)  # a kept framing handed out in other windows: the same again
    parts = []
    while not replay.done:
        parts.append(replay.window(replay.position + int(rng.integers(1, 4_000))))
    for i in range(8):
        assert np.array_equal(np.concatenate([p[i] for p in parts]), whole[i])


@pytest.mark.parametrize("seed", range(3))
def test_editions_framing_alike_are_framed_once_and_counted_the_same(seed: int) -> None:
    buf = damaged_stream(seed)
    seg = read_segments(buf, "raw")
    eds = _editions_oldest_first(21)
    tables = {ed: tables_for({48: None, 21: ed}) for ed in eds}
    grouped = alike_framings(buf, seg, CAREFUL, tables, 21)
    for ed in eds:
        each = survey(buf, seg, CAREFUL, tables[ed])
        assert (grouped[ed].error_bytes, grouped[ed].errors) == (each.error_bytes, each.errors), ed
        assert np.array_equal(grouped[ed].blocks, each.blocks), ed
    assert len({id(s) for s in grouped.values()}) < len(eds)  # some editions shared a framing


def test_sample_keeps_every_kth_block_whatever_the_windows() -> None:
    starts = np.arange(100_000, dtype=np.int64) * 10
    one, many = Sample(), Sample()
    one.add(starts, starts + 1)
    cuts = [0, 7, 5_000, 5_001, 60_000, 100_000]
    for a, b in zip(cuts[:-1], cuts[1:], strict=True):
        many.add(starts[a:b], starts[a:b] + 1)
    for smp in (one, many):
        kept, lens = smp.arrays()
        assert smp.k == 4 and np.array_equal(kept, starts[::4]) and np.array_equal(lens, kept + 1)


def test_segments_of_every_mode_in_one_framing_frame_as_built() -> None:
    """Four segments: container payloads (one tiling into blocks, one that does not), a raw stream with
    random bytes between two of its blocks (framed carefully) and a raw chain that holds. In windows of any
    size, framing gives the blocks each segment was built of and the errors put in, as built: the careful
    segment's search and the plain segments' shortcut (kernel.frame_plain) share one framing."""
    whole = (FIXTURES / "radar.ast").read_bytes()
    starts, lens = clean_blocks(whole)
    blocks = [whole[a:a + n] for a, n in zip(starts[:12].tolist(), lens[:12].tolist(), strict=True)]
    junk = np.random.default_rng(5).integers(0, 256, 300, np.uint8).tobytes()
    payloads = [b"".join(blocks[0:3]), b"".join(blocks[3:5]) + b"\x30\x00",
                b"".join(blocks[5:8]) + junk + b"".join(blocks[8:10]), b"".join(blocks[10:12])]
    modes = np.array([kernel.MODE_EXACT, kernel.MODE_EXACT, kernel.MODE_CAREFUL, kernel.MODE_CHAIN], np.int8)
    buf = np.frombuffer(b"".join(payloads), np.uint8)
    stop = np.cumsum([len(p) for p in payloads])
    seg = read_segments(buf, "raw")
    seg.start, seg.stop = np.concatenate([[0], stop[:-1]]).astype(np.int64), stop.astype(np.int64)
    seg.capture_day, seg.capture_tod = np.full(4, -1), np.full(4, np.nan)
    # built: each block's offset and segment, the undivided payload and the random bytes as errors
    offsets, segments = [], []
    for s, (first, last) in enumerate([(0, 3), (3, 5), (5, 10), (10, 12)]):
        at = int(seg.start[s])
        for b in range(first, last):
            if s == 1:  # skipped whole
                continue
            offsets.append(at)
            segments.append(s)
            at += len(blocks[b]) + (len(junk) if b == 7 else 0)
    junk_at = int(seg.start[2]) + sum(len(b) for b in blocks[5:8])
    errors = [(int(seg.start[1]), len(payloads[1]), kernel.E_NO_FRAME),
              (junk_at, len(junk), kernel.E_GARBAGE)]
    tables = tables_for({48: None})
    rng = np.random.default_rng(1)
    for largest in (1, 500, 5_000, 100_000):
        framer = Framer(buf, seg, modes, tables)
        parts = []
        while not framer.done:
            parts.append(framer.window(framer.position + int(rng.integers(1, largest + 1))))
        got = [np.concatenate([p[i] for p in parts]) for i in range(8)]
        assert got[0].tolist() == offsets and got[3].tolist() == segments, largest
        assert list(zip(got[4].tolist(), got[5].tolist(), got[7].tolist(), strict=True)) == errors, largest
