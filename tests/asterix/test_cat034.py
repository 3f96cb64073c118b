"""CAT034 radar service messages: records written by hand from the 1.27-1.29 layouts, values worked by hand.

UAP (every edition): FRN 1 I034/010 SAC SIC, 2 I034/000 message type, 3 I034/030 time of day (1/128 s),
4 I034/020 sector (360/2^8 deg), 5 I034/041 rotation period (1/128 s), 6 I034/050 status (compound),
7 I034/060 processing mode (compound), 8 I034/070 counters (count + 2 bytes each), 9 I034/100 polar
window, 10 I034/110 data filter, 11 I034/120 source position, 12 I034/090 collimation error.
"""

from __future__ import annotations

import datetime as dt

import pandas as pd
import pytest
from asterix_bytes import block, decode_bytes, fspec

from msdc.asterix.encode import encode_record

EDITIONS = ["1.27", "1.28", "1.29"]

# North marker, with rotation period and system status.
# I034/030 36000.5 s * 128 = 4608064 = 0x465040 (0x46 * 65536 = 4587520, 0x50 * 256 = 20480, + 0x40 = 64)
# I034/041 0x0266 = 614 -> 614 / 128 = 4.796875 s
# I034/050 FSPEC 0x8C: COM (bit 1), SSR (bit 5), MDS (bit 6)
#   COM 0x4A = 0100 1010: NOGO 0, RDPC 1, RDPR 0, OVLRDP 0, OVLXMT 1, MSC 0, TSV 1, spare 0
#   SSR 0xC8 = 1 10 0 1 000: ANT 1, CHAB 2, OVL 0, MSC 1
#   MDS 0x3480 = 0 01 1 0 1 0 0 | 1 0000000: ANT 0, CHAB 1, OVLSUR 1, MSC 0, SCF 1, DLF 0, OVLSCF 0, OVLDLF 1
NORTH = (fspec(1, 2, 3, 5, 6) + bytes([25, 201]) + b"\x01" + bytes.fromhex("465040") + bytes.fromhex("0266")
         + bytes.fromhex("8C4AC83480"))

# Sector crossing at sector 0x40 = 64 -> 64 * 1.40625 = 90.0 deg, with processing mode and two counters.
# I034/030 36001.25 s * 128 = 4608160 = 0x4650A0 (4608064 + 96)
# I034/060 FSPEC 0x94: COM (bit 1), PSR (bit 4), MDS (bit 6)
#   COM 0x3A = 0 011 101 0: REDRDP 3, REDXMT 5
#   PSR 0xAC = 1 010 11 00: POL 1, REDRAD 2, STC 3
#   MDS 0x90 = 100 1 0000: REDRAD 4, CLU 1
# I034/070 count 2: 0x0003 (TYP 0 misses, COUNT 3); 0x13E8 = 00010 01111101000 (TYP 2, COUNT 1000)
SECTOR = (fspec(1, 2, 3, 4, 7, 8) + bytes([25, 201]) + b"\x02" + bytes.fromhex("4650A0") + b"\x40"
          + bytes.fromhex("943AAC90") + bytes.fromhex("02000313E8"))

# Geographical filtering message from SIC 202, no time: polar window, filter, source position, collimation.
# I034/100 RHOST 0x0A00 = 2560 / 256 = 10 NM; RHOEND 0x6480 = 25728 / 256 = 100.5 NM;
#          THETAST 0x2000 = 8192 * 360 / 65536 = 45 deg; THETAEND 0x4000 = 16384 -> 90 deg
# I034/110 3 (PSR filter)
# I034/120 HGT 0xFFFB = -5 m; LAT 0x200000 = 2^21 * 180 / 2^23 = 45 deg;
#          LON 0xC00000 = 2^24 - 2^22 -> -2^22 * 180 / 2^23 = -90 deg
# I034/090 RNG 0xFD = -3 / 128 = -0.0234375 NM; AZM 0x05 = 5 * 360 / 2^14 = 0.10986328125 deg
FILTER = (fspec(1, 2, 9, 10, 11, 12) + bytes([25, 202]) + b"\x03" + bytes.fromhex("0A00648020004000")
          + b"\x03" + bytes.fromhex("FFFB200000C00000") + bytes.fromhex("FD05"))


def decode34(*records: bytes, **kw) -> pd.DataFrame:
    rec = decode_bytes(b"".join(block(34, r) for r in records), categories=[34], **kw)
    assert rec.errors.empty, rec.errors.to_dict("records")
    return rec.frames[34]


def test_fspecs_worked_by_hand() -> None:
    # FRN 1, 2, 3, 5, 6 -> 0x80 | 0x40 | 0x20 | 0x08 | 0x04 = 0xEC; FRN 8 needs a second octet (FX)
    assert fspec(1, 2, 3, 5, 6) == b"\xec"
    assert fspec(1, 2, 3, 4, 7, 8) == b"\xf3\x80"
    assert fspec(1, 2, 9, 10, 11, 12) == b"\xc1\x78"


@pytest.mark.parametrize("edition", EDITIONS)
def test_north_marker(edition: str) -> None:
    r = decode34(NORTH, editions={34: edition}).iloc[0]
    assert (r.sac, r.sic, r.message_type) == (25, 201, 1)
    assert r.time_of_day == 36000.5
    assert r.antenna_rotation_period_s == 4.796875
    assert pd.isna(r.sector_number) and pd.isna(r.sector_azimuth_deg)
    assert (r.nogo, r.rdpc, r.rdp_reset, r.rdp_overload, r.transmission_overload) == (0, 1, 0, 0, 1)
    assert (r.monitoring_disconnected, r.time_source_invalid) == (0, 1)
    assert (r.ssr_antenna, r.ssr_channels, r.ssr_overload, r.ssr_monitoring_disconnected) == (1, 2, 0, 1)
    assert (r.mds_antenna, r.mds_channels, r.mds_overload, r.mds_monitoring_disconnected) == (0, 1, 1, 0)
    assert (r.mds_scf_channel, r.mds_dlf_channel, r.mds_scf_overload, r.mds_dlf_overload) == (1, 0, 0, 1)
    assert pd.isna(r.psr_antenna) and pd.isna(r.psr_channels)  # PSR subfield absent
    assert pd.isna(r.rdp_reduction_step) and pd.isna(r.message_counters)  # I034/060, /070 absent


@pytest.mark.parametrize("edition", EDITIONS)
def test_sector_crossing(edition: str) -> None:
    r = decode34(SECTOR, editions={34: edition}).iloc[0]
    assert (r.message_type, r.sector_number, r.sector_azimuth_deg) == (2, 64, 90.0)
    assert r.time_of_day == 36001.25
    assert pd.isna(r.antenna_rotation_period_s) and pd.isna(r.nogo)
    assert (r.rdp_reduction_step, r.transmission_reduction_step) == (3, 5)
    assert (r.psr_circular_polarization, r.psr_reduction_step, r.psr_stc_map) == (1, 2, 3)
    assert pd.isna(r.ssr_reduction_step)
    assert (r.mds_reduction_step, r.mds_not_autonomous) == (4, 1)
    assert r.message_counters == 2


def test_geographical_filter_message() -> None:
    r = decode34(FILTER).iloc[0]
    assert (r.sac, r.sic, r.message_type, r.data_filter) == (25, 202, 3, 3)
    assert pd.isna(r.time_of_day)
    assert (r.window_rho_start_nm, r.window_rho_end_nm) == (10.0, 100.5)
    assert (r.window_theta_start_deg, r.window_theta_end_deg) == (45.0, 90.0)
    assert (r.source_height_m, r.source_latitude, r.source_longitude) == (-5.0, 45.0, -90.0)
    assert r.collimation_range_error_nm == -0.0234375
    assert r.collimation_azimuth_error_deg == 0.10986328125


def test_default_edition_day_and_timestamp() -> None:
    # 23:59:59.5 then 00:00:00.5: the second north marker is on the next day
    late = fspec(1, 2, 3) + bytes([25, 201, 1]) + (86399 * 128 + 64).to_bytes(3, "big")
    early = fspec(1, 2, 3) + bytes([25, 201, 1]) + (64).to_bytes(3, "big")
    rec = decode_bytes(block(34, late) + block(34, early), categories=[34], date="2019-03-01")
    f = rec.frames[34]
    assert rec.editions == {34: "1.29"}
    assert list(f.day) == [0, 1]
    assert list(f.timestamp) == [pd.Timestamp("2019-03-01 23:59:59.5", tz="UTC"),
                                 pd.Timestamp("2019-03-02 00:00:00.5", tz="UTC")]
    assert rec.date == dt.date(2019, 3, 1)


def test_not_decoded_unless_asked() -> None:
    # by default CAT034 blocks are stepped over and counted as ignored bytes, not reported as errors
    data = block(34, NORTH) + block(34, SECTOR)
    rec = decode_bytes(data)
    assert rec.frames == {} and rec.errors.empty
    assert rec.ignored_blocks == {34: 2} and rec.ignored_bytes == len(data)


def test_message_types_of_later_editions_read_by_every_edition() -> None:
    # 5 solar storm (1.28+), 7 Mode S jamming strobe (1.29): same layout, the code is just a value
    recs = [fspec(1, 2) + bytes([25, 201, t]) for t in (5, 7)]
    for edition in EDITIONS:
        assert list(decode34(*recs, editions={34: edition}).message_type) == [5, 7]


@pytest.mark.parametrize("edition", EDITIONS)
def test_encoder_writes_the_hand_bytes(edition: str) -> None:
    north = encode_record(34, {
        "sac": 25, "sic": 201, "message_type": 1, "time_of_day": 36000.5,
        "antenna_rotation_period_s": 4.796875,
        "nogo": 0, "rdpc": 1, "rdp_reset": 0, "rdp_overload": 0, "transmission_overload": 1,
        "monitoring_disconnected": 0, "time_source_invalid": 1, "ssr_antenna": 1, "ssr_channels": 2,
        "ssr_overload": 0, "ssr_monitoring_disconnected": 1, "mds_antenna": 0, "mds_channels": 1,
        "mds_overload": 1, "mds_monitoring_disconnected": 0, "mds_scf_channel": 1, "mds_dlf_channel": 0,
        "mds_scf_overload": 0, "mds_dlf_overload": 1}, edition=edition)
    assert north == NORTH
    sector = encode_record(34, {
        "sac": 25, "sic": 201, "message_type": 2, "time_of_day": 36001.25, "sector_azimuth_deg": 90.0,
        "rdp_reduction_step": 3, "transmission_reduction_step": 5, "psr_circular_polarization": 1,
        "psr_reduction_step": 2, "psr_stc_map": 3, "mds_reduction_step": 4, "mds_not_autonomous": 1},
        edition=edition, extra={"070": bytes.fromhex("02000313E8")})
    assert sector == SECTOR
    geo = encode_record(34, {
        "sac": 25, "sic": 202, "message_type": 3, "window_rho_start_nm": 10.0, "window_rho_end_nm": 100.5,
        "window_theta_start_deg": 45.0, "window_theta_end_deg": 90.0, "data_filter": 3,
        "source_height_m": -5.0, "source_latitude": 45.0, "source_longitude": -90.0,
        "collimation_range_error_nm": -0.0234375, "collimation_azimuth_error_deg": 0.10986328125},
        edition=edition)
    assert geo == FILTER


def test_sector_number_and_azimuth_must_agree() -> None:
    assert encode_record(34, {"sector_number": 64, "sector_azimuth_deg": 90.0}) == fspec(4) + b"\x40"
    with pytest.raises(ValueError, match="conflicts"):
        encode_record(34, {"sector_number": 65, "sector_azimuth_deg": 90.0})
