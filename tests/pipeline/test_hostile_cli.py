"""A user's hostile inputs on the command line: special files, outputs that are inputs, damaged positions,
odd sensor files. Each run either works or fails with one line naming the file or option and the reason,
with no traceback, and a failed run writes nothing."""

from __future__ import annotations

import os
import threading
from pathlib import Path

import numpy as np
import pytest

from msdc.pipeline.cli import main
from msdc.pipeline.jobs import stats
from msdc.pipeline.jobs.common import OptionError

FIX = Path(__file__).resolve().parents[2] / "fixtures"
RADAR, ADSB, SENSORS = FIX / "radar.ast", FIX / "adsb.ast", FIX / "sensors.toml"


def _run(argv: list[str], capsys) -> tuple[int, str, str]:
    try:
        status = main([str(a) for a in argv])
    except SystemExit as exc:  # argparse's usage errors
        status = exc.code
    out, err = capsys.readouterr()
    return status, out, err


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no FIFOs on this system")
def test_a_fifo_input_is_refused_not_read(tmp_path):
    """A FIFO's bytes can be read once only (the digest that spots repeated inputs would eat them) and
    opening one blocks until a writer comes: it is refused by name. A writer is provided so that a
    version that reads it does not hang the test but passes validation, which fails the test."""
    fifo = tmp_path / "live.ast"
    os.mkfifo(fifo)

    def writer():
        try:
            with open(fifo, "wb") as fh:
                fh.write(RADAR.read_bytes())
        except BrokenPipeError:  # the reader below closes without reading: what a refusal does
            pass

    threading.Thread(target=writer, daemon=True).start()
    try:
        with pytest.raises(OptionError, match="live.ast: input is not a regular file"):
            stats.validate(stats.StatsOptions(inputs=(str(fifo),)))
    finally:  # release the writer if it is still waiting for a reader
        fd = os.open(fifo, os.O_RDONLY | os.O_NONBLOCK)
        os.close(fd)


@pytest.mark.skipif(not Path("/dev/null").exists(), reason="no /dev/null")
def test_a_device_input_is_refused_by_name(capsys):
    status, _, err = _run(["stats", "/dev/null"], capsys)
    assert status == 2
    assert err.strip() == "msdc stats: /dev/null: input is not a regular file (a FIFO, socket or device); " \
                          "give a recording file"


# (id, the input's name in tmp_path (a copy of the radar fixture), argv after the command's own words,
#  the option that names it); {IN} is the copied input, {D} the directory
CORR = ["correlate", "{IN}", "{A}", "--sensors", "{S}", "--callsign", "MAS72"]
SPARE = [
    ("decode-o", "rec.csv", ["decode", "{IN}", "{A}", "-o", "{IN}"], "-o {IN}"),
    ("decode-category-file", "out_cat048.csv", ["decode", "{IN}", "{A}", "-o", "{D}/out.csv"],
     "-o {D}/out.csv"),
    ("correlate-json", "rec.json", [*CORR, "--json", "{IN}"], "--json {IN}"),
    ("correlate-figure", "r_tracks.png", [*CORR, "-o", "{D}/r.xlsx"], "-o {D}/r.xlsx"),
    ("quality-o", "rec.xlsx", ["quality", "{IN}", "{A}", "--sensors", "{S}", "--all", "-o", "{IN}"],
     "-o {IN}"),
    ("track-o", "rec.parquet", ["track", "{IN}", "{A}", "--sensors", "{S}", "--all", "-o", "{IN}"],
     "-o {IN}"),
    ("conflicts-o", "rec.csv", ["conflicts", "{IN}", "{A}", "--sensors", "{S}", "-o", "{IN}"], "-o {IN}"),
    ("conflicts-companion", "c_losses.csv", ["conflicts", "{IN}", "{A}", "--sensors", "{S}",
                                             "-o", "{D}/c.csv"], "-o {D}/c.csv"),
]


@pytest.mark.parametrize(("name", "argv", "option"), [c[1:] for c in SPARE], ids=[c[0] for c in SPARE])
def test_an_output_that_is_an_input_is_refused_and_the_input_kept(name, argv, option, tmp_path, capsys):
    """Recordings may carry any name: an output (or a file written beside it) that is one of the inputs
    would overwrite the recording. It is refused before anything is read or written."""
    recording = tmp_path / name
    recording.write_bytes(RADAR.read_bytes())
    values = {"IN": recording, "A": ADSB, "S": SENSORS, "D": tmp_path}
    status, _, err = _run([a.format(**values) for a in argv], capsys)
    assert status == 2, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in err
    assert lines[0].startswith(f"msdc {argv[0]}: {option.format(**values)}")
    assert lines[0].endswith(f"is the input {recording}; writing it would destroy the recording")
    assert recording.read_bytes() == RADAR.read_bytes()
    assert sorted(p.name for p in tmp_path.iterdir()) == [name]


def test_an_output_linked_to_an_input_is_refused(tmp_path, capsys):
    """The same file under another name (a hard link) is still the input."""
    recording = tmp_path / "rec.ast"
    recording.write_bytes(RADAR.read_bytes())
    os.link(recording, tmp_path / "out.csv")
    status, _, err = _run(["decode", recording, "-o", tmp_path / "out.csv"], capsys)
    assert status == 2 and f"is the input {recording}" in err
    assert recording.read_bytes() == RADAR.read_bytes()


def _mas72(tmp_path: Path, cat: int, latitude_of_row: dict[int, float] | None = None) -> Path:
    """The fixture's MAS72 reports of one category from 08:00 to 08:10 as a raw file, with the latitudes
    of some rows (by position) replaced."""
    import msdc.asterix as asterix
    from msdc.asterix.encode import encode_frame

    f = asterix.read(RADAR if cat == 48 else ADSB).frames[cat]
    f = f[(f.callsign == "MAS72") & f.time_of_day.between(28800, 29400)].copy()
    for row, lat in (latitude_of_row or {}).items():
        f.iloc[row, f.columns.get_loc("latitude")] = lat
    p = tmp_path / f"cat{cat:03d}.ast"
    p.write_bytes(encode_frame(cat, f))
    return p


@pytest.mark.parametrize("command", ["correlate", "quality", "track", "conflicts"])
def test_an_adsb_position_off_the_earth_is_named_and_left_out(command, tmp_path, capsys):
    """I021/131 encodes latitudes up to 360 deg: a damaged report may carry one. The run goes on without
    it and a warning names the file, the count, the first report's offset and value."""
    import msdc.asterix as asterix

    radar, adsb = _mas72(tmp_path, 48), _mas72(tmp_path, 21, {5: 120.0, 9: -95.0})
    with pytest.warns(asterix.ContentWarning,
                      match=r"2 of its \d+ CAT021 records hold a position off the Earth.*likely damaged"):
        frame = asterix.read(adsb).frames[21]
    assert frame["latitude"].iloc[5] == pytest.approx(120.0, abs=1e-6)  # the damage is in the file
    out = tmp_path / "out"
    out.mkdir()
    argv = [command, radar, adsb, "--sensors", SENSORS, "--date", "2019-03-01"]
    argv += {"correlate": ["--callsign", "MAS72", "--json", out / "c.json"],
             "quality": ["--callsign", "MAS72", "--json", out / "q.json"],
             "track": ["--callsign", "MAS72", "--json", out / "t.json", "--noise", "declared"],
             "conflicts": ["-o", out / "k.csv", "--step", "10"]}[command]
    status, _, err = _run(argv, capsys)
    assert status == 0, err
    assert "Traceback" not in err
    assert (f"msdc {command}: warning: cat021.ast: 2 CAT021 report(s) with a position off the Earth "
            f"(first at offset {int(frame['offset'].iloc[5])}: latitude 120.0000, longitude "
            f"{frame['longitude'].iloc[5]:.4f}): damaged data, left out of the measurements") in err


def test_measurements_leave_out_adsb_positions_off_the_earth(tmp_path):
    import msdc.asterix as asterix
    from msdc.pipeline.model.measurements import build_measurements

    with pytest.warns(asterix.ContentWarning, match="1 of its .* likely damaged"):
        frame = asterix.read(_mas72(tmp_path, 21, {3: 91.0})).frames[21]
    frame.loc[7, "longitude"] = -180.5
    from msdc.pipeline.model.measurements import OffEarthWarning

    with pytest.warns(OffEarthWarning, match="2 CAT021 report"):
        meas = build_measurements(None, frame, date=None)
    assert len(meas) == len(frame) - 2
    assert set(meas["offset"]) == set(frame["offset"]) - {frame["offset"].iloc[3], frame["offset"].iloc[7]}


@pytest.mark.parametrize("altitude", ["nan", "inf", "-inf", "1e300", "-100001.0"])
def test_a_sensor_altitude_that_is_no_height_is_refused_by_name(altitude, tmp_path, capsys):
    """A NaN, infinite or absurd antenna height used to put every plot at NaN and end in a traceback after
    decoding; it is refused with the file, the entry, the sensor and the value before anything is
    decoded (docs/guide/sensors.md: "naming the file, the entry, the radar and the value")."""
    sensors = tmp_path / "s.toml"
    sensors.write_text(SENSORS.read_text().replace("altitude_m = 40.0", f"altitude_m = {altitude}"))
    status, _, err = _run(["correlate", RADAR, ADSB, "--sensors", sensors, "--callsign", "MAS72"], capsys)
    assert status == 2
    value = repr(float(altitude))
    assert err.strip() == (f"msdc correlate: {sensors}: [[sensor]] entry 1 ('KLIA MSSR', SAC 25 SIC 201): "
                           f"altitude_m = {value} is outside -100000.0..100000.0")


def test_a_sensor_file_that_is_not_utf8_is_named(tmp_path, capsys):
    """TOML is UTF-8: a Latin-1 file (a site name with an accent) is refused naming the file and byte."""
    sensors = tmp_path / "s.toml"
    sensors.write_bytes(SENSORS.read_bytes().replace(b"KLIA MSSR", b"Barcelona Montseny \xe9"))
    status, _, err = _run(["correlate", RADAR, ADSB, "--sensors", sensors, "--callsign", "MAS72"], capsys)
    at = SENSORS.read_bytes().index(b"KLIA MSSR") + len(b"Barcelona Montseny ")
    assert status == 2
    assert err.strip() == (f"msdc correlate: {sensors}: not valid TOML: byte {at} is not UTF-8 "
                           "(invalid continuation byte)")


def test_a_misspelt_sensor_key_is_refused_not_ignored(tmp_path, capsys):
    """``sigma_range = 30`` (without _m) used to be ignored, leaving the 70 m default in every covariance
    without a word; an unknown key is refused with the nearest allowed one."""
    sensors = tmp_path / "s.toml"
    sensors.write_text(SENSORS.read_text() + "sigma_range = 30.0\n")
    argv = ["track", RADAR, ADSB, "--sensors", sensors, "--all", "--json", tmp_path / "t.json"]
    status, _, err = _run(argv, capsys)
    assert status == 2
    assert err.strip() == (f"msdc track: {sensors}: [[sensor]] entry 1: unknown key 'sigma_range' (did you "
                           "mean sigma_range_m? allowed: name, sac, sic, latitude, longitude, altitude_m, "
                           "sigma_range_m, sigma_azimuth_deg, category, kind, sigma_m, min_range_nm, "
                           "max_range_nm, min_elevation_deg, max_elevation_deg)")
    assert not (tmp_path / "t.json").exists()


def test_stats_with_a_category_whose_every_block_failed(capsys):
    """The fixture's CAT021 is edition 2.7; pinned to 0.26 none of its blocks walks. stats lists the radar
    and the skipped blocks (a KeyError traceback before); alone, the ADS-B file decodes nothing: exit 1."""
    status, out, err = _run(["stats", RADAR, ADSB, "--edition", "21=0.26"], capsys)
    assert status == 0, err
    assert "Traceback" not in err
    cats = out.split("Records per category:")[1].split("\n\n")[0]
    assert "48" in cats and "21" not in cats
    skipped = out.split("Skipped blocks by reason:")[1].split("\n\n")[0]
    assert "none" not in skipped and "21" in skipped
    status, out, err = _run(["stats", ADSB, "--edition", "21=0.26"], capsys)
    assert status == 1 and "Traceback" not in err
    size = os.path.getsize(ADSB)  # the input and its size named ('msdc: nothing could be decoded' before)
    assert err.strip().endswith(f"msdc stats: nothing could be decoded from {ADSB} ({size:,} bytes)")


def test_stats_of_an_empty_file_names_it(tmp_path, capsys):
    empty = tmp_path / "empty.ast"
    empty.write_bytes(b"")
    status, _, err = _run(["stats", str(empty)], capsys)
    assert status == 1 and err.strip().endswith(f"msdc stats: nothing could be decoded from {empty} (empty)")


def test_two_different_pins_of_one_category_are_refused(tmp_path, capsys):
    """The last of two pins used to win silently; the same pin twice is harmless."""
    status, _, err = _run(["decode", RADAR, "--edition", "21=0.26", "--edition", "21=2.7",
                           "-o", tmp_path / "o.csv"], capsys)
    assert status == 2
    assert err.strip() == ("msdc decode: --edition 21=2.7: CAT021 is already pinned to 0.26; give one "
                           "edition per category")
    assert not list(tmp_path.iterdir())
    assert _run(["decode", RADAR, "--edition", "48=1.27", "--edition", "48=1.27"], capsys)[0] == 0


@pytest.mark.parametrize("bad_tod", [120000.0, 86400.0, 131071.0])
def test_one_time_of_day_past_midnight_moves_no_other_report(bad_tod, tmp_path, capsys):
    """A raw recording counts midnights from its times of day in file order. One damaged I048/140 of
    120000 s (the 24-bit field reaches 131072 s) in an 08:00-11:20 recording used to look like a jump
    back of a day and forth again, and put every other report on the next day."""
    import msdc.asterix as asterix
    from msdc.asterix.encode import encode_frame

    frame = asterix.read(RADAR).frames[48]
    i = len(frame) // 2
    damaged = frame.copy()
    damaged.iloc[i, damaged.columns.get_loc("time_of_day")] = bad_tod
    path = tmp_path / "r.ast"
    path.write_bytes(encode_frame(48, damaged))
    good = asterix.read(RADAR, date="2019-03-01").frames[48]["timestamp"]
    with pytest.warns(asterix.ContentWarning, match="1 of its 3266 CAT048 records hold .* likely damaged"):
        got = asterix.read(path, date="2019-03-01").frames[48]
    others = np.arange(len(frame)) != i
    assert (got["day"].to_numpy()[others] == 0).all()
    assert (got["timestamp"][others] == good[others]).all()
    status, out, _ = _run(["stats", path, "--date", "2019-03-01"], capsys)
    assert status == 0
    assert "2019-03-01 08:00:02" in out.split("Records per SAC/SIC")[0]


def test_a_wrong_edition_pin_is_suggested_when_no_adsb_record_decodes(capsys):
    """The fixture's CAT021 is edition 2.7: pinned to 0.26, no block walks. The message said only 'no ADS-B
    records'; it now says the blocks failed under that edition, and the editions they walk under: every
    2.x edition (the fixture's items are laid out alike in all of them, ../shared/specs). Every block is
    counted (2 before: careful framing cut the holding chain of blocks that were of another edition)."""
    data = Path(ADSB).read_bytes()
    blocks, q = 0, 0
    while q < len(data):  # the fixture's blocks, from their LEN fields
        blocks, q = blocks + 1, q + int.from_bytes(data[q + 1:q + 3], "big")
    status, _, err = _run(["correlate", RADAR, ADSB, "--sensors", SENSORS, "--callsign", "MAS72",
                           "--edition", "21=0.26"], capsys)
    assert status == 1
    assert (f"msdc correlate: no ADS-B (CAT021) records in the inputs: {blocks} CAT021 block(s) could not be "
            "decoded under edition 0.26; every one sampled decodes under 2.1, 2.2, 2.3, 2.4, 2.5, 2.6, 2.7: "
            "pin the right one or try --edition 21=auto ('msdc stats' lists them)") in err


@pytest.mark.parametrize(("argv", "option"), [
    (["stats", ""], "input"),
    (["correlate", RADAR, ADSB, "--sensors", "", "--all"], "--sensors"),
    (["correlate", RADAR, ADSB, "--sensors", SENSORS, "--all", "-o", ""], "-o"),
    (["quality", RADAR, ADSB, "--sensors", SENSORS, "--all", "--json", " "], "--json"),
    (["track", RADAR, ADSB, "--sensors", SENSORS, "--all", "--figures", ""], "--figures"),
    (["conflicts", RADAR, ADSB, "--sensors", SENSORS, "-o", "c.csv", "--figures", ""], "--figures"),
], ids=["input", "sensors", "output", "json", "track-figures", "conflicts-figures"])
def test_an_empty_path_is_named_as_empty(argv, option, tmp_path, monkeypatch, capsys):
    """An unset shell variable gives an empty path, which Path() reads as '.': messages said '-o .: must
    end in .xlsx' or '.: input is a directory', and --figures '' drew into the current directory."""
    monkeypatch.chdir(tmp_path)
    status, _, err = _run(argv, capsys)
    assert status == 2
    value = argv[argv.index(option) + 1] if option != "input" else ""
    assert err.strip() == f"msdc {argv[0]}: {option} {value!r}: an empty path"
    assert not list(tmp_path.iterdir())


def _with_sic(tmp_path: Path, rows: list[int], sic: int = 202) -> tuple[Path, list[int]]:
    """The fixture's MAS72 radar plots from 08:00 to 08:10 with the SIC of some rows (by position) damaged,
    and the offsets those rows get in the file."""
    import msdc.asterix as asterix
    from msdc.asterix.encode import encode_frame

    good = _mas72(tmp_path, 48)
    f = asterix.read(good).frames[48]
    f.iloc[rows, f.columns.get_loc("sic")] = sic
    p = tmp_path / "damaged048.ast"
    p.write_bytes(encode_frame(48, f))
    decoded = asterix.read(p).frames[48]
    assert (decoded["sic"].iloc[rows] == sic).all()  # the damage is in the file
    return p, [int(decoded["offset"].iloc[r]) for r in rows]


_SELECT = {"correlate": ["--callsign", "MAS72"], "quality": ["--callsign", "MAS72"],
           "track": ["--callsign", "MAS72", "--noise", "declared"], "conflicts": ["--step", "10"]}


def _run_with_radar(command: str, radar, tmp_path, capsys):
    """Run ``command`` on ``radar`` and MAS72's ADS-B, writing its JSON (conflicts: its CSV) into a fresh
    folder: (status, stderr, the path written)."""
    adsb = _mas72(tmp_path, 21)
    out = tmp_path / "out"
    out.mkdir()
    written = out / ("k.csv" if command == "conflicts" else "r.json")
    argv = [command, radar, adsb, "--sensors", SENSORS, "--date", "2019-03-01", *_SELECT[command],
            "-o" if command == "conflicts" else "--json", written]
    status, _, err = _run(argv, capsys)
    return status, err, written


@pytest.mark.parametrize("command", ["correlate", "quality", "track", "conflicts"])
def test_a_phantom_radar_of_two_damaged_records_is_left_out_with_a_warning(command, tmp_path, capsys):
    """One damaged I048/010 used to stop the whole run with 'not in the sensor table'. Two records of a
    SAC/SIC the sensor file lacks are fewer than 3 (the floor of the stray-radar rule): the run goes on
    without them, and a warning names the file, the pair, the count and the first offset."""
    radar, offsets = _with_sic(tmp_path, [4, 20])
    status, err, written = _run_with_radar(command, radar, tmp_path, capsys)
    assert status == 0, err
    assert "Traceback" not in err
    assert (f"warning: damaged048.ast: 2 CAT048 record(s) from SAC/SIC 25/202 (first at offset {offsets[0]}) "
            f"not in {SENSORS} and too few for a radar (fewer than 3") in err
    assert written.is_file()


def test_the_phantom_records_are_the_only_ones_left_out(tmp_path):
    """The stray rule drops exactly the records of the undeclared pair, nothing else."""
    import msdc.asterix as asterix
    from msdc.pipeline.model.sensors import declared_radar, read_sensors

    radar, offsets = _with_sic(tmp_path, [4, 20])
    frame = asterix.read(radar).frames[48].assign(file="damaged048.ast")
    kept, warnings = declared_radar(frame, read_sensors(SENSORS), str(SENSORS))
    assert len(warnings) == 1
    assert sorted(set(frame["offset"]) - set(kept["offset"])) == offsets
    assert len(kept) == len(frame) - 2


@pytest.mark.parametrize("command", ["correlate", "quality", "track", "conflicts"])
def test_an_undeclared_radar_with_enough_records_still_stops_the_run(command, tmp_path, capsys):
    """Three records of one undeclared pair reach the floor: that may be a real radar, whose plots cannot be
    placed without its site, so the run stops with the sensor-file lines to add and writes nothing."""
    radar, _ = _with_sic(tmp_path, [4, 20, 30])
    status, err, written = _run_with_radar(command, radar, tmp_path, capsys)
    assert status == 1
    assert "Traceback" not in err
    assert f"radar SAC/SIC 25/202 not in {SENSORS}; add its position:" in err
    assert "sic = 202" in err
    assert list(written.parent.iterdir()) == []


@pytest.fixture(scope="module")
def adsb_0_23(tmp_path_factory) -> Path:
    """The fixture's ADS-B reports written as edition 0.23, one record per block (what the real LEBL
    ground station records): nothing on the wire says which edition it is."""
    import msdc.asterix as asterix
    from msdc.asterix.encode import encode_frame

    columns = ["sac", "sic", "time_of_day", "latitude", "longitude", "address", "callsign", "flight_level"]
    frame = asterix.read(ADSB).frames[21][columns].iloc[:400]
    path = tmp_path_factory.mktemp("e023") / "adsb023.ast"
    path.write_bytes(encode_frame(21, frame, edition="0.23", records_per_block=1))
    return path


def test_a_0_23_recording_pinned_to_2_7_is_named_in_every_job(adsb_0_23, tmp_path, capsys):
    """Read as 2.7 (a wrong pin), the 0.23 blocks fail: each job names the edition to pin (I021/130 is 6
    bytes in 0.23 and 8 from 0.24 on, so 0.23 alone walks them), writes nothing, and pinned right (or not
    pinned: auto) it works."""
    advice = "400 CAT021 block(s) could not be decoded under edition 2.7; every one sampled decodes under " \
             "0.23: pin it with --edition 21=0.23"
    wrong = ["--edition", "21=2.7"]
    status, _, err = _run(["stats", adsb_0_23, *wrong], capsys)
    assert status == 1 and f"msdc stats: warning: adsb023.ast: {advice}" in err
    status, _, err = _run(["decode", adsb_0_23, "-o", tmp_path / "d.csv", *wrong], capsys)
    assert status == 1 and f"msdc decode: warning: adsb023.ast: {advice}" in err
    assert "not ASTERIX" not in err  # blocks of another edition are ASTERIX
    # one line per skipped block for the first 20, then a count
    assert err.count(f"msdc decode: {adsb_0_23}: offset ") == 20
    assert f"msdc decode: {adsb_0_23}: 380 more skipped block(s)" in err
    status, _, err = _run(["track", adsb_0_23, "--all", "-o", tmp_path / "t.parquet", *wrong], capsys)
    assert status == 1 and f"records in the inputs (--sources radar,adsb): {advice} ('msdc stats'" in err
    status, _, err = _run(["correlate", RADAR, adsb_0_23, "--sensors", SENSORS, "--all", "--date",
                           "2019-03-01", "-o", tmp_path / "r.xlsx", *wrong], capsys)
    assert status == 1 and f"no ADS-B (CAT021) records in the inputs: {advice} ('msdc stats'" in err
    assert not list(tmp_path.iterdir())
    for right in (["--edition", "21=0.23"], []):
        status, _, err = _run(["stats", adsb_0_23, *right], capsys)
        assert status == 0 and "warning" not in err


def test_a_0_23_recording_pinned_to_2_7_alone_is_why_quality_and_correlate_have_no_records(
        adsb_0_23, tmp_path, capsys):
    """quality needs only one kind of sensor: given the 0.23 recording alone, pinned to 2.7, it said "no
    radar (CAT048) records", sending the user for a radar file; the failed CAT021 blocks and the edition
    come first. correlate (which needs both) names them too."""
    advice = "400 CAT021 block(s) could not be decoded under edition 2.7; every one sampled decodes under " \
             "0.23: pin it with --edition 21=0.23 ('msdc stats' lists them)"
    for job in (["quality", adsb_0_23, "--all", "-o", tmp_path / "q.xlsx"],
                ["correlate", adsb_0_23, "--sensors", SENSORS, "--all", "-o", tmp_path / "r.xlsx"]):
        status, _, err = _run([*job, "--edition", "21=2.7"], capsys)
        assert status == 1 and "Traceback" not in err
        assert f"msdc {job[0]}: no ADS-B (CAT021) or radar (CAT048) records in the inputs: {advice}" in err
    assert not list(tmp_path.iterdir())


def test_a_0_23_recording_beside_a_2_7_one(adsb_0_23, capsys):
    """Two ADS-B inputs of different editions: unpinned, auto chooses each one's edition and both decode;
    pinned to 2.7, the 2.7 one decodes and the 0.23 one is named with its edition (a warning: the run goes
    on with what decoded)."""
    status, out, err = _run(["stats", ADSB, adsb_0_23], capsys)
    assert status == 0 and "could not be decoded" not in err  # (it warns that the copy runs back in time)
    assert "chose 2.7" in out and "chose 0.23" in out
    status, _, err = _run(["stats", ADSB, adsb_0_23, "--edition", "21=2.7"], capsys)
    assert status == 0
    warned = [line for line in err.splitlines() if "warning" in line]
    assert len(warned) == 1 and "adsb023.ast: 400 CAT021 block(s)" in warned[0] and "21=0.23" in warned[0]


@pytest.mark.parametrize(("command", "date"), [("decode", "9999-12-31"), ("stats", "0001-01-01"),
                                               ("correlate", "1000-01-01"), ("decode", "2262-04-11")])
def test_a_date_nanosecond_timestamps_cannot_hold_is_refused(command, date, tmp_path, capsys):
    """9999-12-31 wrapped decode's timestamps to 1816 and 1000-01-01 correlate's window to 2169 (exit 0);
    stats raised an OverflowError traceback. Now: one line naming --date, the value and the range."""
    out = tmp_path / "out"
    out.mkdir()
    argv = {"decode": ["decode", RADAR, "-o", out / "d.csv"], "stats": ["stats", RADAR],
            "correlate": ["correlate", RADAR, ADSB, "--sensors", SENSORS, "--callsign", "MAS72",
                          "-o", out / "c.xlsx"]}[command]
    status, stdout, err = _run([*argv, "--date", date], capsys)
    assert status == 2 and "Traceback" not in err and stdout == ""
    assert err.strip() == (f"msdc {command}: --date {date}: outside the days msdc can time (1678-01-01 to "
                           f"2261-12-31: nanosecond UTC timestamps); give the UTC day of the recording")
    assert list(out.iterdir()) == []


def test_a_radar_of_categories_the_jobs_do_not_read_is_named(tmp_path, capsys):
    """An older radar's recording (CAT001 plots between CAT002 north markers) given to correlate, track and
    evaluate, which take CAT048 plots: correlate said only "no radar (CAT048) records in the inputs" and
    track that the file held no CAT021 or CAT048 record, as for an empty file. Each now says what the file
    holds. Blocks by hand: CAT001 I001/010 SAC 20 SIC 1 and I001/020 (FSPEC 0xC0, a plot: TYP 0); CAT002
    I002/010 and I002/000 message type 1 (north marker)."""
    plot = bytes([1, 0, 7, 0xC0, 20, 1, 0x20])
    north = bytes([2, 0, 7, 0xC0, 20, 1, 1])
    old = tmp_path / "old_radar.ast"
    old.write_bytes(north + plot + plot + north + plot)
    holds = (f"{old}: it holds CAT001 (3 blocks) and CAT002 (2 blocks), which this command does not read "
             "('msdc decode' and 'msdc stats' decode them)")
    out = tmp_path / "out"
    out.mkdir()
    status, _, err = _run(["correlate", old, ADSB, "--sensors", SENSORS, "--all", "--date", "2019-03-01",
                           "-o", out / "r.xlsx"], capsys)
    assert status == 1 and f"msdc correlate: no radar (CAT048) records in the inputs\n  {holds}\n" in err
    status, _, err = _run(["track", old, ADSB, "--all", "-o", out / "t.parquet"], capsys)
    assert status == 0 and (out / "t.parquet").exists()  # the ADS-B tracks: the warning says the rest
    assert f"msdc track: warning: {holds}\n" in err and "no CAT021 or CAT048 record" not in err
    status, _, err = _run(["evaluate", old, ADSB, "--sensors", SENSORS, "--preset", "eurocontrol-1997-ssr",
                           "--date", "2019-03-01"], capsys)
    # evaluate reads CAT002 (a radar's north markers give its scan period): only CAT001 is left unread
    assert status == 1 and (f"present: 021:0/1 (adsb)\n  {old}: it holds CAT001 (3 blocks), which this "
                            "command does not read") in err


@pytest.mark.parametrize("option", ["--sensors", "--sectors", "--reference-file", "--preset"])
def test_an_output_that_is_a_file_another_option_reads_is_refused(option, tmp_path, capsys):
    """--json naming the sectors (or sensors, reference, preset) file replaced it with the evaluation: a
    recording given as an output was refused, those files were not. The file is left byte for byte."""
    import shutil

    sources = {"--sensors": SENSORS, "--sectors": None, "--reference-file": None, "--preset": None}
    target = tmp_path / "in.json"
    if sources[option] is not None:
        shutil.copy(sources[option], target)
    else:
        target.write_text("{}")  # never read: the outputs are checked first
    argv = ["evaluate", RADAR, ADSB, "--sensors", target if option == "--sensors" else SENSORS, "--date",
            "2019-03-01", "--preset", target if option == "--preset" else "eurocontrol-1997-ssr"]
    if option not in ("--sensors", "--preset"):
        argv += [option, target]
    before = target.read_bytes()
    status, _, err = _run([*argv, "--json", target], capsys)
    assert status == 2, err
    assert f"--json {target}: is the {option} file {target}; writing it would destroy it" in err
    assert target.read_bytes() == before


def test_evaluate_without_sensor_records_names_no_option_it_lacks(tmp_path, capsys):
    """It ended "(--sources radar,adsb,mlat,smr)": evaluate has no --sources (it reads every sensor kind),
    and the user who tried it was refused."""
    empty = tmp_path / "empty.ast"
    empty.write_bytes(b"")
    status, _, err = _run(["evaluate", empty, "--sensors", SENSORS, "--preset", "eurocontrol-1997-ssr",
                           "--date", "2019-03-01"], capsys)
    assert status == 1 and "records in the inputs" in err and "--sources" not in err, err
    status, _, err = _run(["track", empty, "--sensors", SENSORS, "--all", "-o", tmp_path / "t.csv"], capsys)
    assert "(--sources radar,adsb)" in err  # track has it


def test_an_input_name_that_is_not_utf8_is_written_as_its_escape(tmp_path, capsys):
    """A file name with the byte 0xFF (not UTF-8; Python holds it as the lone surrogate U+DCFF) ended decode,
    correlate, quality, track, conflicts, evaluate and ingest in a UnicodeEncodeError traceback: no CSV,
    Parquet, JSON or workbook writer takes it. The name is written as the text we\\xffird.ast."""
    import json

    import pandas as pd
    from openpyxl import load_workbook

    name = os.fsdecode(b"we\xffird.ast")
    radar = tmp_path / name
    radar.write_bytes(RADAR.read_bytes())
    out = tmp_path / "out"
    out.mkdir()
    status, _, err = _run(["decode", radar, "--date", "2019-03-01", "-o", out / "d.parquet"], capsys)
    assert status == 0 and "Traceback" not in err
    assert set(pd.read_parquet(out / "d.parquet")["file"].astype(str)) == {"we\\xffird.ast"}
    status, _, err = _run(["correlate", radar, ADSB, "--sensors", SENSORS, "--date", "2019-03-01",
                           "--callsign", "MAS72", "-o", out / "c.xlsx", "--json", out / "c.json"], capsys)
    assert status == 0 and "Traceback" not in err
    doc = json.loads((out / "c.json").read_text(encoding="utf-8"))
    assert doc["inputs"][0]["path"] == str(tmp_path / "we\\xffird.ast")
    sheet = load_workbook(out / "c.xlsx")["Parameters"]
    cells = [c for row in sheet.iter_rows(values_only=True) for c in row]
    assert str(tmp_path / "we\\xffird.ast") in cells
    status, _, err = _run(["ingest", "--dataset", out / "ds", radar, "--date", "2019-03-01"], capsys)
    assert status == 0 and "Traceback" not in err
    manifest = json.loads((out / "ds" / "manifest.json").read_text(encoding="utf-8"))
    assert manifest["inputs"][0]["file"] == "we\\xffird.ast"


@pytest.mark.parametrize("command", ["decode", "stats", "track", "quality"])
def test_a_damaged_input_whose_name_is_not_utf8_is_said_with_its_escape(tmp_path, capsys, command):
    """Its skipped blocks' table put the name (lone surrogate U+DCFF) into a pandas str column: a
    UnicodeEncodeError traceback in every command; stats' --format hint then opened the escaped text, a
    file of another name ("No such file or directory")."""
    name = os.fsdecode(b"we\xffird.ast")
    radar = tmp_path / name
    data = RADAR.read_bytes()
    radar.write_bytes(data[:100] + b"\x00\x00\x01" + data[100:])  # three bytes no block starts with
    argv = {"decode": ["-o", tmp_path / "d.csv"], "stats": [],
            "track": ["--sensors", SENSORS, "--all", "-o", tmp_path / "t.csv"],
            "quality": ["--sensors", SENSORS, "--all", "-o", tmp_path / "q.xlsx"]}[command]
    status, out, err = _run([command, radar, "--date", "2019-03-01", *argv], capsys)
    assert "Traceback" not in err and "No such file" not in err, err
    assert status == 0, err
    if command == "stats":
        assert "we\\xffird.ast" in out.split("Skipped blocks by reason:")[1]


def test_a_time_of_day_past_24_h_is_no_time(tmp_path):
    """One MAS72 ADS-B report's I021/071 damaged to 130,000 s (the item holds up to 131,072 s; a time of day
    is below 86,400 s): it made a time the next day at 12:06:40, a third track segment there and every span
    a day long. The report gets no time, is left out of the measurements, and a warning names it (a frame
    read by asterix.read has no file column: "the inputs")."""
    import warnings as python_warnings

    import pandas as pd

    import msdc.asterix as asterix
    from msdc.asterix.encode import encode_frame
    from msdc.pipeline.model.measurements import LeftOutWarning, build_measurements
    from msdc.pipeline.model.time import absolute_time

    adsb = asterix.read(ADSB).frames[21]
    at = adsb.index[adsb["callsign"] == "MAS72"][10]
    adsb.loc[at, ["time_of_day", "time_applicability_position"]] = 130_000.0  # both I021/071
    path = tmp_path / "tod.ast"
    path.write_bytes(encode_frame(21, adsb.drop(columns=["timestamp", "day"], errors="ignore")))
    with pytest.warns(asterix.ContentWarning, match="1 of its .* CAT021 records hold .* likely damaged"):
        frame = asterix.read(path, date="2019-03-01").frames[21]
    assert frame["time_of_day"].max() == 130_000.0  # decoded as the bytes say
    times = absolute_time(frame)
    assert times.isna().sum() == 1 and times.max() < pd.Timestamp("2019-03-02", tz="UTC")
    with python_warnings.catch_warnings(record=True) as said:
        python_warnings.simplefilter("always")
        meas = build_measurements(None, frame, date=None)
    texts = [str(w.message) for w in said if issubclass(w.category, LeftOutWarning)]
    offset = int(frame.loc[frame["time_of_day"] == 130_000.0, "offset"].iloc[0])
    assert texts == [f"the inputs: 1 CAT021 record(s) with a time of day outside 0-24 h (first at offset "
                     f"{offset}: 130,000.000 s): damaged data, left out of the measurements"]
    assert len(meas) == len(frame) - 1 and meas["time"].max() < pd.Timestamp("2019-03-02", tz="UTC")


NOT_ASTERIX = {  # a file that is not a recording at all: its name and bytes
    "text": ("notes.txt", b"the radar was switched off at noon\n" * 50),
    "jpeg": ("photo.jpg", b"\xff\xd8\xff\xe0\x00\x10JFIF\x00\x01\x01" + bytes(range(256)) * 8 + b"\xff\xd9"),
    "random": ("noise.bin", np.random.default_rng(7).integers(0, 256, 3000, np.uint8).tobytes()),
}
ANALYSES = {  # each analysis command's argv after the input, with the outputs it needs
    "correlate": ["--sensors", SENSORS, "--all"],
    "quality": ["--sensors", SENSORS, "--all"],
    "track": ["--sensors", SENSORS, "--all", "--json", "{D}/t.json"],
    "conflicts": ["--sensors", SENSORS, "-o", "{D}/c.xlsx"],
    "evaluate": ["--sensors", SENSORS, "--preset", "eurocontrol-1997-ssr"],
    "stats": [],
}


def _not_asterix_said(command: str, name: str, data: bytes, err: str) -> None:
    """The input is named as not ASTERIX, with its size, as decode says it, ahead of any other line about
    what the inputs lack."""
    said = (f"msdc {command}: warning: {name} is not ASTERIX: read as raw, 100% of its {len(data)} bytes "
            "frame into no data block that decodes")
    assert said in err, err
    lacking = [line for line in err.splitlines() if " records in the inputs" in line]
    assert all(err.index(said) < err.index(line) for line in lacking)


@pytest.mark.parametrize("kind", sorted(NOT_ASTERIX))
@pytest.mark.parametrize("command", sorted(ANALYSES))
def test_an_input_that_is_not_asterix_is_named_by_every_analysis(command, kind, tmp_path, capsys):
    """correlate and quality said only 'no radar (CAT048) or ADS-B (CAT021) records in the inputs' of a text
    file, a JPEG or random bytes; every analysis now names the file as not ASTERIX, as decode does."""
    name, data = NOT_ASTERIX[kind]
    (tmp_path / name).write_bytes(data)
    argv = [command, tmp_path / name, *(str(a).replace("{D}", str(tmp_path)) for a in ANALYSES[command])]
    status, _, err = _run(argv, capsys)
    assert status == 1 and "Traceback" not in err
    _not_asterix_said(command, name, data, err)


@pytest.mark.parametrize("command", ["correlate", "quality"])
def test_an_input_that_is_not_asterix_beside_a_radar_is_named_before_what_is_missing(command, tmp_path,
                                                                                      capsys):
    """Beside the radar fixture, correlate failed with 'no ADS-B (CAT021) records in the inputs', naming
    neither the text file nor what it is; quality warned so, and said nothing of the file either."""
    name, data = NOT_ASTERIX["text"]
    (tmp_path / name).write_bytes(data)
    status, _, err = _run([command, tmp_path / name, RADAR, *ANALYSES[command]], capsys)
    assert status == (1 if command == "correlate" else 0) and "Traceback" not in err
    _not_asterix_said(command, name, data, err)
