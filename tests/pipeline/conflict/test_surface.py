"""Aircraft on the aerodrome surface in `msdc conflicts`: separation minima apply between airborne aircraft,
so pairs with an aircraft on the surface are left out of the losses and alerts (counted apart), unless
--surface include. The on-ground indication comes from the reports (CAT021 GBS, CAT048 STAT codes as the
spec's table gives them, RAB), else from a tracked speed below 50 kt."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from pyproj import Geod

from msdc.asterix.encode import encode_frame
from msdc.pipeline.cli import main
from msdc.pipeline.conflict import losses_of_separation
from msdc.pipeline.conflict.events import losses_by_pairs
from msdc.pipeline.conflict.surface import on_surface, surface_pairs

GEOD = Geod(ellps="WGS84")


def zip_(*columns) -> zip:
    return zip(*columns, strict=True)
NM = 1852.0
KT = NM / 3600.0  # m/s per kt
LAT0, LON0 = 41.30, 2.08  # the aerodrome's reference point
T_END_S = 300.0
T0 = pd.Timestamp("2019-03-01", tz="UTC")


def test_a_report_saying_airborne_is_believed_at_any_speed_and_speed_decides_only_when_none_said():
    tracks = pd.DataFrame({"speed_kt": [30.0, 30.0, 30.0, 120.0, 49.9, 50.0],
                           "on_ground": pd.array([False, True, None, True, None, None], dtype="boolean")})
    surface, by_speed = on_surface(tracks)
    assert surface.tolist() == [False, True, True, True, True, False]  # a helicopter at 30 kt flies
    assert by_speed.tolist() == [False, False, True, False, True, False]


def _pairs_tracks() -> pd.DataFrame:
    """Three aircraft on a 1 s grid for 4 s: A and B airborne 1 NM apart at FL100 throughout; C 0.5 NM
    from A at FL100, on the surface at t = 1 and 2 s only (as a report would say)."""
    rows = []
    for k in range(4):
        t = T0 + pd.Timedelta(seconds=k)
        for ident, north_nm, ground in (("A", 0.0, False), ("B", 1.0, False), ("C", -0.5, k in (1, 2))):
            lon, lat, _ = GEOD.fwd(LON0, LAT0, 0.0, north_nm * NM)
            rows.append({"aircraft_id": ident, "time": t, "latitude": lat, "longitude": lon,
                         "flight_level": 100.0, "on_surface": ground})
    return pd.DataFrame(rows)


def test_losses_split_by_surface_pairs():
    tracks = _pairs_tracks()
    # by hand: every pair is within 5 NM and at the same level at every second; A-B never on the surface;
    # A-C and B-C are pairs with a surface aircraft at 1-2 s, airborne pairs at 0 s and at 3 s
    every = losses_of_separation(tracks)
    assert sorted(zip_(every["aircraft_a"], every["aircraft_b"], every["duration_s"])) == [
        ("A", "B", 3.0), ("A", "C", 3.0), ("B", "C", 3.0)]
    airborne = losses_of_separation(tracks, pairs="airborne")
    got = sorted(zip_(airborne["aircraft_a"], airborne["aircraft_b"], (airborne["start"] - T0).dt.seconds,
                     airborne["duration_s"]))
    assert got == [("A", "B", 0, 3.0), ("A", "C", 0, 0.0), ("A", "C", 3, 0.0), ("B", "C", 0, 0.0),
                   ("B", "C", 3, 0.0)]
    surface = losses_of_separation(tracks, pairs="surface")
    got = sorted(zip_(surface["aircraft_a"], surface["aircraft_b"], (surface["start"] - T0).dt.seconds,
                     surface["duration_s"]))
    assert got == [("A", "C", 1, 1.0), ("B", "C", 1, 1.0)]
    pc = pd.DataFrame({"time": [T0, T0 + pd.Timedelta(seconds=1), T0 + pd.Timedelta(seconds=1)],
                       "aircraft_a": ["A", "A", "C"], "aircraft_b": ["B", "C", "B"]})
    assert surface_pairs(pc, tracks).tolist() == [False, True, True]
    both = losses_by_pairs(tracks, kinds=("all", "airborne", "surface"))  # one pair search, the same runs
    for kind, alone in (("all", every), ("airborne", airborne), ("surface", surface)):
        pd.testing.assert_frame_equal(both[kind], alone)
    with pytest.raises(ValueError, match="on_surface"):
        losses_of_separation(tracks.drop(columns="on_surface"), pairs="airborne")


# --- the scenario through msdc conflicts ------------------------------------------------------------------

DEPARTURE_KT = 150.0
LIFT_OFF_S = 60.0
CLIMB_FPM = 2000.0
AIRBORNE_KT = 250.0
OFFSET_NM = 1.0  # the airborne pair's lateral offset
START_APART_NM = 20.0
# the airborne pair closes at 500 kt from 20 NM apart, 1 NM abeam: closer than 5 NM while
# |20 - 500 t / 3600| < sqrt(5^2 - 1^2), i.e. from 108.7 s to 179.3 s: grid times 110 to 175 at 5 s
CLOSING_NM_S = 2 * AIRBORNE_KT / 3600.0
LOSS_FROM_S = (START_APART_NM - np.sqrt(5.0**2 - OFFSET_NM**2)) / CLOSING_NM_S
LOSS_TO_S = (START_APART_NM + np.sqrt(5.0**2 - OFFSET_NM**2)) / CLOSING_NM_S


def _report_rows(address: str, t: np.ndarray, east_m: np.ndarray, north_m: np.ndarray, fl: np.ndarray,
                 speed_kt: np.ndarray, track_deg: float, gbs: np.ndarray, origin=(LON0, LAT0)
                 ) -> pd.DataFrame:
    """1 Hz CAT021 reports of one aircraft at east/north metres from ``origin`` (east then north)."""
    n = len(t)
    lon, lat, _ = GEOD.fwd(np.full(n, origin[0]), np.full(n, origin[1]), np.full(n, 90.0), east_m)
    lon, lat, _ = GEOD.fwd(lon, lat, np.zeros(len(t)), north_m)
    return pd.DataFrame({"sac": 0, "sic": 107, "time_of_day": t, "latitude": lat, "longitude": lon,
                         "address": address, "flight_level": fl, "ground_speed_kt": speed_kt,
                         "track_angle_deg": track_deg, "nacp": 9, "gbs": gbs})


def surface_scenario() -> pd.DataFrame:
    """Five aircraft reporting every second for 300 s (CAT021 2.7, exact positions, NACp 9):
    - P1 (A00001) and P2 (A00002) parked 60 m apart at the aerodrome, ground bit set, FL 0;
    - D (A00003) rolls east at 150 kt on a runway 300 m north of them from 3 km west, ground bit set and
      FL 0, lifts off at 60 s and climbs at 2000 fpm (ground bit clear): it passes the parked aircraft;
    - E (A00004) and W (A00005) fly at FL100 and 250 kt 30 NM north of the aerodrome, E eastbound from
      10 NM west of a point, W westbound from 10 NM east of it 1 NM further north: a real loss."""
    t = np.arange(0.0, T_END_S + 1.0)
    n = len(t)
    zero, one = np.zeros(n), np.ones(n, int)
    parts = [_report_rows("A00001", t, zero, zero, zero, zero, 0.0, one),
             _report_rows("A00002", t, zero + 60.0, zero, zero, zero, 0.0, one)]
    air = t >= LIFT_OFF_S
    fl_d = np.where(air, (t - LIFT_OFF_S) * CLIMB_FPM / 60.0 / 100.0, 0.0)
    parts.append(_report_rows("A00003", t, -3000.0 + DEPARTURE_KT * KT * t, zero + 300.0, fl_d,
                              np.full(n, DEPARTURE_KT), 90.0, np.where(air, 0, 1)))
    centre = GEOD.fwd(LON0, LAT0, 0.0, 30 * NM)[:2]
    run_m = AIRBORNE_KT * KT * t
    parts.append(_report_rows("A00004", t, -START_APART_NM / 2 * NM + run_m, zero, np.full(n, 100.0),
                              np.full(n, AIRBORNE_KT), 90.0, 0 * one, origin=centre))
    parts.append(_report_rows("A00005", t, START_APART_NM / 2 * NM - run_m, zero + OFFSET_NM * NM,
                              np.full(n, 100.0), np.full(n, AIRBORNE_KT), 270.0, 0 * one, origin=centre))
    return pd.concat(parts, ignore_index=True).sort_values("time_of_day", kind="stable")


@pytest.fixture(scope="module")
def surface_file(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("surface") / "surface.ast"
    path.write_bytes(encode_frame(21, surface_scenario()))
    return path


def _run(path: Path, out: Path, *extra: str) -> tuple[pd.DataFrame, pd.DataFrame, dict, str]:
    code = main(["conflicts", str(path), "--date", "2019-03-01", "--step", "5", "-o", str(out / "c.csv"),
                 "--json", str(out / "c.json"), *extra])
    assert code == 0
    losses = pd.read_csv(out / "c_losses.csv", parse_dates=["start", "end"], dtype={"aircraft_a": str,
                                                                                   "aircraft_b": str})
    alerts = pd.read_csv(out / "c.csv", dtype={"aircraft_a": str, "aircraft_b": str})
    return losses, alerts, json.loads((out / "c.json").read_text()), str(out)


def test_surface_pairs_are_left_out_of_losses_and_alerts_and_counted(surface_file, tmp_path, capsys):
    losses, alerts, doc, _ = _run(surface_file, tmp_path)
    text = capsys.readouterr().out
    # by hand: the one airborne pair, E and W, from the first grid time after 108.7 s to the last before
    # 179.3 s; nothing else, though the parked pair and the departure are within 5 NM and 975 ft
    assert list(zip_(losses["aircraft_a"], losses["aircraft_b"])) == [("A00004", "A00005")]
    assert (losses["start"].iloc[0] - T0).total_seconds() == 5 * np.ceil(LOSS_FROM_S / 5) == 110.0
    assert (losses["end"].iloc[0] - T0).total_seconds() == 5 * np.floor(LOSS_TO_S / 5) == 175.0
    assert len(alerts) and set(zip_(alerts["aircraft_a"], alerts["aircraft_b"])) == {("A00004", "A00005")}
    assert not alerts["false_alert"].any()
    surface = doc["counts"]["surface"]
    # the surface pairs' losses, by hand: P1-P2 parked the whole time, P1-D and P2-D from the start until
    # D climbs through 975 ft above them (89 s): one run each
    assert surface["losses"] == 3 and surface["excluded"] is True
    assert surface["aircraft"] == 3 and surface["rows_by_speed"] == 0  # every report says
    assert surface["alerts"] >= 3  # the parked pair alone alerts at every horizon
    assert doc["counts"]["losses"] == 1 and doc["parameters"]["surface"] == "exclude"
    # what --surface include would give: the four losses of the test below; this run's own tables
    assert surface["include"]["losses"] == 4
    assert surface["exclude"] == {"losses": 1, "alerts": len(alerts)}
    n_include, n_alone = surface["include"]["alerts"], surface["alerts"]
    assert ("pairs with an aircraft on the surface are left out of the tables: --surface include would "
            f"give 4 loss(es) and {n_include} alert event(s) instead of 1 and {len(alerts)} "
            f"(3 loss(es) and {n_alone} alert event(s) among the surface pairs' samples alone") in text


def test_surface_include_keeps_them(surface_file, tmp_path, capsys):
    losses, alerts, doc, _ = _run(surface_file, tmp_path, "--surface", "include")
    pairs = sorted(zip_(losses["aircraft_a"], losses["aircraft_b"]))
    assert pairs == [("A00001", "A00002"), ("A00001", "A00003"), ("A00002", "A00003"), ("A00004", "A00005")]
    parked = losses[(losses["aircraft_a"] == "A00001") & (losses["aircraft_b"] == "A00002")].iloc[0]
    assert (parked["start"] - T0).total_seconds() == 0.0 and (parked["end"] - T0).total_seconds() >= T_END_S
    # D climbs through 975 ft above the parked aircraft at 60 + 975 / 2000 * 60 = 89.25 s; its tracked
    # level lags the climb's start by a few seconds (the rate is learnt again after the ground roll)
    for other in ("A00001", "A00002"):
        run = losses[(losses["aircraft_a"] == other) & (losses["aircraft_b"] == "A00003")].iloc[0]
        assert 85.0 <= (run["end"] - T0).total_seconds() <= 100.0
    # the parked pair's PC stays near 1: one alert event per horizon, all its time
    parked_alerts = alerts[(alerts["aircraft_a"] == "A00001") & (alerts["aircraft_b"] == "A00002")]
    assert sorted(parked_alerts["horizon_s"]) == [20.0, 60.0, 120.0]
    assert doc["counts"]["losses"] == 4 and doc["counts"]["surface"]["losses"] == 3
    assert doc["counts"]["surface"]["excluded"] is False and "kept in the tables" in capsys.readouterr().out
    assert doc["counts"]["surface"]["include"] == {"losses": 4, "alerts": len(alerts)}
    assert doc["counts"]["surface"]["exclude"]["losses"] == 1


def test_surface_counts_reconcile_between_the_two_modes(surface_file, tmp_path):
    """Each run says what the other mode's tables hold: the other run's table sizes."""
    (tmp_path / "x").mkdir()
    (tmp_path / "i").mkdir()
    lx, ax, dx, _ = _run(surface_file, tmp_path / "x")
    li, ai, di, _ = _run(surface_file, tmp_path / "i", "--surface", "include")
    assert dx["counts"]["surface"]["include"] == {"losses": len(li), "alerts": len(ai)}
    assert di["counts"]["surface"]["exclude"] == {"losses": len(lx), "alerts": len(ax)}


def test_bad_surface_option_is_refused(surface_file, tmp_path, capsys):
    assert main(["conflicts", str(surface_file), "--surface", "maybe", "-o", str(tmp_path / "c.csv")]) == 2
    err = capsys.readouterr().err.strip()
    assert "--surface 'maybe': must be exclude or include" in err and "\n" not in err
    assert list(tmp_path.iterdir()) == []
