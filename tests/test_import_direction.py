"""Imports in pipeline/ flow one way, cli -> jobs -> steps -> model: read from the source (every import
statement, those inside functions included), so a lazy import breaking the rule is caught too."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

PIPELINE = Path(__file__).resolve().parents[1] / "pipeline"
STEPS = ("correlate", "quality", "report", "track", "conflict")
FRONT = ("pipeline.jobs", "pipeline.jobs_track", "pipeline.jobs_conflict", "pipeline.cli")


def _module(path: Path) -> str:
    return ".".join(path.relative_to(PIPELINE.parent).with_suffix("").parts).removesuffix(".__init__")


def _imports(path: Path) -> set[str]:
    """Every pipeline module named by an import statement of the file (relative imports resolved)."""
    out = set()
    package = _module(path).rsplit(".", 1)[0] if path.name != "__init__.py" else _module(path)
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                parent = package.rsplit(".", node.level - 1)[0] if node.level > 1 else package
                base = f"{parent}.{base}" if base else parent
            out |= {base} | {f"{base}.{a.name}" for a in node.names}
        elif isinstance(node, ast.Import):
            out |= {a.name for a in node.names}
    return {m for m in out if m == "pipeline" or m.startswith("pipeline.")}


MODULES = {_module(p): _imports(p) for p in sorted(PIPELINE.rglob("*.py"))}


def _within(name: str, package: str) -> bool:
    return name == package or name.startswith(package + ".")


def _offenders(importer: str, forbidden: tuple[str, ...]) -> list[str]:
    return [f"{mod} imports {name}" for mod, names in MODULES.items() if _within(mod, importer)
            for name in sorted(names) if any(_within(name, f) for f in forbidden)]


def test_the_modules_were_read():
    assert "pipeline.correlate.correlation" in MODULES and "pipeline.model.aircraft" in MODULES
    assert "pipeline.model.aircraft" in MODULES["pipeline.quality.quality_run"]  # the reader sees imports


@pytest.mark.parametrize("importer, forbidden", [
    ("pipeline.quality", ("pipeline.correlate",)),
    ("pipeline.correlate", ("pipeline.quality",)),
    *[(f"pipeline.{step}", FRONT) for step in STEPS],
    ("pipeline.stats", FRONT),
    ("pipeline.model", FRONT + tuple(f"pipeline.{s}" for s in STEPS) + ("pipeline.stats",)),
])
def test_imports_flow_one_way(importer, forbidden):
    assert _offenders(importer, forbidden) == []


def test_the_check_sees_a_wrong_import():
    """A step importing the jobs layer is reported (so the tests above can fail)."""
    MODULES["pipeline.quality.fake"] = {"pipeline.jobs", "pipeline.correlate.slots"}
    try:
        assert _offenders("pipeline.quality", FRONT) == ["pipeline.quality.fake imports pipeline.jobs"]
        assert _offenders("pipeline.quality", ("pipeline.correlate",)) == [
            "pipeline.quality.fake imports pipeline.correlate.slots"]
    finally:
        del MODULES["pipeline.quality.fake"]
