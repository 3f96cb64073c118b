"""A command imports only what it uses: ``msdc --help`` loads no heavy library (issue 8, item 7)."""

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
HEAVY = ("pandas", "numba", "scipy", "openpyxl", "matplotlib")

_SCRIPT = """
import atexit, runpy, sys
sys.argv = ["msdc", *{argv!r}]
# an exit handler: pipeline.cli's run() ends the process with os._exit once the handlers have run
atexit.register(lambda: print("loaded:" + ",".join(m for m in {heavy!r} if m in sys.modules),
                              file=sys.stderr))
try:
    runpy.run_module("msdc.pipeline.cli", run_name="__main__")
except SystemExit:
    pass
"""


def _loaded(*argv: str, heavy: tuple[str, ...] = HEAVY) -> tuple[str, list[str]]:
    """stdout of ``python -m pipeline.cli ARGV`` in a fresh interpreter, and which of ``heavy`` it loaded."""
    done = subprocess.run([sys.executable, "-c", _SCRIPT.format(argv=list(argv), heavy=heavy)], cwd=ROOT,
                          capture_output=True, text=True, timeout=120)
    last = [line for line in done.stderr.splitlines() if line.startswith("loaded:")][-1]
    return done.stdout, [m for m in last.removeprefix("loaded:").split(",") if m]


def test_help_imports_no_heavy_library():
    out, loaded = _loaded("--help")
    assert "correlate" in out and "stats" in out  # the help was printed
    assert loaded == []


def test_subcommand_help_imports_no_heavy_library():
    out, loaded = _loaded("correlate", "--help")
    assert "--slot" in out
    assert loaded == []


def test_the_check_sees_a_heavy_import():
    """The same probe reports pandas once a command really uses it (so the tests above can fail)."""
    out, loaded = _loaded("stats", "fixtures/radar.ast")
    assert "Records per category" in out and "pandas" in loaded


# what msdc stats does not use: the correlate, quality and report steps and the libraries behind them
NOT_FOR_STATS = ("matplotlib", "openpyxl", "msdc.pipeline.correlate.correlation", "msdc.pipeline.model.jumps",
                 "msdc.pipeline.model.measurements", "msdc.pipeline.quality.quality_run",
                 "msdc.pipeline.report.excel", "msdc.pipeline.report.tables", "msdc.pipeline.model.sensors",
                 "scipy.linalg")


def test_stats_imports_only_the_stats_path():
    out, loaded = _loaded("stats", "fixtures/radar.ast", heavy=NOT_FOR_STATS)
    assert "Records per category" in out
    assert loaded == []


def test_the_stats_check_sees_a_step_import():
    """The same probe reports the correlate steps once a command imports them (so the test above can fail):
    correlate decodes and correlates before it finds no such aircraft."""
    _, loaded = _loaded("correlate", "fixtures/radar.ast", "fixtures/adsb.ast", "--sensors",
                        "fixtures/sensors.toml", "--callsign", "NOSUCH1", heavy=NOT_FOR_STATS)
    assert "msdc.pipeline.correlate.correlation" in loaded and "msdc.pipeline.model.jumps" in loaded


def test_track_with_estimated_noise_does_not_import_scipy_stats(tmp_path):
    """scipy.stats is ~45 MB a process and 0.3-1 s of import: the tracker and its noise estimate take the
    chi-square quantiles from scipy.special (the run's memory while figures are drawn beside it, issue 26)."""
    out, loaded = _loaded("track", "fixtures/radar.ast", "fixtures/adsb.ast", "--sensors",
                          "fixtures/sensors.toml", "--date", "2019-03-01", "--all", "--json",
                          str(tmp_path / "t.json"),
                          heavy=("scipy.stats", "scipy.special", "matplotlib"))
    assert "Measurement noise estimated" in out  # the default --noise estimate ran
    assert loaded == ["scipy.special"]  # the probe sees what the run does import


_NUMBA_AFTER = """
import numpy as np
from numba import njit
from msdc.pipeline.cli import _numba_without_scipy

_numba_without_scipy()
assert "scipy.linalg" not in __import__("sys").modules
a, b = np.arange(1.0, 6.0), np.array([2.0, -1.0, 0.5])
dot = njit(lambda x, y: np.dot(x, y))(a, a)  # BLAS: imports scipy.linalg.cython_blas when compiled
conv = njit(lambda x, y: np.convolve(x, y))(a, b)  # the loop numba takes without BLAS
print(dot, *conv)
"""


def test_numba_started_without_scipy_still_compiles_blas_and_convolve():
    """Numba started without scipy.linalg (msdc stats) still compiles np.dot (it imports BLAS then) and
    np.convolve; values worked by hand: 1+4+9+16+25 = 55, and (1..5) * (2, -1, 0.5) in full."""
    done = subprocess.run([sys.executable, "-c", _NUMBA_AFTER], cwd=ROOT, capture_output=True, text=True,
                          timeout=300)
    assert done.returncode == 0, done.stderr
    values = [float(v) for v in done.stdout.split()]
    assert values == [55.0, 2.0, 3.0, 4.5, 6.0, 7.5, -3.0, 2.5]


def test_correlate_and_quality_start_numba_without_scipy(tmp_path):
    """correlate and quality use no BLAS kernel: numba starts without scipy.linalg for them too (the probe
    sees scipy.linalg once imported: test_numba_started_without_scipy_still_compiles_blas_and_convolve)."""
    inputs = ("fixtures/radar.ast", "fixtures/adsb.ast", "--sensors", "fixtures/sensors.toml", "--all")
    out, loaded = _loaded("correlate", *inputs, "-o", str(tmp_path / "r.xlsx"), heavy=("scipy.linalg",))
    assert "MAS72" in out and loaded == []
    out, loaded = _loaded("quality", *inputs, heavy=("scipy.linalg",))
    assert out and loaded == []


def test_evaluate_takes_its_intervals_without_scipy_stats(tmp_path):
    """evaluate's exact binomial and Poisson intervals and its bias-drift test come from scipy.special (the
    functions scipy.stats evaluates for them): a worker restarted between windows imports no scipy.stats."""
    out = tmp_path / "e.json"
    _, loaded = _loaded("evaluate", "fixtures/radar.ast", "fixtures/adsb.ast", "--sensors",
                        "fixtures/sensors.toml", "--preset", "eurocontrol-1997-ssr", "--date", "2019-03-01",
                        "--json", str(out),
                        heavy=("scipy.stats", "scipy.special"))
    assert out.stat().st_size > 0  # the evaluation ran and wrote its intervals
    assert loaded == ["scipy.special"]
