"""End-to-end tracking validation against the simulator's truth: the default scenario (five aircraft,
65 min) with its second radar (fixtures.multiradar), forward and smoothed. Prints the RMS errors of each
sensor's reports and of the tracks built from several source sets; with --figures DIR also writes a
track figure per aircraft and the error of each track against time. --noise estimate|timing first
rescales the covariances as msdc track does (pipeline.track.noise; timing: with the ADS-B timing term).

    python benchmarks/track_e2e.py [--seed 2019] [--figures DIR] [--noise declared|estimate|timing]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402

import fixtures.track_e2e_data as d  # noqa: E402
from msdc.pipeline.report.figures import new_figure, save_png  # noqa: E402
from msdc.pipeline.report.track_figures import aircraft_figure  # noqa: E402


def _print(label: str, f: dict) -> None:
    rep, trk = f["reports"], f["tracks"]
    print(f"\n{label}")
    print(f"  reports: ADS-B {rep[d.ADSB]:.1f} m (jumps excluded; {rep['adsb_with_jumps']:.0f} m with them), "
          f"radar 1 {rep[d.R1]:.1f} m, radar 2 {rep[d.R2]:.1f} m")
    print(f"  fused track (every output time, coasting included): {trk['fused']:.1f} m")
    print("  fused track at the instants each sensor reported: " + ", ".join(
        f"{sid} {trk[f'fused_at_{sid}']:.1f} m" for sid in (d.ADSB, d.R1, d.R2)))
    print(f"  radar-only tracks: both {trk['radars']:.1f} m, radar 1 alone {trk['radar1']:.1f} m, "
          f"radar 2 alone {trk['radar2']:.1f} m")
    print(f"  on radar 1's track times: both {trk['radars_on_radar1_times']:.1f} m vs radar 1 alone "
          f"{trk['radar1_on_common_times']:.1f} m; on radar 2's: both {trk['radars_on_radar2_times']:.1f} m "
          f"vs radar 2 alone {trk['radar2_on_common_times']:.1f} m")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seed", type=int, default=2019)
    ap.add_argument("--figures", type=Path)
    ap.add_argument("--noise", choices=("declared", "estimate", "timing"), default="declared")
    args = ap.parse_args()
    t0 = time.monotonic()
    e = d.build(seed=args.seed)
    if args.noise != "declared":
        from msdc.pipeline.track.noise import estimate_noise

        est = estimate_noise(e.measurements, sites=d.SITES, timing=args.noise == "timing")
        e.measurements = est.measurements
        table = est.sensors.drop(columns=["sensor_kind"])
        print(f"noise {args.noise} ({est.passes} passes):\n"
              + table.to_string(index=False, float_format=lambda v: f"{v:.4g}"))
    n = e.measurements["sensor_id"].value_counts()
    print(f"default scenario + second radar, seed {args.seed}: {len(e.measurements)} reports "
          f"({', '.join(f'{k} {v}' for k, v in sorted(n.items()))}), "
          f"{int(e.jump.sum())} ADS-B jumps injected")
    forward = d.figures(e)
    _print("forward filter (RMS against truth)", forward)
    smooth = d.figures(e, smooth=True)
    _print("smoothed (RMS against truth)", smooth)
    print(f"\n{time.monotonic() - t0:.1f} s")
    if args.figures:
        args.figures.mkdir(parents=True, exist_ok=True)
        fused = forward["_tracks"]["fused"]
        for ident, g in fused.groupby("aircraft_id"):
            rep = e.measurements[e.measurements["aircraft_id"] == ident]
            aircraft_figure(g.reset_index(drop=True), rep, args.figures / f"e2e_{ident}.png", str(ident))
        fig = new_figure(9.0, 4.5)
        ax = fig.subplots()
        colors = {"fused": "k", "radars": "#1f77b4", "radar1": "#d62728", "radar2": "#9467bd"}
        for name, color in colors.items():
            tr = forward["_tracks"][name]
            err = tr["error_m"].to_numpy()
            ax.semilogy(tr["time"].dt.tz_convert(None), np.where(err > 0, err, np.nan), ".", ms=1,
                        color=color, label=f"{name}: RMS {forward['tracks'][name]:.0f} m")
        ax.set_ylabel("error against truth (m)")
        ax.legend(markerscale=8, fontsize=8)
        ax.grid(True, lw=0.3)
        save_png(fig, args.figures / "e2e_errors.png")
        print(f"figures in {args.figures}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
