"""The measurement schema: every report of every sensor as one row; name, dtype, unit and meaning per column.

This is the single source of truth for the columns that ``msdc.pipeline.model.measurements`` builds and every
later step (correlation, quality, tracking) reads. ``docs/measurements.md`` is generated from it
(``python -m msdc.pipeline.model.schema > docs/measurements.md``; a test keeps the two in sync).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd
from pandas.api.types import union_categoricals


@dataclass(frozen=True)
class Column:
    """One measurement column: its name, pandas dtype, unit ("" if none) and what it holds."""

    name: str
    dtype: str
    unit: str
    description: str


# Text columns are categorical: each distinct text is stored once and every row holds a small integer code
# (a week of recordings repeats a few sensors and thousands of aircraft over millions of rows). Categories
# are the distinct texts in sorted order, so sorting and grouping by the codes is sorting by the text.
_TEXT = "category"  # <NA> where absent
LABEL_DTYPE = pd.StringDtype()  # the dtype of every text column's categories ("string", <NA> semantics)
# Small nullable integers, sized to the widest field the ASTERIX items carry (SAC/SIC 8 bits, track number
# 12 bits, NIC/NACp/NUCr/SIL/MOPS version at most 4 bits). Arithmetic in these dtypes can overflow: widen
# first (``.astype("Int64")``). ``conform`` refuses values outside the dtype's range instead of wrapping.
_SMALL = "Int8"
_SHORT = "Int16"

MEASUREMENT_SCHEMA: tuple[Column, ...] = (
    Column("time", "datetime64[ns, UTC]", "UTC",
           "Instant of the report (radar I048/140, ADS-B time of applicability, I010/140, I020/140); an "
           "undated recording is "
           "placed on 1970-01-01 (see msdc.pipeline.model.time)"),
    Column("sensor_id", _TEXT, "",
           "Sensor: category, SAC and SIC as \"CCC:SAC/SIC\" (e.g. 048:25/201, 021:0/107, 020:25/10), and "
           "for CAT010, whose one SAC/SIC may carry both, its kind: \"010:0/107:mlat\", \"010:0/7:smr\""),
    Column("sensor_kind", _TEXT, "", "\"radar\" (CAT048), \"adsb\" (CAT021), \"mlat\" (multilateration: "
           "CAT020, CAT010 with I010/020 TYP 0, 1 or 5) or \"smr\" (surface movement radar: CAT010 TYP 3)"),
    Column("sac", _SHORT, "", "System area code of the sensor"),
    Column("sic", _SHORT, "", "System identification code of the sensor"),
    Column("aircraft_id", _TEXT, "",
           "Aircraft identity assigned once (msdc.pipeline.model.identity): the 24-bit address, else the "
           "address the call sign is uniquely seen with, else \"CS:\" call sign, else the address the Mode "
           "3/A code is uniquely seen with (if within reach), else \"M3A:\" Mode 3/A code; <NA> when the "
           "report has none"),
    Column("latitude", "float64", "deg", "WGS-84 latitude"),
    Column("longitude", "float64", "deg", "WGS-84 longitude, -180..180"),
    Column("height_m", "float64", "m",
           "Height used for the position, above the WGS-84 ellipsoid (see height_source); NaN if none"),
    Column("height_source", _TEXT, "",
           "\"flight_level\" (FL x 100 ft taken as height), \"geometric\" (ADS-B or CAT020 geometric height) "
           "or \"none\" (radar plot without FL: placed at zero elevation; CAT010/CAT020 x/y without a "
           "height: on the plane tangent at the reference point)"),
    Column("flight_level", "float64", "FL", "Flight level (pressure altitude / 100 ft)"),
    Column("ground_speed_kt", "float64", "kt", "Ground speed"),
    Column("on_ground", "boolean", "",
           "The report says the aircraft is on the surface: CAT021 I021/040 GBS set (and CAT010 I010/020, "
           "CAT020 I020/020 GBS; <NA> for surface radar reports), CAT048 I048/230 STAT "
           "1 or 3 (on ground), or either's RAB set (a field monitor: a fixed transponder); False for GBS "
           "clear or STAT 0 or 2 (airborne); <NA> when the report does not say (no such item, STAT 4, 5 "
           "or 7)"),
    Column("heading_deg", "float64", "deg",
           "Direction of motion, clockwise from true north (radar I048/200 heading, ADS-B track angle, "
           "CAT010/CAT020 the velocity vector's direction, else I010/200 track angle)"),
    Column("address", _TEXT, "", "24-bit ICAO aircraft address, 6 upper-case hex digits"),
    Column("callsign", _TEXT, "", "Call sign (target identification), upper case without spaces"),
    Column("mode3a", _TEXT, "", "Mode 3/A code, 4 octal digits"),
    Column("track_number", _SHORT, "", "Sensor track number"),
    Column("rho_nm", "float64", "NM", "Radar slant range (I048/040); NaN for the other sensors"),
    Column("theta_deg", "float64", "deg", "Radar azimuth clockwise from north (I048/040); NaN for ADS-B"),
    Column("position_item", _TEXT, "",
           "Source item of a radar, multilateration or surface radar position: \"040\" polar, \"042\" "
           "cartesian or (CAT010, CAT020) \"041\" WGS-84; <NA> for ADS-B"),
    Column("nucp_nic", _SMALL, "", "ADS-B NUCp (MOPS version 0) or NIC (versions 1, 2)"),
    Column("nacp", _SMALL, "", "ADS-B navigation accuracy category for position"),
    Column("nucr_nacv", _SMALL, "", "ADS-B NUCr or NACv"),
    Column("sil", _SMALL, "", "ADS-B source integrity level"),
    Column("mops_version", _SMALL, "", "ADS-B MOPS version (0, 1, 2)"),
    Column("fom_pa", _SMALL, "",
           "CAT021 0.2x figure of merit I021/090 PA (position accuracy); not NUCp, NIC or NACp (their scales "
           "are not documented as the same), so not read as any of them; <NA> for 2.x reports"),
    Column("cov_ee_m2", "float64", "m^2",
           "Horizontal position covariance, east-east, in the local east/north frame at the report; radar: "
           "from the sensor's range and azimuth sigmas with the slant-range geometry; ADS-B: "
           "(NACp 95 % bound / 2.4477)^2 (2.4477 = sqrt(-2 ln 0.05), the 95 % radius of a circular "
           "Gaussian; NACp 11: 1.50 m^2); multilateration and surface radar: I010/500 or I020/500 standard "
           "deviations squared, else the sensor file's sigma_m squared; NaN when unknown, and for radar "
           "plots almost overhead (slant range over 10 x ground distance from the site) or within 1 m of "
           "the site on the ground (a range of 0: its azimuth error vanishes and the matrix is singular)"),
    Column("cov_en_m2", "float64", "m^2", "Horizontal position covariance, east-north"),
    Column("cov_nn_m2", "float64", "m^2", "Horizontal position covariance, north-north"),
    Column("sigma_major_m", "float64", "m", "Standard deviation along the error ellipse's major axis"),
    Column("file", _TEXT, "", "Input file the report came from: its name, or its path as given when two "
           "inputs share a name"),
    Column("offset", "Int64", "B", "Byte offset of the record in that file"),
)
MEASUREMENT_COLUMNS = [c.name for c in MEASUREMENT_SCHEMA]
SENSOR_KINDS = ("radar", "adsb", "mlat", "smr")  # the values of sensor_kind
_BY_NAME = {c.name: c for c in MEASUREMENT_SCHEMA}


class SchemaError(ValueError):
    """A frame does not follow the measurement schema; names the column."""


def schema_columns(names=None) -> list[Column]:
    """The schema's columns named in ``names`` (every column when None), in schema order: how a job asks
    for the part of the model it reads. SchemaError for a name the schema does not have."""
    if names is None:
        return list(MEASUREMENT_SCHEMA)
    names = {names} if isinstance(names, str) else set(names)  # one name is one column, not its letters
    unknown = sorted(names - _BY_NAME.keys())
    if unknown:
        raise SchemaError(f"{unknown[0]!r} is not a measurement column (see pipeline.model.schema)")
    return [c for c in MEASUREMENT_SCHEMA if c.name in names]


def column_names(names=None) -> list[str]:
    """The names of ``schema_columns(names)``: ``names`` checked against the schema, in schema order."""
    return [c.name for c in schema_columns(names)]


def empty_measurements(columns=None) -> pd.DataFrame:
    """A measurement frame with no rows and every column (or the ``columns`` named) at its schema dtype."""
    return conform(pd.DataFrame(index=pd.RangeIndex(0)), columns)


_INT_RANGES = {"Int8": (-(2**7), 2**7 - 1), "Int16": (-(2**15), 2**15 - 1)}


def as_dtype(values: pd.Series, column: Column) -> pd.Series:
    """``values`` cast to the column's dtype: text to sorted categories, small integers only when every
    value fits (SchemaError naming the column otherwise: a cast would wrap silently)."""
    if column.dtype == _TEXT:
        return text_categorical(values)
    if column.dtype in _INT_RANGES and str(values.dtype) != column.dtype:
        lo, hi = _INT_RANGES[column.dtype]
        numbers = pd.to_numeric(values, errors="coerce") if values.dtype == object else values
        if len(values) and ((numbers < lo) | (numbers > hi)).fillna(False).to_numpy(bool).any():
            raise SchemaError(f"measurement column {column.name!r} has values outside {lo}..{hi} "
                              f"(its dtype is {column.dtype})")
    return values.astype(column.dtype)


def coded_text(codes, labels) -> pd.Categorical:
    """Text from integer ``codes`` into ``labels`` (-1, or a missing label: <NA>) as the schema's
    categorical: equal labels merged, categories sorted."""
    labels = [None if lab is None or pd.isna(lab) else str(lab) for lab in labels]
    texts = sorted({lab for lab in labels if lab is not None})
    at = {t: k for k, t in enumerate(texts)}
    remap = np.array([-1 if lab is None else at[lab] for lab in labels] + [-1], np.int64)
    codes = np.asarray(codes, np.int64)
    return pd.Categorical.from_codes(remap[np.where(codes >= 0, codes, len(labels))],
                                     categories=pd.Index(texts, dtype=LABEL_DTYPE))


def equals_text(values: pd.Series, text: str) -> np.ndarray:
    """Per row, whether the text column reads ``text`` (as ``values.astype(str) == text`` for any value but a
    missing one, which is never equal); a categorical is compared by its codes, with no text made per row."""
    if isinstance(values.dtype, pd.CategoricalDtype):
        hits = np.flatnonzero(np.asarray(values.cat.categories.astype(str) == text, bool))
        return np.isin(values.cat.codes.to_numpy(), hits)
    return (values.astype(str) == text).to_numpy(bool) & values.notna().to_numpy(bool)


def first_rows(frame: pd.DataFrame, columns: list[str]) -> np.ndarray:
    """The positions, ascending, of the first row of each distinct combination of ``columns`` (missing
    values equal to one another), found on integer codes: no text made per row."""
    key, distinct = np.zeros(len(frame), np.int64), 1
    for c in columns:
        codes, uniques = pd.factorize(frame[c])
        if distinct * (len(uniques) + 1) >= 2**62:  # renumbered before the packed key could overflow
            _, key = np.unique(key, return_inverse=True)
            distinct = int(key.max()) + 1 if len(key) else 1
        key = key * (len(uniques) + 1) + codes + 1
        distinct *= len(uniques) + 1
    _, first = np.unique(key, return_index=True)
    return np.sort(first)


def text_categorical(values: pd.Series) -> pd.Series:
    """Text as the schema's categorical: categories of the pandas string dtype, in sorted order."""
    if isinstance(values.dtype, pd.CategoricalDtype):
        labels = values.cat.categories
        if labels.dtype == LABEL_DTYPE and labels.is_monotonic_increasing:
            return values
        if pd.api.types.is_string_dtype(labels):  # same texts, recoded in sorted order
            return values.cat.set_categories(pd.Index(sorted(labels), dtype=LABEL_DTYPE))
    return values.astype(LABEL_DTYPE).astype(_TEXT)


def conform(frame: pd.DataFrame, columns=None) -> pd.DataFrame:
    """The schema columns of ``frame`` (all, or the ``columns`` named) in schema order, each cast to its
    dtype (missing ones all NA)."""
    out = {}
    for c in schema_columns(columns):
        if c.name in frame:
            out[c.name] = as_dtype(frame[c.name], c)
        elif c.dtype == _TEXT:
            out[c.name] = pd.Series(coded_text(np.full(len(frame), -1), []), index=frame.index)
        else:
            out[c.name] = pd.Series(pd.NA if c.dtype.startswith("Int") else float("nan"),
                                    index=frame.index).astype(c.dtype)
    # a block per column (no consolidating copy): concat_columns frees them one by one
    return pd.DataFrame(out, index=frame.index, copy=False)


def concat_columns(parts: list[pd.DataFrame]) -> pd.DataFrame:
    """Frames with the same columns end to end (index reset), built column by column: the list is emptied
    first (pass frames held nowhere else), each part's column then held only here and freed once joined,
    so the join never holds the parts and the result whole at once. Categorical text keeps one sorted set of
    categories (pd.concat would turn differing categories into objects)."""
    if len(parts) == 1:
        return parts.pop().reset_index(drop=True)
    held = [dict(p.items()) for p in parts]
    parts.clear()  # not a column deleted at a time from each frame: 0.3 ms each, most of a small join
    out = {}
    for name in list(held[0]):
        columns = [h.pop(name) for h in held]
        if isinstance(columns[0].dtype, pd.CategoricalDtype):
            out[name] = pd.Series(union_categoricals(columns, sort_categories=True))
        else:
            out[name] = pd.concat(columns, ignore_index=True)
        del columns
    return pd.DataFrame(out, copy=False)


def validate(frame: pd.DataFrame, columns=None) -> pd.DataFrame:
    """``frame`` unchanged if it has every schema column (or every one of the ``columns`` named: a job's
    narrower frame) with its dtype and sane values; else SchemaError naming the first offending column."""
    wanted = schema_columns(columns)
    for c in wanted:
        if c.name not in frame:
            raise SchemaError(f"measurement column {c.name!r} is missing ({c.description})")
        if str(frame[c.name].dtype) != c.dtype:
            raise SchemaError(f"measurement column {c.name!r} has dtype {frame[c.name].dtype}, "
                              f"the schema says {c.dtype}")
        if c.dtype == _TEXT:
            labels = frame[c.name].cat.categories
            if len(labels) and not (labels.dtype == LABEL_DTYPE and labels.is_monotonic_increasing):
                raise SchemaError(f"measurement column {c.name!r}: its categories must be text (string "
                                  f"dtype, not {labels.dtype}) in sorted order")
    names = {c.name for c in wanted}
    if "time" in names and frame["time"].isna().any():
        raise SchemaError("measurement column 'time' has missing values")
    kinds = set(frame["sensor_kind"].dropna().unique()) - set(SENSOR_KINDS) if "sensor_kind" in names else ()
    if kinds or ("sensor_kind" in names and frame["sensor_kind"].isna().any()):
        raise SchemaError(f"measurement column 'sensor_kind' holds {sorted(kinds) or ['<NA>']}; "
                          f"allowed: {', '.join(SENSOR_KINDS)}")
    for name, lo, hi in (("latitude", -90.0, 90.0), ("longitude", -180.0, 180.0)):
        v = frame[name] if name in names else None
        if v is not None and (v.isna().any() or ((v < lo) | (v > hi)).any()):
            raise SchemaError(f"measurement column {name!r} has values missing or outside {lo:g}..{hi:g}")
    for name in ("cov_ee_m2", "cov_nn_m2", "sigma_major_m"):
        if name in names and (frame[name] < 0).any():
            raise SchemaError(f"measurement column {name!r} has negative values")
    return frame


def markdown() -> str:
    """The schema as a Markdown table (docs/measurements.md)."""
    lines = [
        "# Measurement columns",
        "",
        "Generated from `pipeline/model/schema.py`",
        "(`python -m msdc.pipeline.model.schema > docs/measurements.md`).",
        "One row per report of every sensor (radar, ADS-B, multilateration, surface radar) alike;",
        "`validate(frame)` checks a frame against",
        "it. A job that reads only some columns may ask for those alone (`schema_columns`, `validate(frame,",
        "columns)`): `msdc correlate` builds the columns listed by",
        "`msdc.pipeline.jobs.correlate.correlate_columns`",
        "(with `--fill predict` also those the tracker reads, with `--quality` those quality reads),",
        "`msdc quality` those of `msdc.pipeline.jobs.quality.quality_columns` (with `--reference track` the",
        "tracker's too). Derived for",
        "the thesis tables (not stored): `time_of_day`,",
        "seconds since midnight UTC of the run's first day (above 86400 after midnight), from",
        "`msdc.pipeline.model.time.with_clock`.",
        "",
        "Dtypes: `category` columns hold text as categories of the pandas string dtype in sorted order",
        "(each distinct text stored once, a small integer code per row; sorting or grouping by the codes",
        "is sorting by the text), `<NA>` where absent. `Int8`/`Int16` are nullable integers sized to the",
        "ASTERIX field (SAC/SIC 8 bits, track number 12 bits, quality indicators 4 bits): widen them",
        "before arithmetic that could overflow. Positions, heights, speeds and covariances are float64.",
        "",
        "| column | dtype | unit | description |",
        "|---|---|---|---|",
    ]
    lines += [f"| `{c.name}` | {c.dtype} | {c.unit} | {c.description} |" for c in MEASUREMENT_SCHEMA]
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    print(markdown(), end="")
