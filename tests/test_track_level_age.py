"""The tracked flight level after the level reports stop (an aircraft that lands and taxies reports its
position but, in CAT021 0.2x, no level): extrapolated with the last vertical rate for at most
--max-coast seconds, like the position, then unknown; never flown on for minutes below the ground."""

import numpy as np
import pandas as pd
import pytest
from pyproj import Geod

from pipeline.track import track

GEOD = Geod(ellps="WGS84")
T0 = pd.Timestamp("2016-05-10T22:30:00Z")
LAST_FL_S = 120.0  # the last level report
RATE_FL_S = -500.0 / 100.0 / 60.0  # -500 ft/min in FL per second


def _landing() -> pd.DataFrame:
    """1 Hz ADS-B due north at 40 m/s: 120 s descending at -500 ft/min from FL 20, then 300 s on with no
    level reported."""
    t = np.arange(0.0, 421.0)
    north_m = 40.0 * t
    lon, lat, _ = GEOD.fwd(np.full(len(t), 2.08), np.full(len(t), 41.0), np.zeros(len(t)), north_m)
    fl = np.where(t <= LAST_FL_S, 20.0 + RATE_FL_S * t, np.nan)
    return pd.DataFrame({"time": T0 + pd.to_timedelta(t, unit="s"), "sensor_id": "021:0/107",
                         "sensor_kind": "adsb", "aircraft_id": "344386", "latitude": lat, "longitude": lon,
                         "flight_level": fl, "cov_ee_m2": 100.0, "cov_en_m2": 0.0, "cov_nn_m2": 100.0})


@pytest.mark.parametrize("smooth", [False, True])
def test_the_level_is_extrapolated_for_max_coast_seconds_then_unknown(smooth):
    out = track(_landing(), step_s=1.0, max_coast_s=60.0, smooth=smooth).tracks
    age = (out["time"] - T0).dt.total_seconds() - LAST_FL_S
    assert len(out) and out["segment"].nunique() == 1
    before = out[age <= 0]
    assert before["flight_level"].notna().all()
    # within 60 s: the last level flown on at the last rate (FL 10 at the last report, 5 FL a minute)
    soon = out[(age > 0) & (age <= 60.0)]
    expected = 10.0 + RATE_FL_S * age[soon.index]
    assert np.abs(soon["flight_level"] - expected).max() < 0.5
    later = out[age > 60.0]
    assert len(later) > 200  # the position is still tracked on the surface...
    assert later["flight_level"].isna().all()  # ...its level is unknown, not FL -15
    assert later["vertical_rate_fpm"].isna().all()
