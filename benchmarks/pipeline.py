"""End-to-end speed and memory of the msdc commands on simulated recordings (issue 8, item 7).

Builds a scenario with the simulator in ``fixtures/`` (several radars and ADS-B over N hours and M aircraft),
writes it as ASTERIX files, then runs each command in a fresh interpreter under ``/usr/bin/time`` and prints
its wall time and peak RSS, with the machine's load average (the figures mean little on a loaded machine).

    python benchmarks/pipeline.py                       # 3 h, 16 aircraft, 2 radars (the issue's first case)
    python benchmarks/pipeline.py --hours 24 --aircraft 200 --radars 3     # a day
    python benchmarks/pipeline.py --keep DIR            # keep the recordings and reports in DIR
    python benchmarks/pipeline.py --keep /tmp/bench3h --only correlate,quality   # reuse DIR's recordings

With ``--keep DIR``, recordings already in DIR for the same scenario (hours, aircraft, radars, seed) are
reused instead of simulated again; ``--only`` runs a subset of the commands (help, stats, correlate,
quality).
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402

from fixtures.multiradar import SecondRadar, simulate_two_radars  # noqa: E402
from fixtures.scenario import DEFAULT_AIRCRAFT, AircraftSpec, RadarSite, Scenario  # noqa: E402

DATE = "2019-03-01"
THIRD = SecondRadar(site=RadarSite(name="Butterworth MSSR", sac=25, sic=203, latitude=5.4659,
                                   longitude=100.3912, altitude_m=10.0),
                    scan_period_s=12.0, sigma_range_m=90.0, sigma_azimuth_deg=0.1, max_range_nm=200.0)


def scenario(hours: float, n_aircraft: int, seed: int) -> Scenario:
    """``n_aircraft`` aircraft, each on one flight of 40-90 min placed at random within ``hours`` hours."""
    rng = np.random.default_rng(seed)
    span_s = hours * 3600.0
    specs = []
    for i in range(n_aircraft):
        dur = float(min(rng.uniform(2400.0, 5400.0), span_s))
        start = float(rng.uniform(0.0, span_s - dur))
        base = DEFAULT_AIRCRAFT[i % len(DEFAULT_AIRCRAFT)]
        specs.append(AircraftSpec(f"TST{i:04d}", 0x700000 + i, f"{(i % 4096):04o}", ((start, dur),),
                                  nic=base.nic, nacp=base.nacp, nacv=base.nacv, sil=base.sil))
    start_tod = 0.0 if hours >= 20 else 8 * 3600.0  # a day starts at midnight and stays within it
    return Scenario(name="bench", start_tod_s=start_tod, aircraft=tuple(specs))


def build(out: Path, hours: float, n_aircraft: int, radars: int, seed: int) -> list[Path]:
    """Write radar1.ast, radar2.ast (radar3.ast), adsb.ast and sensors.toml; return the input files."""
    from fixtures.simulate import sensors_toml
    from msdc.asterix.encode import encode_frame

    sc = scenario(hours, n_aircraft, seed)
    two = simulate_two_radars(sc, seed=seed)
    files = {"radar1.ast": (48, two.sim.radar), "radar2.ast": (48, two.radar2),
             "adsb.ast": (21, two.sim.adsb)}
    toml = two.sensors_toml()
    if radars >= 3:
        three = simulate_two_radars(sc, THIRD, seed=seed)
        files["radar3.ast"] = (48, three.radar2)
        toml += "\n" + sensors_toml(THIRD.site)
    for name, (cat, frame) in files.items():
        (out / name).write_bytes(encode_frame(cat, frame, edition=None))
    (out / "sensors.toml").write_text(toml)
    return [out / n for n in files]


def timed(label: str, argv: list[str], cwd: Path) -> None:
    """Run ``python -m pipeline.cli ARGV`` in a fresh interpreter; print wall time, CPU time (user + system:
    steadier than wall time on a shared machine), peak RSS and load."""
    cmd = ["/usr/bin/time", "-f", "%e %M %U %S", sys.executable, "-m", "msdc.pipeline.cli", *argv]
    load = os.getloadavg()[0]
    done = subprocess.run(cmd, cwd=cwd, capture_output=True, text=True,
                          env={**os.environ, "PYTHONPATH": str(ROOT)})
    lines = done.stderr.strip().splitlines()
    wall_s, rss_kb, user_s, sys_s = lines[-1].split()
    why = lines[-2] if len(lines) > 1 else ""
    status = "" if done.returncode == 0 else f"  EXIT {done.returncode}: {why}"
    print(f"{label:34s} {float(wall_s):7.2f} s  CPU {float(user_s) + float(sys_s):7.2f} s  "
          f"peak RSS {int(rss_kb) / 1024:7.0f} MB  (load {load:.2f} before){status}", flush=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--hours", type=float, default=3.0)
    ap.add_argument("--aircraft", type=int, default=16)
    ap.add_argument("--radars", type=int, choices=(2, 3), default=2)
    ap.add_argument("--seed", type=int, default=2019)
    ap.add_argument("--keep", type=Path, help="directory for the recordings and reports (default: "
                    "temporary); recordings of the same scenario already there are reused")
    ap.add_argument("--only", default="help,stats,correlate,quality",
                    help="comma-separated commands to time (help, stats, correlate, quality, evaluate)")
    args = ap.parse_args()
    only = set(args.only.split(","))
    with tempfile.TemporaryDirectory() as tmp:
        out = args.keep or Path(tmp)
        out.mkdir(parents=True, exist_ok=True)
        t0 = time.perf_counter()
        tag = out / "scenario.txt"
        key = f"{args.hours:g} h, {args.aircraft} aircraft, {args.radars} radars, seed {args.seed}"
        names = ["radar1.ast", "radar2.ast", "adsb.ast", *(["radar3.ast"] if args.radars >= 3 else [])]
        if tag.exists() and tag.read_text() == key and all((out / n).exists() for n in names):
            inputs = [out / n for n in names]
        else:
            inputs = build(out, args.hours, args.aircraft, args.radars, args.seed)
            tag.write_text(key)
        size = sum(p.stat().st_size for p in inputs)
        print(f"scenario: {args.hours:g} h, {args.aircraft} aircraft, {args.radars} radars and ADS-B: "
              f"{size / 1e6:.1f} MB in {len(inputs)} files, simulated in {time.perf_counter() - t0:.1f} s; "
              f"{os.cpu_count()} CPUs", flush=True)
        files = [str(p) for p in inputs]
        common = ["--sensors", str(out / "sensors.toml"), "--all", "--date", DATE]
        if "help" in only:
            timed("msdc --help", ["--help"], ROOT)
        if "stats" in only:
            timed("msdc stats fixtures/radar.ast", ["stats", "fixtures/radar.ast"], ROOT)
            timed("msdc stats (scenario)", ["stats", *files, "--date", DATE], ROOT)
        if "correlate" in only:
            timed("msdc correlate --all -o report.xlsx", ["correlate", *files, *common, "-o",
                                                         str(out / "report.xlsx")], ROOT)
        if "quality" in only:
            timed("msdc quality --all", ["quality", *files, *common, "-o", str(out / "quality.xlsx")], ROOT)
        if "evaluate" in only:
            timed("msdc evaluate (1997 SSR preset, XLSX, JSON, HTML)",
                  ["evaluate", *files, "--sensors", str(out / "sensors.toml"), "--date", DATE, "--preset",
                   "eurocontrol-1997-ssr", "-o", str(out / "eval.xlsx"), "--json", str(out / "eval.json"),
                   "--html", str(out / "eval.html")], ROOT)


if __name__ == "__main__":
    main()
