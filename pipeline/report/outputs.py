"""Outputs written in forked child processes (``Background``, ``Prepared``) while this process writes others:
given staged paths (report.transaction), waited for or cancelled before the transaction ends."""

from __future__ import annotations

import contextlib
import gc
import os
import pickle
import signal
import sys
from collections.abc import Callable

from msdc.pipeline.report.transaction import TERMINATING


class BackgroundFailed(RuntimeError):
    """A background writer ended without saying why (killed, or its error could not be sent back)."""


class Background:
    """``fn(*args)`` run in a forked child process, so an output is written on the other core while this
    process writes another; ``wait()`` returns what ``fn`` returned or re-raises the child's error here
    (the result must pickle). Where fork is not available
    (or not safe: only Linux is trusted) it runs at once, in this process. Call ``wait()`` or
    ``cancel()`` before the output transaction it writes into ends, so no file appears after its clean-up."""

    def __init__(self, fn: Callable[..., object], *args: object):
        self._pid, self._value = 0, None
        if not (FORK_OK and hasattr(os, "fork")):
            self._value = fn(*args)
            return
        read, write = os.pipe()
        pid = _fork(lambda: _run_and_send(fn, args, write), close=(read,))
        os.close(write)
        self._pid, self._read = pid, read

    def wait(self) -> object:
        """Wait for the child and return what ``fn`` returned; raise its error (BackgroundFailed when it
        died without one)."""
        if not self._pid:
            return self._value
        try:
            with os.fdopen(self._read, "rb") as pipe:
                message = pipe.read()
        finally:  # closed, even when interrupted: cancel() must not close it again
            self._read = -1
        pid, self._pid = self._pid, 0  # reaped below: cancel() must not wait for it again
        try:
            _, status = os.waitpid(pid, 0)
        except BaseException:  # a signal's exception before the child was reaped: cancel() reaps it
            self._pid = pid
            raise
        try:
            sent = pickle.loads(message) if message else None
        except Exception:  # noqa: BLE001 - cut short: the child died while sending
            sent = None
        if isinstance(sent, BaseException):
            raise sent
        if status or not isinstance(sent, _Returned):
            code = os.waitstatus_to_exitcode(status)
            raise BackgroundFailed(f"killed by signal {-code}" if code < 0 else
                                   f"exit status {code}" if code else "ended without a result")
        self._value = sent.value
        return self._value

    def cancel(self) -> None:
        """Stop the child if it still runs (this process failed) and reap it."""
        if not self._pid:
            return
        _stop(self._pid)
        if self._read >= 0:
            os.close(self._read)
        self._pid, self._read = 0, -1


class Prepared:
    """A child forked now, while this process still has work to do, that gets ready on the other core
    (``warm()``: imports, caches) and then runs ``fn(*args)`` once start(*args) sends the arguments: a
    Background without its start-up on the critical path. ``fn`` is taken at fork time (only the
    arguments travel, pickled through an unnamed file); where fork is not available start() runs the
    work at once, as Background does. close() stops a child that was never started. The child's heap as
    warmed is frozen (gc.freeze): a full collection walking it, copying every page it touches from the
    parent's, cost 0.06-0.16 s of the 3 h run's critical path."""

    def __init__(self, fn: Callable[..., object], *, warm: Callable[[], object] | None = None):
        self._fn, self._pid = fn, 0
        if not (FORK_OK and hasattr(os, "fork") and hasattr(os, "memfd_create")):
            return
        data = os.memfd_create("msdc-args", os.MFD_CLOEXEC)
        go_read, go_write = os.pipe()
        done_read, done_write = os.pipe()

        def child() -> int:
            if warm is not None:
                with contextlib.suppress(Exception):  # fn meets the same trouble and reports it
                    warm()
            gc.freeze()  # what is here now stays: no collection walks (and copies) the forked heap
            size = int.from_bytes(os.read(go_read, 8) or b"\0", "little")
            if not size:
                return 0  # closed unused
            return _run_and_send(lambda: fn(*_received(data, size)), (), done_write)

        pid = _fork(child, close=(go_write, done_read))
        os.close(go_read)
        os.close(done_write)
        self._pid, self._data, self._go, self._done = pid, data, go_write, done_read

    def start(self, *args: object) -> Background:
        """Send ``args`` to the child, which runs ``fn(*args)``; wait() on the result re-raises its error.
        Without a child (or with arguments that do not pickle) a Background does the work instead."""
        if not self._pid:
            return Background(self._fn, *args)
        try:  # streamed into the unnamed file: no second copy of a large run in memory
            with os.fdopen(os.dup(self._data), "wb") as sink:
                sink.seek(0)
                sink.truncate()
                pickle.dump(args, sink, protocol=pickle.HIGHEST_PROTOCOL)
                size = sink.tell()
        except Exception:  # noqa: BLE001 - e.g. a lambda: the work is done the usual way
            self.close()
            return Background(self._fn, *args)
        job = Background.__new__(Background)
        job._pid, job._read, job._value = self._pid, self._done, None
        try:
            os.write(self._go, size.to_bytes(8, "little"))
        except BaseException:
            job.cancel()
            raise
        finally:
            self._release()
        return job

    def close(self) -> None:
        """Stop and reap a child that was never started."""
        if not self._pid:
            return
        _stop(self._pid)
        os.close(self._done)
        self._release()

    def _release(self) -> None:
        os.close(self._go)
        os.close(self._data)
        self._pid = 0


def _flush() -> None:
    """Before a fork: the child leaves by os._exit and never writes what was buffered here; flushed
    anyway, so nothing buffered can come out twice (a closed pipe stays this process's business)."""
    with contextlib.suppress(OSError, ValueError):
        sys.stdout.flush()
        sys.stderr.flush()


def _fork(child: Callable[[], int], close: tuple[int, ...] = ()) -> int:
    """Fork (output flushed first); the child closes the parent's ends ``close``, runs ``child`` and leaves
    by os._exit with its status (1 if it raised); the parent gets the child's pid."""
    _flush()
    pid = os.fork()
    if pid == 0:  # pragma: no cover - the child (coverage does not follow it)
        status = 1
        try:
            for sig in TERMINATING:  # the parent's Terminated is the parent's: SIGTERM ends a child as usual
                signal.signal(sig, signal.SIG_DFL)
            for fd in close:
                os.close(fd)
            status = child()
        finally:
            os._exit(status)
    return pid


def _run_and_send(fn: Callable[..., object], args: tuple, fd: int) -> int:
    """In a child: run ``fn(*args)`` and send what it returned, or its error, through ``fd``; the child's
    exit status (1: it failed)."""
    try:
        message, status = _returned(fn(*args)), 0
    except BaseException as exc:  # noqa: BLE001 - sent back to be raised in the parent
        message, status = _pickled(exc), 1
    with os.fdopen(fd, "wb") as out:
        out.write(message)
    return status


def _stop(pid: int) -> None:
    """Kill a child and reap it; one reaped already (a signal's exception can land between a wait's reaping
    and its bookkeeping) is left as it is, so that the signal, not ECHILD, ends the run."""
    with contextlib.suppress(ProcessLookupError):
        os.kill(pid, signal.SIGKILL)
    with contextlib.suppress(ChildProcessError):
        os.waitpid(pid, 0)


def _received(data: int, size: int) -> tuple:
    """The arguments the parent pickled into the unnamed file ``data``; the file is closed (its pages go
    once the parent has closed it too)."""
    args = pickle.loads(_read_all(data, size))
    os.close(data)
    return args


def _read_all(fd: int, size: int) -> bytes:
    """``size`` bytes of ``fd`` from its start (pread: the offset the parent's writes moved is not used)."""
    chunks, offset = [], 0
    while offset < size:
        chunk = os.pread(fd, min(size - offset, 1 << 30), offset)
        if not chunk:
            break
        chunks.append(chunk)
        offset += len(chunk)
    return b"".join(chunks)


FORK_OK = sys.platform.startswith("linux")  # macOS: fork is unsafe with system frameworks; Windows: none


class _Returned:
    """What a child's ``fn`` returned, as sent back (an exception sent back is raised instead)."""

    def __init__(self, value: object):
        self.value = value


def _returned(value: object) -> bytes:
    """The child's result, pickled; a result that does not pickle is an error of its own."""
    try:
        return pickle.dumps(_Returned(value), protocol=pickle.HIGHEST_PROTOCOL)
    except Exception as exc:  # noqa: BLE001 - reported like any other failure of the child
        return _pickled(exc)


def _pickled(exc: BaseException) -> bytes:
    """The exception, pickled; its type and text as a BackgroundFailed when it does not pickle."""
    try:
        data = pickle.dumps(exc)
        pickle.loads(data)
        return data
    except Exception:  # noqa: BLE001 - any exception type may fail to round-trip
        return pickle.dumps(BackgroundFailed(f"{type(exc).__name__}: {exc}"))
