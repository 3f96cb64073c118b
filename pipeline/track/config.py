"""Tracker settings: the mode set, the transition-probability law, gating and coasting."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy.special import gammaincinv

from .imm import CA, CT, CV, TPM_DYNAMIC, TPM_EXPM, TPM_FIXED

_KINDS = {"cv": CV, "ct": CT, "ca": CA}
# expm sojourn times: from about the ASTERIX time quantum (1/128 s: a shorter mean stay cannot be observed;
# near 0, 1/TAU overflows and the closed form gives NaN) to 1e7 s (116 days: never left within a recording)
EXPM_SOJOURN_RANGE_S = (0.01, 1e7)


def chi2_quantile(p: float, dof: int) -> float:
    """The p quantile of chi-square with dof degrees of freedom, 2 P^-1(dof/2, p), as scipy.stats.chi2.ppf
    computes it, without importing scipy.stats (0.3-1 s and ~45 MB a process)."""
    return float(2.0 * gammaincinv(dof / 2.0, p))


@dataclass(frozen=True)
class Mode:
    """One motion model: kind "cv" | "ct" | "ca", turn rate (deg/s, positive = right turn: clockwise seen
    from above, track angle increasing, as the track table's turn_rate_dps; CT only) and the white-noise
    acceleration sigma (m/s^2; jerk, m/s^3, for CA)."""

    name: str
    kind: str
    sigma_a_mps2: float
    turn_rate_dps: float = 0.0


def default_modes(turn_rate_dps: float = 3.0, *, sigma_cv_mps2: float = 0.5, sigma_ct_mps2: float = 1.0,
                  with_ca: bool = False, sigma_ca_mps3: float = 1.0) -> tuple[Mode, ...]:
    """CV plus coordinated turns at +-turn_rate_dps (the dynamic-TPM paper's set), optionally CA. The
    sigmas are set for real traffic (the paper's 0.1 and 0.5 m/s^2 lag real decelerations)."""
    modes = [Mode("cv", "cv", sigma_cv_mps2), Mode("turn_left", "ct", sigma_ct_mps2, -turn_rate_dps),
             Mode("turn_right", "ct", sigma_ct_mps2, turn_rate_dps)]
    if with_ca:
        modes.append(Mode("ca", "ca", sigma_ca_mps3))
    return tuple(modes)


def parse_tpm(spec: str) -> tuple[int, float, float]:
    """'fixed:P' (0 < P <= 1), 'dynamic' (p(T) = min(0.995, 1.0019 - 0.005 T); 'dynamic:A,B' for
    min(0.995, A - B T)) or 'expm:TAU[,TAU2]' (continuous-time chain: mean sojourn TAU s in the first
    mode, TAU2 s (default TAU) in the others) -> (kernel code, parameter, second parameter); a
    ValueError names the bad value."""
    kind, _, value = spec.strip().partition(":")
    kind = kind.lower()
    if kind == "dynamic" and not value:
        return TPM_DYNAMIC, 1.0019, 0.005
    parts = value.split(",")
    try:
        numbers = [float(v) for v in parts]
    except ValueError:
        numbers = [math.nan]
    if kind == "fixed" and len(numbers) == 1 and 0.0 < numbers[0] <= 1.0:
        return TPM_FIXED, numbers[0], 0.0
    if kind == "dynamic" and len(numbers) == 2 and all(math.isfinite(v) for v in numbers):
        return TPM_DYNAMIC, numbers[0], numbers[1]
    lo, hi = EXPM_SOJOURN_RANGE_S
    if kind == "expm" and len(numbers) in (1, 2) and all(lo <= v <= hi for v in numbers):
        return TPM_EXPM, numbers[0], numbers[-1]
    raise ValueError(f"tpm {spec!r}: expected 'dynamic', 'dynamic:A,B', 'fixed:P' with 0 < P <= 1, or "
                     f"'expm:TAU' / 'expm:TAU,TAU2' with sojourn times from {lo:g} to {hi:,.0f} seconds")


def check_tpm(spec: str, max_dt_s: float) -> tuple[int, float, float]:
    """parse_tpm, and for 'dynamic:A,B' that p(T) = min(0.995, A - B T) is a probability above 0 for every
    update interval T from 0 to max_dt_s (p is linear in T, so both ends suffice; the kernel would clamp a
    p <= 0 to 0: the modes would switch at every update); a ValueError names the value otherwise."""
    kind, a, b = parse_tpm(spec)
    if kind == TPM_DYNAMIC:
        for t in (0.0, float(max_dt_s)):
            p = min(0.995, a - b * t)
            if not p > 0.0:
                raise ValueError(f"tpm {spec!r}: p(T) = min(0.995, {a:g} - {b:g} T) is {p:g} at T = {t:g} s; "
                                 f"it must stay above 0 for every update interval from 0 to {max_dt_s:g} s")
    return kind, a, b


@dataclass(frozen=True)
class TrackerConfig:
    """Everything the filter needs besides the measurements."""

    modes: tuple[Mode, ...] = field(default_factory=default_modes)
    tpm: str = "expm:150,20"  # mean sojourn 150 s in CV, 20 s in a turn: see docs/tracker.md
    gate_probability: float = 0.999
    max_coast_s: float = 60.0
    coast_substep_s: float = 1.0  # longest IMM prediction cycle for estimates between updates
    restart_after: int = 3  # consecutive gated reports that restart the track at the last one (0: never)
    # ... if that one lies within this speed of the gated report before it (+ 4 sigma of their noise): a
    # position jump (an ADS-B report hundreds of km off) never starts a segment; 600 m/s is ~1,170 kt
    max_speed_mps: float = 600.0
    sigma_fl: float = 0.3  # flight-level measurement sigma (FL): 100 ft Mode C quantisation
    sigma_vertical_fl_s2: float = 0.03  # vertical white-noise acceleration, FL/s^2 (about 1 m/s^2)
    sigma_init_speed_mps: float = 200.0  # velocity prior of a new segment without reported velocity
    sigma_reported_velocity_mps: float = 10.0  # velocity prior from a reported ground speed and heading

    def __post_init__(self) -> None:
        check_tpm(self.tpm, max(self.max_coast_s, self.coast_substep_s))
        if not self.modes:
            raise ValueError("modes: at least one mode is needed")
        for m in self.modes:
            if m.kind not in _KINDS:
                raise ValueError(f"mode {m.name!r}: kind {m.kind!r} is not one of cv, ct, ca")
            if not m.sigma_a_mps2 >= 0.0:
                raise ValueError(f"mode {m.name!r}: sigma_a_mps2 {m.sigma_a_mps2!r} must be >= 0")
        if not 0.0 < self.gate_probability <= 1.0:
            raise ValueError(f"gate_probability {self.gate_probability!r}: must be in (0, 1]")
        if not self.coast_substep_s > 0.0:
            raise ValueError(f"coast_substep_s {self.coast_substep_s!r}: must be > 0")
        if not self.max_speed_mps > 0.0:
            raise ValueError(f"max_speed_mps {self.max_speed_mps!r}: must be > 0")
        if not self.max_coast_s > 0.0:
            raise ValueError(f"max_coast_s {self.max_coast_s!r}: must be > 0")

    def kernel_args(self) -> dict:
        """Arrays and scalars in the kernel's units (rad/s, variances)."""
        tpm_kind, tpm_param, tpm_param2 = parse_tpm(self.tpm)
        r = len(self.modes)
        mu0 = np.full(r, 0.0)
        mu0[0] = 1.0 if r == 1 else 0.8
        if r > 1:
            mu0[1:] = 0.2 / (r - 1)
        p = self.gate_probability
        gate = math.inf if p >= 1.0 else chi2_quantile(p, 2)
        return {
            "kinds": np.array([_KINDS[m.kind] for m in self.modes], dtype=np.int64),
            # the kernel turns counter-clockwise (east/north plane, mathematical sense) for omega > 0
            "omegas": -np.radians(np.array([m.turn_rate_dps for m in self.modes], dtype=float)),
            "qs": np.array([m.sigma_a_mps2 for m in self.modes], dtype=float) ** 2,
            "mu0": mu0, "tpm_kind": tpm_kind, "tpm_param": tpm_param,
            "tpm_param2": tpm_param2, "gate_d2": gate,
            "max_coast_s": float(self.max_coast_s), "restart_after": int(self.restart_after),
            "max_speed_mps": float(self.max_speed_mps),
            "coast_substep_s": float(self.coast_substep_s),
            "q_fl": self.sigma_vertical_fl_s2 ** 2,
            "var_fl": self.sigma_fl ** 2,
        }
