"""Status and service message columns: CAT019 (MLAT system status), CAT023 (ground station and service
status), CAT025 (ground system status), CAT063 (sensor status), CAT065 (SDPS service status).

Each keeps the time and the message type (CAT063 has no message type item) and the health fields that say
a station, sensor or service was degraded, as the raw bits of the specification (their codes in each
column's meaning). Repetitive lists (remote sensors, error codes, statistics counters) are counted.
"""

from __future__ import annotations

from .base import _COMMON_ID, Column, _c

_TIME = "Time of day of the message (UTC seconds since midnight)"

CAT019: list[Column] = [
    *_COMMON_ID,
    _c("time_of_day", "140", "", unit="s", doc=_TIME),
    _c("message_type", "000", "", "int", doc="I019/000: 1 start of update cycle, 2 periodic status, "
       "3 event-triggered status"),
    _c("nogo", "550", "NOGO", "int",
       doc="System status NOGO: 0 operational, 1 degraded, 2 NOGO, 3 undefined"),
    _c("overload", "550", "OVL", "flag", doc="System status OVL: 1 overload"),
    _c("time_source_invalid", "550", "TSV", "flag", doc="System status TSV: 1 time source invalid"),
    _c("test_target_failure", "550", "TTF", "flag", doc="System status TTF: 1 test target failure"),
    *[_c(f"tp{i}_{what}", "551", f"TP{i}{bit}", "flag", doc=f"Tracking processor {i}: {meaning}")
      for i in range(1, 5) for what, bit, meaning in (("exec", "A", "0 standby, 1 exec"),
                                                      ("good", "B", "0 faulted, 1 good"))],
    _c("remote_sensor_count", "552", "", "count", doc="Remote sensors listed in I019/552 (their detail is "
       "not decoded)"),
    *[_c(f"ref_transponder_{i}", "553", f"REFTR{i}", "int",
         doc=f"Reference transponder {i} status: 1 warning, 2 faulted, 3 good (0 not given)")
      for i in range(1, 5)],
    _c("reference_latitude", "600", "LAT", unit="deg",
       doc="WGS-84 latitude of the MLT system reference point"),
    _c("reference_longitude", "600", "LON", unit="deg",
       doc="WGS-84 longitude of the MLT system reference point"),
    _c("reference_height_m", "610", "", unit="m", doc="Height of the MLT system reference point (WGS-84)"),
    _c("geoid_undulation_m", "620", "", unit="m", doc="WGS-84 undulation at the reference point"),
]

CAT023: list[Column] = [
    *_COMMON_ID,
    _c("time_of_day", "070", "", unit="s", doc=_TIME),
    _c("message_type", "000", "", "int", doc="I023/000 report type: 1 ground station status, 2 service "
       "status, 3 service statistics"),
    _c("service_id", "015", "SID", "int", doc="Service identification (I023/015 SID)"),
    _c("service_type", "015", "STYP", "int", doc="Type of service: 1 ADS-B VDL4, 2 ADS-B 1090 ES, 3 ADS-B "
       "UAT, 4 TIS-B VDL4, 5 TIS-B 1090 ES, 6 TIS-B UAT, 7 FIS-B VDL4, 8 GRAS VDL4, ..."),
    _c("nogo", "100", "NOGO", "flag", doc="Ground station NOGO: 1 data must not be used operationally"),
    _c("dp_overload", "100", "ODP", "flag", doc="Ground station ODP: 1 data processor overload"),
    _c("transmission_overload", "100", "OXT", "flag", doc="Ground station OXT: 1 ground interface overload"),
    _c("monitoring_connected", "100", "MSC", "flag", doc="Ground station MSC: 1 monitoring system connected, "
       "0 not connected or unknown"),
    _c("time_source_invalid", "100", "TSV", "flag", doc="Ground station TSV: 1 time source invalid"),
    _c("spoofing", "100", "SPO", "flag", doc="Ground station SPO: 1 potential spoofing attack"),
    _c("track_renumbered", "100", "RN", "flag", doc="Ground station RN: 1 track numbering has restarted"),
    _c("status_period_s", "100", "GSSP", unit="s", doc="Ground station status reporting period"),
    _c("report_period_s", "101", "RP", unit="s", doc="Report period for CAT021 reports (0.5 s)"),
    _c("service_class", "101", "SC", "int", doc="Service class: 0 no information, 1 NRA class"),
    _c("service_status_period_s", "101", "SSRP", unit="s", doc="Service status reporting period"),
    _c("operational_range_nm", "200", "", unit="NM", doc="Operational range of the ground station"),
    _c("service_status", "110", "STAT", "int", doc="Service status: 0 unknown, 1 failed, 2 disabled, "
       "3 degraded, 4 normal, 5 initialisation"),
    _c("statistics_count", "120", "", "count", doc="Statistics counters in I023/120 (not decoded)"),
]

CAT025: list[Column] = [
    *_COMMON_ID,
    _c("time_of_day", "070", "", unit="s", doc=_TIME),
    _c("message_type", "000", "RTYP", "int", doc="I025/000 RTYP: report type (the raw 7-bit code)"),
    _c("event_driven", "000", "RG", "flag", doc="I025/000 RG: 0 periodic, 1 event-driven report"),
    _c("message_id", "200", "", "int", doc="Message identification (I025/200, 24 bits)"),
    _c("service_id", "015", "", "int", doc="Service identification"),
    _c("service_designator", "020", "", "icao", doc="Service designator (6-bit ICAO characters)"),
    _c("nogo", "100", "NOGO", "flag", doc="NOGO: 1 data must not be used operationally"),
    _c("operational_state", "100", "OPS", "int", doc="OPS: 0 operational, 1 operational but standby, "
       "2 maintenance"),
    _c("system_service_status", "100", "SSTAT", "int", doc="SSTAT: 0 running, 1 failed, 2 degraded, "
       "3 undefined"),
    _c("system_status", "100", "SYSTAT", "int", doc="SYSTAT: 0 running / OK, 1 failed, 2 degraded, "
       "3 undefined"),
    _c("service_status", "100", "SESTAT", "int", doc="SESTAT: 0 OK, 1 failed, 2 degraded, 3 undefined"),
    _c("error_count", "105", "", "count", doc="System and service error codes in I025/105 (not decoded)"),
    _c("component_count", "120", "", "count", doc="Component status entries in I025/120 (not decoded)"),
    _c("statistics_count", "140", "", "count", doc="Statistics counters in I025/140 (not decoded)"),
    _c("reference_latitude", "600", "LAT", unit="deg", doc="WGS-84 latitude of the system reference point"),
    _c("reference_longitude", "600", "LON", unit="deg", doc="WGS-84 longitude of the system reference point"),
    _c("reference_height_m", "610", "", unit="m", doc="Height of the system reference point (WGS-84)"),
]

CAT063: list[Column] = [
    *_COMMON_ID,
    _c("time_of_day", "030", "", unit="s", doc=_TIME),
    _c("service_id", "015", "", "int", doc="Service identification"),
    _c("sensor_sac", "050", "SAC", "int", doc="SAC of the sensor the message is about"),
    _c("sensor_sic", "050", "SIC", "int", doc="SIC of the sensor the message is about"),
    _c("sensor_status", "060", "CON", "int", doc="Sensor CON: 0 operational, 1 degraded, 2 initialization, "
       "3 not currently connected"),
    _c("psr_nogo", "060", "PSR", "flag", doc="1: PSR NOGO"),
    _c("ssr_nogo", "060", "SSR", "flag", doc="1: SSR NOGO"),
    _c("mds_nogo", "060", "MDS", "flag", doc="1: Mode S NOGO"),
    _c("ads_nogo", "060", "ADS", "flag", doc="1: ADS NOGO"),
    _c("mlt_nogo", "060", "MLT", "flag", doc="1: multilateration NOGO"),
    _c("operational_use_inhibited", "060", "OPS", "flag",
       doc="OPS: 1 operational use of the system inhibited"),
    _c("dp_overload", "060", "ODP", "flag", doc="ODP: 1 data processor overload"),
    _c("transmission_overload", "060", "OXT", "flag", doc="OXT: 1 transmission subsystem overload"),
    _c("monitoring_disconnected", "060", "MSC", "flag", doc="MSC: 1 monitoring system disconnected"),
    _c("time_source_invalid", "060", "TSV", "flag", doc="TSV: 1 time source invalid"),
    _c("no_plots", "060", "NPW", "flag", doc="NPW: 1 no plots being received"),
    _c("time_stamping_bias_ms", "070", "", unit="ms", doc="Time stamping bias"),
    _c("ssr_range_gain", "080", "SRG", doc="SSR / Mode S range gain (1e-5)"),
    _c("ssr_range_bias_nm", "080", "SRB", unit="NM", doc="SSR / Mode S range bias"),
    _c("ssr_azimuth_bias_deg", "081", "", unit="deg", doc="SSR / Mode S azimuth bias"),
    _c("psr_range_gain", "090", "PRG", doc="PSR range gain (1e-5)"),
    _c("psr_range_bias_nm", "090", "PRB", unit="NM", doc="PSR range bias"),
    _c("psr_azimuth_bias_deg", "091", "", unit="deg", doc="PSR azimuth bias"),
    _c("psr_elevation_bias_deg", "092", "", unit="deg", doc="PSR elevation bias"),
]

CAT065: list[Column] = [
    *_COMMON_ID,
    _c("time_of_day", "030", "", unit="s", doc=_TIME),
    _c("message_type", "000", "", "int", doc="I065/000: 1 SDPS status, 2 end of batch, 3 service status "
       "report"),
    _c("service_id", "015", "", "int", doc="Service identification"),
    _c("batch_number", "020", "", "int", doc="Batch number"),
    _c("nogo", "040", "NOGO", "int", doc="SDPS NOGO: 0 operational, 1 degraded, 2 not currently connected, "
       "3 unknown"),
    _c("overload", "040", "OVL", "flag", doc="SDPS OVL: 1 overload"),
    _c("time_source_invalid", "040", "TSV", "flag", doc="SDPS TSV: 1 invalid time source"),
    _c("processing_system", "040", "PSS", "int", doc="SDPS PSS: 0 not applicable, 1-3 SDPS-1/2/3 selected"),
    _c("track_renumbered", "040", "STTN", "flag", doc="SDPS STTN: track re-numbering indication"),
    _c("service_status_report", "050", "", "int", doc="I065/050: 1 service degradation, 2 degradation "
       "ended, 3 main radar out of service, 4 interrupted by the operator, 5 interrupted by contingency, "
       "6 ready for restart after contingency, 7 ended by the operator, 8 failure of user main radar, ..."),
]
