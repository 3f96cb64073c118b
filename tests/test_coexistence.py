"""msdc shares an environment with the other Python ASTERIX decoders, both of which install a top-level
``asterix``: in a fresh virtual environment with msdc and asterix-decoder (or libasterix), installed in
either order, every msdc module imports, ``msdc stats`` decodes, and the other package's ``asterix`` is
its own.

The other decoders come from PyPI (pip's cache after the first run); without the network the test skips."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

pytestmark = pytest.mark.xdist_group("wheel")  # the wheel is built once, on one worker
ROOT = Path(__file__).resolve().parents[1]
OTHERS = {  # PyPI name -> a check that its own ``asterix`` module is the one imported
    "asterix_decoder": "import asterix; assert callable(asterix.parse), asterix.__file__",
    "libasterix": "import asterix.base; assert asterix.base.__file__.startswith(sys.prefix)",
}
IMPORT_ALL = """
import importlib, pkgutil, sys
import msdc
assert msdc.__file__.startswith(sys.prefix), msdc.__file__
names = [m.name for m in pkgutil.walk_packages(msdc.__path__, "msdc.")]
for name in names:
    importlib.import_module(name)
print(len(names))
"""


def _first_blocks(data: bytes, size: int) -> bytes:
    """The whole data blocks (category, then LEN in two bytes) from the start that end within ``size``
    bytes, at least one."""
    end = 0
    while end < len(data):
        step = int.from_bytes(data[end + 1:end + 3], "big")
        if end and end + step > size:
            break
        end += step
    return data[:end]


def _run(*argv: str, cwd: Path = ROOT, timeout: float = 600) -> subprocess.CompletedProcess:
    return subprocess.run(argv, cwd=cwd, capture_output=True, text=True, timeout=timeout)


@pytest.fixture(scope="module")
def wheels(tmp_path_factory, msdc_wheel) -> dict[str, Path]:
    """msdc's wheel built from the checkout, and the other decoders' wheels (pip builds asterix-decoder once
    from its sdist and caches it)."""
    out = tmp_path_factory.mktemp("wheels")
    done = _run(sys.executable, "-m", "pip", "wheel", "--no-deps", "-q", "-w", str(out), *OTHERS)
    if done.returncode != 0:
        pytest.skip(f"the other ASTERIX decoders could not be fetched or built from PyPI: "
                    f"{done.stderr[-300:]}")
    return {"msdc": msdc_wheel} | {name: next(out.glob(f"{name}-*.whl")) for name in OTHERS}


# each decoder once, each install order once: msdc installs only ``msdc``, so neither order can overwrite
# the other's files; the four combinations cost 40 s of the suite's CPU for nothing the two do not check.
# The default run installs asterix-decoder after msdc (7 s); libasterix before it under -m validation
@pytest.mark.slow
@pytest.mark.parametrize(("other", "msdc_first"), [
    pytest.param("asterix_decoder", True, id="msdc-first-asterix_decoder"),
    pytest.param("libasterix", False, id="msdc-second-libasterix", marks=pytest.mark.validation)])
def test_msdc_and_another_decoder_in_one_environment(wheels, other, msdc_first, tmp_path):
    env = tmp_path / "venv"
    made = _run(sys.executable, "-m", "venv", "--without-pip", "--system-site-packages", str(env))
    assert made.returncode == 0, made.stderr
    python = str(env / "bin" / "python")
    order = ["msdc", other] if msdc_first else [other, "msdc"]
    for name in order:  # --ignore-installed: the test run's own msdc is visible through the system site
        done = _run(sys.executable, "-m", "pip", "--python", python, "install", "-q", "--no-deps",
                    "--no-compile", "--ignore-installed", str(wheels[name]))
        assert done.returncode == 0, done.stderr
    done = _run(python, "-c", IMPORT_ALL, cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert int(done.stdout) > 50  # every module of msdc.asterix and msdc.pipeline imported
    done = _run(python, "-c", f"import sys; {OTHERS[other]}", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    # the decoding kernel run as Python (compiling it in every new environment would cost a minute each),
    # on the fixture's first blocks: the whole file took 5-7 s that way
    head = tmp_path / "head.ast"
    head.write_bytes(_first_blocks((ROOT / "fixtures" / "radar.ast").read_bytes(), 3000))
    argv = [str(env / "bin" / "msdc"), "stats", str(head)]
    done = subprocess.run(argv, cwd=tmp_path, capture_output=True, text=True, timeout=600,
                          env={**os.environ, "NUMBA_DISABLE_JIT": "1"})
    assert done.returncode == 0, done.stderr
    assert "Records per category" in done.stdout
