"""Why the LEBL multilateration fails ED-117A's manoeuvring-area accuracy and false-report rows: its error
against ADS-B alone, split by the aircraft's speed, and the part of it along the track (the check of
docs/methods/evaluate.md's LEBL paragraph by another method than `msdc evaluate`).

The recordings are decoded with msdc.asterix; the plane, the ADS-B reference (by address, field monitors
and jumps left out, cut at 30 s gaps) and the area test are benchmarks/lebl_pd_independent.py's. Each
multilateration target report (TYP 1, with an address, inside a stretch of its aircraft's ADS-B, in the
manoeuvring area) is compared with the ADS-B position interpolated at its time; the reference speed is the
ADS-B displacement over the interval holding that time. A time offset between the two shows as an
along-track error growing with speed: along-track error / speed is printed as the implied lead (s), per
aircraft too (one multilateration clock serves them all: a lead that differs by aircraft is the latency of
that aircraft's ADS-B, version 0.23 carrying no time of applicability).

Run by hand: ``python benchmarks/lebl_mlat_speed.py [../shared/real]``.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
from lebl_pd_independent import (
    ORIGINS,
    ROOT,
    inside,
    lebl_frames,
    manoeuvring,
    plane,
    real_folder,
    reference,
    seconds,
)

FALSE_M = 60.0  # ED-117A's manoeuvring-area false-report distance
SLOW_MPS = 15.0  # taxiing below, take-off and landing runs above
LATE_S = 0.75  # an aircraft's median lead above it: its ADS-B is late (the others' lie within 0.7 s)


def errors(mlat: pd.DataFrame, ref) -> pd.DataFrame:
    """Per report inside its aircraft's ADS-B stretch: error east/north (m), along-track (m), speed (m/s)."""
    ox, oy = plane(*ORIGINS[107])
    px, py = mlat["x_m"].to_numpy(float) + ox, mlat["y_m"].to_numpy(float) + oy
    t, address = seconds(mlat), mlat["address"].astype(str).to_numpy()
    parts = []
    for a in np.unique(address):
        mine = np.flatnonzero(address == a)
        for tt, xx, yy in ref.get(a, []):
            on = mine[(t[mine] >= tt[0]) & (t[mine] <= tt[-1])]
            if not on.size:
                continue
            k = np.clip(np.searchsorted(tt, t[on], "right") - 1, 0, tt.size - 2)
            dt = np.maximum(tt[k + 1] - tt[k], 1e-3)
            vx, vy = (xx[k + 1] - xx[k]) / dt, (yy[k + 1] - yy[k]) / dt
            ex, ey = px[on] - np.interp(t[on], tt, xx), py[on] - np.interp(t[on], tt, yy)
            speed = np.hypot(vx, vy)
            along = np.where(speed > 0, (ex * vx + ey * vy) / np.maximum(speed, 1e-9), 0.0)
            parts.append(pd.DataFrame({"address": a, "x": px[on], "y": py[on], "error_m": np.hypot(ex, ey),
                                       "along_m": along, "speed_mps": speed,
                                       "adsb_dt_s": tt[k + 1] - tt[k]}))
    return pd.concat(parts, ignore_index=True)


def describe(label: str, e: pd.DataFrame) -> None:
    far = e["error_m"] > FALSE_M
    print(f"{label}: {len(e):,} reports, {e['address'].nunique()} aircraft; error p95 "
          f"{np.percentile(e['error_m'], 95):.1f} m, median {e['error_m'].median():.1f} m; beyond "
          f"{FALSE_M:g} m: {int(far.sum()):,} ({100 * far.mean():.2f} %)")
    moving = e[e["speed_mps"] > 1.0]
    if len(moving):
        lead = moving["along_m"] / moving["speed_mps"]
        print(f"    along-track error median {moving['along_m'].median():+.1f} m over {len(moving):,} moving "
              f"reports (implied lead median {lead.median():+.2f} s)")
    if far.any():
        f = e[far]
        print(f"    beyond {FALSE_M:g} m: along-track median {f['along_m'].median():+.1f} m (lead "
              f"{(f['along_m'] / f['speed_mps']).median():+.2f} s), across median "
              f"{np.sqrt(np.maximum(f['error_m'] ** 2 - f['along_m'] ** 2, 0)).median():.1f} m, speeds "
              f"{f['speed_mps'].quantile(0.05):.0f}-{f['speed_mps'].quantile(0.95):.0f} m/s (5-95 %), ADS-B "
              f"interval median {f['adsb_dt_s'].median():.2f} s (all moving: "
              f"{moving['adsb_dt_s'].median():.2f} s)")


def main() -> None:
    adsb, mlat, _ = lebl_frames(real_folder(__doc__))
    mlat = mlat[(mlat["typ"] == 1) & mlat["address"].notna() & mlat["x_m"].notna()]
    e = errors(mlat, reference(adsb))
    e = e[inside(e["x"].to_numpy(), e["y"].to_numpy(),
                 manoeuvring(ROOT / "docs" / "examples" / "lebl-areas.geojson"))]
    describe("manoeuvring area, all", e)
    describe(f"  below {SLOW_MPS:g} m/s", e[e["speed_mps"] < SLOW_MPS])
    fast = e[e["speed_mps"] >= SLOW_MPS]
    describe(f"  at {SLOW_MPS:g} m/s or more", fast)
    # one multilateration clock serves every aircraft: a lead that differs by aircraft is the ADS-B's latency
    per = fast.assign(lead_s=fast["along_m"] / fast["speed_mps"], far=fast["error_m"] > FALSE_M).groupby(
        "address").agg(reports=("far", "size"), beyond=("far", "sum"), lead_s=("lead_s", "median"),
                       speed_mps=("speed_mps", "median")).sort_values("lead_s", ascending=False)
    print(f"\nper aircraft at {SLOW_MPS:g} m/s or more (median implied lead):")
    print(per.to_string(float_format=lambda v: f"{v:.2f}"))
    late = per.index[per["lead_s"] > LATE_S]
    print(f"aircraft with a lead over {LATE_S:g} s: {len(late)} of {len(per)}, holding "
          f"{int(per.loc[late, 'beyond'].sum())} of the {int(per['beyond'].sum())} reports beyond "
          f"{FALSE_M:g} m")
    describe("manoeuvring area without them", e[~e["address"].isin(late)])


if __name__ == "__main__":
    main()
