"""Large blocks of a category not decoded (a tracker's CAT062 system tracks, 25 records a block, as a centre
records them beside its radars) are stepped over by their LEN when the chain after them holds: the bytes
inside them that read, by chance, as a short block of a decoded category that walks (CAT010, CAT020, CAT048
records are a few bytes) are no evidence against a block whose next block proves its LEN. Before, such a
chance reading broke the chain there and the framer resynchronised inside the track messages, decoding
their bytes as CAT010, CAT020 and CAT048 records. The streams are built with msdc's encoder; what is
expected follows from how they are built (the blocks and records written), not from the decoder."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from live_bytes import raw_blocks

import msdc.asterix as asterix
from msdc.asterix.encode import encode_frame

RECORDS_PER_BLOCK = 25


def _tracks(n: int, rng: np.random.Generator) -> pd.DataFrame:
    """System track messages as the decode benchmark makes them (the items a tracker sends on nearly every
    update)."""
    return _bench_decode().cat062_frame(n, rng)


def _plots(n: int, rng: np.random.Generator) -> pd.DataFrame:
    return pd.DataFrame({"sac": 20, "sic": 1, "time_of_day": np.sort(rng.uniform(0, 86000, n)).round(2),
                         "rho_nm": rng.uniform(1, 200, n).round(2),
                         "theta_deg": rng.uniform(0, 359, n).round(2)})


def _read(path: Path, **kw) -> asterix.Recording:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return asterix.read(path, **kw)


def test_a_trackers_blocks_beside_radar_plots_are_stepped_over(tmp_path):
    rng = np.random.default_rng(62)
    tracks = raw_blocks(encode_frame(62, _tracks(100 * RECORDS_PER_BLOCK, rng),
                                     records_per_block=RECORDS_PER_BLOCK))
    plots = raw_blocks(encode_frame(48, _plots(100 * 4, rng), records_per_block=4))
    assert len(tracks) == len(plots) == 100
    path = tmp_path / "centre.ast"
    path.write_bytes(b"".join(p + t for p, t in zip(plots, tracks, strict=True)))
    rec = _read(path)  # the default categories: CAT048 among them, CAT062 not
    assert set(rec.frames) == {48}, f"records decoded out of the track messages: {sorted(rec.frames)}"
    assert len(rec.frames[48]) == 400
    assert rec.errors.empty, rec.errors.head().to_string()
    assert rec.ignored_blocks == {62: 100}
    assert rec.ignored_bytes == sum(len(t) for t in tracks)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        parts = list(asterix.iter_read(path, chunk=20_000))  # framed a chunk at a time, the state carried
    assert len(parts) > 5
    assert sum(len(p.frames.get(48, ())) for p in parts) == 400
    assert all(p.errors.empty and set(p.frames) <= {48} for p in parts)


def test_a_recording_of_a_trackers_blocks_alone_decodes_nothing_and_loses_nothing(tmp_path):
    rng = np.random.default_rng(7)
    data = encode_frame(62, _tracks(200 * RECORDS_PER_BLOCK, rng), records_per_block=RECORDS_PER_BLOCK)
    path = tmp_path / "tracks.ast"
    path.write_bytes(data)
    rec = _read(path)
    assert not any(len(f) for f in rec.frames.values()), sorted(rec.frames)
    assert rec.errors.empty, rec.errors.head().to_string()
    assert rec.ignored_blocks == {62: 200}
    assert rec.ignored_bytes == len(data)
    assert len(_read(path, categories=[62]).frames[62]) == 200 * RECORDS_PER_BLOCK


def _bench_decode():
    """benchmarks/decode.py, whose recordings of each category (msdc's encoder) the pairs below reuse."""
    import importlib.util

    path = Path(__file__).resolve().parents[2] / "benchmarks" / "decode.py"
    spec = importlib.util.spec_from_file_location("msdc_bench_decode", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _records(stream: int, category: int, blocks: list[bytes]) -> int:
    """Records of ``category`` in a benchmark stream's blocks, by how it is built: 25 a block, but the
    CAT001 stream's CAT002 sector messages, one a block."""
    per = 1 if (stream, category) == (1, 2) else RECORDS_PER_BLOCK
    return per * sum(1 for blk in blocks if blk[0] == category)


def test_every_category_beside_every_other_decodes_as_alone(tmp_path):
    """Blocks of two categories interleaved one for one (40 blocks of 25 records each: the benchmark's
    recordings of CAT048, CAT021, CAT010, CAT020, CAT062, CAT063, CAT002, and CAT001 with its CAT002
    sector messages), one of them decoded: its records are those of the two streams read apart, with no
    error and no record of another category. Before, 9 of the 56 pairs reported errors, 3 of them with
    records made of the other category's bytes (CAT021 beside CAT001: 1,005 for 1,000)."""
    bench = _bench_decode()
    cats = (48, 21, 10, 20, 62, 63, 2, 1)
    streams = {}
    for c in cats:
        path = tmp_path / f"c{c}.ast"
        bench.build(path, c, 1000)
        streams[c] = raw_blocks(path.read_bytes())[:40]
    failures = []
    for a in cats:
        for b in cats:
            if a == b:
                continue
            expected = _records(a, a, streams[a]) + _records(b, a, streams[b])
            mixed = tmp_path / "mixed.ast"
            mixed.write_bytes(b"".join(x + y for x, y in zip(streams[a], streams[b], strict=True)))
            rec = _read(mixed, categories=[a])
            got = len(rec.frames.get(a, ()))
            if got != expected or not rec.errors.empty or set(rec.frames) - {a}:
                failures.append(f"CAT{a:03d} beside CAT{b:03d}: {got} records for {expected}, "
                                f"{len(rec.errors)} errors")
    assert not failures, failures


def _chance_cat010(sources: list[tuple[int, int]]) -> bytes:
    """Bytes that read as a CAT010 block walking exactly: one record per source, each I010/010 alone (FSPEC
    0x80, then SAC and SIC: FRN 1 of the I010 layout)."""
    body = b"".join(bytes([0x80, sac, sic]) for sac, sic in sources)
    return bytes([10]) + (3 + len(body)).to_bytes(2, "big") + body


def _with_special_purpose(block: bytes, sp_data: bytes) -> bytes:
    """A CAT062 block with one more record at its end: I062/010 (SAC 9, SIC 9) and I062/SP (FRN 35: FSPEC
    0x81 0x01 0x01 0x01 0x02, then a length byte counting itself), its data ``sp_data``; LEN made whole."""
    record = bytes([0x81, 1, 1, 1, 0x02, 9, 9, 1 + len(sp_data)]) + sp_data
    body = block[3:] + record
    return bytes([62]) + (3 + len(body)).to_bytes(2, "big") + body


def test_a_trackers_block_ending_in_bytes_that_read_as_a_short_walking_block_is_stepped_over(tmp_path):
    """A track message whose last bytes read as a CAT010 block that walks exactly and ends where the next
    real block starts (seven records of data sources met nowhere), the 'block' behind a CAT031 header: a
    chance reading that the decode benchmark's 40,000 tracker blocks met once, decoding 7 CAT010 'reports'
    and losing the block with an error. One short walking block names a data source already met before it
    counts against a LEN its next blocks prove; the tracker's blocks are stepped over."""
    rng = np.random.default_rng(5)
    blocks = raw_blocks(encode_frame(62, _tracks(8 * RECORDS_PER_BLOCK, rng),
                                     records_per_block=RECORDS_PER_BLOCK))
    chance = _chance_cat010([(54, 212), (117, 0), (72, 1), (3, 100), (0, 100), (88, 7), (201, 33)])
    blocks[4] = _with_special_purpose(blocks[4], bytes([31, 0, 40]) + bytes(37) + chance)
    path = tmp_path / "tracks.ast"
    path.write_bytes(b"".join(blocks))
    rec = _read(path)  # the default categories: CAT010 among them, CAT062 not
    assert not any(len(f) for f in rec.frames.values()), {c: len(f) for c, f in rec.frames.items()}
    assert rec.errors.empty, rec.errors.head().to_string()
    assert rec.ignored_blocks == {62: 8}
    tracks = _read(path, categories=[62])  # the block with the extra record is a whole CAT062 block
    assert tracks.errors.empty and len(tracks.frames[62]) == 8 * RECORDS_PER_BLOCK + 1


def test_a_len_swallowing_one_block_of_a_met_source_still_yields_it(tmp_path):
    """The other side of the rule above: a block of a category not decoded, met before (CAT034), whose LEN
    is damaged to run exactly over the next real block, a CAT048 block of the radar met before: that block
    walks, names a met source and lands on the next real block, so it decodes and the damaged block is
    reported. Plots: I048/010 and I048/040 (FSPEC 0x90), RHO in 1/256 NM, THETA in 360/2^16 degrees."""
    def plots(k: int) -> bytes:
        body = b"".join(bytes([0x90, 20, 1, 10, k, 0x40, k]) for _ in range(2))
        return bytes([48, 0, 3 + len(body)]) + body

    north = bytes([34, 0, 7, 0xC0, 20, 1, 1])  # I034/010 SAC 20 SIC 1, I034/000 message type 1 (north marker)
    swallowed = plots(7)
    damaged = north[:1] + (len(north) + len(swallowed)).to_bytes(2, "big") + north[3:]
    pieces = [north, plots(1), north, plots(2), damaged, swallowed, plots(3), north, plots(4), plots(5)]
    path = tmp_path / "radar.ast"
    path.write_bytes(b"".join(pieces))
    rec = _read(path, categories=[48])
    got = rec.frames[48].set_index("offset")
    at = sum(len(p) for p in pieces[:5])
    assert [at + 3, at + 10] == [o for o in got.index if at <= o < at + len(swallowed)]
    assert np.allclose(got.loc[[at + 3, at + 10], "rho_nm"], (10 * 256 + 7) / 256)
    assert len(rec.frames[48]) == 6 * 2
    assert rec.errors["offset"].tolist() == [sum(len(p) for p in pieces[:4])]


@pytest.mark.parametrize("damage", ["zeros before the first block", "zeros after the 30th block",
                                    "the last block cut short"])
def test_streams_of_categories_not_decoded_alone_are_stepped_over_whole(tmp_path, damage):
    """Recordings holding only categories the default read leaves out, interleaved block for block (a CAT001
    radar's plot blocks between its CAT002 sector messages, as the decode benchmark builds it; a tracker's
    CAT062 tracks with CAT063 sensor status, or with CAT002; CAT063 with the CAT001 radar: three categories),
    with damage that makes them framed carefully: every block is stepped over, no record is decoded, and the
    damage is the one error. Before, the first block of a category not met yet and followed by a block of
    another such category was taken for damage, and with no decoded block to anchor a chain framing never
    resumed: the benchmark's CAT001 recording read with the default categories gave 24 errors and 83 CAT010,
    CAT020 and CAT048 'records' made of plot bytes. Damage after a block: the block before it has no next
    block to prove its LEN, and the bytes of its records or of the block after the damage read as a short
    walking CAT010 or CAT020 block now and then, which framing resumed at."""
    bench = _bench_decode()
    streams = {}
    for c in (1, 62, 63, 2):
        path = tmp_path / f"c{c}.ast"
        bench.build(path, c, 1000)
        streams[c] = raw_blocks(path.read_bytes())[:40]
    failures = []
    for pieces in ([streams[1]], [streams[62], streams[63]], [streams[62], streams[2]],
                   [streams[63], streams[1]]):
        blocks = [blk for pair in zip(*pieces, strict=True) for blk in pair]
        whole = b"".join(blocks)
        if damage == "zeros before the first block":
            data, error = bytes(5) + whole, [0, 5]
            kept = blocks
        elif damage == "zeros after the 30th block":
            at = sum(len(blk) for blk in blocks[:30])
            data, error = whole[:at] + bytes(5) + whole[at:], [at, 5]
            kept = blocks
        else:
            data, error = whole[:-7], [len(whole) - len(blocks[-1]), len(blocks[-1]) - 7]
            kept = blocks[:-1]
        expected: dict[int, int] = {}
        for blk in kept:
            expected[blk[0]] = expected.get(blk[0], 0) + 1
        path = tmp_path / "mixed.ast"
        path.write_bytes(data)
        rec = _read(path)
        decoded = {c: len(f) for c, f in rec.frames.items() if len(f)}
        errors = rec.errors[["offset", "length"]].values.tolist()
        if decoded or errors != [error] or rec.ignored_blocks != expected:
            failures.append(f"{sorted(expected)}: {decoded} decoded, errors {errors[:4]}, "
                            f"{rec.ignored_blocks} stepped over")
    assert not failures, failures


def test_a_false_header_does_not_swallow_blocks_of_categories_not_decoded(tmp_path):
    """Damage inserted before a block of a CAT001/CAT002 recording (read with the default categories): 23
    bytes starting with a header of a category met nowhere (CAT013) whose LEN, 31,493, runs over some 120
    real blocks and lands inside one. Those blocks are stepped over, not swallowed: a chain of four blocks of
    met categories inside a block not decoded is real blocks its LEN would swallow. The inserted bytes are
    the one error."""
    bench = _bench_decode()
    path = tmp_path / "c1.ast"
    bench.build(path, 1, 5000)
    blocks = raw_blocks(path.read_bytes())[:300]
    junk = bytes([13, 0x7B, 0x05]) + bytes(range(100, 120))
    at = sum(len(blk) for blk in blocks[:40])
    assert at + 0x7B05 < sum(len(blk) for blk in blocks)
    damaged = tmp_path / "damaged.ast"
    damaged.write_bytes(b"".join(blocks[:40]) + junk + b"".join(blocks[40:]))
    rec = _read(damaged)
    assert not any(len(f) for f in rec.frames.values()), {c: len(f) for c, f in rec.frames.items()}
    assert rec.errors[["offset", "length"]].values.tolist() == [[at, len(junk)]]
    assert rec.ignored_blocks == {1: 150, 2: 150}


def _modes(data: bytes) -> list[int]:
    """How framing takes a raw stream read with the default categories (kernel.segment_modes)."""
    from msdc.asterix import kernel
    from msdc.asterix.reader import tables_for, walked_editions

    buf = np.frombuffer(data, np.uint8)
    tables = tables_for(walked_editions({}, None))
    return kernel.segment_modes(buf, np.array([0]), np.array([len(buf)]), False, False, tables).tolist()


def test_a_chain_hiding_only_chance_blocks_is_taken_as_it_is(tmp_path):
    """A radar's CAT048 plots (20/1) between a tracker's CAT062 blocks, one of which ends in bytes that walk
    as a CAT048 block of two plots: whole chain from end to end. The hidden block names a data source none of
    the chain's CAT048 blocks names (54/212: chance bytes), so the chain is taken as it is (before, any
    walking block hidden anywhere made the whole recording framed carefully: 1.76 s for the benchmark's
    71 MB CAT062 file against 0.46 s); naming the radar's own source (20/1), it is framed carefully (a real
    block a damaged LEN may have swallowed). Plots: I048/010 and I048/040 (FSPEC 0x90)."""
    from msdc.asterix import kernel

    rng = np.random.default_rng(11)
    tracks = raw_blocks(encode_frame(62, _tracks(6 * RECORDS_PER_BLOCK, rng),
                                     records_per_block=RECORDS_PER_BLOCK))
    radar = raw_blocks(encode_frame(48, _plots(6 * 4, rng), records_per_block=4))

    def hidden(sac: int, sic: int) -> bytes:
        body = b"".join(bytes([0x90, sac, sic, 10, k, 0x40, k]) for k in range(2))
        return bytes([48]) + (3 + len(body)).to_bytes(2, "big") + body

    for source, mode in (((54, 212), kernel.MODE_CHAIN), ((20, 1), kernel.MODE_CAREFUL)):
        blocks = list(tracks)
        blocks[3] = _with_special_purpose(blocks[3], bytes(20) + hidden(*source))
        data = b"".join(p + t for p, t in zip(radar, blocks, strict=True))
        assert _modes(data) == [mode], source
    path = tmp_path / "centre.ast"
    path.write_bytes(b"".join(p + t for p, t in zip(radar, tracks[:3] + [_with_special_purpose(
        tracks[3], bytes(20) + hidden(54, 212))] + tracks[4:], strict=True)))
    rec = _read(path)  # taken as it is: the radar's 24 plots, the tracker's 6 blocks stepped over
    assert rec.errors.empty and rec.ignored_blocks == {62: 6} and len(rec.frames[48]) == 24


def test_a_first_block_whose_len_lands_where_framing_resumes_is_kept(tmp_path):
    """A centre's recording that starts with a CAT063 sensor status block followed by blocks of other
    categories not met yet (CAT002, CAT062) and of decoded ones (CAT020), with damage later so that it is
    framed carefully: nothing proves the first block's LEN, and framing resumes exactly where it ends, so
    it is kept as a block (before, its 478 bytes were reported as bytes that start no block)."""
    bench = _bench_decode()
    streams = {}
    for c in (63, 2, 62, 20):
        path = tmp_path / f"c{c}.ast"
        bench.build(path, c, 1000)
        streams[c] = iter(raw_blocks(path.read_bytes()))
    order = [63, 2, 63, 62, 20, 2, 63, 20, 62, 2, 63, 20, 62, 2, 20, 63]
    blocks = [next(streams[c]) for c in order]
    at = sum(len(blk) for blk in blocks[:12])
    data = b"".join(blocks[:12]) + bytes(5) + b"".join(blocks[12:])
    path = tmp_path / "centre.ast"
    path.write_bytes(data)
    rec = _read(path)
    assert rec.errors[["offset", "length"]].values.tolist() == [[at, 5]]
    assert rec.ignored_blocks == {63: 5, 2: 4, 62: 3}
    assert len(rec.frames[20]) == 4 * RECORDS_PER_BLOCK


def test_a_centres_categories_shuffled_decode_as_apart(tmp_path):
    """Blocks of eight categories shuffled as a centre records them (the decode benchmark's recordings:
    CAT048, CAT021, CAT010, CAT020 decoded by default; CAT062, CAT063, CAT002 and the CAT001 radar with its
    CAT002 messages not), each category's blocks in their own order, over six shuffles: with the default
    categories every decoded block's records and no other, every other block stepped over, no error."""
    bench = _bench_decode()
    streams = {}
    for c in (48, 21, 10, 20, 62, 63, 2, 1):
        path = tmp_path / f"c{c}.ast"
        bench.build(path, c, 1000)
        streams[c] = raw_blocks(path.read_bytes())[:30]
    failures = []
    for seed in range(6):
        rng = np.random.default_rng(seed)
        labels = np.concatenate([np.full(len(b), c) for c, b in streams.items()])
        rng.shuffle(labels)
        nxt = {c: iter(b) for c, b in streams.items()}
        blocks = [next(nxt[int(c)]) for c in labels]
        path = tmp_path / "centre.ast"
        path.write_bytes(b"".join(blocks))
        rec = _read(path)
        kept: dict[int, int] = {}
        records: dict[int, int] = {}
        for blk in blocks:
            if blk[0] in (48, 21, 10, 20):
                records[blk[0]] = records.get(blk[0], 0) + RECORDS_PER_BLOCK
            else:
                kept[blk[0]] = kept.get(blk[0], 0) + 1
        got = {c: len(f) for c, f in rec.frames.items() if len(f)}
        if got != records or rec.ignored_blocks != kept or not rec.errors.empty:
            failures.append(f"seed {seed}: {got} for {records}, {rec.ignored_blocks} for {kept}, "
                            f"{len(rec.errors)} errors")
    assert not failures, failures
