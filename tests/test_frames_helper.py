"""The tests' frame comparison (tests/frames.py) fails where pandas' does, categorical columns included."""

import pandas as pd
import pytest
from frames import assert_frame_equal


def _frame(codes, categories=("a", "b", "c"), order=("x", "cat", "y")) -> pd.DataFrame:
    columns = {"x": [1, 2, 3], "cat": pd.Categorical.from_codes(codes, categories=list(categories)),
               "y": [0.5, 1.5, 2.5]}
    return pd.DataFrame({k: columns[k] for k in order})


def test_equal_frames_pass():
    assert_frame_equal(_frame([0, 1, -1]), _frame([0, 1, -1]))


@pytest.mark.parametrize("other", [
    _frame([0, 2, -1]),  # a value differs
    _frame([0, 1, 1]),  # a missing value is not
    _frame([1, 0, -1], categories=("b", "a", "c")),  # the same values, categories in another order
    _frame([0, 1, -1], categories=("a", "b", "d")),  # an unused category differs
    _frame([0, 1, -1], order=("x", "y", "cat")),  # the columns in another order
], ids=["value", "missing", "category order", "categories", "column order"])
def test_differences_fail_as_in_pandas(other):
    with pytest.raises(AssertionError):
        pd.testing.assert_frame_equal(_frame([0, 1, -1]), other)
    with pytest.raises(AssertionError):
        assert_frame_equal(_frame([0, 1, -1]), other)


def test_a_difference_outside_the_categoricals_fails():
    other = _frame([0, 1, -1])
    other.loc[1, "y"] = 9.0
    with pytest.raises(AssertionError):
        assert_frame_equal(_frame([0, 1, -1]), other)
