"""The threads a decode's kernels run on: the kernels release the GIL, so a large decode's records are split
into contiguous ranges, one per CPU this process may run on (at most OMP_NUM_THREADS when it is set: Dask's
workers set it to 1, one process per core already)."""

from __future__ import annotations

import os
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor

import numpy as np

MIN_RECORDS_PER_THREAD = 50_000  # below this a thread's start costs more than its share of the work


def decode_threads() -> int:
    """The CPUs this process may run on (taskset), at most OMP_NUM_THREADS when that is a positive number."""
    cpus = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)
    cap = os.environ.get("OMP_NUM_THREADS", "").strip()
    if cap.isdigit() and int(cap) > 0:
        cpus = min(cpus, int(cap))
    return max(1, cpus)


def ranges(n: int, threads: int | None = None) -> list[tuple[int, int]]:
    """Contiguous [start, stop) ranges covering n records, one per thread, none under MIN_RECORDS_PER_THREAD
    (one range for a small decode)."""
    k = max(1, min(threads or decode_threads(), n // MIN_RECORDS_PER_THREAD))
    cuts = np.linspace(0, n, k + 1).astype(np.int64)
    return [(int(a), int(b)) for a, b in zip(cuts[:-1], cuts[1:], strict=True)]


def over_ranges(fn: Callable[[int, int], object], n: int, threads: int | None = None) -> None:
    """fn(start, stop) over ``ranges(n)``, in threads when there are several; fn's exceptions propagate."""
    parts = ranges(n, threads)
    if len(parts) == 1:
        fn(*parts[0])
        return
    with ThreadPoolExecutor(len(parts), thread_name_prefix="msdc-decode") as pool:
        for f in [pool.submit(fn, a, b) for a, b in parts]:
            f.result()
