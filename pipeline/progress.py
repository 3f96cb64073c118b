"""Stage messages on stderr, with an in-place bar when stderr is a terminal."""

from __future__ import annotations

import sys
import time
from typing import TextIO


class Progress:
    """Prints "Stage..." lines; on a terminal, redraws one line with a bar for counted work."""

    def __init__(self, stream: TextIO | None = None, enabled: bool = True):
        self.stream = stream or sys.stderr
        self.enabled = enabled
        self.tty = enabled and hasattr(self.stream, "isatty") and self.stream.isatty()
        self._t0 = time.monotonic()

    def stage(self, name: str) -> None:
        """Announce a pipeline stage ("Processing data files", "Slotting data", ...)."""
        if self.enabled:
            print(f"{name}...", file=self.stream, flush=True)

    def step(self, text: str) -> None:
        """A sub-step of the current stage (one input file, one aircraft)."""
        if self.enabled:
            print(f"  {text}", file=self.stream, flush=True)

    def bar(self, done: int, total: int, label: str = "", *, unit: str = "MB",
            since: float | None = None) -> None:
        """Redraw a progress bar (terminal only): done of total units (bytes for "MB", else counted
        ``unit``s), the rate since ``since`` (time.monotonic(); default this Progress's start)."""
        if not self.tty or total <= 0:
            return
        width = 30
        filled = int(width * min(done, total) / total)
        rate = done / max(time.monotonic() - (self._t0 if since is None else since), 1e-9)
        speed = f"{rate / 1e6:.1f} MB/s" if unit == "MB" else f"{done}/{total}, {rate:.1f} {unit}/s"
        end = "\n" if done >= total else ""
        print(f"\r  {label} [{'#' * filled}{'.' * (width - filled)}] {100 * done / total:5.1f}% "
              f"({speed})", end=end, file=self.stream, flush=True)
