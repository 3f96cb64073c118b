"""PC methods against independent references, at a scale too slow for CI.

Run from the repository root: `python benchmarks/conflict_validation.py [--random 200]`. References:
the noncentral chi-square (isotropic), adaptive 2-D quadrature (QUADPACK) of the density over the disc
in polar coordinates, and Monte Carlo with its standard error.
"""

from __future__ import annotations

import argparse
import sys
import time
import warnings
from pathlib import Path

import numpy as np
from scipy.stats import ncx2

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from fixtures.conflict_reference import polar_reference, rotated  # noqa: E402
from msdc.pipeline.conflict import conflict_probability  # noqa: E402


def methods(m, p, d):
    row = {"exact": conflict_probability(m, p, d), "one-block": conflict_probability(m, p, d, "one-block")}
    for n in (4, 16, 64):
        row[f"blocks {n}"] = conflict_probability(m, p, d, "blocks", n=n)
    row["midpoint 16"] = conflict_probability(m, p, d, "midpoint", n=16)
    return row


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--random", type=int, default=200)
    args = parser.parse_args()
    warnings.simplefilter("ignore")  # QUADPACK's round-off notes; its result is compared, not trusted

    print("1. Named cases, disc radius d, sigma = principal standard deviations, angle of the major axis")
    cases = [((0, 2), rotated(1, 1, 0), 2), ((0, 2), rotated(0.316228, 0.316228, 0), 2),
             ((1.5, 2), rotated(0.3, 0.3, 0), 2), ((3, 0), rotated(2, 0.5, 0), 2),
             ((0, 3), rotated(2, 0.5, 0), 2),
             ((1.2, -1.7), rotated(1, 0.2, 0.7), 2), ((0.7, 0.72), rotated(0.03, 0.03, 0), 1),
             ((4, 4), rotated(3, 1, -0.4), 5), ((10, -3), rotated(40, 15, 1), 5),
             ((0, 0), rotated(100, 1, 0.3), 5),
             ((1.01, 0), rotated(1e-2, 1e-4, 0.3), 1), ((-2, 1), rotated(1, 1e-3, 1.2), 2)]
    head = ["reference", "exact", "one-block", "blocks 4", "blocks 16", "blocks 64", "midpoint 16"]
    print(f"{'mean':>14} {'sigmas':>16} {'ang':>5} {'d':>3} " + " ".join(f"{h:>11}" for h in head))
    for m, p, d in cases:
        ref = polar_reference(np.array(m, float), p, d)
        row = methods(np.array(m, float), p, d)
        w, v = np.linalg.eigh(p)
        isotropic = w[1] <= w[0] * (1 + 1e-9)
        ang = "    -" if isotropic else f"{np.degrees(np.arctan2(v[1, 1], v[0, 1])) % 180:5.0f}"
        print(f"{str(m):>14} {np.sqrt(w[1]):7.3g},{np.sqrt(w[0]):<8.3g} {ang} {d:3g} {ref:11.6f} "
              + " ".join(f"{row[h]:11.6f}" for h in head[1:]))

    print(f"\n2. {args.random} random cases: d = 1, major sigma 1e-3..30, axis ratio 1..3000, any angle, "
          "mean anywhere from the centre to beyond the edge")
    rng = np.random.default_rng(2026)
    worst = {h: 0.0 for h in head[1:]}
    below = {h: 0 for h in head[1:]}
    t0 = time.perf_counter()
    for _ in range(args.random):
        s_major = 10 ** rng.uniform(-3, 1.5)
        p = rotated(s_major, s_major / 10 ** rng.uniform(0, 3.5), rng.uniform(0, np.pi))
        ang = rng.uniform(0, 2 * np.pi)
        r = abs(rng.uniform(0, 1.3) + rng.normal() * s_major)
        m = r * np.array([np.cos(ang), np.sin(ang)])
        ref = polar_reference(m, p, 1.0)
        for h, v in methods(m, p, 1.0).items():
            worst[h] = max(worst[h], abs(v - ref))
            below[h] += v < ref - 1e-9
    print(f"   reference time {time.perf_counter() - t0:.0f} s")
    print(f"   {'method':<12} {'max |PC - ref|':>15} {'cases below ref':>16}")
    for h in head[1:]:
        print(f"   {h:<12} {worst[h]:15.2e} {below[h]:16d}")

    print("\n3. Isotropic: 100,000 random cases against the noncentral chi-square, d = 1")
    k = 100_000
    s = 10 ** rng.uniform(-6, 4, k)
    ang = rng.uniform(0, 2 * np.pi, k)
    r = np.abs(rng.uniform(0, 1.5, k) + np.sqrt(s) * rng.normal(size=k))
    m = np.column_stack([r * np.cos(ang), r * np.sin(ang)])
    truth = ncx2.cdf(1 / s, 2, r**2 / s)
    t0 = time.perf_counter()
    exact = conflict_probability(m, s[:, None, None] * np.eye(2), 1.0)
    spent = time.perf_counter() - t0
    print(f"   max |exact - ncx2| = {np.max(np.abs(exact - truth)):.2e}; "
          f"{k / spent:,.0f} exact PCs per second")

    print("\n4. Monte Carlo, 10^8 samples each (standard error shown)")
    for m, p, d in ((np.array([0.0, 1.0]), rotated(1.0, 1e-4, 0.3), 1.0),
                    (np.array([1.01, 0.0]), rotated(1e-2, 1e-4, 0.3), 1.0),
                    (np.array([3.0, 4.0]), rotated(2.0, 0.7, 2.0), 5.0)):
        chol = np.linalg.cholesky(p)
        hits = 0
        for _ in range(10):
            z = rng.standard_normal((10_000_000, 2)) @ chol.T + m
            hits += int(np.count_nonzero((z**2).sum(1) <= d * d))
        mc = hits / 1e8
        print(f"   mean {m.tolist()}: exact {conflict_probability(m, p, d):.6f}, Monte Carlo {mc:.6f} "
              f"+- {np.sqrt(mc * (1 - mc) / 1e8):.1e}")


if __name__ == "__main__":
    main()
