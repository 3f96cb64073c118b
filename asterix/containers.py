"""Container layer: find the ASTERIX payloads in raw, pcap, pcapng, IOSS "final", GPS and ORADIS recordings.

Every input byte ends up in exactly one place: a payload range, ``container_bytes`` or a problem.
"""

from __future__ import annotations

import datetime as dt
import struct
from dataclasses import dataclass

import numpy as np
from numba import njit

from .recorders import (
    ANY_CATEGORY,
    GPS_HEADER_BYTES,
    ORADIS_HEADER_BYTES,
    blocks_tile,
    detect_recorder,
    read_gps,
    read_oradis,
)

FORMATS = ("raw", "pcap", "pcapng", "final", "gps", "oradis")
UNTIMED = ("raw", "oradis")  # no capture time: midnights are counted in file order from the reports' times
DETECT_BYTES = 1 << 17  # two maximal final frames: enough head for detect_format
SECONDS_PER_DAY = 86400
FINAL_HEADER_BYTES = 8
FINAL_TRAILER = b"\xa5\xa5\xa5\xa5"
FINAL_MIN_FRAME_BYTES = FINAL_HEADER_BYTES + len(FINAL_TRAILER)
FINAL_TOD_UNIT_S = 0.01
FINAL_TOD_LIMIT = 86400 * 100  # header times of day at or past 24 h are damage
FINAL_MAX_STEP = 600 * 100  # chained frames: times of day at most 10 minutes on...
FINAL_MAX_BACK = 100  # ... or at most 1 s back (as GPS frames chain)
# A capture time further than this from most of the packets around it is damage: from 12 h on, it would put
# its reports on another day (each goes on the day nearest its capture) and could re-date the recording.
CAPTURE_JUMP_S = 43200
CAPTURE_NEIGHBOURS = 8  # packets on each side that judge a capture time

_PCAP_MAGICS = {  # first four file bytes -> (big endian, nanosecond timestamps)
    b"\xd4\xc3\xb2\xa1": (False, False),
    b"\xa1\xb2\xc3\xd4": (True, False),
    b"\x4d\x3c\xb2\xa1": (False, True),
    b"\xa1\xb2\x3c\x4d": (True, True),
}
_PCAP_HEADER_BYTES = 24
_PCAP_MAX_PACKET_BYTES = 262144  # a captured length above this and the snapshot length is damage
_PCAPNG_SHB = b"\x0a\x0d\x0d\x0a"
_PCAPNG_BYTE_ORDERS = {b"\x1a\x2b\x3c\x4d": ">", b"\x4d\x3c\x2b\x1a": "<"}
# section header, interface description, packet, simple packet, name resolution, interface statistics,
# enhanced packet, IRIG timestamp, ARINC 429, systemd journal export, decryption secrets, custom blocks
_PCAPNG_BLOCK_TYPES = (0x0A0D0D0A, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 0xBAD, 0x40000BAD)

# Packet classes returned by _classify; codes >= 2 are problems.
_PKT_IGNORED, _PKT_UDP, _PKT_LINK, _PKT_FAMILY, _PKT_IPV6, _PKT_NOT_IP = 0, 1, 7, 8, 9, 10
_PKT_REASONS = {
    2: "IPv4 fragment (not reassembled)",
    3: "bad IPv4 header",
    4: "truncated IPv4 header",
    5: "truncated UDP header",
    6: "bad UDP length",
}
_LINKS_READ = "Ethernet 1, Linux SLL 113, Linux SLL2 276, raw IP 12, 101, 228, BSD loopback 0, 108"
_LOOPBACK_FAMILIES = (2, 10, 24, 28, 30)  # AF_INET; AF_INET6 of Linux, NetBSD/OpenBSD, FreeBSD, macOS
_FINAL_REASONS = {
    1: "impossible frame length",
    2: "bad frame trailer",
    3: "frame time of day at or past 24 h",
    4: "frame length does not lead to the next frame (damaged length)",
    5: "bytes after a frame that do not start a final frame",
}
_PCAPNG_REASONS = {1: "bad packet block", 2: "packet for unknown interface"}


@dataclass
class Segments:
    """ASTERIX payload byte ranges of one recording, their capture times, and the byte accounting."""

    format: str  # "raw" | "pcap" | "pcapng" | "final" | "gps" | "oradis"
    start: np.ndarray  # int64 file offset of each ASTERIX payload
    stop: np.ndarray  # int64 exclusive end offset
    capture_day: np.ndarray  # int64: days since 1970-01-01 UTC (pcap, pcapng), recording-day byte (final),
    #                          midnights counted in the recording times (gps), else -1 (also for a pcap/pcapng
    #                          capture time reported as implausible, so that its neighbours date it)
    capture_tod: np.ndarray  # float64 seconds since midnight of the capture; NaN when unknown
    dated: bool  # True when capture_day is a real calendar day (pcap, pcapng)
    exact: bool  # True when each payload must frame exactly into ASTERIX blocks
    container_bytes: int  # headers, trailers, padding and ignored (non-UDP) packets
    problems: list[tuple[int, int, str]]  # (file offset, length, reason) for damaged container structure


def detect_format(head: bytes) -> str:
    """Guess the container format from the first bytes of a file (pass >= DETECT_BYTES if available)."""
    head = bytes(head[:DETECT_BYTES])
    if head[:4] in _PCAP_MAGICS:
        return "pcap"
    if head[:4] == _PCAPNG_SHB:
        return "pcapng"
    first_bytes = _final_frame_bytes(head, 0)
    if first_bytes == 0:
        return detect_recorder(head, whole=len(head) < DETECT_BYTES) or "raw"
    if len(head) - first_bytes < 2:  # a single frame, or the next one is out of sight
        return "final"
    # The first trailer is strong evidence; the next frame need only have a plausible length, so that a
    # recording whose second frame is damaged is still recognised.
    second_bytes = int.from_bytes(head[first_bytes:first_bytes + 2], "big")
    return "final" if second_bytes >= FINAL_MIN_FRAME_BYTES else "raw"


def check_format(fmt) -> None:
    """ValueError unless ``fmt`` is None (detect) or one of FORMATS."""
    if fmt is not None and fmt not in FORMATS:
        raise ValueError(f"unknown container format {fmt!r}; expected one of {FORMATS}")


def readonly(buf: np.ndarray) -> np.ndarray:
    """``buf`` as a read-only array (a view when it was writable): the kernels then compile once, for the
    read-only bytes a mapped file gives, not again for a writable copy (about 6 s of a first run)."""
    if not buf.flags.writeable:
        return buf
    view = buf.view()
    view.flags.writeable = False
    return view


def read_segments(data: bytes | memoryview | np.ndarray, fmt: str | None = None) -> Segments:
    """Locate the ASTERIX payloads of a recording held in memory; fmt=None detects the format."""
    check_format(fmt)
    if isinstance(data, np.ndarray):
        buf = readonly(np.ascontiguousarray(data).reshape(-1).view(np.uint8))
    else:
        buf = readonly(np.frombuffer(data, dtype=np.uint8))
    fmt = fmt or detect_format(buf[:DETECT_BYTES].tobytes())
    if fmt == "raw":
        return _read_raw(buf)
    if fmt == "pcap":
        return _read_pcap(buf)
    if fmt == "pcapng":
        return _read_pcapng(buf)
    if fmt in ("gps", "oradis"):
        return _segments(fmt, buf.size, *(read_gps(buf) if fmt == "gps" else read_oradis(buf)))
    return _read_final(buf)


def recorder_hint(head: bytes) -> str | None:
    """The recorder format (final, gps, oradis) a head that detection took for raw would be detected as but
    for its first frame: read as that format it gives at least 4 payloads and no problem but one before the
    first payload (and the last frame cut by the end of the head), and detection takes it without the first
    frame. None otherwise, as for any raw stream (which detection keeps raw wherever it starts)."""
    head = bytes(head[:DETECT_BYTES])
    cut = len(head) == DETECT_BYTES
    for fmt in ("final", "gps", "oradis"):
        seg = read_segments(head, fmt)
        problems = [(at, n) for at, n, _ in seg.problems if not (cut and at + n == len(head))]
        if len(seg.start) < 4 or len(problems) > 1 or (problems and problems[0][0] >= seg.start[0]):
            continue
        second = int(seg.start[1])  # where the second frame starts (its data, for gps: the trailer follows)
        rest = {"final": head[second - FINAL_HEADER_BYTES:], "oradis": head[second - ORADIS_HEADER_BYTES:],
                "gps": head[:GPS_HEADER_BYTES] + head[second:]}[fmt]
        if detect_format(rest) == fmt:
            return fmt
    return None


def _final_frame_bytes(head: bytes, pos: int) -> int:
    """Length of the plausible final frame starting at pos in head, else 0."""
    if len(head) - pos < FINAL_MIN_FRAME_BYTES:
        return 0
    frame_bytes = int.from_bytes(head[pos:pos + 2], "big")
    end = pos + frame_bytes
    if frame_bytes < FINAL_MIN_FRAME_BYTES or end > len(head) or head[end - 4:end] != FINAL_TRAILER:
        return 0
    return frame_bytes


def _segments(fmt: str, n_bytes: int, start: np.ndarray, stop: np.ndarray, day: np.ndarray,
              tod: np.ndarray, problems: list[tuple[int, int, str]]) -> Segments:
    """Assemble a Segments; container bytes are whatever is neither payload nor problem."""
    problems.sort()
    payload_bytes = int((stop - start).sum())
    problem_bytes = sum(length for _, length, _ in problems)
    return Segments(fmt, start.astype(np.int64), stop.astype(np.int64), day.astype(np.int64),
                    tod.astype(np.float64), fmt in ("pcap", "pcapng"), fmt != "raw",
                    n_bytes - payload_bytes - problem_bytes, problems)


def _empty(fmt: str, n_bytes: int, problems: list[tuple[int, int, str]]) -> Segments:
    """Segments with no payload at all."""
    none = np.zeros(0, np.int64)
    return _segments(fmt, n_bytes, none, none, none, np.zeros(0), problems)


def _read_raw(buf: np.ndarray) -> Segments:
    """The whole file is one payload of concatenated ASTERIX data blocks."""
    if buf.size == 0:
        return _empty("raw", 0, [])
    return _segments("raw", buf.size, np.array([0]), np.array([buf.size]), np.array([-1]),
                     np.array([np.nan]), [])


# ---------------------------------------------------------------- numba helpers (byte-level walkers)

@njit(cache=True)
def _be16(buf, pos):
    return (np.int64(buf[pos]) << 8) | np.int64(buf[pos + 1])


@njit(cache=True)
def _u32(buf, pos, big):
    b0, b1 = np.int64(buf[pos]), np.int64(buf[pos + 1])
    b2, b3 = np.int64(buf[pos + 2]), np.int64(buf[pos + 3])
    if big:
        return (b0 << 24) | (b1 << 16) | (b2 << 8) | b3
    return (b3 << 24) | (b2 << 16) | (b1 << 8) | b0


@njit(cache=True)
def _ip_offset(buf, start, stop, link):
    """(file offset of the IP header inside a link-layer packet, 4 or 6: its version), or (0, code) with
    code -1 if it carries no IP, -2 for a link type msdc does not read, -3 for a loopback header whose
    address family is none of _LOOPBACK_FAMILIES, -4 for a raw IP packet (link type 101 or 12) that starts
    with neither an IPv4 nor an IPv6 header."""
    if link == 1:  # Ethernet
        pos, type_pos = start + 14, start + 12
    elif link == 113:  # Linux cooked SLL
        pos, type_pos = start + 16, start + 14
    elif link == 276:  # Linux cooked SLL2
        pos, type_pos = start + 20, start
    elif link == 228:  # raw IPv4
        return start, 4
    elif link == 101 or link == 12:  # raw IP: v4 or v6
        if stop <= start:
            return 0, -1
        version = buf[start] >> 4
        return (start, np.int64(version)) if version == 4 or version == 6 else (0, -4)
    elif link == 0 or link == 108:  # BSD loopback: 4-byte address family, AF_INET = 2 in either order
        if stop - start < 4:
            return 0, -1
        little, big = _u32(buf, start, False), _u32(buf, start, True)
        if little == 2 or big == 2:
            return start + 4, 4
        for family in _LOOPBACK_FAMILIES:
            if little == family or big == family:
                return start + 4, 6
        return 0, -3
    else:
        return 0, -2
    if pos > stop:
        return 0, -1
    ethertype = _be16(buf, type_pos)
    while (ethertype == 0x8100 or ethertype == 0x88A8 or ethertype == 0x9100) and pos + 4 <= stop:
        ethertype = _be16(buf, pos + 2)  # VLAN tag: 2-byte TCI, then the next ethertype
        pos += 4
    if ethertype == 0x0800:
        return pos, 4
    if ethertype == 0x86DD:
        return pos, 6
    return 0, -1


@njit(cache=True)
def _classify_packet(buf, start, stop, link):
    """(class, payload start, payload stop) of one captured packet; see _PKT_REASONS."""
    ip, version = _ip_offset(buf, start, stop, link) if stop > start else (0, -1)
    if version == -2:
        return _PKT_LINK, 0, 0
    if version == -3:
        return _PKT_FAMILY, 0, 0
    if version == -4:
        return _PKT_NOT_IP, 0, 0
    if version == 6:  # IPv6: a UDP datagram (next header 17) is reported as not read, anything else ignored
        if stop - ip >= 40 and buf[ip] >> 4 == 6 and buf[ip + 6] == 17:
            return _PKT_IPV6, 0, 0
        return _PKT_IGNORED, 0, 0
    if version < 0:
        return _PKT_IGNORED, 0, 0
    if stop - ip < 20:
        return 4, 0, 0
    header_bytes = (np.int64(buf[ip]) & 15) * 4
    if buf[ip] >> 4 != 4 or header_bytes < 20:
        return 3, 0, 0
    if stop - ip < header_bytes:
        return 4, 0, 0
    if buf[ip + 9] != 17:  # not UDP
        return _PKT_IGNORED, 0, 0
    if _be16(buf, ip + 6) & 0x3FFF:  # more-fragments flag or fragment offset
        return 2, 0, 0
    limit = stop
    total_bytes = _be16(buf, ip + 2)
    if total_bytes >= header_bytes and ip + total_bytes < limit:  # ignore link padding; 0 = TSO, unbounded
        limit = ip + total_bytes
    udp = ip + header_bytes
    if limit - udp < 8:
        return 5, 0, 0
    udp_bytes = _be16(buf, udp + 4)
    if udp_bytes < 8:
        return 6, 0, 0
    return _PKT_UDP, udp + 8, min(udp + udp_bytes, limit)


@njit(cache=True)
def _classify(buf, pkt_start, pkt_stop, link):
    """Vector form of _classify_packet over captured packet ranges with per-packet link types."""
    count = pkt_start.size
    kind = np.zeros(count, np.int8)
    pay_start = np.zeros(count, np.int64)
    pay_stop = np.zeros(count, np.int64)
    for i in range(count):
        kind[i], pay_start[i], pay_stop[i] = _classify_packet(buf, pkt_start[i], pkt_stop[i], link[i])
    return kind, pay_start, pay_stop


@njit(cache=True)
def _pcap_header_code(buf, pos, big, units_per_s, snap_limit):
    """0 if the 16-byte pcap record header at pos is plausible and its packet ends in the file, else why not:
    1 fewer than 16 bytes left, 3 timestamp fraction of a second too large, 4 captured length above the
    snapshot limit, 5 captured length above the original length, 2 packet runs past the end of the file."""
    if buf.size - pos < 16:
        return 1
    captured_bytes, original_bytes = _u32(buf, pos + 8, big), _u32(buf, pos + 12, big)
    if _u32(buf, pos + 4, big) >= units_per_s:
        return 3
    if captured_bytes > snap_limit:
        return 4
    if captured_bytes > original_bytes:
        return 5
    if pos + 16 + captured_bytes > buf.size:
        return 2
    return 0


@njit(cache=True)
def _pcap_close(buf, pos, big, ref_s):
    """True when the record at pos has a capture second within CAPTURE_JUMP_S of ref_s (or ref_s < 0)."""
    return ref_s < 0 or abs(_u32(buf, pos, big) - ref_s) <= CAPTURE_JUMP_S


@njit(cache=True)
def _pcap_strong(buf, pos, big, units_per_s, snap_limit, ref_s):
    """True when three plausible records chain from pos (fewer if the file ends exactly after them), each
    captured within CAPTURE_JUMP_S of the one before, the first within it of ref_s (unless ref_s < 0)."""
    for _ in range(3):
        if _pcap_header_code(buf, pos, big, units_per_s, snap_limit) != 0:
            return False
        if not _pcap_close(buf, pos, big, ref_s):
            return False
        ref_s = _u32(buf, pos, big)
        pos += 16 + _u32(buf, pos + 8, big)
        if pos == buf.size:
            return True
    return True


@njit(cache=True)
def _pcap_resync(buf, start, stop, big, units_per_s, snap_limit, ref_s):
    """First offset in [start, stop) where a strong record chain starts (see _pcap_strong), else stop."""
    for pos in range(start, min(stop, buf.size - 15)):
        if _pcap_strong(buf, pos, big, units_per_s, snap_limit, ref_s):
            return pos
    return stop


@njit(cache=True)
def _walk_pcap(buf, big, units_per_s, snap_limit, fill, pkt_start, pkt_stop, ts_s, ts_frac, bad):
    """Walk classic pcap records, resynchronising after damage; fills the arrays when fill.

    A record is kept when its header is plausible (_pcap_header_code) and either the next record header
    is plausible and captured within CAPTURE_JUMP_S of it, or no strong chain (_pcap_strong) starts inside
    it (else its captured length is wrong). Damage is reported from the damaged header up to the next
    strong chain: bad rows (offset, bytes, code, detail: the offset of the chain found inside the record
    for code 6, bytes past the end for code 2; offset of the record before when it did not chain, or -1).
    Returns (packets, bad rows).
    """
    pos, count, problems = 24, 0, 0
    ref_s = np.int64(-1)  # capture second of the last record kept
    before = np.int64(-1)  # offset of the last record kept when its next record header was not plausible
    while pos < buf.size:
        code = _pcap_header_code(buf, pos, big, units_per_s, snap_limit)
        captured_bytes = _u32(buf, pos + 8, big) if buf.size - pos >= 16 else np.int64(0)
        detail = np.int64(0)
        nxt = pos + 16 + captured_bytes
        if code == 0 or code == 2:
            chains = nxt == buf.size or (
                code == 0 and _pcap_header_code(buf, nxt, big, units_per_s, snap_limit) == 0
                and _pcap_close(buf, nxt, big, _u32(buf, pos, big)))
            inside = buf.size if chains else _pcap_resync(buf, pos + 1, min(nxt, buf.size), big, units_per_s,
                                                          snap_limit, _u32(buf, pos, big))
            if inside < min(nxt, buf.size):
                code, detail = 6, inside
            elif code == 0:
                if fill:
                    pkt_start[count], pkt_stop[count] = pos + 16, nxt
                    ts_s[count], ts_frac[count] = _u32(buf, pos, big), _u32(buf, pos + 4, big)
                count += 1
                ref_s = _u32(buf, pos, big)
                before = -1 if chains else pos
                pos = nxt
                continue
            else:
                detail = nxt - buf.size
        resume = buf.size
        if code != 1 and code != 2:
            resume = _pcap_resync(buf, pos + 1, buf.size, big, units_per_s, snap_limit, ref_s)
        if code == 1 or (code != 3 and _pcap_close(buf, pos, big, ref_s)):
            before = -1  # a record header but for its damage: the record before is not in question
        if fill:
            bad[problems, 0], bad[problems, 1], bad[problems, 2] = pos, resume - pos, code
            bad[problems, 3], bad[problems, 4] = detail, before
        problems += 1
        before = -1
        pos = resume
    return count, problems


@njit(cache=True)
def _final_frame_error(buf, pos):
    """0 if a well-formed final frame starts at pos, else a _FINAL_REASONS code."""
    if buf.size - pos < 2:
        return 1
    frame_bytes = _be16(buf, pos)
    end = pos + frame_bytes
    if frame_bytes < 12 or end > buf.size:
        return 1
    if buf[end - 4] != 0xA5 or buf[end - 3] != 0xA5 or buf[end - 2] != 0xA5 or buf[end - 1] != 0xA5:
        return 2
    return 0


@njit(cache=True)
def _final_tod(buf, pos):
    """Time of day (10 ms units) in the header of the frame at pos."""
    return (np.int64(buf[pos + 5]) << 16) | _be16(buf, pos + 6)


@njit(cache=True)
def _final_plausible(buf, pos):
    """A well-formed final frame at pos whose time of day is below 24 h."""
    return pos < buf.size and _final_frame_error(buf, pos) == 0 and _final_tod(buf, pos) < FINAL_TOD_LIMIT


@njit(cache=True)
def _final_chained(buf, pos, nxt):
    """A plausible frame at nxt whose time of day follows that of the frame at pos (as GPS frames chain)."""
    if not _final_plausible(buf, nxt):
        return False
    step = (_final_tod(buf, nxt) - _final_tod(buf, pos)) % FINAL_TOD_LIMIT
    return step <= FINAL_MAX_STEP or step >= FINAL_TOD_LIMIT - FINAL_MAX_BACK


@njit(cache=True)
def _final_ends(buf, pos):
    """True at the end of the file or where the rest is a frame cut by it (a truncated tail)."""
    return buf.size - pos < FINAL_MIN_FRAME_BYTES or pos + _be16(buf, pos) > buf.size


@njit(cache=True)
def _final_strong(buf, pos, end_ok):
    """Three chained frames from pos (two if the end follows; one if end_ok and the end follows); the end
    includes a frame cut by it. The first frame's data must be data blocks end to end (so that a false frame
    inside damaged data, whose length happens to reach a true frame, is not taken)."""
    if not _final_plausible(buf, pos):
        return False
    if not blocks_tile(buf, pos + FINAL_HEADER_BYTES, pos + _be16(buf, pos) - 4, ANY_CATEGORY):
        return False
    n1 = pos + _be16(buf, pos)
    if _final_ends(buf, n1):
        return end_ok
    if not _final_chained(buf, pos, n1):
        return False
    n2 = n1 + _be16(buf, n1)
    return _final_ends(buf, n2) or _final_chained(buf, n1, n2)


@njit(cache=True)
def _final_first_strong(buf, pos, stop, end_ok):
    """First offset in [pos, stop) where a strong frame starts, else stop."""
    for r in range(pos, stop):
        if _final_strong(buf, r, end_ok):
            return r
    return stop


@njit(cache=True)
def _final_resync(buf, pos):
    """Where the walk resumes from pos: the first strong frame, unless one starts inside it (its length then
    reached a true frame by coincidence: take the inner one, and so on); the end if none."""
    r = _final_first_strong(buf, pos, buf.size, True)
    while r < buf.size:
        inner_stop = min(r + _be16(buf, r), buf.size)
        inner = _final_first_strong(buf, r + 1, inner_stop, False)
        if inner == inner_stop:
            return r
        r = inner
    return buf.size


@njit(cache=True)
def _walk_final(buf, fill, seg_start, seg_stop, seg_day, seg_tod, bad_start, bad_stop, bad_code):
    """Walk final frames as recorders.py walks GPS frames (only from trusted positions; a frame that does not
    chain is kept unless a strong frame starts inside it; resynchronise on three chained frames); fills
    the arrays when fill. Returns (frames, problems)."""
    pos, frames, problems, trusted = np.int64(0), 0, 0, True
    while pos < buf.size:
        code = _final_frame_error(buf, pos)
        if code == 0 and _final_tod(buf, pos) >= FINAL_TOD_LIMIT:
            code = 3
        if trusted and code == 0:
            frame_bytes = _be16(buf, pos)
            nxt = pos + frame_bytes
            chains = _final_ends(buf, nxt) or _final_chained(buf, pos, nxt)
            # the first frame has no predecessor vouching for its start: it must not hide a chained frame
            if chains and frames + problems > 0 or _final_first_strong(buf, pos + 1, nxt, False) == nxt:
                if frame_bytes > 12:
                    if fill:
                        seg_start[frames] = pos + 8
                        seg_stop[frames] = nxt - 4
                        seg_day[frames] = buf[pos + 4]
                        seg_tod[frames] = _final_tod(buf, pos) * FINAL_TOD_UNIT_S
                    frames += 1
                pos, trusted = nxt, chains
                continue
            code = 4
        resume = _final_resync(buf, pos + (1 if trusted else 0))
        if resume > pos:
            if fill:
                bad_start[problems], bad_stop[problems] = pos, resume
                bad_code[problems] = code if code != 0 else 5
            problems += 1
        pos, trusted = resume, True
    return frames, problems


# ---------------------------------------------------------------- format readers

def _packet_segments(fmt: str, buf: np.ndarray, pkt_start: np.ndarray, pkt_stop: np.ndarray,
                     link: np.ndarray, day: np.ndarray, tod: np.ndarray,
                     problems: list[tuple[int, int, str]]) -> Segments:
    """Extract IPv4/UDP payloads from captured packets; problem packets are reported whole.

    A payload's packet whose capture time is implausible (``implausible_captures``) keeps its payload, loses
    its capture time (its reports are dated by the packets around it) and is reported at its timestamp field,
    the 8 bytes before the 8 that precede the packet data in both a pcap record and a pcapng packet block.
    """
    kind, pay_start, pay_stop = _classify(buf, pkt_start, pkt_stop, link)
    for code, reason in _PKT_REASONS.items():
        for i in np.flatnonzero(kind == code):
            problems.append((int(pkt_start[i]), int(pkt_stop[i] - pkt_start[i]), reason))
    for i in np.flatnonzero(kind == _PKT_IPV6):
        problems.append((int(pkt_start[i]), int(pkt_stop[i] - pkt_start[i]),
                         "IPv6 UDP packet: not read (msdc reads IPv4 only)"))
    for i in np.flatnonzero((kind == _PKT_LINK) | (kind == _PKT_FAMILY) | (kind == _PKT_NOT_IP)):
        why = _link_reason(int(link[i]), int(kind[i]))
        problems.append((int(pkt_start[i]), int(pkt_stop[i] - pkt_start[i]), why))
    keep = (kind == _PKT_UDP) & (pay_stop > pay_start)
    timed = (day >= 0) & np.isfinite(tod)
    bad_time = np.zeros(len(day), bool)
    bad_time[timed] = implausible_captures(day[timed], tod[timed])
    day, tod = day.copy(), tod.astype(np.float64)
    for i in np.flatnonzero(bad_time & keep):
        why = ("implausible capture time, more than 12 h from most packets around it: its reports are dated "
               f"by theirs (capture time {_stamp(day[i], tod[i])})")
        problems.append((int(pkt_start[i]) - 16, 8, why))
        day[i], tod[i] = -1, np.nan
    return _segments(fmt, buf.size, pay_start[keep], pay_stop[keep], day[keep], tod[keep], problems)


def _link_reason(link: int, kind: int) -> str:
    """Why a packet of a link type msdc does not read, or a loopback packet of no known family, is skipped."""
    if kind == _PKT_LINK:
        return f"packet of link type {link}, which msdc does not read (it reads {_LINKS_READ})"
    if kind == _PKT_NOT_IP:
        return (f"packet of link type {link} (raw IP) that starts with neither an IPv4 nor an IPv6 header: "
                "a wrong link type (an Ethernet capture?) or a damaged packet")
    return (f"packet of link type {link} (BSD loopback) whose address family is neither IPv4 nor IPv6: "
            "a wrong link type or a damaged packet")


def implausible_captures(day: np.ndarray, tod: np.ndarray,
                         neighbours: int = CAPTURE_NEIGHBOURS) -> np.ndarray:
    """True for each capture time (in file order) further than CAPTURE_JUMP_S from more than half of itself
    and its ``neighbours`` packets on each side: a damaged time. A clock step that lasts longer than
    ``neighbours`` packets keeps a majority on each side, so is never flagged."""
    seconds = day.astype(np.float64) * SECONDS_PER_DAY + tod
    agree = np.ones(len(seconds), np.int64)
    window = np.ones(len(seconds), np.int64)
    for shift in range(1, min(neighbours, len(seconds) - 1) + 1):
        close = np.abs(seconds[shift:] - seconds[:-shift]) <= CAPTURE_JUMP_S
        agree[shift:] += close
        agree[:-shift] += close
        window[shift:] += 1
        window[:-shift] += 1
    return 2 * agree < window


def _stamp(day: int, tod: float) -> str:
    """A capture time as an ISO UTC date-time, or as days and seconds when it is past the calendar's range."""
    try:
        return (dt.datetime(1970, 1, 1) + dt.timedelta(days=int(day), seconds=float(tod))).isoformat(" ")
    except OverflowError:
        return f"day {int(day)} after 1970-01-01, {float(tod):.6f} s"


def _day_tod(ts_s: np.ndarray, ts_frac: np.ndarray, units_per_s: int) -> tuple[np.ndarray, np.ndarray]:
    """(days since 1970-01-01, seconds since midnight) of Unix times given as seconds + fraction units."""
    seconds = ts_s + ts_frac // units_per_s
    return seconds // SECONDS_PER_DAY, seconds % SECONDS_PER_DAY + (ts_frac % units_per_s) / units_per_s


def _read_pcap(buf: np.ndarray) -> Segments:
    """Classic libpcap: 24-byte file header, then 16-byte record headers each followed by a packet."""
    magic = buf[:4].tobytes()
    if magic not in _PCAP_MAGICS:
        return _empty("pcap", buf.size, [(0, buf.size, "bad pcap magic")] if buf.size else [])
    if buf.size < _PCAP_HEADER_BYTES:
        return _empty("pcap", buf.size, [(0, buf.size, "truncated pcap file header")])
    big, nano = _PCAP_MAGICS[magic]
    link = struct.unpack_from(">I" if big else "<I", buf, 20)[0] & 0xFFFF
    units_per_s = 10**9 if nano else 10**6
    snap_bytes = struct.unpack_from(">I" if big else "<I", buf, 16)[0]
    snap_limit = max(snap_bytes, _PCAP_MAX_PACKET_BYTES)
    none, no_bad = np.zeros(0, np.int64), np.zeros((0, 5), np.int64)
    count, bad = _walk_pcap(buf, big, units_per_s, snap_limit, False, none, none, none, none, no_bad)
    pkt_start, pkt_stop, ts_s, ts_frac = (np.zeros(count, np.int64) for _ in range(4))
    bad_rows = np.zeros((bad, 5), np.int64)
    _walk_pcap(buf, big, units_per_s, snap_limit, True, pkt_start, pkt_stop, ts_s, ts_frac, bad_rows)
    problems = [(int(row[0]), int(row[1]), _pcap_reason(buf, big, row, units_per_s, snap_bytes))
                for row in bad_rows]
    day, tod = _day_tod(ts_s, ts_frac, units_per_s)
    return _packet_segments("pcap", buf, pkt_start, pkt_stop, np.full(count, link, np.int64), day, tod,
                            problems)


def _pcap_reason(buf: np.ndarray, big: bool, row: np.ndarray, units_per_s: int, snap_bytes: int) -> str:
    """Why the pcap bytes of a _walk_pcap bad row were skipped, and where reading resumes."""
    pos, length, code, detail, before = (int(v) for v in row)
    end = pos + length
    if code == 1:
        return f"truncated packet record header ({length} of its 16 bytes)"
    frac, captured, original = struct.unpack_from(">III" if big else "<III", buf, pos + 4)
    if code == 2:
        return (f"truncated packet record (captured length {captured}, {detail} bytes past the end of the "
                "file)")
    why = {
        3: f"implausible packet record header (timestamp fraction {frac}, not below {units_per_s})",
        4: f"captured length {captured} exceeds the snapshot length {snap_bytes}",
        5: f"captured length {captured} exceeds the original length {original}",
        6: f"captured length {captured} runs past the packet record at offset {detail}",
    }[code]
    if before >= 0:
        why = (f"implausible packet record header ({why.removeprefix('implausible packet record header (')})"
               if code != 3 else why)
        why += (f", where the captured length of the record at offset {before} leads: that length may be the "
                "damage")
    if end < buf.size:
        return why + f"; reading resumes at the next plausible packet record, offset {end}"
    return why + "; no plausible packet record follows"


def _idb_options(raw: memoryview, order: str, pos: int, end: int) -> tuple[int, int]:
    """(timestamp units per second, timestamp offset in s) from an Interface Description Block's options."""
    units_per_s, offset_s = 10**6, 0
    while end - pos >= 4:
        code, length = struct.unpack_from(order + "HH", raw, pos)
        value = pos + 4
        if code == 0 or value + length > end:
            break
        if code == 9 and length >= 1:  # if_tsresol: 10^-v, or 2^-v when the top bit is set
            resolution = raw[value]
            units_per_s = 2 ** (resolution & 0x7F) if resolution & 0x80 else 10**resolution
        elif code == 14 and length == 8:  # if_tsoffset
            offset_s = struct.unpack_from(order + "q", raw, value)[0]
        pos = value + (length + 3) // 4 * 4
    return units_per_s, offset_s


@njit(cache=True)
def _walk_pcapng(buf, pos, big, interfaces, snap_bytes, fill, packets, bad):
    """Walk one section's packet and skippable blocks from pos; stop at an SHB, IDB or broken block framing.

    Fills (when fill) packets rows (offset, captured bytes, interface, ts high, ts low or -1 if none) and bad
    rows (offset, bytes, _PCAPNG_REASONS code). Returns (packet rows, bad rows, offset where it stopped).
    """
    count, problems = 0, 0
    while buf.size - pos >= 12:
        block_type, block_bytes = _u32(buf, pos, big), _u32(buf, pos + 4, big)
        if block_type == 1 or block_type == 0x0A0D0D0A or block_bytes < 12 or block_bytes % 4 != 0:
            break
        if block_bytes > buf.size - pos or _u32(buf, pos + block_bytes - 4, big) != block_bytes:
            break
        if block_type == 2 or block_type == 6:  # obsolete / enhanced packet block
            start, captured_bytes, interface, ts_high, ts_low = pos + 28, -1, 0, 0, 0
            if block_bytes >= 32:
                interface = _u32(buf, pos + 8, big)
                if block_type == 2:  # 2-byte interface id, then a 2-byte drop count
                    interface = interface >> 16 if big else interface & 0xFFFF
                ts_high, ts_low = _u32(buf, pos + 12, big), _u32(buf, pos + 16, big)
                captured_bytes = _u32(buf, pos + 20, big)
                if captured_bytes > block_bytes - 32:
                    captured_bytes = -1
        elif block_type == 3:  # simple packet block: interface 0, no timestamp, captured length implied
            start, captured_bytes, interface, ts_high, ts_low = pos + 12, -1, 0, 0, -1
            if block_bytes >= 16:
                captured_bytes = min(_u32(buf, pos + 8, big), block_bytes - 16)
                if snap_bytes > 0:
                    captured_bytes = min(captured_bytes, snap_bytes)
        else:
            pos += block_bytes
            continue
        if captured_bytes < 0 or (interface >= interfaces and captured_bytes > 0):
            if fill:
                if captured_bytes < 0:
                    bad[problems, 0], bad[problems, 1], bad[problems, 2] = pos, block_bytes, 1
                else:
                    bad[problems, 0], bad[problems, 1], bad[problems, 2] = start, captured_bytes, 2
            problems += 1
        elif interface < interfaces:
            if fill:
                packets[count, 0], packets[count, 1], packets[count, 2] = start, captured_bytes, interface
                packets[count, 3], packets[count, 4] = ts_high, ts_low
            count += 1
        pos += block_bytes
    return count, problems, pos


@njit(cache=True)
def _pcapng_block_ok(buf, pos, big):
    """Offset just past the pcapng block at pos when its type is a known one (_PCAPNG_BLOCK_TYPES) and its
    leading and trailing lengths agree, else -1."""
    if buf.size - pos < 12:
        return -1
    block_type, block_bytes = _u32(buf, pos, big), _u32(buf, pos + 4, big)
    known = False
    for kind in _PCAPNG_BLOCK_TYPES:
        known = known or block_type == kind
    if not known or block_bytes < 12 or block_bytes % 4 != 0 or block_bytes > buf.size - pos:
        return -1
    if _u32(buf, pos + block_bytes - 4, big) != block_bytes:
        return -1
    return pos + block_bytes


@njit(cache=True)
def _pcapng_resync(buf, start, big):
    """First offset >= start of a block that _pcapng_block_ok takes and that ends the file or is followed by
    another it takes (a chain of two), else the buffer size."""
    for pos in range(start, buf.size - 11):
        nxt = _pcapng_block_ok(buf, pos, big)
        if nxt >= 0 and (nxt == buf.size or _pcapng_block_ok(buf, nxt, big) >= 0):
            return pos
    return buf.size


def _pcapng_damage(buf: np.ndarray, pos: int, order: str, why: str) -> tuple[int, tuple[int, int, str]]:
    """(where reading resumes, the problem) for the pcapng block at pos whose framing is broken (why)."""
    resume = int(_pcapng_resync(buf, pos + 1, order == ">"))
    if resume < buf.size:
        why += f"; reading resumes at the next block whose lengths agree, offset {resume}"
    else:
        why += "; no block whose lengths agree follows"
    return resume, (pos, resume - pos, why)


def _read_pcapng(buf: np.ndarray) -> Segments:
    """pcapng: walk blocks by their lengths; packets come from EPB, SPB and obsolete packet blocks.

    Section and interface blocks and broken framing are handled here; runs of other blocks by _walk_pcapng.
    """
    raw, n = memoryview(buf), buf.size
    problems: list[tuple[int, int, str]] = []
    interfaces: list[tuple[int, int, int, int]] = []  # every section's: (link, units per s, offset s, snap)
    first_interface = 0  # index in interfaces of the current section's interface 0
    packets = [np.zeros((0, 5), np.int64)]  # rows (offset, bytes, interface index, ts high, ts low)
    pos, order = 0, ""
    while pos < n:
        if order:
            section_interfaces = interfaces[first_interface:]
            snap_bytes = section_interfaces[0][3] if section_interfaces else 0
            walk = (buf, pos, order == ">", len(section_interfaces), snap_bytes)
            count, bad, _ = _walk_pcapng(*walk, False, np.zeros((0, 5), np.int64), np.zeros((0, 3), np.int64))
            rows, bad_rows = np.zeros((count, 5), np.int64), np.zeros((bad, 3), np.int64)
            _, _, pos = _walk_pcapng(*walk, True, rows, bad_rows)
            rows[:, 2] += first_interface
            packets.append(rows)
            problems.extend((int(offset), int(length), _PCAPNG_REASONS[int(code)])
                            for offset, length, code in bad_rows)
            if pos >= n:
                break
        if n - pos < 12:
            problems.append((pos, n - pos, "truncated block"))
            break
        if raw[pos:pos + 4] == _PCAPNG_SHB:
            order = _PCAPNG_BYTE_ORDERS.get(bytes(raw[pos + 8:pos + 12]), "")
            if not order:
                problems.append((pos, n - pos, "bad section header byte order"))
                break
            first_interface = len(interfaces)
        elif not order:
            problems.append((pos, n - pos, "missing section header"))
            break
        block_type, block_bytes = struct.unpack_from(order + "II", raw, pos)
        if block_bytes < 12 or block_bytes % 4 or block_bytes > n - pos:
            past = f", {block_bytes - (n - pos)} bytes past the end of the file" * (block_bytes > n - pos)
            pos, problem = _pcapng_damage(buf, pos, order, f"bad block length ({block_bytes}{past})")
            problems.append(problem)
            continue
        trailing = struct.unpack_from(order + "I", raw, pos + block_bytes - 4)[0]
        if trailing != block_bytes:
            why = f"block length mismatch (leading length {block_bytes}, trailing length {trailing})"
            pos, problem = _pcapng_damage(buf, pos, order, why)
            problems.append(problem)
            continue
        if block_type == 0x0A0D0D0A and block_bytes < 28:
            problems.append((pos, block_bytes, "bad section header block"))
        elif block_type == 1 and block_bytes < 20:
            problems.append((pos, block_bytes, "bad interface description block"))
            interfaces.append((-1, 10**6, 0, 0))
        elif block_type == 1:  # Interface Description Block
            link, _, snap_bytes = struct.unpack_from(order + "HHI", raw, pos + 8)
            interfaces.append((link, *_idb_options(raw, order, pos + 16, pos + block_bytes - 4), snap_bytes))
        pos += block_bytes
    table = np.concatenate(packets)
    start, stop, interface = table[:, 0], table[:, 0] + table[:, 1], table[:, 2]
    link = np.array([link for link, *_ in interfaces], np.int64)[interface]
    day, tod = _pcapng_day_tod(table[:, 3], table[:, 4], interface, interfaces)
    return _packet_segments("pcapng", buf, start, stop, link, day, tod, problems)


def _pcapng_day_tod(ts_high: np.ndarray, ts_low: np.ndarray, interface: np.ndarray,
                    interfaces: list[tuple[int, int, int, int]]) -> tuple[np.ndarray, np.ndarray]:
    """(days since 1970-01-01, seconds since midnight) of pcapng timestamps; -1 / NaN where ts_low < 0."""
    day, tod = np.full(len(interface), -1, np.int64), np.full(len(interface), np.nan)
    for index, (_, units_per_s, offset_s, _) in enumerate(interfaces):
        rows = np.flatnonzero((interface == index) & (ts_low >= 0))
        if len(rows) == 0:
            continue
        if units_per_s < 2**63:
            ts = (ts_high[rows].astype(np.uint64) << np.uint64(32)) | ts_low[rows].astype(np.uint64)
            seconds, fraction = np.divmod(ts, np.uint64(units_per_s))
            seconds = seconds.astype(np.int64) + np.int64(offset_s)  # wraps only for absurd ts / resolution
            day[rows] = seconds // SECONDS_PER_DAY
            tod[rows] = seconds % SECONDS_PER_DAY + fraction / units_per_s
        else:  # resolutions finer than 2^-63 s: exact integers in Python
            for row in rows:
                seconds, fraction = divmod((int(ts_high[row]) << 32) | int(ts_low[row]), units_per_s)
                day[row], second_of_day = divmod(seconds + offset_s, SECONDS_PER_DAY)
                tod[row] = second_of_day + fraction / units_per_s
    return day, tod


def _read_final(buf: np.ndarray) -> Segments:
    """IOSS final: frames of 8-byte header, ASTERIX data and an A5A5A5A5 trailer."""
    none_i, none_f = np.zeros(0, np.int64), np.zeros(0)
    frames, bad = _walk_final(buf, False, none_i, none_i, none_i, none_f, none_i, none_i, none_i)
    start, stop, day = (np.zeros(frames, np.int64) for _ in range(3))
    bad_start, bad_stop, bad_code = (np.zeros(bad, np.int64) for _ in range(3))
    tod = np.zeros(frames)
    _walk_final(buf, True, start, stop, day, tod, bad_start, bad_stop, bad_code)
    problems = [(int(s), int(e - s), _FINAL_REASONS[int(c)])
                for s, e, c in zip(bad_start, bad_stop, bad_code, strict=True)]
    return _segments("final", buf.size, start, stop, day, tod, problems)
