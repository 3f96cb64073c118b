"""Where an aircraft is reported: the track samples a loss of separation may be measured on.

The tracker puts out a row at every accepted report (`coasted` False) and on the grid, coasting up to
`--max-coast` after the last report. A coasted position is an extrapolation, not a measurement: on the
real radar recording a loss of 45 s lay wholly after a Mode A target's last plot. So losses are counted
on the grid times that lie between two consecutive accepted reports of the aircraft at most
``max_gap_s`` apart, at positions interpolated linearly between those two reports; a stretch of such
reports is one reported interval (``interval``: a loss run ends where an aircraft's interval does). A
report the tracker rejected (gated as an outlier) is not one; a new track segment's first report is
(the tracker restarts a segment on consistent reports its filter had gated).

The horizontal positions are the reports' own (the radar plot, the ADS-B position), not the filter's
estimates there: the real-time filter lags an aircraft that accelerates or turns (on the real radar hour
a departure's estimates lay up to 150 m behind its plots in the take-off roll, and the minima of losses
with a departure 0.08 NM below the plots'). The level is the tracker's at the report (the vertical filter
holds it across plots without Mode C and on the surface). Linear interpolation between reports 15 s
apart (the default) of an aircraft at 250 kt turning at 3 deg/s strays at most 190 m (0.1 NM) from its
arc. An aircraft reported by several sensors would zigzag between them by their disagreement (a radar
plot 155 NM out lies some 300 m across the beam, the ADS-B reports a second either side 5 m off: one loss
fell apart into five and its minimum came out 0.25 NM short), so where two reports of the aircraft's
finest sensor (the lowest median sigma_major_m) at most ``max_gap_s`` apart bracket a report of a sensor
more than FINER times coarser, that report is not one the loss is measured on: a coarser sensor counts
where the finest is silent.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from msdc.pipeline.conflict.pairs import _require, time_key
from msdc.pipeline.model.arguments import finite_number

MAX_GAP_S = 15.0
FINER = 2.0  # a sensor whose median sigma is more than this times the finest's yields where that reports
REPORT_COLUMNS = ["aircraft_id", "time", "latitude", "longitude", "flight_level"]
_TOLERANCE_NS = 1000  # grid and report times are whole nanoseconds of float seconds: 1 us either side


def report_rows(tracks: pd.DataFrame, measurements: pd.DataFrame | None = None,
                rejected: pd.DataFrame | None = None, max_gap_s: float = MAX_GAP_S) -> pd.DataFrame:
    """The accepted reports of every aircraft: REPORT_COLUMNS sorted by aircraft and time, at the
    tracker's rows at accepted reports (`coasted` False), with the level there and the position of the
    report itself, from `measurements` (`aircraft_id, time, sensor_id, latitude, longitude`, optional
    `sigma_major_m`) less the tracker's `rejected` ones, and without the reports of a coarser sensor that
    the aircraft's finest one brackets within max_gap_s (the module's rule); without measurements, the
    tracker's estimate there."""
    _require(tracks, REPORT_COLUMNS + ["coasted"], "tracks")
    rows = tracks.loc[~tracks["coasted"].to_numpy(bool), REPORT_COLUMNS]
    rows = rows.assign(aircraft_id=rows["aircraft_id"].astype(str))
    if measurements is None:
        return rows.sort_values(["aircraft_id", "time"], kind="stable").reset_index(drop=True)
    max_gap_s = finite_number("max_gap_s", max_gap_s, "s")
    rows, sensor, sigma = _report_positions(rows, measurements, rejected)
    rows = rows.assign(_sensor=sensor, _sigma=sigma).sort_values(["aircraft_id", "time"], kind="stable")
    keep = ~_bracketed(pd.factorize(rows["aircraft_id"])[0], time_key(rows["time"]),
                       rows["_sensor"].to_numpy(np.int64), rows["_sigma"].to_numpy(float), max_gap_s)
    return rows.loc[keep, REPORT_COLUMNS].reset_index(drop=True)


def _bracketed(code: np.ndarray, t: np.ndarray, sensor: np.ndarray, sigma: np.ndarray, max_gap_s: float
               ) -> np.ndarray:
    """Per report (sorted by aircraft, then time; its aircraft's code, its sensor's code, -1 unknown, and
    its sigma_major_m), whether two reports of its aircraft's finest sensor at most max_gap_s apart bracket
    it while its own sensor is more than FINER times coarser (median sigmas of the aircraft's reports)."""
    n = len(code)
    known = (sensor >= 0) & np.isfinite(sigma)
    if not known.any():
        return np.zeros(n, bool)
    median = pd.DataFrame({"code": code[known], "sensor": sensor[known], "sigma": sigma[known]}).groupby(
        ["code", "sensor"], sort=True)["sigma"].median()
    finest = median.groupby(level="code").min()
    at_min = median.to_numpy() == finest.reindex(median.index.get_level_values("code")).to_numpy()
    best = median.index[at_min]
    best = best[~best.get_level_values("code").duplicated()]  # one finest sensor an aircraft
    pair = pd.MultiIndex.from_arrays([code, sensor])
    fine = pair.isin(best)
    coarse = median.reindex(pair).to_numpy(float) > FINER * finest.reindex(code).to_numpy(float)
    idx = np.arange(n)
    prev = np.maximum.accumulate(np.where(fine, idx, -1))
    nxt = np.minimum.accumulate(np.where(fine, idx, n)[::-1])[::-1]
    p, q = np.clip(prev, 0, n - 1), np.clip(nxt, 0, n - 1)
    around = (prev >= 0) & (nxt < n) & (code[p] == code) & (code[q] == code)
    return coarse & ~fine & around & (t[q] - t[p] <= max_gap_s * 1e9 + _TOLERANCE_NS)


def _report_positions(rows: pd.DataFrame, measurements: pd.DataFrame, rejected: pd.DataFrame | None
                      ) -> tuple[pd.DataFrame, np.ndarray, np.ndarray]:
    """rows with latitude and longitude of the measurement of the same aircraft at the same time (to
    _TOLERANCE_NS) that the tracker did not reject (a row without one keeps the tracker's), and per row
    that measurement's sensor code (-1: none) and sigma_major_m (NaN: none, or not given)."""
    ids = pd.Categorical(measurements["aircraft_id"])  # the measurements' own categories: no text per row
    code = ids.codes.astype(np.int64)
    t = time_key(measurements["time"])
    lat, lon = measurements["latitude"].to_numpy(float), measurements["longitude"].to_numpy(float)
    sensor = (pd.factorize(measurements["sensor_id"].astype(str))[0] if "sensor_id" in measurements
              else np.zeros(len(measurements), np.int64))
    sigma = (measurements["sigma_major_m"].to_numpy(float) if "sigma_major_m" in measurements
             else np.full(len(measurements), np.nan))
    usable = (code >= 0) & np.isfinite(lat) & np.isfinite(lon)
    if rejected is not None and len(rejected):
        # the few measurements at a rejected report's time, then exactly by aircraft, time and sensor
        maybe = np.flatnonzero(usable & np.isin(t, time_key(rejected["time"])))
        gated = pd.MultiIndex.from_arrays([rejected["aircraft_id"].astype(str), time_key(rejected["time"]),
                                           rejected["sensor_id"].astype(str)])
        at = pd.MultiIndex.from_arrays([np.asarray(ids.categories.astype(str))[code[maybe]], t[maybe],
                                        measurements["sensor_id"].astype(str).to_numpy()[maybe]])
        usable[maybe[at.isin(gated)]] = False
    meas = pd.DataFrame({"code": code[usable], "t": t[usable], "lat": lat[usable], "lon": lon[usable],
                         "sensor": sensor[usable], "sigma": sigma[usable]})
    row_code = pd.Categorical(rows["aircraft_id"], categories=ids.categories).codes.astype(np.int64)
    left = pd.DataFrame({"code": row_code, "t": time_key(rows["time"]), "row": np.arange(len(rows))})
    found = pd.merge_asof(left.sort_values("t"), meas.sort_values("t"), on="t", by="code",
                          direction="nearest", tolerance=_TOLERANCE_NS)
    hit = found["lat"].notna().to_numpy(bool)
    out = rows.copy()
    at_rows = found["row"].to_numpy()[hit]
    out.iloc[at_rows, out.columns.get_loc("latitude")] = found["lat"].to_numpy()[hit]
    out.iloc[at_rows, out.columns.get_loc("longitude")] = found["lon"].to_numpy()[hit]
    row_sensor, row_sigma = np.full(len(rows), -1, np.int64), np.full(len(rows), np.nan)
    row_sensor[at_rows] = found["sensor"].to_numpy()[hit].astype(np.int64)
    row_sigma[at_rows] = found["sigma"].to_numpy(float)[hit]
    return out, row_sensor, row_sigma


def reported_samples(grid: pd.DataFrame, reports: pd.DataFrame, max_gap_s: float = MAX_GAP_S
                     ) -> pd.DataFrame:
    """The rows of `grid` (one aircraft and time a row) that lie within a reported interval of their
    aircraft (`report_rows`: between two consecutive reports at most max_gap_s apart, or on a lone
    report), with `latitude, longitude, flight_level` interpolated between those reports and `interval`,
    the interval's number (distinct per aircraft and interval). Other columns are kept as they are."""
    max_gap_s = finite_number("max_gap_s", max_gap_s, "s")
    _require(grid, ["aircraft_id", "time"], "grid")
    _require(reports, REPORT_COLUMNS, "reports")
    ids = np.r_[reports["aircraft_id"].astype(str).to_numpy(dtype=object),
                grid["aircraft_id"].astype(str).to_numpy(dtype=object)]
    codes = pd.factorize(ids)[0]
    r_code, r_t = codes[:len(reports)], time_key(reports["time"])
    order = np.lexsort((r_t, r_code))
    at, interval, lat, lon, fl = _interpolate(r_code[order], r_t[order], reports.iloc[order],
                                              codes[len(reports):], time_key(grid["time"]), max_gap_s)
    out = grid.iloc[at].copy()
    out["latitude"], out["longitude"], out["flight_level"] = lat, lon, fl
    out["interval"] = interval
    return out


def reported_intervals(reports_ns: np.ndarray, max_gap_s: float, codes: np.ndarray | None = None
                       ) -> tuple[np.ndarray, np.ndarray]:
    """Per report (sorted by aircraft code, then time, int64 ns; one aircraft without codes), its
    interval number, and per interval the report positions where it starts (the last entry: the number of
    reports). An interval ends where the next report is more than max_gap_s later or of another aircraft."""
    link = np.diff(reports_ns) <= max_gap_s * 1e9 + _TOLERANCE_NS
    if codes is not None:
        link &= codes[1:] == codes[:-1]
    interval = np.r_[0, np.cumsum(~link)]
    starts = np.r_[0, np.flatnonzero(~link) + 1, len(reports_ns)]
    return interval, starts


def positions_at(reports: pd.DataFrame, times_ns: np.ndarray, max_gap_s: float = MAX_GAP_S
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """One aircraft's reports (REPORT_COLUMNS, sorted by time) at times_ns (int64): which times lie in a
    reported interval, their interval numbers and latitude, longitude and flight level there."""
    times_ns = np.asarray(times_ns, np.int64)
    at, interval, lat, lon, fl = _interpolate(np.zeros(len(reports), np.int64), time_key(reports["time"]),
                                              reports, np.zeros(len(times_ns), np.int64), times_ns, max_gap_s)
    inside = np.zeros(len(times_ns), bool)
    inside[at] = True
    return inside, interval, lat, lon, fl


def _interpolate(r_code: np.ndarray, r_t: np.ndarray, reports: pd.DataFrame, q_code: np.ndarray,
                 q_t: np.ndarray, max_gap_s: float):
    """Positions within the reported intervals at the queries (aircraft code, time ns), from the reports
    sorted by (code, time) (`reports` their rows in that order): the positions of the queries inside, their
    interval, latitude, longitude and flight level."""
    if not len(r_t):
        return (np.zeros(0, np.int64),) + (np.zeros(0),) * 4
    interval, starts = reported_intervals(r_t, max_gap_s, r_code)
    # the report at or before each query (one within the tolerance after it counts as at it)
    j = _last_at_or_before(r_code, r_t, q_code, q_t + _TOLERANCE_NS)
    found = j >= 0
    j = np.maximum(j, 0)
    k = interval[j]
    first, last = starts[k], starts[k + 1] - 1
    inside = (found & (r_code[j] == q_code) & (q_t >= r_t[first] - _TOLERANCE_NS)
              & (q_t <= r_t[last] + _TOLERANCE_NS))
    at = np.flatnonzero(inside)
    j, first, last = np.clip(j[at], first[at], np.maximum(last[at] - 1, first[at])), first[at], last[at]
    nxt = np.minimum(j + 1, last)
    span = (r_t[nxt] - r_t[j]).astype(float)
    with np.errstate(invalid="ignore", divide="ignore"):
        w = np.where(span > 0, (q_t[at] - r_t[j]) / span, 0.0)
    w = np.clip(w, 0.0, 1.0)
    lat, lon, fl = (reports[c].to_numpy(float) for c in ("latitude", "longitude", "flight_level"))
    dlon = (lon[nxt] - lon[j] + 180.0) % 360.0 - 180.0  # across the antimeridian the short way
    out_lon = (lon[j] + w * dlon + 180.0) % 360.0 - 180.0
    return (at, k[at], lat[j] + w * (lat[nxt] - lat[j]), out_lon, fl[j] + w * (fl[nxt] - fl[j]))


def _last_at_or_before(r_code: np.ndarray, r_t: np.ndarray, q_code: np.ndarray, q_t: np.ndarray
                       ) -> np.ndarray:
    """Per query, the position of the last report (sorted by code, then time) at or before it in that
    order: of its own aircraft when it has one at or before its time, else of an earlier aircraft; -1 when
    none comes before it."""
    is_query = np.r_[np.zeros(len(r_t), bool), np.ones(len(q_t), bool)]
    order = np.lexsort((is_query, np.r_[r_t, q_t], np.r_[r_code, q_code]))  # reports first on a tie
    count = np.cumsum(~is_query[order])
    out = np.empty(len(q_t), np.int64)
    queries = is_query[order]
    out[order[queries] - len(r_t)] = count[queries] - 1
    return out
