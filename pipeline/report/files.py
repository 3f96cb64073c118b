"""Writing one output file: the one JSON writer (``write_json``: strict JSON, one time format); an error
names the file (``named``)."""

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

from msdc.pipeline.model.time import utc_text

_ERRNO_IN_TEXT = re.compile(r"\[errno (\d+)\]", re.IGNORECASE)  # pyarrow's "Detail: [errno 28] ..."


@contextlib.contextmanager
def named(path: str | os.PathLike[str]) -> Iterator[None]:
    """Writing ``path``: an OSError that names no file (pyarrow's, Pillow's, a zip's on a full disk) is
    raised again naming it, with the system's message for its error number."""
    try:
        yield
    except OSError as exc:
        if exc.filename is not None:
            raise
        found = _ERRNO_IN_TEXT.search(str(exc))
        code = exc.errno or (int(found.group(1)) if found else None)
        message = os.strerror(code) if code else (exc.strerror or str(exc))
        raise OSError(code, message, os.fspath(path)) from exc


def write_json(doc: Any, path: str | os.PathLike[str]) -> Path:
    """``doc`` as strict JSON (``json_value``: no NaN, times ISO 8601 UTC to the millisecond with Z), UTF-8,
    indented by 2, with a final newline; an error names ``path``. Returns ``path``."""
    text = json.dumps(json_value(doc), indent=2, ensure_ascii=False, allow_nan=False) + "\n"
    path = Path(path)
    with named(path):
        path.write_text(text, encoding="utf-8")
    return path


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
