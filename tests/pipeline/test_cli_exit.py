"""``python -m pipeline.cli`` (and the installed ``msdc``, pipeline.cli:run) leaves through os._exit after
main(): the status is main's, stdout arrives whole through a pipe, stderr too, and the exit handlers
still run (openpyxl removes its temporary sheet files in one)."""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
FIX = ROOT / "fixtures"


def _msdc(*argv: str, env=None) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "msdc.pipeline.cli", *argv], cwd=ROOT, capture_output=True,
                          text=True, timeout=300, env=env)


def test_status_and_whole_output_through_a_pipe(tmp_path, capsys):
    from msdc.pipeline.cli import main

    argv = ["correlate", str(FIX / "radar.ast"), str(FIX / "adsb.ast"), "--sensors",
            str(FIX / "sensors.toml"), "--all"]
    assert main(argv) == 0
    expected = capsys.readouterr().out
    done = _msdc(*argv)
    assert done.returncode == 0, done.stderr
    assert done.stdout == expected and expected.count("\n") > 3  # every line, the last one too
    assert "window(s) correlated" in done.stdout


def test_failure_status_and_message():
    done = _msdc("correlate", str(FIX / "radar.ast"), "--sensors", "nowhere.toml", "--all")
    assert done.returncode == 2 and "nowhere.toml" in done.stderr and "Traceback" not in done.stderr


def test_exit_handlers_run_and_status_is_kept():
    code = ("import atexit, sys\n"
            "from pipeline.cli import run\n"
            "atexit.register(lambda: print('handler ran', flush=True))\n"
            "sys.argv = ['msdc', 'stats', 'no-such-file.ast']\n"
            "run()\n"
            "print('not reached')\n")
    done = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert done.stdout == "handler ran\n"  # the handler ran; nothing after run()
    assert done.returncode == 2 and "no-such-file.ast" in done.stderr


def test_the_command_collects_garbage_rarely():
    """run() raises the first generation's threshold to a million (Python's default is 700) before the
    command runs; importing pipeline.cli leaves it as it was (a notebook's interpreter keeps its own)."""
    code = ("import gc\n"
            "from pipeline import cli\n"
            "before = gc.get_threshold()\n"
            "cli.main = lambda: print(before, gc.get_threshold(), sep='\\n', flush=True) or 0\n"
            "cli.run()\n")
    done = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    before, after = (ast.literal_eval(line) for line in done.stdout.splitlines())
    assert before[0] < 10_000 and after == (1_000_000, *before[1:])
