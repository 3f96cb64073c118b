"""Compile msdc's cached numba kernels once, before the test workers need them: the commands the suite runs
most (decode, track, evaluate, conflicts, correlate with quality) on the bundled fixtures, in one process.

    python tests/prewarm.py DONE_FILE

Started by tests/conftest.py beside the xdist workers' collection. The decoder's kernels first (``msdc
stats`` of the fixtures, then of a fixture with random bytes inside, framed carefully: about 20 s on a
cold cache), then DONE_FILE, which each worker waits for before its first test (started before the
careful framing's kernels, the workers compiled them beside this, each in its damaged-recording tests:
the suite took 25 s longer); then the tracker's and the others' (about 20 s more), while the workers run
their first tests: a test needing one of them before compiles it itself, as without this. Then the file
"all" beside DONE_FILE once the dataset jobs' kernels are (the Dask cluster's fixture waits for it: its
processes compile apart), then the conflicts' kernels and the IMM smoother's. tests/test_prewarm.py
checks the commands parse (a failing one is swallowed here)."""

from __future__ import annotations

import contextlib
import io
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
FIX = ROOT / "fixtures"
DAMAGED = "damaged.ast"  # the radar fixture with bytes inside, written by main


def commands(tmp: str) -> list[list[str]]:
    """The commands, outputs in the folder ``tmp``: the decodes of the fixtures and of a damaged recording
    (main writes it there), evaluate and correlate with quality (what the dataset jobs run: track, quality,
    evaluate), then conflicts and the IMM smoother's track."""
    inputs = [str(FIX / "radar.ast"), str(FIX / "adsb.ast")]
    sensors = ["--sensors", str(FIX / "sensors.toml")]
    return [["stats", *inputs],
            ["stats", f"{tmp}/{DAMAGED}"],
            ["evaluate", *inputs, *sensors, "--preset", "eurocontrol-1997-ssr", "--json", f"{tmp}/e.json"],
            ["correlate", *inputs, *sensors, "--all", "--quality", "--json", f"{tmp}/q.json"],
            ["conflicts", *inputs, *sensors, "-o", f"{tmp}/c.xlsx"],
            ["track", *inputs, *sensors, "--address", "750312", "--smoother", "imm", "-o", f"{tmp}/t.csv"]]


def main(done: Path) -> None:
    """Run the commands (outputs thrown away): DONE_FILE written after the two decodes (whatever happened),
    the file "all" after evaluate and correlate."""
    from msdc.pipeline import cli

    with tempfile.TemporaryDirectory() as tmp:
        todo = commands(tmp)
        try:
            radar = (FIX / "radar.ast").read_bytes()  # random bytes inside: framed carefully
            Path(tmp, DAMAGED).write_bytes(radar[:5_000] + bytes(range(7, 250)) + radar[5_000:])
            for argv in todo[:2]:
                _quietly(cli.main, argv)
        finally:
            done.write_text("done\n")
        for argv in todo[2:4]:
            _quietly(cli.main, argv)
        done.with_name("all").write_text("done\n")
        for argv in todo[4:]:
            _quietly(cli.main, argv)


def _quietly(fn, argv: list[str]) -> None:
    """fn(argv), its output and any failure swallowed (the tests say what fails)."""
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        with contextlib.suppress(SystemExit, Exception):
            fn(argv)


if __name__ == "__main__":
    main(Path(sys.argv[1]))
