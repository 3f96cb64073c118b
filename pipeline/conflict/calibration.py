"""Calibration of predicted covariances: how often the outcome falls inside the predicted ellipse.

A prediction (mean, 2x2 covariance) made h seconds ahead is scored against the position the aircraft
reported at exactly t + h (linear interpolation between the two reports around it). For a calibrated
Gaussian prediction the squared Mahalanobis distance is chi-square with 2 degrees of freedom: a share
`p` of the outcomes falls inside the ellipse d2 <= chi2(2).ppf(p) = -2 ln(1 - p) (5.991 for 95 %).
"""

from __future__ import annotations

import math

import numpy as np


def chi2_2_ppf(p: float) -> float:
    """Quantile of the chi-square distribution with 2 degrees of freedom, in closed form: -2 ln(1 - p)."""
    return -2.0 * math.log1p(-p)


def mahalanobis2(error: np.ndarray, cov: np.ndarray) -> np.ndarray:
    """Squared Mahalanobis distances e^T C^-1 e of errors (n, 2) under covariances (n, 2, 2)."""
    e = np.asarray(error, float)
    c = np.asarray(cov, float)
    a, b, d = c[:, 0, 0], 0.5 * (c[:, 0, 1] + c[:, 1, 0]), c[:, 1, 1]
    det = a * d - b * b
    return (d * e[:, 0] ** 2 - 2.0 * b * e[:, 0] * e[:, 1] + a * e[:, 1] ** 2) / det


def interpolate_reports(t_s: np.ndarray, east_m: np.ndarray, north_m: np.ndarray, query_s: np.ndarray,
                        max_gap_s: float = 5.0) -> np.ndarray:
    """Positions (n, 2) at query times by linear interpolation between the two reports around each
    (report times strictly increasing); NaN outside the reports or where those two reports are more than
    max_gap_s apart (no interpolation across a dropout), unless the query falls on a report."""
    t = np.asarray(t_s, float)
    q = np.asarray(query_s, float)
    out = np.full((len(q), 2), np.nan)
    if len(t) < 2:
        return out
    hi = np.clip(np.searchsorted(t, q, side="left"), 1, len(t) - 1)
    lo = hi - 1
    span = t[hi] - t[lo]
    on_report = (q == t[lo]) | (q == t[hi])
    ok = (q >= t[0]) & (q <= t[-1]) & ((span <= max_gap_s) | on_report)
    w = (q - t[lo]) / span
    for k, v in enumerate((np.asarray(east_m, float), np.asarray(north_m, float))):
        out[ok, k] = (v[lo] + w * (v[hi] - v[lo]))[ok]
    return out


def coverage(d2: np.ndarray, p: float = 0.95) -> float:
    """Share of squared Mahalanobis distances inside the p-ellipse (NaN for none)."""
    d2 = np.asarray(d2, float)
    d2 = d2[np.isfinite(d2)]
    return float((d2 <= chi2_2_ppf(p)).mean()) if len(d2) else math.nan
