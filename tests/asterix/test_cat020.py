"""CAT020 1.9-1.11 (multilateration, WAM): records written by hand from ../shared/specs/Cat_020_1_*.txt,
every value worked out by hand from the bytes.

UAP (all three editions): FRN 1 I020/010, 2 /020 descriptor (FX), 3 /140 time (1/128 s), 4 /041 WGS-84
(180/2^25 deg), 5 /042 Cartesian (24-bit, 0.5 m), 6 /161 track, 7 /170 status (FX) | 8 /070 Mode 3/A,
9 /202 Vx Vy (0.25 m/s), 10 /090 FL, 11 /100 Mode C, 12 /220 address, 13 /245 identification, 14 /110
height | 15 /105 geometric height (6.25 ft), 16 /210, 17 /300, 18 /310, 19 /500 accuracy (compound),
20 /400 devices, 21 /250 BDS | 22 /230, 23 /260, 24 /030 warnings (FX), 25 /055, 26 /050, 27 RE, 28 SP.

Edition differences: 1.10 adds I020/020's third octet (CF) and 1.11 puts CASEVN in two spare bits of
I020/230. Neither changes the bytes walked: an extended item is walked by its FX bits, so a 1.9 reader
steps over a third I020/020 octet as the same one octet, and I020/230 is two bytes in all three.
"""

from __future__ import annotations

import pandas as pd
import pytest
from asterix_bytes import block, decode_bytes, fspec

EDITIONS = ["1.9", "1.10", "1.11"]
TIME = bytes.fromhex("465040")  # I020/140: 0x465040 = 4608064 = 36000.5 s x 128

# WAM report. FSPEC FF ED 89 A0: FRNs 1-7 | 8 9 10 12 13 | 15 19 | 22 24.
# I020/010 SAC 25 SIC 10.
# I020/020 0xBF = 1 0 1 1 1 1 1 FX: SSR 1, MS 0, HF VDL4 UAT DME OT 1; 0x21 = 0 0 1 0 0 0 0 FX: CHN 1;
#          0x80 = 10 00000 0: CF 2 (1.10 on; a 1.9 reader walks the octet and has no CF).
# I020/041 LAT 0x00600000 = 6291456 x 180/2^25 = 33.75 deg, LON 0xFFF80000 = -2^19 x 180/2^25 = -2.8125 deg.
# I020/042 X 0xFFF82F = 16775215 - 2^24 = -2001 x 0.5 = -1000.5 m, Y 0x006072 = 24690 x 0.5 = 12345 m.
# I020/161 0x0FFF = 4095. I020/170 0x32 = 0 0 1 10 0 1 0: CST 1, CDM 2, STH 1, no GHO octet.
# I020/070 0x8F40: V 1, code 7500 octal (3904 = 0xF40). I020/202 VX 0xFFFF = -0.25, VY 0x0190 = 400 x 0.25.
# I020/090 0x4578: G 1, FL 0x578 = 1400 / 4 = 350. I020/220 0x4CA1B2.
# I020/245 0x80: STI 2; "RYR1AB  ": R 18 Y 25 R 18 '1' 49 A 1 B 2 ' ' 32 ' ' 32 =
#          010010 011001 010010 110001 000001 000010 100000 100000 = 49 94 B1 04 28 20.
# I020/105 0x0640 = 1600 x 6.25 = 10000 ft.
# I020/500 primary 0x60: SDP (bit 2), SDH (bit 3). SDP X 0x0014 = 5 m, Y 0x0028 = 10 m, XY 0x0004 = 1;
#          SDH 0x0010 = 16 x 0.5 = 8 m.
# I020/230 0x24A5 = 001 001 00 1 0 1 0 0101: COM 1, STAT 1, (spare / 1.11 CASEVN 0), MSSC 1, ARC 0, AIC 1.
# I020/030 0x03 0x20: code 1 (FX), code 16 (end).
WAM = (bytes.fromhex("FFED89A0") + bytes([25, 10]) + bytes.fromhex("BF2180") + TIME
       + bytes.fromhex("00600000FFF80000") + bytes.fromhex("FFF82F006072") + bytes.fromhex("0FFF") + b"\x32"
       + bytes.fromhex("8F40") + bytes.fromhex("FFFF0190") + bytes.fromhex("4578") + bytes.fromhex("4CA1B2")
       + bytes.fromhex("804994B1042820") + bytes.fromhex("0640")
       + bytes.fromhex("60" "001400280004" "0010") + bytes.fromhex("24A5") + bytes.fromhex("0320"))

# A surface report: two-octet I020/020 (GBS, RAB), DOP subfield, 1.11's CASEVN bits set in I020/230.
# FSPEC E1 01 09 80: FRNs 1 2 3 | | 19 | 22.
# I020/020 0x7F = 0 1 1 1 1 1 1 FX: SSR 0 (non-Mode S multilateration), MS..OT 1;
#          0x92 = 1 0 0 1 0 0 1 0: RAB 1, GBS 1, TST 1, end.
# I020/500 primary 0x80: DOP. X 0x0006 = 1.5, Y 0x0008 = 2, XY 0x0001 = 0.25.
# I020/230 0x4AC0 = 010 010 10 1 1 0 0 0000: COM 2, STAT 2, CASEVN 2 (1.11; spare before), MSSC 1, ARC 1.
SURFACE = (bytes.fromhex("E1010980") + bytes([25, 11]) + bytes.fromhex("7F92") + TIME
           + bytes.fromhex("80" "000600080001") + bytes.fromhex("4AC0"))


def decode20(*records: bytes, edition: str | None = None) -> pd.DataFrame:
    rec = decode_bytes(b"".join(block(20, r) for r in records),
                       editions={20: edition} if edition else None)
    assert rec.errors.empty, rec.errors.to_dict("records")
    assert rec.decoded_bytes == sum(len(r) + 3 for r in records)
    return rec.frames[20]


def test_fspecs_worked_by_hand() -> None:
    assert fspec(1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 12, 13, 15, 19, 22, 24) == bytes.fromhex("FFED89A0")
    assert fspec(1, 2, 3, 19, 22) == bytes.fromhex("E1010980")


@pytest.mark.parametrize("edition", EDITIONS)
def test_wam_report(edition: str) -> None:
    r = decode20(WAM, edition=edition).iloc[0]
    assert (r.sac, r.sic, r.time_of_day) == (25, 10, 36000.5)
    assert pd.isna(r.message_type)  # CAT020 has no message type item
    assert (r.tech_ssr, r.tech_ms, r.tech_hf, r.tech_vdl4, r.tech_uat, r.tech_dme, r.tech_ot) == (
        1, 0, 1, 1, 1, 1, 1)
    assert (r.rab, r.spi, r.chn, r.gbs, r.crt, r.sim, r.tst) == (0, 0, 1, 0, 0, 0, 0)
    assert (r.latitude, r.longitude) == (33.75, -2.8125)
    assert (r.x_m, r.y_m) == (-1000.5, 12345.0)
    assert r.track_number == 4095
    assert (r.cnf, r.tre, r.cst, r.cdm, r.mah, r.sth) == (0, 0, 1, 2, 0, 1) and pd.isna(r.gho)
    assert r.mode3a == "7500" and (r.mode3a_v, r.mode3a_g, r.mode3a_l) == (1, 0, 0)
    assert (r.vx_ms, r.vy_ms) == (-0.25, 100.0)
    assert r.flight_level == 350.0 and (r.flight_level_v, r.flight_level_g) == (0, 1)
    assert r.address == "4CA1B2" and r.callsign == "RYR1AB" and r.sti == 2
    assert r.geometric_height_ft == 10000.0
    assert (r.sigma_x_m, r.sigma_y_m, r.sdp_xy, r.sigma_height_m) == (5.0, 10.0, 1.0, 8.0)
    assert pd.isna(r.dop_x)
    assert (r.com, r.flight_status) == (1, 1)
    assert r.warning_codes == "1,16"


@pytest.mark.parametrize(("edition", "cf"), [("1.9", None), ("1.10", 2), ("1.11", 2)])
def test_third_descriptor_octet_walked_in_every_edition_read_from_1_10(edition: str, cf) -> None:
    """The same bytes walk alike (decode20 checks every byte is decoded and the next items land where the
    hand-worked values say); only 1.10 and 1.11 give the third octet a meaning."""
    f = decode20(WAM, SURFACE, edition=edition)
    assert f.offset.tolist() == [3, 3 + len(WAM) + 3]
    got = f.cf.iloc[0]
    assert pd.isna(got) if cf is None else got == cf
    assert pd.isna(f.cf.iloc[1])  # two-octet descriptor
    assert f.time_of_day.tolist() == [36000.5, 36000.5]


@pytest.mark.parametrize("edition", EDITIONS)
def test_surface_report_and_casevn_bits(edition: str) -> None:
    r = decode20(SURFACE, edition=edition).iloc[0]
    assert (r.tech_ssr, r.tech_ms) == (0, 1)
    assert (r.rab, r.gbs, r.tst, r.spi) == (1, 1, 1, 0)
    assert (r.dop_x, r.dop_y, r.dop_xy) == (1.5, 2.0, 0.25)
    assert pd.isna(r.sigma_x_m) and pd.isna(r.sigma_height_m)
    # the CASEVN bits (1.11) or spare bits (1.9, 1.10) change neither COM nor STAT
    assert (r.com, r.flight_status) == (2, 2)


def test_default_edition_is_1_11_and_auto_picks_it_when_all_walk() -> None:
    data = block(20, WAM)
    assert decode_bytes(data).editions == {20: "1.11"}
    rec = decode_bytes(data, editions={20: "auto"})
    assert rec.editions == {20: "1.11"} and "1.9" in rec.edition_choice[20]


def test_short_records_are_walked_once(monkeypatch) -> None:
    """The record arrays are sized from a sample of the blocks: 600 records of 9 bytes (FSPEC E4,
    I020/010, one-octet I020/020, I020/140, I020/161) fit the first guess, so the full walk runs once (a
    guess of one record per 40 bytes ran it twice); the sample's own walk is the other call."""
    from msdc.asterix import reader

    calls: list[int] = []
    scan = reader.kernel.scan

    def counting(*args):
        out = scan(*args)
        calls.append(out[2])
        return out

    monkeypatch.setattr(reader.kernel, "scan", counting)
    records = [bytes([0xE4, 25, 10, 0x40]) + (128 * i).to_bytes(3, "big") + i.to_bytes(2, "big")
               for i in range(600)]
    f = decode20(*[b"".join(records[j:j + 20]) for j in range(0, 600, 20)])
    assert f.track_number.tolist() == list(range(600))
    assert len(calls) == 2 and calls[-1] == 600  # the sample, then one full walk that fit
