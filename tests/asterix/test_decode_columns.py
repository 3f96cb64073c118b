"""Decoding only the columns a job needs: the same values, fewer columns, and the same measurements."""

from __future__ import annotations

from pathlib import Path

import pandas as pd
import pytest

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
    pd.testing.assert_frame_equal(got, full[got.columns])
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
    pd.testing.assert_frame_equal(build_measurements(part[0][48], part[1][21], sensors),
                                  build_measurements(full[0][48], full[1][21], sensors))
