"""The msdc command line on the bundled fixtures: outputs, messages and exit codes."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path

import openpyxl
import pandas as pd
import pytest

import msdc.asterix as asterix
from msdc.asterix.encode import encode_frame
from msdc.pipeline.cli import main
from msdc.pipeline.report.headers import column_name

FIX = Path(__file__).resolve().parents[2] / "fixtures"
RADAR, ADSB, SENSORS = FIX / "radar.ast", FIX / "adsb.ast", FIX / "sensors.toml"
TRUTH = json.loads((FIX / "truth.json").read_text())


def test_decode_two_categories_writes_one_csv_each(tmp_path, capsys):
    out = tmp_path / "out.csv"
    assert main(["decode", str(RADAR), str(ADSB), "-o", str(out)]) == 0
    err = capsys.readouterr().err
    r, a = tmp_path / "out_cat048.csv", tmp_path / "out_cat021.csv"
    assert "out_cat048.csv" in err and "out_cat021.csv" in err
    radar, adsb = pd.read_csv(r), pd.read_csv(a, dtype={"address": str, "mode3a": str})
    assert len(radar) == TRUTH["radar"]["rows"] and len(adsb) == TRUTH["adsb"]["rows"]
    assert {"sac", "sic", "time_of_day", "rho_nm", "theta_deg", "mode3a", "address", "callsign"} <= set(radar)
    assert set(adsb.address) == {ac["address"] for ac in TRUTH["aircraft"]}


def test_decode_single_category_parquet(tmp_path):
    out = tmp_path / "r.parquet"
    assert main(["decode", str(RADAR), "-o", str(out)]) == 0
    frame = pd.read_parquet(out)
    assert len(frame) == TRUTH["radar"]["rows"]
    assert frame["sac"].iloc[0] == TRUTH["radar"]["sac"]


def test_decode_exit_codes(tmp_path, capsys):
    junk = tmp_path / "junk.bin"
    junk.write_bytes(bytes(range(200)))
    assert main(["decode", str(junk)]) == 1
    err = capsys.readouterr().err
    assert "junk.bin is not ASTERIX" in err and "nothing written" in err
    assert main(["decode", str(tmp_path / "nope.ast")]) == 2
    assert "nope.ast" in capsys.readouterr().err
    damaged = tmp_path / "damaged.ast"
    data = RADAR.read_bytes()
    damaged.write_bytes(data[:1000] + b"\x00\x13\x37" + data[1000:])
    assert main(["decode", str(damaged)]) == 0
    assert "skipped" in capsys.readouterr().err


def test_stats(capsys):
    assert main(["stats", str(RADAR), str(ADSB)]) == 0
    out = capsys.readouterr().out
    assert str(TRUTH["radar"]["rows"]) in out and str(TRUTH["adsb"]["rows"]) in out
    assert "Skipped blocks" in out
    assert main(["stats", RADAR, ADSB]) == 0  # path objects from a library caller: their paths
    assert capsys.readouterr().out == out


def test_correlate_report_json_and_figure(tmp_path, capsys):
    xlsx, js = tmp_path / "report.xlsx", tmp_path / "s.json"
    assert main(["correlate", str(RADAR), str(ADSB), "--sensors", str(SENSORS), "--callsign", "mas 72",
                 "-o", str(xlsx), "--json", str(js)]) == 0
    captured = capsys.readouterr()
    for stage in ("Processing data files", "Pre-processing data", "Slotting data", "Correlating data"):
        assert stage in captured.err
    assert "MAS72" in captured.out
    expected = [w for w in TRUTH["overlap_windows"] if w["callsign"] == "MAS72"]
    windows = json.loads(js.read_text())["windows"]
    assert len(windows) == len(expected)
    for got, exp in zip(windows, expected, strict=True):
        assert got["start_tod"] == pytest.approx(exp["start_s"], abs=1 / 128)
        assert got["end_tod"] == pytest.approx(exp["end_s"], abs=1 / 128)
    wb = openpyxl.load_workbook(xlsx)
    assert {"Summary", "Correlation", "Slots", "Parameters"} <= set(wb.sheetnames)
    params = [[c.value for c in row] for row in wb["Parameters"].iter_rows()]
    flat = " ".join(str(v) for row in params for v in row if v is not None)
    assert "sha256" in flat.lower() and RADAR.name in flat
    assert (tmp_path / "report_tracks.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_correlate_unknown_callsign_lists_closest(capsys):
    assert main(["correlate", str(RADAR), str(ADSB), "--sensors", str(SENSORS), "--callsign", "MAS73"]) == 1
    err = capsys.readouterr().err
    assert "MAS73" in err and "MAS72" in err


def test_correlate_missing_radar_prints_toml(tmp_path, capsys):
    other = tmp_path / "sensors.toml"
    other.write_text('[[sensor]]\nname = "Other"\nsac = 1\nsic = 2\nlatitude = 1.0\nlongitude = 1.0\n'
                     'altitude_m = 0.0\n')
    assert main(["correlate", str(RADAR), str(ADSB), "--sensors", str(other), "--callsign", "MAS72"]) == 1
    err = capsys.readouterr().err
    assert "25/201" in err and "[[sensor]]" in err and "sac = 25" in err and "sic = 201" in err


def test_printed_sensor_template_pasted_unedited_is_refused(tmp_path, capsys):
    # the lines msdc prints for a radar without a site, pasted as they are, would put every plot at 0 N 0 E
    assert main(["quality", str(RADAR), "--all", "-o", str(tmp_path / "first.xlsx")]) == 1
    err = capsys.readouterr().err
    template = err[err.index("[[sensor]]"):]
    assert "latitude = 0.0" in template and "longitude = 0.0" in template
    sensors = tmp_path / "todo.toml"
    sensors.write_text(template)
    out = tmp_path / "q.xlsx"
    assert main(["quality", str(RADAR), "--sensors", str(sensors), "--all", "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert f"{sensors}: [[sensor]] entry 1 ('radar SAC 25 SIC 201', SAC 25 SIC 201)" in err
    assert "latitude 0, longitude 0 is no radar site" in err and "Traceback" not in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["todo.toml"]  # nothing written


def test_correlate_no_overlap_gives_spans(tmp_path, capsys):
    # MAS72 radar only before 08:03:20, ADS-B only after 08:36:40: the sensors never overlap
    r = asterix.read(RADAR).frames[48]
    a = asterix.read(ADSB).frames[21]
    r = r[(r.callsign == "MAS72") & (r.time_of_day < 29000)]
    a = a[(a.callsign == "MAS72") & (a.time_of_day > 31000)]
    rp, ap = tmp_path / "r.ast", tmp_path / "a.ast"
    rp.write_bytes(encode_frame(48, r))
    ap.write_bytes(encode_frame(21, a))
    assert main(["correlate", str(rp), str(ap), "--sensors", str(SENSORS), "--callsign", "MAS72"]) == 1
    err = capsys.readouterr().err
    assert "never overlap" in err and "radar" in err.lower()


def test_correlate_unreadable_input(capsys):
    assert main(["correlate", "/nonexistent/x.ast", "--sensors", str(SENSORS), "--all"]) == 2
    assert "/nonexistent/x.ast" in capsys.readouterr().err


def test_version(capsys):
    """--version prints the version (looked up only when asked) and exits 0."""
    with pytest.raises(SystemExit) as done:
        main(["--version"])
    assert done.value.code in (0, None)
    out = capsys.readouterr().out
    assert out.startswith("msdc ") and out.strip() != "msdc"


def test_program_exit_status_and_output():
    """``python -m pipeline.cli`` (the console entry point) prints everything and exits with main's status."""
    def msdc_stats(path: str) -> subprocess.CompletedProcess:
        return subprocess.run([sys.executable, "-m", "msdc.pipeline.cli", "stats", path], capture_output=True,
                              text=True, cwd=FIX.parent, timeout=300)

    done = msdc_stats(str(RADAR))
    assert done.returncode == 0
    assert done.stdout.startswith("Records per category") and done.stdout.endswith("\n")
    done = msdc_stats("/nonexistent/x.ast")
    assert done.returncode == 2 and "/nonexistent/x.ast" in done.stderr and done.stdout == ""


@pytest.mark.skipif(shutil.which("msdc") is None, reason="console script not installed")
def test_console_script():
    out = subprocess.run(["msdc", "--version"], capture_output=True, text=True, check=True)
    assert out.stdout.startswith("msdc ")
    done = subprocess.run([sys.executable, "-m", "msdc.pipeline.cli", "--help"], capture_output=True)
    assert done.returncode == 0


def test_quality_command(tmp_path, capsys):
    xlsx, js = tmp_path / "quality.xlsx", tmp_path / "q.json"
    assert main(["quality", str(RADAR), str(ADSB), "--sensors", str(SENSORS), "--callsign", "MAS72",
                 "-o", str(xlsx), "--json", str(js)]) == 0
    captured = capsys.readouterr()
    out = captured.out
    assert "Radar biases" in out and "NACp" in out
    # every file written is named on the terminal, the PNGs beside the workbook too, and nothing else is there
    pngs = sorted(tmp_path.glob("*.png"))
    assert pngs and f"msdc quality: {len(pngs) + 2} file(s) written:" in captured.err
    assert all(f"  {p} (figure)" in captured.err for p in pngs)
    assert f"  {xlsx} (workbook)" in captured.err and f"  {js} (JSON)" in captured.err
    assert all(f"{name}_se_{unit}" in out
               for name, unit in (("range_bias", "m"), ("azimuth_bias", "deg"), ("time_bias", "s")))
    wb = openpyxl.load_workbook(xlsx)
    assert {"Quality", "Update intervals", "Gaps", "Jumps", "ADS-B quality", "Radar accuracy", "Radar biases",
            "Figures", "Parameters"} <= set(wb.sheetnames)
    tables = json.loads(js.read_text())["tables"]
    jumps = [j for j in TRUTH["jumps"] if j["callsign"] == "MAS72"]
    assert len(tables["Jumps"]) == len(jumps)
    assert (tmp_path / "quality_intervals.png").exists()
    # the sheet lists the bins that hold intervals; the JSON every bin, with the same total per sensor
    ws = wb["Update intervals"]
    header = [column_name(c.value) for c in ws[1]]
    sheet = pd.DataFrame(list(ws.iter_rows(min_row=2, values_only=True)), columns=header)
    every = pd.DataFrame(tables["Update intervals"])
    assert (sheet["intervals"] > 0).all() and (every["intervals"] == 0).any()
    assert sheet.groupby("sensor")["intervals"].sum().to_dict() == every.groupby("sensor")["intervals"].sum(
        ).to_dict()


def test_correlate_filters_and_quality_sheets(tmp_path, capsys):
    xlsx, js = tmp_path / "c.xlsx", tmp_path / "c.json"
    assert main(["correlate", str(RADAR), str(ADSB), "--sensors", str(SENSORS), "--callsign", "MAS72",
                 "--drop-jumps", "--quality", "-o", str(xlsx), "--json", str(js)]) == 0
    err = capsys.readouterr().err
    pngs = sorted(set(tmp_path.glob("*.png")) - {tmp_path / "c_tracks.png"})  # the map is the track figure
    assert {p.name for p in pngs} >= {"c_intervals.png", "c_lags_1.png", "c_slotting_1.png"}
    assert f"  {tmp_path / 'c_tracks.png'} (track figure)" in err
    assert all(f"  {p} (figure)" in err for p in pngs)
    n_jumps = len(TRUTH["jumps"])  # filters run over all the input's ADS-B reports, before selection
    assert f"filter jumps: {n_jumps} of the input's ADS-B reports" in err
    doc = json.loads(js.read_text())
    assert doc["filters"]["jumps"] == n_jumps
    sheets = set(openpyxl.load_workbook(xlsx).sheetnames)
    assert {"Quality", "Radar accuracy", "Radar biases", "Figures"} <= sheets
    # without filters the thesis numbers are reproduced: nothing removed, no filter entry
    assert main(["correlate", str(RADAR), str(ADSB), "--sensors", str(SENSORS), "--callsign", "MAS72",
                 "--json", str(js)]) == 0
    assert json.loads(js.read_text())["filters"] == {}


def test_correlate_single_pcap_with_both_categories(tmp_path):
    # the fixture blocks, one per UDP packet, merged by time into one capture dated 2019-03-01
    from container_bytes import pcap_file, udp_frame

    day0 = 1551398400  # 2019-03-01T00:00:00Z = 17956 days * 86400 s
    blocks = []
    for path in (RADAR, ADSB):
        data = path.read_bytes()
        frame = asterix.read(path).frames
        (cat,) = frame
        first_tod = frame[cat].groupby("block")["time_of_day"].first()
        pos, i = 0, 0
        while pos < len(data):
            n = int.from_bytes(data[pos + 1:pos + 3], "big")
            blocks.append((float(first_tod[i]), data[pos:pos + n]))
            pos, i = pos + n, i + 1
    blocks.sort(key=lambda b: b[0])
    packets = [(day0 + int(t), int((t % 1) * 1e6), udp_frame(b)) for t, b in blocks]
    pcap = tmp_path / "both.pcap"
    pcap.write_bytes(pcap_file(packets)[0])
    js = tmp_path / "s.json"
    assert main(["correlate", str(pcap), "--sensors", str(SENSORS), "--callsign", "MAS72",
                 "--json", str(js)]) == 0
    windows = json.loads(js.read_text())["windows"]
    expected = [w for w in TRUTH["overlap_windows"] if w["callsign"] == "MAS72"]
    assert [round(w["start_tod"], 2) for w in windows] == [round(w["start_s"], 2) for w in expected]
    assert windows[0]["start"].startswith("2019-03-01T08:00:0")


def test_correlate_names_the_sensors_and_pairs(tmp_path, capsys):
    out = tmp_path / "s.json"
    assert main(["correlate", str(RADAR), str(ADSB), "--sensors", str(SENSORS), "--callsign", "MAS72",
                 "--json", str(out)]) == 0
    assert "048:25/201 vs 021:0/1" in capsys.readouterr().out
    windows = json.loads(out.read_text())["windows"]
    assert {(w["radar_sensor"], w["reference_sensor"]) for w in windows} == {("048:25/201", "021:0/1")}
    # one radar: no radar pair to correlate, said plainly
    assert main(["correlate", str(RADAR), str(ADSB), "--sensors", str(SENSORS), "--all",
                 "--pairs", "radar-radar"]) == 1
    assert "no aircraft is seen by two radars" in capsys.readouterr().err


@pytest.mark.parametrize("pin", [[], ["--edition", "21=auto"]])
def test_decode_says_which_edition_auto_chose(tmp_path, capsys, pin):
    """CAT021 is read with auto unless pinned (--edition 21=auto says it again): decode names the edition it
    walked (the simulator writes the newest, 2.7), as stats does; the 0.2x and 2.x families read I021/130
    and /131 differently."""
    assert main(["decode", str(ADSB), *pin, "-o", str(tmp_path / "a.csv")]) == 0
    err = capsys.readouterr().err
    assert f"{ADSB}: CAT021 edition auto chose 2.7 (" in err
    assert "none needed telling apart" in err or "apart:" in err


@pytest.mark.parametrize("who", [["--callsign", "MAS72"], ["--address", "750312"]])
def test_correlate_radar_radar_names_the_one_radar(tmp_path, capsys, who):
    """The fixtures hold one radar (048:25/201, fixtures/sensors.toml): MAS72 is NOT seen by two radars, and
    the message names it and the radar it was seen by; nothing is written."""
    out = tmp_path / "rr.json"
    assert main(["correlate", str(RADAR), str(ADSB), "--sensors", str(SENSORS), *who,
                 "--pairs", "radar-radar", "--json", str(out)]) == 1
    expected = "MAS72 (address 750312) is not seen by two radars (only by 048:25/201) (--pairs radar-radar)"
    assert expected in capsys.readouterr().err
    assert not out.exists()


def test_failing_job_prints_the_warning_that_explains_it(tmp_path, capsys):
    """The fixtures' radar hour moved to start just after midnight (00:00:00.5), behind two plots stamped
    23:59:59 and 23:59:59.5: with --date 2019-03-01 the hour falls on 2019-03-02, a day after the ADS-B
    (08:00-09:00), so correlate fails with "never overlap in time"; the warning that names the fix (--date
    2019-02-28) comes before the error, and nothing is written."""
    plots = asterix.read(str(RADAR)).frames[48]
    plots = plots.assign(time_of_day=plots["time_of_day"] - plots["time_of_day"].min() + 0.5)
    early = plots.head(2).assign(time_of_day=[86399.0, 86399.5])
    radar = tmp_path / "early.ast"
    radar.write_bytes(encode_frame(48, early) + encode_frame(48, plots))
    out = tmp_path / "e.json"
    assert main(["correlate", str(radar), str(ADSB), "--sensors", str(SENSORS), "--date", "2019-03-01",
                 "--callsign", "MAS72", "--json", str(out)]) == 1
    err = capsys.readouterr().err
    warning, error = err.find("early.ast: its first 2 report(s)"), err.find("never overlap in time")
    assert 0 <= warning < error
    assert "give --date 2019-02-28" in err[warning:error]
    assert not out.exists()
