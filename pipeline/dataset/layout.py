"""Where a dataset keeps things: ``date=YYYY-MM-DD/category=CCC/sensor=SAC_SIC/part-ID-NNNNN.parquet``
(hive-style: DuckDB, pyarrow and Polars read the partition keys from the folder names), the manifest and
the lock at the top."""

from __future__ import annotations

import datetime as dt
from pathlib import Path

MANIFEST = "manifest.json"
LOCK = ".ingest.lock"
PART_GLOB = "date=*/category=*/sensor=*/part-*.parquet"
TEMP_GLOB = "date=*/category=*/sensor=*/.part-*.tmp"
UNKNOWN_SENSOR = "unknown"  # records without SAC/SIC
INPUT_ID_CHARS = 16  # a part names its input by this many hex digits of the input's SHA-256


def sensor_key(sac: int | None, sic: int | None) -> str:
    """The sensor partition's value: ``SAC_SIC`` (``20_129``), ``unknown`` when either is missing."""
    if sac is None or sic is None:
        return UNKNOWN_SENSOR
    return f"{int(sac)}_{int(sic)}"


def partition_dir(root: Path, date: dt.date, category: int, sensor: str) -> Path:
    """The folder of one (day, category, sensor) partition."""
    return root / f"date={date.isoformat()}" / f"category={category:03d}" / f"sensor={sensor}"


def part_name(prefix: str, seq: int) -> str:
    """A part's file name: its input's id (SHA-256 prefix; then the window's number when windows of the
    input are written apart) and its number among the parts of that."""
    return f"part-{prefix}-{seq:05d}.parquet"


def input_files(root: Path, input_id: str) -> list[Path]:
    """Every part of an input on disk, renamed into place or temporary."""
    return [*root.glob(f"date=*/category=*/sensor=*/part-{input_id}-*.parquet"),
            *root.glob(f"date=*/category=*/sensor=*/.part-{input_id}-*.tmp")]


def temp_path(final: Path) -> Path:
    """Where a part is written before it is renamed to ``final`` (hidden: readers never list it)."""
    return final.with_name(f".{final.stem}.tmp")


def input_id(sha256: str) -> str:
    """An input's id in part names."""
    return sha256[:INPUT_ID_CHARS]


def relative(root: Path, path: Path) -> str:
    """A path inside the dataset as the manifest writes it (POSIX, relative to the root)."""
    return path.relative_to(root).as_posix()
