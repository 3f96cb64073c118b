"""Radar accuracy against ADS-B: per-report errors in the radar's own terms, their statistics, and biases.

Each radar report of an aircraft that also has (jump-free, de-duplicated) ADS-B is compared with the ADS-B
track interpolated linearly to the radar time, only across ADS-B gaps of at most ``max_gap_s``; the
reference height is the ADS-B geometric height where the reports carry it (I021/140), else the flight
level (FL * 100 ft, taken as height above the ellipsoid, as ``pipeline.model.measurements`` does for
radar); ``adsb_height_source`` says which, per report, and the note says which was used. The radar
plot is placed at that same height, so the horizontal errors reflect range and azimuth only.

Limitation (thesis): ADS-B is the reference but carries its own position error, bounded at 95 % by its
NACp (DO-260B: NACp 8 < 92.6 m, 9 < 30 m, 10 < 10 m, 11 < 3 m); systematic errors below that level cannot
be attributed to the radar.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from msdc.pipeline.model.aircraft import aircraft_rows
from msdc.pipeline.model.dedup import DEDUP_KEYS, deduplicate
from msdc.pipeline.model.geodesy import (
    M_PER_NM,
    M_PER_S_PER_KT,
    distance_m,
    ecef_to_enu,
    enu_basis,
    flight_level_to_m,
    geodetic_to_ecef,
    polar_to_geodetic,
    slant_range_azimuth,
    wrap180,
)
from msdc.pipeline.model.jumps import JUMP_INPUTS, detect_jumps
from msdc.pipeline.model.measurements import NACP_95_M
from msdc.pipeline.model.sensors import sensor_sites
from msdc.pipeline.model.time import midnight, with_clock
from msdc.pipeline.parallel import map_ordered
from msdc.pipeline.quality.checks import (
    check_frame,
    check_options,
    check_reference,
    check_seconds,
    check_sensors,
)
from msdc.pipeline.quality.surface import SURFACE_ALL, SURFACE_INPUTS, mostly_surface, on_surface

MAX_ADSB_GAP_S = 10.0
ERROR_COLUMNS = [
    "radar", "sac", "sic", "callsign", "address", "time_of_day", "timestamp", "radar_row", "rho_nm",
    "theta_deg", "adsb_latitude", "adsb_longitude", "adsb_height_m", "adsb_track_deg", "adsb_speed_ms",
    "adsb_gap_s", "adsb_nacp", "slant_range_m", "ground_range_m", "azimuth_deg", "range_rate_ms",
    "tangential_speed_ms", "range_error_m", "azimuth_error_deg", "along_track_m", "cross_track_m",
    "horizontal_error_m", "adsb_height_source", "sigma_range_m", "sigma_azimuth_deg", "on_surface",
]
ERROR_METRICS = ["range_error_m", "azimuth_error_deg", "along_track_m", "cross_track_m", "horizontal_error_m"]
BIAS_COLUMNS = [
    "radar", "sac", "sic", "n_reports", "n_rejected", "n_overhead", "aircraft", "range_bias_m",
    "range_bias_se_m", "range_gain_ppm", "range_gain_se_ppm", "azimuth_bias_deg", "azimuth_bias_se_deg",
    "time_bias_s", "time_bias_se_s", "range_residual_rms_m", "azimuth_residual_rms_deg", "chi2_per_dof",
    "site_offset_m", "fit_trusted",
    "adsb_nacp_median", "adsb_nacp_95_m", "note",
]
# The measurement columns the ADS-B reference and the errors read (with mark_once's duplicate and jump flags
# when the frame carries them); --reference track hands the tracker every column
ACCURACY_INPUTS = list(dict.fromkeys([
    *DEDUP_KEYS, *JUMP_INPUTS, "sensor_id", "sensor_kind", "sac", "sic", "address", "callsign",
    "flight_level", "height_m", "height_source", "rho_nm", "theta_deg", "nacp", *SURFACE_INPUTS]))
# what radar_errors cannot do without (the rest of ACCURACY_INPUTS is read where present)
MEASUREMENT_INPUTS = ("sensor_kind", "time", "sac", "sic", "latitude", "longitude", "flight_level")
AIRCRAFT_COLUMNS = ["sensor_kind", "aircraft_id", "callsign", "address"]  # what aircraft_rows reads
MIN_BIAS_REPORTS = 20
HEIGHT_SOURCES = ["flight_level", "geometric"]  # adsb_height_source: the reference height used per report
# Below this many aircraft the aircraft-clustered standard errors (fit_biases) rest on few independent
# pieces and are themselves uncertain: the note says so
MIN_SE_AIRCRAFT = 10
# Student t 97.5 % quantiles for 1-9 degrees of freedom (any t table): the 95 % interval with G aircraft
T975 = {1: 12.71, 2: 4.30, 3: 3.18, 4: 2.78, 5: 2.57, 6: 2.45, 7: 2.36, 8: 2.31, 9: 2.26}
LIMITATION_NOTE = ("ADS-B is the reference but carries its own position error, bounded at 95 % by its NACp "
                   "(DO-260B: NACp 8 < 92.6 m, 9 < 30 m, 10 < 10 m, 11 < 3 m); radar errors below that "
                   "level cannot be attributed to the radar (thesis limitation). All four biases are "
                   "relative to ADS-B: the time bias is radar time minus ADS-B time (positive: the radar "
                   "stamps its plots late), so an ADS-B latency (time of applicability stamped late) enters "
                   "it with the opposite sign.")
CLIP_SIGMAS = 5.0  # rows further than this many robust sigmas from the fit are rejected
# Above this elevation seen from the site (the radar's cone of silence, or a target nearly overhead) the
# azimuth means nothing: a few metres across the line of sight are degrees, at azimuth rates of tens of
# degrees per second, so one such plot would decide the azimuth and time biases. Their azimuth rows are
# left out of the fit (their range rows stay) and counted as n_overhead.
MAX_AZIMUTH_ELEVATION_DEG = 45.0
_FIT_PASSES = 6


def nacp_bound_m(nacp) -> float:
    """95 % horizontal accuracy bound (m) of a NACp value (NaN when unknown or 0)."""
    if nacp is None or pd.isna(nacp):
        return float("nan")
    return NACP_95_M.get(int(nacp), float("nan"))


def reference_height_m(adsb: pd.DataFrame) -> tuple[np.ndarray, np.ndarray]:
    """The ADS-B reports' height above the ellipsoid (m): their geometric height where they carry it
    (I021/140, ``height_source`` "geometric"), else the flight level x 100 ft taken as height; and whether
    each is geometric."""
    fl_m = flight_level_to_m(adsb["flight_level"].to_numpy(float))
    if "height_source" not in adsb or "height_m" not in adsb:
        return fl_m, np.zeros(len(adsb), bool)
    geometric = (adsb["height_source"].astype(str) == "geometric").to_numpy(bool) & np.isfinite(
        adsb["height_m"].to_numpy(float))
    return np.where(geometric, adsb["height_m"].to_numpy(float), fl_m), geometric


def _adsb_track(adsb: pd.DataFrame) -> pd.DataFrame:
    """One aircraft's ADS-B reports by unique time (reports at the same time averaged, NACp the worst,
    geometric when every report at that time gives its geometric height)."""
    a = adsb.sort_values("time_of_day", kind="stable")
    lon = np.unwrap(a["longitude"].to_numpy(float), period=360.0)
    trk = np.radians(a["heading_deg"].to_numpy(float))
    gs_ms = a["ground_speed_kt"].to_numpy(float) * M_PER_S_PER_KT
    h, geometric = reference_height_m(a)
    frame = pd.DataFrame({"t": a["time_of_day"].to_numpy(float), "lat": a["latitude"].to_numpy(float),
                          "lon": lon, "h": h, "geo": geometric.astype(float),
                          "ve": gs_ms * np.sin(trk), "vn": gs_ms * np.cos(trk),
                          "nacp": pd.to_numeric(a["nacp"], errors="coerce").to_numpy(float)
                          if "nacp" in a else np.nan})
    agg = {c: "mean" for c in ("lat", "lon", "h", "ve", "vn")} | {"nacp": "min", "geo": "min"}
    return frame.groupby("t", sort=True).agg(agg).reset_index()


def _interpolate(track: pd.DataFrame, t_s: np.ndarray, max_gap_s: float) -> dict[str, np.ndarray]:
    """ADS-B state at the radar times: position, height, ENU velocity (m/s), gap and NACp of the segment."""
    ta = track["t"].to_numpy()
    out = {k: np.full(t_s.size, np.nan) for k in ("lat", "lon", "h", "ve", "vn", "vu", "gap", "nacp", "geo")}
    if ta.size < 2:
        return out
    k = np.searchsorted(ta, t_s, side="right") - 1
    k = np.where(t_s == ta[-1], ta.size - 2, k)
    inside = (k >= 0) & (k <= ta.size - 2)
    k = np.clip(k, 0, ta.size - 2)
    gap = ta[k + 1] - ta[k]
    ok = inside & (gap <= max_gap_s)
    f = np.where(ok, (t_s - ta[k]) / gap, np.nan)

    def col(name: str) -> tuple[np.ndarray, np.ndarray]:
        v = track[name].to_numpy()
        return v[k], v[k + 1]

    for name in ("lat", "lon", "h", "ve", "vn"):
        a, b = col(name)
        out[name] = a + f * (b - a)
    h0, h1 = col("h")
    out["vu"] = np.nan_to_num((h1 - h0) / gap)
    # velocity of the segment itself where the reported ground vector is missing at either end
    lat0, lat1 = col("lat")
    lon0, lon1 = col("lon")
    e0, n0, _ = ecef_to_enu(*geodetic_to_ecef(lat0, lon0, h0), out["lat"], out["lon"], out["h"])
    e1, n1, _ = ecef_to_enu(*geodetic_to_ecef(lat1, lon1, h1), out["lat"], out["lon"], out["h"])
    no_vel = ~(np.isfinite(out["ve"]) & np.isfinite(out["vn"]))
    out["ve"] = np.where(no_vel, (e1 - e0) / gap, out["ve"])
    out["vn"] = np.where(no_vel, (n1 - n0) / gap, out["vn"])
    out["gap"] = np.where(ok, gap, np.nan)
    out["nacp"] = np.fmin(*col("nacp"))
    out["geo"] = np.fmin(*col("geo"))  # 1: both ends geometric; a segment mixing the two counts as not
    out["lon"] = wrap180(out["lon"])
    for name in out:
        out[name] = np.where(ok, out[name], np.nan)
    return out


def _clocked(meas: pd.DataFrame, rows: np.ndarray, midnight_utc: pd.Timestamp | None) -> pd.DataFrame:
    """The reports at positions ``rows`` with the thesis clock counted from ``midnight_utc`` (that of the
    whole frame) and their ``radar_row``."""
    return with_clock(meas.iloc[rows].reset_index(drop=True), midnight_utc).assign(radar_row=rows)


def _matched(meas: pd.DataFrame, max_gap_s: float, jump_kw: dict | None, reference: str = "adsb"
             ) -> pd.DataFrame:
    """Radar reports (de-duplicated) with the interpolated ADS-B reference (or, with reference "track",
    the smoothed ADS-B-only track: pipeline.quality.track_reference), for aircraft seen by both;
    ``radar_row`` is the report's row in ``meas``. One aircraft's reports are copied at a time (and with
    the ADS-B reference only ACCURACY_INPUTS of them)."""
    if reference == "adsb":  # the smoothed track reads more of the model
        meas = meas[[c for c in meas if c in ACCURACY_INPUTS or c in ("duplicate", "jump")]]
    is_adsb = (meas["sensor_kind"] == "adsb").to_numpy(bool)
    adsb = meas[[c for c in meas if c in (*JUMP_INPUTS, "jump")]][is_adsb]
    jumps = detect_jumps(adsb, **(jump_kw or {})).to_numpy() if len(adsb) else np.zeros(0, bool)
    del adsb
    drop = np.zeros(len(meas), bool)
    drop[np.flatnonzero(is_adsb)[jumps]] = True
    keep = np.flatnonzero(~drop)
    start = midnight(meas["time"])

    def one(item: tuple) -> pd.DataFrame:  # one aircraft's radar reports with their reference
        callsign, address, _, radar, other = item
        r, _ = deduplicate(_clocked(meas, keep[radar], start))
        a, _ = deduplicate(_clocked(meas, keep[other], start))
        if reference == "track":
            from msdc.pipeline.quality.track_reference import track_reference

            ref = track_reference(a, r["time_of_day"].to_numpy(float), max_gap_s)
        else:
            ref = _interpolate(_adsb_track(a), r["time_of_day"].to_numpy(float), max_gap_s)
        r = r.assign(callsign=callsign or pd.NA, address=address or pd.NA,
                     **{f"ref_{k}": v for k, v in ref.items()})
        return r[np.isfinite(ref["lat"])]

    # the smoothed tracks overlap on threads (their kernels release the lock); interpolation is pandas alone
    parts = list(map_ordered(one, aircraft_rows(meas[AIRCRAFT_COLUMNS].iloc[keep]),
                             threads=None if reference == "track" else 1))
    if not parts:
        return pd.DataFrame(columns=[*meas.columns, "time_of_day", "timestamp", "radar_row", "ref_lat"])
    return pd.concat(parts, ignore_index=True)


def site_geometry(lat, lon, h, ve, vn, vu, s_lat, s_lon, s_alt) -> tuple[np.ndarray, ...]:
    """Reference positions (deg, deg, m above the ellipsoid) with their east/north/up velocity (m/s) seen
    from a radar site: east and north offsets (m, the site's local frame), slant and ground range (m), range
    rate and tangential speed (m/s, positive clockwise): the geometry ``fit_biases`` regresses on."""
    e, n, u = ecef_to_enu(*geodetic_to_ecef(lat, lon, h), s_lat, s_lon, s_alt)
    slant_m, ground_m = np.sqrt(e**2 + n**2 + u**2), np.hypot(e, n)
    east, north, up = enu_basis(lat, lon)
    v_ecef = ve[:, None] * east + vn[:, None] * north + vu[:, None] * up
    del east, north, up  # (n, 3) arrays: gone before the next ones
    s_east, s_north, s_up = enu_basis(s_lat, s_lon)
    vs_e, vs_n, vs_u = ((v_ecef * b).sum(-1) for b in (s_east, s_north, s_up))
    range_rate = (e * vs_e + n * vs_n + u * vs_u) / slant_m
    tangential = (n * vs_e - e * vs_n) / ground_m
    return e, n, slant_m, ground_m, range_rate, tangential


def radar_errors(meas: pd.DataFrame, sensors: pd.DataFrame, *, max_gap_s: float = MAX_ADSB_GAP_S,
                 jump_kw: dict | None = None, reference: str = "adsb") -> pd.DataFrame:
    """One row per radar report matched to ADS-B: range, azimuth, along/cross-track and horizontal error.
    reference: "adsb" (reports interpolated linearly) or "track" (the smoothed ADS-B-only track).

    range_error_m = radar slant range - slant range from the site to the ADS-B reference; azimuth error
    wrapped to +-180 deg; along-track along the ADS-B ground track, cross-track positive to the right of
    it. Also the reference geometry (slant/ground range, azimuth, range rate, tangential speed) that
    ``estimate_biases`` regresses on.
    """
    check_frame("meas", meas, MEASUREMENT_INPUTS)
    check_sensors(sensors, meas)
    check_seconds("max_gap_s", max_gap_s)
    check_options("jump_kw", jump_kw)
    check_reference(reference)
    m = _matched(meas, max_gap_s, jump_kw, reference)
    if m.empty:
        return pd.DataFrame(columns=ERROR_COLUMNS)
    site = sensor_sites(m, sensors)
    s_lat, s_lon, s_alt = (site[c].to_numpy(float) for c in ("latitude", "longitude", "altitude_m"))
    lat, lon, h = m["ref_lat"].to_numpy(), m["ref_lon"].to_numpy(), m["ref_h"].to_numpy()
    ve, vn, vu = m["ref_ve"].to_numpy(), m["ref_vn"].to_numpy(), m["ref_vu"].to_numpy()

    # reference geometry seen from the site, and its rates from the ADS-B velocity
    e, n, slant_m, ground_m, range_rate, tangential = site_geometry(lat, lon, h, ve, vn, vu, s_lat, s_lon,
                                                                    s_alt)

    # the radar plot in its own terms; cartesian-only plots get them from their position
    rho_nm, theta = m["rho_nm"].to_numpy(float), m["theta_deg"].to_numpy(float)
    polar = np.isfinite(rho_nm) & np.isfinite(theta)
    if (~polar).any():
        fl_h = flight_level_to_m(m["flight_level"].to_numpy(float))
        rr, tt, _ = slant_range_azimuth(s_lat, s_lon, s_alt, m["latitude"].to_numpy(float),
                                        m["longitude"].to_numpy(float), np.where(np.isfinite(fl_h), fl_h, h))
        rho_nm, theta = np.where(polar, rho_nm, rr), np.where(polar, theta, tt)
    p_lat, p_lon, p_h = polar_to_geodetic(s_lat, s_lon, s_alt, rho_nm, theta, h)
    de, dn, _ = ecef_to_enu(*geodetic_to_ecef(p_lat, p_lon, p_h), lat, lon, h)
    trk = np.arctan2(ve, vn)
    geometric = m["ref_geo"].to_numpy(float) == 1.0 if "ref_geo" in m else np.zeros(len(m), bool)

    columns = {
        "radar": site["name"].array, "sac": m["sac"].astype("Int64").to_numpy(),
        "sic": m["sic"].astype("Int64").to_numpy(), "callsign": m["callsign"].to_numpy(),
        "address": m["address"].to_numpy(), "time_of_day": m["time_of_day"].to_numpy(float),
        "timestamp": m["timestamp"].to_numpy(), "radar_row": m["radar_row"].to_numpy(),
        "rho_nm": rho_nm, "theta_deg": theta, "adsb_latitude": lat, "adsb_longitude": lon,
        "adsb_height_m": h, "adsb_track_deg": np.degrees(trk) % 360.0, "adsb_speed_ms": np.hypot(ve, vn),
        "adsb_gap_s": m["ref_gap"].to_numpy(), "adsb_nacp": m["ref_nacp"].to_numpy(),
        "slant_range_m": slant_m, "ground_range_m": ground_m,
        "azimuth_deg": np.degrees(np.arctan2(e, n)) % 360.0, "range_rate_ms": range_rate,
        "tangential_speed_ms": tangential, "range_error_m": rho_nm * M_PER_NM - slant_m,
        "azimuth_error_deg": wrap180(theta - np.degrees(np.arctan2(e, n))),
        "along_track_m": de * np.sin(trk) + dn * np.cos(trk),
        "cross_track_m": de * np.cos(trk) - dn * np.sin(trk),
        "horizontal_error_m": distance_m(lat, lon, p_lat, p_lon),
        "adsb_height_source": pd.Categorical.from_codes(geometric.astype(np.int8), HEIGHT_SOURCES),
        "sigma_range_m": site["sigma_range_m"].to_numpy(float),
        "sigma_azimuth_deg": site["sigma_azimuth_deg"].to_numpy(float),
        "on_surface": on_surface(m),  # the radar report's own (pipeline.quality.surface)
    }
    # sorted by radar and time: the order found on the three key columns alone, then each column taken in
    # it, so that the table is built once and not copied (selected, sorted, re-indexed) as a whole
    keys = pd.DataFrame({k: columns[k] for k in ("sac", "sic", "time_of_day")})
    order = keys.sort_values(["sac", "sic", "time_of_day"], kind="stable").index.to_numpy()
    del keys, m, site
    return pd.DataFrame({k: columns.pop(k)[order] for k in ERROR_COLUMNS}, columns=ERROR_COLUMNS, copy=False)


def _moments(values: pd.Series, base: str, unit: str) -> dict[str, float]:
    v = values.to_numpy(float)
    v = v[np.isfinite(v)]
    if v.size == 0:
        return {f"{base}_{s}_{unit}": np.nan for s in ("mean", "std", "rms")}
    return {f"{base}_mean_{unit}": float(v.mean()), f"{base}_std_{unit}": float(v.std(ddof=1)) if v.size > 1
            else np.nan, f"{base}_rms_{unit}": float(np.sqrt(np.mean(v**2)))}


def error_stats(errors: pd.DataFrame) -> pd.DataFrame:
    """Mean, standard deviation and RMS of each error per radar, for the aircraft in the air ("(all)"), those
    on the surface ("(all surface)", when there are: pipeline.quality.surface) and each one."""
    check_frame("errors", errors, ("radar", "sac", "sic", "callsign", "address", *ERROR_METRICS))
    rows = []
    for (name, sac, sic), g in errors.groupby(["radar", "sac", "sic"], sort=True, dropna=False):
        aircraft = [(cs, addr, a) for (cs, addr), a in g.groupby(["callsign", "address"], sort=True,
                                                                  dropna=False)]
        surface = [mostly_surface(a["on_surface"].to_numpy(bool)) if "on_surface" in a else False
                   for _, _, a in aircraft]
        pooled = []
        for label, on in (("(all)", False), (SURFACE_ALL, True)):
            if on in surface:
                pooled.append((label, "", pd.concat([a for (_, _, a), s in zip(aircraft, surface, strict=True)
                                                     if s == on])))
        parts = pooled + aircraft
        for cs, addr, a in parts:
            row = {"radar": name, "sac": sac, "sic": sic, "callsign": cs, "address": addr,
                   "n_reports": len(a)}
            for metric in ERROR_METRICS:
                base, unit = metric.rsplit("_", 1)
                row |= _moments(a[metric], base, unit)
            rows.append(row)
    stats = [f"{base}_{s}_{unit}" for base, unit in (m.rsplit("_", 1) for m in ERROR_METRICS)
             for s in ("mean", "std", "rms")]
    columns = ["radar", "sac", "sic", "callsign", "address", "n_reports", *stats]
    return pd.DataFrame(rows, columns=columns)


def _robust_sigma(r: np.ndarray) -> float:
    return float(1.4826 * np.median(np.abs(r - np.median(r)))) if r.size else float("nan")


def elevation_deg(errors: pd.DataFrame) -> np.ndarray:
    """Elevation of the ADS-B reference seen from the site (deg, flat-earth from slant and ground range)."""
    slant, ground = errors["slant_range_m"].to_numpy(float), errors["ground_range_m"].to_numpy(float)
    return np.degrees(np.arctan2(np.sqrt(np.maximum(slant**2 - ground**2, 0.0)), ground))


def _robust_cov(xw: np.ndarray, rw: np.ndarray, cov: np.ndarray) -> np.ndarray:
    """HC3 sandwich covariance of a weighted fit (rows xw, weighted residuals rw, (Xw'Xw)^-1 = cov): each
    residual inflated by its leverage, so a parameter one plot decides gets the error of leaving it out."""
    leverage = np.einsum("ij,jk,ik->i", xw, cov, xw)
    u = rw / np.maximum(1.0 - leverage, 1e-9)
    meat = (xw * (u**2)[:, None]).T @ xw
    return cov @ meat @ cov


def _cluster_cov(xw: np.ndarray, yw: np.ndarray, beta: np.ndarray, groups: np.ndarray) -> np.ndarray:
    """Delete-one-aircraft jackknife covariance (CR3) of a weighted fit (rows xw, yw, estimate beta):
    (G-1)/G times the sum over the G groups of (fit without the group - beta)^2, so an error shared by all
    of one aircraft's plots counts once and an aircraft that decides a parameter gives it the error of
    leaving it out. NaN with fewer than two groups or when a fit without one group is singular."""
    codes, uniques = pd.factorize(groups)
    n_groups, n_par = len(uniques), xw.shape[1]
    nan = np.full((n_par, n_par), np.nan)
    if n_groups < 2:
        return nan
    # per-group X'X and X'y by bincount: no (rows, K, K) array on millions of plots
    a_g = np.empty((n_groups, n_par, n_par))
    for i in range(n_par):
        for j in range(i, n_par):
            a_g[:, i, j] = a_g[:, j, i] = np.bincount(codes, xw[:, i] * xw[:, j], n_groups)
    c_g = np.stack([np.bincount(codes, xw[:, i] * yw, n_groups) for i in range(n_par)], axis=1)
    a_out, c_out = a_g.sum(0) - a_g, c_g.sum(0) - c_g
    if (np.linalg.matrix_rank(a_out) < n_par).any():
        return nan
    d = np.linalg.solve(a_out, c_out[:, :, None])[:, :, 0] - beta
    return (n_groups - 1) / n_groups * d.T @ d


def aircraft_codes(errors: pd.DataFrame) -> np.ndarray:
    """One integer per aircraft (callsign and address; a missing one is a value of its own) per row."""
    if not {"callsign", "address"} <= set(errors.columns):
        return np.zeros(len(errors), np.int64)
    callsign = pd.factorize(errors["callsign"], use_na_sentinel=False)[0].astype(np.int64)
    address = pd.factorize(errors["address"], use_na_sentinel=False)[0].astype(np.int64)
    return callsign * (int(address.max(initial=0)) + 1) + address


def _robust_fit(x: np.ndarray, y: np.ndarray, is_range: np.ndarray, usable: np.ndarray,
                aircraft: np.ndarray) -> dict | None:
    """Weighted least squares of rows ``x``, ``y`` (range rows and azimuth rows, each type weighted by the
    inverse of its residual sigma), re-weighted and clipped at CLIP_SIGMAS robust sigmas until stable;
    None when the rows cannot separate the parameters. Standard errors: the largest of the model's, the
    leverage-robust (HC3) and the delete-one-aircraft (CR3) ones."""
    n_par = x.shape[1]
    if np.linalg.matrix_rank(x[usable]) < n_par:
        return None
    keep = usable.copy()
    sig = np.array([_robust_sigma(y[is_range]), _robust_sigma(y[~is_range & usable])])
    sig = np.where(sig > 0, sig, 1.0)
    for _ in range(_FIT_PASSES):
        w = np.where(is_range, 1.0 / sig[0], 1.0 / sig[1])
        if np.linalg.matrix_rank(x[keep]) < n_par:
            return None
        beta, *_ = np.linalg.lstsq(x[keep] * w[keep, None], y[keep] * w[keep], rcond=None)
        res = y - x @ beta
        robust = np.array([_robust_sigma(res[is_range & keep]), _robust_sigma(res[~is_range & keep])])
        new_keep = usable & (np.abs(res) <= CLIP_SIGMAS * np.where(is_range, robust[0], robust[1]))
        new_sig = np.array([np.std(res[is_range & new_keep]), np.std(res[~is_range & new_keep])])
        stable = np.array_equal(new_keep, keep) and np.allclose(new_sig, sig, rtol=1e-3)
        keep, sig = new_keep, np.where(new_sig > 0, new_sig, 1.0)
        if stable:
            break
    if np.linalg.matrix_rank(x[keep]) < n_par:
        return None
    w = np.where(is_range, 1.0 / sig[0], 1.0 / sig[1])
    xw = x[keep] * w[keep, None]
    beta, *_ = np.linalg.lstsq(xw, y[keep] * w[keep], rcond=None)
    res = y - x @ beta
    cov = np.linalg.inv(xw.T @ xw)
    robust_cov = _robust_cov(xw, res[keep] * w[keep], cov)
    cluster_cov = _cluster_cov(xw, y[keep] * w[keep], beta, aircraft[keep])
    se = np.sqrt(np.fmax(np.maximum(np.diag(cov), np.diag(robust_cov)), np.diag(cluster_cov)))
    covs = [c for c in (cov, robust_cov, cluster_cov) if np.all(np.isfinite(c))]
    return {"params": beta, "se": se, "covs": covs, "keep": keep, "res": res}


def fit_biases(errors: pd.DataFrame) -> dict:
    """Joint weighted least squares of one radar's errors: range rows [1, R, 0, -range_rate] (R in Mm,
    giving ppm) and azimuth rows [0, 0, 1, -azimuth_rate] in degrees, weighted by the inverse residual
    variance of each row type, re-weighted and clipped at CLIP_SIGMAS robust sigmas until stable. Azimuth
    rows above MAX_AZIMUTH_ELEVATION_DEG are left out (``n_overhead``). Standard errors are the largest of
    the model's, the leverage-robust (HC3) and the delete-one-aircraft (CR3) ones, so a fit decided by a few
    plots, or errors shared by all plots of an aircraft (transponder delay, ADS-B offset), do not look
    precise; ``aircraft`` counts the aircraft with fitted rows. Also its goodness of fit against the declared
    sigmas (``chi2_per_dof``) and the site-offset check (pipeline.quality.fit_checks). A fit also gives
    ``rows`` (the positions in ``errors`` of the fitted plots), and per fit row (their range rows, then
    their azimuth rows) ``residuals`` (m, deg) and ``kept`` (not clipped nor overhead)."""
    from msdc.pipeline.quality import fit_checks

    ok = errors[["range_error_m", "azimuth_error_deg", "slant_range_m", "ground_range_m", "range_rate_ms",
                 "tangential_speed_ms"]].notna().all(axis=1).to_numpy()
    e = errors[ok]
    n = len(e)
    aircraft = np.tile(aircraft_codes(e), 2)  # a plot's range and azimuth rows are of one aircraft
    az_rate_dps = np.degrees(e["tangential_speed_ms"].to_numpy() / e["ground_range_m"].to_numpy())
    x = np.zeros((2 * n, 4))
    x[:n, 0], x[:n, 1], x[:n, 3] = 1.0, e["slant_range_m"].to_numpy() * 1e-6, -e["range_rate_ms"].to_numpy()
    x[n:, 2], x[n:, 3] = 1.0, -az_rate_dps
    y = np.concatenate([e["range_error_m"].to_numpy(), e["azimuth_error_deg"].to_numpy()])
    is_range = np.arange(2 * n) < n
    usable = np.concatenate([np.ones(n, bool), elevation_deg(e) <= MAX_AZIMUTH_ELEVATION_DEG])
    result = {"n_reports": n, "n_rejected": 0, "n_overhead": int(n - usable[n:].sum()),
              "params": np.full(4, np.nan), "se": np.full(4, np.nan), "rms": (np.nan, np.nan), "aircraft": 0,
              "chi2_per_dof": np.nan, "offset": np.full(2, np.nan), "offset_se": np.nan, "wald": np.nan,
              "offset_flagged": False, "offset_checked": False}
    fit = _robust_fit(x, y, is_range, usable, aircraft) if n >= MIN_BIAS_REPORTS else None
    if fit is None:
        return result
    keep, res = fit["keep"], fit["res"]
    sigmas = fit_checks.declared_sigmas(e)
    result.update(params=fit["params"], se=fit["se"], n_rejected=int((usable & ~keep).sum()),
                  rows=np.flatnonzero(ok), residuals=res, kept=keep,
                  aircraft=int(np.unique(aircraft[keep]).size),
                  rms=(float(np.sqrt(np.mean(res[is_range & keep] ** 2))),
                       float(np.sqrt(np.mean(res[~is_range & keep] ** 2)))),
                  chi2_per_dof=fit_checks.chi2_per_dof(res[keep], None if sigmas is None else sigmas[keep],
                                                       4))
    extra = fit_checks.offset_columns(e)
    if extra is not None:
        wide = _robust_fit(np.hstack([x, extra]), y, is_range, usable, aircraft)
        if wide is not None:
            offset = wide["params"][4:]
            cov = max((c[4:, 4:] for c in wide["covs"]), key=lambda c: float(np.trace(c)))  # the widest
            wald, flagged = fit_checks.offset_verdict(offset, cov)
            result.update(offset=offset, offset_se=float(np.sqrt(np.trace(cov) / 2.0)), wald=wald,
                          offset_flagged=flagged, offset_checked=True)
    return result


def _note(nacp_median: float) -> str:
    """The radar's own ADS-B accuracy level (the general limitation is LIMITATION_NOTE, once per table)."""
    bound = nacp_bound_m(nacp_median)
    return (f"median NACp {nacp_median:g}: 95 % of ADS-B positions within {bound:g} m (DO-260B)"
            if np.isfinite(bound) else "ADS-B NACp unknown")


def _few_aircraft_note(n_aircraft: int) -> str:
    """What the standard errors are worth when they rest on fewer than MIN_SE_AIRCRAFT aircraft."""
    if n_aircraft >= MIN_SE_AIRCRAFT:
        return ""
    if n_aircraft < 2:
        return ("the standard errors rest on one aircraft: an error shared by all its plots (transponder "
                "delay, ADS-B offset or latency) is not in them; ")
    return (f"the standard errors rest on {n_aircraft} aircraft (fewer than {MIN_SE_AIRCRAFT}): for a 95 % "
            f"interval use +-{T975[n_aircraft - 1]:.2f} standard errors (Student t, {n_aircraft - 1} "
            "degrees of freedom); ")


def height_note(errors: pd.DataFrame) -> str:
    """Which height the reference had at the compared reports (``adsb_height_source``); "" if unknown."""
    if "adsb_height_source" not in errors or not len(errors):
        return ""
    n = len(errors)
    geometric = int((errors["adsb_height_source"].astype(str) == "geometric").sum())
    pressure = ("the ADS-B pressure altitude (flight level x 100 ft, taken as height above the WGS-84 "
                "ellipsoid: off by the difference between the two, which moves the slant range by that "
                "difference times the sine of the elevation)")
    if geometric == n:
        return f"Reference height: the ADS-B geometric height (I021/140) at all {n} compared reports."
    if geometric == 0:
        return f"Reference height: {pressure} at all {n} compared reports; no geometric height was used."
    return (f"Reference height: the ADS-B geometric height (I021/140) at {geometric} of the {n} compared "
            f"reports, {pressure} at the other {n - geometric}.")


def _offset_note(fit: dict) -> str:
    """The site-offset check's result for a radar's note (pipeline.quality.fit_checks)."""
    if not fit["offset_checked"]:
        return "site offset not checked: the plots do not surround the radar enough to separate it; "
    east, north = fit["offset"]
    verdict = "flagged" if fit["offset_flagged"] else "not flagged"
    return (f"site offset {np.hypot(east, north):.0f} m ({east:+.0f} m east, {north:+.0f} m north, SE "
            f"{fit['offset_se']:.0f} m per axis): {verdict}; ")


def fit_trust(fit: dict) -> tuple[str, str]:
    """Whether a fit of ``fit_biases`` can be trusted (the fit_trusted column), and why not: "no" with the
    warning when a check (pipeline.quality.fit_checks) says so, "unchecked" when the goodness of fit could
    not be measured (no declared sigmas) or the site offset not checked, else "yes"."""
    from msdc.pipeline.quality.fit_checks import fit_warning

    warning = fit_warning(fit["chi2_per_dof"], fit["offset"], fit["offset_flagged"])
    if warning:
        return "no", warning
    if not fit["offset_checked"] or not np.isfinite(fit["chi2_per_dof"]):
        return "unchecked", ""
    return "yes", ""


def estimate_biases(errors: pd.DataFrame) -> pd.DataFrame:
    """Per radar: range bias (m), range gain (ppm), azimuth bias (deg) and time bias (s, radar time minus
    ADS-B time: positive when the radar stamps late, and an ADS-B latency enters with the opposite sign)
    over all aircraft by ``fit_biases``, with standard errors, counts, residual RMS, the goodness of fit and
    site-offset check (pipeline.quality.fit_checks) and the ADS-B accuracy note (the general limitation,
    the reference height used, radars whose standard errors rest on few aircraft and fits not to be
    trusted, in ``attrs["note"]``)."""
    check_frame("errors", errors, ("radar", "sac", "sic"))
    rows, few_notes, distrust = [], [], []
    for (name, sac, sic), g in errors.groupby(["radar", "sac", "sic"], sort=True, dropna=False):
        fit = fit_biases(g)
        nacp = pd.to_numeric(g["adsb_nacp"], errors="coerce").dropna()
        nacp_median = float(np.floor(nacp.median())) if len(nacp) else float("nan")
        (b_r, gain, b_a, dt), (se_r, se_g, se_a, se_t) = fit["params"], fit["se"]
        note = _note(nacp_median)
        trusted, warning = "no", ""
        if np.isfinite(b_r):
            few = _few_aircraft_note(fit["aircraft"])
            trusted, warning = fit_trust(fit)
            note = _offset_note(fit) + note
            note = few + note
            if warning:
                note = f"NOT TO BE TRUSTED: {warning}; " + note
                distrust.append(f"{name}: the bias fit is not to be trusted: {warning}.")
            if few:
                few_notes.append(f"{name}: {few.rstrip('; ')}.")
        else:
            note = (f"too few reports (< {MIN_BIAS_REPORTS}) or too little geometry diversity to separate "
                    "range bias, gain, azimuth bias and time bias; ") + note
        rows.append({"radar": name, "sac": sac, "sic": sic, "n_reports": fit["n_reports"],
                     "n_rejected": fit["n_rejected"], "n_overhead": fit["n_overhead"],
                     "aircraft": len(g[["callsign", "address"]].drop_duplicates()),
                     "range_bias_m": b_r, "range_bias_se_m": se_r, "range_gain_ppm": gain,
                     "range_gain_se_ppm": se_g, "azimuth_bias_deg": b_a, "azimuth_bias_se_deg": se_a,
                     "time_bias_s": dt, "time_bias_se_s": se_t, "range_residual_rms_m": fit["rms"][0],
                     "azimuth_residual_rms_deg": fit["rms"][1], "chi2_per_dof": fit["chi2_per_dof"],
                     "site_offset_m": float(np.hypot(*fit["offset"])),
                     "fit_trusted": trusted,
                     "adsb_nacp_median": nacp_median,
                     "adsb_nacp_95_m": nacp_bound_m(nacp_median), "note": note})
    out = pd.DataFrame(rows, columns=BIAS_COLUMNS)
    out.attrs["note"] = " ".join(filter(None, [*distrust, LIMITATION_NOTE, height_note(errors), *few_notes]))
    out.attrs["distrust"] = distrust
    return out
