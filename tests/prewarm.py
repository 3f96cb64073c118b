"""Compile msdc's cached numba kernels once, before the test workers need them: the commands the suite runs
most (decode, track, evaluate, conflicts, correlate with quality) on the bundled fixtures, in one process.

    python tests/prewarm.py DONE_FILE

Started by tests/conftest.py beside the xdist workers' collection. The decoder's kernels for intact
recordings first (``msdc stats``, about 9 s on a cold cache), then DONE_FILE, which each worker waits for
before its first test; then the careful framing's (``msdc stats`` of a fixture with random bytes inside,
about 11 s), the tracker's and the others' (about 20 s more), while the workers run their first tests: a
test needing one of them before compiles it itself, as without this. Then the file "all" beside DONE_FILE
once the dataset jobs' kernels are (the Dask cluster's fixture waits for it: its processes compile apart),
then the conflicts' kernels and the IMM smoother's. tests/test_prewarm.py checks the commands parse (a
failing one is swallowed here)."""

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
    """The commands run after the decode, outputs in the folder ``tmp``: the decode of a damaged recording
    (main writes it there), evaluate and correlate with quality (what the dataset jobs run: track, quality,
    evaluate), then conflicts and the IMM smoother's track."""
    inputs = [str(FIX / "radar.ast"), str(FIX / "adsb.ast")]
    sensors = ["--sensors", str(FIX / "sensors.toml")]
    return [["stats", f"{tmp}/{DAMAGED}"],
            ["evaluate", *inputs, *sensors, "--preset", "eurocontrol-1997-ssr", "--json", f"{tmp}/e.json"],
            ["correlate", *inputs, *sensors, "--all", "--quality", "--json", f"{tmp}/q.json"],
            ["conflicts", *inputs, *sensors, "-o", f"{tmp}/c.xlsx"],
            ["track", *inputs, *sensors, "--address", "750312", "--smoother", "imm", "-o", f"{tmp}/t.csv"]]


def main(done: Path) -> None:
    """Decode (DONE_FILE written after it, whatever happened), then run the commands (outputs thrown away),
    the file "all" written after the first three."""
    from msdc.pipeline import cli

    try:
        _quietly(cli.main, ["stats", str(FIX / "radar.ast"), str(FIX / "adsb.ast")])
    finally:
        done.write_text("done\n")
    with tempfile.TemporaryDirectory() as tmp:
        radar = (FIX / "radar.ast").read_bytes()  # random bytes inside: framed carefully
        Path(tmp, DAMAGED).write_bytes(radar[:5_000] + bytes(range(7, 250)) + radar[5_000:])
        later = commands(tmp)
        for argv in later[:3]:
            _quietly(cli.main, argv)
        done.with_name("all").write_text("done\n")
        for argv in later[3:]:
            _quietly(cli.main, argv)


def _quietly(fn, argv: list[str]) -> None:
    """fn(argv), its output and any failure swallowed (the tests say what fails)."""
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        with contextlib.suppress(SystemExit, Exception):
            fn(argv)


if __name__ == "__main__":
    main(Path(sys.argv[1]))
