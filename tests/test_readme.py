"""What the README and the documentation site (docs/) show, run as written: the commands work and the printed
output is the program's, every msdc command line shown parses, and the site builds with mkdocs --strict."""

from __future__ import annotations

import contextlib
import importlib.util
import io
import os
import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

from msdc.pipeline.cli import build_parser, main

ROOT = Path(__file__).resolve().parents[1]
README = "README.md"
FIXTURES = ["fixtures/radar.ast", "fixtures/adsb.ast", "--sensors", "fixtures/sensors.toml"]


def _text(page: str) -> str:
    return (ROOT / page).read_text()


_FENCE = re.compile(r"^```([a-z]*)\n(.*?)^```$", re.S | re.M)


def _blocks(text: str, lang: str | None = None, start: int = 0) -> list[str]:
    """The fenced blocks of a Markdown text that begin at or after ``start``, in order (only those of language
    ``lang`` when given: "" is a block with no language)."""
    return [m.group(2) for m in _FENCE.finditer(text)
            if m.start() >= start and (lang is None or m.group(1) == lang)]


def _block_after(page: str, words: str, lang: str | None = None) -> str:
    """The first fenced block that begins after ``words`` in ``page`` (a path from the repository root)."""
    text = _text(page)
    blocks = _blocks(text, lang, text.index(words))
    assert blocks, f"{page}: no code block after {words!r}"
    return blocks[0]


def _pages() -> list[str]:
    return [README, *sorted(str(p.relative_to(ROOT)) for p in (ROOT / "docs").rglob("*.md"))]


def _run(argv: list[str], capsys) -> tuple[str, str]:
    assert main(argv) == 0, argv
    out = capsys.readouterr()
    return out.out, out.err


# --- printed output -----------------------------------------------------------------------------------------

def test_the_correlate_terminal_output_is_what_the_command_prints(capsys, monkeypatch):
    monkeypatch.chdir(ROOT)
    printed, _ = _run(["correlate", *FIXTURES, "--callsign", "MAS72", "--date", "2019-03-01"], capsys)
    assert printed == _block_after("docs/guide/correlate.md", "The terminal prints the same windows")


@pytest.mark.parametrize(("page", "words", "inputs"), [
    (README, "What the recordings hold", ["fixtures/radar.ast"]),
    ("docs/guide/stats.md", "On the bundled fixtures", ["fixtures/radar.ast", "fixtures/adsb.ast"]),
])
def test_the_stats_output_is_what_the_command_prints(capsys, monkeypatch, page, words, inputs):
    monkeypatch.chdir(ROOT)
    shown = _block_after(page, words)  # the command, then what it prints
    assert shown.split() == ["msdc", "stats", *inputs, "--date", "2019-03-01"]
    printed, _ = _run(["stats", *inputs, "--date", "2019-03-01"], capsys)
    text = _text(page)
    assert printed == _blocks(text, "", text.index(shown))[0]


def test_the_quality_biases_shown_are_what_the_command_prints(capsys, monkeypatch):
    monkeypatch.chdir(ROOT)
    printed, _ = _run(["quality", *FIXTURES, "--all"], capsys)
    assert _block_after("docs/guide/quality.md", "note on what ADS-B as the reference") in printed


def test_the_track_terminal_output_is_what_the_command_prints(capsys, monkeypatch, tmp_path):
    monkeypatch.chdir(ROOT)
    printed, _ = _run(["track", *FIXTURES, "--callsign", "SIA305", "--date", "2019-03-01",
                       "--json", str(tmp_path / "tracks.json")], capsys)
    assert printed == _block_after("docs/guide/track.md", "command above prints")


def test_the_conflicts_lines_shown_are_what_the_command_prints(capsys, monkeypatch, tmp_path):
    monkeypatch.chdir(ROOT)
    printed, _ = _run(["conflicts", *FIXTURES, "--date", "2019-03-01", "-o", str(tmp_path / "conflicts.csv")],
                      capsys)
    assert _block_after("docs/guide/conflicts.md", "as on the fixtures") in printed


def test_a_truncated_recording_is_reported_as_shown(capsys, monkeypatch, tmp_path):
    page = "docs/decoding/bad-input.md"
    assert "head -c 100000 fixtures/radar.ast > cut.ast" in _block_after(page, "as a truncated recording is")
    (tmp_path / "cut.ast").write_bytes((ROOT / "fixtures" / "radar.ast").read_bytes()[:100_000])
    monkeypatch.chdir(tmp_path)
    printed, said = _run(["decode", "cut.ast", "--date", "2019-03-01"], capsys)
    assert "CAT048: 3200 records" in printed
    assert _block_after(page, "and says on stderr", "") in said
    printed, _ = _run(["stats", "cut.ast", "--date", "2019-03-01"], capsys)
    assert _block_after(page, "ends with", "") in printed


def test_the_encoder_example_prints_what_the_page_shows(monkeypatch, tmp_path):
    page = "docs/decoding/encoder.md"
    monkeypatch.chdir(tmp_path)
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        exec(_block_after(page, "read back", "python"), {})
    assert out.getvalue() == _block_after(page, "prints", "")


def test_the_library_examples_run(monkeypatch, tmp_path):
    """From Python: the jobs examples (they write report.xlsx and evaluation.xlsx: run in a folder of its
    own) and the steps."""
    page = "docs/guide/python.md"
    (tmp_path / "fixtures").symlink_to(ROOT / "fixtures", target_is_directory=True)
    monkeypatch.chdir(tmp_path)
    jobs = {}
    exec(_block_after(page, "writing is a separate call", "python"), jobs)
    assert (tmp_path / "report.xlsx").is_file() and (tmp_path / "report_tracks.png").is_file()
    evaluation = {}
    exec(_block_after(page, "The evaluation, for instance", "python"), evaluation)
    assert (tmp_path / "evaluation.xlsx").is_file()
    card = evaluation["card"]
    assert {"048:25/201", "021:0/107"} >= set(card["sensor"]) and "pd" in set(card["requirement"])
    steps = {}
    exec(_block_after(page, "plain functions on DataFrames", "python"), steps)
    assert [w.summary["window"] for w in steps["run"].windows] == [1, 2]


# --- command lines ------------------------------------------------------------------------------------------

def _shell_commands(page: str) -> list[str]:
    """Every msdc command line in the page's bash blocks (continuations joined, `a && b` split)."""
    found = []
    for block in _blocks(_text(page), "bash"):
        for line in block.replace("\\\n", " ").splitlines():
            for part in line.split("&&"):
                words = shlex.split(part, comments=True)
                if words[:1] == ["msdc"]:
                    found.append(words[1:])
    return found


def test_every_msdc_command_shown_parses():
    parser = build_parser()
    shown = [(page, argv) for page in _pages() for argv in _shell_commands(page)]
    assert len(shown) >= 12
    for page, argv in shown:
        try:
            parser.parse_args(argv)
        except SystemExit as exc:  # argparse's usage error
            pytest.fail(f"{page}: msdc {shlex.join(argv)} does not parse ({exc})")


def _option_strings() -> dict[str, set[str]]:
    parser = build_parser()
    (sub,) = [a for a in parser._actions if a.choices and isinstance(a.choices, dict)]
    return {"": set(parser._option_string_actions)} | {
        name: set(p._option_string_actions) for name, p in sub.choices.items()}


def test_every_option_in_a_synopsis_is_the_command_s():
    """The usage blocks (plain ``` blocks of msdc lines) name only options their command has."""
    options, checked = _option_strings(), 0
    for page in _pages():
        for block in (b for b in _blocks(_text(page), "") if b.startswith("msdc ")):
            command = None
            for line in block.splitlines():
                words = line.split()
                if words[:1] == ["msdc"]:
                    command = "" if words[1].startswith("-") else words[1]
                for option in re.findall(r"(?<![\w-])--?[a-z][a-z0-9-]*", line):
                    assert option in options[command], f"{page}: msdc {command} has no {option}"
                    checked += 1
    assert checked > 100


def test_the_readme_test_command_is_what_ci_runs():
    ci = (ROOT / ".ci" / "run").read_text().strip().splitlines()[-1]
    assert ci == "pip install '.[test]' && pytest"
    readme = _text(README)
    blocks = _blocks(readme, "bash", readme.index("## Set up"))
    assert blocks[1].strip() == "python3 -m venv .venv && . .venv/bin/activate && " + ci
    assert blocks[0].startswith("python3 -m venv .venv && . .venv/bin/activate && pip install . && msdc ")


def test_the_readme_is_short():
    assert len(_text(README).splitlines()) <= 150


# --- the site -----------------------------------------------------------------------------------------------

def test_the_site_builds_strictly(tmp_path):
    missing = [m for m in ("mkdocs", "material", "mkdocstrings", "mkdocstrings_handlers.python")
               if importlib.util.find_spec(m.split(".")[0]) is None
               or (m == "mkdocstrings_handlers.python" and importlib.util.find_spec(m) is None)]
    if missing:
        pytest.skip(f"the docs tools are not installed ({', '.join(missing)}): pip install '.[test]'")
    env = dict(os.environ, NO_MKDOCS_2_WARNING="1")
    done = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "--config-file",
                           str(ROOT / "mkdocs.yml"), "--site-dir", str(tmp_path / "site")],
                          capture_output=True, text=True, env=env, timeout=600)
    assert done.returncode == 0, done.stdout + done.stderr
    assert (tmp_path / "site" / "index.html").is_file()
    assert (tmp_path / "site" / "api" / "index.html").is_file()
