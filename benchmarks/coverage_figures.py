"""The coverage figures of docs/methods/evaluate.md: the polar PD map and the vertical coverage diagram of a
simulated radar (fixtures/radar_effects.py: PD 0.9 out to 60 NM, falling linearly to 0 at 100 NM, none above
30 deg of elevation), coverage estimated from its own detections, the simulator's truth as reference.

    python benchmarks/coverage_figures.py [--out docs] [--seed 2028]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT)]

from fixtures.radar_effects import RadarEffects, simulate_effects  # noqa: E402
from msdc.pipeline.evaluate import bins  # noqa: E402
from msdc.pipeline.evaluate.coverage import Sensor  # noqa: E402
from msdc.pipeline.evaluate.detection import expected_updates  # noqa: E402
from msdc.pipeline.evaluate.reference import associate  # noqa: E402
from msdc.pipeline.evaluate.requirements import radar_reports  # noqa: E402
from msdc.pipeline.report.coverage_figures import polar_pd_figure, vertical_coverage_figure  # noqa: E402

EFFECTS = RadarEffects(pd=0.9, full_range_nm=60.0, max_range_nm=100.0, cone_elevation_deg=30.0)


def main() -> None:
    """Simulate, evaluate the expected updates and draw both figures."""
    args = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    args.add_argument("--out", default=str(ROOT / "docs"))
    args.add_argument("--seed", type=int, default=2028)
    a = args.parse_args()
    start = time.perf_counter()
    sim = simulate_effects(effects=EFFECTS, seed=a.seed)
    site, m = sim.declared_site, sim.north_markers
    sensor = Sensor(site.latitude, site.longitude, site.altitude_m, name="simulated radar",
                    north_markers_s=(m["day"] * 86400.0 + m["time_of_day"]).to_numpy())
    ref = sim.reference()
    table, cov, notes = expected_updates(associate(radar_reports(sim.radar, sensor), ref), ref, {}, sensor)
    out = Path(a.out)
    polar_pd_figure(bins.polar_grid(table), out / "coverage_polar.png",
                    "Simulated radar: PD by slant range (NM) and azimuth", min_expected=bins.MIN_EXPECTED)
    vertical_coverage_figure(bins.vertical_grid(table), out / "coverage_vertical.png",
                             "Simulated radar: vertical coverage", min_expected=bins.MIN_EXPECTED,
                             cone_elevation_deg=cov.max_elevation_deg, site_altitude_m=site.altitude_m,
                             max_range_nm=cov.max_range_nm)
    print("; ".join(notes))
    print(f"{len(table)} expected updates; figures in {out} ({time.perf_counter() - start:.1f} s)")


if __name__ == "__main__":
    main()
