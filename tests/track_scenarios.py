"""Truth trajectories and sensor simulators for the tracker's tests and benchmarks (plane coordinates).

Angles: headings and azimuths clockwise from north (deg); turn rates positive = left (counter-
clockwise), as in the tracker's CT modes. Nothing here calls the tracker.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

DT_TRUTH_S = 0.01


@dataclass
class Truth:
    """Dense truth samples: t (s), east/north (m), velocity (m/s)."""

    t: np.ndarray
    e: np.ndarray
    n: np.ndarray
    ve: np.ndarray
    vn: np.ndarray

    def at(self, times):
        """Positions (east, north) at arbitrary times by linear interpolation of the dense samples."""
        return np.interp(times, self.t, self.e), np.interp(times, self.t, self.n)

    def velocity_at(self, times):
        return np.interp(times, self.t, self.ve), np.interp(times, self.t, self.vn)


def fly(start_en, heading_deg, speed_mps, legs, dt=DT_TRUTH_S) -> Truth:
    """Integrate legs of (duration_s, turn_rate_dps (left +), along-track acceleration m/s^2) at steps of
    dt by the midpoint rule (heading and speed exact, position to O(dt^2))."""
    rates, accels = [], []
    for duration, rate_dps, accel in legs:
        steps = int(round(duration / dt))
        rates.append(np.full(steps, np.radians(rate_dps)))
        accels.append(np.full(steps, float(accel)))
    w = np.concatenate(rates)
    a = np.concatenate(accels)
    psi0 = np.radians(90.0 - heading_deg)  # math angle, counter-clockwise from east
    psi = psi0 + np.concatenate([[0.0], np.cumsum(w * dt)])
    v = speed_mps + np.concatenate([[0.0], np.cumsum(a * dt)])
    v_mid = v[:-1] + 0.5 * a * dt
    psi_mid = psi[:-1] + 0.5 * w * dt
    e = start_en[0] + np.concatenate([[0.0], np.cumsum(v_mid * np.cos(psi_mid) * dt)])
    n = start_en[1] + np.concatenate([[0.0], np.cumsum(v_mid * np.sin(psi_mid) * dt)])
    t = np.arange(len(e)) * dt
    return Truth(t, e, n, v * np.cos(psi), v * np.sin(psi))


def polar_covariance(rho_m, theta_deg, sigma_r_m, sigma_theta_deg):
    """Linearised converted-measurement covariance (ee, en, nn) of range/azimuth (clockwise from north),
    written out independently of the package: R = J diag(sr^2, st^2) J^T with e = r sin t, n = r cos t."""
    th = np.radians(theta_deg)
    st = np.radians(sigma_theta_deg)
    j = np.array([[np.sin(th), rho_m * np.cos(th)], [np.cos(th), -rho_m * np.sin(th)]])
    j = np.moveaxis(j, -1, 0) if j.ndim == 3 else j
    d = np.diag([sigma_r_m**2, st**2]) if np.ndim(rho_m) == 0 else None
    if d is not None:
        r = j @ d @ j.T
        return r[0, 0], r[0, 1], r[1, 1]
    var = np.stack([np.full_like(th, sigma_r_m**2), np.full_like(th, st**2)], -1)
    r = np.einsum("nik,nk,njk->nij", j, var, j)
    return r[:, 0, 0], r[:, 0, 1], r[:, 1, 1]


@dataclass
class Plots:
    """Sensor reports: time, measured east/north, covariance, sensor number."""

    t: np.ndarray
    e: np.ndarray
    n: np.ndarray
    ree: np.ndarray
    ren: np.ndarray
    rnn: np.ndarray
    sensor: np.ndarray


def rotating_radar(truth: Truth, site_en, period_s, phase_deg, pd, sigma_r_m, sigma_theta_deg, rng,
                   sensor=0) -> Plots:
    """A plot each time the antenna (clockwise from north, azimuth phase + 360 t / period) sweeps over
    the target, kept with probability pd; noise in range and azimuth, converted back to the plane."""
    de = truth.e - site_en[0]
    dn = truth.n - site_en[1]
    az_target = np.degrees(np.arctan2(de, dn))
    az_antenna = phase_deg + 360.0 * truth.t / period_s
    diff = (az_antenna - az_target + 180.0) % 360.0 - 180.0
    cross = np.flatnonzero((diff[:-1] < 0.0) & (diff[1:] >= 0.0) & (diff[1:] - diff[:-1] < 90.0))
    f = -diff[cross] / (diff[cross + 1] - diff[cross])
    t = truth.t[cross] + f * (truth.t[cross + 1] - truth.t[cross])
    t = t[rng.random(len(t)) < pd]
    e, n = truth.at(t)
    rho = np.hypot(e - site_en[0], n - site_en[1]) + rng.normal(0.0, sigma_r_m, len(t))
    theta = np.degrees(np.arctan2(e - site_en[0], n - site_en[1])) + rng.normal(0.0, sigma_theta_deg, len(t))
    me = site_en[0] + rho * np.sin(np.radians(theta))
    mn = site_en[1] + rho * np.cos(np.radians(theta))
    ree, ren, rnn = polar_covariance(rho, theta, sigma_r_m, sigma_theta_deg)
    return Plots(t, me, mn, ree, ren, rnn, np.full(len(t), sensor))


def merge(*plots: Plots) -> Plots:
    """All sensors' reports in time order."""
    cat = {k: np.concatenate([getattr(p, k) for p in plots]) for k in Plots.__dataclass_fields__}
    order = np.argsort(cat["t"], kind="stable")
    return Plots(**{k: v[order] for k, v in cat.items()})


def position_sensor(truth: Truth, times, mean_err_m, std_err_m, rng, sensor=0) -> Plots:
    """The robust-IMM paper's sensor: Euclidean error magnitude ~ N(mean, std^2), uniform direction;
    reported covariance isotropic with the same second moment."""
    e, n = truth.at(times)
    rho = np.abs(rng.normal(mean_err_m, std_err_m, len(times)))
    ang = rng.uniform(0.0, 2.0 * np.pi, len(times))
    var = 0.5 * (mean_err_m**2 + std_err_m**2)
    z = np.zeros(len(times))
    return Plots(np.asarray(times, float), e + rho * np.cos(ang), n + rho * np.sin(ang), z + var, z, z + var,
                 np.full(len(times), sensor))


# the dynamic-TPM paper's truth (tracking.md 1.4): 90 m/s, ten legs (duration s, turn deg/s, accel)
TPM_PAPER_LEGS = [(330, 0.0, 0.0), (63, 1.5, 0.0), (120, 0.0, 0.0), (57, -0.25, 0.0), (105, 0.0, 0.0),
                  (43, -2.0, 0.0), (122, 0.0, 0.0), (23, -2.5, 0.0), (70, -0.5, 0.0), (86, 0.0, 0.0)]
# our choice of start (not in the paper): keeps the target 32-80 km from radars A, B and C
TPM_PAPER_START_EN = (0.0, -40000.0)
TPM_PAPER_HEADING_DEG = 135.0
TPM_PAPER_RADARS = [((0.0, 0.0), 10.0, 0.0, 1.0), ((35000.0, 15000.0), 12.0, 30.0, 1.0),
                    ((30000.0, -15000.0), 12.0, 240.0, 0.5)]
TPM_PAPER_MANOEUVRES_S = [(330, 393), (513, 570), (675, 718), (840, 933)]


def tpm_paper_truth() -> Truth:
    return fly(TPM_PAPER_START_EN, TPM_PAPER_HEADING_DEG, 90.0, TPM_PAPER_LEGS)
