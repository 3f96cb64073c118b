"""Days and timestamps: a recording's reports on one continuous time line, across midnight.

Raw streams and ORADIS files count midnights in file order (a drop of more than 12 h is a new day);
containers with capture times put each report on the day nearest its capture time.
"""

from __future__ import annotations

import datetime as dt
from dataclasses import dataclass, field

import numpy as np
import pandas as pd
from numba import njit

from .containers import UNTIMED, Segments


def known_captures(seg: Segments) -> tuple[np.ndarray | None, np.ndarray | None]:
    """Capture day and time of each segment, an untimed one (pcapng Simple Packet Block) taking the
    nearest timed segment before it in file order (after it when none is before); None when none is timed."""
    known = (seg.capture_day >= 0) & np.isfinite(seg.capture_tod) if len(seg.start) else np.zeros(0, bool)
    if not known.any():
        return None, None
    if known.all():
        return seg.capture_day, seg.capture_tod
    order = np.argsort(seg.start, kind="stable")
    timed = known[order]
    at = np.maximum.accumulate(np.where(timed, np.arange(len(order)), -1))  # last timed one so far
    at[at < 0] = np.flatnonzero(timed)[0]
    pick = np.empty_like(order)
    pick[order] = order[at]
    return seg.capture_day[pick], seg.capture_tod[pick]


def assign_days(frames: dict[int, dict], seg: Segments, blk_seg: np.ndarray) -> int | None:
    """Add the ``day`` column to each category's columns: days after the first report's in file order
    (raw streams), after the earliest report's (containers with capture times); return the container's
    day number of day 0 (days since 1970 when ``seg.dated``), None for raw streams."""
    parts = [(c, f) for c, f in frames.items() if len(f["offset"])]
    if not parts:
        for f in frames.values():
            f["day"] = np.zeros(0, np.int64)
        return None
    capture_day, capture_tod = known_captures(seg)
    if seg.format in UNTIMED or not len(seg.start) or capture_day is None:
        file_order_days(frames)
        first_day = None
    else:
        # container capture time: the day that puts the report nearest its capture
        all_days = []
        for _, f in parts:
            s = blk_seg[np.asarray(f["block"])]
            cday, ctod = capture_day[s], capture_tod[s]
            tod = np.asarray(f["time_of_day"])
            tod = np.where(np.isnan(tod), ctod, tod)
            all_days.append(cday + np.rint((ctod - tod) / 86400.0).astype(np.int64))
        first_day = int(min(a.min() for a in all_days))
        for (_, f), a in zip(parts, all_days, strict=True):
            f["day"] = a - first_day
    for f in frames.values():
        if "day" not in f:
            f["day"] = np.zeros(len(f["offset"]), np.int64)
    return first_day


# Day 0 of a raw stream is the day of its first report that agrees with the reports after it: a first
# report whose time of day was damaged (one bit of I048/140 moves it by 65536 s) re-dated all the others.
ANCHOR_AGREE_S = 3600.0  # agreeing: within this on the 24 h clock (86398 s and 2 s are 4 s apart)
ANCHOR_FOLLOWERS = 8  # of the next this many valid times of day, at least half
ANCHOR_CANDIDATES = 16  # the first this many are tried; none agreeing: the first report is day 0
ANCHOR_REPORTS = ANCHOR_CANDIDATES + ANCHOR_FOLLOWERS  # valid times of day that settle it


def _file_order(parts: list[dict]) -> tuple[np.ndarray, np.ndarray]:
    """The reports' order by offset, and their times of day in that order (NaN outside 0-86400 s)."""
    off = np.concatenate([np.asarray(f["offset"]) for f in parts])
    tod = np.concatenate([np.asarray(f["time_of_day"], dtype=float) for f in parts])
    order = np.argsort(off, kind="stable")
    t = tod[order]
    # a time of day outside 0-86400 s (damaged: I048/140 and I021/071-073 reach 131072 s) is no
    # evidence of a midnight; left in, one such report put every other report on another day
    return order, np.where((t >= 0.0) & (t < 86400.0), t, np.nan)


def valid_times(frames: dict[int, dict]) -> np.ndarray:
    """The reports' times of day in file order, those within 0-86400 s only (what anchors day 0)."""
    parts = [f for f in frames.values() if len(f["offset"])]
    if not parts:
        return np.zeros(0)
    t = _file_order(parts)[1]
    return t[np.isfinite(t)]


def first_report_day(tod_s: np.ndarray) -> int:
    """The day of the first of these valid times of day (file order) that puts on day 0 the first one
    within ANCHOR_AGREE_S (24 h clock) of at least half its next ANCHOR_FOLLOWERS; 0 when none is."""
    head = np.asarray(tod_s, dtype=float)[:ANCHOR_REPORTS]
    anchor = 0  # the last report has no follower to agree with: never chosen over the first
    for i in range(min(ANCHOR_CANDIDATES, len(head) - 1)):
        after = head[i + 1:i + 1 + ANCHOR_FOLLOWERS]
        apart = np.abs((after - head[i] + 43200.0) % 86400.0 - 43200.0)
        if 2 * int((apart <= ANCHOR_AGREE_S).sum()) >= len(after):
            anchor = i
            break
    d = np.diff(head[:anchor + 1])
    return -int((d < -43200).sum() - (d > 43200).sum())


# Counting midnights in file order, a report at a time, dates each report against the last report that
# agreed with those before it (within ANCHOR_AGREE_S of at least half of the ANCHOR_FOLLOWERS valid times
# of day before it): damaged records that walk (random bytes read as times of day) neither count a midnight
# nor become what the next reports are dated against (one such run moved 2,230 reports of intact blocks to
# the next day: benchmarks/fuzz_reader.py, seed 99).
HALF_DAY_S = 43200.0


@dataclass(frozen=True)
class DayClock:
    """Where counting midnights in file order stands after some reports, for the reports after them: the day
    and time of day of the last report that agreed with those before it (the reference the next ones are
    dated against), the last ANCHOR_FOLLOWERS valid times of day (what the next ones must agree with), and
    the day of the last valid report (what the reports without a valid time after it take)."""

    day: int
    ref_tod_s: float = np.nan
    recent_s: np.ndarray = field(default_factory=lambda: np.zeros(0))
    last_day: int | None = None


def _steps(step_s: np.ndarray) -> np.ndarray:
    """Midnights crossed by each step between two times of day: +1 for a drop of more than 12 h, -1 for a
    rise of more than 12 h (a late report from the day before), 0 otherwise or for NaN."""
    return (step_s < -HALF_DAY_S).astype(np.int64) - (step_s > HALF_DAY_S).astype(np.int64)


@njit(cache=True, nogil=True)
def _day_count(tod_s, recent_s, ref_s, day):
    """count_days's pass over valid times of day in file order: (each one's day, the day and time of the last
    agreeing one after them, the first agreeing one's time, NaN when none agreed)."""
    k = ANCHOR_FOLLOWERS
    ring = np.empty(k)
    held = 0
    for x in recent_s[-k:]:
        ring[held % k] = x
        held += 1
    days = np.empty(tod_s.shape[0], np.int64)
    first_s = np.nan
    for i in range(tod_s.shape[0]):
        t = tod_s[i]
        known = min(held, k)
        close = 0
        for j in range(known):  # on the 24 h clock: valid times are 0-86400 s, so one fold is enough
            apart = abs(t - ring[j])
            if min(apart, 86400.0 - apart) <= ANCHOR_AGREE_S:
                close += 1
                if 2 * close >= known:
                    break
        d = day
        if ref_s == ref_s:  # not NaN: the day nearest the last agreeing report
            if t - ref_s < -HALF_DAY_S:
                d += 1
            elif t - ref_s > HALF_DAY_S:
                d -= 1
        if known == 0 or 2 * close >= known:  # agrees: midnights counted from it on
            day, ref_s = d, t
            if first_s != first_s:
                first_s = t
        days[i] = d
        ring[held % k] = t
        held += 1
    return days, day, ref_s, first_s


def count_days(tod_s: np.ndarray, clock: DayClock) -> tuple[np.ndarray, DayClock]:
    """The day of each valid time of day (file order) after ``clock``, and the clock after them: the reports
    that agree with the ANCHOR_FOLLOWERS before them (within ANCHOR_AGREE_S of at least half) count midnights
    between them (a drop or rise of more than 12 h); every report takes the day that puts it nearest the last
    agreeing report at or before it."""
    tod_s = np.ascontiguousarray(tod_s, dtype=float)
    recent = np.ascontiguousarray(clock.recent_s, dtype=float)
    days, day, ref_s, _ = _day_count(tod_s, recent, float(clock.ref_tod_s), int(clock.day))
    after = DayClock(int(day), float(ref_s), np.concatenate([recent, tod_s])[-ANCHOR_FOLLOWERS:].copy(),
                     int(days[-1]) if len(days) else clock.last_day)
    return days, after


def agreed_run(tod_s: np.ndarray, before_s: np.ndarray) -> tuple[float, float, int]:
    """Of these valid times of day, after ``before_s`` and no agreeing report: the first and last that agree
    with those before them and the midnights between them (what stream.WindowClock keeps of a window)."""
    _, day, last_s, first_s = _day_count(np.ascontiguousarray(tod_s, dtype=float),
                                         np.ascontiguousarray(before_s, dtype=float), np.nan, 0)
    return float(first_s), float(last_s), int(day)


def file_order_days(frames: dict[int, dict], clock: DayClock | None = None) -> DayClock:
    """Set each category's ``day`` by counting midnights in file order after ``clock`` (count_days; a report
    without a valid time of day takes the day of the valid one before it, at the very start the one after
    it); return the clock after them, so that chunks continue it exactly. ``clock`` None: these are the whole
    file's first reports, day 0 anchored by ``first_report_day``."""
    parts = [f for f in frames.values() if len(f["offset"])]
    if not parts:
        return clock if clock is not None else DayClock(0)
    order, t = _file_order(parts)
    valid = np.isfinite(t)
    if clock is None:
        clock = DayClock(first_report_day(t[valid]))
    valid_days, after = count_days(t[valid], clock)
    if valid.all():
        day_sorted = valid_days
    else:
        day_sorted = np.full(len(t), np.nan)
        day_sorted[valid] = valid_days
        filled = pd.Series(day_sorted).ffill()
        if clock.last_day is not None:
            filled = filled.fillna(clock.last_day)
        day_sorted = filled.bfill().fillna(clock.day).to_numpy()
    days = np.empty(len(t), np.int64)
    days[order] = day_sorted.astype(np.int64)
    i = 0
    for f in parts:
        n = len(f["offset"])
        f["day"] = days[i:i + n]
        i += n
    return after


def timestamp_index(day, tod, date: dt.date | None) -> pd.DatetimeIndex:
    """UTC timestamps from day offsets and times of day (NaT when the date or the time is unknown)."""
    day, tod = np.asarray(day), np.asarray(tod)
    if date is None:
        return pd.DatetimeIndex(np.full(len(day), np.datetime64("NaT"), "datetime64[ns]")).tz_localize("UTC")
    ns = np.rint((day * 86400.0 + tod) * 1e9)
    missing = np.isnan(ns)
    vals = np.datetime64(date, "ns") + np.where(missing, 0, ns).astype("timedelta64[ns]")
    vals[missing] = np.datetime64("NaT")
    return pd.DatetimeIndex(vals).tz_localize("UTC")


def restamp(frames: dict[int, pd.DataFrame], date: dt.date | None) -> None:
    """Recompute the timestamp column of finished frames (after a day shift)."""
    for f in frames.values():
        f["timestamp"] = timestamp_index(f["day"], f["time_of_day"], date)
