"""CAT021 (ADS-B target reports) columns: the 2.x and the 0.2x families."""

from __future__ import annotations

from .base import _COMMON_ID, NM_PER_S_TO_KT, Column, _c, _flags

_PRIORITY_CODES = ("0 no emergency / not reported, 1 general emergency, 2 lifeguard / medical, "
                   "3 minimum fuel, 4 no communications, 5 unlawful interference")

_CAT021_SHARED = [
    _c("address", "080", "", "hex", doc="24-bit target address, 6 upper-case hex digits"),
    _c("callsign", "170", "", "icao", doc="Target identification, trailing spaces stripped"),
    _c("mode3a", "070", "MODE3A", "octal", doc="Mode 3/A code, 4 octal digits"),
    _c("flight_level", "145", "", unit="FL", doc="Flight level (barometric, 100 ft)"),
    _c("geometric_height_ft", "140", "", unit="ft", doc="Geometric height (2.x) / altitude (0.2x)"),
    _c("track_angle_deg", "160", "TA", unit="deg", doc="Track angle, clockwise from true north"),
    _c("magnetic_heading_deg", "152", "", unit="deg", doc="Magnetic heading"),
    _c("roll_angle_deg", "230", "", unit="deg", doc="Roll angle"),
    _c("emitter_category", "020", "", "int", doc="Emitter category code"),
]

CAT021_V2: list[Column] = [
    *_COMMON_ID,
    _c("time_of_day", "071", "", unit="s", also=(("073", ""),),
       doc="Time of applicability for position (I021/071), else of reception for position (I021/073)"),
    _c("time_applicability_position", "071", "", unit="s", doc="I021/071"),
    _c("time_applicability_velocity", "072", "", unit="s", doc="I021/072"),
    _c("time_reception_position", "073", "", unit="s", doc="I021/073"),
    _c("time_reception_velocity", "075", "", unit="s", doc="I021/075"),
    _c("time_report_transmission", "077", "", unit="s", doc="I021/077"),
    *_flags("040", {"atp": "ATP", "arc": "ARC", "rc": "RC", "rab": "RAB", "dcr": "DCR", "gbs": "GBS",
                    "sim": "SIM", "tst": "TST", "saa": "SAA", "cl": "CL"}, "Target report descriptor"),
    _c("latitude", "131", "LAT", unit="deg", also=(("130", "LAT"),),
       doc="WGS-84 latitude, high resolution (I021/131) else I021/130"),
    _c("longitude", "131", "LON", unit="deg", also=(("130", "LON"),),
       doc="WGS-84 longitude, high resolution (I021/131) else I021/130"),
    *_CAT021_SHARED,
    _c("ground_speed_kt", "160", "GS", unit="kt", scale=NM_PER_S_TO_KT, doc="Airborne ground speed"),
    _c("track_number", "161", "TRNUM", "int", doc="Track number"),
    _c("nucp_nic", "090", "NUCPNIC", "int", doc="NUCp (DO-260) or NIC (DO-260A/B)"),
    _c("nucr_nacv", "090", "NUCRNACV", "int", doc="NUCr or NACv"),
    _c("nacp", "090", "NACP", "int", doc="Navigation accuracy category for position"),
    _c("sil", "090", "SIL", "int", doc="Surveillance/source integrity level"),
    _c("nic_baro", "090", "NICBARO", "int", doc="NIC for barometric altitude"),
    _c("mops_version", "210", "VN", "int", doc="MOPS version (0 DO-260, 1 DO-260A, 2 DO-260B)"),
    _c("link_technology", "210", "LTT", "int", doc="Link technology type (2 = 1090 ES)"),
    _c("true_airspeed_kt", "151", "TAS", unit="kt", doc="True airspeed"),
    _c("service_id", "015", "", "int", doc="Service identification"),
    _c("receiver_id", "400", "", "int", doc="Receiver ID"),
    _c("baro_vertical_rate_ftmin", "155", "BVR", unit="ft/min", doc="Barometric vertical rate"),
    _c("geo_vertical_rate_ftmin", "157", "GVR", unit="ft/min", doc="Geometric vertical rate"),
    _c("priority_status", "200", "PS", "int", doc="I021/200 PS: " + _PRIORITY_CODES + ", 6 downed aircraft"),
    _c("surveillance_status", "200", "SS", "int", doc="I021/200 SS: 0 no condition, 1 permanent alert "
       "(emergency), 2 temporary alert (Mode 3/A change other than emergency), 3 SPI set"),
    _c("icf", "200", "ICF", "flag", doc="I021/200 ICF: 1 intent change flag raised"),
    _c("lnav_not_engaged", "200", "LNAV", "flag", doc="I021/200 LNAV: 1 LNAV mode not engaged, 0 engaged"),
    _c("me", "200", "ME", "flag", doc="I021/200 ME: 1 military emergency (2.2 on; a spare bit in 2.1)"),
]

CAT021_V0: list[Column] = [
    *_COMMON_ID,
    _c("time_of_day", "030", "", unit="s", doc="Time of day (I021/030)"),
    *_flags("040", {"atp": "ATP", "arc": "ARC", "rab": "RAB", "dcr": "DCR", "gbs": "GBS", "sim": "SIM",
                    "tst": "TST", "saa": "SAA", "spi": "SPI"}, "Target report descriptor"),
    _c("latitude", "130", "LAT", unit="deg", doc="WGS-84 latitude (I021/130)"),
    _c("longitude", "130", "LON", unit="deg", doc="WGS-84 longitude (I021/130)"),
    *_CAT021_SHARED,
    _c("ground_speed_kt", "160", "GS", unit="kt", scale=NM_PER_S_TO_KT, doc="Ground speed (signed in 0.2x)"),
    _c("fom_ac", "090", "AC", "int", doc="Figure of merit: ACAS capabilities"),
    _c("fom_mn", "090", "MN", "int", doc="Figure of merit: multiple navigation aids"),
    _c("fom_dc", "090", "DC", "int", doc="Figure of merit: differential correction"),
    _c("fom_pa", "090", "PA", "int", doc="Figure of merit: position accuracy, the raw 4 bits 0-15 (the "
       "0.2x specs print a signed quantity: an erratum, see docs/decoding/editions.md)"),
    _c("priority_status", "200", "", "int", doc="I021/200 Target Status: " + _PRIORITY_CODES),
    _c("signal_amplitude", "131", "", "int", doc="Signal amplitude (0.26 only)"),
    _c("true_airspeed_kt", "151", "", unit="kt", doc="True airspeed"),
    _c("baro_vertical_rate_ftmin", "155", "", unit="ft/min", doc="Barometric vertical rate"),
    _c("geo_vertical_rate_ftmin", "157", "", unit="ft/min", doc="Geometric vertical rate"),
]
