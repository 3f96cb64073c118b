"""CAT002 monoradar service messages: records written by hand from the 1.0-1.2 layouts, values worked by hand.

UAP (every edition): FRN 1 I002/010 SAC SIC, 2 I002/000 message type, 3 I002/020 sector (360/2^8 deg),
4 I002/030 time of day (24 bits, 1/128 s), 5 I002/041 rotation period (1/128 s), 6 I002/050 and
7 I002/060 (7-bit FX repetitions), 8 I002/070 plot counts (count + 2 bytes each), 9 I002/100 window (8
bytes), 10 I002/090 collimation error, 11 I002/080 warnings (7-bit FX repetitions), 12 spare, 13 SP,
14 RFS. The three editions print the same UAP and items.
"""

from __future__ import annotations

import pandas as pd
import pytest
from asterix_bytes import block, decode_bytes, fspec

from msdc.asterix.encode import encode_record

EDITIONS = ["1.0", "1.1", "1.2"]

# North marker with the rotation period: FSPEC D8 (FRNs 1, 2, 4, 5)
# I002/030 36000.5 s * 128 = 4608064 = 0x465040; I002/041 0x0266 = 614 / 128 = 4.796875 s
NORTH = bytes.fromhex("D8") + bytes([25, 201]) + b"\x01" + bytes.fromhex("465040") + bytes.fromhex("0266")

# Sector crossing with station status, plot counts, collimation error and warnings:
# FSPEC F7 (FRNs 1-4, 6, 7, FX) B0 (FRNs 8, 10, 11)
# I002/020 0x40 = 64 * 1.40625 = 90 deg; I002/030 36001.25 s * 128 = 4608160 = 0x4650A0
# I002/050 0x03 0x02 and I002/060 0x00: FX repetitions, not decoded (walked)
# I002/070 count 2: 0x8C05 = 1 00011 0000000101 (A 1: antenna 2, IDENT 3: combined, COUNTER 5), 0x0800
# I002/090 RE 0xFD = -3 / 128 = -0.0234375 NM; AE 0x05 = 5 * 360 / 2^14 = 0.10986328125 deg
# I002/080 0x41 0x02: codes 32 (FX) and 1
SECTOR = (bytes.fromhex("F7B0") + bytes([25, 201]) + b"\x02" + b"\x40" + bytes.fromhex("4650A0")
          + bytes.fromhex("0302") + b"\x00" + bytes.fromhex("028C050800") + bytes.fromhex("FD05")
          + bytes.fromhex("4102"))

# Activation of blind zone filtering over a window: FSPEC C1 (FRNs 1, 2, FX) 40 (FRN 9)
# I002/100 RS 0x0A00 = 2560 / 128 = 20 NM; RE 0x6480 = 25728 / 128 = 201 NM; TS 0x2000 = 45 deg;
#          TE 0x4000 = 90 deg
BLIND = bytes.fromhex("C140") + bytes([25, 202]) + b"\x08" + bytes.fromhex("0A00648020004000")


def decode2(*records: bytes, **kw) -> pd.DataFrame:
    rec = decode_bytes(b"".join(block(2, r) for r in records), categories=[2], **kw)
    assert rec.errors.empty, rec.errors.to_dict("records")
    return rec.frames[2]


def test_fspecs_worked_by_hand() -> None:
    assert fspec(1, 2, 4, 5) == NORTH[:1]
    assert fspec(1, 2, 3, 4, 6, 7, 8, 10, 11) == SECTOR[:2]
    assert fspec(1, 2, 9) == BLIND[:2]


@pytest.mark.parametrize("edition", EDITIONS)
def test_north_marker(edition: str) -> None:
    r = decode2(NORTH, editions={2: edition}).iloc[0]
    assert (r.sac, r.sic, r.message_type) == (25, 201, 1)
    assert r.time_of_day == 36000.5 and r.antenna_rotation_period_s == 4.796875
    assert pd.isna(r.sector_number) and pd.isna(r.sector_azimuth_deg) and pd.isna(r.plot_counters)


@pytest.mark.parametrize("edition", EDITIONS)
def test_sector_crossing(edition: str) -> None:
    r = decode2(SECTOR, editions={2: edition}).iloc[0]
    assert (r.message_type, r.sector_number, r.sector_azimuth_deg) == (2, 64, 90.0)
    assert r.time_of_day == 36001.25 and pd.isna(r.antenna_rotation_period_s)
    assert r.plot_counters == 2
    assert r.collimation_range_error_nm == -0.0234375 and r.collimation_azimuth_error_deg == 0.10986328125
    assert r.warning_codes == "32,1"


def test_blind_zone_window_and_file_order() -> None:
    f = decode2(NORTH, BLIND, SECTOR)
    assert f.message_type.tolist() == [1, 8, 2] and f.sic.tolist() == [201, 202, 201]
    r = f.iloc[1]
    assert pd.isna(r.time_of_day)
    assert (r.window_rho_start_nm, r.window_rho_end_nm) == (20.0, 201.0)
    assert (r.window_theta_start_deg, r.window_theta_end_deg) == (45.0, 90.0)


def test_editions_are_read_with_one_table() -> None:
    for edition in EDITIONS:
        rec = decode_bytes(block(2, NORTH, SECTOR), categories=[2], editions={2: edition})
        assert rec.editions == {2: "1.2"} and len(rec.frames[2]) == 2


def test_rfs_is_reported_not_walked() -> None:
    rec = decode_bytes(block(2, fspec(1, 14) + bytes([25, 201, 1, 2, 0])), categories=[2])
    assert len(rec.errors) == 1 and "Random Field Sequencing (RFS)" in rec.errors.reason.iloc[0]


def test_not_decoded_unless_asked() -> None:
    data = block(2, NORTH, SECTOR)
    rec = decode_bytes(data)
    assert rec.frames == {} and rec.errors.empty
    assert rec.ignored_blocks == {2: 1} and rec.ignored_bytes == len(data)


@pytest.mark.parametrize("edition", EDITIONS)
def test_encoder_writes_the_hand_bytes(edition: str) -> None:
    assert encode_record(2, {"sac": 25, "sic": 201, "message_type": 1, "time_of_day": 36000.5,
                             "antenna_rotation_period_s": 4.796875}, edition=edition) == NORTH
    assert encode_record(2, {
        "sac": 25, "sic": 201, "message_type": 2, "sector_azimuth_deg": 90.0, "time_of_day": 36001.25,
        "collimation_range_error_nm": -0.0234375, "collimation_azimuth_error_deg": 0.10986328125,
        "warning_codes": "32,1"}, edition=edition,
        extra={"050": bytes.fromhex("0302"), "060": b"\x00", "070": bytes.fromhex("028C050800")}) == SECTOR
    assert encode_record(2, {
        "sac": 25, "sic": 202, "message_type": 8, "window_rho_start_nm": 20.0, "window_rho_end_nm": 201.0,
        "window_theta_start_deg": 45.0, "window_theta_end_deg": 90.0}, edition=edition) == BLIND
