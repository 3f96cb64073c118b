"""Independent references for the probability of conflict, shared by the tests and
benchmarks/conflict_validation.py: QUADPACK quadrature of the density over the disc, and covariances
built from their axes."""

import numpy as np
from scipy import integrate


def polar_reference(m, p, d) -> float:
    """Adaptive quadrature (QUADPACK) of the Gaussian density over the disc, in polar coordinates about
    the origin, the angle restricted to where the density is not negligible (10 sigma)."""
    m, p = np.asarray(m, float), np.asarray(p, float)
    p_inv = np.linalg.inv(p)
    norm = 1 / (2 * np.pi * np.sqrt(np.linalg.det(p)))
    s_max = np.sqrt(np.linalg.eigvalsh(p)[-1])
    r_m, a_m = np.hypot(*m), np.arctan2(m[1], m[0])
    r_lo, r_hi = max(0.0, r_m - 10 * s_max), min(d, r_m + 10 * s_max)
    if r_hi <= r_lo:
        return 0.0
    half = np.arcsin(min(1.0, 10 * s_max / r_m)) if r_m > 10 * s_max else np.pi

    def density(r, a):
        v = np.array([r * np.cos(a) - m[0], r * np.sin(a) - m[1]])
        return norm * np.exp(-0.5 * v @ p_inv @ v) * r

    def ring(a):
        return integrate.quad(density, r_lo, r_hi, args=(a,), epsabs=1e-13, epsrel=1e-11, limit=400)[0]

    return integrate.quad(ring, a_m - half, a_m + half, points=[a_m], epsabs=1e-12, epsrel=1e-10,
                          limit=400)[0]


def rotated(sigma_major, sigma_minor, angle) -> np.ndarray:
    """The covariance with these standard deviations along axes turned by ``angle`` (rad)."""
    c, s = np.cos(angle), np.sin(angle)
    u = np.array([[c, -s], [s, c]])
    return u @ np.diag([sigma_major**2, sigma_minor**2]) @ u.T
