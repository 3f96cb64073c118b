"""The Dask engine (pipeline.dataset.cluster): results in the items' order whatever order the tasks end in,
a failed task retried, one that fails every try named with its cause, the job's --scheduler and --workers
checked, an unreachable scheduler said; and the progress bar's time left."""

from __future__ import annotations

import io
import os
import socket
import time
import warnings
from pathlib import Path

import pytest

from msdc.pipeline.dataset import cluster
from msdc.pipeline.dataset.cluster import DaskDistributor, TaskFailed
from msdc.pipeline.jobs.common import JobError, OptionError, check_scheduler, distributed
from msdc.pipeline.jobs.options import TrackOptions
from msdc.pipeline.parallel import map_ordered
from msdc.pipeline.progress import Progress, eta_text

pytestmark = pytest.mark.xdist_group("dask")  # one Dask cluster for these tests


def _slow_square(x: int) -> int:
    time.sleep(0.02 * (5 - x % 5))  # the early items end last
    return x * x


def _flaky(item: tuple[str, int]) -> int:
    """Fails on its first try (a file beside the test counts the tries: workers are other processes)."""
    folder, x = item
    tries = Path(folder) / f"tries-{x}"
    tries.write_text(tries.read_text() + "x" if tries.exists() else "x")
    if len(tries.read_text()) == 1:
        raise OSError("first try fails")
    return x


def _always_fails(item: tuple[str, int]) -> int:
    folder, x = item
    tries = Path(folder) / f"tries-{x}"
    tries.write_text(tries.read_text() + "x" if tries.exists() else "x")
    raise ValueError(f"bad aircraft {x}")


def test_results_come_in_the_items_order(dask_scheduler):
    engine = DaskDistributor(dask_scheduler)
    try:
        assert list(engine.map_ordered(_slow_square, range(20))) == [x * x for x in range(20)]
        assert engine.tasks == 20 and engine.failed == []
        assert "20 task(s) on the Dask scheduler at" in engine.summary()
    finally:
        engine.close()


def test_a_failed_task_is_retried(dask_scheduler, tmp_path):
    engine = DaskDistributor(dask_scheduler)
    try:
        assert list(engine.map_ordered(_flaky, [(str(tmp_path), x) for x in range(3)])) == [0, 1, 2]
    finally:
        engine.close()
    assert [len((tmp_path / f"tries-{x}").read_text()) for x in range(3)] == [2, 2, 2]


def test_a_task_failing_every_try_is_named(dask_scheduler, tmp_path):
    engine = DaskDistributor(dask_scheduler)
    items = [(str(tmp_path), x) for x in range(3)]
    try:
        with pytest.raises(TaskFailed) as exc:
            list(engine.map_ordered(_always_fails, items, label=lambda item: f"aircraft A{item[1]}"))
    finally:
        engine.close()
    text = str(exc.value)
    assert text.startswith("aircraft A0: failed on 3 tries") and "ValueError: bad aircraft 0" in text
    assert len((tmp_path / "tries-0").read_text()) == 3  # the first try and RETRIES = 2 more
    assert engine.failed == ["aircraft A0"]


def test_the_job_context_installs_the_cluster_and_reports_a_failure(dask_scheduler, tmp_path):
    options = TrackOptions(dataset=str(tmp_path), scheduler=dask_scheduler)
    items = [(str(tmp_path), x) for x in range(2)]
    with distributed(options) as engine:  # distributable work goes to the cluster, the rest stays here
        assert list(map_ordered(_slow_square, range(4), distributable=True)) == [0, 1, 4, 9]
        assert list(map_ordered(_slow_square, range(3))) == [0, 1, 4]
        assert engine.tasks == 4
    with pytest.raises(JobError) as exc, distributed(options):
        list(map_ordered(_always_fails, items, distributable=True, label=lambda item: f"partition {item[1]}"))
    assert "partition 0: failed on 3 tries" in str(exc.value)
    with distributed(TrackOptions(scheduler="none")) as engine:  # threads, as without --dataset
        assert engine is None and list(map_ordered(_slow_square, range(3), distributable=True)) == [0, 1, 4]


def _trim_threshold(_) -> str | None:
    return os.environ.get("MALLOC_TRIM_THRESHOLD_")


def test_local_workers_keep_glibcs_own_heap_trimming(monkeypatch):
    """Dask's nanny gives its workers MALLOC_TRIM_THRESHOLD_=65536 (distributed's own configuration, read
    here, not copied); the local cluster msdc starts leaves it unset, and a value the user exports wins."""
    import dask

    pytest.importorskip("distributed", reason="dask's distributed scheduler is not installed")
    assert dask.config.get("distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_") is not None
    monkeypatch.delenv("MALLOC_TRIM_THRESHOLD_", raising=False)
    engine = DaskDistributor(workers=1)
    try:
        assert list(engine.map_ordered(_trim_threshold, [0])) == [None]
    finally:
        engine.close()
    monkeypatch.setenv("MALLOC_TRIM_THRESHOLD_", "1048576")
    engine = DaskDistributor(workers=1)
    try:
        assert list(engine.map_ordered(_trim_threshold, [0])) == ["1048576"]
    finally:
        engine.close()


def test_a_local_cluster_leaves_dasks_dashboard_port_alone():
    """With Dask's dashboard port 8787 taken (here by the test, as by a notebook's cluster or another msdc
    run), the local cluster starts without distributed's "Port 8787 is already in use" warning, which reached
    the command's output, and its scheduler listens on the loopback only."""
    pytest.importorskip("distributed", reason="dask's distributed scheduler is not installed")
    holder = socket.socket()
    try:
        holder.bind(("127.0.0.1", 8787))  # taken already (another worker's cluster): as good
        holder.listen()
    except OSError:
        pass
    engine = DaskDistributor(workers=1)
    try:
        with warnings.catch_warnings(record=True) as seen:
            warnings.simplefilter("always")
            assert list(engine.map_ordered(_slow_square, [3])) == [9]
        assert not [w for w in seen if "8787" in str(w.message)], [str(w.message) for w in seen]
        http = engine._cluster.scheduler.http_server
        assert http.port != 8787 and http.address == "127.0.0.1"
    finally:
        engine.close()
        holder.close()


def _sigint_ignored(_) -> bool:
    import signal

    return signal.getsignal(signal.SIGINT) is signal.SIG_IGN


def test_local_workers_leave_ctrl_c_to_the_main_process():
    """Ctrl-C reaches the terminal's whole process group: a local worker ended by its own KeyboardInterrupt
    printed a traceback. Each ignores it (the main process closes the cluster)."""
    pytest.importorskip("distributed", reason="dask's distributed scheduler is not installed")
    engine = DaskDistributor(workers=1)
    try:
        assert list(engine.map_ordered(_sigint_ignored, [0])) == [True]
    finally:
        engine.close()


def _hugepage_state(_) -> tuple[str | None, bool]:
    from numpy._core.multiarray import _get_madvise_hugepage

    return os.environ.get("NUMPY_MADVISE_HUGEPAGE"), bool(_get_madvise_hugepage())


def test_local_workers_do_not_mark_numpys_arrays_for_huge_pages(monkeypatch):
    """A local worker's numpy starts with NUMPY_MADVISE_HUGEPAGE=0 (its arrays not marked for transparent
    huge pages, as numpy reports it in the worker), unless the user exports a value, which wins."""
    pytest.importorskip("distributed", reason="dask's distributed scheduler is not installed")
    monkeypatch.delenv("NUMPY_MADVISE_HUGEPAGE", raising=False)
    engine = DaskDistributor(workers=1)
    try:
        assert list(engine.map_ordered(_hugepage_state, [0])) == [("0", False)]
    finally:
        engine.close()
    monkeypatch.setenv("NUMPY_MADVISE_HUGEPAGE", "1")
    engine = DaskDistributor(workers=1)
    try:
        assert list(engine.map_ordered(_hugepage_state, [0])) == [("1", True)]
    finally:
        engine.close()


def test_scheduler_and_workers_are_checked():
    for good in ("local", "none", "tcp://127.0.0.1:8786", "tls://sched.example:8786"):
        check_scheduler(TrackOptions(scheduler=good))
    for bad in ("127.0.0.1:8786", "tcp://host", "http://127.0.0.1:8786", ""):
        with pytest.raises(OptionError, match="--scheduler"):
            check_scheduler(TrackOptions(scheduler=bad))
    check_scheduler(TrackOptions(dataset="d", workers=2))  # the local cluster: the default with --dataset
    for options in (TrackOptions(workers=2), TrackOptions(dataset="d", workers=2, scheduler="none"),
                    TrackOptions(workers=2, scheduler="tcp://127.0.0.1:8786")):
        with pytest.raises(OptionError, match="--workers 2: sizes the local Dask cluster"):
            check_scheduler(options)


def test_an_unreachable_scheduler_is_said(monkeypatch, tmp_path):
    import socket

    with socket.socket() as s:  # a loopback port nothing listens on
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    monkeypatch.setattr(cluster, "CONNECT_TIMEOUT_S", 1.0)
    options = TrackOptions(dataset=str(tmp_path), scheduler=f"tcp://127.0.0.1:{port}")
    with pytest.raises(JobError, match=f"--scheduler tcp://127.0.0.1:{port}: cannot be reached"), \
            distributed(options):
        list(map_ordered(_slow_square, range(2), distributable=True))


def test_the_bar_says_the_time_left():
    assert [eta_text(s) for s in (0.4, 42, 425, 7380)] == ["0 s", "42 s", "7 min 05 s", "2 h 03 min"]

    class Tty(io.StringIO):
        def isatty(self) -> bool:
            return True

    out = Tty()
    bar = Progress(out)
    started = time.monotonic() - 10.0  # 25 tasks in 10 s: 2.5 tasks/s, 75 left: 30 s
    bar.bar(25, 100, "tasks", unit="tasks", since=started)
    assert "25/100, 2.5 tasks/s, ETA 30 s" in out.getvalue()
    bar.bar(100, 100, "tasks", unit="tasks", since=started)
    assert out.getvalue().endswith("tasks/s)\n")  # done: no time left shown
