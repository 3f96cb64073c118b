"""CAT062 system tracks: records written by hand from the 1.16-1.21 layouts, values worked by hand.

UAP (every edition 1.16-1.21): FRN 1 I062/010, 3 /015, 4 /070 ToD (1/128 s), 5 /105 WGS-84 (180/2^25 deg),
6 /100 X Y (0.5 m), 7 /185 VX VY (0.25 m/s), 8 /210, 9 /060 Mode 3/A, 10 /245 identification, 11 /380
aircraft-derived data (compound, 28 subfields), 12 /040 track number, 13 /080 track status (extended),
14 /290 update ages (compound), 15 /200 mode of movement, 16 /295 data ages (compound), 17 /136 measured FL,
18 /130 geometric altitude, 19 /135 barometric altitude, 20 /220 ROCD, 21 /390 flight plan (compound),
22 /270, 23 /300, 24 /110, 25 /120, 26 /510 composed track number (FX-repetitive, 3 bytes),
27 /500 accuracies (compound), 28 /340 measured information (compound), 34 RE, 35 SP (explicit).
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from asterix_bytes import block, decode_bytes, fspec

from msdc.asterix.encode import encode_record
from msdc.asterix.layout import compile_layout

EDITIONS = ["1.16", "1.17", "1.18", "1.19", "1.20", "1.21"]

# Items of the full record, worked by hand (edition 1.21):
ITEMS = [
    (1, "1964"),  # I062/010 SAC 25 SIC 100
    (3, "05"),  # I062/015 service 5
    (4, "070840"),  # I062/070 3600.5 s * 128 = 460864 = 0x070840
    # I062/105 LAT 45 deg = 45 * 2^25 / 180 = 2^23 = 0x00800000; LON -90 deg = -2^24 = 0xFF000000
    (5, "00800000" "FF000000"),
    (6, "0007D1" "FFFFD8"),  # I062/100 X 1000.5 m / 0.5 = 2001 = 0x7D1; Y -20 m / 0.5 = -40 = 0xFFFFD8
    (7, "0191" "FFF4"),  # I062/185 VX 100.25 / 0.25 = 401 = 0x191; VY -3 / 0.25 = -12 = 0xFFF4
    # I062/060 V 1, G 0, CH 1, spare, 7700 octal = 0xFC0: 1010 1111 1100 0000 = 0xAFC0
    (9, "AFC0"),
    # I062/245 STI 0, spare 6, "DLH65A  ": D 4, L 12, H 8, 6 54, 5 53, A 1, space 32, 32
    #   000100 001100 001000 110110 | 110101 000001 100000 100000 = 10 C2 36 | D4 18 20
    (10, "00" "10C236D41820"),
    # I062/380 FSPEC: subfields 1 ADR, 3 MHG, 6 SAL (0xA4 | FX = 0xA5); 9 TID (0x40 | FX = 0x41);
    #   none in 15-21 (0x01); 27 MAC (0x04, last)
    #   ADR 3C660C; MHG 90 deg = 16384 * 360/2^16 -> 0x4000;
    #   SAL SAS 1, SRC 2, ALT 35000 ft / 25 = 1400 = 0b0010101111000 -> 1 10 0010101111000 = 0xC578
    #   TID count 1, one 15-byte repetition (0xAA...); MAC 0.8 / 0.008 = 100 = 0x0064
    (11, "A5410104" "3C660C" "4000" "C578" "01" + "AA" * 15 + "0064"),
    (12, "04D2"),  # I062/040 track 1234 = 0x04D2
    # I062/080: MON 1 SPI 0 MRH 0 SRC 2 CNF 1 FX -> 1 0 0 010 1 1 = 0x8B
    #   SIM 0 TSE 0 TSB 1 FPC 1 AFF 0 STP 0 KOS 0 FX -> 0x31; AMA MD4 ME MI MD5 0, FX -> 0x01
    #   CST 1 PSR 1 SSR MDS ADS SUC AAC 0, FX -> 0xC1; SDS 1 EMS 0 PFT 0 FPLT 0, FX -> 01 000 0 0 1 = 0x41
    #   DUPT DUPF DUPM 0, SFC 1, IDD IEC 0, MLAT 1, FX -> 0001 0011 = 0x13; M5I 1, spare, no FX -> 0x80
    (13, "8B3101C1411380"),
    # I062/290 FSPEC 0x8C (1 TRK, 5 ADS, 6 ES): TRK 1.25 s / 0.25 = 5; ADS (16 bits) 300 s -> 1200 = 0x04B0;
    #   ES 0.5 s -> 2
    (14, "8C" "05" "04B0" "02"),
    (15, "66"),  # I062/200 TRANS 1, LONG 2, VERT 1, ADF 1, spare: 01 10 01 1 0 = 0x66
    (16, "80" "08"),  # I062/295 FSPEC 0x80 (1 MFL), MFL 2 s / 0.25 = 8
    (17, "0579"),  # I062/136 350.25 FL * 4 = 1401 = 0x0579
    (18, "15E0"),  # I062/130 35000 ft / 6.25 = 5600 = 0x15E0
    (19, "FFF6"),  # I062/135 QNH 1, CTB -2.5 FL * 4 = -10 -> 15 bits 0x7FF6 | 0x8000 = 0xFFF6
    (20, "FF10"),  # I062/220 -1500 ft/min / 6.25 = -240 = 0xFF10
    # I062/390 FSPEC: 1 TAG, 2 CS (0xC0 | FX = 0xC1); 10 CFL, 12 TOD (0x20 | 0x08 | FX = 0x29); 18 PEC (0x10)
    #   TAG 07 08; CS "DLH65A " ASCII; CFL 310 FL * 4 = 1240 = 0x04D8; TOD count 2 of 4 bytes; PEC "ABC    "
    (21, "C12910" "0708" "444C4836354120" "04D8" "02" "0000000011111111" "41424320202020"),
    # I062/510: IDENT 9, TRACK 4321 = 0b001000011100001, FX 1 -> 00001001 00100001 11000011 = 09 21 C3;
    #   IDENT 10, TRACK 5, FX 0 -> 0A 00 0A
    (26, "0921C3" "0A000A"),
    # I062/500 FSPEC 1 APC, 2 COV (0xC0 | FX = 0xC1), 8 ARC (0x80): APC X 10 m / 0.5 = 20, Y 12.5 m -> 25;
    #   COV -3 m / 0.5 = -6 = 0xFFFA; ARC 125 ft/min / 6.25 = 20 = 0x14
    (27, "C180" "0014" "0019" "FFFA" "14"),
    # I062/340 FSPEC 1 SID, 2 POS, 6 TYP (0x80 | 0x40 | 0x04 = 0xC4): SID 25 201; RHO 100 NM * 256 = 0x6400,
    #   THETA 180 deg = 2^15 = 0x8000; TYP 5, SIM RAB TST 0: 101 0 0 0 00 = 0xA0
    (28, "C4" "19C9" "6400" "8000" "A0"),
    (34, "03ABCD"),  # RE: length 3 (counting itself), two bytes
    (35, "02EE"),  # SP: length 2
]
FULL = fspec(*(frn for frn, _ in ITEMS)) + b"".join(bytes.fromhex(h) for _, h in ITEMS)
# A short record after it (I062/010, I062/040 track 7): read right only if the full one was walked exactly
SHORT = fspec(1, 12) + bytes.fromhex("1964" "0007")

EXPECTED = {
    "sac": 25, "sic": 100, "service_id": 5, "time_of_day": 3600.5, "latitude": 45.0, "longitude": -90.0,
    "x_m": 1000.5, "y_m": -20.0, "vx_ms": 100.25, "vy_ms": -3.0, "mode3a": "7700", "mode3a_changed": 1,
    "callsign": "DLH65A", "callsign_source": 0, "address": "3C660C", "magnetic_heading_deg": 90.0,
    "selected_altitude_ft": 35000.0, "selected_altitude_sas": 1, "selected_altitude_source": 2,
    "mach": 0.8, "track_number": 1234, "mon": 1, "spi": 0, "mrh": 0, "altitude_source": 2, "cnf": 1,
    "sim": 0, "tsb": 1, "fpc": 1, "cst": 1, "cst_psr": 1, "cst_ssr": 0, "sds": 1, "ems": 0,
    "track_age_s": 1.25, "adsc_age_s": 300.0, "adsb_age_s": 0.5, "movement_transversal": 1,
    "movement_longitudinal": 2, "movement_vertical": 1, "altitude_discrepancy": 1, "flight_level_age_s": 2.0,
    "flight_level": 350.25, "geometric_altitude_ft": 35000.0, "barometric_altitude_fl": -2.5,
    "barometric_altitude_qnh": 1, "vertical_rate_ftmin": -1500.0, "fpps_sac": 7, "fpps_sic": 8,
    "cleared_flight_level": 310.0, "accuracy_x_m": 10.0, "accuracy_y_m": 12.5, "accuracy_xy_cov_m": -3.0,
    "accuracy_vertical_rate_ftmin": 125.0, "measured_sac": 25, "measured_sic": 201, "measured_rho_nm": 100.0,
    "measured_theta_deg": 180.0, "measured_report_type": 5,
}
# Fields later editions define in bits earlier ones leave spare: (column, value here, first edition)
LATER = [("mode3a_v", 1, "1.17"), ("mode3a_g", 0, "1.17"), ("sfc", 1, "1.18"), ("idd", 0, "1.18"),
         ("iec", 0, "1.18"), ("cst_mlat", 1, "1.20"), ("cst_m5", 1, "1.21")]
ABSENT = ["psr_age_s", "ssr_age_s", "true_airspeed_kt", "indicated_airspeed_kt", "mode2", "ax_ms2",
          "target_length_m", "accuracy_latitude_deg"]


def decode62(*records: bytes, **kw) -> pd.DataFrame:
    data = b"".join(block(62, r) for r in records)
    rec = decode_bytes(data, categories=[62], **kw)
    assert rec.errors.empty, rec.errors.to_dict("records")
    assert rec.decoded_bytes == len(data)
    return rec.frames[62]


def _version(edition: str) -> tuple[int, ...]:
    return tuple(int(x) for x in edition.split("."))


def test_fspec_worked_by_hand() -> None:
    # FRNs 1,3-7 -> 0xBE|FX; 9-14 -> 0x7E|FX; 15-21 -> 0xFE|FX; 26,27,28 -> 0x0E|FX; 34,35 -> 0x06
    assert FULL[:5] == bytes.fromhex("BF7FFF0F06")


@pytest.mark.parametrize("edition", EDITIONS)
def test_full_record_values(edition: str) -> None:
    f = decode62(FULL + SHORT, editions={62: edition})
    assert len(f) == 2
    row = f.iloc[0]
    for name, want in EXPECTED.items():
        assert row[name] == pytest.approx(want) if isinstance(want, float) else row[name] == want, name
    for name, want, since in LATER:
        if _version(edition) >= _version(since):
            assert row[name] == want, name
        else:  # a spare bit (or an octet group the edition does not define) there: absent, not 0
            assert pd.isna(row[name]), name
    for name in ABSENT:
        assert pd.isna(row[name]), name
    # the short record after the full one: walked from the right byte
    assert f.track_number.tolist() == [1234, 7] and f.offset.tolist() == [3, 3 + len(FULL)]
    assert pd.isna(f.latitude.iloc[1]) and pd.isna(f.callsign.iloc[1])


def test_callsign_from_380_when_245_is_absent() -> None:
    # I062/380 FSPEC 0x40 (2 ID): "KLM1605 ": K 11, L 12, M 13, 1 49, 6 54, 0 48, 5 53, space 32
    #   001011 001100 001101 110001 | 110110 110000 110101 100000 = 2C C3 71 | DB 0D 60
    rec = fspec(1, 11) + bytes.fromhex("1964" "40" "2CC371DB0D60")
    f = decode62(rec)
    assert f.callsign.iloc[0] == "KLM1605" and f.callsign_hex.iloc[0] == "2CC371DB0D60"


def test_every_edition_walks_the_same_bytes() -> None:
    # The printed 1.16-1.21 layouts differ only inside fixed-size parts (I062/060 V/G, I062/080 bits) and
    # by I062/080's seventh octet group (M5I, 1.21), one byte ending with FX like the six before it: every
    # part has the same kind and size, and every extended part octet groups of one byte with FX or the same
    # groups, so a record walks the same bytes under each (test_full_record_values walks one that way)
    def groups(lay, part: int) -> list[tuple[int, int]]:
        lo = lay.ext_start[part]
        return list(zip(lay.ext_sizes[lo:lo + lay.ext_count[part]].tolist(),
                        lay.ext_fx[lo:lo + lay.ext_count[part]].tolist(), strict=True))

    first = compile_layout(62, EDITIONS[0])
    status = first.item_frn["080"] - 1
    for edition in EDITIONS:
        lay = compile_layout(62, edition)
        for attr in ("kind", "size", "sub_start", "sub_count", "sub_parts"):
            assert np.array_equal(getattr(lay, attr), getattr(first, attr)), (edition, attr)
        for part in range(len(lay.kind)):
            if part != status:
                assert groups(lay, part) == groups(first, part), (edition, part)
        assert groups(lay, status) == [(1, 1)] * (7 if edition == "1.21" else 6)


def test_repetitive_and_explicit_lengths_are_walked() -> None:
    # I062/380 BDS (subfield 25) count 2 of 8 bytes; I062/390 TOD count 0; I062/510 three entries; RE 1 byte
    # (its own length only). FSPEC of I062/380: subfield 25 -> octet 4 bit 0x10, octets 1-3 FX only
    rec = (fspec(1, 11, 12, 21, 26, 34) + bytes.fromhex("1964") + bytes.fromhex("01010110")
           + bytes.fromhex("02") + bytes(range(16)) + bytes.fromhex("0009")
           + bytes.fromhex("0108") + b"\x00" + bytes.fromhex("000001" "000003" "000004") + b"\x01")
    f = decode62(rec + SHORT)
    assert f.track_number.tolist() == [9, 7]


def test_encoder_writes_hand_bytes() -> None:
    # the items the columns carry, in the order of the hand record (no I062/380 TID, /390 TOD, PEC, /510,
    # RE, SP: written by hand, passed whole)
    values = {k: v for k, v in EXPECTED.items()}
    values |= {"mode3a_v": 1, "mode3a_g": 0, "sfc": 1, "idd": 0, "iec": 0, "cst_mlat": 1, "cst_m5": 1,
               "tse": 0, "aff": 0, "stp": 0, "kos": 0, "ama": 0, "md4": 0, "me": 0, "mi": 0, "md5": 0,
               "cst_mds": 0, "cst_ads": 0, "suc": 0, "aac": 0, "pft": 0, "fplt": 0, "dupt": 0, "dupf": 0,
               "dupm": 0}
    hand = dict(ITEMS)
    extra = {"380": bytes.fromhex(hand[11]), "390": bytes.fromhex(hand[21]), "510": bytes.fromhex(hand[26]),
             "RE": bytes.fromhex(hand[34]), "SP": bytes.fromhex(hand[35])}
    values = {k: v for k, v in values.items() if k not in {"address", "magnetic_heading_deg", "mach",
              "selected_altitude_ft", "selected_altitude_sas", "selected_altitude_source", "fpps_sac",
              "fpps_sic", "cleared_flight_level"}}
    assert encode_record(62, values, edition="1.21", extra=extra) == FULL


def test_not_decoded_unless_asked() -> None:
    rec = decode_bytes(block(62, FULL, SHORT))
    assert 62 not in rec.frames and rec.ignored_blocks == {62: 1}
    assert rec.ignored_bytes == 3 + len(FULL) + len(SHORT)


def test_auto_edition_reads_the_newest() -> None:
    rec = decode_bytes(block(62, FULL), categories=[62], editions={62: "auto"})
    assert rec.editions == {62: "1.21"} and rec.frames[62].cst_m5.iloc[0] == 1
