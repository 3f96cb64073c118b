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

import numpy as np
import pandas as pd

UTC_DTYPE = "datetime64[ns, UTC]"
UNDATED_DAY = pd.Timestamp("1970-01-01", tz="UTC")
_UNDATED_END = pd.Timestamp("1971-01-01", tz="UTC")  # an undated recording spans days, never a year


def absolute_time(frame: pd.DataFrame, fallback_date: dt.date | None = None) -> pd.Series:
    """UTC instant of each decoded record: its ``timestamp``, else ``day``/``time_of_day`` counted from
    ``fallback_date`` (else from ``UNDATED_DAY``); NaT where the record has no time."""
    tod = frame["time_of_day"].to_numpy(float) if "time_of_day" in frame else np.full(len(frame), np.nan)
    day = frame["day"].to_numpy(float) if "day" in frame else np.zeros(len(frame))
    base = UNDATED_DAY if fallback_date is None else pd.Timestamp(fallback_date, tz="UTC")
    seconds = day * 86400.0 + tod
    ok = np.isfinite(seconds)
    ns = np.zeros(len(frame), dtype="int64")
    ns[ok] = np.rint(seconds[ok] * 1e9).astype("int64") + base.value
    out = pd.Series(pd.DatetimeIndex(ns.astype("datetime64[ns]")).tz_localize("UTC"), index=frame.index)
    out[~ok] = pd.NaT
    if "timestamp" in frame:
        stamps = frame["timestamp"]
        if isinstance(stamps.dtype, pd.DatetimeTZDtype):  # decoded frames: no per-row objects
            stamps = stamps.dt.tz_convert("UTC")
        else:
            stamps = pd.to_datetime(pd.Series(stamps.to_numpy(), index=frame.index), utc=True)
        out = stamps.where(stamps.notna(), out)
    return out.astype(UTC_DTYPE)


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


def iso_utc(instant) -> str | None:
    """ISO 8601 UTC text with milliseconds and "Z"; None when missing or undated."""
    if instant is None or pd.isna(instant):
        return None
    ts = pd.Timestamp(instant)
    ts = ts.tz_localize("UTC") if ts.tzinfo is None else ts.tz_convert("UTC")
    if not is_dated(ts):
        return None
    return ts.isoformat(timespec="milliseconds").replace("+00:00", "Z")


def with_clock(meas: pd.DataFrame, reference: pd.Timestamp | None = None) -> pd.DataFrame:
    """Measurements with the derived thesis columns: ``time_of_day`` (s since ``reference``, default the
    midnight of the earliest time) and ``timestamp`` (``time`` where dated, else NaT)."""
    ref = reference if reference is not None else midnight(meas["time"])
    tod = seconds_since(meas["time"], ref) if ref is not None else np.full(len(meas), np.nan)
    return meas.assign(time_of_day=tod, timestamp=dated_or_nat(meas["time"]))
