"""The common time grid the loss and alert runs are counted on.

`track()` puts out a row at every accepted report time as well as at the grid of `step_s` (whole
multiples of step_s since UTC midnight): a run of grid times in loss would end at every report row one
aircraft has and the other has not. `grid_rows` keeps the grid rows; `grid_step_s` refuses a frame whose
times are not one common grid, with a message saying how to select it.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from msdc.pipeline.model.arguments import finite_number

_TOLERANCE_S = 1e-6  # the tracker's times are whole nanoseconds of a float time of day


def on_grid(tracks: pd.DataFrame, step_s: float) -> np.ndarray:
    """True for the rows at a whole multiple of step_s since UTC midnight (to a millionth of a step): by
    the tracker's `time_of_day` when the frame has it, else by `time` from midnight of its earliest day."""
    finite_number("step_s", step_s)
    if "time_of_day" in tracks.columns:
        seconds = tracks["time_of_day"].to_numpy(float)
    else:
        times = tracks["time"]
        if not len(times):
            return np.zeros(0, dtype=bool)
        seconds = ((times - times.min().floor("D")).dt.total_seconds()).to_numpy(float)
    turns = seconds / float(step_s)
    return np.abs(turns - np.round(turns)) < 1e-6


def grid_rows(tracks: pd.DataFrame, step_s: float) -> pd.DataFrame:
    """The rows of a track frame on the grid of step_s (`on_grid`), e.g. the grid rows of
    `track(meas, step_s=5).tracks` with step_s=5."""
    return tracks[on_grid(tracks, step_s)]


def grid_step_s(tracks: pd.DataFrame, name: str = "tracks") -> float:
    """The step of the frame's common time grid: the smallest step between its times. ValueError when
    the rows are not on one grid (each aircraft's steps whole multiples of it, most of them equal to it,
    and every aircraft with two rows or more one step apart somewhere): the off-grid report rows of
    `track()` output, or aircraft at different steps."""
    if len(tracks) < 2:
        return 1.0
    frame = pd.DataFrame({"id": tracks["aircraft_id"].to_numpy(), "t": _nanoseconds(tracks["time"])})
    frame = frame.sort_values(["id", "t"], kind="stable")
    ids, t = frame["id"].to_numpy(), frame["t"].to_numpy()
    gaps = np.diff(np.unique(t))
    if not len(gaps):
        return 1.0
    step = int(gaps.min())
    same = ids[1:] == ids[:-1]
    steps = np.diff(t)[same]
    if not len(steps):
        return step / 1e9
    off = np.abs(steps / step - np.round(steps / step)) * step > _TOLERANCE_S * 1e9
    at_step = np.abs(steps - step) <= _TOLERANCE_S * 1e9
    min_step = pd.Series(steps).groupby(ids[1:][same]).min()
    lonely = np.abs(min_step.to_numpy() - step) > _TOLERANCE_S * 1e9
    if off.any() or at_step.mean() < 0.5 or lonely.any():
        why = (f"{int(off.sum())} of {len(steps)} steps between an aircraft's rows are not whole multiples "
               f"of the smallest step, {step / 1e9:g} s" if off.any() else
               f"only {int(at_step.sum())} of {len(steps)} steps between an aircraft's rows equal the "
               f"smallest step, {step / 1e9:g} s" if at_step.mean() < 0.5 else
               f"aircraft {min_step.index[np.flatnonzero(lonely)[0]]!r} is never {step / 1e9:g} s (the "
               "smallest step) from its next row")
        raise ValueError(f"{name}: the rows are not on one common time grid ({why}); a loss run would end "
                         "at every row one aircraft has and the other has not. track() output has a row at "
                         "every report time as well as the grid: pass step_s (the tracker's step) or "
                         "select the grid rows with pipeline.conflict.grid_rows(tracks, step_s)")
    return step / 1e9


def _nanoseconds(times: pd.Series) -> np.ndarray:
    array = times.array
    return array.as_unit("ns").asi8 if hasattr(array, "asi8") else np.asarray(times)
