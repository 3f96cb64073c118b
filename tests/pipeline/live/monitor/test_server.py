"""The monitor's web server over real HTTP on loopback: the page and its files come from msdc itself, the
snapshot and the event stream carry the replayed fixture's sensors, a client that drops its stream leaves
the server serving, a bad state is reported on the page, a taken port is refused with a message."""

from __future__ import annotations

import json
import re
import socket
import time
import urllib.error
import urllib.request

import pytest
from live_fake_state import ReplayState, running, synthetic_measurements

from msdc.pipeline.live.monitor import Thresholds, serve
from msdc.pipeline.live.monitor.server import ServeError

THRESHOLDS = Thresholds(silent_s=5.0, window_s=30.0)


@pytest.fixture(scope="module")
def frame():
    return synthetic_measurements()


def get(url: str) -> tuple[int, dict, bytes]:
    try:
        with urllib.request.urlopen(url, timeout=5) as r:
            return r.status, dict(r.headers), r.read()
    except urllib.error.HTTPError as e:
        return e.code, dict(e.headers), e.read()


def first_event(url: str) -> tuple[int, dict]:
    """The first snapshot of the event stream (its id and JSON); the connection is then dropped."""
    with urllib.request.urlopen(url + "events", timeout=5) as r:
        assert r.headers["Content-Type"].startswith("text/event-stream")
        seq = None
        for line in r:
            line = line.decode()
            if line.startswith("id: "):
                seq = int(line[4:])
            if line.startswith("data: "):
                return seq, json.loads(line[6:])
    raise AssertionError("the stream ended without an event")


def test_the_page_and_its_files_come_from_msdc(frame) -> None:
    state = ReplayState(frame, speed=20.0, start_wall_s=time.time() - 10.0)
    with running(state, THRESHOLDS) as (url, _, _):
        assert url.startswith("http://127.0.0.1:")
        status, headers, body = get(url)
        assert status == 200 and "default-src 'none'" in headers["content-security-policy"]
        links = re.findall(r'(?:src|href)="([^"]*)"', body.decode())
        assert sorted(links) == ["data:,", "static/monitor.css", "static/monitor.js"]  # nothing from outside
        for link in links[1:]:
            assert get(url + link)[0] == 200
        assert get(url + "static/../server.py")[0] == 404
        assert get(url + "static/monitor.js")[1]["content-type"].startswith(("text/javascript",
                                                                           "application/javascript"))
        status, _, body = get(url + "snapshot.json")
        snap = json.loads(body)
        assert snap["schema"] == "msdc-live-monitor/1"
        assert [s["sensor_id"] for s in snap["sensors"]] == ["021:0/1", "048:25/201"]  # the replayed ones
        assert len(snap["targets"]) == 6  # three aircraft seen by both
        assert snap["thresholds"] == {"silent_s": 5.0, "min_pd": 0.97, "min_mode3a_valid": 0.98,
                                      "min_modec_valid": 0.96, "window_s": 30.0}


def test_dropped_streams_leave_the_server_serving(frame) -> None:
    state = ReplayState(frame, speed=20.0, start_wall_s=time.time() - 10.0)
    with running(state, THRESHOLDS) as (url, thread, _):
        first, snap = first_event(url)
        assert {s["sensor_id"] for s in snap["sensors"]} == {"021:0/1", "048:25/201"}
        for _ in range(5):  # clients that go away mid-stream, the hard way
            s = socket.create_connection(("127.0.0.1", int(url.rsplit(":", 1)[1].strip("/"))))
            s.sendall(b"GET /events HTTP/1.1\r\nHost: x\r\n\r\n")
            assert b"text/event-stream" in s.recv(4096)
            s.close()
        later, snap = first_event(url)
        for _ in range(25):  # the next snapshot (once a second)
            if later > first:
                break
            time.sleep(0.2)
            later, snap = first_event(url)
        assert later > first and thread.is_alive()  # new snapshots, pushed to a new page
        assert get(url + "snapshot.json")[0] == 200


def test_stop_ends_the_server_with_a_page_still_listening(frame) -> None:
    state = ReplayState(frame, speed=20.0, start_wall_s=time.time() - 10.0)
    with running(state, THRESHOLDS) as (url, thread, stop):
        stream = urllib.request.urlopen(url + "events", timeout=5)
        assert stream.readline().startswith(b"retry:")
        stop.set()
        thread.join(5.0)
        assert not thread.is_alive()  # the open stream ended with the server
        stream.close()


class BrokenState(ReplayState):
    def recent(self, window_s: float):
        raise RuntimeError("the state broke")


def test_a_failing_snapshot_is_reported_and_the_server_runs_on(frame) -> None:
    state = BrokenState(frame, speed=20.0)
    with running(state, THRESHOLDS) as (url, thread, _):
        _, snap = first_event(url)
        assert "snapshot failed" in snap["error"] and "the state broke" in snap["error"]
        assert get(url)[0] == 200 and thread.is_alive()


def test_a_taken_port_is_refused_naming_the_address(frame) -> None:
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen(1)
        port = taken.getsockname()[1]
        import threading
        with pytest.raises(ServeError, match=f"cannot listen on 127.0.0.1:{port}"):
            serve(ReplayState(frame, speed=1.0), "127.0.0.1", port, THRESHOLDS, threading.Event())
