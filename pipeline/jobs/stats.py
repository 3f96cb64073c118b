"""The stats job (``msdc stats``): what the recordings hold, streamed in chunks (memory follows the chunk,
not the file): every category present (those msdc does not decode with their blocks), records per category
and SAC/SIC of every category msdc decodes, aircraft per sensor, skipped blocks
(``pipeline.quality.inventory``)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from msdc.pipeline.jobs.common import (
    Checked,
    JobError,
    check_decoding,
    date_ignored,
    format_hints,
    no_sensor_kind,
    order_warnings,
    select_chunk,
    sensor_table,
)
from msdc.pipeline.jobs.options import StatsOptions, check_declared
from msdc.pipeline.model import editions as edition_notes
from msdc.pipeline.model.decoded_reports import VIEW_COLUMNS
from msdc.pipeline.model.load import time_spans, widen_spans
from msdc.pipeline.model.report_selection import recorded
from msdc.pipeline.progress import Progress


def validate(options: StatsOptions) -> Checked:
    """Check the inputs, editions, --chunk-mb and the report selection before any decoding; OptionError if
    bad."""
    check_declared(options)
    checked = check_decoding(options)
    no_sensor_kind(checked.selection, "stats")
    checked.sensors = None if options.sensors is None else sensor_table(options.sensors)  # for --area
    return checked


@dataclass
class StatsResult:
    """What the recordings hold: the stats tables, and per input its format, records per category, skipped
    blocks, editions and how an 'auto' edition was chosen (``edition_choice``)."""

    tables: dict[str, pd.DataFrame]
    inputs: list[dict]
    warnings: list[str]
    selection: dict | None = None  # what the report selection kept and left out (report_selection.recorded)

    @property
    def records(self) -> int:
        """Records decoded over every input and category."""
        return sum(n for info in self.inputs for n in info["records"].values())


def stats_job(options: StatsOptions, *, progress: Progress | None = None) -> StatsResult:
    """Validate, then stream every input in chunks of ``chunk_mb`` (asterix.iter_read) and fold the tables of
    records, sources, aircraft and skipped blocks chunk by chunk: memory is bounded by the chunk, not
    the file."""
    import msdc.asterix as asterix
    from msdc.asterix.categories import DECODABLE
    from msdc.asterix.errors import UnreadableInput
    from msdc.asterix.verdict import Tally, head_of, sniff
    from msdc.pipeline.model.sources import file_labels, path_text
    from msdc.pipeline.model.time import UNDATED_DAY, DayTally
    from msdc.pipeline.quality.inventory import STATS_COLUMNS, StatsAccumulator

    checked = validate(options)
    if progress:
        progress.stage("Processing data files")
    if checked.dataset is not None:
        return _dataset_stats(options, checked, progress)
    acc = StatsAccumulator()
    failed: dict[tuple[str, int], edition_notes.Failed] = {}
    inputs: list[dict] = []
    decoded: list[Path] = []  # the files of ``inputs`` (their "path" is text: a name not UTF-8 escaped)
    spans: list[dict[int, tuple[pd.Timestamp, pd.Timestamp]]] = []
    chunk = max(int(options.chunk_mb * 1e6), 1)
    early_start: list[str] = []  # DayTally's warnings
    labels = file_labels(checked.inputs)
    content: list[str] = []  # what the inputs turned out to be, when not sound (asterix.verdict)
    selection = checked.selection if checked.selection is not None and checked.selection.active else None
    columns = STATS_COLUMNS if selection is None else (*STATS_COLUMNS, *VIEW_COLUMNS)
    left_out: dict[str, int] = {}
    n_read = kept = 0
    day = None
    for i, path in enumerate(checked.inputs):
        if progress:
            progress.step(f"{path.name} ({i + 1}/{len(checked.inputs)})")
        try:
            said = sniff(path, options.format)  # a file that is not ASTERIX at all is said at once
        except UnreadableInput as exc:
            raise JobError(str(exc), 2) from exc
        if said:
            content.append(said)
            continue
        account = Tally(str(path))
        info = {"path": path_text(path), "bytes": 0, "format": None, "records": {}, "skipped_blocks": 0,
                "editions": {}, "edition_choice": {}, "date": None}
        by_source: dict[str, tuple[pd.Timestamp, pd.Timestamp]] = {}
        tally = DayTally()
        bar = (lambda done, total, what, name=path.name: progress.bar(done, total, f"{name}: {what}")
               ) if progress else None
        try:
            # every category msdc decodes (tracks and status messages too: stats lists them per SAC/SIC)
            for rec in asterix.iter_read(path, chunk=chunk, editions=checked.editions or None,
                                         date=options.date, format=options.format, columns=columns,
                                         categories=DECODABLE, progress=bar):
                if selection is not None:
                    day = day or rec.date
                    n, k = select_chunk(rec, selection, checked.sensors, left_out, path)
                    n_read, kept = n_read + n, kept + k
                acc.add(rec.frames, rec.errors, rec.ignored)
                account.add(rec)
                tally.add(rec.frames)
                edition_notes.fold(failed, rec)
                info["bytes"], info["format"] = rec.size_bytes, rec.format
                info["date"] = info["date"] or rec.date
                for cat, frame in rec.frames.items():
                    info["records"][cat] = info["records"].get(cat, 0) + len(frame)
                info["skipped_blocks"] += len(rec.errors)
                info["editions"].update(rec.editions)
                info["edition_choice"] = {**rec.edition_choice, **info["edition_choice"]}
                by_source = widen_spans(by_source, time_spans(rec.frames, rec.date))
        except UnreadableInput as exc:
            raise JobError(str(exc), 2) from exc
        early_start += tally.warning(labels[i], info["date"], info["format"])
        content += account.warnings(head_of(path), hint=False, detected=options.format is None)
        content += account.notes()  # records no real report would be, too few to doubt the input
        inputs.append(info)
        decoded.append(path)
        spans.append(by_source)
    dates = [info["date"] for info in inputs if info["date"] is not None]
    if dates:  # undated inputs are dated by the earliest known date, as load() does
        shift = pd.Timestamp(min(dates), tz="UTC") - UNDATED_DAY
        spans = [s if info["date"] else {c: (lo + shift, hi + shift) for c, (lo, hi) in s.items()}
                 for info, s in zip(inputs, spans, strict=True)]
    read = [Path(info["path"]) for info in inputs]  # the inputs decoded: not those said to be not ASTERIX
    warnings = [*checked.warnings, *content, *edition_notes.warnings(failed), *order_warnings(read, spans),
                *date_ignored(options, inputs), *format_hints(options, inputs, decoded), *early_start]
    record = recorded(selection, day, n_read, kept, left_out) if selection is not None else None
    return StatsResult(acc.tables(), inputs, warnings, record)


def _dataset_stats(options: StatsOptions, checked: Checked, progress: Progress | None) -> StatsResult:
    """The stats of a dataset's inputs, one task per partition (pipeline.dataset.partition_stats) on the
    job's distributor, folded per input in the order of the manifest and the partitions: the tables equal
    the recordings' but for what a dataset does not keep (the skipped bytes' account, the categories not
    ingested), which the warnings say."""
    from msdc.pipeline.dataset.partition_stats import PartitionTask, partition_stats, partitions
    from msdc.pipeline.model.decoded_reports import VIEW_COLUMNS
    from msdc.pipeline.parallel import map_ordered
    from msdc.pipeline.quality.inventory import STATS_COLUMNS, StatsAccumulator

    source = checked.dataset
    selection = checked.selection if checked.selection is not None and checked.selection.active else None
    columns = STATS_COLUMNS if selection is None else (*STATS_COLUMNS, *VIEW_COLUMNS)
    keys = partitions(source.root, source.records, source.pruning)
    tasks = []
    for i, day, cat, sensor in keys:
        rec = source.records[i]
        own = [p for p in rec["parts"] if (p["date"], int(p["category"]), p["sensor"]) == (day, cat, sensor)]
        tasks.append(PartitionTask(source.root, {**rec, "parts": own}, day, cat, sensor, tuple(columns),
                                   selection, checked.sensors))
    acc = StatsAccumulator()
    blocks: dict[tuple[int, int], list] = {}
    inputs = [{"path": rec["path"], "bytes": int(rec["size_bytes"]), "format": rec.get("format"),
               "records": {}, "skipped_blocks": int(rec.get("skipped_blocks", 0)),
               "editions": {int(c): e for c, e in rec.get("editions", {}).items()}, "edition_choice": {},
               "date": source.date(i)} for i, rec in enumerate(source.records)]
    spans: list[dict] = [{} for _ in source.records]
    left_out: dict[str, int] = {}
    n_read = 0
    parts = map_ordered(partition_stats, tasks, distributable=True, label=PartitionTask.label)
    for (i, _, _, _), part in zip(keys, parts, strict=True):
        if part.unreadable:  # a part damaged or removed since the ingest: said as the other commands do
            raise JobError(part.unreadable, 2)
        acc.merge(part.accumulator)
        for cat, ids in part.blocks.items():
            blocks.setdefault((i, cat), []).append(ids)
        for cat, n in part.records.items():
            inputs[i]["records"][cat] = inputs[i]["records"].get(cat, 0) + n
        for why, n in part.left_out.items():
            left_out[why] = left_out.get(why, 0) + n
        n_read += part.read
        spans[i] = widen_spans(spans[i], part.spans)
    counts: dict[int, int] = {}
    for (_, cat), ids in blocks.items():  # a block split over partitions (midnight, two sensors) counts once
        counts[cat] = counts.get(cat, 0) + len(np.unique(np.concatenate(ids)))
    acc.set_blocks(counts)
    skipped = sum(info["skipped_blocks"] for info in inputs)
    warnings = [*checked.warnings]
    if skipped:
        warnings.append(f"--dataset {source.root}: {skipped} data block(s) were skipped when the inputs were "
                        "ingested (the manifest's skipped_blocks); a dataset keeps their count, not their "
                        "account: msdc stats on the recordings lists them by reason")
    asked = sorted({int(c) for rec in source.records for c in rec.get("options", {}).get("categories", [])})
    if asked:
        listed = ", ".join(f"CAT{c:03d}" for c in asked)
        warnings.append(f"--dataset {source.root}: holds the categories msdc ingest was asked for "
                        f"({listed}); blocks of others in the recordings are not listed")
    read = [Path(info["path"]) for info in inputs]
    warnings += order_warnings(read, spans)
    kept = sum(n for info in inputs for n in info["records"].values())
    day = next((info["date"] for info in inputs if info["date"] is not None), None)
    record = recorded(selection, day, n_read, kept, left_out) if selection is not None else None
    return StatsResult(acc.tables(), inputs, warnings, record)


__all__ = ["StatsOptions", "StatsResult", "stats_job", "validate"]
