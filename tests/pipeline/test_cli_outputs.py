"""Every job writes through one output transaction: a run that fails while writing, or is interrupted
(Ctrl-C, SIGTERM, SIGHUP), leaves a previous run's outputs byte for byte and another program's file in
the folder untouched, with no staging folder left; outputs that are not regular files are refused at once."""

from __future__ import annotations

import errno
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from msdc.pipeline.report.transaction import STAGING_PREFIX

ROOT = Path(__file__).resolve().parents[2]
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
# failing while writing: a full disk met by a figure (decode: a CSV chunk), another program busy meanwhile

# the file each job is writing when the disk fills up (decode: the first category's, the output while it is
# the only one)
FULL_AT = {"decode": "o.csv", "correlate": "r_tracks.png", "quality": "q_intervals.png",
           "track": "figs/track_MAS72_750312.png", "conflicts": "figs/alert_001_"}


@pytest.mark.parametrize("job", list(JOBS))
def test_a_write_failing_leaves_the_previous_outputs_and_other_files_as_they_were(tmp_path, monkeypatch,
                                                                                  capsys, job):
    import matplotlib.figure
    import pandas as pd

    from msdc.pipeline.cli import main
    from msdc.pipeline.report import figure_pool

    before = _previous_run(job, tmp_path)
    meanwhile = tmp_path / "made_meanwhile.txt"
    # the per-alert figures are drawn here, not on the figure workers the patch would not reach
    monkeypatch.setattr(figure_pool, "cores", lambda: 1)

    def disk_full(*args, **kwargs):
        meanwhile.write_bytes(b"another program's file, made during the run\n")
        raise OSError(errno.ENOSPC, "No space left on device")  # as Pillow and pandas raise it: no file

    if job == "decode":
        monkeypatch.setattr(pd.DataFrame, "to_csv", disk_full)
    else:  # drawn in a forked child by correlate: the child has the patch too
        monkeypatch.setattr(matplotlib.figure.Figure, "savefig", disk_full)
    assert main(_argv(job, tmp_path)) == 1
    err = capsys.readouterr().err
    assert f"msdc {job}: {tmp_path / FULL_AT[job]}" in err and err.endswith(": No space left on device\n")
    assert err.count(f"msdc {job}: ") == 1 and "Traceback" not in err
    assert _listing(tmp_path) == {**before, meanwhile.name: meanwhile.read_bytes()} and _no_staging(tmp_path)


# ---------------------------------------------------------------------------------------------------------
# interrupted: a subprocess signalled while its staging folder exists


@pytest.mark.parametrize("job, sig", [("decode", signal.SIGINT), ("correlate", signal.SIGTERM),
                                      ("quality", signal.SIGHUP), ("track", signal.SIGINT),
                                      ("conflicts", signal.SIGTERM)])
def test_a_signal_while_writing_leaves_the_folder_as_it_was(tmp_path, job, sig):
    """The run signalled once its staging folder exists. On a loaded machine the writing can end between
    two looks (or before the signal lands): a run that ends written (status 0) has not been tested, so it is
    tried again in a fresh folder, five times at most; a run that ignores the signal fails every try."""
    for attempt in range(5):
        folder = tmp_path / f"try{attempt}"
        folder.mkdir()
        before = _previous_run(job, folder)
        run = subprocess.Popen([sys.executable, "-m", "msdc.pipeline.cli", *_argv(job, folder)], cwd=ROOT,
                               stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                               preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
        deadline = time.monotonic() + 120
        while _no_staging(folder) and run.poll() is None and time.monotonic() < deadline:
            time.sleep(0.002)
        run.send_signal(sig)
        _, err = run.communicate(timeout=60)
        if run.returncode != 0:
            break
    assert run.returncode == (130 if sig == signal.SIGINT else 128 + sig), err
    assert "Traceback" not in err
    assert _listing(folder) == before and _no_staging(folder)


# ---------------------------------------------------------------------------------------------------------
# the terminal lists every file written, every file replaced, and a file of an earlier run left beside them


def test_the_terminal_lists_the_files_written_and_replaced_and_an_earlier_runs_file_left(tmp_path, capsys):
    """One category to o.csv, then both (o_cat021.csv, o_cat048.csv, o.csv stale beside them), then both
    again (replacing them): stderr says each, stdout keeps its lines."""
    from msdc.pipeline.cli import main

    o, c21, c48 = tmp_path / "o.csv", tmp_path / "o_cat021.csv", tmp_path / "o_cat048.csv"
    left = "file(s) left as they were (named like this run's outputs, not written by it):\n"
    assert main(["decode", *INPUTS, "--category", "48", "-o", str(o)]) == 0
    out, err = capsys.readouterr()
    assert out == f"CAT048: 3266 records -> {o}\n"
    assert err.endswith(f"msdc decode: 1 file(s) written:\n  {o} (CAT048 records)\n")
    assert main(["decode", *INPUTS, "-o", str(o)]) == 0
    err = capsys.readouterr().err
    assert err.endswith(f"msdc decode: 2 file(s) written:\n  {c21} (CAT021 records)\n"
                        f"  {c48} (CAT048 records)\nmsdc decode: 1 earlier {left}  {o}\n")
    assert main(["decode", *INPUTS, "-o", str(o)]) == 0
    err = capsys.readouterr().err
    assert err.endswith(f"msdc decode: 2 file(s) written (2 replaced earlier files):\n"
                        f"  {c21} (CAT021 records, replaced)\n  {c48} (CAT048 records, replaced)\n"
                        f"msdc decode: 1 earlier {left}  {o}\n")
    assert main(["decode", *INPUTS, "--category", "21", "-o", str(o)]) == 0
    err = capsys.readouterr().err
    assert err.endswith(f"  {o} (CAT021 records, replaced)\nmsdc decode: 2 earlier {left}  {c21}\n  {c48}\n")


# per job but decode: side files an earlier run left that this run does not write (named like its outputs)
EARLIER = {"correlate": ["r_intervals.png", "r_radar_errors_9_9.png", "r_lags_7.png", "r_slots.parquet"],
           "quality": ["q_radar_errors_9_9.png"], "track": ["figs/track_OLD_9.png"],
           "conflicts": ["figs/alert_099_A_B_60s.png"]}


@pytest.mark.parametrize("job", list(EARLIER))
def test_every_command_lists_what_it_replaced_and_the_earlier_side_files_it_left(tmp_path, capsys, job):
    """A previous run's files (JOBS) and side files this run does not write: the ones it rewrites are
    listed as replaced, the others as left as they were, byte for byte; another program's file is not
    named."""
    from msdc.pipeline.cli import main

    before = _previous_run(job, tmp_path)
    for name in EARLIER[job]:
        (tmp_path / name).write_bytes(b"an earlier run's side file\n")
    assert main(_argv(job, tmp_path)) == 0
    err = capsys.readouterr().err
    written, _, rest = err.partition(f"msdc {job}: ")[2].partition(f"msdc {job}: ")
    listed = [line.strip() for line in rest.splitlines()[1:]]
    left = sorted({*EARLIER[job], *(n for n in JOBS[job][1] if n.startswith("figs/"))})
    assert rest.startswith(f"{len(left)} earlier file(s) left as they were"), err
    assert sorted(listed) == sorted(str(tmp_path / n) for n in left)
    for name in left:
        assert (tmp_path / name).read_bytes() == before.get(name, b"an earlier run's side file\n")
    replaced = [n for n in JOBS[job][1] if not n.startswith("figs/")]
    assert all(f"{tmp_path / n} (" in written and written.split(f"{tmp_path / n} (")[1].split(")")[0]
               .endswith(", replaced") for n in replaced), written
    assert "theirs.txt" not in err


# ---------------------------------------------------------------------------------------------------------
# outputs that are not regular files: refused before any decoding, naming the option and the file


@pytest.mark.parametrize("job, option, name", [
    ("decode", "-o", "o_cat048.csv"), ("correlate", "--json", "r.json"), ("quality", "--json", "q.json"),
    ("track", "--json", "t.json"), ("conflicts", "--json", "k.json")])
def test_a_fifo_as_an_output_is_refused_at_once(tmp_path, capsys, job, option, name):
    """A FIFO blocks its writer until someone reads it (after all the work): refused like an input, before
    anything is decoded. decode's o_cat048.csv is the file -o o.csv writes when both categories decode.
    Run in this process (the refusal is the command's, not the interpreter's); should the command write to
    the FIFO after all, a reader opened after 60 s drains it, so the run ends (status 0, not 2) instead of
    hanging."""
    import threading

    from msdc.pipeline.cli import main

    fifo = tmp_path / name
    os.mkfifo(fifo)

    def drain() -> None:
        with open(fifo, "rb") as reader:  # lets a writer blocked on the FIFO go on
            while reader.read(1 << 16):
                pass

    watchdog = threading.Timer(60, drain)
    watchdog.daemon = True  # never keeps the test process from ending
    watchdog.start()
    try:
        status = main(_argv(job, tmp_path))
    finally:
        watchdog.cancel()
    err = capsys.readouterr().err
    given = tmp_path / JOBS[job][0][JOBS[job][0].index(option) + 1].removeprefix("OUT/")
    assert status == 2 and "Traceback" not in err
    named = f"its CAT048 file {fifo}" if given != fifo else f"{option} {fifo}:"
    assert err.strip().endswith("is not a regular file (a FIFO, socket or device): give a file name")
    assert f"{option} {given}" in err and named in err
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


def _small_disk(folder: Path, size: str) -> bool:
    """Mount a tmpfs of ``size`` on ``folder`` (root, where mounting is allowed); False when it cannot."""
    try:
        done = subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={size}", "tmpfs", str(folder)],
                              capture_output=True, timeout=30)
    except (OSError, subprocess.SubprocessError):
        return False
    return done.returncode == 0


def test_a_full_disk_names_the_output_and_keeps_the_previous_one(tmp_path):
    """quality --json (70 kB) on a 32 kB tmpfs: one line naming q.json, exit 1, the previous q.json kept.
    Where no tmpfs can be mounted, a 32 kB file size limit (RLIMIT_FSIZE) fills the disk instead."""
    import resource

    disk = tmp_path / "disk"
    disk.mkdir()
    mounted = _small_disk(disk, "32k")
    try:
        (disk / "q.json").write_bytes(b"previous run's q.json\n")
        before = _listing(disk)

        def limited() -> None:
            signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # the write fails with EFBIG instead of a kill
            resource.setrlimit(resource.RLIMIT_FSIZE, (32_000, 32_000))

        done = subprocess.run([sys.executable, "-m", "msdc.pipeline.cli", "quality", *AIRCRAFT, "--callsign",
                               "MAS72", "--json", str(disk / "q.json")], cwd=ROOT, capture_output=True,
                              text=True, timeout=120, preexec_fn=None if mounted else limited)
        reason = "No space left on device" if mounted else "File too large"
        assert done.returncode == 1 and "Traceback" not in done.stderr
        assert done.stderr.splitlines()[-1] == f"msdc quality: {disk / 'q.json'}: {reason}"
        assert _listing(disk) == before and _no_staging(disk)
    finally:
        if mounted:
            subprocess.run(["umount", str(disk)], check=True, timeout=30)
