"""Compile msdc's cached numba kernels once, before the test workers need them: the commands the suite runs
most (decode, track, evaluate, conflicts, correlate with quality) on the bundled fixtures, in one process
(and one beside it for the careful framing).

    python tests/prewarm.py DONE_FILE
    python tests/prewarm.py --careful RECORDING    (what the first starts beside it)

Started by tests/conftest.py beside the xdist workers' collection. The decoder's kernels first: ``msdc
stats`` of the fixtures, with the careful framing's kernels compiled beside it in a second process
(careful_framing, on a fixture with random bytes inside), then ``msdc stats`` of that fixture; about 13 s
on a cold cache, 20 s one after the other. Then DONE_FILE, which each worker waits for before its first
test (started before the careful framing's kernels, the workers compiled them too, each in its
damaged-recording tests: the suite took 25 s longer); then the tracker's and the others' (about 20 s
more), while the workers run their first tests: a test needing one of them before compiles it itself, as
without this. Then the file "all" beside DONE_FILE once the dataset jobs' kernels are (the Dask cluster's
fixture waits for it: its processes compile apart), then the conflicts' kernels and the IMM smoother's.
tests/test_prewarm.py checks the commands parse (a failing one is swallowed here)."""

from __future__ import annotations

import contextlib
import io
import subprocess
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
    the careful framing's kernels compiled beside the first (careful_framing, in a process of its own: the
    workers wait for both on otherwise idle cores), the file "all" after evaluate and correlate."""
    from msdc.pipeline import cli

    with tempfile.TemporaryDirectory() as tmp:
        todo = commands(tmp)
        try:
            radar = (FIX / "radar.ast").read_bytes()  # random bytes inside: framed carefully
            Path(tmp, DAMAGED).write_bytes(radar[:5_000] + bytes(range(7, 250)) + radar[5_000:])
            beside = subprocess.Popen([sys.executable, __file__, "--careful", str(Path(tmp, DAMAGED))],
                                      stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
            _quietly(cli.main, todo[0])
            beside.wait()
            _quietly(cli.main, todo[1])  # what else a damaged recording's decode compiles
        finally:
            done.write_text("done\n")
        for argv in todo[2:4]:
            _quietly(cli.main, argv)
        done.with_name("all").write_text("done\n")
        for argv in todo[4:]:
            _quietly(cli.main, argv)


def careful_framing(path: Path) -> None:
    """Frame the recording at ``path`` carefully, window by window, as a decode does (kernel.frame_window
    and the resynchronisation search compiled with a decode's argument types: a later decode loads them),
    then walk captures of its first block (capture_walkers)."""
    import numpy as np

    from msdc.asterix import kernel
    from msdc.asterix.containers import read_segments
    from msdc.asterix.framing import Framer
    from msdc.asterix.reader import tables_for

    buf = np.frombuffer(path.read_bytes(), np.uint8)
    seg = read_segments(buf, "raw")
    framer = Framer(buf, seg, np.full(len(seg.start), kernel.MODE_CAREFUL, np.int8), tables_for({48: None}))
    while not framer.done:
        framer.window()
    capture_walkers(bytes(buf[:int.from_bytes(buf[1:3].tobytes(), "big")]))


def capture_walkers(block: bytes) -> None:
    """Walk a pcap and a pcapng capture of ``block``: their walkers and resynchronisation (about 3 s of
    compiling on a cold cache, else paid by the first container test of each worker)."""
    import numpy as np
    from container_bytes import pcap_file, png_epb, png_idb, png_shb, udp_frame

    from msdc.asterix.containers import read_segments

    pcap, _ = pcap_file([(1_551_427_200 + i, 0, udp_frame(block)) for i in range(3)])
    read_segments(np.frombuffer(pcap, np.uint8), "pcap")
    pcapng = png_shb("<") + png_idb("<", 1) + b"".join(png_epb("<", 0, 10**6 * i, udp_frame(block))
                                                       for i in range(3))
    read_segments(np.frombuffer(pcapng, np.uint8), "pcapng")


def _quietly(fn, argv: list[str]) -> None:
    """fn(argv), its output and any failure swallowed (the tests say what fails)."""
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        with contextlib.suppress(SystemExit, Exception):
            fn(argv)


if __name__ == "__main__":
    if sys.argv[1] == "--careful":
        careful_framing(Path(sys.argv[2]))
    else:
        main(Path(sys.argv[1]))
