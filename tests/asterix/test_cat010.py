"""CAT010 1.1 (surface radar and airport multilateration): records written by hand from the layout in
../shared/specs/Cat_010_1_1.txt, every value worked out by hand from the bytes.

UAP: FRN 1 I010/010, 2 /000 message type, 3 /020 descriptor (FX), 4 /140 time (1/128 s), 5 /041 WGS-84
(180/2^31 deg), 6 /040 polar (1 m, 360/2^16 deg), 7 /042 Cartesian (1 m) | 8 /200 speed (2^-14 NM/s,
360/2^16 deg), 9 /202 Vx Vy (0.25 m/s: the printout's 1/16 is wrong), 10 /161 track, 11 /170 status (FX),
12 /060 Mode 3/A, 13 /220 address, 14 /245 identification | 15 /250 MB data (count), 16 /300 fleet,
17 /090 FL (1/4, 14-bit signed), 18 /091 height (6.25 ft), 19 /270 size (FX), 20 /550 system status,
21 /310 message | 22 /500 sigma (0.25 m), 23 /280 presence (count), 24 /131 amplitude, 25 /210
acceleration (1/16 m/s^2), 26 spare, 27 SP, 28 RE.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from asterix_bytes import SHARED, block, decode_bytes, fspec

import msdc.asterix as asterix

TIME = bytes.fromhex("465040")  # I010/140: 0x465040 = 4608064 = 36000.5 s x 128

# Multilateration target report (TYP 1).
# FSPEC F3 EF 21 80: FRNs 1 2 3 4 7 | 8 9 10 12 13 14 | 17 | 22.
# I010/020 0x2C = 001 0 1 1 0 0: TYP 1, DCR 0, CHN 1, GBS 1, CRT 0, FX 0.
# I010/042 X 0xFF4D = 65357 - 65536 = -179 m, Y 0x03F7 = 1015 m.
# I010/200 GSP 0x0055 = 85 x 2^-14 NM/s x 3600 = 18.6767578125 kt; TRA 0x8000 = 32768 x 360/65536 = 180 deg.
# I010/202 VX 0xFFEA = -22 x 0.25 = -5.5 m/s (1/16 would give -1.375), VY 0x001F = 31 x 0.25 = 7.75 m/s.
# I010/161 0x048C = track 1164. I010/060 0x07D2: code 3722 octal (2002 = 0x7D2), V G L 0.
# I010/220 0x345205. I010/245 STI 0, "VLG20JM ": V 22 L 12 G 7 '2' 50 '0' 48 J 10 M 13 ' ' 32 =
#   010110 001100 000111 110010 110000 001010 001101 100000 = 58 C1 F2 C0 A3 60.
# I010/090 0x0006 = 6 x 0.25 = FL 1.5. I010/500 DEVX 0x0A = 2.5 m, DEVY 0x14 = 5 m, COVXY 0xFFF8 = -8 x 0.25.
MLAT = (bytes.fromhex("F3EF2180") + bytes([0, 107]) + b"\x01" + b"\x2C" + TIME + bytes.fromhex("FF4D03F7")
        + bytes.fromhex("00558000") + bytes.fromhex("FFEA001F") + bytes.fromhex("048C")
        + bytes.fromhex("07D2")
        + bytes.fromhex("345205") + bytes.fromhex("0058C1F2C0A360") + bytes.fromhex("0006")
        + bytes.fromhex("0A14FFF8"))

# Surface radar target report (TYP 3), polar and Cartesian.
# FSPEC F7 31 09 60: FRNs 1 2 3 4 6 7 | 10 11 | 19 | 23 24.
# I010/020 0x61 = 011 0 0 0 0 1: TYP 3, FX; 0x05 = 0 0 0 00 10 1: TOT 2 (ground vehicle), FX; 0x80: SPI 1.
# I010/040 RHO 0x0427 = 1063 m, TH 0x9BF4 = 39924 x 360/65536 = 219.30908203125 deg.
# I010/042 X 0xFD5F = 64863 - 65536 = -673 m, Y 0xFCC9 = 64713 - 65536 = -823 m. I010/161 0x0CF1 = 3313.
# I010/170 0x67 = 0 1 10 0 1 1 1: CNF 0, TRE 1, CST 2, MAH 0, TCC 1, STH 1, FX;
#          0x9A = 10 011 01 0: TOM 2, DOU 3, MRS 1 (no GHO octet).
# I010/270 0x3D = 0011110 1: length 30 m, FX; 0x81 = 1000000 1: 64 x 2.8125 = 180 deg, FX; 0x18: width 12 m.
# I010/280 count 2, (FD 02) (05 FF). I010/131 0xC8 = 200.
SMR = (bytes.fromhex("F7310960") + bytes([0, 7]) + b"\x01" + bytes.fromhex("610580") + TIME
       + bytes.fromhex("04279BF4") + bytes.fromhex("FD5FFCC9") + bytes.fromhex("0CF1") + bytes.fromhex("679A")
       + bytes.fromhex("3D8118") + bytes.fromhex("02FD0205FF") + b"\xC8")

# Start of update cycle (message type 2) with the system status.
# FSPEC D1 01 04: FRNs 1 2 4 | (none) | 20. I010/550 0x68 = 01 1 0 1 0 00: NOGO 1, OVL 1, TSV 0, DIV 1, TTF 0.
STATUS = bytes.fromhex("D10104") + bytes([0, 107]) + b"\x02" + TIME + b"\x68"

# An ADS-B report (TYP 2) with WGS-84 position and the rarer items.
# FSPEC F9 01 D3 10: FRNs 1 2 3 4 5 | | 15 16 18 21 | 25.
# I010/020 0x50 = 010 1 0 0 0 0: TYP 2, DCR 1. I010/041 LAT 0x20000000 = 2^29 x 180/2^31 = 45 deg,
#   LON 0xFC000000 = -2^26 x 180/2^31 = -5.625 deg. I010/250 count 1 + 8 bytes. I010/300 3 (fire).
# I010/091 0xFFF0 = -16 x 6.25 = -100 ft. I010/310 0x84 = 1 0000100: TRB 1, MSG 4.
# I010/210 AX 0x10 = 16/16 = 1 m/s^2, AY 0xF8 = -8/16 = -0.5 m/s^2.
ADSB = (bytes.fromhex("F901D310") + bytes([0, 107]) + b"\x01" + b"\x50" + TIME
        + bytes.fromhex("20000000FC000000") + bytes.fromhex("01" "1122334455667740") + b"\x03"
        + bytes.fromhex("FFF0") + b"\x84" + bytes.fromhex("10F8"))


def decode10(*records: bytes) -> pd.DataFrame:
    rec = decode_bytes(b"".join(block(10, r) for r in records))
    assert rec.errors.empty, rec.errors.to_dict("records")
    return rec.frames[10]


def test_fspecs_worked_by_hand() -> None:
    assert fspec(1, 2, 3, 4, 7, 8, 9, 10, 12, 13, 14, 17, 22) == bytes.fromhex("F3EF2180")
    assert fspec(1, 2, 3, 4, 6, 7, 10, 11, 19, 23, 24) == bytes.fromhex("F7310960")
    assert fspec(1, 2, 4, 20) == bytes.fromhex("D10104")
    assert fspec(1, 2, 3, 4, 5, 15, 16, 18, 21, 25) == bytes.fromhex("F901D310")


def test_decoded_by_default_as_cat010() -> None:
    f = decode10(MLAT, SMR, STATUS, ADSB)
    assert len(f) == 4 and f.offset.tolist()[0] == 3
    assert f.message_type.tolist() == [1, 1, 2, 1]
    assert f.typ.astype("Int64").tolist()[:2] == [1, 3] and pd.isna(f.typ.iloc[2]) and f.typ.iloc[3] == 2


def test_multilateration_report() -> None:
    r = decode10(MLAT).iloc[0]
    assert (r.sac, r.sic, r.message_type, r.time_of_day) == (0, 107, 1, 36000.5)
    assert (r.typ, r.dcr, r.chn, r.gbs, r.crt) == (1, 0, 1, 1, 0)
    assert pd.isna(r.sim) and pd.isna(r.spi)  # octet-groups not sent
    assert (r.x_m, r.y_m) == (-179.0, 1015.0)
    assert r.ground_speed_kt == 18.6767578125 and r.track_angle_deg == 180.0
    assert (r.vx_ms, r.vy_ms) == (-5.5, 7.75)
    assert r.track_number == 1164 and r.mode3a == "3722" and (r.mode3a_v, r.mode3a_g, r.mode3a_l) == (0, 0, 0)
    assert r.address == "345205" and r.callsign == "VLG20JM" and r.sti == 0
    assert r.flight_level == 1.5
    assert (r.sigma_x_m, r.sigma_y_m, r.cov_xy_m2) == (2.5, 5.0, -2.0)
    assert np.isnan(r.rho_m) and np.isnan(r.latitude)


def test_surface_radar_report() -> None:
    r = decode10(SMR).iloc[0]
    assert (r.sac, r.sic, r.typ, r.tot, r.spi, r.sim, r.rab, r.lop) == (0, 7, 3, 2, 1, 0, 0, 0)
    assert (r.rho_m, r.theta_deg) == (1063.0, 219.30908203125)
    assert (r.x_m, r.y_m) == (-673.0, -823.0)
    assert r.track_number == 3313
    assert (r.cnf, r.tre, r.cst, r.mah, r.tcc, r.sth) == (0, 1, 2, 0, 1, 1)
    assert (r.tom, r.dou, r.mrs) == (2, 3, 1) and pd.isna(r.gho)
    assert (r.target_length_m, r.target_orientation_deg, r.target_width_m) == (30.0, 180.0, 12.0)
    assert r.presence_count == 2 and r.amplitude == 200
    assert pd.isna(r.address) and pd.isna(r.mode3a) and np.isnan(r.flight_level)


def test_status_message() -> None:
    r = decode10(STATUS).iloc[0]
    assert (r.message_type, r.time_of_day) == (2, 36000.5)
    assert (r.nogo, r.overload, r.time_source_invalid, r.diversity_degraded, r.test_target_failure) == (
        1, 1, 0, 1, 0)
    assert pd.isna(r.typ) and np.isnan(r.x_m)


def test_wgs84_and_rarer_items() -> None:
    r = decode10(ADSB).iloc[0]
    assert (r.typ, r.dcr) == (2, 1)
    assert (r.latitude, r.longitude) == (45.0, -5.625)
    assert r.bds_count == 1 and r.vehicle_fleet == 3 and r.measured_height_ft == -100.0
    assert (r.trouble, r.preprogrammed_message) == (1, 4)
    assert (r.ax_ms2, r.ay_ms2) == (1.0, -0.5)


def test_negative_flight_level_is_twos_complement_over_14_bits() -> None:
    # FSPEC: FRN 1 and 17 -> 81 01 20 (FRN 17 is the third bit of the third octet); FL 0x3FFB = 16379 - 16384
    rec = bytes.fromhex("810120") + bytes([0, 107]) + bytes.fromhex("3FFB")
    assert decode10(rec).flight_level.tolist() == [-1.25]


def test_explicit_items_and_the_spare_frn() -> None:
    # FRN 1 and 27 (SP, 0x04 in the fourth FSPEC octet): length byte 3 counting itself, two data bytes
    sp = bytes.fromhex("81010104") + bytes([0, 107]) + bytes.fromhex("03AABB")
    f = decode10(sp)
    assert len(f) == 1 and f.sic.tolist() == [107]
    # FRN 26 (0x08 in the fourth octet) is a spare FRN: the block is reported, not guessed through
    bad = bytes.fromhex("81010108") + bytes([0, 107]) + b"\x00"
    rec = decode_bytes(block(10, bad))
    assert 10 not in rec.frames or rec.frames[10].empty
    assert rec.errors.offset.tolist() == [0] and "FRN" in rec.errors.reason.iloc[0]


REAL = SHARED / "real"


@pytest.mark.skipif(not REAL.is_dir(), reason=f"{REAL} not present: real-recording cases skipped")
@pytest.mark.parametrize("name", ["mlat_160510-lebl-220001.ast", "smr_160510-lebl-220001.ast"])
def test_velocity_lsb_is_a_quarter_metre_per_second_on_real_data(name: str) -> None:
    """The I010/202 erratum checked against the recording's own I010/200: |(Vx, Vy)| equals the ground speed
    (median ratio 1 within 2 %) with 0.25 m/s; the printout's 1/16 would make it a quarter of it."""
    f = asterix.read(REAL / name).frames[10]
    speed_ms = np.hypot(f.vx_ms, f.vy_ms)
    ground_ms = f.ground_speed_kt * 1852.0 / 3600.0
    moving = (ground_ms > 2.0).to_numpy()
    assert moving.sum() > 20_000
    assert abs(float(np.median(speed_ms[moving] / ground_ms[moving])) - 1.0) < 0.02
