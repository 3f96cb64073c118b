"""One input of ``msdc ingest`` decoded into its parts (pipeline.dataset): streamed in chunks into one
writer, or, with a pool, a raw recording's windows decoded and written in the pool's processes; its manifest
record and its warnings returned, every file of it removed on failure."""

from __future__ import annotations

import datetime as dt
from collections import deque
from dataclasses import dataclass, field
from pathlib import Path

BLOCKS_KEPT = 20  # skipped blocks of an input kept to be listed (msdc decode lists as many); the rest counted


class IngestFailed(RuntimeError):
    """An input that cannot be ingested (the message names it and why; ``status`` 2 when it cannot be read,
    else 1): the ingest job says it as its error."""

    def __init__(self, message: str, status: int = 1):
        super().__init__(message)
        self.status = status

    def __reduce__(self):
        """Pickled with its status (raised in a pool process, re-raised in the main one)."""
        return type(self), (str(self), self.status)


@dataclass
class SkippedBlocks:
    """An input's data blocks skipped as damaged: its path (as text, escaped), the first BLOCKS_KEPT (offset,
    reason), and how many there were and their bytes."""

    path: str
    blocks: list[tuple[int, str]] = field(default_factory=list)
    count: int = 0
    length_bytes: int = 0


@dataclass(frozen=True)
class IngestSettings:
    """What shapes an input's rows and how it is read (the ingest job's options, checked): the categories,
    the chunk size, the editions pinned (and as given, for the manifest), --date, --format, --lenient, and
    the pool's processes."""

    categories: list[int]
    chunk_bytes: int
    editions: dict[int, str]
    edition_args: list[str]
    date: dt.date | None
    format: str | None
    lenient: bool
    workers: int


def ingest_input(path: Path, digest: str, label: str, settings: IngestSettings, root: Path,
                 pool, on_chunk) -> tuple[dict, list[str], SkippedBlocks]:
    """Decode one input into its parts: its manifest record, its warnings and its skipped blocks; every file
    of it removed on failure.
    With a pool, a raw recording's windows are decoded and written in the pool's processes (_windows);
    anything else streams here (its chunks decoded in the pool when it is a raw stream)."""
    from msdc.asterix.errors import UnreadableInput
    from msdc.asterix.verdict import Tally, head_of
    from msdc.pipeline.dataset.layout import input_files, input_id
    from msdc.pipeline.dataset.manifest import prune_empty
    from msdc.pipeline.dataset.writer import Undated
    from msdc.pipeline.meta import software_version
    from msdc.pipeline.model import editions as edition_notes
    from msdc.pipeline.model.sources import path_text
    from msdc.pipeline.model.time import DayTally

    cats = settings.categories
    size = path.stat().st_size
    seen = _Seen(DayTally(), Tally(str(path)), {}, SkippedBlocks(path_text(path)))
    iid = input_id(digest)
    futures: list = []
    try:
        parts = None if pool is None else _windows(path, label, settings, root, iid, cats, pool, seen,
                                                    futures, on_chunk)
        if parts is None:
            parts = _stream(path, label, settings, root, iid, cats, pool, seen, on_chunk)
        content = seen.account.warnings(head_of(path), hint=False, detected=settings.format is None)
        if content and not settings.lenient:
            raise IngestFailed("; ".join(content) + "; nothing ingested from it (--lenient ingests it "
                               "anyway)")
    except BaseException as exc:
        for f in futures:  # the pool's writes of this input end before its files are removed
            f.cancel()
        for f in futures:
            if not f.cancelled():
                try:
                    f.result()
                except BaseException:  # noqa: BLE001,S110 - its own failure is the one raised below
                    pass
        removed = input_files(root, iid)
        for p in removed:
            p.unlink(missing_ok=True)
        prune_empty(root, {p.parent for p in removed})
        if isinstance(exc, UnreadableInput):
            raise IngestFailed(str(exc), 2) from exc
        if isinstance(exc, Undated):
            raise IngestFailed(f"{path}: {exc}: give --date YYYY-MM-DD (the dataset's partitions are UTC "
                               "days); nothing ingested from it") from None
        raise
    if on_chunk:
        on_chunk(size, size, f"{path.name}: decoding")
    warnings = (content + seen.account.notes() + seen.tally.warning(label, seen.date, seen.fmt)
                + edition_notes.warnings(seen.failed))
    if not seen.rows:
        warnings.append(f"{path}: no record of {', '.join(f'CAT{c:03d}' for c in cats)} decoded; "
                               "recorded as ingested, with no part")
    record = {"sha256": digest, "file": label, "path": path_text(path.resolve()), "size_bytes": size,
            "format": seen.fmt, "date": None if seen.date is None else seen.date.isoformat(),
            "editions": {f"{c:03d}": e for c, e in sorted(seen.editions.items()) if c in seen.rows},
            "rows": {f"{c:03d}": n for c, n in sorted(seen.rows.items())},
            "skipped_blocks": seen.skipped.count,
            "parts": sorted(parts, key=lambda p: p["path"].rsplit("/", 1)[1]), "msdc": software_version(),
            "ingested_at": dt.datetime.now(dt.UTC).isoformat(timespec="seconds"),
            "options": {"categories": cats, "editions": settings.edition_args,
                        "date": None if settings.date is None else str(settings.date),
                        "format": settings.format}}
    return record, warnings, seen.skipped


@dataclass
class _Seen:
    """What the main process folds of an input's decoded chunks: the warnings' tallies, rows, editions and
    skipped blocks."""

    tally: object
    account: object
    failed: dict
    skipped: SkippedBlocks
    rows: dict[int, int] = field(default_factory=dict)
    editions: dict[int, str] = field(default_factory=dict)
    fmt: str | None = None
    date: dt.date | None = None

    def fold(self, rec, rows: dict[int, int]) -> None:
        from msdc.pipeline.model import editions as edition_notes

        self.fmt, self.date = rec.format, self.date or rec.date
        self.editions.update({int(c): e for c, e in rec.editions.items() if e})
        s = self.skipped
        s.count += len(rec.errors)
        s.length_bytes += int(rec.errors["length"].sum()) if len(rec.errors) else 0
        kept = rec.errors.iloc[:max(BLOCKS_KEPT - len(s.blocks), 0)]
        s.blocks += [(int(o), str(r)) for o, r in zip(kept["offset"], kept["reason"], strict=True)]
        self.tally.add(rec.frames)
        self.account.add(rec)
        edition_notes.fold(self.failed, rec)
        for c, n in rows.items():
            self.rows[c] = self.rows.get(c, 0) + n


def _stream(path: Path, label: str, settings: IngestSettings, root: Path, iid: str,
            cats: list[int], pool, seen: _Seen, on_chunk) -> list[dict]:
    """The input streamed in chunks (asterix.iter_read) into one writer: its parts' records."""
    import msdc.asterix as asterix
    from msdc.pipeline.dataset.writer import InputWriter
    from msdc.pipeline.report.record_schema import record_schema

    writer = InputWriter(root, iid, {c: record_schema(c).arrow() for c in cats})
    bar = (lambda done, total, what: on_chunk(done, total, f"{path.name}: {what}")) if on_chunk else None
    try:
        for rec in asterix.iter_read(path, chunk=settings.chunk_bytes,
                                     editions=settings.editions or None, date=settings.date,
                                     format=settings.format, categories=cats, progress=bar, pool=pool):
            seen.fold(rec, writer.add_recording(rec, label))
        return writer.finish()
    except BaseException:
        writer.abort()
        raise


def _windows(path: Path, label: str, settings: IngestSettings, root: Path, iid: str,
             cats: list[int], pool, seen: _Seen, futures: list, on_chunk) -> list[dict] | None:
    """A raw recording's windows decoded and written in the pool (dataset.windows), at most two per
    process in flight; their parts' records, or None when the recording is not one whose windows decode
    apart (asterix.stream.plan_windows)."""
    from msdc.asterix.stream import plan_windows
    from msdc.pipeline.dataset.windows import write_window

    planned = plan_windows(path, pool, chunk=settings.chunk_bytes,
                           editions=settings.editions or None, date=settings.date, categories=cats,
                           format=settings.format)
    if planned is None:
        return None
    plan, windows = planned
    ahead = 2 * max(settings.workers, 1)
    parts: list[dict] = []
    size = path.stat().st_size
    pending: deque = deque()

    def fold_oldest() -> None:
        got, rows, rec = pending.popleft().result()
        parts.extend(got)
        seen.fold(rec, rows)
        if on_chunk:  # the share of the windows done
            on_chunk(size * (len(futures) - len(pending)) // len(windows), size, f"{path.name}: decoding")

    for window in windows:
        futures.append(pool.submit(write_window, str(path), plan, window, label, root, iid, cats))
        pending.append(futures[-1])
        if len(pending) >= ahead:
            fold_oldest()
    while pending:
        fold_oldest()
    return parts


__all__ = ["IngestFailed", "IngestSettings", "SkippedBlocks", "ingest_input"]
