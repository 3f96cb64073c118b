"""The selection of aircraft samples (issue 26): codes parsed, Mode-A-only targets, identity at a time and
the samples kept, on hand-built reports."""

import numpy as np
import pandas as pd
import pytest

from msdc.pipeline.model.selection import (
    Selection,
    identity_at,
    identity_timeline,
    is_mode_a_only,
    parse_codes,
    selected_samples,
)

T0 = pd.Timestamp("2023-05-02 08:00:00", tz="UTC")


def at(*seconds):
    return [T0 + pd.Timedelta(seconds=s) for s in seconds]


def test_codes_are_four_octal_digits():
    assert parse_codes("7000, 2000,7000") == ("2000", "7000")
    assert parse_codes(("0021",)) == ("0021",)
    for bad, words in (("7000,7008", "item 2 '7008' is not a Mode 3/A code"), ("70000", "'70000' is not"),
                       ("", "'' is not")):
        with pytest.raises(ValueError) as info:
            parse_codes(bad)
        assert str(info.value).startswith(f"--exclude-codes {bad!r}") and words in str(info.value)


def test_mode_a_only_is_the_identity_rules_m3a_label():
    # identity rule 4: no address and no call sign in any report gives "M3A:" and the code
    ids = ["M3A:7000", "4CA216", "CS:VLG12", None]
    assert is_mode_a_only(ids).tolist() == [True, False, False, False]


def reports():
    """X squawks 7000 with no call sign, gets ABC12 at 10 s, code 5301 at 20 s; a plot at 30 s without a
    code. Y never reports a code."""
    return pd.DataFrame({"aircraft_id": ["X", "X", "X", "X", "Y"], "time": at(0, 10, 20, 30, 5),
                         "callsign": [None, "ABC12", "ABC12", "ABC12", None],
                         "mode3a": ["7000", "7000", "5301", None, None]})


def test_identity_at_a_time_is_the_last_reported_or_the_first():
    timeline = identity_timeline(reports())
    # X's first report and its code change at 20 s (the call sign first reported at 10 s stands from the
    # start), and Y's first report
    assert len(timeline) == 3
    found = identity_at(timeline, ["X", "X", "X", "X", "X", "Y", "Z"], at(-5, 5, 15, 25, 35, 5, 5))
    # before any report, and before the first call sign, the first reported; a plot without a code does
    # not erase it; an aircraft without one, or unknown, gets ""
    assert found["callsign"].tolist() == ["ABC12", "ABC12", "ABC12", "ABC12", "ABC12", "", ""]
    assert found["mode3a"].tolist() == ["7000", "7000", "7000", "5301", "5301", "", ""]


def test_selected_samples_by_rule():
    samples = pd.DataFrame({"aircraft_id": ["X", "X", "X", "M3A:4445", "Y"], "time": at(5, 15, 25, 5, 5),
                            "flight_level": [30.0, 60.0, 80.0, 90.0, np.nan]})
    timeline = identity_timeline(reports())
    keep, counts = selected_samples(samples, Selection(), timeline)
    assert keep.all() and counts == {}
    keep, counts = selected_samples(samples, Selection(min_fl=50.0), timeline)  # no level: left out
    assert keep.tolist() == [False, True, True, True, False] and counts == {"below_min_fl": 2}
    keep, counts = selected_samples(samples, Selection(exclude_mode_a_only=True), timeline)
    assert keep.tolist() == [True, True, True, False, True] and counts == {"mode_a_only": 1}
    keep, counts = selected_samples(samples, Selection(exclude_codes=("7000",)), timeline)
    assert keep.tolist() == [False, False, True, True, True]  # X squawks 7000 until 20 s
    assert counts == {"excluded_codes": 2}
    keep, _ = selected_samples(samples, Selection(min_fl=50.0, exclude_codes=("7000",)), timeline)
    assert keep.tolist() == [False, False, True, True, False]
