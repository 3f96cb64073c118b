"""msdc evaluate on the real recordings beside the repository (../shared/real): the Barcelona radar hour
against the 1997 SSR preset, and the LEBL hour's multilateration (ED-117A, ED-87E) and surface radar
(ED-116) against the ADS-B-based reference, with the airport areas of docs/examples. Prints each
scorecard's global, surface/airborne and area rows and the run time; ``--figures DIR`` writes the Barcelona
radar's coverage figures there (docs/evaluate_bcn_*.png were made so).

Run by hand: ``python benchmarks/evaluate_real.py [../shared/real] [--figures docs]``.
"""

from __future__ import annotations

import argparse
import datetime as dt
import tempfile
import time
from pathlib import Path

import pandas as pd

from msdc.pipeline.jobs.evaluate import EvaluateOptions, coverage, evaluate_job

ROOT = Path(__file__).resolve().parents[1]
BCN_SITE = ('[[sensor]]\nname = "BCN (site guessed at the airport reference point)"\nsac = 20\nsic = 129\n'
            "latitude = 41.297\nlongitude = 2.078\naltitude_m = 10.0\n")
LEBL_HOUR = ROOT / "docs" / "methods" / "lebl-hour.md"  # its sensor file: the corrected reference points
AREAS = ROOT / "docs" / "examples" / "lebl-areas.geojson"
# CAT021 0.23 carries no NACp: the ADS-B reference's declared sigma per axis (lebl-hour.md: the
# multilateration's surface reports scatter 5.0 m about the ADS-B positions)
ADSB_SIGMA_M = 5.0


def lebl_sensors() -> str:
    """The [[sensor]] tables of docs/methods/lebl-hour.md (its TOML block)."""
    text = LEBL_HOUR.read_text(encoding="utf-8")
    start = text.index("[[sensor]]")
    return text[start:text.index("```", start)]


def show(label: str, options: EvaluateOptions, figures: Path | None = None) -> None:
    t0 = time.perf_counter()
    result = evaluate_job(options)
    took = time.perf_counter() - t0
    card = result.scorecard
    areas = {r.area for r in result.checked.preset.requirements if r.area}
    rows = card[card["sector"].isin({"global", "surface", "airborne", "field monitors", *areas})]
    print(f"\n## {label}: {len(card)} rows, evaluated in {took:.1f} s")
    with pd.option_context("display.width", 200, "display.max_columns", 20):
        cols = ["sensor", "sector", "requirement", "parameters", "value", "ci_low", "ci_high", "threshold",
                "verdict", "n"]
        print(rows[cols].to_string(index=False, float_format=lambda v: f"{v:.4g}"))
    for note in result.parameters["notes"]:
        print("  note:", note)
    if figures is not None:
        figures.mkdir(parents=True, exist_ok=True)
        for i, (title, png) in enumerate(coverage(result).items()):
            name = ("evaluate_bcn_polar.png", "evaluate_bcn_vertical.png")[i]
            (figures / name).write_bytes(png)
            print(f"  figure {title} -> {figures / name}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("real", nargs="?", type=Path, default=ROOT.parent / "shared" / "real")
    ap.add_argument("--figures", type=Path, help="write the Barcelona radar's coverage figures here")
    a = ap.parse_args()
    bcn = a.real / "230502-est-080001_BCN_60MN_08_09.ast"
    lebl = [a.real / n for n in ("adsb_v023_160510-lebl-220001.ast", "mlat_160510-lebl-220001.ast",
                                 "smr_160510-lebl-220001.ast")]
    with tempfile.TemporaryDirectory() as d:
        site, airport = Path(d) / "bcn.toml", Path(d) / "lebl.toml"
        site.write_text(BCN_SITE)
        airport.write_text(lebl_sensors())
        if bcn.exists():
            show("Barcelona radar hour, eurocontrol-1997-ssr",
                 EvaluateOptions(inputs=(str(bcn),), sensors=str(site), preset="eurocontrol-1997-ssr",
                                 date=dt.date(2023, 5, 2)), a.figures)
        if all(p.exists() for p in lebl):
            for preset in ("ed117a", "ed87e", "ed116"):
                show(f"LEBL hour, {preset}", EvaluateOptions(
                    inputs=tuple(map(str, lebl)), sensors=str(airport), preset=preset, sectors=str(AREAS),
                    editions=("21=0.23",), date=dt.date(2016, 5, 10), adsb_sigma_m=ADSB_SIGMA_M,
                    reference="adsb"))


if __name__ == "__main__":
    main()
