"""Measurement covariances in the local east/north frame at the report (m^2)."""

from __future__ import annotations

import numpy as np

from msdc.pipeline.model.measurements import CIRCULAR_95_PER_SIGMA, NACP_95_M

EARTH_RADIUS_M = 6371000.0
# NACp 95 % horizontal position bounds (EPU), m, DO-260B (NACp 0, unknown, has none): the measurement model's
# table, so that the tracker and the model give one covariance per level
NACP_EPU_M = dict(sorted(NACP_95_M.items()))
# NACv (DO-260B) and NUCr (DO-260/260A, the same levels): 95 % horizontal velocity error bounds, m/s;
# level 0 is "unknown or >= 10 m/s" and bounds nothing
NACV_95_M_S = {1: 10.0, 2: 3.0, 3: 1.0, 4: 0.3}
# a circular Gaussian holds 95 % within sqrt(-2 ln 0.05) = 2.4477 sigma (the model's constant)
SIGMA_PER_95_BOUND = 1.0 / CIRCULAR_95_PER_SIGMA


def radar_covariance(rho_m, theta_deg, target_height_m, site_height_m, sigma_range_m, sigma_azimuth_deg,
                     convergence_deg=0.0, earth_radius_m: float = EARTH_RADIUS_M):
    """(cov_ee_m2, cov_en_m2, cov_nn_m2) of a radar plot converted to a horizontal position.

    The slant range rho is turned into the ground arc g by the spherical triangle of site and target
    heights (tracking.md 5.1), east = g sin(theta), north = g cos(theta) with theta clockwise from north,
    and R = J diag(sigma_range^2, sigma_azimuth^2) J^T with J the Jacobian of (east, north) by (rho,
    theta). convergence_deg rotates the result from the radar's north into the report's local north
    (the true azimuth of the line of sight at the target minus theta). A target height above the
    reachable range gives NaN.
    """
    rho, theta, ht, hs, sr, sa, conv = np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in (
        rho_m, theta_deg, target_height_m, site_height_m, sigma_range_m, sigma_azimuth_deg,
        convergence_deg)))
    ra = earth_radius_m + hs
    rb = earth_radius_m + np.where(np.isnan(ht), hs, ht)
    cos_gamma = (ra * ra + rb * rb - rho * rho) / (2.0 * ra * rb)
    with np.errstate(invalid="ignore"):
        gamma = np.arccos(np.where(np.abs(cos_gamma) <= 1.0, cos_gamma, np.nan))
        ground_m = earth_radius_m * gamma
        # d(gamma)/d(rho) = rho / (ra rb sin gamma)
        dg_drho = earth_radius_m * rho / (ra * rb * np.sin(gamma))
    dg_drho = np.where(gamma > 0.0, dg_drho, 1.0)
    az = np.radians(theta + conv)
    s, c = np.sin(az), np.cos(az)
    var_along = (dg_drho * sr) ** 2
    var_cross = (ground_m * np.radians(sa)) ** 2
    cov_ee = var_along * s * s + var_cross * c * c
    cov_nn = var_along * c * c + var_cross * s * s
    cov_en = (var_along - var_cross) * s * c
    return cov_ee, cov_en, cov_nn


def nacp_covariance(nacp):
    """Isotropic ADS-B covariance (m^2) per axis from NACp: (EPU / 2.4477)^2, as the measurement model's
    cov_ee_m2 / cov_nn_m2 (NACp 11: 1.50 m^2); NaN where NACp is 0, missing or out of range."""
    values = np.asarray(nacp, dtype=float)
    epu = np.full(values.shape, np.nan)
    for level, bound in NACP_EPU_M.items():
        epu[values == level] = bound
    sigma = epu * SIGMA_PER_95_BOUND
    return sigma * sigma


def nacv_variance(nucr_nacv):
    """Per-axis variance ((m/s)^2) of a reported ADS-B velocity from NUCr / NACv: (bound / 2.4477)^2; NaN
    where the level is 0 (unknown), missing or out of range."""
    values = np.asarray(nucr_nacv, dtype=float)
    bound = np.full(values.shape, np.nan)
    for level, b in NACV_95_M_S.items():
        bound[values == level] = b
    return (bound * SIGMA_PER_95_BOUND) ** 2


def principal_variances(cov: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The larger and smaller eigenvalues of each symmetric 2 x 2 covariance (n, 2, 2), in closed form: the
    variances along the error ellipse's major and minor axes (m^2; unclipped)."""
    a, b, c = cov[:, 0, 0], 0.5 * (cov[:, 0, 1] + cov[:, 1, 0]), cov[:, 1, 1]
    mean, half = 0.5 * (a + c), np.hypot(0.5 * (a - c), b)
    return mean + half, mean - half
