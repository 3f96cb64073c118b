"""A dataset as the jobs' input (``--dataset DIR``): each input the manifest lists read back as the Recording
decoding its file gives (its records in file order, the columns of its edition), from the committed parts
alone, with partition pruning (day, category, sensor) and column pushdown through pyarrow.dataset."""

from __future__ import annotations

import datetime as dt
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np
import pandas as pd

from msdc.pipeline.dataset.reader import open_manifest

# A record's partition day is its own UTC day (the ``day`` column); a report's time may come from another
# field of the record (ADS-B time of applicability beside its time of reception): --from/--to prune the
# days of the window widened by this margin, and the selection then keeps exactly [from, to).
PRUNE_MARGIN = pd.Timedelta(minutes=5)
PARTITION_KEYS = (("date", "string"), ("category", "int32"), ("sensor", "string"))
PROVENANCE = ("block", "offset")


def checked_parquet():
    """Parquet read with each page's CRC-32 verified where the part has them (ingest writes them; an older
    part, without, reads as before): a damaged page is an error, not other values."""
    import pyarrow.dataset as ds

    return ds.ParquetFileFormat(
        default_fragment_scan_options=ds.ParquetFragmentScanOptions(page_checksum_verification=True))


class UnreadablePart(ValueError):
    """A part the manifest lists cannot be read as Parquet: the message names it and the reason."""


@dataclass(frozen=True)
class Pruning:
    """Which partitions a run reads: days from ``first`` to ``last`` (inclusive; None: unbounded), the
    sensors as (category or None, "SAC_SIC") pairs (empty: every sensor) and the categories (None: all);
    and which of their records: those whose ``timestamp`` lies from ``since`` to ``until`` (inclusive; None:
    unbounded) or who have none (the row groups outside are skipped by their statistics)."""

    first: dt.date | None = None
    last: dt.date | None = None
    sensors: tuple[tuple[int | None, str], ...] = ()
    categories: tuple[int, ...] | None = None
    since: pd.Timestamp | None = None
    until: pd.Timestamp | None = None

    def expression(self):
        """The pyarrow.dataset filter on the partition keys and the timestamp (None: no filter)."""
        import pyarrow as pa
        import pyarrow.dataset as ds

        terms = []
        if self.first is not None:
            terms.append(ds.field("date") >= self.first.isoformat())
        if self.last is not None:
            terms.append(ds.field("date") <= self.last.isoformat())
        if self.categories is not None:
            terms.append(ds.field("category").isin(list(self.categories)))
        if self.sensors:
            one = None
            for category, sensor in self.sensors:
                term = ds.field("sensor") == sensor
                if category is not None:
                    term = term & (ds.field("category") == category)
                one = term if one is None else one | term
            terms.append(one)
        if self.since is not None or self.until is not None:
            stamp = ds.field("timestamp")
            inside = None
            for bound, term in ((self.since, lambda v: stamp >= v), (self.until, lambda v: stamp <= v)):
                if bound is not None:
                    one = term(pa.scalar(bound.tz_convert("UTC"), type=pa.timestamp("ns", tz="UTC")))
                    inside = one if inside is None else inside & one
            terms.append(inside | stamp.is_null())
        out = None
        for t in terms:
            out = t if out is None else out & t
        return out

    def keeps(self, part: dict) -> bool:
        """Whether a manifest part record (date, category, sensor) is in the pruned partitions."""
        day = dt.date.fromisoformat(part["date"])
        if (self.first is not None and day < self.first) or (self.last is not None and day > self.last):
            return False
        if self.categories is not None and int(part["category"]) not in self.categories:
            return False
        return not self.sensors or any(part["sensor"] == s and c in (None, int(part["category"]))
                                       for c, s in self.sensors)


def pruning(selection, categories=None) -> Pruning:
    """The partitions a report selection (pipeline.model.report_selection.ReportSelection, or None) can
    keep a report of: the days of --from/--to given as instants (PRUNE_MARGIN; a time of day prunes no
    day: the recording's day is known once read) and the --sensor pairs; ``categories``: those the job
    reads."""
    first = last = None
    sensors: tuple[tuple[int | None, str], ...] = ()
    if selection is not None:
        if selection.start is not None and selection.start.instant is not None:
            first = (selection.start.instant - PRUNE_MARGIN).date()
        if selection.end is not None and selection.end.instant is not None:
            last = (selection.end.instant + PRUNE_MARGIN).date()
        sensors = tuple((ref.category, f"{ref.sac}_{ref.sic}") for ref in selection.sensors)
    return Pruning(first, last, sensors, None if categories is None else tuple(sorted(set(categories))))


def reading_pruning(prune: Pruning, selection) -> Pruning:
    """``prune`` narrowed to what a measurement job reads of a time window given as instants: the records
    whose ``timestamp`` lies within report_selection.READING_MARGIN of it (a measurement's time is its
    record's timestamp, model.time.absolute_time, so the margin's cut keeps every record read; records
    without one are read whatever the window), and the days those cover. ``prune`` as it is otherwise (no
    window, or a bound given as a time of day: the day is known once read)."""
    from msdc.pipeline.model.report_selection import READING_MARGIN

    if selection is None or not selection.timed or not selection.placed:
        return prune
    since = None if selection.start is None else selection.start.instant - READING_MARGIN
    until = None if selection.end is None else selection.end.instant + READING_MARGIN
    return replace(prune, since=since, until=until, first=None if since is None else since.date(),
                   last=None if until is None else until.date())


@dataclass
class DatasetInputs:
    """The inputs of a dataset as a job reads them: the manifest's input records in ingest order, and the
    partitions to read (``pruning``)."""

    root: Path
    records: list[dict]
    pruning: Pruning = field(default_factory=Pruning)
    read_parts: list[Path] = field(default_factory=list)  # every part file opened, in order (what was read)

    @property
    def paths(self) -> list[Path]:
        """Each input's original path (as ingested): what messages name."""
        return [Path(rec["path"]) for rec in self.records]

    @property
    def labels(self) -> list[str]:
        """Each input's ``file`` label, as its parts hold it."""
        return [rec["file"] for rec in self.records]

    @property
    def digests(self) -> list[str]:
        return [rec["sha256"] for rec in self.records]

    def date(self, i: int) -> dt.date | None:
        """The date input ``i`` was read with (its ``day`` column counts from it)."""
        text = self.records[i].get("date")
        return None if text is None else dt.date.fromisoformat(text)

    def touched(self, i: int, categories=None) -> bool:
        """Whether ``read(i, categories)`` would open any part of input ``i`` (a day, sensor and category
        the pruning keeps)."""
        prune = replace(self.pruning, categories=_narrower(self.pruning.categories, categories))
        return any(prune.keeps(part) for part in self.records[i]["parts"])

    def read(self, i: int, categories=None, columns=None):
        """Input ``i`` as an asterix Recording: its records of ``categories`` (None: all) in the pruned
        partitions, each category's in file order (by ``offset``), with the columns its edition decodes
        (``columns``: only those, besides the leading ones and ``block``/``offset``, as asterix.read).
        The skipped-bytes account is not kept in a dataset: ``errors`` is empty (the manifest counts the
        skipped blocks)."""
        from msdc.asterix.reader import Recording

        rec = self.records[i]
        prune = replace(self.pruning, categories=_narrower(self.pruning.categories, categories))
        by_cat: dict[int, dict[Path, int]] = {}  # each category's parts, with the rows the manifest lists
        for part in rec["parts"]:
            if prune.keeps(part):
                by_cat.setdefault(int(part["category"]), {})[self.root / part["path"]] = int(part["rows"])
        editions = {int(c): e for c, e in rec.get("editions", {}).items()}
        frames = {}
        for cat, files in sorted(by_cat.items()):
            frames[cat] = self._frame(files, cat, editions.get(cat), columns, prune)
        # the tables' buffers go back to the heap, where the next input's read reuses them: the caller trims
        # once it has them all (load._joined, load_measurements), not here after each input (12 trims a
        # window made each input's pages faulted in again: a peak window 2.0-2.5 -> 1.7-1.8 s of system time)
        errors = pd.DataFrame({"offset": pd.Series(dtype=np.int64), "length": pd.Series(dtype=np.int64),
                               "category": pd.Series(dtype=np.int64), "reason": pd.Series(dtype=object)})
        return Recording(frames, errors, {c: e for c, e in editions.items() if c in frames}, path=rec["path"],
                         format=rec.get("format") or "", date=self.date(i), size_bytes=int(rec["size_bytes"]))

    def _frame(self, files: dict[Path, int], category: int, edition: str | None, columns, prune: Pruning
               ) -> pd.DataFrame:
        """One category's records of one input from its part files (with the rows the manifest lists: a
        part that holds other rows was changed since the ingest, UnreadablePart): the partition filter and
        the columns pushed down to pyarrow.dataset, then put in file order."""
        import pyarrow as pa
        import pyarrow.dataset as ds

        names = _columns(category, edition, columns)
        partitioning = ds.partitioning(pa.schema([pa.field(k, t) for k, t in PARTITION_KEYS]), flavor="hive")
        # the category's own schema: no part is opened to learn it (pruned parts are never read)
        from msdc.pipeline.report.record_schema import record_schema

        schema = record_schema(category).arrow()
        # Arrow's buffers from the C heap, not its own pool: mimalloc kept about as much as the frames after
        # release_unused (1,258 MB against 847 MB after reading a 10-minute window's 50 minutes)
        pool = pa.system_memory_pool()
        schema = pa.unify_schemas([schema, pa.schema([pa.field(k, t) for k, t in PARTITION_KEYS])])
        fragments: list = []
        try:
            data = ds.dataset([str(f) for f in files], schema=schema, format=checked_parquet(),
                              partitioning=partitioning, partition_base_dir=str(self.root))
            names = [n for n in names if n in data.schema.names]
            fragments = list(data.get_fragments(filter=prune.expression()))
            self.read_parts += [Path(f.path) for f in fragments]
            for f in fragments:  # the footer's count, read before the rows
                held, listed = f.metadata.num_rows, files.get(Path(f.path))
                if listed is not None and held != listed:
                    raise UnreadablePart(f"{self.root}: a part of CAT{category:03d} holds {held:,} rows "
                                         f"where the manifest lists {listed:,} (changed since the ingest): "
                                         f"{f.path}")
            table = data.to_table(columns=names, filter=prune.expression(), memory_pool=pool)
        except FileNotFoundError as exc:
            raise UnreadablePart(f"{self.root}: a part of CAT{category:03d} is missing (the manifest lists "
                                 f"it): {exc}") from None
        except (OSError, pa.ArrowException) as exc:
            where = _failing_part(fragments, names)
            raise UnreadablePart(f"{self.root}: a part of CAT{category:03d} cannot be read{where}: {exc}"
                                 ) from None
        frame = table.to_pandas(memory_pool=pool)
        for name in frame.columns:  # text labels as decoding gives them (object, not Arrow's str)
            if isinstance(frame[name].dtype, pd.CategoricalDtype):
                cats = pd.Index(frame[name].cat.categories.to_numpy(dtype=object), dtype=object)
                frame[name] = pd.Categorical.from_codes(frame[name].cat.codes, categories=cats)
        offset = frame["offset"].to_numpy(np.int64)
        if bool(np.all(offset[1:] >= offset[:-1])):  # the parts as written, in file order: no copy
            return frame.reset_index(drop=True)
        return frame.iloc[np.argsort(offset, kind="stable")].reset_index(drop=True)


def _failing_part(fragments: list, names: list[str]) -> str:
    """' (PATH)' of the first part whose columns fail to read on their own (a read of several parts names
    none), else ''."""
    import pyarrow as pa

    for f in fragments:
        try:
            f.to_table(columns=names)
        except (OSError, pa.ArrowException):
            return f" ({f.path})"
    return ""


def _narrower(a, b) -> tuple[int, ...] | None:
    """The categories both allow (None: any)."""
    if a is None:
        return None if b is None else tuple(sorted(set(b)))
    return tuple(sorted(set(a) if b is None else set(a) & set(b)))


def _columns(category: int, edition: str | None, columns) -> list[str]:
    """The columns to read of a category stored under ``edition``: those decoding it gives (asterix.read:
    the leading ones, the edition's columns or the ``columns`` asked among them, block and offset), in the
    stored schema's order."""
    from msdc.asterix.columns import columns_for
    from msdc.asterix.reader import LEADING
    from msdc.pipeline.report.record_schema import record_schema

    stored = record_schema(category).columns
    if edition is None:
        own = set(stored)
    else:
        own = set()
        for col in columns_for(category, edition):
            own.add(col.name)
            if col.kind == "icao":
                own.add(f"{col.name}_hex")
    asked = own if columns is None else own & {*columns, *(f"{c}_hex" for c in columns)}
    keep = set(LEADING) | asked | set(PROVENANCE)
    return [c for c in stored if c in keep and c != "file"]


def open_inputs(root: str | Path) -> DatasetInputs:
    """The dataset at ``root`` as inputs; reader.NotADataset (no folder, no manifest) or
    manifest.ManifestError (unreadable manifest) naming the folder."""
    root = Path(root)
    manifest = open_manifest(root)
    return DatasetInputs(root, list(manifest.inputs.values()))
