"""Conflict monitoring speed: 300 aircraft, 1 hour at 1 s, horizons 20, 60 and 120 s, exact PC.

Run from the repository root: `python benchmarks/conflicts.py [--aircraft 300] [--minutes 60]`.

STAND-IN PREDICTION: until the IMM tracker (pipeline/track) lands, each aircraft's predicted position
is the straight-line extrapolation of its true state, with a covariance that grows along and across
track (initial 100 m, velocity error 2.5 m/s along and 1.5 m/s across, unmodelled acceleration
0.05 m/s^2). Traffic: random straight flights at 380-500 kt over a 300 x 300 NM square around
3N 101.5E, one in five climbing or descending at 1000-2500 ft/min, the others level on FL200-FL410;
an aircraft leaving the square comes back on the opposite side as a new flight.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from pipeline.conflict import (  # noqa: E402
    alert_events,
    classify_alerts,
    closing_margin_m,
    losses_of_separation,
    pair_probabilities,
    pairs_per_step,
    pc_margin,
    warning_times,
)

M_PER_NM = 1852.0
KT = M_PER_NM / 3600.0
LAT0, LON0 = 3.0, 101.5
SIDE_M = 300 * M_PER_NM
HORIZONS_S = (20, 60, 120)
MAX_SPEED_KT, MAX_RATE_FPM = 500.0, 2500.0
SIGMA0_M, SIGMA_V_ALONG, SIGMA_V_CROSS, SIGMA_ACC = 100.0, 2.5, 1.5, 0.05


def scenario(n: int, seconds: int, seed: int = 2026):
    """True states at 1 s: east/north (m) in the square, velocity (m/s), flight level, flight ids."""
    rng = np.random.default_rng(seed)
    t = np.arange(seconds, dtype=float)
    heading = rng.uniform(0, 2 * np.pi, n)
    speed = rng.uniform(380, 500, n) * KT
    ve, vn = speed * np.sin(heading), speed * np.cos(heading)
    raw_e = rng.uniform(0, SIDE_M, n)[None, :] + ve[None, :] * t[:, None]
    raw_n = rng.uniform(0, SIDE_M, n)[None, :] + vn[None, :] * t[:, None]
    laps = np.floor_divide(raw_e, SIDE_M) * 7 + np.floor_divide(raw_n, SIDE_M)  # new flight per wrap
    east, north = np.mod(raw_e, SIDE_M), np.mod(raw_n, SIDE_M)
    fl0 = rng.integers(200, 411, n).astype(float)
    level = rng.random(n) >= 0.2
    fl0[level] = np.round(fl0[level] / 10) * 10
    rate_fl_s = np.where(level, 0.0, rng.uniform(1000, 2500, n) / 60 / 100 * rng.choice([-1, 1], n))
    fl = np.clip(fl0[None, :] + rate_fl_s[None, :] * t[:, None], 100, 450)
    vz = np.where((fl > 100) & (fl < 450), rate_fl_s[None, :], 0.0)
    flight = np.char.add(np.char.add(np.array([f"AC{i:03d}" for i in range(n)])[None, :], "-"),
                         laps.astype(int).astype(str))
    return t, east, north, ve, vn, fl, vz, flight


def to_latlon(east, north):
    """Local equirectangular plane about (LAT0, LON0) to latitude/longitude (stand-in for the tracker's)."""
    r_m = 6378137.0 * (1 - 0.0033528 * np.sin(np.radians(LAT0)) ** 2)
    lat = LAT0 + np.degrees((north - SIDE_M / 2) / r_m)
    lon = LON0 + np.degrees((east - SIDE_M / 2) / (r_m * np.cos(np.radians(LAT0))))
    return lat, lon


def predictions(t, east, north, ve, vn, fl, vz, flight):
    """Straight-line predictions with growing along/cross-track covariance, every time and horizon."""
    n_t, n = east.shape
    start = pd.Timestamp("2024-05-01 10:00", tz="UTC")
    times = np.repeat(start + pd.to_timedelta(t, unit="s"), n)
    speed = np.hypot(ve, vn)
    ue, un = ve / speed, vn / speed  # along-track unit vector
    frames = []
    for h in HORIZONS_S:
        along = SIGMA0_M**2 + (SIGMA_V_ALONG * h) ** 2 + (0.5 * SIGMA_ACC * h * h) ** 2
        cross = SIGMA0_M**2 + (SIGMA_V_CROSS * h) ** 2 + (0.5 * SIGMA_ACC * h * h) ** 2
        frames.append(pd.DataFrame({
            "aircraft_id": flight.ravel(), "time": times, "horizon_s": h,
            "east_m": (east + ve[None, :] * h).ravel(), "north_m": (north + vn[None, :] * h).ravel(),
            "var_east_m2": np.tile(along * ue**2 + cross * un**2, n_t),
            "cov_east_north_m2": np.tile((along - cross) * ue * un, n_t),
            "var_north_m2": np.tile(along * un**2 + cross * ue**2, n_t),
            "flight_level": np.clip(fl + vz * h, 100, 450).ravel()}))
    return pd.concat(frames, ignore_index=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--aircraft", type=int, default=300)
    parser.add_argument("--minutes", type=float, default=60)
    parser.add_argument("--threshold", type=float, default=0.2)
    args = parser.parse_args()
    seconds = int(args.minutes * 60)
    print(f"Scenario: {args.aircraft} aircraft, {seconds} s at 1 s, horizons {HORIZONS_S} s, radius 5 NM, "
          f"1000 ft, exact PC, one core")
    print("NOTE: predictions are a STAND-IN (straight-line extrapolation of the true state with a growing "
          "covariance), not the IMM prediction, which is not built yet.")
    clock = {}
    t0 = time.perf_counter()
    t, east, north, ve, vn, fl, vz, flight = scenario(args.aircraft, seconds)
    pred = predictions(t, east, north, ve, vn, fl, vz, flight)
    lat, lon = to_latlon(east, north)
    tracks = pd.DataFrame({"aircraft_id": flight.ravel(), "time": pred["time"].iloc[:east.size].to_numpy(),
                           "latitude": lat.ravel(), "longitude": lon.ravel(), "flight_level": fl.ravel()})
    clock["scenario and stand-in predictions (not counted)"] = time.perf_counter() - t0

    t1 = time.perf_counter()
    pc = pair_probabilities(pred, radius_nm=5.0, vertical_ft=1000.0, method="exact")
    clock["A: tree on predicted positions + PC margin, exact PC"] = time.perf_counter() - t1

    # B, in 10-minute slices to bound memory: candidate pairs from current positions, radius widened by
    # the largest closing distance within 120 s and the PC margin, then PC at every horizon
    sigma_max = np.sqrt(2 * (SIGMA0_M**2 + (SIGMA_V_ALONG * 120) ** 2 + (0.5 * SIGMA_ACC * 120**2) ** 2))
    margin_nm = (closing_margin_m(MAX_SPEED_KT, max(HORIZONS_S)) + float(pc_margin(sigma_max))) / M_PER_NM
    vmargin_ft = 2 * MAX_RATE_FPM / 60 * max(HORIZONS_S)
    n_candidates, parts, clock_pairs, clock_pc = 0, [], 0.0, 0.0
    edges = np.unique(np.r_[np.arange(0, seconds, 600), seconds])
    start = tracks["time"].iloc[0]
    for lo, hi in zip(edges[:-1], edges[1:], strict=True):
        window = (start + pd.Timedelta(seconds=int(lo)), start + pd.Timedelta(seconds=int(hi)))
        t2 = time.perf_counter()
        part = tracks[(tracks["time"] >= window[0]) & (tracks["time"] < window[1])]
        candidates = pairs_per_step(part, 5.0, 1000.0, margin_nm=margin_nm, vertical_margin_ft=vmargin_ft)
        t3 = time.perf_counter()
        part_pred = pred[(pred["time"] >= window[0]) & (pred["time"] < window[1])]
        parts.append(pair_probabilities(part_pred, 5.0, 1000.0, method="exact", pairs=candidates))
        clock_pairs += t3 - t2
        clock_pc += time.perf_counter() - t3
        n_candidates += len(candidates)
    pc_b = pd.concat(parts, ignore_index=True)
    clock["B: tree on current positions + closing distance (pairs)"] = clock_pairs
    clock["B: PC of those pairs at every horizon (bound, then exact)"] = clock_pc

    t4 = time.perf_counter()
    losses = losses_of_separation(tracks)
    clock["losses of separation in the truth tracks"] = time.perf_counter() - t4
    t5 = time.perf_counter()
    alerts = alert_events(pc, threshold=args.threshold)
    scored = classify_alerts(alerts, losses)
    warn = warning_times(losses, alerts, HORIZONS_S)
    clock["alert events, false alerts, warning times"] = time.perf_counter() - t5

    key = ["time", "aircraft_a", "aircraft_b", "horizon_s"]
    same = pc.set_index(key)["pc"].sort_index()
    other = pc_b.set_index(key)["pc"].sort_index()
    other = other[other > 1e-6]
    print(f"pair-steps with PC > 1e-6: A {len(same):,}, B {len(other):,}; "
          f"identical sets: {same.index.equals(other.index)}, max |PC_A - PC_B| "
          f"{np.max(np.abs(same.to_numpy() - other.reindex(same.index).to_numpy())) if len(same) else 0:.1e}")
    print(f"B: {n_candidates:,} candidate pair-steps from the closing-distance pre-filter "
          f"(margin {margin_nm:.1f} NM, {vmargin_ft:.0f} ft)")
    print(f"losses of separation: {len(losses)} (median duration {losses['duration_s'].median():.0f} s)")
    for h in HORIZONS_S:
        a = scored[scored["horizon_s"] == h]
        w = warn[warn["horizon_s"] == h]["warning_s"]
        print(f"horizon {h:>3} s: {len(a):>4} alert events, {int(a['false_alert'].sum()):>4} false; "
              f"losses warned before they began {int((w > 0).sum())}/{len(w)}, median warning "
              f"{w[w > 0].median():.0f} s")
    print("timings (s):")
    for name, sec in clock.items():
        print(f"  {name:<58} {sec:7.2f}")
    total = sum(v for k, v in clock.items() if "not counted" not in k and not k.startswith("B"))
    print(f"  {'total, pre-filter A + losses + scoring':<58} {total:7.2f}")


if __name__ == "__main__":
    main()
