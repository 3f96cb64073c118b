"""One table of column -> unit -> display format, shared by the workbook, the stdout table and the figures.

A column's unit comes from its exact name (``COLUMN_UNITS``), else from the first matching name pattern
(``_UNIT_PATTERNS``); each unit has one Excel number format and one count of decimals for text output.
"""

from __future__ import annotations

import re
from dataclasses import dataclass


@dataclass(frozen=True)
class Unit:
    """How a unit is shown: Excel number format, decimals in text, and a short label for headers."""

    excel: str
    decimals: int
    label: str


UNITS: dict[str, Unit] = {
    "deg": Unit("0.0000", 4, "deg"),          # angles and WGS-84 coordinates
    "point_deg": Unit("0.0000000", 7, "deg"), # a sensor's reference point, to the centimetre it is typed in
    "coef": Unit("0.000000", 6, ""),          # correlation coefficients
    "m": Unit("0.0", 1, "m"),                 # distances
    "nm": Unit("0.000", 3, "NM"),
    "kt": Unit("0.0", 1, "kt"),
    "ft": Unit("0", 0, "ft"),
    "s": Unit("0.000", 3, "s"),               # durations and intervals
    "ppm": Unit("0.0", 1, "ppm"),
    "pct": Unit("0.0", 1, "%"),
    "count": Unit("0", 0, ""),                # counts, lags in slots, identifiers
    "bytes": Unit("#,##0", 0, "bytes"),
    "fl": Unit("0.00", 2, "FL"),
    "tod": Unit("[hh]:mm:ss.000", 3, "UTC"),  # seconds since midnight, shown as a clock time
    # the edges of bins (evaluate's range bands, azimuth sectors, flight-level bands): round numbers
    "edge_nm": Unit("0.0", 1, "NM"),
    "edge_deg": Unit("0.0", 1, "deg"),
    "edge_fl": Unit("0", 0, "FL"),
}

COLUMN_UNITS: dict[str, str] = {
    "window": "count", "slot": "count", "slots": "count", "lag": "count", "sac": "count", "sic": "count",
    "radar_before": "count", "radar_after": "count", "adsb_before": "count", "adsb_after": "count",
    "radar_duplicates": "count", "adsb_duplicates": "count", "adsb_jumps": "count",
    "radar_filled_slots": "count", "adsb_filled_slots": "count", "radar_count": "count",
    "adsb_count": "count", "sep_slots": "count", "matched_reports": "count", "quality_reports": "count",
    "ncc_peak_lag_lat": "count", "ncc_peak_lag_lon": "count", "pearson_peak_lag_lat": "count",
    "pearson_peak_lag_lon": "count", "n_reports": "count", "reports": "count", "intervals": "count",
    "gaps": "count", "jumps": "count", "blocks": "count", "records": "count", "track_number": "count",
    # the evaluation's counts, floats where a left join leaves an aircraft without them (171, not 171.0)
    "expected": "count", "detected": "count", "expected_updates": "count", "detected_updates": "count",
    "errors_judged": "count", "reference_samples": "count", "pairs": "count",
    "lag_s": "s", "time_bias_s": "s", "time_bias_se_s": "s",
    "range_gain_ppm": "ppm", "range_gain_se_ppm": "ppm",
    "flight_level": "fl", "flight_level_a": "fl", "flight_level_b": "fl",
    "range_from_nm": "edge_nm", "range_to_nm": "edge_nm", "azimuth_from_deg": "edge_deg",
    "azimuth_to_deg": "edge_deg", "fl_from": "edge_fl", "fl_to": "edge_fl",
    "point_latitude": "point_deg", "point_longitude": "point_deg", "corrected_latitude": "point_deg",
    "corrected_longitude": "point_deg",
    "bytes": "bytes", "size_bytes": "bytes", "length": "bytes", "offset": "bytes", "first_offset": "bytes",
}

# (pattern on the lower-case name, unit), first match wins
_UNIT_PATTERNS: list[tuple[re.Pattern[str], str]] = [
    (re.compile(p), u) for p, u in (
        (r"(^|_)(time_of_day|tod)($|_s$)|_tod(_s)?$", "tod"),
        (r"ncc|pearson|(^|_)(corr|coef|coefficient)($|_)", "coef"),  # not "corrected_", "_correct"
        (r"_pct$|(^|_)share", "pct"),
        (r"_ppm$", "ppm"),
        (r"_deg$|(^|_)(lat|lon|latitude|longitude)($|_|\d)", "deg"),
        (r"_m$", "m"),
        (r"_nm$", "nm"),
        (r"_kt$", "kt"),
        (r"_ft$", "ft"),
        (r"_s$", "s"),
    )
]


def column_unit(name: str) -> str | None:
    """The unit key of a column (see ``UNITS``), or None when nothing in the table names it."""
    key = str(name).lower()
    if key in COLUMN_UNITS:
        return COLUMN_UNITS[key]
    return next((unit for pattern, unit in _UNIT_PATTERNS if pattern.search(key)), None)


def excel_format(name: str) -> str | None:
    """Excel number format of a column, or None when its unit is unknown."""
    unit = column_unit(name)
    return UNITS[unit].excel if unit else None


def decimals(name: str, default: int = 3) -> int:
    """Decimals to print for a column in text output."""
    unit = column_unit(name)
    return UNITS[unit].decimals if unit else default
