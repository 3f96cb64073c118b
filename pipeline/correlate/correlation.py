"""Cross-correlation of slotted radar and ADS-B positions, and the per-aircraft orchestration.

Lag convention (thesis eqs. 5.4/5.5): at lag d the radar series x[i] is paired with the ADS-B series
y[i - d]. A positive peak lag d means the radar series repeats the ADS-B series d slots later
(x[i] ~ y[i - d]: radar lags ADS-B); a negative one means radar leads.
"""

from __future__ import annotations

import functools
import itertools
import math

import numpy as np
import pandas as pd

from msdc.pipeline.correlate.matched import matched_pairs, matched_summary
from msdc.pipeline.correlate.results import (
    LAG_COLUMNS,
    SUMMARY_KEYS,
    CorrelationRun,
    SkippedWindow,
    WindowResult,
)
from msdc.pipeline.correlate.slots import slot_count, slot_series
from msdc.pipeline.correlate.verdict import window_verdict
from msdc.pipeline.correlate.windows import in_window, overlap_windows, short_window_reason
from msdc.pipeline.meta import FILLS, PAIRS
from msdc.pipeline.model.aircraft import NoSuchAircraft, aircraft_rows, one_aircraft
from msdc.pipeline.model.arguments import finite_number
from msdc.pipeline.model.dedup import duplicate_mask
from msdc.pipeline.model.geodesy import distance_m
from msdc.pipeline.model.jumps import JUMP_FLAG_COLUMNS, detect_jumps
from msdc.pipeline.model.schema import coded_text
from msdc.pipeline.model.time import clock, is_dated, iso_utc, midnight, seconds_since, utc_frame, with_clock
from msdc.pipeline.parallel import map_ordered

# A Pearson coefficient is shown where at least this many slot pairs overlap: of m pairs of independent
# noise, |r| exceeds 0.997 by chance 5 % of the time at m = 3, 0.878 at m = 5 and 0.632 at m = 10 (r = +-1
# always at m = 2), and slotted tracks are smooth, so short overlaps say nothing; 10 slots are 100 s at
# the default 10 s slot, 8-25 radar scans.
PEARSON_MIN_OVERLAP = 10
# the measurement columns correlate() reads (identity, time, position, dedup keys, job-wide flags); the
# tracker behind --fill predict reads more
CORRELATION_INPUTS = ["time", "time_of_day", "sensor_id", "sensor_kind", "aircraft_id", "callsign",
                      "address", "latitude", "longitude", "ground_speed_kt", "heading_deg", "duplicate",
                      *JUMP_FLAG_COLUMNS]
# what a frame must hold (the duplicate and jump flags, speed and heading are worked out or left out without)
REQUIRED_INPUTS = ("time", "latitude", "longitude", "sensor_kind", "sensor_id", "aircraft_id", "callsign",
                   "address")
# Per --pairs value, the sensor kind correlated (the "radar" role of the slot and summary tables) and the
# kind it is correlated against (the "adsb" role: the reference); radar-radar and all correlate radars with
# each other too. Rows of other kinds are left out of the run.
PAIR_KINDS = {"radar-adsb": ("radar", "adsb"), "radar-radar": ("radar", "adsb"), "all": ("radar", "adsb"),
              "mlat-adsb": ("mlat", "adsb"), "smr-mlat": ("smr", "mlat")}
ROLE_NOUNS = {"radar": "radar", "adsb": "ADS-B", "mlat": "multilateration", "smr": "surface radar"}
# A run holds every window's slot table (one row a slot) and lag table (2N - 1 rows for N slots) until
# its writers are done, so the slots of all windows together are capped by the memory those tables take:
# a slot row is 82 bytes (ten 8-byte columns, two 1-byte flags), a lag row 40 (five 8-byte columns), so
# a slot costs 162 bytes with its two lag rows. 512 MiB of tables allows 3.3 M slots: the benchmark
# week (docs/development/benchmarks.md: 292 MB, 7.4 M reports) at the default 10 s slot (1.0 M) or 5 s
# (2.0 M); --slot 0.1 over its day (14 M) is refused.
SLOT_ROW_BYTES, LAG_ROW_BYTES = 82, 40
TABLE_BUDGET_BYTES = 512 * 2**20
MAX_SLOTS = TABLE_BUDGET_BYTES // (SLOT_ROW_BYTES + 2 * LAG_ROW_BYTES)  # 3,314,017 over all windows of a run

__all__ = ["MAX_SLOTS", "PAIRS", "PEARSON_MIN_OVERLAP", "NoOverlap", "NoSuchAircraft", "TooManySlots",
           "correlate", "lag_identifiable", "lag_signal", "ncc", "pearson_by_lag", "pearson_max_lag",
           "pearson_peak", "pearson_search_limit",
           "peak_lag", "separation_stats", "separation_summary"]


class NoOverlap(LookupError):
    """Radar and ADS-B both saw the aircraft, but never at the same time; gives each sensor's time span."""

    def __init__(self, aircraft: str, radar_span_s: tuple[float, float], adsb_span_s: tuple[float, float],
                 reference: pd.Timestamp | None = None):
        self.radar_span_s, self.adsb_span_s = radar_span_s, adsb_span_s

        def span(s: tuple[float, float]) -> str:  # UTC date-times when dated, else HH:MM:SS
            if is_dated(reference):
                return f"{iso_utc(at_seconds(reference, s[0]))} to {iso_utc(at_seconds(reference, s[1]))}"
            return f"{clock(s[0])} to {clock(s[1])}"

        super().__init__(f"{aircraft}: radar ({span(radar_span_s)}) and ADS-B ({span(adsb_span_s)}) "
                         "tracks never overlap in time")


class TooManySlots(ValueError):
    """The windows of a run need more than ``limit`` slots at ``slot_s``: refused before the work explodes."""

    def __init__(self, slots: int, limit: int, slot_s: float):
        self.slots, self.limit, self.slot_s = slots, limit, slot_s
        super().__init__(f"slots of {slot_s:g} s need more than {limit:,} slots over the windows "
                         f"(at least {slots:,}); use a longer slot")


def _lags(n: int) -> np.ndarray:
    return np.arange(-(n - 1), n)


def _pair(x, y) -> tuple[np.ndarray, np.ndarray]:
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    if x.shape != y.shape or x.ndim != 1:
        raise ValueError(f"series must be 1-D and of equal length, got {x.shape} and {y.shape}")
    return x, y


def _xcorr(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Full cross-correlation sum_i x[i] y[i-d] for d = -(N-1)..N-1 by FFT, O(N log N)."""
    n = x.size
    if n == 0:
        return np.zeros(0)
    size = 1 << (2 * n - 1).bit_length()
    full = np.fft.irfft(np.fft.rfft(x, size) * np.fft.rfft(y[::-1], size), size)
    return full[: 2 * n - 1]  # index j holds lag j - (N - 1)


# Slot means of one held position can differ in their last bit (the real LEBL hour's parked 4CA1C3: its
# multilateration latitude 41.29832531 in 71 slots and one unit in the last place above it in the last):
# values within this share of the series' magnitude are one value, so that a Pearson coefficient is never
# the correlation of rounding. 1e-12 of 41 deg is 4e-11 deg (5 micrometres), far below any sensor's
# resolution (the finest CAT021 position LSB, 180/2^30 deg, is 2 cm).
SAME_VALUE_REL = 1e-12


def _constant_run(v: np.ndarray) -> int:
    """Length of the longest run at the end of ``v`` whose values lie within rounding of one another
    (SAME_VALUE_REL of the series' largest magnitude, at least of 1); a NaN ends the run."""
    if v.size == 0:
        return 0
    finite = np.abs(v[np.isfinite(v)])
    tol = SAME_VALUE_REL * max(1.0, float(finite.max()) if finite.size else 1.0)
    tail = v[::-1]
    spread = np.maximum.accumulate(tail) - np.minimum.accumulate(tail)  # NaN from the first NaN on
    return int(np.count_nonzero(spread <= tol))


def ncc(x, y) -> tuple[np.ndarray, np.ndarray]:
    """Lags d = -(N-1)..N-1 and r(d) = sum_i x[i] y[i-d] / sqrt(sum x^2 sum y^2); not circular, mean kept."""
    x, y = _pair(x, y)
    norm = math.sqrt(float(x @ x) * float(y @ y))
    num = _xcorr(x, y)
    return _lags(x.size), num / norm if norm > 0 else np.full(num.shape, np.nan)


def pearson_by_lag(x, y, min_overlap: int = 2) -> tuple[np.ndarray, np.ndarray]:
    """Lags and the Pearson coefficient of the overlapping pairs (x[i], y[i-d]), mean removed per overlap.

    NaN where the overlap has fewer than ``min_overlap`` (at least 2) points or either side is constant;
    correlate() asks for PEARSON_MIN_OVERLAP. O(N log N): the overlap sums come from cumulative sums and the
    cross products from one FFT correlation.
    """
    if isinstance(min_overlap, bool) or not isinstance(min_overlap, int | np.integer) or min_overlap < 2:
        raise ValueError(f"min_overlap must be an integer >= 2 (a coefficient needs two pairs), "
                         f"got {min_overlap!r}")
    x, y = _pair(x, y)
    n = x.size
    lags = _lags(n)
    if n < 2:
        return lags, np.full(lags.size, np.nan)
    # constancy of a side (raw values, within rounding): its overlap is a suffix or prefix of the series
    x_tail, x_head = _constant_run(x), _constant_run(x[::-1])
    y_tail, y_head = _constant_run(y), _constant_run(y[::-1])
    x, y = x - x.mean(), y - y.mean()  # shifts leave r unchanged and keep the sums small
    m = (n - np.abs(lags)).astype(float)  # overlap size
    cx, cxx = np.concatenate([[0.0], np.cumsum(x)]), np.concatenate([[0.0], np.cumsum(x * x)])
    cy, cyy = np.concatenate([[0.0], np.cumsum(y)]), np.concatenate([[0.0], np.cumsum(y * y)])
    # d >= 0: x[d:], y[:n-d]; d < 0: x[:n+d], y[-d:]
    x_lo, x_hi = np.maximum(lags, 0), np.minimum(n, n + lags)
    y_lo, y_hi = np.maximum(-lags, 0), np.minimum(n, n - lags)
    sx, sxx = cx[x_hi] - cx[x_lo], cxx[x_hi] - cxx[x_lo]
    sy, syy = cy[y_hi] - cy[y_lo], cyy[y_hi] - cyy[y_lo]
    sxy = _xcorr(x, y)
    with np.errstate(invalid="ignore", divide="ignore"):
        vx, vy = sxx - sx * sx / m, syy - sy * sy / m
        r = (sxy - sx * sy / m) / np.sqrt(vx * vy)
    x_flat = np.where(lags >= 0, m <= x_tail, m <= x_head)
    y_flat = np.where(lags >= 0, m <= y_head, m <= y_tail)
    bad = (m < min_overlap) | x_flat | y_flat | ~(vx > 0) | ~(vy > 0)
    return lags, np.where(bad, np.nan, np.clip(r, -1.0, 1.0))


def peak_lag(lags: np.ndarray, r: np.ndarray, max_abs_lag: int | None = None) -> int | None:
    """Lag of the largest coefficient with |lag| <= max_abs_lag (first, i.e. most negative, on ties;
    NaN ignored); None if there is none."""
    lags, r = np.asarray(lags), np.asarray(r, dtype=float)
    if max_abs_lag is not None:
        keep = np.abs(lags) <= max_abs_lag
        lags, r = lags[keep], r[keep]
    if r.size == 0 or np.all(np.isnan(r)):
        return None
    return int(lags[int(np.nanargmax(r))])


def pearson_max_lag(n_slots: int) -> int:
    """Largest |lag| searched for the Pearson peak: the overlap keeps at least half the slots.

    Short overlaps are degenerate (any 2-point overlap has r = +-1), so the peak is not searched there.
    """
    return n_slots // 2


def pearson_search_limit(n_slots: int) -> int:
    """Largest |lag| the Pearson peak is searched over in an N-slot window: at least half the slots and
    at least PEARSON_MIN_OVERLAP of them overlap (0: no lag can be estimated)."""
    return max(0, min(pearson_max_lag(n_slots), n_slots - PEARSON_MIN_OVERLAP))


def pearson_peak(lags: np.ndarray, r: np.ndarray, n_slots: int) -> tuple[int | None, bool]:
    """The Pearson peak lag of an N-slot window and whether it sits at the search limit: there the
    coefficient still rises towards lags that are not searched, so it is no lag estimate (None, True)."""
    limit = pearson_search_limit(n_slots)
    if limit < 1:
        return None, False
    lag = peak_lag(lags, r, limit)
    if lag is not None and abs(lag) == limit:
        return None, True
    return lag, False


# A lag is told from its neighbours when a one-slot error costs more than the noise can hide (docs/methods/
# correlation.md): sqrt(E1) >= 2 z sigma with z = 2 (two standard deviations), see lag_identifiable
LAG_SIGNAL_Z = 2.0
# a slot covering a share f of its interval has its mean time (1 - f) / 2 slot off the centre: at 3/4 an
# eighth of a slot (310 m at 250 m/s and 10 s slots, about the radar's per-slot noise)
FULL_SLOT_SHARE = 0.75
_MAD_TO_SIGMA = 1.4826  # a normal variable's standard deviation from its median absolute value


def _noise_sigma(v: np.ndarray) -> float:
    """Per-slot white-noise standard deviation of a smooth series, from its third differences (a track's
    constant velocity and acceleration cancel in them; white noise gives variance 20 sigma^2), by their
    median absolute value so that a few jumps or turns do not inflate it."""
    d3 = np.diff(v, 3)
    return _MAD_TO_SIGMA * float(np.median(np.abs(d3))) / math.sqrt(20.0) if d3.size else math.nan


def lag_signal(x, y, y_count=None) -> tuple[float, float]:
    """A window's manoeuvre signal sqrt(E1) and noise sigma for the Pearson lag, in the series' units.

    E1 = sum (dy - mean dy)^2 over the reference series' slot-to-slot steps dy between two full slots,
    less their expected noise 2 sigma_y^2 a step: what a one-slot lag error adds to the squared mismatch
    of the two series (zero on a straight, constant-speed leg, where a time shift is a constant offset).
    A slot with fewer than FULL_SLOT_SHARE of the median reports (``y_count``; 0: filled) covers part of
    its interval, so its mean sits off the centre by more than an eighth of a slot of flight, a step no
    radar repeats: its steps are left out. sigma: the per-slot noise of x - y (_noise_sigma; the common
    motion cancels)."""
    x, y = _pair(x, y)
    if x.size < 4:
        return math.nan, math.nan
    count = np.ones(y.size) if y_count is None else np.asarray(y_count, dtype=float)
    reported = count[count > 0]
    full = count >= FULL_SLOT_SHARE * np.median(reported) if reported.size else np.zeros(y.size, bool)
    dy = np.diff(y)[full[1:] & full[:-1]]
    if dy.size < 2:
        return math.nan, math.nan
    energy = float(np.sum((dy - dy.mean()) ** 2)) - 2.0 * dy.size * _noise_sigma(y[full]) ** 2
    return math.sqrt(max(energy, 0.0)), _noise_sigma(x - y)


def lag_identifiable(x, y, lag: int, y_count=None) -> bool:
    """Whether the Pearson peak ``lag`` of radar x against reference y can be told from its neighbours,
    judged on the manoeuvre in the slots that overlap at that lag (x[i] with y[i - lag]) against the
    noise of all slots.

    Moving the lag one slot from the true one adds E1 (lag_signal) to the expected squared mismatch, while
    the noise moves that difference by 2 sigma sqrt(E1) (one standard deviation): the lag is identified
    when E1 >= LAG_SIGNAL_Z * 2 sigma sqrt(E1), i.e. sqrt(E1) >= 2 LAG_SIGNAL_Z sigma. Lags further off
    cost more (about k^2 E1 at k slots), so the neighbours decide. A peak whose overlap leaves the
    manoeuvre out has no E1 there and is no estimate either."""
    x, y = _pair(x, y)
    n = x.size
    count = np.ones(n) if y_count is None else np.asarray(y_count, dtype=float)
    xs, ys = (slice(lag, n), slice(0, n - lag)) if lag >= 0 else (slice(0, n + lag), slice(-lag, n))
    signal, _ = lag_signal(x[xs], y[ys], count[ys])
    sigma = _noise_sigma(x - y)  # the sensors' noise, from every slot (a short overlap's estimate varies)
    if not math.isfinite(signal) or not math.isfinite(sigma):
        return False
    return signal > 0.0 and signal >= 2.0 * LAG_SIGNAL_Z * sigma


def separation_stats(sep_m) -> dict[str, float]:
    """Mean, RMS, 95th percentile (linear interpolation) and maximum of separations in metres."""
    sep_m = np.asarray(sep_m, dtype=float)
    if sep_m.size == 0:
        return dict.fromkeys(["sep_mean_m", "sep_rms_m", "sep_p95_m", "sep_max_m"], math.nan)
    return {"sep_mean_m": float(sep_m.mean()), "sep_rms_m": float(np.sqrt(np.mean(sep_m**2))),
            "sep_p95_m": float(np.percentile(sep_m, 95)), "sep_max_m": float(sep_m.max())}


def separation_summary(sep_m: np.ndarray, radar_filled: np.ndarray, adsb_filled: np.ndarray
                       ) -> dict[str, float | int]:
    """A window's separation statistics over the slots where both sensors reported (``sep_slots`` of
    them): a filled slot holds a position the sensor did not report then, so its distance says how far
    the aircraft moved, not how far the sensors disagree. ``sep_rms_all_m`` is the RMS over every slot."""
    sep_m = np.asarray(sep_m, dtype=float)
    both = ~np.asarray(radar_filled, dtype=bool) & ~np.asarray(adsb_filled, dtype=bool)
    used = sep_m[both]
    return {**separation_stats(used), "sep_median_m": float(np.median(used)) if used.size else math.nan,
            "sep_slots": int(both.sum()),
            "sep_rms_all_m": float(np.sqrt(np.mean(sep_m**2))) if sep_m.size else math.nan}


def at_seconds(reference: pd.Timestamp | None, seconds: float) -> pd.Timestamp | None:
    """The UTC instant (tz-aware) ``seconds`` after ``reference``; None when undated or not finite. Reports
    take it as it is (a workbook writes it as a date-time, JSON as ISO 8601 text)."""
    if reference is None or not np.isfinite(seconds):
        return None
    instant = reference + pd.to_timedelta(seconds, unit="s")
    return instant if is_dated(instant) else None


def _unwrapped_lon(radar_lon: np.ndarray, adsb_lon: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Longitude series without +-180 jumps, ADS-B shifted by whole turns to sit next to radar."""
    x, y = np.unwrap(radar_lon, period=360.0), np.unwrap(adsb_lon, period=360.0)
    return x, y + 360.0 * np.round((x[0] - y[0]) / 360.0)


def _none_if_nan(v):
    return None if isinstance(v, float) and math.isnan(v) else v


def _window_result(ac: tuple[str, str], number: int, start_s: float, end_s: float,
                   radar: tuple[np.ndarray, ...], adsb: tuple[np.ndarray, ...],
                   dups: tuple[int, int], slot_s: float, reference: pd.Timestamp, sensors: dict[str, str],
                   adsb_jumps: int | None = 0, predictors: tuple = (None, None), matched: dict | None = None
                   ) -> WindowResult:
    """Slot, correlate and summarise one window of one aircraft (call sign, address) from each side's
    reports in it (time of day, latitude, longitude arrays); with predictors (``--fill predict``), empty
    slots take the tracker's prediction (pipeline.correlate.fill) instead of the previous slot. ``matched``:
    the window's lead numbers and verdict (pipeline.correlate.matched, .verdict), worked out beforehand."""
    rs, as_ = slot_series(*radar, start_s, end_s, slot_s), slot_series(*adsb, start_s, end_s, slot_s)
    if predictors[0] is not None or predictors[1] is not None:
        from msdc.pipeline.correlate.fill import fill_predicted

        rs, as_ = fill_predicted(rs, slot_s, predictors[0]), fill_predicted(as_, slot_s, predictors[1])
    tod = rs["time_of_day"]
    if not is_dated(reference):
        stamps = pd.Series(pd.NaT, index=pd.RangeIndex(len(tod)), dtype="datetime64[ns, UTC]")
    else:
        stamps = (reference + pd.to_timedelta(tod, unit="s")).astype("datetime64[ns, UTC]")
    slots = pd.DataFrame({  # columns as arrays, in SLOT_COLUMNS order: one frame, no alignment
        "slot": rs["slot"], "time_of_day": tod, "timestamp": stamps,
        "radar_lat": rs["latitude"], "radar_lon": rs["longitude"],
        "adsb_lat": as_["latitude"], "adsb_lon": as_["longitude"],
        "radar_count": rs["count"], "adsb_count": as_["count"],
        "radar_filled": rs["filled"], "adsb_filled": as_["filled"],
        "sep_m": distance_m(rs["latitude"], rs["longitude"], as_["latitude"], as_["longitude"]),
    })
    x_lon, y_lon = _unwrapped_lon(rs["longitude"], as_["longitude"])
    lags, ncc_lat = ncc(rs["latitude"], as_["latitude"])
    _, ncc_lon = ncc(x_lon, y_lon)
    _, p_lat = pearson_by_lag(rs["latitude"], as_["latitude"], PEARSON_MIN_OVERLAP)
    _, p_lon = pearson_by_lag(x_lon, y_lon, PEARSON_MIN_OVERLAP)
    (peak_lat, limit_lat), (peak_lon, limit_lon) = (pearson_peak(lags, p, len(slots)) for p in (p_lat, p_lon))
    # a straight, constant-speed window leaves the Pearson curve flat within noise: no lag estimate
    flat_lat = peak_lat is not None and not lag_identifiable(rs["latitude"], as_["latitude"], peak_lat,
                                                             as_["count"])
    flat_lon = peak_lon is not None and not lag_identifiable(x_lon, y_lon, peak_lon, as_["count"])
    peak_lat, peak_lon = (None if flat_lat else peak_lat), (None if flat_lon else peak_lon)
    lag_frame = pd.DataFrame(dict(zip(LAG_COLUMNS, [lags, ncc_lat, ncc_lon, p_lat, p_lon], strict=True)))
    zero = len(slots) - 1
    summary = {
        "callsign": ac[0], "address": ac[1], "window": number, **sensors,
        "start_tod": float(start_s), "end_tod": float(end_s),
        "start": at_seconds(reference, start_s), "end": at_seconds(reference, end_s), **(matched or {}),
        "slots": len(slots),
        "radar_before": len(radar[0]), "radar_after": len(slots),
        "adsb_before": len(adsb[0]), "adsb_after": len(slots),
        "radar_duplicates": dups[0], "adsb_duplicates": dups[1], "adsb_jumps": adsb_jumps,
        "radar_filled_slots": int(rs["filled"].sum()),
        "adsb_filled_slots": int(as_["filled"].sum()),
        "ncc0_lat": float(ncc_lat[zero]), "ncc0_lon": float(ncc_lon[zero]),
        "ncc_peak_lag_lat": peak_lag(lags, ncc_lat), "ncc_peak_lag_lon": peak_lag(lags, ncc_lon),
        "pearson0_lat": float(p_lat[zero]), "pearson0_lon": float(p_lon[zero]),
        "pearson_peak_lag_lat": peak_lat, "pearson_peak_lag_lon": peak_lon,
        "pearson_peak_at_limit_lat": limit_lat, "pearson_peak_at_limit_lon": limit_lon,
        "pearson_lag_unidentified_lat": flat_lat, "pearson_lag_unidentified_lon": flat_lon,
        **separation_summary(slots["sep_m"].to_numpy(), rs["filled"], as_["filled"]),
    }
    summary = {k: _none_if_nan(summary.get(k)) for k in SUMMARY_KEYS}
    return WindowResult(summary=summary, slots=slots, lags=lag_frame)


def _span(times: np.ndarray) -> tuple[float, float]:
    """Earliest and latest time, NaN ignored (NaN when there is none)."""
    t = times[~np.isnan(times)]
    return (float(t.min()), float(t.max())) if t.size else (math.nan, math.nan)


class _Columns:
    """The columns correlate() reads, as arrays over the rows of a measurement frame (read once per run,
    not per aircraft or sensor pair); ``dup`` and ``jump`` are None when the frame does not carry the
    job-wide flags (pipeline.model.marks.mark_once), which are then worked out per source as before.
    ``adsb_reference``: whether the reference role's rows are ADS-B (in_roles renames a multilateration
    reference to that role: its verdicts then name its id, and it has no ADS-B jumps)."""

    def __init__(self, meas: pd.DataFrame, adsb_reference: bool = True):
        self.meas = meas
        self.adsb_reference = adsb_reference
        self.time_ns = meas["time"].array.asi8  # (a view: nothing of the run's size is copied but flags)
        self.tod = meas["time_of_day"].to_numpy(float)
        self.lat, self.lon = meas["latitude"].to_numpy(float), meas["longitude"].to_numpy(float)
        self.is_adsb = (meas["sensor_kind"] == "adsb").to_numpy(bool)
        self.is_radar = (meas["sensor_kind"] == "radar").to_numpy(bool)
        sid = meas["sensor_id"]
        if isinstance(sid.dtype, pd.CategoricalDtype):  # grouped in category order, as groupby does
            self.sensor = sid.cat.codes.to_numpy()
            self.names = [str(c) for c in sid.cat.categories]
        else:
            codes, uniques = pd.factorize(sid, sort=True)
            self.sensor, self.names = codes, [str(u) for u in uniques]
        self.dup = meas["duplicate"].astype(bool).to_numpy() if "duplicate" in meas else None
        self.jump = meas["jump"].fillna(False).astype(bool).to_numpy() if "jump" in meas else None

    @functools.cached_property
    def track_inputs(self):
        """The columns the tracker reads (``--fill predict``) as arrays, read on first use."""
        from msdc.pipeline.correlate.fill import TrackInputs

        return TrackInputs(self.meas)

    def time_order(self, rows: np.ndarray) -> np.ndarray:
        """``rows`` in sort_by_time's order: stable by time, NaT last."""
        key = self.time_ns[rows]
        key = np.where(key == np.iinfo(np.int64).min, np.iinfo(np.int64).max, key)  # NaT: the smallest
        return rows[np.argsort(key, kind="stable")]

    def by_sensor(self, rows: np.ndarray) -> dict[str, np.ndarray]:
        """Rows (ascending positions) grouped by sensor_id in groupby order; rows without one are left out."""
        codes = self.sensor[rows]
        return {self.names[c]: rows[codes == c] for c in np.unique(codes[codes >= 0])}

    def sources(self, radar_rows: np.ndarray, other_rows: np.ndarray, split_adsb: bool
                ) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray]]:
        """One aircraft's radar sources and ADS-B sources (rows of each): each radar (``sensor_id``) on
        its own; ADS-B one source named by its ground stations joined with "+" (apart: ``split_adsb``)."""
        adsb = other_rows[self.is_adsb[other_rows]]
        if not adsb.size:
            return self.by_sensor(radar_rows), {}
        if split_adsb:
            return self.by_sensor(radar_rows), self.by_sensor(adsb)
        codes = np.unique(self.sensor[adsb])
        return self.by_sensor(radar_rows), {"+".join(sorted(self.names[c] for c in codes if c >= 0)): adsb}


class _Source:
    """One sensor source of one aircraft, ready for windows: its reports in time order without repeats
    (time of day, latitude, longitude), the times of its repeats and of its ADS-B jumps, and (for
    ``--fill predict``) its track predictor."""

    def __init__(self, cols: _Columns, rows: np.ndarray, track: bool = False):
        order = cols.time_order(rows)
        meas = cols.meas
        if cols.dup is not None:
            dup = cols.dup[order]
        else:  # per source, as duplicate_mask reads it
            dup = duplicate_mask(meas.iloc[order].reset_index(drop=True)).to_numpy(bool)
        kept = order[~dup]
        self.dup_t = cols.tod[order[dup]]
        self.t, self.lat, self.lon = cols.tod[kept], cols.lat[kept], cols.lon[kept]
        self.jump = np.zeros(kept.size, bool)
        self.is_adsb = cols.adsb_reference and bool(kept.size) and bool(cols.is_adsb[kept].all())
        if self.is_adsb:  # jumps are an ADS-B notion
            if cols.jump is not None:
                self.jump = cols.jump[kept]
            else:
                self.jump = detect_jumps(meas.iloc[kept].reset_index(drop=True)).to_numpy(bool)
        self.jump_t = self.t[self.jump]
        self._track = (cols, kept) if track else None
        self._predictor: tuple | None = None

    def predictor(self, reference: pd.Timestamp, max_coast_s: float):
        """Its track predictor (``--fill predict``; pipeline.correlate.fill), built on first use and
        shared by all its pairs (the same arguments in one run)."""
        if self._predictor is None:
            from msdc.pipeline.correlate.fill import rows_predictor

            cols, kept = self._track
            self._predictor = (rows_predictor(cols.track_inputs, kept, reference, max_coast_s),)
            self._track = None
        return self._predictor[0]

    def inside(self, start_s: float, end_s: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Its reports inside [start, end]."""
        keep = in_window(self.t, start_s, end_s)
        return self.t[keep], self.lat[keep], self.lon[keep]

    def clean_inside(self, start_s: float, end_s: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Its reports inside [start, end] without its ADS-B position jumps."""
        keep = in_window(self.t, start_s, end_s) & ~self.jump
        return self.t[keep], self.lat[keep], self.lon[keep]


def _aircraft_pairs(cols: _Columns, radar_rows: np.ndarray, other_rows: np.ndarray, pairs: str,
                    split_adsb: bool, fill: str) -> list[tuple[str, _Source, str, _Source]]:
    """(radar id, its source, reference id, its source) to correlate for one aircraft given by its rows:
    every radar against every ADS-B source ("radar-adsb"), every two radars ("radar-radar"), or both
    ("all"); each source prepared once for all its pairs."""
    if pairs not in PAIRS:
        raise ValueError(f"pairs must be one of {', '.join(PAIRS)}, got {pairs!r}")
    radars, adsb = cols.sources(radar_rows, other_rows, split_adsb)
    made: dict[tuple[str, str], _Source] = {}

    def source(kind: str, name: str, rows: np.ndarray) -> _Source:
        if (kind, name) not in made:
            made[kind, name] = _Source(cols, rows, track=fill == "predict")
        return made[kind, name]

    out = []
    if pairs in ("radar-adsb", "all"):
        out += [(r, source("radar", r, rr), a, source("adsb", a, ar))
                for r, rr in radars.items() for a, ar in adsb.items()]
    if pairs in ("radar-radar", "all"):
        ids = sorted(radars)
        out += [(a, source("radar", a, radars[a]), b, source("radar", b, radars[b]))
                for i, a in enumerate(ids) for b in ids[i + 1:]]
    return out


def _prepared_pairs(cols: _Columns, pairs: str, split_adsb: bool, fill: str, reference: pd.Timestamp,
                    slot_s: float, gap_s: float, target: tuple) -> tuple[tuple[str, str], list]:
    """One aircraft's (call sign, address) labels and sensor pairs (_aircraft_pairs); with ``fill``
    "predict" the predictors of the pairs that overlap are built now (each pair's _correlate_pair then
    finds them built)."""
    callsign, address, _, radar_rows, other_rows = target
    found = _aircraft_pairs(cols, radar_rows, other_rows, pairs, split_adsb, fill)
    if fill == "predict":
        coast_s = max(gap_s, slot_s)
        for _, radar, _, adsb in found:
            if overlap_windows(radar.t, adsb.t, gap_s):
                radar.predictor(reference, coast_s)
                adsb.predictor(reference, coast_s)
    return (callsign, address), found


def _correlate_pair(ac: tuple[str, str], run: CorrelationRun, pair: tuple[str, _Source, str, _Source],
                    slot_s: float, gap_s: float, reference: pd.Timestamp, fill: str = "hold",
                    budget: list[int] | None = None) -> NoOverlap | None:
    """Append the windows (or skipped windows) of one aircraft (call sign, address) and sensor pair to
    ``run``; the NoOverlap when the two sensors never overlap. ``budget`` holds the slots used so far by
    the run (TooManySlots past MAX_SLOTS, checked before any window of the pair is slotted)."""
    radar_id, radar, ref_id, adsb = pair
    callsign, address = ac
    windows = overlap_windows(radar.t, adsb.t, gap_s)
    sensors = {"radar_sensor": radar_id, "reference_sensor": ref_id}
    if not windows:
        label = f"{callsign or address} ({radar_id} and {ref_id})"
        r_span, a_span = _span(radar.t), _span(adsb.t)
        gap = NoOverlap(label, r_span, a_span, reference)
        run.skipped.append(SkippedWindow(callsign, address, min(r_span[0], a_span[0]),
                                         max(r_span[1], a_span[1]), str(gap), **sensors))
        return gap
    if budget is not None:
        budget[0] += sum(slot_count(a, b, slot_s) for a, b in windows if b - a >= slot_s)
        if budget[0] > MAX_SLOTS:
            raise TooManySlots(budget[0], MAX_SLOTS, slot_s)
    predictors = (None, None)
    if fill == "predict":  # each side's own forward track, coasting across the longest gap a window has
        coast_s = max(gap_s, slot_s)
        predictors = (radar.predictor(reference, coast_s), adsb.predictor(reference, coast_s))
    number = 0
    for start_s, end_s in windows:
        r_in, a_in = radar.inside(start_s, end_s), adsb.inside(start_s, end_s)
        reason = short_window_reason(start_s, end_s, slot_s)
        if reason is None and (not r_in[0].size or not a_in[0].size):
            reason = f"no {radar_id if not r_in[0].size else ref_id} measurement inside the window"
        if reason:
            run.skipped.append(SkippedWindow(callsign, address, start_s, end_s, reason, **sensors))
            continue
        number += 1
        dups = (int(in_window(radar.dup_t, start_s, end_s).sum()),
                int(in_window(adsb.dup_t, start_s, end_s).sum()))
        # jumps are looked for in ADS-B only: none where the reference is multilateration, not zero
        jumps = int(in_window(adsb.jump_t, start_s, end_s).sum()) if adsb.is_adsb else None
        matched = matched_summary(matched_pairs(r_in, adsb.clean_inside(start_s, end_s), start_s, end_s,
                                                slot_s))
        matched["verdict"] = window_verdict({**matched, "adsb_jumps": jumps},
                                            "ADS-B" if adsb.is_adsb else ref_id, radar_id)
        run.windows.append(_window_result(ac, number, start_s, end_s, r_in, a_in, dups, slot_s, reference,
                                          sensors, jumps, predictors, matched))
    return None


def in_roles(meas: pd.DataFrame, pairs: str) -> pd.DataFrame:
    """The rows of the two sensor kinds a ``pairs`` value correlates, their sensor_kind renamed to the roles
    the correlation runs with ("radar" the correlated sensor, "adsb" its reference: PAIR_KINDS); ``meas``
    itself when it holds radar and ADS-B rows alone (radar-adsb, radar-radar, all)."""
    tested, reference = PAIR_KINDS[pairs]
    kind = meas["sensor_kind"].astype(str).to_numpy()
    roles = np.select([kind == tested, kind == reference], [0, 1], -1)
    if (tested, reference) == ("radar", "adsb") and (roles >= 0).all():
        return meas
    keep = roles >= 0
    out = meas[keep].reset_index(drop=True)
    out["sensor_kind"] = pd.Series(coded_text(roles[keep], ["radar", "adsb"]), index=out.index)
    return out


def correlate(meas: pd.DataFrame, *, callsign: str | None = None, address: str | None = None,
              all_aircraft: bool = False, slot_s: float = 10.0, gap_s: float = 180.0,
              pairs: str = "radar-adsb", split_adsb: bool = False, fill: str = "hold") -> CorrelationRun:
    """Correlate per aircraft, sensor pair and overlap window (see the module docstring).

    ``meas`` is a measurement frame (pipeline.model.schema). Each radar is correlated on its own (plots
    of two radars are never mixed) against each ADS-B source and/or each other radar (``pairs``); ADS-B
    ground stations are one source unless ``split_adsb``. ``pairs`` "mlat-adsb" correlates each
    multilateration system against ADS-B, "smr-mlat" each surface movement radar against multilateration
    (in the tables the correlated sensor takes the radar's columns, its reference the ADS-B ones). One
    aircraft by call sign and/or address (NoSuchAircraft, NoOverlap when no pair overlaps), or with
    ``all_aircraft`` every aircraft seen by a pair (TooManySlots when the windows need more than MAX_SLOTS
    slots). Times in the tables count seconds from midnight UTC of the earliest report. ``fill``: empty
    slots take the previous slot ("hold", the thesis) or the tracker's prediction ("predict").
    """
    if fill not in FILLS:
        raise ValueError(f"fill must be {' or '.join(map(repr, FILLS))}, got {fill!r}")
    finite_number("slot_s", slot_s)
    finite_number("gap_s", gap_s, above=None, at_least=0.0)
    if pairs not in PAIRS:
        raise ValueError(f"pairs must be one of {', '.join(PAIRS)}, got {pairs!r}")
    for name, value in (("callsign", callsign), ("address", address)):
        if value is not None and not isinstance(value, str):  # 0x750312 is the int 7668498, not "750312"
            raise TypeError(f"{name} {value!r}: a string (an address as 6 hex digits, e.g. '750312'), not "
                            f"{type(value).__name__}")
    if all_aircraft and (callsign is not None or address is not None):
        given = ", ".join(f"{k}={v!r}" for k, v in (("callsign", callsign), ("address", address))
                          if v is not None)
        raise ValueError(f"all_aircraft=True correlates every aircraft: give it or callsign/address, not "
                         f"both (got {given})")
    if not isinstance(meas, pd.DataFrame) or "time" not in meas:
        raise TypeError("meas must be a measurement frame (pipeline.model.schema) with a 'time' column, got "
                        + (type(meas).__name__ if not isinstance(meas, pd.DataFrame) else "no 'time' column"))
    missing = [c for c in REQUIRED_INPUTS if c not in meas]
    if missing:
        raise ValueError(f"meas: lacks the column(s) {', '.join(missing)} (a measurement frame: "
                         "pipeline.model.schema)")
    for c in ("latitude", "longitude"):
        inf = np.isinf(pd.to_numeric(meas[c], errors="coerce").to_numpy(float))
        if inf.any():
            first = meas.index[int(np.flatnonzero(inf)[0])]
            raise ValueError(f"meas: {int(inf.sum())} row(s) with an infinite {c}, the first at index "
                             f"{first}: a position is finite, or NaN where unknown")
    meas = utc_frame(meas, ["time"], "meas")  # aware times of any zone as UTC; naive ones refused
    if str(meas["time"].dtype) != "datetime64[ns, UTC]":
        meas = meas.assign(time=meas["time"].dt.as_unit("ns"))
    reference = midnight(meas["time"])
    tested, against = (ROLE_NOUNS[k] for k in PAIR_KINDS[pairs])
    adsb_reference = PAIR_KINDS[pairs][1] == "adsb"
    if reference is None:
        raise NoSuchAircraft("any aircraft", [tested, against], [], "there are no measurements")
    if "sensor_kind" in meas:
        meas = in_roles(meas, pairs)
    if fill == "hold":  # the steps below read these columns only (time_of_day, not timestamp); each window
        # copies its rows
        columns = [c for c in dict.fromkeys(CORRELATION_INPUTS) if c in meas or c == "time_of_day"]
        meas = meas.assign(time_of_day=seconds_since(meas["time"], reference))[columns]
    else:
        meas = with_clock(meas, reference)
    run = CorrelationRun(parameters={
        "callsign": callsign, "address": address, "all_aircraft": all_aircraft, "slot_s": slot_s,
        "gap_s": gap_s, "pairs": pairs, "split_adsb": split_adsb,
        **({"fill": fill} if fill != "hold" else {}),  # the thesis default leaves the parameters as they were
        "date": reference.date().isoformat() if is_dated(reference) else None})
    role_pairs = pairs if pairs in ("radar-radar", "all") else "radar-adsb"  # the pairs of the two roles
    need_adsb = role_pairs == "radar-adsb"
    if all_aircraft:  # one aircraft's rows at a time (aircraft_rows), not a second copy of the run
        cols = _Columns(meas, adsb_reference)
        targets = aircraft_rows(meas, need_adsb=need_adsb)
        first = next(targets, None)
        if first is None:
            raise NoSuchAircraft("any aircraft", [tested, against], [],
                                 f"no aircraft is seen by both {tested} and {against}")
        targets = itertools.chain([first], targets)
        del first
    else:
        try:
            ac = one_aircraft(meas, callsign, address, need_adsb=need_adsb)
        except NoSuchAircraft as exc:  # the roles by their own names
            if (tested, against) == ("radar", "ADS-B"):
                raise
            names = {"radar": tested, "ADS-B": against}
            missing = [names.get(m, m) for m in exc.missing_in]
            # the closest names say which role saw them: "(radar only)" is the sensor correlated's
            closest = [c.replace("(radar only)", f"({tested} only)").replace(
                "(ADS-B only)", f"({against} only)") for c in exc.closest]
            text = str(exc).replace("radar or ADS-B", " or ".join(missing)).replace(
                " by radar", f" by {tested}").replace(" by ADS-B", f" by {against}")
            for said, meant in zip(exc.closest, closest, strict=True):
                text = text.replace(said, meant)
            raise NoSuchAircraft(exc.wanted, missing, closest, text) from None
        cols = _Columns(pd.concat([ac.radar, ac.adsb], ignore_index=True), adsb_reference)
        targets = iter([(ac.callsign, ac.address, ac.aircraft_id, np.arange(len(ac.radar)),
                         np.arange(len(ac.radar), len(ac.radar) + len(ac.adsb)))])
        del ac
    paired, budget = False, [0]
    prepare = functools.partial(_prepared_pairs, cols, role_pairs, split_adsb, fill, reference, slot_s, gap_s)
    if fill == "predict":
        _ = cols.track_inputs  # read here once, not by the threads
    # --fill predict builds each aircraft's predictors on the per-aircraft threads (their filter kernels
    # release the GIL); the windows are then correlated here, in aircraft order, as before
    for (callsign_label, address_label), aircraft_pairs in map_ordered(
            prepare, targets, threads=None if fill == "predict" else 1):
        found = [_correlate_pair((callsign_label, address_label), run, pair, slot_s, gap_s, reference, fill,
                                 budget)
                 for pair in aircraft_pairs]
        paired |= bool(found)
        if not all_aircraft and found and all(f is not None for f in found):
            raise found[0]
    if not paired:
        seen_by = None if all_aircraft else (callsign_label, address_label, sorted(cols.by_sensor(
            np.flatnonzero(cols.is_radar))))
        raise NoSuchAircraft("a sensor pair", [tested], [], _unpaired_message(pairs, seen_by))
    return run


def _unpaired_message(pairs: str, aircraft: tuple[str, str, list[str]] | None) -> str:
    """Why no sensor pair was found: for every aircraft (``aircraft`` None), or for the one asked for
    (call sign, address, the radars that saw it)."""
    wanted = {"radar-radar": "two radars", "radar-adsb": "radar and ADS-B",
              "mlat-adsb": "multilateration and ADS-B", "smr-mlat": "surface radar and multilateration"}.get(
        pairs, "two radars nor by radar and ADS-B")
    if aircraft is None:
        wanted = wanted.replace(" nor ", " or ")
        return f"no aircraft is seen by {wanted} (--pairs {pairs})"
    callsign, address, radars = aircraft
    who = " ".join(part for part in (callsign, f"(address {address})" if address else "") if part)
    noun = ROLE_NOUNS[PAIR_KINDS[pairs][0]]
    seen = f"only by {', '.join(radars)}" if radars else f"by no {noun}"
    return f"{who or 'the aircraft'} is not seen by {wanted} ({seen}) (--pairs {pairs})"
