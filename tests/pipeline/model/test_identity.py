"""aircraft_labels (pipeline.model.identity): the most frequent call sign and address per aircraft, ADS-B
first, the smallest of equally frequent values, "" when none; worked out by hand."""

from __future__ import annotations

import pandas as pd
import pytest

from msdc.pipeline.model.identity import aircraft_labels


@pytest.mark.parametrize("dtype", ["string", "category"])
def test_labels_by_hand(dtype):
    rows = [  # aircraft_id, sensor_kind, callsign, address
        ("A", "adsb", "BBB", "AAAAAA"), ("A", "adsb", "AAA", "AAAAAA"), ("A", "adsb", "BBB", None),
        ("A", "adsb", "AAA", None), ("A", "radar", "ZZZ", None), ("A", "radar", "ZZZ", None),
        ("A", "radar", "ZZZ", None),  # radar's more frequent ZZZ loses to ADS-B's tie AAA/BBB -> AAA
        ("B", "radar", "RAD", "BBBBBB"), ("B", "radar", "QQQ", None), ("B", "radar", "RAD", None),
        ("C", "adsb", None, None), ("C", "radar", None, "CCCCCC"),
        (None, "adsb", "NONE", "DDDDDD"),  # unidentified rows carry no label
    ]
    meas = pd.DataFrame(rows, columns=["aircraft_id", "sensor_kind", "callsign", "address"]).astype(dtype)
    got = aircraft_labels(meas)
    assert got.to_dict("list") == {"aircraft_id": ["A", "B", "C"], "callsign": ["AAA", "RAD", ""],
                                   "address": ["AAAAAA", "BBBBBB", "CCCCCC"]}


@pytest.mark.filterwarnings("error")
def test_an_aircraft_with_no_label_of_a_kind_reads_empty_without_a_warning():
    # no call sign anywhere (a pandas 3 FutureWarning, a pandas 4 error, when "" filled a float column)
    meas = pd.DataFrame({"aircraft_id": pd.Series(["M3A:1200", "40621D"], dtype="category"),
                         "sensor_kind": pd.Series(["radar", "radar"], dtype="category"),
                         "callsign": pd.Series([None, None], dtype=object),
                         "address": pd.Series([None, "40621D"], dtype=object)})
    got = aircraft_labels(meas)
    assert got.to_dict("list") == {"aircraft_id": ["40621D", "M3A:1200"], "callsign": ["", ""],
                                   "address": ["40621D", ""]}
