"""mark_once (pipeline.model.marks): duplicate flags and the ADS-B jump verdicts shared by repeated reports,
against a plain row-by-row reference of the documented rule written here."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from msdc.pipeline.model.dedup import DEDUP_KEYS, duplicate_mask
from msdc.pipeline.model.jumps import JUMP_FLAG_COLUMNS, jump_flags
from msdc.pipeline.model.load import load
from msdc.pipeline.model.marks import mark_once
from msdc.pipeline.model.measurements import build_measurements
from msdc.pipeline.model.sensors import read_sensors

# one worker runs the module: the fixtures' measurements made once, not on each worker
pytestmark = pytest.mark.xdist_group("marks")

ROOT = Path(__file__).resolve().parents[3]


def _key_value(v):
    if v is None or v is pd.NaT or (isinstance(v, float) and math.isnan(v)):
        return "<NA>"
    return v + 0.0 if isinstance(v, float) else v  # -0.0 and 0.0 are one key


def reference(meas: pd.DataFrame, split_adsb: bool = False) -> pd.DataFrame:
    """The rule, one row at a time: duplicates as duplicate_mask says; jump columns judged on the ADS-B
    reports that are not repeats; every ADS-B row takes, per column, the first known value among the ADS-B
    rows with the same time, position, speed and heading (in frame order); radar rows carry no verdict."""
    ordered = meas.sort_values("time", kind="stable")
    dup = duplicate_mask(ordered, split_adsb=split_adsb).reindex(meas.index).to_numpy(bool)
    adsb = (meas["sensor_kind"] == "adsb").to_numpy(bool)
    judged = jump_flags(meas[adsb & ~dup])
    keys = [k for k in DEDUP_KEYS if k in meas]
    columns = [meas[k].tolist() for k in keys]  # the values .iloc gives, taken once: .iloc per row is slow
    verdicts = dict(zip(judged.index, judged[JUMP_FLAG_COLUMNS].itertuples(index=False), strict=True))
    firsts: dict[tuple, dict[str, object]] = {}
    row_keys = []
    for i in range(len(meas)):
        if not adsb[i]:
            row_keys.append(None)
            continue
        key = tuple(_key_value(column[i]) for column in columns)
        row_keys.append(key)
        slot = firsts.setdefault(key, {})
        if adsb[i] and not dup[i]:
            for c, v in zip(JUMP_FLAG_COLUMNS, verdicts[meas.index[i]], strict=True):
                if c not in slot and not (isinstance(v, float) and math.isnan(v)):
                    slot[c] = v
    out = {"duplicate": dup}
    for c in JUMP_FLAG_COLUMNS:
        missing = False if c == "jump" else np.nan
        out[c] = np.array([missing if k is None else firsts[k].get(c, missing) for k in row_keys],
                          dtype=bool if c == "jump" else float)
    return pd.DataFrame(out, index=meas.index)


def _check(meas: pd.DataFrame, split_adsb: bool = False) -> pd.DataFrame:
    got = mark_once(meas, split_adsb=split_adsb)
    want = reference(meas, split_adsb)
    for c in want.columns:
        np.testing.assert_array_equal(got[c].to_numpy(), want[c].to_numpy(), err_msg=c)
        assert got[c].dtype == want[c].dtype, c
    return got


@pytest.fixture(scope="module")
def fixture_meas() -> pd.DataFrame:
    loaded = load([ROOT / "fixtures" / "radar.ast", ROOT / "fixtures" / "adsb.ast"], date="2019-03-01")
    return build_measurements(loaded.frames[48], loaded.frames[21],
                              read_sensors(ROOT / "fixtures" / "sensors.toml"), date=loaded.date)


def test_fixtures_match_reference(fixture_meas):
    got = _check(fixture_meas)
    assert got["duplicate"].any() and got["jump"].any()  # the comparison covers both


def test_repeats_share_verdict_on_fixtures_with_injected_repeats(fixture_meas):
    """Every jump repeated twice (once by another ground station, once shuffled to the end): the
    repeats carry the verdict of the report they repeat; split_adsb judges each station's copy."""
    first = mark_once(fixture_meas)
    jumps = fixture_meas[first["jump"].to_numpy()]
    copy = jumps.assign(sensor_id="021:0/9")
    meas = pd.concat([fixture_meas, copy, jumps.iloc[::-1]], ignore_index=True)
    got = _check(meas)
    n = len(fixture_meas)
    assert got["jump"].iloc[n:].all() and got["duplicate"].iloc[n:].all()
    _check(meas, split_adsb=True)


def test_missing_keys_are_one_value(fixture_meas):
    """NaN speed and heading compare equal: two ADS-B reports differing only in NaN are one report."""
    meas = fixture_meas.copy()
    adsb = np.flatnonzero((meas["sensor_kind"] == "adsb").to_numpy())
    meas.loc[meas.index[adsb[::3]], ["ground_speed_kt", "heading_deg"]] = np.nan
    meas = pd.concat([meas, meas.iloc[adsb[::30]]], ignore_index=True)
    got = _check(meas)
    assert got["duplicate"].iloc[len(fixture_meas):].all()


def test_two_radar_scenario_matches_reference(tmp_path):
    from fixtures.multiradar import simulate_two_radars

    m = simulate_two_radars()
    (tmp_path / "sensors.toml").write_text(m.sensors_toml())
    sensors = read_sensors(tmp_path / "sensors.toml")
    radar = pd.concat([m.sim.radar, m.radar2], ignore_index=True)
    meas = build_measurements(radar, m.sim.adsb, sensors, date=pd.Timestamp("2019-03-01").date())
    got = _check(meas)
    assert got["duplicate"].any() and got["jump"].any()


def test_only_the_jump_flag_when_asked(fixture_meas):
    """flags=["jump"] (what correlate without --quality asks for): the duplicate and jump columns of the
    documented rule, with repeats sharing the verdict, and no fit columns."""
    first = mark_once(fixture_meas)
    jumps = fixture_meas[first["jump"].to_numpy()]
    meas = pd.concat([fixture_meas, jumps.assign(sensor_id="021:0/9"), jumps.iloc[::-1]], ignore_index=True)
    for split in (False, True):
        got = mark_once(meas, split_adsb=split, flags=["jump"])
        want = reference(meas, split)
        assert not {"jump_size_m", "fit_latitude", "fit_longitude"} & set(got.columns)
        for c in ("duplicate", "jump"):
            np.testing.assert_array_equal(got[c].to_numpy(), want[c].to_numpy(), err_msg=c)
        assert got["jump"].iloc[len(fixture_meas):].all()
