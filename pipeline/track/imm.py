"""The IMM kernel: numba, fixed 6-state [e, ve, ae, n, vn, an] per mode, no allocation per update.

Modes are nearly-constant velocity (CV), coordinated turn at a fixed rate (CT, positive = left, i.e.
counter-clockwise in the east-north plane) and constant acceleration (CA); CV and CT keep their
acceleration states at exactly zero, so mixing with a CA mode is the zero-padded mixing of
tracking.md section 2.2. Process noise is the discrete white-noise acceleration of the dynamic-TPM
paper (Gamma sigma_a^2 Gamma^T, acceleration constant over one step); CA adds white jerk.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

NX = 6
CV, CT, CA = 0, 1, 2
TPM_FIXED, TPM_DYNAMIC, TPM_EXPM = 0, 1, 2
STATUS_REJECTED, STATUS_UPDATED, STATUS_STARTED = 0, 1, 2
LOG_2PI = math.log(2.0 * math.pi)


@njit(cache=True, nogil=True)
def tpm_into(kind, param, param2, dt, r, out):
    """Mode transition matrix for an update interval dt (s) into out[:r, :r]: mode 0 (CV) leaves to the
    others with equal probability, the others only return to mode 0 (the dynamic-TPM paper's eq. 14)."""
    for i in range(r):
        for j in range(r):
            out[i, j] = 0.0
    if r == 1:
        out[0, 0] = 1.0
        return
    m = r - 1
    if kind == TPM_EXPM:
        # continuous-time chain: mode 0 left at rate a = 1/param (split evenly), the others left
        # (back to mode 0) at rate b = 1/param2; closed form of expm(G dt) for this structure
        a = 1.0 / param
        b = 1.0 / param2
        e_ab = math.exp(-(a + b) * dt)
        e_b = math.exp(-b * dt)
        stay_base = (b + a * e_ab) / (a + b)
        to_base = b * (1.0 - e_ab) / (a + b)
        out[0, 0] = stay_base
        for j in range(1, r):
            out[0, j] = (1.0 - stay_base) / m
            out[j, 0] = to_base
            same = (1.0 - to_base + (m - 1) * e_b) / m
            for k in range(1, r):
                out[j, k] = same if k == j else same - e_b
        return
    if kind == TPM_DYNAMIC:
        p = min(0.995, param - param2 * dt)
        p = max(p, 0.0)
    else:
        p = param
    out[0, 0] = p
    for j in range(1, r):
        out[0, j] = (1.0 - p) / m
        out[j, 0] = 1.0 - p
        out[j, j] = p


@njit(cache=True, nogil=True)
def transition_into(kind, omega, q, dt, F, Q):
    """State transition F and process noise Q of one mode over dt (s); omega in rad/s, q = sigma_a^2."""
    for i in range(NX):
        for j in range(NX):
            F[i, j] = 0.0
            Q[i, j] = 0.0
    dt2 = dt * dt
    if kind == CA:
        g0, g1, g2 = 0.5 * dt2, dt, 1.0
        for o in (0, 3):
            F[o, o] = 1.0
            F[o, o + 1] = dt
            F[o, o + 2] = 0.5 * dt2
            F[o + 1, o + 1] = 1.0
            F[o + 1, o + 2] = dt
            F[o + 2, o + 2] = 1.0
            Q[o, o] = q * g0 * g0
            Q[o, o + 1] = Q[o + 1, o] = q * g0 * g1
            Q[o, o + 2] = Q[o + 2, o] = q * g0 * g2
            Q[o + 1, o + 1] = q * g1 * g1
            Q[o + 1, o + 2] = Q[o + 2, o + 1] = q * g1 * g2
            Q[o + 2, o + 2] = q * g2 * g2
        return
    for o in (0, 3):
        Q[o, o] = q * 0.25 * dt2 * dt2
        Q[o, o + 1] = Q[o + 1, o] = q * 0.5 * dt2 * dt
        Q[o + 1, o + 1] = q * dt2
    wt = omega * dt
    if kind == CT and abs(wt) > 1e-9:
        s, c = math.sin(wt), math.cos(wt)
        F[0, 0] = 1.0
        F[0, 1] = s / omega
        F[0, 4] = -(1.0 - c) / omega
        F[1, 1] = c
        F[1, 4] = -s
        F[3, 1] = (1.0 - c) / omega
        F[3, 3] = 1.0
        F[3, 4] = s / omega
        F[4, 1] = s
        F[4, 4] = c
    else:
        for o in (0, 3):
            F[o, o] = 1.0
            F[o, o + 1] = dt
            F[o + 1, o + 1] = 1.0


@njit(cache=True, nogil=True)
def fpft_q(F, P, Q, tmp, out):
    """out = F P F^T + Q (6x6), using tmp as scratch."""
    for i in range(NX):
        for j in range(NX):
            acc = 0.0
            for k in range(NX):
                acc += F[i, k] * P[k, j]
            tmp[i, j] = acc
    for i in range(NX):
        for j in range(i, NX):
            acc = Q[i, j]
            for k in range(NX):
                acc += tmp[i, k] * F[j, k]
            out[i, j] = acc
            out[j, i] = acc


@njit(cache=True, nogil=True)
def fx_into(F, x, out):
    """out = F x (6-vector)."""
    for i in range(NX):
        acc = 0.0
        for k in range(NX):
            acc += F[i, k] * x[k]
        out[i] = acc


@njit(cache=True, nogil=True)
def predicted_modes_into(PI, mu, r, cbar):
    """cbar = PI^T mu: the mode probabilities after one transition."""
    for j in range(r):
        acc = 0.0
        for i in range(r):
            acc += PI[i, j] * mu[i]
        cbar[j] = acc


@njit(cache=True, nogil=True)
def mix_into(PI, mu, x, P, r, cbar, x0, P0):
    """IMM interaction: predicted mode probabilities cbar and mixed initial conditions x0, P0."""
    predicted_modes_into(PI, mu, r, cbar)
    for j in range(r):
        for a in range(NX):
            x0[j, a] = 0.0
            for b in range(NX):
                P0[j, a, b] = 0.0
        if cbar[j] <= 0.0:
            for a in range(NX):
                x0[j, a] = x[j, a]
                for b in range(NX):
                    P0[j, a, b] = P[j, a, b]
            continue
        for i in range(r):
            w = PI[i, j] * mu[i] / cbar[j]
            for a in range(NX):
                x0[j, a] += w * x[i, a]
        for i in range(r):
            w = PI[i, j] * mu[i] / cbar[j]
            if w == 0.0:
                continue
            for a in range(NX):
                da = x[i, a] - x0[j, a]
                for b in range(NX):
                    P0[j, a, b] += w * (P[i, a, b] + da * (x[i, b] - x0[j, b]))


@njit(cache=True, nogil=True)
def combine_into(w, x, P, r, xc, Pc):
    """Moment-matched mixture: xc = sum w_j x_j, Pc = sum w_j [P_j + (x_j - xc)(x_j - xc)^T]."""
    for a in range(NX):
        acc = 0.0
        for j in range(r):
            acc += w[j] * x[j, a]
        xc[a] = acc
    for a in range(NX):
        for b in range(NX):
            acc = 0.0
            for j in range(r):
                acc += w[j] * (P[j, a, b] + (x[j, a] - xc[a]) * (x[j, b] - xc[b]))
            Pc[a, b] = acc


@njit(cache=True, nogil=True)
def predict_into(kinds, omegas, qs, tpm_kind, tpm_param, tpm_param2, dt, r, mu, x, P,
                 PI, F, Q, tmp, cbar, x0, P0, xp, Pp):
    """One IMM prediction over dt: mixing with PI(dt), then each mode's F, Q (mode-conditioned xp, Pp);
    cbar = PI^T mu are the predicted mode probabilities."""
    tpm_into(tpm_kind, tpm_param, tpm_param2, dt, r, PI)
    mix_into(PI, mu, x, P, r, cbar, x0, P0)
    for j in range(r):
        transition_into(kinds[j], omegas[j], qs[j], dt, F, Q)
        fx_into(F, x0[j], xp[j])
        fpft_q(F, P0[j], Q, tmp, Pp[j])


@njit(cache=True, nogil=True)
def cycle_scratch(r):
    """Scratch for predict_into, allocated once per kernel call: PI, F, Q, tmp, cbar, x0, P0, xp, Pp."""
    return (np.empty((r, r)), np.empty((NX, NX)), np.empty((NX, NX)), np.empty((NX, NX)), np.empty(r),
            np.empty((r, NX)), np.empty((r, NX, NX)), np.empty((r, NX)), np.empty((r, NX, NX)))


@njit(cache=True, nogil=True)
def chain_scratch(r):
    """A coasting chain's mode probabilities (r,), states (r, NX) and covariances (r, NX, NX)."""
    return np.empty(r), np.empty((r, NX)), np.empty((r, NX, NX))


@njit(cache=True, nogil=True)
def copy_chain(r, mu, x, P, mu_c, x_c, P_c):
    """Copy mode probabilities (r,), states (r, NX) and covariances (r, NX, NX) into a chain's arrays."""
    for j in range(r):
        mu_c[j] = mu[j]
        for a in range(NX):
            x_c[j, a] = x[j, a]
            for b in range(NX):
                P_c[j, a, b] = P[j, a, b]


@njit(cache=True, nogil=True)
def coast_chain(g, d, g_c, t_c, cycle_s, tol, mu_h, x_h, P_h, kinds, omegas, qs, tpm_kind, tpm_param,
                tpm_param2, r, mu_c, x_c, P_c, PI, F, Q, tmp, cbar, x0, P0, xp, Pp):
    """Carry the chain (mu_c, x_c, P_c), now t_c s after posterior g_c, to d s after posterior g by IMM
    cycles without measurement of at most cycle_s (restarting from posterior g when it is another row or
    d is behind); returns the new (g_c, t_c). Consecutive queries of one row thus cost one cycle a step."""
    if g != g_c or d < t_c:
        g_c = g
        t_c = 0.0
        copy_chain(r, mu_h[g], x_h[g], P_h[g], mu_c, x_c, P_c)
    while t_c < d - tol:
        h = min(cycle_s, d - t_c)
        predict_into(kinds, omegas, qs, tpm_kind, tpm_param, tpm_param2, h, r, mu_c, x_c, P_c,
                     PI, F, Q, tmp, cbar, x0, P0, xp, Pp)
        copy_chain(r, cbar, xp, Pp, mu_c, x_c, P_c)
        t_c += h
    return g_c, t_c


@njit(cache=True, nogil=True)
def _init_state(r, ze, zn, ree, ren, rnn, ve, vn, var_v, var_a, mu0, mu, x, P):
    for j in range(r):
        mu[j] = mu0[j]
        for a in range(NX):
            x[j, a] = 0.0
            for b in range(NX):
                P[j, a, b] = 0.0
        x[j, 0] = ze
        x[j, 3] = zn
        x[j, 1] = ve
        x[j, 4] = vn
        P[j, 0, 0] = ree
        P[j, 0, 3] = P[j, 3, 0] = ren
        P[j, 3, 3] = rnn
        P[j, 1, 1] = var_v
        P[j, 4, 4] = var_v
        P[j, 2, 2] = var_a[j]
        P[j, 5, 5] = var_a[j]


@njit(cache=True, nogil=True)
def _reachable(i, k, t, ze, zn, ree, rnn, max_speed):
    """Report i lies within max_speed (m/s) of report k (k < 0: no report to compare, True), allowing
    4 sigma of the two reports' noise."""
    if k < 0:
        return True
    reach = max_speed * (t[i] - t[k]) + 4.0 * math.sqrt(ree[i] + rnn[i] + ree[k] + rnn[k])
    return math.hypot(ze[i] - ze[k], zn[i] - zn[k]) <= reach


@njit(cache=True, nogil=True)
def run_filter(t, ze, zn, ree, ren, rnn, ve0, vn0, var_v0, fl, ground, kinds, omegas, qs, mu0,
               tpm_kind, tpm_param, tpm_param2, gate_d2, max_coast_s, restart_after, max_speed, q_fl, var_fl,
               status, nis, segment, t_state, mu_h, x_h, P_h, zv_h, Pv_h, keep):
    """Filter one aircraft's time-ordered measurements (plane coordinates, m; covariances m^2).

    Per measurement i it writes status (rejected/updated/started), nis (d^2 with the combined
    predicted covariance; the gate takes the smallest mode-matched d^2), the segment number, t_state
    (time of the state after i) and, when keep, the mode-conditioned posteriors (mu_h, x_h, P_h) and
    the vertical state (zv_h, Pv_h). A segment starts at the first measurement, whenever the last
    accepted update is older than max_coast_s, or at the restart_after-th consecutive gated report
    (0: never) when it lies within max_speed (m/s) of the gated report before it, plus 4 sigma of their
    noise (else it stays gated: an ADS-B position jump never starts a segment). A segment restarted
    after its first report alone, where that report is out of reach of the restarting one (a jump after
    a gap or at the start), is withdrawn: its report becomes a rejected one. ve0/vn0/var_v0
    initialise the velocity of a new segment (mean and per-axis variance). ground: 1 where the report says
    the aircraft is on the surface (else 0 or NaN): an accepted one sets the vertical rate to 0, so the
    level is held at its estimate at the last level report, not flown on below the ground.
    Returns the number of accepted updates.
    """
    n = t.shape[0]
    r = kinds.shape[0]
    mu = np.empty(r)
    x = np.empty((r, NX))
    P = np.empty((r, NX, NX))
    PI, F, Q, tmp, cbar, x0, P0, xp, Pp = cycle_scratch(r)
    loglik = np.empty(r)
    var_a = np.empty(r)
    for j in range(r):
        var_a[j] = 25.0 if kinds[j] == CA else 0.0
    zv = np.zeros(2)
    Pv = np.zeros((2, 2))
    tv = -1e300
    have_v = False
    t_last = -1e300
    seg = -1
    rejections = 0
    last_rejected = np.int64(-1)
    accepted = 0
    seg_first = np.int64(-1)  # the report that started the current segment
    seg_updates = 0  # accepted reports in the current segment
    for i in range(n):
        start = seg < 0 or t[i] - t_last > max_coast_s
        restart = False
        ok = True
        if not start:
            dt = t[i] - t_last
            predict_into(kinds, omegas, qs, tpm_kind, tpm_param, tpm_param2, dt, r, mu, x, P,
                         PI, F, Q, tmp, cbar, x0, P0, xp, Pp)
            # NIS with the combined prediction (mixture moments of the position); the gate accepts a
            # report that any mode's own prediction accepts (a turn's onset is not an outlier)
            me = 0.0
            mn = 0.0
            for j in range(r):
                me += cbar[j] * xp[j, 0]
                mn += cbar[j] * xp[j, 3]
            s00 = ree[i]
            s01 = ren[i]
            s11 = rnn[i]
            d2_min = np.inf
            for j in range(r):
                de = xp[j, 0] - me
                dn = xp[j, 3] - mn
                s00 += cbar[j] * (Pp[j, 0, 0] + de * de)
                s01 += cbar[j] * (Pp[j, 0, 3] + de * dn)
                s11 += cbar[j] * (Pp[j, 3, 3] + dn * dn)
                a00 = Pp[j, 0, 0] + ree[i]
                a01 = Pp[j, 0, 3] + ren[i]
                a11 = Pp[j, 3, 3] + rnn[i]
                ve = ze[i] - xp[j, 0]
                vn = zn[i] - xp[j, 3]
                dj = a00 * a11 - a01 * a01
                # a singular innovation covariance accepts nothing (d2j stays inf), rather than dividing by 0
                d2j = (a11 * ve * ve - 2.0 * a01 * ve * vn + a00 * vn * vn) / dj if dj > 0.0 else np.inf
                if d2j < d2_min:
                    d2_min = d2j
            det = s00 * s11 - s01 * s01
            ne = ze[i] - me
            nn = zn[i] - mn
            d2 = (s11 * ne * ne - 2.0 * s01 * ne * nn + s00 * nn * nn) / det if det > 0.0 else np.inf
            nis[i] = d2
            if not (d2_min <= gate_d2):
                rejections += 1
                if restart_after > 0 and rejections >= restart_after and _reachable(
                        i, last_rejected, t, ze, zn, ree, rnn, max_speed):
                    start = True
                    restart = True
                else:
                    ok = False
                    status[i] = STATUS_REJECTED
                    last_rejected = i
            else:
                rejections = 0
                status[i] = STATUS_UPDATED
                best = -1e300
                for j in range(r):
                    # mode-matched update, Joseph form
                    a00 = Pp[j, 0, 0] + ree[i]
                    a01 = Pp[j, 0, 3] + ren[i]
                    a11 = Pp[j, 3, 3] + rnn[i]
                    dj = a00 * a11 - a01 * a01
                    i00 = a11 / dj
                    i01 = -a01 / dj
                    i11 = a00 / dj
                    ve = ze[i] - xp[j, 0]
                    vn = zn[i] - xp[j, 3]
                    loglik[j] = (-0.5 * (i00 * ve * ve + 2.0 * i01 * ve * vn + i11 * vn * vn)
                                 - LOG_2PI - 0.5 * math.log(dj))
                    if loglik[j] > best:
                        best = loglik[j]
                    # K = Pp H^T S^-1 (6x2), stored in tmp[:, 0:2]
                    for a in range(NX):
                        pa0 = Pp[j, a, 0]
                        pa3 = Pp[j, a, 3]
                        tmp[a, 0] = pa0 * i00 + pa3 * i01
                        tmp[a, 1] = pa0 * i01 + pa3 * i11
                    for a in range(NX):
                        x[j, a] = xp[j, a] + tmp[a, 0] * ve + tmp[a, 1] * vn
                    # A = I - K H; P = A Pp A^T + K R K^T; F is scratch for A Pp
                    for a in range(NX):
                        for b in range(NX):
                            F[a, b] = Pp[j, a, b] - tmp[a, 0] * Pp[j, 0, b] - tmp[a, 1] * Pp[j, 3, b]
                    for a in range(NX):
                        ka0 = tmp[a, 0]
                        ka1 = tmp[a, 1]
                        for b in range(a, NX):
                            kb0 = tmp[b, 0]
                            kb1 = tmp[b, 1]
                            v = F[a, b] - F[a, 0] * kb0 - F[a, 3] * kb1
                            v += (ka0 * (ree[i] * kb0 + ren[i] * kb1) + ka1 * (ren[i] * kb0 + rnn[i] * kb1))
                            P[j, a, b] = v
                            P[j, b, a] = v
                total = 0.0
                for j in range(r):
                    mu[j] = cbar[j] * math.exp(loglik[j] - best)
                    total += mu[j]
                for j in range(r):
                    mu[j] /= total
        if start:
            if restart and seg_updates == 1 and not _reachable(i, seg_first, t, ze, zn, ree, rnn, max_speed):
                # the segment's only report is out of reach of the reports that followed it (a position
                # jump started it): withdrawn, counted as gated, and its number reused
                status[seg_first] = STATUS_REJECTED
                accepted -= 1
                seg -= 1
            seg += 1
            seg_first = i
            seg_updates = 0
            rejections = 0
            v_e, v_n, var_v = ve0[i], vn0[i], var_v0[i]
            if restart and last_rejected >= 0 and t[i] - t[last_rejected] > 0.0:
                # two-point start from the previous (gated) report when that is the sharper prior
                d = t[i] - t[last_rejected]
                var_2p = 0.5 * (ree[i] + rnn[i] + ree[last_rejected] + rnn[last_rejected]) / (d * d)
                if var_2p < var_v:
                    v_e = (ze[i] - ze[last_rejected]) / d
                    v_n = (zn[i] - zn[last_rejected]) / d
                    var_v = var_2p
            _init_state(r, ze[i], zn[i], ree[i], ren[i], rnn[i], v_e, v_n, var_v, var_a,
                        mu0, mu, x, P)
            have_v = False
            status[i] = STATUS_STARTED
            nis[i] = np.nan
        if ok:
            t_last = t[i]
            accepted += 1
            seg_updates += 1
            # vertical: nearly-constant rate on flight level, updated by accepted reports only
            if not math.isnan(fl[i]):
                if not have_v:
                    zv[0] = fl[i]
                    zv[1] = 0.0
                    Pv[0, 0] = var_fl
                    Pv[0, 1] = Pv[1, 0] = 0.0
                    Pv[1, 1] = 1.0  # (FL/s)^2: 6000 ft/min
                    have_v = True
                else:
                    d = t[i] - tv
                    zv[0] += d * zv[1]
                    p00 = Pv[0, 0] + 2.0 * d * Pv[0, 1] + d * d * Pv[1, 1] + q_fl * 0.25 * d ** 4
                    p01 = Pv[0, 1] + d * Pv[1, 1] + q_fl * 0.5 * d ** 3
                    p11 = Pv[1, 1] + q_fl * d * d
                    s = p00 + var_fl
                    k0 = p00 / s
                    k1 = p01 / s
                    inn = fl[i] - zv[0]
                    zv[0] += k0 * inn
                    zv[1] += k1 * inn
                    Pv[0, 0] = (1.0 - k0) * p00
                    Pv[0, 1] = Pv[1, 0] = (1.0 - k0) * p01
                    Pv[1, 1] = p11 - k1 * p01
                tv = t[i]
            if have_v and ground[i] == 1.0:
                # on the surface: the level is held (a landing roll does not descend on at the approach's
                # rate); the covariance is kept, so the rate is learnt again on the climb-out
                zv[1] = 0.0
        segment[i] = seg
        t_state[i] = t_last
        if keep:
            for j in range(r):
                mu_h[i, j] = mu[j]
                for a in range(NX):
                    x_h[i, j, a] = x[j, a]
                    for b in range(NX):
                        P_h[i, j, a, b] = P[j, a, b]
            if have_v:
                # vertical state predicted to t_state so every row's states share one time
                d = t_last - tv
                zv_h[i, 0] = zv[0] + d * zv[1]
                zv_h[i, 1] = zv[1]
                Pv_h[i, 0, 0] = Pv[0, 0] + 2.0 * d * Pv[0, 1] + d * d * Pv[1, 1] + q_fl * 0.25 * d ** 4
                Pv_h[i, 0, 1] = Pv_h[i, 1, 0] = Pv[0, 1] + d * Pv[1, 1] + q_fl * 0.5 * d ** 3
                Pv_h[i, 1, 1] = Pv[1, 1] + q_fl * d * d
            else:
                zv_h[i, 0] = np.nan
                zv_h[i, 1] = np.nan
    return accepted


@njit(cache=True, nogil=True)
def coast_modes(g, d, g_c, t_c, cycle_s, tol, mu_h, tpm_kind, tpm_param, tpm_param2, r, mu_c, PI, cbar):
    """coast_chain's mode probabilities alone (mu <- PI^T mu each cycle, the same cycles and arithmetic):
    for a query whose state is not wanted, only its mode probabilities."""
    if g != g_c or d < t_c:
        g_c = g
        t_c = 0.0
        for j in range(r):
            mu_c[j] = mu_h[g, j]
    while t_c < d - tol:
        h = min(cycle_s, d - t_c)
        tpm_into(tpm_kind, tpm_param, tpm_param2, h, r, PI)
        predicted_modes_into(PI, mu_c, r, cbar)
        for j in range(r):
            mu_c[j] = cbar[j]
        t_c += h
    return g_c, t_c


@njit(cache=True, nogil=True)
def predict_rows(gov, dt, want_state, kinds, omegas, qs, tpm_kind, tpm_param, tpm_param2, q_fl, substep_s,
                 mu_h, x_h, P_h, zv_h, Pv_h, xc_out, Pc_out, mu_out, zv_out, Pv_out):
    """Combined estimate at query q: the posterior of row gov[q] predicted dt[q] s ahead (dt 0: the
    posterior itself) by IMM cycles without measurement of at most substep_s each (mixing, mode-matched
    prediction, mu <- PI^T mu), combined with the spread of the mode means. Consecutive queries with the
    same governing row continue one chain, so a coasted gap costs one cycle per substep. Where
    want_state[q] is False (a smoother replaces that state) only the mode probabilities are predicted and
    the state is NaN; it must be the same for every query of one governing row."""
    r = kinds.shape[0]
    m = gov.shape[0]
    PI, F, Q, tmp, cbar, x0, P0, xp, Pp = cycle_scratch(r)
    mu_c, x_c, P_c = chain_scratch(r)
    g_c = np.int64(-1)
    t_c = 0.0
    whole = True  # the chain carries states too, not only mode probabilities
    for q in range(m):
        g = gov[q]
        d = dt[q]
        if d == 0.0:
            for j in range(r):
                mu_out[q, j] = mu_h[g, j]
            combine_into(mu_h[g], x_h[g], P_h[g], r, xc_out[q], Pc_out[q])
        elif want_state[q]:
            if not whole:
                g_c = np.int64(-1)  # its states were not carried: start again from the posterior
            g_c, t_c = coast_chain(g, d, g_c, t_c, substep_s, 0.0, mu_h, x_h, P_h, kinds, omegas, qs,
                                   tpm_kind, tpm_param, tpm_param2, r, mu_c, x_c, P_c,
                                   PI, F, Q, tmp, cbar, x0, P0, xp, Pp)
            whole = True
            for j in range(r):
                mu_out[q, j] = mu_c[j]
            combine_into(mu_c, x_c, P_c, r, xc_out[q], Pc_out[q])
        else:
            g_c, t_c = coast_modes(g, d, g_c, t_c, substep_s, 0.0, mu_h, tpm_kind, tpm_param, tpm_param2, r,
                                   mu_c, PI, cbar)
            whole = False
            for j in range(r):
                mu_out[q, j] = mu_c[j]
            for a in range(NX):
                xc_out[q, a] = np.nan
                for b in range(NX):
                    Pc_out[q, a, b] = np.nan
        zv_out[q, 0] = zv_h[g, 0] + d * zv_h[g, 1]
        zv_out[q, 1] = zv_h[g, 1]
        Pv_out[q, 0, 0] = (Pv_h[g, 0, 0] + 2.0 * d * Pv_h[g, 0, 1] + d * d * Pv_h[g, 1, 1]
                           + q_fl * 0.25 * d ** 4)
        Pv_out[q, 0, 1] = Pv_out[q, 1, 0] = Pv_h[g, 0, 1] + d * Pv_h[g, 1, 1] + q_fl * 0.5 * d ** 3
        Pv_out[q, 1, 1] = Pv_h[g, 1, 1] + q_fl * d * d


@njit(cache=True, nogil=True)
def propagate_ends(gov, horizon, kinds, omegas, qs, tpm_kind, tpm_param, tpm_param2, mu_h, x_h, P_h,
                   xc_out, Pc_out):
    """For query q, the combined estimate ``propagate`` ends at from the posterior of row gov[q] over
    horizon[q] > 0 s in steps of min(1, horizon[q]) (``predict``'s default), bit for bit: the same cycles
    in the same order. The unit steps before a query's last one continue those of the previous query of
    the same row, so queries sorted by row, then horizon, cost about one cycle per second of look-ahead."""
    r = kinds.shape[0]
    PI, F, Q, tmp, cbar, x0, P0, xp, Pp = cycle_scratch(r)
    mu_c, x_c, P_c = chain_scratch(r)
    g_c = -1
    done_c = 0  # unit steps the chain (mu_c, x_c, P_c) has made from posterior g_c
    for q in range(gov.shape[0]):
        g = gov[q]
        h = horizon[q]
        step = min(1.0, h)
        full = math.ceil(h / step - 1e-9) - 1  # steps before the last: each exactly 1 s (propagate's min)
        if g != g_c or done_c > full:
            g_c = g
            done_c = 0
            copy_chain(r, mu_h[g], x_h[g], P_h[g], mu_c, x_c, P_c)
        while done_c < full:
            predict_into(kinds, omegas, qs, tpm_kind, tpm_param, tpm_param2, 1.0, r, mu_c, x_c, P_c,
                         PI, F, Q, tmp, cbar, x0, P0, xp, Pp)
            copy_chain(r, cbar, xp, Pp, mu_c, x_c, P_c)
            done_c += 1
        d = min(step, h - float(full))
        predict_into(kinds, omegas, qs, tpm_kind, tpm_param, tpm_param2, d, r, mu_c, x_c, P_c,
                     PI, F, Q, tmp, cbar, x0, P0, xp, Pp)
        combine_into(cbar, xp, Pp, r, xc_out[q], Pc_out[q])


@njit(cache=True, nogil=True)
def propagate(kinds, omegas, qs, tpm_kind, tpm_param, tpm_param2, mu, x, P, horizon_s, step_s,
              mu_out, x_out, P_out, xc_out, Pc_out):
    """Repeated IMM prediction cycles without measurements (the conflict paper's trajectory
    prediction): steps of step_s up to horizon_s; writes per step the mode-conditioned states and the
    combined mean and mixture covariance. Returns the number of steps."""
    r = kinds.shape[0]
    cbar = np.empty(r)
    x0 = np.empty((r, NX))
    P0 = np.empty((r, NX, NX))
    PI = np.empty((r, r))
    F = np.empty((NX, NX))
    Q = np.empty((NX, NX))
    tmp = np.empty((NX, NX))
    mu_c = mu.copy()
    x_c = x.copy()
    P_c = P.copy()
    n = x_out.shape[0]
    done = 0.0
    for k in range(n):
        d = min(step_s, horizon_s - done)
        predict_into(kinds, omegas, qs, tpm_kind, tpm_param, tpm_param2, d, r, mu_c, x_c, P_c,
                     PI, F, Q, tmp, cbar, x0, P0, x_out[k], P_out[k])
        for j in range(r):
            mu_out[k, j] = cbar[j]
            mu_c[j] = cbar[j]
        x_c[:] = x_out[k]
        P_c[:] = P_out[k]
        combine_into(cbar, x_out[k], P_out[k], r, xc_out[k], Pc_out[k])
        done += d
    return n
