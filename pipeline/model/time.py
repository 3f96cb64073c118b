"""One time axis: absolute UTC instants (tz-aware), and the thesis's seconds-of-day derived from them.

Measurements carry ``time`` (datetime64[ns, UTC]). A recording without a date (a raw or "final" file
read without ``--date``) is placed on ``UNDATED_DAY`` (1970-01-01, a day no surveillance recording
has; its later days follow), so its instants keep their order and differences; anything before 1971
is undated. ``is_dated`` tells them apart and reports
show such times as time of day only. Seconds since a reference midnight are computed here and only
here, exactly for times that are multiples of 1/128 s (the ASTERIX time LSB).
"""

from __future__ import annotations

import datetime as dt
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

UTC_DTYPE = "datetime64[ns, UTC]"
UNDATED_DAY = pd.Timestamp("1970-01-01", tz="UTC")
_UNDATED_END = pd.Timestamp("1971-01-01", tz="UTC")  # an undated recording spans days, never a year
NAT_NS = np.iinfo("int64").min  # NaT as int64 nanoseconds


def absolute_time(frame: pd.DataFrame, fallback_date: dt.date | None = None) -> pd.Series:
    """UTC instant of each decoded record: its ``timestamp``, else ``day``/``time_of_day`` counted from
    ``fallback_date`` (else from ``UNDATED_DAY``); NaT where the record has no time, or a time of day
    outside 0-24 h (damaged bytes: 130,000 s made a time the next day, stretching every span)."""
    tod = frame["time_of_day"].to_numpy(float) if "time_of_day" in frame else np.full(len(frame), np.nan)
    bad = impossible_time_of_day(tod)
    tod = np.where(bad, np.nan, tod)
    day = frame["day"].to_numpy(float) if "day" in frame else np.zeros(len(frame))
    base = UNDATED_DAY if fallback_date is None else pd.Timestamp(fallback_date, tz="UTC")
    seconds = day * 86400.0 + tod
    ok = np.isfinite(seconds)
    ns = np.full(len(frame), NAT_NS, dtype="int64")
    ns[ok] = np.rint(seconds[ok] * 1e9).astype("int64") + base.value
    if "timestamp" in frame:  # int64 nanoseconds throughout: no object array of Timestamps
        stamps = pd.DatetimeIndex(pd.to_datetime(frame["timestamp"], utc=True)).as_unit("ns").asi8
        ns = np.where((stamps != NAT_NS) & ~bad, stamps, ns)
    return pd.Series(pd.DatetimeIndex(ns.view("datetime64[ns]")).tz_localize("UTC"), index=frame.index)


def impossible_time_of_day(tod_s: np.ndarray) -> np.ndarray:
    """Whether each time of day (s; NaN: none) lies outside 0-24 h, which no real report's does."""
    tod_s = np.asarray(tod_s, float)
    with np.errstate(invalid="ignore"):
        return (tod_s < 0.0) | (tod_s >= 86400.0)


def midnight(times: pd.Series) -> pd.Timestamp | None:
    """Midnight UTC of the earliest instant (the reference of the thesis's seconds-of-day); None if empty."""
    t = times.dropna()
    return t.min().floor("D") if len(t) else None


def seconds_since(times: pd.Series, reference: pd.Timestamp) -> np.ndarray:
    """Seconds from ``reference`` to each instant (float64, NaN for NaT), above 86400 after midnight."""
    t = pd.DatetimeIndex(times)
    ns = t.asi8 - reference.value
    out = ns.astype("float64") / 1e9
    out[t.isna()] = np.nan
    return out


def is_dated(instant: pd.Timestamp | None) -> bool:
    """False for times placed on ``UNDATED_DAY`` (the recording had no date) and for None/NaT."""
    return instant is not None and not pd.isna(instant) and instant.value >= _UNDATED_END.value


def dated_or_nat(times: pd.Series) -> pd.Series:
    """The instants where the recording was dated, NaT where it was not (for reports)."""
    t = pd.DatetimeIndex(times)
    t = t.tz_localize("UTC") if t.tz is None else t.tz_convert("UTC")
    keep = t.asi8 >= _UNDATED_END.value  # NaT is the smallest int64: dropped too
    return pd.Series(t.array, index=times.index).where(keep).astype(UTC_DTYPE)


def clock(seconds: float) -> str:
    """HH:MM:SS of seconds since midnight of the first day (with "+Nd " past it); "-" when missing."""
    if not np.isfinite(seconds):
        return "-"
    day, rem = divmod(int(seconds // 1), 86400)
    text = f"{rem // 3600:02d}:{rem % 3600 // 60:02d}:{rem % 60:02d}"
    return f"+{day}d {text}" if day else text


def utc_text(instant) -> str:
    """ISO 8601 UTC text to the millisecond (truncated) with "Z", the one time format of msdc's JSON; a
    naive instant is taken as UTC."""
    ts = pd.Timestamp(instant)
    ts = ts.tz_localize("UTC") if ts.tzinfo is None else ts.tz_convert("UTC")
    return ts.isoformat(timespec="milliseconds").replace("+00:00", "Z")


def iso_utc(instant) -> str | None:
    """``utc_text``; None when missing or undated."""
    if instant is None or pd.isna(instant) or not is_dated(pd.Timestamp(instant)):
        return None
    return utc_text(instant)


def with_clock(meas: pd.DataFrame, reference: pd.Timestamp | None = None) -> pd.DataFrame:
    """Measurements with the derived thesis columns: ``time_of_day`` (s since ``reference``, default the
    midnight of the earliest time) and ``timestamp`` (``time`` where dated, else NaT)."""
    ref = reference if reference is not None else midnight(meas["time"])
    tod = seconds_since(meas["time"], ref) if ref is not None else np.full(len(meas), np.nan)
    return meas.assign(time_of_day=tod, timestamp=dated_or_nat(meas["time"]))


# A raw stream's day 0 is its first report's day (asterix.timeline): a recording started at midnight whose
# first few plots are stamped just before it starts the day before, and --date then names that day.
EARLY_START_S = 300.0  # reports before the file's first midnight all within this of it
EARLY_START_SHARE = 0.01  # and at most this share of the input's reports
JUMP_SAMPLE = 64  # every this many reports of a category one is kept for the time line (a month's input
# keeps ~1/64 of its reports' times)
JUMP_SMOOTH = 5  # the kept times in file order, each the median of this many in a row: damaged records read
# as random times of day stand alone and move no median
# a step of the median time in file order said: a silence this long (the bundled fixtures' 2 h is not: a
# night's silence of an ADS-B station is), or going back this far (late plots are seconds late; parts of a
# recording laid out of order)
JUMP_FORWARD_S = 6 * 3600.0
JUMP_BACK_S = 600.0
JUMPS_LISTED = 3


def _hm(time_s: float) -> str:
    """A time of day to the minute (the medians of report groups stand for them only to the minute)."""
    t = int(time_s) % 86400
    return f"{t // 3600:02d}:{t % 3600 // 60:02d}"


def _jump_words(step_s: float, fmt: str) -> str:
    """What a step of ``step_s`` in a raw stream's time line means, and what else it could be (about: from
    the medians of report groups)."""
    hours, other = abs(step_s) / 3600.0, (86400.0 - abs(step_s)) / 3600.0
    undated = f"a {fmt} recording carries no date, so had"
    if step_s > 0:
        return (f"read as about {hours:.1f} h later (a silence); {undated} its parts been laid out of order "
                f"(about {other:.1f} h earlier) or the silence been about {hours + 24:.1f} h, the later "
                "reports' day is wrong")
    return (f"read as about {hours:.1f} h earlier (reports laid out of order); {undated} it been silent for "
            f"about {other:.1f} h instead, the later reports' day is wrong")


@dataclass
class DayTally:
    """Per input, chunk by chunk: the reports before the file's first midnight (day <= 0), the earliest
    time of day among them, and the reports after it, to tell a day 0 that is only a few late plots."""

    before: int = 0
    earliest_tod_s: float = np.inf
    after: int = 0
    # each category's time line: every JUMP_SAMPLE-th report's byte offset and time (s from day 0), chunk
    # by chunk (a category apiece: one file may hold one recording's categories one after the other)
    sample_categories: list[np.ndarray] = field(default_factory=list)
    sample_offsets: list[np.ndarray] = field(default_factory=list)
    sample_times_s: list[np.ndarray] = field(default_factory=list)

    def add(self, frames: dict) -> None:
        for category, frame in frames.items():
            if not len(frame) or "day" not in frame:
                continue
            day = np.asarray(frame["day"])
            tod = np.asarray(frame["time_of_day"], dtype=float)
            first = day <= 0
            self.before += int(first.sum())
            self.after += int((~first).sum())
            if first.any():
                self.earliest_tod_s = min(self.earliest_tod_s, float(np.nanmin(tod[first], initial=np.inf)))
            if "offset" in frame:
                times = day[::JUMP_SAMPLE] * 86400.0 + tod[::JUMP_SAMPLE]
                keep = np.isfinite(times)
                self.sample_categories.append(np.full(int(keep.sum()), int(category)))
                self.sample_offsets.append(np.asarray(frame["offset"])[::JUMP_SAMPLE][keep].astype(np.int64))
                self.sample_times_s.append(times[keep])

    def jumps(self) -> pd.DataFrame:
        """Steps of each category's time line in file order (chunks may come in any order: ingest's
        workers) over JUMP_FORWARD_S, or back over JUMP_BACK_S, in file order: the category, the byte offset
        of the first kept report after the step, the smoothed times (s from day 0) before and after it, and
        the step. Per category: a file of one hour's CAT048 then the same hour's CAT021 has no jump."""
        columns = ["category", "offset", "from_s", "to_s", "step_s"]
        if not self.sample_offsets:
            return pd.DataFrame(columns=columns)
        categories = np.concatenate(self.sample_categories)
        offsets, times = np.concatenate(self.sample_offsets), np.concatenate(self.sample_times_s)
        parts = []
        for category in np.unique(categories):
            own = categories == category
            order = np.argsort(offsets[own], kind="stable")
            at_offset, line = offsets[own][order], times[own][order]
            if len(line) >= JUMP_SMOOTH:
                padded = np.pad(line, JUMP_SMOOTH // 2, mode="reflect")  # a damaged first one stays alone
                line = np.median(np.lib.stride_tricks.sliding_window_view(padded, JUMP_SMOOTH), axis=1)
            step = np.diff(line)
            at = np.flatnonzero((step > JUMP_FORWARD_S) | (step < -JUMP_BACK_S))
            parts.append(pd.DataFrame({"category": int(category), "offset": at_offset[at + 1],
                                       "from_s": line[at], "to_s": line[at + 1], "step_s": step[at]}))
        if not parts:  # chunks whose sampled reports had no time
            return pd.DataFrame(columns=columns)
        return pd.concat(parts, ignore_index=True).sort_values("offset", kind="stable").reset_index(drop=True)

    def jump_warnings(self, name: str, fmt: str | None) -> list[str]:
        """Per step of a raw stream's (or ORADIS file's) time line (jumps): where, and the other reading
        the day rule (a drop over 12 h is a midnight, a rise a day back) could not tell it from."""
        if fmt not in ("raw", "oradis"):
            return []
        found = self.jumps()
        out = [f"{name}: the time of day of its CAT{r.category:03d} reports jumps from about {_hm(r.from_s)} "
               f"to about {_hm(r.to_s)} near byte {r.offset}: "
               f"{_jump_words(r.step_s, fmt)}" for r in found.head(JUMPS_LISTED).itertuples()]
        if len(found) > JUMPS_LISTED:
            out.append(f"{name}: and {len(found) - JUMPS_LISTED} more such jump(s) of its time of day")
        return out

    def warning(self, name: str, date: dt.date | None, fmt: str | None) -> list[str]:
        """The time line's jumps (jump_warnings), and a warning when ``date`` (given for a raw stream or
        ORADIS file) names a first day that holds only a few plots stamped in the last minutes before
        midnight, the rest of the recording the day after."""
        return [*self.jump_warnings(name, fmt), *self._first_day_warning(name, date, fmt)]

    def _first_day_warning(self, name: str, date: dt.date | None, fmt: str | None) -> list[str]:
        if date is None or fmt not in ("raw", "oradis") or not self.before or not self.after:
            return []
        if self.earliest_tod_s < 86400.0 - EARLY_START_S or self.before > EARLY_START_SHARE * (
                self.before + self.after):
            return []
        t = int(self.earliest_tod_s)
        hms = f"{t // 3600:02d}:{t % 3600 // 60:02d}:{t % 60:02d}"
        return [f"{name}: its first {self.before} report(s) are stamped from {hms} to midnight and the other "
                f"{self.after} follow it: --date {date} names the day of a raw stream's first report, so the "
                f"rest are on {date + dt.timedelta(days=1)}; if the recording is of {date}, give --date "
                f"{date - dt.timedelta(days=1)}"]


def utc_frame(frame: pd.DataFrame, columns: list[str], name: str) -> pd.DataFrame:
    """The frame with its time columns in UTC: time-zone-aware datetimes converted exactly, an empty
    column as it is; TypeError naming the frame and column for anything else (naive datetimes, strings,
    numbers), which cannot be compared with the UTC times of the other tables."""
    out = frame
    for c in columns:
        dtype = frame[c].dtype
        if isinstance(dtype, pd.DatetimeTZDtype):
            if str(dtype.tz) != "UTC":
                out = out.copy() if out is frame else out
                out[c] = frame[c].dt.tz_convert("UTC")
        elif len(frame):
            naive = pd.api.types.is_datetime64_dtype(dtype)
            hint = ("naive datetimes: localise them, .dt.tz_localize('UTC')" if naive
                    else f"dtype {dtype}: convert with pd.to_datetime(..., utc=True)")
            raise TypeError(f"{name}: column {c!r} must hold time-zone-aware UTC datetimes, got {hint}")
    return out
