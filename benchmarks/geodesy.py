"""pyproj against pipeline/model/geodesy.py on the same work (issue 8, item 6): speed and agreement.

On N random points of the radar/ADS-B domain (latitude -60..60, any longitude, height 0-13 km), times
geodetic -> ECEF, ECEF -> geodetic and ECEF -> ENU about one origin (a radar site), msdc's hand-written
code against pyproj, and prints the largest difference between the two in millimetres. (Geodesic
distances now go through pyproj.Geod.inv; the figures of the Vincenty code it replaced are in
pipeline/model/geodesy.py.)

    python benchmarks/geodesy.py            # 1,000,000 points
    python benchmarks/geodesy.py --n 100000
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import numpy as np  # noqa: E402
from pyproj import Transformer  # noqa: E402

from msdc.pipeline.model import geodesy as g  # noqa: E402

SITE = (2.7456, 101.7072, 40.0)  # a radar site: latitude, longitude (deg), height (m)


def best(fn, repeat: int = 3) -> tuple[float, object]:
    """Best wall time of ``repeat`` calls (s) and the last result."""
    times, out = [], None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return min(times), out


def report(label: str, ours_s: float, theirs_s: float, diff_mm: float) -> None:
    print(f"{label:28s} msdc {ours_s * 1e3:8.1f} ms   pyproj {theirs_s * 1e3:8.1f} ms   "
          f"pyproj/msdc {theirs_s / ours_s:5.2f}   max |difference| {diff_mm:.2e} mm", flush=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=1_000_000)
    n = ap.parse_args().n
    rng = np.random.default_rng(8)
    lat, lon, h = rng.uniform(-60, 60, n), rng.uniform(-180, 180, n), rng.uniform(0, 13000, n)
    print(f"{n:,} points; load {os.getloadavg()[0]:.2f} (1 min), {os.cpu_count()} CPUs", flush=True)

    to_ecef = Transformer.from_crs("EPSG:4979", "EPSG:4978")  # WGS 84 3-D geographic -> geocentric
    t_ours, ours = best(lambda: g.geodetic_to_ecef(lat, lon, h))
    t_theirs, theirs = best(lambda: to_ecef.transform(lat, lon, h))
    report("geodetic -> ECEF", t_ours, t_theirs,
           max(np.max(np.abs(a - b)) for a, b in zip(ours, theirs, strict=True)) * 1e3)

    x, y, z = ours
    to_geo = Transformer.from_crs("EPSG:4978", "EPSG:4979")
    t_ours, ours = best(lambda: g.ecef_to_geodetic(x, y, z))
    t_theirs, theirs = best(lambda: to_geo.transform(x, y, z))
    # angles as metres along the meridian and the parallel
    dlat_mm = np.max(np.abs(ours[0] - theirs[0])) * np.pi / 180 * g.A_M * 1e3
    dlon_mm = np.max(np.abs(ours[1] - theirs[1]) * np.cos(np.radians(lat))) * np.pi / 180 * g.A_M * 1e3
    dh_mm = np.max(np.abs(ours[2] - theirs[2])) * 1e3
    report("ECEF -> geodetic", t_ours, t_theirs, max(dlat_mm, dlon_mm, dh_mm))

    near_lat, near_lon = SITE[0] + rng.uniform(-3, 3, n), SITE[1] + rng.uniform(-3, 3, n)
    nx, ny, nz = g.geodetic_to_ecef(near_lat, near_lon, h)
    topo = Transformer.from_pipeline(f"+proj=topocentric +ellps=WGS84 +lat_0={SITE[0]} +lon_0={SITE[1]} "
                                     f"+h_0={SITE[2]}")
    t_ours, ours = best(lambda: g.ecef_to_enu(nx, ny, nz, *SITE))
    t_theirs, theirs = best(lambda: topo.transform(nx, ny, nz))
    report("ECEF -> ENU (one origin)", t_ours, t_theirs,
           max(np.max(np.abs(a - b)) for a, b in zip(ours, theirs, strict=True)) * 1e3)


if __name__ == "__main__":
    main()
