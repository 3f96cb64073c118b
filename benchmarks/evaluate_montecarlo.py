"""Coverage of msdc evaluate's requirement functions in simulation: over seeded runs of a radar with known
performance (fixtures/radar_effects.py), the share of runs whose 95 % interval holds each injected rate
(issue #28 target: at least 93 %; with 100 runs the binomial SD of a coverage near 0.95 is 2.2 %).

Each run flies the default traffic for an hour (five aircraft, an overflight through the cone of silence, a
surface target) under a radar that detects with pd inside 140 NM (falling to 0 at 180 NM, none above 40 deg
of elevation), garbles and errs Mode 3/A and Mode C codes, adds false plots per scan and split plots. The
reference is the simulator's truth; coverage is declared (140 NM, 40 deg).

    python benchmarks/evaluate_montecarlo.py [--runs 100] [--first-seed 1] [--pd 0.9] [--site-offset-m 0]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT)]

import numpy as np  # noqa: E402

from fixtures.radar_effects import RadarEffects, expected_rates, simulate_effects  # noqa: E402
from msdc.pipeline.evaluate.coverage import Sensor  # noqa: E402
from msdc.pipeline.evaluate.reference import associate  # noqa: E402
from msdc.pipeline.evaluate.requirements import REQUIREMENTS, radar_reports  # noqa: E402

TARGET = 0.93  # issue #28: each injected rate inside its 95 % interval in at least 93 % of the runs


def effects(pd: float, site_offset_m: float) -> RadarEffects:
    """The injected performance of one configuration."""
    return RadarEffects(pd=pd, full_range_nm=140.0, max_range_nm=180.0, cone_elevation_deg=40.0,
                        mode3a_garble=0.03, mode3a_error=0.01, modec_garble=0.02, modec_error=0.015,
                        false_per_scan=2.0, split=0.03, site_offset_m=(site_offset_m, 0.0))


def one_run(eff: RadarEffects, seed: int) -> dict[str, tuple[bool, float, int]]:
    """Per requirement: whether its interval holds the injected rate, its value and its n."""
    sim = simulate_effects(effects=eff, seed=seed)
    site, m = sim.declared_site, sim.north_markers
    sensor = Sensor(site.latitude, site.longitude, site.altitude_m, max_range_nm=eff.full_range_nm,
                    max_elevation_deg=eff.cone_elevation_deg,
                    north_markers_s=(m["day"] * 86400.0 + m["time_of_day"]).to_numpy())
    ref = sim.reference()
    rep = associate(radar_reports(sim.radar, sensor), ref)
    out = {}
    for name, (truth, params) in expected_rates(eff, sim.scan_period_s).items():
        o = REQUIREMENTS[name](rep, ref, params, sensor)
        out[name] = (bool(o.ci_low <= truth <= o.ci_high), float(o.value), int(o.n))
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=100)
    parser.add_argument("--first-seed", type=int, default=1)
    parser.add_argument("--pd", type=float, default=0.9)
    parser.add_argument("--site-offset-m", type=float, default=0.0)
    args = parser.parse_args()
    eff = effects(args.pd, args.site_offset_m)
    truths = expected_rates(eff, 4.8)
    rows: dict[str, list] = {k: [] for k in truths}
    start = time.perf_counter()
    for seed in range(args.first_seed, args.first_seed + args.runs):
        for name, got in one_run(eff, seed).items():
            rows[name].append(got)
    took = time.perf_counter() - start
    print(f"{args.runs} runs (seeds {args.first_seed}-{args.first_seed + args.runs - 1}), pd {args.pd}, "
          f"site offset {args.site_offset_m:g} m: {took:.0f} s ({took / args.runs:.2f} s a run)")
    print(f"{'requirement':24s} {'injected':>9s} {'coverage':>9s} {'mean value':>11s} {'mean n':>8s}")
    short = []
    for name, got in rows.items():
        hit = np.array([g[0] for g in got])
        print(f"{name:24s} {truths[name][0]:9.4f} {hit.mean():9.3f} {np.mean([g[1] for g in got]):11.5f} "
              f"{np.mean([g[2] for g in got]):8.0f}")
        if hit.mean() < TARGET:
            short.append(f"{name} {hit.mean():.3f}")
    print(f"below the target {TARGET}: {', '.join(short) if short else 'none'}")


if __name__ == "__main__":
    main()
