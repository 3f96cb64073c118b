"""Backward passes: Rauch-Tung-Striebel smoothing of the combined IMM estimate (`smooth_rows`, the
default) and an IMM smoother with per-mode states and smoothed mode probabilities (`imm_smooth_rows`).

RTS on the combined estimate: between consecutive accepted updates k and k+1 the joint law of
(x_k, x_k+1) is taken from the IMM's own prediction: mixing with PI(dt), then per target mode j,
x_k ~ N(x0_j, P0_j) and x_k+1 = F_j x_k + w_j, so
Cov(x_k, x_k+1) = sum_j cbar_j [P0_j F_j^T + (x0_j - x_k)(xp_j - xp)^T]. Output times between two
updates are smoothed from the same joint law (the acceleration noise is constant over the interval, as
in the filter's process model), which keeps every joint covariance positive semi-definite.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .imm import (
    CA,
    NX,
    combine_into,
    fpft_q,
    fx_into,
    mix_into,
    predicted_modes_into,
    tpm_into,
    transition_into,
)


@njit(cache=True, nogil=True)
def _inverse(A, out, work):
    """out = A^-1 for a 6x6 covariance; exactly-zero variances (CV/CT acceleration states without a
    CA mode) are replaced by 1, which leaves the gain's columns for them at zero."""
    for i in range(NX):
        for j in range(NX):
            work[i, j] = A[i, j]
            out[i, j] = 1.0 if i == j else 0.0
        if work[i, i] <= 0.0:
            for j in range(NX):
                work[i, j] = 0.0
                work[j, i] = 0.0
            work[i, i] = 1.0
    for c in range(NX):
        p = c
        for i in range(c + 1, NX):
            if abs(work[i, c]) > abs(work[p, c]):
                p = i
        if p != c:
            for j in range(NX):
                work[c, j], work[p, j] = work[p, j], work[c, j]
                out[c, j], out[p, j] = out[p, j], out[c, j]
        d = work[c, c]
        for j in range(NX):
            work[c, j] /= d
            out[c, j] /= d
        for i in range(NX):
            if i != c:
                f = work[i, c]
                if f != 0.0:
                    for j in range(NX):
                        work[i, j] -= f * work[c, j]
                        out[i, j] -= f * out[c, j]


@njit(cache=True, nogil=True)
def _gamma_cross(kind, q, a, t, Qx):
    """Cov(noise over [0, a], noise over [0, t]) for one constant acceleration (CA: jerk) per step."""
    for i in range(NX):
        for j in range(NX):
            Qx[i, j] = 0.0
    if kind == CA:
        ga = (0.5 * a * a, a, 1.0)
        gt = (0.5 * t * t, t, 1.0)
        n = 3
    else:
        ga = (0.5 * a * a, a, 0.0)
        gt = (0.5 * t * t, t, 0.0)
        n = 2
    for o in (0, 3):
        for i in range(n):
            for j in range(n):
                Qx[o + i, o + j] = q * ga[i] * gt[j]


@njit(cache=True, nogil=True)
def _apply_gain(C, Pbar_inv, xf, Pf, xs_next, Ps_next, xbar, Pbar, G, tmp, xs, Ps):
    """G = C Pbar^-1; xs = xf + G (xs_next - xbar); Ps = Pf + G (Ps_next - Pbar) G^T (Pbar is scratch: it
    holds Ps_next - Pbar afterwards)."""
    for i in range(NX):
        for j in range(NX):
            acc = 0.0
            for k in range(NX):
                acc += C[i, k] * Pbar_inv[k, j]
            G[i, j] = acc
    for i in range(NX):
        acc = xf[i]
        for k in range(NX):
            acc += G[i, k] * (xs_next[k] - xbar[k])
        xs[i] = acc
    for i in range(NX):
        for j in range(NX):
            Pbar[i, j] = Ps_next[i, j] - Pbar[i, j]
    fpft_q(G, Pbar, Pf, tmp, Ps)


@njit(cache=True, nogil=True)
def smooth_rows(acc_t, acc_seg, mu_a, x_a, P_a, kinds, omegas, qs, tpm_kind, tpm_param, tpm_param2,
                q_acc, q_dt, xf_q, Pf_q, xs_q, Ps_q):
    """Smoothed combined estimate at every query q (q_acc: index of its governing accepted update, in
    ascending order; q_dt: time after it). Queries after a segment's last update keep their forward
    prediction. The queries between two updates are smoothed in the backward pass, from the same joint
    law of the interval (and its inverse) as the update they follow."""
    na = acc_t.shape[0]
    r = kinds.shape[0]
    xs = np.empty((na, NX))
    Ps = np.empty((na, NX, NX))
    cbar = np.empty(r)
    x0 = np.empty((r, NX))
    P0 = np.empty((r, NX, NX))
    xp = np.empty((r, NX))
    Pp = np.empty((r, NX, NX))
    PI = np.empty((r, r))
    Fa = np.empty((NX, NX))
    Qa = np.empty((NX, NX))
    Ft = np.empty((NX, NX))
    Qt = np.empty((NX, NX))
    Cj = np.empty((NX, NX))
    C = np.empty((NX, NX))
    G = np.empty((NX, NX))
    tmp = np.empty((NX, NX))
    work = np.empty((NX, NX))
    Pbar_inv = np.empty((NX, NX))
    xbar = np.empty(NX)
    Pbar = np.empty((NX, NX))
    Pbar_k = np.empty((NX, NX))
    xk = np.empty(NX)
    Pk = np.empty((NX, NX))
    xt = np.empty((r, NX))
    Pt = np.empty((r, NX, NX))
    xtc = np.empty(NX)
    Ptc = np.empty((NX, NX))
    q = q_acc.shape[0] - 1  # the last query not yet smoothed (queries go back with the updates)
    # backward pass over accepted updates, and the queries inside each interval
    for k in range(na - 1, -1, -1):
        combine_into(mu_a[k], x_a[k], P_a[k], r, xs[k], Ps[k])
        if k == na - 1 or acc_seg[k + 1] != acc_seg[k]:
            continue
        for a in range(NX):
            xk[a] = xs[k, a]
            for b in range(NX):
                Pk[a, b] = Ps[k, a, b]
        t = acc_t[k + 1] - acc_t[k]
        _joint(kinds, omegas, qs, tpm_kind, tpm_param, tpm_param2, t, r, mu_a[k], x_a[k], P_a[k], xk, PI,
               cbar, x0, P0, xp, Pp, Ft, Qt, Cj, C, tmp, xbar, Pbar)
        _inverse(Pbar, Pbar_inv, work)
        for a in range(NX):
            for b in range(NX):
                Pbar_k[a, b] = Pbar[a, b]  # _apply_gain leaves Ps_next - Pbar in Pbar
        _apply_gain(C, Pbar_inv, xk, Pk, xs[k + 1], Ps[k + 1], xbar, Pbar, G, tmp, xs[k], Ps[k])
        while q >= 0 and q_acc[q] > k:
            q -= 1
        while q >= 0 and q_acc[q] == k:
            a = q_dt[q]
            if a != 0.0:
                _query_between(kinds, omegas, qs, a, t, r, cbar, x0, P0, xp, xbar, Pbar_k, Pbar_inv,
                               xs[k + 1], Ps[k + 1], Fa, Qa, Ft, Qt, Cj, C, G, tmp, xt, Pt, xtc, Ptc, Pbar,
                               xs_q[q], Ps_q[q])
            q -= 1
    # queries at an update, and after a segment's last one
    for q in range(q_acc.shape[0]):
        k = q_acc[q]
        if q_dt[q] == 0.0:
            _copy_state(xs[k], Ps[k], xs_q[q], Ps_q[q])
        elif k == na - 1 or acc_seg[k + 1] != acc_seg[k]:
            _copy_state(xf_q[q], Pf_q[q], xs_q[q], Ps_q[q])


@njit(cache=True, nogil=True)
def _copy_state(x, P, x_out, P_out):
    """x and P into x_out and P_out, element by element: a slice assignment would compile numba's
    shape-mismatch message, about a second on a cold cache."""
    for a in range(x.shape[0]):
        x_out[a] = x[a]
        for b in range(x.shape[0]):
            P_out[a, b] = P[a, b]


@njit(cache=True, nogil=True)
def _query_between(kinds, omegas, qs, a, t, r, cbar, x0, P0, xp, xbar, Pbar_k, Pbar_inv, xs_next, Ps_next,
                   Fa, Qa, Ft, Qt, Cj, C, G, tmp, xt, Pt, xtc, Ptc, Pbar, x_out, P_out):
    """The smoothed state a s after an update, t s before the next: the output time's marginal and its
    cross-covariance with x_k+1 per target mode, from the interval's mixed priors (cbar, x0, P0), predicted
    mixture (xp, xbar, Pbar_k) and its inverse, then one RTS step to the next update's smoothed state."""
    for j in range(r):
        transition_into(kinds[j], omegas[j], qs[j], a, Fa, Qa)
        transition_into(kinds[j], omegas[j], qs[j], t, Ft, Qt)
        fx_into(Fa, x0[j], xt[j])
        for i1 in range(NX):
            for j1 in range(NX):
                acc = 0.0
                for k1 in range(NX):
                    acc += Fa[i1, k1] * P0[j, k1, j1]
                tmp[i1, j1] = acc
        for i1 in range(NX):
            for j1 in range(NX):
                acc_p = Qa[i1, j1]
                for k1 in range(NX):
                    acc_p += tmp[i1, k1] * Fa[j1, k1]
                Pt[j, i1, j1] = acc_p
        _gamma_cross(kinds[j], qs[j], a, t, Cj)
        for i1 in range(NX):
            for j1 in range(NX):
                acc = 0.0
                for k1 in range(NX):
                    acc += tmp[i1, k1] * Ft[j1, k1]
                Cj[i1, j1] += acc
        if j == 0:
            for i1 in range(NX):
                for j1 in range(NX):
                    C[i1, j1] = 0.0
        _add_scaled(cbar[j], Cj, C)
    combine_into(cbar, xt, Pt, r, xtc, Ptc)
    _add_spread(cbar, xt, xtc, xp, xbar, r, C)
    for i1 in range(NX):
        for j1 in range(NX):
            Pbar[i1, j1] = Pbar_k[i1, j1]
    _apply_gain(C, Pbar_inv, xtc, Ptc, xs_next, Ps_next, xbar, Pbar, G, tmp, x_out, P_out)


@njit(cache=True, nogil=True)
def _joint(kinds, omegas, qs, tpm_kind, tpm_param, tpm_param2, dt, r, mu, x, P, xk, PI, cbar, x0, P0, xp, Pp,
           F, Q, Cj, C, tmp, xbar, Pbar):
    """Predicted mixture (xbar, Pbar) over dt and its cross-covariance C with the current combined xk."""
    tpm_into(tpm_kind, tpm_param, tpm_param2, dt, r, PI)
    mix_into(PI, mu, x, P, r, cbar, x0, P0)
    for a in range(NX):
        for b in range(NX):
            C[a, b] = 0.0
    for j in range(r):
        transition_into(kinds[j], omegas[j], qs[j], dt, F, Q)
        for a in range(NX):
            acc = 0.0
            for k in range(NX):
                acc += F[a, k] * x0[j, k]
            xp[j, a] = acc
        for a in range(NX):
            for b in range(NX):
                acc = 0.0
                for k in range(NX):
                    acc += P0[j, a, k] * F[b, k]
                Cj[a, b] = acc  # P0 F^T
        for a in range(NX):
            for b in range(NX):
                acc = Q[a, b]
                for k in range(NX):
                    acc += F[a, k] * Cj[k, b]
                Pp[j, a, b] = acc
        _add_scaled(cbar[j], Cj, C)
    combine_into(cbar, xp, Pp, r, xbar, Pbar)
    _add_spread(cbar, x0, xk, xp, xbar, r, C)


@njit(cache=True, nogil=True)
def _add_scaled(w, M, C):
    """C += w M (6x6)."""
    for a in range(NX):
        for b in range(NX):
            C[a, b] += w * M[a, b]


@njit(cache=True, nogil=True)
def _add_spread(cbar, xa, ma, xb, mb, r, C):
    """C += sum_j cbar_j (xa_j - ma)(xb_j - mb)^T: the spread of the modes' means in a mixture's
    cross-covariance."""
    for j in range(r):
        for a in range(NX):
            for b in range(NX):
                C[a, b] += cbar[j] * (xa[j, a] - ma[a]) * (xb[j, b] - mb[b])


@njit(cache=True, nogil=True)
def _pair_smooth(kind, omega, q, a, t, xi, Pi, xs_next, Ps_next, Fa, Qa, Ft, Qt, C, G, tmp, work,
                 Pbar, Pbar_inv, xbar, xt, Pt, x_out, P_out):
    """One mode-matched RTS step: the state a s after an update, given the state at the update N(xi, Pi)
    moved by this mode's model over the interval of t s and this mode's smoothed state (xs_next, Ps_next)
    at its end."""
    transition_into(kind, omega, q, t, Ft, Qt)
    fx_into(Ft, xi, xbar)
    fpft_q(Ft, Pi, Qt, tmp, Pbar)
    if a == 0.0:
        for r in range(NX):
            xt[r] = xi[r]
            for c in range(NX):
                Pt[r, c] = Pi[r, c]
                acc = 0.0
                for k in range(NX):
                    acc += Pi[r, k] * Ft[c, k]
                C[r, c] = acc
    else:
        transition_into(kind, omega, q, a, Fa, Qa)
        fx_into(Fa, xi, xt)
        fpft_q(Fa, Pi, Qa, tmp, Pt)
        for r in range(NX):
            for c in range(NX):
                acc = 0.0
                for k in range(NX):
                    acc += Fa[r, k] * Pi[k, c]
                tmp[r, c] = acc
        _gamma_cross(kind, q, a, t, C)
        for r in range(NX):
            for c in range(NX):
                acc = 0.0
                for k in range(NX):
                    acc += tmp[r, k] * Ft[c, k]
                C[r, c] += acc
    _inverse(Pbar, Pbar_inv, work)
    _apply_gain(C, Pbar_inv, xt, Pt, xs_next, Ps_next, xbar, Pbar, G, tmp, x_out, P_out)


@njit(cache=True, nogil=True)
def _psd_project(L, lv, D, V):
    """Keep the non-negative part of the symmetric information L (Jacobi eigen-decomposition, D and V
    scratch) and lv's part in its span: the later data cannot make the state less certain."""
    for r in range(NX):
        for c in range(NX):
            D[r, c] = 0.5 * (L[r, c] + L[c, r])
            V[r, c] = 1.0 if r == c else 0.0
    scale = 0.0
    for r in range(NX):
        scale += abs(D[r, r])
    for _ in range(60):
        off = 0.0
        for r in range(NX):
            for c in range(r + 1, NX):
                off += D[r, c] * D[r, c]
        if off <= (1e-14 * scale) ** 2 or off == 0.0:
            break
        for p in range(NX):
            for q in range(p + 1, NX):
                if D[p, q] == 0.0:
                    continue
                theta = (D[q, q] - D[p, p]) / (2.0 * D[p, q])
                t = (1.0 if theta >= 0.0 else -1.0) / (abs(theta) + math.sqrt(theta * theta + 1.0))
                c = 1.0 / math.sqrt(t * t + 1.0)
                s = t * c
                for k in range(NX):
                    dkp = D[k, p]
                    dkq = D[k, q]
                    D[k, p] = c * dkp - s * dkq
                    D[k, q] = s * dkp + c * dkq
                for k in range(NX):
                    dpk = D[p, k]
                    dqk = D[q, k]
                    D[p, k] = c * dpk - s * dqk
                    D[q, k] = s * dpk + c * dqk
                for k in range(NX):
                    vkp = V[k, p]
                    vkq = V[k, q]
                    V[k, p] = c * vkp - s * vkq
                    V[k, q] = s * vkp + c * vkq
    negative = False
    for m in range(NX):
        if D[m, m] < 0.0:
            negative = True
    if not negative:
        return
    for r in range(NX):
        for c in range(NX):
            acc = 0.0
            for m in range(NX):
                if D[m, m] > 0.0:
                    acc += V[r, m] * D[m, m] * V[c, m]
            L[r, c] = acc
    # lv <- V+ V+^T lv, with D's first row as scratch for V+^T lv
    for m in range(NX):
        acc = 0.0
        if D[m, m] > 0.0:
            for k in range(NX):
                acc += V[k, m] * lv[k]
        D[0, m] = acc if D[m, m] > 0.0 else 0.0
    for r in range(NX):
        acc = 0.0
        for m in range(NX):
            acc += V[r, m] * D[0, m]
        lv[r] = acc


@njit(cache=True, nogil=True)
def _backward_information(kind, omega, q, t, x0, P0, xs_next, Ps_next, F, Q, work, xp, Pp, inv_p, inv_s, L,
                          M, Minv, lv, Om, om):
    """Information the data after an update carry on the state at it, given the mode over the next
    interval (t s): at its end the smoothed over predicted ratio L = Ps^-1 - Pp^-1, lv = Ps^-1 xs - Pp^-1 xp
    (prediction from the mixed prior x0, P0; its non-negative part: a mode's smoothed state is a mixture
    and can be wider than the prediction), carried back through x_k+1 = F x_k + w:
    Om = F^T L (I + Q L)^-1 F, om = F^T (I + L Q)^-1 lv (no inverse of the possibly near-singular prior)."""
    transition_into(kind, omega, q, t, F, Q)
    for r in range(NX):
        acc = 0.0
        for c in range(NX):
            acc += F[r, c] * x0[c]
        xp[r] = acc
    fpft_q(F, P0, Q, M, Pp)
    _inverse(Pp, inv_p, work)
    _inverse(Ps_next, inv_s, work)
    for r in range(NX):
        acc = 0.0
        for c in range(NX):
            held = Pp[r, r] > 0.0 and Pp[c, c] > 0.0
            L[r, c] = inv_s[r, c] - inv_p[r, c] if held else 0.0
            if held:
                acc += inv_s[r, c] * xs_next[c] - inv_p[r, c] * xp[c]
        lv[r] = acc if Pp[r, r] > 0.0 else 0.0
    _psd_project(L, lv, M, Minv)
    for r in range(NX):  # M = I + Q L
        for c in range(NX):
            acc = 1.0 if r == c else 0.0
            for k in range(NX):
                acc += Q[r, k] * L[k, c]
            M[r, c] = acc
    _inverse(M, Minv, work)
    for r in range(NX):  # inv_p <- L (I + Q L)^-1, inv_s[:, 0] <- (I + L Q)^-1 lv = Minv^T lv
        for c in range(NX):
            acc = 0.0
            for k in range(NX):
                acc += L[r, k] * Minv[k, c]
            inv_p[r, c] = acc
        acc = 0.0
        for k in range(NX):
            acc += Minv[k, r] * lv[k]
        inv_s[r, 0] = acc
    for r in range(NX):
        acc = 0.0
        for k in range(NX):
            acc += F[k, r] * inv_s[k, 0]
        om[r] = acc
        for c in range(r, NX):
            acc = 0.0
            for k in range(NX):
                f = F[k, r]
                if f != 0.0:
                    for m in range(NX):
                        acc += f * 0.5 * (inv_p[k, m] + inv_p[m, k]) * F[m, c]
            Om[r, c] = acc
            Om[c, r] = acc


@njit(cache=True, nogil=True)
def _fuse(x, P, Om, om, work, A, Ainv, b, x_out, P_out):
    """N(x, P) times the backward information (Om, om), conditioned on the dimensions P holds exactly
    (zero variance: a CV or CT mode's acceleration) keeping their value: x_out = A^-1 b, P_out = A^-1."""
    _inverse(P, A, work)
    for r in range(NX):
        acc = 0.0
        for c in range(NX):
            acc += A[r, c] * x[c] if P[c, c] > 0.0 else 0.0
        b[r] = acc
    for r in range(NX):
        if P[r, r] <= 0.0:
            continue
        acc = om[r]
        for c in range(NX):
            if P[c, c] > 0.0:
                A[r, c] += Om[r, c]
            else:
                acc -= Om[r, c] * x[c]
        b[r] += acc
    for r in range(NX):
        if P[r, r] <= 0.0:
            for c in range(NX):
                A[r, c] = 0.0
                A[c, r] = 0.0
    _inverse(A, Ainv, work)
    for r in range(NX):
        if P[r, r] <= 0.0:
            x_out[r] = x[r]
            for c in range(NX):
                P_out[r, c] = 0.0
                P_out[c, r] = 0.0
            continue
        acc = 0.0
        for c in range(NX):
            acc += Ainv[r, c] * b[c] if P[c, c] > 0.0 else 0.0
        x_out[r] = acc
    for r in range(NX):
        if P[r, r] <= 0.0:
            continue
        for c in range(NX):
            P_out[r, c] = Ainv[r, c] if P[c, c] > 0.0 else 0.0


@njit(cache=True, nogil=True)
def imm_smooth_rows(acc_t, acc_seg, mu_a, x_a, P_a, kinds, omegas, qs, tpm_kind, tpm_param, tpm_param2,
                    q_acc, q_dt, xf_q, Pf_q, muf_q, xs_q, Ps_q, mus_q):
    """Fixed-interval IMM smoother in two-filter form (after Lopez & Danes): smoothed mode probabilities and
    mode-conditioned smoothed states at every accepted update, combined estimates at the queries.

    Between updates k and k+1 (interval t), for each mode j over the interval: the information the later
    data carry on x_k given j (`_backward_information`, from mode j's smoothed state at k+1 against the
    forward filter's own prediction from the mixed prior) is fused with each mode i's filtered state at
    k (`_fuse`); the pair (i at k, j over the interval) has Kim's probability
    w_ij = PI_ij mu_k^i mus_k+1^j / cbar_j, and mode i's smoothed state is the mixture of its pairs.
    Fusing with the filtered state, rather than running RTS from it through mode j's model (Kim's
    smoother), keeps an unlikely low-noise mode from drifting along its own model. Output times between
    updates: each mode's mixed prior smoothed by one RTS step with the joint law of that time and k+1 (as
    `smooth_rows`), weighted by the smoothed probabilities at k+1 (the mode over the interval). With one
    mode this is exactly RTS. Queries after a segment's last update keep the forward prediction."""
    na = acc_t.shape[0]
    r = kinds.shape[0]
    mus = np.empty((na, r))
    xs = np.empty((na, r, NX))
    Ps = np.empty((na, r, NX, NX))
    PI = np.empty((r, r))
    cbar = np.empty(r)
    x0 = np.empty((r, NX))
    P0 = np.empty((r, NX, NX))
    w = np.empty((r, r))
    wq = np.empty(r)
    xq = np.empty((r, NX))
    Pq = np.empty((r, NX, NX))
    Om = np.empty((r, NX, NX))
    om = np.empty((r, NX))
    xf = np.empty((r, NX))
    Pf = np.empty((r, NX, NX))
    Fa = np.empty((NX, NX))
    Qa = np.empty((NX, NX))
    Ft = np.empty((NX, NX))
    Qt = np.empty((NX, NX))
    C = np.empty((NX, NX))
    G = np.empty((NX, NX))
    tmp = np.empty((NX, NX))
    work = np.empty((NX, NX))
    Pbar = np.empty((NX, NX))
    Pbar_inv = np.empty((NX, NX))
    xbar = np.empty(NX)
    xt = np.empty(NX)
    Pt = np.empty((NX, NX))
    b = np.empty(NX)
    for k in range(na - 1, -1, -1):
        if k == na - 1 or acc_seg[k + 1] != acc_seg[k]:
            for i in range(r):
                mus[k, i] = mu_a[k, i]
                for a in range(NX):
                    xs[k, i, a] = x_a[k, i, a]
                    for c in range(NX):
                        Ps[k, i, a, c] = P_a[k, i, a, c]
            continue
        t = acc_t[k + 1] - acc_t[k]
        _pair_weights(tpm_kind, tpm_param, tpm_param2, t, r, mu_a[k], mus[k + 1], PI, cbar, w)
        mix_into(PI, mu_a[k], x_a[k], P_a[k], r, cbar, x0, P0)
        for j in range(r):
            _backward_information(kinds[j], omegas[j], qs[j], t, x0[j], P0[j], xs[k + 1, j], Ps[k + 1, j], Ft,
                                  Qt, work, xbar, Pbar, Pbar_inv, C, Fa, G, Qa, xt, Om[j], om[j])
        for i in range(r):
            mi = 0.0
            for j in range(r):
                mi += w[i, j]
            mus[k, i] = mi
            if mi <= 0.0:  # mode i has no probability left: keep its filtered state
                for a in range(NX):
                    xs[k, i, a] = x_a[k, i, a]
                    for c in range(NX):
                        Ps[k, i, a, c] = P_a[k, i, a, c]
                continue
            for j in range(r):
                wq[j] = w[i, j] / mi
                _fuse(x_a[k, i], P_a[k, i], Om[j], om[j], work, tmp, G, b, xf[j], Pf[j])
            combine_into(wq, xf, Pf, r, xs[k, i], Ps[k, i])
    for q in range(q_acc.shape[0]):
        k = q_acc[q]
        a = q_dt[q]
        if a == 0.0:
            for j in range(r):
                mus_q[q, j] = mus[k, j]
            combine_into(mus[k], xs[k], Ps[k], r, xs_q[q], Ps_q[q])
            continue
        if k == na - 1 or acc_seg[k + 1] != acc_seg[k]:
            _copy_state(xf_q[q], Pf_q[q], xs_q[q], Ps_q[q])
            for j in range(r):
                mus_q[q, j] = muf_q[q, j]
            continue
        t = acc_t[k + 1] - acc_t[k]
        tpm_into(tpm_kind, tpm_param, tpm_param2, t, r, PI)
        mix_into(PI, mu_a[k], x_a[k], P_a[k], r, cbar, x0, P0)
        for j in range(r):
            _pair_smooth(kinds[j], omegas[j], qs[j], a, t, x0[j], P0[j], xs[k + 1, j], Ps[k + 1, j],
                         Fa, Qa, Ft, Qt, C, G, tmp, work, Pbar, Pbar_inv, xbar, xt, Pt, xq[j], Pq[j])
            mus_q[q, j] = mus[k + 1, j]
        combine_into(mus[k + 1], xq, Pq, r, xs_q[q], Ps_q[q])


@njit(cache=True, nogil=True)
def _pair_weights(tpm_kind, tpm_param, tpm_param2, t, r, mu, mus_next, PI, cbar, w):
    """w[i, j] = P(mode i at k, mode j at k+1 | all data) = PI_ij mu_i mus_next_j / cbar_j (Kim's
    approximation: the mode at k given the mode at k+1 does not depend on later data)."""
    tpm_into(tpm_kind, tpm_param, tpm_param2, t, r, PI)
    predicted_modes_into(PI, mu, r, cbar)
    total = 0.0
    for i in range(r):
        for j in range(r):
            v = PI[i, j] * mu[i] * mus_next[j] / cbar[j] if cbar[j] > 0.0 else 0.0
            w[i, j] = v
            total += v
    for i in range(r):
        for j in range(r):
            w[i, j] /= total
