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
from msdc.pipeline.model.geodesy import ecef_to_enu, geodetic_to_ecef
from msdc.pipeline.model.measurements import build_measurements
from msdc.pipeline.model.sensors import read_sensors
from msdc.pipeline.quality.reference_offset import SURFACE_SPEED_KT, reference_offsets

ARP = (41.2969, 2.0785)
MAX_SPAN_S = 2.0  # ADS-B reports further apart than this are not interpolated between
MOVING_MS = 0.5  # an ADS-B segment slower than this (a stationary aircraft) gives no track direction
KT_MS = 1852.0 / 3600.0
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


def _counts(values: pd.Series) -> dict[int, int]:
    """How many of each value, as plain integers."""
    return {int(k): int(v) for k, v in values.value_counts().items()}


def contents(mlat: pd.DataFrame, smr: pd.DataFrame) -> None:
    for name, f in (("MLAT", mlat), ("SMR", smr)):
        reports = f[f["message_type"] == 1]
        print(f"{name}: {len(f):,} records: message types {_counts(f['message_type'])}, "
              f"TYP {_counts(reports['typ'])}; target reports without a position: "
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


def field_monitors(mlat: pd.DataFrame) -> None:
    """The multilateration's field monitors (fixed transponders: the addresses of the target reports with
    I010/020 RAB set), in its own x/y (metres from its reference point, whatever that point is): per address
    its reports, median and longest interval, and the standard deviation of x and of y about its mean
    position; pooled, the RMS of every report's x and y deviation from its address's mean."""
    reports = mlat[mlat["message_type"] == 1]
    address = reports["address"].astype(str)
    monitors = reports[address.isin(address[reports["rab"] == 1].unique())]
    by = monitors.groupby(monitors["address"].astype(str), observed=True)
    rows = []
    for name, f in by:
        dt_s = f["timestamp"].sort_values().diff().dt.total_seconds().dropna()
        rows.append({"address": name, "reports": len(f), "rab_set": int((f["rab"] == 1).sum()),
                     "interval_median_s": dt_s.median(), "longest_interval_s": dt_s.max(),
                     "sd_x_m": f["x_m"].std(), "sd_y_m": f["y_m"].std()})
    table = pd.DataFrame(rows)
    print(f"MLAT field monitors (I010/020 RAB set): {len(table)} addresses, {len(monitors):,} of its "
          f"{len(reports):,} target reports")
    print(table.to_string(index=False, float_format=lambda v: f"{v:.2f}"))
    dev = np.concatenate([monitors["x_m"] - by["x_m"].transform("mean"),
                          monitors["y_m"] - by["y_m"].transform("mean")])
    sd = table[["sd_x_m", "sd_y_m"]].to_numpy()
    print(f"  scatter per axis {sd.min():.1f} to {sd.max():.1f} m (standard deviation), pooled "
          f"{np.sqrt(np.mean(dev ** 2)):.1f} m")


def disagreement(meas: pd.DataFrame, max_span_s: float = MAX_SPAN_S) -> pd.DataFrame:
    """Multilateration minus ADS-B, one row per multilateration report that has an ADS-B report of its
    Mode S address at most ``max_span_s`` before and after it: the ADS-B position interpolated linearly in
    time between those two. Positions are east/north metres on the plane tangent at the multilateration's
    median position. ``distance_m`` is the horizontal distance; ``along_m`` its displacement along the
    direction of the two ADS-B positions (positive: the multilateration ahead) and ``across_m`` to the right
    of it, NaN where that segment is slower than MOVING_MS (a stationary aircraft has no direction);
    ``speed_kt`` is the multilateration's ground speed."""
    kind = meas["sensor_kind"].astype(str).to_numpy()
    mlat, adsb = meas[kind == "mlat"], meas[kind == "adsb"]
    lat0, lon0 = float(mlat["latitude"].median()), float(mlat["longitude"].median())

    def plane(f: pd.DataFrame) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        e, n, _ = ecef_to_enu(*geodetic_to_ecef(f["latitude"].to_numpy(float), f["longitude"].to_numpy(float),
                                                np.zeros(len(f))), lat0, lon0, 0.0)
        return f["time"].to_numpy("datetime64[ns]").astype("int64") / 1e9, e, n

    parts = []
    adsb_by = dict(tuple(adsb.groupby(adsb["address"].astype(str), observed=True)))
    for address, m in mlat.groupby(mlat["address"].astype(str), observed=True):
        a = adsb_by.get(address)
        if a is None or len(a) < 2:
            continue
        ta, ea, na = plane(a.sort_values("time"))
        tm, em, nm = plane(m)
        j = np.clip(np.searchsorted(ta, tm), 1, len(ta) - 1)  # ta[j - 1] < tm <= ta[j] inside the span
        span = ta[j] - ta[j - 1]
        ok = (tm >= ta[j - 1]) & (tm <= ta[j]) & (span <= max_span_s)
        w = (tm - ta[j - 1]) / np.maximum(span, 1e-9)
        de = em - (ea[j - 1] + w * (ea[j] - ea[j - 1]))
        dn = nm - (na[j - 1] + w * (na[j] - na[j - 1]))
        step = np.hypot(ea[j] - ea[j - 1], na[j] - na[j - 1])
        moving = step >= MOVING_MS * np.maximum(span, 1e-9)
        ue, un = (ea[j] - ea[j - 1]) / np.maximum(step, 1e-9), (na[j] - na[j - 1]) / np.maximum(step, 1e-9)
        parts.append(pd.DataFrame({
            "distance_m": np.hypot(de, dn), "along_m": np.where(moving, de * ue + dn * un, np.nan),
            "across_m": np.where(moving, de * un - dn * ue, np.nan),
            "speed_kt": m["ground_speed_kt"].to_numpy(float)})[ok])
    return pd.concat(parts, ignore_index=True)


def disagreement_table(pairs: pd.DataFrame) -> pd.DataFrame:
    """The surface (below SURFACE_SPEED_KT) and airborne rows of disagreement(): reports, median and 95th
    percentile distance; of the reports with a direction, the median along and across track, the median
    speed and the time of flight the median along track makes at that speed (``lead_s``)."""
    rows = []
    for name, part in (("surface", pairs[pairs["speed_kt"] < SURFACE_SPEED_KT]),
                       ("airborne", pairs[pairs["speed_kt"] >= SURFACE_SPEED_KT])):
        moving = part[part["along_m"].notna()]
        along_m, speed_ms = moving["along_m"].median(), moving["speed_kt"].median() * KT_MS
        rows.append({"": name, "reports": len(part), "median_m": part["distance_m"].median(),
                     "p95_m": part["distance_m"].quantile(0.95), "with_direction": len(moving),
                     "along_median_m": along_m, "across_median_m": moving["across_m"].median(),
                     "speed_median_ms": speed_ms, "lead_s": along_m / speed_ms})
    return pd.DataFrame(rows)


def _intervals(part: pd.DataFrame) -> np.ndarray:
    """The intervals (s) between one aircraft's consecutive reports, every aircraft of ``part``."""
    t = part["time"].astype("datetime64[ns, UTC]").array.asi8 / 1e9
    order = np.lexsort((t, part["aircraft_id"].astype(str).to_numpy()))
    ids, t = part["aircraft_id"].astype(str).to_numpy()[order], t[order]
    return np.diff(t)[ids[1:] == ids[:-1]]


def update_table(meas: pd.DataFrame, gap_s: float = 180.0, twice_s: float = 0.1) -> pd.DataFrame:
    """Per sensor, every aircraft pooled (in the air and on the surface: the Quality sheet splits them):
    its reports (of no identity too, as the Quality sheet's "reports"), then after de-duplication the
    median and 95th percentile of the intervals up to gap_s between one aircraft's consecutive reports, the
    gaps beyond it and the longest; before de-duplication, the intervals up to gap_s and those under twice_s
    (a target reported twice)."""
    rows = []
    for sensor, every in meas.groupby("sensor_id", observed=True, sort=True):
        joined = every[every["aircraft_id"].notna()]
        raw = _intervals(joined)
        raw = raw[raw <= gap_s]
        dt_s = _intervals(deduplicate(joined)[0])
        inside = dt_s[dt_s <= gap_s]
        rows.append({"sensor": sensor, "reports": len(every), "interval_median_s": np.median(inside),
                     "interval_p95_s": np.percentile(inside, 95), "gaps": int((dt_s > gap_s).sum()),
                     "longest_gap_s": dt_s.max() if (dt_s > gap_s).any() else np.nan,
                     "intervals_before_dedup": len(raw), f"under_{twice_s:g}_s": int((raw < twice_s).sum())})
    return pd.DataFrame(rows)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("real", nargs="?", default=str(Path(__file__).resolve().parents[2] / "shared" / "real"))
    ap.add_argument("--sensors", help="sensor file (default: both systems at the airport reference point)")
    args = ap.parse_args()
    real = Path(args.real)
    adsb, mlat, smr = decoded(real)
    contents(mlat, smr)
    field_monitors(mlat)
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
    table = disagreement_table(disagreement(meas))
    print(f"MLAT minus ADS-B interpolated between ADS-B reports at most {MAX_SPAN_S:g} s apart "
          f"(along/across: positive ahead/right, of reports moving at least {MOVING_MS:g} m/s):")
    print(table.to_string(index=False, float_format=lambda v: f"{v:.2f}"))
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
