"""The listen command reads Thresholds for its options' defaults: importing the monitor package loads no
web server and no heavy library (msdc --help stays light)."""

import subprocess
import sys
from dataclasses import fields

from msdc.pipeline.live.monitor import Thresholds

PROBE = ("import sys, msdc.pipeline.live.monitor as m; m.Thresholds(); "
         "print(','.join(x for x in ('pandas', 'numpy', 'starlette', 'uvicorn') if x in sys.modules))")


def test_the_monitor_package_imports_light() -> None:
    done = subprocess.run([sys.executable, "-c", PROBE], capture_output=True, text=True, timeout=60)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == ""


def test_every_threshold_has_a_unit_and_a_help() -> None:
    for f in fields(Thresholds):
        assert f.metadata["unit"] in ("s", "") and len(f.metadata["help"]) > 20
        assert f.metadata["unit"] == ("s" if f.name.endswith("_s") else "")
