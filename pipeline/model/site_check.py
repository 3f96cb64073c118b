"""Where each radar's plots lie against ADS-B: plots matched to the same aircraft's nearest ADS-B report in
time, and the median distance between them. A radar whose site is wrong in the sensor file puts every
plot kilometres from the aircraft's own GNSS position; quality, track and conflicts use this to say so
(``site_warnings``), correlate judges the same from its correlation windows (``far_separations``)."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from msdc.pipeline.model.geodesy import M_PER_NM, distance_m
from msdc.pipeline.model.sensors import radar_entries

SITE_CHECK_INPUTS = ["time", "sensor_kind", "sensor_id", "address", "latitude", "longitude", "rho_nm"]
MATCH_TOLERANCE_S = 1.0  # an ADS-B report at most this far in time from the plot (1 Hz: half a second)
MIN_MATCHED_PLOTS = 20  # fewer matched plots say too little about a site
FAR_SEPARATION_FACTOR = 10.0  # times a radar's own position sigma at its far plots
SLOTTING_MARGIN_M = 1000.0  # what 10 s slots of a fast aircraft add to any separation
FAST_AIRCRAFT_MPS = 300.0  # ground speed no airliner exceeds (580 kt)
# the measurement columns far_separations reads
FAR_SEPARATION_INPUTS = ["sensor_id", "sac", "sic", "rho_nm"]


def radar_offsets(meas: pd.DataFrame, tolerance_s: float = MATCH_TOLERANCE_S) -> pd.DataFrame:
    """One row per radar with at least MIN_MATCHED_PLOTS plots matched by address to an ADS-B report within
    ``tolerance_s``: ``sensor_id``, ``matched_plots``, ``offset_median_m`` (median plot-to-report distance)
    and ``rho_p95_nm`` (95th percentile of the matched plots' slant range)."""
    columns = ["sensor_id", "matched_plots", "offset_median_m", "rho_p95_nm"]
    kind = meas["sensor_kind"]
    keep = ["time", "address", "latitude", "longitude"]
    radar = meas.loc[(kind == "radar").to_numpy(bool), [*keep, "sensor_id", "rho_nm"]]
    adsb = meas.loc[(kind == "adsb").to_numpy(bool), keep]
    radar = radar[radar["address"].notna().to_numpy(bool) & radar["latitude"].notna().to_numpy(bool)]
    adsb = adsb[adsb["address"].notna().to_numpy(bool) & adsb["latitude"].notna().to_numpy(bool)]
    if radar.empty or adsb.empty:
        return pd.DataFrame(columns=columns)
    radar = radar.assign(address=radar["address"].astype(str)).sort_values("time", kind="stable")
    adsb = adsb.assign(address=adsb["address"].astype(str)).sort_values("time", kind="stable")
    both = pd.merge_asof(radar, adsb.rename(columns={"latitude": "adsb_lat", "longitude": "adsb_lon"}),
                         on="time", by="address", direction="nearest",
                         tolerance=pd.Timedelta(seconds=tolerance_s))
    both = both[both["adsb_lat"].notna().to_numpy(bool)]
    if both.empty:
        return pd.DataFrame(columns=columns)
    lat, lon = both["latitude"].to_numpy(float), both["longitude"].to_numpy(float)
    both = both.assign(offset_m=distance_m(lat, lon, both["adsb_lat"].to_numpy(float),
                                           both["adsb_lon"].to_numpy(float)))
    out = both.groupby("sensor_id", observed=True).agg(
        matched_plots=("offset_m", "size"), offset_median_m=("offset_m", "median"),
        rho_p95_nm=("rho_nm", lambda r: float(np.nanpercentile(r, 95)) if r.notna().any() else np.nan))
    out = out[out["matched_plots"] >= MIN_MATCHED_PLOTS].reset_index()
    return out[columns]


def far_separations(summaries: list[dict], meas: pd.DataFrame, sensors: pd.DataFrame,
                    sensors_path: str) -> list[str]:
    """Warnings for radars whose correlation windows (their ``summaries``) put the aircraft much further from
    ADS-B (median over windows of the median slot separation) than the radar's accuracy allows: most likely
    a wrong site."""
    rows = [s for s in summaries
            if s.get("sep_median_m") is not None and str(s.get("reference_sensor")).startswith("021")]
    if not rows:
        return []
    warnings = []
    for sensor_id, sep_m in pd.DataFrame(rows).groupby("radar_sensor")["sep_median_m"].median().items():
        rho = meas.loc[(meas["sensor_id"] == sensor_id).to_numpy(bool), "rho_nm"].to_numpy(float)
        if np.isfinite(rho).any():
            warnings += _far_site(str(sensor_id), float(sep_m), float(np.nanpercentile(rho, 95)), sensors,
                                  sensors_path, SLOTTING_MARGIN_M)
    return warnings


def site_warnings(meas: pd.DataFrame, sensors: pd.DataFrame, sensors_path: str) -> list[str]:
    """far_separations for the jobs without correlation windows (quality, track, conflicts, evaluate):
    each radar's plots against the same aircraft's ADS-B report nearest in time (radar_offsets)."""
    return list(far_sites(meas, sensors, sensors_path).values())


def far_sites(meas: pd.DataFrame, sensors: pd.DataFrame, sensors_path: str) -> dict[str, str]:
    """site_warnings by radar: its sensor id and the warning."""
    margin_m = MATCH_TOLERANCE_S * FAST_AIRCRAFT_MPS  # how far an aircraft flies between plot and report
    return {str(row.sensor_id): w for row in radar_offsets(meas).itertuples() if np.isfinite(row.rho_p95_nm)
            for w in _far_site(str(row.sensor_id), float(row.offset_median_m), float(row.rho_p95_nm), sensors,
                               sensors_path, margin_m)}


def _far_site(sensor_id: str, sep_m: float, far_nm: float, sensors: pd.DataFrame, sensors_path: str,
              margin_m: float) -> list[str]:
    """The wrong-site warning when a radar's median separation from ADS-B exceeds FAR_SEPARATION_FACTOR
    times its position sigma at ``far_nm`` (its far plots) plus ``margin_m``; [] otherwise."""
    if not sensor_id.startswith("048:"):  # a radar's site only
        return []
    try:
        sac, sic = (int(x) for x in sensor_id.split(":")[1].split("/"))
    except (IndexError, ValueError):  # a radar without SAC/SIC ("048:?/?") has no site to check
        return []
    sensors = radar_entries(sensors)
    site = sensors[(sensors["sac"] == sac) & (sensors["sic"] == sic)]
    if site.empty:
        return []
    far_m = far_nm * M_PER_NM
    sigma_m = math.hypot(float(site["sigma_range_m"].iloc[0]),
                         far_m * math.radians(float(site["sigma_azimuth_deg"].iloc[0])))
    if sep_m <= FAR_SEPARATION_FACTOR * sigma_m + margin_m:
        return []
    return [f"radar {sensor_id}: its plots lie a median {sep_m / 1000:.1f} km from ADS-B, far beyond its "
            f"accuracy ({sigma_m:.0f} m at {far_nm:.0f} NM); check its site in {sensors_path}"]
