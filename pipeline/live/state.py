"""``LiveState``: what the live feeds have brought so far (counters per feed, the recent reports, the last
status message of each sensor), written by the receiving and decoding threads and read by the monitor page.

The contract with the monitor is docs/guide/live.md's and the notes' ``LiveState`` protocol: counters(),
recent(window_s), status_times(), started_wall_s(); everything here is thread-safe (one lock).
"""

from __future__ import annotations

import threading
import time
from collections import deque
from dataclasses import dataclass, field

import pandas as pd

KEEP_S = 300.0  # the recent reports are kept this long (wall clock): the monitor's windows are shorter
# every datagram received (packets) is exactly one of: framed, unframed, empty, dropped, or still waiting
# in its queue to be decoded (packets less the other four); decode_errors count data blocks, not datagrams
COUNTER_KEYS = ("packets", "bytes", "framed", "unframed", "empty", "decode_errors", "dropped")


def waiting_datagrams(feed: dict) -> int:
    """The feed's datagrams received but not decoded yet (in its queue or the batch being decoded): its
    packets less those framed, unframed, empty and dropped, which each datagram is exactly one of once
    decoded."""
    return feed["packets"] - sum(feed[k] for k in ("framed", "unframed", "empty", "dropped"))


@dataclass
class FeedCounters:
    """One feed's counts since listening started."""

    packets: int = 0
    bytes: int = 0
    framed: int = 0  # datagrams whose bytes frame exactly into ASTERIX data blocks
    unframed: int = 0  # datagrams that do not frame exactly into ASTERIX data blocks
    empty: int = 0  # datagrams of no byte: no data block, no garbage (neither framed nor unframed)
    decode_errors: int = 0  # data blocks that frame but whose records do not decode (or a failed batch)
    dropped: int = 0  # datagrams dropped because msdc's own queue was full
    records: dict[str, int] = field(default_factory=dict)  # sensor_id ("048:20/129") -> records
    last_record_wall_s: dict[str, float] = field(default_factory=dict)  # sensor_id -> last arrival
    last_packet_wall_s: float | None = None

    def as_dict(self) -> dict:
        """The protocol's dict (a copy)."""
        return {"packets": self.packets, "bytes": self.bytes, "framed": self.framed,
                "unframed": self.unframed, "empty": self.empty, "decode_errors": self.decode_errors,
                "dropped": self.dropped, "records": dict(self.records),
                "last_record_wall_s": dict(self.last_record_wall_s),
                "last_packet_wall_s": self.last_packet_wall_s}


class LiveState:
    """Counters per feed, the reports of the last ``keep_s`` seconds and the sensors' last status messages;
    thread-safe: the receiving and decoding threads write, the web server reads."""

    def __init__(self, feeds: list[str] | tuple[str, ...] = (), keep_s: float = KEEP_S,
                 clock=time.time):
        self._lock = threading.Lock()
        self._clock = clock
        self._started = clock()
        self._keep_s = keep_s
        self._feeds: dict[str, FeedCounters] = {name: FeedCounters() for name in feeds}
        self._recent: deque[tuple[float, pd.DataFrame]] = deque()  # (latest wall_s in it, reports)
        self._status: dict[str, float] = {}
        self.recording_error: str | None = None  # why recording stopped (the job prints it)

    # ------------------------------------------------------------------ the monitor's protocol

    def counters(self) -> dict[str, dict]:
        """Per feed (by its name as given): packets, bytes, framed, unframed, empty, decode_errors, dropped,
        records per sensor_id and last_packet_wall_s (time.time() of the last datagram); a copy."""
        with self._lock:
            return {name: c.as_dict() for name, c in self._feeds.items()}

    def recent(self, window_s: float) -> pd.DataFrame:
        """The reports whose datagram arrived in the last ``window_s`` seconds (wall clock): the measurement
        schema's columns plus wall_s, feed, mode3a_valid and modec_valid (docs/guide/live.md)."""
        since = self._clock() - window_s
        with self._lock:
            parts = [frame for latest, frame in self._recent if latest >= since]
        if not parts:
            return empty_recent()
        frame = pd.concat(parts, ignore_index=True) if len(parts) > 1 else parts[0]
        return frame[frame["wall_s"].to_numpy() >= since].reset_index(drop=True)

    def status_times(self) -> dict[str, float]:
        """sensor_id -> time.time() of the last status message (north marker, sector...) of that sensor,
        under the status category's own id and the id of the reports it goes with (docs/guide/live.md)."""
        with self._lock:
            return dict(self._status)

    def started_wall_s(self) -> float:
        """time.time() when listening started."""
        return self._started

    # ------------------------------------------------------------------ what the threads write

    def feeds(self) -> list[str]:
        """The feeds' names, in the order given."""
        with self._lock:
            return list(self._feeds)

    def received(self, feed: str, n_bytes: int, wall_s: float) -> None:
        """One datagram arrived on ``feed``."""
        with self._lock:
            c = self._feeds.setdefault(feed, FeedCounters())
            c.packets += 1
            c.bytes += n_bytes
            c.last_packet_wall_s = wall_s

    def dropped(self, feed: str, count: int = 1) -> None:
        """``count`` datagrams of ``feed`` dropped: msdc's queue was full."""
        with self._lock:
            self._feeds.setdefault(feed, FeedCounters()).dropped += count

    def decoded(self, feed_counts: dict[str, dict], reports: pd.DataFrame | None,
                status: dict[str, float]) -> None:
        """Fold one decoded batch: per feed its "framed", "unframed", "empty", "decode_errors", "records"
        (sensor_id -> count) and "last_record_wall_s" (sensor_id -> the latest arrival of its records), the
        reports for recent() (with wall_s), the status messages' times."""
        now = self._clock()
        with self._lock:
            for feed, counts in feed_counts.items():
                c = self._feeds.setdefault(feed, FeedCounters())
                c.framed += counts.get("framed", 0)
                c.unframed += counts.get("unframed", 0)
                c.empty += counts.get("empty", 0)
                c.decode_errors += counts.get("decode_errors", 0)
                for sensor, n in counts.get("records", {}).items():
                    c.records[sensor] = c.records.get(sensor, 0) + n
                for sensor, t in counts.get("last_record_wall_s", {}).items():
                    c.last_record_wall_s[sensor] = max(t, c.last_record_wall_s.get(sensor, float("-inf")))
            if reports is not None and len(reports):
                self._recent.append((float(reports["wall_s"].max()), reports))
            while self._recent and self._recent[0][0] < now - self._keep_s:
                self._recent.popleft()
            for sensor, t in status.items():
                if t > self._status.get(sensor, float("-inf")):
                    self._status[sensor] = t

    def clashes(self) -> dict[str, list[str]]:
        """Sensor ids seen on more than one feed (clashing SAC/SIC): sensor_id -> the feeds, kept apart."""
        with self._lock:
            seen: dict[str, list[str]] = {}
            for feed, c in self._feeds.items():
                for sensor in c.records:
                    seen.setdefault(sensor, []).append(feed)
        return {s: feeds for s, feeds in sorted(seen.items()) if len(feeds) > 1}


def empty_recent() -> pd.DataFrame:
    """recent()'s columns with no row."""
    from msdc.pipeline.model.schema import conform

    frame = conform(pd.DataFrame())
    frame["wall_s"] = pd.Series(dtype="float64")
    frame["feed"] = pd.Series(dtype="object")
    frame["mode3a_valid"] = pd.Series(dtype="boolean")
    frame["modec_valid"] = pd.Series(dtype="boolean")
    return frame
