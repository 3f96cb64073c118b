"""Fixtures shared by the whole suite."""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from budget import FULL_MAX_EXAMPLES
from hypothesis import settings

ROOT = Path(__file__).resolve().parents[1]


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


@pytest.fixture(scope="session")
def dask_scheduler():
    """The address of a 2-process Dask LocalCluster on the loopback (one per xdist worker), for the jobs'
    --scheduler: started once, as a user's running cluster would be."""
    import logging

    distributed = pytest.importorskip("distributed", reason="dask's distributed scheduler is not installed")
    cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                                       dashboard_address=None, silence_logs=logging.ERROR)
    yield cluster.scheduler_address
    cluster.close()


# Hypothesis: "ci" (default) draws a quarter of each property test's written count (tests/budget.py),
# "full" draws them all: pytest --hypothesis-profile=full
settings.register_profile("ci", max_examples=25)
settings.register_profile("full", max_examples=FULL_MAX_EXAMPLES)
settings.load_profile("ci")
