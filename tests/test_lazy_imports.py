"""A command imports only what it uses: ``msdc --help`` loads no heavy library (issue 8, item 7)."""

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
HEAVY = ("pandas", "numba", "scipy", "openpyxl", "matplotlib")

_SCRIPT = """
import atexit, runpy, sys
sys.argv = ["msdc", *{argv!r}]
# an exit handler: pipeline.cli's run() ends the process with os._exit once the handlers have run
atexit.register(lambda: print(",".join(m for m in {heavy!r} if m in sys.modules), file=sys.stderr))
try:
    runpy.run_module("pipeline.cli", run_name="__main__")
except SystemExit:
    pass
"""


def _loaded(*argv: str) -> tuple[str, list[str]]:
    """stdout of ``python -m pipeline.cli ARGV`` in a fresh interpreter, and the heavy modules it loaded."""
    done = subprocess.run([sys.executable, "-c", _SCRIPT.format(argv=list(argv), heavy=HEAVY)], cwd=ROOT,
                          capture_output=True, text=True, timeout=120)
    last = done.stderr.strip().splitlines()[-1] if done.stderr.strip() else ""
    return done.stdout, [m for m in last.split(",") if m]


def test_help_imports_no_heavy_library():
    out, loaded = _loaded("--help")
    assert "correlate" in out and "stats" in out  # the help was printed
    assert loaded == []


def test_subcommand_help_imports_no_heavy_library():
    out, loaded = _loaded("correlate", "--help")
    assert "--slot" in out
    assert loaded == []


def test_the_check_sees_a_heavy_import():
    """The same probe reports pandas once a command really uses it (so the tests above can fail)."""
    out, loaded = _loaded("stats", "fixtures/radar.ast")
    assert "Records per category" in out and "pandas" in loaded
