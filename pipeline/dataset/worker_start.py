"""Preloaded into each worker process of msdc's local Dask cluster (cluster.DaskDistributor): Ctrl-C reaches
the terminal's whole process group, and a worker ended by its own KeyboardInterrupt printed a traceback
("Process Dask Worker process (from Nanny): ..."). The worker ignores it; the main process closes the
cluster, which ends its workers."""

from __future__ import annotations

import signal
import threading


def dask_setup(worker) -> None:
    """Dask's preload hook, run as the worker starts (in its process's main thread)."""
    if threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGINT, signal.SIG_IGN)
