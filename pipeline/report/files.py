"""Writing one output file: the one JSON writer (``write_json``: strict JSON, one time format) and the one
CSV writer (``write_csv``: formula-like text guarded); an error names the file (``named``)."""

from __future__ import annotations

import contextlib
import datetime as dt
import json
import math
import os
import re
from collections.abc import Iterator, Mapping
from numbers import Integral, Real
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from msdc.pipeline.model.sources import escaped
from msdc.pipeline.model.time import utc_text
from msdc.pipeline.report.textguard import guard_frame

_ERRNO_IN_TEXT = re.compile(r"\[errno (\d+)\]", re.IGNORECASE)  # pyarrow's "Detail: [errno 28] ..."


CSV_TIME = "%Y-%m-%dT%H:%M:%S.%fZ"  # ISO 8601 UTC to the microsecond: what every CSV output writes


@contextlib.contextmanager
def named(path: str | os.PathLike[str], instead_of: str | os.PathLike[str] | None = None) -> Iterator[None]:
    """Writing ``path``: an OSError that names no file (pyarrow's, Pillow's, a zip's on a full disk), or
    names ``instead_of``, is raised again naming ``path``, with the system's message for its error number."""
    try:
        yield
    except OSError as exc:
        other = instead_of is None or os.fspath(exc.filename) != os.fspath(instead_of)
        if exc.filename is not None and other:
            raise
        found = _ERRNO_IN_TEXT.search(str(exc))
        code = exc.errno or (int(found.group(1)) if found else None)
        message = os.strerror(code) if code else (exc.strerror or str(exc))
        raise OSError(code, message, os.fspath(path)) from exc


def write_json(doc: Any, path: str | os.PathLike[str]) -> Path:
    """``doc`` as strict JSON (``json_value``: no NaN, times ISO 8601 UTC to the millisecond with Z), UTF-8,
    indented by 2, with a final newline; an error names ``path``. Returns ``path``."""
    text = json.dumps(json_value(doc), indent=2, ensure_ascii=False, allow_nan=False) + "\n"
    text = escaped(text, "\\\\")  # a lone surrogate (a file name's bytes that are not UTF-8) as its escape
    path = Path(path)
    with named(path):
        path.write_text(text, encoding="utf-8")
    return path


def write_csv(frame: pd.DataFrame, path: str | os.PathLike[str], *, append: bool = False,
              decimals: Mapping[str, int] | None = None) -> Path:
    """``frame`` as CSV without its index (``append``: its rows added, no header): text a spreadsheet would
    run as a formula behind an apostrophe (textguard.guard_frame), date-times as ISO 8601 UTC (CSV_TIME;
    naive ones taken as UTC), the float columns named in ``decimals`` rounded (``rounded``); an error names
    ``path``. Returns ``path``."""
    times = {c: _utc(frame[c]).dt.strftime(CSV_TIME) for c in frame.columns
             if isinstance(frame[c].dtype, pd.DatetimeTZDtype) or frame[c].dtype.kind == "M"}
    out = guard_frame(frame).assign(**times)
    path = Path(path)
    with named(path):
        rounded(out, decimals or {}).to_csv(path, mode="a" if append else "w", header=not append, index=False,
                                            errors="backslashreplace")
    return path


def rounded(frame: pd.DataFrame, decimals: Mapping[str, int]) -> pd.DataFrame:
    """The float columns named in ``decimals`` rounded to that many places, a negative zero written as 0 and
    values below 1e-4 as fixed-point text (Python writes 4.48e-05); the other columns as they are (not
    copied)."""
    out = {}
    for name, places in decimals.items():
        if name in frame.columns and frame[name].dtype.kind == "f":
            values = np.round(frame[name].to_numpy(float, na_value=np.nan), places) + 0.0  # -0.0 becomes 0.0
            tiny = (values != 0.0) & (np.abs(values) < 1e-4)
            if tiny.any():
                values = values.astype(object)
                values[tiny] = [f"{v:.{places}f}" for v in values[tiny]]
            out[name] = values
    return frame.assign(**out)


def _utc(times: pd.Series) -> pd.Series:
    """Date-times in UTC (naive ones taken as UTC)."""
    return times.dt.tz_convert("UTC") if isinstance(times.dtype, pd.DatetimeTZDtype) else times


def is_missing(value: Any) -> bool:
    """True for None, NaN, NaT and pd.NA (scalars only)."""
    if value is None or value is pd.NA or value is pd.NaT:
        return True
    if isinstance(value, float | np.floating):
        return math.isnan(value)
    if isinstance(value, np.datetime64 | np.timedelta64):
        return bool(np.isnat(value))
    return False


def json_value(value: Any) -> Any:
    """``value`` as plain JSON types: NaN, NaT, NA and infinities None, times ISO 8601 UTC to the millisecond
    with Z (``utc_text``), mappings and sequences item by item, anything else as text."""
    kind = type(value)
    if kind is str or kind is int or kind is bool or value is None:  # already JSON (most of a document)
        return value
    if kind is float:
        return value if math.isfinite(value) else None
    if kind is dict:
        return {str(k): json_value(v) for k, v in value.items()}
    if kind is list:
        return [json_value(v) for v in value]
    if is_missing(value):
        return None
    if isinstance(value, bool | np.bool_):
        return bool(value)
    if isinstance(value, pd.Timestamp | dt.datetime | np.datetime64):
        return utc_text(value)
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
