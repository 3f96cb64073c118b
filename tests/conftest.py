"""Fixtures shared by the whole suite."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import pytest
from budget import FULL_MAX_EXAMPLES
from hypothesis import settings

ROOT = Path(__file__).resolve().parents[1]
PREWARM_DONE = "MSDC_TEST_PREWARM_DONE"  # the file tests/prewarm.py writes when the kernels are compiled


def pytest_configure(config) -> None:
    """With xdist workers, compile the numba kernels once in a process of its own while the workers collect
    (tests/prewarm.py); without it, each worker compiles every kernel it meets on a cold cache."""
    workers = getattr(config.option, "numprocesses", None)
    if hasattr(config, "workerinput") or not workers or os.environ.get(PREWARM_DONE):
        return
    done = Path(tempfile.mkdtemp(prefix="msdc-prewarm-")) / "done"
    proc = subprocess.Popen([sys.executable, str(ROOT / "tests" / "prewarm.py"), str(done)],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    os.environ[PREWARM_DONE] = f"{done}:{proc.pid}"  # the workers, started after this hook, inherit it
    config._msdc_prewarm = proc


# The order the workers take the tests in (xdist keeps it: --no-loadscope-reorder; by default it ran the
# groups with the most tests first). First the decoder's tests (tests/asterix, tests/fixtures) and the wheel
# group (it compiles in a virtual environment of its own): on a cold numba cache (a fresh install, as in CI)
# they need only the kernels tests/prewarm.py compiles before the workers start, while it compiles the
# tracker's beside them; a group taken first that tracks compiled the same kernels again beside it (the
# track group's first setup took 20 s so, the suite 394 s against 325 s on a warm cache). Then the long
# groups (15-30 s units of work: one starting last leaves the other worker idle at the end), the other
# groups, and the single tests, small units that even out the end.
DECODER_PATHS = ("tests/asterix/", "tests/fixtures/")
LONG_GROUPS = ("dask", "print_workbooks", "ingest")


def _group(item) -> str | None:
    marker = item.get_closest_marker("xdist_group")
    return (marker.kwargs.get("name") or (marker.args[0] if marker.args else None)) if marker else None


def pytest_collection_modifyitems(config, items) -> None:
    """The tests in the order above (stable: each rank keeps its collection order)."""
    def rank(item) -> int:
        group = _group(item)
        if group == "wheel" or item.nodeid.startswith(DECODER_PATHS):
            return 0
        if group in LONG_GROUPS:
            return 1
        return 2 if group else 3

    items.sort(key=rank)


def pytest_unconfigure(config) -> None:
    proc = getattr(config, "_msdc_prewarm", None)
    if proc is not None:
        proc.kill()
        proc.wait()
        shutil.rmtree(Path(os.environ[PREWARM_DONE].rsplit(":", 1)[0]).parent, ignore_errors=True)


def _wait_for_prewarm(stage: str) -> None:
    """Wait (at most 3 minutes, and while the prewarm lives) for its file of ``stage``: "done" (the decoder's
    kernels) or "all" (every command's)."""
    said = os.environ.get(PREWARM_DONE)
    if not said:
        return
    done, pid = said.rsplit(":", 1)
    path = Path(done) if stage == "done" else Path(done).with_name(stage)
    deadline = time.monotonic() + 180
    while not path.exists() and time.monotonic() < deadline:
        try:  # ended without its file (a crash): a zombie until the controller reaps it
            if Path(f"/proc/{pid}/stat").read_text().split(")")[-1].split()[0] == "Z":
                return
        except OSError:
            return
        time.sleep(0.2)


@pytest.fixture(scope="session", autouse=True)
def _kernels_compiled() -> None:
    """The decoder's kernels before a worker's first test (tests/prewarm.py compiles the others while the
    first tests run)."""
    _wait_for_prewarm("done")


@pytest.fixture(scope="session")
def every_kernel_compiled() -> None:
    """Wait for tests/prewarm.py's "all" (every command's kernels compiled): a module fixture running a whole
    tracking command early in the run would otherwise compile the same kernels beside it (on a fresh
    checkout, the track module's fixture took 23 s so, 2 s after the prewarm)."""
    _wait_for_prewarm("all")


@pytest.fixture(scope="session")
def msdc_wheel(tmp_path_factory) -> Path:
    """msdc's wheel, built from a copy of the checkout as pip builds it for an install.

    A copy, because pip builds in the source tree: two xdist workers building in one `build/` race."""
    out = tmp_path_factory.mktemp("msdc_wheel")
    source = tmp_path_factory.mktemp("msdc_source") / "msdc"
    junk = shutil.ignore_patterns(".git", "build", "dist", "site", "*.egg-info", "__pycache__", ".*_cache")
    shutil.copytree(ROOT, source, ignore=junk)
    argv = [sys.executable, "-m", "pip", "wheel", "--no-deps", "-q", "-w", str(out), str(source)]
    done = subprocess.run(argv, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    return next(out.glob("msdc-*.whl"))


@pytest.fixture(scope="module")
def dask_scheduler():
    """The address of a 2-process Dask LocalCluster on the loopback, for the jobs' --scheduler: started once
    for the module that asks for it, as a user's running cluster would be. Not kept for the session: idle,
    its scheduler and workers still took about 30 s of CPU over the rest of the run (heartbeats, dask's
    sampling profiler)."""
    import logging

    distributed = pytest.importorskip("distributed", reason="dask's distributed scheduler is not installed")
    _wait_for_prewarm("all")  # its worker processes load every kernel from the cache, not compile it again
    from msdc.pipeline.dataset.cluster import QUIET_SCHEDULER

    cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                                       dashboard_address=None, silence_logs=logging.ERROR,
                                       scheduler_kwargs=QUIET_SCHEDULER)
    yield cluster.scheduler_address
    cluster.close()


# Hypothesis: "ci" (default) draws a quarter of each property test's written count (tests/budget.py),
# "full" draws them all: pytest --hypothesis-profile=full
settings.register_profile("ci", max_examples=25)
settings.register_profile("full", max_examples=FULL_MAX_EXAMPLES)
settings.load_profile("ci")
