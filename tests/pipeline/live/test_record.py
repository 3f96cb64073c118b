"""The pcapng recorder (pipeline.live.record) checked against the pcapng specification by hand
(draft-ietf-opsawg-pcapng: block types, lengths, byte-order magic, interface ids, if_tsresol, timestamps),
read back through msdc's container reader and, when installed, tshark; rotation and a full disk."""

from __future__ import annotations

import errno
import shutil
import struct
import subprocess

import numpy as np
import pytest

from msdc.asterix.containers import read_segments
from msdc.pipeline.live.decode import Datagram
from msdc.pipeline.live.record import Recorder

FEEDS = ["udp:239.1.2.3:8600", "udp:127.0.0.1:8601"]
ADDRESSES = [("239.1.2.3", 8600), ("127.0.0.1", 8601)]
WALL = 1_700_000_000.25  # 2023-11-14 22:13:20.25 UTC
SENT = [Datagram(0, WALL, b"\x30\x00\x04\x00", ("10.0.0.7", 40000)),  # 4 bytes: 28 + 4 = 32, no padding
        Datagram(1, WALL + 0.5, b"\x15\x00\x05\xaa\xbb", ("10.0.0.8", 40001)),  # 33 bytes: 3 of padding
        Datagram(0, WALL + 1.000001, bytes(range(256)) * 4, ("10.0.0.7", 40000))]


def _blocks(data: bytes) -> list[tuple[int, bytes]]:
    """(block type, body) of every block, checking each trailing length equals the leading one."""
    out, pos = [], 0
    while pos < len(data):
        block_type, total = struct.unpack_from("<II", data, pos)
        assert total % 4 == 0 and struct.unpack_from("<I", data, pos + total - 4)[0] == total
        out.append((block_type, data[pos + 8:pos + total - 4]))
        pos += total
    assert pos == len(data)
    return out


def _options(body: bytes) -> dict[int, bytes]:
    out, pos = {}, 0
    while pos + 4 <= len(body):
        code, length = struct.unpack_from("<HH", body, pos)
        if code == 0:
            break
        out[code] = body[pos + 4:pos + 4 + length]
        pos += 4 + length + (-length % 4)
    return out


def _record(tmp_path, batches, **kw) -> Recorder:
    tmp_path.mkdir(exist_ok=True)
    rec = Recorder(tmp_path, FEEDS, ADDRESSES, **kw)
    for batch in batches:
        rec.write(batch)
    rec.close()
    return rec


def test_the_file_follows_the_pcapng_layout(tmp_path):
    rec = _record(tmp_path, [SENT[:2], SENT[2:]])
    (path,) = rec.files
    assert path.name == "msdc-20231114T221320Z.pcapng" and not list(tmp_path.glob("*.part"))
    blocks = _blocks(path.read_bytes())
    assert [t for t, _ in blocks] == [0x0A0D0D0A, 1, 1, 6, 6, 6]
    magic, major, minor, section = struct.unpack_from("<IHHq", blocks[0][1])
    assert (magic, major, minor, section) == (0x1A2B3C4D, 1, 0, -1)
    for (_, body), name in zip(blocks[1:3], FEEDS, strict=True):
        link, reserved, snap = struct.unpack_from("<HHI", body)
        opts = _options(body[8:])
        assert (link, reserved, snap) == (228, 0, 0)  # LINKTYPE_IPV4, no snap length limit
        assert opts[2] == name.encode() and opts[9] == b"\x09"  # if_name, if_tsresol 10^-9
    for (_, body), d in zip(blocks[3:], SENT, strict=True):
        interface, high, low, captured, original = struct.unpack_from("<IIIII", body)
        packet = body[20:20 + captured]
        assert interface == d.feed and captured == original == 28 + len(d.data)
        assert len(body) == 20 + captured + (-captured % 4)
        assert abs(((high << 32) | low) - d.wall_s * 1e9) < 1000  # within a microsecond
        ip, udp, payload = packet[:20], packet[20:28], packet[28:]
        assert ip[0] == 0x45 and ip[9] == 17 and struct.unpack(">H", ip[2:4])[0] == len(packet)
        assert sum(struct.unpack(">10H", ip)) % 0xFFFF == 0  # the IPv4 header checksum holds
        assert ip[12:16] == bytes(map(int, d.source[0].split("."))) and \
            ip[16:20] == bytes(map(int, ADDRESSES[d.feed][0].split(".")))
        assert struct.unpack(">HHH", udp[:6]) == (d.source[1], ADDRESSES[d.feed][1], 8 + len(d.data))
        assert payload == d.data


def test_msdc_reads_the_recording_back_byte_exact(tmp_path):
    (path,) = _record(tmp_path, [SENT]).files
    data = path.read_bytes()
    seg = read_segments(data)
    assert seg.format == "pcapng" and seg.problems == []
    assert [data[a:b] for a, b in zip(seg.start, seg.stop, strict=True)] == [d.data for d in SENT]
    seconds = seg.capture_day * 86400 + seg.capture_tod
    assert np.allclose(seconds, [d.wall_s for d in SENT], rtol=0, atol=1e-6)


@pytest.mark.skipif(shutil.which("tshark") is None, reason="tshark (an independent pcapng reader) is not "
                    "installed: apt-get install tshark")
def test_tshark_reads_the_recording(tmp_path):
    (path,) = _record(tmp_path, [SENT]).files
    done = subprocess.run(["tshark", "-r", str(path), "-T", "fields", "-e", "frame.interface_id",
                           "-e", "frame.time_epoch", "-e", "udp.dstport", "-e", "udp.payload",
                           "-d", "udp.port==8600,data", "-d", "udp.port==8601,data"],
                          capture_output=True, text=True, timeout=60)
    assert done.returncode == 0, done.stderr
    rows = [line.split("\t") for line in done.stdout.strip().splitlines()]
    assert [int(r[0]) for r in rows] == [0, 1, 0]
    assert [int(r[2]) for r in rows] == [8600, 8601, 8600]
    assert [bytes.fromhex(r[3].replace(":", "")) for r in rows] == [d.data for d in SENT]
    assert np.allclose([float(r[1]) for r in rows], [d.wall_s for d in SENT], rtol=0, atol=1e-6)


def test_rotation_by_size_and_by_clock_closes_every_file(tmp_path):
    many = [Datagram(0, WALL + i, bytes([0x30, 0, 200]) + bytes(197), ("10.0.0.7", 1)) for i in range(10)]
    by_size = _record(tmp_path / "size", [many], rotate_bytes=700)
    # each file: SHB 48 bytes (16 + shb_userappl "msdc listen" 16 + end 4, + 12) and 2 IDBs of 56 (8 +
    # if_name 24 + if_tsresol 8 + end 4, + 12), then EPBs of 260 bytes (12 + 20 + 28 + 200): a file takes
    # a datagram while it holds less than 700 bytes (160, 420, 680): 3 a file
    sizes = [p.stat().st_size for p in by_size.files]
    assert sizes == [940, 940, 940, 420]
    back = [d for p in by_size.files for d in _payloads(p)]
    assert back == [d.data for d in many]
    # a period of 4 s aligned to the clock: WALL (..320.25) falls in [..320, ..324): 4 + 4 + 2 datagrams
    by_clock = _record(tmp_path / "clock", [many[:5], many[5:]], rotate_s=4.0)
    assert [len(_payloads(p)) for p in by_clock.files] == [4, 4, 2]
    assert [p.name for p in by_clock.files] == [f"msdc-20231114T2213{s}Z.pcapng" for s in (20, 24, 28)]
    assert not list(tmp_path.rglob("*.part"))


def _payloads(path) -> list[bytes]:
    data = path.read_bytes()
    seg = read_segments(data)
    assert seg.problems == []
    return [data[a:b] for a, b in zip(seg.start, seg.stop, strict=True)]


def test_a_full_disk_stops_recording_keeps_what_was_written_and_raises_nothing(tmp_path, monkeypatch):
    calls = []
    real = Recorder._write

    def write(self, data):
        calls.append(len(data))
        if len(calls) == 2:  # the second batch finds the disk full
            raise OSError(errno.ENOSPC, "No space left on device")
        real(self, data)

    monkeypatch.setattr(Recorder, "_write", write)
    rec = _record(tmp_path, [SENT[:1], SENT[1:2], SENT[2:]])
    assert "recording stopped: No space left on device" in rec.error and "receiving goes on" in rec.error
    (path,) = rec.files
    assert _payloads(path) == [SENT[0].data]  # the first batch, whole; the rest not recorded
    assert len(calls) == 2 and not list(tmp_path.glob("*.part"))
