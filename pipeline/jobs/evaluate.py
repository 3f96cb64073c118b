"""The evaluate job (``msdc evaluate``): every sensor the preset applies to, judged against the standard's
requirements on a reference msdc builds itself (leave-one-out, ADS-B only) or one given as a file.

``validate`` checks every option, the preset, the sectors and the outputs before anything is decoded;
``evaluate_job`` decodes the inputs, builds the measurements and, per sensor under test, its reference, its
reports and its scorecard rows, per-aircraft and per-bin tables, coverage grids and map points;
``write_evaluation`` writes the workbook, JSON and HTML, all or nothing; ``text`` is the terminal's summary.
"""

from __future__ import annotations

import math
import tempfile
import time
from collections.abc import Iterator
from dataclasses import dataclass, field, replace
from functools import partial
from pathlib import Path

import numpy as np
import pandas as pd

from msdc.pipeline.jobs.common import (
    Checked,
    JobError,
    carrying,
    check_decoding,
    load_inputs,
    output_path,
    run_parameters,
    sensor_table,
    sensors_path,
    source_measurements,
    spare_inputs,
    tracked_reports,
    undated_warning,
    unread_inputs,
)
from msdc.pipeline.jobs.options import EvaluateOptions, OptionError, check_declared, check_installed
from msdc.pipeline.model.load import Loaded
from msdc.pipeline.progress import Progress
from msdc.pipeline.report.transaction import OutputTransaction, staged

# the HTML map thins each sensor's reports (and its reference) to about this many points: a browser draws
# them at once, and the aircraft's paths stay readable
MAP_POINTS_PER_SENSOR = 5_000


@dataclass
class EvaluateChecked(Checked):
    """Checked options, with the preset, the sectors (as scorecard regions) and the HTML output."""

    preset: object = None
    regions: list = field(default_factory=list)
    html: Path | None = None
    tests: tuple = ()


def validate(options: EvaluateOptions) -> EvaluateChecked:
    """Check every option, the sensor file, the preset, the sectors and the output paths, before any
    decoding; OptionError if bad."""
    from msdc.pipeline.evaluate.presets import load_preset
    from msdc.pipeline.model.arguments import finite_number
    from msdc.pipeline.model.report_selection import parse_sensor, span_windows

    check_declared(options)
    if options.preset is None:
        raise OptionError("--preset is required: a shipped preset by name (eurocontrol-1997-ssr, ed117a, "
                          "...) or a TOML file of your own")
    try:  # no flag: the reference tracker's, from Python only (its step is 1 s)
        finite_number("max_coast_s", options.max_coast_s, at_least=1.0, at_least_name="the reference's step")
    except (TypeError, ValueError) as exc:
        raise OptionError(str(exc)) from None
    base = check_decoding(options)
    checked = EvaluateChecked(**vars(base))
    checked.output = output_path("-o", options.output, (".xlsx",))
    checked.json = output_path("--json", options.json, (".json",))
    checked.html = output_path("--html", options.html, (".html", ".htm"))
    if checked.html is not None:
        check_installed(f"--html {checked.html}", "the HTML report's map", ("bokeh",), "html")
    outs = [(f"-o {checked.output}", checked.output), (f"--json {checked.json}", checked.json),
            (f"--html {checked.html}", checked.html)]
    given = [p for _, p in outs if p is not None]
    if len({str(p.resolve()) for p in given}) < len(given):
        raise OptionError("-o, --json and --html name the same file")
    spare_inputs(options, outs)
    checked.sensors = sensor_table(options.sensors)
    try:
        checked.preset = load_preset(options.preset)
    except ValueError as exc:
        raise OptionError(f"--preset: {exc}") from None
    checked.regions, said = _regions(options.sectors, checked.preset)
    checked.warnings += said
    if options.reference_file is not None:
        path = Path(options.reference_file)
        if options.reference != "leave-one-out":  # one reference or the other, not both in silence
            raise OptionError(f"--reference {options.reference} and --reference-file {path}: give one "
                              "(the file is an external reference, --reference builds one)")
        if not path.is_file():
            raise OptionError(f"--reference-file {path}: {'not a file' if path.exists() else 'no such file'}")
    try:
        checked.tests = tuple(parse_sensor(t, "--test") for t in options.test_sensors)
        if options.window_minutes is not None:
            span_windows(checked.selection, options.window_minutes)
    except ValueError as exc:
        raise OptionError(str(exc)) from None
    return checked


def _regions(path: str | None, preset) -> tuple[list, list[str]]:
    """The sector file's sectors as scorecard regions, and the warnings for the preset's areas no sector
    provides (their requirements are not evaluated); ([], warnings) without a file. OptionError naming the
    file."""
    from msdc.pipeline.evaluate.scorecard import Region
    from msdc.pipeline.evaluate.sectors import area_of, check_preset_areas, read_sectors, sector_mask

    if path is None:
        areas = sorted({r.area for r in preset.requirements if r.area is not None})
        return [], ([f"no --sectors: the preset's requirements on its areas ({', '.join(areas)}) are not "
                     "evaluated"] if areas else [])
    try:
        sectors = read_sectors(path)
    except ValueError as exc:
        raise OptionError(f"--sectors: {exc}") from None

    def mask(sector):
        return lambda lat, lon, fl, ground: sector_mask(sector, lat, lon, fl)  # monitors: score_sensor

    return [Region(s.name, mask(s), area_of(s)) for s in sectors], check_preset_areas(preset, sectors)


@dataclass
class SensorResult:
    """What one sensor under test gave: its scorecard rows, tables, coverage grids and map points."""

    sensor: str
    kind: str
    rows: list[dict]
    per_aircraft: pd.DataFrame
    bands: dict[str, pd.DataFrame]
    polar: pd.DataFrame | None
    vertical: pd.DataFrame | None
    map_points: pd.DataFrame
    notes: list[str]
    site: object = None  # the evaluation's coverage.Sensor
    # the scorecard's outcomes by (sector, requirement id, index in the preset), and the judged reports'
    # range, aircraft and error (accuracy.range_errors): what the windows of a span combine
    outcomes: dict = field(default_factory=dict, repr=False)
    range_errors: pd.DataFrame | None = field(default=None, repr=False)


@dataclass
class EvaluateResult:
    """The evaluation of a run: the scorecard, the tables, the map points and what they rest on."""

    options: EvaluateOptions
    checked: EvaluateChecked
    scorecard: pd.DataFrame
    tables: dict[str, pd.DataFrame]
    map_points: pd.DataFrame | None
    sensors: list[SensorResult]
    parameters: dict
    loaded: Loaded
    warnings: list[str] = field(default_factory=list)


def _under_test(meas: pd.DataFrame, preset, tests: tuple, trackers: list[str] = (), unread: str = "",
                reference: str = "leave-one-out") -> tuple[list[tuple[str, str]], list[str]]:
    """The (sensor id, kind) pairs to judge: those of a kind the preset applies to (the measurements'
    sensors and the CAT062 ``trackers``), narrowed by --test; ``unread`` ends the error when none is
    (unread_inputs: inputs of categories the command does not read). The note on the sensors not judged
    says which build the ``reference`` (leave-one-out: all; adsb: the ADS-B; external: none)."""
    from msdc.pipeline.evaluate.sensor_reports import judged_by
    from msdc.pipeline.model.report_selection import sensor_parts
    from msdc.pipeline.model.schema import first_rows

    pairs = meas[["sensor_id", "sensor_kind"]]  # each distinct pair's first row, then as text
    pairs = pairs.iloc[first_rows(pairs, ["sensor_id", "sensor_kind"])].astype(str).drop_duplicates()
    pairs = pairs.sort_values("sensor_id")
    present = [*zip(pairs["sensor_id"], pairs["sensor_kind"], strict=True),
               *((t, "tracker") for t in trackers)]
    fits = [(s, k) for s, k in present if judged_by(k, preset.sensor_types)]
    notes = []
    if tests:
        parts = sensor_parts([s for s, _ in fits])
        keep = np.zeros(len(fits), bool)
        for ref in tests:
            hit = np.array([ref.matches(int(c), int(a), int(b), k) for c, a, b, k in parts.itertuples(
                index=False)], dtype=bool)
            if not hit.any():
                raise JobError(f"--test {ref.text}: no sensor of a kind the preset {preset.name} applies to "
                               f"({', '.join(preset.sensor_types)}) has that id in the inputs (present: "
                               f"{', '.join(f'{s} ({k})' for s, k in present) or 'none'})")
            keep |= hit
        fits = [f for f, k in zip(fits, keep, strict=True) if k]
    if not fits:
        raise JobError(f"no sensor in the inputs is of a kind the preset {preset.name} applies to "
                       f"({', '.join(preset.sensor_types)}); present: "
                       f"{', '.join(f'{s} ({k})' for s, k in present) or 'none'}{unread}")
    left = [(s, k) for s, k in present if (s, k) not in fits]
    if left:
        builders = {"external": [], "adsb": [(s, k) for s, k in left if k == "adsb"]}.get(reference, left)
        role = ("they still build the reference" if builders == left else
                f"{', '.join(f'{s} ({k})' for s, k in builders)} still build the reference" if builders else
                "none builds the reference: " + ("it is the external file" if reference == "external"
                                                 else "it is built from ADS-B alone"))
        notes.append(f"not judged by {preset.name}: {', '.join(f'{s} ({k})' for s, k in left)} ({role})")
    return fits, notes


def _selected(reports: pd.DataFrame, checked: EvaluateChecked, date) -> pd.DataFrame:
    """A tracker's reports after the report selection (--from, --to, --area, --fl, --sensor), as the
    measurements get it."""
    from msdc.pipeline.model.report_selection import select_reports

    if checked.selection is None or not checked.selection.active or reports.empty:
        return reports
    try:
        keep, _ = select_reports(reports, checked.selection, date)
    except ValueError as exc:
        raise OptionError(str(exc)) from None
    return reports[keep].reset_index(drop=True)


def _entry(sensors: pd.DataFrame, sensor_id: str) -> dict | None:
    """The sensor file's row of a sensor (by category, SAC and SIC), or None (ADS-B has none)."""
    from msdc.pipeline.model.report_selection import sensor_parts

    part = sensor_parts([sensor_id]).iloc[0]
    if sensors is None or part["sac"] < 0:
        return None
    hit = sensors[(sensors["sac"] == part["sac"]) & (sensors["sic"] == part["sic"])
                  & (sensors["category"] == part["category"])]
    if part["kind"] is not None and "kind" in hit:
        hit = hit[hit["kind"].astype(str) == part["kind"]]
    return hit.iloc[0].to_dict() if len(hit) else None


def _reference(options: EvaluateOptions, builders: pd.DataFrame, sensor_id: str, gates, epoch,
               external: pd.DataFrame | None, cache: dict | None = None):
    """The reference for one sensor under test: external, ADS-B only or leave-one-out."""
    from msdc.pipeline.evaluate.build_reference import BuiltReference, adsb_reference, leave_one_out

    if external is not None:
        return BuiltReference(external, {}, epoch, [f"external reference {options.reference_file}"])
    present = sensor_id in {str(v) for v in builders["sensor_id"].dropna().unique()}
    if options.reference == "adsb":
        return adsb_reference(builders, sensor_id if present else None, gates=gates, epoch=epoch,
                              max_coast_s=options.max_coast_s, cache=cache)
    return leave_one_out(builders, sensor_id, gates=gates, epoch=epoch, max_coast_s=options.max_coast_s,
                         require_present=False, cache=cache)


def _per_aircraft(sensor_id: str, reports: pd.DataFrame, reference: pd.DataFrame, pd_outcome,
                  association: dict) -> pd.DataFrame:
    """One row per reference aircraft: the sensor's associated reports, its expected and detected updates
    (the first pd requirement's) with PD and interval, the RMS position error, the reference's samples and
    the shares of them that were the sensor's own track and on the surface."""
    from msdc.pipeline.evaluate.accuracy import position_errors
    from msdc.pipeline.evaluate.reference import associated

    rep = associated(reports, reference, association)
    counts = rep[rep["ref_index"] >= 0].groupby("ref_aircraft").size().rename("reports")
    from msdc.pipeline.evaluate.scorecard import MONITOR_CODE, ground_flags

    ground = ground_flags(reference)
    ground[ground == MONITOR_CODE] = 1.0  # a field monitor stands on the surface (not a share of 200 %)
    ref = reference.assign(surface=ground).groupby("aircraft").agg(
        built_by=("built_by", lambda s: " | ".join(sorted(set(map(str, s.unique()))))),
        self_reference_share=("self_reference", "mean"), surface_share=("surface", "mean"),
        reference_samples=("built_by", "size"))
    table = ref.join(counts, how="left")
    table["reports"] = table["reports"].fillna(0).astype(int)
    if pd_outcome is not None and pd_outcome.per_aircraft is not None and len(pd_outcome.per_aircraft):
        per = pd_outcome.per_aircraft.set_index("aircraft")[["expected", "detected", "pd", "ci_low",
                                                             "ci_high"]]
        names = {"expected": "expected_updates", "detected": "detected_updates"}
        table = table.join(per.rename(columns=names), how="left")
    errors = position_errors(rep, reference, association)
    if len(errors):
        rms = np.sqrt(errors["error_m"].pow(2).groupby(errors["aircraft"]).mean())
        table = table.join(rms.rename("rms_error_m"), how="left")
        table = table.join(errors.groupby("aircraft").size().rename("errors_judged"), how="left")
    table.index.name = "aircraft"
    out = table.reset_index()
    out.insert(0, "sensor", sensor_id)
    return out


def _step(n: int, limit: int) -> int:
    """k such that every k-th of ``n`` rows leaves about ``limit`` (1: all, when fewer)."""
    return max(1, math.ceil(n / limit)) if limit > 0 else 1


def _thinned(frame: pd.DataFrame, limit: int) -> pd.DataFrame:
    """Every k-th row so that about ``limit`` remain (all when fewer)."""
    return frame.iloc[::_step(len(frame), limit)]


def _map_points(sensor_id: str, reports: pd.DataFrame, reference: pd.DataFrame,
                association: dict) -> pd.DataFrame:
    """The associated reports and the reference, per aircraft, thinned for the HTML map (the rows chosen
    first, then only the four columns the map shows taken of them)."""
    from msdc.pipeline.evaluate.reference import associated

    rep = associated(reports, reference, association)
    kept = np.flatnonzero(rep["ref_index"].to_numpy() >= 0)
    rep = rep[["ref_aircraft", "latitude", "longitude"]].iloc[kept[::_step(len(kept), MAP_POINTS_PER_SENSOR)]]
    ref = _thinned(reference[["aircraft", "latitude", "longitude"]], MAP_POINTS_PER_SENSOR)
    parts = [pd.DataFrame({"aircraft": rep["ref_aircraft"].astype(str).to_numpy(object), "source": "report",
                           "sensor": sensor_id, "latitude": rep["latitude"].to_numpy(float),
                           "longitude": rep["longitude"].to_numpy(float)}),
             pd.DataFrame({"aircraft": ref["aircraft"].astype(str).to_numpy(object), "source": "reference",
                           "sensor": f"reference for {sensor_id}",
                           "latitude": ref["latitude"].to_numpy(float),
                           "longitude": ref["longitude"].to_numpy(float)})]
    out = pd.concat(parts, ignore_index=True)
    ok = np.isfinite(out["latitude"].to_numpy(float)) & np.isfinite(out["longitude"].to_numpy(float))
    return out[ok].reset_index(drop=True)


def _coverage(reports: pd.DataFrame, reference: pd.DataFrame, sensor, preset,
              linked: pd.DataFrame | None = None) -> tuple[dict, object, object]:
    """PD per band (range, azimuth, flight level, surface/airborne) and on the polar and vertical grids,
    from the expected updates under the preset's first pd requirement's parameters, the field monitors left
    out. ``linked``: the reports already associated with this reference under the preset's gate, used as
    they are when that association is the one needed here (no field monitor, the same gates)."""
    from msdc.pipeline.evaluate.bins import detection_bands, polar_grid, vertical_grid
    from msdc.pipeline.evaluate.detection import expected_updates
    from msdc.pipeline.evaluate.reference import association_gates

    params = {**next((dict(r.parameters) for r in preset.requirements if r.id == "pd"), {}),
              **preset.association()}
    monitors = (reference["field_monitor"].to_numpy(bool) if "field_monitor" in reference.columns
                else np.zeros(len(reference), bool))
    if monitors.any():
        reference = reference[~monitors]
    elif linked is not None and association_gates(params) == association_gates(preset.association()):
        reports = linked
    try:
        table, _, _ = expected_updates(reports, reference, params, sensor)
    except ValueError:
        return {}, None, None
    if table.empty:
        return {}, None, None
    return detection_bands(table, reference), polar_grid(table), vertical_grid(table)


def _sensor(options, checked, loaded, meas, builders, sensor_id, kind, gates, epoch, external, monitors,
            cache: dict | None = None) -> SensorResult:
    """Everything about one sensor under test, its reference's trajectories cut once for all of it."""
    from msdc.pipeline.evaluate.reference import shared_references

    with shared_references():
        return _sensor_result(options, checked, loaded, meas, builders, sensor_id, kind, gates, epoch,
                              external, monitors, cache)


def _sensor_result(options, checked, loaded, meas, builders, sensor_id, kind, gates, epoch, external,
                   monitors, cache: dict | None = None) -> SensorResult:
    """`_sensor`'s work."""
    from msdc.pipeline.evaluate.accuracy import error_bands, range_errors
    from msdc.pipeline.evaluate.scorecard import score_sensor
    from msdc.pipeline.evaluate.sensor_reports import (
        TRACKER_CATEGORY,
        evaluation_sensor,
        joined_columns,
        north_markers_s,
        sensor_reports,
        tracker_reports,
    )
    from msdc.pipeline.model.report_selection import sensor_parts

    built = _reference(options, builders, sensor_id, gates, epoch, external, cache)
    reference = built.frame.assign(field_monitor=built.frame["aircraft"].astype(str).isin(monitors))
    part = sensor_parts([sensor_id]).iloc[0]
    if kind == "tracker":
        reports = _selected(tracker_reports(loaded.frames[TRACKER_CATEGORY], sensor_id, loaded.date, epoch),
                            checked, loaded.date)
    else:  # the decoded frame of the sensor's category gives its validity bits (a radar's: more)
        category = int(part["category"])
        reports = sensor_reports(meas, sensor_id, epoch, loaded.frames.get(category),
                                 joined_columns(category))
    markers = (north_markers_s(loaded.frames, int(part["sac"]), int(part["sic"]), loaded.date, epoch)
               if kind == "radar" else None)
    sensor, said = evaluation_sensor(sensor_id, reports, _entry(checked.sensors, sensor_id), markers)
    notes = [n for n in (said, *built.notes) if n]
    if built.gate_counts and any(built.gate_counts.values()):
        notes.append("reference gates removed " + ", ".join(f"{k} {v}" for k, v in built.gate_counts.items()
                                                            if v))
    score = score_sensor(checked.preset, sensor_id, reports, reference, sensor, checked.regions)
    notes += score.notes
    pd_outcome = next((o for (name, rid, _), o in score.outcomes.items() if rid == "pd" and name == "global"),
                      None)
    gate = checked.preset.association()
    linked = score.reports  # associated once, with the preset's gate: reused below
    bands, polar, vertical = ({}, None, None) if reference.empty else _coverage(reports, reference, sensor,
                                                                                 checked.preset, linked)
    per = _per_aircraft(sensor_id, linked, reference, pd_outcome, gate) if len(reference) else pd.DataFrame()
    points = _map_points(sensor_id, linked, reference, gate) if len(reference) else pd.DataFrame()
    errors = range_errors(linked, reference, sensor, gate) if len(reference) else None
    if errors is not None:
        bands["error_range"] = error_bands(errors)
    return SensorResult(sensor_id, kind, score.rows, per, bands, polar, vertical, points, notes, sensor,
                        score.outcomes, errors)


@dataclass
class WindowRun:
    """One window's evaluation before it is assembled: each sensor's result, the run's notes, what was read
    and whether the reference was an external file."""

    results: list[SensorResult]
    notes: list[str]
    loaded: Loaded
    external: bool
    windows: list[dict] = field(default_factory=list)  # a span's windows: bounds and reports kept
    site_faults: dict[str, str] = field(default_factory=dict)  # radars whose site is wrong: the warning
    mixed: frozenset = frozenset()  # (aircraft_id, sensor_id) whose reports switch between two places


def evaluate_job(options: EvaluateOptions, *, progress: Progress | None = None,
                 checked: EvaluateChecked | None = None, command: str = "evaluate") -> EvaluateResult:
    """Validate, decode, build the measurements, then evaluate every sensor under test (with --window, the
    span window by window, pooled)."""
    started = time.monotonic()
    checked = checked or validate(options)
    with carrying(checked.warnings) as warnings:
        if options.window_minutes is None:
            run, per_window = _evaluate_window(options, checked, progress, warnings), {}
        else:
            run, per_window = _evaluate_span(options, checked, progress, warnings)
        _no_verdict_on_a_wrong_site(run)
        card, tables, points = _assemble(run.results)
        if "Per aircraft" in tables:
            tables["Per aircraft"] = mark_two_targets(tables["Per aircraft"], run.mixed)
        tables = {**per_window, **tables}
        params = _parameters(options, checked, run, started, command)
        if run.windows:
            params["windows"] = run.windows
        params["warnings"] = list(dict.fromkeys(warnings))  # the outputs keep what the terminal said
        return EvaluateResult(options, checked, card, tables, points, run.results, params, run.loaded,
                              warnings)


def mark_two_targets(per_aircraft: pd.DataFrame, mixed) -> pd.DataFrame:
    """The per-aircraft table with ``two_targets_on``: the sensors (of the one under test and those that
    built its reference) whose reports of that aircraft switch between two places (``mixed``: pairs of
    aircraft_id and sensor_id, pipeline.model.mixed), joined by " | "; empty where none do. Such a row's
    figures mix two targets."""
    by_aircraft: dict[str, set[str]] = {}
    for aircraft, sensor in mixed:
        by_aircraft.setdefault(str(aircraft), set()).add(str(sensor))
    marks = []
    columns = (per_aircraft[c].astype(str) for c in ("aircraft", "sensor", "built_by"))
    for aircraft, sensor, built_by in zip(*columns, strict=True):
        involved = {sensor, *built_by.split(" | ")}
        marks.append(" | ".join(sorted(by_aircraft.get(aircraft, set()) & involved)))
    return per_aircraft.assign(two_targets_on=pd.Series(marks, index=per_aircraft.index, dtype="str"))


def _no_verdict_on_a_wrong_site(run: WindowRun) -> None:
    """A radar whose plots lie far from ADS-B (its site in the sensor file is wrong, model.site_check) gets
    no verdict: its plots are placed wrong, so its reference, coverage and association are too. Every row
    of it is inconclusive, the warning in its notes, its figures kept."""
    for result in run.results:
        said = run.site_faults.get(result.sensor)
        if said is None:
            continue
        result.rows = _no_verdict(result.rows, said)
        result.notes.append(f"no verdict: {said}")


def _no_verdict(rows: list[dict], said: str | None) -> list[dict]:
    """Scorecard rows made inconclusive, their notes starting with ``said`` (as the docs say: the reason
    first), then what they said without it."""
    if said is None:
        return rows
    why = f"no verdict: {said}"
    return [{**row, "verdict": "inconclusive", "notes": "; ".join(x for x in (why, row["notes"]) if x)}
            for row in rows]


def _parameters(options: EvaluateOptions, checked: EvaluateChecked, run: WindowRun, started: float,
                command: str) -> dict:
    """The run's parameters as the outputs record them: the common ones, the preset, reference, sectors,
    gates and notes."""
    return {**run_parameters(options, run.loaded, started, command), "preset": checked.preset.name,
            "preset_source": checked.preset.path, "reference": "external" if run.external
            else options.reference, "sectors": options.sectors,
            "gates": {"min_nacp": options.min_nacp, "min_nic": options.min_nic,
                      "min_sil": options.min_sil, "drop_jumps": options.drop_jumps},
            "notes": [*run.notes, *(f"{r.sensor}: {n}" for r in run.results for n in r.notes)]}


def _evaluate_window(options: EvaluateOptions, checked: EvaluateChecked, progress: Progress | None,
                     warnings: list[str]) -> WindowRun:
    """Decode the inputs checked.selection keeps (with its margin), build the measurements and evaluate
    every sensor under test; warnings added to ``warnings``."""
    from msdc.pipeline.evaluate.reference_gates import Gates
    from msdc.pipeline.evaluate.sensor_reports import (
        MONITOR_MODE3A,
        RADAR_EXTRA_COLUMNS,
        SERVICE_CATEGORIES,
        TRACKER_CATEGORY,
        TRACKER_COLUMNS,
        field_monitors,
        fixed_7777,
        tracker_ids,
    )
    from msdc.pipeline.model.heap import release_free_memory
    from msdc.pipeline.model.site_check import far_sites
    from msdc.pipeline.model.time import midnight

    if progress:
        progress.stage("Processing data files")
    wants_tracks = "tracker" in checked.preset.sensor_types
    extra = (*RADAR_EXTRA_COLUMNS, *(TRACKER_COLUMNS if wants_tracks else ()))
    loaded, said = load_inputs(options, checked, progress, extra_columns=extra,
                               extra_categories=(*SERVICE_CATEGORIES,
                                                 *((TRACKER_CATEGORY,) if wants_tracks else ())))
    warnings += said
    if progress:
        progress.stage("Evaluating")
    meas, said = source_measurements(loaded, checked, options)
    warnings += said
    within_margin(loaded, (TRACKER_CATEGORY, *SERVICE_CATEGORIES))
    faults = far_sites(meas, checked.sensors, str(sensors_path(options)))
    warnings += faults.values()
    warnings += undated_warning(loaded, "the reports and the reference")
    if meas.empty:
        raise JobError("no report in the inputs to evaluate")
    trackers = tracker_ids(loaded.frames.get(TRACKER_CATEGORY)) if wants_tracks else []
    tests, notes = _under_test(meas, checked.preset, checked.tests, trackers, unread_inputs(loaded),
                               "external" if options.reference_file is not None else options.reference)
    builders = tracked_reports(meas, options.max_coast_s)
    warnings += builders.attrs.get("repeated", []) + builders.attrs.get("mixed", [])
    epoch = midnight(meas["time"])
    external = _selected_reference(_external(options, epoch), checked, epoch, loaded.date)
    warnings += _reference_outside(external, meas, epoch, options.reference_file)
    flagged = field_monitors(meas, loaded.frames)
    standing = {k: v for k, v in fixed_7777(meas).items() if k not in flagged}
    monitors = flagged | set(standing)
    _keep_frames(loaded, tests)  # what each sensor's part reads
    if monitors:
        said = [f"{a} (RAB set)" for a in sorted(flagged)]
        said += [f"{a} (Mode 3/A {MONITOR_MODE3A} on every report, 95 % within {p95:.3g} m of one point)"
                 for a, p95 in sorted(standing.items())]
        notes.append(f"field monitors (fixed transponders): {', '.join(said)}; judged in their own rows, "
                     "left out of the others")
    if overlap := _area_overlap(checked, meas):
        notes.append(overlap)
    gates = Gates(min_nacp=options.min_nacp, min_nic=options.min_nic, min_sil=options.min_sil,
                  drop_jumps=options.drop_jumps)
    results, cache = [], {}  # the latest reference, reused by the next sensor built from the same
    for i, (sensor_id, kind) in enumerate(tests):
        if progress:
            progress.step(f"{sensor_id} ({i + 1}/{len(tests)})")
        results.append(_sensor(options, checked, loaded, meas, builders, sensor_id, kind, gates, epoch,
                               external, monitors, cache))
        release_free_memory()  # a reference's transient copies, handed back before the next sensor's
    loaded.drop_frames()
    return WindowRun(results, notes, loaded, external is not None, site_faults=faults,
                     mixed=frozenset(builders.attrs.get("mixed_pairs", ())))


PER_WINDOW = "Scorecard per window"
NOTES_PER_WINDOW = "Notes per window"
# a local cluster's worker process is restarted after evaluating this many windows: the heap a window frees
# but the process cannot hand back adds up over a day (dataset.cluster.DaskDistributor._fresh_workers)
WINDOWS_PER_WORKER_PROCESS = 6


def _evaluate_span(options: EvaluateOptions, checked: EvaluateChecked, progress: Progress | None,
                   warnings: list[str]) -> tuple[WindowRun, dict[str, pd.DataFrame]]:
    """--window: each window of the span evaluated as --from/--to of it alone would be (read with its
    margin), folded into each sensor's span (evaluate.windows.SensorSpan) and let go; then pooled, with the
    tables per window. A window the data do not allow (no report, no sensor the preset judges) is said in
    the notes; JobError when none does. What the pooling needs value by value (each sensor's errors by
    range, a percentile's values, a PD's per-aircraft tables) waits in a temporary folder (the system's,
    TMPDIR), removed at the end whatever happens."""
    from msdc.pipeline.model.report_selection import span_windows

    windows = span_windows(checked.selection, options.window_minutes)
    with tempfile.TemporaryDirectory(prefix="msdc-evaluate-") as spill:  # values to pool, off memory
        return _span(options, checked, progress, warnings, windows, Path(spill))


def _span(options: EvaluateOptions, checked: EvaluateChecked, progress: Progress | None, warnings: list[str],
          windows: list, spill: Path) -> tuple[WindowRun, dict[str, pd.DataFrame]]:
    """_evaluate_span's work, each sensor's spilled values in a folder of its own under ``spill``."""
    from msdc.pipeline.evaluate.scorecard_schema import SCORECARD_COLUMNS
    from msdc.pipeline.evaluate.windows import SensorSpan, common_notes

    spans: dict[str, SensorSpan] = {}
    runs: list[tuple[tuple[str, str], list[str]]] = []  # each window's label and run notes
    faults: dict[str, str] = {}  # the radars any window found with a wrong site: the warning
    mixed: frozenset = frozenset()  # what any window found with two targets under one identity
    reads: list[Loaded] = []  # the first window's, then each one's inputs and selection alone
    rows, refused, external = [], [], False
    points = max(1, MAP_POINTS_PER_SENSOR // len(windows))  # the span's map keeps about as many points
    for label, run, said in _window_runs(options, checked, windows, points, progress):
        warnings += said
        if isinstance(run, str):
            refused.append(f"window {label[0]} to {label[1]}: {run}")
            continue
        for r in run.results:
            if r.sensor not in spans:
                spans[r.sensor] = SensorSpan(r.kind, r.site, spill=spill / f"sensor-{len(spans)}")
            span = spans[r.sensor]
            span.add(label, r.outcomes, r.notes, r.per_aircraft, r.bands, r.polar, r.vertical, r.range_errors,
                     r.map_points)
            rows += [{"window_from": label[0], "window_to": label[1], **row}
                     for row in _no_verdict(r.rows, run.site_faults.get(r.sensor))]
        runs.append((label, run.notes))
        faults.update(run.site_faults)
        mixed |= run.mixed
        reads.append(run.loaded if not reads else Loaded({}, [], run.loaded.inputs, run.loaded.date,
                                                         selection=run.loaded.selection))
        external = run.external
    if not runs:
        raise JobError(f"--window {options.window_minutes:g}: no window of the span gave an evaluation ("
                       + "; ".join(refused[:3]) + (f"; and {len(refused) - 3} more" if len(refused) > 3
                                                   else "") + ")")
    warnings[:] = list(dict.fromkeys(warnings))  # each window says the same of the same inputs
    results, noted = [], []
    for sensor_id, span in spans.items():
        result, differing = _pooled_sensor(checked, sensor_id, span)
        results.append(result)
        noted += differing
    notes, differing = common_notes(runs)
    noted = [*((a, b, "", n) for (a, b), n in differing), *noted]
    notes += refused
    tables = {PER_WINDOW: pd.DataFrame(rows, columns=["window_from", "window_to", *SCORECARD_COLUMNS])}
    if noted:
        tables[NOTES_PER_WINDOW] = pd.DataFrame(noted, columns=["window_from", "window_to", "sensor", "note"])
        notes.append(f"{len(noted)} notes differ between windows: in the table {NOTES_PER_WINDOW!r}")
    kept = [{"from": a, "to": b, "kept": (loaded.selection or {}).get("kept")}
            for ((a, b), _), loaded in zip(runs, reads, strict=True)]
    return WindowRun(results, notes, _pooled_loaded(checked, reads), external, kept, faults, mixed), tables


def _window_runs(options: EvaluateOptions, checked: EvaluateChecked, windows: list, map_points: int,
                 progress: Progress | None) -> Iterator[tuple[tuple[str, str], WindowRun | str, list[str]]]:
    """Each window's label, evaluation (or why the data do not allow one) and warnings, in the windows' order.
    On a cluster each window is a task of its own: a worker reads its inputs around the window and evaluates
    it (its per-aircraft work on the worker's threads), so the windows run side by side and this process only
    pools them; otherwise one after the other here. Each window's map points are thinned to ``map_points`` a
    sensor and source where it ran."""
    from msdc.pipeline.parallel import distributed_now, map_ordered

    def label(selection) -> tuple[str, str]:
        return selection.start.text, selection.end.text

    if distributed_now() and len(windows) > 1:
        if progress:
            progress.stage(f"Evaluating {len(windows)} windows, each a task on the cluster")
        task = partial(_window_task, options, checked, map_points)
        outs = map_ordered(task, windows, distributable=True, fresh_after=WINDOWS_PER_WORKER_PROCESS,
                           label=lambda s: f"window {s.start.text} to {s.end.text}")
        try:
            for k, (selection, (run, said)) in enumerate(zip(windows, outs, strict=True)):
                if isinstance(run, OptionError):
                    raise run
                if progress and not progress.tty:  # a terminal has the cluster's bar of tasks instead
                    progress.step(f"window {k + 1} of {len(windows)} evaluated: {selection.start.text} to "
                                  f"{selection.end.text}")
                yield label(selection), run, said
        finally:
            outs.close()  # the windows still running are cancelled now, while the cluster is there
        return
    for k, selection in enumerate(windows):
        if progress:
            a, b = label(selection)
            progress.stage(f"Window {k + 1} of {len(windows)}: {a} to {b}")
        run, said = _window_task(options, checked, map_points, selection, progress)
        if isinstance(run, OptionError):
            raise run
        yield label(selection), run, said


def _window_task(options: EvaluateOptions, checked: EvaluateChecked, map_points: int, selection,
                 progress: Progress | None = None) -> tuple[WindowRun | str | OptionError, list[str]]:
    """One window evaluated as --from/--to of it alone would be, its map points thinned to ``map_points`` a
    sensor and source (what a task sends back is what the span keeps), and its warnings; the JobError's
    message when the data do not allow it, an OptionError returned to be raised by the caller (a task's own
    exceptions are retried as failures). Runs here or on a cluster's worker."""
    from msdc.pipeline.model.heap import release_free_memory

    said: list[str] = []
    try:
        run = _evaluate_window(options, replace(checked, selection=selection), progress, said)
    except JobError as exc:
        return str(exc), said
    except OptionError as exc:
        return exc, said
    finally:
        release_free_memory()  # a worker goes on to its next window
    for r in run.results:
        r.map_points = _thinned_map(r.map_points, map_points)
    return run, said


def _thinned_map(points: pd.DataFrame, limit: int) -> pd.DataFrame:
    """The map points of a sensor thinned to about ``limit`` per source (its reports, its reference)."""
    if points.empty:
        return points
    return pd.concat([_thinned(g, limit) for _, g in points.groupby("source", sort=False)], ignore_index=True)


def _pooled_sensor(checked: EvaluateChecked, sensor_id: str, span) -> tuple[SensorResult, list[tuple]]:
    """One sensor's span as a result: its outcomes pooled and judged again, its folded tables, the error
    bands of every window's judged errors; the notes that differ between windows, with their window."""
    from msdc.pipeline.evaluate.scorecard import judge

    preset = checked.preset
    outcomes = span.pooled(preset.requirements)
    rows = [judge(o, preset.requirements[index], preset, sensor_id, name)
            for (name, _, index), o in outcomes.items()]
    bands = span.band_tables()
    errors = span.error_bands()
    if errors is not None:
        bands["error_range"] = errors
    notes, differing = span.common_notes()
    points = pd.concat(span.map_points, ignore_index=True) if span.map_points else pd.DataFrame()
    polar, vertical = span.grids()
    result = SensorResult(sensor_id, span.kind, rows, span.per_aircraft_table(), bands, polar, vertical,
                          points, notes, span.site, outcomes, None)
    return result, [(a, b, sensor_id, n) for (a, b), n in differing]


def _pooled_loaded(checked: EvaluateChecked, runs: list[Loaded]) -> Loaded:
    """What the windows read, as one: the first window's inputs with every window's records added (a
    report in two windows' margins is read by both), and the span's selection with the windows' counts
    added (the reports kept: each once, windows share none)."""
    from msdc.pipeline.model.report_selection import recorded

    first = runs[0]
    inputs = [{**info, "records": dict(info["records"])} for info in first.inputs]
    by_path = {info["path"]: info for info in inputs}
    for loaded in runs[1:]:
        for info in loaded.inputs:
            mine = by_path.get(info["path"])
            if mine is None:
                inputs.append({**info, "records": dict(info["records"])})
                by_path[info["path"]] = inputs[-1]
                continue
            for cat, n in info["records"].items():
                mine["records"][cat] = mine["records"].get(cat, 0) + n
    records = [r.selection for r in runs if r.selection]
    left: dict[str, int] = {}
    for r in records:
        for k, v in r.get("left_out", {}).items():
            left[k] = left.get(k, 0) + int(v)
    selection = {**recorded(checked.selection, first.date, sum(int(r["reports"]) for r in records),
                            sum(int(r["kept"]) for r in records), left),
                 "windows": len(runs)} if records else None
    return replace(first, inputs=inputs, selection=selection)


def within_margin(loaded: Loaded, categories: tuple[int, ...]) -> None:
    """The decoded records of ``categories`` (tracker tracks, service messages) cut to the time window's
    margin, as the measurements are (``loaded.cut``, report_selection.MarginCut): a window's north markers
    and trackers are those near it, whether the inputs are a day's recording or a dataset read around it."""
    from msdc.pipeline.model.time import absolute_time

    if loaded.cut is None or loaded.cut.span is None:
        return
    for cat in categories:
        frame = loaded.frames.get(cat)
        if frame is None or not len(frame):
            continue
        inside = loaded.cut.inside(absolute_time(frame, loaded.date))
        if not inside.all():
            loaded.frames[cat] = frame[inside].reset_index(drop=True)


def _area_overlap(checked: EvaluateChecked, meas: pd.DataFrame) -> str:
    """The note on sectors of different preset areas overlapping where the inputs' reports lie ('' when they
    do not, or when the preset has no area requirement)."""
    from msdc.pipeline.evaluate.sectors import area_overlaps

    areas = {r.area for r in checked.preset.requirements if r.area is not None}
    regions = [r for r in checked.regions if r.area in areas]
    if len({r.area for r in regions}) < 2 or meas.empty:
        return ""
    lat, lon = meas["latitude"].to_numpy(float), meas["longitude"].to_numpy(float)
    fl = (pd.to_numeric(meas["flight_level"], errors="coerce").to_numpy(float, na_value=np.nan)
          if "flight_level" in meas.columns else None)
    return area_overlaps([(r.name, r.area, r.mask(lat, lon, fl, None)) for r in regions],
                         "inputs' reports")


def _keep_frames(loaded: Loaded, tests: list[tuple[str, str]]) -> None:
    """Keep of the decoded frames, once the measurements are built from them, what each sensor's part reads:
    the radar, tracker and service categories whole, and of the other tested sensors' categories (CAT001,
    010, 020) their validity bits by file and offset (the ADS-B frame, the largest, is no more read: its
    reports are in the measurements)."""
    from msdc.pipeline.evaluate.sensor_reports import (
        RADAR_CATEGORY,
        SERVICE_CATEGORIES,
        TRACKER_CATEGORY,
        joined_columns,
    )
    from msdc.pipeline.model.heap import release_free_memory
    from msdc.pipeline.model.report_selection import sensor_parts

    whole = {RADAR_CATEGORY, TRACKER_CATEGORY, *SERVICE_CATEGORIES}
    tested = {int(c) for c in sensor_parts([s for s, _ in tests])["category"]} if tests else set()
    kept = {}
    for cat, frame in loaded.frames.items():
        if cat in whole:
            kept[cat] = frame
        elif cat in tested:
            columns = [c for c in ("file", "offset", *joined_columns(cat)) if c in frame.columns]
            if len(columns) > 2:
                kept[cat] = frame[columns]
    loaded.frames = kept
    release_free_memory()


def _external(options: EvaluateOptions, epoch) -> pd.DataFrame | None:
    """The external reference file read on the run's clock, or None; OptionError naming file and line."""
    if options.reference_file is None:
        return None
    from msdc.pipeline.evaluate.external_reference import read_external_reference

    try:
        return read_external_reference(options.reference_file, epoch)
    except ValueError as exc:
        raise OptionError(f"--reference-file: {exc}") from None


def _reference_outside(external: pd.DataFrame | None, meas: pd.DataFrame, epoch, path) -> list[str]:
    """A warning when no sample of the external reference lies within the reports' time span (another
    day's file: every figure withheld with no word why)."""
    if external is None:
        return []
    t = (meas["time"] - epoch).dt.total_seconds()
    lo, hi = float(t.min()), float(t.max())
    ref_t = external["t_s"].to_numpy(float)
    if len(ref_t) and ((ref_t >= lo) & (ref_t <= hi)).any():
        return []
    when = "%Y-%m-%d %H:%M:%S"
    span = f"{meas['time'].min():{when}} to {meas['time'].max():{when}} UTC"
    held = "the report selection keeps none of its samples"
    if len(ref_t):
        first, last = (epoch + pd.Timedelta(seconds=float(v)) for v in (ref_t.min(), ref_t.max()))
        held = f"its {len(ref_t):,} samples lie from {first:{when}} to {last:{when}} UTC"
    return [f"--reference-file {path}: no sample within the reports' time ({span}): {held}; is it the "
            "recordings' day? Every figure that needs it is withheld"]


def _selected_reference(external: pd.DataFrame | None, checked: EvaluateChecked, epoch, day
                        ) -> pd.DataFrame | None:
    """The external reference cut by the report selection's time window, area and flight levels, as the
    sensors' reports are (--sensor selects sensors, not the reference): kept whole, its samples outside
    the window expected updates of a sensor whose plots there were cut, every one a miss (PD 44 % where
    the built reference gives 98 %). A sample without an altitude is outside any --fl band."""
    from dataclasses import replace

    from msdc.pipeline.model.geodesy import M_PER_FT
    from msdc.pipeline.model.report_selection import select_reports

    selection = checked.selection
    if external is None or selection is None or not selection.active:
        return external
    altitude_ft = pd.to_numeric(external["altitude_ft"], errors="coerce").to_numpy(float)
    samples = pd.DataFrame({"time": epoch + pd.to_timedelta(external["t_s"].to_numpy(float), unit="s"),
                            "latitude": external["latitude"].to_numpy(float),
                            "longitude": external["longitude"].to_numpy(float),
                            "flight_level": altitude_ft / 100.0, "height_m": altitude_ft * M_PER_FT})
    try:
        keep, _ = select_reports(samples, replace(selection, sensors=()), day)
    except ValueError as exc:
        raise OptionError(str(exc)) from None
    return external[keep].reset_index(drop=True)


BAND_TITLES = {"range_nm": "PD per range band", "azimuth_deg": "PD per azimuth sector",
               "flight_level": "PD per flight-level band", "surface": "PD surface and airborne",
               "error_range": "Position error per range band"}
# the output tables' bin edges named with their units (the workbook's and the HTML's headers and formats)
_RANGE = {"x_low": "range_from_nm", "x_high": "range_to_nm"}
EDGE_COLUMNS = {
    "PD per range band": {"low": "range_from_nm", "high": "range_to_nm"},
    "PD per azimuth sector": {"low": "azimuth_from_deg", "high": "azimuth_to_deg"},
    "PD per flight-level band": {"low": "fl_from", "high": "fl_to"},
    "Position error per range band": {"low_nm": "range_from_nm", "high_nm": "range_to_nm"},
    "PD range x azimuth": {**_RANGE, "y_low": "azimuth_from_deg", "y_high": "azimuth_to_deg"},
    "PD range x height": {**_RANGE, "y_low": "height_from_ft", "y_high": "height_to_ft"},
}


def _assemble(results: list[SensorResult]) -> tuple[pd.DataFrame, dict[str, pd.DataFrame], pd.DataFrame]:
    """The scorecard, the named tables (per aircraft, per band, the grids) and the map points of every
    sensor together."""
    from msdc.pipeline.evaluate.scorecard_schema import SCORECARD_COLUMNS

    card = pd.DataFrame([row for r in results for row in r.rows], columns=list(SCORECARD_COLUMNS))
    tables: dict[str, pd.DataFrame] = {}
    per = [r.per_aircraft for r in results if len(r.per_aircraft)]
    if per:
        tables["Per aircraft"] = pd.concat(per, ignore_index=True)
    for key, title in BAND_TITLES.items():
        parts = [r.bands[key].assign(sensor=r.sensor)[["sensor", *r.bands[key].columns]] for r in results
                 if key in r.bands and len(r.bands[key])]
        if parts:
            tables[title] = pd.concat(parts, ignore_index=True)
    for attr, title in (("polar", "PD range x azimuth"), ("vertical", "PD range x height")):
        parts = [getattr(r, attr).assign(sensor=r.sensor) for r in results if getattr(r, attr) is not None]
        if parts:
            frame = pd.concat(parts, ignore_index=True)
            frame = frame[frame["expected"] > 0].reset_index(drop=True)
            tables[title] = frame[["sensor", *[c for c in frame.columns if c != "sensor"]]]
    tables = {k: t.rename(columns=EDGE_COLUMNS.get(k, {})) for k, t in tables.items()}
    points = [r.map_points for r in results if len(r.map_points)]
    return card, tables, pd.concat(points, ignore_index=True) if points else None


def write_evaluation(result: EvaluateResult, *, tx: OutputTransaction | None = None) -> dict[str, Path]:
    """Write the workbook, the JSON and the HTML report the options ask for, staged in ``tx`` (committed by
    the caller; without one, together here). Returns the final paths, by kind."""
    from msdc.pipeline.report.evaluation_html import write_evaluation_html
    from msdc.pipeline.report.evaluation_json import write_evaluation_json
    from msdc.pipeline.report.evaluation_xlsx import write_evaluation_xlsx

    written: dict[str, Path] = {}
    c = result.checked
    title = f"msdc evaluation: {result.checked.preset.title}"
    images = coverage(result) if c.output or c.html else {}
    run = {"inputs": result.loaded.inputs, "parameters": result.parameters}
    with staged(tx) as stage:
        if c.output:
            write_evaluation_xlsx(result.scorecard, stage.path(c.output), result.tables, images, run=run)
            written["workbook"] = c.output
        if c.json:  # the map: HTML only
            write_evaluation_json(result.scorecard, stage.path(c.json), result.tables, run=run)
            written["json"] = c.json
        if c.html:
            write_evaluation_html(result.scorecard, stage.path(c.html), _html_tables(result.tables),
                                  result.map_points, title=title, images=images, run=run)
            written["html"] = c.html
    return written


def _html_tables(tables: dict[str, pd.DataFrame]) -> dict[str, pd.DataFrame]:
    """The tables as the HTML report shows them: of the scorecard per window, the global rows only (a long
    span's windows make many; the workbook and the JSON hold every sector's)."""
    from msdc.pipeline.evaluate.scorecard import GLOBAL

    if PER_WINDOW not in tables:
        return tables
    per = tables[PER_WINDOW]
    title = f"{PER_WINDOW}, global rows (every sector's in the workbook and the JSON)"
    return {(title if k == PER_WINDOW else k): (per[per["sector"] == GLOBAL].reset_index(drop=True)
                                                 if k == PER_WINDOW else t) for k, t in tables.items()}


def coverage(result: EvaluateResult) -> dict[str, bytes]:
    """Per sensor with a site, its polar PD map and vertical coverage diagram as PNG bytes."""
    from msdc.pipeline.report.coverage_figures import coverage_images

    images: dict[str, bytes] = {}
    for r in result.sensors:
        if r.site is None or r.kind not in ("radar", "smr"):
            continue
        vertical = {"site_altitude_m": r.site.altitude_m}
        if r.site.max_elevation_deg is not None:
            vertical["cone_elevation_deg"] = r.site.max_elevation_deg
        if r.site.max_range_nm is not None:
            vertical["max_range_nm"] = r.site.max_range_nm
        images.update(coverage_images(r.polar, r.vertical, r.sensor, **vertical))
    return images


def _in_units(card: pd.DataFrame) -> pd.DataFrame:
    """The scorecard's numbers as the workbook shows them: each in its requirement's unit (a proportion as a
    percentage, to the decimals its size needs), ``n`` a count."""
    from msdc.pipeline.evaluate.catalogue import CATALOGUE
    from msdc.pipeline.report.evaluation_formats import number_text

    out = card.copy()
    units = [CATALOGUE[r].unit for r in card["requirement"]]
    for col in ("value", "ci_low", "ci_high", "threshold", "n"):  # the HTML report's text, "-" for none
        out[col] = [number_text(float(v), col, set(), u) or "-"
                    for v, u in zip(card[col], units, strict=True)]
    return out


def text(result: EvaluateResult) -> str:
    """The scorecard for the terminal: the global, surface/airborne, field-monitor and preset-area rows (the
    per-sector rows are in the outputs), with the notes."""
    from msdc.pipeline.evaluate.presets import RESERVED_SECTORS
    from msdc.pipeline.evaluate.verdicts import verdicts_text
    from msdc.pipeline.report.summary import frame_text

    card = result.scorecard
    if card.empty:
        return "Scorecard: no row (see the notes)"
    areas = {r.area for r in result.checked.preset.requirements if r.area is not None}
    shown = card[card["sector"].isin({*RESERVED_SECTORS, *areas})]  # global, surface, airborne, monitors
    cols = ["sensor", "sector", "requirement", "parameters", "value", "ci_low", "ci_high", "threshold",
            "verdict", "n"]
    out = "Scorecard (" + result.checked.preset.title + "):\n" + frame_text(_in_units(shown[cols]))
    if len(shown) < len(card):
        out += (f"\n  ... and {len(card) - len(shown)} rows per sector of --sectors (in the outputs)")
    out += "\n" + verdicts_text(card)
    notes = result.parameters.get("notes", [])
    if notes:
        out += "\n\nNotes:\n" + "\n".join(f"  {n}" for n in notes)
    return out


__all__ = ["EvaluateOptions", "EvaluateResult", "evaluate_job", "text", "validate", "write_evaluation"]
