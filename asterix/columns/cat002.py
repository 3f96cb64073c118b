"""CAT002 (monoradar service messages, editions 1.0-1.2) columns."""

from __future__ import annotations

from .base import _COMMON_ID, Column, _c

CAT002: list[Column] = [
    *_COMMON_ID,
    _c("time_of_day", "030", "", unit="s",
       doc="Time of day (UTC seconds since midnight) of the message: north or sector crossing time"),
    _c("message_type", "000", "", "int", doc="Message type: 1 north marker, 2 sector crossing, 3 south "
       "marker, 8 activation / 9 stop of blind zone filtering"),
    _c("sector_number", "020", "", "int", doc="Sector number: the 8 most significant bits of the antenna "
       "azimuth (0-255)"),
    _c("sector_azimuth_deg", "020", "", unit="deg", doc="The sector number as an azimuth (360/256 deg each)"),
    _c("antenna_rotation_period_s", "041", "", unit="s",
       doc="Antenna rotation period (I002/041 'Antenna Rotation Speed': time per revolution, 1/128 s)"),
    _c("plot_counters", "070", "", "count", doc="Plot count values in I002/070 (not decoded)"),
    _c("window_rho_start_nm", "100", "RS", unit="NM", doc="Dynamic window type 1: range start"),
    _c("window_rho_end_nm", "100", "RE", unit="NM", doc="Dynamic window type 1: range end"),
    _c("window_theta_start_deg", "100", "TS", unit="deg", doc="Dynamic window type 1: azimuth start"),
    _c("window_theta_end_deg", "100", "TE", unit="deg", doc="Dynamic window type 1: azimuth end"),
    _c("collimation_range_error_nm", "090", "RE", unit="NM", doc="Collimation error: range (1/128 NM)"),
    _c("collimation_azimuth_error_deg", "090", "AE", unit="deg",
       doc="Collimation error: azimuth (360/2^14 deg)"),
    _c("warning_codes", "080", "", "codes",
       doc="I002/080 warning/error conditions: every 7-bit code, in wire order, joined by ','"),
]
