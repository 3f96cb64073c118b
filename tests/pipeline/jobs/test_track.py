"""``msdc track`` and its job on the bundled fixtures: options refused before decoding (one line, exit 2,
nothing written), the table's columns, sources, the sensor file's sigmas, and the JSON against the
simulator's truth."""

from __future__ import annotations

import json
import math
import re
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from msdc.pipeline.cli import main
from msdc.pipeline.jobs import common, track
from msdc.pipeline.jobs.common import OptionError
from msdc.pipeline.jobs.track import TRACK_COLUMNS, TrackOptions
from msdc.pipeline.track.feasibility import track_rows

# one worker runs the module: the tracked fixtures made once, not on each worker
pytestmark = pytest.mark.xdist_group("track")

FIX = Path(__file__).resolve().parents[3] / "fixtures"
RADAR, ADSB, SENSORS = str(FIX / "radar.ast"), str(FIX / "adsb.ast"), str(FIX / "sensors.toml")
TRUTH = json.loads((FIX / "truth.json").read_text())
BASE = [RADAR, ADSB, "--sensors", SENSORS, "--date", "2019-03-01"]


def opts(**kw) -> TrackOptions:
    base = {"inputs": (RADAR, ADSB), "sensors": SENSORS, "callsign": "MAS72", "output": "t.csv"}
    return TrackOptions(**(base | kw))


BAD = [
    (opts(step_s=0.0), "--step 0.0"),
    (opts(step_s=-1.0), "--step -1.0"),
    (opts(step_s=math.nan), "--step nan"),
    (opts(step_s=math.inf), "--step inf"),
    (opts(step_s=5.0, max_coast_s=2.0), "--max-coast 2.0: must be a finite number of seconds >= --step (5)"),
    (opts(max_coast_s=math.nan), "--max-coast nan"),
    (opts(tpm="fixed:1.5"), "--tpm 'fixed:1.5'"),
    (opts(tpm="expm:-3"), "--tpm 'expm:-3'"),
    (opts(tpm="banana"), "--tpm 'banana'"),
    # p(T) = min(0.995, A - B T) must be a probability above 0 at every interval up to --max-coast: -1 at
    # T = 0 here, and 1 - 0.02 x 60 = -0.2 at the default --max-coast (the kernel clamped both to 0)
    (opts(tpm="dynamic:-1,2"), "--tpm 'dynamic:-1,2': p(T) = min(0.995, -1 - 2 T) is -1 at T = 0 s"),
    (opts(tpm="dynamic:1,0.02"), "is -0.2 at T = 60 s; it must stay above 0"),
    (opts(tpm="dynamic", max_coast_s=300.0), "at T = 300 s"),  # the paper's law ends at 200.4 s
    (opts(tpm="expm:0.001"), "sojourn times from 0.01 to 10,000,000 seconds"),
    (opts(tpm="expm:150,1e-320"), "--tpm 'expm:150,1e-320'"),  # 1/TAU overflows: NaN probabilities
    (opts(smoother="two-filter"), "--smoother 'two-filter': must be rts or imm"),
    (opts(sources=("radar", "wam")), "--sources 'radar,wam'"),
    (opts(sources=()), "--sources"),
    (opts(callsign=None), "exactly one of --callsign, --address or --all"),
    (opts(callsign=None, address="XYZ"), "--address 'XYZ'"),
    (opts(output="t.xlsx"), "-o t.xlsx: must end in .csv or .parquet"),
    (opts(output=None), "give at least one output"),
    (opts(json="t.txt"), "--json t.txt"),
    (opts(sensors="/nonexistent/s.toml"), "--sensors /nonexistent/s.toml"),
]


@pytest.mark.parametrize(("options", "words"), BAD)
def test_bad_options_refused_before_decoding(options, words, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(common, "load", lambda *a, **k: pytest.fail("decoded before validating"))
    with pytest.raises(OptionError) as info:
        track.validate(options, require_output=True)  # as the command validates
    assert words in str(info.value) and "\n" not in str(info.value)
    assert info.value.status == 2


@pytest.mark.parametrize("argv", [
    ["--step", "0"], ["--max-coast", "0.5"], ["--tpm", "fixed:0"], ["--sources", "radar,psr"],
    ["--callsign", "NOSUCH1"]])
def test_cli_failure_writes_nothing(argv, tmp_path, capsys):
    args = ["track", *BASE, "-o", str(tmp_path / "t.csv"), "--json", str(tmp_path / "t.json")]
    if "--callsign" not in argv:
        args += ["--callsign", "MAS72"]
    status = main(args + argv)
    err = capsys.readouterr().err
    assert status == (1 if "NOSUCH1" in argv else 2)
    (last,) = [line for line in err.splitlines() if line.startswith("msdc track: ")]
    assert "Traceback" not in err and len(last) > len("msdc track: ")
    assert list(tmp_path.iterdir()) == []


def test_cli_unknown_callsign_names_the_closest(tmp_path, capsys):
    assert main(["track", *BASE, "--callsign", "MAS73", "-o", str(tmp_path / "t.csv")]) == 1
    err = capsys.readouterr().err
    assert "MAS73 not in the inputs" in err and "MAS72" in err
    assert list(tmp_path.iterdir()) == []


@pytest.fixture(scope="module")
def mas72(tmp_path_factory, every_kernel_compiled):
    d = tmp_path_factory.mktemp("track")
    assert main(["track", *BASE, "--callsign", "mas 72", "-o", str(d / "t.parquet"), "--json",
                 str(d / "t.json"), "--figures", str(d / "figs")]) == 0
    return pd.read_parquet(d / "t.parquet"), json.loads((d / "t.json").read_text()), d


def test_columns_identity_and_times(mas72):
    tracks, _, _ = mas72
    assert list(tracks.columns[:len(TRACK_COLUMNS)]) == TRACK_COLUMNS
    spec = next(a for a in TRUTH["aircraft"] if a["callsign"] == "MAS72")
    assert set(tracks["callsign"]) == {"MAS72"} and set(tracks["address"]) == {spec["address"]}
    assert str(tracks["time"].dt.tz) == "UTC"
    assert (tracks["time"].dt.date == pd.Timestamp("2019-03-01").date()).all()
    # time_of_day is the UTC time as seconds since midnight
    tod = (tracks["time"] - pd.Timestamp("2019-03-01", tz="UTC")).dt.total_seconds()
    assert np.allclose(tod, tracks["time_of_day"], atol=1e-6)
    # the grid: every whole second from the first report to 60 s after the last one is present
    grid = tracks.loc[tracks["time_of_day"] % 1.0 == 0.0, "time_of_day"]
    assert np.all(np.diff(grid) == 1.0)
    modes = tracks[["mode_cv", "mode_turn_left", "mode_turn_right"]].sum(axis=1)
    assert np.allclose(modes, 1.0)
    upd = ~tracks["coasted"]
    assert (tracks.loc[upd, "sources"] != "").all() and (tracks.loc[~upd, "sources"] == "").all()
    assert set(",".join(tracks.loc[upd, "sources"]).split(",")) == {"048:25/201", "021:0/1"}


def test_json_counts_match_the_simulator(mas72):
    _, doc, _ = mas72
    (ac,) = doc["aircraft"]
    assert ac["callsign"] == "MAS72"
    # reports per sensor: the simulator's rows of MAS72 that are not injected repeats
    from fixtures.simulate import simulate

    tt = simulate().truth_tracks
    rows = tt[(tt["callsign"] == "MAS72") & ~tt["duplicate"]].groupby("sensor").size()
    reports = {s["sensor_id"]: s["reports"] for s in ac["sensors"]}
    assert reports == {"048:25/201": rows["radar"], "021:0/1": rows["adsb"]}
    assert sum(s["updates"] + s["gated"] for s in ac["sensors"]) == ac["reports"] == sum(rows)
    # exactly the injected ADS-B position jumps of MAS72 (0.1-6 deg away) are gated, no radar plot is
    jumps = [j for j in TRUTH["jumps"] if j["callsign"] == "MAS72"]
    gated = {s["sensor_id"]: s["gated"] for s in ac["sensors"]}
    assert gated == {"021:0/1": len(jumps), "048:25/201": 0} and len(jumps) > 0
    # tracked: the simulator's first to last good report (one segment); its radar scans every 4.8 s and
    # no gap between MAS72's good reports is longer than 1.5 scans, so nothing is coasted
    good = tt[(tt["callsign"] == "MAS72") & ~tt["duplicate"] & ~tt["jump"]].sort_values("t_s")
    assert ac["segments"] == 1
    assert ac["tracked_s"] == pytest.approx(good["t_s"].iloc[-1] - good["t_s"].iloc[0], abs=1e-6)
    radar_t = good.loc[good["sensor"] == "radar", "t_s"].to_numpy()
    assert ac["update_interval_s"] == pytest.approx(np.median(np.diff(radar_t)), abs=1e-6)
    assert np.diff(good["t_s"].to_numpy()).max() <= 1.5 * ac["update_interval_s"] and ac["coasted_s"] == 0.0
    for s in ac["sensors"]:
        assert s["nis_mean"] > 0


def test_figure_written(mas72):
    _, _, d = mas72
    (png,) = (d / "figs").iterdir()
    assert png.name == "track_MAS72_750312.png" and png.read_bytes()[:4] == b"\x89PNG"


def _radar_only(tmp_path, sensors_text: str, noise: str = "declared") -> dict:
    s = tmp_path / "s.toml"
    s.write_text(sensors_text)
    result = track.track_job(TrackOptions(inputs=(RADAR, ADSB), sensors=str(s), callsign="MAS72",
                                               json=str(tmp_path / "t.json"), date=pd.Timestamp(
                                                   "2019-03-01").date(), sources=("radar",), noise=noise))
    return result


def test_radar_sigmas_from_the_sensor_file(tmp_path):
    """The simulator's radar noise is 70 m / 0.08 deg: with those sigmas (the defaults) the radar's NIS
    averages near 2 (chi-square, 2 degrees of freedom; a little less, as the manoeuvre modes' process
    noise is spent on straight legs); a file claiming 10 times the noise (100 times the variance) makes
    the NIS tens of times smaller and the track's ellipses wider."""
    text = (FIX / "sensors.toml").read_text()
    default = _radar_only(tmp_path, text)
    loose = _radar_only(tmp_path, text + "sigma_range_m = 700.0\nsigma_azimuth_deg = 0.8\n")
    assert set(default.tracks["sources"]) <= {"", "048:25/201"}
    nis = float(default.result.sensors["nis_mean"].iloc[0])
    nis_loose = float(loose.result.sensors["nis_mean"].iloc[0])
    assert 1.2 < nis < 2.6
    assert nis_loose < nis / 20
    # --noise estimate (the default) takes the sigmas from the residuals: the loose file no longer matters
    est = _radar_only(tmp_path, text + "sigma_range_m = 700.0\nsigma_azimuth_deg = 0.8\n", noise="estimate")
    assert 1.5 < float(est.result.sensors["nis_mean"].iloc[0]) < 2.6
    noise = est.noise.set_index("component")
    assert noise.loc["range", "estimated_sigma"] == pytest.approx(70.0, rel=0.2)
    assert noise.loc["azimuth", "estimated_sigma"] == pytest.approx(0.08, rel=0.2)
    assert loose.tracks["sigma_major_m"].median() > 3 * default.tracks["sigma_major_m"].median()


def test_sources_adsb_only(tmp_path):
    out = tmp_path / "t.csv"
    assert main(["track", *BASE, "--address", "750312", "--sources", "adsb", "-o", str(out),
                 "--step", "5", "--max-coast", "30", "--tpm", "dynamic", "--smooth"]) == 0
    t = pd.read_csv(out, dtype={"address": str, "sources": str})
    assert set(t["sources"].dropna()) == {"021:0/1"}
    assert t["time"].str.endswith("Z").all()
    grid = t.loc[~t["coasted"], "time_of_day"]
    assert len(grid) > 0
    coast = t.loc[t["coasted"], "time_of_day"].to_numpy()
    assert np.allclose(coast % 5.0, 0.0)


def test_plots_without_identity_join_by_track_number():
    """MAS72's radar plots stripped of address, call sign and Mode 3/A rejoin MAS72 by the radar track
    number of its identified plots; a stripped plot whose track number is nowhere identified stays out."""
    from msdc.pipeline.model.load import load
    from msdc.pipeline.model.measurements import build_measurements
    from msdc.pipeline.model.sensors import read_sensors
    from msdc.pipeline.track.associate import join_by_track_number

    data = load([RADAR], date="2019-03-01")
    radar = data.frames[48].copy()
    mas72 = np.flatnonzero((radar["callsign"] == "MAS72").to_numpy(bool))
    stripped = mas72[::7]  # every 7th plot
    for c in ("address", "callsign", "mode3a"):
        radar[c] = radar[c].astype(object)
        radar.iloc[stripped, radar.columns.get_loc(c)] = None
    orphan = len(radar)
    radar = pd.concat([radar, radar.iloc[[stripped[0]]].assign(track_number=9999)], ignore_index=True)
    meas = build_measurements(radar, None, read_sensors(SENSORS), date=data.date)
    assert meas["aircraft_id"].isna().sum() == len(stripped) + 1
    joined, n = join_by_track_number(meas)
    assert n == len(stripped)
    assert (joined["aircraft_id"].iloc[stripped] == "750312").all()
    assert joined["aircraft_id"].isna().to_numpy()[orphan]
    assert joined["aircraft_id"].notna().sum() == len(meas) - 1


def test_all_aircraft_gate_exactly_the_injected_jumps(tmp_path, capsys):
    """--all: per aircraft, the ADS-B reports the gate rejects are exactly the simulator's injected
    position jumps (truth.json), and the ADS-B NIS mean is what NACp's claimed sigma predicts for the
    simulator's 5 m noise: 2 (5 / sigma)^2, sigma = NACp 95 % bound / 2.4477 (--noise declared)."""
    out = tmp_path / "s.json"
    assert main(["track", *BASE, "--all", "--json", str(out), "--noise", "declared"]) == 0
    capsys.readouterr()
    doc = json.loads(out.read_text())
    jumps = pd.Series([j["callsign"] for j in TRUTH["jumps"]]).value_counts().to_dict()
    spec = {a["callsign"]: a for a in TRUTH["aircraft"]}
    assert sorted(a["callsign"] for a in doc["aircraft"]) == sorted(spec)
    for ac in doc["aircraft"]:
        adsb = next(s for s in ac["sensors"] if s["sensor_kind"] == "adsb")
        assert adsb["gated"] == jumps[ac["callsign"]], ac["callsign"]
        if ac["callsign"] == "SIA305":  # fixtures/scenario.py: NACp 8 (sigma 37.8 m): NIS far below 2
            assert adsb["nis_mean"] < 0.1
        else:  # NACp 9: sigma 30 / 2.4477 = 12.3 m, the simulator's noise 5 m per axis
            expected = 2.0 * (5.0 / (30.0 / 2.4477)) ** 2
            assert adsb["nis_mean"] == pytest.approx(expected, rel=0.25), ac["callsign"]


def test_all_aircraft_estimated_noise_gates_the_jumps_and_few_others(tmp_path, capsys):
    """--noise estimate (default): the ADS-B sigma becomes the simulator's 5 m, so the NIS mean is near 2
    for every aircraft; every injected jump is still gated, and the 99.9 % gate now also rejects about
    1 in 1000 genuine reports (at most 0.3 % here)."""
    out = tmp_path / "s.json"
    assert main(["track", *BASE, "--all", "--json", str(out)]) == 0
    capsys.readouterr()
    doc = json.loads(out.read_text())
    assert doc["parameters"]["noise"] == "estimate"
    jumps = pd.Series([j["callsign"] for j in TRUTH["jumps"]]).value_counts().to_dict()
    for ac in doc["aircraft"]:
        adsb = next(s for s in ac["sensors"] if s["sensor_kind"] == "adsb")
        assert jumps[ac["callsign"]] <= adsb["gated"] <= jumps[ac["callsign"]] + 0.003 * adsb["reports"]
        assert 1.5 < adsb["nis_mean"] < 2.5, ac["callsign"]


@pytest.mark.parametrize("noise", ["estimate", "declared"])
def test_nothing_trackable_says_why_exit_1_and_writes_nothing(tmp_path, capsys, noise):
    """Every ADS-B report with NACp 0 (unknown accuracy): no covariance, so no track. One line naming the
    count and the reason, exit 1, no file (was an empty table with exit 0, or a traceback)."""
    from dataclasses import replace

    from fixtures.scenario import default_scenario
    from fixtures.simulate import sensors_toml, simulate
    from msdc.asterix.encode import encode_frame
    from msdc.pipeline.cli import main

    sc = default_scenario()
    sim = simulate(replace(sc, aircraft=sc.aircraft[:2]), seed=3)
    (tmp_path / "a.ast").write_bytes(encode_frame(21, sim.adsb.assign(nacp=0)))
    (tmp_path / "s.toml").write_text(sensors_toml(sc.radar))
    code = main(["track", str(tmp_path / "a.ast"), "--sensors", str(tmp_path / "s.toml"), "--all",
                 "--noise", noise, "-o", str(tmp_path / "t.csv"), "--json", str(tmp_path / "t.json")])
    err = capsys.readouterr().err
    assert code == 1 and "Traceback" not in err
    # every report left after deduplication (the simulator injects a few duplicates) is named
    found = re.search(r"no aircraft could be tracked: (\d+) of (\d+) ADS-B reports have no usable accuracy "
                      r"\((\d+) have NACp 0", err)
    assert found and found[1] == found[2] == found[3] and 0.9 * len(sim.adsb) < int(found[1]) <= len(sim.adsb)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.ast", "s.toml"]


def test_track_rows_bound_one_aircraft_by_hand():
    """Reports at 0, 10 and 100 s, --max-coast 60, --step 1: the first segment's grid runs 0..70 s (71
    samples), the second 100..160 s (61): 132 rows. The bound counts 10 + 60 + 60 = 130 s of cover, one
    sample more at each of the segment's ends and one row per report: 135."""
    t0 = pd.Timestamp("2019-03-01T08:00:00Z")
    times = [t0 + pd.Timedelta(seconds=s) for s in (0, 10, 100)]
    meas = pd.DataFrame({"aircraft_id": ["A"] * 3, "time": times})
    assert track_rows(meas, 1.0, 60.0) == 135
    assert track_rows(meas, 0.1, 60.0) == 1300 + 2 + 3


def test_a_tiny_step_is_refused_after_decoding_with_the_rows_it_would_make(tmp_path, capsys):
    """--step 0.001 on the fixtures' 5 aircraft would put out about 16 M rows (65 min of tracks at 1 ms):
    refused by name before tracking, exit 2, nothing written (at --step 1 they make 33 k rows)."""
    out = tmp_path / "t.csv"
    status = main(["track", *BASE, "--all", "--noise", "declared", "-o", str(out), "--step", "0.001"])
    err = capsys.readouterr().err
    assert status == 2 and "Traceback" not in err
    (last,) = [line for line in err.splitlines() if line.startswith("msdc track: ")]
    assert re.search(r"--step 0.001: the tracks of these 5 aircraft would need about 1[56],\d{3},\d{3} "
                     r"output rows, more than 4,000,000; use a longer --step", last), last
    assert list(tmp_path.iterdir()) == []


def test_adsb_alone_needs_no_sensor_file(tmp_path, capsys):
    """An ADS-B recording is tracked without --sensors (no radar to place): the same table as with the
    sensor file, whose radar entries ADS-B never uses, and the JSON records no sensor file."""
    with_file, without = tmp_path / "with.csv", tmp_path / "without.csv"
    common = [ADSB, "--date", "2019-03-01", "--all", "--noise", "declared"]
    assert main(["track", *common, "--sensors", SENSORS, "-o", str(with_file)]) == 0
    assert main(["track", *common, "-o", str(without), "--json", str(tmp_path / "t.json")]) == 0
    assert "Traceback" not in capsys.readouterr().err
    pd.testing.assert_frame_equal(pd.read_csv(with_file), pd.read_csv(without))
    assert json.loads((tmp_path / "t.json").read_text())["parameters"]["sensors"] is None


@pytest.mark.parametrize("command", [["track", "--all", "-o", "t.csv"], ["conflicts", "-o", "t.csv"]])
def test_radar_plots_without_a_sensor_file_name_the_option_and_write_nothing(tmp_path, capsys, command):
    """Radar plots with no --sensors: exit 1 naming the radar's SAC/SIC (25/201 in the fixtures' sensor
    file), --sensors and --sources adsb, with the TOML lines to add; nothing is written. With --sources
    adsb the same inputs are tracked."""
    argv = [command[0], RADAR, ADSB, "--date", "2019-03-01", *command[1:]]
    argv[argv.index("t.csv")] = str(tmp_path / "t.csv")
    assert main(argv) == 1
    err = capsys.readouterr().err
    assert "Traceback" not in err
    assert "radar plots from SAC/SIC 25/201 need the radar's position, and no --sensors file was given" in err
    assert "--sources adsb" in err
    assert '[[sensor]]  # replace the three TODO values' in err
    assert '\nname = "radar SAC 25 SIC 201"\nsac = 25\nsic = 201\n' in err
    assert list(tmp_path.iterdir()) == []
    assert main([*argv, "--sources", "adsb", "--noise", "declared", "--json", str(tmp_path / "t.json")]) == 0
    assert json.loads((tmp_path / "t.json").read_text())["parameters"]["sources"] == ["adsb"]
    if command[0] == "track":
        used = pd.read_csv(tmp_path / "t.csv")["sources"].dropna().str.split(",").explode()
        assert set(used) == {"021:0/1"}


def test_sensor_totals_by_hand():
    """Radar R: aircraft A with 2 updates at NIS mean 1.0 and B with 6 at 3.0 pool to (2 + 18) / 8 = 2.5 over
    8 updates; ADS-B S: one aircraft whose 4 reports were all gated has no NIS mean."""
    sensors = pd.DataFrame({"aircraft_id": ["A", "B", "A"], "sensor_id": ["R", "R", "S"],
                            "reports": [3, 9, 4], "updates": [2, 6, 0], "gated": [1, 1, 4],
                            "invalid": [0, 1, 0], "out_of_range": [0, 1, 0],
                            "nis_mean": [1.0, 3.0, np.nan]})
    out = track.sensor_totals(sensors).set_index("sensor_id")
    assert out.loc["R", ["aircraft", "reports", "updates", "gated", "invalid", "out_of_range"]].tolist() == [
        2, 12, 8, 2, 1, 1]
    assert out.loc["R", "nis_mean"] == pytest.approx(2.5)
    assert out.loc["S", ["aircraft", "reports", "updates", "gated"]].tolist() == [1, 4, 0, 4]
    assert np.isnan(out.loc["S", "nis_mean"])
    # an aircraft whose one update started its track has no NIS: it weighs nothing (it pooled in as 0: the
    # mean read 0.00 where no aircraft had one, and (2 + 18) / 9 = 2.22 beside R's two)
    started = pd.DataFrame({"aircraft_id": ["A", "B", "C"], "sensor_id": ["R", "R", "R"],
                            "reports": [3, 9, 1], "updates": [2, 6, 1], "gated": [0, 0, 0],
                            "invalid": [0, 0, 0], "out_of_range": [0, 0, 0], "nis_mean": [1.0, 3.0, np.nan]})
    assert track.sensor_totals(started)["nis_mean"].iloc[0] == pytest.approx(2.5)
    alone = started.iloc[[2]]
    assert np.isnan(track.sensor_totals(alone)["nis_mean"].iloc[0])


def test_stdout_sums_each_sensor_over_the_aircraft(tmp_path, capsys):
    """--all prints one Sensors line per sensor, whose reports, updates and gated are the sums of the JSON's
    per-aircraft entries (the fixtures: 5 aircraft, ADS-B and one radar)."""
    js = tmp_path / "t.json"
    assert main(["track", *BASE, "--all", "--noise", "declared", "--json", str(js)]) == 0
    out = capsys.readouterr().out
    block = out.split("Sensors:\n")[1].split("\n\n")[0].splitlines()
    rows = {line.split()[0]: [int(v) for v in line.split()[1:5]] for line in block[1:]}
    doc = json.loads(js.read_text())
    expected: dict[str, list[int]] = {}
    for ac in doc["aircraft"]:
        for s in ac["sensors"]:
            e = expected.setdefault(s["sensor_id"], [0, 0, 0, 0])
            e[0] += 1
            e[1] += s["reports"]
            e[2] += s["updates"]
            e[3] += s["gated"]
    assert rows == expected and set(rows) == {"021:0/1", "048:25/201"}
    # every report shows: the sensors' and the aircraft's tables count the unusable and far ones too, and
    # the aircraft table's time columns are defined under it
    assert block[0].split() == ["sensor_id", "aircraft", "reports", "updates", "gated", "invalid",
                                "out_of_range", "nis_mean"]
    tracks = out.split("Tracks:\n")[1]
    assert tracks.splitlines()[0].split()[6:] == ["invalid", "out_of_range", "tracked_s", "update_interval_s",
                                                  "coasted_s"]
    assert "tracked_s: first to last update of each segment" in tracks
    assert "coasted_s: time without any update beyond that interval" in tracks


def test_parquet_in_slices_is_the_whole_table(tmp_path):
    """`pipeline.report.tables.write_parquet` (the track and correlation tables' writer) 3 rows at a time: a
    table whose text column is empty in a whole slice, an object column all None in the first slice, NaN,
    booleans and UTC times reads back equal to `to_parquet` of the whole frame, same schema and metadata."""
    import pyarrow.parquet as pq

    from msdc.pipeline.report.tables import write_parquet

    frame = pd.DataFrame({"aircraft_id": ["A"] * 4 + ["B"] * 3,
                          "time": pd.date_range("2019-03-01T08:00:00Z", periods=7, freq="s"),
                          "speed_kt": [250.0, np.nan, 251.5, 252.0, 120.0, 121.0, np.nan],
                          "coasted": [False, True, False, False, True, True, False],
                          "sources": ["021:0/1", "", "048:25/201", "", "", "", "021:0/1,048:25/201"]})
    frame["sources"] = frame["sources"].astype("str")
    frame["note"] = pd.Series([None, None, None, "jump", None, "gap", None], dtype=object)
    whole, sliced = tmp_path / "whole.parquet", tmp_path / "sliced.parquet"
    frame.to_parquet(whole, index=False)
    write_parquet(frame, sliced, slice_rows=3)
    assert pq.ParquetFile(sliced).metadata.num_row_groups == 3
    assert pq.read_schema(sliced).equals(pq.read_schema(whole), check_metadata=True)
    pd.testing.assert_frame_equal(pd.read_parquet(sliced), pd.read_parquet(whole))


def test_grid_rows_bound_by_hand():
    """The same reports at 0, 10 and 100 s: the grid rows alone, without one row per report: 135 - 3."""
    t0 = pd.Timestamp("2019-03-01T08:00:00Z")
    meas = pd.DataFrame({"aircraft_id": ["A"] * 3,
                         "time": [t0 + pd.Timedelta(seconds=s) for s in (0, 10, 100)]})
    assert track_rows(meas, 1.0, 60.0, grid_only=True) == 132


def test_reports_with_no_identity_are_counted_not_dropped_silently(tmp_path, capsys):
    """25 of MAS72's radar plots (each the only plot at its time) stripped of address, call sign, Mode 3/A
    and track number belong to no aircraft: --all tracks the rest and says how many it left out, in the
    warnings and the JSON, where it used to drop them without a word."""
    import msdc.asterix as asterix
    from msdc.asterix.encode import encode_frame

    radar = asterix.read(RADAR).frames[48]
    lone = ~radar["time_of_day"].duplicated(keep=False).to_numpy(bool)
    mas72 = np.flatnonzero((radar["callsign"] == "MAS72").to_numpy(bool) & lone)
    stripped = mas72[::7][:25]
    assert len(stripped) == 25
    radar = radar.copy()
    for c in ("address", "callsign", "mode3a", "mode3a_v", "mode3a_g", "mode3a_l", "track_number"):
        radar[c] = radar[c].astype(object)  # no I048/070 at all (its flags alone would encode code 0000)
        radar.iloc[stripped, radar.columns.get_loc(c)] = None
    path = tmp_path / "radar.ast"
    path.write_bytes(encode_frame(48, radar.drop(columns="callsign_hex")))  # the call sign from its text
    summary = tmp_path / "t.json"
    assert main(["track", str(path), ADSB, "--sensors", SENSORS, "--date", "2019-03-01", "--all", "--json",
                 str(summary)]) == 0
    err = capsys.readouterr().err
    assert "25 report(s) with no identity" in err
    assert json.loads(summary.read_text())["parameters"]["unidentified_reports_not_tracked"] == 25


def test_csv_floats_at_the_documented_precision(mas72, tmp_path):
    """The CSV rounds each float column to its documented decimals (no 1.7e-17 turn rates, no 17-digit
    floats; audit B14), within half a unit of the last decimal of the Parquet table's full precision."""
    decimals = {"time_of_day": 6, "latitude": 7, "longitude": 7, "flight_level": 2, "vertical_rate_fpm": 1,
                "speed_kt": 2, "track_deg": 3, "turn_rate_dps": 4, "sigma_major_m": 2, "sigma_minor_m": 2,
                "ellipse_orientation_deg": 2, "age_s": 6, "mode_cv": 4, "mode_turn_left": 4,
                "mode_turn_right": 4}
    full, _, _ = mas72
    out = tmp_path / "t.csv"
    assert main(["track", *BASE, "--callsign", "mas 72", "-o", str(out)]) == 0
    text = pd.read_csv(out, dtype=str, keep_default_na=False)
    got = pd.read_csv(out, dtype={"address": str, "sources": str})
    assert len(got) == len(full)
    for name, places in decimals.items():
        cells = text[name][text[name] != ""]
        assert not cells.str.contains("e", case=False).any(), name
        assert (cells.str.partition(".")[2].str.len() <= places).all(), name
        assert not cells.str.fullmatch(r"-0\.?0*").any(), name
        both = np.isfinite(full[name].to_numpy(float))
        diff = np.abs(got[name].to_numpy(float)[both] - full[name].to_numpy(float)[both])
        assert diff.max() <= 0.5 * 10.0 ** -places + 1e-9, name


def test_smoother_implies_smooth(tmp_path):
    """--smoother names the backward pass, so it asks for one: it was accepted and silently ignored
    without --smooth."""
    out, js = tmp_path / "s.csv", tmp_path / "s.json"
    assert main(["track", *BASE, "--address", "750312", "--smoother", "imm", "--step", "5",
                 "-o", str(out), "--json", str(js)]) == 0
    params = json.loads(js.read_text())["parameters"]
    assert params["smooth"] is True and params["smoother"] == "imm"
    assert main(["track", *BASE, "--address", "750312", "--step", "5", "-o", str(out),
                 "--json", str(js)]) == 0
    assert json.loads(js.read_text())["parameters"]["smooth"] is False


def test_update_intervals_by_hand():
    """Radar R every 4 s on two aircraft (one gap of 8 s), ADS-B D every 1 s with one repeated time (left
    out): medians 4 s and 1 s, the fastest first."""
    from msdc.pipeline.track.feasibility import update_intervals

    t0 = pd.Timestamp("2019-03-01T08:00:00Z")
    rows = [("A", "R", s) for s in (0, 4, 8, 16, 20)] + [("B", "R", s) for s in (1, 5, 9)]
    rows += [("A", "D", s) for s in (0, 1, 1, 2, 3)]
    meas = pd.DataFrame(rows, columns=["aircraft_id", "sensor_id", "s"])
    meas["time"] = t0 + pd.to_timedelta(meas.pop("s"), unit="s")
    intervals = update_intervals(meas.sample(frac=1.0, random_state=1))  # any row order
    assert intervals.to_dict() == {"D": 1.0, "R": 4.0} and list(intervals.index) == ["D", "R"]


def test_a_max_coast_below_every_sensor_interval_is_warned():
    """--max-coast 0.001 (with --step 0.001) cut MAS72 into thousands of one-report segments without a
    word. The fixtures' radar turns in 4.8 s and their ADS-B reports every 0.5-1.5 s (fixtures/scenario.py):
    a warning names the option, the shortest and the longest interval; the default 60 s gets none."""
    result = track.track_job(opts(output=None, json="t.json", max_coast_s=0.001, step_s=0.001,
                                  noise="declared", date="2019-03-01"))
    (said,) = [w for w in result.warnings if w.startswith("--max-coast")]
    assert said.startswith("--max-coast 0.001 s is below every sensor's median update interval (the shortest:"
                           " 021:")
    assert "(048:25/201, 4.8 s; default 60 s)" in said
    assert result.result.aircraft["segments"].sum() > 1000
    usual = track.track_job(opts(output=None, json="t.json", noise="declared", date="2019-03-01"))
    assert not [w for w in usual.warnings if "--max-coast" in w]


def test_adsb_without_an_accuracy_is_said_when_the_radar_alone_is_tracked(tmp_path, capsys):
    """ADS-B reports of unknown accuracy (NACp 0 here; without NACp, as CAT021 0.2x, and no --adsb-sigma,
    alike): the tracks are made of the radar's plots alone. That was silent (the LEBL hour's 49,296 ADS-B
    reports went unused); it is a warning naming the count and why, and the ADS-B updates none of the
    tracks."""
    from dataclasses import replace

    from fixtures.scenario import default_scenario
    from fixtures.simulate import sensors_toml, simulate
    from msdc.asterix.encode import encode_frame
    from msdc.pipeline.cli import main

    sc = default_scenario()
    sim = simulate(replace(sc, aircraft=sc.aircraft[:2]), seed=3)
    (tmp_path / "a.ast").write_bytes(encode_frame(21, sim.adsb.assign(nacp=0)))
    (tmp_path / "r.ast").write_bytes(encode_frame(48, sim.radar))
    (tmp_path / "s.toml").write_text(sensors_toml(sc.radar))
    code = main(["track", str(tmp_path / "r.ast"), str(tmp_path / "a.ast"), "--sensors",
                 str(tmp_path / "s.toml"), "--all", "-o", str(tmp_path / "t.csv"), "--json",
                 str(tmp_path / "t.json")])
    err = capsys.readouterr().err
    assert code == 0, err
    found = re.search(r"warning: (\d+) of (\d+) ADS-B reports have no usable accuracy \((\d+) have NACp 0 "
                      r"\(unknown\) or no position\): not used in the tracks", err)
    assert found and found[1] == found[2] == found[3] and 0.9 * len(sim.adsb) < int(found[1]) <= len(sim.adsb)
    tracks = pd.read_csv(tmp_path / "t.csv")
    assert not tracks["sources"].fillna("").str.contains("021:").any()
