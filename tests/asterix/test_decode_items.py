"""Per-item decoding from hand-built bytes, with expected values worked out from the spec."""

from __future__ import annotations

import math

import pandas as pd
import pytest
from asterix_bytes import block, decode_bytes, fspec

# I048/010 SAC=25 SIC=201; I048/140 ToD 0x355d80 = 3497344 / 128 = 27323.0 s
I010 = bytes([25, 201])
I140 = bytes([0x35, 0x5D, 0x80])
TOD = 3497344 / 128


def cat048(*items: tuple[int, bytes]) -> bytes:
    """One CAT048 record from (FRN, item bytes) pairs, FRN-ordered."""
    items = tuple(sorted(items))
    return fspec(*(f for f, _ in items)) + b"".join(b for _, b in items)


def one048(*items: tuple[int, bytes], **kw) -> pd.Series:
    rec = decode_bytes(block(48, cat048((1, I010), (2, I140), *items)), **kw)
    assert rec.errors.empty, rec.errors
    return rec.frames[48].iloc[0]


def test_sac_sic_time_of_day():
    r = one048()
    assert (r.sac, r.sic) == (25, 201)
    assert r.time_of_day == TOD == 27323.0


@pytest.mark.parametrize("edition", ["1.21", "1.27", "1.31", "1.32"])
def test_flight_level_is_14_bit_twos_complement(edition):
    # I048/090 (FRN 6): V=0 G=0, FL field 0x2000 -> -8192 quarter-FL -> FL -2048 (every edition)
    assert one048((6, bytes([0x20, 0x00])), editions={48: edition}).flight_level == -2048
    # 0x3FFC -> -4 quarter-FL -> FL -1
    assert one048((6, bytes([0x3F, 0xFC])), editions={48: edition}).flight_level == -1
    # 0x0528 -> 1320 * 0.25 = FL 330; V bit set (0x8000) flags "not validated"
    r = one048((6, bytes([0x85, 0x28])))
    assert r.flight_level == 330 and r.flight_level_v == 1 and r.flight_level_g == 0


def test_polar_position_lsbs():
    # I048/040 (FRN 4): RHO 0xC5AF = 50607 / 256 NM; THETA 0xF1E0 = 61920 * 360 / 65536 deg
    r = one048((4, bytes([0xC5, 0xAF, 0xF1, 0xE0])))
    assert r.rho_nm == 50607 / 256 == 197.68359375
    assert r.theta_deg == 61920 * 360 / 65536 == 340.13671875


def test_icao_six_bit_callsign():
    # "DLH65A  ": D=4 L=12 H=8 '6'=54 '5'=53 A=1 ' '=32 ' '=32 as 6-bit codes:
    # 000100 001100 001000 110110 110101 000001 100000 100000 = 10 C2 36 D4 18 20
    r = one048((9, bytes.fromhex("10C236D41820")))
    assert r.callsign == "DLH65A"


def test_octal_mode3a_and_hex_address():
    # Mode 3/A 7106 octal = 7*512 + 1*64 + 0*8 + 6 = 3654 = 0x0E46; I048/220 3C660C
    r = one048((5, bytes([0x0E, 0x46])), (8, bytes.fromhex("3C660C")))
    assert r.mode3a == "7106"
    assert r.address == "3C660C"
    # leading zeros are kept: code 0021 octal = 17 = 0x011
    assert one048((5, bytes([0x00, 0x11]))).mode3a == "0021"


def test_multi_octet_extended_item_020():
    # I048/020 (FRN 3) in 1.32: octet 1 TYP=5 (101) SIM=0 RDP=0 SPI=1 RAB=0 FX=1 -> 1010 0101 = 0xA5
    # octet 2: TST=1 ERR=0 XPP=0 ME=1 MI=0 FOEFRI=2 (10) FX=1 -> 1001 0101 = 0x95
    # octet 3: ADSB EP=1 VAL=1, SCN 00, PAI 00, spare, FX=0 -> 1100 0000 = 0xC0
    r = one048((3, bytes([0xA5, 0x95, 0xC0])))
    assert (r.typ, r.sim, r.rdp, r.spi, r.rab) == (5, 0, 0, 1, 0)
    assert (r.tst, r.err, r.xpp, r.me, r.mi, r.foe_fri) == (1, 0, 0, 1, 0, 2)


def test_extension_fields_absent_when_octet_absent():
    # One octet only: TST etc. are absent (<NA>), not 0
    r = one048((3, bytes([0xA0])))
    assert r.typ == 5 and pd.isna(r.tst) and pd.isna(r.foe_fri)


def test_track_status_and_velocity():
    # I048/200 (FRN 13): GSP 0x0789 = 1929 * 2^-14 NM/s * 3600 = 423.852... kt; HDG 0x4000 = 90 deg
    # I048/170 (FRN 14): CNF=0 RAD=2 (10) DOU=0 MAH=1 CDM=1 (01) FX=0 -> 0100 1010 = 0x4A
    r = one048((13, bytes([0x07, 0x89, 0x40, 0x00])), (14, bytes([0x4A])))
    assert r.ground_speed_kt == pytest.approx(1929 / 16384 * 3600)
    assert r.heading_deg == 90.0
    assert (r.cnf, r.rad, r.dou, r.mah, r.cdm) == (0, 2, 0, 1, 1)
    assert pd.isna(r.tre)


def test_cartesian_position_signed():
    # I048/042 (FRN 12): X 0xFF00 = -256 / 128 NM = -2.0; Y 0x0280 = 640 / 128 = 5.0
    r = one048((12, bytes([0xFF, 0x00, 0x02, 0x80])))
    assert (r.x_nm, r.y_nm) == (-2.0, 5.0)


def test_repetitive_250_then_following_item():
    # I048/250 (FRN 10): REP=2, two 8-byte registers; I048/161 (FRN 11) must still line up after it
    bds = bytes([2]) + bytes(range(1, 9)) + bytes(range(11, 19))
    r = one048((10, bds), (11, bytes([0x0D, 0xEB])))
    assert r.bds_count == 2
    assert r.track_number == 0xDEB == 3563


def test_compound_130_with_two_subfields():
    # I048/130 (FRN 7) primary subfield octet: SRL (bit 8) and SAM (bit 6) -> 1010 0000 = 0xA0
    # SRL 0x10 = 16 * 0.0439453125 deg = 0.703125; SAM 0xFB = -5 dBm (signed)
    # followed by I048/220 (FRN 8) to prove the walk length
    r = one048((7, bytes([0xA0, 0x10, 0xFB])), (8, bytes.fromhex("ABCDEF")))
    assert r.ssr_runlength_deg == 16 * 0.0439453125
    assert r.ssr_amplitude_dbm == -5.0
    assert pd.isna(r.ssr_replies) and math.isnan(r.psr_runlength_deg)
    assert r.address == "ABCDEF"


def test_compound_120_with_repetitive_subfield():
    # I048/120 (FRN 20): CAL (subfield 1) and RDS (subfield 2) -> 1100 0000 = 0xC0
    # CAL: D=0, spare, CAL 10-bit 0x3F6 = -10 m/s -> 0x03 0xF6; RDS: REP=1, 6 bytes
    # then I048/230 (FRN 21) COM=1 -> 0x20 0x00
    item120 = bytes([0xC0, 0x03, 0xF6, 1, 0, 5, 0, 9, 0x0B, 0xB8])
    r = one048((20, item120), (21, bytes([0x20, 0x00])))
    assert r.doppler_speed_ms == -10.0
    assert r.com == 1


def test_special_purpose_and_reserved_expansion_are_stepped_over():
    # FRN 27 SP and FRN 28 RE: length byte counts itself; content is arbitrary
    sp = bytes([4, 0xFF, 0xFF, 0xFF])
    re_ = bytes([3, 0x80, 0x01])
    rec = decode_bytes(block(48, cat048((1, I010), (2, I140), (27, sp), (28, re_)),
                             cat048((1, bytes([1, 2])), (2, I140))))
    assert rec.errors.empty
    f = rec.frames[48]
    assert list(f.sac) == [25, 1] and list(f.sic) == [201, 2]


def test_absent_items_are_missing_not_zero():
    r = one048()
    assert math.isnan(r.rho_nm) and math.isnan(r.flight_level)
    assert pd.isna(r.callsign) and pd.isna(r.address) and pd.isna(r.track_number)


# --- CAT021: one byte stream, three edition families ---------------------------------------------
# FRN 1 I021/010, then I021/130. In 0.2x I021/130 is FRN 4, in 2.x FRN 6.

def test_021_position_0_23_six_bytes():
    # 0.23: I021/130 is 2 x 24 bits at 180/2^23 deg. lat 0x200000 = 2^21 -> 45 deg; lon 0xE00000 -> -45
    rec = decode_bytes(block(21, fspec(1, 3, 4) + bytes([0, 1]) + bytes([0, 0, 128]) +
                             bytes.fromhex("200000E00000")), editions={21: "0.23"})
    r = rec.frames[21].iloc[0]
    assert (r.latitude, r.longitude) == (45.0, -45.0)
    assert r.time_of_day == 1.0  # I021/030 0x000080 = 128/128 s


def test_021_position_0_24_eight_bytes():
    # 0.24-0.26: I021/130 is 2 x 32 bits at 180/2^25 deg. lat 0x00800000 = 2^23 -> 45 deg
    body = fspec(1, 4) + bytes([0, 1]) + bytes.fromhex("00800000FF800000")
    for ed in ("0.24", "0.25", "0.26"):
        r = decode_bytes(block(21, body), editions={21: ed}).frames[21].iloc[0]
        assert (r.latitude, r.longitude) == (45.0, -45.0), ed
    # the same bytes under 2.x do not walk (FRN 4 is I021/015, 1 byte; leftovers break the block)
    assert not decode_bytes(block(21, body), editions={21: "2.7"}).errors.empty


def test_021_2x_high_resolution_position_preferred():
    # 2.x: I021/130 (FRN 6) 6 bytes at 180/2^23 and I021/131 (FRN 7) 8 bytes at 180/2^30.
    # 131: lat 2^28 * 180/2^30 = 45.0; 130 carries 10 deg (0x071C72 ~ 466034 * 180/2^23 = 10.0000)
    i130 = (466034).to_bytes(3, "big") * 2
    i131 = (2**28).to_bytes(4, "big") + (-(2**28) & 0xFFFFFFFF).to_bytes(4, "big")
    r = decode_bytes(block(21, fspec(1, 6, 7) + bytes([0, 1]) + i130 + i131)).frames[21].iloc[0]
    assert (r.latitude, r.longitude) == (45.0, -45.0)
    r = decode_bytes(block(21, fspec(1, 6) + bytes([0, 1]) + i130)).frames[21].iloc[0]
    assert r.latitude == pytest.approx(466034 * 180 / 2**23)


def test_021_0_26_signal_amplitude_is_not_a_position():
    # 0.26 FRN 28 is I021/131 signal amplitude, one byte
    body = fspec(1, 28) + bytes([0, 1]) + bytes([77])
    r = decode_bytes(block(21, body), editions={21: "0.26"}).frames[21].iloc[0]
    assert r.signal_amplitude == 77 and math.isnan(r.latitude)


def test_021_quality_indicators_2x_and_figure_of_merit_0x():
    # 2.x I021/090 (FRN 17): NUCr/NACv=2 (010) NUCp/NIC=7 (0111) FX=1 -> 0100 1111 = 0x4F;
    # NICbaro=1 SIL=3 (11) NACp=9 (1001) FX=0 -> 1111 0010 = 0xF2
    r = decode_bytes(block(21, fspec(1, 17) + bytes([0, 1, 0x4F, 0xF2]))).frames[21].iloc[0]
    assert (r.nucr_nacv, r.nucp_nic, r.nic_baro, r.sil, r.nacp) == (2, 7, 1, 3, 9)
    # 0.23 I021/090 (FRN 7): AC=1 MN=2 DC=3 -> 0110 1100, spare 6 bits + PA=5 (0101) -> 0000 0101
    r = decode_bytes(block(21, fspec(1, 7) + bytes([0, 1, 0x6C, 0x05])),
                     editions={21: "0.23"}).frames[21].iloc[0]
    assert (r.fom_ac, r.fom_mn, r.fom_dc, r.fom_pa) == (1, 2, 3, 5)


def test_021_time_items_each_in_own_column():
    # 2.x: 071 (FRN 5) = 256/128 = 2 s; 073 (FRN 12) = 384/128 = 3 s; time_of_day prefers 071
    body = fspec(1, 5, 12) + bytes([0, 1]) + (256).to_bytes(3, "big") + (384).to_bytes(3, "big")
    r = decode_bytes(block(21, body)).frames[21].iloc[0]
    assert (r.time_applicability_position, r.time_reception_position, r.time_of_day) == (2.0, 3.0, 2.0)
    body = fspec(1, 12) + bytes([0, 1]) + (384).to_bytes(3, "big")
    assert decode_bytes(block(21, body)).frames[21].iloc[0].time_of_day == 3.0


def test_021_ground_vector_and_ages_compound():
    # I021/160 (FRN 26): RE=0 GS 0x0800 = 2048 * 2^-14 NM/s = 0.125 NM/s = 450 kt; TA 0x2000 = 45 deg
    # I021/295 (FRN 42) compound: AOS (sub 1) only -> 0x80, then 1 byte; stepped over exactly
    body = (fspec(1, 26, 42) + bytes([0, 1]) + bytes([0x08, 0x00, 0x20, 0x00]) + bytes([0x80, 7]))
    rec = decode_bytes(block(21, body))
    assert rec.errors.empty
    r = rec.frames[21].iloc[0]
    assert r.ground_speed_kt == 450.0 and r.track_angle_deg == 45.0


def test_021_auto_edition_picks_the_family_that_walks():
    # 0.24-style records (I021/130 of 8 bytes at FRN 4, time at FRN 3) walk only under 0.2x
    recs = [fspec(1, 3, 4) + bytes([0, 1]) + (128 * i).to_bytes(3, "big") + bytes.fromhex("00800000FF800000")
            for i in range(1, 6)]
    rec = decode_bytes(block(21, *recs), editions={21: "auto"})
    assert rec.editions[21].startswith("0.2") and rec.errors.empty
    assert "0.2" in rec.edition_choice[21]
    assert list(rec.frames[21].latitude) == [45.0] * 5


def test_column_docs_are_current():
    from pathlib import Path

    from msdc.asterix.columns import markdown_schema

    doc = Path(__file__).resolve().parents[2] / "docs" / "columns.md"
    assert doc.read_text().strip() == markdown_schema().strip(), "regenerate docs/columns.md"


# --- identification text: code 0 is no character ---------------------------------------------------

@pytest.mark.parametrize(("hex6", "text", "raw"), [
    ("000000000000", None, "000000000000"),  # eight code-0 characters: absent, not '????????'
    ("820820820820", None, "820820820820"),  # eight spaces (100000 x 8): absent
    # "AB" then code 0 then "C" + 4 spaces: A=000001 B=000010 0=000000 C=000011 then 100000 x 4
    # 000001 000010 000000 000011 100000 100000 100000 100000 = 04 20 03 82 08 20
    ("042003820820", "AB?C", "042003820820"),
])
def test_identification_text_outside_icao_set(hex6, text, raw):
    # I048/240 (FRN 9) and I021/170 (0.23 FRN 18) carry the same 6-bit text
    r = one048((9, bytes.fromhex(hex6)))
    assert (pd.isna(r.callsign) if text is None else r.callsign == text)
    assert r.callsign_hex == raw
    # CAT021 0.23: FSPEC FRN 1 (81) and FRN 18: 17 = 2*7 + 3 -> octet 2 bit 0x80 >> 3 = 0x10: 81 01 10
    rec = decode_bytes(block(21, bytes.fromhex("810110") + bytes([0, 1]) + bytes.fromhex(hex6)),
                       editions={21: "0.23"})
    r21 = rec.frames[21].iloc[0]
    assert (pd.isna(r21.callsign) if text is None else r21.callsign == text)
    assert r21.callsign_hex == raw


def test_callsign_hex_absent_without_the_item():
    r = one048()
    assert pd.isna(r.callsign) and pd.isna(r.callsign_hex)


def test_021_0_2x_position_accuracy_is_the_raw_four_bits():
    # 0.23 I021/090 (FRN 7): AC=MN=DC=0, spare, PA bits 1100 -> 0x00 0x0C. The 0.2x specs print PA as a
    # "signed quantity", which would read -4; a negative accuracy category means nothing, so msdc keeps the
    # raw bits (docs/decoding/editions.md: the documented errata): 12, and 1111 -> 15
    for edition in ("0.23", "0.24", "0.25", "0.26"):
        for pa_bits, raw in ((0x0C, 12), (0x0F, 15), (0x08, 8)):
            r = decode_bytes(block(21, fspec(1, 7) + bytes([0, 1, 0x00, pa_bits])),
                             editions={21: edition}).frames[21].iloc[0]
            assert r.fom_pa == raw, (edition, pa_bits)


@pytest.mark.parametrize("edition", ["2.2", "2.5", "2.7"])
def test_021_2x_target_status(edition):
    # I021/200 (FRN 23): ICF=1 LNAV=0 ME=1 PS=101 (5, unlawful interference) SS=10 (2, temporary alert)
    # -> 1 0 1 101 10 = 0xB6; then ICF=0 LNAV=1 ME=0 PS=001 (general emergency) SS=01 -> 0100 0101 = 0x45
    f = decode_bytes(block(21, fspec(1, 23) + bytes([0, 1, 0xB6]), fspec(1, 23) + bytes([0, 1, 0x45])),
                     editions={21: edition}).frames[21]
    got = f[["icf", "lnav_not_engaged", "me", "priority_status", "surveillance_status"]].astype(int)
    assert got.values.tolist() == [[1, 0, 1, 5, 2], [0, 1, 0, 1, 1]]
    absent = decode_bytes(block(21, fspec(1) + bytes([0, 1])), editions={21: edition}).frames[21].iloc[0]
    assert pd.isna(absent.priority_status) and pd.isna(absent.me)


def test_021_2_1_target_status_has_no_military_emergency():
    # 2.1 prints the third bit of I021/200 as spare: even set, it is no ME (<NA>); PS and SS as in 2.2
    r = decode_bytes(block(21, fspec(1, 23) + bytes([0, 1, 0xB6])), editions={21: "2.1"}).frames[21].iloc[0]
    assert (r.icf, r.lnav_not_engaged, r.priority_status, r.surveillance_status) == (1, 0, 5, 2)
    assert pd.isna(r.me)


@pytest.mark.parametrize("edition", ["0.23", "0.24", "0.25", "0.26"])
def test_021_0_2x_target_status_is_one_code(edition):
    # 0.2x I021/200 (FRN 21) is one 8-bit code, with 2.x PS's table: 1 general emergency, 4 no communications
    f = decode_bytes(block(21, fspec(1, 21) + bytes([0, 1, 0x01]), fspec(1, 21) + bytes([0, 1, 0x04])),
                     editions={21: edition}).frames[21]
    assert f["priority_status"].tolist() == [1, 4]
    assert "surveillance_status" not in f and "me" not in f


@pytest.mark.parametrize("edition", ["1.27", "1.31", "1.32"])
def test_048_warning_codes_every_code_in_wire_order(edition):
    # I048/030 (FRN 16): 7-bit codes, each followed by FX. 0x06 = 0000011 0 -> [3] (split plot);
    # 0x03 0x06 = 0000001 1, 0000011 0 -> [1, 3]; 0x19 0xFF 0x00 -> [12 (FX), 127 (FX), 0] in that order
    rows = [one048((16, bytes([0x06])), editions={48: edition}),
            one048((16, bytes([0x03, 0x06])), editions={48: edition}),
            one048((16, bytes([0x19, 0xFF, 0x00])), editions={48: edition}),
            one048(editions={48: edition})]
    assert [r.warning_codes for r in rows[:3]] == ["3", "1,3", "12,127,0"]
    assert pd.isna(rows[3].warning_codes)


def test_048_warning_codes_do_not_shift_the_items_after_them():
    # FRN 16 (030, two codes) then FRN 21 (230 COM=1 STAT=2 -> 001 010 00 = 0x28, second byte 0)
    r = one048((16, bytes([0x03, 0x06])), (21, bytes([0x28, 0x00])))
    assert r.warning_codes == "1,3" and (r.com, r.flight_status) == (1, 2)


def test_048_warning_codes_of_many_records_of_any_length():
    # one block: [3], [1, 3], [3, 0] (0x07 0x00: the trailing code 0 is not padding), none, and
    # nine codes 1..9 (over 8 bytes): 0x03 0x05 ... 0x11 with FX, then 0x12 (code 9, FX 0)
    nine = bytes([(c << 1) | 1 for c in range(1, 9)]) + bytes([9 << 1])
    items = [bytes([0x06]), bytes([0x03, 0x06]), bytes([0x07, 0x00]), None, nine, bytes([0x06])]
    recs = [cat048((1, I010), (2, I140), *([(16, it)] if it else [])) for it in items]
    f = decode_bytes(block(48, *recs)).frames[48]
    got = f["warning_codes"].astype(object).where(f["warning_codes"].notna(), None).tolist()
    assert got == ["3", "1,3", "3,0", None, "1,2,3,4,5,6,7,8,9", "3"]
