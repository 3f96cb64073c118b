"""Ingest speed and memory: records/s of ``msdc ingest`` with 1 and 2 workers, and the peak RSS of the main
process and of the largest worker, on a generated raw recording.

Run by hand (never a timed test): ``python benchmarks/ingest.py [--records 3000000] [--work DIR]``. The
recording is a day of 10 radars' CAT048 plots (80 %) and one ADS-B station's CAT021 reports (20 %), built with
msdc's encoder in time order (cached in --work). Each measurement is a fresh process running the ingest job
into an empty dataset (numba's cached kernels load in the first chunk, counted); the file is read once
before, so it is in the page cache. RSS: ru_maxrss of the process, and the largest VmHWM among its
descendants (the forkserver and the pool's workers), polled every 0.05 s; CPU: the process's user and
system time and its descendants' as last polled (a loaded machine stretches the wall time, much less the
CPU time).
"""

from __future__ import annotations

import argparse
import json
import shutil
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from decode import cat021_frame, cat048_frame  # noqa: E402

RADARS = [(20, 129 + k) for k in range(10)]
STEP = 200_000  # records encoded at a time: a slice of the day


def build(path: Path, n: int) -> None:
    """``n`` records over a day, in time order: per slice, the radars' plots then the ADS-B reports."""
    from msdc.asterix.encode import encode_frame

    rng = np.random.default_rng(29)
    part = path.with_suffix(".part")
    slices = max(n // STEP, 1)
    with open(part, "wb") as fh:
        for k in range(slices):
            m = n // slices
            lo, hi = 86000.0 * k / slices, 86000.0 * (k + 1) / slices
            radar = cat048_frame(int(m * 0.8), rng)
            pick = rng.integers(0, len(RADARS), len(radar))
            radar["sac"], radar["sic"] = np.array(RADARS)[pick].T
            radar["time_of_day"] = np.sort(rng.uniform(lo, hi, len(radar))).round(2)
            adsb = cat021_frame(m - len(radar), rng)
            tod = np.sort(rng.uniform(lo, hi, len(adsb))).round(2)
            for c in ("time_applicability_position", "time_applicability_velocity"):
                adsb[c] = tod
            for c, dt_s in (("time_reception_position", 0.5), ("time_reception_velocity", 0.5),
                            ("time_report_transmission", 0.6)):
                adsb[c] = tod + dt_s
            fh.write(encode_frame(48, radar, records_per_block=25))
            fh.write(encode_frame(21, adsb, records_per_block=25,
                                  prefer={"latitude": "130", "longitude": "130"}))
    part.rename(path)


def read_through(path: Path) -> None:
    """Read a file through, 16 MB at a time, to have it in the page cache: not whole, since a measured
    process starts with its parent's peak RSS as its own (Linux keeps ru_maxrss across fork and exec)."""
    with open(path, "rb") as fh:
        while fh.read(1 << 24):
            pass


MEASURE = r"""
import json, os, resource, sys, threading, time
from pathlib import Path
from msdc.pipeline.jobs.ingest import ingest_job
peak = {}  # pid -> VmHWM (kB) of this process's descendants (the forkserver and the pool's workers)
cpu = {}  # pid -> CPU seconds (user + system) of each descendant, as last seen
TICK = os.sysconf("SC_CLK_TCK")
def descendants():
    kids = {}
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
            kids.setdefault(int(fields[1]), []).append(int(stat.parent.name))
        except (OSError, IndexError, ValueError):
            pass
    out, todo = [], [os.getpid()]
    while todo:
        for k in kids.get(todo.pop(), []):
            out.append(k)
            todo.append(k)
    return out
def watch():
    while True:
        for pid in descendants():
            try:
                f = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
                cpu[pid] = (int(f[11]) + int(f[12])) / TICK
                for line in Path(f"/proc/{pid}/status").read_text().splitlines():
                    if line.startswith("VmHWM:"):
                        peak[pid] = max(peak.get(pid, 0), int(line.split()[1]))
            except OSError:
                pass
        time.sleep(0.05)
threading.Thread(target=watch, daemon=True).start()
from msdc.pipeline.jobs.options import IngestOptions
paths = json.loads(sys.argv[1]) if sys.argv[1].startswith("[") else [sys.argv[1]]
root, workers, chunk = sys.argv[2], int(sys.argv[3]), float(sys.argv[4])
date = __import__("datetime").date.fromisoformat(sys.argv[5] if len(sys.argv) > 5 else "2026-11-28")
t = time.perf_counter()
result = ingest_job(IngestOptions(inputs=tuple(paths), dataset=root, workers=workers, date=date,
                                  chunk_mb=chunk))
took = time.perf_counter() - t
own = resource.getrusage(resource.RUSAGE_SELF)
print(json.dumps({"seconds": took, "records": sum(sum(r["rows"].values()) for r in result.ingested),
                  "parts": sum(len(r["parts"]) for r in result.ingested),
                  "dataset_mb": sum(p.stat().st_size for p in Path(root).rglob("*.parquet")) / 1e6,
                  "main_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
                  "worker_rss_mb": max(peak.values(), default=0) / 1024,
                  "cpu_s": own.ru_utime + own.ru_stime + sum(cpu.values())}))
"""


def measure(path: Path, work: Path, workers: int, chunk_mb: float) -> dict:
    root = work / f"dataset_{workers}"
    shutil.rmtree(root, ignore_errors=True)
    done = subprocess.run([sys.executable, "-c", MEASURE, str(path), str(root), str(workers), str(chunk_mb)],
                          capture_output=True, text=True, check=True)
    out = json.loads(done.stdout.strip().splitlines()[-1])
    shutil.rmtree(root, ignore_errors=True)
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--records", type=int, default=3_000_000)
    parser.add_argument("--work", type=Path, default=Path("/tmp/msdc_bench_ingest"))
    parser.add_argument("--chunk-mb", type=float, default=16.0)
    parser.add_argument("--workers", type=int, nargs="+", default=[1, 2])
    args = parser.parse_args()
    args.work.mkdir(parents=True, exist_ok=True)
    path = args.work / f"day_{args.records}.ast"
    if not path.exists():
        t = time.perf_counter()
        build(path, args.records)
        print(f"built {path} ({path.stat().st_size / 1e6:.0f} MB) in {time.perf_counter() - t:.0f} s")
    read_through(path)  # in the page cache
    print(f"{path.name}: {path.stat().st_size / 1e6:.0f} MB, --chunk-mb {args.chunk_mb:g}")
    base = None
    for workers in args.workers:
        m = measure(path, args.work, workers, args.chunk_mb)
        rate = m["records"] / m["seconds"]
        base = base or rate
        print(f"workers {workers}: {m['records']} records in {m['seconds']:.1f} s = {rate / 1e6:.2f} M "
              f"records/s (x{rate / base:.2f}), {m['parts']} parts; peak RSS main {m['main_rss_mb']:.0f} MB, "
              f"largest worker {m['worker_rss_mb']:.0f} MB; CPU {m['cpu_s']:.1f} s = "
              f"{m['records'] / m['cpu_s'] / 1e6:.2f} M records per CPU-second")


if __name__ == "__main__":
    main()
