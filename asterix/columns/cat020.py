"""CAT020 (multilateration and wide-area multilateration target reports) columns, 1.9-1.11."""

from __future__ import annotations

from .base import _COMMON_ID, Column, _c

_TECH = ("raw I020/020 bit; the printed table reads 0 = {0} multilateration, 1 = no {0} multilateration "
         "(the bit is kept as sent)")

CAT020: list[Column] = [
    *_COMMON_ID,
    _c("time_of_day", "140", "", unit="s", doc="Time of day (UTC seconds since midnight) of the report"),
    _c("message_type", "000", "", "int", doc="Always <NA>: CAT020 has no message type item (every record is "
       "a target report); the column is there so that every CAT010/CAT020 frame has it"),
    _c("tech_ssr", "020", "SSR", "flag", doc=_TECH.format("non-Mode S 1090 MHz")),
    _c("tech_ms", "020", "MS", "flag", doc=_TECH.format("Mode S 1090 MHz")),
    _c("tech_hf", "020", "HF", "flag", doc=_TECH.format("HF")),
    _c("tech_vdl4", "020", "VDL4", "flag", doc=_TECH.format("VDL Mode 4")),
    _c("tech_uat", "020", "UAT", "flag", doc=_TECH.format("UAT")),
    _c("tech_dme", "020", "DME", "flag", doc=_TECH.format("DME/TACAN")),
    _c("tech_ot", "020", "OT", "flag", doc=_TECH.format("other technology")),
    _c("rab", "020", "RAB", "flag", doc="1: report from a field monitor (element transponder)"),
    _c("spi", "020", "SPI", "flag", doc="1: special position identification"),
    _c("chn", "020", "CHN", "flag", doc="Chain: 0 chain 1, 1 chain 2"),
    _c("gbs", "020", "GBS", "flag", doc="1: transponder ground bit set"),
    _c("crt", "020", "CRT", "flag", doc="1: corrupted replies in multilateration"),
    _c("sim", "020", "SIM", "flag", doc="1: simulated target report"),
    _c("tst", "020", "TST", "flag", doc="1: test target"),
    _c("cf", "020", "CF", "int", doc="Configuration (1.10 on; <NA> in 1.9): 0 24-bit ICAO address, "
       "1 non-ICAO 24-bit address, 2 non-ADS-B message, 3 information not available"),
    _c("latitude", "041", "LAT", unit="deg", doc="WGS-84 latitude (I020/041, 180/2^25 deg)"),
    _c("longitude", "041", "LON", unit="deg", doc="WGS-84 longitude (I020/041)"),
    _c("x_m", "042", "X", unit="m", doc="Cartesian x (east) from the system's reference point (I020/042)"),
    _c("y_m", "042", "Y", unit="m", doc="Cartesian y (north) from the system's reference point (I020/042)"),
    _c("track_number", "161", "TRN", "int", doc="Track number"),
    _c("cnf", "170", "CNF", "flag", doc="Track status: 1 track in initiation phase, 0 confirmed"),
    _c("tre", "170", "TRE", "flag", doc="Track status: 1 last report for a track"),
    _c("cst", "170", "CST", "flag", doc="Track status: 1 extrapolated (1.9) / coasted (1.10 on)"),
    _c("cdm", "170", "CDM", "int", doc="Climbing/descending mode: 0 maintaining, 1 climbing, 2 descending, "
       "3 invalid"),
    _c("mah", "170", "MAH", "flag", doc="Track status: 1 horizontal manoeuvre"),
    _c("sth", "170", "STH", "flag", doc="Track status: 0 measured position, 1 smoothed position"),
    _c("gho", "170", "GHO", "flag", doc="Track status: 1 ghost track"),
    _c("mode3a", "070", "MODE3A", "octal", doc="Mode 3/A code, 4 octal digits"),
    _c("mode3a_v", "070", "V", "flag", doc="Mode 3/A not validated"),
    _c("mode3a_g", "070", "G", "flag", doc="Mode 3/A garbled"),
    _c("mode3a_l", "070", "L", "flag", doc="Mode 3/A not extracted during the last update period"),
    _c("vx_ms", "202", "VX", unit="m/s", doc="Calculated velocity x (east)"),
    _c("vy_ms", "202", "VY", unit="m/s", doc="Calculated velocity y (north)"),
    _c("flight_level", "090", "FL", unit="FL", doc="Flight level (100 ft), 14-bit two's complement"),
    _c("flight_level_v", "090", "V", "flag", doc="Flight level not validated"),
    _c("flight_level_g", "090", "G", "flag", doc="Flight level garbled"),
    _c("address", "220", "", "hex", doc="24-bit target address, 6 upper-case hex digits"),
    _c("callsign", "245", "CHR", "icao", doc="Target identification, trailing spaces stripped"),
    _c("sti", "245", "STI", "int", doc="Identification type: 0 not downlinked, 1 registration downlinked, "
       "2 call sign downlinked, 3 not defined"),
    _c("measured_height_ft", "110", "", unit="ft", doc="Measured height in local Cartesian coordinates"),
    _c("geometric_height_ft", "105", "", unit="ft", doc="Geometric height above the WGS-84 ellipsoid"),
    _c("ax_ms2", "210", "AX", unit="m/s^2", doc="Calculated acceleration x"),
    _c("ay_ms2", "210", "AY", unit="m/s^2", doc="Calculated acceleration y"),
    _c("vehicle_fleet", "300", "", "int", doc="Vehicle fleet identification (0 unknown, 1 ATC equipment "
       "maintenance, 2 airport maintenance, 3 fire, ... 16 follow me)"),
    _c("trouble", "310", "TRB", "flag", doc="Pre-programmed message: 1 in trouble"),
    _c("preprogrammed_message", "310", "MSG", "int", doc="Pre-programmed message: 1 towing aircraft, "
       "2 follow me, 3 runway check, 4 emergency operation, 5 work in progress"),
    _c("dop_x", "500", "DOP/X", doc="I020/500 DOP of position, x component (LSB 0.25)"),
    _c("dop_y", "500", "DOP/Y", doc="I020/500 DOP of position, y component (LSB 0.25)"),
    _c("dop_xy", "500", "DOP/XY", doc="I020/500 DOP of position, 'correlation XY' (LSB 0.25, unsigned as "
       "printed)"),
    _c("sigma_x_m", "500", "SDP/X", unit="m", doc="I020/500 standard deviation of the x position"),
    _c("sigma_y_m", "500", "SDP/Y", unit="m", doc="I020/500 standard deviation of the y position"),
    _c("sdp_xy", "500", "SDP/XY", doc="I020/500 SDP 'correlation XY' (LSB 0.25, unsigned, no unit as "
       "printed): decoded, not used by the measurement model (its meaning is not stated)"),
    _c("sigma_height_m", "500", "SDH/SDH", unit="m", doc="I020/500 standard deviation of the geometric "
       "height"),
    _c("bds_count", "250", "", "count", doc="Number of BDS registers in I020/250"),
    _c("com", "230", "COM", "int", doc="Transponder communications capability (I020/230)"),
    _c("flight_status", "230", "STAT", "int", doc="Flight status: 0 no alert no SPI airborne, 1 on ground, "
       "2 alert airborne, 3 alert on ground, 4 alert SPI, 5 SPI, 7 not yet extracted"),
    _c("warning_codes", "030", "", "codes",
       doc="I020/030 warning/error conditions: every 7-bit code, in wire order, joined by ',' (1 multipath "
       "reply, 3 split plot, 10 phantom SSR plot, 11 non-matching Mode 3/A, 12 abnormal Mode C/altitude, "
       "15 transponder anomaly, 16 duplicated or illegal Mode S address, ...)"),
    _c("mode2", "050", "MODE2", "octal", doc="Mode 2 code, 4 octal digits"),
    _c("mode1", "055", "MODE1", "int", doc="Mode 1 code (raw 5 bits)"),
]
