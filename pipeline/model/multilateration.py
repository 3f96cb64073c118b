"""CAT010 and CAT020 target reports to measurement rows: multilateration ("mlat") and surface movement
radar ("smr") reports as WGS-84 positions with their horizontal covariance.

Which reports are measurements: CAT010 target reports (I010/000 message type 1; the status messages, types
2-4, are not) whose I010/020 TYP says multilateration (0 SSR, 1 Mode S, 5 HF: "mlat") or a primary surface
radar (3 PSR: "smr"); the other CAT010 kinds (2 ADS-B, 4 magnetic loop, 6, 7, or no TYP) are left out and
counted. Every CAT020 report is multilateration. Sensor ids: "010:SAC/SIC:mlat" and "010:SAC/SIC:smr" (one
CAT010 SAC/SIC may carry both kinds), "020:SAC/SIC".

Position: I010/041 or I020/041 (WGS-84) when the report has it; else the Cartesian x/y (I010/042, I020/042:
metres east and north of the system's reference point, on the plane tangent to the ellipsoid there) placed
from the reference point that the sensor file's entry of that category, kind, SAC and SIC gives, at the
report's height when known (CAT020 geometric height, else the flight level) and on the tangent plane
otherwise, as radar x/y are (pipeline.model.geodesy.plane_to_geodetic); else (CAT010) the I010/040 polar
position from the same point. A report to place without an entry is left out and listed (``unplaced``).

Covariance (east, north): the report's own standard deviations (I010/500 DEVX, DEVY; I020/500 SDP X, Y)
squared, without a cross term (what I010/500 COVXY and I020/500 SDP "correlation XY" hold is not certain:
docs/decoding/editions.md); else the entry's sigma_m squared (a CAT010 entry's default: the A-SMGCS
requirement, pipeline.model.sensors.DEFAULT_SIGMA_M; the same for a CAT010 report placed by its own
WGS-84 position without an entry); else NaN (unknown).

Motion: heading is the direction of the velocity vector (I010/202, I020/202, east and north) when the
report has one, else the I010/200 track angle; ground speed is I010/200's, else the vector's length. The
real LEBL multilateration's I010/200 track angle does not follow its own velocity vector (median 90 deg
apart), while the vector follows its positions (docs/methods/lebl-hour.md).
"""

from __future__ import annotations

import datetime as dt
import math
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from msdc.pipeline.model.geodesy import M_PER_NM, flight_level_to_m, plane_to_geodetic
from msdc.pipeline.model.schema import coded_text
from msdc.pipeline.model.sensors import DEFAULT_SIGMA_M, reference_entries

# CAT010 I010/020 TYP -> sensor kind; the kinds not listed are no measurements of msdc's
TYP_KIND = {0: "mlat", 1: "mlat", 5: "mlat", 3: "smr"}
TYP_NAMES = {2: "ADS-B", 4: "magnetic loop", 6: "not defined", 7: "other types"}
TARGET_REPORT = 1  # I010/000 message type of a target report
KT_PER_MS = 3600.0 / M_PER_NM
UNPLACED_COLUMNS = ["category", "kind", "sac", "sic", "file", "records", "offset"]


@dataclass
class LocalRows:
    """CAT010/CAT020 measurement rows, one frame per category (measurement columns, not yet at the schema's
    dtypes), the reports left unplaced for want of a sensor-file entry (UNPLACED_COLUMNS), and the CAT010
    target reports of other kinds left out, counted by I010/020 TYP (-1: none)."""

    parts: list[pd.DataFrame]
    unplaced: pd.DataFrame = field(default_factory=lambda: pd.DataFrame(columns=UNPLACED_COLUMNS))
    other_kinds: dict[int, int] = field(default_factory=dict)


def _float(frame: pd.DataFrame, name: str) -> np.ndarray:
    return frame[name].to_numpy(float, na_value=np.nan) if name in frame else np.full(len(frame), np.nan)


def _int(frame: pd.DataFrame, name: str) -> np.ndarray:
    """An integer column as int64, -1 where absent."""
    if name not in frame:
        return np.full(len(frame), -1, np.int64)
    return frame[name].astype("Int64").fillna(-1).to_numpy(np.int64)


def report_kinds(frame: pd.DataFrame, category: int) -> tuple[np.ndarray, dict[int, int]]:
    """Per report its kind ("mlat", "smr" or "" when no measurement) and the CAT010 target reports of
    other kinds counted by TYP; CAT010 status messages are no reports (not counted)."""
    if category == 20:
        return np.full(len(frame), "mlat", dtype=object), {}
    report = _int(frame, "message_type") == TARGET_REPORT
    typ = _int(frame, "typ")
    kind = np.array([TYP_KIND.get(t, "") for t in range(-1, 8)], dtype=object)[np.clip(typ, -1, 7) + 1]
    kind = np.where(report, kind, "")
    other, counts = np.unique(typ[report & (kind == "")], return_counts=True)
    return kind, {int(t): int(n) for t, n in zip(other, counts, strict=True)}


def _entry_rows(frame: pd.DataFrame, category: int, kind: np.ndarray, sensors: pd.DataFrame | None
                ) -> pd.DataFrame:
    """Per report, its sensor-file entry (reference_entries' columns; NaN/None where it has none)."""
    entries = reference_entries(sensors)
    entries = entries[entries["category"] == category]
    keys = pd.DataFrame({"kind": kind, "sac": _int(frame, "sac"), "sic": _int(frame, "sic")})
    table = entries[["kind", "sac", "sic", "latitude", "longitude", "altitude_m", "sigma_m"]]
    table = table.astype({"sac": "int64", "sic": "int64", "kind": object})
    return keys.merge(table, on=["kind", "sac", "sic"], how="left", sort=False, validate="many_to_one")


def _sensor_ids(category: int, kind: np.ndarray, sac: np.ndarray, sic: np.ndarray, index: pd.Index
                ) -> pd.Series:
    """"010:SAC/SIC:kind" / "020:SAC/SIC" per report ("?" for a missing SAC or SIC), formatted once per
    distinct sensor."""
    keys = pd.DataFrame({"k": kind, "a": sac, "b": sic})
    codes = keys.groupby(["k", "a", "b"], sort=False).ngroup().to_numpy()
    first = keys.drop_duplicates()

    def one(k: str, a: int, b: int) -> str:
        pair = f"{a if a >= 0 else '?'}/{b if b >= 0 else '?'}"
        return f"{category:03d}:{pair}" + (f":{k}" if category == 10 else "")

    labels = [one(k, a, b) for k, a, b in first.itertuples(index=False)]
    return pd.Series(coded_text(codes, labels), index=index)


def _place(frame: pd.DataFrame, entry: pd.DataFrame, height_m: np.ndarray
           ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Latitude, longitude, the position's source item (0 "041", 1 "042", 2 "040", -1 none), whether a
    reference point was wanted and not found, and the height the position stands at."""
    lat, lon = _float(frame, "latitude"), _float(frame, "longitude")
    x_m, y_m = _float(frame, "x_m"), _float(frame, "y_m")
    rho_m, theta = _float(frame, "rho_m"), _float(frame, "theta_deg")
    wgs = np.isfinite(lat) & np.isfinite(lon)
    plane = ~wgs & np.isfinite(x_m) & np.isfinite(y_m)
    polar = ~wgs & ~plane & np.isfinite(rho_m) & np.isfinite(theta)
    ref_lat, ref_lon, ref_alt = (entry[c].to_numpy(float) for c in ("latitude", "longitude", "altitude_m"))
    has_ref = np.isfinite(ref_lat)
    wants = (plane | polar) & ~has_ref
    out_lat, out_lon = np.where(wgs, lat, np.nan), np.where(wgs, lon, np.nan)
    h = np.where(wgs, height_m, np.nan)
    if polar.any():  # on the plane tangent at the point, at the measured range and azimuth
        t = np.radians(theta)
        x_m, y_m = np.where(polar, rho_m * np.sin(t), x_m), np.where(polar, rho_m * np.cos(t), y_m)
    at = (plane | polar) & has_ref
    if at.any():
        out_lat[at], out_lon[at], h[at] = plane_to_geodetic(
            ref_lat[at], ref_lon[at], ref_alt[at], x_m[at] / M_PER_NM, y_m[at] / M_PER_NM, height_m[at])
    item = np.select([wgs, plane, polar], [0, 1, 2], -1)
    return out_lat, out_lon, np.where(at | wgs, item, -1), wants, h


def _one(frame: pd.DataFrame, category: int, sensors: pd.DataFrame | None, date: dt.date | None
         ) -> tuple[pd.DataFrame | None, pd.DataFrame, dict[int, int]]:
    """The rows of one category's frame, its unplaced reports and its other kinds (LocalRows' parts)."""
    from msdc.pipeline.model.measurements import _common, _labels  # one way of making the shared columns

    kind, other = report_kinds(frame, category)
    keep = kind != ""
    frame, kind = frame[keep], kind[keep]
    if not len(frame):
        return None, pd.DataFrame(columns=UNPLACED_COLUMNS), other
    entry = _entry_rows(frame, category, kind, sensors)
    geometric_m = _float(frame, "geometric_height_ft") * 0.3048
    fl_m = flight_level_to_m(_float(frame, "flight_level"))
    height_m = np.where(np.isfinite(geometric_m), geometric_m, fl_m)
    lat, lon, item, wants, h = _place(frame, entry, height_m)
    unplaced = _unplaced(frame, category, kind, wants)
    out = _common(frame, category, "mlat", date)
    out["sensor_kind"] = _labels(np.where(kind == "smr", 1, 0), ["mlat", "smr"], frame.index)
    out["sensor_id"] = _sensor_ids(category, kind, _int(frame, "sac"), _int(frame, "sic"), frame.index)
    # a primary radar sees no transponder: its reports' GBS bit (sent as 0) says nothing about the ground
    out["on_ground"] = out["on_ground"].mask(pd.Series(kind == "smr", index=frame.index))
    vx, vy = _float(frame, "vx_ms"), _float(frame, "vy_ms")
    moving = np.isfinite(vx) & np.isfinite(vy)
    vector_deg = np.degrees(np.arctan2(vx, vy)) % 360.0
    gs_kt = _float(frame, "ground_speed_kt")
    index = frame.index
    sigma_x, sigma_y = _float(frame, "sigma_x_m"), _float(frame, "sigma_y_m")
    own = np.isfinite(sigma_x) & np.isfinite(sigma_y)
    fallback = entry["sigma_m"].to_numpy(float)
    if category in DEFAULT_SIGMA_M:  # a report placed by its WGS-84 position may have no entry
        fallback = np.where(np.isfinite(fallback) | np.isfinite(entry["latitude"].to_numpy(float)), fallback,
                            DEFAULT_SIGMA_M[category])
    var_e = np.where(own, sigma_x**2, fallback**2)
    var_n = np.where(own, sigma_y**2, fallback**2)
    height_source = np.where(np.isfinite(geometric_m), 0, np.where(np.isfinite(fl_m), 1, 2))
    placed = np.where(np.isfinite(height_m), h, np.nan)
    arrays = {
        "heading_deg": np.where(moving, vector_deg, _float(frame, "track_angle_deg")),
        "ground_speed_kt": np.where(np.isfinite(gs_kt), gs_kt, np.hypot(vx, vy) * KT_PER_MS),
        "latitude": lat, "longitude": lon, "height_m": placed,
        "height_source": _labels(height_source, ["geometric", "flight_level", "none"], index),
        "position_item": _labels(item, ["041", "042", "040"], index),
        "cov_ee_m2": var_e, "cov_en_m2": np.where(np.isfinite(var_e) & np.isfinite(var_n), 0.0, np.nan),
        "cov_nn_m2": var_n,
    }
    out.update((k, v if isinstance(v, pd.Series) else pd.Series(v, index=index, copy=False))
               for k, v in arrays.items())
    ok = (np.isfinite(lat) & np.isfinite(lon) & (np.abs(lat) <= 90.0) & (np.abs(lon) <= 180.0)
          & out["time"].notna().to_numpy(bool))
    return pd.DataFrame({k: v[ok] for k, v in out.items()}, copy=False), unplaced, other


def _unplaced(frame: pd.DataFrame, category: int, kind: np.ndarray, wants: np.ndarray) -> pd.DataFrame:
    """The reports needing a reference point the sensor file lacks, per category, kind, SAC/SIC and file:
    how many and the first one's offset."""
    if not wants.any():
        return pd.DataFrame(columns=UNPLACED_COLUMNS)
    rows = frame[wants]
    table = pd.DataFrame({
        "category": category, "kind": kind[wants],
        "sac": rows["sac"].astype("Int64").to_numpy() if "sac" in rows else pd.NA,
        "sic": rows["sic"].astype("Int64").to_numpy() if "sic" in rows else pd.NA,
        "file": rows["file"].astype("string").to_numpy() if "file" in rows else pd.NA,
        "offset": rows["offset"].astype("Int64").to_numpy() if "offset" in rows else pd.NA})
    groups = table.groupby(["category", "kind", "sac", "sic", "file"], dropna=False, sort=False)
    return groups.agg(records=("offset", "size"), offset=("offset", "first")).reset_index()[UNPLACED_COLUMNS]


def local_rows(cat010: pd.DataFrame | None, cat020: pd.DataFrame | None, sensors: pd.DataFrame | None, *,
               date: dt.date | None = None) -> LocalRows:
    """The measurement rows of CAT010 and CAT020 frames (see the module docstring), CAT010 first."""
    parts, unplaced, other = [], [], {}
    for category, frame in ((10, cat010), (20, cat020)):
        if frame is None or not len(frame):
            continue
        rows, lost, kinds = _one(frame, category, sensors, date)
        if rows is not None and len(rows):
            parts.append(rows)
        if len(lost):
            unplaced.append(lost)
        for t, n in kinds.items():
            other[t] = other.get(t, 0) + n
    table = pd.concat(unplaced, ignore_index=True) if unplaced else pd.DataFrame(columns=UNPLACED_COLUMNS)
    return LocalRows(parts, table, other)


def other_kinds_warning(name: str, other: dict[int, int]) -> list[str]:
    """A warning naming the CAT010 target reports left out for their kind (TYP 2, 4, 6, 7 or none)."""
    if not other:
        return []
    parts = ", ".join(f"{n} of TYP {t} ({TYP_NAMES.get(t, 'none')})" if t >= 0 else f"{n} without I010/020"
                      for t, n in sorted(other.items()))
    return [f"{name}: CAT010 target reports left out of the measurements, not multilateration (TYP 0, 1, 5) "
            f"nor surface radar (TYP 3): {parts}"]


def unplaced_limit(n_reports: int) -> int:
    """How many reports of one sensor without a sensor-file entry are taken for damaged data (left out with
    a warning) rather than a sensor missing from the file: the radars' rule (sensors.STRAY_RADAR_*)."""
    from msdc.pipeline.model.sensors import STRAY_RADAR_RECORDS, STRAY_RADAR_SHARE

    return max(STRAY_RADAR_RECORDS, math.ceil(STRAY_RADAR_SHARE * n_reports))
