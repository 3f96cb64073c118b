"""``extra_tracks`` and ``track_continuity`` on hand-built test tracks of two aircraft, a report every 4 s
and 4 s intervals (one report per interval and track): counts worked out by hand."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from msdc.pipeline.evaluate.requirements import REQUIREMENTS


def _case() -> tuple[pd.DataFrame, pd.DataFrame]:
    t_ref = np.arange(0.0, 101.0)
    reference = pd.concat([pd.DataFrame({"aircraft": ac, "t_s": t_ref, "latitude": lat,
                                         "longitude": 0.001 * t_ref})
                           for ac, lat in (("A", 0.0), ("B", 1.0))], ignore_index=True)
    t = np.arange(0.0, 100.0, 4.0)  # 25 reports an aircraft, one per 4 s interval
    a = pd.DataFrame({"t_s": t, "latitude": 0.0, "longitude": 0.001 * t,
                      "track_number": np.where(t < 50, 1, 2)})
    extra = a[a["t_s"].isin([20.0, 24.0])].assign(track_number=9)  # a second track beside track 1 twice
    b = pd.DataFrame({"t_s": t, "latitude": 1.0, "longitude": 0.001 * t, "track_number": 5})
    b.loc[b["t_s"] == 40.0, "track_number"] = 6  # one interval under another number: 5 -> 6 -> 5
    return pd.concat([a, extra, b], ignore_index=True), reference


def test_extra_tracks_and_continuity_counted_by_hand():
    reports, reference = _case()
    extra = REQUIREMENTS["extra_tracks"](reports, reference, {"interval_s": 4.0})
    assert (extra.count, extra.n) == (2, 50)
    assert extra.per_aircraft.set_index("aircraft")["extra"].to_dict() == {"A": 2, "B": 0}
    cont = REQUIREMENTS["track_continuity"](reports, reference, {"interval_s": 4.0})
    assert (cont.count, cont.n) == (3, 2.0)  # A: 1 -> 2 once; B: 5 -> 6 -> 5
    assert cont.value == pytest.approx(1.5)


def test_without_track_numbers_both_are_withheld():
    reports, reference = _case()
    for rid in ("extra_tracks", "track_continuity"):
        out = REQUIREMENTS[rid](reports.drop(columns="track_number"), reference, {})
        assert np.isnan(out.value) and "track number" in out.notes[0]
