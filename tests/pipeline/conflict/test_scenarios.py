"""Simulated encounters through the conflict job (decode -> track -> predict -> PC -> events): the loss
the tracked data shows starts when the hand geometry says and is alerted before it at the 60 s horizon;
a 6 NM near miss shows no loss and no alert at 20 s. benchmarks/conflict_scenarios.py runs them all over
several seeds (warning times, false alerts per horizon)."""

from __future__ import annotations

import math
from dataclasses import replace

import pandas as pd
import pytest

from fixtures.conflict_scenarios import DATE, encounters, run_encounter
from fixtures.flight import Segment

ENCOUNTERS = {e.name: e for e in encounters()}
MIDNIGHT = pd.Timestamp(str(DATE), tz="UTC")


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    cache = {}

    def get(name):
        if name not in cache:
            cache[name] = run_encounter(ENCOUNTERS[name], tmp_path_factory.mktemp("enc"))
        return cache[name]
    return get


@pytest.mark.parametrize("name", ["converging 30 deg", "climbing through FL350",
                                  "descending through FL350"])
def test_loss_starts_as_the_geometry_says_and_is_alerted_before_it_at_60_s(runs, name):
    enc = ENCOUNTERS[name]
    r = runs(name)
    assert len(r.losses) == 1
    loss = r.losses.iloc[0]
    start = (loss["start"] - MIDNIGHT).total_seconds()
    end = (loss["end"] - MIDNIGHT).total_seconds()
    # 1 s grid: the first grid time inside the loss is within 1 s of the geometry's start; 1 s more for
    # the tracked (not true) positions and levels
    assert abs(start - enc.loss_s[0]) <= 2.0, (start, enc.loss_s)
    assert abs(end - enc.loss_s[1]) <= 2.0, (end, enc.loss_s)
    warn = r.warning_times.set_index("horizon_s")["warning_s"]
    assert warn.loc[60.0] > 0.0  # alerted before the loss started
    assert warn.loc[20.0] > 0.0
    assert not r.alerts.loc[r.alerts["horizon_s"] <= 60.0, "false_alert"].any()
    if enc.a.alt_ft != enc.b.alt_ft:  # through the level at 420 s, 33 ft/s: < 17 ft at a grid second
        assert loss["min_vertical_ft"] < 100.0


def test_six_nm_crossing_keeps_separation_and_raises_no_20_s_alert(runs):
    r = runs("crossing, 6 NM miss")
    assert r.losses.empty
    # at 20 s the predicted sigmas are a few hundred metres against a 1 NM margin: PC stays far below 0.2
    assert (r.alerts["horizon_s"] == 20.0).sum() == 0
    assert r.alerts["false_alert"].all()  # whatever the 60/120 s horizons raised is false


def test_levelling_off_1000_ft_below_is_no_loss(runs):
    # the tracked levels wobble a few feet either side of 1000 ft apart (983-1003.5 ft over 6 seeds):
    # within the 25 ft level quantum, so separated; with the strict rule the same tracks were losses
    assert runs("levelling off 1000 ft below").losses.empty


def test_nothing_trackable_is_one_line_exit_1_and_writes_nothing(tmp_path, capsys):
    # NACp 0 (unknown) on every ADS-B report: no covariance, so no track (was a traceback)
    from dataclasses import replace

    from fixtures.scenario import default_scenario
    from fixtures.simulate import sensors_toml, simulate
    from msdc.asterix.encode import encode_frame
    from msdc.pipeline.cli import main

    sc = default_scenario()
    sim = simulate(replace(sc, aircraft=sc.aircraft[:2]), seed=3)
    (tmp_path / "a.ast").write_bytes(encode_frame(21, sim.adsb.assign(nacp=0)))
    (tmp_path / "s.toml").write_text(sensors_toml(sc.radar))
    code = main(["conflicts", str(tmp_path / "a.ast"), "--sensors", str(tmp_path / "s.toml"), "--date",
                 "2019-03-01", "-o", str(tmp_path / "c.csv"), "--json", str(tmp_path / "c.json")])
    err = capsys.readouterr().err
    assert code == 1 and "no aircraft could be tracked" in err and "Traceback" not in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.ast", "s.toml"]


def test_climbing_encounter_over_the_radar_is_tracked(tmp_path):
    """Plots almost overhead have no usable horizontal covariance (NaN, skipped by the tracker); the
    encounter is still tracked and its one loss found (this used to divide by a zero determinant)."""
    from fixtures.conflict_scenarios import shifted

    enc = shifted(ENCOUNTERS["climbing through FL350"], -30.0, -20.0)  # crossing point over the radar
    r = run_encounter(enc, tmp_path, seed=11)
    assert len(r.losses) == 1


@pytest.mark.parametrize("cut", ["both", "b"])
def test_a_recording_cut_before_the_closest_point_has_no_loss_after_the_last_report(tmp_path, cut):
    # the converging encounter (closest at 400 s, loss from 322.7 s) with the reports of both aircraft, or
    # of B alone, stopping at 360 s: the tracks coast on for 60 s through the closest point, but a loss is
    # measured only where both are reported. By the geometry the pair is |dv| (400 s - t) apart, |dv| =
    # 2 x 450 kt x sin 15 deg: 2.59 NM at 360 s; before issue 26 the coasted samples gave a loss to 420 s
    # with a minimum near 0
    enc = ENCOUNTERS["converging 30 deg"]
    b = replace(enc.b, segments=(Segment(360.0),))
    a = replace(enc.a, segments=(Segment(360.0),)) if cut == "both" else enc.a
    r = run_encounter(replace(enc, a=a, b=b), tmp_path)
    dv_nm_s = 2 * 450.0 * math.sin(math.radians(15.0)) / 3600.0
    assert len(r.losses) == 1
    loss = r.losses.iloc[0]
    end_s = (loss["end"] - MIDNIGHT).total_seconds()
    assert abs((loss["start"] - MIDNIGHT).total_seconds() - enc.loss_s[0]) <= 2.0
    assert 355.0 <= end_s <= 360.0  # the last grid second both aircraft are reported
    # the closest reported point is at the last reports (4 s radar scans, 1 s ADS-B), 0.1 NM of noise
    assert dv_nm_s * (400.0 - 360.0) - 0.1 <= loss["min_horizontal_nm"] <= dv_nm_s * (400.0 - 355.0) + 0.1
    assert not loss["began_inside"]
