"""Every loss of separation `msdc conflicts` finds on the real Barcelona radar hour, checked against the raw
plots (issue 26): the minimum distance the raw plots give over the loss's span, against the table's.

    python benchmarks/conflict_real_losses.py [--step 5] [--losses OTHER.json] [--out losses.csv]

Raw minimum: each aircraft flown straight from plot to plot (plots at most --max-report-gap apart; every
plot, the ones the tracker gated too), the closest point of the two paths over the loss's [start, end],
the distance there on the WGS-84 ellipsoid (pyproj's geodesic, not the job's chord); a loss with no
stretch where both have such plots has no raw minimum (it lies where one aircraft has no plots).
The radar's site is not in the recording: a site file guesses it at the airport reference point, 41.297 N
2.078 E, as docs/conflict.md did. --losses checks the losses of another run's JSON (main's, say) against
the same plots. No truth: the plots carry the radar's own noise (70 m, 0.08 deg: 0.02-0.04 NM at 15-30 NM).
"""

from __future__ import annotations

import argparse
import datetime as dt
import json
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

REAL = ROOT.parent / "shared" / "real" / "230502-est-080001_BCN_60MN_08_09.ast"
SITE = """[[sensor]]
name = "BCN (site guessed at the airport reference point)"
sac = 20
sic = 129
latitude = 41.297
longitude = 2.078
altitude_m = 0.0
"""
AGREE_NM = 0.1


def _at(plots: pd.DataFrame, t_ns: int, max_gap_s: float) -> tuple[float, float] | None:
    """An aircraft's position at t_ns, linearly between its two plots around it (at most max_gap_s apart;
    a plot exactly at t_ns is its own position); None when there are no such plots."""
    t = plots["time"].array.as_unit("ns").asi8
    k = int(np.searchsorted(t, t_ns, side="right"))
    if k and t[k - 1] == t_ns:
        p = plots.iloc[k - 1]
        return float(p["latitude"]), float(p["longitude"])
    if k == 0 or k == len(t) or (t[k] - t[k - 1]) / 1e9 > max_gap_s:
        return None
    p0, p1 = plots.iloc[k - 1], plots.iloc[k]
    w = (t_ns - t[k - 1]) / (t[k] - t[k - 1])
    return (float(p0["latitude"] + w * (p1["latitude"] - p0["latitude"])),
            float(p0["longitude"] + w * (p1["longitude"] - p0["longitude"])))


def raw_minimum(plots_a: pd.DataFrame, plots_b: pd.DataFrame, start: pd.Timestamp, end: pd.Timestamp,
                max_gap_s: float) -> tuple[float, int]:
    """The smallest distance (NM) over [start, end] between the two aircraft's plot paths (straight between
    consecutive plots at most max_gap_s apart), and how many pieces were counted. On each piece between
    consecutive plot times of either aircraft the relative motion is straight: its closest point is found
    in a flat east-north frame, the distance there measured on the ellipsoid."""
    from msdc.pipeline.model.geodesy import distance_m

    t0, t1 = start.value, end.value
    inner = [p["time"].array.as_unit("ns").asi8 for p in (plots_a, plots_b)]
    times = np.unique(np.concatenate([[t0, t1]] + [t[(t > t0) & (t < t1)] for t in inner]))
    best, counted = np.inf, 0

    def distance(t_ns: int) -> float | None:
        a, b = _at(plots_a, t_ns, max_gap_s), _at(plots_b, t_ns, max_gap_s)
        if a is None or b is None:
            return None
        return float(distance_m(a[0], a[1], b[0], b[1])) / 1852.0

    for lo, hi in zip(times[:-1], times[1:], strict=True) if len(times) > 1 else [(times[0], times[0])]:
        ends = [(_at(plots_a, t, max_gap_s), _at(plots_b, t, max_gap_s)) for t in (lo, hi)]
        if any(p is None for pair in ends for p in pair):
            continue
        counted += 1
        lat0 = ends[0][0][0]
        k_east = np.cos(np.radians(lat0)) * 60.0  # NM per degree of longitude, of latitude: 60
        rel = [np.array([(b[1] - a[1]) * k_east, (b[0] - a[0]) * 60.0]) for a, b in ends]
        d = rel[1] - rel[0]
        s = float(np.clip(-(rel[0] @ d) / (d @ d), 0.0, 1.0)) if d @ d > 0 else 0.0
        for t in (lo, hi, int(lo + round(s * (hi - lo)))):
            found = distance(t)
            if found is not None:
                best = min(best, found)
    return (best if counted else np.nan), counted


def check(losses: pd.DataFrame, meas: pd.DataFrame, max_gap_s: float) -> pd.DataFrame:
    """Per loss: the table's minimum, the raw plots' and their difference."""
    plots = {a: g.sort_values("time") for a, g in meas.groupby("aircraft_id", observed=True)}
    rows = []
    for _, loss in losses.iterrows():
        a, b = str(loss["aircraft_a"]), str(loss["aircraft_b"])
        raw, n = raw_minimum(plots[a], plots[b], loss["start"], loss["end"], max_gap_s)
        last = min(plots[a]["time"].max(), plots[b]["time"].max())
        rows.append({"aircraft_a": a, "aircraft_b": b, "start": loss["start"], "end": loss["end"],
                     "min_nm": loss["min_horizontal_nm"], "raw_min_nm": raw, "raw_pieces": n,
                     "difference_nm": loss["min_horizontal_nm"] - raw,
                     "after_last_plot_s": max((loss["start"] - last).total_seconds(), 0.0)})
    return pd.DataFrame(rows)


def main() -> None:
    from msdc.pipeline.jobs.common import tracker_inputs
    from msdc.pipeline.jobs.conflicts import ConflictOptions, conflict_job, text, validate

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--step", type=float, default=5.0)
    parser.add_argument("--max-report-gap", type=float, default=15.0)
    parser.add_argument("--losses", help="check the losses of this conflicts JSON instead of running the job")
    parser.add_argument("--out", help="write the per-loss comparison to this CSV")
    a = parser.parse_args()
    if not REAL.exists():
        sys.exit(f"{REAL} is not there: the real recordings are beside the repository in ../shared/real")
    with tempfile.TemporaryDirectory() as d:
        site = Path(d) / "bcn.toml"
        site.write_text(SITE)
        options = ConflictOptions(inputs=(str(REAL),), sensors=str(site), date=dt.date(2023, 5, 2),
                                  output=str(Path(d) / "c.csv"), step_s=a.step,
                                  max_report_gap_s=a.max_report_gap)
        _, meas, _ = tracker_inputs(options, validate(options), None, "the losses")
        if a.losses:
            doc = json.loads(Path(a.losses).read_text())
            losses = pd.DataFrame(doc["losses"])
            for c in ("start", "end"):
                losses[c] = pd.to_datetime(losses[c], utc=True)
        else:
            t0 = time.monotonic()
            result = conflict_job(options)
            print(text(result))
            print(f"job: {time.monotonic() - t0:.1f} s wall")
            losses = result.losses
    table = check(losses, meas, a.max_report_gap)
    pd.set_option("display.width", 200)
    print(table.to_string(float_format=lambda v: f"{v:.3f}"))
    have = table["raw_min_nm"].notna()
    agree = have & (table["difference_nm"].abs() <= AGREE_NM)
    print(f"{len(table)} losses; {int(have.sum())} with raw plots over their span, {int(agree.sum())} of "
          f"them within {AGREE_NM:g} NM of the raw minimum (median |difference| "
          f"{table.loc[agree, 'difference_nm'].abs().median():.3f} NM); "
          f"{int((table['after_last_plot_s'] > 0).sum())} begin after an aircraft's last plot")
    if a.out:
        table.to_csv(a.out, index=False)


if __name__ == "__main__":
    main()
