"""Wall time and peak memory of the whole process tree (the command and its figure workers) of the real hour's
`track --all --figures` and `conflicts --figures` (issue #26 item 5).

    python benchmarks/figures.py [--limit N ...] [--commands track,conflicts] [--keep DIR]
    PYTHONPATH=/path/to/old-checkout-parent python benchmarks/figures.py --old   # before, every figure

Memory is sampled from /proc every 50 ms: the peak of the summed RSS of every process of the tree (shared
pages counted once per process: an upper bound) and of the summed PSS (shared pages split between the
processes sharing them: what the tree really holds). Linux only. The machine's load (uptime) is printed
before and after: timings on a loaded machine are not comparable with a quiet one's.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from conflict_real_losses import REAL, SITE  # noqa: E402

SAMPLE_S = 0.05


def _children() -> dict[int, list[int]]:
    """Every process's children, by parent pid, from /proc."""
    kids: dict[int, list[int]] = {}
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            with open(f"/proc/{entry}/stat") as f:
                ppid = int(f.read().rsplit(")", 1)[1].split()[1])
        except (OSError, IndexError, ValueError):
            continue
        kids.setdefault(ppid, []).append(int(entry))
    return kids


def _tree(pid: int) -> list[int]:
    kids, out, todo = _children(), [], [pid]
    while todo:
        p = todo.pop()
        out.append(p)
        todo += kids.get(p, [])
    return out


def _kb(pid: int, path: str, key: str) -> int:
    try:
        with open(f"/proc/{pid}/{path}") as f:
            for line in f:
                if line.startswith(key):
                    return int(line.split()[1])
    except OSError:
        pass
    return 0


def _cpu_s(pid: int) -> float:
    """User + system CPU seconds of one process so far."""
    try:
        with open(f"/proc/{pid}/stat") as f:
            fields = f.read().rsplit(")", 1)[1].split()
        return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")
    except (OSError, IndexError, ValueError):
        return 0.0


def run(argv: list[str]) -> tuple[float, float, float, float, int]:
    """Run argv: wall seconds, the tree's CPU seconds (each process's last sample: a process ending within
    a sample's 50 ms loses that much), peak summed RSS and PSS of its process tree (MB), most processes at
    once."""
    peak = {"rss": 0, "pss": 0, "procs": 0}
    cpu: dict[int, float] = {}
    proc = subprocess.Popen(argv, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    stop = threading.Event()

    def sample() -> None:
        while not stop.is_set():
            pids = _tree(proc.pid)
            peak["rss"] = max(peak["rss"], sum(_kb(p, "status", "VmRSS:") for p in pids))
            peak["pss"] = max(peak["pss"], sum(_kb(p, "smaps_rollup", "Pss:") for p in pids))
            peak["procs"] = max(peak["procs"], len(pids))
            cpu.update({p: _cpu_s(p) or cpu.get(p, 0.0) for p in pids})
            stop.wait(SAMPLE_S)

    t0 = time.monotonic()
    sampler = threading.Thread(target=sample, daemon=True)
    sampler.start()
    _, err = proc.communicate()
    wall = time.monotonic() - t0
    stop.set()
    sampler.join()
    if proc.returncode:
        sys.exit(f"{' '.join(argv)} failed ({proc.returncode}):\n{err}")
    return wall, sum(cpu.values()), peak["rss"] / 1024, peak["pss"] / 1024, peak["procs"]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--limit", type=int, nargs="+", default=[50, 0], help="--figures-limit values to time")
    ap.add_argument("--commands", default="track,conflicts")
    ap.add_argument("--keep", help="write the figures here (default: a temporary folder)")
    ap.add_argument("--old", action="store_true",
                    help="msdc predates --figures-limit (PYTHONPATH=an old checkout's parent): every figure, "
                         "in one process")
    a = ap.parse_args()
    if not REAL.exists():
        sys.exit(f"{REAL}: not found (the real recording is beside the repository in /work/shared/real)")
    msdc = [sys.executable, "-m", "msdc.pipeline.cli"]
    print(f"load before: {os.getloadavg()[0]:.2f} (1 min), {os.cpu_count()} cores")
    with tempfile.TemporaryDirectory() as tmp:
        d = Path(a.keep or tmp)
        site = d / "site.toml"
        d.mkdir(parents=True, exist_ok=True)
        site.write_text(SITE)
        common = [str(REAL), "--sensors", str(site), "--date", "2023-05-02"]
        for command in a.commands.split(","):
            for limit in [None, *([0] if a.old else a.limit)]:
                folder = str(d / f"{command}_{limit}")
                extra = [] if limit is None else ["--figures", folder, *(
                    [] if a.old else ["--figures-limit", str(limit)])]
                if command == "track":
                    argv = [*msdc, "track", *common, "--all", *(extra or ["--json", str(d / "t.json")])]
                else:
                    argv = [*msdc, "conflicts", *common, "-o", str(d / "c.csv"), *extra]
                wall, cpu_s, rss, pss, procs = run(argv)
                drawn = len(list((d / f"{command}_{limit}").glob("*.png"))) if limit is not None else 0
                what = "no figures" if limit is None else f"--figures-limit {limit}"
                print(f"{command:10s} {what:20s} {drawn:4d} PNGs  {wall:6.1f} s wall  {cpu_s:6.1f} s CPU  "
                      f"peak RSS {rss:6.0f} MB (summed)  PSS {pss:6.0f} MB  {procs} processes", flush=True)
    print(f"load after: {os.getloadavg()[0]:.2f} (1 min)")


if __name__ == "__main__":
    main()
