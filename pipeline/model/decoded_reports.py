"""The report selection over decoded records (``msdc decode`` and ``msdc stats``, which build no
measurements): each category's frame seen as the columns ``report_selection.select_reports`` reads.

- time: the record's UTC instant (``pipeline.model.time.absolute_time``: I048/140, I021/073... on the
  recording's day); sensor: its category and SAC/SIC ("048:20/129"; a CAT010 record has no kind here);
  flight level: its decoded ``flight_level``;
- position: its decoded WGS-84 ``latitude``/``longitude`` (CAT021, CAT010/CAT020 I010/041, CAT062...), a
  CAT048 plot's I048/040 range and azimuth placed from its radar's site in the sensor file at its flight
  level (as the measurements place it), else none: a Cartesian position without its system's reference
  point, or a radar the sensor file lacks, is left out by --area.
"""

from __future__ import annotations

import datetime as dt

import numpy as np
import pandas as pd

from msdc.pipeline.model.geodesy import flight_level_to_m, polar_to_geodetic
from msdc.pipeline.model.report_selection import ReportSelection, select_reports
from msdc.pipeline.model.sources import source_id
from msdc.pipeline.model.time import absolute_time

# decoded columns the view reads besides SAC/SIC and the times (what msdc stats adds with a selection)
VIEW_COLUMNS = ("flight_level", "latitude", "longitude", "rho_nm", "theta_deg")


def _floats(frame: pd.DataFrame, name: str) -> np.ndarray:
    """A decoded column as float64 (NaN for <NA>), all NaN when the frame lacks it."""
    if name not in frame:
        return np.full(len(frame), np.nan)
    return pd.to_numeric(frame[name], errors="coerce").astype("float64").to_numpy(float, na_value=np.nan)


def report_view(frame: pd.DataFrame, category: int, date: dt.date | None, sensors: pd.DataFrame | None
                ) -> pd.DataFrame:
    """The decoded records of one category as select_reports' columns (module docstring)."""
    sac = pd.Series(frame["sac"] if "sac" in frame else pd.NA, index=frame.index).astype("Int64")
    sic = pd.Series(frame["sic"] if "sic" in frame else pd.NA, index=frame.index).astype("Int64")
    pairs = pd.DataFrame({"sac": sac.to_numpy(), "sic": sic.to_numpy()})
    codes = pairs.groupby(["sac", "sic"], dropna=False, sort=False).ngroup().to_numpy()
    first = pairs.drop_duplicates()
    labels = np.array([source_id(category, a, b) for a, b in zip(first["sac"], first["sic"], strict=True)],
                      dtype=object)
    level = _floats(frame, "flight_level")
    lat, lon = _floats(frame, "latitude"), _floats(frame, "longitude")
    rho, theta = _floats(frame, "rho_nm"), _floats(frame, "theta_deg")
    height = flight_level_to_m(level)
    if category == 48 and sensors is not None and len(sensors) and np.isfinite(rho).any():
        sites = sensors[sensors["category"] == 48] if "category" in sensors else sensors
        for row in sites.itertuples(index=False):
            own = ((sac == row.sac) & (sic == row.sic)).fillna(False).to_numpy(bool)
            own &= np.isfinite(rho) & np.isfinite(theta)
            if own.any():
                lat[own], lon[own], _ = polar_to_geodetic(row.latitude, row.longitude, row.altitude_m,
                                                          rho[own], theta[own], height[own])
    return pd.DataFrame({"time": absolute_time(frame, date), "sensor_id": labels[codes] if len(codes) else [],
                         "flight_level": level, "latitude": lat, "longitude": lon, "height_m": height,
                         "rho_nm": rho, "theta_deg": theta}, index=frame.index)


def select_decoded(frames: dict[int, pd.DataFrame], selection: ReportSelection, date: dt.date | None,
                   sensors: pd.DataFrame | None, left_out: dict[str, int]
                   ) -> tuple[dict[int, pd.DataFrame], int]:
    """Each category's records the selection keeps, the counts of those left out added to ``left_out``
    per criterion; and how many records were read. ValueError naming the option when a time cannot be
    placed on the recording's day."""
    out, read = {}, 0
    for cat, frame in frames.items():
        keep, counts = select_reports(report_view(frame, cat, date, sensors), selection, date)
        for k, v in counts.items():
            left_out[k] = left_out.get(k, 0) + v
        read += len(frame)
        out[cat] = frame[keep].reset_index(drop=True) if not keep.all() else frame
    return out, read


__all__ = ["VIEW_COLUMNS", "report_view", "select_decoded"]
