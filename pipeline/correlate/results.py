"""Result types passed from the correlation steps to the report writers.

Each window belongs to one aircraft and one sensor pair: ``radar_sensor`` (a radar's sensor_id) and
``reference_sensor`` (the ADS-B source, its ground stations joined by "+", or a second radar). In the
slot and summary columns "radar" means the radar sensor and "adsb" the reference sensor.

Correlation reads measurement frames (pipeline.model.schema). ``start_tod``, ``end_tod`` and the slots'
``time_of_day`` count seconds from midnight UTC of the run's earliest report (above 86400 after
midnight); ``start``, ``end`` and ``timestamp`` are UTC, None/NaT when the recording had no date.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import pandas as pd

# Columns of WindowResult.slots
SLOT_COLUMNS = [
    "slot", "time_of_day", "timestamp", "radar_lat", "radar_lon", "adsb_lat", "adsb_lon",
    "radar_count", "adsb_count", "radar_filled", "adsb_filled", "sep_m",
]
# Columns of WindowResult.lags
LAG_COLUMNS = ["lag", "ncc_lat", "ncc_lon", "pearson_lat", "pearson_lon"]
# The numbers a report leads with (pipeline.correlate.matched): the radar's reports against the reference
# at their own times, over the slots both reported, ADS-B jumps left out
MATCHED_KEYS = ["matched_reports", "matched_sep_median_m", "matched_sep_rms_m", "matched_sep_p95_m",
                "matched_along_mean_m", "matched_along_se_m", "matched_cross_mean_m", "matched_cross_se_m",
                "matched_time_offset_s"]
# With --quality: the radar's errors against ADS-B in its own terms over the window (None without)
WINDOW_QUALITY_KEYS = ["quality_reports", "range_error_mean_m", "range_error_std_m", "azimuth_error_mean_deg",
                       "azimuth_error_std_deg"]
# With --quality: per radar, its accuracy and fitted biases against ADS-B over the whole run
RADAR_KEYS = ["radar", "radar_sensor", "n_reports", "horizontal_error_rms_m", "range_error_std_m",
              "azimuth_error_std_deg", "range_bias_m", "range_bias_se_m", "range_gain_ppm",
              "range_gain_se_ppm", "azimuth_bias_deg", "azimuth_bias_se_deg", "time_bias_s", "time_bias_se_s",
              "note"]
# Keys of WindowResult.summary, in report order (the JSON fields of a window): identity, the lead numbers
# and verdict, then the thesis's measures
SUMMARY_KEYS = [
    "callsign", "address", "window", "radar_sensor", "reference_sensor", "start_tod", "end_tod", "start",
    "end", *MATCHED_KEYS, *WINDOW_QUALITY_KEYS, "verdict", "slots",
    "radar_before", "radar_after", "adsb_before", "adsb_after", "radar_duplicates", "adsb_duplicates",
    "adsb_jumps", "radar_filled_slots", "adsb_filled_slots",
    "ncc0_lat", "ncc0_lon", "ncc_peak_lag_lat", "ncc_peak_lag_lon",
    "pearson0_lat", "pearson0_lon", "pearson_peak_lag_lat", "pearson_peak_lag_lon",
    "pearson_peak_at_limit_lat", "pearson_peak_at_limit_lon",
    "pearson_lag_unidentified_lat", "pearson_lag_unidentified_lon",
    "sep_mean_m", "sep_median_m", "sep_rms_m", "sep_p95_m", "sep_max_m", "sep_slots", "sep_rms_all_m",
]


@dataclass
class WindowResult:
    """One overlap window of one aircraft: its slots, its lag table and its summary row."""

    summary: dict
    slots: pd.DataFrame
    lags: pd.DataFrame


@dataclass
class SkippedWindow:
    """A window that was found but not correlated, and why."""

    callsign: str
    address: str
    start_tod: float
    end_tod: float
    reason: str
    radar_sensor: str = ""  # sensor_id of the radar
    reference_sensor: str = ""  # sensor_id(s) of the ADS-B source or of the second radar


@dataclass
class CorrelationRun:
    """Everything one ``msdc correlate`` run produced, for the report, JSON and figure writers."""

    windows: list[WindowResult] = field(default_factory=list)
    skipped: list[SkippedWindow] = field(default_factory=list)
    parameters: dict = field(default_factory=dict)  # options, editions, software version, run time
    inputs: list[dict] = field(default_factory=list)  # {"path", "sha256", "bytes", "format"}
    filters: dict = field(default_factory=dict)  # filter name -> reports removed (issue 4 filters)
    extra_sheets: dict[str, pd.DataFrame] = field(default_factory=dict)  # e.g. Quality, Radar accuracy
    radars: list[dict] = field(default_factory=list)  # --quality: each radar's accuracy, biases (RADAR_KEYS)
