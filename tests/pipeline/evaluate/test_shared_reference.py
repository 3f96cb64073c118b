"""A reference's trajectories cut once per frame inside `shared_references`, and the rows of each reference
aircraft found by one sort (pipeline/evaluate/reference.py)."""

from __future__ import annotations

import numpy as np
import pandas as pd

from msdc.pipeline.evaluate import reference as refmod
from msdc.pipeline.evaluate.reference import checked_trajectories, rows_by_index, shared_references


def _reference() -> pd.DataFrame:
    """Two aircraft, given out of order (B before A), one row without a position."""
    return pd.DataFrame({"aircraft": ["B", "B", "A", "A", "A"], "t_s": [5.0, 6.0, 1.0, 2.0, 3.0],
                         "latitude": [1.0, 1.1, 2.0, np.nan, 2.2], "longitude": [3.0, 3.1, 4.0, 4.1, 4.2]})


def test_rows_by_index_are_the_rows_of_each_index_in_order():
    rng = np.random.default_rng(7)
    idx = rng.integers(-2, 6, size=500)  # -1 and -2: reports of no aircraft, in no group
    groups = rows_by_index(idx, 6)
    assert len(groups) == 6
    for k in range(6):  # the definition, one pass per aircraft
        np.testing.assert_array_equal(groups[k], np.flatnonzero(idx == k))
    assert sum(len(g) for g in groups) == int((idx >= 0).sum())
    assert [len(g) for g in rows_by_index(np.array([], np.int64), 2)] == [0, 0]
    np.testing.assert_array_equal(rows_by_index(np.array([2, 0, 2]), 3)[2], [0, 2])


def test_the_trajectories_are_cut_once_per_frame_inside_the_scope(monkeypatch):
    calls = []
    cut = refmod.trajectories
    monkeypatch.setattr(refmod, "trajectories", lambda ref: calls.append(1) or cut(ref))
    frame = _reference()
    ref, trajs = checked_trajectories(frame)
    assert [t.label for t in trajs] == ["A", "B"]  # sorted by aircraft, the row without a position dropped
    np.testing.assert_array_equal(trajs[0].t_s, [1.0, 3.0])
    assert list(ref["aircraft"]) == ["A", "A", "B", "B"]
    checked_trajectories(frame)
    assert len(calls) == 2  # outside the scope: every call cuts afresh
    with shared_references():
        first = checked_trajectories(frame)
        with shared_references():  # a scope inside another shares its memo
            assert checked_trajectories(frame) is first
        assert checked_trajectories(frame) is first
        other = checked_trajectories(frame.copy())  # equal values, another frame: cut afresh
        assert other is not first
    assert len(calls) == 4
    checked_trajectories(frame)
    assert len(calls) == 5  # the scope ended: nothing is kept


def test_the_expected_updates_are_made_once_per_frames_and_parameters_inside_the_scope():
    """The pd requirement, long gaps and the coverage maps of one sensor ask for the same expected updates:
    inside the scope they are made once for the same frames, sensor and parameters that change them, and
    again for another interval; the table equals the one made outside the scope."""
    from msdc.pipeline.evaluate.coverage import Sensor
    from msdc.pipeline.evaluate.detection import expected_updates
    from msdc.pipeline.model.geodesy import polar_to_geodetic

    t = np.arange(0.0, 41.0, 1.0)
    lat, lon, _ = polar_to_geodetic(0.0, 0.0, 0.0, 30.0 + 0.1 * t, 0.0, 0.0)
    ref = pd.DataFrame({"aircraft": "A", "t_s": t, "latitude": lat, "longitude": lon, "height_m": 0.0})
    seen = np.arange(0.0, 41.0, 4.0)[[0, 1, 2, 4, 5, 6, 8, 9]]  # scans every 4 s: 12, 28 and 40 s missed
    rep = pd.DataFrame({"t_s": seen, "latitude": lat[seen.astype(int)], "longitude": lon[seen.astype(int)]})
    markers = -2.0 + 4.0 * np.arange(12)
    sensor = Sensor(0.0, 0.0, 0.0, name="hand", max_range_nm=100.0, north_markers_s=markers)
    alone = expected_updates(rep, ref, {}, sensor)[0]
    assert int(alone["detected"].sum()) == 8 and len(alone) == 11  # 11 scans from 0 to 40 s, 8 seen
    with shared_references():
        first = expected_updates(rep, ref, {}, sensor)
        # a parameter it does not read
        assert expected_updates(rep, ref, {"scope": "global"}, sensor) is first
        windows = expected_updates(rep, ref, {"interval_s": 8.0}, sensor)
        assert windows is not first and len(windows[0]) == 5  # 40 s in whole 8 s intervals
        assert expected_updates(rep.copy(), ref, {}, sensor) is not first
    pd.testing.assert_frame_equal(first[0], alone)
