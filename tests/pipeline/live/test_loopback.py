"""listen and replay over the loopback interface (127.0.0.1, and multicast 239.255.x.x sent with TTL 0 out
of 127.0.0.1): what listen counts and records after a replay, against msdc stats on the same files (the
file reader, another code path) and the files' own data blocks; a feed that stops and resumes; msdc's own
queue full; a port already taken."""

from __future__ import annotations

import socket
import threading
import time
from pathlib import Path

import pytest
from asterix_bytes import block
from live_bytes import cat048_record, free_port, raw_blocks, send_all

from msdc.asterix.containers import read_segments
from msdc.pipeline.jobs.listen import ListenOptions, listen_job
from msdc.pipeline.jobs.options import OptionError, ReplayOptions, StatsOptions
from msdc.pipeline.jobs.replay import replay_job
from msdc.pipeline.jobs.stats import stats_job
from msdc.pipeline.live.decode import BatchDecoder
from msdc.pipeline.live.receive import Listener, parse_endpoint
from msdc.pipeline.live.state import LiveState

ROOT = Path(__file__).resolve().parents[3]
FIXTURES = [ROOT / "fixtures" / "radar.ast", ROOT / "fixtures" / "adsb.ast"]


class Running:
    """listen_job in a thread: started (sockets open) on entry, stopped and its result kept on exit."""

    def __init__(self, options: ListenOptions):
        self.options, self.stop, self.ready = options, threading.Event(), threading.Event()
        self.result, self.error, self.state, self.ingest = None, None, None, None

    def _ready(self, state):
        self.state = state
        self.ready.set()

    def packets(self) -> int:
        return sum(c["packets"] for c in self.state.counters().values())

    def _run(self):
        try:
            self.result = listen_job(self.options, stop=self.stop, say=lambda line: None, ready=self._ready,
                                     ingest=self.ingest)
        except Exception as exc:  # said by the test
            self.error = exc
            self.ready.set()

    def __enter__(self):
        self.thread = threading.Thread(target=self._run, daemon=True)
        self.thread.start()
        assert self.ready.wait(30) and self.error is None, self.error
        return self

    def __exit__(self, *exc):
        self.stop.set()
        self.thread.join(30)


def _wait(condition, timeout_s: float = 10.0) -> None:
    end = time.monotonic() + timeout_s
    while not condition():
        assert time.monotonic() < end, "timed out"
        time.sleep(0.02)


def test_listen_counts_and_records_a_replay_as_stats_reads_the_files(tmp_path):
    port = free_port()
    expected = stats_job(StatsOptions(inputs=tuple(map(str, FIXTURES)))).inputs
    per_sensor = {f"{cat:03d}:{sac}/{sic}": n for cat, sac, sic, n in (
        (48, 25, 201, expected[0]["records"][48]), (21, 0, 1, expected[1]["records"][21]))}
    with Running(ListenOptions(udp=(f"127.0.0.1:{port}",), record=str(tmp_path / "rec"))) as run:
        sent = replay_job(ReplayOptions(inputs=tuple(map(str, FIXTURES)), to=f"127.0.0.1:{port}",
                                        speed=40_000.0))
        _wait(lambda: run.packets() == sent.datagrams)
    (counters,) = run.result.counters.values()
    assert counters["packets"] == sent.datagrams and counters["dropped"] == 0
    assert counters["records"] == per_sensor and counters["unframed"] == counters["decode_errors"] == 0
    (path,) = run.result.recordings
    data = path.read_bytes()
    seg = read_segments(data)
    recorded = [data[a:b] for a, b in zip(seg.start, seg.stop, strict=True)]
    assert sorted(recorded) == sorted(b for f in FIXTURES for b in raw_blocks(f.read_bytes()))
    again = stats_job(StatsOptions(inputs=(str(path),))).inputs[0]["records"]
    assert again == {48: per_sensor["048:25/201"], 21: per_sensor["021:0/1"]}


def test_multicast_on_loopback(tmp_path):
    port = free_port()
    group = "239.255.77.1"
    records = [block(48, cat048_record(25, 201, 100.0 + i)) for i in range(3)]
    try:
        run = Running(ListenOptions(udp=(f"{group}:{port}",), iface="127.0.0.1")).__enter__()
    except AssertionError as exc:
        pytest.skip(f"multicast on loopback is not available here: {exc}")
    try:
        send_all(records, port, group)
        end = time.monotonic() + 3
        while run.packets() < 3 and time.monotonic() < end:
            time.sleep(0.02)
    finally:
        run.__exit__()
    (counters,) = run.result.counters.values()
    if counters["packets"] == 0:
        pytest.skip("multicast sent on 127.0.0.1 does not loop back in this sandbox")
    assert counters["packets"] == 3 and counters["records"] == {"048:25/201": 3}


def test_a_feed_that_stops_and_resumes():
    port = parse_endpoint(f"127.0.0.1:{free_port()}", "--udp")
    state = LiveState([port.name])
    listener = Listener([port], state, BatchDecoder(state, [port.name], reports=False), batch_s=0.05)
    listener.start()
    try:
        send_all([block(48, cat048_record(25, 201, 1.0))] * 2, port.port)
        _wait(lambda: sum(state.counters()[port.name]["records"].values()) == 2)
        first = state.counters()[port.name]["last_packet_wall_s"]
        time.sleep(0.3)
        assert state.counters()[port.name]["last_packet_wall_s"] == first  # silent: nothing moves
        send_all([block(48, cat048_record(25, 201, 2.0))], port.port)
        _wait(lambda: sum(state.counters()[port.name]["records"].values()) == 3)
        c = state.counters()[port.name]
        assert c["packets"] == 3 and c["last_packet_wall_s"] >= first + 0.3
    finally:
        listener.stop()


def test_an_empty_datagram_on_the_wire_is_counted_empty():
    """A UDP datagram of no byte, received for real: one packet, counted empty; with a whole block and
    garbage, the 3 packets are 1 framed + 1 unframed + 1 empty."""
    port = parse_endpoint(f"127.0.0.1:{free_port()}", "--udp")
    state = LiveState([port.name])
    listener = Listener([port], state, BatchDecoder(state, [port.name], reports=False), batch_s=0.05)
    listener.start()
    try:
        send_all([b"", block(48, cat048_record(25, 201, 1.0)), b"garbage"], port.port)
        _wait(lambda: sum(state.counters()[port.name][k] for k in ("framed", "unframed", "empty")) == 3)
        c = state.counters()[port.name]
        assert (c["packets"], c["bytes"]) == (3, 0 + len(block(48, cat048_record(25, 201, 1.0))) + 7)
        assert (c["framed"], c["unframed"], c["empty"], c["dropped"]) == (1, 1, 1, 0)
    finally:
        listener.stop()


def test_a_full_queue_drops_and_counts_never_silently():
    port = parse_endpoint(f"127.0.0.1:{free_port()}", "--udp")
    state = LiveState([port.name])
    decoder = BatchDecoder(state, [port.name], reports=False)
    gate = threading.Event()
    decode = decoder.decode

    def slow(batch):
        gate.wait(10)  # decoding stalls: the queue (2 datagrams) fills
        decode(batch)

    decoder.decode = slow
    listener = Listener([port], state, decoder, queue_datagrams=2, batch_s=0.01)
    listener.start()
    try:
        send_all([block(48, cat048_record(25, 201, float(i))) for i in range(20)], port.port)
        _wait(lambda: state.counters()[port.name]["packets"] == 20)
    finally:
        gate.set()
        listener.stop()
    c = state.counters()[port.name]
    decoded = sum(c["records"].values())
    assert c["dropped"] >= 20 - 2 - 2 and decoded + c["dropped"] == 20  # at most a batch and a queue kept


def test_a_full_disk_stops_the_recording_and_receiving_goes_on(tmp_path, monkeypatch):
    import errno

    from msdc.pipeline.live.record import Recorder

    port = parse_endpoint(f"127.0.0.1:{free_port()}", "--udp")
    state = LiveState([port.name])
    recorder = Recorder(tmp_path, [port.name], [(port.host, port.port)])
    real = Recorder._write

    def write(self, data):
        if self.packets >= 2:  # the disk fills once two datagrams are recorded
            raise OSError(errno.ENOSPC, "No space left on device")
        real(self, data)

    monkeypatch.setattr(Recorder, "_write", write)
    listener = Listener([port], state, BatchDecoder(state, [port.name], reports=False), recorder,
                        batch_s=0.02)
    listener.start()
    try:
        send_all([block(48, cat048_record(25, 201, 1.0))] * 2, port.port)
        _wait(lambda: sum(state.counters()[port.name]["records"].values()) == 2)
        send_all([block(48, cat048_record(25, 201, 2.0))] * 3, port.port)
        _wait(lambda: sum(state.counters()[port.name]["records"].values()) == 5)
    finally:
        listener.stop()
    assert "No space left on device" in recorder.error and listener.failure is None
    (path,) = recorder.files
    data = path.read_bytes()
    seg = read_segments(data)
    assert len(seg.start) == 2 and seg.problems == []  # the two recorded before, whole


def test_dataset_ingests_each_closed_recording(tmp_path):
    import pyarrow.parquet as pq

    from msdc.pipeline.cli import _ingester
    from msdc.pipeline.dataset.reader import category_parts

    port = free_port()
    options = ListenOptions(udp=(f"127.0.0.1:{port}",), record=str(tmp_path / "rec"),
                            dataset=str(tmp_path / "ds"))
    run = Running(options)
    run.ingest = _ingester(options.dataset, ())
    with run:
        send_all([block(48, cat048_record(25, 201, 80000.0 + i), cat048_record(25, 201, 80000.5 + i))
                  for i in range(4)], port)
        _wait(lambda: run.packets() == 4)
    assert len(run.result.ingested) == 1 and run.result.ingested == run.result.recordings
    parts = category_parts(tmp_path / "ds")
    assert set(parts) == {48} and sum(pq.read_metadata(p).num_rows for p in parts[48]) == 8


def test_a_port_already_taken_is_refused_naming_the_feed():
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as taken:
        taken.bind(("127.0.0.1", 0))
        port = taken.getsockname()[1]
        with pytest.raises(OptionError, match=rf"^--udp 127.0.0.1:{port}: cannot receive: Address already"):
            listen_job(ListenOptions(udp=(f"127.0.0.1:{port}",)), say=lambda line: None)


def test_listen_serves_the_monitor_of_a_replay(tmp_path):
    """listen --http end to end: the fixtures replayed over the loopback at 6,000 times real time (about 2 s)
    show on the monitor's snapshot as targets and sensors with counts; once the replay ends, the radar is
    said silent (--alarm-silent 1). The page itself is tested in a browser on a replaying state
    (tests/pipeline/live/monitor/test_page.py)."""
    import json
    import urllib.request

    port, http = free_port(), free_port()
    options = ListenOptions(udp=(f"127.0.0.1:{port}",), http=f"127.0.0.1:{http}",
                            sensors=str(ROOT / "fixtures" / "sensors.toml"), alarm_silent_s=1.0,
                            window_s=30.0)

    def snapshot() -> dict:
        with urllib.request.urlopen(f"http://127.0.0.1:{http}/snapshot.json", timeout=5) as reply:
            return json.loads(reply.read())

    with Running(options) as run:
        sent = replay_job(ReplayOptions(inputs=tuple(map(str, FIXTURES)), to=f"127.0.0.1:{port}",
                                        speed=6000.0))
        _wait(lambda: run.packets() == sent.datagrams)
        _wait(lambda: len(snapshot()["targets"]) > 0, timeout_s=5.0)
        snap = snapshot()
        assert {s["sensor_id"] for s in snap["sensors"]} == {"048:25/201", "021:0/1"}
        _wait(lambda: any(a["kind"] == "silent" and a.get("sensor_id") == "048:25/201"
                          for a in snapshot()["alarms"]), timeout_s=5.0)
    assert run.result.counters[f"udp:127.0.0.1:{port}"]["records"]["048:25/201"] > 0
