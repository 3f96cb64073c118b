"""Receiving UDP feeds: one socket and one thread per feed, each putting the datagrams it reads into its own
bounded queue (a full queue drops the datagram and counts it: never silently); a decoding thread takes them
in batches, hands them to the recorder and decodes them (decode.BatchDecoder)."""

from __future__ import annotations

import ipaddress
import logging
import queue
import socket
import struct
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass

from msdc.pipeline.live.decode import Datagram

log = logging.getLogger("msdc.live")

QUEUE_DATAGRAMS = 50_000  # per feed: ~7 s of a busy centre's 7,000 datagrams a second
BATCH_S = 0.2  # the decoding thread decodes what arrived every this many seconds...
BATCH_DATAGRAMS = 20_000  # ...or as soon as this many are waiting
RECEIVE_BUFFER_BYTES = 8 << 20  # the socket's own buffer asked of the kernel (it may grant less)
POLL_S = 0.2  # how often a receiving thread looks at the stop flag
MAX_DATAGRAM_BYTES = 65_535


@dataclass(frozen=True)
class Endpoint:
    """A feed's address: an IPv4 multicast group or unicast address, and a UDP port."""

    host: str
    port: int

    @property
    def multicast(self) -> bool:
        return ipaddress.IPv4Address(self.host).is_multicast

    @property
    def name(self) -> str:
        """The feed's name in the counters and the recording: udp:HOST:PORT."""
        return f"udp:{self.host}:{self.port}"


def parse_endpoint(text: str, option: str) -> Endpoint:
    """ADDR:PORT (IPv4 address, port 1-65535), else ValueError naming ``option`` and the value."""
    host, sep, port = str(text).strip().rpartition(":")
    if not sep or not host:
        raise ValueError(f"{option} {text!r}: expected ADDR:PORT (e.g. 239.1.2.3:8600 or 127.0.0.1:8600)")
    try:
        ipaddress.IPv4Address(host)
    except ValueError:
        raise ValueError(f"{option} {text!r}: {host!r} is not an IPv4 address") from None
    if not port.isdigit() or not 1 <= int(port) <= 65535:
        raise ValueError(f"{option} {text!r}: the port must be a number from 1 to 65535") from None
    return Endpoint(host, int(port))


def open_socket(endpoint: Endpoint, iface: str | None) -> socket.socket:
    """A UDP socket receiving ``endpoint``: bound to the group and joined to it on ``iface`` (default: the
    interface the kernel chooses) for a multicast group, bound to the address for unicast. OSError if the
    port is taken or the address is not this machine's."""
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM, socket.IPPROTO_UDP)
    try:
        if endpoint.multicast:  # several listeners of one group may share the port
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, RECEIVE_BUFFER_BYTES)
        except OSError:
            pass  # the kernel's default buffer
        sock.bind((endpoint.host, endpoint.port))
        if endpoint.multicast:
            mreq = struct.pack("4s4s", socket.inet_aton(endpoint.host), socket.inet_aton(iface or "0.0.0.0"))
            sock.setsockopt(socket.IPPROTO_IP, socket.IP_ADD_MEMBERSHIP, mreq)
        sock.settimeout(POLL_S)
    except OSError:
        sock.close()
        raise
    return sock


class Listener:
    """Receive feeds (one thread each), decode them in batches in one more thread, record them: start(),
    then stop() (which drains the queues, decodes and records what was received, and closes the
    recording)."""

    def __init__(self, endpoints: list[Endpoint], state, decoder, recorder=None, *, iface: str | None = None,
                 queue_datagrams: int = QUEUE_DATAGRAMS, batch_s: float = BATCH_S,
                 on_drop: Callable[[str, int], None] | None = None):
        self.endpoints, self.state, self.decoder, self.recorder = endpoints, state, decoder, recorder
        self.iface, self.batch_s = iface, batch_s
        self.queues: list[queue.Queue] = [queue.Queue(queue_datagrams) for _ in endpoints]
        self.sockets: list[socket.socket] = []
        self.stopping = threading.Event()
        self.threads: list[threading.Thread] = []
        self.on_drop = on_drop
        self.failure: BaseException | None = None  # what ended the decoding thread, if anything did

    def open(self) -> None:
        """Open every feed's socket (OSError names the feed; those opened are closed again)."""
        for e in self.endpoints:
            try:
                self.sockets.append(open_socket(e, self.iface))
            except OSError as exc:
                self.close_sockets()
                where = f" (--iface {self.iface})" if self.iface and e.multicast else ""
                raise OSError(exc.errno, f"{e.host}:{e.port}: cannot receive{where}: {exc.strerror or exc}"
                              ) from exc

    def start(self) -> None:
        """Open the sockets (if not yet) and start the threads."""
        if not self.sockets:
            self.open()
        for i, sock in enumerate(self.sockets):
            t = threading.Thread(target=self._receive, args=(i, sock), name=f"msdc-receive-{i}", daemon=True)
            self.threads.append(t)
        self.decoding = threading.Thread(target=self._decode_loop, name="msdc-decode", daemon=True)
        for t in (*self.threads, self.decoding):
            t.start()

    def stop(self) -> None:
        """Stop receiving, then decode and record what is queued, and close the sockets and recording."""
        self.stopping.set()
        decoding = getattr(self, "decoding", None)
        for t in (*self.threads, *([decoding] if decoding is not None else [])):
            if t.ident is not None:  # started (a Ctrl-C may come as start() starts them)
                t.join()
        self.close_sockets()
        if self.recorder is not None:
            self.recorder.close()

    def close_sockets(self) -> None:
        for s in self.sockets:
            s.close()
        self.sockets = []

    def _receive(self, i: int, sock: socket.socket) -> None:
        """Read datagrams into feed i's queue until stopped; a full queue drops (and counts) them."""
        name, q, state = self.endpoints[i].name, self.queues[i], self.state
        recv = sock.recvfrom
        while not self.stopping.is_set():
            try:
                data, source = recv(MAX_DATAGRAM_BYTES)
            except TimeoutError:
                continue
            except OSError as exc:
                if self.stopping.is_set():
                    return
                log.error("%s: receiving failed: %s", name, exc)
                time.sleep(POLL_S)
                continue
            wall_s = time.time()
            state.received(name, len(data), wall_s)
            try:
                q.put_nowait(Datagram(i, wall_s, data, source))
            except queue.Full:
                state.dropped(name)
                if self.on_drop is not None:
                    self.on_drop(name, 1)

    def take(self, limit: int = BATCH_DATAGRAMS) -> list[Datagram]:
        """What the queues hold (up to ``limit`` datagrams), in arrival order."""
        batch: list[Datagram] = []
        for q in self.queues:
            while len(batch) < limit:
                try:
                    batch.append(q.get_nowait())
                except queue.Empty:
                    break
        if len(self.queues) > 1:
            batch.sort(key=lambda d: d.wall_s)
        return batch

    def waiting(self) -> int:
        return sum(q.qsize() for q in self.queues)

    def _decode_loop(self) -> None:
        """Every batch_s (or as soon as BATCH_DATAGRAMS wait) record and decode what arrived; after stop,
        what is left."""
        try:
            while True:
                stopping = self.stopping.is_set()
                deadline = time.monotonic() + self.batch_s
                while not stopping and time.monotonic() < deadline and self.waiting() < BATCH_DATAGRAMS:
                    time.sleep(0.01)
                    stopping = self.stopping.is_set()
                if stopping:
                    for t in self.threads:
                        t.join()
                batch = self.take()
                while batch:
                    self.handle(batch)
                    batch = self.take() if stopping else []
                if stopping:
                    return
        except BaseException as exc:  # said by the job (listen_job); receiving goes on counting what arrives
            self.failure = exc

    def handle(self, batch: list[Datagram]) -> None:
        """Record a batch, then decode it."""
        if self.recorder is not None:
            self.recorder.write(batch)
        self.decoder.decode(batch)
