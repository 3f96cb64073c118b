"""Fresh workers (pipeline.dataset.cluster.DaskDistributor, ``fresh_after``): on a local cluster each worker
process is restarted after so many tasks, never while it runs one, the results still in the items' order.
Not in the "dask" group: it starts a local cluster of its own, beside the shared one."""

from __future__ import annotations

import os
import time

import pytest

from msdc.pipeline.dataset.cluster import DaskDistributor


def _item_and_process(x: int) -> tuple[int, int]:
    time.sleep(0.02 * (3 - x % 3))  # the early items end last
    return x, os.getpid()


def test_local_workers_are_restarted_after_so_many_tasks():
    """fresh_after=2 on a local cluster of 2 workers: no process runs more than 2 of the tasks, so 6 tasks
    need at least 3 processes (told apart by their pids), and the results still come in the items' order;
    without it, the 2 processes run them all."""
    pytest.importorskip("distributed", reason="dask's distributed scheduler is not installed")
    engine = DaskDistributor(workers=2)
    try:
        fresh = list(engine.map_ordered(_item_and_process, range(6), fresh_after=2))
        kept = list(engine.map_ordered(_item_and_process, range(6)))
    finally:
        engine.close()
    assert [x for x, _ in fresh] == list(range(6)) and engine.tasks == 12
    per_process = [pid for _, pid in fresh]
    assert max(per_process.count(p) for p in per_process) <= 2 and len(set(per_process)) >= 3, per_process
    assert len({pid for _, pid in kept}) <= 2
