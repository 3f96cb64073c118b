"""Predicted closest approach of each alert: where the pair's relative mean motion at the alert's start
takes them, flown straight on (positions, ground velocities and vertical rates from the tracks).

tracks: `aircraft_id, time, latitude, longitude, flight_level, speed_kt, track_deg, vertical_rate_fpm`.
Adds to an alerts frame `time_to_cpa_s` (from the alert's start; 0 when the pair is already diverging),
`cpa_time` (UTC), `cpa_horizontal_nm` and `cpa_vertical_ft`; NaN where a track is missing at the start.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from msdc.pipeline.conflict.geometry import FT_PER_FL, M_PER_NM, surface_ecef_m
from msdc.pipeline.conflict.pairs import _require
from msdc.pipeline.model.geodesy import M_PER_S_PER_KT
from msdc.pipeline.model.time import utc_frame

APPROACH_COLUMNS = ["time_to_cpa_s", "cpa_time", "cpa_horizontal_nm", "cpa_vertical_ft"]
TRACK_COLUMNS = ["aircraft_id", "time", "latitude", "longitude", "flight_level", "speed_kt", "track_deg",
                 "vertical_rate_fpm"]


def closest_approach(alerts: pd.DataFrame, tracks: pd.DataFrame) -> pd.DataFrame:
    """alerts (`aircraft_a, aircraft_b, start`, ...) with the predicted closest approach columns."""
    _require(alerts, ["aircraft_a", "aircraft_b", "start"], "alerts")
    _require(tracks, TRACK_COLUMNS, "tracks")
    alerts, tracks = utc_frame(alerts, ["start"], "alerts"), utc_frame(tracks, ["time"], "tracks")
    state = tracks[TRACK_COLUMNS].drop_duplicates(["aircraft_id", "time"]).set_index(["aircraft_id", "time"])
    a = state.reindex(pd.MultiIndex.from_arrays([alerts["aircraft_a"], alerts["start"]]))
    b = state.reindex(pd.MultiIndex.from_arrays([alerts["aircraft_b"], alerts["start"]]))
    t, horizontal_m, vertical_ft = relative_cpa(a, b)
    out = alerts.copy()
    out["time_to_cpa_s"] = t
    out["cpa_time"] = out["start"] + pd.to_timedelta(t, unit="s")
    out["cpa_horizontal_nm"] = horizontal_m / M_PER_NM
    out["cpa_vertical_ft"] = vertical_ft
    return out


def relative_cpa(a: pd.DataFrame, b: pd.DataFrame) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Time (s), horizontal (m) and vertical (ft) distance of closest horizontal approach of b relative
    to a, each flying straight at its ground velocity and vertical rate, in the local east-north-up plane
    at a (the points below the aircraft on the WGS-84 surface)."""
    lat = np.radians(a["latitude"].to_numpy(float))
    lon = np.radians(a["longitude"].to_numpy(float))
    d = (surface_ecef_m(b["latitude"].to_numpy(float), b["longitude"].to_numpy(float))
         - surface_ecef_m(a["latitude"].to_numpy(float), a["longitude"].to_numpy(float)))
    east_dir = np.stack([-np.sin(lon), np.cos(lon), np.zeros_like(lon)], axis=-1)
    north_dir = np.stack([-np.sin(lat) * np.cos(lon), -np.sin(lat) * np.sin(lon), np.cos(lat)], axis=-1)
    r = np.stack([(d * east_dir).sum(-1), (d * north_dir).sum(-1)], axis=-1)

    def velocity(x: pd.DataFrame) -> np.ndarray:
        speed = x["speed_kt"].to_numpy(float) * M_PER_S_PER_KT
        track = np.radians(x["track_deg"].to_numpy(float))
        return np.stack([speed * np.sin(track), speed * np.cos(track)], axis=-1)

    v = velocity(b) - velocity(a)
    vv = (v * v).sum(-1)
    with np.errstate(invalid="ignore", divide="ignore"):
        t = np.where(vv > 0.0, -(r * v).sum(-1) / vv, 0.0)
    t = np.where(np.isfinite(vv) & np.isfinite(r).all(-1), np.maximum(t, 0.0), np.nan)
    horizontal = np.hypot(*(r + v * t[:, None]).T)
    dz = (b["flight_level"].to_numpy(float) - a["flight_level"].to_numpy(float)) * FT_PER_FL
    rate = (b["vertical_rate_fpm"].to_numpy(float) - a["vertical_rate_fpm"].to_numpy(float)) / 60.0
    return t, horizontal, np.abs(dz + rate * t)
