"""One output transaction for a whole run: every file is written into a hidden staging folder beside its
target and moved into place, as a set, only when the run has succeeded.

A failed or interrupted run (an error, Ctrl-C, SIGTERM, SIGHUP) removes its staging folders and leaves
every file that was there before exactly as it was, and touches no other file of the folder (files other
programs create meanwhile included). Side files a writer names after its output (``o_cat048.csv`` beside
``o.csv``, ``r_tracks.png`` beside ``r.xlsx``) land in the same staging folder under their final names, so
they are committed with it. An output that is a symbolic link is written through: the link stays and the
file it points to is replaced. Outputs that exist and are not regular files (a FIFO, a device, a folder)
are refused before any work (``output_problem``).
"""

from __future__ import annotations

import contextlib
import errno
import glob
import os
import shutil
import signal
import uuid
from collections.abc import Iterable, Iterator
from dataclasses import dataclass, field
from pathlib import Path

STAGING_PREFIX = ".msdc-staging-"
BLOCKED = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)  # held back while the set is moved into place
TERMINATING = (signal.SIGTERM, signal.SIGHUP)  # raised as Terminated by raise_on_termination


def target(path: str | os.PathLike[str]) -> Path:
    """Where an output really goes: the file a symbolic link points to (the link is kept), else the path."""
    path = Path(path)
    return Path(os.path.realpath(path)) if path.is_symlink() else path.absolute()


def output_problem(path: str | os.PathLike[str]) -> str | None:
    """Why ``path`` cannot be an output (an existing folder, FIFO, socket or device), None when it can."""
    real = target(path)
    if not real.exists():
        return None
    if real.is_dir():
        return "is a directory"
    if not real.is_file():  # writing a FIFO blocks until someone reads it; a device is no report
        return "is not a regular file (a FIFO, socket or device): give a file name"
    return None


@dataclass(frozen=True)
class Written:
    """One file a committed run put in place, and whether it replaced a file that was there."""

    path: Path
    replaced: bool


@dataclass
class OutputTransaction:
    """The files of one run, staged per target folder and committed together (see the module docstring).

    Use it as a context manager: leaving the block without ``commit()`` (an exception, an interrupt)
    removes everything staged."""

    _stages: dict[Path, Path] = field(default_factory=dict)  # target folder -> its staging folder
    _spelled: dict[Path, Path] = field(default_factory=dict)  # staging folder -> its folder as given
    written: list[Written] = field(default_factory=list)

    def __enter__(self) -> OutputTransaction:
        return self

    def __exit__(self, kind, exc, tb) -> None:
        named = self.final_name(exc.filename) if isinstance(exc, OSError) and exc.filename else None
        self.abort()
        if named is not None and named != exc.filename:  # the output the user named, not the staged file
            raise OSError(exc.errno, exc.strerror, named) from exc

    def path(self, output: str | os.PathLike[str]) -> Path:
        """The staged path to write ``output`` to: its final name inside its folder's staging folder."""
        real = target(output)
        stage = self._stage(real.parent)
        if not Path(output).is_symlink():
            self._spelled.setdefault(stage, Path(output).parent)
        return stage / real.name

    def folder(self, directory: str | os.PathLike[str]) -> Path:
        """A staged folder standing for ``directory`` (created at commit when absent): what is written in
        it goes into ``directory`` under the same names."""
        stage = self._stage(target(directory))
        if not Path(directory).is_symlink():
            self._spelled.setdefault(stage, Path(directory))
        return stage

    def final_name(self, staged: str | os.PathLike[str]) -> str:
        """The output a staged path stands for, its folder spelled as the user gave it (the real folder for
        a symbolic link); ``staged`` unchanged when it is not staged here."""
        staged = Path(staged)
        for final_dir, stage in self._stages.items():
            if staged == stage or stage in staged.parents:
                return str(self._spelled.get(stage, final_dir) / staged.relative_to(stage))
        return str(staged)

    def final(self, staged: str | os.PathLike[str]) -> Path:
        """``final_name`` as a Path."""
        return Path(self.final_name(staged))

    def commit(self) -> list[Written]:
        """Move every staged file into place as a set, interrupts held back meanwhile: if one move fails,
        the files already moved are put back as they were and the error raised (naming the output)."""
        moves = [(stage / rel, final_dir / rel) for final_dir, stage in self._stages.items()
                 for rel in _files(stage)]
        with _signals_held():
            done: list[tuple[Path, Path | None, Path]] = []  # recorded before each move: _undo can tell
            try:
                for staged, final in moves:
                    final.parent.mkdir(parents=True, exist_ok=True)
                    if final.is_dir() and not final.is_symlink():  # made meanwhile: never moved away
                        raise IsADirectoryError(errno.EISDIR, os.strerror(errno.EISDIR), str(final))
                    had = final.exists() or final.is_symlink()
                    backup = staged.with_name(staged.name + ".replaced") if had else None
                    done.append((final, backup, staged))
                    if backup is not None:
                        os.replace(final, backup)
                    os.replace(staged, final)
            except OSError as exc:
                _undo(done)
                raise OSError(exc.errno, exc.strerror, str(final)) from exc
            except BaseException:
                _undo(done)
                raise
            self.written = [Written(final, backup is not None) for final, backup, _ in done]
            self.abort()  # the staging folders now hold only the replaced files' old content
        return self.written

    def abort(self) -> None:
        """Remove every staging folder and what is in it, nothing else. Interrupts are held back meanwhile;
        one already on its way (its handler raises at any step) is raised once every folder is gone."""
        interrupted = None
        with _signals_held():
            while self._stages:
                final_dir, stage = next(iter(self._stages.items()))
                try:
                    shutil.rmtree(stage, ignore_errors=True)
                except BaseException as exc:  # noqa: BLE001 - the same folder again, then raised
                    interrupted = interrupted or exc
                    continue
                del self._stages[final_dir]
            self._spelled.clear()
        if interrupted is not None:
            raise interrupted

    def _stage(self, final_dir: Path) -> Path:
        """The staging folder of ``final_dir`` (made on first use; for a folder that does not exist yet, in
        the nearest one that does, so the commit's moves stay on one file system)."""
        if final_dir in self._stages:
            return self._stages[final_dir]
        home = final_dir
        while not home.is_dir():
            home = home.parent
        stage = home / f"{STAGING_PREFIX}{os.getpid()}-{uuid.uuid4().hex[:8]}"
        self._stages[final_dir] = stage  # recorded first: an interrupt cannot leave it unknown to abort()
        stage.mkdir()
        return stage


def left_beside(patterns: Iterable[str | os.PathLike[str]], written: Iterable[Written]) -> list[Path]:
    """The files matching ``patterns`` (a folder and a glob of names, e.g. ``out/r_lags_*.png``: the side
    files a command may write) that the run did not put in place: an earlier run's, left as they were.
    Spelled as the patterns spell them, in a stable order, each once."""
    done = {os.path.normpath(w.path) for w in written}
    out: list[Path] = []
    for pattern in map(Path, patterns):
        for path in sorted(pattern.parent.glob(pattern.name)):
            if (path.is_file() or path.is_symlink()) and os.path.normpath(path.absolute()) not in done \
                    and path not in out:
                out.append(path)
    return out


def side_pattern(output: str | os.PathLike[str], suffix_glob: str) -> Path:
    """The glob of a side file named after ``output`` (``r.xlsx``, ``"_lags_*.png"``: ``r_lags_*.png`` beside
    it), the output's own name escaped (a ``[`` in it is no glob)."""
    output = Path(output)
    return output.with_name(glob.escape(output.stem) + suffix_glob)


@contextlib.contextmanager
def staged(tx: OutputTransaction | None = None) -> Iterator[OutputTransaction]:
    """``tx`` itself when given (whoever opened it commits it, with the rest of the run), else a transaction
    of the block's own, committed when the block succeeds."""
    if tx is not None:
        yield tx
        return
    with OutputTransaction() as own:
        yield own
        own.commit()


def _files(stage: Path) -> list[Path]:
    """The files staged under ``stage``, relative to it, in a stable order."""
    return sorted(p.relative_to(stage) for p in stage.rglob("*") if p.is_file() or p.is_symlink())


def _undo(done: list[tuple[Path, Path | None, Path]]) -> None:
    """Put back what a failed commit moved: each replaced file's old content, or no file where none was
    (``final`` is removed only when its staged file was moved there)."""
    for final, backup, staged in reversed(done):
        with contextlib.suppress(OSError):
            if backup is not None:
                if backup.exists() or backup.is_symlink():
                    os.replace(backup, final)
            elif not (staged.exists() or staged.is_symlink()):
                final.unlink(missing_ok=True)


@contextlib.contextmanager
def _signals_held() -> Iterator[None]:
    """Hold back SIGINT, SIGTERM and SIGHUP (delivered when the block ends) where the platform can."""
    if not hasattr(signal, "pthread_sigmask"):
        yield
        return
    old = signal.pthread_sigmask(signal.SIG_BLOCK, [])  # the mask as it is: restored even if a handler
    try:  # that was already due raises right after the next call
        signal.pthread_sigmask(signal.SIG_BLOCK, BLOCKED)
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, old)


class Terminated(BaseException):
    """SIGTERM or SIGHUP, raised where the program is so that every ``with`` block cleans up as for
    Ctrl-C; the exit status is 128 + the signal's number."""

    def __init__(self, signum: int):
        super().__init__(f"terminated by signal {signum}")
        self.signum = signum

    def __reduce__(self):
        return Terminated, (self.signum,)


def raise_on_termination() -> dict[int, object]:
    """Turn SIGTERM and SIGHUP into Terminated in this process (the command's main thread); returns the
    handlers it replaced, for ``restore_handlers``."""
    def _raise(signum, frame):
        raise Terminated(signum)

    previous = {}
    for sig in TERMINATING:
        with contextlib.suppress(ValueError, OSError):  # not the main thread, or not on this platform
            previous[sig] = signal.signal(sig, _raise)
    return previous


def restore_handlers(previous: dict[int, object]) -> None:
    """Put back the signal handlers ``raise_on_termination`` replaced."""
    for sig, handler in previous.items():
        with contextlib.suppress(ValueError, OSError, TypeError):
            signal.signal(sig, handler)

