"""Position accuracy on hand-built aircraft: each report placed with pyproj's geodesic (an independent
method) at a chosen offset behind and to the right of the reference, so every statistic is known."""

from __future__ import annotations

import math
import re

import numpy as np
import pandas as pd
import pytest
from pyproj import Geod

from msdc.pipeline.evaluate.requirements import REQUIREMENTS

GEOD = Geod(ellps="WGS84")


def _case(behind_m, right_m) -> tuple[pd.DataFrame, pd.DataFrame]:
    """12 aircraft due east at 200 m/s, 0.5 deg of latitude apart; reports every 4 s for 60 s, each
    behind_m behind and right_m to the right of (south of) the reference; offsets per aircraft."""
    refs, reps = [], []
    for k in range(12):
        lat0 = 0.5 * k
        t = np.arange(0.0, 71.0)
        lon, lat, _ = GEOD.fwd(np.zeros(t.size), np.full(t.size, lat0), np.full(t.size, 90.0), 200.0 * t)
        refs.append(pd.DataFrame({"aircraft": f"A{k}", "t_s": t, "latitude": lat, "longitude": lon}))
        tr = np.arange(4.0, 64.0, 4.0)
        east = np.full(tr.size, 90.0)
        rlon, rlat, _ = GEOD.fwd(np.zeros(tr.size), np.full(tr.size, lat0), east, 200.0 * tr)
        b, r = behind_m[k], right_m[k]
        az = math.degrees(math.atan2(-b, -r)) % 360.0  # east component -b, north component -r
        plon, plat, _ = GEOD.fwd(rlon, rlat, np.full(tr.size, az), np.full(tr.size, math.hypot(b, r)))
        reps.append(pd.DataFrame({"t_s": tr, "latitude": plat, "longitude": plon}))
    return pd.concat(reps, ignore_index=True), pd.concat(refs, ignore_index=True)


def test_one_offset_everywhere_gives_every_statistic_by_hand():
    reports, reference = _case([20.0] * 12, [30.0] * 12)
    error = math.hypot(20.0, 30.0)
    for rid, want in (("rms_m", error), ("mean_m", error), ("p95_m", error), ("max_m", error),
                      ("along_rms_m", 20.0), ("across_rms_m", 30.0), ("latency_p95_s", 20.0 / 200.0)):
        out = REQUIREMENTS[rid](reports, reference, {})
        assert out.value == pytest.approx(want, rel=2e-3), rid
        assert out.n == 12 * 15
    out = REQUIREMENTS["rms_m"](reports, reference, {})
    assert out.ci_low == pytest.approx(error, rel=2e-3) and out.ci_high == pytest.approx(error, rel=2e-3)


def test_offsets_per_aircraft_against_numpy_and_the_self_reference_left_out():
    behind = np.arange(12) * 5.0  # 0, 5, ... 55 m behind; no cross-track offset
    reports, reference = _case(behind, np.zeros(12))
    out = REQUIREMENTS["rms_m"](reports, reference, {})
    assert out.value == pytest.approx(math.sqrt(np.mean(behind**2)), rel=2e-3)
    assert out.ci_low < out.value < out.ci_high  # aircraft differ: a real interval over aircraft
    assert REQUIREMENTS["mean_m"](reports, reference, {}).value == pytest.approx(behind.mean(), rel=2e-3)
    own = reference.assign(self_reference=reference["aircraft"] == "A11")  # A11's reference is its own track
    out = REQUIREMENTS["rms_m"](reports, own, {})
    assert out.n == 11 * 15
    assert out.value == pytest.approx(math.sqrt(np.mean(behind[:11] ** 2)), rel=2e-3)
    only = reference.assign(self_reference=True)
    assert np.isnan(REQUIREMENTS["rms_m"](reports, only, {}).value)


def _accelerating(leads_s, seed: int) -> tuple[pd.DataFrame, pd.DataFrame]:
    """12 aircraft due east, 0.5 deg of latitude apart, accelerating from 10 to 80 m/s over 120 s (a
    take-off run); each report placed (pyproj) where the aircraft is leads_s[k] later, plus 3 m of noise
    along and across the track."""
    rng = np.random.default_rng(seed)
    refs, reps = [], []
    for k, lead in enumerate(leads_s):
        t = np.arange(0.0, 121.0)
        s = 10.0 * t + 0.5 * (70.0 / 120.0) * t**2
        lon, lat, _ = GEOD.fwd(np.zeros(t.size), np.full(t.size, 0.5 * k), np.full(t.size, 90.0), s)
        refs.append(pd.DataFrame({"aircraft": f"A{k}", "t_s": t, "latitude": lat, "longitude": lon}))
        tr = np.arange(2.0, 118.0)
        tl = tr + lead
        along = 10.0 * tl + 0.5 * (70.0 / 120.0) * tl**2 + rng.normal(0.0, 3.0, tr.size)
        plon, plat, _ = GEOD.fwd(np.zeros(tr.size), np.full(tr.size, 0.5 * k), np.full(tr.size, 90.0), along)
        plon, plat, _ = GEOD.fwd(plon, plat, np.full(tr.size, 180.0), rng.normal(0.0, 3.0, tr.size))
        reps.append(pd.DataFrame({"t_s": tr, "latitude": plat, "longitude": plon}))
    return pd.concat(reps, ignore_index=True), pd.concat(refs, ignore_index=True)


def test_a_late_reference_of_two_aircraft_is_named_on_the_accuracy_rows():
    """A0 and A1's reference lags their reports by 1 s: their errors at speed are up to 80 m along the
    track. The p95 row's note names them (leads within 0.1 s of 1 s) and no other aircraft; with every lead
    zero the note is silent."""
    reports, reference = _accelerating([1.0, 1.0] + [0.0] * 10, seed=7)
    out = REQUIREMENTS["p95_m"](reports, reference, {"threshold_m": 12.0})
    (note,) = [n for n in out.notes if n.startswith("timing:")]
    assert note.startswith("timing: 2 of 12 aircraft lead or lag the reference unlike the others (A0 +")
    named = dict(re.findall(r"(A\d+) ([+-]\d\.\d\d) s", note.split("; the others")[0]))
    assert named.keys() == {"A0", "A1"} and all(abs(float(v) - 1.0) < 0.1 for v in named.values())
    reports, reference = _accelerating([0.0] * 12, seed=8)
    assert not [n for n in REQUIREMENTS["p95_m"](reports, reference, {}).notes if n.startswith("timing:")]


def test_false_reports_ahead_of_a_late_reference_are_said_to_be_maybe_true():
    """The same two late references: their reports lie 1 s of travel ahead, over 40 m once the aircraft
    passes 40 m/s (t > 51 s: 67 reports each, a few either side by the 3 m noise), so they count as false
    beyond 40 m; the note says all of them lie near the two aircraft the timing finds late."""
    reports, reference = _accelerating([1.0, 1.0] + [0.0] * 10, seed=7)
    out = REQUIREMENTS["false_reports"](reports, reference, {"distance_m": 40.0})
    assert 130 <= out.count <= 138
    (note,) = [n for n in out.notes if n.startswith("timing:")]
    assert note.startswith(f"timing: {out.count} of the {out.count} false reports lie near an aircraft")
    assert "(A0, A1: see the accuracy rows)" in note
    reports, reference = _accelerating([0.0] * 12, seed=8)
    assert REQUIREMENTS["false_reports"](reports, reference, {"distance_m": 40.0}).notes == ()


def test_an_adsb_sensor_under_test_owns_its_aircrafts_latencies():
    """The same two aircraft 1 s ahead, the reports an ADS-B sensor's: each transponder keeps its own clock,
    so the note calls the lead the reports' own error, and the false reports are not said to be maybe
    true."""
    reports, reference = _accelerating([1.0, 1.0] + [0.0] * 10, seed=7)
    reports = reports.assign(sensor_kind="adsb")
    (note,) = [n for n in REQUIREMENTS["p95_m"](reports, reference, {"threshold_m": 12.0}).notes
               if n.startswith("timing:")]
    assert "ADS-B under test" in note and "their reference is early or late" not in note
    out = REQUIREMENTS["false_reports"](reports, reference, {"distance_m": 40.0})
    assert out.count > 100 and not [n for n in out.notes if n.startswith("timing:")]
