"""Issue 9 item 1: every option, the sensor file and every output path are checked before decoding.

Table-driven, in-process (``pipeline.cli.main``). An error exits 2 (usage) or 1 (data) with one line
naming the option or file and what is allowed, never a traceback, and writes nothing in the output
directory; the validation cases must fail before any input is decoded (decoding is made to fail the
test). A warning names the problem on stderr and the run goes on.
"""

from __future__ import annotations

import json
import os
import re
from pathlib import Path

import pytest

import msdc.asterix as asterix
from msdc.asterix.encode import encode_frame
from msdc.pipeline.cli import main
from msdc.pipeline.jobs import common

FIX = Path(__file__).resolve().parents[2] / "fixtures"
RADAR, ADSB, SENSORS = FIX / "radar.ast", FIX / "adsb.ast", FIX / "sensors.toml"
TRUTH = json.loads((FIX / "truth.json").read_text())

# {R} radar fixture, {A} ADS-B fixture, {S} sensor file, {O} the (empty) output directory, {RO} a directory
# that cannot be written, {BAD} a malformed sensor file, {X} a tiny raw file
CORR = ["correlate", "{R}", "{A}", "--sensors", "{S}", "--callsign", "MAS72"]
QUAL = ["quality", "{R}", "{A}", "--sensors", "{S}", "--callsign", "MAS72"]
CONF = ["conflicts", "{R}", "{A}", "--sensors", "{S}"]
TRACK = ["track", "{R}", "{A}", "--sensors", "{S}", "--callsign", "MAS72", "--json", "{O}/t.json"]

# (id, argv, exit status, words the one-line message must contain)
ERRORS = [
    ("slot-zero", CORR + ["--slot", "0"], 2, ["--slot", "0.1 to 3600"]),
    ("slot-nan", CORR + ["--slot", "nan"], 2, ["--slot", "finite"]),
    ("slot-tiny", CORR + ["--slot", "1e-9"], 2, ["--slot", "0.1 to 3600"]),
    ("slot-inf", CORR + ["--slot", "inf"], 2, ["--slot", "finite"]),
    ("slot-0.01", CORR + ["--slot", "0.01"], 2, ["--slot", "0.1 to 3600"]),
    ("slot-negative", CORR + ["--slot", "-10"], 2, ["--slot", "0.1 to 3600"]),
    ("slot-huge", CORR + ["--slot", "7200"], 2, ["--slot", "0.1 to 3600"]),
    ("slot-text", CORR + ["--slot", "ten"], 2, ["--slot", "float"]),
    ("gap-negative", CORR + ["--gap", "-1"], 2, ["--gap", "0.1 to 86400"]),
    ("gap-nan", CORR + ["--gap", "nan"], 2, ["--gap", "finite"]),
    ("gap-zero", CORR + ["--gap", "0"], 2, ["--gap", "0.1 to 86400"]),
    ("gap-inf", CORR + ["--gap", "inf"], 2, ["--gap", "finite"]),
    ("quality-gap-negative", QUAL + ["--gap", "-5"], 2, ["--gap", "0.1 to 86400"]),
    ("quality-gap-nan", QUAL + ["--gap", "nan"], 2, ["--gap", "finite"]),
    ("edition-decode", ["decode", "{R}", "--edition", "21=9.9"], 2, ["--edition 21=9.9", "2.7"]),
    ("edition-stats", ["stats", "{R}", "--edition", "21=9.9"], 2, ["--edition 21=9.9", "2.7"]),
    ("edition-correlate", CORR + ["--edition", "21=9.9"], 2, ["--edition 21=9.9", "2.7"]),
    ("edition-category", CORR + ["--edition", "99=1.0"], 2, ["--edition 99=1.0", "21"]),
    ("edition-48-unknown", ["stats", "{R}", "--edition", "48=1.99"], 2, ["--edition 48=1.99"]),
    ("edition-syntax", ["stats", "{R}", "--edition", "21"], 2, ["--edition", "CAT=EDITION"]),
    ("out-readonly-dir", CORR + ["-o", "{RO}/report.xlsx"], 2, ["-o", "not writable"]),
    ("out-is-directory", CORR + ["-o", "{O}/dir.xlsx"], 2, ["-o", "is a directory"]),
    ("out-figure-is-directory", CORR + ["-o", "{O}/fig.xlsx"], 2,
     ["-o", "fig_tracks.png is a directory"]),
    ("out-missing-dir", CORR + ["-o", "{O}/nowhere/report.xlsx"], 2, ["-o", "does not exist"]),
    # figures written beside the workbook: the sensor file's radar 25/201, and the first six windows
    ("quality-radar-figure-is-directory", QUAL + ["-o", "{O}/q.xlsx"], 2,
     ["-o", "q_radar_errors_25_201.png is a directory"]),
    ("quality-intervals-figure-is-directory", QUAL + ["-o", "{O}/i.xlsx"], 2,
     ["-o", "i_intervals.png is a directory"]),
    ("correlate-quality-lag-figure-is-directory", CORR + ["--quality", "-o", "{O}/c.xlsx"], 2,
     ["-o", "c_lags_3.png is a directory"]),
    ("out-table-is-directory", CORR + ["-o", "{O}/tab.xlsx"], 2, ["-o", "tab_slots.parquet is a directory"]),
    ("out-table-is-directory-parquet", CORR + ["-o", "{O}/tab.xlsx", "--tables", "parquet"], 2,
     ["-o", "tab_slots.parquet is a directory"]),
    # the conflict tables beside a CSV output: -o named as given, then the file beside it
    ("conflicts-losses-is-directory", CONF + ["-o", "{O}/c.csv"], 2,
     ["msdc conflicts: -o {O}/c.csv: its losses table {O}/c_losses.csv is a directory"]),
    ("conflicts-warning-times-is-directory", CONF + ["-o", "{O}/w.csv"], 2,
     ["msdc conflicts: -o {O}/w.csv: its warning times table {O}/w_warning_times.csv is a directory"]),
    ("tables-unknown", CORR + ["--tables", "csv"], 2, ["--tables", "auto"]),
    ("tables-parquet-no-output", CORR + ["--tables", "parquet"], 2, ["--tables parquet", "needs -o"]),
    ("out-txt", CORR + ["-o", "{O}/report.txt"], 2, ["-o", ".xlsx"]),
    ("out-no-suffix", CORR + ["-o", "{O}/report"], 2, ["-o", ".xlsx"]),
    ("json-readonly-dir", CORR + ["--json", "{RO}/s.json"], 2, ["--json", "not writable"]),
    ("json-is-directory", CORR + ["--json", "{O}/dir.json"], 2, ["--json", "is a directory"]),
    ("json-txt", CORR + ["--json", "{O}/s.txt"], 2, ["--json", ".json"]),
    ("quality-out-csv", QUAL + ["-o", "{O}/q.csv"], 2, ["-o", ".xlsx"]),
    ("quality-json-dir", QUAL + ["--json", "{O}/dir.json"], 2, ["--json", "is a directory"]),
    ("decode-out-xlsx", ["decode", "{R}", "-o", "{O}/out.xlsx"], 2, ["-o", ".csv or .parquet"]),
    ("decode-out-dir", ["decode", "{R}", "-o", "{O}/dir.csv"], 2, ["-o", "is a directory"]),
    ("decode-out-readonly", ["decode", "{R}", "-o", "{RO}/out.csv"], 2, ["-o", "not writable"]),
    ("min-nacp-negative", CORR + ["--min-nacp", "-3"], 2, ["--min-nacp", "0 to 11"]),
    ("min-nacp-12", CORR + ["--min-nacp", "12"], 2, ["--min-nacp", "0 to 11"]),
    ("min-nic-99", CORR + ["--min-nic", "99"], 2, ["--min-nic", "0 to 11"]),
    ("min-nic-fraction", CORR + ["--min-nic", "5.5"], 2, ["--min-nic", "int"]),
    ("chunk-zero", ["decode", "{R}", "--chunk-mb", "0"], 2, ["--chunk-mb", "0.1 to 4096"]),
    ("chunk-nan", ["decode", "{R}", "--chunk-mb", "nan"], 2, ["--chunk-mb", "finite"]),
    ("chunk-negative", ["decode", "{R}", "--chunk-mb", "-1"], 2, ["--chunk-mb", "0.1 to 4096"]),
    ("stats-chunk-zero", ["stats", "{R}", "--chunk-mb", "0"], 2, ["--chunk-mb", "0.1 to 4096"]),
    ("stats-chunk-inf", ["stats", "{R}", "--chunk-mb", "inf"], 2, ["--chunk-mb", "finite"]),
    ("address-xyz", CORR[:-2] + ["--address", "XYZ"], 2, ["--address", "hex"]),
    ("address-7-digits", CORR[:-2] + ["--address", "1234567"], 2, ["--address", "6 hex digits"]),
    ("callsign-punctuation", CORR[:-2] + ["--callsign", "MAS-72"], 2, ["--callsign", "letters and digits"]),
    ("two-aircraft-selections", CORR + ["--all"], 2, ["--all", "--callsign"]),
    ("sensors-malformed", ["correlate", "{R}", "{A}", "--sensors", "{BAD}", "--all"], 2, ["{BAD}"]),
    ("sensors-missing", ["correlate", "{R}", "{A}", "--sensors", "{O}/none.toml", "--all"], 2,
     ["--sensors", "does not exist"]),
    ("sensors-directory", ["correlate", "{R}", "{A}", "--sensors", "{O}", "--all"], 2,
     ["--sensors", "sensor is a directory, not a TOML sensor file"]),
    ("sensors-device", ["correlate", "{R}", "{A}", "--sensors", "/dev/null", "--all"], 2,
     ["--sensors /dev/null: sensor is not a regular file (a FIFO, socket or device)"]),
    ("input-missing", ["stats", "{O}/none.ast"], 2, ["none.ast", "does not exist"]),
    ("input-directory", ["decode", "{O}", "-o", "{O}/x.csv"], 2, ["is a directory"]),
    ("date-malformed", ["stats", "{R}", "--date", "2019-13-01"], 2, ["--date", "YYYY-MM-DD"]),
    ("format-unknown", ["stats", "{R}", "--format", "zip"], 2, ["--format", "raw"]),
    ("category-8-decode", ["decode", "{R}", "--category", "8"], 2, ["--category", "62"]),
    ("pairs-unknown", CORR + ["--pairs", "radar"], 2, ["--pairs", "radar-adsb"]),
    ("track-step-zero", TRACK + ["--step", "0"], 2, ["--step", "> 0"]),
    ("track-step-nan", TRACK + ["--step", "nan"], 2, ["--step", "finite"]),
    ("track-step-inf", TRACK + ["--step", "inf"], 2, ["--step", "finite"]),
    ("track-step-huge", TRACK + ["--step", "7200"], 2, ["--step", "3600"]),
    ("track-coast-negative", TRACK + ["--max-coast", "-1"], 2, ["--max-coast", ">= --step"]),
    ("track-coast-nan", TRACK + ["--max-coast", "nan"], 2, ["--max-coast", "finite"]),
    ("track-coast-below-step", TRACK + ["--step", "10", "--max-coast", "5"], 2, ["--max-coast", ">= --step"]),
    ("track-tpm-unknown", TRACK + ["--tpm", "magic"], 2, ["--tpm", "magic"]),
    ("track-tpm-nan", TRACK + ["--tpm", "fixed:nan"], 2, ["--tpm"]),
    ("track-sources-unknown", TRACK + ["--sources", "radar,wam"], 2, ["--sources", "radar,adsb"]),
    ("track-sources-repeat", TRACK + ["--sources", "radar,radar"], 2, ["--sources", "without repeats"]),
    ("track-sources-empty", TRACK + ["--sources", ""], 2, ["--sources"]),
    ("track-noise-unknown", TRACK + ["--noise", "nacp"], 2, ["--noise", "declared, estimate"]),
    ("track-out-xlsx", TRACK + ["-o", "{O}/t.xlsx"], 2, ["-o", ".csv or .parquet"]),
    ("track-out-readonly", TRACK + ["-o", "{RO}/t.csv"], 2, ["-o", "not writable"]),
    ("track-json-dir", TRACK[:-2] + ["--json", "{O}/dir.json"], 2, ["--json", "is a directory"]),
    ("track-figures-file", TRACK + ["--figures", "{S}"], 2, ["--figures", "not a directory"]),
    # a folder that cannot be made: track drew every figure's track first and failed at the end, exit 1
    ("track-figures-readonly", TRACK + ["--figures", "{RO}/fig"], 2, ["--figures", "is not writable"]),
    ("conflicts-figures-readonly", CONF + ["-o", "{O}/c.xlsx", "--figures", "{RO}/fig"], 2,
     ["--figures", "is not writable"]),
    ("track-no-output", TRACK[:-2], 2, ["at least one output"]),
    ("track-gap-nan", TRACK + ["--address", "ABC"], 2, ["--address", "--callsign"]),
]


@pytest.fixture
def paths(tmp_path):
    """The placeholders' values: an output directory (with two directories named like outputs), a
    directory that cannot be written, a malformed sensor file."""
    out = tmp_path / "out"
    out.mkdir()
    for name in ("dir.xlsx", "dir.json", "dir.csv", "fig_tracks.png", "tab_slots.parquet",
                 "q_radar_errors_25_201.png", "i_intervals.png", "c_lags_3.png", "c_losses.csv",
                 "w_warning_times.csv"):
        (out / name).mkdir()
    ro = tmp_path / "readonly"
    ro.mkdir()
    ro.chmod(0o555)
    if os.access(ro, os.W_OK) and os.geteuid() == 0:  # root writes anywhere a mode allows nothing
        ro = Path("/proc")
    bad = tmp_path / "bad.toml"
    bad.write_text('[[sensor]]\nname = "KLIA"\nsac = 25\nsic = \nlatitude = 2.7\n')
    yield {"R": str(RADAR), "A": str(ADSB), "S": str(SENSORS), "O": str(out), "RO": str(ro), "BAD": str(bad)}
    (tmp_path / "readonly").chmod(0o755)


def _fill(argv: list[str], paths: dict[str, str]) -> list[str]:
    return [a.format(**paths) for a in argv]


def _contents(d: Path) -> set[str]:
    return {str(p.relative_to(d)) for p in d.rglob("*")}


def _run(argv: list[str], capsys) -> tuple[int, str, str]:
    try:
        status = main(argv)
    except SystemExit as exc:  # argparse's usage errors
        status = exc.code
    out, err = capsys.readouterr()
    return status, out, err


@pytest.fixture
def no_decoding(monkeypatch):
    """Decoding anything fails the test: these errors must be found before."""
    def decoded(*args, **kwargs):
        raise AssertionError("an input was decoded before the options were checked")

    monkeypatch.setattr(common, "load", decoded)
    monkeypatch.setattr(asterix, "iter_read", decoded)
    monkeypatch.setattr(asterix.reader, "categories_in", decoded)


@pytest.mark.parametrize(("argv", "status", "words"), [c[1:] for c in ERRORS], ids=[c[0] for c in ERRORS])
def test_bad_option_fails_before_decoding(argv, status, words, paths, capsys, no_decoding):
    out_dir = Path(paths["O"])
    before = _contents(out_dir)
    got, stdout, err = _run(_fill(argv, paths), capsys)
    assert got == status, err
    assert "Traceback" not in err + stdout
    message = [line for line in err.splitlines() if line.startswith("msdc") and "warning:" not in line]
    assert len(message) == 1, err  # argparse: "msdc correlate: error: ..." after its usage lines
    for word in _fill(words, paths):
        assert word in message[0], (word, message[0])
    assert _contents(out_dir) == before


def test_malformed_sensor_file_is_named_once(paths, capsys, no_decoding):
    status, _, err = _run(_fill(["quality", "{R}", "{A}", "--sensors", "{BAD}", "--all"], paths), capsys)
    assert status == 2
    assert err.count(paths["BAD"]) == 1, err


# ---------------------------------------------------------------------------------------------------------
# Warnings: the run goes on


def _tiny(tmp_path: Path, name: str, tod_from: float, tod_to: float, cat: int = 48) -> Path:
    """A raw file of the fixture's MAS72 records of one category between two times of day."""
    f = asterix.read(RADAR if cat == 48 else ADSB).frames[cat]
    f = f[(f.callsign == "MAS72") & f.time_of_day.between(tod_from, tod_to)]
    p = tmp_path / name
    p.write_bytes(encode_frame(cat, f))
    return p


def test_implausible_sensor_altitude_warns(tmp_path, capsys):
    sensors = tmp_path / "s.toml"
    sensors.write_text(SENSORS.read_text().replace("altitude_m = 40.0", "altitude_m = -99999"))
    status, _, err = _run(["quality", str(RADAR), str(ADSB), "--sensors", str(sensors), "--callsign",
                           "MAS72"], capsys)
    assert status == 0, err
    assert "warning" in err and "altitude_m = -99999" in err and str(sensors) in err


def test_same_input_twice_is_skipped_and_not_doubled(tmp_path, capsys):
    copy = tmp_path / "radar_copy.ast"
    copy.write_bytes(RADAR.read_bytes())
    js = tmp_path / "s.json"
    status, _, err = _run(["correlate", str(RADAR), str(ADSB), str(copy), "--sensors", str(SENSORS),
                           "--callsign", "MAS72", "--json", str(js)], capsys)
    assert status == 0, err
    assert "warning" in err and "radar_copy.ast" in err and "skipped" in err
    once = tmp_path / "once.json"
    assert _run(["correlate", str(RADAR), str(ADSB), "--sensors", str(SENSORS), "--callsign", "MAS72",
                 "--json", str(once)], capsys)[0] == 0
    windows, single = (json.loads(p.read_text())["windows"] for p in (js, once))
    assert len(windows) == len([w for w in TRUTH["overlap_windows"] if w["callsign"] == "MAS72"])
    assert windows == single  # same reports, same duplicate counts: the copy added nothing


@pytest.mark.parametrize("command", [["stats"], ["decode"], ["decode", "-o", "out.csv"]])
def test_date_on_a_pcap_warns(tmp_path, capsys, command):
    """A pcap is dated by its capture time: --date is ignored, and every command that reads it says so
    (decode said nothing), naming the file; a raw recording beside it takes the date without a word."""
    from container_bytes import pcap_file, udp_frame

    raw = _tiny(tmp_path, "r.ast", 28800, 28900)
    pcap = tmp_path / "r.pcap"
    pcap.write_bytes(pcap_file([(1551398400 + 28800, 0, udp_frame(raw.read_bytes()))])[0])
    argv = [command[0], str(pcap), str(raw), "--date", "2020-01-01",
            *(str(tmp_path / a) if a.endswith(".csv") else a for a in command[1:])]
    status, _, err = _run(argv, capsys)
    assert status == 0, err
    ignored = [line for line in err.splitlines() if "--date ignored" in line]
    assert len(ignored) == 1 and "warning" in ignored[0] and str(pcap) in ignored[0]


def test_inputs_running_backwards_warn(tmp_path, capsys):
    late = _tiny(tmp_path, "late.ast", 30000, 30100)
    early = _tiny(tmp_path, "early.ast", 28800, 28900)
    status, _, err = _run(["stats", str(late), str(early)], capsys)
    assert status == 0, err
    assert "warning" in err and "backwards" in err and "early.ast" in err


# ---------------------------------------------------------------------------------------------------------
# Data errors found after decoding: exit 1, one clear line, nothing written


def test_unknown_callsign_writes_nothing(tmp_path, capsys):
    out = tmp_path / "out"
    out.mkdir()
    status, _, err = _run(["correlate", str(RADAR), str(ADSB), "--sensors", str(SENSORS), "--callsign",
                           "NOPE1", "-o", str(out / "r.xlsx"), "--json", str(out / "r.json")], capsys)
    assert status == 1 and "NOPE1" in err and "Traceback" not in err
    assert _contents(out) == set()


def test_nothing_decoded_writes_no_csv(tmp_path, capsys):
    junk = tmp_path / "junk.ast"
    junk.write_bytes(bytes(range(256)) * 4)
    out = tmp_path / "out"
    out.mkdir()
    status, _, err = _run(["decode", str(junk), "-o", str(out / "x.csv")], capsys)
    assert status == 1 and "junk.ast is not ASTERIX" in err and "nothing written" in err
    assert _contents(out) == set()


def test_a_category_the_input_lacks_is_named_with_what_it_holds(tmp_path, capsys):
    """decode <radar file> --category 21 said only 'nothing could be decoded'; it names what the file holds,
    its blocks counted here by walking the raw headers (CAT, 2-byte LEN) independently of the decoder."""
    radar = Path(__file__).resolve().parents[2] / "fixtures" / "radar.ast"
    data, at, blocks = radar.read_bytes(), 0, 0
    while at < len(data):
        assert data[at] == 48
        at += int.from_bytes(data[at + 1:at + 3], "big")
        blocks += 1
    out = tmp_path / "out"
    out.mkdir()
    status, _, err = _run(["decode", str(radar), "--category", "21", "-o", str(out / "x.csv")], capsys)
    assert status == 1 and "Traceback" not in err
    assert (f"msdc decode: nothing could be decoded with --category 21: {radar} holds CAT048 ({blocks} "
            "block(s)); msdc decodes CAT048 with --category 48" in err)
    assert _contents(out) == set()


def test_a_trackers_recording_decoded_with_the_defaults_names_the_category_to_ask(tmp_path, capsys):
    """A recording of CAT062 system tracks alone, decoded without --category (the measurement categories):
    nothing decodes, and the message names the --category that decodes it, not a list of bytes read as
    CAT010 records (which the framer made of the track messages before it stepped over their blocks)."""
    import pandas as pd

    from msdc.asterix.encode import encode_frame

    frame = pd.DataFrame({"sac": 25, "sic": 100, "time_of_day": [float(t) for t in range(100)],
                          "latitude": 41.3, "longitude": 2.1, "track_number": list(range(100)),
                          "flight_level": 350.0, "x_m": 1000.0, "y_m": -2000.0, "vx_ms": 200.0, "vy_ms": 0.0})
    path = tmp_path / "tracks.ast"
    path.write_bytes(encode_frame(62, frame, records_per_block=25))
    out = tmp_path / "out"
    out.mkdir()
    status, _, err = _run(["decode", str(path), "-o", str(out / "x.csv")], capsys)
    assert status == 1 and "Traceback" not in err
    assert (f"msdc decode: nothing could be decoded: {path} holds CAT062 (4 block(s)); msdc decodes CAT062 "
            "with --category 62 (without --category: the measurement categories CAT010, CAT020, CAT021, "
            "CAT048)" in err)
    assert _contents(out) == set()


def test_filter_removing_every_report_says_so(tmp_path, capsys):
    # --min-nacp 11: no fixture ADS-B report reaches NACp 11 (the simulator's NACp is 8 to 10)
    out = tmp_path / "out"
    out.mkdir()
    status, _, err = _run(["correlate", str(RADAR), str(ADSB), "--sensors", str(SENSORS), "--callsign",
                           "MAS72", "--min-nacp", "11", "-o", str(out / "r.xlsx")], capsys)
    assert status == 1, err
    assert "not seen by" not in err
    assert "MAS72: --min-nacp 11 removed all" in err and "of its ADS-B reports" in err
    assert _contents(out) == set()


def _no_overlap_inputs(tmp_path: Path) -> tuple[Path, Path]:
    # MAS72 radar only before 08:03:20 (28999 s), ADS-B only after 08:36:40: the sensors never overlap
    return _tiny(tmp_path, "r.ast", 0, 28999), _tiny(tmp_path, "a.ast", 31001, 86400, cat=21)


def test_all_without_overlap_gives_the_reason(tmp_path, capsys):
    r, a = _no_overlap_inputs(tmp_path)
    status, stdout, err = _run(["correlate", str(r), str(a), "--sensors", str(SENSORS), "--all"], capsys)
    assert status == 0, err  # a report: nothing correlated, one skipped window with its reason
    assert "0 window(s) correlated, 1 skipped" in stdout
    assert "never overlap" in stdout and "MAS72" in stdout


def test_spans_are_times_not_seconds_of_day(tmp_path, capsys):
    r, a = _no_overlap_inputs(tmp_path)
    status, _, err = _run(["correlate", str(r), str(a), "--sensors", str(SENSORS), "--callsign", "MAS72"],
                          capsys)
    assert status == 1
    assert "08:0" in err and "08:3" in err  # radar ends 08:03, ADS-B starts 08:36
    assert not re.search(r"\d{5}(\.\d+)?-\d{5}", err), err  # no "28800.0-28999.0 s"


def test_a_run_failing_while_writing_leaves_nothing(tmp_path: Path, monkeypatch, capsys) -> None:
    """The JSON is written before the workbook, the track figure meanwhile: if the workbook fails, they go
    too, files that were there before stay, and the run ends with a one-line message, not a traceback."""
    import msdc.pipeline.report.excel as excel

    def disk_full(*args, **kwargs):
        raise OSError(28, "No space left on device", str(tmp_path / "r.xlsx"))

    monkeypatch.setattr(excel, "write_report", disk_full)
    (tmp_path / "kept.txt").write_text("was here")
    code = main(["correlate", str(FIX / "radar.ast"), str(FIX / "adsb.ast"), "--sensors",
                 str(FIX / "sensors.toml"), "--callsign", "MAS72", "-o", str(tmp_path / "r.xlsx"),
                 "--json", str(tmp_path / "r.json")])
    err = capsys.readouterr().err
    assert code == 1 and "Traceback" not in err and "No space left on device" in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["kept.txt"]


def test_separations_far_beyond_the_radar_accuracy_warn_of_a_wrong_site(tmp_path: Path, capsys) -> None:
    """A site 0.5 deg (about 55 km) north of the real one puts every plot tens of km from ADS-B: warned,
    naming the radar and the sensor file; the true site gives median separations of a few hundred m."""
    args = [str(FIX / "radar.ast"), str(FIX / "adsb.ast"), "--callsign", "MAS72"]
    assert main(["correlate", *args, "--sensors", str(FIX / "sensors.toml")]) == 0
    assert "check its site" not in capsys.readouterr().err
    moved = tmp_path / "moved.toml"
    moved.write_text((FIX / "sensors.toml").read_text().replace("latitude = 2.7456", "latitude = 3.2456"))
    assert main(["correlate", *args, "--sensors", str(moved)]) == 0
    err = capsys.readouterr().err
    assert "radar 048:25/201" in err and "check its site in" in err and str(moved) in err


@pytest.mark.parametrize("command", [["quality", "--all"], ["track", "--callsign", "MAS72"],
                                     ["conflicts", "--date", "2019-03-01", "--step", "5"]])
def test_quality_track_and_conflicts_warn_of_a_wrong_site_too(command, tmp_path: Path, capsys) -> None:
    """quality printed range and azimuth biases of km and degrees, track gated most plots, with no word
    of the cause: the plots are matched to the same aircraft's ADS-B report within 1 s, and a site 0.5 deg
    (about 55 km) north puts their median tens of km away; the true site, a few hundred m at most."""
    # quality prints its tables without -o (its workbook and figures are no part of the check)
    output = [] if command[0] == "quality" else ["-o", str(tmp_path / "out.csv")]
    args = [command[0], str(FIX / "radar.ast"), str(FIX / "adsb.ast"), *command[1:], *output]
    assert main([*args, "--sensors", str(FIX / "sensors.toml")]) == 0
    assert "check its site" not in capsys.readouterr().err
    moved = tmp_path / "moved.toml"
    moved.write_text((FIX / "sensors.toml").read_text().replace("latitude = 2.7456", "latitude = 3.2456"))
    main([*args, "--sensors", str(moved)])
    err = capsys.readouterr().err
    assert "radar 048:25/201: its plots lie a median" in err and f"check its site in {moved}" in err
    km = float(err.split("its plots lie a median ")[1].split(" km")[0])
    assert 50 < km < 60  # 0.5 deg of latitude is 55.5 km; the plots, placed from the moved site, follow it


@pytest.mark.parametrize("only", ["adsb", "radar"])
def test_quality_on_one_kind_of_sensor_fills_the_sheets_it_can(only, tmp_path, capsys):
    """quality refused ADS-B-only input ('no radar (CAT048) records') though the intervals, gaps, jumps and
    ADS-B quality sheets need no radar. With one kind of sensor it fills its own sheets, says which stay
    empty (radar accuracy needs both), and exits 0. Counts from the decoder: 14,986 ADS-B reports of 5
    aircraft, 3,266 radar plots."""
    import json

    import msdc.asterix as asterix

    path, cat = (ADSB, 21) if only == "adsb" else (RADAR, 48)
    frame = asterix.read(path).frames[cat]
    out = tmp_path / "out"
    out.mkdir()
    status, _, err = _run(["quality", str(path), "--sensors", str(SENSORS), "--all",
                           "--json", str(out / "q.json"), "-o", str(out / "q.xlsx")], capsys)
    assert status == 0, err
    assert "Traceback" not in err
    missing = "radar (CAT048)" if only == "adsb" else "ADS-B (CAT021)"
    assert f"warning: no {missing} records in the inputs: " in err
    doc = json.loads((out / "q.json").read_text())
    quality = doc["tables"]["Quality"]
    assert {row["sensor"] for row in quality} == {only}
    (total,) = [row for row in quality if row["callsign"] == "(all)"]
    assert total["reports"] == len(frame)
    assert len(quality) == 1 + frame["callsign"].nunique()
    assert doc["tables"]["Radar accuracy"] == [] and doc["tables"]["Radar biases"] == []
    assert (len(doc["tables"]["ADS-B quality"]) > 0) == (only == "adsb")
    assert doc["parameters"]["notes"] and f"CAT{cat ^ 21 ^ 48:03d}" in doc["parameters"]["notes"][0]
    assert (out / "q.xlsx").is_file()


@pytest.mark.parametrize("command", ["track", "conflicts"])
def test_track_and_conflicts_say_when_their_times_are_on_1970(command, tmp_path: Path, capsys) -> None:
    """Raw recordings carry no date: without --date the tracks' times were written on 1970-01-01 with no
    word; now a warning says so and how to fix it, and with --date there is none."""
    args = [command, str(FIX / "radar.ast"), str(FIX / "adsb.ast"), "--sensors", str(FIX / "sensors.toml"),
            "--callsign" if command == "track" else "--step", "MAS72" if command == "track" else "5"]
    assert main([*args, "-o", str(tmp_path / "a.csv")]) == 0
    assert "the inputs carry no date and --date was not given" in capsys.readouterr().err
    assert main([*args, "-o", str(tmp_path / "b.csv"), "--date", "2019-03-01"]) == 0
    assert "--date was not given" not in capsys.readouterr().err


def test_quality_of_adsb_alone_needs_no_sensor_file(tmp_path: Path, capsys) -> None:
    """quality refused ADS-B input without --sensors, which ADS-B never uses; radar plots without it stop
    the run naming their SAC/SIC (it said 'not in None'), and nothing is written."""
    out = tmp_path / "q.xlsx"
    assert main(["quality", str(FIX / "adsb.ast"), "--all", "--date", "2019-03-01", "-o", str(out)]) == 0
    assert out.exists()
    out.unlink()
    for png in tmp_path.iterdir():
        png.unlink()
    capsys.readouterr()
    assert main(["quality", str(FIX / "radar.ast"), str(FIX / "adsb.ast"), "--all", "-o", str(out)]) == 1
    err = capsys.readouterr().err
    assert "radar plots from SAC/SIC 25/201 need the radar's position, and no --sensors file was given" in err
    assert "ADS-B recordings alone" in err and "None" not in err
    assert list(tmp_path.iterdir()) == []


def test_an_input_that_decodes_nothing_is_named(tmp_path: Path, capsys) -> None:
    """A text file given by mistake beside a recording: the run goes on with the recording, and a warning
    names the file (it was silent); an empty file likewise."""
    text = tmp_path / "notes.txt"
    text.write_text("Two real ASTERIX recordings from public repositories.\n" * 20)
    empty = tmp_path / "empty.ast"
    empty.write_bytes(b"")
    args = [str(text), str(empty), str(FIX / "adsb.ast"), "--all", "--date", "2019-03-01"]
    assert main(["quality", *args, "-o", str(tmp_path / "q.xlsx")]) == 0
    err = capsys.readouterr().err
    assert f"{text}: no record decoded (" in err and f"{empty}: no CAT021 or CAT048 record in it" in err
    assert main(["track", *args, "-o", str(tmp_path / "t.csv")]) == 0
    assert f"{text}: no record decoded (" in capsys.readouterr().err


@pytest.mark.parametrize("command,flag,default", [
    ("decode", "--chunk-mb", "64"), ("ingest", "--chunk-mb", "8"), ("ingest", "--workers", "1"),
    ("sql", "--limit", "50"), ("listen", "--rotate", "1h"), ("listen", "--queue", "50000"),
    ("replay", "--ttl", "1"), ("replay", "--speed", "1"),
])
def test_help_gives_each_options_default(command, flag, default, capsys):
    """docs/guide/index.md: "msdc COMMAND --help lists each command's options with their defaults" (the
    defaults of the guide's options tables)."""
    with pytest.raises(SystemExit):
        main([command, "--help"])
    text = " ".join(capsys.readouterr().out.split())
    entry = text[text.index(f" {flag} "):]
    entry = entry[:entry.index(" --", 3)] if " --" in entry[3:] else entry
    assert f"(default: {default})" in entry


def test_replay_refuses_a_format_it_cannot_send_in_its_usage(capsys):
    with pytest.raises(SystemExit) as stop:
        main(["replay", "x.ast", "--to", "127.0.0.1:9", "--format", "oradis"])
    assert stop.value.code == 2
    assert "invalid choice: 'oradis'" in capsys.readouterr().err


@pytest.mark.parametrize("argv", [
    ["decode", "x.ast", "--area", "25/201:0-60nm:0-90deg", "--area", "25/201:0-60nm:90-180deg"],
    ["evaluate", "x.ast", "--sensors", "s.toml", "--preset", "ed117a", "--fl", "100:200", "--fl", "300:"],
    ["stats", "x.ast", "--from", "08:00", "--from", "09:00"],
])
def test_an_option_of_one_value_given_twice_is_refused(argv, capsys):
    """Not their union, and not the last silently (``--sensor`` and ``--edition`` are repeatable)."""
    with pytest.raises(SystemExit) as stop:
        main(argv)
    assert stop.value.code == 2
    err = capsys.readouterr().err
    assert f"{argv[-2]} given twice" in err and "give it once" in err


def test_a_date_given_twice_is_said_as_written(capsys):
    """It was said in Python's spelling: "(datetime.date(2019, 3, 1) and datetime.date(2019, 3, 2))"."""
    with pytest.raises(SystemExit):
        main(["stats", "x.ast", "--date", "2019-03-01", "--date", "2019-03-02"])
    assert "--date given twice (2019-03-01 and 2019-03-02): give it once" in capsys.readouterr().err


def test_a_scheduler_the_run_never_needed_is_said_unused(tmp_path, capsys):
    """correlate distributes nothing: a scheduler given to it (here one nothing listens at) was accepted in
    silence, as if the run had gone there."""
    argv = _fill(CORR, {"R": str(RADAR), "A": str(ADSB), "S": str(SENSORS)})
    status, _, err = _run([*argv, "--json", str(tmp_path / "c.json"), "--scheduler", "tcp://127.0.0.1:1"],
                          capsys)
    assert status == 0, err
    assert ("msdc correlate: warning: --scheduler tcp://127.0.0.1:1: not used: this run had no per-aircraft "
            "or per-partition work to distribute") in err
    status, _, err = _run([*argv, "--json", str(tmp_path / "c.json"), "--scheduler", "none"], capsys)
    assert status == 0 and "--scheduler" not in err  # nothing to say where no cluster was asked for
