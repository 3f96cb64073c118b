"""MkDocs hook: the Library API page is generated from this checkout's code, imported as ``msdc``.

The repository root is the package ``msdc`` (pyproject.toml maps it so: its ``__init__.py`` and the folders
``asterix/`` and ``pipeline/``), but the root folder may have any name (a clone, a worktree), and mkdocstrings
finds packages with griffe by folder name along ``sys.path``. Run as ``mkdocs build``, ``sys.path[0]`` is the
folder of the ``mkdocs`` script, where an installed msdc's ``msdc`` console script also lies: griffe would
take that file for the package. So griffe is pointed at a temporary folder holding ``msdc/``, made of links
to the package's files in the checkout (not the whole root: griffe would also read tests/, benchmarks/ and a
.venv/ made in the checkout). The API page documents the code the rest of the site describes, installed or
not, and nothing is imported.
"""

from __future__ import annotations

import atexit
import shutil
import tempfile
from pathlib import Path

from mkdocs.plugins import event_priority

PACKAGES = ("asterix", "pipeline")  # the folders installed as msdc.asterix and msdc.pipeline
_LINKS: dict[Path, Path] = {}  # repository root -> the temporary folder that holds its ``msdc``


def _linked(root: Path) -> Path:
    if root not in _LINKS:  # once per process: ``mkdocs serve`` reloads the config on every change
        folder = Path(tempfile.mkdtemp(prefix="msdc-api-"))
        atexit.register(shutil.rmtree, folder, ignore_errors=True)
        package = folder / "msdc"
        package.mkdir()
        for module in root.glob("*.py"):  # __init__.py
            (package / module.name).symlink_to(module)
        for name in PACKAGES:
            (package / name).symlink_to(root / name, target_is_directory=True)
        _LINKS[root] = folder
    return _LINKS[root]


@event_priority(100)  # before mkdocstrings' own on_config, which may create the handler already
def on_config(config):
    root = Path(config.config_file_path).resolve().parent
    python = config.plugins["mkdocstrings"].config.handlers.setdefault("python", {})
    python["paths"] = [str(_linked(root)), *python.get("paths", [])]
    return config
