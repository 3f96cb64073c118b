"""The ingest job (``msdc ingest``): recordings decoded in chunks into a Parquet dataset partitioned by UTC
day, category and sensor (pipeline.dataset), each input committed whole: its parts renamed into place,
then its record written to the manifest. An input already in the manifest (same SHA-256) is not ingested
again; what an interrupted ingest left (parts of an input the manifest does not list) is removed first."""

from __future__ import annotations

import fcntl
import os
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path

from msdc.pipeline.jobs.common import (
    Checked,
    JobError,
    OptionError,
    check_decoding,
    first_missing,
    nonempty_path,
    remove_if_empty,
    writable_dataset,
)
from msdc.pipeline.jobs.options import INGEST_CATEGORIES, DecodingOptions, IngestOptions, check_declared

# what the pool's processes import (about 0.6 s of CPU each), imported once by the forkserver they fork from,
# then the decoder's compiled kernels loaded there (dataset.warm: about 1 s of CPU each)
POOL_PRELOAD = ("msdc.pipeline.dataset.windows", "msdc.asterix.stream", "msdc.pipeline.model.editions",
                "pyarrow.parquet", "msdc.pipeline.dataset.parallel", "msdc.pipeline.dataset.ingest_input",
                "msdc.pipeline.dataset.warm")


def validate(options: IngestOptions) -> tuple[Checked, Path]:
    """Check every option, the inputs and the dataset folder before anything is read or written: the
    inputs (duplicates dropped) and the folder; OptionError if bad."""
    check_declared(options)
    if options.dataset is None:
        raise OptionError("--dataset is required")
    nonempty_path("--dataset", options.dataset)
    checked = check_decoding(DecodingOptions(inputs=options.inputs, editions=options.editions,
                                             date=options.date, format=options.format))
    root = writable_dataset(options.dataset)
    for p in checked.inputs:
        if root.resolve() in p.resolve().parents:
            raise OptionError(f"{p}: an input inside the dataset folder {root}")
    return checked, root


@dataclass
class IngestResult:
    """What an ingest did: the inputs ingested now (their manifest records) and the blocks they skipped as
    damaged, those already in the dataset (path, why), the files of an interrupted ingest removed first, and
    the warnings."""

    dataset: Path
    ingested: list[dict] = field(default_factory=list)
    damaged: list = field(default_factory=list)  # dataset.ingest_input.SkippedBlocks of each input ingested
    skipped: list[tuple[str, str]] = field(default_factory=list)
    discarded: list[Path] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)


def ingest_job(options: IngestOptions, *, on_chunk: Callable[[int, int, str], None] | None = None
               ) -> IngestResult:
    """Ingest every input not in the dataset yet (keyed by the SHA-256 validation hashed). With
    ``options.workers`` > 1 the inputs are checked in a process pool; then, when the command names at least as
    many inputs (distinct files, ingested already or not) as workers, each pool process ingests whole inputs
    (dataset.parallel), else the inputs
    are ingested one after the other, a raw recording's windows decoded and written in the pool. Either
    way the inputs are committed in input order. A failure removes the parts of the input that failed (and
    of those after it); the inputs before it are committed (run again to go on). JobError for bad or
    unreadable input, OptionError for bad options."""
    from msdc.asterix.errors import UnreadableInput
    from msdc.asterix.verdict import sniff
    from msdc.pipeline.dataset import manifest as mf
    from msdc.pipeline.dataset.ingest_input import IngestFailed, IngestSettings, ingest_input
    from msdc.pipeline.dataset.layout import LOCK
    from msdc.pipeline.dataset.parallel import check_inputs, ingest_all
    from msdc.pipeline.model.load import sha256

    check_declared(options)
    if options.workers > 1:  # the pool's server starts now: its imports overlap the hashing below
        _forkserver()
    checked, root = validate(options)
    if options.workers <= 1:
        for path in checked.inputs:  # a file that is not ASTERIX at all is said before anything is written
            try:
                said = sniff(path, options.format)
            except UnreadableInput as exc:
                raise JobError(str(exc), 2) from exc
            _refuse(said, options)
    made = first_missing(root)  # the folder itself: validate found its parent
    result = IngestResult(root, warnings=list(checked.warnings))
    try:
        with _locked(root), _pool(options.workers) as pool:
            try:
                manifest = mf.load(root)
            except mf.ManifestError as exc:
                raise JobError(str(exc), 2) from None
            settings = IngestSettings(sorted(set(options.categories or INGEST_CATEGORIES)),
                                      max(int(options.chunk_mb * 1e6), 1), checked.editions,
                                      list(options.editions), options.date, options.format, options.lenient,
                                      options.workers)
            if pool is not None:  # the checks above, in the pool, still before anything is written
                check_inputs(pool.executor, checked.inputs, options.format,
                             lambda said: _refuse(said, options))
            digests = [checked.digests.get(path) or sha256(path) for path in checked.inputs]
            result.discarded = mf.discard_unlisted(root, manifest)
            todo, skipped = _plan(checked.inputs, digests, manifest)

            def commit(record: dict, warnings: list[str], skipped) -> None:
                result.warnings += warnings
                result.damaged.append(skipped)
                manifest.inputs[record["sha256"]] = record
                manifest.msdc = record["msdc"]
                mf.save(root, manifest)  # last: the input is in the dataset from now on
                result.ingested.append(record)

            # whole inputs or windows by the command's inputs, not by those left: a run resumed after a kill
            # writes each input's parts as the uninterrupted run did
            if pool is not None and len(set(digests)) >= options.workers:
                ingest_all(todo, settings, root, pool.executor, pool.stop, pool.progress, commit, on_chunk)
            else:
                for t in todo:
                    commit(*ingest_input(t.path, t.digest, t.label, settings, root,
                                         None if pool is None else pool.executor, on_chunk))
            for path, digest in skipped:
                rec = manifest.inputs[digest]
                result.skipped.append((str(path), f"already in the dataset (same SHA-256 as {rec['file']}, "
                                                  f"ingested {rec['ingested_at']}): nothing to do"
                                                  + _options_not_applied(rec, settings)))
    except BaseException as exc:
        # the folder this run made, holding nothing but its lock (and partition folders a run stopped before
        # its first part made): as it was, absent
        remove_if_empty(made, besides=(LOCK,))
        if isinstance(exc, IngestFailed):
            raise JobError(str(exc), exc.status) from None
        raise
    return result


_OPTION_FLAGS = {"date": "--date", "format": "--format", "editions": "--edition", "categories": "--category"}


def _options_not_applied(record: dict, settings) -> str:
    """What an input skipped as already ingested was given now that its ingest was not (its manifest
    record's options): the rows keep the options they were ingested with, which the skip would hide."""
    now = {"date": None if settings.date is None else str(settings.date), "format": settings.format,
           "editions": list(settings.edition_args), "categories": list(settings.categories)}
    then = record.get("options") or {}

    def shown(key: str, value) -> str:
        if value is None or value == []:
            return "none" if key != "format" else "auto"
        return ",".join(map(str, value)) if isinstance(value, list) else str(value)

    differ = [f"{_OPTION_FLAGS[k]} {shown(k, now[k])} now, {shown(k, then.get(k))} then"
              for k in now if k in then and now[k] != then.get(k)]
    if not differ:
        return ""
    return (f"; its rows keep the options it was ingested with ({'; '.join(differ)}): to apply these, "
            "ingest it into another dataset")


def _refuse(said: str | None, options: IngestOptions) -> None:
    """JobError for an input that is not ASTERIX at all (asterix.verdict.sniff's ``said``), unless
    --lenient."""
    if said and not options.lenient:
        raise JobError(f"{said}; nothing ingested (--lenient ingests it anyway)")


def _plan(paths: list[Path], digests: list[str], manifest) -> tuple[list, list[tuple[Path, str]]]:
    """The inputs to ingest (dataset.parallel.Todo, in input order, each with its ``file`` label: its name,
    or its resolved path when an input of another content has that name) and those skipped (path, SHA-256):
    already in the dataset, or the same bytes as an input before them."""
    from msdc.pipeline.dataset.parallel import Todo
    from msdc.pipeline.model.sources import path_text

    labels = manifest.labels()
    todo, skipped, planned = [], [], set()
    for index, (path, digest) in enumerate(zip(paths, digests, strict=True)):
        if digest in manifest.inputs or digest in planned:
            skipped.append((path, digest))
            continue
        name = path_text(path.name)
        label = name if labels.get(name, digest) == digest else path_text(path.resolve())
        labels[label] = digest
        planned.add(digest)
        todo.append(Todo(index, path, digest, label, path.stat().st_size))
    return todo, skipped


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


@dataclass
class _Pool:
    """The pool's processes, the index above which inputs stop (dataset.parallel) and the queue of their
    progress."""

    executor: object
    stop: object
    progress: object


@contextmanager
def _pool(workers: int) -> Iterator[_Pool | None]:
    """A process pool of ``workers`` (None for one: everything runs in this process). Its processes start
    from a fresh server process (forkserver), not forked from this one's threads; the server imports what
    they run first (POOL_PRELOAD), once for all of them. They die with the forkserver, so with this process
    (dataset.parallel.worker_start)."""
    if workers <= 1:
        yield None
        return
    from concurrent.futures import ProcessPoolExecutor

    from msdc.pipeline.dataset.parallel import NO_STOP, worker_start

    ctx = _forkserver()
    stop, progress = ctx.Value("q", NO_STOP), ctx.Queue()
    pool = ProcessPoolExecutor(workers, mp_context=ctx, initializer=worker_start, initargs=(stop, progress))
    try:
        yield _Pool(pool, stop, progress)
    finally:
        pool.shutdown(wait=True, cancel_futures=True)
        progress.close()


def _forkserver():
    """The forkserver context, its server started (if not yet) with POOL_PRELOAD: it imports them while this
    process goes on."""
    import multiprocessing
    from multiprocessing import forkserver

    from msdc.pipeline.dataset.warm import WARM_ENV

    ctx = multiprocessing.get_context("forkserver")
    ctx.set_forkserver_preload(list(POOL_PRELOAD))
    os.environ[WARM_ENV] = "1"  # the server starts with it: dataset.warm warms there, and only there
    try:
        forkserver.ensure_running()
    finally:
        os.environ.pop(WARM_ENV, None)
    return ctx


def skipped_lines(result: IngestResult) -> list[str]:
    """The blocks each input ingested skipped as damaged (stderr): one line each (path, offset, reason) as
    msdc decode lists them, how many more, then their count and bytes."""
    lines = []
    for s in result.damaged:
        lines += [f"{s.path}: offset {offset}: {reason}" for offset, reason in s.blocks]
        if s.count > len(s.blocks):
            lines.append(f"{s.path}: {s.count - len(s.blocks)} more skipped block(s) ('msdc stats' groups "
                         "them by reason)")
        if s.count:
            lines.append(f"{s.path}: {s.count} block(s) skipped ({s.length_bytes} bytes): their records are "
                         "not in the dataset")
    return lines


def summary_lines(result: IngestResult) -> list[str]:
    """What the ingest did, a line per input."""
    lines = []
    for rec in result.ingested:
        counts = ", ".join(f"CAT{c}: {n}" for c, n in rec["rows"].items()) or "no record"
        lines.append(f"{rec['path']}: {counts} -> {len(rec['parts'])} part(s) in {result.dataset}")
    lines += [f"{path}: {why}" for path, why in result.skipped]
    return lines


__all__ = ["IngestOptions", "IngestResult", "ingest_job", "skipped_lines", "summary_lines", "validate"]
