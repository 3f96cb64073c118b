"""``msdc stats --dataset``, one task per partition: its records read back (pruned, the stats columns alone),
the report selection applied, and folded into the stats tables' accumulator with the partition's distinct
data block numbers and time spans, so that the partitions' results combine exactly into an input's."""

from __future__ import annotations

import datetime as dt
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from msdc.pipeline.dataset.inputs import DatasetInputs, Pruning, UnreadablePart


@dataclass(frozen=True)
class PartitionTask:
    """One partition (day, category, sensor) of one input: the manifest record, the columns to read, and
    the report selection with the sensor table it needs (None: every record)."""

    root: Path
    record: dict
    date: str
    category: int
    sensor: str
    columns: tuple[str, ...]
    selection: object | None = None
    sensors: pd.DataFrame | None = None

    def label(self) -> str:
        """The task named for progress and failure messages: the input and the partition."""
        return (f"{self.record['path']} partition date={self.date}/category={self.category:03d}/"
                f"sensor={self.sensor}")


@dataclass
class PartitionStats:
    """What a partition adds to the stats: the accumulator, the distinct data block numbers per category,
    the records read and kept per category, the left-out counts and the time span per data source; or only
    why its part cannot be read (``unreadable``: a result, not an error, so that a cluster does not retry it
    and the job says it as without one)."""

    accumulator: object
    blocks: dict[int, np.ndarray]
    read: int
    records: dict[int, int]
    left_out: dict[str, int]
    spans: dict
    unreadable: str | None = None


def partitions(root: Path, records: list[dict], pruning: Pruning) -> list[tuple[int, str, int, str]]:
    """(input index, date, category, sensor) of every partition the pruning keeps, in input order, then
    day, category and sensor: each once, however many parts it has."""
    out: list[tuple[int, str, int, str]] = []
    for i, rec in enumerate(records):
        seen = sorted({(p["date"], int(p["category"]), p["sensor"])
                       for p in rec["parts"] if pruning.keeps(p)})
        out += [(i, *key) for key in seen]
    return out


def partition_stats(task: PartitionTask) -> PartitionStats:
    """Read one partition and fold it (runs on a worker)."""
    from msdc.pipeline.model.decoded_reports import select_decoded
    from msdc.pipeline.model.load import time_spans
    from msdc.pipeline.quality.inventory import StatsAccumulator

    day = dt.date.fromisoformat(task.date)
    source = DatasetInputs(task.root, [task.record],
                           Pruning(day, day, ((task.category, task.sensor),), (task.category,)))
    try:
        rec = source.read(0, columns=task.columns)
    except UnreadablePart as exc:  # damaged or removed since the ingest
        return PartitionStats(None, {}, 0, {}, {}, {}, unreadable=str(exc))
    read = sum(len(f) for f in rec.frames.values())
    left_out: dict[str, int] = {}
    if task.selection is not None:
        rec.frames, _ = select_decoded(rec.frames, task.selection, rec.date, task.sensors, left_out)
    acc = StatsAccumulator()
    acc.add(rec.frames)
    blocks = {cat: np.unique(f["block"].to_numpy(np.int64)) for cat, f in rec.frames.items() if len(f)}
    return PartitionStats(acc, blocks, read, {c: len(f) for c, f in rec.frames.items()}, left_out,
                          time_spans(rec.frames, rec.date))
