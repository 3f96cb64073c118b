"""Damaged container framing in the middle of a recording: the damaged packet or frame is reported at its own
offset with a true reason, every skipped byte is an error, and reading resumes at the next intact one.

Recordings are hand-built (tests/container_bytes.py, struct from the format descriptions) around CAT048
blocks from the encoder; what must be kept is the undamaged recording's own decode minus the damaged unit's
reports, and offsets are worked out from the lengths written here.
"""

from __future__ import annotations

import struct
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from container_bytes import ETH_IP_UDP, PCAP_RECORD, pcap_file, png_epb, png_idb, png_shb, udp_frame

import msdc.asterix as asterix
from msdc.asterix.encode import encode_frame

TS_10H = 1_551_434_400  # 2019-03-01 10:00:00 UTC
PCAP_HEADER = 24
N_PACKETS, DAMAGED = 12, 5
COLUMNS = ["time_of_day", "track_number", "rho_nm", "theta_deg"]


def block(i: int) -> bytes:
    """One CAT048 block of 3 reports, tracks 3i..3i+2, 10:00:00 + i s."""
    tods = [36000.0 + i + k / 8 for k in range(3)]
    return encode_frame(48, pd.DataFrame({
        "sac": 25, "sic": 1, "time_of_day": tods, "rho_nm": [10.0 + i, 11.0 + i, 12.0 + i],
        "theta_deg": [3.0 * i, 3.0 * i + 1, 3.0 * i + 2], "track_number": [3 * i, 3 * i + 1, 3 * i + 2],
    }), records_per_block=3)


def accounted(rec: asterix.Recording) -> int:
    return rec.decoded_bytes + int(rec.errors["length"].sum()) + rec.container_bytes + rec.ignored_bytes


def reports(rec: asterix.Recording) -> pd.DataFrame:
    return rec.frames[48][COLUMNS].reset_index(drop=True)


def read(tmp_path: Path, name: str, data: bytes) -> asterix.Recording:
    path = tmp_path / name
    path.write_bytes(data)
    return asterix.read(path)


# ---------------------------------------------------------------- pcap

def good_pcap() -> tuple[bytes, list[int]]:
    """The recording and the file offset of each packet record header."""
    data, payload_at = pcap_file([(TS_10H + i, 0, udp_frame(block(i))) for i in range(N_PACKETS)])
    return data, [at - ETH_IP_UDP - PCAP_RECORD for at in payload_at]


@pytest.mark.parametrize(("captured", "original", "reason"), [
    (+4, 0, "captured length {c} exceeds the original length {o}"),
    (0xFFFF, None, "captured length {c} exceeds the original length {o}"),
    (0x7FFFFFFF, None, "captured length {c} exceeds the snapshot length 65535"),
    (+4, +4, "captured length {c} runs past the packet record at offset {next}"),  # original length too
    (+700, +700, "captured length {c} runs past the packet record at offset {next}"),
])
def test_pcap_one_bad_captured_length_loses_only_its_packet(tmp_path: Path, captured: int,
                                                            original: int | None, reason: str) -> None:
    data, record_at = good_pcap()
    whole = reports(read(tmp_path, "good.pcap", data))
    assert len(whole) == 3 * N_PACKETS
    at, size = record_at[DAMAGED], record_at[DAMAGED + 1] - record_at[DAMAGED] - PCAP_RECORD
    c = size + captured if captured < 0x100 else captured
    o = size + original if original is not None else size
    damaged = bytearray(data)
    struct.pack_into("<II", damaged, at + 8, c, o)
    rec = read(tmp_path, "damaged.pcap", bytes(damaged))
    want = whole.drop(index=range(3 * DAMAGED, 3 * DAMAGED + 3)).reset_index(drop=True)
    pd.testing.assert_frame_equal(reports(rec), want)
    assert len(rec.errors) == 1
    err = rec.errors.iloc[0]
    nxt = record_at[DAMAGED + 1]
    assert (err.offset, err.length) == (at, nxt - at)  # the whole damaged record, up to the next one
    assert reason.format(c=c, o=o, next=nxt) in err.reason
    assert err.reason.endswith(f"reading resumes at the next plausible packet record, offset {nxt}")
    assert accounted(rec) == len(data) == rec.size_bytes


def test_pcap_short_captured_length_keeps_the_rest(tmp_path: Path) -> None:
    # packet 5 said 4 bytes short: its payload no longer frames (skipped as such); its last 4 bytes and the
    # next record header then read as an implausible header, reported where the short length leads
    data, record_at = good_pcap()
    whole = reports(read(tmp_path, "good.pcap", data))
    at, nxt = record_at[DAMAGED], record_at[DAMAGED + 1]
    damaged = bytearray(data)
    struct.pack_into("<I", damaged, at + 8, nxt - at - PCAP_RECORD - 4)
    rec = read(tmp_path, "damaged.pcap", bytes(damaged))
    want = whole.drop(index=range(3 * DAMAGED, 3 * DAMAGED + 3)).reset_index(drop=True)
    pd.testing.assert_frame_equal(reports(rec), want)
    header = rec.errors[rec.errors.reason.str.contains("packet record header")]
    assert header[["offset", "length"]].values.tolist() == [[nxt - 4, 4]]
    assert f"where the captured length of the record at offset {at} leads" in header.reason.iloc[0]
    assert accounted(rec) == len(data) == rec.size_bytes


def test_pcap_damaged_capture_time_is_not_framing_damage(tmp_path: Path) -> None:
    # a timestamp far off breaks no framing: the packet is kept (its time reported by the capture-time check)
    data, record_at = good_pcap()
    damaged = bytearray(data)
    struct.pack_into("<I", damaged, record_at[DAMAGED], TS_10H - 2**30)
    rec = read(tmp_path, "damaged.pcap", bytes(damaged))
    assert rec.frames[48].track_number.tolist() == list(range(3 * N_PACKETS))
    assert rec.errors.offset.tolist() == [record_at[DAMAGED]]
    assert np.all(rec.errors.length == 8)


# ---------------------------------------------------------------- pcapng

def good_pcapng() -> tuple[bytes, list[int]]:
    """The recording (SHB, IDB of link type 1, one EPB per packet) and the file offset of each EPB."""
    data, epb_at = png_shb("<") + png_idb("<", 1), []
    for i in range(N_PACKETS):
        epb_at.append(len(data))
        data += png_epb("<", 0, (TS_10H + i) * 10**6, udp_frame(block(i)))
    return data, epb_at


def damage_trailer(data: bytes, at: int, nxt: int) -> tuple[bytes, str]:
    size = nxt - at
    return (data[:nxt - 4] + struct.pack("<I", 12345) + data[nxt:],
            f"block length mismatch (leading length {size}, trailing length 12345)")


def damage_leading(data: bytes, at: int, nxt: int) -> tuple[bytes, str]:
    # the trailing length is then read from the next block's first 4 bytes: its type, 6 (an EPB)
    size = nxt - at
    return (data[:at + 4] + struct.pack("<I", size + 4) + data[at + 8:],
            f"block length mismatch (leading length {size + 4}, trailing length 6)")


def cut_packet(data: bytes, at: int, nxt: int) -> tuple[bytes, str]:
    # the EPB loses its last 40 bytes (its trailing length, 36 of the packet): the trailing length read
    # where its leading one says is 36 bytes into the next EPB, 8 into its Ethernet frame: source MAC
    # bytes 22 33 44 55 (udp_frame), little-endian 0x55443322
    size = nxt - at
    return (data[:nxt - 40] + data[nxt:],
            f"block length mismatch (leading length {size}, trailing length {0x55443322})")


@pytest.mark.parametrize("damage", [damage_trailer, damage_leading, cut_packet])
def test_pcapng_one_broken_block_loses_only_its_packet(tmp_path: Path, damage) -> None:
    data, epb_at = good_pcapng()
    whole = reports(read(tmp_path, "good.pcapng", data))
    assert len(whole) == 3 * N_PACKETS
    at, nxt = epb_at[DAMAGED], epb_at[DAMAGED + 1]
    damaged, reason = damage(data, at, nxt)
    resume = nxt - (len(data) - len(damaged))  # where the next EPB now starts
    rec = read(tmp_path, "damaged.pcapng", damaged)
    want = whole.drop(index=range(3 * DAMAGED, 3 * DAMAGED + 3)).reset_index(drop=True)
    pd.testing.assert_frame_equal(reports(rec), want)
    assert len(rec.errors) == 1
    err = rec.errors.iloc[0]
    assert (err.offset, err.length) == (at, resume - at)
    assert err.reason == (f"container: {reason}; reading resumes at the next block whose lengths agree, "
                          f"offset {resume}")
    assert accounted(rec) == len(damaged) == rec.size_bytes


# ---------------------------------------------------------------- final (IOSS)

RADAR = Path(__file__).resolve().parents[2] / "fixtures" / "radar.ast"


def radar_final() -> tuple[bytes, list[int]]:
    """fixtures/radar.ast's data blocks, one per final frame (length, 2 bytes, day, 3-byte time of day in
    10 ms, block, A5A5A5A5), 20 s apart from 08:00; and the offset of each frame."""
    data, blocks, at = RADAR.read_bytes(), [], 0
    while at < len(data):
        n = int.from_bytes(data[at + 1:at + 3], "big")
        blocks.append(data[at:at + n])
        at += n
    frames = [struct.pack(">HBBB", 12 + len(b), 0, 0, 0) + ((28800 + 20 * i) * 100).to_bytes(3, "big") + b
              + b"\xa5" * 4 for i, b in enumerate(blocks)]
    return b"".join(frames), [sum(map(len, frames[:i])) for i in range(len(frames))]


@pytest.mark.parametrize("frame", [10, 50, 120])
def test_final_length_one_too_large_loses_only_its_frame(tmp_path: Path, frame: int) -> None:
    # the trailer is then looked for one byte late (A5 A5 A5 and the next frame's first byte): bad trailer;
    # resynchronising on any well-formed frame took a false one inside the damaged frame's data
    data, frame_at = radar_final()
    whole = read(tmp_path, "good.final", data)
    at, nxt = frame_at[frame], frame_at[frame + 1]
    damaged = bytearray(data)
    struct.pack_into(">H", damaged, at, nxt - at + 1)
    path = tmp_path / "damaged.final"
    path.write_bytes(bytes(damaged))
    rec = asterix.read(path, date=whole.date)
    lost = whole.frames[48].offset.between(at, nxt)
    pd.testing.assert_frame_equal(reports(rec), whole.frames[48][~lost][COLUMNS].reset_index(drop=True))
    assert lost.sum() > 0
    assert rec.errors[["offset", "length", "reason"]].values.tolist() == [[at, nxt - at,
                                                                           "container: bad frame trailer"]]
    assert accounted(rec) == len(data) == rec.size_bytes
