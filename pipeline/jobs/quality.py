"""The quality job (``msdc quality``): sensor data quality and radar accuracy against ADS-B.

``validate`` checks every option, the sensor file and the outputs before anything is decoded;
``quality_job`` decodes straight into measurements (only the columns ``quality_columns`` names), marks
duplicates and jumps once and computes the quality and accuracy tables; ``write_quality`` writes the JSON
and the workbook with its figures, all or nothing (report.transaction); ``text`` is the terminal's summary.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import pandas as pd

from msdc.pipeline.jobs.common import (
    QUALITY_FIGURE_GLOBS,
    QUALITY_WITHOUT,
    Checked,
    absent_categories,
    carrying,
    check_aircraft,
    check_decoding,
    check_workbook,
    filter_parameters,
    filters_asked,
    marked_measurements,
    output_path,
    quality_figures,
    quality_inputs,
    quality_step,
    run_parameters,
    sensors_path,
    side_files_beside,
)
from msdc.pipeline.jobs.options import QualityOptions, check_declared
from msdc.pipeline.model.load import Loaded
from msdc.pipeline.progress import Progress
from msdc.pipeline.report.transaction import OutputTransaction, staged

if TYPE_CHECKING:
    from msdc.pipeline.quality.quality_run import QualityResult


def validate(options: QualityOptions) -> Checked:
    """Check every option, the sensor file and the output paths, before any decoding; OptionError if bad."""
    check_declared(options)
    checked = check_decoding(options)
    check_aircraft(options)
    checked.output = output_path("-o", options.output, (".xlsx",))
    checked.warnings += check_workbook(options, checked, figure_windows=0, sensors_required=False)
    return checked


@dataclass
class QualityJobResult:
    """Quality tables and radar accuracy of a run, with its parameters, inputs and warnings (validation's
    first)."""

    options: QualityOptions
    checked: Checked
    quality: QualityResult
    parameters: dict
    loaded: Loaded
    warnings: list[str] = field(default_factory=list)


def quality_columns(options: QualityOptions) -> list[str]:
    """The measurement columns a quality job builds, in schema order: what the quality tables, the radar
    errors against the reference (with ``reference="track"`` the tracker's inputs), mark_once, the aircraft
    selection and the two-targets check (pipeline.model.mixed) read. Two thirds of the bytes of a row with
    the ADS-B reference."""
    from msdc.pipeline.model.mixed import MIXED_INPUTS
    from msdc.pipeline.model.schema import MEASUREMENT_COLUMNS, column_names
    from msdc.pipeline.model.site_check import SITE_CHECK_INPUTS

    need = set(quality_inputs(options.reference)) | set(SITE_CHECK_INPUTS) | set(MIXED_INPUTS)
    return column_names(need & set(MEASUREMENT_COLUMNS))  # the job-wide flags are added by mark_once


def quality_job(options: QualityOptions, *, progress: Progress | None = None, checked: Checked | None = None,
                command: str = "quality") -> QualityJobResult:
    """Validate, decode, build measurements and compute the quality and accuracy tables."""
    from msdc.pipeline.model.site_check import site_warnings
    from msdc.pipeline.quality.filters import filter_warnings

    started = time.monotonic()
    checked = checked or validate(options)
    with carrying(checked.warnings) as warnings:
        if progress:
            progress.stage("Processing data files")
        loaded, meas, said = marked_measurements(options, checked, progress, "Analysing data quality",
                                                 either=True, columns=quality_columns(options),
                                                 needs=((48,), (21,), (10, 20)))
        warnings += said
        absent = absent_categories(loaded)
        warnings += site_warnings(meas, checked.sensors, str(sensors_path(options)))
        reference, removed = _filtered(meas, options)
        warnings += filter_warnings(removed, options.min_nic, options.min_nacp)
        quality = quality_step(meas, checked.sensors, options, reference_meas=reference)
        del reference
        warnings += quality.sheets["Radar biases"].attrs.get("distrust", [])  # fits not to be trusted
        params = {**run_parameters(options, loaded, started, command), "callsign": options.callsign,
                  "address": options.address, "gap_s": options.gap_s,
                  "filters": filter_parameters(options, removed),
                  "notes": [*(f"no CAT{cat:03d} records in the inputs: {QUALITY_WITHOUT[cat]}"
                              for cat in absent), *quality.notes]}
        return QualityJobResult(options, checked, quality, params, loaded, warnings)


def _filtered(meas, options: QualityOptions) -> tuple[pd.DataFrame | None, dict[str, int]]:
    """The measurements the reference is built from, the ADS-B filters asked for applied (None when none
    is), and the count each removed (pipeline.quality.filters)."""
    from msdc.pipeline.quality.filters import FILTER_KEYS, apply_filters

    if not filters_asked(options):
        return None, dict.fromkeys(FILTER_KEYS, 0)
    return apply_filters(meas, drop_jumps=options.drop_jumps, min_nic=options.min_nic,
                         min_nacp=options.min_nacp)


def write_quality(result: QualityJobResult, *, tx: OutputTransaction | None = None) -> dict[str, Path]:
    """Write the JSON tables and/or the workbook with its figures, as the options ask, staged in ``tx``
    (committed by the caller; without one, the files are committed together here). Returns the final
    paths, by kind."""
    from msdc.pipeline.quality.tables import workbook_sheets
    from msdc.pipeline.report.excel import write_tables
    from msdc.pipeline.report.files import write_json
    from msdc.pipeline.report.summary import table_records

    written: dict[str, Path] = {}
    with staged(tx) as stage:
        if result.checked.json:
            doc = {"parameters": result.parameters, "inputs": result.loaded.inputs,
                   "tables": {name: table_records(t) for name, t in result.quality.sheets.items()}}
            write_json(doc, stage.path(result.checked.json))
            written["json"] = result.checked.json
        if result.checked.output:
            out = stage.path(result.checked.output)
            images = quality_figures(result.quality, out.parent, out.stem, stage)
            write_tables(workbook_sheets(result.quality.sheets), out, images=images,
                         parameters={**result.parameters, "inputs": result.loaded.inputs})
            written["report"] = result.checked.output
            written.update((f"image {name}", stage.final(path)) for name, path in images.items())
    return written


def text(result: QualityJobResult) -> str:
    """The per-sensor summary and the bias estimates, for the terminal."""
    q = result.quality.sheets["Quality"]
    b = result.quality.sheets["Radar biases"]
    keep = [c for c in ("callsign", "address", "sensor", "sac", "sic", "reports", "duplicates_removed",
                        "interval_median_s",
                        "interval_p95_s", "speed_missing_or_zero_pct", "gaps", "jumps") if c in q]
    bias_cols = [c for c in ("radar", "n_reports", "n_rejected", "n_overhead", "range_bias_m",
                             "range_bias_se_m", "range_gain_ppm", "range_gain_se_ppm", "azimuth_bias_deg",
                             "azimuth_bias_se_deg", "time_bias_s", "time_bias_se_s", "chi2_per_dof",
                             "site_offset_m", "fit_trusted") if c in b]
    from msdc.pipeline.report.summary import frame_text

    out = "Quality:\n" + (frame_text(q[keep]) if len(q) else
                           "  none: no report with a position in the inputs (status messages only, or none)")
    removed = result.parameters.get("filters", {}).get("removed", {})
    if removed:
        out += "\n\nADS-B filters (radar accuracy and biases use what they leave): " + ", ".join(
            f"{name} {n}" for name, n in removed.items())
    out += "\n\nRadar biases:\n"
    empty = next((n for n in result.quality.notes if n.startswith("No radar report")), "")
    out += frame_text(b[bias_cols]) if len(b) else f"  none. {empty or 'No radar report matched to ADS-B.'}"
    points = result.quality.sheets.get("Reference points")
    if points is not None:  # multilateration and surface radar: where their x/y origin lies
        out += ("\n\nReference points (offset of each sensor's surface positions from its reference's; "
                "corrected: the sensor-file point that removes it):\n" + frame_text(points))
    note = b.attrs.get("note")
    if note and not len(b):  # its reason is said above
        note = note.removeprefix(empty).strip()
    return out + (f"\n\nNote: {note}" if note else "")


def side_files(checked: Checked) -> list[Path]:
    """The figures quality -o may write beside the workbook, as globs."""
    return side_files_beside(checked.output, QUALITY_FIGURE_GLOBS)


__all__ = ["QualityJobResult", "QualityOptions", "quality_columns", "quality_job", "side_files", "text",
           "validate",
           "write_quality"]
