"""Conflict analysis speed on the real path: 300 aircraft, 1 hour at 1 s, horizons 20, 60 and 120 s.

    python benchmarks/conflicts.py [--aircraft 300] [--minutes 60] [--command-hours 1 --command-aircraft 30]

Traffic (plane coordinates around 3N 101.5E, then latitude/longitude): each aircraft flies for the whole
period at 200-250 m/s from a random point of a 300 x 300 km square, alternating straight legs of 2-7 min
and turns of 10-40 s at 1.5 or 3 deg/s either way; four in five level on FL200-FL410 (whole thousands of
feet), one in five climbing or descending at 1000-2500 ft/min between FL100 and FL450. Each is reported
by 1 Hz ADS-B (irregular spacing, position error 20 +- 5 m, flight level in 25 ft steps). Then the stages
of `msdc conflicts` after decoding, each timed on `--cpus` cores (default 1: the process is pinned to its
first CPU, so msdc's per-aircraft threads are one; NUMBA_NUM_THREADS=1): `track(...,
keep_states=True)` of every aircraft (the real tracker, not synthetic states), `predict_tracks` (IMM
prediction at every second and horizon), `pair_probabilities` (sort and sweep of the predicted positions
widened by the PC margin, cheap bound, exact PC), losses of separation on the samples between reports
with their closest points, alert events, false alerts, closest approach and warning times. The numba
kernels are compiled (or loaded from their cache) on a warm-up run first, not counted.

Then the whole command (`python -m pipeline.cli conflicts`, a fresh interpreter, decoding included) on a
smaller recording made by the project's simulator (benchmarks/pipeline.py's scenario: one radar pair and
ADS-B), with its wall time and peak memory. Timings mean little on a loaded machine: the load is printed.
"""

from __future__ import annotations

import argparse
import importlib.util
import os
import sys
import tempfile
import time
from pathlib import Path

os.environ.setdefault("NUMBA_NUM_THREADS", "1")
ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

import msdc.pipeline.conflict.pairs_pc as pairs_pc  # noqa: E402
from fixtures.track_scenarios import fly, position_sensor  # noqa: E402
from msdc.pipeline.conflict import (  # noqa: E402
    alert_events,
    classify_alerts,
    grid_rows,
    warning_times,
)
from msdc.pipeline.conflict.approach import closest_approach  # noqa: E402
from msdc.pipeline.conflict.events import losses_by_pairs  # noqa: E402
from msdc.pipeline.conflict.loss_minimum import loss_minima  # noqa: E402
from msdc.pipeline.conflict.predict import predict_tracks  # noqa: E402
from msdc.pipeline.conflict.reported import report_rows, reported_samples  # noqa: E402
from msdc.pipeline.parallel import thread_count  # noqa: E402
from msdc.pipeline.track import Plane, track  # noqa: E402

LAT0, LON0 = 3.0, 101.5
HORIZONS_S = (20.0, 60.0, 120.0)
START = pd.Timestamp("2024-05-01 10:00", tz="UTC")


def scenario(n: int, seconds: int, seed: int = 2026) -> pd.DataFrame:
    """The ADS-B measurement frame (the tracker's input schema) of n aircraft over `seconds`."""
    rng = np.random.default_rng(seed)
    plane = Plane(LAT0, LON0)
    parts = []
    for i in range(n):
        legs = []
        while sum(d for d, _, _ in legs) < seconds + 60:
            legs.append((rng.uniform(120, 420), 0.0, 0.0))
            legs.append((rng.uniform(10, 40), rng.choice([-3.0, -1.5, 1.5, 3.0]), 0.0))
        truth = fly(rng.uniform(-150e3, 150e3, 2), rng.uniform(0, 360), rng.uniform(200, 250), legs, dt=0.5)
        t = np.sort(rng.uniform(0, seconds, seconds))
        plots = position_sensor(truth, t, 20.0, 5.0, rng)
        if rng.random() < 0.8:
            fl = np.full(len(t), float(rng.integers(20, 42)) * 10)
        else:
            rate = rng.uniform(1000, 2500) / 6000.0 * rng.choice([-1, 1])
            fl = np.clip(rng.uniform(150, 400) + rate * t, 100, 450)
        lat, lon = plane.inverse(plots.e, plots.n)
        parts.append(pd.DataFrame({
            "time": START + pd.to_timedelta(np.round(t, 3), unit="s"), "sensor_id": "021:0/1",
            "sensor_kind": "adsb", "aircraft_id": f"AC{i:03d}", "latitude": lat, "longitude": lon,
            "flight_level": np.round(fl * 4) / 4, "cov_ee_m2": plots.ree, "cov_en_m2": plots.ren,
            "cov_nn_m2": plots.rnn}))
    return pd.concat(parts, ignore_index=True)


class Clock:
    """Wall and CPU seconds per named stage."""

    def __init__(self) -> None:
        self.rows: list[tuple[str, float, float]] = []

    def run(self, name: str, fn, *args, **kw):
        w, c = time.perf_counter(), time.process_time()
        out = fn(*args, **kw)
        self.rows.append((name, time.perf_counter() - w, time.process_time() - c))
        return out


def timed_inside(module, name: str, totals: dict, label: str) -> None:
    """Wrap module.name so that its wall time adds up in totals[label]."""
    inner = getattr(module, name)

    def wrapper(*args, **kw):
        w = time.perf_counter()
        try:
            return inner(*args, **kw)
        finally:
            totals[label] = totals.get(label, 0.0) + time.perf_counter() - w

    setattr(module, name, wrapper)


def pipeline_stages(meas: pd.DataFrame, threshold: float, sigma_alt: bool = False) -> None:
    clock = Clock()
    result = clock.run("track (IMM, 3 modes, keep_states)", track, meas, keep_states=True)
    tracks = result.tracks
    grid = grid_rows(tracks, 1.0).reset_index(drop=True)
    pred = clock.run("predict_tracks (20, 60, 120 s at every second)", predict_tracks, result, HORIZONS_S,
                     sigma_alt=sigma_alt)
    inside: dict[str, float] = {}
    timed_inside(pairs_pc, "_chunk_pairs", inside, "pre-filter")
    timed_inside(pairs_pc, "conflict_probability", inside, "exact PC")
    pc = clock.run("pair_probabilities (pre-filter, bound, exact PC)", pairs_pc.pair_probabilities, pred,
                   5.0, 1000.0, "exact")

    def reported_losses():  # as msdc conflicts: on the samples between reports, closest points refined
        reports = report_rows(result.tracks, meas, result.rejected)
        samples = reported_samples(grid, reports)
        found = losses_by_pairs(samples, kinds=("all",), step_s=1.0)["all"]
        return loss_minima(found, reports, 5.0, 975.0)

    losses = clock.run("losses of separation (reported samples, closest points)", reported_losses)

    def scoring():
        events = alert_events(pc, threshold, step_s=1.0)
        alerts = closest_approach(classify_alerts(events, losses), grid)
        return alerts, warning_times(losses, events, HORIZONS_S)

    alerts, warn = clock.run("alerts, false alerts, closest approach, warnings", scoring)
    print(f"tracked: {grid['aircraft_id'].nunique()} aircraft, {len(grid):,} grid rows; predictions "
          f"{len(pred):,} rows; pair-steps with PC > 1e-6: {len(pc):,}")
    print(f"losses of separation: {len(losses)} (median duration {losses['duration_s'].median():.0f} s)")
    for h in HORIZONS_S:
        a = alerts[alerts["horizon_s"] == h]
        w = warn[warn["horizon_s"] == h]["warning_s"]
        print(f"horizon {h:>5.0f} s: {len(a):>4} alert events, {int(a['false_alert'].sum()):>4} false; "
              f"losses alerted before they began {int((w > 0).sum())}/{len(w)}, median warning "
              f"{w[w > 0].median():.0f} s")
    print(f"timings on {thread_count()} CPU(s) (load {os.getloadavg()[0]:.2f} now):")
    print(f"  {'stage':<52} {'wall s':>8} {'CPU s':>8}")
    for name, wall, cpu in clock.rows:
        print(f"  {name:<52} {wall:8.2f} {cpu:8.2f}")
        if name.startswith("pair_probabilities"):
            for k, v in inside.items():
                print(f"    of which {k:<42} {v:8.2f}")
    print(f"  {'total':<52} {sum(r[1] for r in clock.rows):8.2f} {sum(r[2] for r in clock.rows):8.2f}")


def whole_command(hours: float, n_aircraft: int, step: float) -> None:
    spec = importlib.util.spec_from_file_location("bench_pipeline", ROOT / "benchmarks" / "msdc.pipeline.py")
    bench = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(bench)
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp)
        t0 = time.perf_counter()
        inputs = bench.build(out, hours, n_aircraft, 2, 2019)
        size = sum(p.stat().st_size for p in inputs)
        built_s = time.perf_counter() - t0
        print(f"\nwhole command: {hours:g} h, {n_aircraft} aircraft (flights of 40-90 min), 2 radars and "
              f"ADS-B, {size / 1e6:.1f} MB in {len(inputs)} files (simulated in {built_s:.0f} s)")
        bench.timed(f"msdc conflicts --step {step:g} -o c.csv",
                    ["conflicts", *map(str, inputs), "--sensors", str(out / "sensors.toml"), "--date",
                     bench.DATE, "--step", f"{step:g}", "-o", str(out / "c.csv")], ROOT)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--aircraft", type=int, default=300)
    parser.add_argument("--minutes", type=float, default=60)
    parser.add_argument("--threshold", type=float, default=0.2)
    parser.add_argument("--command-hours", type=float, default=1.0)
    parser.add_argument("--command-aircraft", type=int, default=30)
    parser.add_argument("--skip-command", action="store_true")
    parser.add_argument("--cpus", type=int, default=1,
                        help="pin the benchmark (and the command it runs) to this many CPUs (default 1)")
    parser.add_argument("--vertical", choices=("gate", "gaussian"), default="gate",
                        help="vertical proximity as msdc conflicts --vertical (default gate)")
    args = parser.parse_args()
    if hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, sorted(os.sched_getaffinity(0))[:max(args.cpus, 1)])
    seconds = int(args.minutes * 60)
    t0 = time.perf_counter()
    meas = scenario(args.aircraft, seconds)
    print(f"scenario: {args.aircraft} aircraft x {seconds} s, {len(meas):,} ADS-B reports (built in "
          f"{time.perf_counter() - t0:.0f} s); horizons {HORIZONS_S} s, 5 NM, 1000 ft, exact PC, threshold "
          f"{args.threshold:g}, vertical {args.vertical}, {os.cpu_count()} CPUs, "
          f"load {os.getloadavg()[0]:.2f}")
    t0 = time.perf_counter()
    early = meas["time"] < START + pd.Timedelta(minutes=5)
    warm = meas[meas["aircraft_id"].isin(["AC000", "AC001"]) & early]
    predict_tracks(track(warm, keep_states=True), HORIZONS_S)
    print(f"warm-up (numba compile or cache load): {time.perf_counter() - t0:.1f} s")
    pipeline_stages(meas, args.threshold, sigma_alt=args.vertical == "gaussian")
    if not args.skip_command:
        whole_command(args.command_hours, args.command_aircraft, 1.0)


if __name__ == "__main__":
    main()
