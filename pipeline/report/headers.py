"""The column headers people read in msdc's workbooks: one table, keyed by the snake_case column name.

Only the workbook writers use it: JSON, CSV and Parquet keep the snake_case names. A header is the
column's label (``LABELS``) followed by its unit in parentheses: the unit the workbook formats the
column's numbers in (``formats.column_unit``, the shared unit table), else the few written here
(``UNIT_TEXT``: time zones of date-times, lags in slots). A name with no label prints as it is; a test
runs every command on the fixtures and fails on such a column, so a new column gets its header.
"""

from __future__ import annotations

from msdc.pipeline.report.formats import UNITS, column_unit

# name -> label, without the unit (the unit follows from the unit table or UNIT_TEXT)
LABELS: dict[str, str] = {
    # who and when: windows, sensors, aircraft
    "window": "Window", "callsign": "Call sign", "address": "Address", "sensors": "Sensors",
    "radar_sensor": "Radar sensor", "reference_sensor": "Reference sensor", "sensor": "Sensor",
    "radar": "Radar", "aircraft": "Aircraft", "sac": "SAC", "sic": "SIC", "start": "Start", "end": "End",
    "reason": "Reason", "note": "Note", "section": "Section", "key": "Key", "value": "Value",
    # Correlation and Slots sheets
    "lag": "Lag", "lag_s": "Lag", "ncc_lat": "NCC latitude", "ncc_lon": "NCC longitude",
    "pearson_lat": "Pearson latitude", "pearson_lon": "Pearson longitude", "slot": "Slot",
    "time_utc": "Slot start", "radar_lat": "Radar latitude", "radar_lon": "Radar longitude",
    "adsb_lat": "Reference latitude", "adsb_lon": "Reference longitude", "radar_count": "Radar reports",
    "adsb_count": "Reference reports", "radar_filled": "Radar slot filled",
    "adsb_filled": "Reference slot filled", "sep_m": "Separation",
    # Summary: what each window shows (report to reference), with --quality the radar's errors in it
    "matched_reports": "Matched reports", "matched_sep_median_m": "Report separation median",
    "matched_sep_rms_m": "Report separation RMS", "matched_sep_p95_m": "Report separation 95th percentile",
    "matched_along_mean_m": "Along-track mean", "matched_along_se_m": "Along-track SE",
    "matched_cross_mean_m": "Cross-track mean", "matched_cross_se_m": "Cross-track SE",
    "matched_time_offset_s": "Time offset", "quality_reports": "Reports compared with ADS-B",
    # Summary: the thesis's measures
    "slots": "Slots", "radar_before": "Radar before", "radar_after": "Radar after",
    "adsb_before": "ADS-B before", "adsb_after": "ADS-B after", "radar_duplicates": "Radar duplicates",
    "adsb_duplicates": "ADS-B duplicates", "adsb_jumps": "ADS-B jumps",
    "radar_filled_slots": "Radar filled slots", "adsb_filled_slots": "ADS-B filled slots",
    "ncc0_lat": "NCC(0) latitude", "ncc0_lon": "NCC(0) longitude",
    "ncc_peak_lag_lat": "NCC peak lag latitude", "ncc_peak_lag_lon": "NCC peak lag longitude",
    "pearson0_lat": "Pearson(0) latitude", "pearson0_lon": "Pearson(0) longitude",
    "pearson_peak_lag_lat": "Pearson peak lag latitude", "pearson_peak_lag_lon": "Pearson peak lag longitude",
    "pearson_peak_at_limit_lat": "Pearson peak at limit, latitude",
    "pearson_peak_at_limit_lon": "Pearson peak at limit, longitude",
    "pearson_lag_unidentified_lat": "Pearson lag unidentified, latitude",
    "pearson_lag_unidentified_lon": "Pearson lag unidentified, longitude",
    "sep_mean_m": "Slot separation mean", "sep_median_m": "Slot separation median",
    "sep_rms_m": "Slot separation RMS", "sep_p95_m": "Slot separation 95th percentile",
    "sep_max_m": "Slot separation max", "sep_slots": "Separation slots",
    "sep_rms_all_m": "Slot separation RMS, every slot",
    # radar accuracy and biases against ADS-B
    "n_reports": "Reports compared", "n_rejected": "Rejected reports", "n_overhead": "Overhead reports",
    "range_error_mean_m": "Range error mean", "range_error_std_m": "Range error SD",
    "range_error_rms_m": "Range error RMS", "azimuth_error_mean_deg": "Azimuth error mean",
    "azimuth_error_std_deg": "Azimuth error SD", "azimuth_error_rms_deg": "Azimuth error RMS",
    "along_track_mean_m": "Along-track error mean", "along_track_std_m": "Along-track error SD",
    "along_track_rms_m": "Along-track error RMS", "cross_track_mean_m": "Cross-track error mean",
    "cross_track_std_m": "Cross-track error SD", "cross_track_rms_m": "Cross-track error RMS",
    "horizontal_error_mean_m": "Horizontal error mean", "horizontal_error_std_m": "Horizontal error SD",
    "horizontal_error_rms_m": "Horizontal error RMS", "range_bias_m": "Range bias",
    "range_bias_se_m": "Range bias SE", "range_gain_ppm": "Range gain", "range_gain_se_ppm": "Range gain SE",
    "azimuth_bias_deg": "Azimuth bias", "azimuth_bias_se_deg": "Azimuth bias SE", "time_bias_s": "Time bias",
    "time_bias_se_s": "Time bias SE", "range_residual_rms_m": "Range residual RMS",
    "azimuth_residual_rms_deg": "Azimuth residual RMS",
    "chi2_per_dof": "Chi-square per degree of freedom", "site_offset_m": "Site offset",
    "fit_trusted": "Fit trusted", "adsb_nacp_median": "ADS-B NACp median",
    "adsb_nacp_95_m": "ADS-B NACp 95 % bound",
    # quality: reports, update intervals, gaps, jumps, ADS-B quality indicators
    "reports": "Reports", "on_surface": "On the surface", "duplicates_removed": "Duplicates removed",
    "reports_after_dedup": "Reports after de-duplication", "first_tod": "First report time of day",
    "last_tod": "Last report time of day", "first_utc": "First report", "last_utc": "Last report",
    "intervals": "Intervals", "interval_min_s": "Interval min", "interval_median_s": "Interval median",
    "interval_p95_s": "Interval 95th percentile", "interval_max_s": "Interval max, gaps included",
    "interval_max_within_gap_s": "Interval max within the gap rule", "gaps": "Gaps",
    "longest_gap_s": "Longest gap", "reappearances": "Reappearances after 1 h",
    "speed_missing": "Speed missing", "speed_zero": "Speed zero",
    "speed_missing_or_zero": "Speed missing or zero", "speed_missing_or_zero_pct": "Speed missing or zero",
    "jumps": "Jumps", "nucp_below_5_pct": "NUCp below 5", "nic_below_6_pct": "NIC below 6",
    "low_integrity_pct": "Low integrity", "mops_versions": "MOPS versions",
    "bin_start_s": "Interval from", "bin_end_s": "Interval to", "gap_start_tod": "Gap start time of day",
    "gap_end_tod": "Gap end time of day", "gap_start_utc": "Gap start", "gap_end_utc": "Gap end",
    "gap_duration_s": "Gap duration", "reappeared_after_1h": "Reappeared after 1 h",
    "time_of_day": "Time of day", "utc": "Time", "latitude": "Latitude", "longitude": "Longitude",
    "fit_latitude": "Fitted latitude", "fit_longitude": "Fitted longitude", "jump_size_m": "Jump size",
    "indicator": "Indicator", "share_pct": "Share", "bin_start_tod": "Bin start time of day",
    "bin_start_utc": "Bin start", "nucp_nic_median": "NUCp/NIC median", "nacp_median": "NACp median",
    "nucr_nacv_median": "NUCr/NACv median", "sil_median": "SIL median",
    "fom_pa_median": "Figure of merit PA median",
    # conflicts: alerts, losses of separation, warning times
    "aircraft_a": "Aircraft A", "callsign_a": "Call sign A", "mode3a_a": "Mode 3/A A",
    "aircraft_b": "Aircraft B", "callsign_b": "Call sign B", "mode3a_b": "Mode 3/A B",
    "horizon_s": "Horizon", "flight_level_a": "Flight level A", "flight_level_b": "Flight level B",
    "peak_pc": "Peak probability of conflict", "time_of_peak": "Peak time", "loss_start": "Loss start",
    "false_alert": "False alert", "time_to_cpa_s": "Time to CPA", "cpa_time": "CPA time",
    "cpa_horizontal_nm": "CPA horizontal", "cpa_vertical_ft": "CPA vertical", "duration_s": "Duration",
    "began_inside": "Began inside", "min_horizontal_nm": "Min horizontal", "time_of_min": "Time of min",
    "vertical_at_min_ft": "Vertical at min", "min_vertical_ft": "Min vertical",
    "alert_start": "Alert start", "warning_s": "Warning",
    # evaluate: the scorecard's columns (its own sheet prints them) and its per-aircraft and per-bin tables
    "sector": "Sector", "requirement": "Requirement", "ci_low": "95 % interval, low",
    "ci_high": "95 % interval, high", "n": "Sample size", "threshold": "Threshold", "verdict": "Verdict",
    "clause": "Clause", "checked": "Threshold checked against the standard", "notes": "Notes",
    "expected_updates": "Expected updates", "detected_updates": "Detected updates",
    "pd": "Probability of detection", "range_from_nm": "Range from", "range_to_nm": "Range to",
    "parameters": "Parameters", "built_by": "Reference built by",
    "self_reference_share": "Self-reference share", "surface_share": "Surface share",
    "two_targets_on": "Two targets on", "two_targets": "Two targets",
    "reference_samples": "Reference samples", "errors_judged": "Errors judged",
    "rms_error_m": "RMS position error", "windows": "Windows", "window_from": "Window from",
    "window_to": "Window to", "expected": "Expected", "detected": "Detected",
    "class": "Class", "low": "Band from", "high": "Band to", "low_nm": "Band from", "high_nm": "Band to",
    "rms_m": "RMS error", "p95_m": "95th percentile error", "max_m": "Maximum error", "x_low": "x from",
    "x_high": "x to", "y_low": "y from", "y_high": "y to",
    "enough": "Enough to show (20 expected or more)", "azimuth_from_deg": "Azimuth from",
    "azimuth_to_deg": "Azimuth to", "fl_from": "Flight level from", "fl_to": "Flight level to",
    "height_from_ft": "Height from", "height_to_ft": "Height to",
    # quality: where a multilateration's or surface radar's reference point lies (Reference points)
    "sensor_id": "Sensor id", "reference": "Measured against", "pairs": "Report pairs",
    "east_offset_m": "East offset", "north_offset_m": "North offset", "rotation_deg": "Rotation",
    "scatter_m": "Scatter about the fit", "point_latitude": "Sensor-file point latitude",
    "point_longitude": "Sensor-file point longitude", "corrected_latitude": "Corrected point latitude",
    "corrected_longitude": "Corrected point longitude",
}

_DATETIMES = ("start", "end", "time_utc", "first_utc", "last_utc", "gap_start_utc", "gap_end_utc", "utc",
              "bin_start_utc", "time_of_peak", "loss_start", "cpa_time", "time_of_min", "alert_start")
_IN_SLOTS = ("lag", "ncc_peak_lag_lat", "ncc_peak_lag_lon", "pearson_peak_lag_lat", "pearson_peak_lag_lon")
# units the unit table does not give: date-times (UTC, or a UTC clock time when the date is unknown), lags
UNIT_TEXT: dict[str, str] = {**dict.fromkeys(_DATETIMES, "UTC"), **dict.fromkeys(_IN_SLOTS, "slots")}


def header_unit(name: str) -> str:
    """The unit a column's header shows: UNIT_TEXT's, else the unit table's label ("" for none)."""
    if name in UNIT_TEXT:
        return UNIT_TEXT[name]
    unit = column_unit(name)
    return UNITS[unit].label if unit else ""


def workbook_header(name: str) -> str:
    """The header a workbook prints for column ``name``: its label and unit, ``Range error SD (m)``; a
    name with no label as it is (``has_header`` says which)."""
    label = LABELS.get(name)
    if label is None:
        return name
    unit = header_unit(name)
    return f"{label} ({unit})" if unit else label


def has_header(name: str) -> bool:
    """Whether ``name`` has a label of its own (workbook_header would otherwise print it as it is)."""
    return name in LABELS


def column_name(header: str) -> str:
    """The snake_case name of a workbook header (workbook_header's inverse; a header without a label is
    its own name): how a reader of a workbook finds a column by the name JSON, CSV and Parquet use."""
    return _NAMES.get(header, header)


_NAMES: dict[str, str] = {workbook_header(name): name for name in LABELS}
