"""``dubious`` on a hand-built aircraft: 200 m/s east along the equator at FL 100, a report every 4 s,
with one report of each kind broken (position, level, speed, heading): each breaks its limit against the
report before it and makes the next one break it too (the way back)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from msdc.pipeline.evaluate.dubious import dubious, dubious_flags
from msdc.pipeline.evaluate.requirements import REQUIREMENTS

DEG_PER_M = 180.0 / (np.pi * 6378137.0)  # along the equator, on the sphere the function measures on
KT = 3600.0 / 1852.0  # knots per m/s


def _aircraft() -> tuple[pd.DataFrame, pd.DataFrame]:
    t_ref = np.arange(0.0, 121.0)
    reference = pd.DataFrame({"aircraft": "A", "t_s": t_ref, "latitude": 0.0,
                              "longitude": 200.0 * t_ref * DEG_PER_M, "altitude_ft": 10_000.0})
    t = np.arange(0.0, 120.0, 4.0)  # 30 reports
    reports = pd.DataFrame({"t_s": t, "latitude": 0.0, "longitude": 200.0 * t * DEG_PER_M,
                            "flight_level": 100.0, "ground_speed_kt": 200.0 * KT, "heading_deg": 90.0})
    reports.loc[5, "latitude"] = 3000.0 * DEG_PER_M  # 3 km north: sqrt(800^2 + 3000^2) / 4 s = 776 m/s
    reports.loc[10, "flight_level"] = 150.0  # 5,000 ft in 4 s: 1,250 ft/s
    reports.loc[15, "ground_speed_kt"] = 200.0 * KT + 250.0  # 128.6 m/s in 4 s: 32.2 m/s^2
    reports.loc[20, "heading_deg"] = 270.0  # 180 deg in 4 s: 45 deg/s
    split = reports.iloc[[25]].assign(t_s=reports.loc[25, "t_s"] + 0.2)  # a split plot 0.2 s on: not compared
    return pd.concat([reports, split], ignore_index=True), reference


def test_each_broken_report_and_the_one_after_it_are_dubious():
    reports, reference = _aircraft()
    out = dubious(reports, reference, {})
    assert (out.count, out.n) == (8, 29)  # 30 reports compared but the first; the split plot not compared
    assert out.value == pytest.approx(8 / 29)
    assert out.ci_low < 8 / 29 < out.ci_high
    assert out.per_aircraft[["compared", "dubious"]].to_numpy().tolist() == [[29, 8]]
    assert REQUIREMENTS["dubious"] is dubious


def test_each_limit_flags_its_own_pair_with_the_rate_worked_out_by_hand():
    reports, reference = _aircraft()
    from msdc.pipeline.evaluate.reference import associate

    flags = dubious_flags(associate(reports, reference, {}), {}).set_index("t_s")
    fast = flags.index[flags["too_fast"]].tolist()
    assert fast == [20.0, 24.0]
    assert flags.loc[20.0, "speed_kt"] == pytest.approx(np.hypot(800.0, 3000.0) / 4.0 * KT, rel=1e-3)
    assert flags.index[flags["climbs_too_fast"]].tolist() == [40.0, 44.0]
    assert flags.loc[40.0, "vertical_ftps"] == pytest.approx(1250.0)
    assert flags.index[flags["too_sudden"]].tolist() == [60.0, 64.0]
    assert flags.loc[60.0, "accel_mps2"] == pytest.approx(250.0 / KT / 4.0)
    assert flags.index[flags["turns_too_fast"]].tolist() == [80.0, 84.0]
    assert flags.loc[80.0, "turn_dps"] == pytest.approx(45.0)
    assert not flags.drop(index=[20.0, 24.0, 40.0, 44.0, 60.0, 64.0, 80.0, 84.0])["dubious"].any()


def test_limits_are_parameters_and_missing_velocity_is_said():
    reports, reference = _aircraft()
    assert dubious(reports, reference, {"max_speed_kt": 2000.0}).count == 6  # 776 m/s is 1,508 kt
    bare = reports.drop(columns=["ground_speed_kt", "heading_deg"])
    out = dubious(bare, reference, {})
    assert out.count == 4 and any("acceleration and turn rate not judged" in n for n in out.notes)
    far = reports.assign(latitude=1.0)  # 111 km off: nothing associated
    assert np.isnan(dubious(far, reference, {}).value)
