"""IMM prediction without measurements as one linear map on the mode-weighted moments, batched in numba.

Without measurements the IMM cycle (mixing, mode-matched F x, F P F^T + Q, mu <- PI^T mu) propagates
exactly the first two moments of the Markov-jump linear system. In the mode-weighted moments
s = (mu_j, y_j = mu_j x_j, N_j = mu_j (P_j + x_j x_j^T)) one cycle over dt is linear:

    mu'_j = sum_i PI_ij mu_i,  y'_j = F_j sum_i PI_ij y_i,  N'_j = F_j (sum_i PI_ij N_i) F_j^T + mu'_j Q_j

and the mixture mean and second moment (spread of the mode means included) are sum_j y_j and sum_j N_j.
So the prediction to a horizon is a fixed matrix per (config, cycle, horizon), computed once, and each
output time costs a few hundred multiply-adds instead of one IMM cycle per step. Positions are taken
relative to the combined position before forming s (every mode's F leaves a pure position unchanged, so
this is exact) to keep the second moments small.
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np
from numba import njit

from msdc.pipeline.track.imm import NX, coast_chain, cycle_scratch, tpm_into, transition_into

POSITION_PAIRS = ((0, 0), (0, 3), (3, 3))  # east-east, east-north, north-north
ALL_PAIRS = tuple((a, b) for a in range(NX) for b in range(NX))


def _dims(r: int) -> tuple[int, int, int]:
    """Offsets of the y and N blocks in s and its length."""
    return r, r + NX * r, r * (1 + NX + NX * NX)


def step_matrix(args: dict, dt: float) -> np.ndarray:
    """The linear map of one prediction cycle over dt (s) on s (see the module docstring)."""
    kinds = args["kinds"]
    r = len(kinds)
    oy, on, d = _dims(r)
    PI = np.empty((r, r))
    tpm_into(args["tpm_kind"], args["tpm_param"], args["tpm_param2"], float(dt), r, PI)
    L = np.zeros((d, d))
    F, Q = np.empty((NX, NX)), np.empty((NX, NX))
    for j in range(r):
        transition_into(kinds[j], args["omegas"][j], args["qs"][j], float(dt), F, Q)
        FF = np.kron(F, F)
        for i in range(r):
            w = PI[i, j]
            L[j, i] = w
            L[oy + NX * j:oy + NX * (j + 1), oy + NX * i:oy + NX * (i + 1)] = w * F
            L[on + NX * NX * j:on + NX * NX * (j + 1), on + NX * NX * i:on + NX * NX * (i + 1)] = w * FF
            L[on + NX * NX * j:on + NX * NX * (j + 1), i] = w * Q.ravel()
    return L


def horizon_matrices(args: dict, aheads_s, cycle_s: float, pairs=POSITION_PAIRS) -> np.ndarray:
    """(len(aheads_s), NX + len(pairs), D): rows giving, from s, the mixture mean (NX) and the second
    moments of `pairs` after predicting each ahead_s in cycles of cycle_s (the last one shorter)."""
    r = len(args["kinds"])
    oy, on, d = _dims(r)
    C = np.zeros((NX + len(pairs), d))
    for j in range(r):
        for a in range(NX):
            C[a, oy + NX * j + a] = 1.0
        for k, (a, b) in enumerate(pairs):
            C[NX + k, on + NX * NX * j + NX * a + b] = 1.0
    L = step_matrix(args, cycle_s)
    out = np.empty((len(aheads_s),) + C.shape)
    for h, ahead in enumerate(aheads_s):
        n = math.ceil(ahead / cycle_s - 1e-9)
        last = ahead - (n - 1) * cycle_s if n else 0.0
        R = C if n == 0 else C @ (L if abs(last - cycle_s) < 1e-9 * cycle_s else step_matrix(args, last))
        for _ in range(max(n - 1, 0)):
            R = R @ L
        out[h] = R
    return out


@lru_cache(maxsize=32)
def _cached(key, aheads: tuple[float, ...], cycle_s: float, pairs: tuple) -> np.ndarray:
    kinds, omegas, qs, tpm_kind, tpm_param, tpm_param2 = key
    args = {"kinds": np.array(kinds, np.int64), "omegas": np.array(omegas), "qs": np.array(qs),
            "tpm_kind": tpm_kind, "tpm_param": tpm_param, "tpm_param2": tpm_param2}
    out = horizon_matrices(args, aheads, cycle_s, pairs)
    out.flags.writeable = False
    return out


def cached_horizon_matrices(args: dict, aheads_s, cycle_s: float, pairs=POSITION_PAIRS) -> np.ndarray:
    """`horizon_matrices`, computed once per mode set, TPM, horizons and cycle."""
    key = (tuple(int(k) for k in args["kinds"]), tuple(float(w) for w in args["omegas"]),
           tuple(float(q) for q in args["qs"]), int(args["tpm_kind"]), float(args["tpm_param"]),
           float(args["tpm_param2"]))
    return _cached(key, tuple(float(a) for a in aheads_s), float(cycle_s), tuple(pairs))


@njit(cache=True, nogil=True)
def predict_batch(gov, dt, kinds, omegas, qs, tpm_kind, tpm_param, tpm_param2, cycle_s, mu_h, x_h, P_h,
                  A_mean, cols_mean, A_moment, cols_moment, pair_a, pair_b, mean_out, cov_out):
    """For each query q: the posterior of row gov[q] (mu_h, x_h, P_h) coasted dt[q] s by IMM cycles of at
    most cycle_s (consecutive queries with the same row continue one chain, dt ascending), then every
    horizon at once: mean = A_mean[h] @ s[cols_mean], second moments = A_moment[h] @ s[cols_moment] (the
    nonzero columns of `horizon_matrices`); mean_out (m, H, NX), cov_out (m, H, K) the mixture
    covariance of the K index pairs (pair_a[k], pair_b[k])."""
    r = kinds.shape[0]
    m = gov.shape[0]
    n_h = A_mean.shape[0]
    n_k = pair_a.shape[0]
    oy = r
    on = r + NX * r
    PI, F, Q, tmp, cbar, x0, P0, xp, Pp = cycle_scratch(r)
    mu_c = np.empty(r)
    x_c = np.empty((r, NX))
    P_c = np.empty((r, NX, NX))
    s = np.empty(r * (1 + NX + NX * NX))
    mean = np.empty(NX)
    g_c = np.int64(-1)
    t_c = 0.0
    for q in range(m):
        g = gov[q]
        d = dt[q]
        g_c, t_c = coast_chain(g, d, g_c, t_c, cycle_s, 1e-9, mu_h, x_h, P_h, kinds, omegas, qs, tpm_kind,
                               tpm_param, tpm_param2, r, mu_c, x_c, P_c, PI, F, Q, tmp, cbar, x0, P0, xp, Pp)
        ce = 0.0
        cn = 0.0
        for j in range(r):
            ce += mu_c[j] * x_c[j, 0]
            cn += mu_c[j] * x_c[j, 3]
        # mode-weighted moments, positions relative to the combined position
        for j in range(r):
            w = mu_c[j]
            s[j] = w
            for a in range(NX):
                xa = x_c[j, a] - (ce if a == 0 else (cn if a == 3 else 0.0))
                s[oy + NX * j + a] = w * xa
                for b in range(NX):
                    xb = x_c[j, b] - (ce if b == 0 else (cn if b == 3 else 0.0))
                    s[on + NX * NX * j + NX * a + b] = w * (P_c[j, a, b] + xa * xb)
        for h in range(n_h):
            for a in range(NX):
                acc = 0.0
                for k in range(cols_mean.shape[0]):
                    acc += A_mean[h, a, k] * s[cols_mean[k]]
                mean[a] = acc
            for k in range(n_k):
                acc = 0.0
                for i in range(cols_moment.shape[0]):
                    acc += A_moment[h, k, i] * s[cols_moment[i]]
                cov_out[q, h, k] = acc - mean[pair_a[k]] * mean[pair_b[k]]
            for a in range(NX):
                mean_out[q, h, a] = mean[a]
            mean_out[q, h, 0] += ce
            mean_out[q, h, 3] += cn


def predict_states(args: dict, gov, dt, mu_h, x_h, P_h, aheads_s, cycle_s: float, pairs=POSITION_PAIRS
                   ) -> tuple[np.ndarray, np.ndarray]:
    """Mixture means (m, H, NX) and covariances of `pairs` (m, H, K) of the posteriors mu_h/x_h/P_h[gov]
    coasted dt s (ascending within each row) and predicted each ahead_s further, in cycles of cycle_s."""
    A = cached_horizon_matrices(args, aheads_s, cycle_s, pairs)
    # only the columns some row uses (CV and turn modes never touch the acceleration moments)
    cols_mean = np.flatnonzero((A[:, :NX] != 0).any(axis=(0, 1)))
    cols_moment = np.flatnonzero((A[:, NX:] != 0).any(axis=(0, 1)))
    A_mean = np.ascontiguousarray(A[:, :NX][:, :, cols_mean])
    A_moment = np.ascontiguousarray(A[:, NX:][:, :, cols_moment])
    gov = np.ascontiguousarray(gov, np.int64)
    m = len(gov)
    mean = np.empty((m, A.shape[0], NX))
    cov = np.empty((m, A.shape[0], len(pairs)))
    pa = np.array([p[0] for p in pairs], np.int64)
    pb = np.array([p[1] for p in pairs], np.int64)
    predict_batch(gov, np.ascontiguousarray(dt, float), args["kinds"], args["omegas"], args["qs"],
                  args["tpm_kind"], args["tpm_param"], args["tpm_param2"], float(cycle_s),
                  np.ascontiguousarray(mu_h, float), np.ascontiguousarray(x_h, float),
                  np.ascontiguousarray(P_h, float), A_mean, cols_mean.astype(np.int64), A_moment,
                  cols_moment.astype(np.int64), pa, pb, mean, cov)
    return mean, cov
