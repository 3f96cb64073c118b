"""IMM-predicted trajectories of tracked aircraft: the `predictions` frame `pair_probabilities` takes.

At every output time of a track, the IMM posterior after the last update is coasted to that time and
propagated without measurements to each look-ahead (mixing, mode-matched prediction, mode probabilities
by the Markov chain, mixture covariance including the spread of the mode means), in cycles of at most
the step: all horizons of all output times of one aircraft in one numba call (`pipeline.conflict.moments`:
the prediction is a fixed linear map of the mode-weighted moments). Positions and covariances are moved
from each aircraft's own plane into one common plane. Vertically, the track's flight level is
extrapolated with its vertical rate; with `sigma_alt=True` the vertical filter's variance, propagated by
its own model, gives `sigma_alt_ft` (PC is then multiplied by the probability of vertical proximity).
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from msdc.pipeline.conflict.grid import on_grid
from msdc.pipeline.conflict.moments import ALL_PAIRS, POSITION_PAIRS, predict_states
from msdc.pipeline.model.arguments import finite_number
from msdc.pipeline.parallel import map_ordered
from msdc.pipeline.track.frame import Plane
from msdc.pipeline.track.imm import NX
from msdc.pipeline.track.tracker import ImmState, TrackResult

FL_PER_S_PER_FPM = 1.0 / 6000.0
FT_PER_FL = 100.0


def propagate_state(state: ImmState, ahead_s, step_s: float, *, args: dict | None = None
                    ) -> tuple[np.ndarray, np.ndarray]:
    """Combined mean (k, 6) and mixture covariance (k, 6, 6) of the state propagated to each ahead_s
    (seconds after state.time, ascending, >= 0), each in IMM cycles of step_s (the last one shorter).
    args: the config's `kernel_args()` (computed when not given)."""
    ahead = np.asarray(ahead_s, float)
    if ahead.ndim != 1 or (np.diff(ahead) < 0).any() or (ahead < 0).any():
        raise ValueError("ahead_s: expected ascending times >= 0 s")
    args = state.config.kernel_args() if args is None else args
    mean, cov = predict_states(args, np.zeros(1, np.int64), np.zeros(1), np.asarray(state.mu, float)[None],
                               np.asarray(state.x, float)[None], np.asarray(state.P, float)[None], ahead,
                               step_s, ALL_PAIRS)
    return mean[0], cov[0].reshape(len(ahead), NX, NX)


def vertical_prediction(zv: np.ndarray, Pv: np.ndarray, coast_s, ahead_s, q_fl: float, cycle_s: float
                        ) -> tuple[np.ndarray, np.ndarray]:
    """Flight level (FL) and its sigma (ft) of the vertical filter's state zv = [FL, FL/s] with covariance
    Pv, coasted coast_s (cycles of cycle_s, the last shorter) then ahead_s further (whole cycles) by its
    nearly-constant-rate model: a white acceleration of variance q_fl (FL^2/s^4) held over each cycle,
    as the horizontal IMM cycles (closed form of the iterated F P F^T + Q)."""
    c = np.asarray(coast_s, float)
    h = np.asarray(ahead_s, float)
    d = c + h
    fl = zv[..., 0] + d * zv[..., 1]
    var = Pv[..., 0, 0] + 2.0 * d * Pv[..., 0, 1] + d * d * Pv[..., 1, 1]
    # a run of n cycles of length s followed by r more seconds adds q s^2 sum_j (r + s (j + 1/2))^2
    n1 = np.floor(c / cycle_s + 1e-9)
    part = np.maximum(c - n1 * cycle_s, 0.0)
    n_h = np.round(h / cycle_s)
    after = part + n_h * cycle_s
    var += q_fl * cycle_s**4 * (n_h**3 / 3.0 - n_h / 12.0)
    var += q_fl * part**2 * (0.5 * part + n_h * cycle_s) ** 2
    var += q_fl * cycle_s**2 * (n1 * after**2 + after * cycle_s * n1**2
                                + cycle_s**2 * (n1**3 / 3.0 - n1 / 12.0))
    return fl, np.sqrt(np.maximum(var, 0.0)) * FT_PER_FL


def _inv2(m: np.ndarray) -> np.ndarray:
    """Inverses of (n, 2, 2) matrices in closed form."""
    det = m[:, 0, 0] * m[:, 1, 1] - m[:, 0, 1] * m[:, 1, 0]
    return np.stack([np.stack([m[:, 1, 1], -m[:, 0, 1]], -1), np.stack([-m[:, 1, 0], m[:, 0, 0]], -1)],
                    -2) / det[:, None, None]


def predict_tracks(result: TrackResult, horizons_s, *, step_s: float = 1.0,
                   plane: Plane | None = None, sigma_alt: bool = False) -> pd.DataFrame:
    """Predictions of every aircraft at every grid time of its track (multiples of step_s) and horizon.

    result: from `track(..., keep_states=True)`. Returns `aircraft_id, time, horizon_s, east_m, north_m,
    var_east_m2, cov_east_north_m2, var_north_m2, flight_level` in `plane` (default: around the median
    track position), plus `latitude, longitude` of the predicted mean, and with sigma_alt the predicted
    flight level's sigma `sigma_alt_ft` (from the vertical filter's covariance). step_s must be a whole
    multiple of the tracks' own step (ValueError otherwise: only the rows both grids share would be
    predicted).
    """
    step_s = finite_number("step_s", step_s)
    if isinstance(horizons_s, int | float | np.number):
        horizons_s = (horizons_s,)  # one horizon
    try:
        horizons = np.array(sorted({float(h) for h in horizons_s}))
    except (TypeError, ValueError):
        raise TypeError(f"horizons_s {horizons_s!r}: give the horizons as numbers of seconds, "
                        "e.g. (20, 60, 120)") from None
    if not len(horizons) or not (horizons > 0).all():
        raise ValueError(f"horizons_s {list(horizons_s)!r}: must be > 0")
    grid_s = float(result.parameters.get("step_s", step_s))
    ratio = float(step_s) / grid_s
    if abs(ratio - round(ratio)) > 1e-9 * max(ratio, 1.0) or round(ratio) < 1:
        # a step off the tracks' grid would predict only where the two grids meet (every 15 s for 3 s on 5 s)
        raise ValueError(f"step_s {step_s!r}: predictions start from the tracks' grid rows, every "
                         f"{grid_s:g} s (track(step_s={grid_s:g})); give a whole multiple of {grid_s:g} s, "
                         f"or track with step_s={step_s!r}")
    tracks = result.tracks
    if plane is None and len(tracks):
        plane = Plane.around(tracks["latitude"].to_numpy(float), tracks["longitude"].to_numpy(float))
    n_h = len(horizons)

    def one(item: tuple) -> pd.DataFrame | None:  # one aircraft's predictions, none without grid rows
        aircraft_id, rows = item
        if str(aircraft_id) not in result.runs:
            raise KeyError(f"aircraft {aircraft_id!r}: no filter history (run track(..., keep_states=True))")
        own, run, epoch = result.runs[str(aircraft_id)]
        rows = rows.loc[on_grid(rows, step_s) & np.isfinite(rows["latitude"].to_numpy(float))]
        if rows.empty:
            return None
        t = (rows["time"] - epoch).dt.total_seconds().to_numpy(float)
        upd = np.flatnonzero(run.accepted)
        which = np.searchsorted(run.t[upd], t + 1e-9, side="right") - 1
        keep = which >= 0
        rows, t, which = rows.loc[keep], t[keep], which[keep]
        if rows.empty:
            return None
        gov = upd[which]
        dt = np.maximum(t - run.t[gov], 0.0)
        order = np.lexsort((dt, gov))  # the kernel continues one coasting chain per governing update
        mean, cov = np.empty((len(t), n_h, NX)), np.empty((len(t), n_h, len(POSITION_PAIRS)))
        args = run.config.kernel_args()
        mean[order], cov[order] = predict_states(args, gov[order], dt[order], run.mu,
                                                 run.x, run.P, horizons, step_s)
        e, n = mean[:, :, 0].ravel(), mean[:, :, 3].ravel()
        c2 = np.empty((len(e), 2, 2))
        c2[:, 0, 0] = cov[:, :, 0].ravel()
        c2[:, 0, 1] = c2[:, 1, 0] = cov[:, :, 1].ravel()
        c2[:, 1, 1] = cov[:, :, 2].ravel()
        lat, lon = own.inverse(e, n)
        east, north = plane.forward(lat, lon)
        # plane vector = M_common @ local = M_common @ inv(M_own) @ own-plane vector, taken at the track's
        # position for all its horizons (over the 30 km of a 120 s prediction the two planes' relative
        # rotation and scale change the variances by about 1e-4 of themselves)
        lat_now, lon_now = rows["latitude"].to_numpy(float), rows["longitude"].to_numpy(float)
        m = np.repeat(plane.local_to_plane(lat_now, lon_now) @ _inv2(own.local_to_plane(lat_now, lon_now)),
                      n_h, axis=0)
        c2 = m @ c2 @ np.swapaxes(m, 1, 2)
        fl, sig = vertical_prediction(run.zv[np.repeat(gov, n_h)], run.Pv[np.repeat(gov, n_h)],
                                      np.repeat(dt, n_h), np.tile(horizons, len(t)),
                                      args["q_fl"], step_s)
        frame = {"aircraft_id": np.repeat(str(aircraft_id), len(e)),
                 "time": rows["time"].array.take(np.repeat(np.arange(len(t)), n_h)),
                 "horizon_s": np.tile(horizons, len(t)), "east_m": east, "north_m": north,
                 "var_east_m2": c2[:, 0, 0], "cov_east_north_m2": c2[:, 0, 1], "var_north_m2": c2[:, 1, 1],
                 "flight_level": fl, "latitude": lat, "longitude": lon}
        if sigma_alt:
            frame["sigma_alt_ft"] = sig
        return pd.DataFrame(frame)

    groups = tracks.groupby("aircraft_id", sort=True, observed=True)
    out = [f for f in map_ordered(one, groups) if f is not None]
    columns = ["aircraft_id", "time", "horizon_s", "east_m", "north_m", "var_east_m2", "cov_east_north_m2",
               "var_north_m2", "flight_level", "latitude", "longitude"]
    columns += ["sigma_alt_ft"] if sigma_alt else []
    if not out:
        return pd.DataFrame({c: pd.Series(dtype=tracks["time"].dtype if c == "time" else
                                          (object if c == "aircraft_id" else float)) for c in columns})
    return pd.concat(out, ignore_index=True)
