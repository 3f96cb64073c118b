"""Position accuracy on hand-built aircraft: each report placed with pyproj's geodesic (an independent
method) at a chosen offset behind and to the right of the reference, so every statistic is known."""

from __future__ import annotations

import math

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
