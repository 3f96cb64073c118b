"""End to end: encoded CAT048/CAT021 blocks inside hand-built pcap, final and raw recordings, through read().

Containers are written here with struct from the format descriptions (classic pcap with Ethernet/IPv4/UDP,
the IOSS "final" frame, raw concatenated blocks); ASTERIX blocks come from the encoder. Every test checks the
byte accounting: decoded + error + container + ignored bytes == file size.
"""

from __future__ import annotations

import datetime as dt
import struct
import warnings
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from container_bytes import ETH_IP_UDP, pcap_file, udp_frame

import msdc.asterix as asterix
from msdc.asterix.encode import encode_frame
from msdc.pipeline.quality.inventory import reason_kind

UTC = dt.UTC
# 2019-03-01 10:00:00 UTC, worked by hand: 17956 days * 86400 = 1551398400 (2019-03-01 00:00:00);
# + 36000 s (10 h) = 1551434400
TS_10H = 1_551_434_400
MIDNIGHT = 1_551_484_800  # 2019-03-02 00:00:00 UTC = 1551398400 + 86400
MARCH_1 = dt.date(2019, 3, 1)
PCAP_HEADER, PCAP_RECORD = 24, 16
NOT_FRAMING = "does not frame"


def test_epochs_worked_by_hand() -> None:
    assert dt.datetime.fromtimestamp(TS_10H, UTC) == dt.datetime(2019, 3, 1, 10, 0, 0, tzinfo=UTC)
    assert dt.datetime.fromtimestamp(MIDNIGHT, UTC) == dt.datetime(2019, 3, 2, tzinfo=UTC)


# ---------------------------------------------------------------------------------------------------------
# Hand builders



ARP = (b"\xff" * 6 + b"\x00\x11\x22\x33\x44\x55" + b"\x08\x06"
       + struct.pack(">HHBBH", 1, 0x0800, 6, 4, 1) + bytes(20))



def final_file(frames: list[tuple[int, float, bytes]]) -> tuple[bytes, list[int]]:
    """IOSS final: per frame a 2-byte length (all of it), board, line, day byte, ToD in 10 ms (3 bytes),
    the data, then A5A5A5A5. Returns (file bytes, offset of each frame's data)."""
    out, data_at = b"", []
    for day, tod_s, data in frames:
        data_at.append(len(out) + 8)
        out += struct.pack(">HBBB", 8 + len(data) + 4, 3, 1, day) + round(tod_s * 100).to_bytes(3, "big")
        out += data + b"\xa5" * 4
    return out, data_at


def cat048(tods, sic: int = 1, first_track: int = 0, per_block: int = 20) -> bytes:
    n = len(tods)
    return encode_frame(48, pd.DataFrame({
        "sac": 25, "sic": sic, "time_of_day": tods, "rho_nm": np.linspace(10, 60, n),
        "theta_deg": np.linspace(0, 300, n), "flight_level": np.linspace(-10, 350, n),
        "track_number": np.arange(first_track, first_track + n), "callsign": "AFR 12B",
    }), records_per_block=per_block)


def cat021(tods, first_address: int = 0x3C0000, per_block: int = 20) -> bytes:
    n = len(tods)
    return encode_frame(21, pd.DataFrame({
        "sac": 25, "sic": 9, "time_of_day": tods, "latitude": np.linspace(43.5, 44.5, n),
        "longitude": np.linspace(-1.5, 1.5, n), "flight_level": 310.0,
        "address": [f"{first_address + i:06X}" for i in range(n)],
    }), edition="2.7", records_per_block=per_block)


def short_len(block: bytes) -> bytes:
    """The same block with a LEN one byte short of its size: the payload then does not frame."""
    n = int.from_bytes(block[1:3], "big")
    return block[:1] + (n - 1).to_bytes(2, "big") + block[3:]


def write(tmp_path: Path, name: str, data: bytes) -> Path:
    path = tmp_path / name
    path.write_bytes(data)
    return path


def accounted(rec: asterix.Recording) -> int:
    return rec.decoded_bytes + int(rec.errors["length"].sum()) + rec.container_bytes + rec.ignored_bytes


def ts(date: dt.date, seconds: float) -> pd.Timestamp:
    return pd.Timestamp(dt.datetime.combine(date, dt.time(), UTC)) + pd.Timedelta(seconds=seconds)


def near(stamps: pd.Series, want: list[str], tol_s: float = 1 / 256) -> bool:
    """Timestamps within tol_s of the given UTC times (a time of day is kept to 1/128 s)."""
    diff = stamps.reset_index(drop=True) - pd.Series(pd.to_datetime(want, utc=True))
    return bool((diff.abs() <= pd.Timedelta(seconds=tol_s)).all())


def check_timestamps(frame: pd.DataFrame, date: dt.date) -> None:
    want = [ts(date, 86400 * d + t) for d, t in zip(frame.day, frame.time_of_day, strict=True)]
    assert (frame.timestamp - pd.Series(want, index=frame.index)).abs().max() < pd.Timedelta(microseconds=1)


# ---------------------------------------------------------------------------------------------------------
# pcap


def mixed_pcap() -> tuple[bytes, dict]:
    b48a = cat048([36000.0, 36000.5, 36001.0], first_track=1)
    b21a = cat021([36000.25, 36000.75])
    b48b = cat048([36002.0], first_track=4)
    b21b = cat021([36002.25, 36002.5, 36002.75], first_address=0x3C0010)
    bad = short_len(cat048([36003.0, 36003.5], first_track=10))
    data, at = pcap_file([
        (TS_10H, 0, udp_frame(b48a)),
        (TS_10H, 250_000, udp_frame(b21a)),
        (TS_10H + 1, 0, ARP),
        (TS_10H + 2, 0, udp_frame(b48b + b21b)),  # mixed: one block of each category
        (TS_10H + 3, 0, udp_frame(bad)),
    ])
    return data, {"bad_at": at[4], "bad_len": len(bad), "b21_bytes": len(b21a) + len(b21b),
                  "b21_blocks": 2, "mixed_at": at[3]}


def test_pcap_mixed_categories_arp_and_a_payload_that_does_not_frame(tmp_path: Path) -> None:
    data, info = mixed_pcap()
    path = write(tmp_path, "mixed.pcap", data)
    rec = asterix.read(path)
    assert rec.format == "pcap" and rec.path == str(path)
    assert set(rec.frames) == {21, 48}
    f48, f21 = rec.frames[48], rec.frames[21]
    assert f48.track_number.tolist() == [1, 2, 3, 4]
    assert f48.time_of_day.tolist() == [36000.0, 36000.5, 36001.0, 36002.0]
    assert f21.address.tolist() == ["3C0000", "3C0001", "3C0010", "3C0011", "3C0012"]
    assert f21.latitude.iloc[0] == pytest.approx(43.5, abs=1e-6)
    assert (f48.callsign == "AFR 12B").all()
    # the CAT048 record offsets: the first right after its packet's UDP header and the block header
    assert f48.offset.iloc[0] == PCAP_HEADER + PCAP_RECORD + ETH_IP_UDP + 3
    assert f48.offset.iloc[3] == info["mixed_at"] + 3
    # the payload whose block LEN is one short: skipped whole, at its payload offset
    assert len(rec.errors) == 1
    err = rec.errors.iloc[0]
    assert err.offset == info["bad_at"] and err.length == info["bad_len"]
    assert NOT_FRAMING in err.reason and err.category == 48 and err.file == str(path)
    # date from the capture time; timestamp = date + time of day
    assert rec.date == MARCH_1
    assert (f48.day == 0).all() and (f21.day == 0).all()
    assert f48.timestamp.iloc[1] == pd.Timestamp("2019-03-01 10:00:00.5", tz="UTC")
    assert f21.timestamp.iloc[0] == pd.Timestamp("2019-03-01 10:00:00.25", tz="UTC")
    check_timestamps(f48, MARCH_1)
    check_timestamps(f21, MARCH_1)
    assert accounted(rec) == len(data) == rec.size_bytes
    assert rec.ignored_bytes == 0 and rec.ignored_blocks == {}


def test_categories_filter_ignores_cat021(tmp_path: Path) -> None:
    data, info = mixed_pcap()
    rec = asterix.read(write(tmp_path, "mixed.pcap", data), categories=[48])
    assert list(rec.frames) == [48] and len(rec.frames[48]) == 4
    assert rec.ignored_blocks == {21: info["b21_blocks"]}
    assert rec.ignored_bytes == info["b21_bytes"]
    assert len(rec.errors) == 1 and NOT_FRAMING in rec.errors.reason.iloc[0]
    assert accounted(rec) == len(data)


def test_strict_names_the_path_and_the_first_bad_offset(tmp_path: Path) -> None:
    data, info = mixed_pcap()
    path = write(tmp_path, "damaged.pcap", data)
    with pytest.raises(asterix.DecodeError) as exc:
        asterix.read(path, strict=True)
    assert exc.value.path == str(path) and exc.value.offset == info["bad_at"]
    assert str(path) in str(exc.value) and f"offset {info['bad_at']}" in str(exc.value)
    assert NOT_FRAMING in str(exc.value)
    with pytest.raises(asterix.DecodeError) as exc:  # streamed: the chunks before the damage come out first
        for _ in asterix.iter_read(path, chunk=100, strict=True):
            pass
    assert exc.value.offset == info["bad_at"] and exc.value.path == str(path)
    # an undamaged capture reads the same with strict on
    good, _ = pcap_file([(TS_10H, 0, udp_frame(cat048([1.0, 2.0])))])
    assert len(asterix.read(write(tmp_path, "good.pcap", good), strict=True).frames[48]) == 2


def midnight_pcap() -> bytes:
    data, _ = pcap_file([
        (MIDNIGHT - 1, 0, udp_frame(cat048([86399.5], first_track=1))),  # 23:59:59
        (MIDNIGHT - 1, 500_000, udp_frame(cat021([86399.75]))),
        (MIDNIGHT, 200_000, udp_frame(cat048([86399.9], first_track=2))),  # late: yesterday's report
        (MIDNIGHT + 1, 0, udp_frame(cat048([0.5], first_track=3))),  # 00:00:01 next day
        (MIDNIGHT + 1, 100_000, udp_frame(cat021([0.75], first_address=0x3C0001))),
    ])
    return data


def test_pcap_crossing_midnight(tmp_path: Path) -> None:
    data = midnight_pcap()
    rec = asterix.read(write(tmp_path, "midnight.pcap", data))
    f48, f21 = rec.frames[48], rec.frames[21]
    assert rec.date == MARCH_1
    assert f48.day.tolist() == [0, 0, 1] and f21.day.tolist() == [0, 1]
    # 86399.9 s is 86399.8984375 at the 1/128 s LSB
    assert near(f48.timestamp, ["2019-03-01 23:59:59.5", "2019-03-01 23:59:59.9", "2019-03-02 00:00:00.5"])
    assert f48.timestamp.is_monotonic_increasing and f21.timestamp.is_monotonic_increasing
    assert f21.timestamp.tolist() == [pd.Timestamp("2019-03-01 23:59:59.75", tz="UTC"),
                                      pd.Timestamp("2019-03-02 00:00:00.75", tz="UTC")]
    check_timestamps(f48, MARCH_1)
    assert accounted(rec) == len(data)


def test_pcap_starting_after_midnight_with_a_late_report(tmp_path: Path) -> None:
    # first packet at 00:00:00.2 carries 23:59:59.9 of the day before: the recording's date is that day
    data, _ = pcap_file([(MIDNIGHT, 200_000, udp_frame(cat048([86399.9, 0.1])))])
    rec = asterix.read(write(tmp_path, "late.pcap", data))
    assert rec.date == MARCH_1 and rec.frames[48].day.tolist() == [0, 1]
    assert rec.frames[48].timestamp.is_monotonic_increasing


def test_pcap_one_damaged_capture_time_dates_nothing(tmp_path: Path) -> None:
    # 12 packets, one CAT048 report each, 10:00:00 + i s; packet 0's ts_sec loses bit 30 (2^30 s, 34 years)
    packets = [(TS_10H + i, 0, udp_frame(cat048([36000.0 + i], first_track=i))) for i in range(12)]
    packets[0] = (TS_10H - 2**30, 0, packets[0][2])
    data, _ = pcap_file(packets)
    path = write(tmp_path, "flipped.pcap", data)
    rec = asterix.read(path)
    f48 = rec.frames[48]
    assert rec.date == MARCH_1 and f48.day.tolist() == [0] * 12
    # every report at 2019-03-01 10:00:00 + i s, exactly (no float day * 86400 at 1e9 s)
    assert f48.timestamp.tolist() == [pd.Timestamp("2019-03-01 10:00:00", tz="UTC") + pd.Timedelta(seconds=i)
                                      for i in range(12)]
    assert len(rec.errors) == 1
    err = rec.errors.iloc[0]
    # 1551434400 - 1073741824 = 477692576 s = day 5528 (15 years with 4 leap days = 5479 days to 1985-01-01;
    # + 49: 31 of January, then 19 February) + 73376 s (20:22:56)
    assert err.offset == PCAP_HEADER and err.length == 8 and err.file == str(path)
    assert err.reason.endswith("(capture time 1985-02-19 20:22:56)")
    kind = "container: implausible capture time, more than 12 h from most packets around it: its reports are "
    assert reason_kind(err.reason) == kind + "dated by theirs"  # the value left out: stats groups them
    assert accounted(rec) == len(data)
    assert_chunks_equal_read(path, 60)
    with pytest.raises(asterix.DecodeError) as exc:
        asterix.read(path, strict=True)
    assert exc.value.offset == PCAP_HEADER


def test_pcap_link_type_not_read_names_it(tmp_path: Path) -> None:
    data, _ = pcap_file([(TS_10H, 0, udp_frame(cat048([36000.0])))])
    data = data[:20] + struct.pack("<I", 147) + data[24:]  # LINKTYPE_USER0
    rec = asterix.read(write(tmp_path, "user0.pcap", data))
    assert rec.frames == {} and len(rec.errors) == 1
    assert rec.errors.offset.iloc[0] == PCAP_HEADER + PCAP_RECORD
    assert "link type 147, which msdc does not read" in rec.errors.reason.iloc[0]
    assert accounted(rec) == len(data)


# ---------------------------------------------------------------------------------------------------------
# final


def midnight_final() -> tuple[bytes, list[int], int]:
    bad = short_len(cat048([3.0], first_track=9))
    data, at = final_file([
        (5, 86398.0, cat048([86397.9, 86398.0], first_track=1)),
        (5, 86399.5, cat021([86399.25]) + cat048([86399.4], first_track=3)),
        (6, 0.5, cat048([86399.95], first_track=4)),  # late report after the day byte went up
        (6, 1.0, cat048([0.9], first_track=5)),
        (6, 1.5, cat021([1.25], first_address=0x3C0001)),
        (6, 3.0, bad),
    ])
    return data, at, len(bad)


@pytest.mark.parametrize("date", [None, "2019-03-01", MARCH_1])
def test_final_crossing_midnight(tmp_path: Path, date) -> None:
    data, at, bad_len = midnight_final()
    path = write(tmp_path, "midnight.final", data)
    rec = asterix.read(path, date=date)
    assert rec.format == "final"
    f48, f21 = rec.frames[48], rec.frames[21]
    assert f48.track_number.tolist() == [1, 2, 3, 4, 5]
    assert f48.day.tolist() == [0, 0, 0, 0, 1] and f21.day.tolist() == [0, 1]
    assert f48.offset.iloc[0] == at[0] + 3
    assert len(rec.errors) == 1 and rec.errors.offset.iloc[0] == at[5]
    assert rec.errors.length.iloc[0] == bad_len and NOT_FRAMING in rec.errors.reason.iloc[0]
    assert accounted(rec) == len(data)
    if date is None:  # final frames carry no calendar date
        assert rec.date is None
        assert f48.timestamp.isna().all() and f21.timestamp.isna().all()
        assert str(f48.timestamp.dtype) == "datetime64[ns, UTC]"
    else:
        assert rec.date == MARCH_1
        check_timestamps(f48, MARCH_1)
        check_timestamps(f21, MARCH_1)
        assert f48.timestamp.is_monotonic_increasing
        assert near(f48.timestamp.iloc[-1:], ["2019-03-02 00:00:00.9"])
        assert f21.timestamp.iloc[-1] == pd.Timestamp("2019-03-02 00:00:01.25", tz="UTC")


# ---------------------------------------------------------------------------------------------------------
# raw


def midnight_raw() -> tuple[bytes, int]:
    """Raw blocks across midnight; returns the bytes and the offset of the first block after midnight."""
    before = (cat048([86390.0 + i for i in range(8)], first_track=1, per_block=2)
              + cat021([86398.5]) + cat048([86399.0], first_track=9))
    after = (cat048([1.0], first_track=10) + cat021([1.5], first_address=0x3C0001)
             + cat048([2.0 + i for i in range(8)], first_track=11, per_block=3))
    return before + after, len(before)


def test_raw_crossing_midnight(tmp_path: Path) -> None:
    data, cut = midnight_raw()
    path = write(tmp_path, "midnight.ast", data)
    rec = asterix.read(path, date="2019-03-01")
    assert rec.format == "raw" and rec.errors.empty
    f48, f21 = rec.frames[48], rec.frames[21]
    assert f48.day.tolist() == [0] * 9 + [1] * 9 and f21.day.tolist() == [0, 1]
    assert (f48.offset >= cut).tolist() == [False] * 9 + [True] * 9
    assert f48.timestamp.is_monotonic_increasing and f21.timestamp.is_monotonic_increasing
    assert f48.timestamp.iloc[8] == pd.Timestamp("2019-03-01 23:59:59", tz="UTC")
    assert f48.timestamp.iloc[9] == pd.Timestamp("2019-03-02 00:00:01", tz="UTC")
    check_timestamps(f48, MARCH_1)
    check_timestamps(f21, MARCH_1)
    assert accounted(rec) == len(data) and rec.container_bytes == 0
    # no date: NaT timestamps, days still counted
    rec = asterix.read(path)
    assert rec.date is None and rec.frames[48].timestamp.isna().all()
    assert rec.frames[48].day.tolist() == [0] * 9 + [1] * 9 and rec.frames[21].day.tolist() == [0, 1]


# ---------------------------------------------------------------------------------------------------------
# format detection and override


def test_format_detection_and_override(tmp_path: Path) -> None:
    pcap_data, _ = mixed_pcap()
    final_data, _, _ = midnight_final()
    raw_data, _ = midnight_raw()
    files = {"pcap": write(tmp_path, "a.bin", pcap_data), "final": write(tmp_path, "b.bin", final_data),
             "raw": write(tmp_path, "c.bin", raw_data)}
    sizes = {"pcap": len(pcap_data), "final": len(final_data), "raw": len(raw_data)}
    for fmt, path in files.items():
        rec = asterix.read(path)
        assert rec.format == fmt
        assert len(rec.frames[48]) > 0
        assert accounted(rec) == sizes[fmt]
        assert asterix.read(path, format=fmt).format == fmt
    # forcing another format: read as told, every byte still accounted for; a wrong one that leaves most bytes
    # undecoded is said, naming the file
    for fmt, path in files.items():
        for forced in ("raw", "pcap", "final"):
            with warnings.catch_warnings(record=True) as said:
                warnings.simplefilter("always")
                rec = asterix.read(path, format=forced)
            assert rec.format == forced
            assert accounted(rec) == sizes[fmt]
            if forced == fmt:
                assert not said
            for w in said:
                assert issubclass(w.category, asterix.ContentWarning) and path.name in str(w.message)
    # a raw file forced as pcap has no pcap magic: nothing decoded, the whole file is a problem, said
    with pytest.warns(asterix.ContentWarning, match="c.bin is not ASTERIX: read as pcap"):
        rec = asterix.read(files["raw"], format="pcap")
    assert rec.frames == {} and rec.decoded_bytes == 0
    assert rec.errors.length.sum() == sizes["raw"] and "magic" in rec.errors.reason.iloc[0]
    # the final frames' payloads are exact: forced raw, the headers and trailers become errors
    with pytest.warns(asterix.ContentWarning, match="b.bin: 82% of its 261 bytes did not decode"):
        rec = asterix.read(files["final"], format="raw")
    assert not rec.errors.empty and rec.container_bytes == 0
    with pytest.raises(asterix.UnreadableInput, match="format"):
        asterix.read(files["raw"], format="pcapx")


@pytest.mark.parametrize(("forced", "reason"), [
    ("pcap", "bad pcap magic"),  # the first four bytes are a CAT048 block header, not a pcap magic
    ("pcapng", "missing section header"),  # nor the pcapng section header 0A 0D 0D 0A
    # a final frame's first two bytes are its length: 30 00 (a CAT048 block under 256 bytes) is 12288,
    # longer than the file
    ("final", "impossible frame length")])
def test_a_container_format_forced_on_a_raw_stream_is_said(tmp_path: Path, forced: str, reason: str) -> None:
    """format="pcap" (pcapng, final) on a raw stream returned no frame and no warning, the reason only in
    .errors, where gps and oradis warned: now a ContentWarning names the file, the format and the reason,
    and that detection reads it as raw."""
    data, _ = midnight_raw()
    assert data[0] == 48 and data[1] == 0 and len(data) < 12288
    path = write(tmp_path, "c.ast", data)
    with pytest.warns(asterix.ContentWarning) as said:
        rec = asterix.read(path, format=forced)
    assert rec.frames == {} and len(said) == 1
    text = str(said[0].message)
    assert text.startswith(f"c.ast is not ASTERIX: read as {forced}, 100% of its {len(data)} bytes frame "
                           f"into no data block that decodes ({len(data)} bytes that do not read as "
                           f"{forced}: {reason})")
    assert text.endswith(f"; read as {forced} as told (detection would read it as raw)")


def test_a_final_format_forced_on_a_mostly_raw_file_is_said(tmp_path: Path) -> None:
    """Raw blocks, then one final frame: read as final, the raw head is one damaged run and the frame's
    records decode; the head being most of the payload, the file is mostly not ASTERIX as read."""
    head = cat048([10.0 + i for i in range(6)], per_block=6)
    frame, data_at = final_file([(0, 20.0, cat048([20.0, 21.0], first_track=7))])
    data = head + frame
    assert data[1] == 0 and len(data) < 12288  # a first frame length of 0x30xx: past the end
    payload = len(data) - 12  # the frame's 8 header and 4 trailer bytes are container
    share = len(head) / payload
    assert 0.5 <= share < 0.9
    path = write(tmp_path, "m.ast", data)
    with pytest.warns(asterix.ContentWarning) as said:
        rec = asterix.read(path, format="final")
    assert rec.frames[48].track_number.tolist() == [7, 8]
    assert [str(w.message) for w in said] == [
        f"m.ast: {share:.0%} of its {payload} bytes did not decode ({len(head)} bytes that do not read as "
        "final: impossible frame length): most of it is not ASTERIX; read as final as told (detection "
        "would read it as raw)"]


# ---------------------------------------------------------------------------------------------------------
# iter_read


def _plain(frame: pd.DataFrame) -> pd.DataFrame:
    """A frame with categoricals as objects (chunks have their own categories)."""
    out = frame.reset_index(drop=True)
    for name in out.columns:
        if isinstance(out[name].dtype, pd.CategoricalDtype):
            out[name] = out[name].astype(object).where(out[name].notna(), None)
    return out


def assert_chunks_equal_read(path: Path, chunk: int, min_chunks: int = 2, in_order: bool = True,
                             **kw) -> list[asterix.Recording]:
    whole = asterix.read(path, **kw)
    parts = list(asterix.iter_read(path, chunk=chunk, **kw))
    assert len(parts) >= min_chunks
    for cat, frame in whole.frames.items():
        pieces = [p.frames[cat] for p in parts if cat in p.frames]
        joined = pd.concat(pieces, ignore_index=True)
        pd.testing.assert_frame_equal(_plain(joined), _plain(frame), check_dtype=False)
        assert not in_order or joined.timestamp.isna().all() or joined.timestamp.is_monotonic_increasing
    assert {c for p in parts for c, f in p.frames.items() if len(f)} == {
        c for c, f in whole.frames.items() if len(f)}
    errors = pd.concat([p.errors for p in parts], ignore_index=True).sort_values("offset", ignore_index=True)
    pd.testing.assert_frame_equal(errors, whole.errors.sort_values("offset", ignore_index=True),
                                  check_dtype=False)
    assert sum(accounted(p) for p in parts) == whole.size_bytes
    assert sum(p.decoded_bytes for p in parts) == whole.decoded_bytes
    return parts


def test_iter_read_raw_across_midnight(tmp_path: Path) -> None:
    data, cut = midnight_raw()
    second = int.from_bytes(data[1:3], "big")  # garbage between the first two blocks
    data = data[:second] + b"\xee" * 7 + data[second:]
    cut += 7
    path = write(tmp_path, "midnight.ast", data)
    errors = asterix.read(path).errors
    assert errors[["offset", "length"]].values.tolist() == [[second, 7]]
    for chunk in (200, 97, cut):
        assert_chunks_equal_read(path, chunk, date="2019-03-01")
        assert_chunks_equal_read(path, chunk)
    # a chunk boundary right at the first block after midnight
    parts = assert_chunks_equal_read(path, cut, date="2019-03-01")
    firsts = [min(int(f.offset.min()) for f in p.frames.values() if len(f)) for p in parts]
    assert cut + 3 in firsts
    after = next(p for p in parts if min(int(f.offset.min()) for f in p.frames.values()) == cut + 3)
    assert (after.frames[48].day == 1).all()



def test_raw_late_reports_give_the_same_days_for_every_chunk(tmp_path: Path) -> None:
    # a raw daily recording: two plots stamped just before midnight, then the day after with late plots
    # (23:59:59.5) sent after reports of 00:00 and 00:03. Worked by hand: day 0 is the first report's day,
    # so the two first plots and every late one are on day 0 and the rest on day 1, whatever the chunks
    # (a late plot at a chunk's start had put the rest of the file a day later).
    tods = [86399.0, 86399.25] + [0.5 + i for i in range(40)] + [86399.5] + [41.0 + i for i in range(40)]
    late = {0, 1, 42}
    path = write(tmp_path, "daily.ast", b"".join(cat048([t], first_track=i) for i, t in enumerate(tods)))
    want = [0 if i in late else 1 for i in range(len(tods))]
    assert asterix.read(path).frames[48].day.tolist() == want
    for chunk in (9, 40, 100, 380, 390, 400):
        parts = assert_chunks_equal_read(path, chunk, in_order=False, date="2019-03-01")
        assert pd.concat([p.frames[48] for p in parts]).day.tolist() == want
    # a late plot after reports of the new day, before any midnight in the file: the day before day 0
    path = write(tmp_path, "late.ast", b"".join(cat048([t], first_track=i)
                                                for i, t in enumerate([0.5, 1.5, 86399.75, 2.5])))
    f48 = asterix.read(path, date="2019-03-02").frames[48]
    assert f48.day.tolist() == [0, 0, -1, 0]
    assert f48.timestamp.iloc[2] == pd.Timestamp("2019-03-01 23:59:59.75", tz="UTC")
    assert f48.timestamp.iloc[3] == pd.Timestamp("2019-03-02 00:00:02.5", tz="UTC")
    for chunk in (9, 20, 30):
        assert_chunks_equal_read(path, chunk, in_order=False, date="2019-03-02")

def test_iter_read_pcap(tmp_path: Path) -> None:
    data, _ = mixed_pcap()
    path = write(tmp_path, "mixed.pcap", data)
    parts = assert_chunks_equal_read(path, 200)
    assert all(p.date == MARCH_1 for p in parts)
    path = write(tmp_path, "midnight.pcap", midnight_pcap())
    for chunk in (1, 60, 100):  # chunk sizes count payload bytes: 291 here
        assert_chunks_equal_read(path, chunk)
        assert_chunks_equal_read(path, chunk, date="2019-03-01")
        with pytest.warns(UserWarning, match="midnight.pcap: date=2018-12-31 ignored, the capture time"):
            assert_chunks_equal_read(path, chunk, date="2018-12-31")  # a capture's own date wins over date=


def test_iter_read_final(tmp_path: Path) -> None:
    data, _, _ = midnight_final()
    path = write(tmp_path, "midnight.final", data)
    for chunk in (1, 60, 150):
        assert_chunks_equal_read(path, chunk, date="2019-03-01")
        assert_chunks_equal_read(path, chunk)


def test_iter_read_many_small_chunks(tmp_path: Path) -> None:
    tods = 86000.0 + np.arange(600) * 1.0  # 10 minutes at 1 s, across midnight
    tods = np.where(tods >= 86400, tods - 86400, tods)
    data = b"".join(cat048(tods[i:i + 10], first_track=i, per_block=5) + cat021(tods[i:i + 10] + 0.5)
                    for i in range(0, 600, 10))
    path = write(tmp_path, "long.ast", data)
    parts = assert_chunks_equal_read(path, 200, min_chunks=50, date="2019-03-01")
    days = pd.concat([p.frames[48] for p in parts if 48 in p.frames]).day.to_numpy()
    assert days.tolist() == [0] * 400 + [1] * 200


# ---------------------------------------------------------------------------------------------------------
# editions={21: "auto"}


def cat021_stream(edition: str, n: int = 400) -> bytes:
    rng = np.random.default_rng(21)
    frame = pd.DataFrame({
        "sac": 25, "sic": 9, "time_of_day": 30000.0 + np.arange(n) * 0.5,
        "latitude": rng.uniform(40, 50, n), "longitude": rng.uniform(-5, 10, n),
        "address": [f"{0x3C0000 + i % 50:06X}" for i in range(n)],
        "flight_level": rng.uniform(0, 400, n),
    })
    if edition.startswith("2."):
        frame["callsign"] = [f"TST{i % 50:03d}" for i in range(n)]
        frame["track_number"] = np.arange(n) % 4096
    return encode_frame(21, frame, edition=edition, records_per_block=8), frame


@pytest.mark.parametrize(("edition", "family"), [
    ("0.23", "0.23"), ("0.24", "0.26"), ("0.25", "0.26"), ("0.26", "0.26"), ("2.1", "2.7"), ("2.7", "2.7")])
def test_auto_edition_picks_the_family(tmp_path: Path, edition: str, family: str) -> None:
    data, truth = cat021_stream(edition)
    path = write(tmp_path, f"cat021_{edition}.ast", data)
    rec = asterix.read(path, editions={21: "auto"})
    assert rec.editions[21] == family
    why = rec.edition_choice[21]
    assert why.startswith(f"chose {family}") and "0.23" in why and "0.26" in why and "2.7" in why
    assert rec.errors.empty and accounted(rec) == len(data)
    f = rec.frames[21]
    assert len(f) == len(truth)
    step = 180 / 2**23 if edition == "0.23" else 180 / 2**25 if edition.startswith("0.") else 180 / 2**30
    assert np.abs(f.latitude.to_numpy() - truth.latitude.to_numpy()).max() <= step / 2 + 1e-12
    assert np.abs(f.longitude.to_numpy() - truth.longitude.to_numpy()).max() <= step / 2 + 1e-12
    assert np.abs(f.time_of_day.to_numpy() - truth.time_of_day.to_numpy()).max() == 0
    assert f.address.tolist() == truth.address.tolist()


def test_auto_tells_0_23_from_0_24(tmp_path: Path) -> None:
    # the same values: I021/130 is 2 x 3 bytes in 0.23, 2 x 4 bytes from 0.24
    d23, _ = cat021_stream("0.23")
    d24, _ = cat021_stream("0.24")
    assert len(d24) - len(d23) == 400 * 2
    r23 = asterix.read(write(tmp_path, "a.ast", d23), editions={21: "auto"})
    r24 = asterix.read(write(tmp_path, "b.ast", d24), editions={21: "auto"})
    assert (r23.editions[21], r24.editions[21]) == ("0.23", "0.26")
    # read under the other edition, neither walks cleanly
    with pytest.warns(asterix.EditionWarning, match=r"decoded under edition 0\.24; every one sampled decodes "
                                                   r"under 0\.23: pin it with editions=\{21: '0\.23'\}"):
        wrong = asterix.read(write(tmp_path, "a.ast", d23), editions={21: "0.24"})
    assert not wrong.errors.empty
    with pytest.warns(asterix.EditionWarning, match=r"decoded under edition 0\.23; every one sampled decodes "
                                                   r"under 0\.24, 0\.25, 0\.26"):
        wrong = asterix.read(write(tmp_path, "b.ast", d24), editions={21: "0.23"})
    assert not wrong.errors.empty


def test_auto_in_a_pcap_and_with_iter_read(tmp_path: Path) -> None:
    data, truth = cat021_stream("0.23", 120)
    blocks, pos = [], 0
    while pos < len(data):
        n = int.from_bytes(data[pos + 1:pos + 3], "big")
        blocks.append(data[pos:pos + n])
        pos += n
    pcap, _ = pcap_file([(TS_10H + i, 0, udp_frame(b)) for i, b in enumerate(blocks)])
    path = write(tmp_path, "auto.pcap", pcap)
    rec = asterix.read(path, editions={21: "auto"})
    assert rec.editions[21] == "0.23" and len(rec.frames[21]) == 120 and rec.errors.empty
    parts = assert_chunks_equal_read(path, 400, editions={21: "auto"})
    assert {p.editions[21] for p in parts} == {"0.23"}


def test_auto_on_a_damaged_stream_loses_no_block_of_the_auto_category(tmp_path: Path) -> None:
    """CAT048 blocks, junk, CAT021 2.1 blocks, junk, CAT048: framing cannot walk a category whose edition
    is still to be chosen, and used to lose every CAT021 block after the first junk. Each CAT021 record of
    the clean prefix (decoded alone, undamaged) must come back, at its offset shifted by what precedes it."""
    root = Path(__file__).resolve().parents[2] / "fixtures"
    radar, adsb = (root / "radar.ast").read_bytes(), (root / "adsb.ast").read_bytes()
    junk = bytes([0x15, 0x00, 0x02]) + bytes(range(200, 234))  # a CAT021 header with LEN 2, then noise
    cut = 40000
    clean = asterix.read(write(tmp_path, "clean.ast", adsb[:cut]), editions={21: "2.1"})
    damaged = write(tmp_path, "d.ast", radar[:30000] + junk + adsb[:cut] + junk + radar[30000:60000])
    rec = asterix.read(damaged, editions={21: "auto"})
    assert rec.editions[21].startswith("2.")
    shift = 30000 + len(junk)
    assert rec.frames[21]["offset"].tolist() == (clean.frames[21]["offset"] + shift).tolist()
    assert len(rec.frames[48]) == len(asterix.read(damaged, editions={21: "2.1"}).frames[48])
    assert_chunks_equal_read(damaged, 10_000, editions={21: "auto"})  # chunk planning frames the same way


def test_pcapng_simple_packet_blocks_without_capture_time(tmp_path: Path) -> None:
    """A Simple Packet Block carries no timestamp: its reports take the day of the nearest timed packet
    before it (after it when none is before); a file of SPBs only is ordered like a raw stream."""
    from container_bytes import png_epb, png_idb, png_shb, png_spb

    # EPB at 2019-03-01 10:00:00 (microseconds) with a report at 36000 s; then an SPB with 36004.5 s
    data = (png_shb("<") + png_idb("<", 1) + png_epb("<", 0, TS_10H * 10**6, udp_frame(cat048([36000.0])))
            + png_spb("<", udp_frame(cat048([36004.5]))))
    rec = asterix.read(write(tmp_path, "spb.pcapng", data))
    assert rec.date == MARCH_1 and rec.errors.empty
    assert rec.frames[48].timestamp.tolist() == [ts(MARCH_1, 36000.0), ts(MARCH_1, 36004.5)]
    assert accounted(rec) == len(data)
    # SPB first, then the timed EPB: the SPB takes the EPB's day
    swapped = (png_shb("<") + png_idb("<", 1) + png_spb("<", udp_frame(cat048([35990.0])))
               + png_epb("<", 0, TS_10H * 10**6, udp_frame(cat048([36000.0]))))
    rec = asterix.read(write(tmp_path, "spb_first.pcapng", swapped))
    assert rec.frames[48].timestamp.tolist() == [ts(MARCH_1, 35990.0), ts(MARCH_1, 36000.0)]
    chunks = list(asterix.iter_read(tmp_path / "spb_first.pcapng", chunk=1))  # one packet per chunk
    assert [t for c in chunks for t in c.frames[48].timestamp] == [ts(MARCH_1, 35990.0), ts(MARCH_1, 36000.0)]
    # only SPBs: no capture time at all, so no date unless given, and days counted in file order
    only = png_shb("<") + png_idb("<", 1) + png_spb("<", udp_frame(cat048([86399.5, 0.5])))
    rec = asterix.read(write(tmp_path, "spb_only.pcapng", only), date="2019-03-01")
    assert rec.frames[48].day.tolist() == [0, 1]
    assert rec.frames[48].timestamp.tolist() == [ts(MARCH_1, 86399.5), ts(MARCH_1, 86400.5)]
    assert accounted(rec) == len(only)
