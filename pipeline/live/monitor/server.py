"""The live monitor's web server: Starlette on uvicorn, serving the page and its scripts from the package (no
internet), a JSON snapshot computed once a second by one thread for every page, pushed as server-sent
events. A page that closes or drops its connection ends only its own stream."""

from __future__ import annotations

import asyncio
import json
import logging
import socket
import threading
import time
from collections.abc import Callable
from pathlib import Path

import uvicorn
from starlette.applications import Starlette
from starlette.requests import Request
from starlette.responses import HTMLResponse, Response, StreamingResponse
from starlette.routing import Mount, Route
from starlette.staticfiles import StaticFiles

from msdc.pipeline.live.health import SCHEMA, Memory, lookback_s, snapshot
from msdc.pipeline.live.monitor import Thresholds

STATIC = Path(__file__).resolve().parent / "static"
PERIOD_S = 1.0  # one snapshot a second
POLL_S = 0.1  # how often a page's stream looks for a new snapshot
RETRY_MS = 2000  # the browser reconnects this long after a dropped stream
# the page loads nothing but what msdc serves (its own scripts and styles, the event stream)
CSP = ("default-src 'none'; script-src 'self'; style-src 'self'; connect-src 'self'; img-src 'self' data:; "
       "base-uri 'none'; form-action 'none'; frame-ancestors 'none'")
log = logging.getLogger("msdc.live.monitor")


class ServeError(OSError):
    """The monitor cannot listen on the address it was given; says which and why."""


class Publisher:
    """Computes the monitor's snapshot once a second from the live state (one computation for any number of
    pages) and keeps the latest as JSON text with a sequence number."""

    def __init__(self, state, thresholds: Thresholds, period_s: float = PERIOD_S) -> None:
        self.state, self.thresholds, self.period_s = state, thresholds, period_s
        self.done = threading.Event()
        self._lock = threading.Lock()
        self._memory: Memory | None = None
        self._seq, self._text = 0, json.dumps({"schema": SCHEMA, "pending": True})
        self._last: dict | None = None

    def latest(self) -> tuple[int, str]:
        """The latest snapshot's sequence number and JSON text."""
        with self._lock:
            return self._seq, self._text

    def publish_once(self) -> None:
        """Compute one snapshot; a failure keeps the last good one, marked with the error (the server runs
        on)."""
        now = time.time()
        try:
            frame = self.state.recent(lookback_s(self.thresholds))
            snap, self._memory = snapshot(frame, self.state.counters(), self.state.status_times(), now,
                                          float(self.state.started_wall_s()), self.thresholds, self._memory)
            text = json.dumps(snap, allow_nan=False, separators=(",", ":"), default=str)
            self._last = snap
        except Exception as exc:  # the monitor must outlive a bad snapshot: shown on the page, logged
            log.exception("live monitor: snapshot failed")
            snap = dict(self._last or {"schema": SCHEMA})
            snap["error"] = f"snapshot failed at {time.strftime('%H:%M:%S', time.gmtime(now))} UTC: {exc}"
            text = json.dumps(snap, allow_nan=False, separators=(",", ":"), default=str)
        with self._lock:
            self._seq += 1
            self._text = text

    def run(self, stop: threading.Event) -> None:
        """Publish every period until ``stop`` or ``done`` is set."""
        while not (stop.is_set() or self.done.is_set()):
            started = time.monotonic()
            self.publish_once()
            stop.wait(max(0.0, self.period_s - (time.monotonic() - started)))


def create_app(publisher: Publisher, stop: threading.Event) -> Starlette:
    """The monitor's routes: the page (/), its files (/static), the latest snapshot (/snapshot.json) and the
    event stream (/events: one ``data:`` line of snapshot JSON a second)."""
    page = (STATIC / "index.html").read_text(encoding="utf-8")
    headers = {"Content-Security-Policy": CSP, "Cache-Control": "no-store",
               "X-Content-Type-Options": "nosniff"}

    async def index(request: Request) -> Response:
        return HTMLResponse(page, headers=headers)

    async def latest(request: Request) -> Response:
        return Response(publisher.latest()[1], media_type="application/json",
                        headers={"Cache-Control": "no-store"})

    async def events(request: Request) -> Response:
        async def stream():
            yield f"retry: {RETRY_MS}\n\n"
            sent = -1
            while not (stop.is_set() or publisher.done.is_set()):
                seq, text = publisher.latest()
                if seq != sent:
                    sent = seq
                    yield f"id: {seq}\ndata: {text}\n\n"
                await asyncio.sleep(POLL_S)

        return StreamingResponse(stream(), media_type="text/event-stream",
                                 headers={"Cache-Control": "no-store", "X-Accel-Buffering": "no"})

    return Starlette(routes=[Route("/", index), Route("/snapshot.json", latest), Route("/events", events),
                             Mount("/static", StaticFiles(directory=STATIC), name="static")])


def listening_socket(host: str, port: int) -> socket.socket:
    """A TCP socket bound to host:port and listening; ServeError naming the address and the reason."""
    try:
        family, kind, proto, _, address = socket.getaddrinfo(host, port, type=socket.SOCK_STREAM)[0]
        sock = socket.socket(family, kind, proto)
    except (OSError, UnicodeError) as exc:
        raise ServeError(f"the monitor cannot listen on {host}:{port}: {exc}") from None
    try:
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        sock.bind(address)
        sock.listen(64)
    except OSError as exc:
        sock.close()
        raise ServeError(f"the monitor cannot listen on {host}:{port}: {exc.strerror or exc}") from None
    return sock


def url_of(sock: socket.socket) -> str:
    """The page's address for a listening socket (IPv6 in brackets)."""
    host, port = sock.getsockname()[:2]
    return f"http://[{host}]:{port}/" if ":" in host else f"http://{host}:{port}/"


def serve(state, host: str, port: int, thresholds: Thresholds, stop: threading.Event, *,
          on_ready: Callable[[str], None] | None = None) -> None:
    """Run the monitor (blocking) until ``stop`` is set. ``on_ready`` receives the page's address once the
    server listens (port 0: a free port). ServeError when it cannot listen."""
    sock = listening_socket(host, port)
    publisher = Publisher(state, thresholds)
    publisher.publish_once()  # the first page gets a snapshot at once
    server = uvicorn.Server(uvicorn.Config(create_app(publisher, stop), log_level="warning", lifespan="off",
                                           access_log=False, timeout_graceful_shutdown=2))

    def watch() -> None:
        """Tell on_ready the address once the server listens; stop the server once ``stop`` is set."""
        while on_ready is not None and not (server.started or publisher.done.is_set()):
            if stop.wait(0.05):
                break
        if on_ready is not None and server.started:
            on_ready(url_of(sock))
        while not (stop.wait(0.2) or publisher.done.is_set()):
            pass
        server.should_exit = True

    threads = [threading.Thread(target=publisher.run, args=(stop,), name="msdc-monitor-snapshots",
                                daemon=True),
               threading.Thread(target=watch, name="msdc-monitor-stop", daemon=True)]
    for t in threads:
        t.start()
    try:
        server.run(sockets=[sock])
    finally:
        publisher.done.set()
        sock.close()
