"""Whether a radar's bias fit can be trusted: its residuals against the declared sigmas, and a site offset.

``goodness_of_fit``: the normalised chi-square per degree of freedom of the bias fit's kept rows, each
residual divided by the sigma declared for it: the radar's (the sensor file's ``sigma_range_m`` and
``sigma_azimuth_deg``) and the ADS-B reference's (per axis, from its NACp's 95 % bound / 2.4477, the 95 %
radius of a circular Gaussian; none when NACp is unknown) added in quadrature. About 1 when the four biases
and the declared noise explain the errors; above CHI2_TRUST_MAX (residuals twice the declared sigmas) the
fit is not trusted.

``site_offset``: the four-bias model extended by a horizontal offset (east, north) of the radar from its
declared site. Seen from a site displaced by d, a target at (e, n) from the declared site is at slant range
|p| - (e d_e + n d_n) / slant and azimuth az + (e d_n - n d_e) / g^2 (g the ground range): a range error
that follows the azimuth as a sinusoid and an azimuth error falling with range, which no range bias, gain,
azimuth bias or time bias can take. The offset is flagged when it is significant (Wald statistic above the
chi-square 99.9 % point for 2 degrees of freedom) and larger than SITE_OFFSET_MIN_M.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from msdc.pipeline.model.measurements import NACP_95_M

CHI2_TRUST_MAX = 4.0  # residuals twice the declared sigmas: the model or the sigmas are wrong
WALD_2DOF_999 = 13.816  # chi-square, 2 degrees of freedom, 99.9 % point (any chi-square table)
SITE_OFFSET_MIN_M = 100.0  # below this an offset is within what range and azimuth biases absorb harmlessly
R95_PER_SIGMA = 2.4477  # 95 % radius of a circular Gaussian over its per-axis sigma: sqrt(-2 ln 0.05)
DECLARED_COLUMNS = ("sigma_range_m", "sigma_azimuth_deg")


def reference_sigma_m(nacp: np.ndarray) -> np.ndarray:
    """Per-axis 1-sigma of the ADS-B reference from its NACp (0 where NACp is unknown)."""
    bound = pd.Series(nacp).map(lambda v: NACP_95_M.get(int(v), np.nan) if pd.notna(v) else np.nan)
    return np.nan_to_num(bound.to_numpy(float) / R95_PER_SIGMA)


def declared_sigmas(e: pd.DataFrame) -> np.ndarray | None:
    """Per fit row (range rows, then azimuth rows) the declared sigma of its residual (m, deg), or None
    when the errors carry no declared radar sigmas."""
    if not set(DECLARED_COLUMNS) <= set(e.columns):
        return None
    ref_m = reference_sigma_m(e["adsb_nacp"].to_numpy(float) if "adsb_nacp" in e else np.full(len(e), np.nan))
    ground = e["ground_range_m"].to_numpy(float)
    range_m = np.hypot(e["sigma_range_m"].to_numpy(float), ref_m)
    azimuth_deg = np.hypot(e["sigma_azimuth_deg"].to_numpy(float), np.degrees(ref_m / ground))
    return np.concatenate([range_m, azimuth_deg])


def chi2_per_dof(residuals: np.ndarray, sigmas: np.ndarray | None, n_params: int) -> float:
    """Sum of squared normalised residuals over the degrees of freedom; NaN without sigmas or freedom."""
    if sigmas is None or residuals.size <= n_params:
        return float("nan")
    return float(np.sum((residuals / sigmas) ** 2) / (residuals.size - n_params))


def offset_columns(e: pd.DataFrame) -> np.ndarray | None:
    """The two design columns (east, north offset of the radar in m) of the range rows then the azimuth
    rows; None when the errors lack the reference azimuth."""
    if "azimuth_deg" not in e:
        return None
    az = np.radians(e["azimuth_deg"].to_numpy(float))
    ground, slant = e["ground_range_m"].to_numpy(float), e["slant_range_m"].to_numpy(float)
    east, north = ground * np.sin(az), ground * np.cos(az)
    range_rows = np.column_stack([-east / slant, -north / slant])
    azimuth_rows = np.degrees(np.column_stack([-north, east]) / (ground**2)[:, None])
    return np.vstack([range_rows, azimuth_rows])


def offset_verdict(offset_m: np.ndarray, cov_m2: np.ndarray) -> tuple[float, bool]:
    """The Wald statistic of a fitted site offset (east, north) and whether it is flagged."""
    if not (np.all(np.isfinite(offset_m)) and np.all(np.isfinite(cov_m2))):
        return float("nan"), False
    try:
        wald = float(offset_m @ np.linalg.solve(cov_m2, offset_m))
    except np.linalg.LinAlgError:
        return float("nan"), False
    return wald, bool(wald > WALD_2DOF_999 and np.hypot(*offset_m) > SITE_OFFSET_MIN_M)


def fit_warning(chi2: float, offset_m: np.ndarray, flagged: bool) -> str:
    """Why a radar's fit cannot be trusted ("" when nothing says so)."""
    said = []
    if flagged:
        east, north = offset_m
        bearing = np.degrees(np.arctan2(east, north)) % 360.0
        said.append(f"the errors follow the azimuth as a radar {np.hypot(east, north):.0f} m from its "
                    f"declared site would (toward bearing {bearing:.0f} deg: {east:+.0f} m east, "
                    f"{north:+.0f} m north): check the site in the sensor file; the four biases absorb "
                    "part of it and are not to be trusted")
    if np.isfinite(chi2) and chi2 > CHI2_TRUST_MAX:
        said.append(f"the residuals are {np.sqrt(chi2):.1f} times the declared sigmas (chi-square per "
                    f"degree of freedom {chi2:.1f} > {CHI2_TRUST_MAX:g}): the four biases do not explain "
                    "the errors, or the sensor file's sigmas are wrong; the fit is not to be trusted")
    return "; ".join(said)
