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
        self._label: str | None = None  # the bar being drawn
        self._bar_t0, self._bar_done0, self._ended = time.monotonic(), 0, True

    def stage(self, name: str) -> None:
        """Announce a pipeline stage ("Processing data files", "Slotting data", ...)."""
        if self.enabled:
            print(f"{_escaped(name)}...", file=self.stream, flush=True)

    def step(self, text: str) -> None:
        """A sub-step of the current stage (one input file, one aircraft)."""
        if self.enabled:
            print(f"  {_escaped(text)}", file=self.stream, flush=True)

    def bar(self, done: int, total: int, label: str = "", *, unit: str = "MB",
            since: float | None = None) -> None:
        """Redraw a progress bar (terminal only): done of total units (bytes for "MB", else counted
        ``unit``s); a new label starts a new bar, its rate counted from then (a file's passes each start from
        its beginning) or from ``since`` (time.monotonic(), counting from 0 units)."""
        if not self.tty or total <= 0:
            return
        now = time.monotonic()
        if label != self._label:
            if self._label is not None and not self._ended:
                print(file=self.stream)  # the bar before stopped short of 100 %: keep it on its own line
            self._label = label
            self._bar_t0, self._bar_done0 = (now, done) if since is None else (since, 0)
        width = 30
        filled = int(width * min(done, total) / total)
        rate = (done - self._bar_done0) / max(now - self._bar_t0, 1e-9)
        speed = (f"{rate / 1e6:.1f} MB/s" if unit == "MB" else f"{done}/{total}, {rate:.1f} {unit}/s")
        if 0 < rate and done < total:
            speed += f", ETA {eta_text((total - done) / rate)}"
        speed = f" ({speed})" if done > self._bar_done0 else ""  # none from the first call: it has not moved
        self._ended = done >= total
        end = "\n" if done >= total else ""
        print(f"\r  {label} [{'#' * filled}{'.' * (width - filled)}] {100 * done / total:5.1f}%{speed}",
              end=end, file=self.stream, flush=True)


def eta_text(seconds: float) -> str:
    """Time left as a bar shows it: "42 s", "7 min 05 s", "2 h 03 min"."""
    s = int(round(seconds))
    if s < 60:
        return f"{s} s"
    if s < 3600:
        return f"{s // 60} min {s % 60:02d} s"
    return f"{s // 3600} h {s % 3600 // 60:02d} min"


def _escaped(text: str) -> str:
    """``text`` with a file name's bytes that are not UTF-8 as escapes (model.sources.escaped, imported only
    then: this module stays light for the pool processes that report through it)."""
    if text.isascii():
        return text
    from msdc.pipeline.model.sources import escaped

    return escaped(text)
