"""Backward pass: Rauch-Tung-Striebel smoothing of the combined IMM estimate.

Between consecutive accepted updates k and k+1 the joint law of (x_k, x_k+1) is taken from the IMM's own
prediction: mixing with PI(dt), then per target mode j, x_k ~ N(x0_j, P0_j) and x_k+1 = F_j x_k + w_j,
so Cov(x_k, x_k+1) = sum_j cbar_j [P0_j F_j^T + (x0_j - x_k)(xp_j - xp)^T]. Output times between two
updates are smoothed from the same joint law (the acceleration noise is constant over the interval, as
in the filter's process model), which keeps every joint covariance positive semi-definite.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from .imm import CA, NX, combine_into, fpft_q, mix_into, tpm_into, transition_into


@njit(cache=True)
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


@njit(cache=True)
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


@njit(cache=True)
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


@njit(cache=True)
def smooth_rows(acc_t, acc_seg, mu_a, x_a, P_a, kinds, omegas, qs, tpm_kind, tpm_param, tpm_param2,
                q_acc, q_dt, xf_q, Pf_q, xs_q, Ps_q):
    """Smoothed combined estimate at every query q (q_acc: index of its governing accepted update,
    q_dt: time after it). Queries after a segment's last update keep their forward prediction."""
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
    xk = np.empty(NX)
    Pk = np.empty((NX, NX))
    xt = np.empty((r, NX))
    Pt = np.empty((r, NX, NX))
    xtc = np.empty(NX)
    Ptc = np.empty((NX, NX))
    # backward pass over accepted updates
    for k in range(na - 1, -1, -1):
        combine_into(mu_a[k], x_a[k], P_a[k], r, xs[k], Ps[k])
        if k == na - 1 or acc_seg[k + 1] != acc_seg[k]:
            continue
        for a in range(NX):
            xk[a] = xs[k, a]
            for b in range(NX):
                Pk[a, b] = Ps[k, a, b]
        _joint(kinds, omegas, qs, tpm_kind, tpm_param, tpm_param2, acc_t[k + 1] - acc_t[k], r, mu_a[k],
               x_a[k], P_a[k], xk, PI, cbar, x0, P0, xp, Pp, Ft, Qt, Cj, C, tmp, xbar, Pbar)
        _inverse(Pbar, Pbar_inv, work)
        _apply_gain(C, Pbar_inv, xk, Pk, xs[k + 1], Ps[k + 1], xbar, Pbar, G, tmp, xs[k], Ps[k])
    # queries
    for q in range(q_acc.shape[0]):
        k = q_acc[q]
        a = q_dt[q]
        if a == 0.0:
            xs_q[q] = xs[k]
            Ps_q[q] = Ps[k]
            continue
        if k == na - 1 or acc_seg[k + 1] != acc_seg[k]:
            xs_q[q] = xf_q[q]
            Ps_q[q] = Pf_q[q]
            continue
        t = acc_t[k + 1] - acc_t[k]
        combine_into(mu_a[k], x_a[k], P_a[k], r, xk, Pk)
        _joint(kinds, omegas, qs, tpm_kind, tpm_param, tpm_param2, t, r, mu_a[k], x_a[k], P_a[k], xk, PI,
               cbar, x0, P0, xp, Pp, Ft, Qt, Cj, C, tmp, xbar, Pbar)
        # the output time's marginal and its cross-covariance with x_k+1, per target mode
        for j in range(r):
            transition_into(kinds[j], omegas[j], qs[j], a, Fa, Qa)
            transition_into(kinds[j], omegas[j], qs[j], t, Ft, Qt)
            for i1 in range(NX):
                acc = 0.0
                for k1 in range(NX):
                    acc += Fa[i1, k1] * x0[j, k1]
                xt[j, i1] = acc
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
            for i1 in range(NX):
                for j1 in range(NX):
                    C[i1, j1] += cbar[j] * Cj[i1, j1]
        combine_into(cbar, xt, Pt, r, xtc, Ptc)
        for j in range(r):
            for i1 in range(NX):
                for j1 in range(NX):
                    C[i1, j1] += cbar[j] * (xt[j, i1] - xtc[i1]) * (xp[j, j1] - xbar[j1])
        _inverse(Pbar, Pbar_inv, work)
        _apply_gain(C, Pbar_inv, xtc, Ptc, xs[k + 1], Ps[k + 1], xbar, Pbar, G, tmp, xs_q[q], Ps_q[q])


@njit(cache=True)
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
        for a in range(NX):
            for b in range(NX):
                C[a, b] += cbar[j] * Cj[a, b]
    combine_into(cbar, xp, Pp, r, xbar, Pbar)
    for j in range(r):
        for a in range(NX):
            for b in range(NX):
                C[a, b] += cbar[j] * (x0[j, a] - xk[a]) * (xp[j, b] - xbar[b])


@njit(cache=True)
def _pair_smooth(kind, omega, q, a, t, xi, Pi, xs_next, Ps_next, Fa, Qa, Ft, Qt, C, G, tmp, work,
                 Pbar, Pbar_inv, xbar, xt, Pt, x_out, P_out):
    """RTS step of one mode pair: the state a s after an update, given the state of mode i at the update
    N(xi, Pi) moved by mode j's model (kind, omega, q) over the interval of t s, and mode j's smoothed
    state (xs_next, Ps_next) at its end."""
    transition_into(kind, omega, q, t, Ft, Qt)
    for r in range(NX):
        acc = 0.0
        for c in range(NX):
            acc += Ft[r, c] * xi[c]
        xbar[r] = acc
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
        for r in range(NX):
            acc = 0.0
            for c in range(NX):
                acc += Fa[r, c] * xi[c]
            xt[r] = acc
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


@njit(cache=True)
def imm_smooth_rows(acc_t, acc_seg, mu_a, x_a, P_a, kinds, omegas, qs, tpm_kind, tpm_param, tpm_param2,
                    q_acc, q_dt, xf_q, Pf_q, muf_q, xs_q, Ps_q, mus_q):
    """Fixed-interval IMM smoother (Kim 1994): smoothed mode probabilities and mode-conditioned states.

    Between updates k and k+1 (interval t, transition matrix PI(t)), each pair (mode i at k, mode j over
    the interval) has the smoothed probability w_ij = PI_ij mu_k^i mus_k+1^j / cbar_j (Kim's approximation:
    the mode at k given the mode at k+1 does not depend on later data) and one RTS step from the
    filtered x_k^i through mode j's model to mode j's smoothed state at k+1; mode i's smoothed state is
    the moment-matched mixture of its pairs (weights w_ij / mus_k^i). Output times between updates use the
    same pairs with the joint law of that time and k+1 (as `smooth_rows`); the mode over the interval is
    the one at k+1, so their probabilities are those smoothed at k+1. With one mode this is exactly RTS.
    Queries after a segment's last update keep their forward prediction (xf_q, Pf_q, muf_q)."""
    na = acc_t.shape[0]
    r = kinds.shape[0]
    mus = np.empty((na, r))
    xs = np.empty((na, r, NX))
    Ps = np.empty((na, r, NX, NX))
    PI = np.empty((r, r))
    cbar = np.empty(r)
    w = np.empty((r, r))
    wq = np.empty(r * r)
    xq = np.empty((r * r, NX))
    Pq = np.empty((r * r, NX, NX))
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
    for k in range(na - 1, -1, -1):
        if k == na - 1 or acc_seg[k + 1] != acc_seg[k]:
            for i in range(r):
                mus[k, i] = mu_a[k, i]
                for a in range(NX):
                    xs[k, i, a] = x_a[k, i, a]
                    for b in range(NX):
                        Ps[k, i, a, b] = P_a[k, i, a, b]
            continue
        t = acc_t[k + 1] - acc_t[k]
        _pair_weights(tpm_kind, tpm_param, tpm_param2, t, r, mu_a[k], mus[k + 1], PI, cbar, w)
        for i in range(r):
            mi = 0.0
            for j in range(r):
                mi += w[i, j]
            mus[k, i] = mi
            n = 0
            for j in range(r):
                if w[i, j] <= 0.0:
                    continue
                _pair_smooth(kinds[j], omegas[j], qs[j], 0.0, t, x_a[k, i], P_a[k, i], xs[k + 1, j],
                             Ps[k + 1, j], Fa, Qa, Ft, Qt, C, G, tmp, work, Pbar, Pbar_inv, xbar, xt, Pt,
                             xq[n], Pq[n])
                wq[n] = w[i, j] / mi
                n += 1
            if n == 0:  # mode i has no probability left: keep its filtered state
                for a in range(NX):
                    xs[k, i, a] = x_a[k, i, a]
                    for b in range(NX):
                        Ps[k, i, a, b] = P_a[k, i, a, b]
            else:
                combine_into(wq, xq, Pq, n, xs[k, i], Ps[k, i])
    for q in range(q_acc.shape[0]):
        k = q_acc[q]
        a = q_dt[q]
        if a == 0.0:
            for j in range(r):
                mus_q[q, j] = mus[k, j]
            combine_into(mus[k], xs[k], Ps[k], r, xs_q[q], Ps_q[q])
            continue
        if k == na - 1 or acc_seg[k + 1] != acc_seg[k]:
            xs_q[q] = xf_q[q]
            Ps_q[q] = Pf_q[q]
            mus_q[q] = muf_q[q]
            continue
        t = acc_t[k + 1] - acc_t[k]
        _pair_weights(tpm_kind, tpm_param, tpm_param2, t, r, mu_a[k], mus[k + 1], PI, cbar, w)
        n = 0
        for i in range(r):
            for j in range(r):
                if w[i, j] <= 0.0:
                    continue
                _pair_smooth(kinds[j], omegas[j], qs[j], a, t, x_a[k, i], P_a[k, i], xs[k + 1, j],
                             Ps[k + 1, j], Fa, Qa, Ft, Qt, C, G, tmp, work, Pbar, Pbar_inv, xbar, xt, Pt,
                             xq[n], Pq[n])
                wq[n] = w[i, j]
                n += 1
        combine_into(wq, xq, Pq, n, xs_q[q], Ps_q[q])
        for j in range(r):
            mus_q[q, j] = mus[k + 1, j]


@njit(cache=True)
def _pair_weights(tpm_kind, tpm_param, tpm_param2, t, r, mu, mus_next, PI, cbar, w):
    """w[i, j] = P(mode i at k, mode j at k+1 | all data) = PI_ij mu_i mus_next_j / cbar_j (Kim's
    approximation: the mode at k given the mode at k+1 does not depend on later data)."""
    tpm_into(tpm_kind, tpm_param, tpm_param2, t, r, PI)
    for j in range(r):
        acc = 0.0
        for i in range(r):
            acc += PI[i, j] * mu[i]
        cbar[j] = acc
    total = 0.0
    for i in range(r):
        for j in range(r):
            v = PI[i, j] * mu[i] * mus_next[j] / cbar[j] if cbar[j] > 0.0 else 0.0
            w[i, j] = v
            total += v
    for i in range(r):
        for j in range(r):
            w[i, j] /= total
