"""CAT062 (SDPS system track messages) columns, editions 1.16-1.21.

A tracker's output, read as tracks under test: position (WGS-84 and the system plane), velocity, track
number and status, Mode 3/A, flight levels and altitudes, the aircraft-derived data of I062/380, the
update ages of I062/290 and I062/295, mode of movement and estimated accuracies. Fields that an edition
lacks (the I062/060 V and G bits before 1.17, the I062/080 SFC/IDD/IEC bits before 1.18, MLAT before
1.20, M5I before 1.21) decode as absent there, never as 0.
"""

from __future__ import annotations

from .base import _COMMON_ID, NM_PER_S_TO_KT, Column, _c, _flags

_AGE = "Age of the last update (s) of"

CAT062: list[Column] = [
    *_COMMON_ID,
    _c("time_of_day", "070", "", unit="s", doc="Time of track information (UTC seconds since midnight)"),
    _c("service_id", "015", "", "int", doc="Service identification"),
    _c("track_number", "040", "", "int", doc="System track number (16 bits)"),
    _c("latitude", "105", "LAT", unit="deg", doc="Calculated WGS-84 latitude (180/2^25 deg)"),
    _c("longitude", "105", "LON", unit="deg", doc="Calculated WGS-84 longitude (180/2^25 deg)"),
    _c("x_m", "100", "X", unit="m", doc="Calculated position in the system plane: X (east), 0.5 m"),
    _c("y_m", "100", "Y", unit="m", doc="Calculated position in the system plane: Y (north), 0.5 m"),
    _c("vx_ms", "185", "VX", unit="m/s", doc="Calculated velocity: X component (east), 0.25 m/s"),
    _c("vy_ms", "185", "VY", unit="m/s", doc="Calculated velocity: Y component (north), 0.25 m/s"),
    _c("ax_ms2", "210", "AX", unit="m/s2", doc="Calculated acceleration: X component, 0.25 m/s2"),
    _c("ay_ms2", "210", "AY", unit="m/s2", doc="Calculated acceleration: Y component, 0.25 m/s2"),
    _c("mode3a", "060", "MODE3A", "octal", doc="Track Mode 3/A code, 4 octal digits"),
    _c("mode3a_v", "060", "V", "flag", doc="Mode 3/A not validated (1.17 on; spare in 1.16: absent)"),
    _c("mode3a_g", "060", "G", "flag", doc="Mode 3/A garbled (1.17 on; spare in 1.16: absent)"),
    _c("mode3a_changed", "060", "CH", "flag", doc="1: Mode 3/A has changed"),
    _c("callsign", "245", "CHR", "icao", also=(("380", "ID/ID"),),
       doc="Target identification (I062/245), else the downlinked one (I062/380 ID), trailing "
       "spaces stripped"),
    _c("callsign_source", "245", "STI", "int", doc="I062/245 STI: 0 callsign or registration downlinked, "
       "1 callsign not downlinked, 2 registration not downlinked, 3 invalid"),
    _c("address", "380", "ADR/ADR", "hex",
       doc="24-bit target address (I062/380 ADR), 6 upper-case hex digits"),
    _c("flight_level", "136", "", unit="FL", doc="Measured flight level: the last valid Mode C (1/4 FL)"),
    _c("geometric_altitude_ft", "130", "", unit="ft", doc="Calculated track geometric altitude (6.25 ft)"),
    _c("barometric_altitude_fl", "135", "CTB", unit="FL",
       doc="Calculated track barometric altitude (1/4 FL; QNH-corrected when barometric_altitude_qnh is 1)"),
    _c("barometric_altitude_qnh", "135", "QNH", "flag", doc="1: QNH correction applied to I062/135"),
    _c("vertical_rate_ftmin", "220", "", unit="ft/min", doc="Calculated rate of climb (+) / descent (-)"),
    # I062/080 track status: the raw bits (CNF 0 confirmed, 1 tentative)
    *_flags("080", {"mon": "MON", "spi": "SPI", "mrh": "MRH"}, "Track status"),
    _c("altitude_source", "080", "SRC", "int", doc="Track status SRC, source of I062/130: 0 none, 1 GNSS, "
       "2 3D radar, 3 triangulation, 4 height from coverage, 5 speed look-up table, 6 default, 7 MLAT"),
    *_flags("080", {"cnf": "CNF", "sim": "SIM", "tse": "TSE", "tsb": "TSB", "fpc": "FPC", "aff": "AFF",
                    "stp": "STP", "kos": "KOS", "ama": "AMA"}, "Track status"),
    _c("md4", "080", "MD4", "int", doc="Track status MD4: 0 no Mode 4 interrogation, 1 friendly, 2 unknown, "
       "3 no reply"),
    *_flags("080", {"me": "ME", "mi": "MI"}, "Track status"),
    _c("md5", "080", "MD5", "int", doc="Track status MD5: 0 no Mode 5 interrogation, 1 friendly, 2 unknown, "
       "3 no reply"),
    _c("cst", "080", "CST", "flag", doc="Track status CST: 1 coasting (age of the last track update above "
       "the system threshold)"),
    _c("cst_psr", "080", "PSR", "flag", doc="Track status PSR: 1 the last PSR update is older than the "
       "threshold"),
    _c("cst_ssr", "080", "SSR", "flag", doc="Track status SSR: 1 the last SSR update is older than the "
       "threshold"),
    _c("cst_mds", "080", "MDS", "flag", doc="Track status MDS: 1 the last Mode S update is older than the "
       "threshold"),
    _c("cst_ads", "080", "ADS", "flag", doc="Track status ADS: 1 the last ADS-B update is older than the "
       "threshold"),
    *_flags("080", {"suc": "SUC", "aac": "AAC"}, "Track status"),
    _c("sds", "080", "SDS", "int", doc="Track status SDS: 0 combined, 1 co-operative only, 2 non-cooperative "
       "only, 3 not defined"),
    _c("ems", "080", "EMS", "int", doc="Track status EMS: 0 no emergency, 1 general, 2 lifeguard/medical, "
       "3 minimum fuel, 4 no communications, 5 unlawful interference, 6 downed aircraft, 7 undefined"),
    *_flags("080", {"pft": "PFT", "fplt": "FPLT", "dupt": "DUPT", "dupf": "DUPF", "dupm": "DUPM"},
            "Track status"),
    _c("sfc", "080", "SFC", "flag", doc="Track status SFC: 1 surface target (1.18 on)"),
    _c("idd", "080", "IDD", "flag", doc="Track status IDD: 1 duplicate flight-ID (1.18 on)"),
    _c("iec", "080", "IEC", "flag", doc="Track status IEC: 1 inconsistent emergency code (1.18 on)"),
    _c("cst_mlat", "080", "MLAT", "flag", doc="Track status MLAT: 1 the last MLAT update is older than the "
       "threshold (1.20 on)"),
    _c("cst_m5", "080", "M5I", "flag",
       doc="Track status M5I: 1 the last Mode 5 interrogation update is older "
       "than the threshold (1.21)"),
    # I062/200 mode of movement
    _c("movement_transversal", "200", "TRANS", "int", doc="Mode of movement TRANS: 0 constant course, "
       "1 right turn, 2 left turn, 3 undetermined"),
    _c("movement_longitudinal", "200", "LONG", "int", doc="Mode of movement LONG: 0 constant ground speed, "
       "1 increasing, 2 decreasing, 3 undetermined"),
    _c("movement_vertical", "200", "VERT", "int", doc="Mode of movement VERT: 0 level, 1 climb, 2 descent, "
       "3 undetermined"),
    _c("altitude_discrepancy", "200", "ADF", "flag", doc="Mode of movement ADF: 1 altitude discrepancy"),
    # I062/290 system track update ages
    _c("track_age_s", "290", "TRK/TRK", unit="s", doc=f"{_AGE} the track (I062/290 TRK)"),
    _c("psr_age_s", "290", "PSR/PSR", unit="s", doc=f"{_AGE} a PSR plot (I062/290)"),
    _c("ssr_age_s", "290", "SSR/SSR", unit="s", doc=f"{_AGE} an SSR plot (I062/290)"),
    _c("mds_age_s", "290", "MDS/MDS", unit="s", doc=f"{_AGE} a Mode S plot (I062/290)"),
    _c("adsc_age_s", "290", "ADS/ADS", unit="s", doc=f"{_AGE} an ADS-C report (I062/290, 16 bits)"),
    _c("adsb_age_s", "290", "ES/ES", unit="s", doc=f"{_AGE} an ADS-B extended squitter report (I062/290 ES)"),
    _c("vdl_age_s", "290", "VDL/VDL", unit="s", doc=f"{_AGE} an ADS-B VDL Mode 4 report (I062/290)"),
    _c("uat_age_s", "290", "UAT/UAT", unit="s", doc=f"{_AGE} an ADS-B UAT report (I062/290)"),
    _c("loop_age_s", "290", "LOP/LOP", unit="s", doc=f"{_AGE} a loop detector (I062/290)"),
    _c("mlt_age_s", "290", "MLT/MLT", unit="s", doc=f"{_AGE} a multilateration report (I062/290)"),
    # I062/295 track data ages (a selection)
    _c("flight_level_age_s", "295", "MFL/MFL", unit="s",
       doc=f"{_AGE} the measured flight level (I062/295 MFL)"),
    _c("mode3a_age_s", "295", "MDA/MDA", unit="s", doc=f"{_AGE} the Mode 3/A code (I062/295 MDA)"),
    _c("magnetic_heading_age_s", "295", "MHG/MHG", unit="s", doc=f"{_AGE} the magnetic heading (I062/295)"),
    _c("ias_age_s", "295", "IAS/IAS", unit="s", doc=f"{_AGE} the indicated airspeed / Mach (I062/295)"),
    _c("tas_age_s", "295", "TAS/TAS", unit="s", doc=f"{_AGE} the true airspeed (I062/295)"),
    _c("selected_altitude_age_s", "295", "SAL/SAL", unit="s", doc=f"{_AGE} the selected altitude (I062/295)"),
    _c("baro_vertical_rate_age_s", "295", "BVR/BVR", unit="s",
       doc=f"{_AGE} the barometric vertical rate (I062/295)"),
    _c("roll_angle_age_s", "295", "RAN/RAN", unit="s", doc=f"{_AGE} the roll angle (I062/295)"),
    _c("ground_speed_age_s", "295", "GSP/GSP", unit="s", doc=f"{_AGE} the ground speed (I062/295)"),
    _c("adsb_position_age_s", "295", "POS/POS", unit="s", doc=f"{_AGE} the ADS-B position (I062/295 POS)"),
    _c("adsb_geometric_altitude_age_s", "295", "GAL/GAL", unit="s",
       doc=f"{_AGE} the ADS-B geometric altitude (I062/295 GAL)"),
    # I062/380 aircraft derived data (a selection)
    _c("magnetic_heading_deg", "380", "MHG/MHG", unit="deg", doc="Magnetic heading (I062/380 MHG)"),
    _c("true_airspeed_kt", "380", "TAS/TAS", unit="kt", doc="True airspeed (I062/380 TAS)"),
    _c("indicated_airspeed_kt", "380", "IAR/IAR", unit="kt",
       doc="Indicated airspeed (I062/380 IAR, 1 kt; the "
       "IAS subfield, IAS or Mach by its IM bit, is not decoded)"),
    _c("mach", "380", "MAC/MAC", unit="Mach", doc="Mach number (I062/380 MAC, 0.008)"),
    _c("selected_altitude_ft", "380", "SAL/ALT", unit="ft", doc="Selected altitude (I062/380 SAL, 25 ft)"),
    _c("selected_altitude_source", "380", "SAL/SRC", "int", doc="I062/380 SAL SRC: 0 unknown, 1 aircraft "
       "altitude, 2 FCU/MCP, 3 FMS (meaningful when selected_altitude_sas is 1)"),
    _c("selected_altitude_sas", "380", "SAL/SAS", "flag", doc="I062/380 SAL SAS: 1 source information given"),
    _c("final_selected_altitude_ft", "380", "FSS/ALT", unit="ft",
       doc="Final state selected altitude (I062/380 FSS, 25 ft)"),
    _c("baro_vertical_rate_ftmin", "380", "BVR/BVR", unit="ft/min",
       doc="Barometric vertical rate (I062/380)"),
    _c("geo_vertical_rate_ftmin", "380", "GVR/GVR", unit="ft/min", doc="Geometric vertical rate (I062/380)"),
    _c("roll_angle_deg", "380", "RAN/RAN", unit="deg", doc="Roll angle (I062/380 RAN, 0.01 deg)"),
    _c("track_angle_deg", "380", "TAN/TAN", unit="deg",
       doc="Track angle reported by the aircraft (I062/380)"),
    _c("adsb_ground_speed_kt", "380", "GS/GS", unit="kt", scale=NM_PER_S_TO_KT,
       doc="Ground speed reported by the aircraft (I062/380 GS)"),
    _c("emitter_category", "380", "EMC/EMC", "int", doc="Emitter category (I062/380 EMC)"),
    _c("adsb_latitude", "380", "POS/LAT", unit="deg", doc="Position reported by the aircraft (I062/380 POS)"),
    _c("adsb_longitude", "380", "POS/LON", unit="deg",
       doc="Position reported by the aircraft (I062/380 POS)"),
    _c("adsb_geometric_altitude_ft", "380", "GAL/GAL", unit="ft", doc="Geometric altitude reported by the "
       "aircraft (I062/380 GAL, 6.25 ft)"),
    _c("barometric_pressure_setting_mb", "380", "BPS/BPS", unit="mb",
       doc="Barometric pressure setting (I062/380 BPS, 0.1 mb)"),
    _c("com", "380", "COM/COM", "int", doc="Transponder communications capability (I062/380 COM)"),
    _c("flight_status", "380", "COM/STAT", "int", doc="Flight status (I062/380 COM STAT): alert, SPI, "
       "on ground"),
    # I062/500 estimated accuracies
    _c("accuracy_x_m", "500", "APC/X", unit="m", doc="Estimated accuracy of the position: X (I062/500 APC)"),
    _c("accuracy_y_m", "500", "APC/Y", unit="m", doc="Estimated accuracy of the position: Y (I062/500 APC)"),
    _c("accuracy_xy_cov_m", "500", "COV/COV", unit="m", doc="XY covariance component (I062/500 COV, signed)"),
    _c("accuracy_latitude_deg", "500", "APW/LAT", unit="deg", doc="Estimated accuracy of the WGS-84 "
       "latitude (I062/500 APW)"),
    _c("accuracy_longitude_deg", "500", "APW/LON", unit="deg", doc="Estimated accuracy of the WGS-84 "
       "longitude (I062/500 APW)"),
    _c("accuracy_geometric_altitude_ft", "500", "AGA/AGA", unit="ft",
       doc="Estimated accuracy of the geometric altitude (I062/500 AGA)"),
    _c("accuracy_barometric_altitude_fl", "500", "ABA/ABA", unit="FL",
       doc="Estimated accuracy of the barometric altitude (I062/500 ABA)"),
    _c("accuracy_vx_ms", "500", "ATV/X", unit="m/s", doc="Estimated accuracy of the velocity: X (I062/500)"),
    _c("accuracy_vy_ms", "500", "ATV/Y", unit="m/s", doc="Estimated accuracy of the velocity: Y (I062/500)"),
    _c("accuracy_vertical_rate_ftmin", "500", "ARC/ARC", unit="ft/min",
       doc="Estimated accuracy of the rate of climb/descent (I062/500 ARC)"),
    # I062/340 the last measurement that updated the track
    _c("measured_sac", "340", "SID/SAC", "int", doc="SAC of the sensor of the last measurement (I062/340)"),
    _c("measured_sic", "340", "SID/SIC", "int", doc="SIC of the sensor of the last measurement (I062/340)"),
    _c("measured_rho_nm", "340", "POS/RHO", unit="NM", doc="Measured slant range (I062/340 POS)"),
    _c("measured_theta_deg", "340", "POS/THETA", unit="deg", doc="Measured azimuth (I062/340 POS)"),
    _c("measured_report_type", "340", "TYP/TYP", "int", doc="I062/340 TYP: 0 no detection, 1 PSR, 2 SSR, "
       "3 SSR + PSR, 4 Mode S all-call, 5 Mode S roll-call, 6 all-call + PSR, 7 roll-call + PSR"),
    # I062/390 flight plan related data (numbers only)
    _c("fpps_sac", "390", "TAG/SAC", "int", doc="SAC of the flight plan processing system (I062/390 TAG)"),
    _c("fpps_sic", "390", "TAG/SIC", "int", doc="SIC of the flight plan processing system (I062/390 TAG)"),
    _c("cleared_flight_level", "390", "CFL/CFL", unit="FL",
       doc="Current cleared flight level (I062/390 CFL)"),
    # I062/270 target size and orientation
    _c("target_length_m", "270", "LENGTH", unit="m", doc="Target length (I062/270)"),
    _c("target_orientation_deg", "270", "ORIENTATION", unit="deg", doc="Target orientation (I062/270)"),
    _c("target_width_m", "270", "WIDTH", unit="m", doc="Target width (I062/270)"),
    _c("mode2", "120", "MODE2", "octal", doc="Track Mode 2 code, 4 octal digits"),
]
