"""For the live monitor's tests: a stand-in for msdc.pipeline.live.state.LiveState (the protocol of issue
#30's live interface) that replays a recording's measurement rows against the wall clock, accelerated: a row
of report time t is "received" at start + (t - t0) / speed. One sensor can be silenced from a given moment,
as if its feed stopped. And the monitor run on a free loopback port in a thread."""

from __future__ import annotations

import contextlib
import threading
import time
from pathlib import Path

import numpy as np
import pandas as pd

from msdc.pipeline.live.monitor import Thresholds, serve

ROOT = Path(__file__).resolve().parents[1]
FEED = "udp:239.1.2.3:8600"


def fixture_measurements() -> pd.DataFrame:
    """fixtures/radar.ast and fixtures/adsb.ast decoded into measurement rows as the jobs do (sensors from
    fixtures/sensors.toml), with the radar's Mode 3/A and Mode C validity (I048/070, I048/090 V bit clear)
    as the live state gives them: mode3a_valid, modec_valid."""
    from msdc.pipeline.model.load import load, load_measurements
    from msdc.pipeline.model.sensors import read_sensors

    paths = [ROOT / "fixtures" / "radar.ast", ROOT / "fixtures" / "adsb.ast"]
    _, frame = load_measurements(paths, read_sensors(ROOT / "fixtures" / "sensors.toml"))
    radar = load([paths[0]]).frames[48][["offset", "mode3a_v", "flight_level_v"]]
    bits = radar.set_index("offset")
    is_radar = (frame["sensor_kind"] == "radar").to_numpy()
    offsets = frame["offset"].to_numpy()
    for bit, valid in (("mode3a_v", "mode3a_valid"), ("flight_level_v", "modec_valid")):
        v = pd.array([pd.NA] * len(frame), dtype="boolean")
        got = bits[bit].reindex(offsets[is_radar])
        v[is_radar] = pd.array((got == 0).where(got.notna(), pd.NA).to_numpy(), dtype="boolean")
        frame[valid] = v
    return frame.sort_values("time", kind="stable", ignore_index=True)


def synthetic_measurements(duration_s: float = 600.0) -> pd.DataFrame:
    """A small made-up recording for the server's tests (no decoding): a 4 s radar "048:25/201" and an
    ADS-B station "021:0/1" (a report a second) seeing three aircraft flying north from 2.7 N 101.7 E."""
    parts = []
    for sensor, kind, period_s in (("048:25/201", "radar", 4.0), ("021:0/1", "adsb", 1.0)):
        t = np.arange(0.0, duration_s, period_s)
        for k in range(3):
            parts.append(pd.DataFrame({
                "time": pd.Timestamp("2026-11-28T12:00:00Z") + pd.to_timedelta(t + 0.3 * k, unit="s"),
                "sensor_id": sensor, "sensor_kind": kind, "aircraft_id": f"7500{k}0",
                "track_number": pd.array([100 + k] * t.size, "Int16"), "latitude": 2.7 + t * 1e-3,
                "longitude": 101.7 + 0.2 * k, "flight_level": 300.0, "mode3a": f"100{k}",
                "callsign": f"MAS{k}",
                "mode3a_valid": pd.array([kind == "radar" or pd.NA] * t.size, "boolean")}))
    return pd.concat(parts, ignore_index=True).sort_values("time", kind="stable", ignore_index=True)


class ReplayState:
    """The LiveState protocol over a measurement frame replayed at ``speed`` times real time from now."""

    def __init__(self, frame: pd.DataFrame, speed: float, feed: str = FEED,
                 start_wall_s: float | None = None) -> None:
        self._lock = threading.Lock()
        self._started = time.time() if start_wall_s is None else start_wall_s
        t = frame["time"].to_numpy("datetime64[ns]").astype("int64") / 1e9
        self._frame = frame.assign(wall_s=self._started + (t - t[0]) / speed, feed=feed)
        self._wall = self._frame["wall_s"].to_numpy(float)
        self._sensor = self._frame["sensor_id"].astype(str).to_numpy(object)
        self._silenced: dict[str, float] = {}
        self.feed = feed

    def silence(self, sensor_id: str, at_wall_s: float | None = None) -> None:
        """No row of this sensor arrives after at_wall_s (now by default)."""
        with self._lock:
            self._silenced[sensor_id] = time.time() if at_wall_s is None else at_wall_s

    def _arrived(self, now: float) -> np.ndarray:
        ok = self._wall <= now
        with self._lock:
            for s, at in self._silenced.items():
                ok &= ~((self._sensor == s) & (self._wall > at))
        return ok

    def counters(self) -> dict[str, dict]:
        now = time.time()
        ok = self._arrived(now)
        records = pd.Series(self._sensor[ok]).value_counts().to_dict() if ok.any() else {}
        last = float(self._wall[ok].max()) if ok.any() else None
        # every datagram of the replay frames (one row each): the protocol's parts add up to the packets
        return {self.feed: {"packets": int(ok.sum()), "bytes": 60 * int(ok.sum()), "framed": int(ok.sum()),
                            "unframed": 0, "empty": 0, "decode_errors": 0, "dropped": 0,
                            "records": {str(k): int(v) for k, v in records.items()},
                            "last_packet_wall_s": last}}

    def recent(self, window_s: float) -> pd.DataFrame:
        now = time.time()
        ok = self._arrived(now) & (self._wall >= now - window_s)
        return self._frame.loc[ok].reset_index(drop=True)

    def status_times(self) -> dict[str, float]:
        return {}  # the fixture recordings hold no CAT034

    def started_wall_s(self) -> float:
        return self._started


@contextlib.contextmanager
def running(state, thresholds: Thresholds, timeout_s: float = 10.0):
    """msdc's live monitor serving ``state`` on 127.0.0.1 (a free port): yields its address, its thread and
    its stop event."""
    stop = threading.Event()
    ready: list[str] = []
    got = threading.Event()
    failed: list[BaseException] = []

    def run() -> None:
        try:
            serve(state, "127.0.0.1", 0, thresholds, stop,
                  on_ready=lambda url: (ready.append(url), got.set()))
        except BaseException as exc:  # reported by the test, not lost in the thread
            failed.append(exc)
            got.set()

    thread = threading.Thread(target=run, name="monitor-under-test", daemon=True)
    thread.start()
    assert got.wait(timeout_s), "the monitor did not start listening"
    assert not failed, failed
    try:
        yield ready[0], thread, stop
    finally:
        stop.set()
        thread.join(timeout_s)
    assert not thread.is_alive(), "the monitor did not stop"
    assert not failed, failed
