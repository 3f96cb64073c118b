"""Dask's distributed scheduler as the engine of the jobs' per-aircraft and per-partition work: a LocalCluster
of worker processes on this machine, or an existing cluster by its scheduler's address. The cluster starts
on the first task (a job with nothing to distribute starts none); tasks are submitted a few per worker
ahead of the results, which come back in the items' order, so results equal a one-process run's."""

from __future__ import annotations

import logging
import os
import re
import time
from collections import deque
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass, field
from typing import Any, TypeVar

from msdc.asterix.threads import process_cpus
from msdc.pipeline.progress import Progress

T = TypeVar("T")
R = TypeVar("R")

# The local scheduler's HTTP server (it starts one without a dashboard) on a free loopback port: not Dask's
# well-known 8787, whose owner (a notebook's cluster, another msdc run) made distributed warn "Port 8787 is
# already in use. Perhaps you already have a cluster running?" into msdc's output.
QUIET_SCHEDULER = {"dashboard": False, "dashboard_address": "127.0.0.1:0"}
WORKER_START = "msdc.pipeline.dataset.worker_start"  # preloaded by each local worker: Ctrl-C ignored
LOCAL = "local"  # --scheduler local: a LocalCluster of --workers processes
NONE = "none"  # --scheduler none: threads in this process, as without --dataset
RETRIES = 2  # a failed task is tried this many times more before the run reports it
AHEAD_PER_WORKER = 4  # tasks submitted ahead of the results, per worker: bounds what waits in memory
CONNECT_TIMEOUT_S = 10.0
RESTART_WAIT_S = 60.0  # how long a restarted local worker is waited for to be listed again
# the local cluster's workers keep glibc's own heap trimming: Dask's nanny sets MALLOC_TRIM_THRESHOLD_ to 64
# KiB for them, so every free of a few pages goes back to the kernel and is faulted in again (10 minutes of
# the simulated centre evaluated in one process: 4.0 M page faults and 12 s of system time with that
# setting, 1.0 M and 5 s without). msdc trims itself where a job lets go of its data
# (model.heap.release_free_memory). A value exported in the environment still wins, as Dask lets it.
LOCAL_WORKER_CONFIG = {"distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_": None}
# ... and numpy's large arrays are not marked for transparent huge pages in them (NUMPY_MADVISE_HUGEPAGE=0):
# where the kernel compacts memory on the fault of a page so marked (THP defrag "madvise", Debian's
# default), a worker's system time went 31 -> 24-25 s and its CPU 164-167 -> 157-160 s over 12 windows of
# the simulated centre's peak, its peak memory alike (1.60-1.77 against 1.66-1.70 GB). Unless exported.
HUGEPAGE_VARIABLE = "NUMPY_MADVISE_HUGEPAGE"


def local_worker_config() -> dict:
    """The Dask configuration the local cluster's workers start with (the two settings above)."""
    config: dict = dict(LOCAL_WORKER_CONFIG)
    if HUGEPAGE_VARIABLE not in os.environ:
        config[f"distributed.nanny.pre-spawn-environ.{HUGEPAGE_VARIABLE}"] = "0"
    return config


_ADDRESS = re.compile(r"^(tcp|tls)://[^\s:/]+:\d{1,5}$")


class TaskFailed(RuntimeError):
    """A task failed on every try: the message names the task (its aircraft or partition, input and
    offset) and the cause."""


class ClusterUnavailable(RuntimeError):
    """The scheduler could not be reached or the local cluster not started: the message says which."""


def scheduler_problem(value: str) -> str | None:
    """Why ``value`` is not a --scheduler (None when it is one)."""
    if value in (LOCAL, NONE) or _ADDRESS.match(value):
        return None
    return "expected 'local', 'none' or a scheduler address tcp://HOST:PORT"


def machine_workers() -> int:
    """The local cluster's default size: the CPUs this process may run on."""
    return process_cpus()


@dataclass
class DaskDistributor:
    """Runs tasks on a Dask cluster (pipeline.parallel.Distributor): ``address`` is LOCAL or a scheduler's
    address; ``workers`` sizes a local cluster (None: the machine's CPUs). Counts what it ran."""

    address: str = LOCAL
    workers: int | None = None
    progress: Progress | None = None
    retries: int = RETRIES
    tasks: int = 0
    failed: list[str] = field(default_factory=list)
    _client: Any = None
    _cluster: Any = None
    _reached: bool = False  # the cluster was started or connected to (stays true once closed)

    def client(self):
        """The Dask client, the cluster started (or connected to) on first use; ClusterUnavailable if not."""
        if self._client is not None:
            return self._client
        try:
            import dask
            from distributed import Client, LocalCluster
        except ImportError:
            raise ClusterUnavailable("--scheduler: running on a Dask cluster (the default with --dataset) "
                                     "needs Dask's distributed package: pip install 'msdc[dataset]', or give "
                                     "--scheduler none") from None
        try:
            if self.address == LOCAL:
                with dask.config.set(local_worker_config()):
                    self._cluster = LocalCluster(n_workers=self.workers or machine_workers(),
                                                 threads_per_worker=1, processes=True, host="127.0.0.1",
                                                 dashboard_address=None, silence_logs=logging.ERROR,
                                                 scheduler_kwargs=QUIET_SCHEDULER, preload=[WORKER_START])
                self._client = Client(self._cluster)
            else:
                self._client = Client(self.address, timeout=f"{CONNECT_TIMEOUT_S}s")
            self._reached = True
        except (OSError, TimeoutError, RuntimeError) as exc:  # RuntimeError: a nanny that failed to start
            self.close()
            where = "the local Dask cluster" if self.address == LOCAL else f"--scheduler {self.address}"
            raise ClusterUnavailable(f"{where}: cannot be reached or started ({exc})") from None
        return self._client

    @property
    def used(self) -> bool:
        """Whether the run asked for the cluster (started or connected to it), also once it is closed."""
        return self._reached

    def worker_count(self) -> int:
        """Workers the scheduler knows now (at least 1)."""
        return max(1, len(self.client().scheduler_info().get("workers", {})))

    def map_ordered(self, fn: Callable[[T], R], items: Iterable[T],
                    label: Callable[[T], str] | None = None, fresh_after: int | None = None) -> Iterator[R]:
        """fn over items as tasks, the results in the items' order; TaskFailed naming the first item whose
        task failed on every try (the tasks after it are cancelled). ``fresh_after``: on a local cluster,
        each worker process is restarted after that many tasks (``_fresh_workers``)."""
        if fresh_after and self.address == LOCAL:
            yield from self._fresh_workers(fn, items, label, fresh_after)
            return
        client = self.client()
        ahead = AHEAD_PER_WORKER * self.worker_count()
        total = len(items) if hasattr(items, "__len__") else 0
        pending: deque = deque()
        started, done = time.monotonic(), 0
        try:
            for i, item in enumerate(items):
                name = label(item) if label else f"task {i + 1}"
                pending.append((client.submit(fn, item, pure=False, retries=self.retries), name))
                self.tasks += 1
                if len(pending) >= ahead:
                    yield self._result(*pending.popleft())
                    done += 1
                    self._show(done, total, started)
            while pending:
                yield self._result(*pending.popleft())
                done += 1
                self._show(done, total, started)
        finally:
            _cancel(client, [f for f, _ in pending])

    def _fresh_workers(self, fn: Callable[[T], R], items: Iterable[T], label: Callable[[T], str] | None,
                       every: int) -> Iterator[R]:
        """map_ordered where each worker process is restarted by its nanny once it has run ``every`` tasks
        and runs none (the scheduler may give it one more as it ends one: then after that): a process
        that ran large tasks keeps heap they freed but it cannot hand back (a worker evaluating the
        simulated day's 10-minute windows grew from 1.8 to 2.2 GB at the same traffic). No more tasks run
        than there are workers, so each has at most one, and a worker is restarted only when the scheduler
        says it runs none and every other task is placed: a restart never cuts a task short (but for one
        Dask moves from a lost worker in the moment the restart is asked). A task whose worker is lost runs
        again on another, as Dask does. Results come in the items' order, at most AHEAD_PER_WORKER a worker
        held here waiting for an earlier one."""
        from distributed import wait

        client = self.client()
        workers = self.worker_count()
        total = len(items) if hasattr(items, "__len__") else 0
        todo = iter(enumerate(items))
        running, finished, ran = {}, {}, {}
        started, done, ahead = time.monotonic(), 0, AHEAD_PER_WORKER * workers
        try:
            while True:
                while len(running) < workers and len(running) + len(finished) < ahead:
                    nxt = next(todo, None)
                    if nxt is None:
                        break
                    i, item = nxt
                    future = client.submit(fn, item, pure=False, retries=self.retries)
                    running[future] = (i, label(item) if label else f"task {i + 1}")
                    self.tasks += 1
                if not running and not finished:
                    return
                if done in finished:
                    yield finished.pop(done)
                    done += 1
                    self._show(done, total, started)
                    continue
                for ended in wait(list(running), return_when="FIRST_COMPLETED").done:
                    i, name = running.pop(ended)
                    holders = client.who_has([ended]).get(ended.key) or ()
                    finished[i] = self._result(ended, name)  # fetched before its worker may restart
                    ended.release()
                    for worker in holders[:1]:  # the worker that ran it
                        ran[worker] = ran.get(worker, 0) + 1
                # before the next tasks go out, so none is given to a worker about to restart
                for worker in [w for w, n in ran.items() if n >= every]:
                    if self._idle(client, worker, running):
                        self._restart(client, worker)
                        del ran[worker]
        finally:
            _cancel(client, list(running))

    @staticmethod
    def _idle(client, worker: str, running) -> bool:
        """Whether the scheduler has no task on ``worker`` and every other task running is placed on a
        worker or done (one Dask moves from a lost worker could be given to this one as it restarts)."""
        busy = client.processing()
        placed = {key for keys in busy.values() for key in keys}
        return not busy.get(worker) and all(f.done() or f.key in placed for f in running)

    @staticmethod
    def _restart(client, worker: str) -> None:
        """Restart an idle worker by its nanny and wait until the scheduler lists its new process (its
        restart may return while the old one is still listed; the new one listens on another port), at most
        RESTART_WAIT_S: a worker not back by then is the cluster's to replace."""
        name = {a: w.get("name") for a, w in client.scheduler_info()["workers"].items()}.get(worker)
        if name is None:  # gone already: its nanny or the cluster replaces it
            return
        try:
            client.restart_workers([worker], raise_for_error=False)
        except (OSError, TimeoutError, RuntimeError, KeyError):  # KeyError: the worker left meanwhile
            return
        deadline = time.monotonic() + RESTART_WAIT_S
        while time.monotonic() < deadline:
            now = {w.get("name"): a for a, w in client.scheduler_info()["workers"].items()}
            if now.get(name, worker) != worker:
                return
            time.sleep(0.1)

    def _result(self, future, name: str):
        """A task's result, or TaskFailed naming it."""
        try:
            return future.result()
        except Exception as exc:  # the task's own exception, re-raised here, or the worker's loss
            self.failed.append(name)
            raise TaskFailed(f"{name}: failed on {self.retries + 1} tries ({type(exc).__name__}: {exc})"
                             ) from None

    def _show(self, done: int, total: int, started: float) -> None:
        if self.progress is not None and total:
            self.progress.bar(done, total, "tasks", unit="tasks", since=started)

    def summary(self) -> str | None:
        """One line on what ran on the cluster (None when nothing did)."""
        if not self.tasks:
            return None
        where = (f"a local Dask cluster of {self.workers or machine_workers()} worker process(es)"
                 if self.address == LOCAL else f"the Dask scheduler at {self.address}")
        failed = f", {len(self.failed)} failed: {'; '.join(self.failed)}" if self.failed else ", none failed"
        return f"{self.tasks} task(s) on {where}{failed}"

    def close(self) -> None:
        """Close the client and a local cluster (an external cluster keeps running)."""
        for thing in (self._client, self._cluster):
            if thing is not None:
                try:
                    thing.close()
                except Exception:  # noqa: BLE001 - closing must not hide the run's own outcome
                    pass
        self._client = self._cluster = None


def _cancel(client, futures: list) -> None:
    """Cancel the tasks a run leaves behind (none: nothing to do)."""
    if futures:
        try:
            client.cancel(futures)
        except (RuntimeError, OSError):  # the client already closed: its tasks went with it
            pass
