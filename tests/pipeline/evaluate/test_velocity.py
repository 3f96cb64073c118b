"""``velocity_correct`` on a hand-built aircraft flying east at 200 m/s along the equator: the reference
velocity differenced from its positions is (200, 0) m/s; a report's error is the length of the vector
difference, worked out by hand for each report."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from msdc.pipeline.evaluate.requirements import REQUIREMENTS

DEG_PER_M = 180.0 / (np.pi * 6378137.0)  # along the equator: the normal radius there is the semi-major axis
KT = 3600.0 / 1852.0


def _case() -> tuple[pd.DataFrame, pd.DataFrame]:
    t_ref = np.arange(0.0, 60.0)
    reference = pd.DataFrame({"aircraft": "A", "t_s": t_ref, "latitude": 0.0,
                              "longitude": 200.0 * t_ref * DEG_PER_M})
    t = np.arange(4.0, 44.0, 4.0)  # 10 reports
    reports = pd.DataFrame({"t_s": t, "latitude": 0.0, "longitude": 200.0 * t * DEG_PER_M,
                            "ground_speed_kt": 200.0 * KT, "heading_deg": 90.0})
    reports.loc[3, "heading_deg"] = 100.0  # error 2 x 200 x sin(5 deg) = 34.9 m/s
    reports.loc[6, "ground_speed_kt"] = 205.0 * KT  # error 5 m/s
    reports.loc[8, ["ground_speed_kt", "heading_deg"]] = np.nan  # no velocity: not judged
    return reports, reference


def test_errors_against_the_tolerance_worked_out_by_hand():
    reports, reference = _case()
    fn = REQUIREMENTS["velocity_correct"]
    out = fn(reports, reference, {"tolerance_mps": 10.0})
    assert (out.count, out.n) == (8, 9)  # the 100 deg heading fails; 5 m/s passes; one without velocity
    assert fn(reports, reference, {"tolerance_mps": 4.0}).count == 7  # 5 m/s now fails too
    # the larger of 10 m/s and 20 % of 200 m/s = 40 m/s: 34.9 m/s passes
    assert fn(reports, reference, {"tolerance_mps": 10.0, "tolerance_fraction": 0.2}).count == 9
    vx = reports.assign(vx_ms=200.0, vy_ms=-30.0)  # vx/vy first where given: error 30 m/s everywhere
    assert fn(vx, reference, {"tolerance_mps": 29.0}).count == 0
    assert fn(vx, reference, {"tolerance_mps": 31.0}).count == 10


def test_tolerance_is_required_and_no_velocity_is_withheld():
    reports, reference = _case()
    with pytest.raises(ValueError, match="tolerance_mps"):
        REQUIREMENTS["velocity_correct"](reports, reference, {})
    bare = reports.drop(columns=["ground_speed_kt", "heading_deg"])
    assert np.isnan(REQUIREMENTS["velocity_correct"](bare, reference, {"tolerance_mps": 10.0}).value)


def test_a_sensors_own_track_never_judges_its_velocity():
    reports, reference = _case()
    fn = REQUIREMENTS["velocity_correct"]
    # from 20 s the reference is the sensor's own track: the reports at 20..40 s (6, one without velocity)
    own = reference.assign(self_reference=reference["t_s"] >= 20.0)
    out = fn(reports, own, {"tolerance_mps": 10.0})
    # left: the reports at 4, 8, 12, 16 s, the 16 s one with the 100 deg heading
    assert (out.count, out.n) == (3, 4)
    assert any("5 of 9 reports with a velocity" in n for n in out.notes)
    every = fn(reports, reference.assign(self_reference=True), {"tolerance_mps": 10.0})
    assert np.isnan(every.value) and "independent" in every.notes[0]
