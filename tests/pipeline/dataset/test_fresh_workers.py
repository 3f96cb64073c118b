"""Fresh workers (pipeline.dataset.cluster.DaskDistributor, ``fresh_after``): on a local cluster each worker
process is restarted after so many tasks, never while it runs one, the results still in the items' order.
Not in the "dask" group: it starts a local cluster of its own, beside the shared one."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from msdc.pipeline.dataset.cluster import DaskDistributor


def _process_of(item: tuple[str, int]) -> tuple[int, int]:
    """The item and the pid of the process that ran it; item 1 kills its worker process on its first try (a
    file beside the test counts the tries: workers are other processes)."""
    folder, x = item
    tries = Path(folder) / f"tries-{x}"
    tries.write_text(tries.read_text() + "x" if tries.exists() else "x")
    if x == 1 and len(tries.read_text()) == 1:
        os._exit(1)
    return x, os.getpid()


def test_a_local_worker_is_restarted_after_so_many_tasks_and_replaced_when_lost(tmp_path):
    """fresh_after=2 on a local cluster of 1 worker, item 1 killing its process once: item 0 runs in the
    first process, item 1 again in the one its nanny starts, with item 2; then that one is restarted and a
    third runs items 3 and 4 (processes told apart by their pids). Each result once, in the items' order;
    without fresh_after one process runs them all."""
    pytest.importorskip("distributed", reason="dask's distributed scheduler is not installed")
    engine = DaskDistributor(workers=1)
    try:
        fresh = list(engine.map_ordered(_process_of, [(str(tmp_path), x) for x in range(5)], fresh_after=2))
        kept = list(engine.map_ordered(_process_of, [(str(tmp_path), x) for x in range(5, 8)]))
    finally:
        engine.close()
    assert [x for x, _ in fresh] == list(range(5)) and engine.tasks == 8 and engine.failed == []
    p = [pid for _, pid in fresh]
    assert p[0] != p[1] == p[2] != p[3] == p[4] != p[0], p
    assert [len((tmp_path / f"tries-{x}").read_text()) for x in range(5)] == [1, 2, 1, 1, 1]
    assert len({pid for _, pid in kept}) == 1
