"""CAT048 (monoradar target reports) columns, every edition."""

from __future__ import annotations

from .base import _COMMON_ID, NM_PER_S_TO_KT, Column, _c, _flags

_SEL = "selected altitude (16 ft)"
_ABSENT = "; absent when the register's status bit says not valid"
# I048/250 Mode S registers (asterix/bds.py holds their layouts): kind "bds", float64, NaN when absent
_BDS = [
    _c("mcp_selected_altitude_ft", "250", "BDS40/MCP_ALT", "bds", unit="ft",
       doc=f"BDS 4,0 MCP/FCU {_SEL}{_ABSENT}"),
    _c("fms_selected_altitude_ft", "250", "BDS40/FMS_ALT", "bds", unit="ft",
       doc=f"BDS 4,0 FMS {_SEL}{_ABSENT}"),
    _c("baro_setting_hpa", "250", "BDS40/BARO", "bds", unit="hPa",
       doc=f"BDS 4,0 barometric pressure setting (800 + 0.1 hPa steps){_ABSENT}"),
    _c("roll_angle_deg", "250", "BDS50/ROLL", "bds", unit="deg",
       doc=f"BDS 5,0 roll angle, + right wing down (45/256 deg){_ABSENT}"),
    _c("track_angle_deg", "250", "BDS50/TRK", "bds", unit="deg",
       doc=f"BDS 5,0 true track angle, clockwise from true north, 0-360 (90/512 deg){_ABSENT}"),
    _c("bds50_ground_speed_kt", "250", "BDS50/GS", "bds", unit="kt",
       doc=f"BDS 5,0 ground speed (2 kt; the radar's own is ground_speed_kt){_ABSENT}"),
    _c("track_angle_rate_degs", "250", "BDS50/TAR", "bds", unit="deg/s",
       doc=f"BDS 5,0 track angle rate, + clockwise (1/32 deg/s){_ABSENT}"),
    _c("true_airspeed_kt", "250", "BDS50/TAS", "bds", unit="kt",
       doc=f"BDS 5,0 true airspeed (2 kt){_ABSENT}"),
    _c("magnetic_heading_deg", "250", "BDS60/HDG", "bds", unit="deg",
       doc=f"BDS 6,0 magnetic heading, 0-360 (90/512 deg){_ABSENT}"),
    _c("indicated_airspeed_kt", "250", "BDS60/IAS", "bds", unit="kt",
       doc=f"BDS 6,0 indicated airspeed (1 kt){_ABSENT}"),
    _c("mach", "250", "BDS60/MACH", "bds", unit="Mach", doc=f"BDS 6,0 Mach number (0.004){_ABSENT}"),
    _c("baro_vertical_rate_ftmin", "250", "BDS60/BAR", "bds", unit="ft/min",
       doc=f"BDS 6,0 barometric altitude rate, + climb (32 ft/min){_ABSENT}"),
    _c("inertial_vertical_rate_ftmin", "250", "BDS60/IVV", "bds", unit="ft/min",
       doc=f"BDS 6,0 inertial vertical velocity, + climb (32 ft/min){_ABSENT}"),
]

CAT048: list[Column] = [
    *_COMMON_ID,
    _c("time_of_day", "140", "", unit="s", doc="Time of day (UTC seconds since midnight)"),
    *_flags("020", {"typ": "TYP", "sim": "SIM", "rdp": "RDP", "spi": "SPI", "rab": "RAB", "tst": "TST",
                    "err": "ERR", "xpp": "XPP", "me": "ME", "mi": "MI", "foe_fri": "FOEFRI"},
            "Target report descriptor"),
    _c("rho_nm", "040", "RHO", unit="NM", doc="Measured slant range"),
    _c("theta_deg", "040", "THETA", unit="deg", doc="Measured azimuth, clockwise from north"),
    _c("mode3a", "070", "MODE3A", "octal", doc="Mode 3/A code, 4 octal digits"),
    _c("mode3a_v", "070", "V", "flag", doc="Mode 3/A not validated"),
    _c("mode3a_g", "070", "G", "flag", doc="Mode 3/A garbled"),
    _c("mode3a_l", "070", "L", "flag", doc="Mode 3/A not extracted in the last scan (smoothed)"),
    _c("flight_level", "090", "FL", unit="FL", doc="Flight level (100 ft)"),
    _c("flight_level_v", "090", "V", "flag", doc="Flight level not validated"),
    _c("flight_level_g", "090", "G", "flag", doc="Flight level garbled"),
    _c("ssr_runlength_deg", "130", "SRL/SRL", unit="deg", doc="SSR plot runlength"),
    _c("ssr_replies", "130", "SRR/SRR", "int", doc="Number of received SSR replies"),
    _c("ssr_amplitude_dbm", "130", "SAM/SAM", unit="dBm", doc="SSR reply amplitude"),
    _c("psr_runlength_deg", "130", "PRL/PRL", unit="deg", doc="PSR plot runlength"),
    _c("psr_amplitude_dbm", "130", "PAM/PAM", unit="dBm", doc="PSR plot amplitude"),
    _c("address", "220", "", "hex", doc="24-bit aircraft address, 6 upper-case hex digits"),
    _c("callsign", "240", "", "icao", doc="Aircraft identification, trailing spaces stripped"),
    _c("bds_count", "250", "", "count", doc="Number of BDS registers in I048/250"),
    *_BDS,
    _c("track_number", "161", "TRN", "int", doc="Track number"),
    _c("x_nm", "042", "X", unit="NM", doc="Calculated cartesian X (east)"),
    _c("y_nm", "042", "Y", unit="NM", doc="Calculated cartesian Y (north)"),
    _c("ground_speed_kt", "200", "GSP", unit="kt", scale=NM_PER_S_TO_KT, doc="Calculated ground speed"),
    _c("heading_deg", "200", "HDG", unit="deg", doc="Calculated heading"),
    *_flags("170", {"cnf": "CNF", "rad": "RAD", "dou": "DOU", "mah": "MAH", "cdm": "CDM", "tre": "TRE",
                    "gho": "GHO", "sup": "SUP", "tcc": "TCC"}, "Track status"),
    _c("height_3d_ft", "110", "3DH", unit="ft", doc="Height measured by a 3D radar"),
    _c("doppler_speed_ms", "120", "CAL/CAL", unit="m/s", doc="Calculated radial Doppler speed"),
    _c("warning_codes", "030", "", "codes",
       doc="I048/030 warning/error conditions: every 7-bit code the plot carries, in wire order, joined by "
       "',' ('3' split plot, '1,3'); codes include 1 multipath reply (reflection), 2 sidelobe reply, "
       "3 split plot, 4 second time around reply, 5 angel, 7 fixed PSR plot (the edition's table lists all)"),
    _c("com", "230", "COM", "flag", doc="Transponder communications capability"),
    _c("flight_status", "230", "STAT", "flag", doc="Flight status (alert, SPI, on ground)"),
]
