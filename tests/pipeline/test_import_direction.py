"""Imports flow one way, cli -> jobs -> areas -> model -> asterix: read from the source (every import
statement, those inside functions included), so a lazy import breaking the rule is caught too."""

from __future__ import annotations

import ast
import functools
from pathlib import Path

import pytest

# one worker runs the module: parsing every source file costs about 3 s a process
pytestmark = pytest.mark.xdist_group("import_direction")

ROOT = Path(__file__).resolve().parents[2]
AREAS = ("correlate", "quality", "report", "track", "conflict", "evaluate", "live")
FRONT = ("msdc.pipeline.jobs", "msdc.pipeline.cli")


def _module(path: Path) -> str:
    """The installed name of a source file: the repository root is the package ``msdc``."""
    return ".".join(("msdc", *path.relative_to(ROOT).with_suffix("").parts)).removesuffix(".__init__")


@functools.cache
def _tree(path: Path) -> ast.Module:
    """The parsed source of one file (each file is read once for every check)."""
    return ast.parse(path.read_text(), str(path))


def _imports(path: Path) -> set[str]:
    """Every msdc module named by an import statement of the file (relative imports resolved)."""
    out = set()
    package = _module(path).rsplit(".", 1)[0] if path.name != "__init__.py" else _module(path)
    for node in ast.walk(_tree(path)):
        if isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                parent = package.rsplit(".", node.level - 1)[0] if node.level > 1 else package
                base = f"{parent}.{base}" if base else parent
            out |= {base} | {f"{base}.{a.name}" for a in node.names}
        elif isinstance(node, ast.Import):
            out |= {a.name for a in node.names}
    return {m for m in out if m == "msdc" or m.startswith("msdc.")}


SOURCES = sorted([*(ROOT / "asterix").rglob("*.py"), *(ROOT / "pipeline").rglob("*.py")])


@functools.cache
def _modules() -> dict[str, set[str]]:
    """Every source module's msdc imports, read when a test first asks (not at collection)."""
    return {_module(p): _imports(p) for p in SOURCES}


def _within(name: str, package: str) -> bool:
    return name == package or name.startswith(package + ".")


def _offenders(importer: str, forbidden: tuple[str, ...]) -> list[str]:
    return [f"{mod} imports {name}" for mod, names in _modules().items() if _within(mod, importer)
            for name in sorted(names) if any(_within(name, f) for f in forbidden)]


def test_the_modules_were_read():
    modules = _modules()
    assert "msdc.pipeline.correlate.correlation" in modules and "msdc.pipeline.model.aircraft" in modules
    assert "msdc.asterix.kernel" in modules
    assert "msdc.pipeline.model.aircraft" in modules["msdc.pipeline.quality.quality_run"]  # sees imports


@pytest.mark.parametrize("importer, forbidden", [
    ("msdc.pipeline.quality", ("msdc.pipeline.correlate",)),
    ("msdc.pipeline.correlate", ("msdc.pipeline.quality",)),
    *[(f"msdc.pipeline.{area}", FRONT) for area in AREAS],
    ("msdc.pipeline.model", FRONT + tuple(f"msdc.pipeline.{a}" for a in AREAS)),
    ("msdc.pipeline.jobs", ("msdc.pipeline.cli",)),
    ("msdc.asterix", ("msdc.pipeline",)),
])
def test_imports_flow_one_way(importer, forbidden):
    assert any(_within(mod, importer) for mod in _modules())  # a rule about modules that exist
    assert _offenders(importer, forbidden) == []


def test_the_command_modules_share_only_common_and_public_names():
    """Each module of pipeline/jobs/ imports no other command's module, and neither they nor the CLI import a
    private (``_name``) name of another module: what several share is a public name of jobs.common (or of
    jobs.options, where every option is declared)."""
    commands = {p.stem for p in (ROOT / "pipeline" / "jobs").glob("*.py")} - {"__init__", "common", "options"}
    assert commands == {"decode", "stats", "correlate", "quality", "track", "conflicts", "evaluate", "ingest",
                        "sql", "listen", "replay"}
    wrong = []
    for path in SOURCES:
        mod = _module(path)
        if not any(_within(mod, front) for front in FRONT):
            continue
        for node in ast.walk(_tree(path)):
            if isinstance(node, ast.ImportFrom) and (node.module or "").startswith("msdc."):
                wrong += [f"{mod} imports {node.module}.{a.name}" for a in node.names
                          if a.name.startswith("_")]
        others = [f"msdc.pipeline.jobs.{c}" for c in commands if not mod.endswith(f".{c}")]
        if _within(mod, "msdc.pipeline.jobs"):
            wrong += [f"{mod} imports {name}" for name in sorted(_modules()[mod])
                      if any(_within(name, other) for other in others)]
    assert wrong == []


def test_no_top_level_asterix_or_pipeline_import():
    """Installed code names only ``msdc.*``: a bare ``asterix`` would load another decoder's package."""
    bare = [f"{p.relative_to(ROOT)}: {a.name}" for p in SOURCES
            for node in ast.walk(_tree(p)) if isinstance(node, ast.Import)
            for a in node.names if a.name.split(".")[0] in ("asterix", "pipeline")]
    bare += [f"{p.relative_to(ROOT)}: {node.module}" for p in SOURCES
             for node in ast.walk(_tree(p))
             if isinstance(node, ast.ImportFrom) and not node.level
             and (node.module or "").split(".")[0] in ("asterix", "pipeline")]
    assert bare == []


def test_the_check_sees_a_wrong_import():
    """A step importing the jobs layer is reported (so the tests above can fail)."""
    _modules()["msdc.pipeline.quality.fake"] = {"msdc.pipeline.jobs", "msdc.pipeline.correlate.slots"}
    try:
        assert _offenders("msdc.pipeline.quality", FRONT) == [
            "msdc.pipeline.quality.fake imports msdc.pipeline.jobs"]
        assert _offenders("msdc.pipeline.quality", ("msdc.pipeline.correlate",)) == [
            "msdc.pipeline.quality.fake imports msdc.pipeline.correlate.slots"]
    finally:
        del _modules()["msdc.pipeline.quality.fake"]
