"""GPS recorder and ORADIS files written by hand from their layouts, through read(); values worked by hand.

GPS: 2200-byte file header, then per frame one ASTERIX data block and 10 bytes whose bytes 6-8 are the
recording time of day in 1/128 s (big-endian). ORADIS: per packet a 6-byte header (big-endian length of the
whole packet, then 4 bytes not interpreted) and ASTERIX data blocks. Records are written by hand:
CAT048 FRN 1, 2 (I048/010, I048/140), CAT021 2.x FRN 1, 5 (I021/010, I021/071), CAT034 FRN 1, 2, 3.
Every test checks the byte account: decoded + errors + container + ignored == file size.
"""

from __future__ import annotations

import datetime as dt
import re
import struct
import warnings

import numpy as np
import pandas as pd
import pytest
from asterix_bytes import block, fspec
from budget import examples
from hypothesis import given, settings
from hypothesis import strategies as st

import msdc.asterix as asterix
from msdc.asterix.containers import DETECT_BYTES, detect_format, read_segments, recorder_hint
from msdc.pipeline.cli import main

ALL = [21, 34, 48]
DAY = dt.date(2019, 3, 1)
GPS_HEADER = bytes(range(256)) * 8 + bytes(152)  # 2048 + 152 = 2200 bytes of opaque header
TRAILER_HEAD, TRAILER_TAIL = bytes.fromhex("A1A2A3A4A5A6"), b"\xa7"  # trailer bytes 0-5 and 9: opaque


def tod3(seconds: float) -> bytes:
    """A time of day in 1/128 s, 3 bytes big-endian (exact for the multiples of 1/128 used here)."""
    units = seconds * 128
    assert units == int(units)
    return int(units).to_bytes(3, "big")


def r048(sic: int, tod: float) -> bytes:
    return fspec(1, 2) + bytes([25, sic]) + tod3(tod)  # 1 + 2 + 3 = 6 bytes


def r021(sic: int, tod: float) -> bytes:
    return fspec(1, 5) + bytes([30, sic]) + tod3(tod)  # FSPEC 0x88: 6 bytes


def r034(sic: int, tod: float, message_type: int = 1) -> bytes:
    return fspec(1, 2, 3) + bytes([25, sic, message_type]) + tod3(tod)  # 7 bytes


def gps_file(frames: list[tuple[bytes, float]]) -> tuple[bytes, list[int]]:
    """(file, offset of each frame) for (data block, recording time of day in s) frames."""
    out, at = GPS_HEADER, []
    for data, rec_tod in frames:
        at.append(len(out))
        out += data + TRAILER_HEAD + tod3(rec_tod) + TRAILER_TAIL
    return out, at


def oradis_file(packets: list[bytes]) -> tuple[bytes, list[int]]:
    """(file, offset of each packet) for packets carrying the given data blocks."""
    out, at = b"", []
    for i, data in enumerate(packets):
        at.append(len(out))
        out += (6 + len(data)).to_bytes(2, "big") + (0x01020300 + i).to_bytes(4, "big") + data
    return out, at


def read(tmp_path, data: bytes, name: str, **kw) -> asterix.Recording:
    path = tmp_path / name
    path.write_bytes(data)
    rec = asterix.read(path, categories=kw.pop("categories", ALL), **kw)
    accounted = rec.decoded_bytes + int(rec.errors.length.sum()) + rec.container_bytes + rec.ignored_bytes
    assert accounted == rec.size_bytes == len(data)
    return rec


def test_gps_header_worked_by_hand() -> None:
    assert len(GPS_HEADER) == 2200
    assert tod3(86399.5) == (11059136).to_bytes(3, "big")  # 86399.5 * 128 = 11059136 = 0xA8BFC0
    assert tod3(86399.5).hex() == "a8bfc0"


# ---------------------------------------------------------------------------------------------------------
# GPS recorder


def midnight_gps() -> tuple[bytes, list[int], list[bytes]]:
    blocks = [
        block(48, r048(1, 86399.0), r048(1, 86399.25)),  # 3 + 6 + 6 = 15 bytes, recorded 23:59:59.5
        block(34, r034(1, 86399.75)),                   # 3 + 7 = 10 bytes, recorded 23:59:59.875
        block(21, r021(5, 0.5)),                        # 9 bytes, recorded 00:00:00.75 (next day)
        block(48, r048(3, 86399.5)),                    # a late report, recorded 00:00:01
        block(48, r048(1, 2.0)),                        # recorded 00:00:02.5
    ]
    data, at = gps_file(list(zip(blocks, [86399.5, 86399.875, 0.75, 1.0, 2.5], strict=True)))
    return data, at, blocks


def test_gps_across_midnight(tmp_path) -> None:
    data, at, blocks = midnight_gps()
    assert at == [2200, 2225, 2245, 2264, 2283]  # 2200 + 15 + 10, + 10 + 10, + 9 + 10, + 9 + 10
    rec = read(tmp_path, data, "day.gps", date="2019-03-01")
    assert rec.format == "gps" and rec.errors.empty
    assert rec.container_bytes == 2200 + 5 * 10 and rec.decoded_bytes == 15 + 10 + 9 + 9 + 9
    f48, f34, f21 = rec.frames[48], rec.frames[34], rec.frames[21]
    # day: the one that puts each report nearest its recording time; the late report stays on day 0
    assert list(f48.day) == [0, 0, 0, 1] and list(f34.day) == [0] and list(f21.day) == [1]
    assert list(f48.offset) == [2203, 2209, 2267, 2286]  # frame + 3 (block header) + 6 per record
    assert list(f48.timestamp) == [pd.Timestamp(t, tz="UTC") for t in (
        "2019-03-01 23:59:59", "2019-03-01 23:59:59.25", "2019-03-01 23:59:59.5", "2019-03-02 00:00:02")]
    assert f21.timestamp.iloc[0] == pd.Timestamp("2019-03-02 00:00:00.5", tz="UTC")
    assert f34.time_of_day.iloc[0] == 86399.75 and f34.message_type.iloc[0] == 1


def test_gps_segments_carry_recording_times() -> None:
    data, at, blocks = midnight_gps()
    seg = read_segments(np.frombuffer(data, np.uint8))
    assert seg.format == "gps" and seg.exact and not seg.dated
    assert list(seg.start) == at and list(seg.stop - seg.start) == [len(b) for b in blocks]
    assert list(seg.capture_tod) == [86399.5, 86399.875, 0.75, 1.0, 2.5]
    assert list(seg.capture_day) == [0, 0, 1, 1, 1]  # the drop from 86399.875 to 0.75 s is a midnight


def test_gps_streamed_in_chunks_keeps_days(tmp_path) -> None:
    data, _, _ = midnight_gps()
    path = tmp_path / "day.gps"
    path.write_bytes(data)
    parts = list(asterix.iter_read(path, chunk=20, categories=ALL, date="2019-03-01"))
    assert len(parts) > 2
    days = pd.concat([p.frames[48] for p in parts if 48 in p.frames]).day.tolist()
    assert days == [0, 0, 0, 1]


def gps_six() -> tuple[list[bytes], list[float]]:
    blocks = [block(48, r048(i, 3600.0 + i)) for i in range(1, 7)]  # 9 bytes each
    return blocks, [3600.5 + i for i in range(1, 7)]


def test_gps_damaged_trailer_time(tmp_path) -> None:
    blocks, times = gps_six()
    data, at = gps_file(list(zip(blocks, times, strict=True)))
    assert at == [2200 + 19 * i for i in range(6)]  # 9-byte block + 10-byte trailer
    buf = bytearray(data)
    buf[at[2] + 9 + 6:at[2] + 9 + 9] = b"\xff\xff\xff"  # frame 3: 0xFFFFFF / 128 s is past 24 h
    rec = read(tmp_path, bytes(buf), "bad.gps")
    assert rec.format == "gps"
    assert rec.errors[["offset", "length"]].values.tolist() == [[at[2], 19]]
    assert "24 h" in rec.errors.reason.iloc[0] and rec.errors.reason.iloc[0].startswith("container:")
    assert list(rec.frames[48].sic) == [1, 2, 4, 5, 6]


def test_gps_damaged_length(tmp_path) -> None:
    blocks, times = gps_six()
    data, at = gps_file(list(zip(blocks, times, strict=True)))
    buf = bytearray(data)
    buf[at[2] + 2] = 9 + 5  # frame 3 claims a 14-byte block: its trailer would start 5 bytes into frame 4
    rec = read(tmp_path, bytes(buf), "bad.gps")
    # frame 3 at 2238 reads its 'time' at 2238 + 14 + 6 = 2258 = frame 4 (at 2257) bytes 1-3: 00 09 C0 = 2496,
    # a valid time, so it is well formed; but 2238 + 24 = 2262 (frame 4's SIC 4, LEN 0x070A = 1802 from its
    # time 3604 * 128 = 0x070A00) is no frame, and 2496 / 128 = 19.5 s is no step on from frame 2's 3602.5 s:
    # frame 2 is kept (no chained frame starts inside it), and the walk resynchronises from frame 3 on
    # frame 4, the first of three chained frames
    assert at[2:4] == [2238, 2257]
    assert rec.errors[["offset", "length"]].values.tolist() == [[2238, 19]]
    assert "do not start a GPS frame" in rec.errors.reason.iloc[0]
    assert list(rec.frames[48].sic) == [1, 2, 4, 5, 6]


def test_gps_truncated_end(tmp_path) -> None:
    blocks, times = gps_six()
    data, at = gps_file(list(zip(blocks, times, strict=True)))
    rec = read(tmp_path, data[:-4], "cut.gps")  # frame 6 (at 2295) loses 4 of its 10 trailer bytes
    assert rec.errors[["offset", "length"]].values.tolist() == [[2295, 15]]
    assert "truncated" in rec.errors.reason.iloc[0]
    assert list(rec.frames[48].sic) == [1, 2, 3, 4, 5]


def test_gps_short_header(tmp_path) -> None:
    with pytest.warns(asterix.ContentWarning, match=r"short.gps is not ASTERIX: read as gps, 100% of its 100 "
                                                    r"bytes .*truncated GPS file header"):
        rec = read(tmp_path, GPS_HEADER[:100], "short.gps", format="gps")
    assert rec.errors[["offset", "length"]].values.tolist() == [[0, 100]]
    assert "2200" in rec.errors.reason.iloc[0]


def test_gps_header_only(tmp_path) -> None:
    rec = read(tmp_path, GPS_HEADER, "empty.gps", format="gps")
    assert rec.errors.empty and rec.container_bytes == 2200 and rec.frames == {}


# ---------------------------------------------------------------------------------------------------------
# ORADIS


def mixed_oradis() -> tuple[bytes, list[int]]:
    return oradis_file([
        block(48, r048(1, 100.0)) + block(34, r034(1, 100.5)),  # 9 + 10 = 19 bytes -> packet of 25
        block(21, r021(5, 101.0)),                              # 9 -> 15
        block(48, r048(2, 101.5), r048(2, 102.0)),              # 15 -> 21 (one sensor's block)
        block(34, r034(1, 102.5, 2)) + block(21, r021(6, 103.0)),  # 10 + 9 -> 25
    ])


def test_oradis_mixed_categories(tmp_path) -> None:
    data, at = mixed_oradis()
    assert at == [0, 25, 40, 61] and len(data) == 86
    rec = read(tmp_path, data, "day.oradis", date="2019-03-01")
    assert rec.format == "oradis" and rec.errors.empty
    assert rec.container_bytes == 4 * 6 and rec.decoded_bytes == 86 - 24
    f48, f34, f21 = rec.frames[48], rec.frames[34], rec.frames[21]
    assert list(f48.sic) == [1, 2, 2] and list(f48.offset) == [6 + 3, 46 + 3, 46 + 9]
    assert list(f34.message_type) == [1, 2] and list(f34.offset) == [15 + 3, 67 + 3]
    assert list(f21.time_of_day) == [101.0, 103.0]
    assert f21.timestamp.iloc[1] == pd.Timestamp("2019-03-01 00:01:43", tz="UTC")


def test_oradis_midnight_counted_from_report_times(tmp_path) -> None:
    # no usable packet time: as in a raw stream, a drop of more than 12 h in report time is a new day
    data, _ = oradis_file([block(48, r048(1, 86399.5)), block(34, r034(1, 86399.75)),
                           block(48, r048(1, 0.25))])
    rec = read(tmp_path, data, "night.oradis", date="2019-03-01")
    assert rec.format == "oradis"
    assert list(rec.frames[48].day) == [0, 1] and list(rec.frames[34].day) == [0]
    assert rec.frames[48].timestamp.iloc[1] == pd.Timestamp("2019-03-02 00:00:00.25", tz="UTC")


def test_oradis_streamed_in_chunks_keeps_days(tmp_path) -> None:
    data, _ = oradis_file([block(48, r048(1, 86399.5)), block(48, r048(2, 86399.75)),
                           block(48, r048(3, 0.25)), block(48, r048(4, 0.5))])
    path = tmp_path / "night.oradis"
    path.write_bytes(data)
    parts = [p.frames[48] for p in asterix.iter_read(path, chunk=10, date="2019-03-01") if 48 in p.frames]
    assert len(parts) == 4  # 9-byte payloads, one packet per chunk
    frame = pd.concat(parts)
    assert frame.day.tolist() == [0, 0, 1, 1]
    assert frame.timestamp.iloc[2] == pd.Timestamp("2019-03-02 00:00:00.25", tz="UTC")


def test_oradis_truncated_and_damaged_packets(tmp_path) -> None:
    blocks = [block(48, r048(i, 10.0 * i)) for i in range(1, 7)]  # 9 bytes: packets of 15
    data, at = oradis_file(blocks)
    buf = bytearray(data)
    del buf[at[2] + 6 + 4:at[2] + 6 + 7]  # packet 3 loses 3 bytes of its record: its length now overruns
    # packet 4 now starts at 30 + 12 = 42; in packet 5 (at 57) the block LEN says 10 instead of 9
    buf[57 + 6 + 2] = 10
    buf = buf[:-5]  # packet 6 (at 72) is cut: 10 of its 15 bytes remain
    rec = read(tmp_path, bytes(buf), "bad.oradis")
    assert rec.format == "oradis"
    # packet 3 (30..45 by its length) swallows packet 4's start (42), which chains on: damaged length
    assert rec.errors[["offset", "length"]].values.tolist() == [[30, 12], [57 + 6, 9], [72, 10]]
    reasons = rec.errors.reason.tolist()
    assert "does not lead" in reasons[0] and "does not frame" in reasons[1] and "truncated" in reasons[2]
    assert list(rec.frames[48].sic) == [1, 2, 4]


def test_oradis_resynchronises_on_packets_of_every_category_seen(tmp_path) -> None:
    # CAT034 only ever second in its packet: 9 + 10 = 19-byte payloads, packets of 25 bytes
    data, at = oradis_file([block(48, r048(i, 10.0 * i)) + block(34, r034(i, 10.0 * i + 5))
                            for i in range(1, 9)])
    assert at == [25 * i for i in range(8)]
    buf = bytearray(data)
    buf[at[2]:at[2] + 2] = b"\x00\x03"  # packet 3: length 3
    rec = read(tmp_path, bytes(buf), "bad.oradis")
    assert rec.errors[["offset", "length"]].values.tolist() == [[50, 25]]
    assert list(rec.frames[48].sic) == [1, 2, 4, 5, 6, 7, 8] == list(rec.frames[34].sic)


def test_oradis_forced_on_a_file_detection_would_miss(tmp_path) -> None:
    # second packet damaged: detection sees no ORADIS framing, forcing it recovers the rest
    data, at = oradis_file([block(48, r048(i, 10.0 * i)) for i in range(1, 5)])
    buf = bytearray(data)
    buf[at[1]:at[1] + 2] = b"\x00\x02"  # impossible packet length 2
    rec = read(tmp_path, bytes(buf), "bad.oradis", format="oradis")
    assert rec.errors[["offset", "length"]].values.tolist() == [[15, 15]]
    assert "below 9" in rec.errors.reason.iloc[0]
    assert list(rec.frames[48].sic) == [1, 3, 4]


# ---------------------------------------------------------------------------------------------------------
# Detection


def pcap_bytes(payload: bytes) -> bytes:
    import struct
    udp = struct.pack(">HHHH", 1, 2, 8 + len(payload), 0) + payload
    ip = struct.pack(">BBHHHBBH4s4s", 0x45, 0, 20 + len(udp), 0, 0x4000, 64, 17, 0, bytes(4), bytes(4))
    frame = bytes(12) + b"\x08\x00" + ip + udp
    return struct.pack("<IHHiIII", 0xA1B2C3D4, 2, 4, 0, 0, 65535, 1) + struct.pack(
        "<IIII", 1, 0, len(frame), len(frame)) + frame


def final_bytes(payload: bytes) -> bytes:
    return (8 + len(payload) + 4).to_bytes(2, "big") + bytes(6) + payload + b"\xa5" * 4


def test_existing_formats_not_taken_for_recorders() -> None:
    from pathlib import Path

    fixtures = Path(__file__).resolve().parents[2] / "fixtures"
    raw_one = block(48, r048(1, 1.0))
    raw_mixed = block(34, r034(1, 2.0)) + block(21, r021(2, 3.0)) + block(48, r048(1, 4.0))
    cases = {
        "fixture radar": (fixtures / "radar.ast").read_bytes()[:DETECT_BYTES],
        "fixture adsb": (fixtures / "adsb.ast").read_bytes()[:DETECT_BYTES],
        "one block": raw_one, "mixed": raw_mixed, "long raw": raw_mixed * 400,
    }
    for name, data in cases.items():
        assert detect_format(data) == "raw", name
    assert detect_format(pcap_bytes(raw_mixed)) == "pcap"
    assert detect_format(final_bytes(raw_mixed) * 3) == "final"
    # and the recorder files are told apart from each other
    assert detect_format(midnight_gps()[0]) == "gps"
    assert detect_format(mixed_oradis()[0]) == "oradis"


@pytest.mark.fuzz
@settings(max_examples=examples(60), deadline=None)
@given(st.lists(st.tuples(st.sampled_from([1, 2, 21, 34, 48, 62, 240]), st.binary(min_size=1, max_size=300)),
                min_size=1, max_size=40))
def test_raw_streams_stay_raw(blocks: list[tuple[int, bytes]]) -> None:
    data = b"".join(block(cat, body) for cat, body in blocks)
    assert detect_format(data) == "raw"


def test_forced_format_on_counting_bytes(tmp_path) -> None:
    data = bytes(range(256)) * 12  # 3072 bytes 00 01 02 ... FF 00 01 ...
    with pytest.warns(asterix.ContentWarning, match="garbage.bin is not ASTERIX: read as gps, 100% of its "
                                                    "872 bytes"):
        rec = read(tmp_path, data, "garbage.bin", format="gps")
    # after the 2200-byte header, offset 2200 holds 2200 % 256 = 152: category 152, LEN 0x999A = 39322 runs
    # past the end, and no later offset starts three chained frames
    assert rec.container_bytes == 2200 and rec.frames == {}
    assert rec.errors[["offset", "length"]].values.tolist() == [[2200, 872]]
    assert "truncated" in rec.errors.reason.iloc[0]
    with pytest.warns(asterix.ContentWarning, match="garbage.bin is not ASTERIX: read as oradis, 100% of its "
                                                    "3072 bytes"):
        rec = read(tmp_path, data, "garbage.bin", format="oradis")
    # packet length 0x0001 = 1 at offset 0; a later offset holding k, k + 1 reads length 257k + 1 with its
    # first block LEN 257(k + 7) + 1, longer than the payload (and from k = 12 on, 3085 bytes: past the end)
    assert rec.container_bytes == 0 and rec.frames == {}
    assert rec.errors[["offset", "length"]].values.tolist() == [[0, 3072]]
    assert "below 9" in rec.errors.reason.iloc[0]


# ---------------------------------------------------------------------------------------------------------
# Mutations: any one damage keeps the byte account exact and loses only the frames near it


def mutate(data: bytes, draw) -> tuple[bytes, int, int, str]:
    """One damage: (damaged bytes, first and last original byte it touches, kind)."""
    buf = bytearray(data)
    pos = draw(st.integers(0, len(buf) - 1))
    action = draw(st.sampled_from(["flip", "truncate", "insert", "delete"]))
    if action == "flip":
        buf[pos] ^= 1 << draw(st.integers(0, 7))
    elif action == "truncate":
        del buf[pos:]
    elif action == "insert":
        buf[pos:pos] = draw(st.binary(min_size=1, max_size=8))
    else:
        n = draw(st.integers(1, 8))
        del buf[pos:pos + n]
        return bytes(buf), pos, min(pos + n, len(data)) - 1, action  # a deletion may span two frames
    return bytes(buf), pos, pos, action


def survivors(rec: asterix.Recording) -> set[int]:
    return set(rec.frames[48].track_number) if 48 in rec.frames else set()


def numbered(i: int) -> bytes:
    """A CAT048 block of one record, FRN 1, 2, 11 (I048/161 track number i): FSPEC C1 10, 12 bytes in all."""
    return block(48, fspec(1, 2, 11) + bytes([25, 1]) + tod3(100.0 + i) + i.to_bytes(2, "big"))


@pytest.mark.fuzz
@settings(max_examples=examples(150), deadline=None)
@given(st.data())
def test_mutated_gps_accounted_and_far_frames_survive(tmp_path_factory, data) -> None:
    frames = [(numbered(i), 100.5 + i) for i in range(1, 9)]
    good, at = gps_file(frames)
    bad, pos, last, action = mutate(good, data.draw)
    path = tmp_path_factory.mktemp("gps") / "m.gps"
    path.write_bytes(bad)
    with warnings.catch_warnings():  # damage that leaves most of it unread is said: not what is checked here
        warnings.simplefilter("ignore", asterix.ContentWarning)
        rec = asterix.read(path, format="gps")
    assert rec.decoded_bytes + int(rec.errors.length.sum()) + rec.container_bytes + rec.ignored_bytes \
        == len(bad)
    if pos < at[0]:
        return  # damage in the file header shifts every frame: only the account is promised
    hit = max(i for i, a in enumerate(at) if a <= pos)  # frame index 0-7 holding the damage's first byte
    end = max(i for i, a in enumerate(at) if a <= last)  # and its last (a deletion can reach the next)
    kept = survivors(rec)
    assert set(range(1, hit)) <= kept  # every frame before the damaged one (and its predecessor) decodes
    if action != "truncate":
        assert set(range(end + 3, 9)) <= kept  # and every frame from the second after the last damaged


@pytest.mark.fuzz
@settings(max_examples=examples(150), deadline=None)
@given(st.data())
def test_mutated_oradis_accounted_and_far_packets_survive(tmp_path_factory, data) -> None:
    good, at = oradis_file([numbered(i) for i in range(1, 9)])
    bad, pos, last, action = mutate(good, data.draw)
    path = tmp_path_factory.mktemp("oradis") / "m.oradis"
    path.write_bytes(bad)
    with warnings.catch_warnings():  # damage that leaves most of it unread is said: not what is checked here
        warnings.simplefilter("ignore", asterix.ContentWarning)
        rec = asterix.read(path, format="oradis")
    assert rec.decoded_bytes + int(rec.errors.length.sum()) + rec.container_bytes + rec.ignored_bytes \
        == len(bad)
    hit = max(i for i, a in enumerate(at) if a <= pos)
    end = max(i for i, a in enumerate(at) if a <= last)
    kept = survivors(rec)
    assert set(range(1, hit)) <= kept
    if action != "truncate":
        assert set(range(end + 3, 9)) <= kept


def test_cli_reads_recorder_files(tmp_path, capsys) -> None:
    from msdc.pipeline.cli import main

    data, _, _ = midnight_gps()
    path = tmp_path / "day.gps"
    path.write_bytes(data)
    assert main(["stats", str(path), "--format", "gps", "--date", "2019-03-01"]) == 0
    out = capsys.readouterr()
    assert "Traceback" not in out.err
    # CAT021 and CAT048 records, and the CAT034 block (stats decodes every category msdc decodes)
    assert "Skipped blocks by reason:\n  none" in out.out
    assert "Blocks of categories not decoded:\n  none" in out.out
    assert re.search(r"\n\s*34\s+yes\s+1\s", out.out.split("Records per SAC/SIC")[0])
    oradis, _ = mixed_oradis()
    opath = tmp_path / "day.oradis"
    opath.write_bytes(oradis)
    assert main(["decode", str(opath), "-o", str(tmp_path / "out.csv")]) == 0
    assert (tmp_path / "out_cat048.csv").exists() and (tmp_path / "out_cat021.csv").exists()
    assert pd.read_csv(tmp_path / "out_cat048.csv").sic.tolist() == [1, 2, 2]


# ---------------------------------------------------------------- a damaged first frame: detection says raw

def damaged_first_frames() -> dict[str, bytes]:
    """Eight CAT048 blocks (9 bytes each) as a final, gps and oradis file, each with a damaged first frame."""
    blocks = [block(48, r048(i, 3600.0 + i)) for i in range(1, 9)]
    headers = [struct.pack(">HBBB", 8 + 9 + 4, 3, 1, 0) + (360000 + 100 * i).to_bytes(3, "big")  # ToD 10 ms
               for i in range(len(blocks))]
    final = bytearray(b"".join(h + data + b"\xa5" * 4 for h, data in zip(headers, blocks, strict=True)))
    final[1] ^= 1  # frame length 21 -> 20: its trailer is not where the length says
    gps, at = gps_file([(data, 3600.5 + i) for i, data in enumerate(blocks)])
    gps = bytearray(gps)
    gps[at[0] + 9 + 6:at[0] + 9 + 9] = b"\xff\xff\xff"  # frame 1's recording time past 24 h
    oradis = bytearray(oradis_file(blocks)[0])
    oradis[0] ^= 1  # packet length 15 -> 271: does not lead to the next packet
    return {"final": bytes(final), "gps": bytes(gps), "oradis": bytes(oradis)}


def test_recorder_hint_names_the_format_of_a_damaged_start() -> None:
    for fmt, data in damaged_first_frames().items():
        assert detect_format(data) == "raw"  # the limit docs/decoding/containers.md states
        assert recorder_hint(data) == fmt
    # a raw stream, damaged or not, is no recorder file
    raw = b"".join(block(48, r048(i, 3600.0 + i)) for i in range(1, 40))
    assert recorder_hint(raw) is None and recorder_hint(raw[:100] + b"\x00" + raw[101:]) is None


def test_stats_hints_at_format_for_a_damaged_start(tmp_path, capsys) -> None:
    for fmt, data in damaged_first_frames().items():
        path = tmp_path / f"damaged.{fmt}"
        path.write_bytes(data)
        main(["stats", str(path), "--date", "2019-03-01"])
        err = capsys.readouterr().err
        assert f"{path}: read as a raw ASTERIX stream" in err and f"give --format {fmt}" in err
        assert main(["stats", str(path), "--date", "2019-03-01", "--format", fmt]) == 0
        assert "give --format" not in capsys.readouterr().err


FILLERS = [b" " * 2200, b"\xff" * 2200, b"\x01" * 2200, (b"GPS RECORDER 1.0 " * 130)[:2200]]


@pytest.mark.parametrize("header", FILLERS, ids=["spaces", "0xff", "0x01", "text"])
def test_gps_header_of_any_filler_is_detected_from_its_frames(tmp_path, header) -> None:
    """A GPS recorder file whose 2200-byte header is spaces (0x20 0x20 0x20: CAT032, LEN 8224), 0xFF, 0x01
    or text starts a chain of data blocks: it was read as raw ('blocks of categories 6, 19, 32 ...',
    nothing decoded). Its frames tell it (every frame chains after the header, the raw chain breaks inside
    them): detected as gps, every record of the fixture decodes, nothing skipped."""
    import json
    from pathlib import Path

    fixtures = Path(__file__).resolve().parents[2] / "fixtures"
    raw = (fixtures / "adsb.ast").read_bytes()
    blocks, at = [], 0
    while at < len(raw):  # the fixture's blocks, hopped by LEN
        n = int.from_bytes(raw[at + 1:at + 3], "big")
        blocks.append(raw[at:at + n])
        at += n
    data = header + b"".join(b + TRAILER_HEAD + tod3(28800 + i / 2) + TRAILER_TAIL
                             for i, b in enumerate(blocks))
    assert detect_format(data[:DETECT_BYTES]) == "gps"
    rec = read(tmp_path, data, "filler.gps", categories=None)
    rows = json.loads((fixtures / "truth.json").read_text())["adsb"]["rows"]
    assert rec.format == "gps" and rec.errors.empty and len(rec.frames[21]) == rows
