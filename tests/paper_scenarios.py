"""tracking.md 4.4 scenarios 1 and 2 with IMM-predicted PC: the geometry, the filters (msdc's kernel or
the numpy IMM of tests/paper_imm.py, which can rotate the CA noise with the heading), and the PC error
of a prediction 20 s ahead against the PC of the true positions 20 s later.

Shared by tests/test_conflict_paper_scenarios.py and benchmarks/conflict_paper_scenarios.py. ADS-B at
1 Hz with SIGMA_M position noise per axis; Delta t = 1 s for estimation and prediction; radius 2 NM.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import paper_imm
from paper_imm import PaperMode

from msdc.pipeline.conflict import conflict_probability
from msdc.pipeline.conflict.predict import propagate_state
from msdc.pipeline.track import ImmState, Mode, Plane, TrackerConfig
from msdc.pipeline.track.plane import filter_plane

NM = 1852.0
KT = NM / 3600.0
RADIUS_M = 2.0 * NM
HORIZON_S = 20.0
SIGMA_M = 15.0
TURN_DPS, TURN_START_S, TURN_END_S = 1.5, 50.0, 110.0
B1_M = np.array([7.0, -2.0]) * NM


@dataclass(frozen=True)
class Predictor:
    """A prediction model: its modes, the fixed TPM's stay probability, and which IMM runs it."""

    name: str
    modes: tuple[PaperMode, ...]
    p_stay: float = 0.95
    engine: str = "kernel"  # "kernel" (msdc's) or "numpy" (tests/paper_imm.py; heading-aligned noise)


def standard(sigma_ca: float = 1.0, p_stay: float = 0.95, sigma_cv: float = 0.5) -> list[Predictor]:
    """CV-only, CA-only and CV+CA IMM as in benchmarks/conflict_scenario1.py."""
    cv, ca = PaperMode("cv", sigma_cv), PaperMode("ca", sigma_ca)
    return [Predictor("cv", (cv,), 1.0), Predictor("ca", (ca,), 1.0), Predictor("imm", (cv, ca), p_stay)]


def truth1(t: np.ndarray, speed_mps: float) -> np.ndarray:
    """Scenario 1, aircraft A (m): along +x, a left turn at TURN_DPS from 50 s to 110 s, then along +y."""
    w = np.radians(TURN_DPS)
    r = speed_mps / w
    tt = np.clip(t - TURN_START_S, 0.0, TURN_END_S - TURN_START_S)
    x = np.where(t <= TURN_START_S, t * speed_mps, speed_mps * TURN_START_S + r * np.sin(w * tt))
    y = np.where(t <= TURN_START_S, 0.0, r * (1.0 - np.cos(w * tt)))
    y = y + np.maximum(t - TURN_END_S, 0.0) * speed_mps
    return np.column_stack([x, y])


def truth2(t: np.ndarray, speed_a_mps: float, speed_b_mps: float) -> tuple[np.ndarray, np.ndarray]:
    """Scenario 2 (m): A from (-10, 0) NM and B from (-5, -2) NM, both along +x, A faster."""
    a = np.column_stack([-10.0 * NM + speed_a_mps * t, np.zeros_like(t)])
    b = np.column_stack([-5.0 * NM + speed_b_mps * t, np.full_like(t, -2.0 * NM)])
    return a, b


def predictions(pred: Predictor, t: np.ndarray, z: np.ndarray, made: np.ndarray, var_m2: float = SIGMA_M**2
                ) -> tuple[np.ndarray, np.ndarray]:
    """Filter z (n, 2) at t, then predict HORIZON_S ahead from each time in made: means (k, 2) and
    covariances (k, 2, 2)."""
    idx = np.searchsorted(t, made)
    means, covs = np.empty((len(made), 2)), np.empty((len(made), 2, 2))
    sel = np.ix_([0, 3], [0, 3])
    if pred.engine == "kernel":
        modes = tuple(Mode(m.kind, m.kind, m.sigma) for m in pred.modes)
        cfg = TrackerConfig(modes=modes, tpm=f"fixed:{pred.p_stay:g}")
        var = np.full(len(t), var_m2)
        run = filter_plane(cfg, t, z[:, 0], z[:, 1], var, np.zeros(len(t)), var)
        args = cfg.kernel_args()
        for k, i in enumerate(idx):
            state = ImmState("A", None, Plane(0.0, 0.0), cfg, run.mu[i], run.x[i], run.P[i])
            m, c = propagate_state(state, [HORIZON_S], 1.0, args=args)
            means[k], covs[k] = m[0, [0, 3]], c[0][sel]
        return means, covs
    mu, x, P = paper_imm.filter_track(pred.modes, pred.p_stay, t, z, var_m2)
    PI = paper_imm.tpm_fixed(pred.p_stay, len(pred.modes))
    for k, i in enumerate(idx):
        m, c = paper_imm.propagate(pred.modes, PI, mu[i], x[i], P[i], HORIZON_S)
        means[k], covs[k] = m[[0, 3]], c[sel]
    return means, covs


def scenario1(preds, speed_kt: float, seed: int = 1, var_m2: float = SIGMA_M**2,
              duration_s: float = 130.0) -> dict[str, dict[str, float]]:
    """Per predictor: mean signed and absolute PC error (predicted minus the true-position PC 20 s later,
    B at (7, -2) NM with P_B = I NM^2), overall and for predictions made in the turn's first 20 s
    (52-72 s) and for predictions whose target time is 52-72 s, and the peak predicted PC; plus the
    truth's peak."""
    speed = speed_kt * KT
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, duration_s + 0.5, 1.0)
    z = truth1(t, speed) + rng.normal(0.0, np.sqrt(var_m2), (len(t), 2))
    made = t[(t >= 20.0) & (t + HORIZON_S <= duration_s)]
    P_B = np.eye(2) * NM**2
    ref = conflict_probability(truth1(made + HORIZON_S, speed) - B1_M,
                               np.broadcast_to(P_B, (len(made), 2, 2)), RADIUS_M)
    turn = (made >= 52.0) & (made <= 72.0)
    # the paper plots predicted PC shifted +20 s: if its 52-72 s are target times, predictions made 32-52 s
    target = (made + HORIZON_S >= 52.0) & (made + HORIZON_S <= 72.0)
    out = {}
    for p in preds:
        m, c = predictions(p, t, z, made, var_m2)
        pc = conflict_probability(m - B1_M, c + P_B, RADIUS_M)
        err = pc - ref
        out[p.name] = {"bias": float(err.mean()), "mae": float(np.abs(err).mean()),
                       "turn_bias": float(err[turn].mean()), "turn_mae": float(np.abs(err[turn]).mean()),
                       "target_turn_bias": float(err[target].mean()), "peak_pc": float(pc.max())}
    out["truth"] = {"peak_pc": float(ref.max())}
    return out


def scenario2(preds, speed_a_kt: float, speed_b_kt: float, nav_var_nm2: float, seed: int = 2,
              duration_s: float = 360.0) -> dict[str, dict[str, float]]:
    """Per predictor (both aircraft tracked and predicted 20 s with it): PC error against the PC of the
    true relative position 20 s later, both with the relative navigation covariance nav_var_nm2 I (the
    predicted covariances of A and B are added to it for the prediction); for each, the one-block and
    16-block PC of the same prediction minus its exact PC. Closest clearance 2 NM = radius."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, duration_s + 0.5, 1.0)
    a, b = truth2(t, speed_a_kt * KT, speed_b_kt * KT)
    za = a + rng.normal(0.0, SIGMA_M, a.shape)
    zb = b + rng.normal(0.0, SIGMA_M, b.shape)
    made = t[(t >= 20.0) & (t + HORIZON_S <= duration_s)]
    nav = np.eye(2) * nav_var_nm2 * NM**2
    ta, tb = truth2(made + HORIZON_S, speed_a_kt * KT, speed_b_kt * KT)
    ref = conflict_probability(ta - tb, np.broadcast_to(nav, (len(made), 2, 2)), RADIUS_M)
    out = {"truth": {"peak_pc": float(ref.max())}}
    for p in preds:
        ma, ca = predictions(p, t, za, made)
        mb, cb = predictions(p, t, zb, made)
        cov = ca + cb + nav
        pc = conflict_probability(ma - mb, cov, RADIUS_M)
        one = conflict_probability(ma - mb, cov, RADIUS_M, method="one-block")
        n16 = conflict_probability(ma - mb, cov, RADIUS_M, method="blocks", n=16)
        err = pc - ref
        out[p.name] = {"bias": float(err.mean()), "mae": float(np.abs(err).mean()),
                       "max_abs": float(np.abs(err).max()), "peak_pc": float(pc.max()),
                       "one_block_excess_max": float((one - pc).max()),
                       "one_block_excess_at_peak": float(one[pc.argmax()] - pc.max()),
                       "n16_excess_max": float((n16 - pc).max())}
    return out
