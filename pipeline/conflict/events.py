"""Losses of separation in tracked data, alert events from PC time series, and how well the alerts did.

Schemas (times are pandas datetimes, UTC; a pair is always written with aircraft_a < aircraft_b):

- tracks: `aircraft_id, time, latitude, longitude, flight_level`, one row per aircraft and time of a
  common grid: the grid rows of the tracker's output (`step_s=` or `grid_rows` selects them; a frame
  not on one grid is refused, `pipeline.conflict.grid`).
- losses: `aircraft_a, aircraft_b, start, end, duration_s, began_inside, min_horizontal_nm, time_of_min,
  vertical_at_min_ft, min_vertical_ft`, one row per uninterrupted run of grid times in loss (start and
  end are the first and last such times; began_inside: the pair had no sample one step before the start,
  so it entered the analysis already inside the minimum and no alert could have warned of it).
- pc: `time, aircraft_a, aircraft_b, horizon_s, pc`, PC computed at `time` for `time + horizon_s`;
  pairs and times absent from it count as PC = 0.
- Every time is a time-zone-aware datetime (converted to UTC; naive ones, strings or numbers are refused).
- alerts: `aircraft_a, aircraft_b, horizon_s, start, end, peak_pc, time_of_peak`, one row per run of
  consecutive grid times with PC above the threshold.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from msdc.pipeline.conflict.geometry import (
    FT_PER_FL,
    VERTICAL_TOLERANCE_FT,
    horizontal_distance_nm,
    vertical_limit_ft,
)
from msdc.pipeline.conflict.grid import grid_rows, grid_step_s
from msdc.pipeline.conflict.pairs import _require, pairs_per_step, time_key
from msdc.pipeline.model.arguments import finite_number
from msdc.pipeline.model.time import utc_frame

LOSS_COLUMNS = ["aircraft_a", "aircraft_b", "start", "end", "duration_s", "began_inside", "min_horizontal_nm",
                "time_of_min", "vertical_at_min_ft", "min_vertical_ft"]
ALERT_COLUMNS = ["aircraft_a", "aircraft_b", "horizon_s", "start", "end", "peak_pc", "time_of_peak"]
WARNING_COLUMNS = ["aircraft_a", "aircraft_b", "loss_start", "horizon_s", "alert_start", "warning_s"]


def separation(tracks: pd.DataFrame, radius_nm: float = 5.0, vertical_ft: float = 1000.0) -> pd.DataFrame:
    """Horizontal and vertical distance of every pair within radius_nm and vertical_ft at each time:
    `time, aircraft_a, aircraft_b, horizontal_nm, vertical_ft`."""
    _require(tracks, ["aircraft_id", "time", "latitude", "longitude", "flight_level"], "tracks")
    tracks = utc_frame(tracks, ["time"], "tracks")
    pairs = pairs_per_step(tracks, radius_nm, vertical_ft)
    pos = tracks.set_index(["time", "aircraft_id"])[["latitude", "longitude", "flight_level"]]
    if pos.index.duplicated().any():
        t, a = pos.index[pos.index.duplicated()][0]
        raise ValueError(f"tracks: aircraft {a!r} has more than one row at {t}")
    a = pos.reindex(pd.MultiIndex.from_arrays([pairs["time"], pairs["aircraft_a"]])).to_numpy(float)
    b = pos.reindex(pd.MultiIndex.from_arrays([pairs["time"], pairs["aircraft_b"]])).to_numpy(float)
    out = pairs.copy()
    out["horizontal_nm"] = horizontal_distance_nm(a[:, 0], a[:, 1], b[:, 0], b[:, 1])
    out["vertical_ft"] = np.abs(a[:, 2] - b[:, 2]) * FT_PER_FL
    return out


LOSS_PAIRS = ("all", "airborne", "surface")


def losses_of_separation(tracks: pd.DataFrame, radius_nm: float = 5.0, vertical_ft: float = 1000.0,
                         vertical_tolerance_ft: float = VERTICAL_TOLERANCE_FT, *, pairs: str = "all",
                         step_s: float | None = None) -> pd.DataFrame:
    """Every loss of separation: horizontal distance below radius_nm and vertical below vertical_ft less
    vertical_tolerance_ft (the level quantum: tracked levels 1000 ft apart wobble a few feet) at the same
    grid time. A run ends at the first grid time either aircraft is out of loss or absent, or where the
    tracks' `interval` column (`pipeline.conflict.reported`: an aircraft's reported stretch) changes
    when they have one. pairs: "all"
    samples, "airborne" (neither aircraft on the surface by the tracks' boolean `on_surface`) or "surface"
    (one or both on it); a run also ends where its samples stop being of that kind. step_s: the grid (the
    rows at whole multiples of it since UTC midnight are used, e.g. the grid rows of `track()` output);
    None: every row, which must then lie on one common grid (ValueError otherwise)."""
    return losses_by_pairs(tracks, radius_nm, vertical_ft, vertical_tolerance_ft, kinds=(pairs,),
                           step_s=step_s)[pairs]


def losses_by_pairs(tracks: pd.DataFrame, radius_nm: float = 5.0, vertical_ft: float = 1000.0,
                    vertical_tolerance_ft: float = VERTICAL_TOLERANCE_FT, *,
                    kinds: tuple[str, ...] = ("airborne", "surface"), step_s: float | None = None
                    ) -> dict[str, pd.DataFrame]:
    """``losses_of_separation`` for each kind of pairs in ``kinds`` (LOSS_PAIRS), from one pair search."""
    finite_number("radius_nm", radius_nm, "NM")
    finite_number("vertical_ft", vertical_ft, "ft")
    for kind in kinds:
        if kind not in LOSS_PAIRS:
            raise ValueError(f"pairs {kind!r}: expected one of {', '.join(LOSS_PAIRS)}")
    limit_ft = vertical_limit_ft(vertical_ft, vertical_tolerance_ft)
    _require(tracks, ["aircraft_id", "time"], "tracks")
    tracks = utc_frame(tracks, ["time"], "tracks")
    if step_s is None:
        step_s = grid_step_s(tracks)
    else:
        tracks = grid_rows(tracks, step_s)
    sep = separation(tracks, radius_nm, vertical_ft)
    sep = sep[(sep["horizontal_nm"] < radius_nm) & (sep["vertical_ft"] < limit_ft)]
    surface = None
    if set(kinds) - {"all"}:
        from msdc.pipeline.conflict.surface import surface_pairs

        _require(tracks, ["on_surface"], "tracks")
        surface = surface_pairs(sep, tracks)
    picks = {"all": slice(None), "airborne": ~surface if surface is not None else None, "surface": surface}
    if "interval" in tracks.columns:  # a run ends where either aircraft's reported stretch does
        keys = pd.MultiIndex.from_arrays([time_key(tracks["time"]), tracks["aircraft_id"]])
        interval = pd.Series(tracks["interval"].to_numpy(), index=keys)
        for side in ("a", "b"):
            at = pd.MultiIndex.from_arrays([time_key(sep["time"]), sep[f"aircraft_{side}"]])
            sep[f"interval_{side}"] = interval.reindex(at).to_numpy()
    present = {kind: _present(tracks, kind) for kind in kinds}
    return {kind: _loss_runs(sep[picks[kind]], tracks, float(step_s), present[kind]) for kind in kinds}


def _present(tracks: pd.DataFrame, kind: str) -> pd.MultiIndex:
    """(time ns, aircraft) of the samples a pair of this kind is counted on: every sample, or for
    "airborne" those not on the surface."""
    rows = tracks if kind != "airborne" else tracks[~tracks["on_surface"].to_numpy(bool)]
    return pd.MultiIndex.from_arrays([time_key(rows["time"]), rows["aircraft_id"]])


def _loss_runs(sep: pd.DataFrame, tracks: pd.DataFrame, step_s: float, present: pd.MultiIndex
               ) -> pd.DataFrame:
    """The runs of consecutive grid times (step_s apart) of the separation samples in loss, one row a run;
    began_inside where either aircraft has no sample in `present` one step before the run's start."""
    if sep.empty:
        return _empty(LOSS_COLUMNS, tracks["time"].dtype, tracks["aircraft_id"].dtype)
    sep = sep.sort_values(["aircraft_a", "aircraft_b", "time"], kind="stable").reset_index(drop=True)
    ns = time_key(sep["time"])
    extra = [c for c in ("interval_a", "interval_b") if c in sep.columns]
    sep["run"] = _runs(sep, np.round((ns - ns.min()) / (step_s * 1e9)), 1, extra=extra)
    at_min = sep.loc[sep.groupby("run")["horizontal_nm"].idxmin()].set_index("run")
    runs = sep.groupby("run").agg(aircraft_a=("aircraft_a", "first"), aircraft_b=("aircraft_b", "first"),
                                  start=("time", "min"), end=("time", "max"),
                                  min_vertical_ft=("vertical_ft", "min"))
    runs["duration_s"] = (runs["end"] - runs["start"]).dt.total_seconds()
    before = time_key(runs["start"]) - int(round(step_s * 1e9))
    runs["began_inside"] = ~(pd.MultiIndex.from_arrays([before, runs["aircraft_a"]]).isin(present)
                             & pd.MultiIndex.from_arrays([before, runs["aircraft_b"]]).isin(present))
    runs["min_horizontal_nm"] = at_min["horizontal_nm"]
    runs["time_of_min"] = at_min["time"]
    runs["vertical_at_min_ft"] = at_min["vertical_ft"]
    return runs[LOSS_COLUMNS].sort_values(["start", "aircraft_a", "aircraft_b"]).reset_index(drop=True)


def alert_events(pc: pd.DataFrame, threshold: float = 0.2, step_s: float | None = None) -> pd.DataFrame:
    """Alert events: runs of PC above the threshold per pair and horizon. Samples more than step_s
    apart belong to different events (default: per pair and horizon, the smallest step between its own
    samples; give the step the PC was computed at when a pair's samples may all be gaps apart)."""
    _require(pc, ["time", "aircraft_a", "aircraft_b", "horizon_s", "pc"], "pc")
    if not 0.0 <= threshold < 1.0:
        raise ValueError(f"threshold: a probability in [0, 1) is needed, got {threshold!r}")
    if step_s is not None:
        finite_number("step_s", step_s)
    pc = _ordered(utc_frame(pc, ["time"], "pc"))
    rows = pc.sort_values(["aircraft_a", "aircraft_b", "horizon_s", "time"], kind="stable")
    rows = rows.reset_index(drop=True)
    is_above = rows["pc"].to_numpy() > threshold
    if not is_above.any():
        return _empty(ALERT_COLUMNS, pc["time"].dtype, pc["aircraft_a"].dtype)
    seconds = (rows["time"] - rows["time"].min()).dt.total_seconds().to_numpy()
    group = _runs(rows, np.zeros(len(rows)), 0.0, extra="horizon_s")  # pair and horizon number per row
    if step_s is None:  # each pair and horizon's own smallest step (a lone sample: any)
        step = np.r_[np.nan, np.where(group[1:] == group[:-1], np.diff(seconds), np.nan)]
        max_step = pd.Series(step).groupby(group).transform("min").to_numpy()
    else:
        max_step = np.full(len(rows), float(step_s))
    # a run breaks at a new pair or horizon, a time gap above the step, or a sample at or below threshold
    rows["run"] = _runs(rows, seconds, max_step * (1 + 1e-9), extra="horizon_s", breaks=~is_above)
    above = rows[is_above]
    peak = above.loc[above.groupby("run")["pc"].idxmax()].set_index("run")
    events = above.groupby("run").agg(aircraft_a=("aircraft_a", "first"), aircraft_b=("aircraft_b", "first"),
                                      horizon_s=("horizon_s", "first"), start=("time", "min"),
                                      end=("time", "max"))
    events["peak_pc"] = peak["pc"]
    events["time_of_peak"] = peak["time"]
    return events[ALERT_COLUMNS].sort_values(["start", "aircraft_a", "aircraft_b", "horizon_s"]).reset_index(
        drop=True)


def classify_alerts(alerts: pd.DataFrame, losses: pd.DataFrame) -> pd.DataFrame:
    """alerts with `loss_start` (the earliest loss of the pair during the alert or within its horizon
    after the alert ended, NaT if none) and `false_alert` (no such loss)."""
    _require(alerts, ALERT_COLUMNS, "alerts")
    _require(losses, ["aircraft_a", "aircraft_b", "start", "end"], "losses")
    alerts = utc_frame(alerts, ["start", "end"], "alerts")
    losses = utc_frame(losses, ["start", "end"], "losses")
    matched = _matches(_ordered(alerts).reset_index(drop=True), _ordered(losses))
    first = matched.groupby("alert")["loss_start"].min()
    out = _ordered(alerts).reset_index(drop=True)  # a classified table classified again: its columns replaced
    out["loss_start"] = first.reindex(out.index)
    out["false_alert"] = out["loss_start"].isna()
    return out


def warning_times(losses: pd.DataFrame, alerts: pd.DataFrame, horizons_s=None) -> pd.DataFrame:
    """For each loss and horizon, the earliest alert of the pair at that horizon that was on during the
    loss or within the horizon before it, and the warning it gave: loss start - alert start in seconds
    (negative: the alert came after the loss began; NaN: no alert, a missed loss)."""
    _require(losses, ["aircraft_a", "aircraft_b", "start", "end"], "losses")
    _require(alerts, ALERT_COLUMNS, "alerts")
    alerts = utc_frame(alerts, ["start", "end"], "alerts")
    losses = utc_frame(losses, ["start", "end"], "losses")
    horizons = sorted(set(alerts["horizon_s"]) if horizons_s is None else set(horizons_s))
    losses = _ordered(losses).reset_index(drop=True)
    grid = losses[["aircraft_a", "aircraft_b", "start"]].rename(columns={"start": "loss_start"})
    grid = grid.merge(pd.DataFrame({"horizon_s": horizons}), how="cross")
    matched = _matches(_ordered(alerts).reset_index(drop=True), losses)
    first = matched.groupby(["aircraft_a", "aircraft_b", "loss_start", "horizon_s"], as_index=False)[
        "alert_start"].min()
    out = grid.merge(first, on=["aircraft_a", "aircraft_b", "loss_start", "horizon_s"], how="left")
    if out.empty:
        out["alert_start"] = pd.Series(dtype=losses["start"].dtype)
    out["warning_s"] = (out["loss_start"] - out["alert_start"]).dt.total_seconds()
    order = ["loss_start", "aircraft_a", "aircraft_b", "horizon_s"]
    return out[WARNING_COLUMNS].sort_values(order).reset_index(drop=True)


# --- helpers -------------------------------------------------------------------------------------


def _matches(alerts: pd.DataFrame, losses: pd.DataFrame) -> pd.DataFrame:
    """Alert-loss rows of the same aircraft pair where the loss overlaps [alert start, end + horizon]
    (the alerts' own columns only: a classified table's loss_start is not the one matched here)."""
    both = alerts[ALERT_COLUMNS].reset_index(names="alert").merge(
        losses[["aircraft_a", "aircraft_b", "start", "end"]].rename(columns={"start": "loss_start",
                                                                            "end": "loss_end"}),
        on=["aircraft_a", "aircraft_b"])
    reach = both["end"] + pd.to_timedelta(both["horizon_s"], unit="s")
    keep = (both["loss_start"] <= reach) & (both["loss_end"] >= both["start"])
    return both[keep].rename(columns={"start": "alert_start"})


def _runs(frame: pd.DataFrame, position, max_step, extra: str | list[str] | None = None,
          breaks=None) -> np.ndarray:
    """Run number per row of a frame sorted by pair (and `extra`) then time: a run breaks where the pair
    or an `extra` column changes, `position` advances by more than max_step (a number, or one per row), or
    after a row flagged in `breaks`."""
    keys = ["aircraft_a", "aircraft_b"] + ([extra] if isinstance(extra, str) else list(extra or []))
    new_key = np.zeros(len(frame), dtype=bool)
    for k in keys:
        v = frame[k].to_numpy()
        new_key[1:] |= v[1:] != v[:-1]
    position = np.asarray(position, dtype=float)
    max_step = np.asarray(max_step, dtype=float)  # one for all rows, or each row's from the previous
    new = np.r_[True, new_key[1:] | (np.diff(position) > (max_step[1:] if max_step.ndim else max_step))]
    if breaks is not None:
        new[1:] |= np.asarray(breaks)[:-1]
    return np.cumsum(new) - 1


def _ordered(frame: pd.DataFrame) -> pd.DataFrame:
    """The frame with each pair written as aircraft_a < aircraft_b."""
    a, b = frame["aircraft_a"].to_numpy(), frame["aircraft_b"].to_numpy()
    swap = b < a
    if not swap.any():
        return frame
    out = frame.copy()
    out.loc[swap, "aircraft_a"], out.loc[swap, "aircraft_b"] = b[swap], a[swap]
    return out


def _empty(columns: list[str], time_dtype, id_dtype) -> pd.DataFrame:
    dtypes = {"aircraft_a": id_dtype, "aircraft_b": id_dtype, "start": time_dtype, "end": time_dtype,
              "time_of_min": time_dtype, "time_of_peak": time_dtype}
    dtypes["began_inside"] = dtypes["false_alert"] = bool
    return pd.DataFrame({c: pd.Series(dtype=dtypes.get(c, float)) for c in columns})
