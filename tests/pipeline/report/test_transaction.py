"""The output transaction: a run's files appear together or not at all, and nothing else in the folder
is touched; interrupts (Ctrl-C, SIGTERM, SIGHUP) clean up the same way."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from msdc.pipeline.report import transaction as tx_module
from msdc.pipeline.report.transaction import STAGING_PREFIX, OutputTransaction, Terminated, output_problem


def _listing(folder: Path) -> dict[str, bytes]:
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


def test_commit_puts_every_file_in_place_and_says_which_it_replaced(tmp_path):
    (tmp_path / "o.csv").write_text("old")
    with OutputTransaction() as tx:
        tx.path(tmp_path / "o.csv").write_text("new")
        side = tx.path(tmp_path / "o.csv").with_name("o_cat048.csv")  # a writer's side file, named after o
        side.write_text("side")
        figures = tx.folder(tmp_path / "figs")
        (figures / "a.png").write_bytes(b"png")
        assert not (tmp_path / "figs").exists() and (tmp_path / "o.csv").read_text() == "old"
        written = tx.commit()
    assert _listing(tmp_path) == {"o.csv": b"new", "o_cat048.csv": b"side", "figs/a.png": b"png"}
    assert {(w.path.name, w.replaced) for w in written} == {("o.csv", True), ("o_cat048.csv", False),
                                                            ("a.png", False)}


def test_a_failed_run_leaves_the_folder_as_it_was_and_spares_other_programs_files(tmp_path):
    (tmp_path / "o.csv").write_text("old")
    with pytest.raises(RuntimeError), OutputTransaction() as tx:
        tx.path(tmp_path / "o.csv").write_text("new")
        tx.path(tmp_path / "o.json").write_text("{}")
        (tmp_path / "theirs.txt").write_bytes(b"another program's file, made during the run")
        raise RuntimeError("the run failed")
    theirs = b"another program's file, made during the run"
    assert _listing(tmp_path) == {"o.csv": b"old", "theirs.txt": theirs}
    assert not any(p.name.startswith(STAGING_PREFIX) for p in tmp_path.iterdir())


def test_leaving_without_commit_writes_nothing(tmp_path):
    with OutputTransaction() as tx:
        tx.path(tmp_path / "o.csv").write_text("new")
    assert list(tmp_path.iterdir()) == []


def test_a_symlinked_output_keeps_its_link_and_replaces_the_file_it_points_to(tmp_path):
    real = tmp_path / "real" / "report.json"
    real.parent.mkdir()
    real.write_text("old")
    link = tmp_path / "report.json"
    link.symlink_to(real)
    with OutputTransaction() as tx:
        tx.path(link).write_text("new")
        tx.commit()
    assert link.is_symlink() and real.read_text() == "new"


def test_outputs_that_are_not_regular_files_are_refused(tmp_path):
    fifo = tmp_path / "pipe.json"
    os.mkfifo(fifo)
    assert "FIFO" in output_problem(fifo)
    assert output_problem("/dev/null") and "FIFO" in output_problem("/dev/null")
    assert output_problem(tmp_path) == "is a directory"
    assert output_problem(tmp_path / "new.json") is None
    (tmp_path / "old.json").write_text("{}")
    assert output_problem(tmp_path / "old.json") is None


def test_a_commit_that_fails_half_way_puts_back_what_it_moved(tmp_path, monkeypatch):
    (tmp_path / "a.csv").write_text("old a")
    (tmp_path / "b.csv").write_text("old b")
    real_replace, calls = os.replace, []

    def failing_replace(src, dst):
        calls.append(dst)
        if len(calls) == 4:  # a's backup, a's move, b's backup, then b's move fails
            raise OSError(28, "No space left on device", str(src))
        real_replace(src, dst)

    monkeypatch.setattr(tx_module.os, "replace", failing_replace)
    with pytest.raises(OSError) as raised, OutputTransaction() as tx:
        tx.path(tmp_path / "a.csv").write_text("new a")
        tx.path(tmp_path / "b.csv").write_text("new b")
        tx.commit()
    monkeypatch.undo()
    assert raised.value.filename == str(tmp_path / "b.csv")  # the output, not the staged name
    assert _listing(tmp_path) == {"a.csv": b"old a", "b.csv": b"old b"}


def test_a_folder_made_meanwhile_where_an_output_goes_is_left_alone(tmp_path):
    """Another program makes a folder at b.csv's place during the run: the commit fails naming b.csv, a.csv
    is put back as it was and the folder keeps its content."""
    (tmp_path / "a.csv").write_text("old a")
    with pytest.raises(IsADirectoryError) as raised, OutputTransaction() as tx:
        tx.path(tmp_path / "a.csv").write_text("new a")
        tx.path(tmp_path / "b.csv").write_text("new b")
        (tmp_path / "b.csv").mkdir()
        (tmp_path / "b.csv" / "theirs.txt").write_text("theirs")
        tx.commit()
    assert raised.value.filename == str(tmp_path / "b.csv")
    assert _listing(tmp_path) == {"a.csv": b"old a", "b.csv/theirs.txt": b"theirs"}


def test_an_interrupt_already_due_while_cleaning_up_still_removes_every_staging_folder(tmp_path, monkeypatch):
    """A second Ctrl-C that was on its way when the clean-up began raises in the middle of it (its handler
    runs at any step): every staging folder goes all the same, then the interrupt is raised."""
    real_rmtree, calls = tx_module.shutil.rmtree, []

    def interrupted_once(path, **kw):
        calls.append(path)
        if len(calls) == 1:
            raise KeyboardInterrupt
        real_rmtree(path, **kw)

    monkeypatch.setattr(tx_module.shutil, "rmtree", interrupted_once)
    with pytest.raises(KeyboardInterrupt), OutputTransaction() as tx:
        tx.path(tmp_path / "o.csv").write_text("new")
        (tx.folder(tmp_path / "figs") / "a.png").write_text("png")
        raise RuntimeError("the run failed")
    assert list(tmp_path.iterdir()) == []


def test_a_write_error_names_the_output_not_the_staged_file(tmp_path):
    with pytest.raises(OSError) as raised, OutputTransaction() as tx:
        staged = tx.path(tmp_path / "o.json")
        raise OSError(28, "No space left on device", str(staged))
    assert raised.value.filename == str(tmp_path / "o.json")


CHILD = textwrap.dedent("""
    import os, signal, sys, time
    from pathlib import Path
    from msdc.pipeline.report.transaction import OutputTransaction, Terminated, raise_on_termination
    raise_on_termination()
    folder, how = Path(sys.argv[1]), sys.argv[2]
    try:
        with OutputTransaction() as tx:
            tx.path(folder / "o.csv").write_text("new")
            (tx.folder(folder / "figs") / "a.png").write_text("png")
            os.kill(os.getpid(), {"term": signal.SIGTERM, "hup": signal.SIGHUP, "int": signal.SIGINT}[how])
            time.sleep(5)
            tx.commit()
    except Terminated as exc:
        sys.exit(128 + exc.signum)
    except KeyboardInterrupt:
        sys.exit(130)
""")


def _as_from_a_shell() -> None:
    """The child starts with the signal state a shell gives it: a test runner's worker may leave SIGINT
    ignored or blocked, and a child inherits both (Python then installs no KeyboardInterrupt handler)."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)
    signal.pthread_sigmask(signal.SIG_UNBLOCK, [signal.SIGINT, signal.SIGTERM, signal.SIGHUP])


@pytest.mark.parametrize("how, status", [("term", 128 + signal.SIGTERM), ("hup", 128 + signal.SIGHUP),
                                         ("int", 130)])
def test_signals_clean_up_like_an_error(tmp_path, how, status):
    (tmp_path / "o.csv").write_text("old")
    done = subprocess.run([sys.executable, "-c", CHILD, str(tmp_path), how], capture_output=True, text=True,
                          timeout=60, preexec_fn=_as_from_a_shell)
    assert done.returncode == status, done.stderr
    assert _listing(tmp_path) == {"o.csv": b"old"}


def test_interrupts_are_held_back_while_the_set_is_moved(tmp_path):
    seen = []

    def spy(src, dst):
        seen.append(signal.SIGTERM in signal.pthread_sigmask(signal.SIG_BLOCK, []))
        os.rename(src, dst)

    tx = OutputTransaction()
    tx.path(tmp_path / "o.csv").write_text("x")
    original = tx_module.os.replace
    tx_module.os.replace = spy
    try:
        tx.commit()
    finally:
        tx_module.os.replace = original
    assert seen == [True] and signal.SIGTERM not in signal.pthread_sigmask(signal.SIG_BLOCK, [])


def test_terminated_carries_its_signal():
    assert Terminated(signal.SIGTERM).signum == signal.SIGTERM


def test_left_beside_lists_the_matching_files_the_run_did_not_write(tmp_path, monkeypatch):
    """An earlier run left r_lags_1.png and r_lags_2.png; this one writes r_lags_1.png only: r_lags_2.png is
    named, spelled as the pattern spells it; r_notes.txt matches no pattern. A '[' in the output's own name
    is no glob: 'w[1]_lags_*.png' matches w[1]_lags_5.png, not w1_lags_5.png."""
    from msdc.pipeline.report.transaction import left_beside, side_pattern

    monkeypatch.chdir(tmp_path)
    for name in ("r_lags_1.png", "r_lags_2.png", "r_notes.txt", "w[1]_lags_5.png", "w1_lags_5.png"):
        (tmp_path / name).write_bytes(b"earlier")
    with OutputTransaction() as tx:
        tx.path(Path("r_lags_1.png")).write_bytes(b"now")
        written = tx.commit()
    patterns = [side_pattern(Path("r.xlsx"), "_lags_*.png"), side_pattern(Path("w[1].xlsx"), "_lags_*.png")]
    assert patterns[1] == Path("w[[]1]_lags_*.png")
    assert left_beside(patterns, written) == [Path("r_lags_2.png"), Path("w[1]_lags_5.png")]
    assert left_beside([tmp_path / "r_lags_*.png"], written) == [tmp_path / "r_lags_2.png"]  # absolute too
    assert left_beside([Path("figs") / "track_*.png"], written) == []  # a folder not there: nothing
