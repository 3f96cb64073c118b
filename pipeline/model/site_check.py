"""Where each radar's plots lie against ADS-B: plots matched to the same aircraft's nearest ADS-B report in
time, and the median distance between them. A radar whose site is wrong in the sensor file puts every
plot kilometres from the aircraft's own GNSS position; quality, track and conflicts use this to say so
(correlate judges the same from its correlation windows)."""

from __future__ import annotations

import numpy as np
import pandas as pd

from msdc.pipeline.model.geodesy import distance_m

SITE_CHECK_INPUTS = ["time", "sensor_kind", "sensor_id", "address", "latitude", "longitude", "rho_nm"]
MATCH_TOLERANCE_S = 1.0  # an ADS-B report at most this far in time from the plot (1 Hz: half a second)
MIN_MATCHED_PLOTS = 20  # fewer matched plots say too little about a site


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
