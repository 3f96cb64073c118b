"""The one definition of what an evaluation hands its writers (XLSX, JSON, HTML): the scorecard (one row per
sensor, sector and requirement), optional named tables (per aircraft, per bin) and optional map points
(reports and reference positions per aircraft), each with a validation that names the column, row and value.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
import pandas as pd

from msdc.pipeline.evaluate.catalogue import CATALOGUE
from msdc.pipeline.evaluate.statistics import VERDICTS


@dataclass(frozen=True)
class Field:
    """One column: its kind ('text', 'number', 'count', 'verdict', 'flag'), whether it may be empty, and
    what it holds."""

    name: str
    kind: str
    nullable: bool
    description: str


SCORECARD: tuple[Field, ...] = (
    Field("sensor", "text", False, "the sensor under test (its id in the sensors file)"),
    Field("sector", "text", False, "where the figure holds: 'global', a sector or area name, a band"),
    Field("requirement", "text", False, "the documented requirement id (pd, rms_m, mode3a_correct...)"),
    Field("value", "number", True, "the measured value, in the requirement's unit (a proportion as a "
          "fraction 0-1); empty where withheld"),
    Field("ci_low", "number", True, "lower end of the 95 % interval; empty where there is none"),
    Field("ci_high", "number", True, "upper end of the 95 % interval; empty where there is none"),
    Field("n", "count", False, "the sample: trials of a proportion, reports of an error statistic, the "
          "exposure of a rate"),
    Field("threshold", "number", False, "the preset's threshold, in the requirement's unit"),
    Field("verdict", "verdict", False, "pass, fail or inconclusive (statistics.verdict)"),
    Field("clause", "text", False, "the standard's clause the threshold comes from"),
    Field("checked", "flag", False, "false where the threshold was not checked against the standard's own "
          "text (the preset's `checked`)"),
    Field("notes", "text", False, "why a figure is withheld or inconclusive, what it rests on; may be ''"),
    Field("parameters", "text", False, "the requirement's parameters as the preset gives them (interval_s = "
          "5, tolerance_ft = 300); may be ''"),
)
SCORECARD_COLUMNS: tuple[str, ...] = tuple(f.name for f in SCORECARD)

MAY_BE_EMPTY = ("notes", "parameters")  # text columns that may hold ''

MAP: tuple[Field, ...] = (
    Field("aircraft", "text", False, "the aircraft's id as the measurements assign it: its 24-bit address "
          "when known (750312, call sign or not), else 'CS:' and the call sign, else 'M3A:' and the Mode 3/A "
          "code"),
    Field("source", "text", False, "'report' (the sensor under test) or 'reference'"),
    Field("sensor", "text", False, "the reporting sensor; the reference's own label for reference points"),
    Field("latitude", "number", False, "WGS-84 latitude (deg)"),
    Field("longitude", "number", False, "WGS-84 longitude (deg)"),
)
MAP_COLUMNS: tuple[str, ...] = tuple(f.name for f in MAP)
MAP_SOURCES = ("report", "reference")


def _bad(what: str, column: str, row: int, value, reason: str) -> ValueError:
    """A message naming the frame, the column, the row (0-based position) and the value."""
    return ValueError(f"{what}: column {column!r}, row {row}: {value!r} {reason}")


def _check_columns(what: str, frame: pd.DataFrame, fields: tuple[Field, ...]) -> None:
    """Exactly the declared columns, any order: none missing, none unknown."""
    if not isinstance(frame, pd.DataFrame):
        raise ValueError(f"{what}: must be a pandas DataFrame, got {type(frame).__name__}")
    names = [f.name for f in fields]
    missing = [c for c in names if c not in frame.columns]
    extra = [str(c) for c in frame.columns if c not in names]
    if missing or extra:
        parts = ([f"missing {', '.join(map(repr, missing))}"] if missing else []) + \
                ([f"unknown {', '.join(map(repr, extra))}"] if extra else [])
        raise ValueError(f"{what}: columns {'; '.join(parts)}; the columns are {', '.join(names)}")
    if frame.columns.duplicated().any():
        raise ValueError(f"{what}: repeated column names {list(frame.columns[frame.columns.duplicated()])}")


def _number(value) -> float | None:
    """The value as a float (None for a missing one); raises TypeError for anything not a real number."""
    if value is None or value is pd.NA or value is pd.NaT:
        return None
    if isinstance(value, bool | np.bool_) or not isinstance(value, int | float | np.integer | np.floating):
        raise TypeError
    number = float(value)
    return None if math.isnan(number) else number


def _column(what: str, frame: pd.DataFrame, field: Field) -> list:
    """One column's values checked against its field; returns them as plain Python values."""
    out = []
    for row, value in enumerate(frame[field.name].tolist()):
        if field.kind in ("text", "verdict"):
            empty_ok = field.nullable or field.name in MAY_BE_EMPTY
            if not isinstance(value, str) or (not empty_ok and not value):
                raise _bad(what, field.name, row, value, "is not a non-empty text")
            if field.kind == "verdict" and value not in VERDICTS:
                raise _bad(what, field.name, row, value, f"is not one of {', '.join(VERDICTS)}")
            out.append(value)
        elif field.kind == "flag":
            if not isinstance(value, bool | np.bool_):
                raise _bad(what, field.name, row, value, "is not true or false")
            out.append(bool(value))
        else:
            try:
                number = _number(value)
            except TypeError:
                raise _bad(what, field.name, row, value, "is not a number") from None
            if number is None and not field.nullable:
                raise _bad(what, field.name, row, value, "is missing (only value, ci_low, ci_high may be)")
            if number is not None and not math.isfinite(number):
                raise _bad(what, field.name, row, value, "is not finite")
            if field.kind == "count" and number is not None and number < 0:
                raise _bad(what, field.name, row, value, "is negative")
            out.append(math.nan if number is None else number)
    return out


def validate_scorecard(frame: pd.DataFrame) -> pd.DataFrame:
    """The scorecard checked (columns, types, verdicts, intervals in order and around the value) and
    returned as a new frame in SCORECARD_COLUMNS order with a fresh index; a ValueError names the column,
    row and value of the first fault."""
    what = "scorecard"
    _check_columns(what, frame, SCORECARD)
    data = {f.name: _column(what, frame, f) for f in SCORECARD}
    ends = zip(data["value"], data["ci_low"], data["ci_high"], strict=True)
    for row, (value, low, high) in enumerate(ends):
        if math.isnan(low) != math.isnan(high):
            name = "ci_low" if math.isnan(low) else "ci_high"
            raise _bad(what, name, row, math.nan, "is missing while the other end of the interval is given")
        if not math.isnan(low) and low > high:
            raise _bad(what, "ci_low", row, low, f"exceeds ci_high {high!r}")
        if not math.isnan(low) and math.isnan(value):
            raise _bad(what, "value", row, value, "is missing while its interval is given")
    for row, ident in enumerate(data["requirement"]):
        if ident not in CATALOGUE:
            raise _bad(what, "requirement", row, ident, "is not a documented requirement id "
                       "(evaluate.catalogue; docs/methods/evaluate.md)")
    keys = list(zip(data["sensor"], data["sector"], data["requirement"], data["parameters"],
                    data["threshold"], strict=True))
    seen: dict[tuple, int] = {}
    for row, key in enumerate(keys):
        if key in seen:
            raise _bad(what, "requirement", row, key[2], f"repeats row {seen[key]} (same sensor, sector, "
                       "requirement, parameters and threshold)")
        seen[key] = row
    out = pd.DataFrame(data, columns=list(SCORECARD_COLUMNS))
    for name in ("value", "ci_low", "ci_high", "n", "threshold"):
        out[name] = out[name].astype(float)
    out["checked"] = out["checked"].astype(bool)
    return out


def validate_tables(tables: Mapping[str, pd.DataFrame] | None) -> dict[str, pd.DataFrame]:
    """The optional named tables (per aircraft, per bin): non-empty text names, DataFrames with unique
    text column names; returned as a plain dict ({} for None)."""
    if tables is None:
        return {}
    if not isinstance(tables, Mapping):
        raise ValueError(f"tables: must be a mapping of name -> DataFrame, got {type(tables).__name__}")
    out = {}
    for name, frame in tables.items():
        if not isinstance(name, str) or not name.strip():
            raise ValueError(f"tables: name {name!r} is not a non-empty text")
        if name.strip().lower() == "scorecard":
            raise ValueError(f"tables: name {name!r} is taken by the scorecard")
        if not isinstance(frame, pd.DataFrame):
            raise ValueError(f"tables: {name!r} must be a pandas DataFrame, got {type(frame).__name__}")
        if frame.columns.duplicated().any() or not all(isinstance(c, str) for c in frame.columns):
            raise ValueError(f"tables: {name!r} must have unique text column names, "
                             f"got {list(frame.columns)}")
        out[name] = frame
    return out


def validate_map(frame: pd.DataFrame | None) -> pd.DataFrame | None:
    """The optional map points checked (MAP_COLUMNS, source 'report' or 'reference', latitude within
    +-90 and longitude within +-180) and returned in MAP_COLUMNS order with a fresh index."""
    if frame is None:
        return None
    what = "map points"
    _check_columns(what, frame, MAP)
    data = {f.name: _column(what, frame, f) for f in MAP}
    for row, source in enumerate(data["source"]):
        if source not in MAP_SOURCES:
            raise _bad(what, "source", row, source, f"is not one of {', '.join(MAP_SOURCES)}")
    for name, limit in (("latitude", 90.0), ("longitude", 180.0)):
        for row, value in enumerate(data[name]):
            if abs(value) > limit:
                raise _bad(what, name, row, value, f"is outside -{limit:g} to {limit:g} degrees")
    return pd.DataFrame(data, columns=list(MAP_COLUMNS))


PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def validate_images(images: Mapping[str, bytes] | None) -> dict[str, bytes]:
    """The optional coverage figures (title -> PNG bytes): non-empty text titles, each a PNG (by its
    signature); returned as a plain dict ({} for None)."""
    if images is None:
        return {}
    if not isinstance(images, Mapping):
        raise ValueError(f"images: must be a mapping of title -> PNG bytes, got {type(images).__name__}")
    out = {}
    for title, data in images.items():
        if not isinstance(title, str) or not title.strip():
            raise ValueError(f"images: title {title!r} is not a non-empty text")
        if not isinstance(data, bytes | bytearray) or not bytes(data[:8]) == PNG_SIGNATURE:
            got = f"{len(data)} bytes" if isinstance(data, bytes | bytearray) else type(data).__name__
            raise ValueError(f"images: {title!r} is not a PNG image (no PNG signature; got {got})")
        out[title] = bytes(data)
    return out


def schema_markdown() -> str:
    """The scorecard's and the map's columns as markdown tables (the docs page shows them)."""
    lines = []
    for title, fields in (("Scorecard", SCORECARD), ("Map points", MAP)):
        lines += [f"**{title}**", "", "| column | kind | may be empty | holds |", "| --- | --- | --- | --- |"]
        lines += [f"| `{f.name}` | {f.kind} | {'yes' if f.nullable else 'no'} | {f.description} |"
                  for f in fields]
        lines.append("")
    return "\n".join(lines).rstrip() + "\n"
