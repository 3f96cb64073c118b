"""Decoded CAT048/CAT021 frames to measurement frames (positions in WGS-84), and aircraft selection.

Measurement schema: see ``pipeline.correlate.results``. ``time_of_day`` there is
``day * 86400 + time_of_day``.
Radar rows also carry ``position_item`` ("040" polar, "042" cartesian) and ``height_assumed``
(True where the flight level was absent, so the plot was placed at zero elevation / on the tangent
plane and its latitude/longitude are less accurate). ADS-B rows carry ``nucp_nic`` and ``nacp``.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from pipeline.model.geodesy import M_PER_FT, plane_to_geodetic, polar_to_geodetic
from pipeline.model.sensors import sensor_toml_snippet

MEASUREMENT_COLUMNS = ["sensor", "time_of_day", "timestamp", "latitude", "longitude", "flight_level",
                       "ground_speed_kt", "heading_deg", "callsign", "address", "sac", "sic"]
RADAR_COLUMNS = [*MEASUREMENT_COLUMNS, "rho_nm", "theta_deg", "position_item", "height_assumed"]
ADSB_COLUMNS = [*MEASUREMENT_COLUMNS, "nucp_nic", "nacp", "nucr_nacv", "sil", "mops_version"]


class UnknownRadar(ValueError):
    """Radar reports come from SAC/SIC pairs that the sensor table does not list."""

    def __init__(self, missing: list[tuple[int, int]]):
        self.missing = missing
        pairs = ", ".join(f"SAC {sac} SIC {sic}" for sac, sic in missing)
        snippets = "\n".join(sensor_toml_snippet(sac, sic) for sac, sic in missing)
        super().__init__(f"radar {pairs} not in the sensor table; add:\n{snippets}")


def normalise_callsign(s):
    """Upper-case call sign with spaces removed ("mas 72" -> "MAS72"); Series in, Series out; NA kept."""
    if isinstance(s, pd.Series):
        out = s.astype("str").str.upper().str.replace(" ", "", regex=False)
        return out.where(out.str.len() > 0)
    if s is None or (not isinstance(s, str) and pd.isna(s)):
        return None
    text = str(s).upper().replace(" ", "")
    return text or None


def normalise_address(s):
    """Upper-case 6-hex-digit address ("0x76cd41" -> "76CD41"); Series in, Series out; NA kept."""
    if isinstance(s, pd.Series):
        out = s.astype("str").str.strip().str.upper().str.removeprefix("0X").str.zfill(6)
        return out.where(out.str.len() > 0)
    if s is None or (not isinstance(s, str) and pd.isna(s)):
        return None
    text = str(s).strip().upper().removeprefix("0X")
    return text.zfill(6) if text else None


def _column(frame: pd.DataFrame, name: str, dtype: str = "float64") -> pd.Series:
    if name in frame:
        return frame[name].astype(dtype)
    return pd.Series(np.nan, index=frame.index, dtype=dtype)


def _common(frame: pd.DataFrame, sensor: str) -> pd.DataFrame:
    """The identity/time/kinematics columns shared by both sensors."""
    out = pd.DataFrame(index=frame.index)
    out["sensor"] = pd.Series(sensor, index=frame.index, dtype="str")
    out["time_of_day"] = _column(frame, "day") * 86400.0 + _column(frame, "time_of_day")
    if "timestamp" in frame:
        out["timestamp"] = frame["timestamp"]
    else:
        out["timestamp"] = pd.Series(pd.NaT, index=frame.index, dtype="datetime64[ns, UTC]")
    out["flight_level"] = _column(frame, "flight_level")
    out["ground_speed_kt"] = _column(frame, "ground_speed_kt")
    out["callsign"] = normalise_callsign(frame["callsign"]) if "callsign" in frame else pd.Series(
        np.nan, index=frame.index, dtype="str")
    out["address"] = normalise_address(frame["address"]) if "address" in frame else pd.Series(
        np.nan, index=frame.index, dtype="str")
    out["sac"] = _column(frame, "sac", "Int64")
    out["sic"] = _column(frame, "sic", "Int64")
    return out


def radar_measurements(cat048: pd.DataFrame, sensors: pd.DataFrame) -> pd.DataFrame:
    """Radar plots as WGS-84 positions: I048/040 (slant range, azimuth) else I048/042 (x east, y north).

    Height from the flight level (FL * 100 ft, taken as height above the ellipsoid); rows with no
    position or no time are dropped. Raises ``UnknownRadar`` for SAC/SIC pairs absent from ``sensors``.
    """
    out = _common(cat048, "radar")
    out["heading_deg"] = _column(cat048, "heading_deg")
    out["rho_nm"] = _column(cat048, "rho_nm")
    out["theta_deg"] = _column(cat048, "theta_deg")
    x_nm, y_nm = _column(cat048, "x_nm"), _column(cat048, "y_nm")
    polar = (out["rho_nm"].notna() & out["theta_deg"].notna()).to_numpy()
    plane = ~polar & (x_nm.notna() & y_nm.notna()).to_numpy()
    keep = (polar | plane) & out["time_of_day"].notna().to_numpy()
    out, polar, plane = out[keep], polar[keep], plane[keep]
    x_nm, y_nm = x_nm[keep].to_numpy(), y_nm[keep].to_numpy()

    if sensors.duplicated(["sac", "sic"]).any():
        raise ValueError("sensor table lists a SAC/SIC pair twice")
    site = out[["sac", "sic"]].merge(sensors.astype({"sac": "Int64", "sic": "Int64"}), on=["sac", "sic"],
                                     how="left")
    unknown = site["latitude"].isna().to_numpy()
    if unknown.any():
        pairs = site.loc[unknown, ["sac", "sic"]].drop_duplicates().sort_values(["sac", "sic"])
        raise UnknownRadar([(int(a) if pd.notna(a) else pd.NA, int(b) if pd.notna(b) else pd.NA)
                            for a, b in pairs.itertuples(index=False)])
    site_lat, site_lon, site_alt = (site[c].to_numpy(float) for c in ("latitude", "longitude", "altitude_m"))
    alt_m = out["flight_level"].to_numpy() * 100.0 * M_PER_FT
    lat, lon = np.full(len(out), np.nan), np.full(len(out), np.nan)
    if polar.any():
        la, lo, _ = polar_to_geodetic(site_lat[polar], site_lon[polar], site_alt[polar],
                                      out["rho_nm"].to_numpy()[polar], out["theta_deg"].to_numpy()[polar],
                                      alt_m[polar])
        lat[polar], lon[polar] = la, lo
    if plane.any():
        la, lo, _ = plane_to_geodetic(site_lat[plane], site_lon[plane], site_alt[plane], x_nm[plane],
                                      y_nm[plane], alt_m[plane])
        lat[plane], lon[plane] = la, lo
    out["latitude"], out["longitude"] = lat, lon
    out["position_item"] = pd.Series(np.where(polar, "040", "042"), index=out.index, dtype="str")
    out["height_assumed"] = np.isnan(alt_m)
    return out[RADAR_COLUMNS].reset_index(drop=True)


def adsb_measurements(cat021: pd.DataFrame) -> pd.DataFrame:
    """ADS-B reports with a position and a time, in the measurement schema (heading = track angle)."""
    out = _common(cat021, "adsb")
    out["heading_deg"] = _column(cat021, "track_angle_deg")
    out["latitude"] = _column(cat021, "latitude")
    out["longitude"] = _column(cat021, "longitude")
    out["nucp_nic"] = _column(cat021, "nucp_nic", "Int64")
    if "fom_pa" in cat021:  # 0.2x editions carry the NUCp-like figure as I021/090 PA
        out["nucp_nic"] = out["nucp_nic"].fillna(_column(cat021, "fom_pa", "Int64"))
    out["nacp"] = _column(cat021, "nacp", "Int64")
    for name in ("nucr_nacv", "sil", "mops_version"):
        out[name] = _column(cat021, name, "Int64")
    keep = out[["time_of_day", "latitude", "longitude"]].notna().all(axis=1)
    return out.loc[keep, ADSB_COLUMNS].reset_index(drop=True)


def select(meas: pd.DataFrame, callsign: str | None = None, address: str | None = None, *,
           link_with: pd.DataFrame | None = None) -> pd.DataFrame:
    """Rows of one aircraft: call sign (case/space-insensitive) and/or 24-bit address (hex, any case).

    Rows lacking the call sign are kept when their address was seen with that call sign in ``meas``
    or ``link_with`` (and likewise rows lacking the address), so radar plots without I048/240 count.
    """
    pairs = meas[["callsign", "address"]]
    if link_with is not None:
        pairs = pd.concat([pairs, link_with[["callsign", "address"]]], ignore_index=True)
    mask = pd.Series(True, index=meas.index)
    cs, addr = meas["callsign"], meas["address"]
    if callsign is not None:
        wanted = normalise_callsign(callsign)
        linked = set(pairs.loc[pairs["callsign"] == wanted, "address"].dropna())
        mask &= (cs == wanted) | (cs.isna() & addr.isin(linked))
    if address is not None:
        wanted = normalise_address(address)
        linked = set(pairs.loc[pairs["address"] == wanted, "callsign"].dropna())
        mask &= (addr == wanted) | (addr.isna() & cs.isin(linked))
    return meas[mask.fillna(False).astype(bool)].reset_index(drop=True)
