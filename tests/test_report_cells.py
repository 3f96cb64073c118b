"""The workbook writer's shortcuts give what the cell-by-cell rules give: a column's width from its widest
candidates equals the widest of every cell, and memoised cell values equal excel_value() of each."""

from __future__ import annotations

import datetime as dt
import math

from hypothesis import given, settings
from hypothesis import strategies as st

from pipeline.report.cells import (
    CLOCK_FORMAT,
    DATETIME_FORMAT,
    SUMMARY_DATETIME_FORMAT,
    column_width,
    display_len,
    excel_value,
    memo_values,
)

FORMATS = [None, "0", "0.0", "0.0000", "0.000000", "#,##0", "#,##0.0", CLOCK_FORMAT, DATETIME_FORMAT,
           SUMMARY_DATETIME_FORMAT]
VALUES = st.one_of(st.none(), st.booleans(), st.integers(-10**12, 10**12),
                   st.floats(allow_infinity=False, width=64), st.sampled_from([0.0, -0.0, -1e-9, 0.5, -0.5]),
                   st.text(max_size=12), st.datetimes(min_value=dt.datetime(1990, 1, 1)))


def _naive_width(header: str, values: list, fmt: str | None) -> float:
    """The width rule applied to every cell (what column_width did before it took candidates)."""
    longest = max([max(len(word) for word in header.split(" ")), *(display_len(v, fmt) for v in values)])
    return min(66.0, max(6.0, longest + 2.0))


@settings(max_examples=300, deadline=None)
@given(st.lists(VALUES, max_size=40), st.sampled_from(FORMATS))
def test_width_from_candidates_equals_width_from_every_cell(values, fmt):
    values = [v for v in values if not (isinstance(v, str) and fmt is not None)]  # a column is one kind
    values = [v for v in values if not (isinstance(v, float) and math.isnan(v))]  # NaN is an empty cell
    assert column_width("lat", values, fmt) == _naive_width("lat", values, fmt)


def test_width_sees_negative_zero_and_the_most_negative_value():
    # by hand: "-0.0000" is 7 characters, "0.0000" 6; "-12,345.0" 9
    assert column_width("x", [0.0, -0.0, 1.0], "0.0000") == max(6.0, 7 + 2.0)
    assert column_width("x", [3.0, -12345.0, -1.0], "#,##0.0") == 9 + 2.0


@given(st.lists(st.one_of(VALUES, st.just(math.nan), st.just(float("inf")), st.just("=1+1")), max_size=30))
def test_memo_values_equal_excel_value_of_each(values):
    expected = [excel_value(v) for v in values]
    got = memo_values(values)
    assert [(type(v), v) for v in got] == [(type(v), v) for v in expected]


def test_memo_values_keep_one_true_and_one_point_zero_apart_and_take_lists():
    assert [(type(v), v) for v in memo_values([1, True, 1.0, None])] == \
        [(int, 1), (bool, True), (float, 1.0), (type(None), None)]
    assert memo_values([[1, 2], "a"]) == ["[1, 2]", "a"]
