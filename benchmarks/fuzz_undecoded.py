"""Damaged recordings of only categories the default read leaves out, read with the default categories.

Every record decoded from them is made of their bytes (none is CAT010, CAT020, CAT021 or CAT048), and every
intact block should be stepped over. Streams: the decode benchmark's CAT001 recording (plot blocks between
CAT002 sector messages), its CAT062 recording, CAT062 and CAT063 blocks one for one, and CAT062 with a
CAT063 block after every nine. Slices of 200 kB, 1-3 damages each (tests/reader_fuzz.py's kinds).

    python benchmarks/fuzz_undecoded.py --cases 200 --seed 1 [--work /tmp/msdc-bench]
"""

from __future__ import annotations

import argparse
import collections
import importlib.util
import sys
import tempfile
import warnings
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

import reader_fuzz as rf  # noqa: E402
from live_bytes import raw_blocks  # noqa: E402

import msdc.asterix as asterix  # noqa: E402

SLICE_BYTES = 200_000
STREAM_BLOCKS = 1_500  # blocks of each category read from the benchmark's recordings


def _decode_benchmark():
    spec = importlib.util.spec_from_file_location("msdc_bench_decode", ROOT / "benchmarks" / "decode.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def streams(work: Path) -> dict[str, bytes]:
    """The four recordings, built once with the decode benchmark's recordings (cached in ``work``)."""
    bench = _decode_benchmark()
    blocks = {}
    for c in (1, 62, 63):
        path = work / f"cat{c:03d}_100000.ast"
        if not path.exists():
            bench.build(path, c, 100_000)
        blocks[c] = raw_blocks(path.read_bytes())[:STREAM_BLOCKS]
    rare = []
    for k, blk in enumerate(blocks[62]):
        rare.append(blk)
        if k % 9 == 8:
            rare.append(blocks[63][k // 9])
    return {"CAT001/CAT002": b"".join(blocks[1]), "CAT062": b"".join(blocks[62]),
            "CAT062/CAT063": b"".join(b for pair in zip(blocks[62], blocks[63], strict=True) for b in pair),
            "CAT062, CAT063 every 9": b"".join(rare)}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", type=int, default=200)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--work", type=Path, default=Path(tempfile.gettempdir()) / "msdc-bench")
    args = ap.parse_args()
    args.work.mkdir(parents=True, exist_ok=True)
    recordings = streams(args.work)
    names = list(recordings)
    rng = np.random.default_rng(args.seed)
    tmp = Path(tempfile.mkdtemp(prefix="msdc-fuzz-undecoded-"))
    total: collections.Counter = collections.Counter()
    by_stream: dict[str, collections.Counter] = {n: collections.Counter() for n in names}
    warnings.simplefilter("ignore")
    for _ in range(args.cases):
        name = names[int(rng.integers(len(names)))]
        data = recordings[name]
        starts, _ = rf.clean_blocks(data)
        first = int(rng.integers(0, int(np.searchsorted(starts, len(data) - SLICE_BYTES))))
        last = int(np.searchsorted(starts, starts[first] + SLICE_BYTES))
        data = data[starts[first]:starts[last] if last < len(starts) else len(data)]
        starts, lens = rf.clean_blocks(data)
        damaged = rf.damage(data, rng, starts, int(rng.integers(1, 4)))
        (tmp / "damaged.ast").write_bytes(damaged.data)
        rec = asterix.read(tmp / "damaged.ast")
        made_up = sum(len(f) for f in rec.frames.values())
        intact = len(rf.intact_blocks(damaged, starts, lens))
        stepped = sum(n for c, n in rec.ignored_blocks.items() if c in (1, 2, 62, 63))
        for counter in (total, by_stream[name]):
            counter.update({"slices": 1, "damages": len(damaged.done), "records made of their bytes": made_up,
                            "slices with such records": int(made_up > 0),
                            "errors": len(rec.errors), "intact blocks": intact,
                            "intact blocks not stepped over": max(intact - stepped, 0)})
    print(f"seed {args.seed}: " + ", ".join(f"{k} {v:,}" for k, v in total.items()))
    for name, counter in by_stream.items():
        print(f"  {name}: " + ", ".join(f"{k} {v:,}" for k, v in counter.items()))


if __name__ == "__main__":
    main()
