"""Per-aircraft work on a few threads: the tracking kernels release the GIL, so aircraft overlap."""

from __future__ import annotations

import os
import threading
from collections import deque
from collections.abc import Callable, Iterable, Iterator
from concurrent.futures import ThreadPoolExecutor
from typing import TypeVar

T = TypeVar("T")
R = TypeVar("R")
MAX_THREADS = 8  # past this the Python (GIL) part of each aircraft's work is the limit
PREFIX = "msdc"  # the pool threads' names: work mapped from inside one runs in that thread


def thread_count() -> int:
    """The threads per-aircraft work uses: the CPUs this process may run on (taskset), at most
    MAX_THREADS."""
    cpus = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)
    return max(1, min(cpus, MAX_THREADS))


def map_ordered(fn: Callable[[T], R], items: Iterable[T], threads: int | None = None) -> Iterator[R]:
    """fn over items on up to ``threads`` threads (default `thread_count`), the results in the items'
    order; at most two items per thread are taken ahead, so a lazy iterable stays lazy. fn must not
    touch what another item's call writes. Called from one of its own threads (an aircraft's work that
    maps again) it runs in that thread: no pool inside a pool."""
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
