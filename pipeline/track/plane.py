"""The tracker on plane coordinates: filter a time-ordered measurement sequence, then estimate (predict
or smooth) at any set of times. The DataFrame front end and the validations both build on this."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from msdc.pipeline.meta import SMOOTHERS

from .config import TrackerConfig
from .imm import NX, STATUS_REJECTED, predict_rows, run_filter
from .smooth import imm_smooth_rows, smooth_rows


@dataclass
class PlaneRun:
    """Per measurement: status (0 gated, 1 updated, 2 segment start), nis, segment, t_state and the
    mode-conditioned posterior (mu, x, P) and vertical state (zv, Pv) after it."""

    config: TrackerConfig
    t: np.ndarray
    status: np.ndarray
    nis: np.ndarray
    segment: np.ndarray
    t_state: np.ndarray
    mu: np.ndarray
    x: np.ndarray
    P: np.ndarray
    zv: np.ndarray
    Pv: np.ndarray
    t_fl: np.ndarray | None = None  # time of the last accepted flight level behind each row (NaN: none)

    @property
    def accepted(self) -> np.ndarray:
        return self.status != STATUS_REJECTED


@dataclass
class Estimates:
    """Combined estimates at query times: x (n, 6) = [e, ve, ae, n, vn, an], P (n, 6, 6), mode
    probabilities mu (n, r), vertical zv (n, 2) = [FL, FL/s], Pv, and per query the index of the
    governing measurement row and the time since it (0: an update at that time)."""

    t: np.ndarray
    x: np.ndarray
    P: np.ndarray
    mu: np.ndarray
    zv: np.ndarray
    Pv: np.ndarray
    row: np.ndarray
    age_s: np.ndarray


def filter_plane(config: TrackerConfig, t, ze, zn, cov_ee, cov_en, cov_nn, *, fl=None, ve0=None, vn0=None,
                 var_v0=None, on_ground=None) -> PlaneRun:
    """Run the IMM over measurements sorted by time (s), positions and covariances in the plane. on_ground:
    1 where a report says the aircraft is on the surface (its level is then held, not extrapolated)."""
    args = config.kernel_args()
    t = np.ascontiguousarray(t, float)
    n = len(t)
    if n and np.any(np.diff(t) < 0):
        raise ValueError("measurements must be sorted by time")
    r = len(config.modes)

    def col(v, default):
        return np.full(n, default, float) if v is None else np.ascontiguousarray(v, float)

    status = np.empty(n, np.int64)
    nis = np.empty(n)
    segment = np.empty(n, np.int64)
    t_state = np.empty(n)
    mu = np.empty((n, r))
    x = np.empty((n, r, NX))
    P = np.empty((n, r, NX, NX))
    zv = np.empty((n, 2))
    Pv = np.zeros((n, 2, 2))
    run_filter(t, col(ze, 0), col(zn, 0), col(cov_ee, 0), col(cov_en, 0), col(cov_nn, 0),
               col(ve0, 0.0), col(vn0, 0.0), col(var_v0, config.sigma_init_speed_mps ** 2),
               col(fl, np.nan), col(on_ground, np.nan), args["kinds"], args["omegas"], args["qs"],
               args["mu0"], args["tpm_kind"], args["tpm_param"], args["tpm_param2"], args["gate_d2"],
               args["max_coast_s"], args["restart_after"], args["max_speed_mps"], args["q_fl"],
               args["var_fl"],
               status, nis, segment, t_state, mu, x, P, zv, Pv, True)
    t_fl = _last_level_time(t, status != STATUS_REJECTED, col(fl, np.nan), segment)
    _forget_stale_levels(t_state, t_fl, config.max_coast_s, zv, Pv)
    return PlaneRun(config, t, status, nis, segment, t_state, mu, x, P, zv, Pv, t_fl)


def _last_level_time(t, accepted, fl, segment) -> np.ndarray:
    """Per row, the time of the last accepted report with a flight level in its segment up to it (NaN if
    none): the vertical filter has seen nothing newer."""
    has = accepted & np.isfinite(fl)
    last = np.maximum.accumulate(np.where(has, np.arange(len(t)), -1)) if len(t) else np.zeros(0, int)
    ok = (last >= 0) & (segment[np.maximum(last, 0)] == segment)
    return np.where(ok, t[np.maximum(last, 0)], np.nan)


def _forget_stale_levels(t, t_fl, max_coast_s: float, zv, Pv) -> None:
    """The flight level is extrapolated at most max_coast_s past its last report, like the position: past
    that (an aircraft that stopped reporting its level, e.g. on the surface) it is unknown (NaN), not the
    last vertical rate flown on for minutes."""
    stale = (t - t_fl) > max_coast_s
    zv[stale] = np.nan
    Pv[stale] = np.nan


def estimate(run: PlaneRun, times, *, smooth: bool = False, smoother: str = "rts") -> Estimates:
    """Combined estimates at sorted times (each at or after the first measurement): the last accepted
    update at or before each time, predicted forward, or when smooth, smoothed: smoother "rts" (RTS on the
    combined estimate; mode probabilities stay forward) or "imm" (IMM smoother, smoothed mode
    probabilities too)."""
    if smoother not in SMOOTHERS:
        raise ValueError(f"smoother {smoother!r}: expected one of {', '.join(SMOOTHERS)}")
    args = run.config.kernel_args()
    qt = np.ascontiguousarray(times, float)
    acc_idx = np.flatnonzero(run.accepted)
    acc_t = run.t[acc_idx]
    k = np.searchsorted(acc_t, qt, side="right") - 1
    if np.any(k < 0):
        raise ValueError("estimate: a time precedes the first measurement")
    gov = acc_idx[k]
    dt = qt - acc_t[k]
    nq, r = len(qt), run.mu.shape[1]
    xc = np.empty((nq, NX))
    Pc = np.empty((nq, NX, NX))
    mu = np.empty((nq, r))
    zv = np.empty((nq, 2))
    Pv = np.empty((nq, 2, 2))
    if smooth:  # the smoothers replace every forward state but those after a segment's last update
        seg = run.segment[acc_idx]
        last = np.r_[seg[1:] != seg[:-1], True] if len(seg) else np.zeros(0, bool)
        want = last[k] & (dt != 0.0)
    else:
        want = np.ones(nq, bool)
    predict_rows(gov, dt, want, args["kinds"], args["omegas"], args["qs"], args["tpm_kind"],
                 args["tpm_param"], args["tpm_param2"], args["q_fl"], args["coast_substep_s"], run.mu, run.x,
                 run.P, run.zv, run.Pv, xc, Pc, mu, zv, Pv)
    if run.t_fl is not None:
        _forget_stale_levels(qt, run.t_fl[gov], run.config.max_coast_s, zv, Pv)
    if smooth:
        xs = np.empty_like(xc)
        Ps = np.empty_like(Pc)
        common = (acc_t, run.segment[acc_idx], run.mu[acc_idx], run.x[acc_idx], run.P[acc_idx],
                  args["kinds"], args["omegas"], args["qs"], args["tpm_kind"], args["tpm_param"],
                  args["tpm_param2"], k, dt, xc, Pc)
        if smoother == "imm":
            mus = np.empty_like(mu)
            imm_smooth_rows(*common, mu, xs, Ps, mus)
            mu = mus
        else:
            smooth_rows(*common, xs, Ps)
        xc, Pc = xs, Ps
    return Estimates(qt, xc, Pc, mu, zv, Pv, gov, dt)
