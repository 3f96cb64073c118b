"""Encoder tests: hand-worked bytes from the printed item layouts, the conformance record, every edition."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from budget import examples
from hypothesis import given, settings
from hypothesis import strategies as st

from msdc.asterix.columns import BDS_KINDS, columns_for
from msdc.asterix.encode import (
    EDITIONS,
    encode_block,
    encode_frame,
    encode_item,
    encode_record,
    item_fields,
    load_table,
)

CONFORMANCE = Path(__file__).resolve().parents[2].parent / "shared" / "conformance"


def ref_fspec(frns: list[int]) -> bytes:
    """FSPEC written out bit by bit: FRN f is bit 7 - (f-1) % 7 of octet (f-1) // 7, FX = bit 0."""
    octets = [0] * ((max(frns) - 1) // 7 + 1)
    for f in frns:
        octets[(f - 1) // 7] |= 0x80 >> ((f - 1) % 7)
    for i in range(len(octets) - 1):
        octets[i] |= 1
    return bytes(octets)


def uap_of(category: int, edition: str, name: str = "") -> list:
    """One UAP of an edition table: "uap", or one of "uaps" (CAT001 "plot" and "track")."""
    table = load_table(category, edition)
    return table["uaps"][name] if "uaps" in table else table["uap"]


def frn_of(category: int, edition: str, item_id: str, uap: str = "") -> int:
    return next(i for i, e in enumerate(uap_of(category, edition, uap), 1) if e and e["id"] == item_id)


# ---------------------------------------------------------------------------------------------------------
# Items, worked by hand from ../shared/specs/Cat_048_1_32.txt


def test_flight_level_negative_two_complement() -> None:
    # I048/090: V(1) G(1) FL(14, signed, lsb 1/4 FL). FL -2048 -> raw -8192 = -2^13, the 14-bit minimum:
    # 2^14 - 8192 = 8192 = 0b10_0000_0000_0000 -> with V=G=0: 0x2000
    assert encode_item(48, "1.32", "090", {"FL": -2048}) == b"\x20\x00"
    # FL 330 -> 1320 = 0x528; V=1 sets bit 15: 0x8528
    assert encode_item(48, None, "090", {"FL": 330, "V": 1}) == b"\x85\x28"
    # FL -0.25 -> raw -1 -> 14 ones = 0x3FFF
    assert encode_item(48, None, "090", {"FL": -0.25}) == b"\x3f\xff"


def test_polar_position() -> None:
    # RHO 16 bits lsb 1/256 NM: 197.68359375 * 256 = 50607 = 0xC5AF
    # THETA 16 bits lsb 360/65536: 340.13671875 / (360/65536) = 61920 = 0xF1E0
    got = encode_item(48, None, "040", {"RHO": 197.68359375, "THETA": 340.13671875})
    assert got == bytes.fromhex("c5aff1e0")
    # rounding to nearest: 197.7 * 256 = 50611.2 -> 50611 = 0xC5B3
    # 340.1 / 0.0054931640625 = 61913.3 -> 61913 = 0xF1D9
    assert encode_item(48, None, "040", {"RHO": 197.7, "THETA": 340.1}) == bytes.fromhex("c5b3f1d9")


def test_icao_callsign() -> None:
    # 6-bit codes: D=4 L=12 H=8 '6'=54 '5'=53 A=1, then two spaces = 32 32
    # 000100 001100 001000 110110 110101 000001 100000 100000
    # = 0001 0000 1100 0010 0011 0110 1101 0100 0001 1000 0010 0000 = 10 C2 36 D4 18 20
    assert encode_item(48, None, "240", {"": "DLH65A"}) == bytes.fromhex("10c236d41820")
    assert encode_item(48, None, "240", "DLH65A  ") == bytes.fromhex("10c236d41820")


def test_mode3a_octal() -> None:
    # V G L spare(1) then 12 bits: 0o7106 = 7*512 + 1*64 + 0*8 + 6 = 3654 = 0x0E46
    assert encode_item(48, None, "070", {"MODE3A": "7106"}) == b"\x0e\x46"
    # V=1 -> bit 15 -> 0x8E46; G=1 -> 0x4000 more -> 0xCE46
    assert encode_item(48, None, "070", {"MODE3A": "7106", "V": 1, "G": 1}) == b"\xce\x46"


def test_aircraft_address_and_time() -> None:
    assert encode_item(48, None, "220", "3C660C") == b"\x3c\x66\x0c"
    assert encode_item(48, None, "220", {"": 0x3C660C}) == b"\x3c\x66\x0c"
    # ToD lsb 1/128 s: 27354.6015625 * 128 = 3501389 = 0x356D4D
    assert encode_item(48, None, "140", 27354.6015625) == bytes.fromhex("356d4d")


def test_extended_target_report_descriptor() -> None:
    # octet 1: TYP(3)=5 SIM RDP SPI RAB FX -> 101 0 0 0 0 FX
    assert encode_item(48, None, "020", {"TYP": 5}) == b"\xa0"
    # a field of octet 2 assigned -> FX on octet 1 (0xA1); octet 2: TST=1 at bit 8 -> 0x80, FX 0
    assert encode_item(48, None, "020", {"TYP": 5, "TST": 1}) == b"\xa1\x80"
    # assigned zero still asks for the octet (the decoder reports absent octets as missing, not 0)
    assert encode_item(48, None, "020", {"TYP": 5, "TST": 0}) == b"\xa1\x00"
    # 1.32 octet 3: ADSB/EP is its first bit; octet 2 all zero but with FX -> A1 01 80
    assert encode_item(48, "1.32", "020", {"TYP": 5, "ADSB/EP": 1}) == b"\xa1\x01\x80"
    # 1.27 has two octets only
    with pytest.raises(ValueError, match="ADSB/EP"):
        encode_item(48, "1.27", "020", {"ADSB/EP": 1})


def test_extended_last_group_without_fx() -> None:
    # I021/271 in 2.1: octet 1 = spare(2) POA CDTIS B2LOW RAS IDENT FX; octet 2 = spare(4) LW(4), no FX
    assert encode_item(21, "2.1", "271", {"LW": 3}) == b"\x01\x03"
    assert encode_item(21, "2.1", "271", {"RAS": 1}) == b"\x04"


def test_compound_plot_characteristics() -> None:
    # subitems SRL(1) and SAM(3) -> compound FSPEC 1010 000 FX=0 = 0xA0
    # SRL 8 bits lsb 360/2^13 = 0.0439453125 deg: 1.0107421875 / 0.0439453125 = 23 = 0x17
    # SAM 8 bits signed dBm: -20 -> 256 - 20 = 236 = 0xEC
    expected = bytes.fromhex("a017ec")
    assert encode_item(48, None, "130", {"SRL/SRL": 1.0107421875, "SAM/SAM": -20}) == expected
    assert encode_item(48, None, "130", {"SRL": 1.0107421875, "SAM": -20}) == expected  # bare-element alias
    record = encode_record(48, {"ssr_runlength_deg": 1.0107421875, "ssr_amplitude_dbm": -20})
    assert record == ref_fspec([7]) + expected  # FRN 7 -> 0x02
    assert record[:1] == b"\x02"


def test_compound_with_repetitive_subitem() -> None:
    # I048/120: CAL(1) = D(1) spare(5) CAL(10 signed m/s); RDS(2) = count + DOP AMB FRQ (16 bits each)
    # FSPEC 1100 000 0 = 0xC0; CAL -5 -> 1024 - 5 = 0x3FB; RDS count 1, DOP 1, AMB 0, FRQ 0
    got = encode_item(48, None, "120", {"CAL/CAL": -5, "RDS": [{"DOP": 1}]})
    assert got == bytes.fromhex("c0" "03fb" "01" "0001" "0000" "0000")


def test_compound_fspec_over_several_octets() -> None:
    # I021/295 (2.7): GVR is subitem 15 -> third FSPEC octet, first bit: 0x01 0x01 0x80
    # value 8 bits lsb 0.1 s: 1.0 s -> 10 = 0x0A
    assert encode_item(21, "2.7", "295", {"GVR/GVR": 1.0}) == b"\x01\x01\x80\x0a"
    # AOS (1) and TI2 (18): octet 1 = 0x81, octet 2 = 0x01, octet 3 = subitem 18 is its 4th bit = 0x10
    assert encode_item(21, "2.7", "295", {"AOS": 0.1, "TI2": 0.2}) == b"\x81\x01\x10\x01\x02"


def test_unknown_fields_rejected() -> None:
    with pytest.raises(ValueError, match="RHOO"):
        encode_item(48, None, "040", {"RHOO": 1.0})
    with pytest.raises(ValueError, match="XYZ"):
        encode_item(48, None, "130", {"XYZ/XYZ": 1})
    with pytest.raises(ValueError, match="no item"):
        encode_item(48, None, "999", {})


def test_repetitive_bds_registers() -> None:
    # count byte 2, then 2 x 8 bytes (MBDATA 56 bits, BDS1 4 bits, BDS2 4 bits)
    reg40 = {"MBDATA": 0xC0780031BC0000, "BDS1": 4, "BDS2": 0}  # -> c0780031bc000040
    reg60 = {"MBDATA": 1, "BDS1": 6, "BDS2": 0}  # -> 00000000000001 60
    got = encode_item(48, None, "250", [reg40, reg60])
    assert got == bytes.fromhex("02" "c0780031bc000040" "0000000000000160")
    assert len(got) == 1 + 16
    assert encode_item(48, None, "250", [bytes(8), b"\xff" * 8]) == b"\x02" + bytes(8) + b"\xff" * 8
    assert encode_item(48, None, "250", []) == b"\x00"


def test_fx_repetitive_warning_conditions() -> None:
    # I048/030: 7-bit code then FX: [1, 2] -> 0000001 1 = 0x03, 0000010 0 = 0x04
    assert encode_item(48, None, "030", [1, 2]) == b"\x03\x04"
    assert encode_item(48, None, "030", [{"": 7}]) == b"\x0e"


def test_explicit_reserved_expansion() -> None:
    # 3 content bytes -> length byte counts itself: 4
    assert encode_item(48, None, "RE", b"\xaa\xbb\xcc") == b"\x04\xaa\xbb\xcc"
    assert encode_item(48, None, "RE", {"": b"\xaa\xbb\xcc"}) == b"\x04\xaa\xbb\xcc"
    assert encode_item(48, None, "RE", {"raw": b"\x04\xaa\xbb\xcc"}) == b"\x04\xaa\xbb\xcc"
    with pytest.raises(ValueError):
        encode_item(48, None, "RE", {"raw": b"\x05\xaa\xbb\xcc"})
    assert encode_item(21, "2.7", "SP", b"") == b"\x01"


# ---------------------------------------------------------------------------------------------------------
# Records and blocks


def test_fspec_frn_1_2_9() -> None:
    # FRN 1 (010), 2 (140), 9 (240): octet 1 = 1100 000 FX=1 = 0xC1, octet 2 = FRN 9 is its second bit = 0x40
    record = encode_record(48, {"sac": 25, "sic": 201, "time_of_day": 27354.6015625, "callsign": "DLH65A"})
    assert record[:2] == b"\xc1\x40"
    assert record == bytes.fromhex("c140" "19c9" "356d4d" "10c236d41820")
    assert ref_fspec([1, 2, 9]) == b"\xc1\x40"


def test_no_trailing_zero_fspec_octets() -> None:
    assert encode_record(48, {"sac": 1, "sic": 2}) == b"\x80\x01\x02"
    # FRN 21 (I048/230) only: octets 0x01 0x01 0x02 (FX, FX, FRN 21 = bit 2 of octet 3)
    assert encode_record(48, {"com": 1})[:3] == b"\x01\x01\x02"


def test_block_header() -> None:
    rec = encode_record(48, {"sac": 1, "sic": 2})
    # CAT 48 = 0x30, LEN = 3 + 2 * 3 = 9
    assert encode_block(48, [rec, rec]) == b"\x30\x00\x09" + rec + rec
    with pytest.raises(ValueError):
        encode_block(48, [bytes(70000)])


def test_column_scale_and_absent_values() -> None:
    # ground speed kt / 3600 -> NM/s, lsb 2^-14 NM/s: 434.3994140625 / 3600 * 16384 = 1977 = 0x07B9
    # heading 124.002685546875 / (360/65536) = 22574 = 0x582E
    rec = encode_record(48, {"ground_speed_kt": 434.3994140625, "heading_deg": 124.002685546875,
                             "rho_nm": None, "theta_deg": float("nan"), "address": pd.NA})
    assert rec == ref_fspec([13]) + bytes.fromhex("07b9582e")


def test_unmapped_fields_zero_and_flags() -> None:
    # I048/170 octet 1: CNF RAD(2) DOU MAH CDM(2) FX; RAD=2 -> 0 10 0 0 00 0 = 0x40
    assert encode_record(48, {"rad": 2}) == ref_fspec([14]) + b"\x40"
    # an assigned octet-2 field (TRE=0) keeps the second octet: 0x41 0x00
    assert encode_record(48, {"rad": 2, "tre": 0}) == ref_fspec([14]) + b"\x41\x00"


def test_bds_count_column_and_extra() -> None:
    # bds_count alone: count byte and zero registers
    assert encode_record(48, {"bds_count": 2}) == ref_fspec([10]) + b"\x02" + bytes(16)
    # `extra` replaces the item and is inserted at its FRN (10), between 240 (FRN 9) and 161 (FRN 11)
    reg = encode_item(48, None, "250", [{"MBDATA": 0xC0780031BC0000, "BDS1": 4}])
    rec = encode_record(48, {"callsign": "DLH65A", "track_number": 3563, "bds_count": 1}, extra={"250": reg})
    # TRN 3563 = 0x0DEB (12 bits after 4 spare)
    assert rec == ref_fspec([9, 10, 11]) + bytes.fromhex("10c236d41820") + reg + b"\x0d\xeb"
    re = encode_item(48, None, "RE", b"\x01\x02\x03")
    assert encode_record(48, {"sac": 1, "sic": 2}, extra={"RE": re}) == ref_fspec([1, 28]) + b"\x01\x02" + re


def test_multi_source_columns_cat021() -> None:
    lat, lon = 48.5, -2.25
    # I021/131: 32-bit signed, lsb 180/2^30: 48.5 -> 48.5 * 2^30 / 180 = 289_313_769.2 -> 0x113E93E9
    #           -2.25 -> -13_421_772.8 -> -13421773 -> 2^32 - 13421773 = 0xFF333333
    rec = encode_record(21, {"latitude": lat, "longitude": lon}, edition="2.7")
    assert rec == ref_fspec([7]) + bytes.fromhex("113e93e9" "ff333333")
    # prefer I021/130: 24-bit signed, lsb 180/2^23: 48.5 -> 2260263.8 -> 2260264 = 0x227D28;
    #                  -2.25 -> -104857.6 -> -104858
    #                  -> 2^24 - 104858 = 0xFE6666
    rec = encode_record(21, {"latitude": lat, "longitude": lon}, edition="2.7",
                        prefer={"latitude": "130", "longitude": "130"})
    assert rec == ref_fspec([6]) + bytes.fromhex("227d28" "fe6666")
    # time_of_day goes to I021/071 (FRN 5), unless I021/073 (FRN 12) already carries that value
    t = 3600.5  # * 128 = 460864 = 0x070840
    assert encode_record(21, {"time_of_day": t}, "2.7") == ref_fspec([5]) + bytes.fromhex("070840")
    rec = encode_record(21, {"time_of_day": t, "time_reception_position": t}, "2.7")
    assert rec == ref_fspec([12]) + bytes.fromhex("070840")
    with pytest.raises(ValueError, match="conflicts"):
        encode_record(21, {"time_of_day": t, "time_applicability_position": t + 1}, "2.7")
    with pytest.raises(ValueError, match="prefer"):
        encode_record(21, {"latitude": lat}, "2.7", prefer={"latitude": "071"})


def test_edition_aliases() -> None:
    assert set(EDITIONS) == {1, 2, 10, 19, 20, 21, 23, 25, 34, 48, 62, 63, 65}
    assert EDITIONS[62] == ["1.16", "1.17", "1.18", "1.19", "1.20", "1.21"]
    assert encode_record(23, {"sac": 1, "nogo": 1}, "1.2") == encode_record(23, {"sac": 1, "nogo": 1}, "1.3")
    assert {"1.27", "1.31", "1.32"} <= set(EDITIONS[48])
    assert encode_item(48, "1.21", "020", {"TYP": 1}) == encode_item(48, "1.27", "020", {"TYP": 1})
    assert encode_record(21, {"sac": 1, "sic": 2}, "2.x") == encode_record(21, {"sac": 1, "sic": 2}, "2.7")
    assert encode_record(20, {"sac": 1, "sic": 2}, "1.x") == encode_record(20, {"sac": 1, "sic": 2}, "1.11")
    with pytest.raises(ValueError):
        encode_record(48, {"sac": 1}, "9.9")


# ---------------------------------------------------------------------------------------------------------
# Out of range


@pytest.mark.parametrize(("item", "fields", "name"), [
    ("040", {"RHO": 256.0}, "RHO"),  # 256 * 256 = 65536 > 16-bit max 65535
    ("040", {"RHO": -0.01}, "RHO"),  # unsigned
    ("040", {"THETA": 360.0}, "THETA"),  # 65536
    ("090", {"FL": 2048}, "FL"),  # raw 8192 > 8191
    ("090", {"FL": -2048.25}, "FL"),  # raw -8193 < -8192
    ("010", {"SAC": 256}, "SAC"),
    ("010", {"SAC": 1.5}, "SAC"),  # not an integer
    ("070", {"MODE3A": "7108"}, "MODE3A"),
    ("070", {"MODE3A": "71061"}, "MODE3A"),
    ("240", {"": "DLH65ABCD"}, "element"),
    ("240", {"": "DLH-65"}, "element"),
    ("130", {"SAM/SAM": -129}, "SAM"),
    ("161", {"TRN": 4096}, "TRN"),
    ("140", {"": float("inf")}, "element"),
])
def test_out_of_range_item(item: str, fields: dict, name: str) -> None:
    with pytest.raises(ValueError, match=name):
        encode_item(48, "1.32", item, fields)


def test_out_of_range_record_and_frame() -> None:
    with pytest.raises(ValueError, match="rho_nm"):
        encode_record(48, {"rho_nm": 300.0, "theta_deg": 1.0})
    with pytest.raises(ValueError, match="unknown column"):
        encode_record(48, {"rho": 3.0})
    with pytest.raises(ValueError, match="no value"):
        encode_record(48, {"rho_nm": None})
    frame = pd.DataFrame({"sac": [1, 2, 3], "sic": [1, 1, 1], "flight_level": [100.0, 2100.0, np.nan]})
    with pytest.raises(ValueError, match="row 1"):
        encode_frame(48, frame)
    with pytest.raises(ValueError, match="no value"):
        encode_frame(48, pd.DataFrame({"sac": [1, None]}))


# ---------------------------------------------------------------------------------------------------------
# Arguments: refused naming the argument and the value

# the categories whose tables ship (test_edition_aliases lists them)
ENCODED = "the encoder encodes categories 1, 2, 10, 19, 20, 21, 23, 25, 34, 48, 62, 63, 65"


@pytest.mark.parametrize(("category", "error", "words"), [
    (8, ValueError, "category 8: no edition table to encode it with; " + ENCODED),
    ("48", TypeError, "category '48': a category number (an int), not str; " + ENCODED),
    (48.0, TypeError, "category 48.0: a category number (an int), not float; " + ENCODED)])
def test_a_category_without_tables_is_named(category, error, words) -> None:
    """encode_record(8, ...) and encode_record("48", ...) raised a bare KeyError (8, '48')."""
    for call in (lambda: encode_record(category, {"sac": 1}),
                 lambda: encode_frame(category, pd.DataFrame({"sac": [1], "sic": [2]})),
                 lambda: encode_item(category, None, "010", {"SAC": 1, "SIC": 2})):
        with pytest.raises(error) as info:
            call()
        assert str(info.value) == words


def test_a_frame_is_a_dataframe() -> None:
    """encode_frame(48, [{...}]) failed with AttributeError 'list' object has no attribute 'columns'."""
    with pytest.raises(TypeError, match=r"^frame: a pandas DataFrame \(one row per record, columns named as "
                                        r"decoding names them\), not list; pd.DataFrame\(rows\) makes one"):
        encode_frame(48, [{"sac": 1, "sic": 2}])


@pytest.mark.parametrize(("per_block", "error", "words"), [
    (1.5, TypeError, "records_per_block 1.5: a positive integer (an int), not float"),
    ("5", TypeError, "records_per_block '5': a positive integer (an int), not str"),
    (True, TypeError, "records_per_block True: a positive integer (an int), not bool"),
    (0, ValueError, "records_per_block 0: must be a positive integer (at least 1)"),
    (-2, ValueError, "records_per_block -2: must be a positive integer (at least 1)")])
def test_records_per_block_is_a_positive_integer(per_block, error, words) -> None:
    """records_per_block=1.5 was taken for one row and raised IndexError for three; "5" failed comparing."""
    frame = pd.DataFrame({"sac": [1, 1, 1], "sic": [2, 2, 2]})
    for rows in (frame.iloc[:1], frame):
        with pytest.raises(error) as info:
            encode_frame(48, rows, records_per_block=per_block)
        assert str(info.value) == words
    # a numpy integer is an integer: 3 records of FSPEC 0x80 + I048/010 (3 bytes), 2 per block
    out = encode_frame(48, frame, records_per_block=np.int64(2))
    assert out == b"\x30\x00\x09" + b"\x80\x01\x02" * 2 + b"\x30\x00\x06\x80\x01\x02"


@pytest.mark.parametrize(("records", "words"), [
    (b"\x01\x02", "records b'\\x01\\x02': a sequence of encoded records (bytes each, as encode_record gives "
                  "them), not bytes; one record is [record]"),
    ([b"\x80\x01\x02", 7], "records[1] 7: an encoded record (bytes), not int")])
def test_a_block_takes_a_sequence_of_records(records, words) -> None:
    """encode_block(48, b"\x01\x02") failed with 'sequence item 0: expected a bytes-like object, int found'
    (bytes are a sequence of ints)."""
    with pytest.raises(TypeError) as info:
        encode_block(48, records)
    assert str(info.value) == words
    assert encode_block(48, (b"\x80\x01\x02",)) == b"\x30\x00\x06\x80\x01\x02"  # a tuple is a sequence


def test_an_edition_is_text() -> None:
    """encode_record(48, ..., edition=1.30) said "edition '1.3' is not supported" (a float cannot hold
    1.30)."""
    with pytest.raises(TypeError, match=r"^edition 1\.3: a float; give it as text, as the tables name it "
                                        r"\('1\.30': a float cannot hold 1\.30; CAT048 tables: 1\.27, "):
        encode_record(48, {"sac": 1}, edition=1.30)
    assert encode_record(48, {"sac": 1}, edition="1.30") == b"\x80\x01\x00"


# ---------------------------------------------------------------------------------------------------------
# Frames


def test_frame_blocks() -> None:
    frame = pd.DataFrame({"sac": 25, "sic": 7, "time_of_day": np.arange(45) * 4.0})
    out = encode_frame(48, frame)
    rec_len = 1 + 2 + 3  # FSPEC 0xC0, 010, 140
    sizes = [20, 20, 5]
    assert len(out) == sum(3 + rec_len * k for k in sizes)
    pos = 0
    for k in sizes:
        assert out[pos] == 48 and int.from_bytes(out[pos + 1:pos + 3], "big") == 3 + rec_len * k
        pos += 3 + rec_len * k
    assert out[3:3 + rec_len] == encode_record(48, frame.iloc[0].to_dict())
    # blocks capped at 65535 bytes: 30000 six-byte records, as many per block as fit
    frame = pd.DataFrame({"sac": 1, "sic": 2, "time_of_day": np.zeros(30000)})
    out = encode_frame(48, frame, records_per_block=100_000)
    per_block = (65535 - 3) // rec_len  # 10922
    assert int.from_bytes(out[1:3], "big") == 3 + per_block * rec_len
    assert len(out) == 3 * 3 + 30000 * rec_len
    assert encode_frame(48, frame.iloc[:0]) == b""


def reference_record(category: int, edition: str, values: dict, uap: str = "") -> bytes:
    """A record assembled from encode_item outputs (the bitstring path) with a hand-made FSPEC (FRNs of
    ``uap``, for a category with several)."""
    cols = {c.name: c for c in columns_for(category, edition)}
    by_item: dict[str, dict] = {}
    for name, v in values.items():
        col = cols[name]
        for item, path in col.sources:
            try:
                known = item_fields(category, edition, item)
            except ValueError:
                continue
            key = "/".join(path)
            if key in known:
                if col.kind == "codes":  # '1,3': the repetitions' codes (I048/030)
                    by_item[item] = [int(c) for c in str(v).split(",")]  # type: ignore[assignment]
                elif col.kind == "count":  # zero repetitions of the item's element (8 bytes in I048/250)
                    node = next(e["node"] for e in uap_of(category, edition, uap) if e and e["id"] == item)
                    by_item[item] = [bytes(node["item"]["bits"] // 8)] * int(v)  # type: ignore[assignment]
                else:
                    by_item.setdefault(item, {})[key] = v / col.scale if col.kind == "float" else v
                break
    frns = {frn_of(category, edition, i, uap): encode_item(category, edition, i, f)
            for i, f in by_item.items()}
    return ref_fspec(sorted(frns)) + b"".join(frns[f] for f in sorted(frns))


def _sample(kind: str, bits_lsb: float) -> object:
    samples = {"int": 1, "flag": 1, "count": 2, "octal": "7106", "icao": "DLH65A", "hex": "3C660C",
               "codes": "1,3"}
    return samples.get(kind, bits_lsb)


ALL_EDITIONS = [(c, e, u) for c, eds in sorted(EDITIONS.items()) for e in eds
                for u in load_table(c, e).get("uaps", {"": None})]
# the value of the UAP selector field (CAT001 I001/020 TYP) for each UAP
SELECT = {"plot": {"typ": 0}, "track": {"typ": 1}}
# CAT062 columns of fields added by later editions (latest first), and how many of them each edition lacks
CAT062_LATER = ["cst_m5", "cst_mlat", "sfc", "idd", "iec", "mode3a_v", "mode3a_g"]
CAT062_LATER_FROM = {"1.16": 7, "1.17": 5, "1.18": 2, "1.19": 2, "1.20": 1}


@pytest.mark.parametrize(("category", "edition", "uap"), ALL_EDITIONS)
def test_every_edition_encodes_every_mapped_column(category: int, edition: str, uap: str) -> None:
    items = {e["id"]: e for e in uap_of(category, edition, uap) if e and e["node"]["kind"] != "rfs"}
    values: dict[str, object] = dict(SELECT.get(uap, {}))
    unmapped = []
    for col in columns_for(category, edition):
        if col.name in values or col.kind in BDS_KINDS:  # Mode S register fields: written as extra (test_bds)
            continue
        src = None
        for item, path in col.sources:
            if item in items and "/".join(path) in item_fields(category, edition, item):
                src = (item, "/".join(path))
                break
        if src is None:
            unmapped.append(col.name)
            continue
        # a float value of one LSB (in the column's unit) fits any quantity field
        lsb = _field_lsb(items[src[0]]["node"], src[1].split("/") if src[1] else [])
        values[col.name] = _sample(col.kind, lsb * col.scale)
    # columns whose item/field is not in this edition (0.23-0.25 have no I021/070 or signal amplitude;
    # I021/151 is a group (RE, TAS) in 2.x while the column addresses a bare element; I021/200 ME is a spare
    # bit in 2.1; CAT020 has no message type item, and 1.9 no I020/020 CF)
    if category == 62:  # I062/060 V, G from 1.17; I062/080 SFC, IDD, IEC from 1.18, MLAT 1.20, M5I 1.21
        assert set(unmapped) == set(CAT062_LATER[:CAT062_LATER_FROM.get(edition, 0)])
    else:
        # CAT001: time_of_day is derived from I001/141 and CAT002; plots have no track items
        assert set(unmapped) <= {"mode3a", "signal_amplitude", "true_airspeed_kt", "me", "time_of_day",
                                 "message_type", "cf",
                                 *(("x_nm", "y_nm", "track_number", "ground_speed_kt", "heading_deg", "con",
                                    "rad", "man", "dou", "rdpc", "gho", "tre") if uap == "plot" else ())}
    for name in unmapped:
        with pytest.raises(ValueError, match=f"{name}|not an item of the record's UAP \\({uap}\\)"):
            encode_record(category, {**SELECT.get(uap, {}), name: 1.0}, edition)
    record = encode_record(category, values, edition)
    assert record == reference_record(category, edition, values, uap)
    frame = pd.DataFrame([values, values])
    rec_len = len(record)
    header = bytes([category]) + (3 + 2 * rec_len).to_bytes(2, "big")
    assert encode_frame(category, frame, edition) == header + record + record


def _field_lsb(node: dict, path: list[str]) -> float:
    """The LSB of the element at path (1 for non-quantities), walking the table node by names."""
    if node["kind"] == "element":
        return float(node.get("lsb", 1.0))
    if node["kind"] == "group":
        children = node["items"]
    elif node["kind"] == "extended":
        children = [c for g in node["groups"] for c in g]
    elif node["kind"] == "compound":
        sub = next(s for s in node["subitems"] if s and s["name"] == path[0])
        return _field_lsb(sub["node"], path[1:] if sub["node"]["kind"] != "element" else [])
    else:
        return 1.0
    for child in children:
        if child.get("name") == path[0]:
            return _field_lsb(child, path[1:])
        if child["kind"] == "group" and not child.get("name"):
            try:
                return _field_lsb(child, path)
            except StopIteration:
                pass
    raise StopIteration(path)


CAT048_ROW = st.fixed_dictionaries({
    "sac": st.integers(0, 255), "sic": st.integers(0, 255),
    "time_of_day": st.floats(0, 86399),
    "typ": st.integers(0, 7), "tst": st.none() | st.integers(0, 1), "foe_fri": st.none() | st.integers(0, 3),
    "rho_nm": st.none() | st.floats(0, 255.99), "theta_deg": st.floats(0, 359.99),
    "mode3a": st.none() | st.integers(0, 4095).map(lambda v: f"{v:04o}"),
    "flight_level": st.none() | st.floats(-2048, 2047.75),
    "ssr_runlength_deg": st.none() | st.floats(0, 11.2),
    "psr_amplitude_dbm": st.none() | st.integers(-128, 127),
    "address": st.none() | st.integers(0, (1 << 24) - 1).map(lambda v: f"{v:06X}"),
    "callsign": st.none() | st.text("ABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789 ", max_size=8),
    "bds_count": st.none() | st.integers(0, 3),
    "x_nm": st.none() | st.floats(-255.9, 255.9), "ground_speed_kt": st.none() | st.floats(0, 3599),
    "cdm": st.none() | st.integers(0, 3), "tcc": st.none() | st.integers(0, 1),
    "height_3d_ft": st.none() | st.floats(-204800, 204775),
    "doppler_speed_ms": st.none() | st.integers(-512, 511),
})


@settings(max_examples=examples(60), deadline=None)
@given(st.lists(CAT048_ROW, min_size=1, max_size=8))
def test_frame_matches_item_encoder(rows: list[dict]) -> None:
    frame = pd.DataFrame(rows)
    expected = []
    for row in rows:
        present = {k: v for k, v in row.items()
                   if v is not None and not (isinstance(v, float) and math.isnan(v))}
        expected.append(reference_record(48, "1.32", present))
    blocks: list[list[bytes]] = []  # at most 3 records a block, a new one where the data source changes
    for i, record in enumerate(expected):
        if not blocks or len(blocks[-1]) == 3 or (rows[i]["sac"], rows[i]["sic"]) != (rows[i - 1]["sac"],
                                                                                          rows[i - 1]["sic"]):
            blocks.append([])
        blocks[-1].append(record)
    assert encode_frame(48, frame, records_per_block=3) == b"".join(encode_block(48, b) for b in blocks)


# ---------------------------------------------------------------------------------------------------------
# The conformance record


def test_conformance_cat048_record() -> None:
    raw_path = CONFORMANCE / "cat048.raw"
    if not raw_path.exists():
        pytest.skip(f"{CONFORMANCE} is absent: conformance comparison not run")
    raw = raw_path.read_bytes()
    (exp,) = json.loads((CONFORMANCE / "cat048.raw.expected.json").read_text())
    values = {
        "sac": exp["I010"]["SAC"], "sic": exp["I010"]["SIC"], "time_of_day": exp["I140"]["ToD"],
        **{k.lower(): v for k, v in exp["I020"].items()},
        "rho_nm": exp["I040"]["RHO"], "theta_deg": exp["I040"]["THETA"],
        "mode3a": exp["I070"]["Mode3A"], "mode3a_v": exp["I070"]["V"], "mode3a_g": exp["I070"]["G"],
        "mode3a_l": exp["I070"]["L"],
        "flight_level": exp["I090"]["FL"], "flight_level_v": exp["I090"]["V"],
        "flight_level_g": exp["I090"]["G"],
        "address": exp["I220"]["ACAddr"], "callsign": exp["I240"]["TId"].rstrip(),
        "bds_count": len(exp["I250"]), "track_number": exp["I161"]["Tn"],
        "ground_speed_kt": exp["I200"]["CGS"], "heading_deg": exp["I200"]["CHdg"],
        **{k.lower(): v for k, v in exp["I170"].items()},
        "com": exp["I230"]["COM"], "flight_status": exp["I230"]["STAT"],
    }
    i230 = exp["I230"]
    # I048/230 fields beyond COM and STAT have no column: COM(3)=1 STAT(3)=0 SI=0 spare MSSC=1 ARC=1 AIC=1
    # B1A=1 B1B(4)=5 -> 001 000 0 0 | 1 1 1 1 0101 = 0x20 0xF5
    item230 = encode_item(48, "1.32", "230", {
        "COM": i230["COM"], "STAT": i230["STAT"], "SI": i230["SI"], "MSSC": i230["ModeSSSC"],
        "ARC": i230["ARC"], "AIC": i230["AIC"], "B1A": i230["BDS16"], "B1B": i230["BDS37"]})
    assert item230 == b"\x20\xf5"
    # I048/250 raw from the file: header 3 + FSPEC 3 + 010(2) 140(3) 020(1) 040(4) 070(2) 090(2) 220(3)
    # 240(6) = 29; then count byte + 8 bytes per register
    start = 3 + 3 + 2 + 3 + 1 + 4 + 2 + 2 + 3 + 6
    item250 = raw[start:start + 1 + 8 * len(exp["I250"])]
    assert item250[0] == 1 and item250[-1] == 0x40  # one register, BDS 4,0
    record = encode_record(48, values, "1.32", extra={"250": item250, "230": item230})
    assert encode_block(48, [record]) == raw
    frame = pd.DataFrame([values])
    # without the extras, 230 loses its unmapped fields and 250 its register content; all else identical
    rebuilt = encode_frame(48, frame)
    assert len(rebuilt) == len(raw)
    assert rebuilt[:start + 1] == raw[:start + 1] and rebuilt[start + 1:start + 9] == bytes(8)
    assert rebuilt[start + 9:-1] == raw[start + 9:-1] and rebuilt[-1:] == b"\x00"


def test_warning_codes_are_written_as_their_repetitions():
    # I048/030 (FRN 16): '1,3' -> 0000001 1, 0000011 0 = 0x03 0x06; a column read back as numbers (3.0) is
    # the one code 3 -> 0x06. FSPEC: FRN 1 and 16 -> 1000 0001, 0000 0001, 0100 0000 = 0x81 0x01 0x40
    assert encode_record(48, {"sac": 1, "sic": 2, "warning_codes": "1,3"}) == bytes([0x81, 0x01, 0x40, 1, 2,
                                                                                     0x03, 0x06])
    assert encode_record(48, {"sac": 1, "sic": 2, "warning_codes": 3.0}).endswith(bytes([0x40, 1, 2, 0x06]))
    for bad, why in (("", "not a list of codes"), ("1,,3", "not a list of codes"), ("128", "0-127"),
                     (2.5, "not a list of codes"), ("3;4", "not a list of codes")):
        with pytest.raises(ValueError, match=f"warning_codes.*{why}"):
            encode_record(48, {"sac": 1, "warning_codes": bad})
