"""Recordings and dataset readers shared by the ingest and sql tests."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pyarrow.parquet as pq
from live_bytes import raw_blocks

from msdc.asterix.encode import encode_frame

FIX = Path(__file__).resolve().parents[1] / "fixtures"
RADAR, ADSB = FIX / "radar.ast", FIX / "adsb.ast"
DAY = "2026-11-28"
MIDNIGHT_START_S = 86400.0 - 4.0 * 3000  # radar A's first plot: its 3000th is at midnight


def midnight_frames(n: int = 6000) -> tuple[pd.DataFrame, pd.DataFrame]:
    """Two radars' CAT048 plots, 4 s apart, across midnight: radar 20/129 from 82800 s (its plot 3000 at
    0 s of the next day), radar 20/130 2 s after each (times exact in 1/128 s)."""
    t = (MIDNIGHT_START_S + 4.0 * np.arange(n)) % 86400.0
    a = pd.DataFrame({"sac": 20, "sic": 129, "time_of_day": t,
                      "address": [f"{0x750000 + i % 50:06X}" for i in range(n)]})
    b = a.assign(sic=130, time_of_day=(t + 2.0) % 86400.0)
    return a, b


def midnight_recording(path: Path, n: int = 6000) -> tuple[pd.DataFrame, pd.DataFrame]:
    """Write the two radars' plots as a raw stream, a block of 5 of each in turn, in time order."""
    a, b = midnight_frames(n)
    ba, bb = (raw_blocks(encode_frame(48, f, records_per_block=5)) for f in (a, b))
    path.write_bytes(b"".join(x + y for x, y in zip(ba, bb, strict=True)))
    return a, b


def manifest(root: Path) -> dict:
    return json.loads((root / "manifest.json").read_text())


def listed_parts(root: Path) -> list[str]:
    """The parts the manifest lists, relative to the root, sorted."""
    return sorted(p["path"] for rec in manifest(root)["inputs"] for p in rec["parts"])


def on_disk(root: Path) -> list[str]:
    """Every file under the root but the lock and the manifest, relative, sorted (temporary ones too)."""
    return sorted(p.relative_to(root).as_posix() for p in root.rglob("*")
                  if p.is_file() and p.name not in (".ingest.lock", "manifest.json"))


def category_rows(root: Path, category: int) -> pd.DataFrame:
    """A category's rows from the parts the manifest lists, read with pyarrow, with the partition keys from
    the folder names; sorted by file and offset."""
    frames = []
    for rel in listed_parts(root):
        keys = dict(k.split("=") for k in rel.split("/")[:3])
        if int(keys["category"]) != category:
            continue
        f = pq.read_table(root / rel).to_pandas()
        frames.append(f.assign(date=keys["date"], sensor=keys["sensor"], file=f["file"].astype(str)))
    out = pd.concat(frames, ignore_index=True)
    return out.sort_values(["file", "offset"], kind="stable").reset_index(drop=True)


def same_dataset(a: Path, b: Path) -> None:
    """Assert two datasets hold the same parts (names and rows, compared row by row) and nothing else."""
    assert on_disk(a) == listed_parts(a)
    assert on_disk(b) == listed_parts(b)
    assert listed_parts(a) == listed_parts(b)
    for rel in listed_parts(a):
        x, y = pq.read_table(a / rel), pq.read_table(b / rel)
        assert x.schema.equals(y.schema), rel
        assert x.equals(y), rel
    strip = ("ingested_at", "path")
    ra = [{k: v for k, v in r.items() if k not in strip} for r in manifest(a)["inputs"]]
    rb = [{k: v for k, v in r.items() if k not in strip} for r in manifest(b)["inputs"]]
    assert ra == rb


def partition_rows(root: Path) -> dict[str, object]:
    """Each partition's rows (folder -> Arrow table), its parts read in name order (file order), text
    columns as plain strings (each part has dictionaries of its own)."""
    import pyarrow as pa

    out: dict[str, list] = {}
    for rel in listed_parts(root):
        t = pq.read_table(root / rel)
        t = t.cast(pa.schema([pa.field(f.name, f.type.value_type) if pa.types.is_dictionary(f.type) else f
                              for f in t.schema]))
        out.setdefault(rel.rsplit("/", 1)[0], []).append(t)
    return {k: pa.concat_tables(v) for k, v in out.items()}


def same_rows(a: Path, b: Path) -> None:
    """Assert two datasets hold the same rows in every partition, in the same order, and nothing else."""
    assert on_disk(a) == listed_parts(a) and on_disk(b) == listed_parts(b)
    ra, rb = partition_rows(a), partition_rows(b)
    assert sorted(ra) == sorted(rb)
    for key in ra:
        assert ra[key].equals(rb[key]), key
    assert [r["rows"] for r in manifest(a)["inputs"]] == [r["rows"] for r in manifest(b)["inputs"]]
