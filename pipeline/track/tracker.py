"""Fused tracks from a measurement frame: one IMM per aircraft, every sensor's reports in time order.

Input, one row per report (the measurement model's schema):

| column | meaning |
|---|---|
| `time` | tz-aware UTC datetime64 |
| `sensor_id` | str, e.g. "048:25/201", "021:0/107" |
| `sensor_kind` | "radar" or "adsb" |
| `aircraft_id` | str; association is by this identity |
| `latitude`, `longitude` | deg WGS-84 |
| `flight_level` | FL, may be NaN |
| `cov_ee_m2`, `cov_en_m2`, `cov_nn_m2` | horizontal position covariance (m^2), local east/north |
| `ground_speed_kt`, `heading_deg` | optional; only used to start a segment's velocity |
| `nucr_nacv` | optional; NUCr / NACv of ADS-B reports: that velocity's sigma (bound / 2.4477; else 10 m/s) |
| `on_ground` | optional; the report says the aircraft is on the surface (True), airborne (False) or not |

Radar covariances come from `radar_covariance` (range/azimuth sigmas), ADS-B from `nacp_covariance`.

Rows without a finite position or covariance are counted (`invalid`) and skipped.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, field, replace

import numpy as np
import pandas as pd

from msdc.pipeline.model.arguments import finite_number
from msdc.pipeline.model.coasting import MISSED_UPDATE_FACTOR, coasted_time  # noqa: F401 - importable here too
from msdc.pipeline.model.geodesy import M_PER_S_PER_KT
from msdc.pipeline.model.time import utc_frame
from msdc.pipeline.parallel import map_ordered

from .config import TrackerConfig, default_modes
from .covariance import nacv_variance, principal_variances
from .frame import Plane
from .imm import STATUS_STARTED, STATUS_UPDATED
from .plane import SMOOTHERS, Estimates, PlaneRun, estimate, filter_plane

REQUIRED = ("time", "sensor_id", "sensor_kind", "aircraft_id", "latitude", "longitude", "flight_level",
            "cov_ee_m2", "cov_en_m2", "cov_nn_m2")
# the columns filter_reports reads for the horizontal track (the last three optional); `on_ground`, when
# present, holds the flight level on the surface (the vertical output only, which correlate --fill predict
# and quality --reference track do not use)
FILTER_INPUTS = ("time", "sensor_id", "latitude", "longitude", "flight_level", "cov_ee_m2", "cov_en_m2",
                 "cov_nn_m2", "ground_speed_kt", "heading_deg", "nucr_nacv")
# what an aircraft's task reads (filter, counts, gated reports; file and offset name it on failure):
# only these columns are split per aircraft, so that each split copies no column it does not use
TASK_COLUMNS = (*REQUIRED, *FILTER_INPUTS, "on_ground", "file", "offset")
FT_PER_FL = 100.0
MAX_RANGE_M = 3_000_000.0  # reports farther than this from the aircraft's median position are garbage
# smoothed turn rate: least-squares slope of the smoothed track angle over a centred 8 s window of output
# rows; chosen on the simulator's turns (docs/tracker.md, "Turn rate")
SMOOTH_TURN_RATE_WINDOW_S = 8.0


@dataclass
class ImmState:
    """The mode-conditioned IMM posterior of one aircraft at one time, in its plane."""

    aircraft_id: str
    time: pd.Timestamp
    plane: Plane
    config: TrackerConfig
    mu: np.ndarray  # (r,)
    x: np.ndarray  # (r, 6): east_m, ve, ae, north_m, vn, an
    P: np.ndarray  # (r, 6, 6)


@dataclass
class TrackResult:
    """tracks: the estimates (see `track`); sensors: per aircraft and sensor, reports, updates, gated,
    NIS mean; aircraft: per aircraft, segments, span, coasted time; rejected: every gated report."""

    tracks: pd.DataFrame
    sensors: pd.DataFrame
    aircraft: pd.DataFrame
    rejected: pd.DataFrame
    parameters: dict
    final_states: dict[str, ImmState] = field(default_factory=dict)
    runs: dict[str, tuple] = field(default_factory=dict)  # with keep_states: (plane, PlaneRun, epoch)
    epoch: pd.Timestamp | None = None  # the UTC midnight the filter's seconds count from

    def state_at(self, aircraft_id: str, time: pd.Timestamp) -> ImmState:
        """The IMM posterior after the last accepted update at or before time (needs keep_states);
        `predict(state, horizon)` then propagates it (its time is the update's, not `time`)."""
        if aircraft_id not in self.runs:
            if aircraft_id not in self.final_states:
                known = sorted(self.final_states)
                listed = ", ".join(map(repr, known[:5])) + (", ..." if len(known) > 5 else "")
                raise KeyError(f"aircraft {aircraft_id!r}: not tracked in this result "
                               f"({len(known)} aircraft: {listed or 'none'})")
            raise KeyError(f"aircraft {aircraft_id!r}: no filter history (run track(..., keep_states=True))")
        plane, run, epoch = self.runs[aircraft_id]
        t = (utc_timestamp("time", time) - epoch).total_seconds()
        rows = np.flatnonzero(run.accepted & (run.t <= t))
        if not len(rows):
            raise ValueError(f"aircraft {aircraft_id!r}: no update at or before {time}")
        i = rows[-1]
        return ImmState(aircraft_id, epoch + pd.to_timedelta(run.t[i], unit="s"), plane, run.config,
                        run.mu[i].copy(), run.x[i].copy(), run.P[i].copy())


def utc_timestamp(name: str, value) -> pd.Timestamp:
    """value as a UTC Timestamp (an aware time in another zone converted, which is exact); a ValueError
    naming the argument for a naive time, whose zone nobody knows, or one that is not a time."""
    try:
        stamp = pd.Timestamp(value)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} {value!r}: not a time ({exc})") from None
    if stamp is pd.NaT:
        raise ValueError(f"{name} {value!r}: not a time")
    if stamp.tzinfo is None:
        raise ValueError(f"{name} {value!r}: a naive time (no zone); give a tz-aware time, e.g. "
                         f"pd.Timestamp({str(stamp)!r}, tz='UTC') if it is UTC")
    return stamp.tz_convert("UTC")


def _check(measurements: pd.DataFrame) -> pd.DataFrame:
    """The frame with UTC times, after checking its columns; ValueError naming what is wrong."""
    if not isinstance(measurements, pd.DataFrame):
        raise TypeError(f"measurements: expected a pandas DataFrame, not {type(measurements).__name__}")
    missing = [c for c in REQUIRED if c not in measurements.columns]
    if missing:
        raise ValueError(f"measurements: missing column(s) {', '.join(missing)}")
    return utc_frame(measurements, ["time"], "measurements")  # aware times of any zone as UTC


def track(measurements: pd.DataFrame, *, step_s: float = 1.0, max_coast_s: float = 60.0,
          tpm: str | None = None, smooth: bool = False, config: TrackerConfig | None = None,
          turn_rate_dps: float = 3.0, with_ca: bool = False, keep_states: bool = False,
          smoother: str = "rts", epoch: pd.Timestamp | None = None, columns: tuple[str, ...] | None = None,
          summaries: bool = True) -> TrackResult:
    """Track every aircraft: estimates on a regular grid of step_s (aligned to whole multiples of step_s
    since UTC midnight) and at every accepted report, coasted up to max_coast_s after the last update,
    smoothed backwards when smooth. tpm: 'dynamic[:A,B]', 'fixed:P' or 'expm:TAU[,TAU2]' (default:
    the config's; see `parse_tpm`). smoother: "rts" (RTS on the combined estimate) or "imm" (the IMM
    smoother of `imm_smooth_rows`; also smooths the mode probabilities). keep_states keeps every
    aircraft's filter history for `TrackResult.state_at`. epoch: the UTC midnight the filter counts its
    seconds from (default: that of the earliest usable report; `TrackResult.epoch`), so that a subset of
    the aircraft tracked again gives the same numbers. columns: only these columns of the tracks table are
    kept, in each aircraft's task (what a caller reads: less to send back from a cluster's worker and to
    hold). summaries False: the tracks alone, the sensors, aircraft and gated-report tables and the final
    states left empty (for a caller that reads only the tracks, as the evaluation's reference)."""
    measurements = _check(measurements)
    if smoother not in SMOOTHERS:
        raise ValueError(f"smoother {smoother!r}: expected one of {', '.join(SMOOTHERS)}")
    step_s = finite_number("step_s", step_s)
    turn_rate_dps = finite_number("turn_rate_dps", turn_rate_dps, "degrees per second")
    if config is not None and not isinstance(config, TrackerConfig):
        raise TypeError(f"config {config!r:.40}: a TrackerConfig, not {type(config).__name__}")
    # coasting less than one step would end every gap before the next grid time (the CLI's --max-coast rule)
    max_coast_s = finite_number("max_coast_s", max_coast_s, at_least=step_s, at_least_name="step_s")
    if config is None:
        config = TrackerConfig(modes=default_modes(turn_rate_dps, with_ca=with_ca), max_coast_s=max_coast_s)
    else:
        config = TrackerConfig(**{**config.__dict__, "max_coast_s": max_coast_s})
    if tpm is not None:
        config = TrackerConfig(**{**config.__dict__, "tpm": tpm})
    args = config.kernel_args()
    names = [m.name for m in config.modes]

    if epoch is not None:
        epoch = utc_timestamp("epoch", epoch)
    frame, unidentified = _identified(measurements)
    finite = usable_rows(frame)
    invalid = frame.loc[~finite].groupby(["aircraft_id", "sensor_id", "sensor_kind"], observed=True).size()
    frame = frame.loc[finite, list(dict.fromkeys(c for c in TASK_COLUMNS if c in frame.columns))]
    parameters = {**_parameters(config, step_s, smooth, smoother), "unidentified_reports": unidentified}
    empty = TrackResult(_empty_tracks(names), _empty_sensors(invalid), pd.DataFrame(), pd.DataFrame(),
                        parameters)
    if frame.empty:
        return empty
    epoch = frame["time"].min().floor("D") if epoch is None else epoch
    tracks, sensors, aircraft, rejected, finals, runs = [], [], [], [], {}, {}
    def one(item: tuple) -> tuple:  # the filter run travels back (a cluster's worker) only when kept
        out = _track_one(str(item[0]), item[1], epoch, config, args, names, step_s, smooth, smoother, columns,
                         summaries)
        return item[0], (out if keep_states else replace(out, plane=None, run=None))

    outs = map_ordered(one, per_aircraft(frame, epoch), distributable=True, label=aircraft_label)
    for aircraft_id, out in outs:
        tracks.append(out.tracks)
        sensors.append(out.sensors)
        aircraft.append(out.aircraft)
        rejected.append((str(aircraft_id), out.rejected))
        finals[str(aircraft_id)] = out.final
        if keep_states:
            runs[str(aircraft_id)] = (out.plane, out.run, epoch)
    if not summaries:
        return TrackResult(_tracks_table(tracks, epoch), pd.DataFrame(), pd.DataFrame(), pd.DataFrame(),
                           parameters, {}, runs, epoch)
    sensors_df = _with_invalid(pd.concat(sensors, ignore_index=True), invalid)
    aircraft_df = pd.DataFrame(aircraft)
    counts = sensors_df.groupby("aircraft_id", sort=False)[["reports", "invalid", "out_of_range"]].sum()
    aircraft_df["reports"] = aircraft_df["aircraft_id"].map(counts["reports"]).astype(int)
    for c in ("invalid", "out_of_range"):
        aircraft_df.insert(aircraft_df.columns.get_loc("gated") + 1, c,
                           aircraft_df["aircraft_id"].map(counts[c]).astype(int))
    return TrackResult(_tracks_table(tracks, epoch), sensors_df, aircraft_df,
                       _rejected_table(frame, rejected), parameters, finals, runs, epoch)


SENSOR_COUNTS = ("reports", "updates", "gated", "segments_started", "invalid", "out_of_range")


def _identified(measurements: pd.DataFrame) -> tuple[pd.DataFrame, dict[str, int]]:
    """The rows with an aircraft_id, and per sensor the count of those without one (they cannot be
    associated, so they are not tracked; a UserWarning says how many)."""
    missing = measurements["aircraft_id"].isna().to_numpy(bool)
    if not missing.any():
        return measurements, {}
    counts = measurements.loc[missing, "sensor_id"].astype(str).value_counts().sort_index()
    unidentified = {str(k): int(v) for k, v in counts.items()}
    import warnings

    warnings.warn(f"measurements: {int(missing.sum())} report(s) without an aircraft_id not tracked ("
                  + ", ".join(f"{k}: {v}" for k, v in unidentified.items())
                  + "; TrackResult.parameters['unidentified_reports'])", UserWarning, stacklevel=3)
    return measurements.loc[~missing], unidentified


def aircraft_label(item: tuple) -> str:
    """An aircraft's task named for progress and failure messages: its identity and first report's place."""
    aircraft_id, reports = item
    where = f" (from {reports.first_place[0]} offset {reports.first_place[1]})" if reports.first_place else ""
    return f"aircraft {aircraft_id}{where}"


@dataclass
class AircraftReports:
    """One aircraft's usable reports as arrays, in the frame's order (what its task reads and what is
    shipped to a cluster's worker): their rows in the usable frame, seconds since the epoch, sensor and
    kind names, the filter's inputs (``track``'s schema; the optional ones None when absent), the sensors'
    `sensor_rank` where some of the frame's times repeat, and the first report's file and offset."""

    rows: np.ndarray
    t: np.ndarray
    sensors: np.ndarray
    kinds: np.ndarray
    columns: dict[str, np.ndarray]
    said: np.ndarray | None
    rank: np.ndarray | None
    first_place: tuple | None

    def take(self, order: np.ndarray) -> AircraftReports:
        """The reports in ``order`` (positions, or a mask)."""
        return AircraftReports(self.rows[order], self.t[order], self.sensors[order], self.kinds[order],
                               {c: v[order] for c, v in self.columns.items()}, _part(self.said, order),
                               _part(self.rank, order), self.first_place)


def _part(values: np.ndarray | None, which) -> np.ndarray | None:
    """values[which], None for None."""
    return None if values is None else values[which]


def per_aircraft(frame: pd.DataFrame, epoch: pd.Timestamp) -> Iterator[tuple]:
    """(aircraft_id, AircraftReports) per aircraft, in the order of a sorted groupby by aircraft_id, each
    aircraft's reports in the frame's order: the frame's columns converted once, not per aircraft."""
    if frame.empty:
        return
    codes = frame.groupby("aircraft_id", sort=True, observed=True).ngroup().to_numpy(np.int64)
    order = np.argsort(codes, kind="stable")
    bounds = np.flatnonzero(np.diff(codes[order])) + 1
    starts, ends = np.r_[0, bounds], np.r_[bounds, len(order)]
    t = (frame["time"] - epoch).dt.total_seconds().to_numpy(float)[order]
    sensors = frame["sensor_id"].to_numpy(str)[order]
    kinds = frame["sensor_kind"].to_numpy(str)[order]
    names = ["latitude", "longitude", "cov_ee_m2", "cov_en_m2", "cov_nn_m2", "flight_level"]
    if {"ground_speed_kt", "heading_deg"} <= set(frame.columns):
        names += ["ground_speed_kt", "heading_deg"]
    columns = {c: frame[c].to_numpy(float)[order] for c in names}
    if "heading_deg" in columns and "nucr_nacv" in frame.columns:
        columns["nucr_nacv"] = frame["nucr_nacv"].to_numpy(float, na_value=np.nan)[order]
    said = _part(ground_said(frame), order)
    rank = None
    inside = np.ones(max(len(t) - 1, 0), bool)  # the steps between two rows of one aircraft
    inside[bounds - 1] = False
    if not (np.diff(t)[inside] > 0.0).all():  # times repeat (or are out of order) somewhere: ties need it
        rank = sensor_rank(frame["sensor_id"])[order]
    ids = frame["aircraft_id"].to_numpy(object)[order[starts]]
    places = [None] * len(starts)
    if "file" in frame.columns and "offset" in frame.columns:
        first = order[starts]
        places = list(zip(frame["file"].iloc[first].tolist(), frame["offset"].iloc[first].tolist(),
                          strict=True))
    for k, (a, b) in enumerate(zip(starts, ends, strict=True)):
        part = slice(a, b)
        yield ids[k], AircraftReports(order[part], t[part], sensors[part], kinds[part],
                                      {c: v[part] for c, v in columns.items()}, _part(said, part),
                                      _part(rank, part), places[k])


def usable_rows(frame: pd.DataFrame) -> np.ndarray:
    """Rows with a usable position (finite, latitude within +-90 deg) and a finite covariance; a finite
    covariance that is not positive definite is a ValueError naming the first such row (no measurement
    model makes one: it is a sign error or a corrupted column, and the gate would silently reject the row)."""
    lat, lon, ee, en, nn = (frame[c].to_numpy(dtype=float, na_value=np.nan) for c in (
        "latitude", "longitude", "cov_ee_m2", "cov_en_m2", "cov_nn_m2"))
    cov_finite = np.isfinite(ee) & np.isfinite(en) & np.isfinite(nn)
    with np.errstate(invalid="ignore"):
        not_pd = cov_finite & ~((ee > 0.0) & (nn > 0.0) & (ee * nn - en * en > 0.0))
    if not_pd.any():
        i = int(np.flatnonzero(not_pd)[0])
        raise ValueError(f"measurements: {int(not_pd.sum())} row(s) with a covariance that is not positive "
                         f"definite (cov_ee_m2 > 0, cov_nn_m2 > 0 and cov_ee_m2 cov_nn_m2 > cov_en_m2^2 "
                         f"needed), the first at index {frame.index[i]}: cov_ee_m2 {ee[i]:g}, "
                         f"cov_en_m2 {en[i]:g}, cov_nn_m2 {nn[i]:g}")
    with np.errstate(invalid="ignore"):
        return cov_finite & np.isfinite(lon) & (np.abs(lat) <= 90.0)


def _with_invalid(sensors: pd.DataFrame, invalid: pd.Series) -> pd.DataFrame:
    """The per aircraft and sensor table with the unusable rows counted: `invalid`, and in `reports` (so
    that reports = updates + gated + invalid + out_of_range); a sensor with only unusable rows gets a row
    of zeros besides."""
    if not len(invalid):
        return sensors.assign(invalid=0)
    inv = invalid.rename("invalid").reset_index()
    inv["aircraft_id"] = inv["aircraft_id"].astype(str)
    inv["sensor_kind"] = inv["sensor_kind"].astype(str)
    out = sensors.merge(inv, on=["aircraft_id", "sensor_id"], how="outer", suffixes=("", "_invalid"))
    if "sensor_kind_invalid" in out:
        out["sensor_kind"] = out["sensor_kind"].fillna(out.pop("sensor_kind_invalid"))
    for c in SENSOR_COUNTS:
        out[c] = out[c].fillna(0).astype(int)
    out["reports"] = out["reports"] + out["invalid"]
    return out


def _empty_sensors(invalid: pd.Series) -> pd.DataFrame:
    """The sensor table of a run where no row was usable: every row counted as invalid."""
    base = pd.DataFrame({"aircraft_id": pd.Series(dtype=object), "sensor_id": pd.Series(dtype=object),
                         "sensor_kind": pd.Series(dtype=object), "nis_mean": pd.Series(dtype=float),
                         **{c: pd.Series(dtype=int) for c in SENSOR_COUNTS if c != "invalid"}})
    out = _with_invalid(base, invalid)
    return out[["aircraft_id", "sensor_id", "sensor_kind", "reports", "updates", "gated", "segments_started",
                "nis_mean", "out_of_range", "invalid"]]


def _parameters(config: TrackerConfig, step_s: float, smooth: bool, smoother: str) -> dict:
    return {"step_s": step_s, "smooth": smooth, "smoother": smoother, "max_coast_s": config.max_coast_s,
            "tpm": config.tpm,
            "gate_probability": config.gate_probability,
            "modes": [m.__dict__ for m in config.modes]}


def _tracks_table(parts: list[tuple[int, dict]], epoch: pd.Timestamp) -> pd.DataFrame:
    """The aircraft's rows (`_track_table`'s row counts and arrays) joined into ``track``'s table, a column
    at a time and each aircraft's arrays let go once joined (the parts and the whole are not held at once):
    the names repeated and the times made from the epoch once for all, the text and boolean columns typed
    once, not per aircraft."""
    lengths = [n for n, _ in parts]
    arrays = [a for _, a in parts]
    parts.clear()
    columns = {}
    for name in list(arrays[0]):
        pieces = [a.pop(name) for a in arrays]
        if name == "aircraft_id":
            columns[name] = pd.array(np.repeat(np.array(pieces, dtype=object), lengths), dtype="str")
        elif name == "time":
            columns[name] = epoch + pd.to_timedelta(np.concatenate(pieces), unit="s")
        elif name == "on_ground":
            columns[name] = pd.arrays.BooleanArray(np.concatenate([v for v, _ in pieces]),
                                                   np.concatenate([m for _, m in pieces]))
        elif name == "sources":
            columns[name] = pd.array(np.concatenate(pieces), dtype="str")
        else:
            columns[name] = np.concatenate(pieces)
        del pieces
    return pd.DataFrame(columns, copy=False)


def concat_columns(parts: list[dict[str, pd.Series]]) -> pd.DataFrame:
    """pd.concat of the parts' columns (every part has the first's names), a column at a time, each part's
    column dropped (popped from its dict) as soon as it is joined: the parts and the whole are not held at
    once."""
    columns = {}
    for name in list(parts[0]):
        columns[name] = pd.concat([p.pop(name) for p in parts], ignore_index=True)
    return pd.DataFrame(columns, copy=False)


def _empty_tracks(names: list[str]) -> pd.DataFrame:
    cols = ["aircraft_id", "segment", "time", "time_of_day", "latitude", "longitude", "flight_level",
            "vertical_rate_fpm", "speed_kt", "track_deg", "turn_rate_dps", "sigma_major_m",
            "sigma_minor_m", "ellipse_orientation_deg", "sigma_speed_kt"] + [f"mode_{n}" for n in names] + [
            "coasted", "age_s", "sources"]
    out = pd.DataFrame({c: [] for c in cols})
    out["on_ground"] = pd.Series(dtype="boolean")
    return out


def _ground_at(said: np.ndarray | None, accepted: np.ndarray, segment: np.ndarray,
               gov: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per output row, what the last accepted report of its segment (up to the row's governing report)
    that said anything said about the surface: True (on the ground), False (airborne), <NA> (none said),
    as a boolean array's values and mask."""
    if said is None:
        said = np.full(len(accepted), np.nan)
    known = accepted & np.isfinite(said)
    last = np.maximum.accumulate(np.where(known, np.arange(len(said)), -1)) if len(said) else np.zeros(0, int)
    ok = (last >= 0) & (segment[np.maximum(last, 0)] == segment)
    value = np.where(ok, said[np.maximum(last, 0)], np.nan)[gov]
    return value == 1.0, ~np.isfinite(value)


def _inv2(m: np.ndarray) -> np.ndarray:
    """Inverses of (n, 2, 2) matrices in closed form."""
    det = m[:, 0, 0] * m[:, 1, 1] - m[:, 0, 1] * m[:, 1, 0]
    out = np.empty_like(m)
    out[:, 0, 0] = m[:, 1, 1] / det
    out[:, 1, 1] = m[:, 0, 0] / det
    out[:, 0, 1] = -m[:, 0, 1] / det
    out[:, 1, 0] = -m[:, 1, 0] / det
    return out


def _ellipse(cov: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """1-sigma semi-axes and major-axis orientation (deg clockwise from north, 0-180) of (n, 2, 2)
    east/north covariances, in closed form."""
    a, b, c = cov[:, 0, 0], 0.5 * (cov[:, 0, 1] + cov[:, 1, 0]), cov[:, 1, 1]
    major_var, minor_var = principal_variances(cov)
    major, minor = np.sqrt(np.maximum(major_var, 0.0)), np.sqrt(np.maximum(minor_var, 0.0))
    # the major axis angle from east is 0.5 atan2(2b, a - c); as an azimuth from north, 90 minus that
    orientation = (90.0 - 0.5 * np.degrees(np.arctan2(2.0 * b, a - c))) % 180.0
    return major, minor, orientation


def _sources_by_time(times: np.ndarray, sensors: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The distinct times (times sorted) and at each the comma-joined distinct sensors; single-sensor times
    without a Python join."""
    uniq, start, count = np.unique(times, return_index=True, return_counts=True)
    out = sensors[start].astype(object)
    for i in np.flatnonzero(count > 1):
        out[i] = ",".join(sorted(set(sensors[start[i]:start[i] + count[i]])))
    return uniq, out


def track_angle_rate(t: np.ndarray, track_deg: np.ndarray, segment: np.ndarray, window_s: float,
                     centred: bool) -> np.ndarray:
    """Rate of change of the track angle (deg/s, + = right turn) at each row: the least-squares slope of
    the unwrapped angle over the rows of the same segment within [t - W, t] (or [t - W/2, t + W/2] when
    centred); NaN where the window holds fewer than two distinct times. Rows sorted by time."""
    out = np.full(len(t), np.nan)
    for s in np.unique(segment):
        i = np.flatnonzero(segment == s)
        tt = t[i] - t[i[0]]
        psi = np.degrees(np.unwrap(np.radians(track_deg[i])))
        sums = [np.concatenate([[0.0], np.cumsum(v)]) for v in (np.ones(len(i)), tt, psi, tt * tt, tt * psi)]
        back, ahead = (0.5 * window_s, 0.5 * window_s) if centred else (window_s, 0.0)
        lo = np.searchsorted(tt, tt - back, side="left")
        hi = np.searchsorted(tt, tt + ahead, side="right")
        n, st, sp, stt, stp = (c[hi] - c[lo] for c in sums)
        den = n * stt - st * st
        with np.errstate(invalid="ignore", divide="ignore"):
            out[i] = np.where(den > 1e-9 * np.maximum(n * stt, 1.0), (n * stp - st * sp) / den, np.nan)
    return out


def _smoothed_turn_rate(qt, v_loc, segment, mode_weighted_dps, speed) -> np.ndarray:
    """The smoothed track angle's rate over a centred SMOOTH_TURN_RATE_WINDOW_S; the mode-probability-
    weighted turn rate where the window holds one time or the aircraft is too slow (below 1 m/s the track
    angle means nothing)."""
    track = np.degrees(np.arctan2(v_loc[:, 0], v_loc[:, 1]))
    rate = track_angle_rate(qt, track, segment, SMOOTH_TURN_RATE_WINDOW_S, centred=True)
    return np.where(np.isfinite(rate) & (speed > 1.0), rate, mode_weighted_dps)


@dataclass
class FilteredReports:
    """One aircraft's reports as the filter saw them: the rows kept (sorted by time, then sensor), their
    seconds since the epoch, the plane, the filter's run over them, and per sensor the rows out of range."""

    rows: np.ndarray  # the reports' rows in the usable frame
    t: np.ndarray
    plane: Plane
    run: PlaneRun
    far: pd.Series
    sensors: np.ndarray  # the rows' sensor_id
    ground: np.ndarray | None  # the rows' ground_said


def sensor_rank(sensor_id: pd.Series) -> np.ndarray:
    """Per report, its sensor's place in the order reports of one time are filtered in: a categorical's
    category order, else the names' alphabetical order; a missing sensor last (as pandas sorts them)."""
    if isinstance(sensor_id.dtype, pd.CategoricalDtype):
        codes, n = sensor_id.cat.codes.to_numpy(np.int64), len(sensor_id.cat.categories)
    else:
        codes, uniques = pd.factorize(sensor_id, sort=True)
        codes, n = codes.astype(np.int64), len(uniques)
    return np.where(codes < 0, n, codes)


def in_report_order(t: np.ndarray, rank: np.ndarray) -> bool:
    """Whether reports are already in the filter's order (time, then the sensor's rank: `sensor_rank`), as
    a stable sort by both would leave them; False for a time that is NaN (the sort puts those last)."""
    if t.size < 2:
        return bool(np.isfinite(t).all())
    d = np.diff(t)
    if (d > 0.0).all():  # times all increasing: nearly always
        return True
    if not np.isfinite(t).all() or (d < 0.0).any():
        return False
    tie = d == 0.0  # one time from two sensors (two ADS-B ground stations relaying one report)
    return bool((rank[:-1][tie] <= rank[1:][tie]).all())


def filter_reports(reports: AircraftReports, config: TrackerConfig) -> FilteredReports:
    """Run the IMM forward over one aircraft's reports (finite positions and covariances; ``track``'s
    schema, as `per_aircraft` gives them), in the plane around their median."""
    r = reports
    if not (np.diff(r.t) > 0.0).all():  # times all increasing (nearly always): in order, no rank needed
        if not in_report_order(r.t, r.rank):
            r = r.take(np.lexsort((r.rank, r.t)))  # by time, then sensor, stable (NaN times last)
    c = r.columns
    velocity = "heading_deg" in c
    plane, near, run = filter_columns(
        config, r.t, *(c[n] for n in ("latitude", "longitude", "cov_ee_m2", "cov_en_m2", "cov_nn_m2",
                                       "flight_level")),
        ground_speed_kt=c["ground_speed_kt"] if velocity else None,
        heading_deg=c["heading_deg"] if velocity else None, nucr_nacv=c.get("nucr_nacv"), on_ground=r.said)
    if near.all():  # every report within range of the plane (nearly always): nothing to drop or count
        return FilteredReports(r.rows, r.t, plane, run, pd.Series(dtype=np.int64), r.sensors, r.said)
    far = pd.Series(r.sensors[~near]).value_counts()
    return FilteredReports(r.rows[near], r.t[near], plane, run, far, r.sensors[near],
                           None if r.said is None else r.said[near])


def ground_said(reports: pd.DataFrame) -> np.ndarray | None:
    """Per report 1.0 (says on the surface), 0.0 (says airborne) or NaN (says nothing), from the optional
    ``on_ground`` column; None without it."""
    if "on_ground" not in reports.columns:
        return None
    return reports["on_ground"].astype("boolean").astype("Float64").to_numpy(float, na_value=np.nan)


def filter_columns(config: TrackerConfig, t, lat, lon, cov_ee, cov_en, cov_nn, fl, *, ground_speed_kt=None,
                   heading_deg=None, nucr_nacv=None, on_ground=None) -> tuple[Plane, np.ndarray, PlaneRun]:
    """``filter_reports`` on arrays of reports already in its order (time, then sensor): the plane, which
    reports lie within MAX_RANGE_M of it (the filter sees only those), and the filter's run over them.
    The start velocity comes from ground speed and heading where both are given (NUCr / NACv: its sigma);
    on_ground (1 on the surface, 0 airborne, NaN unknown) holds the level on the surface."""
    plane = Plane.around(lat, lon)
    ze, zn = plane.forward(lat, lon)
    near = np.isfinite(ze) & np.isfinite(zn) & (np.hypot(ze, zn) < MAX_RANGE_M)
    t, ze, zn = t[near], ze[near], zn[near]
    lat = lat[near]
    lon = lon[near]
    m = plane.local_to_plane(lat, lon)
    cov = np.empty((len(t), 2, 2))
    cov[:, 0, 0] = cov_ee[near]
    cov[:, 0, 1] = cov[:, 1, 0] = cov_en[near]
    cov[:, 1, 1] = cov_nn[near]
    cov = m @ cov @ np.swapaxes(m, 1, 2)
    ve0 = np.zeros(len(t))
    vn0 = np.zeros(len(t))
    var_v0 = np.full(len(t), np.nan)
    if ground_speed_kt is not None and heading_deg is not None:
        gs = ground_speed_kt[near] * M_PER_S_PER_KT
        hd = np.radians(heading_deg[near])
        ok = np.isfinite(gs) & np.isfinite(hd)
        v = np.stack([gs * np.sin(hd), gs * np.cos(hd)], axis=-1)
        vp = np.einsum("nij,nj->ni", m, v)
        ve0[ok], vn0[ok] = vp[ok, 0], vp[ok, 1]
        var_v0[ok] = config.sigma_reported_velocity_mps ** 2
        if nucr_nacv is not None:  # ADS-B with NUCr / NACv: the velocity's own accuracy
            var_nac = nacv_variance(nucr_nacv[near])
            nac = ok & np.isfinite(var_nac)
            var_v0[nac] = var_nac[nac]
    var_v0[np.isnan(var_v0)] = config.sigma_init_speed_mps ** 2
    run = filter_plane(config, t, ze, zn, cov[:, 0, 0], cov[:, 0, 1], cov[:, 1, 1],
                       fl=fl[near], ve0=ve0, vn0=vn0, var_v0=var_v0,
                       on_ground=None if on_ground is None else on_ground[near])
    return plane, near, run


@dataclass
class AircraftTrack:
    """One aircraft's share of a TrackResult: its estimates, per-sensor counts, summary row, gated reports,
    IMM posterior after its last update, and its plane and filter run (kept with keep_states)."""

    tracks: tuple[int, dict]  # its rows of the tracks table: their count and columns (`_track_table`)
    sensors: pd.DataFrame | None  # None (and the three after it) when only the tracks are asked for
    aircraft: dict | None
    rejected: tuple[np.ndarray, np.ndarray] | None  # the gated reports' rows in the usable frame, their NIS
    final: ImmState | None
    plane: Plane | None
    run: PlaneRun | None


@dataclass
class Updates:
    """The accepted updates of one aircraft's filter run (in time order): their rows, seconds since the
    epoch, segments and sensors."""

    rows: np.ndarray
    t: np.ndarray
    segment: np.ndarray
    sensor: np.ndarray


@dataclass
class SegmentSpans:
    """Per track segment (ids ascending): its first and last accepted update times, and where its output
    ends, max_coast_s after the last update but before the next segment starts."""

    ids: np.ndarray
    first: np.ndarray
    last: np.ndarray
    end: np.ndarray


def _track_one(aircraft_id: str, reports: AircraftReports, epoch: pd.Timestamp, config: TrackerConfig,
               args: dict, names: list[str], step_s: float, smooth: bool, smoother: str = "rts",
               columns: tuple[str, ...] | None = None, summaries: bool = True) -> AircraftTrack:
    """Track one aircraft (``track``'s steps): filter its reports, estimate at its output times, count;
    columns: only these of its tracks table; summaries False: the tracks alone."""
    filtered = filter_reports(reports, config)
    updates = _updates(filtered)
    spans = _segment_spans(updates, config.max_coast_s)
    qt = _output_times(updates, spans, step_s)
    est = estimate(filtered.run, qt, smooth=smooth, smoother=smoother)
    tracks = _track_table(aircraft_id, filtered, updates, qt, est, epoch, args, names, smooth, columns)
    if not summaries:
        return AircraftTrack(tracks, None, None, None, None, filtered.plane, filtered.run)
    return AircraftTrack(
        tracks=tracks,
        sensors=_sensor_table(aircraft_id, reports, filtered),
        aircraft=_aircraft_row(aircraft_id, filtered, updates, spans, epoch),
        rejected=_rejected(filtered),
        final=_final_state(aircraft_id, filtered, updates, epoch, config),
        plane=filtered.plane, run=filtered.run)


def _updates(filtered: FilteredReports) -> Updates:
    """The filter's accepted updates."""
    rows = np.flatnonzero(filtered.run.accepted)
    return Updates(rows, filtered.t[rows], filtered.run.segment[rows], filtered.sensors[rows])


def _segment_spans(updates: Updates, max_coast_s: float) -> SegmentSpans:
    """Each segment's first and last update, and its output end (coasting up to max_coast_s)."""
    ids = np.unique(updates.segment)
    first = np.array([updates.t[updates.segment == s][0] for s in ids])
    last = np.array([updates.t[updates.segment == s][-1] for s in ids])
    end = last + max_coast_s
    end[:-1] = np.minimum(end[:-1], np.nextafter(first[1:], -np.inf))
    return SegmentSpans(ids, first, last, end)


def _output_times(updates: Updates, spans: SegmentSpans, step_s: float) -> np.ndarray:
    """Output times (sorted, distinct): the accepted update times, and the multiples of step_s within each
    segment's span up to its output end."""
    queries = [np.unique(updates.t)]
    for first, end in zip(spans.first, spans.end, strict=True):
        k0 = np.ceil(first / step_s)
        k1 = np.floor(end / step_s)
        if k1 >= k0:
            queries.append(np.arange(k0, k1 + 1) * step_s)
    return np.unique(np.concatenate(queries))


def _track_table(aircraft_id: str, filtered: FilteredReports, updates: Updates, qt: np.ndarray,
                 est: Estimates, epoch: pd.Timestamp, args: dict, names: list[str],
                 smooth: bool, columns: tuple[str, ...] | None = None) -> tuple[int, dict]:
    """One aircraft's rows of ``track``'s table: their count and the columns as arrays (only ``columns``, in
    their order, when given, and only what they need computed):
    the estimates at the output times qt, in local terms. ``aircraft_id`` and ``time`` are made for every
    aircraft at once (`_tracks_table`): here the aircraft's name and its times in seconds."""
    plane, segment, xc = filtered.plane, filtered.run.segment, est.x
    wanted = None if columns is None else set(columns)

    def needs(*names: str) -> bool:
        return wanted is None or not wanted.isdisjoint(names)

    out_lat, out_lon = plane.inverse(xc[:, 0], xc[:, 3])
    motion = needs("speed_kt", "track_deg", "turn_rate_dps", "sigma_speed_kt")
    ellipse = needs("sigma_major_m", "sigma_minor_m", "ellipse_orientation_deg")
    minv = _inv2(plane.local_to_plane(out_lat, out_lon)) if motion or ellipse else None
    out = {"aircraft_id": aircraft_id, "segment": segment[est.row], "time": qt, "time_of_day": qt,
           "latitude": out_lat, "longitude": out_lon, "flight_level": est.zv[:, 0],
           "vertical_rate_fpm": est.zv[:, 1] * FT_PER_FL * 60.0}
    if motion:
        v_loc, a_loc = _local_motion(minv, est)
        speed = np.hypot(v_loc[:, 0], v_loc[:, 1])
        ccw = _ccw_turn_rate(est.mu, args, v_loc, a_loc, speed)
        out.update({
            "speed_kt": speed / M_PER_S_PER_KT,
            "track_deg": np.degrees(np.arctan2(v_loc[:, 0], v_loc[:, 1])) % 360,
            "turn_rate_dps": (_smoothed_turn_rate(qt, v_loc, segment[est.row], -np.degrees(ccw), speed)
                              if smooth else -np.degrees(ccw))})
    if ellipse:
        sigma_major, sigma_minor, orientation = _ellipse(_local_position_covariance(minv, est))
        out.update({"sigma_major_m": sigma_major, "sigma_minor_m": sigma_minor,
                    "ellipse_orientation_deg": orientation})
    if motion:
        out["sigma_speed_kt"] = _speed_sigma_mps(minv, est, v_loc, speed) / M_PER_S_PER_KT
    for j, name in enumerate(names):
        out[f"mode_{name}"] = est.mu[:, j]
    is_update = est.age_s == 0.0
    out["coasted"], out["age_s"] = ~is_update, est.age_s
    if needs("sources"):
        out["sources"] = _update_sources(qt, is_update, updates)
    if needs("on_ground"):
        out["on_ground"] = _ground_at(filtered.ground, filtered.run.accepted, segment, est.row)
    if columns is not None:
        unknown = [c for c in columns if c not in out]
        if unknown:
            raise ValueError(f"columns: {', '.join(map(repr, unknown))} not in the tracks table (its "
                             f"columns: {', '.join(out)})")
        out = {c: out[c] for c in columns}
    return len(qt), out


def _local_motion(minv: np.ndarray, est: Estimates) -> tuple[np.ndarray, np.ndarray]:
    """The estimates' velocity and acceleration (n, 2) turned from the plane's axes into local east/north
    (minv: per estimate, the plane-to-local matrix at its position)."""
    v_loc = np.einsum("nij,nj->ni", minv, est.x[:, [1, 4]])
    a_loc = np.einsum("nij,nj->ni", minv, est.x[:, [2, 5]])
    return v_loc, a_loc


def _speed_sigma_mps(minv: np.ndarray, est: Estimates, v_loc: np.ndarray, speed: np.ndarray) -> np.ndarray:
    """1-sigma of each estimate's speed: its velocity covariance along the velocity (below 1 m/s, where the
    direction is not known, along the covariance's major axis). A segment started on two reports a few
    seconds apart reads its speed from them: this says how little that speed is worth."""
    cov = minv @ est.P[:, [1, 4]][:, :, [1, 4]] @ np.swapaxes(minv, 1, 2)
    moving = speed > 1.0
    u = np.where(moving[:, None], v_loc / np.where(moving, speed, 1.0)[:, None], 0.0)
    along = np.einsum("ni,nij,nj->n", u, cov, u)
    major = np.linalg.eigvalsh(cov)[:, -1] if len(cov) else np.zeros(0)
    return np.sqrt(np.maximum(np.where(moving, along, major), 0.0))


def _local_position_covariance(minv: np.ndarray, est: Estimates) -> np.ndarray:
    """The estimates' position covariance (n, 2, 2) turned from the plane's axes into local east/north."""
    return minv @ est.P[:, [0, 3]][:, :, [0, 3]] @ np.swapaxes(minv, 1, 2)


def _ccw_turn_rate(mu: np.ndarray, args: dict, v_loc: np.ndarray, a_loc: np.ndarray,
                   speed: np.ndarray) -> np.ndarray:
    """Counter-clockwise turn rate (rad/s): the turn modes' rates weighted by their probabilities, plus the
    acceleration across the velocity over the speed (above 1 m/s)."""
    omegas = args["omegas"]
    with np.errstate(invalid="ignore", divide="ignore"):
        return mu @ np.where(args["kinds"] == 1, omegas, 0.0) + np.where(
            speed > 1.0, (v_loc[:, 0] * a_loc[:, 1] - v_loc[:, 1] * a_loc[:, 0]) / speed**2, 0.0)


def _update_sources(qt: np.ndarray, is_update: np.ndarray, updates: Updates) -> np.ndarray:
    """Per output time, the sensors whose updates it holds (comma-joined), "" for a coasted one."""
    times, names = _sources_by_time(updates.t, updates.sensor)
    sources = np.full(len(qt), "", dtype=object)
    wanted = qt[is_update]
    at = np.searchsorted(times, wanted)
    found = at < len(times)
    found[found] = times[at[found]] == wanted[found]
    picked = np.full(len(wanted), np.nan, dtype=object)  # NaN where no update is at that time, as reindex
    picked[found] = names[at[found]]
    sources[is_update] = picked
    return sources


def _sensor_table(aircraft_id: str, reports: AircraftReports, filtered: FilteredReports) -> pd.DataFrame:
    """Per sensor of the aircraft's usable reports: reports, updates, gated, segments started, NIS mean
    and reports out of range."""
    run, far = filtered.run, filtered.far
    status, accepted = run.status, run.accepted
    all_sensors = reports.sensors
    sids, first = np.unique(all_sensors, return_index=True)
    at = np.searchsorted(sids, filtered.sensors)  # each usable report's sensor
    updated = status == STATUS_UPDATED
    n_far = np.array([int(far.get(sid, 0)) for sid in sids], np.int64)

    def per_sensor(mask: np.ndarray) -> np.ndarray:
        return np.bincount(at[mask], minlength=len(sids)).astype(np.int64)

    nis = np.full(len(sids), np.nan)
    for k in range(len(sids)):
        mine = (at == k) & updated
        if mine.any():
            nis[k] = float(run.nis[mine].mean())
    return pd.DataFrame({
        "aircraft_id": pd.array([aircraft_id] * len(sids), dtype="str"), "sensor_id": list(sids),
        "sensor_kind": list(reports.kinds[first]),
        "reports": np.bincount(at, minlength=len(sids)).astype(np.int64) + n_far,
        "updates": per_sensor(accepted),
        "gated": per_sensor(~accepted), "segments_started": per_sensor(status == STATUS_STARTED),
        "nis_mean": nis, "out_of_range": n_far})


def _aircraft_row(aircraft_id: str, filtered: FilteredReports, updates: Updates, spans: SegmentSpans,
                  epoch: pd.Timestamp) -> dict:
    """The aircraft's summary: segments, reports, updates, gated, span, tracked and coasted time."""
    accepted = filtered.run.accepted
    interval_s, coasted_s = coasted_time(updates.t, updates.segment, updates.sensor)
    return {"aircraft_id": aircraft_id, "segments": len(spans.ids), "reports": len(filtered.rows),
            "updates": int(accepted.sum()), "gated": int((~accepted).sum()),
            "start": epoch + pd.to_timedelta(spans.first[0], unit="s"),
            "end": epoch + pd.to_timedelta(spans.end[-1], unit="s"),
            "tracked_s": float((spans.last - spans.first).sum()), "coasted_s": coasted_s,
            "update_interval_s": interval_s}


def _rejected(filtered: FilteredReports) -> tuple[np.ndarray, np.ndarray]:
    """The reports the gate rejected: their rows in the usable frame and their NIS."""
    gated = ~filtered.run.accepted
    return filtered.rows[gated], filtered.run.nis[gated]


def _rejected_table(frame: pd.DataFrame, rejected: list[tuple[str, tuple[np.ndarray, np.ndarray]]]
                    ) -> pd.DataFrame:
    """Every aircraft's gated reports (`_rejected`, with its aircraft_id), as one table from the frame."""
    rows = np.concatenate([r for _, (r, _) in rejected]) if rejected else np.zeros(0, np.int64)
    ids = [aircraft_id for aircraft_id, (r, _) in rejected for _ in range(len(r))]
    return pd.DataFrame({"aircraft_id": pd.array(ids, dtype="str"),
                         **{c: frame[c].array.take(rows) for c in ("time", "sensor_id", "latitude",
                                                                    "longitude")},
                         "nis": np.concatenate([n for _, (_, n) in rejected]) if rejected else np.zeros(0)})


def _final_state(aircraft_id: str, filtered: FilteredReports, updates: Updates, epoch: pd.Timestamp,
                 config: TrackerConfig) -> ImmState:
    """The IMM posterior after the last accepted update."""
    run, last = filtered.run, updates.rows[-1]
    return ImmState(aircraft_id, epoch + pd.to_timedelta(filtered.t[last], unit="s"), filtered.plane, config,
                    run.mu[last].copy(), run.x[last].copy(), run.P[last].copy())
