"""Every job writes through one output transaction: a run that fails while writing, or is interrupted
(Ctrl-C, SIGTERM, SIGHUP), leaves a previous run's outputs byte for byte and another program's file in
the folder untouched, with no staging folder left; outputs that are not regular files are refused at once."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from msdc.pipeline.report.transaction import STAGING_PREFIX

ROOT = Path(__file__).resolve().parents[1]
FIX = ROOT / "fixtures"
INPUTS = [str(FIX / "radar.ast"), str(FIX / "adsb.ast"), "--date", "2019-03-01"]
AIRCRAFT = [*INPUTS, "--sensors", str(FIX / "sensors.toml")]
# conflicts with alert events on the fixtures (figures drawn)
ALERTS = ["--step", "5", "--radius-nm", "40", "--vertical-ft", "30000", "--horizon", "60"]

# per job: its command line (OUT: the folder) and the files a previous run left there
JOBS = {
    "decode": (["decode", *INPUTS, "--chunk-mb", "0.1", "-o", "OUT/o.csv"],
               ["o_cat021.csv", "o_cat048.csv"]),
    "correlate": (["correlate", *AIRCRAFT, "--callsign", "MAS72", "-o", "OUT/r.xlsx", "--json", "OUT/r.json"],
                  ["r.xlsx", "r.json", "r_tracks.png"]),
    "quality": (["quality", *AIRCRAFT, "--callsign", "MAS72", "-o", "OUT/q.xlsx", "--json", "OUT/q.json"],
                ["q.xlsx", "q.json", "q_intervals.png"]),
    "track": (["track", *AIRCRAFT, "--callsign", "MAS72", "-o", "OUT/t.csv", "--json", "OUT/t.json",
               "--figures", "OUT/figs"], ["t.csv", "t.json", "figs/track_MAS72_1.png"]),
    "conflicts": (["conflicts", *AIRCRAFT, *ALERTS, "-o", "OUT/k.csv", "--json", "OUT/k.json",
                   "--figures", "OUT/figs"], ["k.csv", "k_losses.csv", "k.json", "figs/alert_1.png"]),
}


def _argv(job: str, folder: Path) -> list[str]:
    return [a.replace("OUT", str(folder)) for a in JOBS[job][0]]


def _previous_run(job: str, folder: Path) -> dict[str, bytes]:
    """The folder as a previous run and another program left it: what every test expects to find again."""
    for name in JOBS[job][1]:
        path = folder / name
        path.parent.mkdir(exist_ok=True)
        path.write_bytes(f"previous run's {name}\n".encode())
    (folder / "theirs.txt").write_bytes(b"another program's file\n")
    return _listing(folder)


def _listing(folder: Path) -> dict[str, bytes]:
    """Every file under ``folder`` (staging folders included) and its bytes."""
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


def _no_staging(folder: Path) -> bool:
    return not any(p.name.startswith(STAGING_PREFIX) for p in folder.rglob("*"))


# ---------------------------------------------------------------------------------------------------------
# interrupted: a subprocess signalled while its staging folder exists


@pytest.mark.parametrize("job, sig", [("decode", signal.SIGINT), ("correlate", signal.SIGTERM),
                                      ("quality", signal.SIGHUP), ("track", signal.SIGINT),
                                      ("conflicts", signal.SIGTERM)])
def test_a_signal_while_writing_leaves_the_folder_as_it_was(tmp_path, job, sig):
    before = _previous_run(job, tmp_path)
    run = subprocess.Popen([sys.executable, "-m", "msdc.pipeline.cli", *_argv(job, tmp_path)], cwd=ROOT,
                           stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                           preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    deadline = time.monotonic() + 120
    while _no_staging(tmp_path) and run.poll() is None and time.monotonic() < deadline:
        time.sleep(0.002)
    run.send_signal(sig)
    _, err = run.communicate(timeout=60)
    assert run.returncode == (130 if sig == signal.SIGINT else 128 + sig), err
    assert "Traceback" not in err
    assert _listing(tmp_path) == before and _no_staging(tmp_path)


# ---------------------------------------------------------------------------------------------------------
# outputs that are not regular files: refused before any decoding, naming the option and the file


@pytest.mark.parametrize("job, option, name", [
    ("decode", "-o", "o_cat048.csv"), ("correlate", "--json", "r.json"), ("quality", "--json", "q.json"),
    ("track", "--json", "t.json"), ("conflicts", "--json", "k.json")])
def test_a_fifo_as_an_output_is_refused_at_once(tmp_path, job, option, name):
    """A FIFO blocks its writer until someone reads it (after all the work): refused like an input, before
    anything is decoded. decode's o_cat048.csv is the file -o o.csv writes when both categories decode."""
    fifo = tmp_path / name
    os.mkfifo(fifo)
    done = subprocess.run([sys.executable, "-m", "msdc.pipeline.cli", *_argv(job, tmp_path)], cwd=ROOT,
                          capture_output=True, text=True, timeout=60)
    given = tmp_path / JOBS[job][0][JOBS[job][0].index(option) + 1].removeprefix("OUT/")
    assert done.returncode == 2 and "Traceback" not in done.stderr
    named = f"its CAT048 file {fifo}" if given != fifo else f"{option} {fifo}:"
    assert done.stderr.strip().endswith("is not a regular file (a FIFO, socket or device): give a file name")
    assert f"{option} {given}" in done.stderr and named in done.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == [name]


def test_a_symlinked_output_is_written_through_and_its_side_files_go_beside_the_file_it_points_to(tmp_path):
    """-o link.csv pointing to real/data.csv: the link stays, data.csv is replaced; with both categories
    the per-category files are named after data.csv and written beside it."""
    from msdc.pipeline.cli import main

    real = tmp_path / "real" / "data.csv"
    real.parent.mkdir()
    real.write_text("previous run\n")
    link = tmp_path / "link.csv"
    link.symlink_to(real)
    assert main(["decode", *INPUTS, "--category", "48", "-o", str(link)]) == 0
    assert link.is_symlink() and real.read_text().startswith("sac,sic,")
    assert main(["decode", *INPUTS, "-o", str(link)]) == 0
    assert sorted(p.name for p in real.parent.iterdir()) == ["data.csv", "data_cat021.csv", "data_cat048.csv"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["link.csv", "real"] and link.is_symlink()
