"""Per-item figures (one per aircraft, one per alert) drawn in parallel: a process pool sized to the cores,
each task carrying only its own figure's data and at most a few tasks in flight per worker, so that memory
stays bounded whatever the number of figures; a progress bar on a terminal; a figure that fails is named
with its reason (FigureError; an OSError, which names its file, as it is), never a traceback."""

from __future__ import annotations

import concurrent.futures as cf
import gc
import multiprocessing
import signal
import time
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass, field
from pathlib import Path

from msdc.asterix.threads import process_cpus
from msdc.pipeline.progress import Progress

# matplotlib and the drawing modules loaded once in the fork server: workers forked from it start in
# ~0.1 s instead of importing them again (~1.5 s each); figure_server last: it freezes what they loaded
PRELOAD = ("msdc.pipeline.report.track_figures", "msdc.pipeline.report.conflict_figures",
           "msdc.pipeline.report.figure_server")
IN_FLIGHT_PER_WORKER = 2  # tasks handed to the pool per worker: one drawing, one waiting
MAX_WORKERS = 8  # each ~125 MB RSS, ~70 MB of it its own (the real hour): 8 stay under ~1 GB on a big machine
# a worker is replaced after this many figures (forked from the server in ~0.1 s): matplotlib's caches and
# Python's heap still grow by ~10 MB over 20 of the real hour's track figures, garbage collected after each
TASKS_PER_WORKER = 20
SERIAL_BELOW = 3  # fewer figures than this are drawn in this process: starting workers costs more


class FigureError(RuntimeError):
    """A figure could not be drawn: which one and why."""


@dataclass(frozen=True)
class FigureTask:
    """One figure: its file name, the module-level function drawing it and that function's arguments (only
    this figure's data: they are pickled to the worker)."""

    name: str
    draw: Callable[..., Path]
    kwargs: dict = field(default_factory=dict)


def cores() -> int:
    """The figure workers: one per CPU this process may run on (taskset), at most MAX_WORKERS."""
    return max(1, min(process_cpus(), MAX_WORKERS))


def _context() -> multiprocessing.context.BaseContext:
    """forkserver where the platform has it (workers start from a clean server, not a copy of this
    process with its decoded data and threads), else spawn."""
    method = "forkserver" if "forkserver" in multiprocessing.get_all_start_methods() else "spawn"
    ctx = multiprocessing.get_context(method)
    if method == "forkserver":
        ctx.set_forkserver_preload(list(PRELOAD))
    return ctx


def _worker_start() -> None:
    """Ctrl-C and termination are the parent's to handle: it cancels the pool and cleans its outputs."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def _run(task: FigureTask) -> Path:
    """Draw one figure (in a worker, or here)."""
    return task.draw(**task.kwargs)


def _run_and_collect(task: FigureTask) -> Path:
    """Draw one figure in a worker, then collect its garbage: a figure's artists refer to each other, so
    without a collection its canvas and data wait for the oldest generation's turn (the real hour's 20
    figures a worker: +49 MB, against +10 MB collected after each)."""
    try:
        return _run(task)
    finally:
        gc.collect()


def _failed(task: FigureTask, exc: BaseException) -> FigureError:
    reason = str(exc).strip() or type(exc).__name__
    return FigureError(f"figure {task.name} could not be drawn: {type(exc).__name__}: {reason}")


def render(tasks: Iterable[FigureTask], total: int, *, workers: int | None = None,
           progress: Progress | None = None, label: str = "figures") -> list[Path]:
    """Draw every task's figure (``total`` of them), in parallel on ``workers`` processes (default:
    ``cores()``; 1, or fewer than SERIAL_BELOW figures: in this process). The tasks are made as the pool
    takes them, so only IN_FLIGHT_PER_WORKER figures' data per worker exist at once. Returns the paths in
    task order; FigureError naming the first figure that failed (the others are cancelled)."""
    workers = cores() if workers is None else max(int(workers), 1)
    workers = min(workers, total)
    started = time.monotonic()
    bar = (lambda done: progress.bar(done, total, label, unit="figures", since=started)) if progress else None
    if workers <= 1 or total < SERIAL_BELOW:
        return list(_serial(tasks, bar))
    give_back_freed_memory()
    return _parallel(iter(tasks), workers, bar)


def give_back_freed_memory() -> None:
    """Collect garbage and return the heap's free pages to the system (glibc's malloc_trim, and Arrow's
    pool, which holds pandas' strings) before the workers start: what the run freed (decoding, tracking)
    otherwise stays in this process's RSS while the figures are drawn beside it (the real hour: -18 MB
    from Arrow's pool)."""
    import ctypes
    import sys

    gc.collect()
    try:
        ctypes.CDLL("libc.so.6").malloc_trim(0)
    except (OSError, AttributeError):  # not glibc: nothing to trim
        pass
    arrow = sys.modules.get("pyarrow")  # only if the run loaded it
    if arrow is not None:
        arrow.default_memory_pool().release_unused()


def _serial(tasks: Iterable[FigureTask], bar) -> Iterator[Path]:
    for done, task in enumerate(tasks, start=1):
        try:
            yield _run(task)
        except OSError:  # names the file (the output transaction spells it as the user gave it)
            raise
        except Exception as exc:  # noqa: BLE001 - any failure of matplotlib or of the data: named
            raise _failed(task, exc) from exc
        if bar:
            bar(done)


def _parallel(tasks: Iterator[FigureTask], workers: int, bar) -> list[Path]:
    """The pool's loop: keep workers * IN_FLIGHT_PER_WORKER tasks submitted, collect as they finish."""
    paths: dict[int, Path] = {}
    pending: dict[cf.Future, tuple[int, FigureTask]] = {}
    pool = cf.ProcessPoolExecutor(max_workers=workers, mp_context=_context(), initializer=_worker_start,
                                  max_tasks_per_child=TASKS_PER_WORKER)
    try:
        index = 0
        while True:
            while len(pending) < workers * IN_FLIGHT_PER_WORKER:
                task = next(tasks, None)
                if task is None:
                    break
                pending[pool.submit(_run_and_collect, task)] = (index, task)
                index += 1
            if not pending:
                break
            done, _ = cf.wait(pending, return_when=cf.FIRST_COMPLETED)
            for future in done:
                i, task = pending.pop(future)
                try:
                    paths[i] = future.result()
                except cf.process.BrokenProcessPool as exc:
                    raise FigureError(f"figure {task.name} could not be drawn: a figure process ended "
                                      "abruptly (out of memory?)") from exc
                except OSError:  # the worker's, naming the file: as in one process
                    raise
                except Exception as exc:  # noqa: BLE001 - the worker's error, pickled back: named
                    raise _failed(task, exc) from exc
                if bar:
                    bar(len(paths))
    finally:
        pool.shutdown(wait=True, cancel_futures=True)
    return [paths[i] for i in range(len(paths))]
