"""Field monitors without RAB: known by Mode 3/A 7777 on every report and by standing still."""

import numpy as np
import pandas as pd

from msdc.pipeline.evaluate.sensor_reports import fixed_7777

LAT0, LON0 = 41.3, 2.1
M_PER_DEG_LAT = 111_132.0  # at 41 deg, to 0.1 %: enough for distances of tens of metres


def _aircraft(aid: str, code: str | None, north_m: np.ndarray) -> pd.DataFrame:
    return pd.DataFrame({"aircraft_id": aid, "mode3a": code,
                         "latitude": LAT0 + north_m / M_PER_DEG_LAT, "longitude": LON0})


def test_a_fixed_7777_transponder_is_a_monitor_and_a_moving_or_parked_one_is_not():
    still = np.tile([0.0, 0.0, 2.0, -2.0], 25)  # 100 reports, median 0 m, none farther than 2 m
    flying = np.arange(100) * 250.0  # an interceptor squawking 7777 moves 250 m a report
    parked = np.zeros(100)  # a parked aircraft: still, but its own code
    few = np.zeros(9)  # still and 7777, but 9 reports: too few to tell
    mixed = np.zeros(100)  # still, one report with another code: not a monitor's
    meas = pd.concat([_aircraft("MON", "7777", still), _aircraft("INT", "7777", flying),
                      _aircraft("PARK", "2341", parked), _aircraft("FEW", "7777", few),
                      _aircraft("MIX", "7777", mixed)], ignore_index=True)
    meas.loc[meas.index[meas["aircraft_id"].eq("MIX")][40], "mode3a"] = "7776"
    found = fixed_7777(meas)
    assert list(found) == ["MON"]
    # distances from the median (0 m): 2 m for 50 of the 100 reports, so the 95th percentile is 2 m
    assert abs(found["MON"] - 2.0) < 0.01


def test_reports_without_a_code_do_not_decide_and_a_wide_scatter_is_no_monitor():
    still = np.zeros(20)
    wide = np.r_[np.zeros(12), np.full(8, 60.0)]  # median 0 m; 8 of 20 reports 60 m off: 95 % within 60 m
    meas = pd.concat([_aircraft("MON", "7777", still), _aircraft("MON", None, still[:5]),
                      _aircraft("WIDE", "7777", wide)], ignore_index=True)
    assert list(fixed_7777(meas)) == ["MON"]
