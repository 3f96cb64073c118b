"""CAT001 (monoradar plots and tracks, editions 1.2-1.4) columns: one list for both UAPs.

A column whose item is in both UAPs (I001/040, I001/070, I001/090, I001/141 ...) reads it in either;
the track-only items (I001/161, I001/042, I001/200, I001/170) are absent (NaN / <NA>) on plots.
"""

from __future__ import annotations

from .base import _COMMON_ID, NM_PER_S_TO_KT, Column, _c, _flags

CAT001: list[Column] = [
    *_COMMON_ID,
    Column("time_of_day", (), "float", unit="s",
           doc="Whole time of day (UTC seconds since midnight): I001/141 placed in the 512 s window nearest "
           "the time of day (I002/030) of the same radar's last CAT002 message before it; NaN when none "
           "dates it (Recording.untimed says why; docs/decoding/editions.md)"),
    _c("truncated_time_of_day", "141", "", unit="s",
       doc="I001/141: the time of day modulo 512 s, as sent (1/128 s)"),
    _c("typ", "020", "TYP", "flag", doc="Target report descriptor TYP: 0 plot, 1 track (chooses the UAP)"),
    _c("sim", "020", "SIM", "flag", doc="1: simulated plot or track"),
    _c("ssr_psr", "020", "SSRPSR", "int",
       doc="Detection in the last scan: 0 none, 1 sole primary, 2 sole secondary, 3 combined"),
    _c("ant", "020", "ANT", "flag", doc="Antenna of the report: 0 antenna 1, 1 antenna 2"),
    _c("spi", "020", "SPI", "flag", doc="1: special position identification"),
    _c("rab", "020", "RAB", "flag", doc="1: plot or track from a fixed transponder"),
    _c("tst", "020", "TST", "flag", doc="1: test target"),
    _c("me", "020", "ME", "flag", doc="1: military emergency"),
    _c("mi", "020", "MI", "flag", doc="1: military identification"),
    _c("ds1ds2", "020", "DS1DS2", "int",
       doc="Emergency code: 0 default, 1 unlawful interference (7500), 2 radio failure (7600), 3 emergency "
       "(7700)"),
    _c("rho_nm", "040", "RHO", unit="NM", doc="Measured slant range (1/128 NM)"),
    _c("theta_deg", "040", "THETA", unit="deg", doc="Measured azimuth, clockwise from north (360/2^16 deg)"),
    _c("x_nm", "042", "X", unit="NM",
       doc="Track's calculated cartesian X (east), at the default 1/64 NM (radar-dependent factor f = 0)"),
    _c("y_nm", "042", "Y", unit="NM", doc="Track's calculated cartesian Y (north), 1/64 NM as x_nm"),
    _c("mode3a", "070", "MODE3A", "octal", doc="Mode 3/A code, 4 octal digits"),
    _c("mode3a_v", "070", "V", "flag", doc="Mode 3/A not validated"),
    _c("mode3a_g", "070", "G", "flag", doc="Mode 3/A garbled"),
    _c("mode3a_l", "070", "L", "flag", doc="Mode 3/A smoothed by a local tracker (not from the reply)"),
    _c("flight_level", "090", "HGT", unit="FL", doc="Mode C height (1/4 FL, two's complement)"),
    _c("flight_level_v", "090", "V", "flag", doc="Mode C not validated"),
    _c("flight_level_g", "090", "G", "flag", doc="Mode C garbled"),
    _c("mode2", "050", "MODE2", "octal", doc="Mode 2 code, 4 octal digits"),
    _c("doppler_speed_kt", "120", "", unit="kt", scale=NM_PER_S_TO_KT,
       doc="Measured radial Doppler speed, at the default 2^-8 NM/s = 14.0625 kt (radar-dependent factor "
       "f = 6)"),
    _c("received_power_dbm", "131", "", unit="dBm", doc="Received power of the plot"),
    _c("track_number", "161", "", "int", doc="Track/plot number (I001/161, tracks)"),
    _c("ground_speed_kt", "200", "GSP", unit="kt", scale=NM_PER_S_TO_KT,
       doc="Track's calculated ground speed (2^-14 NM/s)"),
    _c("heading_deg", "200", "HDG", unit="deg", doc="Track's calculated heading (360/2^16 deg)"),
    *_flags("170", {"con": "CON", "rad": "RAD", "man": "MAN", "dou": "DOU", "rdpc": "RDPC", "gho": "GHO",
                    "tre": "TRE"}, "Track status"),
    *_flags("150", {"xa": "XA", "xc": "XC", "x2": "X2"}, "X pulse present in the reply to mode"),
    _c("warning_codes", "030", "", "codes",
       doc="I001/030 warning/error conditions: every 7-bit code, in wire order, joined by ',' (1 garbled "
       "reply, 2 reflection, 3 sidelobe reply, 4 split plot, 5 second time around, 6 angels, 7 terrestrial "
       "vehicle; 64-127 application dependent)"),
]
