"""CAT010 (monosensor surface movement data: surface radar and airport multilateration) columns, 1.1.

One category carries several sensor kinds: I010/020 TYP says per report which (0 SSR multilateration,
1 Mode S multilateration, 2 ADS-B, 3 PSR, 4 magnetic loop, 5 HF multilateration, 6 not defined, 7 other).
I010/000 says whether a record is a target report (1) or a status message (2-4).
"""

from __future__ import annotations

from .base import _COMMON_ID, NM_PER_S_TO_KT, Column, _c

CAT010: list[Column] = [
    *_COMMON_ID,
    _c("time_of_day", "140", "", unit="s", doc="Time of day (UTC seconds since midnight) of the report"),
    _c("message_type", "000", "", "int", doc="Message type: 1 target report, 2 start of update cycle, "
       "3 periodic status message, 4 event-triggered status message"),
    _c("typ", "020", "TYP", "int", doc="I010/020 TYP, the sensor kind of the report: 0 SSR multilateration, "
       "1 Mode S multilateration, 2 ADS-B, 3 PSR (surface radar), 4 magnetic loop, 5 HF multilateration, "
       "6 not defined, 7 other types"),
    _c("dcr", "020", "DCR", "flag", doc="1: differential correction (ADS-B)"),
    _c("chn", "020", "CHN", "flag", doc="Chain: 0 chain 1, 1 chain 2"),
    _c("gbs", "020", "GBS", "flag", doc="1: transponder ground bit set"),
    _c("crt", "020", "CRT", "flag", doc="1: corrupted replies in multilateration"),
    _c("sim", "020", "SIM", "flag", doc="1: simulated target report"),
    _c("tst", "020", "TST", "flag", doc="1: test target"),
    _c("rab", "020", "RAB", "flag", doc="1: report from a field monitor (fixed transponder)"),
    _c("lop", "020", "LOP", "int", doc="Loop status (magnetic loops): 0 undetermined, 1 loop start, "
       "2 loop finish"),
    _c("tot", "020", "TOT", "int", doc="Type of target: 0 undetermined, 1 aircraft, 2 ground vehicle, "
       "3 helicopter"),
    _c("spi", "020", "SPI", "flag", doc="1: special position identification"),
    _c("latitude", "041", "LAT", unit="deg", doc="WGS-84 latitude (I010/041)"),
    _c("longitude", "041", "LON", unit="deg", doc="WGS-84 longitude (I010/041)"),
    _c("rho_m", "040", "RHO", unit="m", doc="Measured range from the sensor (I010/040)"),
    _c("theta_deg", "040", "TH", unit="deg", doc="Measured azimuth, clockwise from north (I010/040)"),
    _c("x_m", "042", "X", unit="m", doc="Cartesian x (east) from the system's reference point (I010/042)"),
    _c("y_m", "042", "Y", unit="m", doc="Cartesian y (north) from the system's reference point (I010/042)"),
    _c("ground_speed_kt", "200", "GSP", unit="kt", scale=NM_PER_S_TO_KT,
       doc="Calculated ground speed (I010/200, NM/s x 3600)"),
    _c("track_angle_deg", "200", "TRA", unit="deg", doc="Calculated track angle, clockwise from north"),
    _c("vx_ms", "202", "VX", unit="m/s", doc="Calculated velocity x (east), I010/202 (LSB 0.25 m/s: the "
       "printed 1/16 is an erratum, see docs/decoding/editions.md)"),
    _c("vy_ms", "202", "VY", unit="m/s", doc="Calculated velocity y (north), I010/202 (LSB 0.25 m/s)"),
    _c("track_number", "161", "TRK", "int", doc="Track number"),
    _c("cnf", "170", "CNF", "flag", doc="Track status: 1 track in initialisation phase, 0 confirmed"),
    _c("tre", "170", "TRE", "flag", doc="Track status: 1 last report for a track"),
    _c("cst", "170", "CST", "int", doc="Track status: extrapolation, 0 none, 1 predictable (sensor refresh "
       "period), 2 predictable in a masked area, 3 unpredictable absence of detection"),
    _c("mah", "170", "MAH", "flag", doc="Track status: 1 horizontal manoeuvre"),
    _c("tcc", "170", "TCC", "flag", doc="Track status: 0 tracking in the sensor plane, 1 slant range "
       "corrected and projected to a plane tangent at the sensor"),
    _c("sth", "170", "STH", "flag", doc="Track status: 0 measured position, 1 smoothed position"),
    _c("tom", "170", "TOM", "int", doc="Type of movement: 0 unknown, 1 taking off, 2 landing, 3 other"),
    _c("dou", "170", "DOU", "int", doc="Doubt: 0 none, 1 doubtful correlation, 2 in clutter, 3 loss of "
       "accuracy, 4 in clutter, 5 unstable track, 6 previously coasted"),
    _c("mrs", "170", "MRS", "int", doc="Merge/split: 0 undetermined, 1 merged by association, 2 merged by "
       "non-association, 3 split track"),
    _c("gho", "170", "GHO", "flag", doc="Track status: 1 ghost track"),
    _c("mode3a", "060", "MODE3A", "octal", doc="Mode 3/A code, 4 octal digits"),
    _c("mode3a_v", "060", "V", "flag", doc="Mode 3/A not validated"),
    _c("mode3a_g", "060", "G", "flag", doc="Mode 3/A garbled"),
    _c("mode3a_l", "060", "L", "flag", doc="Mode 3/A not extracted during the last scan"),
    _c("address", "220", "", "hex", doc="24-bit target address, 6 upper-case hex digits"),
    _c("callsign", "245", "CHR", "icao", doc="Target identification, trailing spaces stripped"),
    _c("sti", "245", "STI", "int", doc="Identification type: 0 downlinked from the transponder, 1 call sign "
       "not downlinked, 2 registration not downlinked"),
    _c("bds_count", "250", "", "count", doc="Number of Mode S MB data registers in I010/250"),
    _c("vehicle_fleet", "300", "", "int", doc="Vehicle fleet identification (0 unknown, 1 ATC equipment "
       "maintenance, 2 airport maintenance, 3 fire, ... 16 follow me)"),
    _c("flight_level", "090", "FL", unit="FL", doc="Flight level (100 ft), 14-bit two's complement"),
    _c("flight_level_v", "090", "V", "flag", doc="Flight level not validated"),
    _c("flight_level_g", "090", "G", "flag", doc="Flight level garbled"),
    _c("measured_height_ft", "091", "", unit="ft", doc="Measured height (I010/091)"),
    _c("target_length_m", "270", "LENGTH", unit="m", doc="Target length"),
    _c("target_orientation_deg", "270", "ORIENTATION", unit="deg",
       doc="Target orientation: where its nose points, clockwise from north"),
    _c("target_width_m", "270", "WIDTH", unit="m", doc="Target width"),
    _c("nogo", "550", "NOGO", "int",
       doc="System status (status messages): 0 operational, 1 degraded, 2 NOGO"),
    _c("overload", "550", "OVL", "flag", doc="System status: 1 overload"),
    _c("time_source_invalid", "550", "TSV", "flag", doc="System status: 1 time source invalid"),
    _c("diversity_degraded", "550", "DIV", "flag", doc="System status: 1 diversity degraded"),
    _c("test_target_failure", "550", "TTF", "flag", doc="System status: 1 test target failure"),
    _c("trouble", "310", "TRB", "flag", doc="Pre-programmed message: 1 in trouble"),
    _c("preprogrammed_message", "310", "MSG", "int", doc="Pre-programmed message: 1 towing aircraft, "
       "2 follow me, 3 runway check, 4 emergency operation, 5 work in progress"),
    _c("sigma_x_m", "500", "DEVX", unit="m", doc="Standard deviation of the x position (I010/500)"),
    _c("sigma_y_m", "500", "DEVY", unit="m", doc="Standard deviation of the y position (I010/500)"),
    _c("cov_xy_m2", "500", "COVXY", unit="m^2", doc="I010/500 COVXY, two's complement, LSB 0.25 (the "
       "printout's unit is m; a covariance is in m^2): decoded, not used by the measurement model"),
    _c("presence_count", "280", "", "count", doc="Number of elementary presences in I010/280"),
    _c("amplitude", "131", "", "int", doc="Amplitude of the primary plot (raw 0-255)"),
    _c("ax_ms2", "210", "AX", unit="m/s^2", doc="Calculated acceleration x"),
    _c("ay_ms2", "210", "AY", unit="m/s^2", doc="Calculated acceleration y"),
]
