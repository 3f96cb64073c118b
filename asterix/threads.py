"""The threads a decode's kernels run on: the kernels release the GIL, so a large decode's blocks are walked
in groups, and its records gathered in ranges, side by side, one per CPU this process may run on (at most
OMP_NUM_THREADS when it is set: Dask's workers set it to 1, one process per core already)."""

from __future__ import annotations

import os
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from typing import TypeVar

import numpy as np

T = TypeVar("T")
MIN_RECORDS_PER_THREAD = 50_000  # below this a thread's start costs more than its share of the work


def process_cpus() -> int:
    """The CPUs this process may run on (taskset; all of the machine's where that cannot be asked)."""
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)


def decode_threads() -> int:
    """The CPUs this process may run on, at most OMP_NUM_THREADS when that is a positive number."""
    cpus = process_cpus()
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


def run_all(calls: list[Callable[[], T]]) -> list[T]:
    """The calls' results in order, each call in a thread of its own when there are several; their
    exceptions propagate."""
    if len(calls) <= 1:
        return [c() for c in calls]
    with ThreadPoolExecutor(len(calls), thread_name_prefix="msdc-decode") as pool:
        futures = [pool.submit(c) for c in calls]
        return [f.result() for f in futures]


def byte_groups(lens: np.ndarray, records: int, threads: int | None = None) -> list[slice]:
    """Contiguous groups of blocks of about equal bytes, one per range of ``ranges(records)`` (records: a
    guess of the blocks' records); one group for a small decode."""
    k = min(len(ranges(records, threads)), max(len(lens), 1))
    if k == 1:
        return [slice(0, len(lens))]
    ends = np.cumsum(lens)
    cuts = [0, *np.searchsorted(ends, ends[-1] * np.arange(1, k) / k, side="right").tolist(), len(lens)]
    return [slice(a, b) for a, b in zip(cuts[:-1], cuts[1:], strict=True) if b > a]
