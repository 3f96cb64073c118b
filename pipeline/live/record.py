"""Recording what the feeds bring, byte for byte, as pcapng (the pcapng specification,
draft-ietf-opsawg-pcapng): a Section Header Block, one Interface Description Block per feed (link type 228,
raw IPv4; if_name the feed's name; if_tsresol 9: nanosecond timestamps) and one Enhanced Packet Block per
datagram, holding an IPv4 and UDP header (sender -> feed address) and the datagram's bytes as received,
stamped with its arrival time. Files are written as NAME.pcapng.part and renamed to NAME.pcapng once closed
and synced, so a reader never sees half a file under the final name; a new file starts every ``rotate_s``
(aligned to the UTC clock) or once a file reaches ``rotate_bytes``."""

from __future__ import annotations

import datetime as dt
import os
import socket
import struct
from collections.abc import Callable
from pathlib import Path

LINKTYPE_IPV4 = 228
SHB_TYPE, IDB_TYPE, EPB_TYPE = 0x0A0D0D0A, 1, 6
BYTE_ORDER_MAGIC = 0x1A2B3C4D
OPT_END, OPT_SHB_USERAPPL, OPT_IF_NAME, OPT_IF_TSRESOL = 0, 4, 2, 9
TS_UNITS_PER_S = 10**9  # if_tsresol 9
PART = ".part"
SUFFIX = ".pcapng"


def _option(code: int, value: bytes) -> bytes:
    """One pcapng option: code, length, value padded to 32 bits."""
    return struct.pack("<HH", code, len(value)) + value + b"\0" * (-len(value) % 4)


def _block(block_type: int, body: bytes) -> bytes:
    """A pcapng block: type, total length, body (a multiple of 4 bytes), total length."""
    total = 12 + len(body)
    return struct.pack("<II", block_type, total) + body + struct.pack("<I", total)


def section_header(application: str = "msdc listen") -> bytes:
    """The Section Header Block (little endian, version 1.0, section length unknown: -1)."""
    options = _option(OPT_SHB_USERAPPL, application.encode()) + _option(OPT_END, b"")
    return _block(SHB_TYPE, struct.pack("<IHHq", BYTE_ORDER_MAGIC, 1, 0, -1) + options)


def interface_description(name: str) -> bytes:
    """An Interface Description Block for one feed: raw IPv4, no snap length limit (0), nanoseconds."""
    options = (_option(OPT_IF_NAME, name.encode()) + _option(OPT_IF_TSRESOL, bytes([9]))
               + _option(OPT_END, b""))
    return _block(IDB_TYPE, struct.pack("<HHI", LINKTYPE_IPV4, 0, 0) + options)


def _ipv4_checksum(header: bytes) -> int:
    total = sum(struct.unpack("!10H", header))
    while total >> 16:
        total = (total & 0xFFFF) + (total >> 16)
    return ~total & 0xFFFF


def udp_packet(payload: bytes, source: tuple[str, int], destination: tuple[str, int], ident: int) -> bytes:
    """An IPv4 packet (no options, DF, TTL 64) holding a UDP datagram (checksum 0: none) of ``payload``."""
    total = 28 + len(payload)
    src, dst = socket.inet_aton(source[0]), socket.inet_aton(destination[0])
    header = struct.pack("!BBHHHBBH4s4s", 0x45, 0, total, ident & 0xFFFF, 0x4000, 64, 17, 0, src, dst)
    header = header[:10] + struct.pack("!H", _ipv4_checksum(header)) + header[12:]
    return header + struct.pack("!HHHH", source[1], destination[1], 8 + len(payload), 0) + payload


def enhanced_packet(interface: int, time_ns: int, packet: bytes) -> bytes:
    """An Enhanced Packet Block: interface id, timestamp (high, low 32 bits), captured = original length."""
    body = struct.pack("<IIIII", interface, time_ns >> 32, time_ns & 0xFFFFFFFF, len(packet), len(packet))
    return _block(EPB_TYPE, body + packet + b"\0" * (-len(packet) % 4))


class RecordingStopped(OSError):
    """Writing the recording failed (disk full...): recording stops, receiving goes on."""


class Recorder:
    """pcapng files in ``folder``, one interface per feed (``feeds``: names; ``addresses``: each feed's
    (host, port) for the packets' destination), rotated every ``rotate_s`` (UTC-aligned) or at
    ``rotate_bytes``. After a write error it records nothing more and says why (``error``)."""

    def __init__(self, folder: str | Path, feeds: list[str], addresses: list[tuple[str, int]], *,
                 rotate_s: float | None = None, rotate_bytes: int | None = None,
                 on_closed: Callable[[Path], None] | None = None):
        self.folder = Path(folder)
        self.feeds, self.addresses = list(feeds), list(addresses)
        self.rotate_s, self.rotate_bytes = rotate_s, rotate_bytes
        self.on_closed = on_closed  # called with each file closed under its final name
        self.files: list[Path] = []  # the recordings closed so far
        self.error: str | None = None
        self.packets = 0  # datagrams recorded in closed or open files
        self._fh = None
        self._part: Path | None = None
        self._final: Path | None = None
        self._period: int | None = None
        self._size = 0  # bytes of whole blocks written to the open file
        self._ident = 0
        self._pending: list[bytes] = []  # blocks of the open file not written yet
        self._pending_packets = 0  # packet blocks among them
        self._pending_bytes = 0

    def write(self, batch) -> None:
        """Append a batch of decode.Datagram; a write error stops the recording (closing what was written)."""
        if self.error is not None:
            return
        try:
            for d in batch:
                self._rotate(d.wall_s)
                packet = udp_packet(d.data, d.source, self.addresses[d.feed], self._ident)
                self._ident += 1
                self._pending.append(enhanced_packet(d.feed, round(d.wall_s * TS_UNITS_PER_S), packet))
                self._pending_packets += 1
                self._pending_bytes += len(self._pending[-1])
            self._flush()
        except OSError as exc:
            if self.error is None:
                self._failed(exc)

    def close(self) -> None:
        """Close the open file (synced, then renamed to its final name)."""
        if self._fh is None:
            return
        try:
            self._flush()
        except OSError as exc:
            self._failed(exc)
            return
        fh, part, final = self._fh, self._part, self._final
        self._fh = None
        try:
            os.fsync(fh.fileno())
            fh.close()
            os.replace(part, final)
            self._sync_folder()
            self.files.append(final)
            if self.on_closed is not None:
                self.on_closed(final)
        except OSError as exc:
            self._failed(exc, closing=(fh, part, final))

    # ------------------------------------------------------------------ internals

    def _flush(self) -> None:
        """Write the pending blocks (one write; the packets count once written)."""
        if self._pending and self._fh is not None:
            blocks, packets = self._pending, self._pending_packets
            self._pending, self._pending_packets, self._pending_bytes = [], 0, 0
            self._write(b"".join(blocks))
            self.packets += packets

    def _write(self, data: bytes) -> None:
        """Append whole blocks to the open (unbuffered) file: the seam the disk-full test replaces."""
        written = self._fh.write(data)
        if written != len(data):
            raise OSError(28, os.strerror(28))
        self._size += len(data)

    def _rotate(self, wall_s: float) -> None:
        """Open a file for a datagram arriving at ``wall_s`` when none is open or the open one is done."""
        period = int(wall_s // self.rotate_s) if self.rotate_s else None
        if self._fh is not None and (period != self._period
                                     or (self.rotate_bytes
                                         and self._size + self._pending_bytes >= self.rotate_bytes)):
            self.close()
            if self.error is not None:
                raise RecordingStopped(self.error)
        if self._fh is None:
            self._open(wall_s, period)

    def _open(self, wall_s: float, period: int | None) -> None:
        stamp = dt.datetime.fromtimestamp(wall_s, dt.UTC).strftime("%Y%m%dT%H%M%S")
        final = self.folder / f"msdc-{stamp}Z{SUFFIX}"
        n = 1
        while final.exists() or final.with_name(final.name + PART).exists() or final in self.files:
            final = self.folder / f"msdc-{stamp}Z-{n}{SUFFIX}"
            n += 1
        part = final.with_name(final.name + PART)
        self._fh = open(part, "wb", buffering=0)  # noqa: SIM115 (closed by close())
        self._part, self._final, self._period, self._size = part, final, period, 0
        self._pending = [section_header(), *(interface_description(f) for f in self.feeds)]
        self._pending_bytes = sum(len(b) for b in self._pending)

    def _failed(self, exc: OSError, closing=None) -> None:
        """Stop recording: keep the open file's whole blocks (truncated to them, renamed) if possible."""
        fh, part, final = closing or (self._fh, self._part, self._final)
        self._fh, self._pending, self._pending_packets, self._pending_bytes = None, [], 0, 0
        kept = ""
        if part is not None and fh is not None:
            try:
                if not fh.closed:
                    try:
                        fh.close()
                    except OSError:
                        pass
                if self._size:
                    os.truncate(part, self._size)
                    os.replace(part, final)
                    self.files.append(final)
                    kept = f"; {final} keeps the datagrams recorded before"
                else:
                    os.remove(part)
            except OSError:
                kept = f"; {part} holds what was written before (possibly cut short)"
        why = exc.strerror or str(exc)
        self.error = f"recording stopped: {why} (writing in {self.folder}){kept}; receiving goes on"

    def _sync_folder(self) -> None:
        try:
            fd = os.open(self.folder, os.O_RDONLY)
        except OSError:
            return
        try:
            os.fsync(fd)
        except OSError:
            pass
        finally:
            os.close(fd)
