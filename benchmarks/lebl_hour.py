"""The real LEBL hour (../shared/real: ADS-B CAT021 0.23, multilateration and surface radar CAT010 of
Barcelona airport, 2016-05-10 22:00 to 00:01 UTC): the figures of docs/methods/lebl-hour.md.

Run by hand: ``python benchmarks/lebl_hour.py [../shared/real] [--sensors S.toml]``. Without --sensors both
CAT010 systems are placed from the airport reference point (41.2969 N, 2.0785 E), the first guess; the
offsets it prints give the corrected points (docs/methods/lebl-hour.md has the file they make).
"""

from __future__ import annotations

import argparse
import tempfile
import warnings
from pathlib import Path

import numpy as np
import pandas as pd

import msdc.asterix as asterix
from msdc.pipeline.correlate.correlation import correlate
from msdc.pipeline.model.dedup import deduplicate
from msdc.pipeline.model.measurements import build_measurements
from msdc.pipeline.model.sensors import read_sensors
from msdc.pipeline.quality.reference_offset import SURFACE_SPEED_KT, reference_offsets

ARP = (41.2969, 2.0785)
GUESS = f"""
[[sensor]]
name = "LEBL MLAT"
category = 10
kind = "mlat"
sac = 0
sic = 107
latitude = {ARP[0]}
longitude = {ARP[1]}
altitude_m = 53.0

[[sensor]]
name = "LEBL SMR"
category = 10
kind = "smr"
sac = 0
sic = 7
latitude = {ARP[0]}
longitude = {ARP[1]}
altitude_m = 53.0
"""


def decoded(real: Path) -> tuple[pd.DataFrame, pd.DataFrame, pd.DataFrame]:
    adsb = asterix.read(real / "adsb_v023_160510-lebl-220001.ast", editions={21: "0.23"}, date="2016-05-10")
    mlat = asterix.read(real / "mlat_160510-lebl-220001.ast", date="2016-05-10")
    smr = asterix.read(real / "smr_160510-lebl-220001.ast", date="2016-05-10")
    return adsb.frames[21], mlat.frames[10], smr.frames[10]


def contents(mlat: pd.DataFrame, smr: pd.DataFrame) -> None:
    for name, f in (("MLAT", mlat), ("SMR", smr)):
        reports = f[f["message_type"] == 1]
        print(f"{name}: {len(f):,} records: message types {f['message_type'].value_counts().to_dict()}, "
              f"TYP {reports['typ'].value_counts().to_dict()}; target reports without a position: "
              f"{int((reports['x_m'].isna() & reports['rho_m'].isna() & reports['latitude'].isna()).sum())}")
        status = f[f["message_type"] == 2]["time_of_day"].diff().dropna()
        print(f"  start-of-update-cycle messages every {status.median():.3f} s (median)")
    both = smr[smr["x_m"].notna() & smr["rho_m"].notna()]
    t = np.radians(both["theta_deg"].to_numpy())
    d = np.hypot(both["rho_m"] * np.sin(t) - both["x_m"], both["rho_m"] * np.cos(t) - both["y_m"])
    print(f"SMR I010/040 polar vs I010/042 Cartesian from one origin: max {d.max():.2f} m over {len(d):,}")
    moving = mlat[(mlat["message_type"] == 1) & (mlat["ground_speed_kt"] > 10)]
    vec = np.degrees(np.arctan2(moving["vx_ms"], moving["vy_ms"])) % 360
    apart = np.abs((vec - moving["track_angle_deg"] + 180) % 360 - 180)
    print(f"MLAT I010/200 track angle vs its I010/202 vector (moving, {len(moving):,}): median "
          f"{apart.median():.1f} deg apart")
    track = mlat[mlat["message_type"] == 1].sort_values(["track_number", "time_of_day"])
    step = track.groupby("track_number")[["x_m", "y_m", "time_of_day"]].diff()
    ok = ((step["time_of_day"] < 1.5) & (np.hypot(step["x_m"], step["y_m"]) > 8)
          & (track["ground_speed_kt"] > 10))
    motion = np.degrees(np.arctan2(step["x_m"][ok], step["y_m"][ok])) % 360
    vec = np.degrees(np.arctan2(track["vx_ms"][ok], track["vy_ms"][ok])) % 360
    tra = track["track_angle_deg"][ok]
    print(f"MLAT direction of its own successive positions vs I010/202 vector: median "
          f"{np.abs((motion - vec + 180) % 360 - 180).median():.1f} deg; vs I010/200 track angle: "
          f"{np.abs((motion - tra + 180) % 360 - 180).median():.1f} deg ({int(ok.sum()):,} steps)")


def update_table(meas: pd.DataFrame, gap_s: float = 180.0) -> pd.DataFrame:
    """Per sensor, every aircraft pooled (in the air and on the surface: the Quality sheet splits them):
    its reports (of no identity too, as the Quality sheet's "reports"), then after de-duplication the
    median and 95th percentile of the intervals up to gap_s between one aircraft's consecutive reports, the
    gaps beyond it and the longest."""
    rows = []
    for sensor, every in meas.groupby("sensor_id", observed=True, sort=True):
        part, _ = deduplicate(every[every["aircraft_id"].notna()])
        t = part["time"].astype("datetime64[ns, UTC]").array.asi8 / 1e9
        order = np.lexsort((t, part["aircraft_id"].astype(str).to_numpy()))
        ids, t = part["aircraft_id"].astype(str).to_numpy()[order], t[order]
        dt_s = np.diff(t)[ids[1:] == ids[:-1]]
        inside = dt_s[dt_s <= gap_s]
        rows.append({"sensor": sensor, "reports": len(every), "interval_median_s": np.median(inside),
                     "interval_p95_s": np.percentile(inside, 95), "gaps": int((dt_s > gap_s).sum()),
                     "longest_gap_s": dt_s.max() if (dt_s > gap_s).any() else np.nan})
    return pd.DataFrame(rows)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("real", nargs="?", default=str(Path(__file__).resolve().parents[2] / "shared" / "real"))
    ap.add_argument("--sensors", help="sensor file (default: both systems at the airport reference point)")
    args = ap.parse_args()
    real = Path(args.real)
    adsb, mlat, smr = decoded(real)
    contents(mlat, smr)
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(args.sensors) if args.sensors else Path(tmp) / "guess.toml"
        if not args.sensors:
            path.write_text(GUESS)
        sensors = read_sensors(path)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        meas = build_measurements(None, adsb, sensors, adsb_sigma_m=10.0,
                                  cat010=pd.concat([mlat, smr], ignore_index=True), date="2016-05-10")
    kinds = meas["sensor_kind"].astype(str)
    print("measurements:", kinds.value_counts().to_dict(), "; surface radar reports joined to an aircraft:",
          f"{meas.loc[kinds == 'smr', 'aircraft_id'].notna().mean():.1%}")
    print(update_table(meas).to_string(index=False))
    print("reference points (surface reports below", SURFACE_SPEED_KT, "kt):")
    print(reference_offsets(meas, sensors).to_string(index=False))
    for pairs in ("mlat-adsb", "smr-mlat"):
        run = correlate(meas, all_aircraft=True, pairs=pairs)
        s = pd.DataFrame([w.summary for w in run.windows])
        print(f"{pairs}: {len(s)} windows, {s['slots'].sum():,} slots; per-window median separation: median "
              f"{s['sep_median_m'].median():.1f} m, range {s['sep_median_m'].min():.1f}-"
              f"{s['sep_median_m'].max():.1f} m; ncc0 lat/lon median {s['ncc0_lat'].median():.4f}/"
              f"{s['ncc0_lon'].median():.4f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
