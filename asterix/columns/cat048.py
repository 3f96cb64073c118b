"""CAT048 (monoradar target reports) columns, every edition."""

from __future__ import annotations

from .base import _COMMON_ID, NM_PER_S_TO_KT, Column, _c, _flags

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
