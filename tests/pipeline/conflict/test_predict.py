"""IMM trajectory prediction for conflicts: checked against the CV model's F P F^T + Q by hand and the
mixture formula, and end to end on a tracked straight flight."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from scipy.stats import norm

from msdc.pipeline.conflict import pair_probabilities
from msdc.pipeline.conflict.predict import predict_tracks, propagate_state, vertical_prediction
from msdc.pipeline.track import ImmState, Mode, Plane, TrackerConfig, track
from msdc.pipeline.track.imm import propagate

T0 = pd.Timestamp("2026-01-01 12:00:00", tz="UTC")


def _cv_fq(dt: float, q: float) -> tuple[np.ndarray, np.ndarray]:
    """Nearly-constant-velocity model per axis (position, velocity, unused acceleration), written out
    here: piecewise-constant white acceleration of variance q."""
    f = np.array([[1.0, dt, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 0.0]])
    g = np.array([dt * dt / 2, dt, 0.0])
    F, Q = np.zeros((6, 6)), np.zeros((6, 6))
    for o in (0, 3):
        F[o:o + 3, o:o + 3] = f
        Q[o:o + 3, o:o + 3] = q * np.outer(g, g)
    return F, Q


def _state(modes, mu, x, P, tpm="fixed:1") -> ImmState:
    cfg = TrackerConfig(modes=tuple(modes), tpm=tpm)
    return ImmState("A", T0, Plane(50.0, 5.0), cfg, np.asarray(mu, float), np.asarray(x, float),
                    np.asarray(P, float))


def test_pure_cv_state_predicts_the_straight_line_and_fpft_plus_q():
    sigma = 0.7
    x0 = np.array([100.0, 150.0, 0.0, -200.0, -80.0, 0.0])
    P0 = np.diag([400.0, 25.0, 0.0, 900.0, 16.0, 0.0])
    P0[0, 1] = P0[1, 0] = 30.0
    state = _state([Mode("cv", "cv", sigma)], [1.0], x0[None], P0[None])
    means, covs = propagate_state(state, np.array([20.0, 60.0]), 1.0)
    F, Q = _cv_fq(1.0, sigma**2)
    P = P0.copy()
    expected = {}
    for k in range(1, 61):
        P = F @ P @ F.T + Q
        expected[k] = P.copy()
    for row, k in enumerate((20, 60)):
        assert np.allclose(means[row, [0, 3]], [100.0 + 150.0 * k, -200.0 - 80.0 * k], atol=1e-6)
        sel = [0, 1, 3, 4]
        assert np.allclose(covs[row][np.ix_(sel, sel)], expected[k][np.ix_(sel, sel)], rtol=1e-9, atol=1e-6)


def test_two_modes_mixture_includes_the_spread_of_the_mode_means():
    # two CV modes, no switching (PI = I): each mode flies its own straight line
    sigma = 0.5
    xa = np.array([0.0, 200.0, 0.0, 0.0, 0.0, 0.0])
    xb = np.array([0.0, 180.0, 0.0, 0.0, 30.0, 0.0])
    P0 = np.diag([100.0, 4.0, 0.0, 100.0, 4.0, 0.0])
    mu = np.array([0.7, 0.3])
    state = _state([Mode("a", "cv", sigma), Mode("b", "cv", sigma)], mu, [xa, xb], [P0, P0])
    means, covs = propagate_state(state, np.array([60.0]), 1.0)
    F, Q = _cv_fq(1.0, sigma**2)
    P = P0.copy()
    xs = [xa.copy(), xb.copy()]
    for _ in range(60):
        P = F @ P @ F.T + Q
        xs = [F @ x for x in xs]
    mean = mu[0] * xs[0] + mu[1] * xs[1]
    cov = sum(m * (P + np.outer(x - mean, x - mean)) for m, x in zip(mu, xs, strict=True))
    assert np.allclose(means[0], mean, atol=1e-6)
    assert np.allclose(covs[0], cov, rtol=1e-9, atol=1e-6)
    # the spread term is what makes the north variance large: 0.21 * (30 m/s * 60 s)^2
    assert covs[0][3, 3] > P[3, 3] + 0.2 * 1800.0**2


def _straight_reports(aircraft_id: str, lat0: float, lon0: float, ve: float, vn: float, fl: float,
                      seconds: int) -> pd.DataFrame:
    plane = Plane(lat0, lon0)
    t = np.arange(seconds, dtype=float)
    lat, lon = plane.inverse(ve * t, vn * t)
    return pd.DataFrame({"time": T0 + pd.to_timedelta(t, unit="s"), "sensor_id": "021:0/1",
                         "sensor_kind": "adsb", "aircraft_id": aircraft_id, "latitude": lat,
                         "longitude": lon, "flight_level": fl, "cov_ee_m2": 25.0, "cov_en_m2": 0.0,
                         "cov_nn_m2": 25.0})


def test_tracked_straight_flight_is_predicted_along_its_line_in_a_common_plane():
    reports = _straight_reports("X", 50.0, 5.0, 200.0, 0.0, 350.0, 120)
    # CV only: the IMM's turn modes would (rightly) pull the 60 s mean short of the straight line
    result = track(reports, keep_states=True, config=TrackerConfig(modes=(Mode("cv", "cv", 0.5),)))
    pred = predict_tracks(result, [20, 60], plane=Plane(50.0, 5.0))
    assert set(pred["horizon_s"]) == {20.0, 60.0}
    row = pred[(pred["time"] == T0 + pd.Timedelta(100, "s")) & (pred["horizon_s"] == 60)].iloc[0]
    # truth: 200 m/s east along the plane's x axis from the origin, at 160 s
    assert abs(row["east_m"] - 200.0 * 160) < 30.0
    assert abs(row["north_m"]) < 30.0
    assert abs(row["flight_level"] - 350.0) < 0.5
    sixty = pred[pred["horizon_s"] == 60]["var_east_m2"].median()
    twenty = pred[pred["horizon_s"] == 20]["var_east_m2"].median()
    assert sixty > twenty > 0


def _sample_jump_system(mu, xs, Ps, omega_rps, sigmas, p_stay, steps, n, rng):
    """Monte Carlo of the Markov-jump linear system the IMM prediction describes, written out here:
    start in mode i with probability mu_i and x ~ N(x_i, P_i); each 1 s step first switches mode
    (stay with p_stay), then moves by that mode's model: straight (omega 0) or a coordinated turn,
    counter-clockwise at omega, plus a white acceleration per axis held over the step."""
    mode = (rng.random(n) >= mu[0]).astype(int)
    x = np.empty((n, 6))
    for i in (0, 1):
        sel = mode == i
        x[sel] = rng.multivariate_normal(xs[i], Ps[i], size=int(sel.sum()), method="svd")
    for _ in range(steps):
        mode = np.where(rng.random(n) < p_stay, mode, 1 - mode)
        e, ve, nn, vn = x[:, 0], x[:, 1], x[:, 3], x[:, 4]
        new = x.copy()
        for i in (0, 1):
            sel = mode == i
            w = omega_rps[i]
            if w == 0.0:
                new[sel, 0] = e[sel] + ve[sel]
                new[sel, 3] = nn[sel] + vn[sel]
            else:
                s, c = np.sin(w), np.cos(w)
                new[sel, 0] = e[sel] + s / w * ve[sel] - (1 - c) / w * vn[sel]
                new[sel, 1] = c * ve[sel] - s * vn[sel]
                new[sel, 3] = nn[sel] + (1 - c) / w * ve[sel] + s / w * vn[sel]
                new[sel, 4] = s * ve[sel] + c * vn[sel]
            acc = rng.normal(0.0, sigmas[i], size=(int(sel.sum()), 2))
            new[sel, 0] += 0.5 * acc[:, 0]
            new[sel, 1] += acc[:, 0]
            new[sel, 3] += 0.5 * acc[:, 1]
            new[sel, 4] += acc[:, 1]
        x = new
    return x, mode


def test_switching_cv_and_turn_modes_match_monte_carlo_of_the_jump_system():
    # CV and a 3 deg/s left turn, switching with probability 0.02 per 1 s cycle, 20 s ahead
    rng = np.random.default_rng(11)
    omega = np.radians(3.0)
    mu = np.array([0.6, 0.4])
    xa = np.array([0.0, 220.0, 0.0, 0.0, 10.0, 0.0])
    xb = np.array([50.0, 200.0, 0.0, -30.0, 60.0, 0.0])
    Pa = np.diag([900.0, 9.0, 0.0, 400.0, 16.0, 0.0])
    Pa[0, 3] = Pa[3, 0] = 200.0
    Pb = np.diag([400.0, 25.0, 0.0, 900.0, 4.0, 0.0])
    state = _state([Mode("cv", "cv", 0.5), Mode("left", "ct", 1.5, -3.0)], mu, [xa, xb], [Pa, Pb],
                   tpm="fixed:0.98")
    means, covs = propagate_state(state, np.array([20.0]), 1.0)
    n = 60_000
    x, mode = _sample_jump_system(mu, [xa, xb], [Pa, Pb], (0.0, omega), (0.5, 1.5), 0.98, 20, n, rng)
    idx = [0, 1, 3, 4]
    sample_mean = x.mean(axis=0)
    se_mean = x.std(axis=0, ddof=1) / np.sqrt(n)
    assert np.all(np.abs(means[0][idx] - sample_mean[idx]) < 4.5 * se_mean[idx])
    d = x - sample_mean
    for a in idx:
        for b in idx:
            prod = d[:, a] * d[:, b]
            se = prod.std(ddof=1) / np.sqrt(n)
            assert abs(covs[0][a, b] - prod.mean()) < 4.5 * se, (a, b, covs[0][a, b], prod.mean(), se)
    # the test can see the spread of the mode means: the final modes' covariances without it (from the
    # tracker's step kernel) put the position variances many standard errors away
    args = state.config.kernel_args()
    out = (np.empty((20, 2)), np.empty((20, 2, 6)), np.empty((20, 2, 6, 6)), np.empty((20, 6)),
           np.empty((20, 6, 6)))
    propagate(args["kinds"], args["omegas"], args["qs"], args["tpm_kind"], args["tpm_param"],
              args["tpm_param2"], mu, np.array([xa, xb]), np.array([Pa, Pb]), 20.0, 1.0, *out)
    no_spread = np.einsum("j,jab->ab", out[0][-1], out[2][-1])
    for a in (0, 3):
        se = (d[:, a] ** 2).std(ddof=1) / np.sqrt(n)
        assert abs(no_spread[a, a] - (d[:, a] ** 2).mean()) > 10 * se


def test_vertical_sigma_is_the_iterated_level_and_rate_model():
    # [FL, FL/s] with F = [[1, s], [0, 1]], Q = q [[s^4/4, s^3/2], [s^3/2, s^2]] per cycle of s seconds,
    # iterated by hand: 2.6 s of coasting (cycles 1, 1, 0.6), then 20 s in whole cycles
    q, zv, Pv = 0.03**2, np.array([350.0, 0.5]), np.array([[0.09, 0.01], [0.01, 0.04]])
    P = Pv.copy()
    for s in [1.0, 1.0, 0.6] + [1.0] * 20:
        F = np.array([[1.0, s], [0.0, 1.0]])
        P = F @ P @ F.T + q * np.array([[s**4 / 4, s**3 / 2], [s**3 / 2, s**2]])
    fl, sigma_ft = vertical_prediction(zv, Pv, 2.6, 20.0, q, 1.0)
    assert fl == pytest.approx(350.0 + 0.5 * 22.6)
    assert sigma_ft == pytest.approx(100.0 * np.sqrt(P[0, 0]), rel=1e-12)
    # no coasting, 2-second cycles
    P = Pv.copy()
    for _ in range(30):
        F = np.array([[1.0, 2.0], [0.0, 1.0]])
        P = F @ P @ F.T + q * np.array([[4.0, 4.0], [4.0, 4.0]])
    sigma_ft = vertical_prediction(zv, Pv, 0.0, 60.0, q, 2.0)[1]
    assert sigma_ft == pytest.approx(100.0 * np.sqrt(P[0, 0]), rel=1e-12)


def test_probabilistic_vertical_pc_is_horizontal_pc_times_the_gaussian_level_probability():
    # two tracked flights 2 km apart, 600 ft apart in level: PC = horizontal PC x P(|dz| < 1000 ft)
    a = _straight_reports("A", 50.0, 5.0, 200.0, 0.0, 350.0, 90)
    b = _straight_reports("B", 50.0, 5.0, 200.0, 0.0, 356.0, 90)
    b["latitude"] += 2000.0 / 111_250.0
    cfg = TrackerConfig(modes=(Mode("cv", "cv", 0.5),))
    result = track(pd.concat([a, b], ignore_index=True), keep_states=True, config=cfg)
    pred = predict_tracks(result, [20, 60], plane=Plane(50.0, 5.0), sigma_alt=True)
    assert (pred.groupby("horizon_s")["sigma_alt_ft"].median().diff().dropna() > 0).all()
    pc = pair_probabilities(pred)
    hard = pair_probabilities(pred.drop(columns="sigma_alt_ft"))
    row = pc[(pc["time"] == T0 + pd.Timedelta(80, "s")) & (pc["horizon_s"] == 60)].iloc[0]
    ra = pred[(pred["time"] == row["time"]) & (pred["horizon_s"] == 60)].set_index("aircraft_id")
    dz = 100.0 * (ra.loc["A", "flight_level"] - ra.loc["B", "flight_level"])
    s = np.hypot(ra.loc["A", "sigma_alt_ft"], ra.loc["B", "sigma_alt_ft"])
    # against 1000 ft less the default 25 ft tolerance (the level quantum)
    p_vertical = norm.cdf((975.0 - dz) / s) - norm.cdf((-975.0 - dz) / s)
    assert 0.05 < p_vertical < 0.99
    h = hard.set_index(["time", "aircraft_a", "aircraft_b", "horizon_s"])["pc"]
    assert row["pc"] == pytest.approx(h.loc[(row["time"], "A", "B", 60.0)] * p_vertical, rel=1e-9)


def test_a_prediction_step_off_the_tracks_grid_is_refused():
    """On a 5 s track a 3 s step met the grid only every 15 s (audit A13): refused, naming both steps;
    a whole multiple of the track's step predicts every one of its times."""
    reports = _straight_reports("X", 50.0, 5.0, 200.0, 0.0, 350.0, 120)
    result = track(reports, step_s=5.0, keep_states=True)
    for bad in (3.0, 1.0, 7.5):
        with pytest.raises(ValueError, match=rf"step_s {bad!r}: .* every 5 s \(track\(step_s=5\)\); give a "
                                             r"whole multiple of 5 s"):
            predict_tracks(result, [21], step_s=bad)
    pred = predict_tracks(result, [20], step_s=10.0)
    seconds = (pred["time"] - T0.floor("D")).dt.total_seconds()
    # the reports run 0-119 s after T0 and coast 60 s more: every multiple of 10 s in that span
    first = np.ceil((T0 - T0.floor("D")).total_seconds() / 10.0) * 10.0
    assert np.allclose(seconds % 10.0, 0.0) and seconds.min() == first
    assert (np.diff(np.sort(seconds.to_numpy())) == 10.0).all()


def test_prediction_arguments_of_the_wrong_type_are_named():
    reports = _straight_reports("X", 50.0, 5.0, 200.0, 0.0, 350.0, 30)
    result = track(reports, step_s=5.0, keep_states=True)
    with pytest.raises(TypeError, match=r"step_s '5': must be a number of seconds, not str"):
        predict_tracks(result, [20], step_s="5")
    with pytest.raises(TypeError, match=r"horizons_s \['a'\]: give the horizons as numbers of seconds"):
        predict_tracks(result, ["a"], step_s=5.0)
    one = predict_tracks(result, 20, step_s=5.0)  # one horizon as a number: the same as (20,)
    pd.testing.assert_frame_equal(one, predict_tracks(result, [20], step_s=5.0))
