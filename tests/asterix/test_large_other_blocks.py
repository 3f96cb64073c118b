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
