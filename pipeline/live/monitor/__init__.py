"""The live monitor: a web page served by msdc (no internet) showing the current targets on a map, per-sensor
figures and alarms, pushed once a second. ``Thresholds`` is light (the CLI reads its defaults); ``serve``
loads the web stack only when called."""

from __future__ import annotations

import math
import threading
from collections.abc import Callable
from dataclasses import dataclass, field, fields


def _threshold(default: float, unit: str, help: str):
    return field(default=default, metadata={"unit": unit, "help": help})


@dataclass(frozen=True)
class Thresholds:
    """When the monitor raises an alarm, and over which window it measures; each field's metadata gives its
    unit and a one-line help (the listen options take their defaults and help from here)."""

    silent_s: float = _threshold(30.0, "s", "a sensor with no report for this long is 'silent'")
    min_pd: float = _threshold(
        0.97, "", "a sensor whose live probability of update is below this (its whole 95 % interval) is "
        "'degraded'")
    min_mode3a_valid: float = _threshold(
        0.98, "", "likewise for the share of its Mode 3/A codes marked valid")
    min_modec_valid: float = _threshold(
        0.96, "", "likewise for the share of its Mode C codes marked valid")
    window_s: float = _threshold(120.0, "s", "the sliding window of the live figures and of the map's trails")

    def __post_init__(self) -> None:
        for f in fields(self):
            v = getattr(self, f.name)
            if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v):
                raise ValueError(f"threshold {f.name}: a finite number is needed, got {v!r}")
            if f.name.startswith("min_") and not 0.0 <= v <= 1.0:
                raise ValueError(f"threshold {f.name}: a share between 0 and 1 is needed, got {v!r}")
            if f.name.endswith("_s") and v <= 0:
                raise ValueError(f"threshold {f.name}: a positive number of seconds is needed, got {v!r}")

    def as_dict(self) -> dict[str, float]:
        """The thresholds by field name (the JSON feed carries them)."""
        return {f.name: float(getattr(self, f.name)) for f in fields(self)}


def thresholds_markdown() -> str:
    """The thresholds as a Markdown table (docs/guide/live-monitor.md shows it; a test keeps them equal)."""
    rows = ["| threshold | default | unit | meaning |", "|---|---|---|---|"]
    for f in fields(Thresholds):
        unit = f.metadata["unit"] or "share"
        rows.append(f"| `{f.name}` | {f.default:g} | {unit} | {f.metadata['help']} |")
    return "\n".join(rows)


def serve(state, host: str, port: int, thresholds: Thresholds, stop: threading.Event, *,
          on_ready: Callable[[str], None] | None = None) -> None:
    """Run the monitor's web server (blocking) until ``stop`` is set: the page and its scripts served by msdc,
    a JSON snapshot pushed once a second over server-sent events (msdc.pipeline.live.monitor.server).
    ``on_ready`` receives the page's address once it listens (port 0: a free port); ServeError (an OSError)
    when it cannot listen, saying on what and why."""
    from msdc.pipeline.live.monitor.server import serve as _serve

    _serve(state, host, port, thresholds, stop, on_ready=on_ready)
