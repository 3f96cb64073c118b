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
