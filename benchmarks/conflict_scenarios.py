"""Simulated encounters through `msdc conflicts` (issue 11): per scenario, the loss found against the
hand geometry, the warning time per horizon (loss start - first alert), and the false alerts per
horizon, over several simulator seeds.

    python benchmarks/conflict_scenarios.py [--seeds 3] [--threshold 0.2]

The scenarios are in fixtures/conflict_scenarios.py (radar + ADS-B, decode -> track -> predict -> PC ->
events).
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import pandas as pd  # noqa: E402

from fixtures.conflict_scenarios import DATE, encounters, run_encounter  # noqa: E402

HORIZONS = (20.0, 60.0, 120.0)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=3)
    parser.add_argument("--threshold", type=float, default=0.2)
    a = parser.parse_args()
    midnight = pd.Timestamp(str(DATE), tz="UTC")
    rows = []
    for enc in encounters():
        for seed in range(11, 11 + a.seeds):
            t0 = time.monotonic()
            with tempfile.TemporaryDirectory() as d:
                try:
                    r = run_encounter(enc, Path(d), seed=seed, threshold=a.threshold)
                except Exception as exc:  # a crash is a result here: print it and go on
                    rows.append({"scenario": enc.name, "seed": seed, "error": f"{type(exc).__name__}: {exc}"})
                    continue
            row = {"scenario": enc.name, "seed": seed, "run_s": time.monotonic() - t0,
                   "truth_start": enc.loss_s[0] if enc.loss_s else None,
                   "truth_end": enc.loss_s[1] if enc.loss_s else None, "losses": len(r.losses)}
            if len(r.losses):
                loss = r.losses.iloc[0]
                row["found_start"] = (loss["start"] - midnight).total_seconds()
                row["found_end"] = (loss["end"] - midnight).total_seconds()
                row["min_nm"] = loss["min_horizontal_nm"]
            for h in HORIZONS:
                times = r.warning_times
                w = times.loc[times["horizon_s"] == h, "warning_s"] if len(times) else []
                row[f"warn_{h:g}"] = float(w.iloc[0]) if len(w) else None
                al = r.alerts[r.alerts["horizon_s"] == h] if len(r.alerts) else r.alerts
                row[f"false_{h:g}"] = int(al["false_alert"].sum()) if len(al) else 0
                row[f"peak_{h:g}"] = float(al["peak_pc"].max()) if len(al) else 0.0
            rows.append(row)
            print(f"  {enc.name} seed {seed}: {row['run_s']:.1f} s", file=sys.stderr)
    df = pd.DataFrame(rows)
    with pd.option_context("display.width", 250, "display.max_columns", 40):
        print(f"threshold {a.threshold:g}; warn_H = loss start - first alert start at horizon H (s; "
              "NaN: missed); false_H = false alert events; peak_H = highest PC of the alerts")
        print(df.drop(columns=["run_s"]).to_string(index=False, float_format=lambda v: f"{v:.2f}"))
        print("\nper scenario, over the seeds: mean warning (s) and total false alerts per horizon")
        agg = {f"warn_{h:g}": "mean" for h in HORIZONS} | {f"false_{h:g}": "sum" for h in HORIZONS}
        agg = {k: v for k, v in agg.items() if k in df}
        print(df.groupby("scenario", sort=False).agg(agg).to_string(float_format=lambda v: f"{v:.1f}"))
    print(f"\nmean run time per scenario and seed: {df['run_s'].mean():.1f} s")


if __name__ == "__main__":
    main()
