"""The ingest job (``msdc ingest``): recordings decoded in chunks into a Parquet dataset partitioned by UTC
day, category and sensor (pipeline.dataset), each input committed whole: its parts renamed into place,
then its record written to the manifest. An input already in the manifest (same SHA-256) is not ingested
again; what an interrupted ingest left (parts of an input the manifest does not list) is removed first."""

from __future__ import annotations

import datetime as dt
import fcntl
import os
from collections import deque
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path

from msdc.pipeline.jobs.common import Checked, JobError, OptionError, check_decoding, nonempty_path
from msdc.pipeline.jobs.options import (
    DEFAULT_CATEGORIES,
    DecodingOptions,
    IngestOptions,
    check_declared,
)

# what the pool's processes import (about 0.6 s of CPU each), imported once by the forkserver they fork from
POOL_PRELOAD = ("msdc.pipeline.dataset.windows", "msdc.asterix.stream", "msdc.pipeline.model.editions",
                "pyarrow.parquet")


def validate(options: IngestOptions) -> tuple[Checked, Path]:
    """Check every option, the inputs and the dataset folder before anything is read or written: the
    inputs (duplicates dropped) and the folder; OptionError if bad."""
    check_declared(options)
    if options.dataset is None:
        raise OptionError("--dataset is required")
    nonempty_path("--dataset", options.dataset)
    checked = check_decoding(DecodingOptions(inputs=options.inputs, editions=options.editions,
                                             date=options.date, format=options.format))
    root = Path(options.dataset)
    if root.exists() and not root.is_dir():
        raise OptionError(f"--dataset {root}: is a file, not a folder")
    parent = root if root.exists() else root.parent
    if not parent.is_dir():
        raise OptionError(f"--dataset {root}: folder {parent} does not exist")
    if not os.access(parent, os.W_OK):
        raise OptionError(f"--dataset {root}: not writable")
    for p in checked.inputs:
        if root.resolve() in p.resolve().parents:
            raise OptionError(f"{p}: an input inside the dataset folder {root}")
    return checked, root


@dataclass
class IngestResult:
    """What an ingest did: the inputs ingested now (their manifest records), those already in the dataset
    (path, why), the files of an interrupted ingest removed first, and the warnings."""

    dataset: Path
    ingested: list[dict] = field(default_factory=list)
    skipped: list[tuple[str, str]] = field(default_factory=list)
    discarded: list[Path] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)


def ingest_job(options: IngestOptions, *, on_chunk: Callable[[int, int, str], None] | None = None
               ) -> IngestResult:
    """Ingest every input not in the dataset yet, one after the other, ``options.workers`` processes
    decoding each raw recording's chunks (asterix.iter_read's pool). A failure removes the parts of the
    input being ingested; the inputs committed before it stay (run again to go on). JobError for bad or
    unreadable input, OptionError for bad options."""
    from msdc.asterix.errors import UnreadableInput
    from msdc.asterix.verdict import sniff
    from msdc.pipeline.dataset import manifest as mf
    from msdc.pipeline.model.load import sha256

    checked, root = validate(options)
    for path in checked.inputs:  # a file that is not ASTERIX at all is said before anything is written
        try:
            said = sniff(path, options.format)
        except UnreadableInput as exc:
            raise JobError(str(exc), 2) from exc
        if said and not options.lenient:
            raise JobError(f"{said}; nothing ingested (--lenient ingests it anyway)")
    made = not root.exists()
    result = IngestResult(root, warnings=list(checked.warnings))
    try:
        with _locked(root), _pool(options.workers) as pool:
            try:
                manifest = mf.load(root)
            except mf.ManifestError as exc:
                raise JobError(str(exc), 2) from None
            result.discarded = mf.discard_unlisted(root, manifest)
            labels = manifest.labels()
            for path in checked.inputs:
                digest = sha256(path)
                if digest in manifest.inputs:
                    rec = manifest.inputs[digest]
                    result.skipped.append((str(path), f"already in the dataset (same SHA-256 as "
                                                      f"{rec['file']}, ingested {rec['ingested_at']}): "
                                                      "nothing to do"))
                    continue
                label = path.name if labels.get(path.name, digest) == digest else str(path.resolve())
                labels[label] = digest
                record = _ingest_one(path, digest, label, options, checked, root, pool, on_chunk, result)
                manifest.inputs[digest] = record
                manifest.msdc = record["msdc"]
                mf.save(root, manifest)  # last: the input is in the dataset from now on
                result.ingested.append(record)
    except BaseException:
        if made and not any(root.glob("date=*")) and not (root / mf.MANIFEST).exists():
            _remove_made(root)  # the folder this run made, holding nothing: as it was, absent
        raise
    return result


def _ingest_one(path: Path, digest: str, label: str, options: IngestOptions, checked: Checked, root: Path,
                pool, on_chunk, result: IngestResult) -> dict:
    """Decode one input into its parts and return its manifest record; every file of it removed on failure.
    With a pool, a raw recording's windows are decoded and written in the pool's processes (_windows);
    anything else streams here (its chunks decoded in the pool when it is a raw stream)."""
    from msdc.asterix.errors import UnreadableInput
    from msdc.asterix.verdict import Tally, head_of
    from msdc.pipeline.dataset.layout import input_files, input_id
    from msdc.pipeline.dataset.manifest import prune_empty
    from msdc.pipeline.dataset.writer import Undated
    from msdc.pipeline.meta import software_version
    from msdc.pipeline.model import editions as edition_notes
    from msdc.pipeline.model.time import FirstDayTally

    cats = sorted(set(options.categories or DEFAULT_CATEGORIES))
    size = path.stat().st_size
    seen = _Seen(FirstDayTally(), Tally(str(path)), {})
    iid = input_id(digest)
    futures: list = []
    try:
        parts = None if pool is None else _windows(path, label, options, checked, root, iid, cats, pool, seen,
                                                    futures, on_chunk)
        if parts is None:
            parts = _stream(path, label, options, checked, root, iid, cats, pool, seen, on_chunk)
        content = seen.account.warnings(head_of(path), hint=False, detected=options.format is None)
        if content and not options.lenient:
            raise JobError("; ".join(content) + "; nothing ingested from it (--lenient ingests it anyway)")
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
            raise JobError(str(exc), 2) from exc
        if isinstance(exc, Undated):
            raise JobError(f"{path}: {exc}: give --date YYYY-MM-DD (the dataset's partitions are UTC days); "
                           "nothing ingested from it") from None
        raise
    if on_chunk:
        on_chunk(size, size, f"{path.name}: decoding")
    result.warnings += content + seen.tally.warning(label, seen.date, seen.fmt) + edition_notes.warnings(
        seen.failed)
    if not seen.rows:
        result.warnings.append(f"{path}: no record of {', '.join(f'CAT{c:03d}' for c in cats)} decoded; "
                               "recorded as ingested, with no part")
    return {"sha256": digest, "file": label, "path": str(path.resolve()), "size_bytes": size,
            "format": seen.fmt, "date": None if seen.date is None else seen.date.isoformat(),
            "editions": {f"{c:03d}": e for c, e in sorted(seen.editions.items()) if c in seen.rows},
            "rows": {f"{c:03d}": n for c, n in sorted(seen.rows.items())}, "skipped_blocks": seen.skipped,
            "parts": sorted(parts, key=lambda p: p["path"].rsplit("/", 1)[1]), "msdc": software_version(),
            "ingested_at": dt.datetime.now(dt.UTC).isoformat(timespec="seconds"),
            "options": {"categories": cats, "editions": list(options.editions),
                        "date": None if options.date is None else str(options.date),
                        "format": options.format}}


@dataclass
class _Seen:
    """What the main process folds of an input's decoded chunks: the warnings' tallies, rows, editions."""

    tally: object
    account: object
    failed: dict
    rows: dict[int, int] = field(default_factory=dict)
    editions: dict[int, str] = field(default_factory=dict)
    fmt: str | None = None
    date: dt.date | None = None
    skipped: int = 0

    def fold(self, rec, rows: dict[int, int]) -> None:
        from msdc.pipeline.model import editions as edition_notes

        self.fmt, self.date = rec.format, self.date or rec.date
        self.editions.update({int(c): e for c, e in rec.editions.items() if e})
        self.skipped += len(rec.errors)
        self.tally.add(rec.frames)
        self.account.add(rec)
        edition_notes.fold(self.failed, rec)
        for c, n in rows.items():
            self.rows[c] = self.rows.get(c, 0) + n


def _stream(path: Path, label: str, options: IngestOptions, checked: Checked, root: Path, iid: str,
            cats: list[int], pool, seen: _Seen, on_chunk) -> list[dict]:
    """The input streamed in chunks (asterix.iter_read) into one writer: its parts' records."""
    import msdc.asterix as asterix
    from msdc.pipeline.dataset.writer import InputWriter, arrow_schema

    writer = InputWriter(root, iid, {c: arrow_schema(c) for c in cats})
    bar = (lambda done, total, what: on_chunk(done, total, f"{path.name}: {what}")) if on_chunk else None
    try:
        for rec in asterix.iter_read(path, chunk=max(int(options.chunk_mb * 1e6), 1),
                                     editions=checked.editions or None, date=options.date,
                                     format=options.format, categories=cats, progress=bar, pool=pool):
            seen.fold(rec, writer.add_recording(rec, label))
        return writer.finish()
    except BaseException:
        writer.abort()
        raise


def _windows(path: Path, label: str, options: IngestOptions, checked: Checked, root: Path, iid: str,
             cats: list[int], pool, seen: _Seen, futures: list, on_chunk) -> list[dict] | None:
    """A raw recording's windows decoded and written in the pool (dataset.windows), at most two per
    process in flight; their parts' records, or None when the recording is not one whose windows decode
    apart (asterix.stream.plan_windows)."""
    from msdc.asterix.stream import plan_windows
    from msdc.pipeline.dataset.windows import write_window

    planned = plan_windows(path, pool, chunk=max(int(options.chunk_mb * 1e6), 1),
                           editions=checked.editions or None, date=options.date, categories=cats,
                           format=options.format)
    if planned is None:
        return None
    plan, windows = planned
    ahead = 2 * max(options.workers, 1)
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


def _abort(writer, prune_empty, root: Path) -> None:
    """Remove every file of the input being written, and the folders it leaves empty."""
    writer.abort()
    prune_empty(root, {p.parent for p in writer.files})


@contextmanager
def _locked(root: Path) -> Iterator[None]:
    """The dataset folder (made if absent) held by this ingest alone: another one fails at once. The lock
    dies with the process, however it ends (SIGKILL included)."""
    from msdc.pipeline.dataset.layout import LOCK

    root.mkdir(exist_ok=True)
    fh = open(root / LOCK, "a")  # noqa: SIM115 - held for the block
    try:
        try:
            fcntl.flock(fh.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            raise JobError(f"--dataset {root}: another msdc ingest is writing it") from None
        yield
    finally:
        fh.close()


@contextmanager
def _pool(workers: int):
    """A process pool of ``workers`` (None for one: the chunks decode in this process). Its processes start
    from a fresh server process (forkserver), not forked from this one's threads; the server imports what
    they run first (POOL_PRELOAD), once for all of them."""
    if workers <= 1:
        yield None
        return
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor

    ctx = multiprocessing.get_context("forkserver")
    ctx.set_forkserver_preload(list(POOL_PRELOAD))
    pool = ProcessPoolExecutor(workers, mp_context=ctx)
    try:
        yield pool
    finally:
        pool.shutdown(wait=True, cancel_futures=True)


def _remove_made(root: Path) -> None:
    """Remove the dataset folder this run made, when it holds only the lock and empty folders."""
    from msdc.pipeline.dataset.layout import LOCK

    (root / LOCK).unlink(missing_ok=True)
    for d in sorted((p for p in root.rglob("*") if p.is_dir()), key=lambda p: len(p.parts), reverse=True):
        try:
            d.rmdir()
        except OSError:
            return
    try:
        root.rmdir()
    except OSError:
        pass


def summary_lines(result: IngestResult) -> list[str]:
    """What the ingest did, a line per input."""
    lines = []
    for rec in result.ingested:
        counts = ", ".join(f"CAT{c}: {n}" for c, n in rec["rows"].items()) or "no record"
        lines.append(f"{rec['path']}: {counts} -> {len(rec['parts'])} part(s) in {result.dataset}")
    lines += [f"{path}: {why}" for path, why in result.skipped]
    return lines


__all__ = ["IngestOptions", "IngestResult", "ingest_job", "summary_lines", "validate"]
