"""I048/250 Mode S registers (BDS 4,0 / 5,0 / 6,0) decoded into columns: values worked out bit by bit from
the ICAO Doc 9871 register layouts, the published worked examples of "The 1090 Megahertz Riddle" (Junzi
Sun, 2nd ed., Enhanced Surveillance chapter, as also asserted by pyModeS's tests), and, on the real radar
file, physical consistency with the radar's own I048/200 and (validation) agreement with pyModeS."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest
from asterix_bytes import SHARED, block, decode_bytes, fspec

from msdc.asterix.encode import encode_frame, encode_record

I010 = bytes([25, 201])  # SAC 25 SIC 201
I140 = bytes([0x35, 0x5D, 0x80])  # time of day 27323 s
FRN_250 = 10  # I048/250 in the CAT048 UAP (every edition)

BDS40 = ["mcp_selected_altitude_ft", "fms_selected_altitude_ft", "baro_setting_hpa"]
BDS50 = ["roll_angle_deg", "track_angle_deg", "bds50_ground_speed_kt", "track_angle_rate_degs",
         "true_airspeed_kt"]
BDS60 = ["magnetic_heading_deg", "indicated_airspeed_kt", "mach", "baro_vertical_rate_ftmin",
         "inertial_vertical_rate_ftmin"]
ALL = BDS40 + BDS50 + BDS60


def group(mb_bits: str, bds: int) -> bytes:
    """One I048/250 repetition: the 56 MB bits (a '0'/'1' string, spaces ignored) then BDS1/BDS2."""
    bits = mb_bits.replace(" ", "")
    assert len(bits) == 56, len(bits)
    return int(bits, 2).to_bytes(7, "big") + bytes([bds])


def from_hex(mb_hex: str, bds: int) -> bytes:
    return bytes.fromhex(mb_hex) + bytes([bds])


def item250(*groups: bytes) -> bytes:
    return bytes([len(groups)]) + b"".join(groups)


def record(*items: tuple[int, bytes]) -> bytes:
    items = tuple(sorted(((1, I010), (2, I140), *items)))
    return fspec(*(f for f, _ in items)) + b"".join(b for _, b in items)


def frame_of(*records: bytes) -> pd.DataFrame:
    rec = decode_bytes(block(48, *records))
    assert rec.errors.empty, rec.errors
    return rec.frames[48]


def one(*groups: bytes) -> pd.Series:
    return frame_of(record((FRN_250, item250(*groups)))).iloc[0]


def test_published_examples():
    # The 1090 Megahertz Riddle (2nd ed.), DF20 replies; MB = hex digits 9-22 of the message.
    # A000029C85E42F313000007047D3 (BDS 4,0): MCP 3008 ft, FMS 3008 ft, baro 1020.0 mb
    r = one(from_hex("85E42F31300000", 0x40))
    assert (r.mcp_selected_altitude_ft, r.fms_selected_altitude_ft) == (3008, 3008)
    assert r.baro_setting_hpa == pytest.approx(1020.0)
    # A000139381951536E024D4CCF6B5 (BDS 5,0): roll 2.1, track 114.258, GS 438, track rate 0.125, TAS 424
    r = one(from_hex("81951536E024D4", 0x50))
    assert r.roll_angle_deg == pytest.approx(2.1, abs=0.05)
    assert r.track_angle_deg == pytest.approx(114.258, abs=5e-4)
    assert (r.bds50_ground_speed_kt, r.track_angle_rate_degs, r.true_airspeed_kt) == (438, 0.125, 424)
    # A0001691FFD263377FFCE02B2BF9 (BDS 5,0): roll -0.4 (a negative, two's complement)
    assert one(from_hex("FFD263377FFCE0", 0x50)).roll_angle_deg == pytest.approx(-0.4, abs=0.05)
    # A00004128F39F91A7E27C46ADC21 (BDS 6,0): heading 42.71484, IAS 252, Mach 0.42, both rates -1920
    r = one(from_hex("8F39F91A7E27C4", 0x60))
    assert r.magnetic_heading_deg == pytest.approx(42.71484, abs=1e-5)
    assert (r.indicated_airspeed_kt, r.mach) == (252, pytest.approx(0.42))
    assert (r.baro_vertical_rate_ftmin, r.inertial_vertical_rate_ftmin) == (-1920, -1920)


def test_bds40_bit_by_bit():
    # bit 1 status, 2-13 MCP/FCU altitude (16 ft): 35008 / 16 = 2188 = 1000 1000 1100
    # bit 14 status, 15-26 FMS altitude: 0 status -> absent whatever follows (zeros as Doc 9871 says)
    # bit 27 status, 28-39 baro - 800 mb (0.1 mb): 1013.2 -> 2132 = 1000 0101 0100
    # 40-56 reserved / mode bits, zero
    mb = "1 100010001100" "0 000000000000" "1 100001010100" + "0" * 17
    r = one(group(mb, 0x40))
    assert r.mcp_selected_altitude_ft == 35008
    assert math.isnan(r.fms_selected_altitude_ft)
    assert r.baro_setting_hpa == pytest.approx(1013.2)
    assert r[BDS50 + BDS60].isna().all()


def test_bds50_bit_by_bit_negative_values():
    # 1 status, 2 sign, 3-11 roll (45/256): -20.0390625 = -114 LSB -> 10-bit two's complement 1110001110
    # 12 status, 13 sign, 14-23 track (90/512): -90 = -512 -> 11-bit 11000000000 -> 270 deg (0-360)
    # 24 status, 25-34 GS (2 kt): 250 kt = 125 = 0001111101
    # 35 status, 36 sign, 37-45 track rate (8/256): -3 deg/s = -96 -> 10-bit 1110100000
    # 46 status 0 (TAS absent), 47-56 zero
    mb = "1 1110001110" "1 11000000000" "1 0001111101" "1 1110100000" "0 0000000000"
    r = one(group(mb, 0x50))
    assert r.roll_angle_deg == pytest.approx(-114 * 45 / 256)
    assert r.track_angle_deg == 270.0
    assert r.bds50_ground_speed_kt == 250
    assert r.track_angle_rate_degs == -3.0
    assert math.isnan(r.true_airspeed_kt)


def test_bds60_bit_by_bit_negative_values():
    # 1 status, 2 sign, 3-12 heading (90/512): -0.17578125 = -1 -> 11111111111 -> 359.82421875
    # 13 status, 14-23 IAS (1 kt): 300 = 0100101100
    # 24 status 0: Mach absent
    # 35 status, 36 sign, 37-45 baro rate (32 ft/min): -1024 = -32 -> 1111100000
    # 46 status, 47 sign, 48-56 inertial rate: +2016 = 63 -> 0000111111
    mb = "1 11111111111" "1 0100101100" "0 0000000000" "1 1111100000" "1 0000111111"
    r = one(group(mb, 0x60))
    assert r.magnetic_heading_deg == pytest.approx(360 - 90 / 512)
    assert r.indicated_airspeed_kt == 300
    assert math.isnan(r.mach)
    assert (r.baro_vertical_rate_ftmin, r.inertial_vertical_rate_ftmin) == (-1024, 2016)


def test_every_status_bit_off_is_absent_not_zero():
    # all status bits 0 (and their fields zero): every column absent, though the register is present
    for bds in (0x40, 0x50, 0x60):
        r = one(group("0" * 56, bds))
        assert r.bds_count == 1 and r[ALL].isna().all()
    # a status bit 1 over a zero field is a real 0
    assert one(group("1" + "0" * 55, 0x60)).magnetic_heading_deg == 0.0


def test_registers_are_chosen_by_the_declared_bds_code():
    mb40 = "1 100010001100" + "0" * 43  # MCP 35008 ft
    mb60 = "0" * 12 + "1 0100101100" + "0" * 33  # IAS 300 kt
    # two registers in one record, in either order; a register the columns do not read (BDS 4,4) is passed
    for groups in ([group(mb40, 0x40), group(mb60, 0x60)], [group(mb60, 0x60), group(mb40, 0x40)],
                   [group(mb60, 0x44), group(mb40, 0x40), group(mb60, 0x60)]):
        r = one(*groups)
        assert (r.mcp_selected_altitude_ft, r.indicated_airspeed_kt) == (35008, 300)
        assert r[BDS50].isna().all()
    # the same bits declared as BDS 5,0 are read as BDS 5,0 (the radar's declaration, never inferred)
    # bits 2-11 1000100011 = 547, as 10-bit two's complement 547 - 1024 = -477
    assert one(group(mb40, 0x50)).roll_angle_deg == pytest.approx(-477 * 45 / 256)
    # one register twice in a record: the first group is read
    second = "1 000001111101" + "0" * 43  # MCP 2000 ft
    assert one(group(mb40, 0x40), group(second, 0x40)).mcp_selected_altitude_ft == 35008
    assert one(group(second, 0x40), group(mb40, 0x40)).mcp_selected_altitude_ft == 2000


def test_many_records_each_keeps_its_own_registers():
    mb40 = "1 100010001100" + "0" * 43
    mb50 = "0" * 23 + "1 0001111101" + "0" * 22  # GS 250 kt
    recs = [record((FRN_250, item250(group(mb40, 0x40)))), record(),  # no I048/250
            record((FRN_250, item250())),  # a count of 0
            record((FRN_250, item250(group(mb50, 0x50), group(mb40, 0x40)))),
            record((FRN_250, item250(group(mb50, 0x50))))]
    f = frame_of(*recs)
    assert f.mcp_selected_altitude_ft.tolist()[0] == 35008 and f.mcp_selected_altitude_ft.tolist()[3] == 35008
    assert f.mcp_selected_altitude_ft.isna().tolist() == [False, True, True, False, True]
    assert f.bds50_ground_speed_kt.isna().tolist() == [True, True, True, False, False]
    assert f.bds50_ground_speed_kt.dtype == np.float64


def test_selected_columns_decode_only_what_is_asked():
    mb60 = "1 00000000001" "1 0100101100" + "0" * 33  # heading 90/512 deg, IAS 300 kt
    buf = block(48, record((FRN_250, item250(group(mb60, 0x60)))))
    f = decode_bytes(buf, columns=["indicated_airspeed_kt"]).frames[48]
    assert f.indicated_airspeed_kt.tolist() == [300] and "magnetic_heading_deg" not in f.columns
    assert decode_bytes(buf, columns=["flight_level"]).frames[48].columns.isin(ALL).sum() == 0


def test_encoder_writes_registers_as_extra_only():
    # the columns are not written from their values: a clear message, and encode_frame leaves them out
    with pytest.raises(ValueError, match="extra"):
        encode_record(48, {"sac": 1, "sic": 2, "time_of_day": 10.0, "mach": 0.5})
    mb60 = "0" * 12 + "1 0100101100" + "0" * 33
    raw = encode_record(48, {"sac": 1, "sic": 2, "time_of_day": 10.0},
                        extra={"250": item250(group(mb60, 0x60))})
    f = frame_of(raw)
    assert f.indicated_airspeed_kt.iloc[0] == 300
    again = decode_bytes(encode_frame(48, f)).frames[48]
    assert again.bds_count.iloc[0] == 1 and again[ALL].isna().all(axis=None)  # zero registers: all absent


def _bits(value: int, width: int) -> str:
    return format(value, f"0{width}b")


def _chars(text: str) -> str:
    """ICAO 6-bit codes of an 8-character text: A-Z 1-26, space 32, 0-9 48-57 (Annex 10 Vol IV 3.1.2.9)."""
    code = {**{c: i + 1 for i, c in enumerate("ABCDEFGHIJKLMNOPQRSTUVWXYZ")}, " ": 32,
            **{c: 48 + i for i, c in enumerate("0123456789")}}
    return "".join(_bits(code[c], 6) for c in text.ljust(8))


def test_bds40_mode_bits_and_target_source():
    # bit 48 status of the mode bits, 49 VNAV 1, 50 ALT HOLD 0, 51 APPROACH 1, 52-53 reserved,
    # bit 54 status of the target source, 55-56 = 10: FCU/MCP selected altitude (2)
    head = "1 100010001100" "0 000000000000" "0 000000000000" + "0" * 8  # MCP 35008 ft, bits 1-47
    r = one(group(head + "1" "101" "00" "1" "10", 0x40))
    assert r.mcp_selected_altitude_ft == 35008
    assert (r.vnav_mode, r.altitude_hold_mode, r.approach_mode, r.target_altitude_source) == (1, 0, 1, 2)
    # status bits 48 and 54 off: the modes and the source are absent, whatever their bits say
    r = one(group(head + "0" "111" "00" "0" "11", 0x40))
    assert r[["vnav_mode", "altitude_hold_mode", "approach_mode", "target_altitude_source"]].isna().all()


def test_bds10_capability_report():
    # 1-8 0001 0000, 9 continuation 0, 10-14 reserved, 15 OCC 0, 16 ACAS 1, 17-23 subnetwork 5 = 0000101,
    # 24 level 5 1, 25 specific services 1, 26-28 UELM 0, 29-32 DELM 0, 33 identification 1, 34 squitter 1,
    # 35 surveillance identifier 0, 36 GICB report 1, 37-40 ACAS, 41-56 DTE
    mb = "00010000" "0" "00000" "0" "1" "0000101" "1" "1" "000" "0000" "1" "1" "0" "1" "0000" + "0" * 16
    r = one(group(mb, 0x10))
    assert (r.mode_s_subnetwork_version, r.mode_s_level5, r.specific_services_capability) == (5, 1, 1)
    assert (r.identification_capability, r.squitter_capability, r.surveillance_identifier_capability) == \
        (1, 1, 0)
    # declared 1,0 but bits 1-8 are not 0001 0000 (another register's content): nothing read
    r = one(group("00100000" + mb[8:], 0x10))
    assert pd.isna(r.mode_s_subnetwork_version) and pd.isna(r.squitter_capability)


def test_bds17_names_the_registers_by_their_bits():
    # Doc 9871 Table A-2-23: bit 1 0,5 ... bit 7 2,0, bit 9 4,0, bit 16 5,0, bit 23 5,F, bit 24 6,0
    bits = ["0"] * 56
    for b in (1, 7, 9, 16, 23, 24):
        bits[b - 1] = "1"
    assert one(group("".join(bits), 0x17)).gicb_capability == "05,20,40,50,5F,60"
    assert pd.isna(one(group("0" * 56, 0x17)).gicb_capability)  # no register at all: nothing to name


def test_bds20_identification():
    r = one(group("00100000" + _chars("KLM1023"), 0x20))
    assert r.bds20_callsign == "KLM1023"
    # The 1090 Megahertz Riddle (2nd ed.), A000083E202CC371C31DE0AA1CCF: MB 202CC371C31DE0 is "KLM1017"
    assert one(from_hex("202CC371C31DE0", 0x20)).bds20_callsign == "KLM1017"
    assert pd.isna(one(group("00000000" + _chars("KLM1023"), 0x20)).bds20_callsign)  # bits 1-8 not 2,0


def test_bds30_resolution_advisory():
    # 1-8 0011 0000, 9-22 ARA 10000000000001 = 8193, 23-26 RAC 0100 = 4, 27 RAT 1, 28 MTE 0,
    # 29-30 TTI 01 (a Mode S address), 31-54 the threat's address 4840D6, 55-56 zero
    mb = "00110000" "10000000000001" "0100" "1" "0" "01" + _bits(0x4840D6, 24) + "00"
    r = one(group(mb, 0x30))
    assert (r.acas_ara, r.acas_rac, r.acas_ra_terminated, r.acas_multiple_threats) == (8193, 4, 1, 0)
    assert (r.acas_threat_type, r.acas_threat_address) == (1, "4840D6")
    # TTI 2: the 26 bits are altitude, range and bearing, not an address
    r = one(group(mb[:28] + "10" + mb[30:], 0x30))
    assert r.acas_threat_type == 2 and pd.isna(r.acas_threat_address)


def test_register_columns_keep_their_dtype_when_absent():
    present = frame_of(record((FRN_250, item250(group("00010000" + "0" * 8 + "0000101" + "0" * 33, 0x10)))))
    absent = frame_of(record())
    for name in ("mode_s_subnetwork_version", "squitter_capability", "gicb_capability", "bds20_callsign",
                 "acas_threat_address", "vnav_mode", "mach"):
        assert present[name].dtype == absent[name].dtype, name
    assert str(absent.vnav_mode.dtype) == "Int8" and str(absent.acas_ara.dtype) == "Int16"
    assert absent.bds20_callsign.dtype == "category" and absent.mach.dtype == np.float64


# --------------------------------------------------------------------------------------------------------
# The real radar file: physics that does not depend on this decoder.

REAL = SHARED / "real" / "230502-est-080001_BCN_60MN_08_09.ast"


@pytest.fixture(scope="module")
def real048() -> pd.DataFrame:
    if not REAL.is_file():
        pytest.skip(f"{REAL} not present: the real-recording checks need it")
    from msdc.asterix import read
    return read(str(REAL)).frames[48]


def _angle_diff(a, b):
    return (np.asarray(a) - np.asarray(b) + 180.0) % 360.0 - 180.0


def test_real_ground_speed_and_track_agree_with_the_radar(real048):
    f = real048.dropna(subset=["bds50_ground_speed_kt", "track_angle_deg"])
    f = f[f.ground_speed_kt > 150]  # airborne: the radar's track velocity is well defined
    assert len(f) > 1000
    assert abs(np.median(f.bds50_ground_speed_kt - f.ground_speed_kt)) < 2  # kt (LSB 2 kt)
    assert np.median(np.abs(_angle_diff(f.track_angle_deg, f.heading_deg))) < 1  # deg, both true track


def test_real_magnetic_heading_within_the_variation(real048):
    # near Barcelona the magnetic variation is about 1.5 deg east in 2023 (magnetic = true - 1.5), and
    # heading differs from track by the wind's drift: the median over many aircraft is a little below 0
    f = real048.dropna(subset=["magnetic_heading_deg"])
    f = f[f.ground_speed_kt > 150]
    assert len(f) > 1000
    assert -4 < np.median(_angle_diff(f.magnetic_heading_deg, f.heading_deg)) < 0


def test_real_selected_altitude_is_a_round_figure(real048):
    # pilots select hundreds of feet; with a 16 ft LSB the register holds the nearest multiple of 16
    alt = real048.mcp_selected_altitude_ft.dropna().to_numpy()
    assert len(alt) > 1000
    off = np.abs((alt + 50) % 100 - 50)
    assert np.mean(off <= 8) > 0.95
    baro = real048.baro_setting_hpa.dropna()
    assert ((baro > 950) & (baro < 1050)).mean() > 0.99


def test_real_mode_c_and_vertical_rates_are_physical(real048):
    f = real048.dropna(subset=["mach", "indicated_airspeed_kt"])
    assert (f.mach < 1.0).mean() > 0.999 and (f.indicated_airspeed_kt < 450).mean() > 0.999
    v = real048.dropna(subset=["baro_vertical_rate_ftmin", "inertial_vertical_rate_ftmin"])
    assert abs(np.median(v.baro_vertical_rate_ftmin - v.inertial_vertical_rate_ftmin)) <= 64


def test_real_registers_sent_are_among_those_the_aircraft_says_it_gives(real048):
    # BDS 1,7 says which registers an aircraft gives; the radar declares each group's register itself:
    # every aircraft's 4,0 / 5,0 / 6,0 groups must be registers its own 1,7 names
    data = REAL.read_bytes()
    declared = real048.dropna(subset=["gicb_capability", "address"]).groupby("address", observed=True)[
        "gicb_capability"].agg(lambda v: set(",".join(v.astype(str)).split(",")))
    assert len(declared) > 50
    sent: dict[str, set] = {}
    for off, address in zip(real048.offset.to_numpy(), real048.address.astype(object), strict=True):
        raw = _item250(data, int(off)) if address in declared.index else None
        if raw is not None:
            sent.setdefault(address, set()).update(
                f"{raw[8 + 8 * k]:02X}" for k in range(raw[0]) if raw[8 + 8 * k] in (0x40, 0x50, 0x60))
    fits = [sent.get(a, set()) <= declared[a] for a in declared.index]
    print(f"{np.mean(fits):.3f} of {len(fits)} aircraft sent only registers their BDS 1,7 names")
    assert np.mean(fits) > 0.95, np.mean(fits)
    versions = real048.mode_s_subnetwork_version.dropna()
    assert len(versions) > 1000 and versions.isin(range(6)).mean() > 0.99  # defined: 0-5 (Doc 9871)


@pytest.mark.validation
def test_real_every_register_agrees_with_pymodes(real048):
    pms = pytest.importorskip("pyModeS.decoder.bds", reason="pyModeS not installed: no independent check")
    from pyModeS.decoder.bds import bds40, bds50, bds60

    from msdc.asterix.layout import compile_layout
    names = {0x40: (bds40.decode_bds40, {"selected_altitude_mcp": "mcp_selected_altitude_ft",
                                          "selected_altitude_fms": "fms_selected_altitude_ft",
                                          "baro_pressure_setting": "baro_setting_hpa"}),
             0x50: (bds50.decode_bds50, {"roll": "roll_angle_deg", "true_track": "track_angle_deg",
                                          "groundspeed": "bds50_ground_speed_kt", "track_rate":
                                          "track_angle_rate_degs", "true_airspeed": "true_airspeed_kt"}),
             0x60: (bds60.decode_bds60, {"magnetic_heading": "magnetic_heading_deg",
                                          "indicated_airspeed": "indicated_airspeed_kt", "mach": "mach",
                                          "baro_vertical_rate": "baro_vertical_rate_ftmin",
                                          "inertial_vertical_rate": "inertial_vertical_rate_ftmin"})}
    assert pms and compile_layout(48).bds_slots
    data = REAL.read_bytes()
    agree = disagree = values = 0
    # the first register of each code in each record, read straight from the file's bytes at the offset
    for off, row in zip(real048.offset.to_numpy(), real048[ALL].itertuples(index=False), strict=True):
        raw = _item250(data, int(off))
        if raw is None:
            continue
        seen = set()
        for k in range(raw[0]):
            g = raw[1 + 8 * k: 9 + 8 * k]
            if g[7] not in names or g[7] in seen:
                continue
            seen.add(g[7])
            dec, cols = names[g[7]]
            got = dec(int.from_bytes(g[:7], "big"))
            for key, col in cols.items():
                ours = getattr(row, col)
                theirs = got.get(key)
                same = (theirs is None and math.isnan(ours)) or (
                    theirs is not None and abs(_angle_diff(ours, theirs) if "deg" in col and "rate" not in col
                                               else ours - theirs) < 1e-9)
                agree += same
                values += same and theirs is not None
                disagree += not same
    print(f"pyModeS agreement: {agree} fields agree ({values} with a value, the rest absent in both), "
          f"{disagree} differ")
    assert values > 100_000 and disagree == 0


def _item250(data: bytes, off: int) -> bytes | None:
    """I048/250 of the record at ``off``, walked by hand for the items this file's records carry before it
    (FRN 1-9 of the CAT048 UAP: 010 140 020 040 070 090 130 220 240)."""
    spec = []
    i = off
    while True:
        spec.append(data[i])
        i += 1
        if not data[i - 1] & 1:
            break
    frns = [7 * o + b + 1 for o, byte in enumerate(spec) for b in range(7) if byte & (0x80 >> b)]
    if FRN_250 not in frns:
        return None
    for frn in (f for f in frns if f < FRN_250):
        if frn == 3 or frn == 7:  # 020 and 130: extended / compound-like with FX on the first byte
            if frn == 3:
                while data[i] & 1:
                    i += 1
                i += 1
            else:
                sub = data[i]
                i += 1 + sum(1 for b in range(7) if sub & (0x80 >> b))  # 130: one byte per subfield
        else:
            i += {1: 2, 2: 3, 4: 4, 5: 2, 6: 2, 8: 3, 9: 6}[frn]
    return data[i:i + 1 + 8 * data[i]]
