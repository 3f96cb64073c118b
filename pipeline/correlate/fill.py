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

Predictor = Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]]


COVARIANCE = ["cov_ee_m2", "cov_en_m2", "cov_nn_m2"]
_NAT = np.iinfo(np.int64).min


class TrackInputs:
    """The columns the tracker reads, as arrays over the rows of a measurement frame, read once per run
    (each source then takes its rows by position): time in ns (NaT as numpy's), the sensor's sort key in
    track()'s order (categorical: its categories' order; text: alphabetical; missing: last), floats."""

    def __init__(self, frame: pd.DataFrame):
        self.time_ns = frame["time"].dt.as_unit("ns").array.asi8
        sensor = frame["sensor_id"]
        if isinstance(sensor.dtype, pd.CategoricalDtype):
            key = sensor.cat.codes.to_numpy().astype(np.int64)
        else:
            key = pd.factorize(sensor, sort=True)[0].astype(np.int64)
        key[key < 0] = np.iinfo(np.int64).max
        self.sensor_key = key
        names = ["latitude", "longitude", *COVARIANCE, "flight_level"]
        if {"ground_speed_kt", "heading_deg"} <= set(frame.columns):  # (NACv only with a velocity)
            names += [c for c in ("ground_speed_kt", "heading_deg", "nucr_nacv") if c in frame.columns]
        self.values = {n: _floats(frame[n]) for n in names}


def _floats(values: pd.Series) -> np.ndarray:
    """A column as float64 (a view where it is one already; nullable integers with NaN for <NA>)."""
    if values.dtype == np.float64:
        return values.to_numpy()
    return values.to_numpy(float, na_value=np.nan)


def track_predictor(reports: pd.DataFrame, reference: pd.Timestamp, max_coast_s: float) -> Predictor | None:
    """Predicted (latitude, longitude) at times given as seconds after ``reference`` (NaN where no
    prediction exists); None when the reports cannot be tracked (no usable covariance). The numbers of
    ``track(reports, max_coast_s=...)`` then ``predict(state_at(t), ahead)``, without the track table or
    a frame per prediction: the filter runs once, every prediction of a call in one kernel call."""
    return rows_predictor(TrackInputs(reports), np.arange(len(reports)), reference, max_coast_s)


def rows_predictor(inputs: TrackInputs, rows: np.ndarray, reference: pd.Timestamp, max_coast_s: float
                   ) -> Predictor | None:
    """``track_predictor`` of the reports at positions ``rows`` (in time order) of a run's inputs."""
    from msdc.pipeline.track import TrackerConfig, default_modes
    from msdc.pipeline.track.predict import predict_ends
    from msdc.pipeline.track.tracker import filter_columns

    v = inputs.values
    finite = np.ones(len(rows), bool)
    for name in ("latitude", "longitude", *COVARIANCE):
        finite &= np.isfinite(v[name][rows])
    rows = rows[finite]
    time_ns = inputs.time_ns[rows]
    dated = time_ns != _NAT
    if not dated.any():
        return None
    config = TrackerConfig(modes=default_modes(), max_coast_s=max_coast_s)  # track()'s defaults
    epoch = pd.Timestamp(time_ns[dated].min(), unit="ns", tz="UTC").floor("D")  # as track() counts seconds
    t = np.full(len(rows), np.nan)
    t[dated] = pd.to_timedelta(time_ns[dated] - epoch.value, unit="ns").total_seconds().to_numpy()
    order = _track_order(t, inputs.sensor_key[rows])
    rows, t = rows[order], t[order]
    plane, _, run = filter_columns(
        config, t, *(v[c][rows] for c in ("latitude", "longitude", *COVARIANCE, "flight_level")),
        **{c: v[c][rows] for c in ("ground_speed_kt", "heading_deg", "nucr_nacv") if c in v})
    accepted = np.flatnonzero(run.accepted)
    acc_t = run.t[accepted]
    acc_time = epoch + pd.to_timedelta(acc_t, unit="s")  # each update's instant, as state_at gives it

    def at(seconds: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        seconds = np.asarray(seconds, float).reshape(-1)
        lat, lon = np.full(seconds.shape, np.nan), np.full(seconds.shape, np.nan)
        when = reference + pd.to_timedelta(seconds, unit="s")
        k = np.searchsorted(acc_t, (when - epoch).total_seconds().to_numpy(), side="right") - 1
        known = k >= 0  # none before the first report
        ahead = np.full(k.shape, np.inf)
        ahead[known] = (when[known] - acc_time[k[known]]).total_seconds().to_numpy()
        coast = known & (ahead > 1e-9) & ~(ahead > max_coast_s)
        if coast.any():
            xc, _ = predict_ends(run, accepted[k[coast]], ahead[coast])
            lat[coast], lon[coast] = plane.inverse(xc[:, 0], xc[:, 3])
        for i in np.flatnonzero(known & (ahead <= 1e-9)):  # at an update: its posterior, combined
            mu, x = run.mu[accepted[k[i]]], run.x[accepted[k[i]]]
            la, lo = plane.inverse(np.array([mu @ x[:, 0]]), np.array([mu @ x[:, 3]]))
            lat[i], lon[i] = la[0], lo[0]
        return lat, lon

    return at


def _track_order(t: np.ndarray, key: np.ndarray) -> np.ndarray:
    """The order ``track`` filters reports in (its stable sort by time, then sensor; missing times last),
    by two stable argsorts."""
    by_sensor = np.argsort(key, kind="stable")
    return by_sensor[np.argsort(t[by_sensor], kind="stable")]


def fill_predicted(slotted: dict[str, np.ndarray], slot_s: float, predictor: Predictor | None
                   ) -> dict[str, np.ndarray]:
    """The slotted arrays (pipeline.correlate.slots.slot_series) with their filled slots after the first
    non-empty one replaced by the prediction at the slot centre where one exists (new latitude and
    longitude arrays; the input is not changed)."""
    if predictor is None:
        return slotted
    counts = np.asarray(slotted["count"])
    first = int(np.argmax(counts > 0)) if (counts > 0).any() else len(counts)
    todo = np.flatnonzero(np.asarray(slotted["filled"], bool) & (np.arange(len(counts)) > first))
    if not len(todo):
        return slotted
    centre = np.asarray(slotted["time_of_day"], float)[todo] + 0.5 * slot_s
    lat, lon = predictor(centre)
    ok = np.isfinite(lat) & np.isfinite(lon)
    out = dict(slotted)
    for name, values in (("latitude", lat), ("longitude", lon)):
        out[name] = np.array(slotted[name], float)
        out[name][todo[ok]] = values[ok]
    return out
