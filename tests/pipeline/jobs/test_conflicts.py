"""``msdc conflicts``: options refused before decoding (one line, exit 2, nothing written), the bundled
fixtures (no loss: empty tables with headers), and a simulated crossing at the same level whose loss of
separation starts when the hand-computed geometry says and is alerted before it at the 60 s horizon."""

from __future__ import annotations

import datetime as dt
import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from openpyxl import load_workbook

from fixtures.flight import Flight, Segment
from fixtures.scenario import AircraftSpec, default_scenario
from fixtures.simulate import sensors_toml, simulate
from msdc.asterix.encode import encode_frame
from msdc.pipeline.cli import main
from msdc.pipeline.jobs import common, conflicts
from msdc.pipeline.jobs.common import OptionError
from msdc.pipeline.jobs.conflicts import ConflictOptions
from msdc.pipeline.report.headers import column_name

FIX = Path(__file__).resolve().parents[3] / "fixtures"
RADAR, ADSB, SENSORS = str(FIX / "radar.ast"), str(FIX / "adsb.ast"), str(FIX / "sensors.toml")


# every table names the pair by address, call sign and Mode 3/A code, and says where the pair was
PAIR = ["aircraft_a", "callsign_a", "mode3a_a", "aircraft_b", "callsign_b", "mode3a_b"]
WHERE = ["latitude", "longitude", "flight_level_a", "flight_level_b"]
ALERT_TABLE = PAIR + ["horizon_s", "start", *WHERE, "end", "peak_pc", "time_of_peak", "loss_start",
                      "false_alert", "time_to_cpa_s", "cpa_time", "cpa_horizontal_nm", "cpa_vertical_ft"]
LOSS_TABLE = PAIR + ["start", "end", "duration_s", "began_inside", "min_horizontal_nm", "time_of_min", *WHERE,
                     "vertical_at_min_ft", "min_vertical_ft"]
WARNING_TABLE = PAIR + ["loss_start", *WHERE, "began_inside", "horizon_s", "alert_start", "warning_s"]


def opts(**kw) -> ConflictOptions:
    return ConflictOptions(**({"inputs": (RADAR, ADSB), "sensors": SENSORS, "output": "c.csv"} | kw))


BAD = [
    (opts(horizons_s="20,x"), "--horizon '20,x': item 2 'x' is not a number"),
    (opts(horizons_s="20,,60"), "--horizon '20,,60': item 2 is empty"),  # named '' before
    (opts(horizons_s="20,20"), "repeated"),
    (opts(horizons_s="0"), "--horizon 0.0"),
    (opts(horizons_s="15", step_s=10.0), "--horizon 15: must be a whole multiple of --step (10 s)"),
    (opts(radius_nm=-5.0), "--radius-nm -5.0"),
    (opts(vertical_ft=float("nan")), "--vertical-ft nan"),
    (opts(vertical_tolerance_ft=-5.0), "--vertical-tolerance-ft -5.0"),
    (opts(vertical_tolerance_ft=float("inf")), "--vertical-tolerance-ft inf"),
    (opts(vertical_ft=100.0, vertical_tolerance_ft=100.0),
     "--vertical-tolerance-ft 100.0: must be less than --vertical-ft (100)"),
    (opts(threshold=1.0), "--threshold 1.0"),
    (opts(threshold=0.0), "--threshold 0.0"),
    (opts(method="montecarlo"), "--method 'montecarlo'"),
    (opts(step_s=0.0), "--step 0.0"),
    (opts(tpm="banana"), "--tpm 'banana'"),
    (opts(tpm="dynamic:-1,2"), "--tpm 'dynamic:-1,2': p(T) = min(0.995, -1 - 2 T) is -1 at T = 0 s"),
    (opts(output="c.parquet"), "-o c.parquet: must end in .csv or .xlsx"),
    (opts(json="c.txt"), "--json c.txt"),
    (opts(sensors="/nonexistent/s.toml"), "--sensors /nonexistent/s.toml"),
    (opts(vertical="probable"), "--vertical 'probable'"),
    (opts(sources="radar,wam"), "--sources 'radar,wam'"),
    (opts(figures="/nonexistent/dir/figs"), "--figures /nonexistent/dir/figs: directory /nonexistent/dir"),
    (opts(figures=RADAR), "--figures " + RADAR + ": exists and is not a directory"),
    (opts(exclude_codes="7000,7008"), "--exclude-codes '7000,7008': item 2 '7008' is not a Mode 3/A code"),
    (opts(exclude_codes=()), "--exclude-codes: give at least one Mode 3/A code"),
    (opts(min_fl=2000.0), "--min-fl 2000.0: must be a finite number from -20 to 1000 FL"),
    (opts(max_report_gap_s=0.0), "--max-report-gap 0.0"),
]


@pytest.mark.parametrize(("options", "words"), BAD)
def test_bad_options_refused_before_decoding(options, words, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(common, "load", lambda *a, **k: pytest.fail("decoded before validating"))
    with pytest.raises(OptionError) as info:
        conflicts.validate(options)
    assert words in str(info.value) and "\n" not in str(info.value)
    assert info.value.status == 2


def test_cli_bad_option_is_one_line_exit_2_and_writes_nothing(tmp_path, capsys):
    out = tmp_path / "c.csv"
    assert main(["conflicts", RADAR, ADSB, "--sensors", SENSORS, "--threshold", "2", "-o", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("msdc conflicts: --threshold 2.0") and "\n" not in err
    assert list(tmp_path.iterdir()) == []


def test_cli_bad_vertical_tolerance_is_one_line_exit_2_and_writes_nothing(tmp_path, capsys):
    out = tmp_path / "c.csv"
    code = main(["conflicts", RADAR, ADSB, "--sensors", SENSORS, "--vertical-tolerance-ft", "-1",
                 "-o", str(out)])
    err = capsys.readouterr().err.strip()
    assert code == 2 and err.startswith("msdc conflicts: --vertical-tolerance-ft -1.0") and "\n" not in err
    assert list(tmp_path.iterdir()) == []


def test_fixtures_without_loss_write_empty_tables_with_headers(tmp_path, capsys):
    out = tmp_path / "c.xlsx"
    code = main(["conflicts", RADAR, ADSB, "--sensors", SENSORS, "--date", "2019-03-01", "--step", "10",
                 "-o", str(out), "--json", str(tmp_path / "c.json")])
    assert code == 0
    text = capsys.readouterr().out
    assert "5 aircraft tracked; 0 loss(es)" in text and "written empty, with their headers" in text
    wb = load_workbook(out, read_only=True)
    assert wb.sheetnames == ["Alerts", "Losses", "Warning times", "Parameters"]
    for sheet, columns in (("Alerts", ALERT_TABLE), ("Losses", LOSS_TABLE), ("Warning times", WARNING_TABLE)):
        rows = list(wb[sheet].iter_rows(values_only=True))
        assert [column_name(h) for h in rows[0]] == columns and len(rows) == 1
    doc = json.loads((tmp_path / "c.json").read_text())
    assert doc["counts"]["losses"] == 0 and doc["parameters"]["horizons_s"] == [20.0, 60.0, 120.0]


# two aircraft at FL350, 420 kt, one flying east from 40 NM west of the radar, one north from 40 NM south:
# their distance is sqrt(2) |40 NM - v t|, below 5 NM from t = (40 - 5/sqrt(2)) / v
SPEED_KT = 420.0
LOSS_START_S = (40.0 - 5.0 / 2**0.5) / (SPEED_KT / 3600.0)  # 312.3 s
CLOSEST_S = 40.0 / (SPEED_KT / 3600.0)  # 342.9 s


@pytest.fixture(scope="module")
def crossing(tmp_path_factory):
    d = tmp_path_factory.mktemp("crossing")
    east = AircraftSpec("CONA", 0x710001, "1001",
                        flights=(Flight(0.0, -40.0, 0.0, 35000.0, SPEED_KT, 90.0, (Segment(600.0),)),))
    north = AircraftSpec("CONB", 0x710002, "1002",
                         flights=(Flight(0.0, 0.0, -40.0, 35000.0, SPEED_KT, 0.0, (Segment(600.0),)),))
    sc = replace(default_scenario(), name="crossing", aircraft=(east, north), adsb_jump_fraction=0.0,
                 adsb_long_dropouts=0, adsb_short_dropouts_per_hour=0.0, adsb_low_quality_episodes=0,
                 radar_long_dropouts=0)
    sim = simulate(sc, seed=7)
    (d / "r.ast").write_bytes(encode_frame(48, sim.radar))
    (d / "a.ast").write_bytes(encode_frame(21, sim.adsb))
    (d / "s.toml").write_text(sensors_toml(sc.radar))
    return d


def test_crossing_loss_found_and_alerted_before_it_starts_at_60_s(crossing, capsys):
    d = crossing
    out = d / "c.csv"
    assert main(["conflicts", str(d / "r.ast"), str(d / "a.ast"), "--sensors", str(d / "s.toml"),
                 "--date", "2019-03-01", "-o", str(out), "--figures", str(d / "figs")]) == 0
    assert "1 loss(es) of separation" in capsys.readouterr().out
    midnight = pd.Timestamp("2019-03-01", tz="UTC")
    losses = pd.read_csv(d / "c_losses.csv", parse_dates=["start", "end", "time_of_min"],
                         dtype={"aircraft_a": str, "aircraft_b": str})
    assert len(losses) == 1
    loss = losses.iloc[0]
    assert (loss["aircraft_a"], loss["aircraft_b"]) == ("710001", "710002")
    start_s = (loss["start"] - midnight).total_seconds()
    assert abs(start_s - LOSS_START_S) <= 2.0
    assert abs((loss["time_of_min"] - midnight).total_seconds() - CLOSEST_S) <= 2.0
    assert loss["min_horizontal_nm"] < 0.2 and loss["min_vertical_ft"] < 100
    warn = pd.read_csv(d / "c_warning_times.csv")
    w60 = warn.loc[warn["horizon_s"] == 60, "warning_s"]
    assert len(w60) == 1 and w60.iloc[0] > 0  # alerted before the loss started
    alerts = pd.read_csv(d / "c.csv", parse_dates=["cpa_time"], dtype={"mode3a_a": str, "mode3a_b": str})
    assert list(alerts.columns) == ALERT_TABLE
    assert list(losses.columns) == LOSS_TABLE and list(warn.columns) == WARNING_TABLE
    # the pair named as the simulator made it (CONA squawking 1001, CONB 1002), and where it met: over the
    # radar (the flights cross at its site), both at FL350
    assert (loss["callsign_a"], loss["mode3a_a"], loss["callsign_b"], loss["mode3a_b"]) == (
        "CONA", 1001, "CONB", 1002)
    assert abs(loss["latitude"] - 2.7456) < 0.005 and abs(loss["longitude"] - 101.7099) < 0.005
    assert abs(loss["flight_level_a"] - 350) < 1 and abs(loss["flight_level_b"] - 350) < 1
    assert not loss["began_inside"] and not warn["began_inside"].any()
    assert (alerts["callsign_a"] == "CONA").all() and (alerts["mode3a_b"] == "1002").all()
    assert not alerts["false_alert"].any()
    assert (alerts.loc[alerts["horizon_s"] == 60, "peak_pc"] > 0.5).all()
    # the predicted closest approach: the geometry's, at 342.9 s, within a few seconds and 0.3 NM
    for _, a in alerts.iterrows():
        assert abs((a["cpa_time"] - midnight).total_seconds() - CLOSEST_S) < 5.0
        assert a["cpa_horizontal_nm"] < 0.3 and a["cpa_vertical_ft"] < 100
    # one figure per alert event, named by its row, pair and horizon
    names = sorted(p.name for p in (d / "figs").iterdir())
    assert names == sorted(f"alert_{i + 1:03d}_710001_710002_{h:g}s.png"
                           for i, h in enumerate(alerts["horizon_s"]))
    png = (d / "figs" / names[0]).read_bytes()
    assert png.startswith(b"\x89PNG\r\n\x1a\n") and len(png) > 20_000


@pytest.mark.parametrize(("selection", "left_out"), [({"min_fl": 360.0}, "below_min_fl"),
                                                    ({"exclude_codes": "1001"}, "excluded_codes")])
def test_the_selection_leaves_samples_out_and_says_what_it_would_give(crossing, selection, left_out):
    # both aircraft fly at FL350 and CONA squawks 1001 throughout: either selection leaves the loss and
    # every alert out, and the counts say what was left out and that the loss is there without it
    d = crossing
    options = ConflictOptions(inputs=(str(d / "r.ast"), str(d / "a.ast")), sensors=str(d / "s.toml"),
                              date=dt.date(2019, 3, 1), output=str(d / "sel.csv"), step_s=5.0, **selection)
    result = conflicts.conflict_job(options)
    assert result.losses.empty and result.alerts.empty
    sel = result.counts["selection"]
    grid = result.tracks
    expected = len(grid) if left_out == "below_min_fl" else int((grid["aircraft_id"] == "710001").sum())
    assert sel["active"] and sel["left_out"] == sel[left_out] == expected and sel["losses_without"] == 1
    assert "without it 1 loss(es)" in conflicts.text(result)


def test_failed_run_after_decoding_writes_nothing(tmp_path, capsys):
    # the radar of the recording (SAC/SIC 25/201) is not in this sensor file: a data error, exit 1
    sensors = tmp_path / "other.toml"
    sensors.write_text('[[sensor]]\nname = "Elsewhere"\nsac = 1\nsic = 1\nlatitude = 3.0\nlongitude = 101.0\n'
                       'altitude_m = 10.0\n')
    out = tmp_path / "c.csv"
    code = main(["conflicts", RADAR, "--sensors", str(sensors), "--date", "2019-03-01", "-o", str(out),
                 "--json", str(tmp_path / "c.json")])
    err = capsys.readouterr().err
    assert code == 1 and "25/201" in err and "Traceback" not in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["other.toml"]


def test_failure_while_writing_figures_leaves_nothing(crossing, tmp_path, monkeypatch, capsys):
    import msdc.pipeline.report.conflict_figures as figures
    from msdc.pipeline.report import figure_pool

    real, calls = figures.alert_figure, []

    def second_fails(**kwargs):
        calls.append(kwargs["path"])
        if len(calls) == 2:
            raise OSError(28, "No space left on device", str(kwargs["path"]))
        return real(**kwargs)

    monkeypatch.setattr(figures, "alert_figure", second_fails)
    monkeypatch.setattr(figure_pool, "cores", lambda: 1)  # the patch reaches this process only: drawn here
    d = crossing
    code = main(["conflicts", str(d / "r.ast"), str(d / "a.ast"), "--sensors", str(d / "s.toml"),
                 "--date", "2019-03-01", "--step", "5", "-o", str(tmp_path / "c.xlsx"),
                 "--json", str(tmp_path / "c.json"), "--figures", str(tmp_path / "figs")])
    err = capsys.readouterr().err
    assert code == 1 and "No space left on device" in err and "Traceback" not in err
    assert len(calls) == 2 and list(tmp_path.iterdir()) == []



def test_an_alert_figure_from_its_cut_data_is_the_one_from_the_whole_frames(crossing, tmp_path):
    # what a worker gets (AlertData: the pair's rows in the figure's window) draws the very pixels that
    # alert_figure draws from the job's whole frames
    from PIL import Image

    from msdc.pipeline.report.conflict_figures import AlertData, alert_figure

    d = crossing
    options = ConflictOptions(inputs=(str(d / "r.ast"), str(d / "a.ast")), sensors=str(d / "s.toml"),
                              date=dt.date(2019, 3, 1), output=str(tmp_path / "c.csv"), step_s=5.0)
    result = conflicts.conflict_job(options)
    assert len(result.alerts)
    alert = result.alerts.iloc[-1]
    whole = alert_figure(alert, result.tracks, result.predictions, result.pc, options.threshold,
                         tmp_path / "whole.png", step_s=5.0)
    data = AlertData(result.tracks, result.predictions, result.pc)(alert)
    assert len(data["tracks"]) < len(result.tracks)  # the figure's window only
    assert set(data["tracks"]["aircraft_id"]) == {"710001", "710002"}
    cut = alert_figure(**data, threshold=options.threshold, path=tmp_path / "cut.png", step_s=5.0)
    with Image.open(whole) as a, Image.open(cut) as b:
        assert a.size == b.size and a.tobytes() == b.tobytes()


def test_no_alert_makes_no_figures_folder(tmp_path, capsys):
    # the fixtures have no alert event (the test above reads the empty Alerts sheet): --figures makes no
    # empty folder, and says why
    figs = tmp_path / "figs"
    assert main(["conflicts", RADAR, ADSB, "--sensors", SENSORS, "--date", "2019-03-01", "--step", "10",
                 "-o", str(tmp_path / "c.csv"), "--figures", str(figs)]) == 0
    assert pd.read_csv(tmp_path / "c.csv").empty
    assert not figs.exists() and "figures: none (no alert events)" in capsys.readouterr().err


def test_a_tiny_step_is_refused_by_the_predictions_it_would_make(tmp_path, capsys):
    """--step 0.01 with three horizons: about 1.6 M track rows on the fixtures, 4.8 M predictions, over the
    4 M bound: refused naming --step after decoding, before tracking; nothing written."""
    out = tmp_path / "c.csv"
    code = main(["conflicts", RADAR, ADSB, "--sensors", SENSORS, "--date", "2019-03-01", "--step", "0.01",
                 "-o", str(out), "--json", str(tmp_path / "c.json")])
    err = capsys.readouterr().err
    assert code == 2 and "Traceback" not in err
    assert "--step 0.01: the tracks of these 5 aircraft would need about 4," in err
    assert "predictions (3 horizon(s) a grid row), more than 4,000,000; use a longer --step" in err
    assert list(tmp_path.iterdir()) == []


def test_predictions_in_batches_equal_those_of_one_batch(crossing, monkeypatch):
    """The aircraft are tracked again with their filter histories for the predictions, a batch of them at a
    time: batches of ~600 reports (one aircraft each on the crossing pair, several on the fixtures) give the
    same predictions, PC, alerts, losses and warning times, bit for bit, as one batch of every aircraft."""
    d = crossing
    cases = [ConflictOptions(inputs=(str(d / "r.ast"), str(d / "a.ast")), sensors=str(d / "s.toml"),
                             output="c.csv", date=dt.date(2019, 3, 1)), opts(date=dt.date(2019, 3, 1))]
    for options in cases:
        whole = conflicts.conflict_job(options)
        monkeypatch.setattr(conflicts, "PREDICTION_BATCH_REPORTS", 600)
        parts = conflicts.conflict_job(options)
        monkeypatch.undo()
        assert parts.predictions["aircraft_id"].nunique() == whole.predictions["aircraft_id"].nunique() >= 2
        for name in ("predictions", "pc", "alerts", "losses", "warning_times", "tracks"):
            pd.testing.assert_frame_equal(getattr(parts, name), getattr(whole, name), check_exact=True)


def test_a_batch_of_untrackable_aircraft_predicts_nothing(monkeypatch):
    """Aircraft "A" flies east at 200 m/s with 1 Hz reports; "Z" has reports without a usable covariance
    (NaN, as for NACp 0). In batches of 50 reports, Z is a batch of its own: it adds no prediction, and
    the predictions (their UTC times included) are those of one batch."""
    from msdc.pipeline.track import Plane, track

    t0 = pd.Timestamp("2019-03-01T08:00:00Z")
    secs = np.arange(60.0)
    rows = {"time": t0 + pd.to_timedelta(np.concatenate([secs, secs]), unit="s"), "sensor_id": "021:0/1",
            "sensor_kind": "adsb", "aircraft_id": ["A"] * 60 + ["Z"] * 60,
            "latitude": 40.0, "longitude": np.concatenate([2.0 + secs * 200.0 / 85_390.0, 3.0 + 0 * secs]),
            "flight_level": 300.0, "cov_ee_m2": [25.0] * 60 + [np.nan] * 60, "cov_en_m2": 0.0,
            "cov_nn_m2": [25.0] * 60 + [np.nan] * 60}
    meas = pd.DataFrame(rows)
    options = ConflictOptions(output="c.csv")
    result = track(meas, step_s=1.0, max_coast_s=60.0)
    plane = Plane.around(result.tracks["latitude"], result.tracks["longitude"])
    whole = conflicts._predictions(meas, result.epoch, plane, (20.0, 60.0), options)
    monkeypatch.setattr(conflicts, "PREDICTION_BATCH_REPORTS", 50)
    parts = conflicts._predictions(meas, result.epoch, plane, (20.0, 60.0), options)
    assert set(parts["aircraft_id"]) == {"A"} and isinstance(parts["time"].dtype, pd.DatetimeTZDtype)
    pd.testing.assert_frame_equal(parts, whole, check_exact=True)


def test_from_python_the_job_needs_no_table_and_writes_only_what_is_given(crossing, tmp_path):
    """Only the command requires -o: the job ran without it refused "-o: give the output" though it writes
    nothing; write_conflicts then writes the JSON alone (the crossing's one loss in it)."""
    d = crossing
    options = ConflictOptions(inputs=(str(d / "r.ast"), str(d / "a.ast")), sensors=str(d / "s.toml"),
                              date=dt.date(2019, 3, 1), json=str(tmp_path / "c.json"), step_s=5.0)
    result = conflicts.conflict_job(options)
    assert len(result.losses) == 1
    assert conflicts.write_conflicts(result) == {"json": tmp_path / "c.json"}
    assert sorted(p.name for p in tmp_path.iterdir()) == ["c.json"]
    assert len(json.loads((tmp_path / "c.json").read_text())["losses"]) == 1


def test_a_selection_that_leaves_nothing_out_says_the_losses_it_has(crossing):
    """--exclude-codes 7777 (neither aircraft squawks it: CONA 1001, CONB 1002) leaves no sample out: the
    selection line said "without it None loss(es)"; it is the crossing's one loss."""
    d = crossing
    options = ConflictOptions(inputs=(str(d / "r.ast"), str(d / "a.ast")), sensors=str(d / "s.toml"),
                              date=dt.date(2019, 3, 1), output=str(d / "none.csv"), step_s=5.0,
                              exclude_codes="7777")
    result = conflicts.conflict_job(options)
    sel = result.counts["selection"]
    assert sel["active"] and sel["left_out"] == 0 and sel["losses_without"] == len(result.losses) == 1
    assert "without it 1 loss(es)" in conflicts.text(result) and "None" not in conflicts.text(result)


def test_a_report_gap_below_every_update_interval_is_said(crossing):
    """--max-report-gap below every sensor's median update interval (the crossing's ADS-B reports about every
    second, the radar every scan) leaves no time reported for both aircraft: the loss vanished and the run
    said nothing; now a warning names the option, the intervals and the default."""
    d = crossing
    options = ConflictOptions(inputs=(str(d / "r.ast"), str(d / "a.ast")), sensors=str(d / "s.toml"),
                              date=dt.date(2019, 3, 1), output=str(d / "gap.csv"), step_s=5.0,
                              max_report_gap_s=0.2)
    result = conflicts.conflict_job(options)
    assert result.losses.empty
    said = [w for w in result.warnings if w.startswith("--max-report-gap 0.2 s is below every sensor")]
    assert len(said) == 1 and "no loss can be found" in said[0] and "default 15 s" in said[0], result.warnings
    quiet = conflicts.conflict_job(replace(options, max_report_gap_s=15.0))
    assert len(quiet.losses) == 1 and not any("--max-report-gap" in w for w in quiet.warnings)


def test_a_loss_seen_by_radar_and_adsb_is_one_with_the_truth_s_minimum():
    """The bundled recordings, MAS72 and MAS136 within 7.2 NM and 7,000 ft: the truth (the simulator's
    positions every 0.05 s, chord distance at the surface: fixtures.geodesy, not msdc's) has one proximity,
    about 08:34:22-08:34:57, closest 7.076 NM. Fused with the radar (its plot at 155 NM lies about 300 m off
    across the beam) the loss fell apart into five and its minimum came out 6.83 NM; measured where the
    ADS-B reports, it is one loss, its minimum within 0.01 NM of the truth's."""
    from fixtures import geodesy as geo
    from fixtures.simulate import DEFAULT_SEED

    sim = simulate(seed=DEFAULT_SEED)
    t_s = np.arange(30_800.0, 30_960.0, 0.05)
    a, b = sim.aircraft_by_callsign("MAS72").truth(t_s), sim.aircraft_by_callsign("MAS136").truth(t_s)
    chord_nm = np.linalg.norm(geo.geodetic_to_ecef(a.latitude, a.longitude, 0.0)
                              - geo.geodetic_to_ecef(b.latitude, b.longitude, 0.0), axis=-1) / 1852.0
    inside = t_s[chord_nm < 7.2]  # NaN where an aircraft is not flying (MAS136's flight ends at 08:35:01)
    assert np.isfinite(chord_nm[(t_s >= inside[0] - 10.0) & (t_s <= inside[-1])]).all()
    assert 30_861.0 < inside[0] < 30_863.0 and 30_896.0 < inside[-1] < 30_898.0  # one run, 08:34:22-57
    assert np.all(np.diff(inside) < 0.06)
    options = ConflictOptions(inputs=(str(FIX / "radar.ast"), str(FIX / "adsb.ast")),
                              sensors=str(FIX / "sensors.toml"), date=dt.date(2019, 3, 1), radius_nm=7.2,
                              vertical_ft=7000.0, from_time="08:30", to_time="08:40")
    result = conflicts.conflict_job(options)
    pair = result.losses[(result.losses["callsign_a"].astype(str) + result.losses["callsign_b"].astype(str))
                         .isin(["MAS72MAS136", "MAS136MAS72"])]
    assert len(pair) == 1, pair[["start", "end", "min_horizontal_nm"]]
    assert pair["min_horizontal_nm"].iloc[0] == pytest.approx(np.nanmin(chord_nm), abs=0.01)
    start_s = (pair["start"].iloc[0] - pd.Timestamp("2019-03-01", tz="UTC")).total_seconds()
    assert abs(start_s - inside[0]) < 1.5


def test_an_aircraft_reported_once_is_left_out_and_named(crossing, tmp_path):
    """The crossing with one CONA ADS-B report's address damaged (710001 -> 710009: a ghost beside its
    aircraft, the report no copy of another's): that one-report track alerted against CONA (same place: PC
    1) and could make a loss of its own. It is left out with a warning naming it; the crossing's one loss
    stays."""
    import msdc.asterix as asterix

    d = crossing
    adsb = asterix.read(d / "a.ast").frames[21]
    at = adsb.index[adsb["address"] == "710001"][300]
    adsb["address"] = adsb["address"].astype(object)
    adsb.loc[at, "address"] = "710009"
    (tmp_path / "a.ast").write_bytes(encode_frame(21, adsb))
    options = ConflictOptions(inputs=(str(d / "r.ast"), str(tmp_path / "a.ast")), sensors=str(d / "s.toml"),
                              date=dt.date(2019, 3, 1), step_s=5.0)
    result = conflicts.conflict_job(options)
    said = [w for w in result.warnings if "reported once in the run left out" in w]
    assert len(said) == 1 and said[0].startswith("1 aircraft") and "710009 (CONA)" in said[0], result.warnings
    assert "710009" not in set(result.alerts[["aircraft_a", "aircraft_b"]].astype(str).to_numpy().ravel())
    assert len(result.losses) == 1 and result.counts["aircraft"] == 2
