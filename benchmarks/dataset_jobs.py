"""The jobs on a dataset with 1 and 2 Dask workers: wall time, CPU time, peak memory of the main process and
of the largest worker (sampled over the process tree every 0.2 s with psutil, which Dask's distributed
depends on).

    python benchmarks/dataset_jobs.py --dataset DIR --sensors SENSORS.toml [--workers 1 2] [--job evaluate]
        [--from 2026-11-28T13:30 --to 2026-11-28T14:30] [--reference adsb] [--window MINUTES]

``--workers 0`` runs the job with ``--scheduler none`` (no cluster: threads in the one process).

Run it by hand on a quiet machine (the figures go to the notes and docs/guide/large-recordings.md); the
dataset comes from ``msdc ingest`` of benchmarks/centre_day.py's recordings."""

from __future__ import annotations

import argparse
import resource
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import psutil

JOBS = {
    "evaluate": ["evaluate", "--preset", "eurocontrol-1997-ssr"],
    "track": ["track", "--all"],
    "stats": ["stats"],
}


def _watch(proc: psutil.Process, peaks: dict, stop: threading.Event) -> None:
    """Peak RSS of the main process and of each child (the workers) until stop."""
    while not stop.is_set():
        try:
            peaks["main"] = max(peaks.get("main", 0), proc.memory_info().rss)
            for child in proc.children(recursive=True):
                try:
                    rss = child.memory_info().rss
                except psutil.Error:
                    continue
                peaks[child.pid] = max(peaks.get(child.pid, 0), rss)
        except psutil.Error:
            break
        stop.wait(0.2)


def run(job: str, dataset: str, sensors: str, workers: int, extra: list[str]) -> dict:
    """One run of the job: wall and CPU seconds, peak memory of main and the largest worker (MB)."""
    with tempfile.TemporaryDirectory() as tmp:
        out = [] if job == "stats" else ["--json", str(Path(tmp) / "out.json")]
        sens = [] if job == "stats" else ["--sensors", sensors]
        engine = ["--workers", str(workers)] if workers else ["--scheduler", "none"]
        argv = ["msdc", *JOBS[job], "--dataset", dataset, *sens, *engine, *out, *extra]
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        started = time.monotonic()
        proc = subprocess.Popen(argv, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        ps = psutil.Process(proc.pid)
        peaks: dict = {}
        stop = threading.Event()
        watcher = threading.Thread(target=_watch, args=(ps, peaks, stop), daemon=True)
        watcher.start()
        _, err = proc.communicate()
        stop.set()
        watcher.join()
        wall = time.monotonic() - started
        after = resource.getrusage(resource.RUSAGE_CHILDREN)  # the msdc process and its workers, reaped
        cpu_s = (after.ru_utime + after.ru_stime) - (before.ru_utime + before.ru_stime)
        if proc.returncode != 0:
            sys.exit(f"{' '.join(argv)} failed ({proc.returncode}):\n{err}")
        others = [v for k, v in peaks.items() if k != "main"]
        return {"job": job, "workers": workers, "wall_s": wall, "cpu_s": cpu_s,
                "main_mb": peaks.get("main", 0) / 1e6, "largest_worker_mb": max(others, default=0) / 1e6,
                "summary": next((line for line in err.splitlines() if "task(s) on" in line), "")}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--dataset", required=True)
    ap.add_argument("--sensors", required=True)
    ap.add_argument("--job", choices=sorted(JOBS), default="evaluate")
    ap.add_argument("--workers", type=int, nargs="+", default=[1, 2],
                    help="local cluster sizes to run; 0: --scheduler none (threads in the one process)")
    ap.add_argument("--from", dest="start")
    ap.add_argument("--to", dest="end")
    ap.add_argument("--reference", choices=["leave-one-out", "adsb"], help="evaluate's reference")
    ap.add_argument("--window", help="evaluate's --window: the span window by window, pooled")
    a = ap.parse_args()
    extra = [*(["--from", a.start] if a.start else []), *(["--to", a.end] if a.end else []),
             *(["--reference", a.reference] if a.reference else []),
             *(["--window", a.window] if a.window else [])]
    print("| job | workers | wall s | CPU s | main peak MB | largest worker MB | tasks |")
    print("|---|---|---|---|---|---|---|")
    for n in a.workers:
        r = run(a.job, a.dataset, a.sensors, n, extra)
        print(f"| {r['job']} | {n} | {r['wall_s']:.1f} | {r['cpu_s']:.1f} | {r['main_mb']:.0f} | "
              f"{r['largest_worker_mb']:.0f} | {r['summary'].split(': ', 1)[-1]} |", flush=True)


if __name__ == "__main__":
    main()
