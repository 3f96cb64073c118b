"""Tracker speed: measurement updates per second on one core, msdc's numba IMM against filterpy.

A day-sized multi-sensor scenario (plane coordinates): 300 aircraft, one hour each, with 1 Hz ADS-B,
a 4.8 s and a 12 s radar; the 3-mode IMM (CV, CT +-3 deg/s), default (expm) and dynamic TPM, gating on.
filterpy's IMMEstimator (optional benchmark dependency) runs the same 3-mode filter, with per-update F, Q, R
and transition matrix, on the first aircraft's measurements of the same scenario.

    python benchmarks/track.py [--aircraft 300]
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

os.environ.setdefault("NUMBA_NUM_THREADS", "1")
ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402

from fixtures.track_scenarios import fly, merge, position_sensor, rotating_radar  # noqa: E402
from msdc.pipeline.track import TrackerConfig  # noqa: E402
from msdc.pipeline.track.imm import tpm_into  # noqa: E402
from msdc.pipeline.track.plane import filter_plane  # noqa: E402


def scenario(n_aircraft: int, rng) -> list:
    flights = []
    for _ in range(n_aircraft):
        legs = []
        for _ in range(12):
            legs.append((rng.uniform(120, 400), 0.0, 0.0))
            legs.append((rng.uniform(10, 40), rng.choice([-3.0, -1.5, 1.5, 3.0]), 0.0))
        truth = fly(rng.uniform(-150e3, 150e3, 2), rng.uniform(0, 360), rng.uniform(120, 250), legs, dt=0.1)
        t_adsb = np.sort(rng.uniform(0, truth.t[-1], int(truth.t[-1])))
        plots = merge(position_sensor(truth, t_adsb, 20.0, 5.0, rng, sensor=0),
                      rotating_radar(truth, (0.0, 0.0), 4.8, 0.0, 0.95, 70.0, 0.08, rng, sensor=1),
                      rotating_radar(truth, (80e3, 40e3), 12.0, 90.0, 0.9, 70.0, 0.08, rng, sensor=2))
        keep = plots.t <= 3600.0
        flights.append(type(plots)(**{k: getattr(plots, k)[keep] for k in plots.__dataclass_fields__}))
    return flights


def run_msdc(flights, cfg) -> float:
    start = time.perf_counter()
    for p in flights:
        filter_plane(cfg, p.t, p.e, p.n, p.ree, p.ren, p.rnn)
    return time.perf_counter() - start


def run_filterpy(p, cfg, limit: int) -> tuple[float, int]:
    from filterpy.kalman import IMMEstimator, KalmanFilter

    ka = cfg.kernel_args()
    omegas, qs = ka["omegas"], ka["qs"]

    def f4(w, dt):
        if w == 0.0:
            return np.array([[1, dt, 0, 0], [0, 1, 0, 0], [0, 0, 1, dt], [0, 0, 0, 1]], float)
        s, c = np.sin(w * dt), np.cos(w * dt)
        return np.array([[1, s / w, 0, -(1 - c) / w], [0, c, 0, -s], [0, (1 - c) / w, 1, s / w],
                         [0, s, 0, c]])

    filters = []
    for _ in omegas:
        kf = KalmanFilter(dim_x=4, dim_z=2)
        kf.x = np.array([p.e[0], 0.0, p.n[0], 0.0])
        kf.P = np.diag([p.ree[0], 4e4, p.rnn[0], 4e4])
        kf.H = np.array([[1.0, 0, 0, 0], [0, 0, 1.0, 0]])
        filters.append(kf)
    pi = np.empty((3, 3))
    imm = IMMEstimator(filters, ka["mu0"].copy(), np.eye(3))
    n = min(limit, len(p.t))
    start = time.perf_counter()
    for i in range(1, n):
        dt = p.t[i] - p.t[i - 1]
        tpm_into(ka["tpm_kind"], ka["tpm_param"], ka["tpm_param2"], dt, 3, pi)
        imm.M = pi
        for kf, w, q in zip(filters, omegas, qs, strict=True):
            kf.F = f4(w, dt)
            g = np.array([[dt * dt / 2, 0], [dt, 0], [0, dt * dt / 2], [0, dt]])
            kf.Q = q * g @ g.T
            kf.R = np.array([[p.ree[i], p.ren[i]], [p.ren[i], p.rnn[i]]])
        imm.predict()
        imm.update(np.array([p.e[i], p.n[i]]))
    return time.perf_counter() - start, n - 1


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--aircraft", type=int, default=300)
    parser.add_argument("--filterpy-updates", type=int, default=20000)
    args = parser.parse_args()
    rng = np.random.default_rng(2026)
    t0 = time.perf_counter()
    flights = scenario(args.aircraft, rng)
    updates = sum(len(p.t) for p in flights)
    print(f"scenario: {args.aircraft} aircraft x 1 h, 1 Hz ADS-B + 4.8 s and 12 s radars, "
          f"{updates:,} measurements (built in {time.perf_counter() - t0:.0f} s)")
    rate = 0.0
    for cfg in (TrackerConfig(), TrackerConfig(tpm="dynamic")):
        run_msdc(flights[:2], cfg)  # compile / load the numba cache
        best = min(run_msdc(flights, cfg) for _ in range(3))
        rate = updates / best
        print(f"msdc IMM (3 modes, tpm {cfg.tpm}, numba, one core): {updates:,} updates in {best:.2f} s = "
              f"{rate:,.0f} updates/s (best of 3, with the per-update history of all mode states)")
    try:
        import filterpy
    except ImportError:
        print("filterpy not installed: no comparison")
        return
    secs, n = run_filterpy(flights[0], cfg, args.filterpy_updates)
    fp_rate = n / secs
    print(f"filterpy {filterpy.__version__} IMMEstimator (same 3 modes, same measurements): {n:,} updates in "
          f"{secs:.2f} s = {fp_rate:,.0f} updates/s")
    print(f"speed-up: {rate / fp_rate:.0f}x")


if __name__ == "__main__":
    main()
