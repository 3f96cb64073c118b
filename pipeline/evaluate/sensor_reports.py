"""The reports of a sensor under test, as the requirement functions take them: its measurement rows (every
report, identified or not, repeats kept: a repeat is the sensor's own doing) on the reference's clock
(``t_s``), with the radar's code validity and warning bits joined from the decoded CAT048 frame; the
evaluation's Sensor of each (site, coverage limits, north markers) and the preset types a sensor kind
can be judged by."""

from __future__ import annotations

import numpy as np
import pandas as pd

from msdc.pipeline.evaluate.coverage import Sensor, sensor_from_entry
from msdc.pipeline.model.schema import equals_text
from msdc.pipeline.model.time import absolute_time, seconds_since

# decoded columns the requirements read besides the measurements: Mode 3/A and Mode C validity and garble
# bits (CAT001, 010, 020 and 048 carry them), and of CAT048 only its I048/030 warning codes (split plots)
# and detection type (PSR/SSR): other categories' warning codes and TYP mean other things
VALIDITY_COLUMNS = ("mode3a_v", "mode3a_g", "flight_level_v", "flight_level_g")
RADAR_EXTRA_COLUMNS = (*VALIDITY_COLUMNS, "warning_codes", "typ")
RADAR_CATEGORY = 48


def joined_columns(category: int) -> tuple[str, ...]:
    """The decoded columns joined to a sensor's reports of this category."""
    return RADAR_EXTRA_COLUMNS if category == RADAR_CATEGORY else VALIDITY_COLUMNS


# measurement columns the requirements read
REPORT_COLUMNS = ("sensor_id", "sensor_kind", "aircraft_id", "latitude", "longitude", "height_m",
                  "flight_level", "mode3a", "address", "callsign", "track_number", "ground_speed_kt",
                  "heading_deg", "on_ground", "rho_nm", "theta_deg", "file", "offset")
# the preset sensor types (presets.SENSOR_TYPES) each measurement sensor kind may be judged by
KIND_TYPES: dict[str, tuple[str, ...]] = {"radar": ("ssr", "mode_s", "psr"), "adsb": ("adsb",),
                                          "mlat": ("mlat", "wam"), "smr": ("smr",), "tracker": ("tracker",)}
TRACKER_CATEGORY = 62  # system tracks: judged from their decoded frame (they are no measurement)
# decoded CAT062 columns a tracker's reports take (besides the common ones: time, sac, sic, offset)
TRACKER_COLUMNS = ("latitude", "longitude", "flight_level", "mode3a", "mode3a_v", "mode3a_g", "address",
                   "callsign", "track_number", "vx_ms", "vy_ms", "cst")
SERVICE_CATEGORIES = (34, 2)  # radar service messages: the north markers give the scan period
NORTH_MARKER = 1  # CAT034 message type 1 (CAT002: 1 too): north marker


def judged_by(kind: str, sensor_types: tuple[str, ...]) -> bool:
    """Whether a preset for these sensor types applies to a sensor of this measurement kind."""
    return bool(set(KIND_TYPES.get(kind, ())) & set(sensor_types))


def sensor_reports(meas: pd.DataFrame, sensor_id: str, epoch: pd.Timestamp,
                   radar_frame: pd.DataFrame | None = None,
                   columns: tuple[str, ...] = RADAR_EXTRA_COLUMNS) -> pd.DataFrame:
    """The sensor's reports with ``t_s`` (seconds from ``epoch``) and ``columns`` joined from its decoded
    frame (``radar_frame``, of the sensor's category) by file and offset (absent columns stay absent: then
    validity is not judged)."""
    rows = meas[equals_text(meas["sensor_id"], sensor_id)]
    cols = [c for c in REPORT_COLUMNS if c in rows.columns]
    out = pd.DataFrame({c: rows[c].to_numpy() if c != "aircraft_id" else rows[c].astype(object).to_numpy()
                        for c in cols})
    for c in ("mode3a", "address", "callsign", "sensor_id", "sensor_kind", "file"):
        if c in out:
            out[c] = out[c].astype(object).where(out[c].notna(), None)
    out.insert(0, "t_s", seconds_since(rows["time"], epoch))
    extra = [c for c in columns if radar_frame is not None and c in radar_frame.columns]
    if extra and {"file", "offset"} <= set(out.columns) and {"file", "offset"} <= set(radar_frame.columns):
        # the decoded records at the sensor's offsets only (the frame holds every radar's): the same join
        mine = radar_frame["offset"].isin(out["offset"].dropna().unique()).to_numpy(bool)
        right = radar_frame.loc[mine, ["file", "offset", *extra]].copy()
        right["file"] = right["file"].astype(str)
        right = right.drop_duplicates(["file", "offset"])
        left = out.assign(file=out["file"].astype(str), offset=out["offset"].astype("int64"))
        joined = left.merge(right.assign(offset=right["offset"].astype("int64")), on=["file", "offset"],
                            how="left", sort=False)
        for c in extra:
            out[c] = joined[c].to_numpy()
    return out.sort_values("t_s", kind="stable", ignore_index=True)


def field_monitors(meas: pd.DataFrame, frames: dict[int, pd.DataFrame]) -> set[str]:
    """The aircraft ids of field monitors (fixed transponders): those with a report whose decoded record
    sets RAB (I048/020, I010/020, I021/040), matched to the measurements by file and offset."""
    keys = []
    for frame in frames.values():
        if frame is None or "rab" not in frame.columns or not {"file", "offset"} <= set(frame.columns):
            continue
        hit = frame[pd.to_numeric(frame["rab"], errors="coerce").eq(1).fillna(False).to_numpy(bool)]
        keys.append(pd.DataFrame({"file": hit["file"].astype(str).to_numpy(object),
                                  "offset": hit["offset"].astype("int64").to_numpy()}))
    if not keys or not {"file", "offset", "aircraft_id"} <= set(meas.columns):
        return set()
    said = pd.concat(keys, ignore_index=True).drop_duplicates()
    if said.empty:
        return set()
    left = pd.DataFrame({"file": meas["file"].astype(str).to_numpy(object),
                         "offset": meas["offset"].astype("int64").to_numpy(),
                         "aircraft_id": meas["aircraft_id"].astype(object).to_numpy()})
    hit = left.merge(said, on=["file", "offset"], how="inner")["aircraft_id"].dropna()
    return set(hit.astype(str))


# A fixed test transponder whose records do not set RAB (the real Barcelona hour's 344045: 899 plots, RAB 0)
# is known by its Mode 3/A code 7777 (ICAO Annex 10 Vol IV and Doc 4444 reserve it for transponders on the
# ground used to monitor the radar) and by standing still: an aircraft squawking 7777 in flight (a military
# interception) moves, a parked one squawks its own code. Barcelona's monitor: 95 % of plots within 3.1 m.
MONITOR_MODE3A = "7777"
MONITOR_SPREAD_M = 50.0  # 95 % of its reports within this of their median position
MONITOR_MIN_REPORTS = 10


def fixed_7777(meas: pd.DataFrame) -> dict[str, float]:
    """The aircraft ids of field monitors that do not set RAB: every report that carries a Mode 3/A code
    says 7777, at least MONITOR_MIN_REPORTS of them, 95 % within MONITOR_SPREAD_M of their median
    position; each with that 95 % distance (m)."""
    from msdc.pipeline.model.geodesy import distance_m

    if not {"aircraft_id", "mode3a", "latitude", "longitude"} <= set(meas.columns) or meas.empty:
        return {}
    code = meas["mode3a"].astype("string")
    ids = meas["aircraft_id"].astype("string")
    coded = code.notna() & ids.notna()
    seven = code.eq(MONITOR_MODE3A).fillna(False)
    all_seven = seven[coded].groupby(ids[coded]).agg(["all", "size"])
    candidates = all_seven.index[all_seven["all"] & all_seven["size"].ge(MONITOR_MIN_REPORTS)]
    out = {}
    for aid in candidates:
        rows = meas[ids.eq(aid).fillna(False).to_numpy(bool)]
        lat, lon = rows["latitude"].to_numpy(float), rows["longitude"].to_numpy(float)
        fine = np.isfinite(lat) & np.isfinite(lon)
        if fine.sum() < MONITOR_MIN_REPORTS:
            continue
        d = distance_m(np.median(lat[fine]), np.median(lon[fine]), lat[fine], lon[fine])
        p95 = float(np.percentile(d, 95))
        if p95 <= MONITOR_SPREAD_M:
            out[str(aid)] = p95
    return out


def tracker_ids(frame: pd.DataFrame | None) -> list[str]:
    """The sensor ids (062:SAC/SIC) of the trackers in a decoded CAT062 frame."""
    if frame is None or not len(frame):
        return []
    pairs = frame[["sac", "sic"]].dropna().drop_duplicates().astype(int).sort_values(["sac", "sic"])
    return [f"{TRACKER_CATEGORY:03d}:{a}/{b}" for a, b in pairs.itertuples(index=False)]


def tracker_reports(frame: pd.DataFrame, sensor_id: str, date, epoch: pd.Timestamp) -> pd.DataFrame:
    """A tracker's track updates as test reports: ``time`` (UTC) and ``t_s`` (seconds from ``epoch``),
    ``sensor_id`` and the TRACKER_COLUMNS the frame has."""
    from msdc.pipeline.model.report_selection import sensor_parts

    part = sensor_parts([sensor_id]).iloc[0]
    rows = frame[(pd.to_numeric(frame["sac"], errors="coerce") == part["sac"]).to_numpy(bool)
                 & (pd.to_numeric(frame["sic"], errors="coerce") == part["sic"]).to_numpy(bool)]
    time = absolute_time(rows, date)
    out = pd.DataFrame({"t_s": seconds_since(time, epoch), "time": time.to_numpy(), "sensor_id": sensor_id,
                        "sensor_kind": "tracker", "sac": int(part["sac"]), "sic": int(part["sic"])})
    for c in (*TRACKER_COLUMNS, "file", "offset"):
        if c in rows.columns:
            values = rows[c].to_numpy()
            out[c] = values.astype(object) if c in ("mode3a", "address", "callsign", "file") else values
    for c in ("mode3a", "address", "callsign"):
        if c in out:
            out[c] = out[c].where(pd.notna(out[c]), None)
    ok = np.isfinite(out["t_s"].to_numpy(float))
    return out[ok].sort_values("t_s", kind="stable", ignore_index=True)


def north_markers_s(frames: dict[int, pd.DataFrame], sac: int, sic: int, date, epoch: pd.Timestamp
                    ) -> np.ndarray | None:
    """The radar's north-marker times (seconds from ``epoch``) from CAT034 (else CAT002) service messages;
    None when the inputs hold none."""
    for cat in (34, 2):
        f = frames.get(cat)
        if f is None or not len(f) or "message_type" not in f.columns:
            continue
        mine = f[(pd.to_numeric(f["sac"], errors="coerce") == sac).to_numpy(bool)
                 & (pd.to_numeric(f["sic"], errors="coerce") == sic).to_numpy(bool)
                 & (pd.to_numeric(f["message_type"], errors="coerce") == NORTH_MARKER).to_numpy(bool)]
        if len(mine) >= 2:
            t = seconds_since(absolute_time(mine, date), epoch)
            t = np.sort(t[np.isfinite(t)])
            return t if t.size >= 2 else None
    return None


def evaluation_sensor(sensor_id: str, reports: pd.DataFrame, entry: dict | None,
                      north_markers: np.ndarray | None = None) -> tuple[Sensor, str]:
    """The evaluation's Sensor: the sensor file's site and coverage limits when it declares the sensor,
    else (ADS-B, no site) a point at the middle of its reports, with a note saying so."""
    if entry is not None:
        return sensor_from_entry({**entry, "name": sensor_id}, north_markers), ""
    lat = float(np.nanmedian(reports["latitude"].to_numpy(float))) if len(reports) else 0.0
    lon = float(np.nanmedian(reports["longitude"].to_numpy(float))) if len(reports) else 0.0
    note = (f"{sensor_id} has no site in the sensor file: its coverage is estimated around the middle of its "
            f"reports ({lat:.4f}, {lon:.4f})")
    return Sensor(lat, lon, 0.0, name=sensor_id), note
