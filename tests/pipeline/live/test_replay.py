"""What replay sends and when (pipeline.live.replay): raw blocks timed by their first record's time of day
(hand-built records), capture times of a hand-built pcap, the pacing by speed and loop on a fake clock."""

from __future__ import annotations

import numpy as np
import pytest
from asterix_bytes import block
from container_bytes import pcap_file, udp_frame
from live_bytes import cat034_north_marker, cat048_record

from msdc.pipeline.live.replay import ReplayError, Schedule, schedule, send


def test_raw_blocks_go_at_their_first_records_time_in_file_order(tmp_path):
    blocks = [block(48, cat048_record(25, 201, 100.0), cat048_record(25, 201, 99.0)),  # first record: 100
              cat034_north_marker(25, 201, 101.5),
              block(30, b"\x80\x01\x02"),  # a category msdc does not decode: the time before it
              block(48, cat048_record(25, 201, 98.0)),  # earlier than the block before: sent right after
              block(48, cat048_record(25, 201, 104.25))]
    path = tmp_path / "feed.ast"
    path.write_bytes(b"".join(blocks))
    sched = schedule([path])
    assert sched.data == blocks
    assert list(sched.time_s) == [0.0, 1.5, 1.5, 1.5, 4.25]


def test_raw_times_run_on_across_midnight(tmp_path):
    blocks = [block(48, cat048_record(25, 201, 86399.5)), block(48, cat048_record(25, 201, 0.25))]
    (tmp_path / "midnight.ast").write_bytes(b"".join(blocks))
    assert list(schedule([tmp_path / "midnight.ast"]).time_s) == [0.0, 0.75]


def test_a_capture_sends_its_datagrams_at_their_capture_times(tmp_path):
    payloads = [block(48, cat048_record(25, 201, 10.0)), block(48, cat048_record(25, 201, 11.0)) * 2,
                cat034_north_marker(25, 201, 12.0)]
    data, _ = pcap_file([(1_700_000_000, 250_000, udp_frame(payloads[0])),
                         (1_700_000_002, 0, udp_frame(payloads[1])),
                         (1_700_000_002, 500_000, udp_frame(payloads[2]))])
    (tmp_path / "c.pcap").write_bytes(data)
    sched = schedule([tmp_path / "c.pcap"])
    assert sched.data == payloads  # the datagrams as captured: two blocks stay one datagram
    assert list(sched.time_s) == [0.0, 1.75, 2.25]


def test_several_recordings_are_merged_by_time(tmp_path):
    a = [block(48, cat048_record(25, 201, t)) for t in (10.0, 12.0)]
    b = [block(48, cat048_record(30, 1, t)) for t in (11.0, 13.0)]
    (tmp_path / "a.ast").write_bytes(b"".join(a))
    (tmp_path / "b.ast").write_bytes(b"".join(b))
    sched = schedule([tmp_path / "a.ast", tmp_path / "b.ast"])
    assert sched.data == [a[0], b[0], a[1], b[1]] and list(sched.time_s) == [0.0, 1.0, 2.0, 3.0]


def test_a_capture_and_a_raw_file_are_not_merged(tmp_path):
    """A capture's times are dated (epoch seconds), a raw file's are times of day: merged, the schedule
    spanned 57 years and replay waited in silence. Refused, naming both."""
    data, _ = pcap_file([(1_700_000_000, 0, udp_frame(block(48, cat048_record(25, 201, 10.0))))])
    (tmp_path / "c.pcap").write_bytes(data)
    (tmp_path / "r.ast").write_bytes(block(48, cat048_record(25, 201, 11.0)))
    with pytest.raises(ReplayError, match=r"c.pcap \(a capture, dated by its capture times\) and .*r.ast "
                                          r"\(times of day, no date\) cannot be merged by time"):
        schedule([tmp_path / "c.pcap", tmp_path / "r.ast"])
    assert len(schedule([tmp_path / "c.pcap", tmp_path / "c.pcap"])) == 2  # two captures merge


def _radar_blocks(n: int) -> list[bytes]:
    """n CAT048 blocks of 3 records of one radar, block i at 100 + i s (all of one length)."""
    return [block(48, *(cat048_record(25, 201, 100.0 + i + r / 10, rho_nm=40.0 + r) for r in range(3)))
            for i in range(n)]


def test_a_len_overwritten_is_named_at_its_offset_and_every_other_block_sent(tmp_path):
    """A LEN overwritten with a value landing inside a later block: replay followed the chain on through
    the bytes after it and named a later offset and a LEN read from inside a block, sending nothing. Framed
    as msdc decode frames it, the damage is named where it is, with the LEN written there, and the other
    blocks go."""
    blocks = _radar_blocks(8)
    n = len(blocks[0])
    data = bytearray(b"".join(blocks))
    data[3 * n + 1:3 * n + 3] = (2 * n + 7).to_bytes(2, "big")  # block 3's LEN: 7 bytes into block 5
    (tmp_path / "len.ast").write_bytes(data)
    sched = schedule([tmp_path / "len.ast"])
    assert sched.warnings == [f"{tmp_path / 'len.ast'}: offset {3 * n}: data block LEN does not fit the "
                              f"block chain (LEN {2 * n + 7}): {n} bytes skipped, not sent"]
    assert sched.data == blocks[:3] + blocks[4:]
    assert list(sched.time_s) == [0.0, 1.0, 2.0, 4.0, 5.0, 6.0, 7.0]


def test_bytes_flipped_at_a_block_are_named_at_its_offset_and_every_other_block_sent(tmp_path):
    blocks = _radar_blocks(8)
    n = len(blocks[0])
    data = bytearray(b"".join(blocks))
    data[2 * n:2 * n + 3] = b"\xff\xff\xff"  # block 2's CAT and LEN
    (tmp_path / "flip.ast").write_bytes(data)
    sched = schedule([tmp_path / "flip.ast"])
    assert sched.warnings == [f"{tmp_path / 'flip.ast'}: offset {2 * n}: bytes that do not start a plausible "
                              f"ASTERIX data block: {n} bytes skipped, not sent"]
    assert sched.data == blocks[:2] + blocks[3:]


def test_a_truncated_last_block_is_named_and_the_whole_ones_sent(tmp_path):
    good = block(48, cat048_record(25, 201, 10.0))
    (tmp_path / "cut.ast").write_bytes(good + good[:-1])
    sched = schedule([tmp_path / "cut.ast"])
    assert sched.data == [good]
    assert sched.warnings == [f"{tmp_path / 'cut.ast'}: offset {len(good)}: data block runs past the end of "
                              f"the data (LEN {len(good)}, 1 bytes past the end): {len(good) - 1} bytes "
                              "skipped, not sent"]


def test_a_file_that_is_not_asterix_is_refused_as_decode_says_it(tmp_path):
    (tmp_path / "notes.txt").write_text("the radar was switched off at noon\n" * 50)
    with pytest.raises(ReplayError, match=r"^notes.txt is not ASTERIX: read as raw, 100% of its 1750 bytes "
                                          r"frame into no data block that decodes .*; nothing sent$"):
        schedule([tmp_path / "notes.txt"])


class _Clock:
    """A fake monotonic clock that sleeping advances."""

    def __init__(self):
        self.now = 0.0

    def __call__(self) -> float:
        return self.now

    def sleep(self, s: float) -> None:
        self.now += s


class _Socket:
    def __init__(self, clock):
        self.clock, self.sent = clock, []

    def send(self, data: bytes) -> int:
        self.sent.append((round(self.clock(), 9), data))
        return len(data)


def test_send_scales_the_times_and_loops_until_the_duration():
    sched = Schedule(np.array([0.0, 1.0, 1.0, 3.0]), [b"a", b"b", b"c", b"d"])
    clock = _Clock()
    sock = _Socket(clock)
    out = send(sched, sock, speed=2.0, clock=clock, sleep=clock.sleep)
    assert sock.sent == [(0.0, b"a"), (0.5, b"b"), (0.5, b"c"), (1.5, b"d")]
    assert (out.datagrams, out.bytes, out.passes) == (4, 4, 1)
    # --loop: a pass lasts the span plus one mean interval (3 + 1 s of recording: 2 s at speed 2)
    clock = _Clock()
    sock2 = _Socket(clock)
    out = send(sched, sock2, speed=2.0, loop=True, duration_s=3.0, clock=clock, sleep=clock.sleep)
    assert [t for t, _ in sock2.sent] == [0.0, 0.5, 0.5, 1.5, 2.0, 2.5, 2.5]
    assert out.datagrams == 7 and out.passes == 1


def test_nothing_listening_does_not_stop_the_replay():
    """UDP needs no receiver, but a connected socket reports the port unreachable of an earlier datagram
    on a later send, which fails: replay stopped ('sending failed: Connection refused', exit 1) when it
    started before its listener or the listener ended. Every datagram is sent, on a real socket to a
    localhost port nothing listens on, and the notices counted."""
    import socket

    from msdc.pipeline.live.receive import Endpoint
    from msdc.pipeline.live.replay import sending_socket

    probe = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    probe.bind(("127.0.0.1", 0))
    port = probe.getsockname()[1]
    probe.close()  # a free port: nothing listens there
    sock = sending_socket(Endpoint("127.0.0.1", port), None, 1)
    try:
        sched = Schedule(np.arange(20) * 0.01, [bytes([48, 0, 3])] * 20)
        out = send(sched, sock, speed=1.0)
    finally:
        sock.close()
    assert (out.datagrams, out.bytes) == (20, 60)
    assert out.refused >= 1  # loopback answers with ICMP port unreachable at once
