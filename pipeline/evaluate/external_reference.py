"""An external reference (e.g. a flight trial's GPS) read from a CSV file, checked line by line: a bad file is
refused with its name, the line and the reason, never a traceback.

Columns (a header line names them, in any order; others are ignored):

| column | meaning |
|---|---|
| `aircraft` | the aircraft's label (text, not empty) |
| `time` | UTC time, ISO 8601 with its zone (`2019-03-01T08:00:00.5Z`, `...+00:00`) |
| `latitude`, `longitude` | deg WGS-84 (-90..90, -180..180) |
| `altitude_ft`, `height_m` | pressure altitude (ft), height above the WGS-84 ellipsoid (m): one needed |
| `sigma_m` | optional: the position's 1-sigma error (m); else the ``sigma_m`` argument, else unknown |
| `mode3a`, `address`, `callsign` | optional identity |

Each aircraft's times must increase.
"""

from __future__ import annotations

import csv
import math
import re
from pathlib import Path

import numpy as np
import pandas as pd

from msdc.pipeline.evaluate.build_reference import BUILT_COLUMNS

EXTERNAL_REQUIRED = ("aircraft", "time", "latitude", "longitude")
EXTERNAL_ALTITUDES = ("altitude_ft", "height_m")
EXTERNAL_OPTIONAL = ("sigma_m", "mode3a", "address", "callsign")
_LIMITS = {"latitude": (-90.0, 90.0), "longitude": (-180.0, 180.0), "altitude_ft": (-2000.0, 100000.0),
           "height_m": (-1000.0, 40000.0), "sigma_m": (0.0, 1e6)}


class ExternalReferenceError(ValueError):
    """A refused external reference file: the message names the file, the line and the reason."""


def _number(path: Path, line: int, name: str, text: str, blank_ok: bool) -> float:
    """A column's value as a finite number inside its limits, NaN for a blank where allowed."""
    if text.strip() == "" and blank_ok:
        return math.nan
    try:
        value = float(text)
    except ValueError:
        raise ExternalReferenceError(f"{path}:{line}: {name} {text!r} is not a number") from None
    lo, hi = _LIMITS[name]
    if not (math.isfinite(value) and lo <= value <= hi):
        raise ExternalReferenceError(f"{path}:{line}: {name} {text!r} is outside {lo:g} to {hi:g}")
    return value


def _time(path: Path, line: int, text: str) -> pd.Timestamp:
    """A UTC time with its zone."""
    try:
        stamp = pd.Timestamp(text.strip())
    except (TypeError, ValueError):
        stamp = pd.NaT
    if stamp is pd.NaT or not text.strip():
        raise ExternalReferenceError(f"{path}:{line}: time {text!r} is not an ISO 8601 time")
    if stamp.tzinfo is None:
        raise ExternalReferenceError(f"{path}:{line}: time {text!r} has no zone; write it in UTC with its "
                                     "zone, e.g. 2019-03-01T08:00:00Z")
    return stamp.tz_convert("UTC")


def _header(path: Path, names: list[str] | None) -> list[str]:
    """The header's column names, checked for the required ones."""
    if not names:
        raise ExternalReferenceError(f"{path}:1: empty file: expected a header line naming the columns "
                                     f"{', '.join(EXTERNAL_REQUIRED)} and altitude_ft or height_m")
    names = [n.strip() for n in names]
    missing = [c for c in EXTERNAL_REQUIRED if c not in names]
    if missing or not any(c in names for c in EXTERNAL_ALTITUDES):
        missing += [] if any(c in names for c in EXTERNAL_ALTITUDES) else ["altitude_ft or height_m"]
        raise ExternalReferenceError(f"{path}:1: missing column(s) {', '.join(missing)} (header: "
                                     f"{', '.join(names)})")
    return names


def _rows(path: Path, text: str) -> tuple[list[str], list[tuple[int, dict[str, str]]]]:
    """The header and every non-blank line's fields by column name, with its line number."""
    reader = csv.reader(text.splitlines())
    names = _header(path, next(reader, None))
    rows = []
    for fields in reader:
        line = reader.line_num
        if not any(f.strip() for f in fields):
            continue
        if len(fields) != len(names):
            raise ExternalReferenceError(f"{path}:{line}: {len(fields)} field(s) where the header has "
                                         f"{len(names)}")
        rows.append((line, dict(zip(names, fields, strict=True))))
    if not rows:
        raise ExternalReferenceError(f"{path}:2: no data line after the header")
    return names, rows


def read_external_reference(path: str | Path, epoch: pd.Timestamp, *,
                            sigma_m: float | None = None) -> pd.DataFrame:
    """The CSV as a reference frame (build_reference.BUILT_COLUMNS, plus ``height_m`` when given), ``t_s``
    in seconds since ``epoch`` (the UTC midnight the test reports count from), ``built_by`` "external",
    ``self_reference`` False, ``updated`` True (every sample a fix); ``sigma_m`` fills the rows without one.
    ExternalReferenceError otherwise."""
    from msdc.pipeline.track.tracker import utc_timestamp

    path = Path(path)
    if sigma_m is not None and not (math.isfinite(sigma_m) and sigma_m > 0):
        raise ExternalReferenceError(f"{path}: declared sigma_m {sigma_m!r} must be a positive number of "
                                     "metres")
    try:
        text = path.read_text(encoding="utf-8-sig")
    except (OSError, UnicodeDecodeError) as exc:
        raise ExternalReferenceError(f"{path}: cannot read the external reference: {exc}") from None
    names, rows = _rows(path, text)
    epoch = utc_timestamp("epoch", epoch)
    cols: dict[str, list] = {c: [] for c in ("line", "aircraft", "time", "latitude", "longitude",
                                             *EXTERNAL_ALTITUDES, *EXTERNAL_OPTIONAL)}
    for line, f in rows:
        aircraft = f["aircraft"].strip()
        if not aircraft:
            raise ExternalReferenceError(f"{path}:{line}: aircraft is empty")
        cols["line"].append(line)
        cols["aircraft"].append(aircraft)
        cols["time"].append(_time(path, line, f["time"]))
        for c in ("latitude", "longitude"):
            cols[c].append(_number(path, line, c, f[c], blank_ok=False))
        for c in (*EXTERNAL_ALTITUDES, "sigma_m"):
            cols[c].append(_number(path, line, c, f[c], blank_ok=True) if c in names else math.nan)
        if all(math.isnan(cols[c][-1]) for c in EXTERNAL_ALTITUDES):
            raise ExternalReferenceError(f"{path}:{line}: no altitude (altitude_ft or height_m)")
        for c in ("mode3a", "address", "callsign"):
            cols[c].append(_identity(path, line, c, f[c]) if c in names else None)
    frame = pd.DataFrame(cols)
    _check_order(path, frame)
    if sigma_m is not None:
        frame["sigma_m"] = frame["sigma_m"].fillna(float(sigma_m))
    frame["t_s"] = (pd.to_datetime(frame["time"], utc=True) - epoch).dt.total_seconds()
    frame["built_by"] = "external"
    frame["self_reference"] = False
    frame["updated"] = True  # every sample is a fix of the aircraft
    frame["on_ground"] = pd.array([None] * len(frame), dtype="boolean")  # a trial's file does not say
    extra = ["height_m"] if "height_m" in names else []
    return frame[list(BUILT_COLUMNS) + extra].sort_values(["aircraft", "t_s"], kind="stable",
                                                          ignore_index=True)


IDENTITY_FORMS = {"mode3a": (re.compile(r"[0-7]{4}"), "four octal digits, 0000 to 7777"),
                  "address": (re.compile(r"[0-9A-Fa-f]{6}"), "six hexadecimal digits (a 24-bit address)")}


def _identity(path: Path, line: int, column: str, text: str) -> str | None:
    """An optional identity value (None when blank); a Mode 3/A code or address that is none refused: a
    code "9999" judged every report's code wrong (mode3a_correct 0 %, a fail)."""
    text = text.strip()
    if not text:
        return None
    form = IDENTITY_FORMS.get(column)
    if form is not None and not form[0].fullmatch(text):
        raise ExternalReferenceError(f"{path}:{line}: {column} {text!r} is not {form[1]}")
    return text.upper() if column == "address" else text


def _check_order(path: Path, frame: pd.DataFrame) -> None:
    """Refuse an aircraft whose times do not increase, naming the first line out of order."""
    t = pd.to_datetime(frame["time"], utc=True).astype("int64").to_numpy()
    for aircraft, rows in frame.groupby("aircraft", sort=False).indices.items():
        bad = np.flatnonzero(np.diff(t[rows]) <= 0)
        if bad.size:
            line = int(frame["line"].iloc[rows[bad[0] + 1]])
            raise ExternalReferenceError(f"{path}:{line}: aircraft {aircraft}'s time does not increase "
                                         f"(line {int(frame['line'].iloc[rows[bad[0]]])} is at or after it)")
