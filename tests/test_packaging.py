"""Packaging: only the decoder and the pipeline are installed; the simulator is imported from the checkout."""

import tomllib
from pathlib import Path

import fixtures

ROOT = Path(__file__).resolve().parents[1]


def test_fixtures_not_installed_as_a_package():
    from setuptools import find_namespace_packages

    config = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
    found = find_namespace_packages(str(ROOT), include=config["packages"]["find"]["include"])
    assert not any(p.startswith(("fixtures", "tests", "benchmarks")) for p in found)
    assert {"asterix", "asterix.tables", "pipeline", "pipeline.model", "pipeline.correlate"} <= set(found)
    assert "fixtures" not in config.get("package-data", {})


def test_simulator_comes_from_the_checkout():
    assert Path(fixtures.__file__).resolve().parent == ROOT / "fixtures"
