"""Several inputs of ``msdc ingest`` at once, each whole in a pool process: first every input's
not-ASTERIX check, in parallel; then each input's decoding and writing, streamed as one process streams it
(ingest_input with no pool), the largest inputs first. The main process commits each input (its manifest
record saved) in input order, once every input before it is committed, so the manifest is the one a single
process writes, whatever order the inputs end in, and a rerun after a kill ends with the same one."""

from __future__ import annotations

import os
import queue
import signal
from collections.abc import Callable
from concurrent.futures import FIRST_COMPLETED, wait
from dataclasses import dataclass
from pathlib import Path

from msdc.pipeline.dataset.ingest_input import IngestFailed, IngestSettings, SkippedBlocks

NO_STOP = 2**62  # the stop index while no input failed: no input's index is above it
POLL_S = 0.2  # how often the main process folds the pool's progress while it waits

# in a pool process: the shared index (multiprocessing.Value) above which inputs stop at their next chunk, and
# the queue where each input's bytes decoded so far are sent
_stop = None
_progress = None


class Stopped(RuntimeError):
    """An input stopped before its end because one before it failed or the run was interrupted."""


@dataclass(frozen=True)
class Todo:
    """An input to ingest: its place among the inputs (the order of commits, labels and warnings), path,
    SHA-256, ``file`` label and size."""

    index: int
    path: Path
    digest: str
    label: str
    size_bytes: int


def worker_start(stop, progress) -> None:
    """A pool process's start: keep the shared stop index and the progress queue, and watch the main
    process: when it ends (SIGKILL included) this one is killed, so that no pool process goes on writing
    parts that a rerun writes again (the forkserver does not end them: it lives as long as they do)."""
    import multiprocessing
    import threading

    global _stop, _progress
    _stop, _progress = stop, progress
    # Ctrl-C reaches the terminal's whole process group: the main process stops this one through ``stop``
    # (at its next chunk); ended by KeyboardInterrupt it printed multiprocessing's traceback
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    progress.cancel_join_thread()  # progress left unsent never holds a process's exit
    main = multiprocessing.parent_process()  # the process that asked for this one: its sentinel ends with it
    if main is not None:
        threading.Thread(target=_die_with, args=(main,), name="msdc-die-with-main", daemon=True).start()


def _die_with(main) -> None:
    """Wait for the main process to end, then kill this one."""
    main.join()
    os.kill(os.getpid(), signal.SIGKILL)


def check_input(path: str, format: str | None) -> str | None:
    """An input's not-ASTERIX verdict (asterix.verdict.sniff; None when it is ASTERIX or a container), in
    a pool process (which loads the decoder's compiled kernels on the way, as its decoding would)."""
    from msdc.asterix.verdict import sniff

    return sniff(path, format)


def ingest_whole(todo: Todo, settings: IngestSettings, root: Path) -> tuple[dict, list[str], SkippedBlocks]:
    """One input ingested whole in a pool process (streamed, its memory bounded by --chunk-mb): its
    manifest record, warnings and skipped blocks; Stopped when an input before it failed."""
    from msdc.pipeline.dataset.ingest_input import ingest_input

    def on_chunk(done: int, total: int, what: str) -> None:
        if _stop is not None and todo.index > _stop.value:
            raise Stopped(f"{todo.path}: stopped")
        if _progress is not None and what.endswith("decoding"):
            _progress.put((todo.index, done))

    return ingest_input(todo.path, todo.digest, todo.label, settings, root, None, on_chunk)


def check_inputs(pool, paths: list[Path], format: str | None, refuse: Callable[[str | None], None]) -> None:
    """Every input's verdict (check_input), in the pool, passed to ``refuse`` (which raises for an input
    refused) in input order; IngestFailed (status 2) for an input that cannot be read."""
    from msdc.asterix.errors import UnreadableInput

    futures = [pool.submit(check_input, str(p), format) for p in paths]
    try:
        for f in futures:
            refuse(f.result())
    except UnreadableInput as exc:
        raise IngestFailed(str(exc), 2) from exc
    finally:
        for f in futures:
            f.cancel()


def ingest_all(todo: list[Todo], settings: IngestSettings, root: Path, pool, stop, progress,
               commit: Callable[[dict, list[str], SkippedBlocks], None], on_chunk) -> None:
    """Ingest every input of ``todo`` (in input order) whole in the pool, the largest first, committing
    each (``commit(record, warnings, skipped)``) once those before it are. When one fails, the inputs after
    it stop and those before it end and are committed (the dataset a single process leaves), then its error
    is raised; whatever is not committed is removed."""
    from msdc.pipeline.dataset.layout import input_files, input_id
    from msdc.pipeline.dataset.manifest import prune_empty

    total = sum(t.size_bytes for t in todo) or 1
    label = f"{len(todo)} inputs, {settings.workers} processes: decoding"
    done_bytes = {t.index: 0 for t in todo}
    stop.value = NO_STOP
    futures = {pool.submit(ingest_whole, t, settings, root): t
               for t in sorted(todo, key=lambda t: (-t.size_bytes, t.index))}
    finished: dict[int, tuple[dict, list[str], SkippedBlocks]] = {}
    failed: dict[int, BaseException] = {}
    committed = 0  # the inputs of todo committed, in order
    pending = set(futures)
    try:
        while pending:
            ended, pending = wait(pending, timeout=POLL_S, return_when=FIRST_COMPLETED)
            for f in ended:
                t = futures[f]
                if f.cancelled():
                    continue
                if f.exception() is not None:
                    failed[t.index] = _said(t, f.exception())
                    _stop_after(min(failed), stop, futures)
                else:
                    finished[t.index] = f.result()
                    done_bytes[t.index] = t.size_bytes
            _fold_progress(progress, done_bytes, total, label, on_chunk)
            first_failed = min(failed, default=NO_STOP)
            while committed < len(todo) and todo[committed].index in finished \
                    and todo[committed].index < first_failed:
                commit(*finished.pop(todo[committed].index))
                committed += 1
        if failed:
            raise failed[min(failed)]
        if on_chunk:
            on_chunk(total, total, label)
    except BaseException:
        stop.value = -1  # every input still decoding stops at its next chunk
        for f in futures:
            f.cancel()
        wait(futures)  # the pool's writes end before the files are removed
        removed = [p for t in todo[committed:] for p in input_files(root, input_id(t.digest))]
        for p in removed:
            p.unlink(missing_ok=True)
        prune_empty(root, {p.parent for p in removed})
        raise


def _said(todo: Todo, exc: BaseException) -> BaseException:
    """An input's failure as raised: a pool process that died (killed, out of memory) breaks every input not
    yet ingested, said as an IngestFailed naming the first of them in input order."""
    from concurrent.futures.process import BrokenProcessPool

    if isinstance(exc, BrokenProcessPool):
        return IngestFailed(f"{todo.path}: nothing ingested from it: a pool process ended abruptly (killed, "
                            f"or out of memory?): {exc}")
    return exc


def _stop_after(index: int, stop, futures: dict) -> None:
    """The inputs after ``index`` (in input order) stop: those not started are cancelled, those decoding
    stop at their next chunk."""
    stop.value = index
    for f, t in futures.items():
        if t.index > index:
            f.cancel()


def _fold_progress(progress, done_bytes: dict[int, int], total: int, label: str, on_chunk) -> None:
    """Take the pool's progress messages (input index, bytes decoded) and move the bar over all inputs."""
    moved = False
    while True:
        try:
            index, done = progress.get_nowait()
        except queue.Empty:
            break
        done_bytes[index] = max(done_bytes[index], done)
        moved = True
    if on_chunk and moved:
        on_chunk(min(sum(done_bytes.values()), total - 1), total, label)


__all__ = ["Stopped", "Todo", "check_inputs", "ingest_all", "worker_start"]
