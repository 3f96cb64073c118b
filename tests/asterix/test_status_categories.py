"""Status and service messages (CAT019 1.3, CAT023 1.2/1.3, CAT025 1.5, CAT063 1.6, CAT065 1.5): one
message per category written by hand from the printed layouts, values worked by hand; the encoder writes
the same bytes; decoded only when asked; random and damaged bytes stay accounted with them decoded."""

from __future__ import annotations

import pandas as pd
import pytest
from asterix_bytes import block, decode_bytes, fspec, mutate
from budget import examples
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from msdc.asterix.categories import DECODABLE
from msdc.asterix.encode import encode_record

# CAT019: FRNs 1-10. I019/010 0 50; /000 2 periodic; /140 43200 s * 128 = 5529600 = 0x546000;
# /550 NOGO 1, OVL 1, TSV 0, TTF 1, spare: 01 1 0 1 000 = 0x68;
# /551 TP1A 1 TP1B 1 TP2A 0 TP2B 0 TP3A 0 TP3B 1 TP4A 0 TP4B 1 = 1100 0101 = 0xC5;
# /552 count 2: RSI 1, 0 1 1 1 1 1 00 = 0x7C; RSI 2, RSS 0: 0 1 1 1 0 1 00 = 0x74;
# /553 REFTR1 3, spare, REFTR2 2, spare, FX: 11 00 10 0 1 = 0xC9; REFTR3 1, REFTR4 3: 01 00 11 0 0 = 0x4C;
# /600 LAT 45 deg / (180/2^30) = 2^28 = 0x10000000, LON -45 deg = -2^28 = 0xF0000000;
# /610 100.5 m / 0.25 = 402 = 0x0192; /620 -20 m = 0xEC
CAT019 = (fspec(*range(1, 11)) + bytes.fromhex("0032" "02" "546000" "68" "C5" "02017C0274" "C94C"
                                               "10000000F0000000" "0192" "EC"))
CAT019_VALUES = {
    "sac": 0, "sic": 50, "message_type": 2, "time_of_day": 43200.0, "nogo": 1, "overload": 1,
    "time_source_invalid": 0, "test_target_failure": 1, "tp1_exec": 1, "tp1_good": 1, "tp2_exec": 0,
    "tp2_good": 0, "tp3_exec": 0, "tp3_good": 1, "tp4_exec": 0, "tp4_good": 1, "ref_transponder_1": 3,
    "ref_transponder_2": 2, "ref_transponder_3": 1, "ref_transponder_4": 3, "reference_latitude": 45.0,
    "reference_longitude": -45.0, "reference_height_m": 100.5, "geoid_undulation_m": -20.0}

# CAT023: FRNs 1-9. I023/010 0 51; /000 1; /015 SID 3 STYP 2 = 0x32; /070 100 s * 128 = 0x003200;
# /100 NOGO 1 ODP 0 OXT 0 MSC 1 TSV 1 SPO 0 RN 1 FX = 1001 1011 = 0x9B; GSSP 5 s, no FX = 0x0A;
# /101 RP 1 s / 0.5 = 2, SC 1, spare 4, FX: 0x02, 001 0000 1 = 0x21; SSRP 10 s = 0001010 0 = 0x14;
# /200 250 NM = 0xFA; /110 spare 4, STAT 3, FX 0: 0000 011 0 = 0x06;
# /120 count 1: TYPE 3, REF 1 + spare = 0x80, CV 100 = 0x00000064
CAT023 = fspec(*range(1, 10)) + bytes.fromhex("0033" "01" "32" "003200" "9B0A" "022114" "FA" "06"
                                              "01" "03" "80" "00000064")
CAT023_VALUES = {
    "sac": 0, "sic": 51, "message_type": 1, "service_id": 3, "service_type": 2, "time_of_day": 100.0,
    "nogo": 1, "dp_overload": 0, "transmission_overload": 0, "monitoring_connected": 1,
    "time_source_invalid": 1, "spoofing": 0, "track_renumbered": 1, "status_period_s": 5.0,
    "report_period_s": 1.0, "service_class": 1, "service_status_period_s": 10.0,
    "operational_range_nm": 250.0,
    "service_status": 3}

# CAT025: FRNs 1-10, 12, 13 (11 is SP). I025/010 0 52; /000 RTYP 2, RG 1: 0000010 1 = 0x05;
# /200 70000 = 0x011170; /015 9; /020 "SVC1    ": S 19, V 22, C 3, 1 49, spaces 32:
#   010011 010110 000011 110001 | 100000 100000 100000 100000 = 4D 60 F1 | 82 08 20;
# /070 1.5 s * 128 = 192 = 0x0000C0; /100 NOGO 1, OPS 2, SSTAT 2, FX: 1 10 0010 1 = 0xC5;
#   spare, SYSTAT 2, SESTAT 1, no FX: 0 010 001 0 = 0x22; /105 count 2: codes 2 (time source invalid), 5;
# /120 count 1: CID 0x0102, ERRC 1, CS 1: 000001 01 = 0x05; /140 count 0;
# /600 LAT 45 deg / (180/2^32) = 2^30 = 0x40000000, LON -90 deg = -2^31 = 0x80000000;
# /610 -2 m / 0.25 = -8 = 0xFFF8
CAT025 = (fspec(*range(1, 11), 12, 13) + bytes.fromhex("0034" "05" "011170" "09" "4D60F1820820" "0000C0"
                                                       "C522" "020205" "01010205" "00" "4000000080000000"
                                                       "FFF8"))
CAT025_VALUES = {
    "sac": 0, "sic": 52, "message_type": 2, "event_driven": 1, "message_id": 70000, "service_id": 9,
    "service_designator": "SVC1", "time_of_day": 1.5, "nogo": 1, "operational_state": 2,
    "system_service_status": 2, "system_status": 2, "service_status": 1, "reference_latitude": 45.0,
    "reference_longitude": -90.0, "reference_height_m": -2.0}

# CAT063: FRNs 1-11. I063/010 0 53; /015 4; /030 86399.9921875 s * 128 = 11059199 = 0xA8BFFF; /050 25 201;
# /060 CON 1, PSR 1, SSR MDS ADS MLT 0, FX: 01 1 0 0 0 0 1 = 0x61;
#   OPS 0 ODP 1 OXT 0 MSC 1 TSV 0 NPW 1 spare, no FX: 0101 0100 = 0x54; /070 -12 ms = 0xFFF4;
# /080 SRG -0.0005 / 1e-5 = -50 = 0xFFCE, SRB 0.25 NM * 128 = 32 = 0x0020; /081 -8 * 360/2^16 = 0xFFF8;
# /090 PRG 0.001 / 1e-5 = 100 = 0x0064, PRB -1/128 NM = 0xFFFF; /091 16 * 360/2^16 = 0x0010; /092 0
CAT063 = fspec(*range(1, 12)) + bytes.fromhex("0035" "04" "A8BFFF" "19C9" "6154" "FFF4" "FFCE0020" "FFF8"
                                              "0064FFFF" "0010" "0000")
CAT063_VALUES = {
    "sac": 0, "sic": 53, "service_id": 4, "time_of_day": 86399.9921875, "sensor_sac": 25, "sensor_sic": 201,
    "sensor_status": 1, "psr_nogo": 1, "ssr_nogo": 0, "mds_nogo": 0, "ads_nogo": 0, "mlt_nogo": 0,
    "operational_use_inhibited": 0, "dp_overload": 1, "transmission_overload": 0,
    "monitoring_disconnected": 1, "time_source_invalid": 0, "no_plots": 1, "time_stamping_bias_ms": -12.0,
    "ssr_range_gain": -0.0005, "ssr_range_bias_nm": 0.25, "ssr_azimuth_bias_deg": -0.0439453125,
    "psr_range_gain": 0.001, "psr_range_bias_nm": -0.0078125, "psr_azimuth_bias_deg": 0.087890625,
    "psr_elevation_bias_deg": 0.0}

# CAT065: FRNs 1-7, 13 RE, 14 SP. I065/010 0 54; /000 3; /015 2; /030 60 s * 128 = 7680 = 0x001E00;
# /020 batch 200 = 0xC8; /040 NOGO 1, OVL 1, TSV 0, PSS 2, STTN 1, spare: 01 1 0 10 1 0 = 0x6A; /050 3;
# RE length 3 (01 02), SP length 2 (FF)
CAT065 = fspec(*range(1, 8), 13, 14) + bytes.fromhex("0036" "03" "02" "001E00" "C8" "6A" "03" "030102" "02FF")
CAT065_VALUES = {
    "sac": 0, "sic": 54, "message_type": 3, "service_id": 2, "time_of_day": 60.0, "batch_number": 200,
    "nogo": 1, "overload": 1, "time_source_invalid": 0, "processing_system": 2, "track_renumbered": 1,
    "service_status_report": 3}

MESSAGES = {19: (CAT019, CAT019_VALUES, {"remote_sensor_count": 2}),
            23: (CAT023, CAT023_VALUES, {"statistics_count": 1}),
            25: (CAT025, CAT025_VALUES, {"error_count": 2, "component_count": 1, "statistics_count": 0}),
            63: (CAT063, CAT063_VALUES, {}),
            65: (CAT065, CAT065_VALUES, {})}
# repetitive and explicit items the encoder takes whole (their contents are not columns)
EXTRA = {19: {"552": "02017C0274"}, 23: {"120": "01038000000064"},
         25: {"105": "020205", "120": "01010205", "140": "00"}, 63: {}, 65: {"RE": "030102", "SP": "02FF"}}


def _check(frame: pd.DataFrame, values: dict) -> None:
    row = frame.iloc[0]
    for name, want in values.items():
        assert row[name] == (pytest.approx(want) if isinstance(want, float) else want), name


@pytest.mark.parametrize("category", sorted(MESSAGES))
def test_message_values(category: int) -> None:
    data, values, counts = MESSAGES[category]
    # the message twice in a block, then once more in a second: each walked exactly to its end
    stream = block(category, data, data) + block(category, data)
    rec = decode_bytes(stream, categories=[category])
    assert rec.errors.empty and rec.decoded_bytes == len(stream)
    f = rec.frames[category]
    assert len(f) == 3 and f.offset.tolist() == [3, 3 + len(data), 6 + 2 * len(data)]
    assert f.block.tolist() == [0, 0, 1]
    _check(f, {**values, **counts})


def test_cat023_editions_read_alike() -> None:
    for edition in ("1.2", "1.3"):
        rec = decode_bytes(block(23, CAT023), categories=[23], editions={23: edition})
        assert rec.editions == {23: "1.3"}
        _check(rec.frames[23], CAT023_VALUES)


def test_cat063_has_no_message_type() -> None:
    # CAT063 defines no message type item: no column, rather than one always absent
    f = decode_bytes(block(63, CAT063), categories=[63]).frames[63]
    assert "message_type" not in f.columns
    assert all("message_type" in decode_bytes(block(c, MESSAGES[c][0]), categories=[c]).frames[c]
               for c in (19, 23, 25, 65))


@pytest.mark.parametrize("category", sorted(MESSAGES))
def test_encoder_writes_the_hand_bytes(category: int) -> None:
    data, values, _ = MESSAGES[category]
    extra = {k: bytes.fromhex(v) for k, v in EXTRA[category].items()}
    assert encode_record(category, values, extra=extra) == data


def test_decoded_only_when_asked() -> None:
    stream = b"".join(block(c, MESSAGES[c][0]) for c in sorted(MESSAGES))
    rec = decode_bytes(stream)
    assert rec.frames == {} or not any(c in rec.frames for c in MESSAGES)
    assert rec.ignored_blocks == dict.fromkeys(sorted(MESSAGES), 1) and rec.ignored_bytes == len(stream)
    rec = decode_bytes(stream, categories=DECODABLE)
    assert sorted(rec.frames) == sorted(MESSAGES) and rec.errors.empty and rec.decoded_bytes == len(stream)


def _accounted(rec) -> int:
    return rec.decoded_bytes + int(rec.errors["length"].sum()) + rec.container_bytes + rec.ignored_bytes


@pytest.mark.fuzz
@settings(max_examples=examples(300), deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.binary(max_size=600))
def test_random_bytes_accounted_with_every_category_decoded(data: bytes) -> None:
    rec = decode_bytes(data, categories=DECODABLE)
    assert _accounted(rec) == len(data)


def _stream() -> tuple[bytes, list[tuple[int, int]]]:
    """Blocks of every new category, twice over: (bytes, [(start, category)])."""
    # CAT062: I062/010, /070 3600.5 s, /040 track 1234, /080 seven octet groups (as in test_cat062.py)
    track = fspec(1, 4, 12, 13) + bytes.fromhex("1964" "070840" "04D2" "8B3101C1411380")
    bodies = {62: track + track, **{c: m[0] for c, m in MESSAGES.items()}}
    out, starts = b"", []
    for _ in range(2):
        for cat, body in bodies.items():
            starts.append((len(out), cat))
            out += block(cat, body)
    return out, starts


@pytest.mark.fuzz
@settings(max_examples=examples(300), deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.data())
def test_damaged_stream_accounted_and_far_blocks_survive(data) -> None:
    stream, starts = _stream()
    buf = bytearray(stream)
    pos, action = mutate(buf, data)
    rec = decode_bytes(bytes(buf), categories=DECODABLE)
    assert _accounted(rec) == len(buf)
    hit = max(i for i, (s, _) in enumerate(starts) if s <= pos)
    decoded = {int(b) for f in rec.frames.values() for b in f.block}  # block numbers that decoded
    offsets = {int(o) for f in rec.frames.values() for o in f.offset}
    # every block before the damage (or before the block before it, when the damage is in a header)
    # decodes at its own place: no block is framed wrongly and read silently
    first_lost = hit - 1 if pos - starts[hit][0] < 3 else hit
    for start, _ in starts[:max(first_lost, 0)]:
        assert start + 3 in offsets
    if action != "truncate":
        shift = len(buf) - len(stream)
        for start, _ in starts[hit + 2:]:
            assert start + shift + 3 in offsets
    assert decoded <= set(range(rec.blocks))
    for frame in rec.frames.values():
        assert frame["offset"].between(0, len(buf) - 1).all()
