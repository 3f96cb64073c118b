"""Per-sensor measurement noise estimated from the tracker's own residuals (``msdc track --noise estimate``).

A pass filters and smooths every aircraft and takes every report's residual against the smoothed
position, r = z - H x_s. Its covariance under the right R is C = R - H P_s H^T for a report the filter
used (the smoother's error is correlated with that report's noise) and R + H P_s H^T for one it gated.
Each sensor's covariance is then rescaled so that the mean normalised square r^T C^-1 r / dof is 1:
ADS-B by one factor per source and declared sigma (NACp level), a radar by one factor along the line of
sight (range) and one across it (azimuth). Gross errors (ADS-B position jumps) are left out by a cut far
out in the tail: a residual more than GROSS_SIGMAS robust sigmas (median-based) away. The gated
reports are kept below that cut: dropping them makes the estimate chase itself down on heavy-tailed
real data (a smaller sigma gates more of the tail, which gives a smaller sigma). A few passes converge
(the smoothed covariance depends on the R in use). ADS-B on the surface (ground speed below
SURFACE_SPEED_KT: the reported one, else the first pass's smoothed speed) and airborne are separate
classes: pooled, the many near-stationary surface reports pulled the sigma far below the airborne scatter.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd
from scipy.stats import chi2

from .config import TrackerConfig, default_modes
from .frame import Plane
from .plane import estimate, filter_plane

# ADS-B reports below this ground speed are surface movements, estimated as their own class: taxi speeds
# stay under ~30 kt and nothing flies below ~100 kt. On the real CAT021 0.23 recording (no ground bit in
# the measurements) 16,503 reports are below 30 kt and only 396 more below 50 kt, every one without a
# flight level (on the surface); the surface residuals (~1 m) are a tenth of the airborne ones, whose
# along-track error grows with speed (time-stamp jitter), so one pooled sigma gated good airborne reports.
SURFACE_SPEED_KT = 50.0
KT_PER_M_S = 3600.0 / 1852.0

CHI2_1_MEDIAN = float(chi2.median(1))  # median of a squared standard normal, 0.4549
CHI2_2_MEDIAN = float(chi2.median(2))  # 2 ln 2
GROSS_SIGMAS = 30.0  # residuals beyond this many robust sigmas are gross errors, not noise
POSITION, RANGE, AZIMUTH = "position", "range", "azimuth"
SCALE_LIMITS = (0.02, 50.0)  # sigma factors are clipped to this per pass
# The tracker's 99.9 % gate should reject 0.1 % of good reports. Real ADS-B errors are heavy-tailed (late
# time stamps: along-track errors of 0.5-0.9 s times the speed), so the variance that matches the mean
# can put a few per cent of the reports below the gross-error cut beyond the gate, where runs of three
# restart the track. The variance factor is raised until at most GATE_SHARE_MAX of them (ten times the
# nominal share) lie beyond the gate.
GATE_PROBABILITY = 0.999
GATE_SHARE_MAX = 0.01


def quadratic_forms(res: np.ndarray, R: np.ndarray, HPH: np.ndarray, radial: np.ndarray | None = None):
    """Squared residuals over their covariance C = R - HPH (pass -HPH for a gated report: R + HPH).

    res (n, 2), R and HPH (n, 2, 2). Without radial: r^T C^-1 r (chi-square, 2 dof), shape (n,). With
    radial (n, 2) unit line-of-sight vectors: along and across it, (v^T r)^2 / (v^T C v) (1 dof each),
    shape (n, 2). NaN where C is not positive (a report alone in its segment)."""
    C = R - HPH
    with np.errstate(invalid="ignore", divide="ignore"):
        if radial is None:
            det = C[:, 0, 0] * C[:, 1, 1] - C[:, 0, 1] * C[:, 1, 0]
            q = (C[:, 1, 1] * res[:, 0] ** 2 - (C[:, 0, 1] + C[:, 1, 0]) * res[:, 0] * res[:, 1]
                 + C[:, 0, 0] * res[:, 1] ** 2) / det
            ok = (det > 1e-9 * np.abs(R[:, 0, 0] * R[:, 1, 1])) & (C[:, 0, 0] > 0)
            return np.where(ok, q, np.nan)
        u = radial
        w = np.stack([-u[:, 1], u[:, 0]], axis=-1)
        out = np.empty((len(res), 2))
        for k, v in enumerate((u, w)):
            cv = np.einsum("ni,nij,nj->n", v, C, v)
            rv = np.einsum("ni,nij,nj->n", v, R, v)
            out[:, k] = np.where(cv > 1e-9 * rv, np.einsum("ni,ni->n", v, res) ** 2 / cv, np.nan)
        return out


def rescale(cov: np.ndarray, k_along, k_across, radial: np.ndarray | None) -> np.ndarray:
    """A R A^T with A = k_along u u^T + k_across w w^T (u the line of sight, w across it); without
    radial, k_along^2 R. Shapes: cov (n, 2, 2), factors (n,)."""
    k_along = np.asarray(k_along, float)
    if radial is None:
        return cov * (k_along**2)[:, None, None]
    u = radial
    w = np.stack([-u[:, 1], u[:, 0]], axis=-1)
    A = (k_along[:, None, None] * np.einsum("ni,nj->nij", u, u)
         + np.asarray(k_across, float)[:, None, None] * np.einsum("ni,nj->nij", w, w))
    return A @ cov @ np.swapaxes(A, 1, 2)


def variance_ratio(q: np.ndarray, dof: int) -> float:
    """The factor by which the variance in use should be multiplied: the mean of q / dof after the
    gross-error cut (q / dof above GROSS_SIGMAS^2 times its robust level), raised where needed so that
    at most GATE_SHARE_MAX of the q kept lie beyond the GATE_PROBABILITY quantile of chi-square(dof)."""
    q = q[np.isfinite(q)]
    level = np.median(q / dof) / (float(chi2.median(dof)) / dof)
    q = q[q / dof <= GROSS_SIGMAS**2 * level]
    tail = np.quantile(q, 1.0 - GATE_SHARE_MAX) / float(chi2.ppf(GATE_PROBABILITY, dof))
    return float(max(np.mean(q / dof), tail))


def plane_forms(run, ze, zn, cov_ee, cov_en, cov_nn, radial=None) -> np.ndarray:
    """`quadratic_forms` of every report of a plane-level run (pipeline.track.plane.filter_plane) against
    the smoothed estimate at its time, gated reports included (with C = R + H P_s H^T)."""
    n = len(run.t)
    if not n:
        return np.empty((0, 2) if radial is not None else 0)
    est = estimate(run, run.t, smooth=True)
    res = np.stack([np.asarray(ze, float) - est.x[:, 0], np.asarray(zn, float) - est.x[:, 3]], -1)
    R = np.empty((n, 2, 2))
    R[:, 0, 0] = cov_ee
    R[:, 0, 1] = R[:, 1, 0] = cov_en
    R[:, 1, 1] = cov_nn
    hph = est.P[:, [0, 3]][:, :, [0, 3]]
    hph = np.where(run.accepted[:, None, None], hph, -hph)
    return quadratic_forms(res, R, hph, radial)


@dataclass
class NoiseEstimate:
    """measurements: the input with its covariances rescaled; sensors: one row per sensor and component
    (sensor_id, sensor_kind, component "position" | "range" | "azimuth", motion "surface" | "airborne"
    for ADS-B ("" for radars: see SURFACE_SPEED_KT), declared_sigma_m for ADS-B
    classes, scale = estimated / declared sigma, residuals used, estimated: False when too few
    residuals, so the declared sigma was kept, declared_from "nacp" | "declared" (ADS-B without NACp)
    | "sensor" (radar), estimated_sigma_m); passes run."""

    measurements: pd.DataFrame
    sensors: pd.DataFrame
    passes: int


def _radials(meas: pd.DataFrame, sites: dict[str, tuple[float, float]] | None) -> np.ndarray:
    """Unit line-of-sight vectors (local east, north) at each radar plot, outward from its site; NaN
    for other rows and radars without a site."""
    from pyproj import Geod

    out = np.full((len(meas), 2), np.nan)
    sid = meas["sensor_id"].astype(str).to_numpy()
    radar = (meas["sensor_kind"].astype(str) == "radar").to_numpy()
    lat, lon = meas["latitude"].to_numpy(float), meas["longitude"].to_numpy(float)
    for s, (site_lat, site_lon) in (sites or {}).items():
        i = np.flatnonzero(radar & (sid == s))
        if len(i):
            az, _, _ = Geod(ellps="WGS84").inv(lon[i], lat[i], np.full(len(i), site_lon),
                                               np.full(len(i), site_lat))
            a = np.radians(np.asarray(az) + 180.0)
            out[i, 0], out[i, 1] = np.sin(a), np.cos(a)
    return out


def _classes(meas: pd.DataFrame, radial: np.ndarray, surface: np.ndarray) -> tuple[np.ndarray, list[tuple]]:
    """Class number per row and the class keys (sensor_id, kind, has_site, declared variance or NaN,
    declared_from, motion): ADS-B by source, NACp level, whether the sigma came from NACp ("nacp") or was
    declared for reports without it ("declared"; also every ADS-B row of a frame without a nacp
    column), so a declared sigma equal to a NACp level's is still its own class, and motion ("surface"
    where `surface`, else "airborne"); radars ("sensor", motion "") by sensor (with a site: separate
    range and azimuth factors; without: one isotropic factor)."""
    sid = meas["sensor_id"].astype(str).to_numpy()
    kind = meas["sensor_kind"].astype(str).to_numpy()
    has_site = np.isfinite(radial[:, 0])
    declared = np.where(kind == "adsb", np.round(meas["cov_ee_m2"].to_numpy(float), 3), np.nan)
    has_nacp = meas["nacp"].notna().to_numpy(bool) if "nacp" in meas else np.zeros(len(meas), bool)
    source = np.where(kind == "adsb", np.where(has_nacp, "nacp", "declared"), "sensor")
    motion = np.where(kind == "adsb", np.where(surface, "surface", "airborne"), "")
    label = (pd.Series(sid, dtype=object) + "|" + kind + "|" + has_site.astype(str) + "|"
             + declared.astype(str) + "|" + source + "|" + motion)
    codes, uniques = pd.factorize(label, sort=True)
    first = [int(np.flatnonzero(codes == c)[0]) for c in range(len(uniques))]
    return codes, [(sid[i], kind[i], bool(has_site[i]), float(declared[i]), str(source[i]), str(motion[i]))
                   for i in first]


def _forms(meas: pd.DataFrame, cov: np.ndarray, radial: np.ndarray,
           config: TrackerConfig) -> tuple[np.ndarray, np.ndarray]:
    """Per row, (along, across) quadratic forms for radars with a site, (q, q) for the others (2 dof),
    from one filter-and-smooth pass per aircraft in its own plane, and the smoothed speed (m/s; NaN for
    rows not tracked)."""
    out = np.full((len(meas), 2), np.nan)
    speed_m_s = np.full(len(meas), np.nan)
    t_all = (meas["time"] - meas["time"].min()).dt.total_seconds().to_numpy(float)
    lat_all, lon_all = meas["latitude"].to_numpy(float), meas["longitude"].to_numpy(float)
    order = np.lexsort((meas["sensor_id"].astype(str).to_numpy(), t_all))
    ident = meas["aircraft_id"].astype(str).to_numpy()[order]
    for a in np.unique(ident):
        rows = order[ident == a]
        rows = rows[np.isfinite(cov[rows]).all(axis=(1, 2)) & np.isfinite(lat_all[rows])]
        if len(rows) < 2:
            continue
        plane = Plane.around(lat_all[rows], lon_all[rows])
        ze, zn = plane.forward(lat_all[rows], lon_all[rows])
        near = np.isfinite(ze) & (np.hypot(ze, zn) < 3_000_000.0)
        rows, ze, zn = rows[near], ze[near], zn[near]
        m = plane.local_to_plane(lat_all[rows], lon_all[rows])
        c = m @ cov[rows] @ np.swapaxes(m, 1, 2)
        run = filter_plane(config, t_all[rows], ze, zn, c[:, 0, 0], c[:, 0, 1], c[:, 1, 1])
        site = np.isfinite(radial[rows, 0])
        u = np.einsum("nij,nj->ni", m, np.nan_to_num(radial[rows]))
        u /= np.maximum(np.hypot(u[:, 0], u[:, 1]), 1e-12)[:, None]
        q_iso = plane_forms(run, ze, zn, c[:, 0, 0], c[:, 0, 1], c[:, 1, 1])
        q_rad = plane_forms(run, ze, zn, c[:, 0, 0], c[:, 0, 1], c[:, 1, 1], u)
        out[rows] = np.where(site[:, None], q_rad, np.stack([q_iso, q_iso], -1))
        x = estimate(run, run.t, smooth=True).x
        speed_m_s[rows] = np.hypot(x[:, 1], x[:, 4])
    return out, speed_m_s


def surface_mask(meas: pd.DataFrame, speed_m_s: np.ndarray) -> np.ndarray:
    """ADS-B rows moving slower than SURFACE_SPEED_KT: the reported ground speed where there is one, else
    the tracker's smoothed speed; a row with neither counts as airborne."""
    reported = (meas["ground_speed_kt"].to_numpy(float) if "ground_speed_kt" in meas
                else np.full(len(meas), np.nan))
    speed_kt = np.where(np.isfinite(reported), reported, np.asarray(speed_m_s, float) * KT_PER_M_S)
    with np.errstate(invalid="ignore"):
        return (meas["sensor_kind"].astype(str).to_numpy() == "adsb") & (speed_kt < SURFACE_SPEED_KT)


def estimate_noise(measurements: pd.DataFrame, *, sites: dict[str, tuple[float, float]] | None = None,
                   config: TrackerConfig | None = None, tpm: str | None = None, max_coast_s: float = 60.0,
                   passes: int = 6, min_residuals: int = 30, tol: float = 0.01) -> NoiseEstimate:
    """Rescale each sensor's covariances to its residual scatter (see the module docstring).

    sites: radar sensor_id -> (latitude, longitude) of its site, for separate range and azimuth factors
    (a radar without one gets a single factor). A class with fewer than min_residuals residuals takes its
    sensor's pooled factor; a sensor with fewer keeps its declared covariance. Stops after `passes`
    passes, or once no factor moves by more than tol. config / tpm / max_coast_s as for `track`."""
    if passes < 1:
        raise ValueError(f"passes {passes!r}: must be >= 1")
    config = TrackerConfig(**{**(config or TrackerConfig(modes=default_modes())).__dict__,
                              "max_coast_s": max_coast_s, **({"tpm": tpm} if tpm else {})})
    meas = measurements.reset_index(drop=True)
    cov0 = np.empty((len(meas), 2, 2))
    cov0[:, 0, 0] = meas["cov_ee_m2"].to_numpy(float)
    cov0[:, 0, 1] = cov0[:, 1, 0] = meas["cov_en_m2"].to_numpy(float)
    cov0[:, 1, 1] = meas["cov_nn_m2"].to_numpy(float)
    radial = _radials(meas, sites)
    site = np.isfinite(radial[:, 0])
    sid = meas["sensor_id"].astype(str).to_numpy()
    codes = keys = None
    cov = cov0
    done = 0
    for _ in range(passes):
        q, speed_m_s = _forms(meas, cov, radial, config)
        done += 1
        if codes is None:  # the classes need a speed: the first pass's smoothed one where none is reported
            codes, keys = _classes(meas, radial, surface_mask(meas, speed_m_s))
            k_along, k_across = np.ones(len(keys)), np.ones(len(keys))
            used = np.zeros(len(keys), int)
            estimated = np.zeros(len(keys), bool)
        dof = np.where(site, 1, 2)
        pooled = {}
        for s in np.unique(sid):
            sel = (sid == s) & np.isfinite(q[:, 0])
            d = 1 if site[sel].all() and sel.any() else 2
            pooled[s] = ((variance_ratio(q[sel, 0], d), variance_ratio(q[sel, 1], d))
                         if sel.sum() >= min_residuals and (site[sel].all() or not site[sel].any()) else None)
        moved = 0.0
        for c, key in enumerate(keys):
            sel = (codes == c) & np.isfinite(q[:, 0])
            used[c] = int(sel.sum())
            if used[c] >= min_residuals:
                d = int(dof[sel][0])
                ratio = (variance_ratio(q[sel, 0], d), variance_ratio(q[sel, 1], d))
            elif pooled[key[0]] is not None:
                ratio = pooled[key[0]]
            else:
                continue
            estimated[c] = True
            new_along = np.clip(k_along[c] * np.sqrt(ratio[0]), *SCALE_LIMITS)
            new_across = np.clip(k_across[c] * np.sqrt(ratio[1]), *SCALE_LIMITS)
            moved = max(moved, abs(new_along / k_along[c] - 1.0), abs(new_across / k_across[c] - 1.0))
            k_along[c], k_across[c] = new_along, new_across
        cov = rescale(cov0, k_along[codes], k_across[codes], None)
        cov[site] = rescale(cov0[site], k_along[codes][site], k_across[codes][site], radial[site])
        if moved <= tol:
            break
    rows = []
    for c, (s, kind, has_site, var, source, motion) in enumerate(keys):
        base = {"sensor_id": s, "sensor_kind": kind, "motion": motion, "residuals": int(used[c]),
                "estimated": bool(estimated[c]), "declared_from": source}
        if has_site:
            for component, k in ((RANGE, k_along[c]), (AZIMUTH, k_across[c])):
                rows.append({**base, "component": component, "declared_sigma_m": np.nan, "scale": float(k)})
        else:
            rows.append({**base, "component": POSITION, "declared_sigma_m": float(np.sqrt(var)),
                         "scale": float(k_along[c])})
    sensors = pd.DataFrame(rows, columns=["sensor_id", "sensor_kind", "component", "motion",
                                          "declared_sigma_m", "scale", "residuals", "estimated",
                                          "declared_from"])
    sensors["estimated_sigma_m"] = sensors["declared_sigma_m"] * sensors["scale"]
    out = meas.assign(cov_ee_m2=cov[:, 0, 0], cov_en_m2=cov[:, 0, 1], cov_nn_m2=cov[:, 1, 1])
    return NoiseEstimate(out.set_axis(measurements.index), sensors, done)
