"""The typed-frame schema: which item field feeds each column, per category family, as data.

Each column lists one or more sources ``(item, field path)``; the first source present in a record
wins (I021/131 before I021/130, for instance). Bit positions, LSBs and signedness come from the
edition table, so one column definition serves every edition in which the field exists; "int" and "flag"
columns are the raw bits, never sign-extended (I021/090 PA, printed signed in 0.2x, reads 0-15).
"""

from __future__ import annotations

from dataclasses import dataclass

NM_PER_S_TO_KT = 3600.0


@dataclass(frozen=True)
class Column:
    """One frame column: its name, sources, how raw bits become a value, and its documentation."""

    name: str
    sources: tuple[tuple[str, tuple[str, ...]], ...]
    kind: str = "float"  # float (LSB-scaled) | int | flag | octal | icao | hex | count | codes
    scale: float = 1.0  # applied after the LSB, for unit conversion (NM/s -> kt)
    unit: str = ""
    doc: str = ""


def _c(name: str, item: str, path: str, kind: str = "float", unit: str = "", doc: str = "",
       scale: float = 1.0, also: tuple[tuple[str, str], ...] = ()) -> Column:
    sources = ((item, tuple(path.split("/")) if path else ()),) + tuple(
        (i, tuple(p.split("/")) if p else ()) for i, p in also)
    return Column(name, sources, kind, scale, unit, doc)


def _flags(item: str, names: dict[str, str], doc: str) -> list[Column]:
    return [_c(col, item, field, "flag", doc=f"{doc} {field}") for col, field in names.items()]


_COMMON_ID = [
    _c("sac", "010", "SAC", "int", doc="System Area Code"),
    _c("sic", "010", "SIC", "int", doc="System Identification Code"),
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


CAT034: list[Column] = [
    *_COMMON_ID,
    _c("time_of_day", "030", "", unit="s", doc="Time of day (UTC seconds since midnight) of the message"),
    _c("message_type", "000", "", "int", doc="Message type: 1 north marker, 2 sector crossing, 3 geographical"
       " filtering, 4 jamming strobe, 5 solar storm (1.28+), 6 SSR / 7 Mode S jamming strobe (1.29)"),
    _c("sector_number", "020", "", "int", doc="Sector number: the 8 most significant bits of the antenna "
       "azimuth (0-255)"),
    _c("sector_azimuth_deg", "020", "", unit="deg", doc="The sector number as an azimuth (360/256 deg each)"),
    _c("antenna_rotation_period_s", "041", "", unit="s",
       doc="Antenna rotation period (I034/041 'Antenna Rotation Speed': time per revolution)"),
    _c("nogo", "050", "COM/NOGO", "flag", doc="1: operational use of the system is inhibited"),
    _c("rdpc", "050", "COM/RDPC", "flag", doc="Radar data processor chain selected: 0 RDPC-1, 1 RDPC-2"),
    _c("rdp_reset", "050", "COM/RDPR", "flag", doc="1: reset/restart of the selected RDP chain"),
    _c("rdp_overload", "050", "COM/OVLRDP", "flag", doc="1: radar data processor overload"),
    _c("transmission_overload", "050", "COM/OVLXMT", "flag", doc="1: transmission subsystem overload"),
    _c("monitoring_disconnected", "050", "COM/MSC", "flag", doc="1: monitoring system disconnected"),
    _c("time_source_invalid", "050", "COM/TSV", "flag", doc="1: time source invalid"),
    _c("psr_antenna", "050", "PSR/ANT", "flag", doc="PSR selected antenna: 0 antenna 1, 1 antenna 2"),
    _c("psr_channels", "050", "PSR/CHAB", "int", doc="PSR channels: 0 none, 1 A, 2 B, 3 diversity A+B"),
    _c("psr_overload", "050", "PSR/OVL", "flag", doc="1: PSR overload"),
    _c("psr_monitoring_disconnected", "050", "PSR/MSC", "flag", doc="1: PSR monitoring system disconnected"),
    _c("ssr_antenna", "050", "SSR/ANT", "flag", doc="SSR selected antenna: 0 antenna 1, 1 antenna 2"),
    _c("ssr_channels", "050", "SSR/CHAB", "int", doc="SSR channels: 0 none, 1 A, 2 B, 3 invalid"),
    _c("ssr_overload", "050", "SSR/OVL", "flag", doc="1: SSR overload"),
    _c("ssr_monitoring_disconnected", "050", "SSR/MSC", "flag", doc="1: SSR monitoring system disconnected"),
    _c("mds_antenna", "050", "MDS/ANT", "flag", doc="Mode S selected antenna: 0 antenna 1, 1 antenna 2"),
    _c("mds_channels", "050", "MDS/CHAB", "int", doc="Mode S channels: 0 none, 1 A, 2 B, 3 illegal"),
    _c("mds_overload", "050", "MDS/OVLSUR", "flag", doc="1: Mode S surveillance overload"),
    _c("mds_monitoring_disconnected", "050", "MDS/MSC", "flag", doc="1: Mode S monitoring disconnected"),
    _c("mds_scf_channel", "050", "MDS/SCF", "flag", doc="Surveillance co-ordination: 0 channel A, 1 B"),
    _c("mds_dlf_channel", "050", "MDS/DLF", "flag", doc="Data link function: 0 channel A, 1 B"),
    _c("mds_scf_overload", "050", "MDS/OVLSCF", "flag", doc="1: surveillance co-ordination overload"),
    _c("mds_dlf_overload", "050", "MDS/OVLDLF", "flag", doc="1: data link function overload"),
    _c("rdp_reduction_step", "060", "COM/REDRDP", "int", doc="RDP overload reduction step (0 none, 1-7)"),
    _c("transmission_reduction_step", "060", "COM/REDXMT", "int",
       doc="Transmission overload reduction step in use (0 none, 1-7)"),
    _c("psr_circular_polarization", "060", "PSR/POL", "flag", doc="PSR polarization: 0 linear, 1 circular"),
    _c("psr_reduction_step", "060", "PSR/REDRAD", "int", doc="PSR overload reduction step (0 none, 1-7)"),
    _c("psr_stc_map", "060", "PSR/STC", "int", doc="PSR sensitivity time control map in use: 0-3 = map 1-4"),
    _c("ssr_reduction_step", "060", "SSR/REDRAD", "int", doc="SSR overload reduction step (0 none, 1-7)"),
    _c("mds_reduction_step", "060", "MDS/REDRAD", "int", doc="Mode S overload reduction step (0 none)"),
    _c("mds_not_autonomous", "060", "MDS/CLU", "flag", doc="Mode S cluster: 0 autonomous, 1 not"),
    _c("message_counters", "070", "", "count", doc="Message counters in I034/070 (not decoded)"),
    _c("window_rho_start_nm", "100", "RHOST", unit="NM", doc="Generic polar window: range start"),
    _c("window_rho_end_nm", "100", "RHOEND", unit="NM", doc="Generic polar window: range end"),
    _c("window_theta_start_deg", "100", "THETAST", unit="deg", doc="Generic polar window: azimuth start"),
    _c("window_theta_end_deg", "100", "THETAEND", unit="deg", doc="Generic polar window: azimuth end"),
    _c("data_filter", "110", "", "int", doc="Data filter (1 weather, 2 jamming strobe, 3 PSR...)"),
    _c("source_height_m", "120", "HGT", unit="m", doc="Height of the data source (WGS-84)"),
    _c("source_latitude", "120", "LAT", unit="deg", doc="WGS-84 latitude of the data source"),
    _c("source_longitude", "120", "LON", unit="deg", doc="WGS-84 longitude of the data source"),
    _c("collimation_range_error_nm", "090", "RNG", unit="NM", doc="Collimation error: range"),
    _c("collimation_azimuth_error_deg", "090", "AZM", unit="deg", doc="Collimation error: azimuth"),
]


def columns_for(category: int, edition: str) -> list[Column]:
    """The column list of a category edition."""
    if category == 48:
        return CAT048
    if category == 21:
        return CAT021_V0 if edition.startswith("0.") else CAT021_V2
    if category == 34:
        return CAT034
    raise KeyError(category)


FAMILIES = {"CAT048 (all editions)": CAT048, "CAT021 2.x (2.1-2.7)": CAT021_V2,
            "CAT021 0.2x (0.23-0.26)": CAT021_V0, "CAT034 (1.27-1.29)": CAT034}
KIND_DTYPES = {"float": "float64 (NaN if absent)", "int": "Int32", "flag": "Int8", "count": "Int16",
               "octal": "text (categorical)", "hex": "text (categorical)", "icao": "text (categorical)",
               "codes": "text (categorical)"}


def markdown_schema() -> str:
    """The column reference (docs/columns.md), generated from the tables above."""
    lines = ["# Frame columns", "", "Generated from `asterix/columns.py` by "
             "`python -c 'from msdc.asterix.columns import markdown_schema; print(markdown_schema())'`.",
             "Every frame also has `day` (int64: days after the recording's first day; in raw streams the "
             "first report's day in file order, -1 for a late report before the file's first midnight), "
             "`timestamp` "
             "(datetime64[ns, UTC], NaT when the date is unknown), `block` (data block index in the file: "
             "blocks of every category counted from 0, whatever the chunk size `iter_read` decodes in) "
             "and `offset` (byte offset of the record in the file).",
             "",
             "Identification text (`icao` columns: `callsign`) holds the 6-bit ICAO characters A-Z, space "
             "and 0-9, trailing spaces stripped. All-zero codes (code 0 is no character) and all spaces are "
             "absent (`<NA>`); any other code outside that set shows as `?`, never as a letter. Beside it, "
             "`callsign_hex` (text, categorical) keeps the item's raw 48 bits as 12 upper-case hex digits "
             "whenever the record carries the item.", "",
             "Code lists (`codes` columns: `warning_codes`, I048/030) hold every code of a repetitive item "
             "in wire order, as decimal numbers joined by `,` (`3`, `1,3`), `<NA>` when the record lacks the "
             "item. A first code and a count would drop the codes after the first; text keeps them all and "
             "filters in one line: `f.warning_codes.str.contains(r\"(?:^|,)3(?:,|$)\", na=False)` selects "
             "the plots carrying code 3 (split plot), `f.warning_codes.str.split(\",\").explode()` gives one "
             "row per code. Its cost is small: a presence check over the records (about 10 ms per million "
             "records), then one reading per distinct item.", ""]
    for family, cols in FAMILIES.items():
        lines += [f"## {family}", "", "| column | unit | dtype | source | meaning |", "|---|---|---|---|---|"]
        for c in cols:
            src = " else ".join(f"I{item}" + (f"/{'/'.join(path)}" if path else "")
                                for item, path in c.sources)
            lines.append(f"| `{c.name}` | {c.unit} | {KIND_DTYPES[c.kind]} | {src} | {c.doc} |")
        lines.append("")
    return "\n".join(lines)
