"""msdc.pipeline.report.outputs.Background: an output written in a forked child while the parent
writes another; the child's error is raised in the parent, a child that dies says so, cancel() stops it,
and without fork the work runs at once in the process. With msdc correlate: a figure failing in the child
ends the run with one line and leaves nothing written."""

from __future__ import annotations

import os
import signal
import time
from pathlib import Path

import pytest

from msdc.pipeline.cli import main
from msdc.pipeline.jobs import correlate
from msdc.pipeline.report import outputs
from msdc.pipeline.report.outputs import Background, BackgroundFailed
from msdc.pipeline.report.transaction import OutputTransaction

FIX = Path(__file__).resolve().parents[3] / "fixtures"
forking = pytest.mark.skipif(not (outputs.FORK_OK and hasattr(os, "fork")),
                             reason="Background forks only on Linux; elsewhere it runs in the process")


def _write(path: Path, text: str) -> None:
    path.write_text(text)


def _fail(path: Path) -> None:
    raise OSError(28, "No space left on device", str(path))


def _die() -> None:
    os.kill(os.getpid(), signal.SIGKILL)


def _sleep_then_write(path: Path) -> None:
    time.sleep(30)
    path.write_text("late")


def _unpicklable() -> None:
    class Local(Exception):  # a local class cannot be pickled
        pass

    raise Local("drawn badly")


@forking
def test_the_child_writes_and_wait_returns(tmp_path):
    job = Background(_write, tmp_path / "a.txt", "drawn elsewhere")
    job.wait()
    assert (tmp_path / "a.txt").read_text() == "drawn elsewhere"
    job.wait()  # a second wait has nothing left to wait for


@forking
def test_the_child_runs_in_another_process(tmp_path):
    job = Background(lambda p: p.write_text(str(os.getpid())), tmp_path / "pid.txt")
    job.wait()
    assert int((tmp_path / "pid.txt").read_text()) != os.getpid()


@forking
def test_the_childs_error_is_raised_in_the_parent(tmp_path):
    job = Background(_fail, tmp_path / "x.png")
    with pytest.raises(OSError) as err:
        job.wait()
    assert err.value.errno == 28 and err.value.filename == str(tmp_path / "x.png")


@forking
def test_an_error_that_does_not_pickle_comes_back_as_its_type_and_text():
    job = Background(_unpicklable)
    with pytest.raises(BackgroundFailed, match="Local: drawn badly"):
        job.wait()


@forking
def test_a_child_killed_without_a_word_is_reported():
    job = Background(_die)
    with pytest.raises(BackgroundFailed, match=f"signal {int(signal.SIGKILL)}"):
        job.wait()


@forking
def test_cancel_stops_the_child_before_it_writes(tmp_path):
    start = time.monotonic()
    job = Background(_sleep_then_write, tmp_path / "late.txt")
    job.cancel()
    assert time.monotonic() - start < 20  # killed, not waited for 30 s
    assert not (tmp_path / "late.txt").exists()
    job.wait()  # nothing left


def test_without_fork_the_work_runs_at_once(tmp_path, monkeypatch):
    monkeypatch.setattr(outputs, "FORK_OK", False)
    seen = []
    job = Background(lambda: seen.append(os.getpid()))
    assert seen == [os.getpid()]  # done before wait(), in this process
    job.wait()
    job.cancel()
    with pytest.raises(OSError):  # its error comes straight away
        Background(_fail, tmp_path / "x.png")


@forking
def test_a_cancelled_child_writing_into_a_transaction_leaves_nothing(tmp_path):
    with pytest.raises(RuntimeError), OutputTransaction() as tx:
        job = Background(_write, tx.path(tmp_path / "fig.png"), "partial")
        try:
            raise RuntimeError("the workbook failed")
        finally:
            job.cancel()
    assert list(tmp_path.iterdir()) == []


def _correlate(tmp_path: Path, capsys) -> tuple[int, str]:
    (tmp_path / "kept.txt").write_text("was here")
    code = main(["correlate", str(FIX / "radar.ast"), str(FIX / "adsb.ast"), "--sensors",
                 str(FIX / "sensors.toml"), "--callsign", "MAS72", "-o", str(tmp_path / "r.xlsx"),
                 "--json", str(tmp_path / "r.json")])
    return code, capsys.readouterr().err


@pytest.mark.parametrize("fork", [True, False])
def test_a_figure_failing_leaves_nothing(tmp_path, monkeypatch, capsys, fork):
    monkeypatch.setattr(outputs, "FORK_OK", fork and outputs.FORK_OK)
    monkeypatch.setattr(correlate, "_track_figure", lambda run, png, sensors: _fail(png))
    code, err = _correlate(tmp_path, capsys)
    assert code == 1 and "Traceback" not in err and "No space left on device" in err and "r_tracks.png" in err
    assert err.count("msdc correlate: ") == 1 and "Exception ignored" not in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["kept.txt"]


@forking
def test_a_figure_process_dying_leaves_nothing(tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(correlate, "_track_figure", lambda run, png, sensors: _die())
    code, err = _correlate(tmp_path, capsys)
    assert code == 1 and "Traceback" not in err
    assert "r_tracks.png: the figure was not drawn (killed by signal 9)" in err
    assert err.strip().splitlines()[-1].startswith("msdc correlate: ")  # the last line, and the only error
    assert err.count("msdc correlate: ") == 1
    assert sorted(p.name for p in tmp_path.iterdir()) == ["kept.txt"]


@forking
def test_cancel_after_an_interrupted_wait_closes_nothing_twice(tmp_path, monkeypatch):
    job = Background(_sleep_then_write, tmp_path / "late.txt")
    with monkeypatch.context() as m:
        m.setattr(os, "fdopen", lambda fd, *a, **k: _Interrupting(fd))
        with pytest.raises(KeyboardInterrupt):
            job.wait()
    spare = os.open(os.devnull, os.O_RDONLY)  # may reuse the pipe's number: cancel() must leave it open
    try:
        job.cancel()
        os.fstat(spare)  # still open
    finally:
        os.close(spare)
    assert not (tmp_path / "late.txt").exists()


@forking
def test_a_signal_landing_once_the_child_is_reaped_is_not_turned_into_an_error(tmp_path, monkeypatch):
    """SIGTERM's exception raised just after wait() reaped the child (the handler runs between two
    statements): cancel() then finds no child to reap, and the signal, not ECHILD ("No child processes",
    seen once in a signalled correlate run), is what the run ends with."""
    job = Background(_write, tmp_path / "done.txt", "x")
    child, reap = job._pid, os.waitpid

    def reaped_then_signalled(pid, options):
        reap(pid, options)
        raise KeyboardInterrupt  # as the signal's handler would, once waitpid has returned

    with monkeypatch.context() as m:
        m.setattr(os, "waitpid", reaped_then_signalled)
        with pytest.raises(KeyboardInterrupt):
            job.wait()
    job.cancel()  # the child is gone: nothing to reap, and no ChildProcessError
    assert (tmp_path / "done.txt").read_text() == "x"
    with pytest.raises(ChildProcessError):  # what cancel() met before: the child reaped already
        os.waitpid(child, 0)


class _Interrupting:
    """A pipe reader interrupted (Ctrl-C) while waiting; closes the descriptor as a real one would."""

    def __init__(self, fd: int):
        self.fd = fd

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        os.close(self.fd)

    def read(self):
        raise KeyboardInterrupt


# Prepared: the child forked early, warmed, then given its arguments

def _write_pid_and_warm(path: Path, warmed: Path) -> None:
    path.write_text(f"{os.getpid()} {warmed.exists()}")


@forking
def test_prepared_child_warms_first_then_runs_the_arguments_sent_later(tmp_path):
    warmed = tmp_path / "warm.txt"
    prepared = outputs.Prepared(_write_pid_and_warm, warm=lambda: warmed.write_text("ready"))
    big = "x" * 300_000  # more than a pipe holds: the arguments must not block the parent
    job = prepared.start(tmp_path / "out.txt", warmed)
    job.wait()
    pid, was_warm = (tmp_path / "out.txt").read_text().split()
    assert int(pid) != os.getpid() and was_warm == "True"
    job2 = outputs.Prepared(_write).start(tmp_path / "big.txt", big)
    job2.wait()
    assert (tmp_path / "big.txt").read_text() == big
    prepared.close()  # already used: nothing to do


def _frozen_objects() -> int:
    import gc

    return gc.get_freeze_count()


@forking
def test_prepared_childs_warmed_heap_is_left_out_of_garbage_collection():
    """The objects the child holds when its work arrives (imports, warm-up) are frozen, so no collection
    walks them; the parent's garbage collection is left as it was."""
    import gc

    before = gc.get_freeze_count()
    frozen = outputs.Prepared(_frozen_objects, warm=lambda: None).start().wait()
    assert frozen > 1000 and gc.get_freeze_count() == before


@forking
def test_prepared_childs_error_and_death_reach_the_parent(tmp_path):
    with pytest.raises(OSError) as err:
        outputs.Prepared(_fail).start(tmp_path / "x.png").wait()
    assert err.value.errno == 28 and err.value.filename == str(tmp_path / "x.png")
    with pytest.raises(BackgroundFailed, match=f"signal {int(signal.SIGKILL)}"):
        outputs.Prepared(_die).start().wait()
    assert list(tmp_path.iterdir()) == []


@forking
def test_prepared_child_closed_unused_is_stopped_and_writes_nothing(tmp_path):
    start = time.monotonic()
    prepared = outputs.Prepared(_write, warm=lambda: time.sleep(30))
    prepared.close()
    assert time.monotonic() - start < 20  # killed, not waited for
    prepared.close()
    assert list(tmp_path.iterdir()) == []


def test_prepared_without_fork_or_with_unpicklable_arguments_works_the_usual_way(tmp_path, monkeypatch):
    seen = []
    job = outputs.Prepared(lambda f: seen.append((os.getpid(), f()))).start(lambda: "local")  # no pickle
    job.wait()
    if outputs.FORK_OK:
        assert seen == []  # it ran in a forked child (a Background), not here
    monkeypatch.setattr(outputs, "FORK_OK", False)
    job = outputs.Prepared(lambda f: seen.append((os.getpid(), f()))).start(lambda: "here")
    assert seen[-1] == (os.getpid(), "here")  # at once, in this process
    job.wait()


@forking
def test_a_run_refused_after_the_figure_child_was_prepared_leaves_no_child(tmp_path, capsys):
    before = set(_children())  # a session fixture's processes (a Dask cluster's workers) are not the run's
    code = main(["correlate", str(FIX / "radar.ast"), str(FIX / "adsb.ast"), "--sensors",
                 str(FIX / "sensors.toml"), "--all", "--slot", "0.01", "-o", str(tmp_path / "r.xlsx")])
    assert code != 0 and "--slot" in capsys.readouterr().err
    assert set(_children()) - before == set()  # the prepared child was stopped and reaped
    assert list(tmp_path.iterdir()) == []


def _children() -> list[int]:
    """This process's child processes, alive or not yet reaped, but multiprocessing's forkserver and resource
    tracker (started once per process by the figure pool of an earlier test in this worker; they live as
    long as we do)."""
    me, found = os.getpid(), []
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
            cmdline = (stat.parent / "cmdline").read_bytes()
        except OSError:  # ended meanwhile
            continue
        if int(fields[1]) == me and b"multiprocessing.forkserver" not in cmdline \
                and b"multiprocessing.resource_tracker" not in cmdline:
            found.append(int(stat.parent.name))
    return found


def _answer(x: int) -> dict:
    return {"twice": 2 * x, "pid": os.getpid()}


@pytest.mark.parametrize("fork", [True, False])
def test_the_childs_result_comes_back(monkeypatch, fork):
    monkeypatch.setattr(outputs, "FORK_OK", fork and outputs.FORK_OK)
    for job in (Background(_answer, 21), outputs.Prepared(_answer).start(21)):
        got = job.wait()
        assert got["twice"] == 42 and (got["pid"] != os.getpid()) == (fork and outputs.FORK_OK)
        assert job.wait() == got  # asked again: the same answer


def _correlate_parquet(tmp_path: Path, capsys) -> tuple[int, str]:
    (tmp_path / "kept.txt").write_text("was here")
    code = main(["correlate", str(FIX / "radar.ast"), str(FIX / "adsb.ast"), "--sensors",
                 str(FIX / "sensors.toml"), "--all", "--tables", "parquet", "-o", str(tmp_path / "r.xlsx")])
    return code, capsys.readouterr().err


@pytest.mark.parametrize("failing", ["slots", "correlation"])
@pytest.mark.parametrize("fork", [True, False])
def test_a_parquet_table_failing_beside_the_workbook_leaves_nothing(tmp_path, monkeypatch, capsys, fork,
                                                                   failing):
    """The slot table is written with the figure (in the child where fork is used), the lag table here: a
    full disk for either ends the run with one line naming that table, and nothing is left."""
    from msdc.pipeline.report import excel

    real = excel.write_table_parquet
    monkeypatch.setattr(outputs, "FORK_OK", fork and outputs.FORK_OK)
    monkeypatch.setattr(excel, "write_table_parquet",
                        lambda run, name, path: _fail(path) if name == failing else real(run, name, path))
    code, err = _correlate_parquet(tmp_path, capsys)
    assert code == 1 and "Traceback" not in err and "No space left on device" in err
    assert f"r_{failing}.parquet" in err and err.count("msdc correlate: ") == 1
    assert sorted(p.name for p in tmp_path.iterdir()) == ["kept.txt"]


@forking
def test_the_table_and_figure_process_dying_names_its_files(tmp_path, monkeypatch, capsys):
    """The child (slot table and map) killed: one line naming the files it was writing; the lag table this
    process wrote meanwhile is removed with everything else."""
    from msdc.pipeline.report import excel

    parent, real = os.getpid(), excel.write_table_parquet
    monkeypatch.setattr(excel, "write_table_parquet",
                        lambda run, name, path: real(run, name, path) if os.getpid() == parent else _die())
    code, err = _correlate_parquet(tmp_path, capsys)
    assert code == 1 and "Traceback" not in err
    last = err.strip().splitlines()[-1]
    assert last.startswith("msdc correlate: ") and "killed by signal 9" in last
    assert all(name in last for name in ("r_slots.parquet", "r_tracks.png"))
    assert "the table and figure were not written" in last and "r_correlation.parquet" not in last
    assert sorted(p.name for p in tmp_path.iterdir()) == ["kept.txt"]


@forking
def test_the_figure_child_is_sent_the_slots_and_not_the_lags(tmp_path, monkeypatch, capsys):
    """The child draws the map from the slots alone: the lag tables (twice the slots' rows) stay here."""
    seen, real = tmp_path / "seen.txt", correlate._track_figure

    def recorded(run, png, sensors):
        seen.write_text(f"{os.getpid()} {sum(len(w.slots) for w in run.windows)} "
                        f"{sum(len(w.lags) for w in run.windows)}")
        real(run, png, sensors)

    monkeypatch.setattr(correlate, "_track_figure", recorded)
    out = tmp_path / "run"
    out.mkdir()
    assert main(["correlate", str(FIX / "radar.ast"), str(FIX / "adsb.ast"), "--sensors",
                 str(FIX / "sensors.toml"), "--all", "--json", str(out / "r.json"),
                 "-o", str(out / "r.xlsx")]) == 0
    capsys.readouterr()
    pid, slots, lags = map(int, seen.read_text().split())
    import json

    windows = json.loads((out / "r.json").read_text())["windows"]
    assert pid != os.getpid() and slots == sum(w["slots"] for w in windows) > 0 and lags == 0


def test_the_figure_child_warms_up_without_error():
    """The prepared child's warm-up is silent about its errors (the real work reports them), so it is run
    here where an error shows: it must get as far as drawing and encoding a PNG."""
    correlate._warm_track_figure()


@forking
@pytest.mark.parametrize("limit", [0, 1_000_000_000])
def test_long_tables_are_written_by_this_process_and_come_out_the_same(tmp_path, monkeypatch, capsys, limit):
    """Over CHILD_MAX_TABLE_ROWS the Parquet tables are written here, not in the figure's child (which then
    writes no table); under it the slot table in the child (which has the slots for the map), the lag
    table here. The files are the same either way."""
    import pandas as pd

    from msdc.pipeline.report import excel

    writers = tmp_path / "writers.txt"
    real = excel.write_table_parquet

    def recorded(run, name, path):
        with open(writers, "a") as f:
            f.write(f"{name} {os.getpid()}\n")
        return real(run, name, path)

    monkeypatch.setattr(correlate, "CHILD_MAX_TABLE_ROWS", limit)
    monkeypatch.setattr(excel, "write_table_parquet", recorded)
    out = tmp_path / "run"
    out.mkdir()
    code = main(["correlate", str(FIX / "radar.ast"), str(FIX / "adsb.ast"), "--sensors",
                 str(FIX / "sensors.toml"), "--all", "--tables", "parquet", "-o", str(out / "r.xlsx")])
    capsys.readouterr()
    assert code == 0
    pids = {line.split()[0]: int(line.split()[1]) for line in writers.read_text().splitlines()}
    assert set(pids) == {"slots", "correlation"}
    assert pids["correlation"] == os.getpid()
    assert (pids["slots"] == os.getpid()) == (limit == 0)
    got = {name: pd.read_parquet(out / f"r_{name}.parquet") for name in pids}
    if limit == 0:  # compared with the child's files of a second run under the default limit
        monkeypatch.setattr(correlate, "CHILD_MAX_TABLE_ROWS", 1_000_000_000)
        other = tmp_path / "other"
        other.mkdir()
        assert main(["correlate", str(FIX / "radar.ast"), str(FIX / "adsb.ast"), "--sensors",
                     str(FIX / "sensors.toml"), "--all", "--tables", "parquet", "-o",
                     str(other / "r.xlsx")]) == 0
        for name, frame in got.items():
            pd.testing.assert_frame_equal(frame, pd.read_parquet(other / f"r_{name}.parquet"))
