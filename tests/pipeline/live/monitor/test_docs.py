"""docs/guide/live-monitor.md shows the thresholds as declared and names every key of the JSON snapshot."""

from __future__ import annotations

import re
import time
from pathlib import Path

from live_fake_state import ReplayState, synthetic_measurements

from msdc.pipeline.live.health import Memory, snapshot
from msdc.pipeline.live.monitor import Thresholds, thresholds_markdown

PAGE = Path(__file__).resolve().parents[4] / "docs" / "guide" / "live-monitor.md"


def test_the_thresholds_table_is_the_declared_one() -> None:
    text = PAGE.read_text(encoding="utf-8")
    table = re.search(r"<!-- thresholds -->\n(.*?)\n<!-- /thresholds -->", text, re.S)
    assert table is not None and table.group(1) == thresholds_markdown()


def test_every_key_of_the_snapshot_is_documented() -> None:
    state = ReplayState(synthetic_measurements(), speed=50.0, start_wall_s=time.time() - 20.0)
    th = Thresholds(window_s=60.0)
    _, memory = snapshot(state.recent(60.0), state.counters(), {}, time.time() - 2.0, state.started_wall_s(),
                         th)
    snap, _ = snapshot(state.recent(60.0), state.counters(), {"048:25/201": time.time() - 1.0}, time.time(),
                       state.started_wall_s(), th, memory)
    assert isinstance(memory, Memory) and snap["targets"] and snap["sensors"] and snap["feeds"]
    keys = set(snap) | set(snap["sensors"][0]) | set(snap["sensors"][0]["pd"]) | set(snap["feeds"][0]) \
        | set(snap["targets"][0]) | set(snap["centre"]) | {"error"}
    quoted = re.findall(r"`([^`]*)`", PAGE.read_text(encoding="utf-8"))  # every `code` span of the page
    documented = {w for q in quoted for w in re.findall(r"\w+", q)}
    assert sorted(keys - documented) == []
    assert len(keys) > 40 and "last_status_age_s" in documented
