"""IMM-predicted trajectories of tracked aircraft: the `predictions` frame `pair_probabilities` takes.

At every output time of a track, the IMM posterior after the last update is propagated without
measurements (`pipeline.track.imm.propagate`: mixing, mode-matched prediction, mode probabilities by the
Markov chain, mixture covariance including the spread of the mode means) to each look-ahead. Positions
and covariances are moved from each aircraft's own plane into one common plane. Vertically, the track's
flight level is extrapolated with its vertical rate (the tracker does not export the vertical
covariance, so no `sigma_alt_ft` column: PC then counts a pair only when the predicted levels differ by
less than the vertical minimum).
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from pipeline.track.frame import Plane
from pipeline.track.imm import NX, propagate
from pipeline.track.tracker import ImmState, TrackResult

FL_PER_S_PER_FPM = 1.0 / 6000.0


def propagate_state(state: ImmState, ahead_s, step_s: float, *, args: dict | None = None
                    ) -> tuple[np.ndarray, np.ndarray]:
    """Combined mean (k, 6) and mixture covariance (k, 6, 6) of the state propagated to each ahead_s
    (seconds after state.time, ascending, >= 0), in IMM cycles of at most step_s. args: the config's
    `kernel_args()` (computed when not given)."""
    ahead = np.asarray(ahead_s, float)
    if ahead.ndim != 1 or (np.diff(ahead) < 0).any() or (ahead < 0).any():
        raise ValueError("ahead_s: expected ascending times >= 0 s")
    args = state.config.kernel_args() if args is None else args
    mu, x, P = (np.asarray(state.mu, float).copy(), np.asarray(state.x, float).copy(),
                np.asarray(state.P, float).copy())
    means = np.empty((len(ahead), NX))
    covs = np.empty((len(ahead), NX, NX))
    done = 0.0
    xc, Pc = _combine(mu, x, P)
    for k, target in enumerate(ahead):
        gap = target - done
        if gap > 1e-9:
            on_grid = abs(gap / step_s - round(gap / step_s)) < 1e-9
            rest = ahead[k:] - done
            # one kernel call to every later target on the same step_s grid
            span = rest[np.abs(rest / step_s - np.round(rest / step_s)) < 1e-9].max() if on_grid else gap
            mu_o, x_o, P_o, xs, Ps = _run(args, mu, x, P, span, step_s)
            reached = done + np.minimum(np.arange(1, len(xs) + 1) * step_s, span)
            idx = np.searchsorted(reached, target - 1e-9)
            mu, x, P = mu_o[idx].copy(), x_o[idx].copy(), P_o[idx].copy()
            xc, Pc = xs[idx], Ps[idx]
            done = float(reached[idx])
        means[k], covs[k] = xc, Pc
    return means, covs


def _run(args: dict, mu, x, P, horizon_s: float, step_s: float):
    n = math.ceil(horizon_s / step_s - 1e-9)
    r = len(mu)
    out = (np.empty((n, r)), np.empty((n, r, NX)), np.empty((n, r, NX, NX)), np.empty((n, NX)),
           np.empty((n, NX, NX)))
    propagate(args["kinds"], args["omegas"], args["qs"], args["tpm_kind"], args["tpm_param"],
              args["tpm_param2"], mu, x, P, float(horizon_s), float(step_s), *out)
    return out


def _combine(mu, x, P) -> tuple[np.ndarray, np.ndarray]:
    """Mixture mean and covariance, including the spread of the mode means."""
    xc = mu @ x
    d = x - xc
    return xc, np.einsum("j,jab->ab", mu, P + d[:, :, None] * d[:, None, :])


def predict_tracks(result: TrackResult, horizons_s, *, step_s: float = 1.0,
                   plane: Plane | None = None) -> pd.DataFrame:
    """Predictions of every aircraft at every grid time of its track (multiples of step_s) and horizon.

    result: from `track(..., keep_states=True)`. Returns `aircraft_id, time, horizon_s, east_m, north_m,
    var_east_m2, cov_east_north_m2, var_north_m2, flight_level` in `plane` (default: around the median
    track position), plus `latitude, longitude` of the predicted mean.
    """
    horizons = np.array(sorted({float(h) for h in horizons_s}))
    if not len(horizons) or not (horizons > 0).all() or not step_s > 0:
        raise ValueError(f"horizons_s {list(horizons_s)!r} and step_s {step_s!r}: must be > 0")
    tracks = result.tracks
    if plane is None and len(tracks):
        plane = Plane.around(tracks["latitude"].to_numpy(float), tracks["longitude"].to_numpy(float))
    parts = []
    for aircraft_id, rows in tracks.groupby("aircraft_id", sort=True, observed=True):
        if str(aircraft_id) not in result.runs:
            raise KeyError(f"aircraft {aircraft_id!r}: no filter history (run track(..., keep_states=True))")
        own, run, epoch = result.runs[str(aircraft_id)]
        tod = rows["time_of_day"].to_numpy(float)
        on_grid = np.abs(tod / step_s - np.round(tod / step_s)) < 1e-6
        rows = rows.loc[on_grid & np.isfinite(rows["latitude"].to_numpy(float))]
        if rows.empty:
            continue
        t = (rows["time"] - epoch).dt.total_seconds().to_numpy(float)
        upd = np.flatnonzero(run.accepted)
        which = np.searchsorted(run.t[upd], t + 1e-9, side="right") - 1
        keep = which >= 0
        rows, t, which = rows.loc[keep], t[keep], which[keep]
        fl = rows["flight_level"].to_numpy(float)
        args = run.config.kernel_args()
        rate = rows["vertical_rate_fpm"].to_numpy(float) * FL_PER_S_PER_FPM
        n_h = len(horizons)
        means = np.empty((len(t) * n_h, NX))
        covs = np.empty((len(t) * n_h, NX, NX))
        order_t = np.argsort(which, kind="stable")
        bounds = np.flatnonzero(np.r_[True, np.diff(which[order_t]) != 0, True])
        for lo, hi in zip(bounds[:-1], bounds[1:], strict=True):
            sel = order_t[lo:hi]
            i = upd[which[sel[0]]]
            state = ImmState(str(aircraft_id), epoch + pd.to_timedelta(run.t[i], unit="s"), own, run.config,
                             run.mu[i], run.x[i], run.P[i])
            ahead = (t[sel, None] - run.t[i] + horizons[None, :]).ravel()
            uniq, inv = np.unique(np.round(ahead, 9), return_inverse=True)
            m, c = propagate_state(state, uniq, step_s, args=args)
            dest = (sel[:, None] * n_h + np.arange(n_h)[None, :]).ravel()
            means[dest], covs[dest] = m[inv], c[inv]
        parts.append({"aircraft_id": np.repeat(str(aircraft_id), len(means)),
                      "time": rows["time"].array.take(np.repeat(np.arange(len(t)), n_h)),
                      "horizon_s": np.tile(horizons, len(t)),
                      "e": means[:, 0], "n": means[:, 3],
                      "cov": covs[:, [[0, 0], [3, 3]], [[0, 3], [0, 3]]],
                      "flight_level": (fl[:, None] + rate[:, None] * horizons[None, :]).ravel(),
                      "own": own})
    columns = ["aircraft_id", "time", "horizon_s", "east_m", "north_m", "var_east_m2", "cov_east_north_m2",
               "var_north_m2", "flight_level", "latitude", "longitude"]
    if not parts:
        return pd.DataFrame({c: pd.Series(dtype=tracks["time"].dtype if c == "time" else
                                          (object if c == "aircraft_id" else float)) for c in columns})
    out = []
    for p in parts:
        lat, lon = p["own"].inverse(p["e"], p["n"])
        east, north = plane.forward(lat, lon)
        # plane vector = M_common @ local = M_common @ inv(M_own) @ own-plane vector
        m = plane.local_to_plane(lat, lon) @ np.linalg.inv(p["own"].local_to_plane(lat, lon))
        cov = m @ p["cov"] @ np.swapaxes(m, 1, 2)
        out.append(pd.DataFrame({"aircraft_id": p["aircraft_id"], "time": p["time"],
                                 "horizon_s": p["horizon_s"], "east_m": east, "north_m": north,
                                 "var_east_m2": cov[:, 0, 0], "cov_east_north_m2": cov[:, 0, 1],
                                 "var_north_m2": cov[:, 1, 1], "flight_level": p["flight_level"],
                                 "latitude": lat, "longitude": lon}))
    return pd.concat(out, ignore_index=True)
