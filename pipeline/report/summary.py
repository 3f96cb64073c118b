"""Plain-data views of a CorrelationRun: the JSON summary and the fixed-width stdout table."""

from __future__ import annotations

import datetime as dt
import json
import math
import os
import uuid
from collections.abc import Callable, Mapping
from numbers import Integral, Real
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from pipeline.correlate.results import SUMMARY_KEYS, CorrelationRun, WindowResult

SKIPPED_KEYS = ["callsign", "address", "start_tod", "end_tod", "reason"]
# Parameter names (top level or under "options") that may hold the slot length in seconds
_SLOT_PARAMETER_KEYS = ("slot_s", "slot_seconds", "slot_duration_s", "slot_length_s", "slot_size_s")


def is_missing(value: Any) -> bool:
    """True for None, NaN, NaT and pd.NA (scalars only)."""
    if value is None or value is pd.NA or value is pd.NaT:
        return True
    if isinstance(value, float | np.floating):
        return math.isnan(value)
    if isinstance(value, np.datetime64 | np.timedelta64):
        return bool(np.isnat(value))
    return False


def utc_naive(value: pd.Timestamp | dt.datetime | np.datetime64 | str) -> dt.datetime | None:
    """A UTC wall-clock datetime without tzinfo (naive input is taken as UTC); None when missing."""
    if is_missing(value):
        return None
    ts = pd.Timestamp(value)
    if ts.tzinfo is not None:
        ts = ts.tz_convert("UTC").tz_localize(None)
    return ts.round("us").to_pydatetime()


def json_value(value: Any) -> Any:
    """Convert ``value`` to plain JSON types: NaN/NaT/NA and infinities become None, times ISO 8601 UTC."""
    if is_missing(value):
        return None
    if isinstance(value, bool | np.bool_):
        return bool(value)
    if isinstance(value, pd.Timestamp | dt.datetime | np.datetime64):
        ts = pd.Timestamp(value)
        ts = ts.tz_convert("UTC") if ts.tzinfo is not None else ts.tz_localize("UTC")
        return ts.isoformat().replace("+00:00", "Z")
    if isinstance(value, dt.date | dt.time):
        return value.isoformat()
    if isinstance(value, pd.Timedelta | dt.timedelta | np.timedelta64):  # before Integral: timedelta64 is one
        return pd.Timedelta(value).total_seconds()
    if isinstance(value, Integral):
        return int(value)
    if isinstance(value, Real):
        number = float(value)
        return number if math.isfinite(number) else None
    if isinstance(value, str):
        return value
    if isinstance(value, Path):
        return str(value)
    if isinstance(value, Mapping):
        return {str(k): json_value(v) for k, v in value.items()}
    if isinstance(value, np.ndarray | pd.Series | list | tuple | set | frozenset):
        items = sorted(value, key=str) if isinstance(value, set | frozenset) else value
        return [json_value(v) for v in items]
    return str(value)


def window_summary(window: WindowResult) -> dict[str, Any]:
    """The window's summary restricted to SUMMARY_KEYS, in order, as JSON values (absent keys -> None)."""
    return {key: json_value(window.summary.get(key)) for key in SUMMARY_KEYS}


def run_to_json(run: CorrelationRun) -> dict[str, Any]:
    """The run as a JSON-ready dict: windows, skipped windows, parameters, inputs and filters."""
    return {
        "windows": [window_summary(w) for w in run.windows],
        "skipped": [{key: json_value(getattr(s, key)) for key in SKIPPED_KEYS} for s in run.skipped],
        "parameters": json_value(run.parameters),
        "inputs": json_value(run.inputs),
        "filters": json_value(run.filters),
    }


def write_atomically(path: str | os.PathLike[str], write: Callable[[Path], object]) -> Path:
    """Call ``write(tmp)`` on a sibling temporary file, then move it over ``path``; returns ``path``."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.{uuid.uuid4().hex[:8]}.tmp")
    try:
        write(tmp)
        os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)
    return path


def write_json(run: CorrelationRun, path: str | os.PathLike[str]) -> Path:
    """Write ``run_to_json(run)`` to ``path`` (UTF-8, indented, strict JSON); returns the path."""
    text = json.dumps(run_to_json(run), indent=2, ensure_ascii=False, allow_nan=False) + "\n"
    return write_atomically(path, lambda tmp: tmp.write_text(text, encoding="utf-8"))


def slot_seconds(window: WindowResult, parameters: Mapping[str, Any] | None = None) -> float:
    """Slot length in seconds: from the slots' time_of_day spacing, else from the parameters, else NaN."""
    slots = window.slots
    if {"slot", "time_of_day"} <= set(slots.columns) and len(slots) > 1:
        slot = pd.to_numeric(slots["slot"], errors="coerce").to_numpy(dtype=float, na_value=np.nan)
        tod = pd.to_numeric(slots["time_of_day"], errors="coerce").to_numpy(dtype=float, na_value=np.nan)
        ok = np.isfinite(slot) & np.isfinite(tod)
        dslot, dtod = np.diff(slot[ok]), np.diff(tod[ok])
        step = dtod[dslot != 0] / dslot[dslot != 0]
        step = step[np.isfinite(step) & (step > 0)]
        if step.size:
            return float(np.median(step))
    for source in (parameters or {}, (parameters or {}).get("options") or {}):
        for key in _SLOT_PARAMETER_KEYS:
            value = source.get(key) if isinstance(source, Mapping) else None
            if isinstance(value, Real) and not isinstance(value, bool) and value > 0:
                return float(value)
    return math.nan


def printable(text: Any) -> str:
    """``text`` as one printable line: control characters escaped, missing values empty."""
    if is_missing(text):
        return ""
    return "".join(c if c.isprintable() else c.encode("unicode_escape").decode("ascii") for c in str(text))


def _clock(timestamp: Any, tod: Any) -> str:
    """HH:MM:SS.s UTC rounded to 0.1 s, from the time of day (+Nd past the first day), else the timestamp."""
    seconds = None
    if not is_missing(tod) and isinstance(tod, Real):
        seconds = float(tod)
    else:
        try:
            moment = utc_naive(timestamp)
        except (TypeError, ValueError):
            moment = None
        if moment is not None:
            seconds = moment.hour * 3600 + moment.minute * 60 + moment.second + moment.microsecond / 1e6
    if seconds is None:
        return "-"
    tenths = int(round(seconds * 10))
    days, tenths = divmod(tenths, 864000)
    hours, tenths = divmod(tenths, 36000)
    minutes, tenths = divmod(tenths, 600)
    text = f"{hours:02d}:{minutes:02d}:{tenths // 10:02d}.{tenths % 10}"
    return text + (f"+{days}d" if days else "")


def _num(value: Any, decimals: int) -> str:
    if is_missing(value) or not isinstance(value, Real) or not math.isfinite(float(value)):
        return "-"
    return f"{float(value):.{decimals}f}"


def _count(value: Any) -> str:
    return "-" if is_missing(value) or not isinstance(value, Real) else f"{int(value)}"


def summary_table(run: CorrelationRun) -> str:
    """A fixed-width text table, one line per window, for printing after a run."""
    header = ["callsign", "window", "sensors", "start", "end", "slots", "radar b>a", "adsb b>a",
              "ncc0_lat", "ncc0_lon", "pearson0_lat", "pearson0_lon", "sep_rms_m"]
    right = [False, True, False, True, True, True, True, True, True, True, True, True, True]
    rows = []
    for w in run.windows:
        s = w.summary
        rows.append([
            printable(s.get("callsign")) or "-",
            printable(s.get("window")) or "-",
            f"{printable(s.get('radar_sensor')) or '-'} vs {printable(s.get('reference_sensor')) or '-'}",
            _clock(s.get("start"), s.get("start_tod")),
            _clock(s.get("end"), s.get("end_tod")),
            _count(s.get("slots")),
            f"{_count(s.get('radar_before'))}>{_count(s.get('radar_after'))}",
            f"{_count(s.get('adsb_before'))}>{_count(s.get('adsb_after'))}",
            _num(s.get("ncc0_lat"), 10), _num(s.get("ncc0_lon"), 10),
            _num(s.get("pearson0_lat"), 6), _num(s.get("pearson0_lon"), 6),
            _num(s.get("sep_rms_m"), 1),
        ])
    widths = [max(len(r[i]) for r in [header, *rows]) for i in range(len(header))]

    def line(cells: list[str]) -> str:
        padded = (c.rjust(n) if r else c.ljust(n) for c, n, r in zip(cells, widths, right, strict=True))
        return "  ".join(padded)

    lines = [line(header), "  ".join("-" * n for n in widths), *(line(r) for r in rows)]
    lines.append(f"{len(run.windows)} window(s) correlated, {len(run.skipped)} skipped")
    return "\n".join(text.rstrip() for text in lines)
