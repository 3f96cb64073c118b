"""tracking.md 4.4 scenario 1: PC predicted 20 s ahead by CV-only, CA-only and CV+CA IMM prediction,
against the PC of the true position 20 s later (B stationary at (7, -2) NM, P_B = I NM^2, radius 2 NM).

Speeds (lost in the paper): 250, 350, 420 and 480 kt, each printed. A turns left at 1.5 deg/s from
50 s to 110 s. ADS-B at 1 Hz with 15 m position noise per axis.
Run: `python benchmarks/conflict_scenario1.py` from the repository root.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from msdc.pipeline.conflict import conflict_probability  # noqa: E402
from msdc.pipeline.conflict.predict import propagate_state  # noqa: E402
from msdc.pipeline.track import ImmState, Mode, Plane, TrackerConfig  # noqa: E402
from msdc.pipeline.track.plane import filter_plane  # noqa: E402

NM = 1852.0
KT = NM / 3600.0
TURN_DPS, TURN_START_S, TURN_END_S = 1.5, 50.0, 110.0
B_M = np.array([7.0, -2.0]) * NM
P_B = np.eye(2) * NM**2
RADIUS_M = 2.0 * NM
HORIZON_S = 20.0
SIGMA_M = 15.0

MODELS = {
    "cv": (Mode("cv", "cv", 0.5),),
    "ca": (Mode("ca", "ca", 1.0),),
    "imm": (Mode("cv", "cv", 0.5), Mode("ca", "ca", 1.0)),
}


def truth(t: np.ndarray, speed_mps: float) -> np.ndarray:
    """True position (m) of A: straight along +x, a left turn at TURN_DPS, then straight along +y."""
    w = np.radians(TURN_DPS)
    r = speed_mps / w
    x0 = speed_mps * TURN_START_S
    tt = np.clip(t - TURN_START_S, 0.0, TURN_END_S - TURN_START_S)
    pos = np.column_stack([np.minimum(t, TURN_START_S) * speed_mps, np.zeros_like(t)])
    pos[:, 0] = np.where(t <= TURN_START_S, pos[:, 0], x0 + r * np.sin(w * tt))
    pos[:, 1] = np.where(t <= TURN_START_S, 0.0, r * (1.0 - np.cos(w * tt)))
    after = np.maximum(t - TURN_END_S, 0.0)
    pos[:, 1] += after * speed_mps
    return pos


def run(speed_kt: float, seed: int = 1, duration_s: float = 130.0) -> dict[str, dict[str, float]]:
    """Per model: mean signed and mean absolute error of the predicted PC against the true-position PC
    20 s later, overall and for predictions made during the turn's first 20 s (52-72 s)."""
    speed_mps = speed_kt * KT
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, duration_s + 0.5, 1.0)
    z = truth(t, speed_mps) + rng.normal(0.0, SIGMA_M, (len(t), 2))
    var = np.full(len(t), SIGMA_M**2)
    made = t[(t >= 20.0) & (t + HORIZON_S <= duration_s)]
    ref = conflict_probability(truth(made + HORIZON_S, speed_mps) - B_M,
                               np.broadcast_to(P_B, (len(made), 2, 2)), RADIUS_M)
    out = {}
    for name, modes in MODELS.items():
        cfg = TrackerConfig(modes=modes, tpm="fixed:0.95" if len(modes) > 1 else "fixed:1")
        pr = filter_plane(cfg, t, z[:, 0], z[:, 1], var, np.zeros(len(t)), var)
        args = cfg.kernel_args()
        pc = np.empty(len(made))
        for k, tk in enumerate(made):
            i = int(np.flatnonzero(t == tk)[0])
            state = ImmState("A", None, Plane(0.0, 0.0), cfg, pr.mu[i], pr.x[i], pr.P[i])
            m, c = propagate_state(state, [HORIZON_S], 1.0, args=args)
            cov = c[0][np.ix_([0, 3], [0, 3])] + P_B
            pc[k] = conflict_probability(m[0, [0, 3]] - B_M, cov, RADIUS_M)
        err = pc - ref
        turn = (made >= 52.0) & (made <= 72.0)
        out[name] = {"bias": float(err.mean()), "mae": float(np.abs(err).mean()),
                     "turn_bias": float(err[turn].mean()), "turn_mae": float(np.abs(err[turn]).mean()),
                     "peak_pc": float(pc.max())}
    out["truth"] = {"peak_pc": float(ref.max())}
    return out


if __name__ == "__main__":
    for speed in (250.0, 350.0, 420.0, 480.0):
        print(f"== {speed:g} kt")
        for name, row in run(speed).items():
            print(f"  {name:5s}", {k: round(v, 4) for k, v in row.items()})
