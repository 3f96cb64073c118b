"""Decoding only the columns a job needs: the same values, fewer columns, and the same measurements."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from frames import assert_frame_equal

import msdc.asterix as asterix
from msdc.pipeline.model.measurements import DECODED_COLUMNS, build_measurements
from msdc.pipeline.model.sensors import read_sensors

ROOT = Path(__file__).resolve().parents[2]
RADAR, ADSB = ROOT / "fixtures" / "radar.ast", ROOT / "fixtures" / "adsb.ast"
BASE = ["sac", "sic", "time_of_day", "day", "timestamp", "block", "offset"]


@pytest.mark.parametrize("path, cat", [(RADAR, 48), (ADSB, 21)])
def test_selected_columns_equal_the_full_decode(path, cat):
    full = asterix.read(path, date="2019-03-01").frames[cat]
    part = asterix.read(path, date="2019-03-01", columns=["address", "callsign_hex", "flight_level"])
    got = part.frames[cat]
    assert set(got.columns) == {*BASE, "address", "callsign", "callsign_hex", "flight_level"}
    assert_frame_equal(got, full[got.columns])
    streamed = pd.concat([r.frames[cat] for r in asterix.iter_read(path, chunk=20_000, columns=["address"])],
                         ignore_index=True)
    assert set(streamed.columns) == {*BASE, "address"} and len(streamed) == len(full)


def test_unknown_column_is_refused_by_name():
    with pytest.raises(ValueError, match="'altitude'"):
        asterix.read(RADAR, columns=["address", "altitude"])


def test_measurements_from_the_selected_columns_equal_those_from_every_column():
    sensors = read_sensors(ROOT / "fixtures" / "sensors.toml")
    full = [asterix.read(p, date="2019-03-01").frames for p in (RADAR, ADSB)]
    part = [asterix.read(p, date="2019-03-01", columns=DECODED_COLUMNS).frames for p in (RADAR, ADSB)]
    assert len(part[0][48].columns) < len(full[0][48].columns) / 2
    assert_frame_equal(build_measurements(part[0][48], part[1][21], sensors),
                                  build_measurements(full[0][48], full[1][21], sensors))


def test_absent_columns_share_one_array_and_a_write_stays_in_its_column():
    """An edition's columns no record carries are all missing; the float ones are one array (a wide
    edition's absent columns cost one column's memory), yet a value set in one never shows in another,
    in the frame or in a copy taken before (copy on write), whatever the column's dtype."""
    frame = asterix.read(RADAR, date="2019-03-01").frames[48]
    absent = [c for c in frame.columns if frame[c].isna().all()]
    by_dtype: dict[str, list[str]] = {}
    for c in absent:
        by_dtype.setdefault(str(frame[c].dtype), []).append(c)
    floats = by_dtype["float64"]
    assert len(floats) >= 3
    assert np.shares_memory(frame[floats[0]].to_numpy(), frame[floats[1]].to_numpy())
    for dtype, value in (("float64", 1.5), ("Int8", 1), ("Int16", 7)):
        first, second, third = by_dtype[dtype][:3]
        frame.loc[0, first] = value  # no other frame refers to these columns
        assert frame.loc[0, first] == value and frame[second].isna().all()
        before = frame.copy(deep=False)
        frame.loc[1, second] = value
        assert before[second].isna().all() and frame[third].isna().all()
    assert frame[floats[3]].isna().all() and frame[floats[3]].dtype == np.float64
