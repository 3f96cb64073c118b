"""Reading a dataset: the parts its manifest lists (a part not listed is an unfinished ingest's, never
read), per category, and a DuckDB connection with one view per category (``cat048``...)."""

from __future__ import annotations

from pathlib import Path

from msdc.pipeline.dataset.layout import MANIFEST
from msdc.pipeline.dataset.manifest import Manifest, load


class NotADataset(ValueError):
    """The folder is no dataset: the message names it and says why."""


def open_manifest(root: Path) -> Manifest:
    """The manifest of the dataset at ``root``; NotADataset when the folder or its manifest is missing."""
    if root.exists() and not root.is_dir():
        raise NotADataset(f"{root}: is a file, not a folder (a dataset is the folder 'msdc ingest' made)")
    if not root.is_dir():
        raise NotADataset(f"{root}: no such folder")
    if not (root / MANIFEST).is_file():
        raise NotADataset(f"{root}: not an msdc dataset (no {MANIFEST}; 'msdc ingest' makes one)")
    return load(root)


def category_parts(root: Path, manifest: Manifest | None = None) -> dict[int, list[Path]]:
    """Each category's parts, in the order they were written."""
    manifest = open_manifest(root) if manifest is None else manifest
    parts: dict[int, list[Path]] = {}
    for rec in manifest.inputs.values():
        for p in rec["parts"]:
            parts.setdefault(int(p["category"]), []).append(root / p["path"])
    return dict(sorted(parts.items()))


def view_name(category: int) -> str:
    """The DuckDB view of a category's records."""
    return f"cat{category:03d}"


def duckdb_views(root: Path, connection=None, manifest: Manifest | None = None,
                 categories: set[int] | None = None):
    """A DuckDB connection (``connection`` or a new in-memory one) with a view per category (of
    ``categories``; None: all) over its parts (those ``manifest`` lists: the dataset's when None), the
    partition keys ``date`` (DATE), ``category`` (INTEGER) and ``sensor`` (VARCHAR) read from the folder
    names; the connection and the views made."""
    import duckdb

    con = duckdb.connect() if connection is None else connection
    made = []
    for category, files in category_parts(root, manifest).items():
        if categories is not None and category not in categories:
            continue
        listed = ", ".join("'" + str(f).replace("'", "''") + "'" for f in files)
        con.execute(f"CREATE OR REPLACE VIEW {view_name(category)} AS SELECT * FROM read_parquet([{listed}], "
                    "hive_partitioning = true, hive_types = {'date': DATE, 'category': INTEGER, "
                    "'sensor': VARCHAR})")
        made.append(view_name(category))
    return con, made
