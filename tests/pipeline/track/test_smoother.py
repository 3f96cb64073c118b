"""The IMM (two-filter) smoother against textbook numpy written here: with one mode it is the
Rauch-Tung-Striebel smoother, with two modes the backward recursion (Kim's pair probabilities, the later
data's information per mode fused with each mode's filtered state, per-mode mixture); and the seeded
comparison with the RTS pass on the combined estimate (fixtures/track_scenarios.py truth)."""

import numpy as np
import pandas as pd
import pytest

import fixtures.track_scenarios as sc
from msdc.pipeline.track import Mode, TrackerConfig, default_modes, track
from msdc.pipeline.track.plane import estimate, filter_plane

IDX = [0, 1, 3, 4]  # e, ve, n, vn: CV and CT keep the acceleration states at exactly zero


def _f(omega, dt):
    """Textbook CV (omega 0) or coordinated-turn transition on [e, ve, n, vn] (tracking.md 1.2)."""
    if omega == 0.0:
        return np.array([[1, dt, 0, 0], [0, 1, 0, 0], [0, 0, 1, dt], [0, 0, 0, 1.0]])
    s, c = np.sin(omega * dt), np.cos(omega * dt)
    return np.array([[1, s / omega, 0, -(1 - c) / omega], [0, c, 0, -s],
                     [0, (1 - c) / omega, 1, s / omega], [0, s, 0, c]])


def _q(sigma, dt):
    g = np.array([[dt * dt / 2, 0], [dt, 0], [0, dt * dt / 2], [0, dt]])
    return sigma**2 * g @ g.T


def _plots(seed, n=14):
    rng = np.random.default_rng(seed)
    truth = sc.fly((0.0, 0.0), 90.0, 100.0, [(20, 0, 0), (25, 3.0, 0), (20, 0, 0)])
    t = np.sort(rng.uniform(0.0, 64.0, n))
    e, nn = truth.at(t)
    var = np.full(n, 900.0)
    return t, e + rng.normal(0, 30.0, n), nn + rng.normal(0, 30.0, n), var


def test_single_mode_is_exactly_rts():
    t, e, n, var = _plots(1)
    cfg = TrackerConfig(modes=(Mode("cv", "cv", 1.5),), gate_probability=1.0)
    run = filter_plane(cfg, t, e, n, var, 0 * var, var)
    x = run.x[:, 0][:, IDX]
    P = run.P[:, 0][:, IDX][:, :, IDX]
    xs, Ps = [x[-1]], [P[-1]]
    for k in range(len(t) - 2, -1, -1):
        F, dt = _f(0.0, t[k + 1] - t[k]), t[k + 1] - t[k]
        Pp = F @ P[k] @ F.T + _q(1.5, dt)
        G = P[k] @ F.T @ np.linalg.inv(Pp)
        xs.insert(0, x[k] + G @ (xs[0] - F @ x[k]))
        Ps.insert(0, P[k] + G @ (Ps[0] - Pp) @ G.T)
    got = estimate(run, t, smooth=True, smoother="imm")
    np.testing.assert_allclose(got.x[:, IDX], np.array(xs), rtol=1e-9, atol=1e-6)
    np.testing.assert_allclose(got.P[:, IDX][:, :, IDX], np.array(Ps), rtol=1e-7, atol=1e-6)
    # between updates too: the same joint law as the RTS pass on the combined estimate
    grid = np.arange(np.ceil(t[0]), t[-1], 0.5)
    np.testing.assert_allclose(estimate(run, grid, smooth=True, smoother="imm").x,
                               estimate(run, grid, smooth=True).x, rtol=1e-9, atol=1e-6)


def test_two_modes_follow_the_two_filter_recursion():
    t, e, n, var = _plots(2)
    omega = np.radians(3.0)
    sig = [0.5, 1.0]
    p = 0.9
    cfg = TrackerConfig(modes=(Mode("cv", "cv", sig[0]), Mode("left", "ct", sig[1], -3.0)), tpm=f"fixed:{p}",
                        gate_probability=1.0)
    run = filter_plane(cfg, t, e, n, var, 0 * var, var)
    PI = np.array([[p, 1 - p], [1 - p, p]])
    mu = run.mu
    x = run.x[:, :, IDX]
    P = run.P[:, :, IDX][:, :, :, IDX]
    K, r = mu.shape
    mus, xs, Ps = mu.copy(), x.copy(), P.copy()
    for k in range(K - 2, -1, -1):
        dt = t[k + 1] - t[k]
        cbar = PI.T @ mu[k]
        w = PI * mu[k][:, None] * mus[k + 1][None, :] / cbar[None, :]  # Kim's pair probabilities
        mus[k] = w.sum(axis=1)
        info = []
        for j, om in enumerate((0.0, omega)):
            m = PI[:, j] * mu[k] / cbar[j]  # the forward mixing for mode j
            x0 = m @ x[k]
            P0 = sum(m[i] * (P[k, i] + np.outer(x[k, i] - x0, x[k, i] - x0)) for i in range(r))
            F, Q = _f(om, dt), _q(sig[j], dt)
            xp, Pp = F @ x0, F @ P0 @ F.T + Q
            # what the later data say about x_k+1 given mode j (smoothed over predicted), non-negative part
            L = np.linalg.inv(Ps[k + 1, j]) - np.linalg.inv(Pp)
            lv = np.linalg.inv(Ps[k + 1, j]) @ xs[k + 1, j] - np.linalg.inv(Pp) @ xp
            lam, V = np.linalg.eigh(L)
            keep = lam > 0
            L = V[:, keep] @ np.diag(lam[keep]) @ V[:, keep].T
            lv = V[:, keep] @ V[:, keep].T @ lv
            # carried back to x_k through x_k+1 = F x_k + w, w ~ N(0, Q)
            B = np.linalg.inv(np.eye(4) + Q @ L)
            info.append((F.T @ L @ B @ F, F.T @ B.T @ lv))
        for i in range(r):
            xf, Pf = [], []
            for Om, om_ in info:
                A = np.linalg.inv(P[k, i]) + Om
                Pf.append(np.linalg.inv(A))
                xf.append(Pf[-1] @ (np.linalg.inv(P[k, i]) @ x[k, i] + om_))
            v = w[i] / mus[k, i]
            xs[k, i] = v[0] * xf[0] + v[1] * xf[1]
            Ps[k, i] = sum(v[j] * (Pf[j] + np.outer(xf[j] - xs[k, i], xf[j] - xs[k, i])) for j in range(r))
    got = estimate(run, t, smooth=True, smoother="imm")
    np.testing.assert_allclose(got.mu, mus, atol=1e-9)
    np.testing.assert_allclose(got.x[:, IDX], np.einsum("ki,kia->ka", mus, xs), rtol=1e-8, atol=1e-5)
    spread = np.einsum("ki,kia,kib->kab", mus, xs, xs) - np.einsum(
        "ka,kb->kab", *(2 * [np.einsum("ki,kia->ka", mus, xs)]))
    np.testing.assert_allclose(got.P[:, IDX][:, :, IDX], np.einsum("ki,kiab->kab", mus, Ps) + spread,
                               rtol=1e-6, atol=1e-4)
    assert (mus[:, 1] > 0.5).any() and (mus[:, 0] > 0.5).any()  # the case exercises both modes


def test_compared_with_rts_on_three_radars():
    # three radars, the dynamic-TPM paper's truth and filter (CV 0.1, CT 0.5; turns of 0.25-2.5 deg/s against
    # the modes' 3 deg/s): both smoothers far better than the forward filter; the IMM smoother better on
    # the straight legs and clearly worse in the manoeuvres (benchmark, 100 runs: 28.6 vs 31.5 m and 51.8
    # vs 43.0 m)
    rng = np.random.default_rng(21)
    truth = sc.tpm_paper_truth()
    grid = np.arange(30.0, truth.t[-1] - 30.0, 1.0)
    man = np.zeros(len(grid), bool)
    for a, b in sc.TPM_PAPER_MANOEUVRES_S:
        man |= (grid >= a) & (grid <= b + 30)
    e, n = truth.at(grid)
    cfg = TrackerConfig(modes=default_modes(3.0, sigma_cv_mps2=0.1, sigma_ct_mps2=0.5))
    err = {"fwd": [], "rts": [], "imm": []}
    for _ in range(4):
        p = sc.merge(*[sc.rotating_radar(truth, site, period, phase, pd, 70.0, 0.08, rng, sensor=i)
                       for i, (site, period, phase, pd) in enumerate(sc.TPM_PAPER_RADARS)])
        run = filter_plane(cfg, p.t, p.e, p.n, p.ree, p.ren, p.rnn)
        for k, kw in (("fwd", {}), ("rts", {"smooth": True}), ("imm", {"smooth": True, "smoother": "imm"})):
            x = estimate(run, grid, **kw).x
            err[k].append((x[:, 0] - e) ** 2 + (x[:, 3] - n) ** 2)
    man_rms = {k: np.sqrt(np.mean(np.array(v)[:, man])) for k, v in err.items()}
    straight = {k: np.sqrt(np.mean(np.array(v)[:, ~man])) for k, v in err.items()}
    for k in ("rts", "imm"):
        assert man_rms[k] < 0.6 * man_rms["fwd"] and straight[k] < 0.6 * straight["fwd"]
    assert man_rms["rts"] < 0.9 * man_rms["imm"]
    assert straight["imm"] < straight["rts"]


def test_track_smoother_option():
    t = np.arange(0.0, 60.0, 4.0)
    frame = pd.DataFrame({"time": pd.Timestamp("2019-03-01T10:00:00Z") + pd.to_timedelta(t, unit="s"),
                          "sensor_id": "r",
                          "sensor_kind": "radar", "aircraft_id": "A", "latitude": 50.0,
                          "longitude": 4.0 + t * 1e-3, "flight_level": 300.0, "cov_ee_m2": 900.0,
                          "cov_en_m2": 0.0, "cov_nn_m2": 900.0})
    res = track(frame, smooth=True, smoother="imm")
    assert res.parameters["smoother"] == "imm"
    assert np.allclose(res.tracks[["mode_cv", "mode_turn_left", "mode_turn_right"]].sum(axis=1), 1.0)
    with pytest.raises(ValueError, match="smoother 'kim'"):
        track(frame, smooth=True, smoother="kim")


def test_after_a_segments_last_update_both_smoothers_keep_the_forward_prediction():
    """Two stretches of plots 200 s apart (two segments) and output times every 0.5 s through both and up to
    50 s after each one's last plot: after a segment's last update both smoothers give the forward
    prediction itself (state, covariance and, for RTS, mode probabilities, which it never smooths), while
    between updates they differ from it; RTS's mode probabilities are the forward ones at every time."""
    t1, e1, n1, var1 = _plots(3)
    t2, e2, n2, var2 = _plots(4)
    t = np.r_[t1, t2 + 264.0]
    e, n, var = np.r_[e1, e2 + 20_000.0], np.r_[n1, n2], np.r_[var1, var2]
    run = filter_plane(TrackerConfig(), t, e, n, var, 0 * var, var)
    seg = run.segment[run.accepted]
    assert len(np.unique(seg)) == 2
    ends = run.t[run.accepted][np.r_[seg[1:] != seg[:-1], True]]
    grid = np.unique(np.r_[np.arange(t[0], ends[0] + 50.0, 0.5),
                           np.arange(t2[0] + 264.0, ends[1] + 50.0, 0.5)])
    after = (grid > ends[0]) & (grid < t2[0] + 264.0) | (grid > ends[1])
    forward = estimate(run, grid)
    for smoother in ("rts", "imm"):
        got = estimate(run, grid, smooth=True, smoother=smoother)
        np.testing.assert_array_equal(got.x[after], forward.x[after])
        np.testing.assert_array_equal(got.P[after], forward.P[after])
        assert np.isfinite(got.x).all() and np.isfinite(got.P).all()
        between = ~after & (forward.age_s > 0)
        assert between.sum() > 100 and (np.abs(got.x[between] - forward.x[between]).max(axis=1) > 1e-6).all()
        if smoother == "rts":
            np.testing.assert_array_equal(got.mu, forward.mu)
