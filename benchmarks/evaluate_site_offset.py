"""The radar bias requirements of msdc evaluate (pipeline/evaluate/biases.py) over seeded runs: a radar
declared 1 km from its true site (toward a bearing drawn per seed) must be flagged every time, one declared
at its exact site never (issue #28); and, on the exact site, the share of runs whose 95 % interval holds
each injected bias and the simulated plot noise.

Each run flies the default traffic for an hour (fixtures/radar_effects.py: five aircraft, an overflight
through the cone of silence, a surface target) under a radar with range bias 150 m, gain 100 ppm, azimuth
bias 0.12 deg and time bias 0.5 s, range noise 70 m and azimuth noise 0.08 deg (declared to the
evaluation); the reference is the simulator's truth.

    python benchmarks/evaluate_site_offset.py [--runs 100] [--first-seed 1] [--offset-m 1000]
"""

from __future__ import annotations

import argparse
import sys
import time
from dataclasses import replace
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT)]

import numpy as np  # noqa: E402

from fixtures.radar_effects import RadarEffects, effects_scenario, simulate_effects  # noqa: E402
from msdc.pipeline.evaluate.coverage import Sensor  # noqa: E402
from msdc.pipeline.evaluate.reference import associate  # noqa: E402
from msdc.pipeline.evaluate.requirements import REQUIREMENTS, radar_reports  # noqa: E402

INJECTED = {"range_bias_m": 150.0, "range_gain_ppm": 100.0, "azimuth_bias_deg": 0.12, "time_bias_s": 0.5}
IDS = ("range_bias_m", "range_gain_ppm", "azimuth_bias_deg", "time_bias_s", "range_sd_m", "azimuth_sd_deg")
FLAG = "from its declared site"  # the site-offset warning's words (quality.fit_checks.fit_warning)


def one_run(seed: int, offset_m: tuple[float, float]) -> dict:
    """The six ids on one seeded hour with the radar declared offset_m (east, north) from its true site."""
    sc = replace(effects_scenario(), **INJECTED)
    sim = simulate_effects(sc, RadarEffects(site_offset_m=offset_m), seed=seed)
    site = sim.declared_site
    sensor = Sensor(site.latitude, site.longitude, site.altitude_m, sigma_range_m=sc.sigma_range_m,
                    sigma_azimuth_deg=sc.sigma_azimuth_deg)
    ref = sim.reference()
    rep = associate(radar_reports(sim.radar, sensor), ref)
    out = {rid: REQUIREMENTS[rid](rep, ref, {"seed": seed}, sensor) for rid in IDS}
    truth = {**INJECTED, "range_sd_m": sc.sigma_range_m, "azimuth_sd_deg": sc.sigma_azimuth_deg}
    return {"flagged": FLAG in " ".join(out["range_bias_m"].notes),
            "withheld": bool(np.isnan(out["range_bias_m"].value)),
            "held": {rid: bool(out[rid].ci_low <= truth[rid] <= out[rid].ci_high) for rid in IDS},
            "value": {rid: out[rid].value for rid in IDS}, "truth": truth,
            "width": {rid: out[rid].ci_high - out[rid].ci_low for rid in IDS}}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=100)
    parser.add_argument("--first-seed", type=int, default=1)
    parser.add_argument("--offset-m", type=float, default=1000.0)
    args = parser.parse_args()
    start = time.perf_counter()
    flagged_off = flagged_exact = withheld_exact = 0
    held = dict.fromkeys(IDS, 0)
    values: dict[str, list[float]] = {rid: [] for rid in IDS}
    widths: dict[str, list[float]] = {rid: [] for rid in IDS}
    for seed in range(args.first_seed, args.first_seed + args.runs):
        bearing = np.radians(np.random.default_rng(seed).uniform(0.0, 360.0))
        off = one_run(seed, (args.offset_m * np.sin(bearing), args.offset_m * np.cos(bearing)))
        exact = one_run(seed, (0.0, 0.0))
        flagged_off += off["flagged"] and off["withheld"]
        flagged_exact += exact["flagged"]
        withheld_exact += exact["withheld"]
        for rid in IDS:
            held[rid] += exact["held"][rid]
            values[rid].append(exact["value"][rid])
            widths[rid].append(exact["width"][rid])
        truth = exact["truth"]
    n = args.runs
    print(f"{n} seeds from {args.first_seed}: site {args.offset_m:g} m off flagged (figures withheld) in "
          f"{flagged_off}/{n}; exact site flagged in {flagged_exact}/{n}, withheld in {withheld_exact}/{n}")
    print("exact site: truth, runs whose 95 % interval holds it, mean estimate, SD of the estimates over the "
          "runs, mean interval width / (2 x 1.96 x that SD)")
    for rid in IDS:
        v = np.asarray(values[rid])
        spread = float(np.std(v, ddof=1))
        print(f"  {rid:<18} {truth[rid]:<8g} {held[rid]}/{n}  {np.mean(v):.5g}  {spread:.3g}  "
              f"{np.mean(widths[rid]) / (2 * 1.96 * spread):.2f}")
    print(f"{time.perf_counter() - start:.0f} s ({2 * n} simulated hours, one process)")


if __name__ == "__main__":
    main()
