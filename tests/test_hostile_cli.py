"""A user's hostile inputs on the command line: special files, outputs that are inputs, damaged positions,
odd sensor files. Each run either works or fails with one line naming the file or option and the reason,
with no traceback, and a failed run writes nothing."""

from __future__ import annotations

import os
import threading
from pathlib import Path

import pytest

from pipeline import jobs
from pipeline.cli import main

FIX = Path(__file__).resolve().parents[1] / "fixtures"
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
        with open(fifo, "wb") as fh:
            fh.write(RADAR.read_bytes())

    threading.Thread(target=writer, daemon=True).start()
    try:
        with pytest.raises(jobs.OptionError, match="live.ast: input is not a regular file"):
            jobs.validate(jobs.StatsOptions(inputs=(str(fifo),)))
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
