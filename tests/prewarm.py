"""Compile msdc's cached numba kernels once, before the test workers need them: the commands the suite runs
most (decode, track, evaluate, conflicts, correlate with quality) on the bundled fixtures, in one process.

    python tests/prewarm.py DONE_FILE

Started by tests/conftest.py beside the xdist workers' collection; each worker waits for DONE_FILE before
its first test, so a cold cache (a fresh checkout, CI) compiles each kernel once, not once per process."""

from __future__ import annotations

import contextlib
import io
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
FIX = ROOT / "fixtures"


def main(done: Path) -> None:
    """Run the commands (their outputs thrown away), then write DONE_FILE whatever happened."""
    try:
        from msdc.pipeline import cli

        inputs = [str(FIX / "radar.ast"), str(FIX / "adsb.ast")]
        sensors = ["--sensors", str(FIX / "sensors.toml")]
        with tempfile.TemporaryDirectory() as tmp:
            preset = ["--preset", "eurocontrol-1997-ssr"]
            runs = [["evaluate", *inputs, *sensors, *preset, "--json", f"{tmp}/e.json"],
                    ["conflicts", *inputs, *sensors, "--json", f"{tmp}/c.json"],
                    ["correlate", *inputs, *sensors, "--all", "--quality", "--json", f"{tmp}/q.json"]]
            for argv in runs:
                with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
                    with contextlib.suppress(SystemExit, Exception):
                        cli.main(argv)
    finally:
        done.write_text("done\n")


if __name__ == "__main__":
    main(Path(sys.argv[1]))
