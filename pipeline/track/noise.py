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
Multilateration and surface radar reports have a third class, stationary (below STATIONARY_SPEED_KT): such a
system repeats a parked transponder's position to the last bit, and those near-zero residuals pooled with
the moving ones put the sigma under a metre and gated the taxiing aircraft. No sigma is estimated below the
rounding of the item a position was written in (pipeline.model.resolution: step / sqrt(12) per axis).
An ADS-B class fast enough gets R = sigma^2 I + sigma_t^2 v v^T, v the report's ground vector: time-stamp
errors move the reported position along the motion by v times the error, so the along-track scatter grows
with speed while the across-track one does not (fit_timing fits both from the residuals along and across).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np
import pandas as pd

from msdc.pipeline.model.geodesy import M_PER_NM
from msdc.pipeline.model.resolution import position_step_m
from msdc.pipeline.parallel import map_ordered

from .config import TrackerConfig, chi2_quantile, default_modes
from .covariance import principal_variances
from .frame import Plane
from .plane import estimate, filter_plane

# ADS-B reports below this ground speed are surface movements, estimated as their own class: taxi speeds
# stay under ~30 kt and nothing flies below ~100 kt. On the real CAT021 0.23 recording (no ground bit in
# the measurements) 16,503 reports are below 30 kt and only 396 more below 50 kt, every one without a
# flight level (on the surface); the surface residuals (~1 m) are a tenth of the airborne ones, whose
# along-track error grows with speed (time-stamp jitter), so one pooled sigma gated good airborne reports.
SURFACE_SPEED_KT = 50.0
# Multilateration and surface radar reports slower than this are a class of their own (motion "stationary"):
# on the real LEBL hour 65 % of the multilateration reports give a ground speed of exactly 0 (five field
# monitors and parked aircraft, positions repeated to the metre), while its taxiing aircraft give 5-30 kt.
STATIONARY_SPEED_KT = 1.0
LOCAL_KINDS = ("mlat", "smr")  # the sensor kinds with a stationary class
KT_PER_M_S = 3600.0 / M_PER_NM

CHI2_1_MEDIAN = chi2_quantile(0.5, 1)  # median of a squared standard normal, 0.4549
CHI2_2_MEDIAN = chi2_quantile(0.5, 2)  # 2 ln 2
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
# The timing term of an ADS-B class, R = sigma^2 I + sigma_t^2 v v^T: v is the report's own ground vector
# (ground speed and track angle), else the last one of the same aircraft and source at most
# VELOCITY_HOLD_S earlier (never a later report, never the smoother's), else none (no timing term).
# sigma_t is fitted only in classes with at least min_residuals reports moving faster than
# SURFACE_SPEED_KT: slower, 0.1 s of jitter is under 3 m along track, inseparable from the position noise.
TIMING = "timing"
VELOCITY_HOLD_S = 5.0
# The gate-share guard also per aircraft in the surface ADS-B classes (AIRCRAFT_GUARD): restarts happen per
# aircraft, and the position error is the avionics' (on the real 0.23 recording a taxiing aircraft reports
# positions that jump 15-17 m back and forth, in a surface class whose many parked aircraft scatter ~1 m).
# Not airborne: there the heavy tail is late time stamps, and raising an isotropic sigma for them made
# predictions through gaps worse (docs/tracker.md). Only aircraft with at least MIN_AIRCRAFT_RESIDUALS
# residuals in the class: fewer cannot place a 1 % tail.
MIN_AIRCRAFT_RESIDUALS = 100
AIRCRAFT_GUARD = ("surface", "stationary")
AIRCRAFT_COLUMNS = ["aircraft_id", "sensor_id", "motion", "declared_sigma_m", "class_sigma_m",
                    "estimated_sigma_m", "residuals"]


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


def variance_ratio(q: np.ndarray, dof: int, level_min: float = 0.0) -> float:
    """The factor by which the variance in use should be multiplied: the mean of q / dof after the
    gross-error cut (q / dof above GROSS_SIGMAS^2 times its robust level, at least level_min), raised where
    needed so that at most GATE_SHARE_MAX of the q kept lie beyond the GATE_PROBABILITY quantile of
    chi-square(dof)."""
    q = _below_gross(q, dof, level_min)
    return float(max(np.mean(q / dof), _tail(q, dof)))


def _below_gross(q: np.ndarray, dof: int, level_min: float = 0.0) -> np.ndarray:
    """The finite q whose q / dof lies within GROSS_SIGMAS^2 times its robust (median-based) level, taken as
    at least level_min (the level residuals at the positions' rounding would have: see rounding_levels)."""
    q = q[np.isfinite(q)]
    level = max(np.median(q / dof) / (chi2_quantile(0.5, dof) / dof), level_min)
    return q[q / dof <= GROSS_SIGMAS**2 * level]


def rounding_levels(cov: np.ndarray, floor_m2: np.ndarray) -> np.ndarray:
    """Per row, the rounding variance over the minor variance of the covariance in use (n, 2, 2): the robust
    level residuals at the positions' rounding would have, below which a class's residuals say nothing
    (their median is the least level of the gross-error cut; 0 without rounding). A multilateration system
    repeats a parked transponder's position, the smoother then fits it to a micrometre, and a level from
    those residuals would cut its real jumps of metres as gross errors."""
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.asarray(floor_m2, float) / minor_variance(cov)


def finite_median(values: np.ndarray) -> float:
    """The median of the finite values, 0 where there is none."""
    values = values[np.isfinite(values)]
    return float(np.median(values)) if len(values) else 0.0


def _tail(q: np.ndarray, dof: int) -> float:
    """The factor on the variance that leaves GATE_SHARE_MAX of q beyond the GATE_PROBABILITY quantile
    of chi-square(dof) (below 1 where fewer lie beyond it already)."""
    return float(np.quantile(q, 1.0 - GATE_SHARE_MAX) / chi2_quantile(GATE_PROBABILITY, dof))


def aircraft_tail(q: np.ndarray, dof: int, level_min: float = 0.0) -> float:
    """The gate-share factor of one aircraft's q in a class: `_tail` below the gross-error cut."""
    return _tail(_below_gross(q, dof, level_min), dof)


def smoothed_at_reports(run) -> tuple[np.ndarray, np.ndarray]:
    """The smoothed state x_s (n, 6) and covariance P_s (n, 6, 6) of a plane-level run at every report's
    time; NaN for reports before its first accepted one (gated reports after a withdrawn start)."""
    n = len(run.t)
    x, P = np.full((n, 6), np.nan), np.full((n, 6, 6), np.nan)
    accepted = run.accepted
    if accepted.any():
        ok = run.t >= run.t[accepted][0]
        est = estimate(run, run.t[ok], smooth=True)
        x[ok], P[ok] = est.x, est.P
    return x, P


def plane_residuals(run, ze, zn, smoothed=None) -> tuple[np.ndarray, np.ndarray]:
    """Every report's residual z - H x_s (n, 2) against the smoothed estimate of a plane-level run
    (pipeline.track.plane.filter_plane) at its time, and H P_s H^T (n, 2, 2) signed for quadratic_forms:
    negated for a gated report (C = R + H P_s H^T); NaN before the first accepted report. smoothed: the
    (x_s, P_s) of `smoothed_at_reports`, if already computed."""
    x, P = smoothed_at_reports(run) if smoothed is None else smoothed
    res = np.stack([np.asarray(ze, float) - x[:, 0], np.asarray(zn, float) - x[:, 3]], -1)
    hph = P[:, [0, 3]][:, :, [0, 3]]
    return res, np.where(run.accepted[:, None, None], hph, -hph)


def plane_forms(run, ze, zn, cov_ee, cov_en, cov_nn, radial=None) -> np.ndarray:
    """`quadratic_forms` of every report of a plane-level run (pipeline.track.plane.filter_plane) against
    the smoothed estimate at its time, gated reports included (with C = R + H P_s H^T)."""
    n = len(run.t)
    if not n:
        return np.empty((0, 2) if radial is not None else 0)
    res, hph = plane_residuals(run, ze, zn)
    return quadratic_forms(res, _matrices(cov_ee, cov_en, cov_nn), hph, radial)


def _matrices(cov_ee, cov_en, cov_nn) -> np.ndarray:
    """(n, 2, 2) symmetric matrices from their three components."""
    cov_ee = np.asarray(cov_ee, float)
    R = np.empty((len(cov_ee), 2, 2))
    R[:, 0, 0] = cov_ee
    R[:, 0, 1] = R[:, 1, 0] = cov_en
    R[:, 1, 1] = cov_nn
    return R


def along_across(vectors: np.ndarray) -> np.ndarray:
    """Rotations Q (n, 2, 2) whose rows are the unit vector along each velocity and the one across it
    (to its left); east and north where the velocity is zero."""
    speed = np.hypot(vectors[:, 0], vectors[:, 1])
    moving = speed > 0
    u = np.where(moving[:, None], vectors / np.where(moving, speed, 1.0)[:, None], [1.0, 0.0])
    return np.stack([u, np.stack([-u[:, 1], u[:, 0]], -1)], 1)


def timing_forms(res_uw: np.ndarray, hph_uw: np.ndarray, speed_m_s: np.ndarray, var_m2: float,
                 var_t_s2: float) -> np.ndarray:
    """r^T C^-1 r (2 dof) with R = var_m2 I + var_t_s2 v v^T, everything along and across the motion:
    res_uw (n, 2), signed hph_uw (n, 2, 2) as for quadratic_forms, speed_m_s (n,)."""
    R = np.zeros((len(res_uw), 2, 2))
    R[:, 0, 0] = var_m2 + var_t_s2 * speed_m_s**2
    R[:, 1, 1] = var_m2
    return quadratic_forms(res_uw, R, hph_uw)


def fit_timing(res_uw: np.ndarray, hph_uw: np.ndarray, speed_m_s: np.ndarray, var_m2: float,
               var_t_s2: float) -> tuple[float, float]:
    """One update of an ADS-B class's (sigma^2 m^2, sigma_t^2 s^2), R = sigma^2 I + sigma_t^2 v v^T, from its
    residuals along and across the motion (arguments as for timing_forms, at the current values).

    Below the gross-error cut (on the 2-dof form, as variance_ratio), each report's 1-dof forms along and
    across the motion rescale the current variances there (R_aa q_along, R_ww q_across: the two-term form
    of variance_ratio's mean update); across = sigma^2 and along = sigma^2 + sigma_t^2 v^2 are fitted to
    them by least squares weighted by 1 / R^2 (their variance is 2 R^2), sigma_t^2 >= 0. The gate-share
    guard then raises each term where needed, the reports' forms rescaled to the new variances: sigma^2
    until at most half of GATE_SHARE_MAX lie beyond the gate across the motion alone (the across-track
    tail: turns), then sigma_t^2 until at most GATE_SHARE_MAX do along and across (the late reports);
    sigma^2 alone against GATE_SHARE_MAX where sigma_t is 0."""
    q = timing_forms(res_uw, hph_uw, speed_m_s, var_m2, var_t_s2)
    ok = np.isfinite(q)
    level = np.median(q[ok] / 2) / (CHI2_2_MEDIAN / 2)
    ok &= q / 2 <= GROSS_SIGMAS**2 * level
    r, h, v2 = res_uw[ok], hph_uw[ok], speed_m_s[ok] ** 2
    along = var_m2 + var_t_s2 * v2
    with np.errstate(invalid="ignore", divide="ignore"):
        q_along, q_across = r[:, 0] ** 2 / (along - h[:, 0, 0]), r[:, 1] ** 2 / (var_m2 - h[:, 1, 1])
    fine = np.isfinite(q_along) & np.isfinite(q_across) & (q_along >= 0) & (q_across >= 0)
    y_along, y_across, along, v2 = along[fine] * q_along[fine], var_m2 * q_across[fine], along[fine], v2[fine]
    w_along, w_across = 1.0 / along**2, np.full(len(v2), 1.0 / var_m2**2)
    a = np.array([[w_across.sum() + w_along.sum(), (w_along * v2).sum()],
                  [(w_along * v2).sum(), (w_along * v2**2).sum()]])
    b = np.array([(w_across * y_across).sum() + (w_along * y_along).sum(), (w_along * y_along * v2).sum()])
    s2, t2 = np.linalg.solve(a, b)
    if t2 <= 0.0:
        s2, t2 = b[0] / a[0, 0], 0.0
    s2 = max(float(s2), 1e-6 * var_m2)
    gate = chi2_quantile(GATE_PROBABILITY, 2)
    if t2 == 0.0:
        return _smallest_factor(lambda g: float(np.mean((y_along + y_across) / (g * s2) > gate)),
                                GATE_SHARE_MAX) * s2, 0.0
    g_s = _smallest_factor(lambda g: float(np.mean(y_across / (g * s2) > gate)), GATE_SHARE_MAX / 2)
    g_t = _smallest_factor(lambda g: float(np.mean(y_along / (g_s * s2 + g * t2 * v2) + y_across / (g_s * s2)
                                                   > gate)), GATE_SHARE_MAX)
    return g_s * s2, g_t * float(t2)


def _smallest_factor(share, share_max: float, top: float = 1e4) -> float:
    """The smallest factor g in [1, top] with share(g) <= share_max (bisection on log g, to ~1e-5
    relative; share decreases with g); top where none is."""
    if share(1.0) <= share_max:
        return 1.0
    lo, hi = 0.0, np.log(top)
    for _ in range(40):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if share(np.exp(mid)) > share_max else (lo, mid)
    return float(np.exp(hi))


def _scaled(cov0, k_along, k_across, var_t, vv, site, radial, floor_m2) -> np.ndarray:
    """The covariances in use: cov0 rescaled per row (radars with a site along and across the line of
    sight, the rest isotropically) plus the ADS-B timing term var_t v v^T, each raised to at least
    floor_m2 (per row) in every direction."""
    cov = rescale(cov0, k_along, k_across, None) + var_t[:, None, None] * vv
    cov[site] = rescale(cov0[site], k_along[site], k_across[site], radial[site])
    return floored(cov, floor_m2)


def minor_variance(cov: np.ndarray) -> np.ndarray:
    """The smaller eigenvalue of each symmetric 2 x 2 matrix (n, 2, 2): the variance along the ellipse's
    minor axis (covariance.principal_variances, the tracker's ellipse's)."""
    return principal_variances(cov)[1]


def floored(cov: np.ndarray, floor_m2: np.ndarray) -> np.ndarray:
    """cov (n, 2, 2) with floor_m2 - minor variance added to the diagonal where the minor variance is below
    it: then no direction's variance is below floor_m2 (rounding noise that every report carries)."""
    add = np.maximum(np.asarray(floor_m2, float) - minor_variance(cov), 0.0)
    if not (add > 0).any():
        return cov
    out = cov.copy()
    out[:, 0, 0] += add
    out[:, 1, 1] += add
    return out


def floor_factors(cov0: np.ndarray, floor_m2: np.ndarray, codes: np.ndarray, keys: list[tuple]) -> np.ndarray:
    """Per class, the smallest sigma factor allowed: SCALE_LIMITS' lower one, raised for an isotropic class
    with rounding steps to the factor at which its least rounded row (floor over declared minor variance)
    reaches its floor: below it every report of the class would have a sigma under its own rounding."""
    out = np.full(len(keys), SCALE_LIMITS[0])
    with np.errstate(invalid="ignore", divide="ignore"):
        ratio = np.sqrt(np.asarray(floor_m2, float) / minor_variance(cov0))
    for c, key in enumerate(keys):
        own = ratio[(codes == c) & np.isfinite(ratio) & (np.asarray(floor_m2) > 0)]
        if not key[2] and len(own):
            out[c] = float(np.clip(own.min(), *SCALE_LIMITS))
    return out


def _raise_aircraft(q: np.ndarray, in_class: np.ndarray, ident: np.ndarray, raised: np.ndarray,
                    min_rows: int, tol: float, level: np.ndarray) -> float:
    """Raise (in place) the sigma factor over the class of each aircraft's rows in `in_class` whose finite
    q number at least min_rows, so that at most GATE_SHARE_MAX of them lie beyond the gate; the factor
    never falls (recomputed from scratch it flipped between two values as gating decisions changed), and
    a raise of tol or less is none (an aircraft alone in its class already meets the class's guard).
    level: per row, the rounding level of the gross-error cut (rounding_levels; the aircraft's median).
    Returns the largest relative move."""
    rows = np.flatnonzero(in_class)
    order = rows[np.argsort(ident[rows], kind="stable")]
    moved = 0.0
    for part in np.split(order, np.flatnonzero(np.diff(ident[order])) + 1):
        own = q[part]
        if np.isfinite(own).sum() < min_rows:
            continue
        old = raised[part[0]]
        factor = np.sqrt(aircraft_tail(own, 2, finite_median(level[part])))
        new = old * factor if factor > 1.0 + tol else old
        raised[part] = new
        moved = max(moved, abs(new / old - 1.0))
    return moved


@dataclass
class NoiseEstimate:
    """measurements: the input with its covariances rescaled; sensors: one row per class and component
    (sensor_id, sensor_kind, component "position" | "timing" | "range" | "azimuth", motion "surface" |
    "airborne" for ADS-B, also "stationary" for multilateration and surface radar, "" for radars (see
    motions), declared_sigma_m of position rows (ADS-B: the class's; multilateration and surface radar:
    the median of its reports' own), scale = estimated / declared sigma, residuals used, estimated: False
    when too few residuals, so the declared sigma was kept (timing: no term fitted, 0 s), declared_from
    "nacp" | "declared" (ADS-B without NACp) | "sensor", at_resolution: the estimate stopped at the
    rounding of the positions' item (pipeline.model.resolution: the residuals say only that the noise is
    no larger), estimated_sigma_m, estimated_sigma_s: the timing row's sigma_t (s), NaN on the others);
    passes run; aircraft: one row per aircraft and class whose sigma the per-aircraft guard raised
    (aircraft_id, sensor_id, motion, declared_sigma_m, class_sigma_m, estimated_sigma_m, residuals)."""

    measurements: pd.DataFrame
    sensors: pd.DataFrame
    passes: int
    aircraft: pd.DataFrame = field(default_factory=lambda: pd.DataFrame(columns=AIRCRAFT_COLUMNS))


# a radar's plots lie within its range (MSSR: 256 NM, 474 km) of its site: a site whose plots' median position
# is farther than this is not that radar's (latitude and longitude swapped, a wrong sensor)
MAX_SITE_DISTANCE_M = 1_000_000.0


def check_sites(meas: pd.DataFrame, sites) -> dict[str, tuple[float, float]]:
    """sites as {radar sensor_id: (latitude, longitude)} floats for the radars of meas; a ValueError naming
    the key and the value for a value that is not a (latitude, longitude) pair of finite degrees within
    range, a site farther than MAX_SITE_DISTANCE_M from its plots' median position, or keys that are not
    radars of meas while some of its radars have no site (a misspelt key; a radar of a sensor file that is
    not in these measurements is otherwise left out: a subset of the aircraft need not see every radar)."""
    from pyproj import Geod

    if sites is None:
        return {}
    if not isinstance(sites, dict):
        raise TypeError(f"sites: expected a dict of radar sensor_id -> (latitude, longitude), "
                        f"not {type(sites).__name__}")
    radar = meas["sensor_kind"].astype(str).to_numpy() == "radar"
    sid = meas["sensor_id"].astype(str).to_numpy()
    radars = sorted(set(sid[radar]))
    out = {}
    unknown = [str(k) for k in sites if str(k) not in radars]
    without = [r for r in radars if r not in {str(k) for k in sites}]
    if unknown and without:
        raise ValueError(f"sites: {', '.join(map(repr, unknown))} not a radar of the measurements, while "
                         f"{', '.join(map(repr, without))} has no site (a misspelt key?)")
    for key, value in sites.items():
        if str(key) not in radars:
            continue
        try:
            lat, lon = (float(v) for v in value)
        except (TypeError, ValueError):
            raise ValueError(f"sites[{key!r}] {value!r}: expected (latitude, longitude) in degrees") from None
        if not (np.isfinite(lat) and np.isfinite(lon) and -90.0 <= lat <= 90.0 and -180.0 <= lon <= 360.0):
            raise ValueError(f"sites[{key!r}] {value!r}: latitude {lat:g} / longitude {lon:g} out of range "
                             "(expected (latitude, longitude): latitude within +-90 deg)")
        i = radar & (sid == str(key))
        plat, plon = meas.loc[i, "latitude"].to_numpy(float), meas.loc[i, "longitude"].to_numpy(float)
        ok = np.isfinite(plat) & np.isfinite(plon)
        if ok.any():
            centre = float(np.median(plon[ok])), float(np.median(plat[ok]))
            _, _, dist = Geod(ellps="WGS84").inv(lon, lat, *centre)
            if dist > MAX_SITE_DISTANCE_M:
                raise ValueError(f"sites[{key!r}] {value!r}: {dist / 1000.0:,.0f} km from its plots' median "
                                 f"position, beyond any radar's range (expected (latitude, longitude))")
        out[str(key)] = (lat, lon)
    return out


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


def _classes(meas: pd.DataFrame, radial: np.ndarray, motion: np.ndarray) -> tuple[np.ndarray, list[tuple]]:
    """Class number per row and the class keys (sensor_id, kind, has_site, declared variance or NaN,
    declared_from, motion): ADS-B by source, NACp level, whether the sigma came from NACp ("nacp") or was
    declared for reports without it ("declared"; also every ADS-B row of a frame without a nacp
    column), so a declared sigma equal to a NACp level's is still its own class; every sensor by the
    row's `motion` (see motions: "" for radars); radars ("sensor") with a site get separate range and
    azimuth factors, the rest one isotropic factor."""
    sid = meas["sensor_id"].astype(str).to_numpy()
    kind = meas["sensor_kind"].astype(str).to_numpy()
    has_site = np.isfinite(radial[:, 0])
    declared = np.where(kind == "adsb", np.round(meas["cov_ee_m2"].to_numpy(float), 3), np.nan)
    has_nacp = meas["nacp"].notna().to_numpy(bool) if "nacp" in meas else np.zeros(len(meas), bool)
    source = np.where(kind == "adsb", np.where(has_nacp, "nacp", "declared"), "sensor")
    motion = np.asarray(motion, dtype=object).astype(str)
    label = (pd.Series(sid, dtype=object) + "|" + kind + "|" + has_site.astype(str) + "|"
             + declared.astype(str) + "|" + source + "|" + motion)
    codes, uniques = pd.factorize(label, sort=True)
    first = [int(np.flatnonzero(codes == c)[0]) for c in range(len(uniques))]
    return codes, [(sid[i], kind[i], bool(has_site[i]), float(declared[i]), str(source[i]), str(motion[i]))
                   for i in first]


class _Pass(NamedTuple):
    """One estimation pass, per row: q (along, across) quadratic forms for radars with a site, (q, q) for
    the others (2 dof); the smoothed speed (m/s; NaN for rows not tracked); the residual (n, 2) and signed
    H P_s H^T (n, 2, 2) along and across the row's ground velocity `velocity` (east, north where it is
    zero), and that velocity's speed in the plane (m/s)."""

    q: np.ndarray
    smoothed_speed_m_s: np.ndarray
    res_uw: np.ndarray
    hph_uw: np.ndarray
    speed_m_s: np.ndarray


class _Aircraft(NamedTuple):
    """What every pass of one aircraft shares (the covariances aside): its rows in time order (sensor id
    on ties), times (s), plane positions (m), local-to-plane matrices, line of sight in the plane (radar
    plots with a site), the ground-velocity frame (along, across) and that velocity's plane speed."""

    rows: np.ndarray
    t: np.ndarray
    ze: np.ndarray
    zn: np.ndarray
    m: np.ndarray
    u: np.ndarray
    site: np.ndarray
    rot: np.ndarray
    speed_m_s: np.ndarray


def _aircraft(meas: pd.DataFrame, cov: np.ndarray, radial: np.ndarray,
              velocity: np.ndarray) -> list[_Aircraft]:
    """Each aircraft's rows with a finite position and covariance (the passes rescale covariances by
    finite factors, so the set does not change), within 3000 km of its median, in its own plane."""
    t_all = (meas["time"] - meas["time"].min()).dt.total_seconds().to_numpy(float)
    lat_all, lon_all = meas["latitude"].to_numpy(float), meas["longitude"].to_numpy(float)
    sensor_codes = pd.factorize(meas["sensor_id"].astype(str), sort=True)[0]
    ident = pd.factorize(meas["aircraft_id"].astype(str), sort=True)[0]
    order = np.lexsort((sensor_codes, t_all))
    order = order[np.argsort(ident[order], kind="stable")]  # by aircraft, each in time order
    bounds = np.flatnonzero(np.diff(ident[order])) + 1
    out = []
    for rows in np.split(order, bounds):
        rows = rows[np.isfinite(cov[rows]).all(axis=(1, 2)) & np.isfinite(lat_all[rows])]
        if len(rows) < 2:
            continue
        plane = Plane.around(lat_all[rows], lon_all[rows])
        ze, zn = plane.forward(lat_all[rows], lon_all[rows])
        near = np.isfinite(ze) & (np.hypot(ze, zn) < 3_000_000.0)
        rows, ze, zn = rows[near], ze[near], zn[near]
        m = plane.local_to_plane(lat_all[rows], lon_all[rows])
        u = np.einsum("nij,nj->ni", m, np.nan_to_num(radial[rows]))
        u /= np.maximum(np.hypot(u[:, 0], u[:, 1]), 1e-12)[:, None]
        v = np.einsum("nij,nj->ni", m, velocity[rows])
        out.append(_Aircraft(rows, t_all[rows], ze, zn, m, u, np.isfinite(radial[rows, 0]), along_across(v),
                             np.hypot(v[:, 0], v[:, 1])))
    return out


def _forms(aircraft: list[_Aircraft], n_rows: int, cov: np.ndarray, config: TrackerConfig) -> _Pass:
    """One filter-and-smooth pass per aircraft in its own plane (see _Pass)."""
    out = np.full((n_rows, 2), np.nan)
    speed_m_s = np.full(n_rows, np.nan)
    res_uw, hph_uw = np.full((n_rows, 2), np.nan), np.full((n_rows, 2, 2), np.nan)
    plane_speed = np.zeros(n_rows)
    def one(a: _Aircraft) -> None:  # writes only the aircraft's own rows
        c = a.m @ cov[a.rows] @ np.swapaxes(a.m, 1, 2)
        run = filter_plane(config, a.t, a.ze, a.zn, c[:, 0, 0], c[:, 0, 1], c[:, 1, 1])
        smoothed = smoothed_at_reports(run)
        res, hph = plane_residuals(run, a.ze, a.zn, smoothed)
        q_iso = quadratic_forms(res, c, hph)
        q_rad = quadratic_forms(res, c, hph, a.u)
        out[a.rows] = np.where(a.site[:, None], q_rad, np.stack([q_iso, q_iso], -1))
        speed_m_s[a.rows] = np.hypot(smoothed[0][:, 1], smoothed[0][:, 4])
        res_uw[a.rows] = np.einsum("nij,nj->ni", a.rot, res)
        hph_uw[a.rows] = a.rot @ hph @ np.swapaxes(a.rot, 1, 2)
        plane_speed[a.rows] = a.speed_m_s

    for _ in map_ordered(one, aircraft):
        pass
    return _Pass(out, speed_m_s, res_uw, hph_uw, plane_speed)


def ground_velocity(meas: pd.DataFrame, hold_s: float = VELOCITY_HOLD_S) -> np.ndarray:
    """Local (east, north) ground velocity (m/s) of each ADS-B report from its own ground speed and
    heading (the track angle), else the last one reported by the same aircraft and source at most hold_s
    earlier; zero for other rows and where there is none. Never a later report: the tracker's forward
    estimate at a report must not depend on what comes after it."""
    out = np.zeros((len(meas), 2))
    if not {"ground_speed_kt", "heading_deg"} <= set(meas.columns) or not len(meas):
        return out
    speed = meas["ground_speed_kt"].to_numpy(float) / KT_PER_M_S
    angle = np.radians(meas["heading_deg"].to_numpy(float))
    t = (meas["time"] - meas["time"].min()).dt.total_seconds().to_numpy(float)
    have = ((meas["sensor_kind"].astype(str) == "adsb").to_numpy() & np.isfinite(speed)
            & np.isfinite(angle))
    group = pd.factorize(meas["aircraft_id"].astype(str) + "|" + meas["sensor_id"].astype(str))[0]
    known = pd.DataFrame({"group": group, "t": np.where(have, t, np.nan),
                          "e": np.where(have, speed * np.sin(angle), np.nan),
                          "n": np.where(have, speed * np.cos(angle), np.nan)})
    order = np.lexsort((~have, t, group))  # at equal times a report's own vector first
    filled = known.iloc[order].groupby("group")[["t", "e", "n"]].ffill().to_numpy()
    ok = (t[order] - filled[:, 0] <= hold_s) & (meas["sensor_kind"].astype(str) == "adsb").to_numpy()[order]
    out[order[ok]] = filled[ok, 1:]
    return out


def motions(meas: pd.DataFrame, speed_m_s: np.ndarray) -> np.ndarray:
    """Each row's motion class by its speed (the reported ground speed where there is one, else the tracker's
    smoothed speed; a row with neither counts as airborne): ADS-B "surface" below SURFACE_SPEED_KT, else
    "airborne"; multilateration and surface radar the same, and "stationary" below STATIONARY_SPEED_KT;
    radars "" (one class)."""
    reported = (meas["ground_speed_kt"].to_numpy(float) if "ground_speed_kt" in meas
                else np.full(len(meas), np.nan))
    speed_kt = np.where(np.isfinite(reported), reported, np.asarray(speed_m_s, float) * KT_PER_M_S)
    kind = meas["sensor_kind"].astype(str).to_numpy()
    with np.errstate(invalid="ignore"):
        moving = np.where(speed_kt < SURFACE_SPEED_KT, "surface", "airborne")
        local = np.isin(kind, LOCAL_KINDS)
        moving = np.where(local & (speed_kt < STATIONARY_SPEED_KT), "stationary", moving)
    return np.where((kind == "adsb") | local, moving, "").astype(object)


def estimate_noise(measurements: pd.DataFrame, *, sites: dict[str, tuple[float, float]] | None = None,
                   config: TrackerConfig | None = None, tpm: str | None = None, max_coast_s: float = 60.0,
                   passes: int = 6, min_residuals: int = 30, tol: float = 0.01,
                   timing: bool = False, aircraft_guard: tuple[str, ...] = AIRCRAFT_GUARD,
                   min_aircraft_residuals: int = MIN_AIRCRAFT_RESIDUALS) -> NoiseEstimate:
    """Rescale each sensor's covariances to its residual scatter (see the module docstring).

    sites: radar sensor_id -> (latitude, longitude) of its site, for separate range and azimuth factors
    (a radar without one gets a single factor); a site out of range or far from its plots, or a key that is
    not a radar of the measurements while one of them has none, is a ValueError (`check_sites`). A
    class with fewer than min_residuals residuals takes its sensor's pooled factor; a sensor with fewer keeps
    its declared covariance. timing: ADS-B classes with
    at least min_residuals reports faster than SURFACE_SPEED_KT also get an along-track timing term
    sigma_t^2 v v^T (fit_timing; v from ground_velocity); False (default): isotropic only. Stops after
    `passes` passes, or once no sigma moves by more than tol. aircraft_guard: the motions ("surface",
    "airborne", "stationary") whose ADS-B, multilateration and surface radar classes then get the
    per-aircraft gate-share guard, for aircraft with at
    least min_aircraft_residuals residuals in the class (up to `passes` more passes; () turns it off).
    config / tpm / max_coast_s as for `track`."""
    if passes < 1:
        raise ValueError(f"passes {passes!r}: must be >= 1")
    config = TrackerConfig(**{**(config or TrackerConfig(modes=default_modes())).__dict__,
                              "max_coast_s": max_coast_s, **({"tpm": tpm} if tpm else {})})
    meas = measurements.reset_index(drop=True)
    sites = check_sites(meas, sites)
    cov0 = _matrices(meas["cov_ee_m2"], meas["cov_en_m2"], meas["cov_nn_m2"])
    floor_m2 = np.nan_to_num(position_step_m(meas) ** 2 / 12.0)  # rounding to the item's step, per axis
    radial = _radials(meas, sites)
    site = np.isfinite(radial[:, 0])
    sid = meas["sensor_id"].astype(str).to_numpy()
    velocity = ground_velocity(meas)
    vv = np.einsum("ni,nj->nij", velocity, velocity)
    codes = keys = None
    cov = floored(cov0, floor_m2)
    aircraft = _aircraft(meas, cov0, radial, velocity)
    ident = pd.factorize(meas["aircraft_id"].astype(str), sort=True)[0]
    raised = np.ones(len(meas))  # per row: an aircraft's sigma factor over its ADS-B class's (>= 1)
    done = 0
    for _ in range(passes):
        fp = _forms(aircraft, len(meas), cov, config)
        q = fp.q
        done += 1
        if codes is None:  # the classes need a speed: the first pass's smoothed one where none is reported
            codes, keys = _classes(meas, radial, motions(meas, fp.smoothed_speed_m_s))
            k_along, k_across = np.ones(len(keys)), np.ones(len(keys))
            var_t = np.zeros(len(keys))
            used = np.zeros(len(keys), int)
            k_min = floor_factors(cov0, floor_m2, codes, keys)
            estimated = np.zeros(len(keys), bool)
            fast = fp.speed_m_s * KT_PER_M_S >= SURFACE_SPEED_KT
            timed = np.array([timing and key[1] == "adsb" and not key[2]
                              and (fast & (codes == c) & np.isfinite(q[:, 0])).sum() >= min_residuals
                              for c, key in enumerate(keys)], bool)
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
            if timed[c]:
                v_ref = float(np.median(fp.speed_m_s[sel & fast]))  # convergence measured at this speed
                before = np.sqrt([k_along[c] ** 2 * key[3], k_along[c] ** 2 * key[3] + var_t[c] * v_ref**2])
                var_m2, var_t[c] = fit_timing(fp.res_uw[sel], fp.hph_uw[sel], fp.speed_m_s[sel],
                                              k_along[c] ** 2 * key[3], var_t[c])
                k_along[c] = k_across[c] = np.clip(np.sqrt(var_m2 / key[3]), k_min[c], SCALE_LIMITS[1])
                after = np.sqrt([k_along[c] ** 2 * key[3], k_along[c] ** 2 * key[3] + var_t[c] * v_ref**2])
                moved = max(moved, float(np.max(np.abs(after / before - 1.0))))
                estimated[c] = True
                continue
            if used[c] >= min_residuals:
                d = int(dof[sel][0])
                low = finite_median(rounding_levels(cov[sel], floor_m2[sel])) if not key[2] else 0.0
                ratio = (variance_ratio(q[sel, 0], d, low), variance_ratio(q[sel, 1], d, low))
            elif pooled[key[0]] is not None:
                ratio = pooled[key[0]]
            else:
                continue
            estimated[c] = True
            new_along = np.clip(k_along[c] * np.sqrt(ratio[0]), k_min[c], SCALE_LIMITS[1])
            new_across = np.clip(k_across[c] * np.sqrt(ratio[1]), k_min[c], SCALE_LIMITS[1])
            moved = max(moved, abs(new_along / k_along[c] - 1.0), abs(new_across / k_across[c] - 1.0))
            k_along[c], k_across[c] = new_along, new_across
        cov = _scaled(cov0, k_along[codes], k_across[codes], var_t[codes], vv, site, radial, floor_m2)
        if moved <= tol:
            break
    own = [c for c, key in enumerate(keys) if key[1] in ("adsb", *LOCAL_KINDS) and not key[2]
           and key[5] in aircraft_guard
           and not timed[c] and used[c] >= min_residuals]
    used_rows = np.zeros(len(meas), bool)
    in_own = np.bincount(ident[np.isin(codes, own)], minlength=ident.max(initial=0) + 1)
    guarded = [a for a in aircraft if in_own[ident[a.rows[0]]] >= min_aircraft_residuals]
    for _ in range(passes if guarded else 0):  # the per-aircraft guard, on the converged class factors
        q = _forms(guarded, len(meas), cov, config).q
        used_rows = np.isfinite(q[:, 0])
        done += 1
        level = rounding_levels(cov, floor_m2)
        moved = max(_raise_aircraft(q[:, 0], codes == c, ident, raised, min_aircraft_residuals, tol, level)
                    for c in own)
        cov = _scaled(cov0, k_along[codes] * raised, k_across[codes], var_t[codes], vv, site, radial,
                      floor_m2)
        if moved <= tol:
            break
    declared_var = _declared_variances(cov0, codes, keys)
    rows = []
    for c, (s, kind, has_site, _, source, motion) in enumerate(keys):
        base = {"sensor_id": s, "sensor_kind": kind, "motion": motion, "residuals": int(used[c]),
                "estimated": bool(estimated[c]), "declared_from": source,
                "at_resolution": bool(k_min[c] > SCALE_LIMITS[0] and k_along[c] <= k_min[c] * (1.0 + 1e-9))}
        if has_site:
            for component, k in ((RANGE, k_along[c]), (AZIMUTH, k_across[c])):
                rows.append({**base, "component": component, "declared_sigma_m": np.nan, "scale": float(k)})
        else:
            rows.append({**base, "component": POSITION, "declared_sigma_m": float(np.sqrt(declared_var[c])),
                         "scale": float(k_along[c])})
        if kind == "adsb" and not has_site and timing:
            rows.append({**base, "component": TIMING, "declared_sigma_m": np.nan, "scale": np.nan,
                         "estimated": bool(timed[c]), "sigma_s": float(np.sqrt(var_t[c]))})
    sensors = pd.DataFrame(rows, columns=["sensor_id", "sensor_kind", "component", "motion",
                                          "declared_sigma_m", "scale", "residuals", "estimated",
                                          "declared_from", "at_resolution", "sigma_s"])
    sensors["estimated_sigma_m"] = sensors["declared_sigma_m"] * sensors["scale"]
    sensors = sensors.rename(columns={"sigma_s": "estimated_sigma_s"})
    sensors = sensors[[c for c in sensors.columns if c != "estimated_sigma_s"] + ["estimated_sigma_s"]]
    out = meas.assign(cov_ee_m2=cov[:, 0, 0], cov_en_m2=cov[:, 0, 1], cov_nn_m2=cov[:, 1, 1])
    return NoiseEstimate(out.set_axis(measurements.index), sensors, done,
                         _raised_table(meas, codes, keys, declared_var, k_along, raised, used_rows))


def _declared_variances(cov0: np.ndarray, codes: np.ndarray, keys: list[tuple]) -> np.ndarray:
    """Per class, the declared per-axis variance: an ADS-B class's own, the median of a multilateration or
    surface radar class's reports' own (I010/500, I020/500, sigma_m); NaN for radars (one per plot)."""
    out = np.array([k[3] for k in keys], float)
    for c, key in enumerate(keys):
        if key[1] in LOCAL_KINDS:
            own = cov0[codes == c, 0, 0]
            out[c] = finite_median(own) if np.isfinite(own).any() else np.nan
    return out


def _raised_table(meas: pd.DataFrame, codes, keys, declared_var, k_along, raised, used_rows) -> pd.DataFrame:
    """NoiseEstimate.aircraft: the aircraft and classes the per-aircraft guard raised."""
    sel = raised > 1.0
    if not sel.any():
        return pd.DataFrame(columns=AIRCRAFT_COLUMNS)
    frame = pd.DataFrame({"aircraft_id": meas["aircraft_id"].astype(str).to_numpy()[sel], "code": codes[sel],
                          "raised": raised[sel], "used": used_rows[sel]})
    out = frame.groupby(["aircraft_id", "code"], sort=True).agg(raised=("raised", "first"),
                                                               residuals=("used", "sum")).reset_index()
    key = [keys[c] for c in out["code"]]
    declared = np.sqrt(declared_var[out["code"].to_numpy()])
    out["class_sigma_m"] = declared * k_along[out["code"].to_numpy()]
    out = out.assign(sensor_id=[k[0] for k in key], motion=[k[5] for k in key], declared_sigma_m=declared,
                     estimated_sigma_m=out["class_sigma_m"] * out["raised"],
                     residuals=out["residuals"].astype(int))
    return out[AIRCRAFT_COLUMNS]
