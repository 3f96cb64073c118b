"""Decoded CAT048/CAT021/CAT010/CAT020 frames to one measurement frame (pipeline.model.schema), and
aircraft selection.

Radar slant range and azimuth (I048/040, else x/y of I048/042) become WGS-84 positions from the radar site
at the height of the flight level; ADS-B positions come from I021/131 or /130; multilateration and surface
radar reports (CAT010, CAT020) from their WGS-84 position or their x/y from the system's reference point
(pipeline.model.multilateration). Each row gets its absolute
UTC ``time``, its sensor, its aircraft identity (pipeline.model.identity) and its horizontal position
covariance. Rows without a position or a time are dropped, and so are ADS-B positions no aircraft can have
(latitude beyond 90 deg or longitude beyond 180 deg: damaged bytes; ``impossible_positions`` names them).
"""

from __future__ import annotations

import datetime as dt
import math
import warnings
from pathlib import Path

import numpy as np
import pandas as pd

from msdc.asterix.reader import parse_date
from msdc.pipeline.meta import ADSB_SIGMA_RANGE_M  # also the commands' --adsb-sigma range
from msdc.pipeline.model.coverage import coverage_warnings, out_of_coverage
from msdc.pipeline.model.geodesy import (
    enu_basis,
    flight_level_to_m,
    geodetic_to_ecef,
    plane_to_geodetic,
    polar_to_geodetic,
)
from msdc.pipeline.model.heap import release_free_memory
from msdc.pipeline.model.identity import identify, normalise_address, normalise_callsign, refused_warnings
from msdc.pipeline.model.schema import (
    coded_text,
    column_names,
    concat_columns,
    conform,
    empty_measurements,
    text_categorical,
    validate,
)
from msdc.pipeline.model.sensors import (
    UnknownRadar,
    UnknownReferencePoint,
    check_table,
    read_sensors,
    sensor_sites,
)
from msdc.pipeline.model.sources import source_id
from msdc.pipeline.model.time import absolute_time

__all__ = ["DECODED_COLUMNS", "IdentityWarning", "LeftOutWarning", "NACP_95_M", "OffEarthWarning",
           "OutOfCoverageWarning", "UnknownRadar", "UnknownReferencePoint", "adsb_measurements",
           "build_measurements", "finish_measurements", "impossible_positions", "impossible_time_rows",
           "impossible_times", "local_measurement_rows",
           "measurement_rows",
           "nacp_sigma_m", "normalise_address", "normalise_callsign", "off_earth_rows", "on_ground",
           "radar_measurements", "select", "sensor_id"]

# The decoded CAT048/CAT021/CAT010/CAT020 columns build_measurements reads (besides sac, sic, time_of_day,
# day, timestamp and offset, which every decoded frame has): jobs decode only these (asterix.read(columns=))
DECODED_COLUMNS = ("flight_level", "ground_speed_kt", "callsign", "address", "mode3a", "track_number",
                   "heading_deg", "rho_nm", "theta_deg", "x_nm", "y_nm", "track_angle_deg", "latitude",
                   "longitude", "nucp_nic", "fom_pa", "nacp", "nucr_nacv", "sil", "mops_version",
                   "geometric_height_ft", "gbs", "flight_status", "rab", "message_type", "typ", "sim",
                   "rho_m", "x_m", "y_m", "vx_ms", "vy_ms", "sigma_x_m", "sigma_y_m")

# Columns worked out over the whole run by finish_measurements, and the built columns each is made from
DERIVED_INPUTS = {"aircraft_id": ("address", "callsign", "mode3a", "time", "latitude", "longitude",
                                   "sensor_kind", "sensor_id", "track_number"),
                  "sigma_major_m": ("cov_ee_m2", "cov_en_m2", "cov_nn_m2")}

# Where a report came from: finish_measurements names them in its out-of-coverage warning, so a job that
# builds only some columns keeps these until then (row_columns) and drops them after
COVERAGE_PLACE = ("file", "offset")


class OffEarthWarning(UserWarning):
    """build_measurements left out ADS-B reports whose position is off the Earth (damaged bytes)."""


class OutOfCoverageWarning(UserWarning):
    """build_measurements left out ADS-B reports beyond any ground station's reach (model.coverage)."""


class LeftOutWarning(UserWarning):
    """build_measurements left out CAT010 target reports of another kind than multilateration or surface
    radar, CAT010/CAT020 reports of a sensor without reference point (too few to stop the run: damage), or
    records that measure no real aircraft (NO_PLOT_REASONS)."""


class IdentityWarning(UserWarning):
    """build_measurements kept reports from the aircraft their Mode 3/A code names: beyond its reach
    (model.identity, rule 4)."""


# What each category's frame must have for any row to be built: a time, and a position
_TIME_COLUMNS = ("time_of_day", "timestamp")  # either
_POSITION_COLUMNS = {48: (("rho_nm", "theta_deg"), ("x_nm", "y_nm")), 21: (("latitude", "longitude"),),
                     10: (("latitude", "longitude"), ("x_m", "y_m"), ("rho_m", "theta_deg")),
                     20: (("latitude", "longitude"), ("x_m", "y_m"))}

# I048/230 STAT codes (CAT048 1.27-1.32 alike): 0 and 2 "aircraft airborne", 1 and 3 "aircraft on ground";
# 4 and 5 "airborne or on ground", 6 unassigned, 7 "unknown" say nothing
STAT_AIRBORNE = (0, 2)
STAT_ON_GROUND = (1, 3)

# Records that measure no real aircraft: I048/020 TYP 0 "no detection" (an update of the radar's own tracker,
# a coasted or primary-only track, with no plot behind it) and SIM 1 (I048/020, I021/040: a simulated target
# report). Left out of the measurements and counted (no_plot_counts), as CAT010's other kinds are.
NO_PLOT_REASONS = {"typ0": "without a plot (I048/020 TYP 0, no detection: the radar tracker's own updates)",
                   "sim": "simulated (SIM 1)"}


def no_plot_masks(frame: pd.DataFrame, category: int) -> dict[str, np.ndarray]:
    """Per NO_PLOT_REASONS key, the records of a decoded CAT048 or CAT021 frame it leaves out."""
    def flag(name: str, value: int) -> np.ndarray:
        if name not in frame:
            return np.zeros(len(frame), bool)
        return frame[name].astype("Int64").eq(value).fillna(False).to_numpy(bool)

    typ0 = flag("typ", 0) if category == 48 else np.zeros(len(frame), bool)
    return {"typ0": typ0, "sim": flag("sim", 1) & ~typ0}


def no_plot(frame: pd.DataFrame, category: int) -> np.ndarray:
    """The records of a decoded CAT048 or CAT021 frame that measure no real aircraft (NO_PLOT_REASONS)."""
    masks = no_plot_masks(frame, category)
    return masks["typ0"] | masks["sim"]


def no_plot_counts(frame: pd.DataFrame | None, category: int, counts: dict | None = None) -> dict:
    """``counts`` (a new dict when None) with the frame's left-out records added, keyed (file, category,
    reason): the file by the frame's ``file`` column, None without one."""
    counts = {} if counts is None else counts
    if frame is None or not len(frame):
        return counts
    files = frame["file"].astype(str).to_numpy() if "file" in frame else np.full(len(frame), None, object)
    for reason, mask in no_plot_masks(frame, category).items():
        if mask.any():
            for name, n in pd.Series(files[mask]).value_counts(dropna=False, sort=False).items():
                key = (name, category, reason)
                counts[key] = counts.get(key, 0) + int(n)
    return counts


def no_plot_warning(counts: dict, name: str = "the inputs") -> list[str]:
    """Per file, the warning naming its records left out for being no plot of a real target
    (no_plot_counts; ``name`` for those of no file)."""
    by_file: dict = {}
    order = list(NO_PLOT_REASONS)
    for (file, cat, reason), n in sorted(counts.items(), key=lambda kv: (str(kv[0][0]), kv[0][1],
                                                                          order.index(kv[0][2]))):
        records = f"record{'s' * (n != 1)}"
        by_file.setdefault(file, []).append(f"{n:,} CAT{cat:03d} {records} {NO_PLOT_REASONS[reason]}")
    return [f"{name if file is None else file}: {' and '.join(parts)} left out of the measurements: they are "
            "no plot of a real target" for file, parts in by_file.items()]


# DO-260B NACp: 95 % horizontal position accuracy bound (EPU) in metres; 0 = unknown
NACP_95_M = {11: 3.0, 10: 10.0, 9: 30.0, 8: 92.6, 7: 185.2, 6: 555.6, 5: 926.0, 4: 1852.0, 3: 3704.0,
             2: 7408.0, 1: 18520.0}
_NACP_95_BY_CODE = np.array([NACP_95_M.get(k, np.nan) for k in range(16)])  # NaN: 0 and codes 12-15
# 95 % of a circular 2-D Gaussian lies within sqrt(-2 ln 0.05) = 2.4477 sigma (the Rayleigh 95th percentile);
# every 95 % bound (NACp, NACv / NUCr) becomes a per-axis sigma by it, here and in pipeline.track.covariance
CIRCULAR_95_PER_SIGMA = math.sqrt(-2.0 * math.log(0.05))


def sensor_id(category: int, sac, sic) -> pd.Series:
    """Sensor ids "CCC:SAC/SIC" (e.g. "048:25/201"; SAC/SIC missing shows as "?") as the schema's
    categorical text, formatted once per distinct pair."""
    sac, sic = pd.Series(sac).astype("Int64"), pd.Series(sic).astype("Int64")
    a = sac.to_numpy(dtype=np.int64, na_value=-1)
    b = sic.to_numpy(dtype=np.int64, na_value=-1)
    if ((sac < 0) | (sac >= 1 << 20) | (sic < 0) | (sic >= 1 << 20)).any():  # beyond any SAC/SIC byte
        a, b = pd.factorize(sac)[0], pd.factorize(sic)[0]  # numbered to fit the key, a missing one -1
    # one integer per pair (a missing SAC or SIC its own value), each pair formatted once
    _, first, row_pair = np.unique((a + 1) * (1 << 21) + (b + 1), return_index=True, return_inverse=True)
    labels = [source_id(category, sac.iloc[i], sic.iloc[i]) for i in first]
    return pd.Series(coded_text(row_pair, labels), index=sac.index)


def _text(frame: pd.DataFrame, name: str) -> pd.Series:
    """A decoded text column as the schema's categorical (all <NA> when the frame lacks it)."""
    if name in frame:
        return text_categorical(frame[name])
    return pd.Series(coded_text(np.full(len(frame), -1), []), index=frame.index)


def _labels(choice: np.ndarray, labels: list[str], index: pd.Index) -> pd.Series:
    """Per row, ``labels[choice]`` as categorical text (one of a few fixed labels)."""
    return pd.Series(coded_text(choice, labels), index=index)


def _column(frame: pd.DataFrame, name: str, dtype: str = "float64") -> pd.Series:
    if name in frame:
        return frame[name].astype(dtype)
    return pd.Series(np.nan, index=frame.index).astype(dtype)


def _common(frame: pd.DataFrame, category: int, kind: str, date: dt.date | None) -> dict[str, pd.Series]:
    """The time, sensor, identity, kinematics and provenance columns of both sensors, by name (one frame is
    made of them at the end: adding columns to a frame one by one costs more than the columns)."""
    out = {"time": absolute_time(frame, date)}
    out["sac"], out["sic"] = _column(frame, "sac", "Int64"), _column(frame, "sic", "Int64")
    out["sensor_id"] = sensor_id(category, out["sac"], out["sic"])
    out["sensor_kind"] = _labels(np.zeros(len(frame), np.int64), [kind], frame.index)
    out["flight_level"] = _column(frame, "flight_level")
    out["ground_speed_kt"] = _column(frame, "ground_speed_kt")
    out["on_ground"] = on_ground(frame, category)
    for name, norm in (("callsign", normalise_callsign), ("address", normalise_address)):
        out[name] = norm(text_categorical(frame[name])) if name in frame else _text(frame, name)
    out["mode3a"] = _text(frame, "mode3a")
    out["track_number"] = _column(frame, "track_number", "Int64")
    out["file"] = _text(frame, "file")
    out["offset"] = _column(frame, "offset", "Int64")
    return out


def on_ground(frame: pd.DataFrame, category: int) -> pd.Series:
    """Whether each decoded report says the aircraft is on the surface (nullable boolean): CAT021 by I021/040
    GBS (set: on ground; CAT010 and CAT020 by I010/020, I020/020 GBS alike), CAT048 by I048/230 STAT
    (STAT_ON_GROUND / STAT_AIRBORNE); a field monitor (RAB set: a fixed transponder) is on the ground
    whatever they say; <NA> where the report says nothing."""
    said = pd.Series(pd.NA, index=frame.index, dtype="boolean")
    if category in (21, 10, 20) and "gbs" in frame:
        said = frame["gbs"].astype("Int64").eq(1)
    elif category == 48 and "flight_status" in frame:
        stat = frame["flight_status"].astype("Int64")
        said = stat.isin(STAT_ON_GROUND).astype("boolean").mask(~stat.isin(STAT_ON_GROUND + STAT_AIRBORNE)
                                                              .fillna(False))
    if "rab" in frame:
        said = said.mask(frame["rab"].astype("Int64").eq(1).fillna(False), True)
    return said.astype("boolean")


def _rows_of(columns: dict[str, pd.Series], keep: np.ndarray) -> dict[str, pd.Series]:
    """The ``keep`` rows of each column."""
    return {name: values[keep] for name, values in columns.items()}


# Near the vertical over the site a slant-range error moves the plot horizontally by r / g times itself; past
# 10x (elevation above 84.3 deg) the plot says almost nothing about its horizontal position along the
# line of sight, and its covariance is too ill-conditioned to invert, so it is NaN (unknown).
MAX_RANGE_STRETCH = 10.0
# A plot within a metre of the site on the ground (range 0: a damaged or test plot; CAT048's range LSB is
# 1/256 NM, 7 m) has no azimuth error to speak of: its covariance is singular to rounding, so NaN too.
MIN_GROUND_M = 1.0


def _radar_covariance(site: pd.DataFrame, lat, lon, h_m) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """East/north covariance (m^2) at each plot from the site's range and azimuth sigmas.

    The slant-range error moves the plot along the horizontal radial by sigma_r * r / g (r slant, g
    horizontal distance: the height is fixed by the flight level), the azimuth error across it by
    g * sigma_theta; the radial direction is taken in the plot's own east/north frame. NaN where r / g
    exceeds MAX_RANGE_STRETCH (almost overhead), the plot lies within MIN_GROUND_M of the site (range 0) or
    the matrix is not positive definite.
    """
    site_ecef = np.stack(geodetic_to_ecef(site["latitude"].to_numpy(float), site["longitude"].to_numpy(float),
                                          site["altitude_m"].to_numpy(float)), -1)
    d = np.stack(geodetic_to_ecef(lat, lon, h_m), -1) - site_ecef
    s_east, s_north, _ = enu_basis(site["latitude"].to_numpy(float), site["longitude"].to_numpy(float))
    g = np.hypot((d * s_east).sum(-1), (d * s_north).sum(-1))
    r = np.linalg.norm(d, axis=-1)
    east, north, _ = enu_basis(lat, lon)
    alpha = np.arctan2((d * east).sum(-1), (d * north).sum(-1))  # radial direction at the plot
    var_tangential = (g * np.radians(site["sigma_azimuth_deg"].to_numpy(float))) ** 2
    sa, ca = np.sin(alpha), np.cos(alpha)
    with np.errstate(divide="ignore", invalid="ignore"):  # a plot right above the site: undefined (NaN)
        var_radial = (site["sigma_range_m"].to_numpy(float) * r / g) ** 2
        cov = (var_radial * sa**2 + var_tangential * ca**2, (var_radial - var_tangential) * sa * ca,
               var_radial * ca**2 + var_tangential * sa**2)
        positive = (cov[0] > 0) & (cov[2] > 0) & (cov[0] * cov[2] - cov[1] ** 2 > 0)
    placeable = (g >= MIN_GROUND_M) & (r <= MAX_RANGE_STRETCH * g) & positive
    return tuple(np.where(placeable, c, np.nan) for c in cov)


def _sigma_major(cov_ee, cov_en, cov_nn) -> np.ndarray:
    """Square root of the larger eigenvalue of [[ee, en], [en, nn]]."""
    half_trace = (cov_ee + cov_nn) / 2.0
    return np.sqrt(half_trace + np.sqrt(((cov_ee - cov_nn) / 2.0) ** 2 + cov_en**2))


def _radar_rows(cat048: pd.DataFrame, sensors: pd.DataFrame, date: dt.date | None) -> pd.DataFrame:
    """Radar plots as WGS-84 positions (see the module docstring); UnknownRadar for SAC/SIC not in sensors."""
    out = _common(cat048, 48, "radar", date)
    out["heading_deg"] = _column(cat048, "heading_deg")
    out["rho_nm"] = _column(cat048, "rho_nm")
    out["theta_deg"] = _column(cat048, "theta_deg")
    x_nm, y_nm = _column(cat048, "x_nm"), _column(cat048, "y_nm")
    polar = (out["rho_nm"].notna() & out["theta_deg"].notna()).to_numpy()
    plane = ~polar & (x_nm.notna() & y_nm.notna()).to_numpy()
    keep = (polar | plane) & out["time"].notna().to_numpy() & ~no_plot(cat048, 48)
    out, polar, plane = _rows_of(out, keep), polar[keep], plane[keep]
    index = cat048.index[keep]
    x_nm, y_nm = x_nm[keep].to_numpy(), y_nm[keep].to_numpy()

    site = sensor_sites(pd.DataFrame({"sac": out["sac"], "sic": out["sic"]}, copy=False), sensors)
    site_lat, site_lon, site_alt = (site[c].to_numpy(float) for c in ("latitude", "longitude", "altitude_m"))
    alt_m = flight_level_to_m(out["flight_level"].to_numpy())
    lat, lon, h = (np.full(len(index), np.nan) for _ in range(3))
    if polar.any():
        lat[polar], lon[polar], h[polar] = polar_to_geodetic(
            site_lat[polar], site_lon[polar], site_alt[polar], out["rho_nm"].to_numpy()[polar],
            out["theta_deg"].to_numpy()[polar], alt_m[polar])
    if plane.any():
        lat[plane], lon[plane], h[plane] = plane_to_geodetic(
            site_lat[plane], site_lon[plane], site_alt[plane], x_nm[plane], y_nm[plane], alt_m[plane])
    known = np.isfinite(alt_m)
    cov = _radar_covariance(site, lat, lon, h)
    arrays = {"latitude": lat, "longitude": lon, "height_m": np.where(known, h, np.nan),
              "height_source": _labels(np.where(known, 0, 1), ["flight_level", "none"], index),
              "position_item": _labels(np.where(polar, 0, 1), ["040", "042"], index),
              "cov_ee_m2": cov[0], "cov_en_m2": cov[1], "cov_nn_m2": cov[2]}
    out.update((k, pd.Series(v, index=index, copy=False)) for k, v in arrays.items())
    return pd.DataFrame(out, copy=False)


def nacp_sigma_m(nacp) -> np.ndarray:
    """1-sigma horizontal error per axis (m) from NACp: its 95 % bound / 2.4477; NaN when absent or 0."""
    codes = pd.Series(nacp).astype("Int64").to_numpy(dtype=np.int64, na_value=-1)
    bound = np.full(len(codes), np.nan)
    listed = (codes >= 0) & (codes < len(_NACP_95_BY_CODE))
    bound[listed] = _NACP_95_BY_CODE[codes[listed]]  # a table lookup: a Series.map took 0.3 s a million
    return bound / CIRCULAR_95_PER_SIGMA


def _adsb_rows(cat021: pd.DataFrame, date: dt.date | None, adsb_sigma_m: float | None = None) -> pd.DataFrame:
    """ADS-B reports with a position and a time (heading = track angle). A report without NACp (CAT021
    0.2x) gets the caller's ``adsb_sigma_m`` per axis when given, else no covariance; NACp 0 ("unknown
    or >= 10 NM") gets none either way: it states a poor accuracy, it does not leave it out."""
    out = _common(cat021, 21, "adsb", date)
    out["heading_deg"] = _column(cat021, "track_angle_deg")
    out["latitude"] = _column(cat021, "latitude")
    out["longitude"] = _column(cat021, "longitude")
    out["nucp_nic"] = _column(cat021, "nucp_nic", "Int64")
    # 0.2x editions carry I021/090 PA instead, on a scale not documented as NUCp's: kept under its own name
    for name in ("nacp", "nucr_nacv", "sil", "mops_version", "fom_pa"):
        out[name] = _column(cat021, name, "Int64")
    geometric_m = _column(cat021, "geometric_height_ft").to_numpy() * 0.3048
    fl_m = flight_level_to_m(out["flight_level"].to_numpy())
    index = cat021.index
    out["height_m"] = pd.Series(np.where(np.isfinite(geometric_m), geometric_m, fl_m), index=index)
    out["height_source"] = _labels(np.where(np.isfinite(geometric_m), 0, np.where(np.isfinite(fl_m), 1, 2)),
                                   ["geometric", "flight_level", "none"], index)
    var = nacp_sigma_m(out["nacp"]) ** 2
    if adsb_sigma_m is not None:
        var = np.where(out["nacp"].isna().to_numpy(bool), float(adsb_sigma_m) ** 2, var)
    for name, values in (("cov_ee_m2", var), ("cov_en_m2", np.where(np.isnan(var), np.nan, 0.0)),
                         ("cov_nn_m2", var)):
        out[name] = pd.Series(values, index=index)
    keep = (out["time"].notna() & out["latitude"].notna() & out["longitude"].notna()
            & out["latitude"].abs().le(90.0) & out["longitude"].abs().le(180.0)).to_numpy(bool)
    return pd.DataFrame(_rows_of(out, keep & ~no_plot(cat021, 21)), copy=False)


def _on_earth(frame: pd.DataFrame) -> pd.Series:
    """Whether each row's latitude is within +-90 deg and its longitude within +-180 deg (False if absent)."""
    return frame["latitude"].abs().le(90.0) & frame["longitude"].abs().le(180.0)


def off_earth_rows(cat021: pd.DataFrame | None) -> pd.DataFrame:
    """The CAT021 reports whose position is present but off the Earth (file, offset, latitude, longitude)."""
    cols = [c for c in ("file", "offset", "latitude", "longitude") if cat021 is not None and c in cat021]
    if cat021 is None or not {"latitude", "longitude"} <= set(cat021):
        return pd.DataFrame(columns=cols)
    present = cat021["latitude"].notna() & cat021["longitude"].notna()
    return cat021.loc[(present & ~_on_earth(cat021)).to_numpy(bool), cols]


def impossible_positions(cat021: pd.DataFrame | None) -> list[str]:
    """One warning per input file whose CAT021 reports carry a position off the Earth (I021/130 and /131
    can encode latitudes up to 180 and 360 deg): how many, and the first one's offset and value."""
    bad = off_earth_rows(cat021)
    files = bad["file"] if "file" in bad else pd.Series("cat021", index=bad.index)
    out = []
    for name, rows in bad.groupby(files.astype(str).to_numpy(), sort=False):
        first = rows.iloc[0]
        offset = rows["offset"].iloc[0] if "offset" in rows else None
        out.append(f"{name}: {len(rows)} CAT021 report(s) with a position off the Earth (first at offset "
                   f"{offset}: latitude {first['latitude']:.4f}, longitude "
                   f"{first['longitude']:.4f}): damaged data, left out of the measurements")
    return out


def impossible_time_rows(frame: pd.DataFrame | None, category: int) -> pd.DataFrame:
    """The records whose time of day lies outside 0-24 h (damaged bytes; model.time.absolute_time gives
    them no time, so no measurement): category, file, offset, time_of_day."""
    from msdc.pipeline.model.time import impossible_time_of_day

    cols = ["category", *(c for c in ("file", "offset", "time_of_day") if frame is not None and c in frame)]
    if frame is None or "time_of_day" not in frame or not len(frame):
        return pd.DataFrame(columns=cols)
    bad = impossible_time_of_day(frame["time_of_day"].to_numpy(float))
    return frame.loc[bad, cols[1:]].assign(category=category)[cols]


def impossible_times(rows: pd.DataFrame | None) -> list[str]:
    """One warning per input file with records whose time of day lies outside 0-24 h
    (impossible_time_rows): how many of which categories, and the first one's offset and value."""
    if rows is None or not len(rows):
        return []
    files = rows["file"] if "file" in rows else pd.Series("the inputs", index=rows.index)
    out = []
    for name, group in rows.groupby(files.astype(str).to_numpy(), sort=False):
        first = group.iloc[0]
        cats = ", ".join(f"CAT{int(c):03d}" for c in sorted(set(group["category"])))
        offset = f"offset {int(first['offset'])}: " if "offset" in group and pd.notna(first["offset"]) else ""
        out.append(f"{name}: {len(group)} {cats} record(s) with a time of day outside 0-24 h (first at "
                   f"{offset}{first['time_of_day']:,.3f} s): damaged data, left out of the measurements")
    return out


def row_columns(columns=None) -> list[str] | None:
    """The columns ``measurement_rows`` keeps so that ``finish_measurements`` can give ``columns`` (None:
    every column): those named, less the derived ones, plus what the derived ones named are made from, and
    COVERAGE_PLACE where the coverage check can run (finish_measurements drops it unless named)."""
    if columns is None:
        return None
    wanted = set(column_names(columns))
    if {"sensor_kind", "sensor_id", "latitude", "longitude"} <= wanted:
        wanted.update(COVERAGE_PLACE)  # named by the out-of-coverage warning, then dropped if not asked for
    for derived, inputs in DERIVED_INPUTS.items():
        if derived in wanted:
            wanted.discard(derived)
            wanted.update(inputs)
    return column_names(wanted)


def measurement_rows(cat048: pd.DataFrame | None = None, cat021: pd.DataFrame | None = None,
                     sensors: pd.DataFrame | None = None, *, date: dt.date | None = None,
                     adsb_sigma_m: float | None = None, columns=None
                     ) -> tuple[pd.DataFrame | None, pd.DataFrame | None]:
    """The radar rows and the ADS-B rows of decoded frames (None where there are none) at the schema's
    dtypes, without the columns worked out over the whole run (``aircraft_id``, ``sigma_major_m``):
    a recording read in chunks builds these per chunk and joins them with ``finish_measurements``.
    ``columns``: only what those measurement columns need (``row_columns``), not every column."""
    radar = adsb = None
    keep = row_columns(columns)
    date = parse_date(date)
    _check_sigma(adsb_sigma_m)
    _check_frame(cat048, 48, "cat048")
    _check_frame(cat021, 21, "cat021")
    if cat048 is not None and len(cat048):
        if sensors is None:
            raise ValueError("radar measurements need the sensor table (radar sites)")
        radar = conform(_radar_rows(cat048, check_table(sensors), date), keep)
    if cat021 is not None and len(cat021):
        adsb = conform(_adsb_rows(cat021, date, adsb_sigma_m), keep)
    return (radar if radar is not None and len(radar) else None,
            adsb if adsb is not None and len(adsb) else None)


def _check_sigma(adsb_sigma_m) -> None:
    """TypeError/ValueError for a declared ADS-B sigma that is not a number in ADSB_SIGMA_RANGE_M."""
    if adsb_sigma_m is None:
        return
    lo, hi = ADSB_SIGMA_RANGE_M
    if isinstance(adsb_sigma_m, bool) or not isinstance(adsb_sigma_m, int | float | np.integer | np.floating):
        raise TypeError(f"adsb_sigma_m {adsb_sigma_m!r}: must be a number of metres")
    if not (math.isfinite(adsb_sigma_m) and lo <= adsb_sigma_m <= hi):
        raise ValueError(f"adsb_sigma_m {adsb_sigma_m!r}: must be from {lo:g} to {hi:g} m (a 1-sigma error "
                         "per axis; a variance is its square)")


def _check_frame(frame, category: int, name: str) -> None:
    """TypeError when ``frame`` is not a DataFrame, ValueError when it lacks the columns every row needs
    (a time and a position): rows without them would be dropped, every one, without a word."""
    if frame is None:
        return
    if not isinstance(frame, pd.DataFrame):
        raise TypeError(f"{name}: a {type(frame).__name__}, not a decoded CAT{category:03d} frame "
                        f"(asterix.read(...).frames[{category}])")
    if not len(frame):  # no row to build: an empty frame stands for none
        return
    lacking = []
    if not any(c in frame for c in _TIME_COLUMNS):
        lacking.append(" or ".join(_TIME_COLUMNS))
    if not any(all(c in frame for c in group) for group in _POSITION_COLUMNS[category]):
        lacking.append(" or ".join("/".join(g) for g in _POSITION_COLUMNS[category]))
    if category in (48, 10, 20):
        lacking += [c for c in ("sac", "sic") if c not in frame]
    if lacking:
        raise ValueError(f"{name}: the frame lacks {'; '.join(lacking)}, so no row could be built: is it "
                         f"a CAT{category:03d} frame (asterix.read(...).frames[{category}]), decoded with "
                         f"those columns? (build_measurements(cat048, cat021, sensors))")


def local_measurement_rows(cat010: pd.DataFrame | None, cat020: pd.DataFrame | None,
                           sensors: pd.DataFrame | None, *, date: dt.date | None = None, columns=None):
    """The CAT010 and CAT020 rows of decoded frames at the schema's dtypes, as ``measurement_rows`` makes
    the others (pipeline.model.multilateration.LocalRows: the rows per category, the reports left unplaced
    for want of a reference point, the CAT010 target reports of other kinds)."""
    from msdc.pipeline.model.multilateration import local_rows

    date = parse_date(date)
    _check_frame(cat010, 10, "cat010")
    _check_frame(cat020, 20, "cat020")
    local = local_rows(cat010, cat020, None if sensors is None else check_table(sensors), date=date)
    keep = row_columns(columns)
    local.parts = [conform(p, keep) for p in local.parts if len(p)]
    return local


def unplaced_verdict(unplaced: pd.DataFrame, reports: dict[int, int]) -> list[str]:
    """Judge the CAT010/CAT020 reports left unplaced for want of a reference point (LocalRows.unplaced over a
    run with ``reports`` records per category): UnknownReferencePoint for a sensor with enough of them to
    be one (multilateration.unplaced_limit), else one warning per sensor and file (damaged data)."""
    from msdc.pipeline.model.multilateration import unplaced_limit

    if unplaced.empty:
        return []
    keys = ["category", "kind", "sac", "sic"]
    total = unplaced.groupby(keys, dropna=False, sort=False)["records"].transform("sum").to_numpy()
    limit = np.array([unplaced_limit(reports.get(int(c), 0)) for c in unplaced["category"]])
    named = (unplaced["sac"].notna() & unplaced["sic"].notna()).to_numpy(bool)
    real = unplaced[named & (total >= limit)]
    if len(real):
        missing = real[keys].drop_duplicates()
        raise UnknownReferencePoint([(int(c), str(k), int(a), int(b)) for c, k, a, b in
                                     missing.itertuples(index=False)])
    out = []
    for row in unplaced.itertuples(index=False):
        name = row.file if pd.notna(row.file) else "input"
        pair = (f"SAC/SIC {row.sac}/{row.sic}" if pd.notna(row.sac) and pd.notna(row.sic)
                else "without SAC/SIC")
        out.append(f"{name}: {row.records} CAT{int(row.category):03d} {row.kind} report(s) {pair} (first at "
                   f"offset {row.offset}) with Cartesian positions and no reference point in the sensor "
                   f"file, too few for a sensor: taken for damaged data, left out of the measurements")
    return out


def finish_measurements(parts: list[pd.DataFrame], columns=None) -> pd.DataFrame:
    """Parts from ``measurement_rows`` joined in order (column by column, the list emptied: see
    schema.concat_columns), with the identity rule applied over all of them and each row's error-ellipse
    major axis; validated.
    ``columns`` (as given to ``measurement_rows``): only those columns, in schema order."""
    if not parts:
        return empty_measurements(columns)
    meas = concat_columns(parts)
    far, beyond = out_of_coverage(meas)
    if far.any():
        meas = meas[~far].reset_index(drop=True)
    wanted = column_names(columns)
    refused: list[str] = []
    if "aircraft_id" in wanted:
        meas["aircraft_id"], table = identify(meas)
        refused = refused_warnings(table, meas)
        if "smr" in set(meas["sensor_kind"].cat.categories):  # surface radar tracks joined by position
            from msdc.pipeline.model.primary_tracks import join_primary_tracks

            meas["aircraft_id"], joined = join_primary_tracks(meas)
            meas.attrs["primary_joined"] = joined
    if "sigma_major_m" in wanted:
        meas["sigma_major_m"] = _sigma_major(meas["cov_ee_m2"].to_numpy(), meas["cov_en_m2"].to_numpy(),
                                             meas["cov_nn_m2"].to_numpy())
    if columns is not None:  # the derived columns' inputs go, the rest in schema order (no copy)
        meas = pd.DataFrame({c: meas[c] for c in wanted}, copy=False)
    meas = validate(meas, columns)
    if len(beyond):  # in words: a table in attrs would break pandas' attrs comparison in concat
        meas.attrs["coverage_warnings"] = tuple(coverage_warnings(beyond))
    if refused:
        meas.attrs["identity_warnings"] = tuple(refused)
    return meas


def build_measurements(cat048: pd.DataFrame | None = None, cat021: pd.DataFrame | None = None,
                       sensors: pd.DataFrame | str | Path | None = None, *, date: dt.date | str | None = None,
                       adsb_sigma_m: float | None = None, cat010: pd.DataFrame | None = None,
                       cat020: pd.DataFrame | None = None, cut=None) -> pd.DataFrame:
    """Every radar, ADS-B, multilateration and surface radar report as one validated measurement frame,
    identity assigned over all of them (``cut``, a report_selection.MarginCut: over those it keeps).

    ``sensors``: the sensor table (read_sensors) or its TOML file's path. ``date`` (the UTC day, as
    asterix.read takes it) dates records that carry no timestamp of their own (see
    pipeline.model.time.absolute_time). ``adsb_sigma_m``: the 1-sigma error per axis (m, 0.5 to 20,000)
    declared for ADS-B reports without NACp. Rows are in input order, radar first. ADS-B reports with a
    position off the Earth (damaged bytes) are left out with an OffEarthWarning saying how many, those
    beyond any ground station's reach with an OutOfCoverageWarning (its words also in
    ``attrs["coverage_warnings"]``); reports the identity rule's reach gate kept from the aircraft their
    Mode 3/A code names give an IdentityWarning (also in ``attrs["identity_warnings"]``). ``cat010`` and
    ``cat020`` (pipeline.model.multilateration) come after the others; their Cartesian positions need the
    sensor table's reference points (UnknownReferencePoint names a missing one; a LeftOutWarning says
    which CAT010 target reports are of another kind, or too few of a sensor without its point).
    """
    if isinstance(sensors, str | Path):
        sensors = read_sensors(sensors)
    parts = measurement_rows(cat048, cat021, sensors, date=date, adsb_sigma_m=adsb_sigma_m)
    for text in impossible_positions(cat021):
        warnings.warn(text, OffEarthWarning, stacklevel=2)
    untimely = [impossible_time_rows(f, c)
                for c, f in ((48, cat048), (21, cat021), (10, cat010), (20, cat020))]
    for text in impossible_times(pd.concat(untimely, ignore_index=True)):
        warnings.warn(text, LeftOutWarning, stacklevel=2)
    for text in no_plot_warning(no_plot_counts(cat021, 21, no_plot_counts(cat048, 48))):
        warnings.warn(text, LeftOutWarning, stacklevel=2)
    parts = [p for p in parts if p is not None]
    if (cat010 is not None and len(cat010)) or (cat020 is not None and len(cat020)):
        from msdc.pipeline.model.multilateration import other_kinds_warning

        local = local_measurement_rows(cat010, cat020, sensors, date=date)
        counts = {10: len(cat010) if cat010 is not None else 0, 20: len(cat020) if cat020 is not None else 0}
        said = other_kinds_warning("cat010", local.other_kinds) + unplaced_verdict(local.unplaced, counts)
        for text in said:
            warnings.warn(text, LeftOutWarning, stacklevel=2)
        parts += local.parts
        local.parts.clear()  # the join frees each part's columns as it goes: held nowhere else
    if cut is not None:
        parts = [cut.keep(p) for p in parts]
        release_free_memory()  # the rows beyond the margin (most of a short window's read) go back at once
    meas = finish_measurements(parts)
    for text in meas.attrs.get("coverage_warnings", ()):
        warnings.warn(text, OutOfCoverageWarning, stacklevel=2)
    for text in meas.attrs.get("identity_warnings", ()):
        warnings.warn(text, IdentityWarning, stacklevel=2)
    return meas


def radar_measurements(cat048: pd.DataFrame, sensors: pd.DataFrame, *, date: dt.date | None = None):
    """Radar reports alone as a measurement frame (identity from radar data only)."""
    return build_measurements(cat048, None, sensors, date=date)


def adsb_measurements(cat021: pd.DataFrame, *, date: dt.date | None = None) -> pd.DataFrame:
    """ADS-B reports alone as a measurement frame (identity from ADS-B data only)."""
    return build_measurements(None, cat021, date=date)


def select(meas: pd.DataFrame, callsign: str | None = None, address: str | None = None) -> pd.DataFrame:
    """Rows of the aircraft (by ``aircraft_id``) seen with this call sign and/or 24-bit address.

    Call signs match case- and space-insensitively, addresses as hex in any case; a radar plot without
    I048/240 belongs to the aircraft when its identity rule linked it there.
    """
    ids = matching_aircraft([meas], callsign, address)
    return meas[meas["aircraft_id"].isin(ids).fillna(False).to_numpy(bool)].reset_index(drop=True)


def matching_aircraft(frames: list[pd.DataFrame], callsign: str | None = None,
                      address: str | None = None) -> set:
    """The aircraft ids ``select`` picks from these frames joined (seen in any of them with this call sign
    and/or address), without joining them."""

    def seen(column: str | None = None, value: str | None = None) -> set:
        return set().union(*(set((f["aircraft_id"] if column is None else
                                  f.loc[f[column] == value, "aircraft_id"]).dropna()) for f in frames))

    ids = seen()
    if callsign is not None:
        ids &= seen("callsign", normalise_callsign(callsign))
    if address is not None:
        ids &= seen("address", normalise_address(address))
    return ids
