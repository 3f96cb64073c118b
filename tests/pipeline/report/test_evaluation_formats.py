"""How the evaluation's tables show numbers (HTML and workbook alike): values worked out by hand."""

from __future__ import annotations

import math

import pandas as pd
import pytest

from msdc.pipeline.report.evaluation_formats import (
    number_text,
    proportion_columns,
    significant,
)


@pytest.mark.parametrize(("value", "text"), [
    (0.983333, "0.9833"), (118 / 120, "0.9833"), (12345.6, "12,346"), (1234.56, "1,235"), (12.3456, "12.35"),
    (0.00012, "0.0001200"), (1.23e-6, "1.230e-06"), (-2.5, "-2.500"), (0.0, "0"), (1e16, "1.000e+16"),
])
def test_other_floats_show_four_significant_digits(value: float, text: str) -> None:
    assert significant(value) == text


def test_proportions_are_the_requirement_named_columns_and_their_interval() -> None:
    bins = pd.DataFrame(columns=["low", "high", "expected", "detected", "pd", "ci_low", "ci_high", "enough"])
    assert proportion_columns(bins) == {"pd", "ci_low", "ci_high"}
    # an interval beside a distance is not a proportion's
    mixed = pd.DataFrame(columns=["aircraft", "pd", "rms_m", "ci_low", "ci_high"])
    assert proportion_columns(mixed) == {"pd"}
    assert proportion_columns(pd.DataFrame(columns=["aircraft", "ci_low"])) == set()


def test_each_kind_of_column_as_the_workbook_shows_it() -> None:
    shares = {"pd"}
    assert number_text(148 / 150, "pd", shares) == "98.67 %"
    assert number_text(50.0, "range_from_nm", shares) == "50.0"  # a bin edge in NM: 1 decimal (formats.UNITS)
    assert number_text(120.45, "error_m", shares) == "120.5"  # metres: 1 decimal
    assert number_text(3725.5, "time_of_day", shares) == "01:02:05.500"  # a clock time
    assert number_text(0.975, "value", shares, "fraction") == "97.50 %"  # beside requirement pd
    assert number_text(120.45, "value", shares, "m") == "120.5"  # beside requirement rms_m
    assert number_text(math.nan, "pd", shares) == ""


def test_the_reference_shares_of_the_per_aircraft_table_are_fractions_shown_as_percentages() -> None:
    """self_reference_share 0.0446 is 4.46 % of the reference's samples (not 0.0 of a percent)."""
    per = pd.DataFrame(columns=["aircraft", "self_reference_share", "surface_share", "reference_samples",
                                "pd", "ci_low", "ci_high", "rms_error_m"])
    shown = proportion_columns(per)
    assert shown == {"self_reference_share", "surface_share", "pd", "ci_low", "ci_high"}
    assert number_text(0.0446, "self_reference_share", shown) == "4.46 %"
    assert number_text(1.0, "surface_share", shown) == "100.00 %"


def test_a_scorecard_rows_sample_reads_as_the_scorecard_shows_it() -> None:
    """In a table of scorecard rows (the scorecard per window) ``n`` is a count, 874 not 874.0, with thousands
    separated; a rate's exposure in scans keeps one decimal; ``n`` of a table without requirements is a plain
    number."""
    assert number_text(874.0, "n", set(), "fraction") == "874"
    assert number_text(2904.0, "n", set(), "fraction") == "2,904"
    assert number_text(2500.4, "n", set(), "per scan") == "2,500.4"
    assert number_text(874.0, "n", set()) == "874.0"


def test_counts_left_as_floats_by_a_join_read_as_counts() -> None:
    """The per-aircraft table's errors judged is a float where an aircraft without reports leaves NaN:
    171.0 reads 171 and 1025.0 reads 1025, as the workbook's count format 0 shows them (they read 171.0 and
    1,025 as other floats); the bins' expected and detected updates alike."""
    assert number_text(171.0, "errors_judged", set()) == "171"
    assert number_text(1025.0, "errors_judged", set()) == "1025"
    assert number_text(7260.0, "expected_updates", set()) == "7260"
    assert number_text(27255.0, "expected", set()) == "27255"
    assert number_text(math.nan, "detected_updates", set()) == ""
