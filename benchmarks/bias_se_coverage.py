"""Radar bias standard errors under errors shared by an aircraft: 95 % interval coverage in simulation.

Each run simulates the fixtures' radar (150 m range bias injected) and ADS-B for N aircraft and adds to
every plot of an aircraft the same range offset, drawn N(0, SD) per aircraft (SSR transponder reply-delay
tolerance: Mode S +-0.25 us = +-37 m, Mode A/C +-0.5 us = +-75 m). It prints, per bias, the spread of the
estimates over the runs against the mean reported standard error, and how often +-1.96 SE holds the truth
(and +-t(N-1) SE with fewer than 10 aircraft, as the note then advises).

    python benchmarks/bias_se_coverage.py [--runs 30] [--sd-m 40] [--aircraft 8]
"""

from __future__ import annotations

import argparse
import sys
import warnings
from dataclasses import asdict
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT)]

import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

from fixtures.scenario import AircraftSpec, Scenario  # noqa: E402
from fixtures.simulate import simulate  # noqa: E402
from msdc.pipeline.model.geodesy import M_PER_NM  # noqa: E402
from msdc.pipeline.model.measurements import build_measurements  # noqa: E402
from msdc.pipeline.model.sensors import REQUIRED_COLUMNS as SENSOR_COLUMNS  # noqa: E402
from msdc.pipeline.quality.accuracy import MIN_SE_AIRCRAFT, T975, estimate_biases, radar_errors  # noqa: E402

TRUTH = {"range_bias_m": 150.0, "range_gain_ppm": 0.0, "azimuth_bias_deg": 0.0, "time_bias_s": 0.0}


def one_run(seed: int, n_aircraft: int, sd_m: float) -> pd.Series:
    """The bias estimates of one simulated run with per-aircraft range offsets."""
    fleet = tuple(AircraftSpec(f"TST{i}", 0x710000 + i, f"{i + 1:04o}", ((0.0, 1200.0),))
                  for i in range(n_aircraft))
    sc = Scenario(name="se", aircraft=fleet, range_bias_m=TRUTH["range_bias_m"], adsb_jump_fraction=0.0,
                  adsb_low_quality_episodes=0)
    sim = simulate(sc, seed=500 + seed)
    draws_m = np.random.default_rng(seed).normal(0.0, sd_m, n_aircraft)
    offset_m = dict(zip([a.callsign for a in fleet], draws_m, strict=True))
    radar = sim.radar.assign(rho_nm=sim.radar["rho_nm"] + sim.radar["callsign"].map(offset_m).astype(float)
                             / M_PER_NM)
    sensors = pd.DataFrame([asdict(sc.radar)])[SENSOR_COLUMNS]
    return estimate_biases(radar_errors(build_measurements(radar, sim.adsb, sensors), sensors)).iloc[0]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=30)
    ap.add_argument("--sd-m", type=float, default=40.0, help="sd of the per-aircraft range offset (m)")
    ap.add_argument("--aircraft", type=int, default=8)
    args = ap.parse_args()
    warnings.simplefilter("ignore")
    b = pd.DataFrame([one_run(s, args.aircraft, args.sd_m) for s in range(args.runs)])
    t = T975.get(args.aircraft - 1) if args.aircraft < MIN_SE_AIRCRAFT else None
    print(f"{args.aircraft} aircraft, per-aircraft range offset sd {args.sd_m:g} m, {args.runs} runs")
    for key, truth in TRUTH.items():
        stem, unit = key.rsplit("_", 1)
        err, se = b[key] - truth, b[f"{stem}_se_{unit}"]
        line = (f"  {key:17s} sd(estimate) {err.std():9.4g}  mean SE {se.mean():9.4g}  "
                f"coverage +-1.96 SE {np.mean(np.abs(err) < 1.96 * se):.2f}")
        print(line + (f"  +-{t:.2f} SE {np.mean(np.abs(err) < t * se):.2f}" if t else ""))


if __name__ == "__main__":
    main()
