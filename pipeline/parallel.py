"""Per-aircraft work on a few threads (the tracking kernels release the GIL, so aircraft overlap), or as tasks
on a cluster when a job installed a distributor (``distributed_by``; pipeline.dataset.cluster)."""

from __future__ import annotations

import threading
from collections import deque
from collections.abc import Callable, Iterable, Iterator
from concurrent.futures import ThreadPoolExecutor
from contextlib import contextmanager
from contextvars import ContextVar
from typing import Protocol, TypeVar

from msdc.asterix.threads import process_cpus

T = TypeVar("T")
R = TypeVar("R")
MAX_THREADS = 8  # past this the Python (GIL) part of each aircraft's work is the limit
PREFIX = "msdc"  # the pool threads' names: work mapped from inside one runs in that thread


class Distributor(Protocol):
    """Runs ``fn`` over items as tasks elsewhere (other processes or machines), the results in the items'
    order; ``label`` names an item in progress and failure messages."""

    def map_ordered(self, fn: Callable[[T], R], items: Iterable[T],
                    label: Callable[[T], str] | None = None, fresh_after: int | None = None
                    ) -> Iterator[R]: ...


_DISTRIBUTOR: ContextVar[Distributor | None] = ContextVar("msdc_distributor", default=None)


@contextmanager
def distributed_by(distributor: Distributor | None) -> Iterator[None]:
    """Within the block, ``map_ordered(..., distributable=True)`` runs on ``distributor`` (None: threads)."""
    token = _DISTRIBUTOR.set(distributor)
    try:
        yield
    finally:
        _DISTRIBUTOR.reset(token)


def distributed_now() -> bool:
    """Whether ``map_ordered(..., distributable=True)`` called here would run on a distributor."""
    return _DISTRIBUTOR.get() is not None and not threading.current_thread().name.startswith(PREFIX)


def thread_count() -> int:
    """The threads per-aircraft work uses: the CPUs this process may run on (taskset), at most
    MAX_THREADS."""
    return max(1, min(process_cpus(), MAX_THREADS))


def map_ordered(fn: Callable[[T], R], items: Iterable[T], threads: int | None = None, *,
                distributable: bool = False, label: Callable[[T], str] | None = None,
                fresh_after: int | None = None) -> Iterator[R]:
    """fn over items on up to ``threads`` threads (default `thread_count`), the results in the items'
    order; at most two items per thread are taken ahead, so a lazy iterable stays lazy. fn must not
    touch what another item's call writes. Called from one of its own threads (an aircraft's work that
    maps again) it runs in that thread: no pool inside a pool. ``distributable``: fn and each item are
    small enough to ship (fn holds no frame of the whole run), so an installed distributor runs them;
    ``fresh_after``: there, a worker process is restarted after that many of these tasks (large ones whose
    leftovers in the process's heap would add up)."""
    if distributable and distributed_now():
        yield from _DISTRIBUTOR.get().map_ordered(fn, items, label, fresh_after)
        return
    n = thread_count() if threads is None else threads
    if n <= 1 or threading.current_thread().name.startswith(PREFIX):
        yield from map(fn, items)
        return
    with ThreadPoolExecutor(n, thread_name_prefix=PREFIX) as pool:
        pending: deque = deque()
        for item in items:
            pending.append(pool.submit(fn, item))
            if len(pending) >= 2 * n:
                yield pending.popleft().result()
        while pending:
            yield pending.popleft().result()
