"""Compile msdc's cached numba kernels once, before the test workers need them: the commands the suite runs
most (decode, track, evaluate, conflicts, correlate with quality) on the bundled fixtures, in one process.

    python tests/prewarm.py DONE_FILE

Started by tests/conftest.py beside the xdist workers' collection. The decoder's kernels first (``msdc
stats``, about 15 s on a cold cache, under the workers' 20 s of collection), then DONE_FILE, which each
worker waits for before its first test; then the tracker's and the others' (about 35 s more), while the
workers run their first tests: a test needing one of them before compiles it itself, as without this. Then
the file "all" beside DONE_FILE once the dataset jobs' kernels are (the Dask cluster's fixture waits for
it: its processes compile apart), then the conflicts' kernels."""

from __future__ import annotations

import contextlib
import io
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
FIX = ROOT / "fixtures"


def main(done: Path) -> None:
    """Decode (DONE_FILE written after it, whatever happened), then run the commands (outputs thrown away)."""
    from msdc.pipeline import cli

    inputs = [str(FIX / "radar.ast"), str(FIX / "adsb.ast")]
    try:
        _quietly(cli.main, ["stats", *inputs])
    finally:
        done.write_text("done\n")
    sensors = ["--sensors", str(FIX / "sensors.toml")]
    with tempfile.TemporaryDirectory() as tmp:
        preset = ["--preset", "eurocontrol-1997-ssr"]
        for argv in (["evaluate", *inputs, *sensors, *preset, "--json", f"{tmp}/e.json"],
                     ["correlate", *inputs, *sensors, "--all", "--quality", "--json", f"{tmp}/q.json"]):
            _quietly(cli.main, argv)
        done.with_name("all").write_text("done\n")  # what the dataset jobs run (track, quality, evaluate)
        _quietly(cli.main, ["conflicts", *inputs, *sensors, "--json", f"{tmp}/c.json"])


def _quietly(fn, argv: list[str]) -> None:
    """fn(argv), its output and any failure swallowed (the tests say what fails)."""
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        with contextlib.suppress(SystemExit, Exception):
            fn(argv)


if __name__ == "__main__":
    main(Path(sys.argv[1]))
