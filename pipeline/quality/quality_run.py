"""The quality step: per-sensor data quality and radar accuracy against ADS-B, as sheets (figures are drawn
by pipeline.jobs); with multilateration or surface radar reports, where their reference points are
(pipeline.quality.reference_offset)."""

from __future__ import annotations

from collections.abc import Collection
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
    """Quality and accuracy sheets (name -> table), the matched radar errors, the figures made, and what the
    run must say about its reference (why accuracy is empty, fits not to be trusted)."""

    sheets: dict[str, pd.DataFrame]
    errors: pd.DataFrame
    figures: dict[str, Path] = field(default_factory=dict)
    notes: list[str] = field(default_factory=list)


def select_aircraft(meas: pd.DataFrame, *, callsign: str | None = None,
                    address: str | None = None) -> pd.DataFrame:
    """Every sensor's measurements of one aircraft, or all of them. NoSuchAircraft, listing the closest,
    only when no sensor saw it: an aircraft seen by one kind of sensor alone (a radar-only aircraft) gets
    what its own reports give, and radar accuracy says it had nothing to compare."""
    if callsign is None and address is None:
        return meas
    from msdc.pipeline.model.measurements import select

    rows = select(meas, callsign, address)
    if len(rows):
        return rows
    one_aircraft(meas, callsign, address)  # raises NoSuchAircraft, naming the closest present
    return rows


def _same_aircraft(reference_meas: pd.DataFrame, callsign: str | None, address: str | None) -> pd.DataFrame:
    """The filtered measurements of the selected aircraft (none of them left: no rows), or all of them."""
    if callsign is None and address is None:
        return reference_meas
    from msdc.pipeline.model.measurements import select

    return select(reference_meas, callsign, address)


def quality_run(meas: pd.DataFrame, sensors: pd.DataFrame, *, callsign: str | None = None,
                address: str | None = None, gap_s: float = 180.0,
                jump_kw: dict | None = None, reference: str = "adsb",
                reference_meas: pd.DataFrame | None = None,
                mixed: Collection[tuple[str, str]] | None = None) -> QualityResult:
    """Quality tables per aircraft and sensor, radar error statistics and per-radar bias estimates.
    ``reference_meas``: the measurements with the ADS-B filters applied (pipeline.quality.filters), which
    radar accuracy, biases and reference points use; the quality sheets describe every report of ``meas``.
    ``mixed``: two targets under one identity already found (quality_tables)."""
    check_frame("meas", meas, MEASUREMENT_INPUTS)  # all checked before the tables are worked out
    check_sensors(sensors, meas)
    check_seconds("gap_s", gap_s)
    check_options("jump_kw", jump_kw)
    check_reference(reference)
    if reference_meas is not None:
        check_frame("reference_meas", reference_meas, MEASUREMENT_INPUTS)
    meas = select_aircraft(meas, callsign=callsign, address=address)
    ref = meas if reference_meas is None else _same_aircraft(reference_meas, callsign, address)
    sheets = quality_tables(meas, gap_s=gap_s, jump_kw=jump_kw, mixed=mixed)
    errors = radar_errors(ref, sensors, jump_kw=jump_kw, reference=reference)
    sheets["Radar accuracy"] = error_stats(errors)
    biases = estimate_biases(errors)
    notes = []
    if errors.empty:
        from msdc.pipeline.quality.empty_reasons import no_comparison_reason

        why = no_comparison_reason(meas, ref, filtered=reference_meas is not None)
        reason = f"No radar report compared with ADS-B: {why}."
        notes.append(reason)
        sheets["Radar accuracy"].attrs["note"] = reason
        biases.attrs["note"] = f"{reason} {biases.attrs.get('note', '')}".strip()
    notes += biases.attrs.get("distrust", [])
    sheets["Radar biases"] = biases
    if ref["sensor_kind"].astype(str).isin(["mlat", "smr"]).any():
        from msdc.pipeline.quality.reference_offset import reference_offsets

        sheets["Reference points"] = reference_offsets(ref, sensors)
    return QualityResult(sheets, errors, notes=notes)
