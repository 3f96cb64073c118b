"""The quality step: per-sensor data quality and radar accuracy against ADS-B, as sheets (figures are drawn
by pipeline.jobs); with multilateration or surface radar reports, where their reference points are
(pipeline.quality.reference_offset)."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import pandas as pd

from msdc.pipeline.model.aircraft import one_aircraft
from msdc.pipeline.quality.accuracy import MEASUREMENT_INPUTS, error_stats, estimate_biases, radar_errors
from msdc.pipeline.quality.checks import (
    check_frame,
    check_options,
    check_reference,
    check_seconds,
    check_sensors,
)
from msdc.pipeline.quality.tables import quality_tables


@dataclass
class QualityResult:
    """Quality and accuracy sheets (name -> table), the matched radar errors, and the figures made."""

    sheets: dict[str, pd.DataFrame]
    errors: pd.DataFrame
    figures: dict[str, Path] = field(default_factory=dict)


def select_aircraft(meas: pd.DataFrame, *, callsign: str | None = None,
                    address: str | None = None) -> pd.DataFrame:
    """Every sensor's measurements of one aircraft, or all of them. NoSuchAircraft lists the closest when
    radar or ADS-B lacks it; with multilateration or surface radar reports in ``meas``, only when no sensor
    saw it (radar accuracy then has nothing to compare, the other sheets do)."""
    if callsign is None and address is None:
        return meas
    if meas["sensor_kind"].astype(str).isin(["mlat", "smr"]).any():
        from msdc.pipeline.model.measurements import select

        rows = select(meas, callsign, address)
        if len(rows):
            return rows
    ac = one_aircraft(meas, callsign, address)
    return pd.concat([ac.radar, ac.adsb], ignore_index=True)


def quality_run(meas: pd.DataFrame, sensors: pd.DataFrame, *, callsign: str | None = None,
                address: str | None = None, gap_s: float = 180.0,
                jump_kw: dict | None = None, reference: str = "adsb") -> QualityResult:
    """Quality tables per aircraft and sensor, radar error statistics and per-radar bias estimates."""
    check_frame("meas", meas, MEASUREMENT_INPUTS)  # all checked before the tables are worked out
    check_sensors(sensors, meas)
    check_seconds("gap_s", gap_s)
    check_options("jump_kw", jump_kw)
    check_reference(reference)
    meas = select_aircraft(meas, callsign=callsign, address=address)
    sheets = quality_tables(meas, gap_s=gap_s, jump_kw=jump_kw)
    errors = radar_errors(meas, sensors, jump_kw=jump_kw, reference=reference)
    sheets["Radar accuracy"] = error_stats(errors)
    biases = estimate_biases(errors)
    sheets["Radar biases"] = biases
    if meas["sensor_kind"].astype(str).isin(["mlat", "smr"]).any():
        from msdc.pipeline.quality.reference_offset import reference_offsets

        sheets["Reference points"] = reference_offsets(meas, sensors)
    return QualityResult(sheets, errors)

