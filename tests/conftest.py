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


# Hypothesis: "ci" (default) draws a quarter of each property test's written count (tests/budget.py),
# "full" draws them all: pytest --hypothesis-profile=full
settings.register_profile("ci", max_examples=25)
settings.register_profile("full", max_examples=FULL_MAX_EXAMPLES)
settings.load_profile("ci")
