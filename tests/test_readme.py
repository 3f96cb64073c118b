"""What the README shows, run as written: the commands work and the printed output is the program's."""

from __future__ import annotations

import re
from pathlib import Path

from msdc.pipeline.cli import main

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text()


def _block_after(words: str) -> str:
    """The first fenced block after ``words`` in the README."""
    at = README.index(words)
    m = re.search(r"```[a-z]*\n(.*?)```", README[at:], re.S)
    assert m, f"no code block after {words!r}"
    return m.group(1)


def test_the_correlate_terminal_output_is_what_the_command_prints(capsys, monkeypatch):
    monkeypatch.chdir(ROOT)
    assert main(["correlate", "fixtures/radar.ast", "fixtures/adsb.ast", "--sensors", "fixtures/sensors.toml",
                 "--callsign", "MAS72", "--date", "2019-03-01"]) == 0
    printed = capsys.readouterr().out
    assert printed == _block_after("The terminal prints the same windows")
