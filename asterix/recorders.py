"""Recorder containers: the GPS recorder format and ORADIS packets.

GPS: a 2200-byte file header, then frames of one ASTERIX data block followed by 10 bytes whose bytes
6-8 are the big-endian recording time of day in 1/128 s (the other 7 bytes are not documented
publicly: kept as container bytes). ORADIS: packets of a 6-byte header (big-endian packet length
counting the header, then 4 bytes a public decoder calls "time" without unit or epoch: opaque) and
ASTERIX data blocks.

The walk only stands on trusted positions: the start of the frames, the end of a frame that chains to
the next one, or a resynchronisation point. A frame that does not chain is kept unless a frame that
chains on starts inside it (then its length is wrong); after it, the walk resynchronises: the first
position where three frames chain (GPS: plausible blocks of the file's own categories, recording times
stepping forward by at most 10 minutes) or a packet whose payload frames exactly into data blocks
(ORADIS). Damage is reported with its offset and length; the byte account stays exact.
"""

from __future__ import annotations

import numpy as np
from numba import njit

GPS_HEADER_BYTES = 2200
GPS_TRAILER_BYTES = 10
GPS_MIN_FRAME_BYTES = 3 + GPS_TRAILER_BYTES
GPS_TOD_UNIT_S = 1 / 128
GPS_TOD_LIMIT = 86400 * 128  # trailer times at or past 24 h are damage
GPS_MAX_STEP = 600 * 128  # chained frames: recording times at most 10 minutes on...
GPS_MAX_BACK = 128  # ... or at most 1 s back
ORADIS_HEADER_BYTES = 6
ORADIS_MIN_PACKET_BYTES = ORADIS_HEADER_BYTES + 3  # the header and at least one data block header
HALF_DAY_S = 43200.0
ANY_CATEGORY = np.ones(256, np.uint8)
ANY_CATEGORY[0] = 0  # ASTERIX has no category 0

GPS_REASONS = {
    1: "truncated GPS frame (data block and its 10-byte trailer)",
    2: "GPS frame with a data block LEN below 3",
    3: "GPS frame trailer time of day at or past 24 h",
    4: "GPS frame length does not lead to the next frame (damaged LEN)",
    5: "bytes after a frame that do not start a GPS frame",
}
ORADIS_REASONS = {
    1: "truncated ORADIS packet",
    2: "ORADIS packet length below 9 (6-byte header and a data block)",
    3: "ORADIS packet length does not lead to the next packet (damaged length)",
    4: "bytes after a packet that do not start an ORADIS packet",
}


@njit(cache=True)
def _be16(buf, pos):
    return (np.int64(buf[pos]) << 8) | np.int64(buf[pos + 1])


# ---------------------------------------------------------------- GPS recorder

@njit(cache=True)
def _gps_error(buf, pos):
    """0 if a well-formed GPS frame starts at pos, else a GPS_REASONS code."""
    if buf.size - pos < GPS_MIN_FRAME_BYTES:
        return 1
    block_bytes = _be16(buf, pos + 1)
    if block_bytes < 3:
        return 2
    end = pos + block_bytes + GPS_TRAILER_BYTES
    if end > buf.size:
        return 1
    tod = (np.int64(buf[end - 4]) << 16) | _be16(buf, end - 3)
    if tod >= GPS_TOD_LIMIT:
        return 3
    return 0


@njit(cache=True)
def _gps_next(buf, pos):
    return pos + _be16(buf, pos + 1) + GPS_TRAILER_BYTES


@njit(cache=True)
def _gps_tod(buf, pos):
    """Recording time of day (1/128 s units) in the trailer of the well-formed frame at pos."""
    end = _gps_next(buf, pos)
    return (np.int64(buf[end - 4]) << 16) | _be16(buf, end - 3)


@njit(cache=True)
def _gps_plausible(buf, pos, cats):
    """A well-formed frame whose block category is one of cats (cats[c] != 0)."""
    return _gps_error(buf, pos) == 0 and cats[buf[pos]] != 0


@njit(cache=True)
def _gps_chained(buf, pos, nxt, cats):
    """A plausible frame at nxt whose recording time follows that of the frame at pos."""
    if not _gps_plausible(buf, nxt, cats):
        return False
    step = (_gps_tod(buf, nxt) - _gps_tod(buf, pos)) % GPS_TOD_LIMIT
    return step <= GPS_MAX_STEP or step >= GPS_TOD_LIMIT - GPS_MAX_BACK


@njit(cache=True)
def _gps_strong(buf, pos, end_ok, cats):
    """Three chained frames from pos (two if the end follows; one if end_ok and the end follows)."""
    if not _gps_plausible(buf, pos, cats):
        return False
    n1 = _gps_next(buf, pos)
    if n1 == buf.size:
        return end_ok
    if not _gps_chained(buf, pos, n1, cats):
        return False
    n2 = _gps_next(buf, n1)
    return n2 == buf.size or _gps_chained(buf, n1, n2, cats)


@njit(cache=True)
def _gps_first_strong(buf, pos, stop, end_ok, cats):
    """First offset in [pos, stop) where a strong frame starts, else stop."""
    for r in range(pos, stop):
        if _gps_strong(buf, r, end_ok, cats):
            return r
    return stop


@njit(cache=True)
def _gps_resync(buf, pos, cats):
    """Where the walk resumes from pos: the first strong frame, unless one starts inside it (its LEN then
    reached a true frame by coincidence: take the inner one, and so on); the end if none."""
    r = _gps_first_strong(buf, pos, buf.size, True, cats)
    while r < buf.size:
        inner_stop = min(_gps_next(buf, r), buf.size)
        inner = _gps_first_strong(buf, r + 1, inner_stop, False, cats)
        if inner == inner_stop:
            return r
        r = inner
    return buf.size


@njit(cache=True)
def _walk_gps(buf, cats, fill, seg_start, seg_stop, seg_tod, bad_start, bad_stop, bad_code):
    """Walk GPS frames after the file header; fills the arrays when fill. Returns (frames, problems)."""
    pos, frames, problems, trusted = np.int64(GPS_HEADER_BYTES), 0, 0, True
    while pos < buf.size:
        code = _gps_error(buf, pos)
        if trusted and code == 0:
            nxt = _gps_next(buf, pos)
            chains = nxt == buf.size or _gps_chained(buf, pos, nxt, cats)
            # the first frame has no predecessor vouching for its start: it must not hide a chained frame
            if chains and frames + problems > 0 or _gps_first_strong(buf, pos + 1, nxt, False, cats) == nxt:
                if fill:
                    seg_start[frames], seg_stop[frames] = pos, nxt - GPS_TRAILER_BYTES
                    seg_tod[frames] = _gps_tod(buf, pos) * GPS_TOD_UNIT_S
                frames += 1
                pos, trusted = nxt, chains
                continue
            code = 4
        resume = _gps_resync(buf, pos + (1 if trusted else 0), cats)
        if resume > pos:
            if fill:
                bad_start[problems], bad_stop[problems] = pos, resume
                bad_code[problems] = code if code != 0 else 5
            problems += 1
        pos, trusted = resume, True
    return frames, problems


def categories_seen(buf: np.ndarray, starts: np.ndarray) -> np.ndarray:
    """The categories of the blocks at starts as a 256-entry mask: those seen twice or more (once, in a
    short recording), so that a block accepted by coincidence at damage does not count."""
    counts = np.bincount(buf[starts], minlength=256) if len(starts) else np.zeros(256, np.int64)
    mask = (counts >= (2 if len(starts) >= 20 else 1)).astype(np.uint8)
    mask[0] = 0
    return mask


def midnight_days(tod: np.ndarray) -> np.ndarray:
    """Day count of a recorder's times of day in file order: a drop of more than 12 h is a new day."""
    if len(tod) == 0:
        return np.zeros(0, np.int64)
    step = np.diff(tod, prepend=tod[:1])
    return (np.cumsum(step < -HALF_DAY_S) - np.cumsum(step > HALF_DAY_S)).astype(np.int64)


def _gps_frames(buf: np.ndarray, cats: np.ndarray):
    """One walk: (start, stop, recording time of day, problems)."""
    none_i, none_f = np.zeros(0, np.int64), np.zeros(0)
    frames, bad = _walk_gps(buf, cats, False, none_i, none_i, none_f, none_i, none_i, none_i)
    start, stop = np.zeros(frames, np.int64), np.zeros(frames, np.int64)
    bad_start, bad_stop, bad_code = (np.zeros(bad, np.int64) for _ in range(3))
    tod = np.zeros(frames)
    _walk_gps(buf, cats, True, start, stop, tod, bad_start, bad_stop, bad_code)
    problems = [(int(s), int(e - s), GPS_REASONS[int(c)])
                for s, e, c in zip(bad_start, bad_stop, bad_code, strict=True)]
    return start, stop, tod, problems


def read_gps(buf: np.ndarray):
    """(start, stop, capture day, capture time of day, problems) of a GPS recorder file's data blocks.

    When the file is damaged, a second walk resynchronises only on blocks of the categories the first
    walk found (any non-zero category is weak evidence: blocks are full of plausible headers).
    """
    if buf.size < GPS_HEADER_BYTES:
        none = np.zeros(0, np.int64)
        problems = [(0, int(buf.size), f"truncated GPS file header ({buf.size} of {GPS_HEADER_BYTES} bytes)")]
        return none, none, none, np.zeros(0), problems if buf.size else []
    start, stop, tod, problems = _gps_frames(buf, ANY_CATEGORY)
    if problems:
        start, stop, tod, problems = _gps_frames(buf, categories_seen(buf, start))
    return start, stop, midnight_days(tod), tod, problems


# ---------------------------------------------------------------- ORADIS

@njit(cache=True)
def _oradis_error(buf, pos):
    """0 if the packet length at pos is possible and fits the file, else an ORADIS_REASONS code."""
    if buf.size - pos < 2:
        return 1
    packet_bytes = _be16(buf, pos)
    if packet_bytes < ORADIS_MIN_PACKET_BYTES:
        return 2
    if pos + packet_bytes > buf.size:
        return 1
    return 0


@njit(cache=True)
def _first_block_ok(buf, pos, cats):
    """The packet at pos (whole or cut by the end) starts its payload with a plausible block header."""
    if buf.size - pos < ORADIS_MIN_PACKET_BYTES:
        return False
    block_bytes = _be16(buf, pos + ORADIS_HEADER_BYTES + 1)
    payload_bytes = _be16(buf, pos) - ORADIS_HEADER_BYTES
    return cats[buf[pos + ORADIS_HEADER_BYTES]] != 0 and 3 <= block_bytes <= payload_bytes


@njit(cache=True)
def blocks_tile(buf, start, stop, cats):
    """The bytes [start, stop) are data blocks of categories in cats, end to end."""
    q = start
    while q < stop:
        if stop - q < 3 or cats[buf[q]] == 0:
            return False
        n = _be16(buf, q + 1)
        if n < 3 or q + n > stop:
            return False
        q += n
    return q == stop


@njit(cache=True)
def _oradis_follows(buf, nxt, cats):
    """What follows a packet is the end, a possible packet starting with a plausible block header (whole
    or cut by the end), or a possible packet leading to one of those (its own content may be damaged)."""
    if nxt == buf.size:
        return True
    code = _oradis_error(buf, nxt)
    if code == 2 or not (code == 0 or _first_block_ok(buf, nxt, cats)):
        return False
    if _first_block_ok(buf, nxt, cats):
        return True
    after = nxt + _be16(buf, nxt)
    return after == buf.size or (_oradis_error(buf, after) != 2 and _first_block_ok(buf, after, cats))


@njit(cache=True)
def _oradis_strong(buf, pos, end_ok, cats):
    """A possible packet whose payload tiles into blocks, followed as _oradis_follows says (the end of the
    file counts only if end_ok)."""
    if _oradis_error(buf, pos) != 0:
        return False
    nxt = pos + _be16(buf, pos)
    if not blocks_tile(buf, pos + ORADIS_HEADER_BYTES, nxt, cats):
        return False
    return (end_ok or nxt < buf.size) and _oradis_follows(buf, nxt, cats)


@njit(cache=True)
def _oradis_first_strong(buf, pos, stop, end_ok, cats):
    """First offset in [pos, stop) where a strong packet starts, else stop."""
    for r in range(pos, stop):
        if _oradis_strong(buf, r, end_ok, cats):
            return r
    return stop


@njit(cache=True)
def _oradis_resync(buf, pos, cats):
    """Where the walk resumes from pos: the first strong packet, unless one starts inside it (then take
    the inner one, and so on); the end if none."""
    r = _oradis_first_strong(buf, pos, buf.size, True, cats)
    while r < buf.size:
        inner_stop = min(r + _be16(buf, r), buf.size)
        inner = _oradis_first_strong(buf, r + 1, inner_stop, True, cats)
        if inner == inner_stop:
            return r
        r = inner
    return buf.size


@njit(cache=True)
def _walk_oradis(buf, cats, fill, seg_start, seg_stop, bad_start, bad_stop, bad_code):
    """Walk ORADIS packets; fills the arrays when fill. Returns (packets, problems)."""
    pos, packets, problems, trusted = np.int64(0), 0, 0, True
    while pos < buf.size:
        code = _oradis_error(buf, pos)
        if trusted and code == 0:
            nxt = pos + _be16(buf, pos)
            chains = _oradis_follows(buf, nxt, cats)
            # a packet that chains is kept unless its payload does not frame and a strong packet starts
            # inside it (its length is wrong); a packet that does not chain only if none starts inside
            good = chains and blocks_tile(buf, pos + ORADIS_HEADER_BYTES, nxt, cats)
            if good or _oradis_first_strong(buf, pos + 1, nxt, True, cats) == nxt:
                if fill:
                    seg_start[packets], seg_stop[packets] = pos + ORADIS_HEADER_BYTES, nxt
                packets += 1
                pos, trusted = nxt, chains
                continue
            code = 3
        resume = _oradis_resync(buf, pos + (1 if trusted else 0), cats)
        if resume > pos:
            if fill:
                bad_start[problems], bad_stop[problems] = pos, resume
                bad_code[problems] = code if code != 0 else 4
            problems += 1
        pos, trusted = resume, True
    return packets, problems


def _oradis_packets(buf: np.ndarray, cats: np.ndarray):
    """One walk: (payload start, payload stop, problems)."""
    none = np.zeros(0, np.int64)
    packets, bad = _walk_oradis(buf, cats, False, none, none, none, none, none)
    start, stop = np.zeros(packets, np.int64), np.zeros(packets, np.int64)
    bad_start, bad_stop, bad_code = (np.zeros(bad, np.int64) for _ in range(3))
    _walk_oradis(buf, cats, True, start, stop, bad_start, bad_stop, bad_code)
    problems = [(int(s), int(e - s), ORADIS_REASONS[int(c)])
                for s, e, c in zip(bad_start, bad_stop, bad_code, strict=True)]
    return start, stop, problems


@njit(cache=True)
def _block_starts(buf, start, stop):
    """Offsets of the data blocks that tile the payloads [start, stop) (up to the first that does not)."""
    out = []
    for i in range(start.size):
        q = start[i]
        while stop[i] - q >= 3:
            n = _be16(buf, q + 1)
            if n < 3 or q + n > stop[i]:
                break
            out.append(q)
            q += n
    return np.array(out, np.int64)


def read_oradis(buf: np.ndarray):
    """(start, stop, capture day, capture time of day, problems) of an ORADIS file's packet payloads.

    The 4 header bytes after the length are not used: no public source gives their unit or epoch. When
    the file is damaged, a second walk resynchronises only on packets of the categories the first found.
    """
    start, stop, problems = _oradis_packets(buf, ANY_CATEGORY)
    if problems:
        blocks = _block_starts(buf, start, stop) if len(start) else np.zeros(0, np.int64)
        start, stop, problems = _oradis_packets(buf, categories_seen(buf, blocks))
    return start, stop, np.full(len(start), -1, np.int64), np.full(len(start), np.nan), problems


# ---------------------------------------------------------------- detection

def _raw_chains(head: bytes, whole: bool) -> bool:
    """The head starts with three data blocks end to end (or fewer that end the file, or the head)."""
    pos, count = 0, 0
    while count < 3:
        if pos == len(head):
            return count > 0
        if len(head) - pos < 3 or head[pos] == 0:
            return False
        block_bytes = int.from_bytes(head[pos + 1:pos + 3], "big")
        if block_bytes < 3:
            return False
        if pos + block_bytes > len(head):
            return count > 0 and not whole
        pos += block_bytes
        count += 1
    return True


def _oradis_head(head: bytes, whole: bool) -> bool:
    """The head starts with two ORADIS packets whose payloads tile into data blocks (or one ends the file)."""
    buf = np.frombuffer(head, np.uint8)
    pos, count = 0, 0
    while count < 2:
        if pos == len(head):
            return count > 0 and whole
        if len(head) - pos < ORADIS_MIN_PACKET_BYTES:
            return False
        packet_bytes = int.from_bytes(head[pos:pos + 2], "big")
        if packet_bytes < ORADIS_MIN_PACKET_BYTES:
            return False
        if pos + packet_bytes > len(head):
            return count > 0 and not whole
        if not blocks_tile(buf, pos + ORADIS_HEADER_BYTES, pos + packet_bytes, ANY_CATEGORY):
            return False
        pos += packet_bytes
        count += 1
    return True


def _gps_head(head: bytes, whole: bool) -> bool:
    """After 2200 bytes, the head holds two chained GPS frames (or one ending the file)."""
    buf = np.frombuffer(head, np.uint8)
    first = GPS_HEADER_BYTES
    if len(head) - first < GPS_MIN_FRAME_BYTES:
        return False
    if not _gps_plausible(buf, first, ANY_CATEGORY):
        return False
    second = _gps_next(buf, first)
    if second == len(head):
        return whole
    if not whole and _gps_error(buf, second) == 1:
        return True  # the second frame runs past the head: the first is all the evidence in sight
    return bool(_gps_chained(buf, first, second, ANY_CATEGORY))


def _raw_blocks_past(head: bytes, at: int) -> int:
    """Blocks of the raw chain from the head's start that start at or past ``at`` (up to its first break)."""
    pos, count = 0, 0
    while len(head) - pos >= 3 and head[pos] != 0:
        block_bytes = int.from_bytes(head[pos + 1:pos + 3], "big")
        if block_bytes < 3 or pos + block_bytes > len(head):
            break
        count += pos >= at
        pos += block_bytes
    return count


def _gps_chain_frames(head: bytes) -> int:
    """GPS frames chained from the end of the 2200-byte header, each plausible and following the one
    before in recording time, up to the first that does not or the end of the head."""
    buf = np.frombuffer(head, np.uint8)
    pos, count = GPS_HEADER_BYTES, 0
    while pos < len(head) and _gps_plausible(buf, pos, ANY_CATEGORY):
        count += 1
        nxt = _gps_next(buf, pos)
        if nxt >= len(head) or not _gps_chained(buf, pos, nxt, ANY_CATEGORY):
            break
        pos = nxt
    return count


def detect_recorder(head: bytes, whole: bool) -> str | None:
    """'oradis' or 'gps' when the head (the whole file if whole) frames as one, None otherwise.

    A head that starts with chained raw data blocks stays raw, whatever else it might look like, but for
    a GPS file whose header (any 2200 bytes: spaces, a text) happens to start a chain of blocks: its frames
    are told apart by number, more GPS frames chaining after the header than raw blocks starting there.
    """
    if _raw_chains(head, whole):
        frames = _gps_chain_frames(head) if _gps_head(head, whole) else 0
        return "gps" if frames > max(_raw_blocks_past(head, GPS_HEADER_BYTES), 1) else None
    if _oradis_head(head, whole):
        return "oradis"
    if _gps_head(head, whole):
        return "gps"
    return None
