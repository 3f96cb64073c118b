"""The IMM kernel against independent textbook implementations written here in plain numpy."""

import numpy as np
import pytest
from scipy.linalg import expm

from fixtures.track_scenarios import polar_covariance
from msdc.pipeline.track import Mode, TrackerConfig, nacp_covariance, parse_tpm, radar_covariance
from msdc.pipeline.track.imm import CA, CT, CV, TPM_DYNAMIC, TPM_EXPM, TPM_FIXED, tpm_into, transition_into
from msdc.pipeline.track.plane import estimate, filter_plane


def _tpm(kind, param, dt, r, param2=None):
    out = np.empty((r, r))
    tpm_into(kind, param, param if param2 is None else param2, dt, r, out)
    return out


@pytest.mark.parametrize("T, p", [(1, 0.995), (2, 0.9919), (4, 0.9819), (5, 0.9769), (10, 0.9519),
                                  (12, 0.9419)])
def test_dynamic_tpm_paper_values(T, p):
    # tracking.md 1.3 sample values and eq. 14's structure
    pi = _tpm(*parse_tpm("dynamic")[:2], T, 3, parse_tpm("dynamic")[2])
    expected = np.array([[p, (1 - p) / 2, (1 - p) / 2], [1 - p, p, 0], [1 - p, 0, p]])
    np.testing.assert_allclose(pi, expected, atol=5e-5)


def test_fixed_tpm():
    np.testing.assert_allclose(_tpm(TPM_FIXED, 0.9, 7.0, 2), [[0.9, 0.1], [0.1, 0.9]])
    np.testing.assert_allclose(_tpm(TPM_FIXED, 0.9, 7.0, 1), [[1.0]])


@pytest.mark.parametrize("r", [2, 3, 4])
@pytest.mark.parametrize("dt", [0.0, 1.0, 4.4, 60.0, 1000.0])
def test_expm_tpm_is_the_matrix_exponential(r, dt):
    tau = 200.0
    g = np.zeros((r, r))
    g[0, 1:] = 1.0 / (tau * (r - 1))  # base mode leaves at rate 1/tau, split evenly
    g[1:, 0] = 1.0 / tau  # each other mode returns to the base at rate 1/tau
    g -= np.diag(g.sum(axis=1))
    np.testing.assert_allclose(_tpm(TPM_EXPM, tau, dt, r), expm(g * dt), atol=1e-12)


@pytest.mark.parametrize("r", [2, 3, 4])
def test_expm_tpm_with_a_shorter_sojourn_in_the_other_modes(r):
    tau0, tau1, dt = 200.0, 30.0, 7.5
    g = np.zeros((r, r))
    g[0, 1:] = 1.0 / (tau0 * (r - 1))
    g[1:, 0] = 1.0 / tau1
    g -= np.diag(g.sum(axis=1))
    out = np.empty((r, r))
    tpm_into(TPM_EXPM, tau0, tau1, dt, r, out)
    np.testing.assert_allclose(out, expm(g * dt), atol=1e-12)


def _fq(kind, omega, q, dt):
    F = np.empty((6, 6))
    Q = np.empty((6, 6))
    transition_into(kind, omega, q, dt, F, Q)
    return F, Q


def test_coordinated_turn_moves_on_the_circle():
    # 90 m/s east, left turn at 3 deg/s for 7 s: exact circular arc
    w = np.radians(3.0)
    F, _ = _fq(CT, w, 0.0, 7.0)
    x = F @ np.array([0, 90.0, 0, 0, 0, 0])
    radius = 90.0 / w
    ang = w * 7.0
    np.testing.assert_allclose(x[[0, 3]], [radius * np.sin(ang), radius * (1 - np.cos(ang))], atol=1e-9)
    np.testing.assert_allclose(x[[1, 4]], [90 * np.cos(ang), 90 * np.sin(ang)], atol=1e-9)


def test_cv_and_ca_transitions():
    F, Q = _fq(CV, 0.0, 4.0, 2.0)
    x = F @ np.array([1.0, 3.0, 9.0, 2.0, -1.0, 9.0])
    np.testing.assert_allclose(x, [7.0, 3.0, 0.0, 0.0, -1.0, 0.0])
    np.testing.assert_allclose(Q[:2, :2], 4.0 * np.outer([2.0, 2.0], [2.0, 2.0]))
    F, Q = _fq(CA, 0.0, 1.0, 2.0)
    x = F @ np.array([0.0, 1.0, 0.5, 0.0, 0.0, -1.0])
    np.testing.assert_allclose(x, [3.0, 2.0, 0.5, -2.0, -2.0, -1.0])
    np.testing.assert_allclose(Q[3:, 3:], np.outer([2.0, 2.0, 1.0], [2.0, 2.0, 1.0]))


# --- an independent IMM, the textbook cycle of tracking.md section 0, 4-state [x, vx, y, vy] -----------

def _f4(omega, dt):
    if omega == 0.0:
        return np.array([[1, dt, 0, 0], [0, 1, 0, 0], [0, 0, 1, dt], [0, 0, 0, 1]], float)
    s, c = np.sin(omega * dt), np.cos(omega * dt)
    return np.array([[1, s / omega, 0, -(1 - c) / omega], [0, c, 0, -s],
                     [0, (1 - c) / omega, 1, s / omega], [0, s, 0, c]])


def _q4(q, dt):
    g = np.array([[dt * dt / 2, 0], [dt, 0], [0, dt * dt / 2], [0, dt]])
    return q * g @ g.T


def _reference_imm(t, z, R, omegas, qs, pi_fn, mu0, var_v):
    r = len(omegas)
    H = np.array([[1.0, 0, 0, 0], [0, 0, 1.0, 0]])
    x = [np.array([z[0, 0], 0, z[0, 1], 0]) for _ in range(r)]
    P = [np.diag([R[0][0, 0], var_v, R[0][1, 1], var_v]) for _ in range(r)]
    for j in range(r):
        P[j][0, 2] = P[j][2, 0] = R[0][0, 1]
    mu = np.array(mu0, float)
    out_x, out_mu = [sum(mu[j] * x[j] for j in range(r))], [mu.copy()]
    for k in range(1, len(t)):
        dt = t[k] - t[k - 1]
        pi = pi_fn(dt)
        cbar = pi.T @ mu
        xs, Ps, lik = [], [], []
        for j in range(r):
            w = pi[:, j] * mu / cbar[j]
            x0 = sum(w[i] * x[i] for i in range(r))
            P0 = sum(w[i] * (P[i] + np.outer(x[i] - x0, x[i] - x0)) for i in range(r))
            F = _f4(omegas[j], dt)
            xp = F @ x0
            Pp = F @ P0 @ F.T + _q4(qs[j], dt)
            S = H @ Pp @ H.T + R[k]
            K = Pp @ H.T @ np.linalg.inv(S)
            nu = z[k] - H @ xp
            xs.append(xp + K @ nu)
            Ps.append(Pp - K @ S @ K.T)
            lik.append(np.exp(-0.5 * nu @ np.linalg.solve(S, nu)) / np.sqrt(np.linalg.det(2 * np.pi * S)))
        mu = cbar * np.array(lik)
        mu /= mu.sum()
        x, P = xs, Ps
        out_x.append(sum(mu[j] * x[j] for j in range(r)))
        out_mu.append(mu.copy())
    return np.array(out_x), np.array(out_mu)


def _measurements(seed, n=60):
    rng = np.random.default_rng(seed)
    t = np.cumsum(rng.uniform(0.5, 6.0, n))
    t -= t[0]
    ang = np.radians(3.0) * np.clip(t - 100, 0, 40)
    z = np.stack([150 * t + 20 * np.sin(ang), 40 * np.cos(ang) * t / 10], -1) + rng.normal(0, 40, (n, 2))
    R = [np.array([[1600.0 + 300 * rng.random(), 200.0], [200.0, 1200.0]]) for _ in range(n)]
    return t, z, R


@pytest.mark.parametrize("tpm", ["fixed:0.95", "dynamic", "expm:200"])
def test_imm_matches_textbook_reference(tpm):
    t, z, R = _measurements(3)
    modes = (Mode("cv", "cv", 0.3), Mode("turn_left", "ct", 1.0, -3.0), Mode("turn_right", "ct", 1.0, 3.0))
    cfg = TrackerConfig(modes=modes, tpm=tpm, gate_probability=1.0)
    ka = cfg.kernel_args()
    R3 = np.array([[m[0, 0], m[0, 1], m[1, 1]] for m in R])
    run = filter_plane(cfg, t, z[:, 0], z[:, 1], R3[:, 0], R3[:, 1], R3[:, 2], var_v0=np.full(len(t), 1e4))
    est = estimate(run, t)

    def pi_fn(dt):
        return _tpm(ka["tpm_kind"], ka["tpm_param"], dt, 3, ka["tpm_param2"])

    ref_x, ref_mu = _reference_imm(t, z, R, [0.0, np.radians(3.0), -np.radians(3.0)], [0.09, 1.0, 1.0],
                                   pi_fn, ka["mu0"], 1e4)
    np.testing.assert_allclose(est.x[:, [0, 1, 3, 4]], ref_x, rtol=1e-7, atol=1e-6)
    np.testing.assert_allclose(est.mu, ref_mu, atol=1e-8)
    assert (run.status[1:] == 1).all()


def test_single_mode_is_a_kalman_filter_and_smoother():
    t, z, R = _measurements(5, 40)
    cfg = TrackerConfig(modes=(Mode("cv", "cv", 2.0),), gate_probability=1.0)
    R3 = np.array([[m[0, 0], m[0, 1], m[1, 1]] for m in R])
    run = filter_plane(cfg, t, z[:, 0], z[:, 1], R3[:, 0], R3[:, 1], R3[:, 2], var_v0=np.full(len(t), 1e4))
    ref_x, _ = _reference_imm(t, z, R, [0.0], [4.0], lambda dt: np.ones((1, 1)), [1.0], 1e4)
    np.testing.assert_allclose(estimate(run, t).x[:, [0, 1, 3, 4]], ref_x, rtol=1e-7, atol=1e-6)
    # a plain Rauch-Tung-Striebel backward pass on the reference filter
    H = np.array([[1.0, 0, 0, 0], [0, 0, 1.0, 0]])
    xs_f, Ps_f, xp_l, Pp_l, F_l = [], [], [], [], []
    x = np.array([z[0, 0], 0, z[0, 1], 0])
    P = np.diag([R[0][0, 0], 1e4, R[0][1, 1], 1e4])
    P[0, 2] = P[2, 0] = R[0][0, 1]
    xs_f.append(x)
    Ps_f.append(P)
    for k in range(1, len(t)):
        F = _f4(0.0, t[k] - t[k - 1])
        xp, Pp = F @ x, F @ P @ F.T + _q4(4.0, t[k] - t[k - 1])
        S = H @ Pp @ H.T + R[k]
        K = Pp @ H.T @ np.linalg.inv(S)
        x, P = xp + K @ (z[k] - H @ xp), Pp - K @ S @ K.T
        xs_f.append(x)
        Ps_f.append(P)
        xp_l.append(xp)
        Pp_l.append(Pp)
        F_l.append(F)
    xs = [xs_f[-1]]
    for k in range(len(t) - 2, -1, -1):
        G = Ps_f[k] @ F_l[k].T @ np.linalg.inv(Pp_l[k])
        xs.insert(0, xs_f[k] + G @ (xs[0] - xp_l[k]))
    np.testing.assert_allclose(estimate(run, t, smooth=True).x[:, [0, 1, 3, 4]], np.array(xs),
                               rtol=1e-7, atol=1e-5)


def test_gate_rejects_a_jump_and_keeps_the_track():
    t = np.arange(30.0)
    e = 100.0 * t
    n = np.zeros(30)
    n[12] = 3000.0  # an ADS-B-style position jump
    var = np.full(30, 100.0)
    run = filter_plane(TrackerConfig(), t, e, n, var, np.zeros(30), var)
    assert list(np.flatnonzero(run.status == 0)) == [12]
    assert run.nis[12] > 1000
    assert run.segment.max() == 0


def test_restart_after_gated_reports_takes_the_two_point_velocity():
    # a CV-only filter cannot follow a sudden 90 degree heading change: three gated reports restart it,
    # and the new segment's velocity comes from the last two reports (north at 100 m/s)
    t = np.arange(40.0)
    e = np.where(t < 20, 100.0 * t, 1900.0)
    n = np.where(t < 20, 0.0, 100.0 * (t - 19))
    var = np.full(40, 25.0)
    cfg = TrackerConfig(modes=(Mode("cv", "cv", 0.05),))
    run = filter_plane(cfg, t, e, n, var, 0 * t, var)
    starts = np.flatnonzero(run.status == 2)
    assert len(starts) == 2 and 20 < starts[1] <= 24
    k = starts[1]
    v = run.x[k, 0, [1, 4]]
    np.testing.assert_allclose(v, [0.0, 100.0], atol=1e-9)
    assert run.P[k, 0, 1, 1] == pytest.approx(25.0 + 25.0, rel=1e-9)  # Var(z_k - z_k-1) per axis, dt 1 s


def test_segments_end_after_max_coast():
    t = np.array([0.0, 1, 2, 3, 70, 71, 72])
    var = np.full(7, 100.0)
    run = filter_plane(TrackerConfig(max_coast_s=60.0), t, 50 * t, 0 * t, var, 0 * t, var)
    assert list(run.segment) == [0, 0, 0, 0, 1, 1, 1]
    assert list(run.status) == [2, 1, 1, 1, 2, 1, 1]


def test_radar_covariance_flat_limit_and_curvature():
    # both heights 0 and a short range: ground range = slant range, the linearised polar covariance
    ref = polar_covariance(5000.0, 30.0, 70.0, 0.08)
    got = radar_covariance(5000.0, 30.0, 0.0, 0.0, 70.0, 0.08)
    np.testing.assert_allclose(got, ref, rtol=1e-5)
    # 10 km up at 100 km slant: ground arc and its derivative from the triangle, by finite difference
    re = 6371000.0

    def ground(rho):
        a, b = re, re + 10000.0
        return re * np.arccos((a * a + b * b - rho * rho) / (2 * a * b))

    g = ground(100000.0)
    dg = (ground(100001.0) - ground(99999.0)) / 2.0
    ee, en, nn = radar_covariance(100000.0, 0.0, 10000.0, 0.0, 70.0, 0.08)
    assert nn == pytest.approx((dg * 70.0) ** 2, rel=1e-6)  # along range = north at azimuth 0
    assert ee == pytest.approx((g * np.radians(0.08)) ** 2, rel=1e-9)
    assert en == pytest.approx(0.0, abs=1e-9)
    assert np.isnan(radar_covariance(1000.0, 0.0, 5000.0, 0.0, 70.0, 0.08)[0])


def test_nacp_covariance():
    """(EPU / k)^2 with k the Rayleigh 95th percentile (2.4477, scipy), no floor: NACp 11 (3 m) gives
    1.502 m^2 (the 3 m floor gave 9 m^2), the measurement model's cov_ee_m2 for the same level."""
    from scipy.stats import rayleigh

    from msdc.pipeline.model.measurements import nacp_sigma_m

    k95 = rayleigh.ppf(0.95)
    got = nacp_covariance([9, 11, 0, np.nan, 7])
    np.testing.assert_allclose(got[[0, 1, 4]], [(30 / k95) ** 2, (3 / k95) ** 2, (185.2 / k95) ** 2],
                               rtol=1e-12)
    assert got[1] == pytest.approx(1.5021, abs=1e-4)
    assert np.isnan(got[2]) and np.isnan(got[3])
    np.testing.assert_allclose(got[[0, 1, 4]], nacp_sigma_m([9, 11, 7]) ** 2, rtol=1e-12)


def test_config_errors_name_the_value():
    with pytest.raises(ValueError, match="'fixed:1.5'"):
        TrackerConfig(tpm="fixed:1.5")
    assert parse_tpm("expm:200,30") == (TPM_EXPM, 200.0, 30.0)
    assert parse_tpm("dynamic:0.99,0.006") == (TPM_DYNAMIC, 0.99, 0.006)
    with pytest.raises(ValueError, match="'expm:x'"):
        TrackerConfig(tpm="expm:x")
    # the paper's p(T) = 1.0019 - 0.005 T is 0.0019 at 200 s and below 0 after 200.38 s
    assert TrackerConfig(tpm="dynamic", max_coast_s=200.0).max_coast_s == 200.0
    with pytest.raises(ValueError, match="at T = 201 s"):
        TrackerConfig(tpm="dynamic", max_coast_s=201.0)
    with pytest.raises(ValueError, match="kind 'xx'"):
        TrackerConfig(modes=(Mode("a", "xx", 1.0),))


@pytest.mark.parametrize("p", [0.5, 0.95, 0.99, 0.9973, 0.999, 0.999999])
def test_gate_is_the_chi_square_quantile_with_two_degrees_of_freedom(p):
    """The gate (Mahalanobis d^2) is chi2.ppf(p, 2) to the bit (it was computed by it), and for 2 degrees
    of freedom the quantile is -2 ln(1 - p) in closed form."""
    from scipy.stats import chi2

    gate = TrackerConfig(gate_probability=p).kernel_args()["gate_d2"]
    assert gate == float(chi2.ppf(p, 2))
    assert gate == pytest.approx(-2.0 * np.log1p(-p), rel=1e-12)
    assert TrackerConfig(gate_probability=1.0).kernel_args()["gate_d2"] == np.inf


@pytest.mark.parametrize(("p", "dof", "expected"), [
    (0.5, 1, 0.6744897501960817**2),  # a squared standard normal's median: the normal's 75 % point squared
    (0.95, 1, 1.959963984540054**2),
    (0.999, 1, 3.2905267314919255**2),
    (0.5, 2, 2.0 * np.log(2.0)),  # chi-square(2) is exponential with mean 2
    (0.999, 2, -2.0 * np.log(0.001)),
    (0.5, 4, 3.356693980033322),  # solves e^(-x/2) (1 + x/2) = 1/2 (chi-square(4) survival), bisected
])
def test_chi2_quantile_matches_closed_forms_and_scipy_stats(p, dof, expected):
    """The quantile without scipy.stats (noise estimation's gates and medians): closed forms for 1, 2 and
    4 degrees of freedom, and scipy.stats.chi2.ppf's bits."""
    from scipy.stats import chi2

    from msdc.pipeline.track.config import chi2_quantile

    q = chi2_quantile(p, dof)
    assert q == pytest.approx(expected, rel=1e-12)
    assert q == float(chi2.ppf(p, dof))
    if dof == 4:
        assert np.exp(-q / 2.0) * (1.0 + q / 2.0) == pytest.approx(1.0 - p, rel=1e-12)
