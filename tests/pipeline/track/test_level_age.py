"""The tracked flight level after the level reports stop. Airborne (or when no report says where the aircraft
is) it is extrapolated with the last vertical rate for at most --max-coast seconds, like the position, then
unknown. On the surface (the reports say so: CAT021 GBS, CAT048 STAT; a landing aircraft in CAT021 0.2x
reports its position but no level) it is held at its estimate at the last level report for the same time,
then unknown: never flown on below the ground at the approach's rate."""

import numpy as np
import pandas as pd
import pytest
from pyproj import Geod

from msdc.pipeline.track import track

GEOD = Geod(ellps="WGS84")
T0 = pd.Timestamp("2016-05-10T22:30:00Z")
LAST_FL_S = 120.0  # the last level report
RATE_FL_S = -500.0 / 100.0 / 60.0  # -500 ft/min in FL per second


def _reports(t: np.ndarray, north_m: np.ndarray, fl: np.ndarray, **extra) -> pd.DataFrame:
    """1 Hz ADS-B reports due north of (41 N, 2.08 E), 10 m sigma per axis."""
    lon, lat, _ = GEOD.fwd(np.full(len(t), 2.08), np.full(len(t), 41.0), np.zeros(len(t)), north_m)
    return pd.DataFrame({"time": T0 + pd.to_timedelta(t, unit="s"), "sensor_id": "021:0/107",
                         "sensor_kind": "adsb", "aircraft_id": "344386", "latitude": lat, "longitude": lon,
                         "flight_level": fl, "cov_ee_m2": 100.0, "cov_en_m2": 0.0, "cov_nn_m2": 100.0,
                         **extra})


def _levels_stop() -> pd.DataFrame:
    """Due north at 40 m/s: 120 s descending at -500 ft/min from FL 20, then 300 s on with no level reported
    and nothing said about the surface."""
    t = np.arange(0.0, 421.0)
    return _reports(t, 40.0 * t, np.where(t <= LAST_FL_S, 20.0 + RATE_FL_S * t, np.nan))


@pytest.mark.parametrize("smooth", [False, True])
def test_the_level_is_extrapolated_for_max_coast_seconds_then_unknown(smooth):
    out = track(_levels_stop(), step_s=1.0, max_coast_s=60.0, smooth=smooth).tracks
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
    assert out["on_ground"].isna().all()  # no report said anything about the surface


TOUCHDOWN_FL = 1.0
APPROACH_FL_S = -700.0 / 100.0 / 60.0  # -700 ft/min


def _landing(with_ground_bit: bool = True) -> pd.DataFrame:
    """An approach at -700 ft/min and 140 kt (72 m/s) reaching FL 1.0 at 120 s (its last level report), then
    a landing roll with the ground bit set and no level (CAT021 0.2x), decelerating at 1.5 m/s^2 to 10 m/s
    and taxiing on: 300 s in all."""
    t = np.arange(0.0, 421.0)
    roll = np.clip(t - LAST_FL_S, 0.0, None)
    v_touchdown, decel, taxi = 72.0, 1.5, 10.0
    stop_s = (v_touchdown - taxi) / decel
    rolled = np.where(roll <= stop_s, v_touchdown * roll - 0.5 * decel * roll**2,
                      v_touchdown * stop_s - 0.5 * decel * stop_s**2 + taxi * (roll - stop_s))
    north = v_touchdown * np.minimum(t, LAST_FL_S) + rolled
    fl = np.where(t <= LAST_FL_S, TOUCHDOWN_FL + APPROACH_FL_S * (t - LAST_FL_S), np.nan)
    extra = {"on_ground": pd.array(t > LAST_FL_S, dtype="boolean")} if with_ground_bit else {}
    return _reports(t, north, fl, **extra)


@pytest.mark.parametrize("smooth", [False, True])
def test_on_the_surface_the_level_is_held_at_the_last_report_not_flown_below_it(smooth):
    out = track(_landing(), step_s=1.0, max_coast_s=60.0, smooth=smooth).tracks
    age = (out["time"] - T0).dt.total_seconds() - LAST_FL_S
    assert out["segment"].nunique() == 1
    rolling = out[(age > 0) & (age <= 60.0)]
    # held at the last report's FL 1.0 (the vertical filter's estimate there: exact on a constant-rate
    # descent, within 0.1 FL = 10 ft), rate 0, for 60 s: never below the lowest level reported
    assert len(rolling) >= 60
    assert np.abs(rolling["flight_level"] - TOUCHDOWN_FL).max() < 0.1
    assert (rolling["vertical_rate_fpm"] == 0.0).all()
    assert rolling["on_ground"].all() and not out.loc[age < 0, "on_ground"].any()
    assert out["flight_level"].min() > TOUCHDOWN_FL - 0.1
    assert out.loc[age > 60.0, "flight_level"].isna().all()  # then unknown, as airborne
    # without the ground bit the same reports are flown on at -700 ft/min: 7 FL below the last report
    # after 60 s (what the recording showed: FL -8.66 under a lowest decoded level of 1.0)
    blind = track(_landing(with_ground_bit=False), step_s=1.0, max_coast_s=60.0, smooth=smooth).tracks
    blind_age = (blind["time"] - T0).dt.total_seconds() - LAST_FL_S
    assert blind.loc[(blind_age > 55.0) & (blind_age <= 60.0), "flight_level"].max() < TOUCHDOWN_FL - 6.0


def test_the_rate_is_learnt_again_on_the_climb_out():
    """Taxi with the ground bit set and level reports at FL 0 (as Mode S radar plots on the ground), then a
    take-off climbing at 2000 ft/min: the tracked level follows the climb within 50 ft after 20 s and the
    surface's zero rate does not hold it down."""
    t = np.arange(0.0, 181.0)
    lift_s, climb_fl_s = 90.0, 2000.0 / 100.0 / 60.0
    fl = np.where(t < lift_s, 0.0, climb_fl_s * (t - lift_s))
    north = np.where(t < lift_s, 5.0 * t, 5.0 * lift_s + 75.0 * (t - lift_s))
    out = track(_reports(t, north, fl, on_ground=pd.array(t < lift_s, dtype="boolean")), step_s=1.0,
                max_coast_s=60.0).tracks
    tt = (out["time"] - T0).dt.total_seconds()
    assert (out.loc[tt < lift_s, "vertical_rate_fpm"] == 0.0).all()
    climbing = out[tt >= lift_s + 20.0]
    truth = climb_fl_s * (tt[climbing.index] - lift_s)
    assert np.abs(climbing["flight_level"] - truth).max() < 0.5
    assert not climbing["on_ground"].any()
