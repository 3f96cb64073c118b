"""Packaging: the repository root installs as the one package ``msdc`` (msdc.asterix, msdc.pipeline); the
simulator, tests and benchmarks stay in the checkout; nothing installs a top-level asterix or pipeline."""

import tomllib
import zipfile
from pathlib import Path

import pytest

import fixtures

pytestmark = pytest.mark.xdist_group("wheel")  # the wheel is built once, on one worker

ROOT = Path(__file__).resolve().parents[1]
CONFIG = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]


def _source_packages() -> set[str]:
    """Every folder of asterix/ and pipeline/ that holds an __init__.py, under its installed name."""
    return {"msdc"} | {".".join(("msdc", *p.parent.relative_to(ROOT).parts))
                       for top in ("asterix", "pipeline") for p in (ROOT / top).rglob("__init__.py")}


def test_every_source_package_is_listed():
    assert CONFIG["package-dir"] == {"msdc": "."}
    assert set(CONFIG["packages"]) == _source_packages()


def test_no_checkout_only_folder_is_installed():
    assert not any(p.split(".")[1:2] and p.split(".")[1] in ("fixtures", "tests", "benchmarks", "docs")
                   for p in CONFIG["packages"])


def test_the_wheel_installs_only_msdc(msdc_wheel):
    names = zipfile.ZipFile(msdc_wheel).namelist()
    tops = {n.split("/")[0] for n in names if not n.split("/")[0].endswith(".dist-info")}
    assert tops == {"msdc"}
    assert {"msdc/__init__.py", "msdc/asterix/kernel.py", "msdc/pipeline/cli.py",
            "msdc/asterix/tables/cat048_1.31.json"} <= set(names)
    assert not any(n.startswith(("msdc/fixtures", "msdc/tests", "msdc/benchmarks")) for n in names)
    shipped = (ROOT / "pipeline" / "evaluate" / "presets").glob("*.toml")
    presets = {f"msdc/pipeline/evaluate/presets/{p.name}" for p in shipped}
    assert presets and presets <= set(names)  # the evaluation presets ship as package data
    static = {f"msdc/pipeline/live/monitor/static/{p.name}"
              for p in (ROOT / "pipeline" / "live" / "monitor" / "static").iterdir()}
    assert len(static) == 3 and static <= set(names)  # the live monitor's page, script and style sheet


def test_simulator_comes_from_the_checkout():
    assert Path(fixtures.__file__).resolve().parent == ROOT / "fixtures"
