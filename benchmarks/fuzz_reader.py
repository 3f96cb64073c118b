"""The full fuzz of the reader (issue 27): whole real and fixture recordings, damaged at random, through
``read`` and ``iter_read`` at random chunk sizes, with the checks of tests/reader_fuzz.py (the byte account,
``iter_read`` equal to ``read`` at every chunk size, every record of an intact block back unchanged).
The seeded suite in the tests runs a few dozen slices of the same; this runs as many whole files as asked.

    python benchmarks/fuzz_reader.py --cases 200 --seed 1
    python benchmarks/fuzz_reader.py --cases 50 --slice 200000    # 200 kB slices: faster, more cases

Failing cases are written to --keep (default: a temporary directory) with what was done to them.
"""

from __future__ import annotations

import argparse
import collections
import sys
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

import reader_fuzz as rf  # noqa: E402

import msdc.asterix as asterix  # noqa: E402

REAL = ROOT.parent / "shared" / "real"
SOURCES = [(REAL / "adsb_v023_160510-lebl-220001.ast", {21: "auto"}),
           (REAL / "230502-est-080001_BCN_60MN_08_09.ast", None),
           (REAL / "smr_160510-lebl-220001.ast", None),
           (ROOT / "fixtures" / "radar.ast", None), (ROOT / "fixtures" / "adsb.ast", None)]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", type=int, default=100)
    ap.add_argument("--seed", type=int, default=27)
    ap.add_argument("--slice", type=int, default=0, help="bytes of each file to damage (0: the whole file)")
    ap.add_argument("--keep", type=Path, help="directory for failing cases")
    args = ap.parse_args()
    sources = [(p, e) for p, e in SOURCES if p.is_file()]
    rng = np.random.default_rng(args.seed)
    keep = args.keep or Path(tempfile.mkdtemp(prefix="msdc-fuzz-"))
    keep.mkdir(parents=True, exist_ok=True)
    work = Path(tempfile.mkdtemp(prefix="msdc-fuzz-work-"))
    kinds: collections.Counter = collections.Counter()
    chunks, failed, records, intact = [], 0, 0, 0
    t0 = time.process_time()
    warnings.simplefilter("ignore", asterix.EditionWarning)
    for case in range(args.cases):
        path, editions = sources[int(rng.integers(len(sources)))]
        data = path.read_bytes()
        if args.slice:
            starts, _ = rf.clean_blocks(data)
            first = int(rng.integers(0, max(int(np.searchsorted(starts, len(data) - args.slice)), 1)))
            last = int(np.searchsorted(starts, starts[first] + args.slice))
            data = data[starts[first]:starts[last] if last < len(starts) else len(data)]
        starts, lens = rf.clean_blocks(data)
        (work / "clean.ast").write_bytes(data)
        damaged = rf.damage(data, rng, starts, int(rng.integers(1, 4)))
        (work / "damaged.ast").write_bytes(damaged.data)
        kinds.update(d.split(" at ")[0] for d in damaged.done)
        clean = asterix.read(work / "clean.ast", editions=editions)
        whole = asterix.read(work / "damaged.ast", editions=editions)
        problems = [] if rf.account(whole) == len(damaged.data) else ["read: byte account"]
        for chunk in np.exp(rng.uniform(np.log(500), np.log(2_000_000), 2)).astype(int).tolist():
            chunks.append(chunk)
            problems += rf.check_chunks(work / "damaged.ast", whole, chunk, editions=editions)
        moved = rf.intact_blocks(damaged, starts, lens)
        problems += rf.check_kept(clean, whole, moved, starts)
        records += sum(len(f) for f in whole.frames.values())
        intact += len(moved)
        if problems:
            failed += 1
            (keep / f"case{case}.ast").write_bytes(damaged.data)
            (keep / f"case{case}.txt").write_text(f"{path} {editions} {damaged.done}\n" + "\n".join(problems))
            print(f"case {case} {path.name} {damaged.done}: {problems}", flush=True)
    what = f"slices of {args.slice} bytes" if args.slice else "whole files"
    damages = ", ".join(f"{k} {n}" for k, n in sorted(kinds.items()))
    print(f"{args.cases} cases (seed {args.seed}, {what}): {sum(kinds.values())} damages ({damages}), "
          f"{len(chunks)} chunked reads (chunk {min(chunks)} to {max(chunks)} bytes), {intact} intact blocks "
          f"checked, {records} records decoded; {failed} failing case(s); "
          f"{time.process_time() - t0:.0f} s CPU")
    if failed:
        print(f"failing cases in {keep}")


if __name__ == "__main__":
    main()
