"""Duplicate removal on small hand-built frames."""

import numpy as np
import pandas as pd

from msdc.pipeline.model.dedup import deduplicate

NAN = np.nan


def frame(rows):
    cols = ["id", "time_of_day", "latitude", "longitude", "ground_speed_kt", "heading_deg"]
    out = pd.DataFrame(rows, columns=cols)
    day = pd.Timestamp("2019-03-01", tz="UTC")
    return out.assign(time=day + pd.to_timedelta(out["time_of_day"], unit="s"))


def test_deduplicate_counts_and_keeps_the_earliest():
    meas = frame([
        ("a", 10.0, 1.0, 103.0, 400.0, 90.0),
        ("b", 5.0, 1.0, 103.0, 400.0, 90.0),  # earlier time: different measurement
        ("c", 10.0, 1.0, 103.0, 400.0, 90.0),  # repeat of a -> dropped
        ("d", 10.0, 1.0, 103.0, 400.0, 91.0),  # heading differs -> kept
        ("e", 20.0, 1.0, 103.0, NAN, NAN),
        ("f", 20.0, 1.0, 103.0, NAN, NAN),  # missing equals missing -> dropped
        ("g", 20.0, 1.0, 103.0, NAN, 10.0),  # heading present vs missing -> kept
        ("h", 10.0, 1.0, 103.0, 400.0, 90.0),  # second repeat of a -> dropped
    ])
    out, dropped = deduplicate(meas)
    assert dropped == 3
    # stable time sort: b (5 s), then a, d (10 s, input order), then e, g (20 s)
    assert out["id"].tolist() == ["b", "a", "d", "e", "g"]
    assert out.index.tolist() == list(range(5))


def test_deduplicate_does_not_mix_sensors_and_handles_empty():
    meas = frame([("r", 1.0, 1.0, 2.0, 3.0, 4.0), ("a", 1.0, 1.0, 2.0, 3.0, 4.0)])
    meas["sensor_kind"] = ["radar", "adsb"]
    meas["sensor_id"] = ["048:1/2", "021:0/9"]
    out, dropped = deduplicate(meas)
    assert dropped == 0 and len(out) == 2
    # two radars never duplicate each other; two ADS-B ground stations relaying one report do
    twice = pd.concat([meas, meas.assign(sensor_id=["048:1/3", "021:0/8"])], ignore_index=True)
    out, dropped = deduplicate(twice)
    assert dropped == 1 and out["sensor_id"].tolist() == ["048:1/2", "021:0/9", "048:1/3"]
    out, dropped = deduplicate(meas.iloc[:0])
    assert dropped == 0 and out.empty


def test_midnight_crossing_sorts_after():
    # measurement time = day * 86400 + item value: 86405 (day 1, 00:00:05) after 86399 (day 0)
    meas = frame([("late", 1 * 86400 + 5.0, 1, 2, 3, 4), ("early", 0 * 86400 + 86399.0, 1, 2, 3, 4)])
    out, _ = deduplicate(meas)
    assert out["id"].tolist() == ["early", "late"]


def test_duplicate_mask_in_time_blocks_equals_one_hashing_of_every_row(monkeypatch):
    # repeats only ever share a time, so hashing blocks of whole time values must flag exactly what
    # pandas' duplicated over all rows flags (NaN and NaT equal, -0.0 equal 0.0, first in frame order)
    from msdc.pipeline.model import dedup

    rng = np.random.default_rng(1)
    n = 20_000
    t = pd.Series(pd.to_datetime(rng.integers(0, 500, n) * 10**9, utc=True)).where(rng.random(n) > 0.01)
    frame = pd.DataFrame({
        "time": t, "latitude": rng.integers(0, 3, n) * 0.5,
        "longitude": np.where(rng.random(n) < 0.1, np.nan, rng.integers(0, 2, n) * 1.0),
        "ground_speed_kt": rng.choice([0.0, -0.0, 1.0], n), "heading_deg": 1.0,
        "sensor_kind": pd.Categorical(rng.choice(["radar", "adsb"], n))})
    expected = frame.duplicated(keep="first")
    monkeypatch.setattr(dedup, "DEDUP_BLOCK_ROWS", 700)
    got = dedup.duplicate_mask(frame)
    assert got.sum() > 1000 and got.equals(expected)


def test_duplicate_mask_equals_hashing_every_row_with_awkward_keys():
    """duplicate_mask hashes only rows sharing their time and latitude with another row; with times and
    latitudes that are NaT, NaN, -0.0 or 0.0 (NaN equals NaN, -0.0 equals 0.0 as keys), it must flag exactly
    what pandas' duplicated over every row flags, in one hashing and in time blocks."""
    from msdc.pipeline.model import dedup

    rng = np.random.default_rng(7)
    n = 5_000
    t = pd.Series(pd.to_datetime(rng.integers(0, 200, n) * 10**9, utc=True)).where(rng.random(n) > 0.02)
    frame = pd.DataFrame({
        "time": t, "latitude": rng.choice([0.0, -0.0, np.nan, 1.5], n),
        "longitude": rng.choice([0.0, -0.0, np.nan], n), "ground_speed_kt": rng.choice([1.0, 2.0], n),
        "heading_deg": 3.0})
    expected = frame.duplicated(keep="first")
    assert expected.sum() > 1000
    assert dedup.duplicate_mask(frame).equals(expected)
    by_time = frame.assign(time=frame["time"].dt.tz_localize(None))  # naive times too
    assert dedup.duplicate_mask(by_time).equals(expected)


def test_shared_rows_are_the_rows_that_share_time_and_latitude():
    from msdc.pipeline.model.dedup import shared_rows

    day = pd.Timestamp("2019-03-01", tz="UTC")
    frame = pd.DataFrame({"time": day + pd.to_timedelta([1, 1, 1, 2, 2, np.nan, np.nan, 3], unit="s"),
                          "latitude": [0.0, -0.0, 1.0, np.nan, np.nan, 5.0, 5.0, 1.0]})
    # rows 0 and 1 (0.0 and -0.0 at 1 s), 3 and 4 (NaN at 2 s), 5 and 6 (5.0 at NaT); 2 and 7 alone
    assert shared_rows(frame).tolist() == [0, 1, 3, 4, 5, 6]
    assert shared_rows(frame, np.array([1, 2, 4, 5, 6, 7])).tolist() == [5, 6]
    assert shared_rows(frame.drop(columns="latitude")) is None


def test_an_aircraft_whose_every_report_is_a_repeat_is_named():
    """Every report of B repeats one of A's (a relayed copy with a damaged address): B is left out whole,
    which the jobs said nowhere (track counted one aircraft fewer). A, with repeats of its own, is not
    named; nor is C, whose one report is its own."""
    from msdc.pipeline.model.dedup import repeated_aircraft

    meas = pd.DataFrame({"aircraft_id": ["A", "A", "A", "B", "B", "C", None]})
    dup = np.array([False, True, False, True, True, False, True])
    assert repeated_aircraft(meas, dup) == [
        "1 aircraft left out whole: every report of B (2 reports) repeats another aircraft's (same time, "
        "position, speed and heading): a damaged identity in a copied report, most likely"]
    assert repeated_aircraft(meas, np.zeros(7, bool)) == []
    many = pd.DataFrame({"aircraft_id": [f"X{i}" for i in range(7)]})
    said = repeated_aircraft(many, np.ones(7, bool), limit=5)[0]
    assert said.startswith("7 aircraft left out whole: every report of X0 (1 report), X1 (1 report)")
    assert "X4 (1 report) and 2 more repeats" in said
