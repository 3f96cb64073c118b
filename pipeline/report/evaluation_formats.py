"""How the evaluation's tables show their numbers, one rule for the workbook and the HTML report: a proportion
(a column named by a proportion requirement's id such as ``pd``, and its ``ci_low``/``ci_high``) as a
percentage with the scorecard's format; a value beside a ``requirement`` column in that requirement's unit; a
column whose name gives its unit (pipeline.report.formats) with that unit's decimals; any other float to four
significant digits."""

from __future__ import annotations

import math

import pandas as pd

from msdc.pipeline.evaluate.catalogue import CATALOGUE
from msdc.pipeline.report.formats import UNITS, column_unit

PROPORTION_FORMAT = "0.00%"  # the scorecard's (evaluation_xlsx.UNIT_FORMATS["fraction"])
INTERVAL_COLUMNS = ("ci_low", "ci_high")
# the per-aircraft table's shares of the reference's samples: fractions 0-1 (formats' "share" columns are
# percentages already elsewhere)
SHARE_COLUMNS = ("self_reference_share", "surface_share")
ROW_UNIT_COLUMNS = ("value", "ci_low", "ci_high", "threshold")  # in the unit of the row's requirement
SIGNIFICANT = 4
# decimals of each requirement unit, as the scorecard shows them (evaluation_xlsx.UNIT_FORMATS)
UNIT_DECIMALS = {"m": 1, "s": 3, "deg": 4, "ppm": 1, "per scan": 3, "per aircraft": 3}


def is_proportion_id(name: str) -> bool:
    """Whether a column is named by a requirement id whose unit is a fraction (pd, mode3a_valid...)."""
    kind = CATALOGUE.get(str(name))
    return kind is not None and kind.unit == "fraction"


def proportion_columns(frame: pd.DataFrame) -> set[str]:
    """The columns holding proportions 0-1: those named by a proportion requirement, and ci_low/ci_high
    when every requirement-named column of the table is a proportion (they are its interval), and the
    reference's shares (SHARE_COLUMNS)."""
    named = [str(c) for c in frame.columns if str(c) in CATALOGUE]
    out = {c for c in named if is_proportion_id(c)}
    if out and len(out) == len(named) and "requirement" not in frame.columns:
        out |= {c for c in INTERVAL_COLUMNS if c in frame.columns}
    return out | {c for c in SHARE_COLUMNS if c in frame.columns}


def percent_decimals(value: float) -> int:
    """Decimals of a proportion shown as a percentage: 2, and below 1 % enough for three significant
    digits (a false-report share of 0.0146 % beside its threshold of 0.01 % would both read 0.01 %)."""
    pct = abs(100.0 * value)
    if not math.isfinite(pct) or pct == 0.0 or pct >= 1.0:
        return 2
    return max(2, 2 - math.floor(math.log10(pct)))


def percent_format(value: float) -> str:
    """The workbook's number format of a proportion (percent_decimals)."""
    return "0." + "0" * percent_decimals(value) + "%"


def unit_text(value: float, unit: str) -> str:
    """A number in a requirement's unit as the scorecard shows it: a fraction as a percentage."""
    if unit == "fraction":
        return f"{100.0 * value:.{percent_decimals(value)}f} %"
    return f"{value:,.{UNIT_DECIMALS[unit]}f}"


def significant(value: float, digits: int = SIGNIFICANT) -> str:
    """A float to ``digits`` significant digits, in fixed notation from 1e-4 to 1e15 (whole numbers of
    ``digits`` digits or more shown whole, thousands separated)."""
    if value == 0.0:
        return "0"
    exponent = math.floor(math.log10(abs(value)))
    if exponent < -4 or exponent >= 15:
        return f"{value:.{digits - 1}e}"
    return f"{value:,.{max(digits - 1 - exponent, 0)}f}"


def _clock(seconds: float) -> str:
    """Seconds of day as hh:mm:ss.sss (hours running past 24, as the workbook's [hh] format)."""
    whole_ms = round(seconds * 1000.0)
    h, rest = divmod(whole_ms, 3_600_000)
    m, rest = divmod(rest, 60_000)
    return f"{h:02d}:{m:02d}:{rest / 1000:06.3f}"


def sample_text(n: float) -> str:
    """A scorecard row's sample ``n``: a count with thousands separated, an exposure (a rate's scans) to one
    decimal."""
    return f"{int(n):,}" if float(n).is_integer() else f"{n:,.1f}"


def column_text(column: str, proportions: set[str], row_unit: str | None = None):
    """A function giving a float of ``column`` as text ('' for NaN), under the rules above; a scorecard
    row's ``n`` (a table with a requirement column) as the scorecard shows it."""
    name = str(column)
    if row_unit is not None and name in ROW_UNIT_COLUMNS:
        return lambda v: unit_text(v, row_unit)
    if row_unit is not None and name == "n":
        return sample_text
    if name in proportions:
        return lambda v: unit_text(v, "fraction")
    unit = column_unit(name)
    if unit == "tod":
        return _clock
    if unit is not None:
        places, comma = UNITS[unit].decimals, "," if unit == "bytes" else ""
        return lambda v: f"{v:{comma}.{places}f}"
    return significant


def number_text(value: float, column: str, proportions: set[str], row_unit: str | None = None) -> str:
    """One float of a table as text, '' for NaN."""
    if math.isnan(value):
        return ""
    return column_text(column, proportions, row_unit)(value)
