"""Pooling a long span's 95th percentile and its interval over aircraft from the files its windows wrote:
time and peak memory of the passes (streamed.streamed_interval, what a span with more than
windows.VALUES_HELD values uses) and, up to --together-max values, of reading them back together
(statistics.clustered_interval), with the figures compared.

Each window is an ADS-B station's 10 minutes at the simulated centre's peak: --per-window errors (gamma,
with an aircraft's own offset) over 470 aircraft drawn from a pool of --pool call signs, written as the span
writes them (SpilledFrames: one Parquet file a window). Each measurement runs in a fresh process.

    python benchmarks/pooled_percentile.py [--windows 6,144] [--per-window 534000] [--pool 20000]
        [--together-max 20000000] [--folder DIR]
"""

from __future__ import annotations

import argparse
import multiprocessing as mp
import resource
import shutil
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT)]

import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402


def write(folder: Path, windows: int, per_window: int, pool: int, seed: int = 1) -> None:
    """The span's files: one frame of values and aircraft a window."""
    from msdc.pipeline.evaluate.spill import SpilledFrames

    rng = np.random.default_rng(seed)
    names = np.array([f"K{k:05d}" for k in range(pool)], dtype=object)
    offset = rng.gamma(2.0, 15.0, pool)
    frames = SpilledFrames(folder)
    for _ in range(windows):
        aircraft = rng.choice(pool, 470, replace=False)[rng.integers(0, 470, per_window)]
        values = offset[aircraft] + rng.gamma(2.0, 20.0, per_window)
        frames.append(pd.DataFrame({"value": values, "aircraft": pd.Categorical(names[aircraft])}))


def measure(folder: str, windows: int, how: str, out) -> None:
    """One pooling in this process: figures, seconds and peak memory above the start."""
    from pandas.api.types import union_categoricals

    from msdc.pipeline.evaluate.statistics import clustered_interval
    from msdc.pipeline.evaluate.streamed import streamed_interval

    def parts():
        for k in range(windows):
            frame = pd.read_parquet(Path(folder) / f"{k:07d}.parquet")
            yield frame["value"].to_numpy(float), pd.Categorical(frame["aircraft"])

    start = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    t = time.perf_counter()
    if how == "passes":
        ci = streamed_interval(parts, "p95")
    else:
        read = list(parts())
        values = np.concatenate([v for v, _ in read])
        clusters = union_categoricals([c for _, c in read], sort_categories=True)
        del read
        ci = clustered_interval(values, clusters.codes, "p95")
    seconds = time.perf_counter() - t
    peak_mb = (resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - start) / 1024
    out.put((ci.value, ci.ci_low, ci.ci_high, ci.n, ci.n_clusters, seconds, peak_mb))


def run(folder: Path, windows: int, how: str) -> tuple:
    queue = mp.get_context("fork").SimpleQueue()
    p = mp.get_context("fork").Process(target=measure, args=(str(folder), windows, how, queue))
    p.start()
    p.join()
    return queue.get()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--windows", default="6,144")
    parser.add_argument("--per-window", type=int, default=534_000)
    parser.add_argument("--pool", type=int, default=20_000)
    parser.add_argument("--together-max", type=int, default=20_000_000)
    parser.add_argument("--folder", type=Path, default=None, help="where the files go (default: TMPDIR)")
    args = parser.parse_args()
    base = Path(tempfile.mkdtemp(prefix="msdc-pooled-", dir=args.folder))
    try:
        print("| windows | values | on disk | how | s | memory added | p95 | 95 % interval | aircraft |")
        print("|---|---|---|---|---|---|---|---|---|")
        for windows in (int(w) for w in args.windows.split(",")):
            folder = base / f"w{windows}"
            write(folder, windows, args.per_window, args.pool)
            disk_mb = sum(f.stat().st_size for f in folder.iterdir()) / 1e6
            figures = {}
            for how in ("passes", "together"):
                if how == "together" and windows * args.per_window > args.together_max:
                    continue
                value, low, high, n, clusters, seconds, peak = run(folder, windows, how)
                figures[how] = (value, low, high)
                print(f"| {windows} | {n:,} | {disk_mb:,.0f} MB | {how} | {seconds:.1f} | {peak:,.0f} MB | "
                      f"{value:.3f} | {low:.3f}-{high:.3f} | {clusters:,} |", flush=True)
            if len(figures) == 2:
                print(f"|  | | | identical figures: {figures['passes'] == figures['together']} | | | | | |")
            shutil.rmtree(folder)
    finally:
        shutil.rmtree(base, ignore_errors=True)


if __name__ == "__main__":
    main()
