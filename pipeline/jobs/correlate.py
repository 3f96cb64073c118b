"""The correlate job (``msdc correlate``): radar against ADS-B per aircraft, the thesis algorithm.

``validate`` checks every option, the sensor file and the outputs before anything is decoded;
``correlate_job`` decodes straight into measurements (only the columns ``correlate_columns`` names), marks
duplicates and jumps once, filters, correlates and, with ``quality``, runs the quality step; nothing is
written. ``write_correlation`` writes the JSON summary and the workbook, whose track figure and Parquet
tables a child process draws meanwhile (``prepare_correlation_writers`` starts it early).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import pandas as pd

from msdc.pipeline.jobs.common import (
    QUALITY_FIGURE_GLOBS,
    Checked,
    JobError,
    OptionError,
    carrying,
    check_aircraft,
    check_beside,
    check_decoding,
    check_workbook,
    filter_parameters,
    filters_asked,
    filters_removed,
    marked_measurements,
    output_path,
    quality_figures,
    quality_inputs,
    quality_step,
    real_output,
    run_parameters,
    selection_note,
    side_files_beside,
)
from msdc.pipeline.jobs.options import CorrelateOptions, check_declared
from msdc.pipeline.model.heap import release_free_memory
from msdc.pipeline.model.load import Loaded
from msdc.pipeline.progress import Progress
from msdc.pipeline.report.outputs import Background, BackgroundFailed, Prepared
from msdc.pipeline.report.transaction import OutputTransaction, staged

if TYPE_CHECKING:
    from msdc.pipeline.correlate.results import CorrelationRun
    from msdc.pipeline.quality.quality_run import QualityResult


FIGURE_WINDOWS = 6  # correlate --quality: slotting and lag figures of the first windows only
# the categories a --pairs value needs, one of each group (CAT048 and CAT021 by default; two radars: CAT048)
NEEDS = {"mlat-adsb": ((10, 20), (21,)), "smr-mlat": ((10,),), "radar-radar": ((48,),)}


def validate(options: CorrelateOptions) -> Checked:
    """Check every option, the sensor file and the output paths, before any decoding; OptionError if bad."""
    from msdc.pipeline.report.tables import TABLE_FILES, parquet_path

    check_declared(options)
    checked = check_decoding(options)
    check_aircraft(options)
    if options.tables == "parquet" and options.output is None:
        raise OptionError("--tables parquet: needs -o (the tables are written beside the workbook)")
    checked.output = output_path("-o", options.output, (".xlsx",))
    if checked.output is not None:  # the figure beside it, and the tables that may go to Parquet beside it
        base = real_output(checked.output)
        beside = [("track figure", base.with_name(f"{base.stem}_tracks.png"))]
        beside += [(f"{name} table", parquet_path(base, name)) for name in TABLE_FILES
                   if options.tables != "xlsx"]
        check_beside("-o", checked.output, beside)
    checked.warnings += check_workbook(options, checked,
                                       figure_windows=FIGURE_WINDOWS if options.quality else None)
    return checked


@dataclass
class CorrelateResult:
    """A correlation run, the measurements it used (the columns ``correlate_columns`` names), the quality
    result (with ``quality``) and the run's warnings (validation's first)."""

    options: CorrelateOptions
    checked: Checked
    run: CorrelationRun
    measurements: pd.DataFrame
    loaded: Loaded
    quality: QualityResult | None = None
    warnings: list[str] = field(default_factory=list)


def _filtered_away(exc, meas_all: pd.DataFrame, options: CorrelateOptions) -> str | None:
    """The message when the aircraft's ADS-B reports exist but the quality filters removed them all."""
    from msdc.pipeline.model.measurements import select

    asked = _filters_given(options)
    if "ADS-B" not in exc.missing_in or not asked:
        return None
    chosen = select(meas_all, options.callsign, options.address)
    n = int((chosen["sensor_kind"] == "adsb").sum())
    if n == 0:
        return None
    removed = f"{' and '.join(asked)} removed all {n}"
    text = (f"{removed} ADS-B reports of the inputs" if options.all_aircraft
            else f"{exc.wanted}: {removed} of its ADS-B reports")
    return f"{text}; lower the filter or leave it out"


def _filters_given(options: CorrelateOptions) -> list[str]:
    """The ADS-B filters given, as written on the command line."""
    return [f for f, on in ((f"--min-nic {options.min_nic}", options.min_nic is not None),
                            (f"--min-nacp {options.min_nacp}", options.min_nacp is not None),
                            ("--drop-jumps", options.drop_jumps)) if on]


def _filtered_aircraft(meas_all: pd.DataFrame, meas: pd.DataFrame, options: CorrelateOptions) -> list[str]:
    """--all with ADS-B filters: a warning naming the aircraft seen by radar and ADS-B whose ADS-B reports
    the filters removed all of (they were left out of the run in silence; --callsign says it as an error)."""
    asked = _filters_given(options)
    if not options.all_aircraft or not asked:
        return []

    def both(frame: pd.DataFrame) -> set:
        kinds = frame[["aircraft_id", "sensor_kind"]].dropna().astype(str).drop_duplicates()
        return set(kinds.loc[kinds["sensor_kind"] == "radar", "aircraft_id"]) & \
            set(kinds.loc[kinds["sensor_kind"] == "adsb", "aircraft_id"])

    gone = sorted(both(meas_all) - both(meas))
    if not gone:
        return []
    adsb = meas_all[(meas_all["sensor_kind"] == "adsb").to_numpy(bool)]
    counts = adsb["aircraft_id"].astype(str).value_counts()
    first = adsb.drop_duplicates("aircraft_id")
    names = dict(zip(first["aircraft_id"].astype(str), first["callsign"], strict=True))
    named = "; ".join(f"{names[a] if pd.notna(names.get(a)) else a} ({a}, {int(counts.get(a, 0)):,} reports)"
                      for a in gone)
    return [f"{' and '.join(asked)} removed all ADS-B reports of {len(gone)} aircraft seen by radar and "
            f"ADS-B, which are not correlated: {named}"]


# the measurement columns correlate --quality's slotting figures read (pipeline.report.quality_figures)
SLOTTING_FIGURE_INPUTS = ["time", "sensor_kind", "sensor_id", "aircraft_id", "callsign", "address",
                          "latitude", "longitude"]


def correlate_columns(options: CorrelateOptions) -> list[str]:
    """The measurement columns a correlate job builds, in schema order: what correlate, mark_once, the
    filters asked for, far_separations and the two-targets check (pipeline.model.mixed) read, with ``fill``
    "predict" what the tracker reads, and with ``quality`` what the quality step (``quality_columns``) and
    its slotting figures read. Half the bytes of a row on a large recording."""
    from msdc.pipeline.correlate.correlation import CORRELATION_INPUTS
    from msdc.pipeline.model.dedup import DEDUP_KEYS
    from msdc.pipeline.model.jumps import JUMP_INPUTS
    from msdc.pipeline.model.mixed import MIXED_INPUTS
    from msdc.pipeline.model.schema import MEASUREMENT_COLUMNS, column_names
    from msdc.pipeline.model.site_check import FAR_SEPARATION_INPUTS

    need = {*CORRELATION_INPUTS, *DEDUP_KEYS, "sensor_kind", "sensor_id", *JUMP_INPUTS,
            *FAR_SEPARATION_INPUTS, *MIXED_INPUTS}
    if options.fill == "predict":
        from msdc.pipeline.track.tracker import FILTER_INPUTS

        need |= set(FILTER_INPUTS)
    need |= {"nucp_nic"} if options.min_nic is not None else set()
    need |= {"nacp"} if options.min_nacp is not None else set()
    if options.quality:  # (the ADS-B reference: correlate has no --reference)
        need |= set(quality_inputs("adsb")) | set(SLOTTING_FIGURE_INPUTS)
    return column_names(need & set(MEASUREMENT_COLUMNS))  # the job-wide flags are added by mark_once


def correlate_job(options: CorrelateOptions, *, progress: Progress | None = None,
                  checked: Checked | None = None, command: str = "correlate") -> CorrelateResult:
    """Validate, decode, build measurements, filter, correlate (and assess quality); nothing is written."""
    from msdc.pipeline.correlate.correlation import NoOverlap, TooManySlots, correlate
    from msdc.pipeline.correlate.verdict import mention_mixed
    from msdc.pipeline.model.aircraft import NoSuchAircraft
    from msdc.pipeline.model.site_check import far_separations
    from msdc.pipeline.quality.filters import apply_filters, filter_warnings
    from msdc.pipeline.quality.tables import workbook_sheets

    started = time.monotonic()
    checked = checked or validate(options)
    with carrying(checked.warnings) as warnings:
        if progress:
            progress.stage("Processing data files")
        columns = correlate_columns(options)
        loaded, meas_all, said = marked_measurements(
            options, checked, progress, "Pre-processing data", split_adsb=options.split_adsb, columns=columns,
            flags=None if options.quality or columns is None else ["jump"], needs=NEEDS.get(options.pairs))
        warnings += said
        meas, removed = apply_filters(meas_all, drop_jumps=options.drop_jumps, min_nic=options.min_nic,
                                      min_nacp=options.min_nacp)
        if progress:  # the thesis tool's stage names
            progress.stage("Slotting data")
            progress.stage("Correlating data")
        try:
            run = correlate(meas, callsign=options.callsign, address=options.address,
                            all_aircraft=options.all_aircraft, slot_s=options.slot_s, gap_s=options.gap_s,
                            pairs=options.pairs, split_adsb=options.split_adsb, fill=options.fill)
        except NoSuchAircraft as exc:
            raise JobError((_filtered_away(exc, meas_all, options) or str(exc)) + selection_note(options)
                           ) from exc
        except NoOverlap as exc:
            raise JobError(str(exc)) from exc
        except TooManySlots as exc:
            raise OptionError(f"--slot {options.slot_s:g}: the overlap windows would need more than "
                              f"{exc.limit:,} slots (at least {exc.slots:,}); use a longer --slot") from exc
        mention_mixed([w.summary for w in run.windows], meas_all.attrs.get("mixed_pairs", ()))
        run.inputs = loaded.inputs
        run.filters = filters_removed(options, removed)
        warnings += filter_warnings(removed, options.min_nic, options.min_nacp)
        gone = _filtered_aircraft(meas_all, meas, options)
        warnings += gone
        run.parameters = {**run.parameters, **run_parameters(options, loaded, started, command),
                          "filters": filter_parameters(options, removed)}
        if gone:  # the outputs say it too: the aircraft is in none of their tables
            run.parameters["notes"] = [*run.parameters.get("notes", []), *gone]
        warnings += far_separations([w.summary for w in run.windows], meas, checked.sensors,
                                    str(options.sensors))
        warnings += _nothing_correlated(run, options)
        result = CorrelateResult(options, checked, run, meas, loaded, warnings=warnings)
        if options.quality:
            if progress:
                progress.stage("Analysing data quality")
            # the quality sheets describe every report; radar accuracy, biases and reference points use the
            # reference the filters left, as the correlation does
            result.quality = quality_step(meas_all, checked.sensors, options,
                                          reference_meas=meas if filters_asked(options) else None)
            run.parameters["notes"] = [*run.parameters.get("notes", []), *result.quality.notes]
            warnings += result.quality.sheets["Radar biases"].attrs.get("distrust", [])
            run.extra_sheets.update(workbook_sheets(result.quality.sheets))
            lead_quality(run, result.quality)
        return result


def lead_quality(run: CorrelationRun, quality: QualityResult) -> None:
    """The quality step's numbers a report leads with: per window the radar's range and azimuth errors
    against ADS-B inside it (pipeline.correlate.matched.window_accuracy), per radar its accuracy and fitted
    biases over the run (``run.radars``, RADAR_KEYS: the Radar accuracy sheet's all-aircraft row and the
    Radar biases sheet)."""
    from msdc.pipeline.correlate.matched import window_accuracy
    from msdc.pipeline.correlate.results import RADAR_KEYS
    from msdc.pipeline.model.measurements import sensor_id

    for w, numbers in zip(run.windows, window_accuracy([w.summary for w in run.windows], quality.errors),
                          strict=True):
        w.summary.update(numbers)
    biases, accuracy = quality.sheets.get("Radar biases"), quality.sheets.get("Radar accuracy")
    if biases is None or biases.empty:
        run.radars = []
        return
    overall = accuracy[accuracy["callsign"] == "(all)"].set_index(["sac", "sic"]) if accuracy is not None \
        else pd.DataFrame()
    ids = sensor_id(48, biases["sac"], biases["sic"]).tolist()
    radars = []
    for ident, row in zip(ids, biases.to_dict("records"), strict=True):
        stats = overall.loc[(row["sac"], row["sic"])] if (row["sac"], row["sic"]) in overall.index else {}
        radars.append({key: row.get(key, stats.get(key) if len(stats) else None) for key in RADAR_KEYS}
                      | {"radar_sensor": ident})
    run.radars = radars


def _nothing_correlated(run: CorrelationRun, options: CorrelateOptions) -> list[str]:
    """A warning when every window was skipped (the run still reports them, and exits 0 as a run of --all
    without overlap does): with the cause when every one is shorter than a slot."""
    if run.windows:
        return []
    short = bool(run.skipped) and all("shorter than one slot" in s.reason for s in run.skipped)
    why = (f": every one is shorter than one slot (--slot {options.slot_s:g}); use a shorter --slot"
           if short else "")
    return [f"no window correlated, {len(run.skipped)} skipped{why} (the reasons are listed with the "
            "skipped windows)"]


def figure_windows_note(n_windows: int, max_windows: int | None = None) -> str | None:
    """What correlate --quality leaves out of its per-window figures (said on the Figures sheet and the
    terminal), None when every window has its figures; ``max_windows`` FIGURE_WINDOWS unless given."""
    max_windows = FIGURE_WINDOWS if max_windows is None else max_windows
    if n_windows <= max_windows:
        return None
    return (f"slotting and lag figures for the first {max_windows} of {n_windows} windows only (the Lag "
            "charts and Slot charts sheets chart more)")


def _track_figure(run: CorrelationRun, png: Path, sensors: pd.DataFrame) -> None:
    """The map of the run's tracks beside the workbook (report.figures.track_figure)."""
    from msdc.pipeline.report.figures import track_figure  # matplotlib: only where a figure is drawn

    track_figure(run, png, sensors)


def _track_figure_and_tables(run: CorrelationRun, png: Path, sensors: pd.DataFrame, out: Path,
                             tables: list[str]) -> dict:
    """The outputs written beside the workbook in a child while the workbook is written: the Parquet
    tables named in ``tables`` (pipeline.report.excel.write_parquet_tables, whose result goes back) and the
    track figure."""
    from msdc.pipeline.report.excel import write_parquet_tables

    parquet = write_parquet_tables(run, out, names=tables)
    _track_figure(run, png, sensors)
    return parquet


def _warm_track_figure() -> None:
    """What the track figure and the Parquet tables first need: matplotlib, pyarrow's Parquet writer,
    pyproj's ellipsoid and a drawn text (fonts)."""
    import io

    import pyarrow.parquet  # noqa: F401 - imported now, used by write_parquet_tables

    import msdc.pipeline.report.excel  # noqa: F401
    from msdc.pipeline.model.geodesy import wgs84_geod
    from msdc.pipeline.report.figures import new_figure

    wgs84_geod()
    fig = new_figure(1.0, 1.0, dpi=10)
    fig.text(0.5, 0.5, "0", fontweight="bold")
    with io.BytesIO() as sink:
        fig.savefig(sink, format="png")


def prepare_correlation_writers(options: CorrelateOptions) -> Prepared | None:
    """When the run writes a workbook, a child that gets ready now to write its Parquet tables and draw its
    track figure (imports matplotlib and pyarrow on the other core while this process decodes and
    correlates); pass it to write_correlation, or close() it when the run ends without writing."""
    return Prepared(_track_figure_and_tables, warm=_warm_track_figure) if options.output else None


def _drawn(drawing: Background, png: Path, tables: list[Path] = ()) -> dict:
    """Wait for the figure (and Parquet tables, their paths ``tables``) written in the background and return
    the tables' rows and columns; a child that died as a JobError naming the files."""
    try:
        return drawing.wait()
    except BackgroundFailed as exc:
        if tables:
            names = ", ".join(str(p) for p in [*tables, png])
            what = "table" if len(tables) == 1 else "tables"
            raise JobError(f"{names}: the {what} and figure were not written ({exc})") from exc
        raise JobError(f"{png}: the figure was not drawn ({exc})") from exc


def write_correlation(result: CorrelateResult, progress: Progress | None = None,
                      max_windows: int | None = None, prepared: Prepared | None = None, *,
                      tx: OutputTransaction | None = None) -> dict[str, Path]:
    """Write what the options ask for: JSON summary, workbook with its track figure (and, with quality,
    the quality and per-window figures), staged in ``tx`` (committed by the caller; without one, the files
    are committed together here). Returns what was written, by kind. ``prepared``
    (prepare_correlation_writers) draws the track figure; it is used up or closed here."""
    release_free_memory()  # what the job freed (the CLI lets go of the measurements), before the tables
    try:
        with staged(tx) as stage:
            shown = FIGURE_WINDOWS if max_windows is None else max_windows
            return _write_correlation(result, stage, progress, shown, prepared)
    finally:
        if prepared is not None:
            prepared.close()  # a no-op once started


# The figure's child gets the run's slots (what the map reads) and writes the slot table beside the workbook
# (the lag table is written here meanwhile) only up to this many rows of slots and lags: the day's 0.5 M
# rows, not the week's 3.3 M (the child would build another 0.3 GB): then both are written here, in batches
CHILD_MAX_TABLE_ROWS = 1_000_000


CHILD_TABLES = ("slots",)  # the tables the child can write from the slots it is sent


def _track_run(run: CorrelationRun) -> CorrelationRun:
    """What the track figure reads of a run (summaries, slots, parameters), without the lag tables."""
    from msdc.pipeline.correlate.results import CorrelationRun, WindowResult

    return CorrelationRun(windows=[WindowResult(w.summary, w.slots, w.lags.iloc[:0]) for w in run.windows],
                          parameters=run.parameters)


def _write_correlation(result: CorrelateResult, stage: OutputTransaction, progress: Progress | None,
                       max_windows: int, prepared: Prepared | None = None) -> dict[str, Path]:
    """write_correlation's files, staged in ``stage``: the child drawing the map starts first."""
    from msdc.pipeline.report.tables import parquet_tables, table_length

    written: dict[str, Path] = {}
    run, checked = result.run, result.checked
    drawing = None
    if checked.output:  # the child starts first: the map takes it longest
        out, mode = stage.path(checked.output), result.options.tables
        png = out.with_name(out.stem + "_tracks.png")
        in_child = [name for name in parquet_tables(run, mode) if name in CHILD_TABLES]
        rows = table_length(run, "slots") + table_length(run, "correlation")
        if rows > CHILD_MAX_TABLE_ROWS:  # a long run's tables are written here, in batches
            in_child = []
        args = (_track_run(run), png, checked.sensors, out, in_child)
        drawing = prepared.start(*args) if prepared is not None else Background(_track_figure_and_tables,
                                                                                 *args)
    try:
        from msdc.pipeline.report.files import write_json
        from msdc.pipeline.report.summary import run_to_json

        if checked.json:
            write_json(run_to_json(run), stage.path(checked.json))
            written["json"] = checked.json
        if drawing is not None:
            written.update(_write_workbook(result, stage, progress, max_windows, drawing, png, in_child))
    finally:
        if drawing is not None:
            drawing.cancel()  # only still running when writing failed
    return written


def _write_workbook(result: CorrelateResult, stage: OutputTransaction, progress: Progress | None,
                    max_windows: int, drawing: Background, png: Path, in_child: list[str]) -> dict[str, Path]:
    """The workbook (and with quality its figures) while ``drawing`` writes the map ``png`` and the Parquet
    tables ``in_child``; the other Parquet tables are written here. Returns the final paths, by kind."""
    from msdc.pipeline.report.excel import write_report
    from msdc.pipeline.report.tables import parquet_path

    run, out = result.run, stage.path(result.checked.output)
    if progress:
        progress.stage("Writing report")
    images = None
    if result.quality is not None:
        from msdc.pipeline.report.figures import lag_figure
        from msdc.pipeline.report.quality_figures import slotting_figure
        from msdc.pipeline.report.summary import window_label

        images = dict(quality_figures(result.quality, out.parent, out.stem, stage))
        shown = result.measurements[SLOTTING_FIGURE_INPUTS]  # what the figures read, not every column copied
        is_radar = (shown["sensor_kind"] == "radar").to_numpy(bool)
        radar, adsb = shown[is_radar], shown[~is_radar]
        del shown
        for i, w in enumerate(run.windows[:max_windows]):
            label = window_label(w.summary)
            images[f"{label}: latitude and longitude before and after slotting"] = slotting_figure(
                w, radar, adsb, out.with_name(f"{out.stem}_slotting_{i + 1}.png"))
            images[f"{label}: coefficient against lag"] = lag_figure(
                w, out.with_name(f"{out.stem}_lags_{i + 1}.png"))
    files = [stage.final(parquet_path(out, name)) for name in in_child]
    note = figure_windows_note(len(run.windows), max_windows) if images is not None else None

    def waited() -> dict:
        return _drawn(drawing, stage.final(png), files)

    tables = write_report(run, out, figure_png=png, images=images, images_note=note or "",
                          tables=result.options.tables, figure_ready=waited,
                          tables_written=waited if in_child else None, elsewhere=in_child)
    written = {"report": result.checked.output, "figure": stage.final(png)}
    written.update((f"image {name}", stage.final(path)) for name, path in (images or {}).items())
    written.update((f"table {p.stem.removeprefix(out.stem + '_')}", stage.final(p)) for p in tables)
    return written


def side_files(checked: Checked) -> list[Path]:
    """The side files correlate -o may write beside the workbook, as globs: the track figure, the Parquet
    tables, and --quality's figures."""
    from msdc.pipeline.report.tables import TABLE_FILES

    return side_files_beside(checked.output, ("_tracks.png", *(f"_{name}.parquet" for name in TABLE_FILES),
                                              *QUALITY_FIGURE_GLOBS, "_slotting_*.png", "_lags_*.png"))


__all__ = ["CorrelateOptions", "CorrelateResult", "correlate_columns", "correlate_job", "figure_windows_note",
           "lead_quality", "prepare_correlation_writers", "side_files", "validate", "write_correlation"]
