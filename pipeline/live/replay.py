"""Replaying recordings as UDP: the datagrams of pcap and pcapng captures (and the frames of final and GPS
recordings) as they were captured, a raw recording one data block per datagram (framed as msdc decode frames
it: pipeline.live.raw_blocks; the bytes it skips are said, not sent); each sent at its original time, scaled
by ``speed``.

Times: a capture's own capture times; a raw file has none, so each block goes out at the time of day of its
first record that has one (I048/140, I021/073...: what msdc decodes as time_of_day), a block without one
(a category msdc does not decode, a block that fails) at the time of the block before it. Within a recording
the order of the file is kept: a block stamped earlier than the one before it goes out right after it.
Several recordings are merged by time."""

from __future__ import annotations

import math
import socket
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from msdc.pipeline.live.receive import Endpoint
from msdc.pipeline.meta import REPLAYED_FORMATS

SECONDS_PER_DAY = 86400
HALF_DAY_S = 43200
TIMED_FORMATS = tuple(f for f in REPLAYED_FORMATS if f != "raw")  # each datagram with its capture time
ABSOLUTE_FORMATS = ("pcap", "pcapng")  # ...a dated one (final and gps: times of day, as raw)
SLEEP_MIN_S = 0.0005  # datagrams due within this are sent at once (the OS sleeps no finer)
SKIPPED_SHOWN = 20  # runs of skipped bytes said one per line, per raw recording (as msdc decode lists them)


class ReplayError(ValueError):
    """A recording cannot be replayed: names it and why."""


@dataclass
class Schedule:
    """The datagrams of one or more recordings in sending order: seconds from the first, and their bytes;
    the warnings about the recordings' bytes (a raw file's bytes skipped, not sent)."""

    time_s: np.ndarray  # float64, non-decreasing, 0 for the first datagram
    data: list[bytes]
    warnings: list[str] = field(default_factory=list)

    @property
    def span_s(self) -> float:
        return float(self.time_s[-1]) if len(self.time_s) else 0.0

    def __len__(self) -> int:
        return len(self.data)


def recording_datagrams(path: str | Path, fmt: str | None = None
                        ) -> tuple[np.ndarray, list[bytes], str, list[str]]:
    """(time in seconds, non-decreasing, file order; datagram bytes; the recording's format; warnings about
    its bytes) of one recording; ReplayError when it cannot be replayed."""
    from msdc.asterix.containers import read_segments
    from msdc.pipeline.model.sources import path_text

    path = Path(path)
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise ReplayError(f"{path_text(path)}: cannot read: {exc.strerror or exc}") from exc
    try:
        seg = read_segments(data, fmt)
    except ValueError as exc:
        raise ReplayError(f"{path_text(path)}: {exc}") from exc
    if seg.format == "raw":
        times, blocks, said = _raw_blocks(path_text(path), data, seg)
        return times, blocks, "raw", said
    if seg.format not in TIMED_FORMATS:
        sent = ", ".join(REPLAYED_FORMATS)
        raise ReplayError(f"{path_text(path)}: a {seg.format} recording; msdc replay sends {sent} recordings")
    if not len(seg.start):
        raise ReplayError(f"{path_text(path)}: no ASTERIX payload found in this {seg.format} recording")
    times = seg.capture_day.astype(np.float64) * SECONDS_PER_DAY + seg.capture_tod
    if seg.format in ("final", "gps"):  # a day number (or none): times of day only, unwrapped in file order
        times = _unwrap(seg.capture_tod)
    payloads = [data[a:b] for a, b in zip(seg.start.tolist(), seg.stop.tolist(), strict=True)]
    return _monotonic(times), payloads, seg.format, []


def _raw_blocks(name: str, data: bytes, seg) -> tuple[np.ndarray, list[bytes], list[str]]:
    """A raw recording's data blocks as msdc decode frames them (pipeline.live.raw_blocks), each one's time
    (module doc), and the bytes framing skipped (not sent), said as decode says them; ``name``: the path as
    text."""
    from msdc.pipeline.live.raw_blocks import raw_blocks

    if not data:
        raise ReplayError(f"{name}: empty recording")
    found = raw_blocks(name, np.frombuffer(data, np.uint8), seg)
    if found.not_asterix:
        raise ReplayError(f"{found.not_asterix}; nothing sent")
    if not np.isfinite(found.time_s).any():
        raise ReplayError(f"{name}: no record with a time of day: nothing to time the blocks by")
    blocks = [data[a:b] for a, b in zip(found.start.tolist(), found.stop.tolist(), strict=True)]
    return _monotonic(_unwrap(_carry(found.time_s))), blocks, _skipped_words(name, found.skipped)


def _skipped_words(name: str, skipped: list[tuple[int, int, str]]) -> list[str]:
    """A warning per run of bytes skipped (offset, reason, as msdc decode lists them), SKIPPED_SHOWN at
    most, then how many more."""
    said = [f"{name}: offset {at}: {why}: {n} bytes skipped, not sent"
            for at, n, why in skipped[:SKIPPED_SHOWN]]
    if len(skipped) > SKIPPED_SHOWN:
        said.append(f"{name}: {len(skipped) - SKIPPED_SHOWN} more run(s) of bytes skipped, not sent "
                    "('msdc stats' groups them by reason)")
    return said


def _carry(t: np.ndarray) -> np.ndarray:
    """NaN times take the time before them (the first valid one at the start)."""
    t = t.copy()
    valid = np.flatnonzero(np.isfinite(t))
    t[:valid[0]] = t[valid[0]]
    idx = np.where(np.isfinite(t), np.arange(len(t)), 0)
    return t[np.maximum.accumulate(idx)]


def _unwrap(tod: np.ndarray) -> np.ndarray:
    """Times of day in file order made continuous across midnights (a drop of more than 12 h is a new day)."""
    tod = _carry(np.asarray(tod, np.float64)) if np.isfinite(tod).any() else np.zeros(len(tod))
    steps = np.diff(tod, prepend=tod[:1])
    return tod + SECONDS_PER_DAY * np.cumsum(steps < -HALF_DAY_S) - SECONDS_PER_DAY * np.cumsum(
        steps > HALF_DAY_S)


def _monotonic(t: np.ndarray) -> np.ndarray:
    """File order kept: each time at least the one before it (NaN: the one before)."""
    t = np.where(np.isfinite(t), t, -np.inf)
    t = np.maximum.accumulate(t)
    return np.where(np.isfinite(t), t, t[np.isfinite(t)][0] if np.isfinite(t).any() else 0.0)


def schedule(paths: list[str | Path], fmt: str | None = None) -> Schedule:
    """Every recording's datagrams merged by time (a stable merge: each file's order kept), as seconds from
    the first datagram. Recordings that do not overlap in time are replayed one after the other only if
    their times say so: their absolute times are kept (a raw file's are times of day). ReplayError when a
    capture (pcap, pcapng: dated capture times) is given with a recording of times of day alone (raw, final,
    gps): their clocks cannot be merged (the schedule spanned 57 years, and replay waited in silence)."""
    times, data, clocks, said = [], [], {}, []
    for p in paths:
        t, d, kind, warnings = recording_datagrams(p, fmt)
        times.append(t)
        data.extend(d)
        said += warnings
        clocks.setdefault(kind in ABSOLUTE_FORMATS, p)
    if len(clocks) == 2:
        raise ReplayError(f"{clocks[True]} (a capture, dated by its capture times) and {clocks[False]} "
                          "(times of day, no date) cannot be merged by time: replay them one at a time")
    t = np.concatenate(times)
    order = np.argsort(t, kind="stable")
    t = t[order]
    return Schedule(t - t[0], [data[i] for i in order], said)


class InterfaceError(OSError):
    """The ``iface`` address cannot send (not an address of this machine): its fault, not the
    destination's."""


def sending_socket(to: Endpoint, iface: str | None, ttl: int) -> socket.socket:
    """A UDP socket sending to ``to``: multicast out of ``iface`` (default: the kernel's route) with ``ttl``
    and loop-back on (a listener on this machine hears it). InterfaceError when ``iface`` cannot be used."""
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM, socket.IPPROTO_UDP)
    try:
        try:
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_SNDBUF, 8 << 20)
        except OSError:
            pass
        if to.multicast:
            sock.setsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_TTL, ttl)
            sock.setsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_LOOP, 1)
        else:
            sock.setsockopt(socket.IPPROTO_IP, socket.IP_TTL, max(ttl, 1))
        if iface:
            try:
                if to.multicast:
                    sock.setsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_IF, socket.inet_aton(iface))
                sock.bind((iface, 0))
            except OSError as exc:
                raise InterfaceError(exc.errno, exc.strerror) from None
        sock.connect((to.host, to.port))
    except OSError:
        sock.close()
        raise
    return sock


@dataclass
class Sent:
    """What a replay sent."""

    datagrams: int = 0
    bytes: int = 0
    passes: int = 0  # times the schedule was gone through (--loop)
    wall_s: float = 0.0
    late_s: float = 0.0  # the most a datagram went out after its scaled time
    refused: int = 0  # ICMP port-unreachable notices (no receiver yet): the datagram is sent again, once


def _send(sock: socket.socket, data: bytes, out: Sent) -> None:
    """One datagram. A connected UDP socket reports an earlier datagram's ICMP port unreachable (nothing
    listening at the destination, yet or any more) on a later send, which then sends nothing: counted and
    sent again (the notice is consumed), so a receiver started late or restarted loses nothing more."""
    try:
        sock.send(data)
    except ConnectionRefusedError:
        out.refused += 1
        sock.send(data)


def send(sched: Schedule, sock: socket.socket, *, speed: float = 1.0, loop: bool = False,
         duration_s: float | None = None, stop: Callable[[], bool] = lambda: False,
         clock: Callable[[], float] = time.monotonic, sleep: Callable[[float], None] = time.sleep,
         out: Sent | None = None) -> Sent:
    """Send the schedule, each datagram at its time / ``speed`` from the start; again and again with
    ``loop`` (the next pass starts one mean datagram interval after the last, 1 s of recording when there
    is no interval); until ``duration_s`` (wall) or ``stop()``. Counted in ``out`` (a new Sent when None),
    which holds what was sent when an exception (Ctrl-C) ends it."""
    out = Sent() if out is None else out
    if not len(sched):
        return out
    gap_s = sched.span_s / (len(sched) - 1) if len(sched) > 1 and sched.span_s > 0 else 1.0
    pass_s = sched.span_s + gap_s
    t0 = clock()
    end = math.inf if duration_s is None else t0 + duration_s
    times = sched.time_s / speed
    while True:
        base = t0 + out.passes * pass_s / speed
        i = 0
        n = len(sched)
        while i < n:
            now = clock()
            if now >= end or stop():
                out.wall_s = now - t0
                return out
            due = base + times[i]
            if due - now > SLEEP_MIN_S:
                sleep(min(due - now, end - now, 0.1))
                continue
            j = int(np.searchsorted(times, now - base, side="right"))  # everything due by now
            j = max(j, i + 1)
            for k in range(i, j):  # counted as each goes: an interrupt says what went
                d = sched.data[k]
                _send(sock, d, out)
                out.datagrams += 1
                out.bytes += len(d)
            out.late_s = max(out.late_s, now - due)
            i = j
        out.passes += 1
        if not loop:
            out.wall_s = clock() - t0
            return out
