"""A small numpy CV/CA IMM written from the conflict paper's description (tracking.md 4.2-4.3), apart from
msdc's numba kernel: it can rotate the CA noise with the heading (the paper's Q_CA = Rot(psi)
diag(sigma_along^2, sigma_cross^2) Rot(psi)^T), which the kernel cannot. With isotropic noise its
prediction is the kernel's (checked in tests/test_conflict_paper_scenarios.py).

State per mode: [east, v_east, a_east, north, v_north, a_north] (m, m/s, m/s^2). CV zeroes the
acceleration; process noise is piecewise-constant per step (acceleration for CV, jerk for CA) with
g = [T^2/2, T, 0] (CV) or [T^2/2, T, 1] (CA), as the kernel and tracking.md 4.2.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

NX = 6


@dataclass(frozen=True)
class PaperMode:
    """kind "cv" or "ca"; sigma (m/s^2 for CV, m/s^3 for CA) isotropic, or along/cross-track (CA only)."""

    kind: str
    sigma: float
    sigma_cross: float | None = None  # CA only: heading-aligned noise, sigma along and this across


def transition(mode: PaperMode, dt: float, velocity=None) -> tuple[np.ndarray, np.ndarray]:
    """F and Q (6x6) of one mode over dt; velocity (v_east, v_north) orients heading-aligned noise."""
    if mode.kind == "cv":
        f = np.array([[1.0, dt, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 0.0]])
        g = np.array([dt * dt / 2.0, dt, 0.0])
    else:
        f = np.array([[1.0, dt, dt * dt / 2.0], [0.0, 1.0, dt], [0.0, 0.0, 1.0]])
        g = np.array([dt * dt / 2.0, dt, 1.0])
    F = np.zeros((NX, NX))
    F[:3, :3] = f
    F[3:, 3:] = f
    if mode.sigma_cross is None or mode.kind == "cv":
        sigma = np.eye(2) * mode.sigma**2
    else:
        v = np.asarray(velocity, float)
        speed = np.hypot(*v)
        u = v / speed if speed > 1e-6 else np.array([1.0, 0.0])
        c = np.array([-u[1], u[0]])
        sigma = mode.sigma**2 * np.outer(u, u) + mode.sigma_cross**2 * np.outer(c, c)
    Q = np.kron(sigma, np.outer(g, g))
    return F, Q


def tpm_fixed(p: float, r: int) -> np.ndarray:
    """The kernel's fixed law: mode 0 stays with p and leaves evenly; the others return to 0 or stay."""
    if r == 1:
        return np.ones((1, 1))
    out = np.zeros((r, r))
    out[0, 0] = p
    out[0, 1:] = (1.0 - p) / (r - 1)
    out[1:, 0] = 1.0 - p
    out[np.arange(1, r), np.arange(1, r)] = p
    return out


def _mix(PI, mu, x, P):
    cbar = PI.T @ mu
    w = PI * mu[:, None] / np.where(cbar > 0, cbar, 1.0)[None, :]  # w[i, j] = mu_{i|j}
    x0 = w.T @ x
    P0 = np.empty_like(P)
    for j in range(len(mu)):
        d = x - x0[j]
        P0[j] = np.einsum("i,iab->ab", w[:, j], P + d[:, :, None] * d[:, None, :])
    return cbar, x0, P0


def combine(mu, x, P) -> tuple[np.ndarray, np.ndarray]:
    """Mixture mean and covariance, including the spread of the mode means."""
    xc = mu @ x
    d = x - xc
    return xc, np.einsum("j,jab->ab", mu, P + d[:, :, None] * d[:, None, :])


def predict(modes, PI, mu, x, P, dt):
    """One IMM cycle without a measurement: (mu, x, P) of every mode after dt."""
    cbar, x0, P0 = _mix(PI, mu, x, P)
    xo, Po = np.empty_like(x0), np.empty_like(P0)
    for j, m in enumerate(modes):
        F, Q = transition(m, dt, x0[j, [1, 4]])
        xo[j] = F @ x0[j]
        Po[j] = F @ P0[j] @ F.T + Q
    return cbar, xo, Po


def propagate(modes, PI, mu, x, P, horizon_s: float, step_s: float = 1.0):
    """Combined mean and covariance after horizon_s of prediction cycles of step_s (a whole multiple)."""
    for _ in range(int(round(horizon_s / step_s))):
        mu, x, P = predict(modes, PI, mu, x, P, step_s)
    return combine(mu, x, P)


def filter_track(modes, p_stay: float, t, z, var_m2: float, var_v0: float = 200.0**2, var_a0: float = 25.0):
    """Filter positions z (n, 2) at times t with isotropic noise var_m2; returns per time the posterior
    (mu (n, r), x (n, r, 6), P (n, r, 6, 6)). Start: first position, zero velocity of variance var_v0,
    zero acceleration of variance var_a0 in CA modes, mode probabilities 0.8 / 0.2 (the kernel's)."""
    modes = tuple(modes)
    r = len(modes)
    PI = tpm_fixed(p_stay, r)
    H = np.zeros((2, NX))
    H[0, 0] = H[1, 3] = 1.0
    R = np.eye(2) * var_m2
    mu = np.array([1.0]) if r == 1 else np.r_[0.8, np.full(r - 1, 0.2 / (r - 1))]
    x = np.zeros((r, NX))
    x[:, 0], x[:, 3] = z[0]
    P = np.zeros((r, NX, NX))
    for j, m in enumerate(modes):
        P[j] = np.diag([var_m2, var_v0, var_a0 if m.kind == "ca" else 0.0] * 2)
    mus, xs, Ps = [mu.copy()], [x.copy()], [P.copy()]
    for k in range(1, len(t)):
        cbar, xp, Pp = predict(modes, PI, mu, x, P, t[k] - t[k - 1])
        like = np.empty(r)
        for j in range(r):
            S = H @ Pp[j] @ H.T + R
            nu = z[k] - H @ xp[j]
            K = Pp[j] @ H.T @ np.linalg.inv(S)
            x[j] = xp[j] + K @ nu
            P[j] = Pp[j] - K @ S @ K.T
            like[j] = np.exp(-0.5 * nu @ np.linalg.solve(S, nu)) / np.sqrt(np.linalg.det(2 * np.pi * S))
        mu = like * cbar
        mu = mu / mu.sum() if mu.sum() > 0 else cbar
        mus.append(mu.copy())
        xs.append(x.copy())
        Ps.append(P.copy())
    return np.array(mus), np.array(xs), np.array(Ps)
