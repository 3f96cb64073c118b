"""IMM trajectory prediction for conflicts: checked against the CV model's F P F^T + Q by hand and the
mixture formula, and end to end on a tracked straight flight."""

from __future__ import annotations

import numpy as np
import pandas as pd

from pipeline.conflict.predict import predict_tracks, propagate_state
from pipeline.track import ImmState, Mode, Plane, TrackerConfig, track

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
