"""dataset.warm warms the decoder in the ingest pool's forkserver only: imported anywhere else (every module
is, by the coexistence and import tests) it must not decode, which on a cold numba cache costs ~20 s."""

from __future__ import annotations

import os
import subprocess
import sys

from msdc.pipeline.dataset.warm import WARM_ENV

CHECK = "import sys, msdc.pipeline.dataset.warm; print('msdc.asterix.verdict' in sys.modules)"


def _imports_the_checker(env: dict) -> bool:
    done = subprocess.run([sys.executable, "-c", CHECK], capture_output=True, text=True, env=env, timeout=300)
    assert done.returncode == 0, done.stderr
    return done.stdout.strip() == "True"


def test_importing_warm_outside_the_forkserver_decodes_nothing():
    env = {k: v for k, v in os.environ.items() if k != WARM_ENV}
    assert not _imports_the_checker(env)


def test_the_forkserver_environment_warms():
    assert _imports_the_checker({**os.environ, WARM_ENV: "1"})
