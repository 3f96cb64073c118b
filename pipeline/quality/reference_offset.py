"""Where a multilateration system's or a surface radar's reference point really is: the offset of its
positions from a reference sensor's, on the aerodrome surface.

CAT010/CAT020 Cartesian positions are metres from the system's reference point, which the recording does
not give; the sensor file's point places them (pipeline.model.multilateration), so a wrong point shifts
every report by the same vector. Measured per sensor against a reference kind (multilateration against
ADS-B; surface radar against multilateration, else ADS-B): each report below SURFACE_SPEED_KT is paired
with the reference reports within MATCH_WINDOW_S of it of the same aircraft (``aircraft_id``), or, for a
report of no aircraft (a primary radar's, whose tracks join aircraft only once the point is right: see
pipeline.model.primary_tracks), with every moving reference report (MIN_SPEED_KT to SURFACE_SPEED_KT) within
MAX_OFFSET_M. The offset is the peak of the displacements' histogram (BIN_M bins: the one vector that
lines most pairs up; stationary and crossing traffic spread over the rest), refined by the median of the
pairs within REFINE_M of the peak, with a small rotation fitted about the sensor-file point (a north
misalignment) and the pairs' scatter about the fit. ``point_latitude``/``point_longitude`` is the sensor
file's point, ``corrected_latitude``/``corrected_longitude`` that point moved by minus the offset: where
the point should be for the two sensors to agree.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from msdc.pipeline.model.geodesy import ecef_to_enu, ecef_to_geodetic, enu_to_ecef, geodetic_to_ecef

SURFACE_SPEED_KT = 50.0  # faster reports are airborne or on a take-off roll: timing and height matter there
MIN_SPEED_KT = 5.0  # a report of no aircraft pairs with moving traffic only (parked aircraft repeat)
MATCH_WINDOW_S = 0.5
MAX_OFFSET_M = 3000.0
BIN_M = 10.0
REFINE_M = 40.0
MIN_PAIRS = 30  # fewer pairs near the peak say nothing
REFERENCE_KIND = {"mlat": ("adsb",), "smr": ("mlat", "adsb")}  # first kind present is the reference
OFFSET_COLUMNS = ["sensor_id", "reference", "pairs", "east_offset_m", "north_offset_m", "rotation_deg",
                  "scatter_m", "point_latitude", "point_longitude", "corrected_latitude",
                  "corrected_longitude"]
OFFSET_INPUTS = ["time", "sensor_kind", "sensor_id", "sac", "sic", "aircraft_id", "latitude", "longitude",
                 "ground_speed_kt"]


def _pairs(own: pd.DataFrame, ref: pd.DataFrame, origin: tuple[float, float, float]) -> np.ndarray:
    """Displacements (own - reference, east and north m, on the plane tangent at ``origin``) and the
    reference position, one row per pair: (d_east, d_north, ref_east, ref_north)."""
    from scipy.spatial import cKDTree

    def enu(f: pd.DataFrame) -> np.ndarray:
        lat, lon = f["latitude"].to_numpy(float), f["longitude"].to_numpy(float)
        e, n, _ = ecef_to_enu(*geodetic_to_ecef(lat, lon, np.full(len(f), origin[2])), *origin)
        return np.column_stack([e, n])

    t_own = own["time"].to_numpy("datetime64[ns]").astype("int64") / 1e9
    t_ref = ref["time"].to_numpy("datetime64[ns]").astype("int64") / 1e9
    t0 = float(min(t_own.min(), t_ref.min()))
    p_own, p_ref = enu(own), enu(ref)
    labels = pd.Index(own["aircraft_id"].dropna().unique().astype(str))
    ident_own = labels.get_indexer(own["aircraft_id"].astype(object).where(own["aircraft_id"].notna(), None))
    ident_ref = labels.get_indexer(ref["aircraft_id"].astype(object).where(ref["aircraft_id"].notna(), None))
    speed_ref = ref["ground_speed_kt"].to_numpy(float)
    moving_ref = (speed_ref >= MIN_SPEED_KT) & (speed_ref < SURFACE_SPEED_KT)
    scale = MAX_OFFSET_M / MATCH_WINDOW_S  # time as distance: the window as wide as the offsets sought
    a = cKDTree(np.column_stack([p_own, (t_own - t0) * scale]))
    b = cKDTree(np.column_stack([p_ref, (t_ref - t0) * scale]))
    found = a.sparse_distance_matrix(b, MAX_OFFSET_M * 1.5, output_type="ndarray")
    i, j = found["i"].astype(np.int64), found["j"].astype(np.int64)
    keep = np.abs(t_ref[j] - t_own[i]) <= MATCH_WINDOW_S
    keep &= np.where(ident_own[i] >= 0, ident_ref[j] == ident_own[i], moving_ref[j])
    i, j = i[keep], j[keep]
    return np.column_stack([p_own[i] - p_ref[j], p_ref[j]])


def _fit(pairs: np.ndarray) -> dict | None:
    """The histogram peak refined: pairs, east/north offset, rotation (deg, positive counter-clockwise:
    own = rotated reference + offset) and scatter; None with too few pairs near the peak."""
    edges = np.arange(-MAX_OFFSET_M, MAX_OFFSET_M + BIN_M, BIN_M)
    hist, xe, ye = np.histogram2d(pairs[:, 0], pairs[:, 1], bins=[edges, edges])
    i, j = np.unravel_index(int(hist.argmax()), hist.shape)
    peak = np.array([xe[i] + BIN_M / 2, ye[j] + BIN_M / 2])
    close = np.hypot(*(pairs[:, :2] - peak).T) <= REFINE_M
    if close.sum() < MIN_PAIRS:
        return None
    d, ref = pairs[close, :2], pairs[close, 2:]
    # small-angle similarity: d = t + a * (-north, east) of the reference position
    a = np.zeros((2 * len(d), 3))
    a[: len(d), 0], a[len(d):, 1] = 1.0, 1.0
    a[: len(d), 2], a[len(d):, 2] = -ref[:, 1], ref[:, 0]
    sol, *_ = np.linalg.lstsq(a, np.concatenate([d[:, 0], d[:, 1]]), rcond=None)
    offset = np.median(d, axis=0)
    resid = np.concatenate([d[:, 0], d[:, 1]]) - a @ sol
    return {"pairs": int(close.sum()), "east_offset_m": float(offset[0]), "north_offset_m": float(offset[1]),
            "rotation_deg": float(np.degrees(sol[2])),
            "scatter_m": float(np.median(np.hypot(resid[: len(d)], resid[len(d):])))}


def reference_offsets(meas: pd.DataFrame, sensors: pd.DataFrame | None = None) -> pd.DataFrame:
    """Per multilateration and surface radar sensor of ``meas``: its offset from the reference kind's
    positions and the corrected reference point (OFFSET_COLUMNS; see the module docstring). A sensor with
    too few pairs near the peak gets a row of NaN (nothing measured), not a guess."""
    from msdc.pipeline.model.sensors import reference_entries

    kind = meas["sensor_kind"].astype(str).to_numpy()
    speed = meas["ground_speed_kt"].to_numpy(float)
    surface = np.isfinite(speed) & (speed < SURFACE_SPEED_KT)
    entries = reference_entries(sensors)
    rows = []
    for sensor_id in sorted(set(meas["sensor_id"].astype(str)[np.isin(kind, list(REFERENCE_KIND))])):
        mine = (meas["sensor_id"].astype(str) == sensor_id).to_numpy(bool)
        own_kind = kind[mine][0]
        reference = next((k for k in REFERENCE_KIND[own_kind] if (kind == k).any()), None)
        point = _entry_point(entries, sensor_id)
        row = dict.fromkeys(OFFSET_COLUMNS, np.nan) | {"sensor_id": sensor_id, "reference": reference,
                                                       "pairs": 0}
        if point is not None:
            row["point_latitude"], row["point_longitude"] = point[0], point[1]
        origin = point or (float(np.median(meas.loc[mine, "latitude"])),
                           float(np.median(meas.loc[mine, "longitude"])), 0.0)
        if reference is not None:
            own = meas.loc[mine & surface, OFFSET_INPUTS]
            ref = meas.loc[(kind == reference) & surface, OFFSET_INPUTS]
            pairs = _pairs(own, ref, origin) if len(own) and len(ref) else np.zeros((0, 4))
            fit = _fit(pairs) if len(pairs) else None
            if fit is not None:
                row |= fit
                if point is not None:
                    x, y, z = enu_to_ecef(-fit["east_offset_m"], -fit["north_offset_m"], 0.0, *point)
                    lat, lon, _ = ecef_to_geodetic(x, y, z)
                    row["corrected_latitude"], row["corrected_longitude"] = float(lat), float(lon)
        rows.append(row)
    return pd.DataFrame(rows, columns=OFFSET_COLUMNS)


def _entry_point(entries: pd.DataFrame, sensor_id: str) -> tuple[float, float, float] | None:
    """The sensor file's point (latitude, longitude, altitude_m) of a "010:SAC/SIC:kind" or "020:SAC/SIC"
    sensor, None when the file has no entry for it."""
    parts = sensor_id.split(":")
    try:
        category = int(parts[0])
        sac, sic = (int(v) for v in parts[1].split("/"))
    except (IndexError, ValueError):  # no SAC/SIC ("010:?/?:mlat"): no entry can be its
        return None
    kind = parts[2] if len(parts) > 2 else "mlat"
    match = entries[(entries["category"] == category) & (entries["kind"] == kind) & (entries["sac"] == sac)
                    & (entries["sic"] == sic)]
    if match.empty:
        return None
    r = match.iloc[0]
    return float(r["latitude"]), float(r["longitude"]), float(r["altitude_m"])
