"""Filling empty slots by the tracker's prediction (``--fill predict``) instead of the previous slot.

For one sensor's reports of one aircraft, ``track_predictor`` runs the IMM tracker forward over them
(that sensor alone, causal: an estimate uses only reports at or before its time) and returns a function
giving the predicted position at any instant: the IMM prediction from the last update at or before it,
up to ``max_coast_s`` after that update. An empty slot then takes the prediction at its centre
(start + (k + 1/2) D). Slots before the sensor's first report in the window keep the thesis rule (the
first non-empty slot), as no prediction exists before a first report.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pandas as pd

FILLS = ("hold", "predict")

Predictor = Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]]


def track_predictor(reports: pd.DataFrame, reference: pd.Timestamp, max_coast_s: float) -> Predictor | None:
    """Predicted (latitude, longitude) at times given as seconds after ``reference`` (NaN where no
    prediction exists); None when the reports cannot be tracked (no usable covariance)."""
    from pipeline.track import predict, track

    rows = reports.assign(aircraft_id="A").dropna(subset=["cov_ee_m2", "cov_en_m2", "cov_nn_m2"])
    if rows.empty:
        return None
    result = track(rows, max_coast_s=max_coast_s, keep_states=True)
    if result.tracks.empty:
        return None

    def at(seconds: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        seconds = np.asarray(seconds, float)
        lat, lon = np.full(seconds.shape, np.nan), np.full(seconds.shape, np.nan)
        for i, s in enumerate(seconds):
            when = reference + pd.to_timedelta(s, unit="s")
            try:
                state = result.state_at("A", when)
            except ValueError:  # before the first report
                continue
            ahead = (when - state.time).total_seconds()
            if ahead > max_coast_s:
                continue
            if ahead <= 1e-9:
                la, lo = state.plane.inverse(np.array([state.mu @ state.x[:, 0]]),
                                             np.array([state.mu @ state.x[:, 3]]))
                lat[i], lon[i] = la[0], lo[0]
                continue
            p = predict(state, ahead, step_s=min(1.0, ahead))
            lat[i], lon[i] = p["latitude"].iloc[-1], p["longitude"].iloc[-1]
        return lat, lon

    return at


def fill_predicted(slotted: pd.DataFrame, slot_s: float, predictor: Predictor | None) -> pd.DataFrame:
    """The slotted frame (pipeline.correlate.slots.SLOTTED_COLUMNS) with its filled slots after the first
    non-empty one replaced by the prediction at the slot centre where one exists."""
    if predictor is None:
        return slotted
    counts = slotted["count"].to_numpy()
    first = int(np.argmax(counts > 0)) if (counts > 0).any() else len(counts)
    todo = np.flatnonzero(slotted["filled"].to_numpy(bool) & (np.arange(len(slotted)) > first))
    if not len(todo):
        return slotted
    centre = slotted["time_of_day"].to_numpy(float)[todo] + 0.5 * slot_s
    lat, lon = predictor(centre)
    ok = np.isfinite(lat) & np.isfinite(lon)
    out = slotted.copy()
    out.loc[out.index[todo[ok]], "latitude"] = lat[ok]
    out.loc[out.index[todo[ok]], "longitude"] = lon[ok]
    return out
