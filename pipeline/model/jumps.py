"""ADS-B position jumps: reports inconsistent with their neighbours in time (implied speed, robust local fit).

Per aircraft (``aircraft_id``; unidentified rows are never judged), reports are sorted by
time and split into segments at gaps longer than ``SEGMENT_GAP_S``. A report is a jump when, against the
reports currently accepted around it (itself excluded):

* speed test: the implied speed to BOTH the previous and the next accepted report exceeds ``max_speed_kt``
  (distance > max speed * dt + ``SPEED_SLACK_M``); at a segment end, to both of the two nearest reports on
  the one side it has; or
* fit test: its distance from a robust local fit (Theil-Sen line of latitude and of longitude against time
  over the ``robust_window - 1`` nearest accepted reports) exceeds ``robust_threshold_m``, plus an allowance
  ``TURN_ACCEL_MS2 * tau^2 / 2`` for the fit's curvature error when the neighbours are far away in time
  (tau^2 = dt_before * dt_after between neighbours, dt * (dt + span) when they are all on one side).

The search is iterative: each pass rejects only the worst offender within +-robust_window/2 reports of its
segment (segments never hold each other back, so they are searched in batches of whole segments), then
re-fits without it, and reinstates rejected reports that agree with the final accepted track, so one
jump never condemns its good neighbours and runs of 2-3 consecutive jumps are peeled off one by one.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
from numba import njit

from msdc.pipeline.model.geodesy import M_PER_S_PER_KT, distance_m, wrap180
from msdc.pipeline.model.time import midnight, seconds_since, with_clock

SPEED_SLACK_M = 300.0  # allowance added to max speed * dt: position noise (NACp 6) and time quantisation
TURN_ACCEL_MS2 = 15.0  # lateral acceleration bound (3.5 deg/s at 480 kt) for the fit's curvature allowance
SEGMENT_GAP_S = 120.0  # neighbours are never taken across a longer gap
MIN_FIT_NEIGHBOURS = 4  # fewer accepted neighbours: the fit test is not applied (speed test only)
_MAX_PASSES = 40
JUMP_BATCH_REPORTS = 250_000  # reports searched at once (whole segments): the search's memory follows it

JUMP_COLUMNS = ["row", "callsign", "address", "sac", "sic", "time_of_day", "timestamp", "latitude",
                "longitude", "fit_latitude", "fit_longitude", "jump_size_m"]


@njit(cache=True)
def _median_sorted(values: np.ndarray, k: int) -> float:
    """Median of the first k values (sorted in place, no allocation); NaN when k is 0. Mean of the two
    middle values when k is even, as numpy's median."""
    if k == 0:
        return np.nan
    for a in range(1, k):
        x = values[a]
        b = a - 1
        while b >= 0 and values[b] > x:
            values[b + 1] = values[b]
            b -= 1
        values[b + 1] = x
    h = k // 2
    low = values[h] if k % 2 == 1 else values[h - 1]
    return (low + values[h]) / 2.0


@njit(cache=True)
def _theil_sen(t, lat, lon, idx, rows):
    """Per report ``rows[r]``, from its neighbours ``idx[r]`` (-1: none): Theil-Sen fitted latitude and
    longitude at its time (median pairwise slope; slope 0 when no pair spans time), nearest time gap
    before and after (NaN: none), farthest gap and the neighbour count."""
    n, width = idx.shape
    fit_lat, fit_lon = np.full(n, np.nan), np.full(n, np.nan)
    dt_b, dt_a, far = np.full(n, np.nan), np.full(n, np.nan), np.full(n, np.nan)
    count = np.zeros(n, np.int64)
    tj, dt, buf = np.empty(width), np.empty(width), np.empty(max(width, width * (width - 1) // 2))
    yj = np.empty((2, width))
    for i in range(n):
        k = 0
        for c in range(width):
            j = idx[i, c]
            if j >= 0:
                tj[k], yj[0, k], yj[1, k] = t[j], lat[j], lon[j]
                dt[k] = t[j] - t[rows[i]]
                k += 1
        count[i] = k
        for c in range(k):
            d = dt[c]
            if d < 0 and not (-d >= dt_b[i]):
                dt_b[i] = -d
            elif d > 0 and not (d >= dt_a[i]):
                dt_a[i] = d
            if not (abs(d) <= far[i]):
                far[i] = abs(d)
        for axis in range(2):
            y = yj[axis]
            m = 0
            for a in range(k):
                for b in range(a + 1, k):
                    span = tj[b] - tj[a]
                    if span != 0:
                        buf[m] = (y[b] - y[a]) / span
                        m += 1
            slope = _median_sorted(buf, m)
            if not np.isfinite(slope):
                slope = 0.0
            for c in range(k):
                buf[c] = y[c] - slope * dt[c]
            (fit_lat if axis == 0 else fit_lon)[i] = _median_sorted(buf, k)
    return fit_lat, fit_lon, dt_b, dt_a, far, count


_EARTH_RADIUS_M = 6371008.8


def _flat_m(lat1, lon1, lat2, lon2) -> np.ndarray:
    """Distance (m) on a local flat earth: within 0.5 % up to 1000 km, enough for the consistency tests."""
    dlon = wrap180(np.asarray(lon2) - lon1)
    mean_lat = np.radians(0.5 * (np.asarray(lat1) + lat2))
    return _EARTH_RADIUS_M * np.radians(np.hypot(np.asarray(lat2) - lat1, dlon * np.cos(mean_lat)))


class _Tracks:
    """Reports of every segment, sorted and concatenated; the search works on all segments at once.

    ``lo``/``hi`` of a report are the first and one-past-last index of its segment.
    """

    def __init__(self, t_s: np.ndarray, lat: np.ndarray, lon: np.ndarray, seg: np.ndarray, half: int):
        self.t, self.lat, self.lon, self.half = t_s, lat, np.unwrap(lon, period=360.0), half
        self.n = t_s.size
        first = np.flatnonzero(np.r_[True, seg[1:] != seg[:-1]])
        size = np.diff(np.r_[first, self.n])
        self.seg_lo = np.repeat(first, size)
        self.seg_hi = self.seg_lo + np.repeat(size, size)
        self.width = 2 * half
        # per report, from the last pass that re-scored it: its neighbours, the Theil-Sen results
        # (_theil_sen's six arrays), the fitted position (NaN with too few neighbours) and the score
        self.idx = np.full((self.n, self.width), -1, dtype=np.int64)
        self._fit = None
        self.fit_lat, self.fit_lon = np.full(self.n, np.nan), np.full(self.n, np.nan)
        self.score = np.zeros(self.n)

    def _accepted_ranges(self, acc: np.ndarray, i: np.ndarray):
        """Per report ``i``: accepted positions before it (left), up to and including it (right), and the
        accepted range [lo, hi) of its segment, all as indices into ``acc``."""
        return (np.searchsorted(acc, i, side="left"), np.searchsorted(acc, i, side="right"),
                np.searchsorted(acc, self.seg_lo[i], side="left"),
                np.searchsorted(acc, self.seg_hi[i], side="left"))

    def neighbours(self, acc: np.ndarray, left, right, lo, hi) -> np.ndarray:
        """Indices (n, 2*half) of the nearest accepted reports of its segment, itself excluded (-1: none)."""
        excl = right - left
        width = self.width
        last = hi - excl  # one past the last index of the virtual list acc[lo:left] + acc[right:hi]
        start = np.minimum(np.maximum(left - self.half, lo), np.maximum(lo, last - width))
        v = start[:, None] + np.arange(width)[None, :]
        pos = np.where(v < left[:, None], v, v + excl[:, None])
        safe = acc[np.clip(pos, 0, acc.size - 1)] if acc.size else np.zeros_like(pos)
        return np.where(v < last[:, None], safe, -1)

    def fit(self, i: np.ndarray, idx: np.ndarray, threshold_m: float):
        """Theil-Sen prediction of reports ``i`` from their neighbours ``idx``; score = distance / allowed
        distance. Only reports whose neighbours changed since they were last fitted are re-fitted."""
        if self._fit is None:  # (the first pass fits every report)
            self._fit = _theil_sen(self.t, self.lat, self.lon, idx, i)
        else:
            new = (idx != self.idx[i]).any(axis=1)
            part = _theil_sen(self.t, self.lat, self.lon, idx[new], i[new])
            for whole, values in zip(self._fit, part, strict=True):
                whole[i[new]] = values
        self.idx[i] = idx
        fit_lat, fit_lon, dt_b, dt_a, far, count = (a[i] for a in self._fit)
        tau2 = np.where(np.isfinite(dt_b) & np.isfinite(dt_a), dt_b * dt_a, np.fmin(dt_b, dt_a) * far)
        enough = count >= MIN_FIT_NEIGHBOURS
        fit_lat = np.where(enough, fit_lat, np.nan)
        fit_lon = np.where(enough, fit_lon, np.nan)
        allowed = threshold_m + 0.5 * TURN_ACCEL_MS2 * np.nan_to_num(tau2)
        return np.nan_to_num(_flat_m(self.lat[i], self.lon[i], fit_lat, fit_lon) / allowed), fit_lat, fit_lon

    def _pair_score(self, i: np.ndarray, j: np.ndarray, ok: np.ndarray, v_max_ms: float) -> np.ndarray:
        """Distance / (max speed * dt + slack) from each report i to report j (0 where ok is False)."""
        jj = np.where(ok, j, 0)
        allowed = v_max_ms * np.abs(self.t[i] - self.t[jj]) + SPEED_SLACK_M
        return np.where(ok, _flat_m(self.lat[i], self.lon[i], self.lat[jj], self.lon[jj]) / allowed, 0.0)

    def speed(self, i: np.ndarray, acc: np.ndarray, left, right, lo, hi, v_max_ms: float) -> np.ndarray:
        """Speed-test score of reports ``i``: min over both sides, or over the two nearest reports on the
        only side."""
        def at(k: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
            ok = (k >= lo) & (k < hi)
            return (acc[np.clip(k, 0, acc.size - 1)] if acc.size else np.zeros_like(k)), ok

        (p1, ok_p1), (p2, ok_p2) = at(left - 1), at(left - 2)
        (n1, ok_n1), (n2, ok_n2) = at(right), at(right + 1)
        s_p1, s_p2 = self._pair_score(i, p1, ok_p1, v_max_ms), self._pair_score(i, p2, ok_p2, v_max_ms)
        s_n1, s_n2 = self._pair_score(i, n1, ok_n1, v_max_ms), self._pair_score(i, n2, ok_n2, v_max_ms)
        one_sided = np.where(ok_n2 & ~ok_p1, np.minimum(s_n1, s_n2),
                             np.where(ok_p2 & ~ok_n1, np.minimum(s_p1, s_p2), 0.0))
        return np.where(ok_p1 & ok_n1, np.minimum(s_p1, s_n1), one_sided)

    def rescore(self, accepted: np.ndarray, i: np.ndarray, v_max_ms: float, threshold_m: float) -> None:
        """Score reports ``i`` (ascending) against the accepted reports: the larger of the fit and speed
        scores, and the fitted position."""
        acc = np.flatnonzero(accepted)
        ranges = self._accepted_ranges(acc, i)
        fit_score, self.fit_lat[i], self.fit_lon[i] = self.fit(i, self.neighbours(acc, *ranges), threshold_m)
        self.score[i] = np.fmax(fit_score, self.speed(i, acc, *ranges, v_max_ms))

    def affected(self, kept: np.ndarray, changed: np.ndarray) -> np.ndarray:
        """Reports (ascending) whose neighbours or speed-test reports may differ once the ``changed``
        reports flip: the changed reports and those of their segment with fewer than 2*half + 1 ``kept``
        reports (accepted before and after the flip) between them (a report reads at most 2*half accepted
        reports on either side, and the speed test two)."""
        stable = np.concatenate([[0], np.cumsum(kept)])  # stable[k]: kept reports before k
        reach = self.width + 1
        hi = np.minimum(np.searchsorted(stable, stable[changed + 1] + reach, side="left") - 1,
                        self.seg_hi[changed] - 1)
        lo = np.maximum(np.searchsorted(stable, stable[changed] - reach, side="right") - 1,
                        self.seg_lo[changed])
        edges = np.zeros(self.n + 1, np.int64)
        np.add.at(edges, lo, 1)
        np.add.at(edges, hi + 1, -1)
        return np.flatnonzero(np.cumsum(edges[:-1]) > 0)

    def _rejected(self, accepted: np.ndarray) -> np.ndarray:
        """Accepted reports scoring above 1 that score at least as high as every accepted report within
        +-half reports of them in their own segment (never across segments: another aircraft's or another
        stretch's offenders do not hold a report back)."""
        live = np.where(accepted, self.score, -np.inf)
        c = np.flatnonzero(live > 1.0)
        most = live[c]
        for d in range(1, self.half + 1):
            for j, inside in ((c - d, c - d >= self.seg_lo[c]), (c + d, c + d < self.seg_hi[c])):
                most = np.where(inside, np.maximum(most, live[np.clip(j, 0, self.n - 1)]), most)
        return c[live[c] >= most]

    def search(self, v_max_ms: float, threshold_m: float):
        """Reject the worst offender per neighbourhood and reinstate what fits, until stable; the jump
        mask and each report's fitted position against the final accepted reports. After the first pass
        only the reports near a flipped one are scored again."""
        accepted = np.ones(self.n, dtype=bool)
        rows = np.arange(self.n)
        for _ in range(_MAX_PASSES):
            self.rescore(accepted, rows, v_max_ms, threshold_m)
            reject = self._rejected(accepted)
            reinstate = np.flatnonzero(~accepted & (self.score <= 1.0))
            if not reject.size and not reinstate.size:
                break
            accepted[reject] = False
            rows = self.affected(accepted, np.union1d(reject, reinstate))  # accepted: kept before and after
            accepted[reinstate] = True
        return ~accepted, self.fit_lat.copy(), wrap180(self.fit_lon)


JUMP_FLAG_COLUMNS = ["jump", "jump_size_m", "fit_latitude", "fit_longitude"]
JUMP_INPUTS = ["time", "aircraft_id", "latitude", "longitude"]  # the measurement columns the search reads


def _detect(adsb_meas: pd.DataFrame, max_speed_kt: float, robust_window: int,
            robust_threshold_m: float, need: list[str] = JUMP_FLAG_COLUMNS) -> pd.DataFrame:
    """Per row (original index): jump flag, distance from the robust fit (m) and the fitted lat/lon; the
    ``need`` columns taken as they are when the frame already carries them (computed once per job,
    pipeline.model.marks.mark_once). The distance is worked out only when ``need`` names it."""
    if robust_window < 3:
        raise ValueError(f"robust_window must be at least 3, got {robust_window}")
    if all(c in adsb_meas for c in need) and (max_speed_kt, robust_window, robust_threshold_m) == _DEFAULTS:
        found = adsb_meas[need].copy()
        found["jump"] = found["jump"].fillna(False).astype(bool)
        return found
    n = len(adsb_meas)
    cols = {"jump": np.zeros(n, bool), "jump_size_m": np.full(n, np.nan), "fit_latitude": np.full(n, np.nan),
            "fit_longitude": np.full(n, np.nan)}
    reference = midnight(adsb_meas["time"])
    key = _sorted_codes(adsb_meas["aircraft_id"])
    t = seconds_since(adsb_meas["time"], reference) if reference is not None else np.full(n, np.nan)
    lat, lon = adsb_meas["latitude"].to_numpy(float), adsb_meas["longitude"].to_numpy(float)
    # int32 positions and segment numbers (a frame of up to 2**31 rows): the search's full-length arrays are
    # the largest memory of a job on a long recording
    index = np.int32 if n < 2**31 else np.int64
    pos = np.flatnonzero((key >= 0) & ~np.isnan(t) & ~np.isnan(lat) & ~np.isnan(lon)).astype(index)
    pos = pos[np.lexsort((t[pos], key[pos]))]  # by aircraft, then time (stable)
    key, t, lat, lon = key[pos], t[pos], lat[pos], lon[pos]
    seg = np.cumsum(np.r_[True, (key[1:] != key[:-1]) | (np.diff(t) > SEGMENT_GAP_S)], dtype=index)
    del key
    judged = (np.bincount(seg) >= 3)[seg]  # shorter segments are not judged
    if not judged.any():
        return pd.DataFrame(cols, index=adsb_meas.index)
    if not judged.all():  # (copies only when some segment is left out)
        pos, t, lat, lon, seg = pos[judged], t[judged], lat[judged], lon[judged], seg[judged]
    del judged
    # segments are judged independently: the search runs over batches of whole segments (bounded memory)
    # on longitudes unwrapped over all of them, as one run over every segment would see them
    unwrapped = np.unwrap(lon, period=360.0)
    starts = np.flatnonzero(np.r_[True, seg[1:] != seg[:-1]])
    cuts = starts[np.r_[True, np.diff(starts // JUMP_BATCH_REPORTS) > 0]]
    for a, b in zip(cuts, np.r_[cuts[1:], pos.size], strict=True):
        tracks = _Tracks(t[a:b], lat[a:b], unwrapped[a:b], seg[a:b], (robust_window - 1) // 2)
        jump, fit_lat, fit_lon = tracks.search(max_speed_kt * M_PER_S_PER_KT, robust_threshold_m)
        del tracks
        at = pos[a:b]
        cols["jump"][at], cols["fit_latitude"][at], cols["fit_longitude"][at] = jump, fit_lat, fit_lon
        if "jump_size_m" in need:
            cols["jump_size_m"][at] = distance_m(lat[a:b], lon[a:b], fit_lat, fit_lon)
    return pd.DataFrame(cols, index=adsb_meas.index, copy=False)


_DEFAULTS = (1000.0, 7, 2000.0)


def _sorted_codes(ident: pd.Series) -> np.ndarray:
    """Integer codes of the aircraft identities, ordered as the texts sort (-1: none), so sorting by
    them sorts by identity without a Python object per row."""
    if isinstance(ident.dtype, pd.CategoricalDtype) and ident.cat.categories.is_monotonic_increasing:
        return ident.cat.codes.to_numpy(np.int32)
    codes, _ = pd.factorize(ident.astype("string"), sort=True)
    return codes.astype(np.int32)


def jump_flags(adsb_meas: pd.DataFrame, columns: list[str] = JUMP_FLAG_COLUMNS) -> pd.DataFrame:
    """JUMP_FLAG_COLUMNS (or only ``columns`` of them) per row (index kept) with the default parameters:
    what a job computes once."""
    need = [c for c in JUMP_FLAG_COLUMNS if c in columns]
    found = _detect(adsb_meas.drop(columns=[c for c in JUMP_FLAG_COLUMNS if c in adsb_meas]), *_DEFAULTS,
                    need=need or ["jump"])
    return found if need == JUMP_FLAG_COLUMNS else found[need]


def detect_jumps(adsb_meas: pd.DataFrame, *, max_speed_kt: float = 1000.0, robust_window: int = 7,
                 robust_threshold_m: float = 2000.0) -> pd.Series:
    """True for ADS-B reports that are position jumps (see the module docstring); indexed like the input."""
    found = _detect(adsb_meas, max_speed_kt, robust_window, robust_threshold_m, ["jump"])
    return found["jump"].rename("jump")


def jump_table(adsb_meas: pd.DataFrame, *, max_speed_kt: float = 1000.0, robust_window: int = 7,
               robust_threshold_m: float = 2000.0) -> pd.DataFrame:
    """One row per jump: identity, time, reported and fitted position, size (distance to the fit, m)."""
    found = _detect(adsb_meas, max_speed_kt, robust_window, robust_threshold_m)
    if "time_of_day" not in adsb_meas:
        adsb_meas = with_clock(adsb_meas)
    hit = found["jump"].to_numpy()
    rows = adsb_meas[hit]
    table = pd.DataFrame({"row": rows.index.to_numpy()})
    for c in JUMP_COLUMNS[1:9]:
        table[c] = rows[c].to_numpy() if c in rows else pd.NA
    for c in ("fit_latitude", "fit_longitude", "jump_size_m"):
        table[c] = found[c].to_numpy()[hit]
    return table[JUMP_COLUMNS].sort_values(["time_of_day", "row"], kind="stable").reset_index(drop=True)
