"""Days and timestamps: a recording's reports on one continuous time line, across midnight.

Raw streams and ORADIS files count midnights in file order (a drop of more than 12 h is a new day);
containers with capture times put each report on the day nearest its capture time.
"""

from __future__ import annotations

import datetime as dt

import numpy as np
import pandas as pd

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


def file_order_days(frames: dict[int, dict], day: int | None = None,
                    last_tod: float = np.nan) -> tuple[int, float]:
    """Set each category's ``day`` by counting midnights in file order from the clock ``(day, last_tod)``
    the reports before them left (a drop of more than 12 h is a new day, a rise of more than 12 h a late
    report from the day before); return the clock after them, so that chunks continue it exactly.
    ``day`` None: these are the whole file's first reports, day 0 anchored by ``first_report_day``."""
    parts = [f for f in frames.values() if len(f["offset"])]
    if not parts:
        return (0 if day is None else day), last_tod
    order, t = _file_order(parts)
    if day is None:
        day = first_report_day(t[np.isfinite(t)])
    t = pd.Series(np.concatenate([[last_tod], t])).ffill().bfill().to_numpy()
    d = np.diff(t)
    day_sorted = day + np.cumsum(d < -43200) - np.cumsum(d > 43200)
    days = np.empty_like(day_sorted)
    days[order] = day_sorted
    i = 0
    for f in parts:
        n = len(f["offset"])
        f["day"] = days[i:i + n].astype(np.int64)
        i += n
    return int(day_sorted[-1]), float(t[-1])


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
