"""The track job (``msdc track``): fused IMM tracks per aircraft from every radar and ADS-B report.

``validate`` checks every option before anything is decoded (one-line ``OptionError`` naming the option);
``track_job`` decodes, builds the measurement model (radar covariances from the sensor file's sigmas,
ADS-B from NACp), drops repeated reports, selects the aircraft and sources, and runs
``pipeline.track.track``; ``write_tracks`` writes the table (CSV or Parquet), the JSON summary and the
per-aircraft figures; ``text`` is the terminal's summary.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from msdc.pipeline.jobs.common import (
    NOT_DRAWN,
    Checked,
    FigureChoice,
    JobError,
    OptionError,
    carrying,
    check_aircraft,
    check_decoding,
    check_figure_options,
    check_figures_dir,
    check_output_rows,
    check_tracking,
    choose,
    estimated_noise,
    noise_text,
    output_path,
    parse_sources,
    run_parameters,
    sensor_table,
    spare_inputs,
    tracker_inputs,
    write_not_drawn,
)
from msdc.pipeline.jobs.options import ESTIMATED, TrackOptions, check_declared
from msdc.pipeline.progress import Progress
from msdc.pipeline.report.files import json_value, write_csv, write_json
from msdc.pipeline.report.transaction import OutputTransaction, staged

# the columns of the track table, in order (issue 10); the tracker's other columns follow
TRACK_COLUMNS = ["aircraft_id", "callsign", "address", "time", "time_of_day", "latitude", "longitude",
                 "flight_level", "speed_kt", "track_deg", "turn_rate_dps", "sigma_major_m", "sigma_minor_m",
                 "mode_cv", "mode_turn_left", "mode_turn_right", "coasted", "sources"]
# decimals of the track CSV's float columns (Parquet keeps full precision): below what any sensor resolves
# (1e-7 deg is 1.1 cm; 1 us; 0.01 ft of level, 0.01 kt, 1e-4 deg/s), so that the filter's round-off
# (turn rates of 1.7e-17) and 17-digit floats do not reach the file; mode_* columns take MODE_DECIMALS
CSV_DECIMALS = {"time_of_day": 6, "latitude": 7, "longitude": 7, "flight_level": 2, "vertical_rate_fpm": 1,
                "speed_kt": 2, "track_deg": 3, "turn_rate_dps": 4, "sigma_major_m": 2, "sigma_minor_m": 2,
                "ellipse_orientation_deg": 2, "sigma_speed_kt": 2, "age_s": 6}
MODE_DECIMALS = 4


def csv_decimals(columns) -> dict[str, int]:
    """The decimals of the track CSV's columns that have some: CSV_DECIMALS, mode probabilities
    MODE_DECIMALS (report.files.write_csv rounds the float ones)."""
    places = {name: CSV_DECIMALS.get(name, MODE_DECIMALS if name.startswith("mode_") else None)
              for name in columns}
    return {name: n for name, n in places.items() if n is not None}


# printed under the terminal's table of tracks: what its columns mean
TRACK_LEGEND = (
    "reports = updates + gated + invalid (no usable position or covariance) + out_of_range (3000 km off)\n"
    "tracked_s: first to last update of each segment, summed; update_interval_s: the slowest sensor's\n"
    "median interval between its updates; coasted_s: time without any update beyond that interval, in gaps\n"
    "longer than 1.5 intervals (a missed 4 s scan counts 4 s); after its last update a segment is coasted\n"
    "--max-coast s more, counted in neither")


def validate(options: TrackOptions, *, require_output: bool = False) -> Checked:
    """Check every option, the sensor file and the output paths before any decoding; OptionError if bad.
    ``require_output`` (the command): at least one of -o, --json and --figures; track_job returns the table
    whatever is written."""
    check_tracking(options)
    check_declared(options)
    checked = check_decoding(options)
    check_aircraft(options)
    parse_sources(options.sources)
    checked.output = output_path("-o", options.output, (".csv", ".parquet"))
    checked.json = output_path("--json", options.json, (".json",))
    spare_inputs(options, [(f"-o {checked.output}", checked.output),
                                  (f"--json {checked.json}", checked.json)])
    if options.figures is not None:
        check_figures_dir(options.figures, writable=True)
        spare_inputs(options, [(f"--figures {options.figures}", Path(options.figures))])
    check_figure_options(options)
    if require_output and checked.output is None and checked.json is None and options.figures is None:
        raise OptionError("give at least one output: -o tracks.csv|tracks.parquet, --json or --figures")
    checked.sensors = sensor_table(options.sensors, required=False)
    return checked


@dataclass
class TrackJobResult:
    """The tracker's result, the measurements it was fed (one row per report), labels and parameters."""

    options: TrackOptions
    checked: Checked
    result: object  # pipeline.track.TrackResult
    tracks: pd.DataFrame  # TRACK_COLUMNS first, then the tracker's other columns
    measurements: pd.DataFrame
    labels: pd.DataFrame  # aircraft_id, callsign, address
    parameters: dict
    loaded: object  # the inputs, editions and date; its decoded frames are freed once measurements are built
    noise: pd.DataFrame | None = None  # --noise estimate: per sensor and component, declared and estimated
    warnings: list[str] = field(default_factory=list)  # the run's, validation's first
    figures: FigureChoice | None = None  # the figures --figures drew and left out, once written


def _select(meas: pd.DataFrame, options: TrackOptions) -> pd.DataFrame:
    """The selected aircraft's reports; JobError naming the closest call signs / addresses present."""
    import difflib

    from msdc.pipeline.model.identity import normalise_address, normalise_callsign
    from msdc.pipeline.model.measurements import select

    if options.all_aircraft:
        return meas
    chosen = select(meas, options.callsign, options.address)
    if len(chosen):
        return chosen
    column, wanted = (("callsign", normalise_callsign(options.callsign)) if options.callsign is not None
                      else ("address", normalise_address(options.address)))
    close = difflib.get_close_matches(wanted or "", sorted(set(meas[column].dropna())), n=5, cutoff=0.5)
    hint = f"closest present: {', '.join(close)}" if close else "nothing similar is present"
    raise JobError(f"{'call sign' if column == 'callsign' else 'address'} {wanted} not in the inputs; {hint}")


def track_job(options: TrackOptions, *, progress: Progress | None = None, checked: Checked | None = None,
              command: str = "track") -> TrackJobResult:
    """Validate, decode, build measurements, select, track; nothing is written."""
    from msdc.pipeline.model.identity import aircraft_labels
    from msdc.pipeline.track import track
    from msdc.pipeline.track.feasibility import untrackable, unused_adsb

    started = time.monotonic()
    checked = checked or validate(options)
    with carrying(checked.warnings) as warnings:
        loaded, meas, said = tracker_inputs(options, checked, progress, "the tracks' times")
        warnings += said
        joined = int(meas.attrs.get("joined_by_track_number", 0))
        unidentified = int(meas.attrs.get("unidentified", 0))
        if unidentified and options.all_aircraft:
            warnings.append(f"{unidentified} report(s) with no identity (no address, call sign or Mode 3/A "
                            "code, nor a radar track number joining them to an aircraft), not tracked")
        meas = _select(meas, options)
        check_output_rows(meas, options)
        noise = None
        if options.noise in ESTIMATED:
            meas, noise = estimated_noise(meas, checked.sensors, options)
        result = track(meas, step_s=float(options.step_s), max_coast_s=float(options.max_coast_s),
                       tpm=options.tpm, smooth=options.smooth, smoother=options.smoother)
        if result.tracks.empty:
            raise JobError(untrackable(meas))
        warnings += unused_adsb(meas)
        labels = aircraft_labels(meas)
        tracks = with_labels(result.tracks, labels)
        params = {**run_parameters(options, loaded, started, command), **result.parameters,
                  "sources": list(parse_sources(options.sources)), "callsign": options.callsign,
                  "address": options.address, "all": bool(options.all_aircraft),
                  "radar_plots_joined_by_track_number": joined,
                  "unidentified_reports_not_tracked": unidentified, "noise": options.noise}
        return TrackJobResult(options, checked, result, tracks, meas, labels, params, loaded, noise, warnings)


def with_labels(tracks: pd.DataFrame, labels: pd.DataFrame) -> pd.DataFrame:
    """The tracker's table with each aircraft's call sign and address ("" when none), TRACK_COLUMNS first;
    the other columns are not copied (a day's table is ~0.35 GB)."""
    by_id = labels.set_index("aircraft_id")
    named = {c: tracks["aircraft_id"].map(by_id[c]).fillna("") for c in ("callsign", "address")}
    out = tracks.assign(**named)
    return out[TRACK_COLUMNS + [c for c in out.columns if c not in TRACK_COLUMNS]]


def summary(result: TrackJobResult) -> dict:
    """The JSON document: parameters, inputs, and per aircraft its span, coasted time and per-sensor
    reports, updates, gated reports and NIS mean."""
    res = result.result
    labels = result.labels.set_index("aircraft_id")
    aircraft = []
    for row in res.aircraft.to_dict("records"):
        ident = row["aircraft_id"]
        sens = res.sensors[res.sensors["aircraft_id"] == ident].drop(columns="aircraft_id")
        aircraft.append({
            "aircraft_id": ident, "callsign": labels.at[ident, "callsign"] if ident in labels.index else "",
            "address": labels.at[ident, "address"] if ident in labels.index else "",
            **{k: json_value(v) for k, v in row.items() if k != "aircraft_id"},
            "sensors": [{k: json_value(v) for k, v in s.items()} for s in sens.to_dict("records")]})
    doc = {"parameters": result.parameters, "inputs": result.loaded.inputs, "aircraft": aircraft}
    if result.noise is not None:
        doc["noise"] = {"passes": result.noise.attrs.get("passes"),
                        "sensors": [{k: json_value(v) for k, v in r.items()}
                                    for r in result.noise.to_dict("records")],
                        "aircraft_raised": [{k: json_value(v) for k, v in r.items()}
                                            for r in result.noise.attrs.get("aircraft", [])]}
    return doc


def sensor_totals(sensors: pd.DataFrame) -> pd.DataFrame:
    """The tracker's per-aircraft sensor table summed per sensor: aircraft, reports, updates, gated, invalid,
    out_of_range, and the NIS mean over the updates that have one (each aircraft's mean weighted by its
    updates; NaN where no aircraft has one)."""
    # an aircraft without a NIS (its updates started the track: no innovation yet) weighs nothing, not a 0
    weight = sensors["updates"].where(sensors["nis_mean"].notna(), 0)
    s = sensors.assign(nis_sum=sensors["nis_mean"].fillna(0.0) * weight, nis_weight=weight)
    out = s.groupby("sensor_id", sort=True).agg(
        aircraft=("aircraft_id", "nunique"), reports=("reports", "sum"), updates=("updates", "sum"),
        gated=("gated", "sum"), invalid=("invalid", "sum"), out_of_range=("out_of_range", "sum"),
        nis_sum=("nis_sum", "sum"), nis_weight=("nis_weight", "sum")).reset_index()
    with np.errstate(invalid="ignore", divide="ignore"):
        nis = out["nis_sum"].to_numpy(float) / out["nis_weight"].to_numpy(float)
    return out.drop(columns=["nis_sum", "nis_weight"]).assign(
        nis_mean=np.where(out["nis_weight"] > 0, nis, np.nan))


def write_tracks(result: TrackJobResult, *, tx: OutputTransaction | None = None,
                 progress: Progress | None = None, workers: int | None = None) -> dict[str, Path]:
    """Write the track table (CSV: times as ISO 8601 UTC; Parquet: tz-aware timestamps), the JSON and
    the figures, as the options ask, staged in ``tx`` (committed by the caller; without one, the files are
    committed together here): a failure leaves nothing behind. The figures are drawn on ``workers``
    processes (None: every core). Returns the final paths, by kind."""
    written: dict[str, Path] = {}
    out, js = result.checked.output, result.checked.json
    with staged(tx) as stage:
        if out is not None:
            from msdc.pipeline.report.tables import write_parquet

            if out.suffix.lower() == ".csv":
                write_csv(result.tracks, stage.path(out), decimals=csv_decimals(result.tracks.columns))
            else:
                write_parquet(result.tracks, stage.path(out))
            written["tracks"] = out
        if js is not None:
            write_json(summary(result), stage.path(js))
            written["json"] = js
        if result.options.figures is not None:
            written.update(_track_figures(result, stage.folder(result.options.figures), stage, progress,
                                          workers))
    return written


def _track_figures(result: TrackJobResult, folder: Path, stage: OutputTransaction,
                   progress: Progress | None, workers: int | None) -> dict[str, Path]:
    """The chosen aircraft's figures (--figures-limit, --figures-only) drawn in ``folder`` (staged), the
    others listed in figures_not_drawn.txt: their final paths, by kind."""
    from msdc.pipeline.report.figure_pool import FigureError, render
    from msdc.pipeline.report.track_figures import figure_names, figure_tasks

    names = figure_names(result.tracks)
    ids = list(names)
    choice = choose([name for name, _ in names.values()], result.options.figures_limit,
                    result.options.figures_only)
    result.figures = choice
    chosen = [ids[i] for i in choice.drawn]
    if progress:
        progress.stage(f"Drawing {len(chosen)} of {len(ids)} track figures")
    try:
        paths = render(figure_tasks(result, folder, chosen), len(chosen), workers=workers, progress=progress)
    except FigureError as exc:
        raise JobError(f"--figures {result.options.figures}: {exc}; nothing written") from exc
    out = {f"figure {ident}": stage.final(p) for ident, p in zip(chosen, paths, strict=True)}
    listed = write_not_drawn(folder, "track", result.options, choice)
    if listed is not None:
        out["figures not drawn"] = stage.final(listed)
    return out


def text(result: TrackJobResult) -> str:
    """Per aircraft: span, updates, gated reports, coasted time; per sensor over every aircraft: aircraft,
    reports, updates, gated, NIS mean (the per-aircraft split is in the JSON: a day of traffic would print
    thousands of lines)."""
    res = result.result
    if res.aircraft.empty:
        return "no track: no report with a usable position and covariance"
    ac = res.aircraft.merge(result.labels, on="aircraft_id", how="left")
    cols = [c for c in ("aircraft_id", "callsign", "segments", "reports", "updates", "gated", "invalid",
                        "out_of_range", "tracked_s", "update_interval_s", "coasted_s") if c in ac]
    out = ("Tracks:\n" + ac[cols].to_string(index=False, float_format=lambda v: f"{v:.1f}", na_rep="-")
           + "\n" + TRACK_LEGEND
           + "\n\nSensors:\n" + sensor_totals(res.sensors).to_string(
               index=False, float_format=lambda v: f"{v:.2f}", na_rep="-"))
    return out + noise_text(result.noise)


def side_files(options: TrackOptions) -> list[Path]:
    """The figures track --figures DIR may write, as globs (one per aircraft: track_<name>.png, and the list
    of those not drawn)."""
    return [] if options.figures is None else [Path(options.figures) / "track_*.png",
                                               Path(options.figures) / NOT_DRAWN]


__all__ = ["TRACK_COLUMNS", "TrackJobResult", "TrackOptions", "sensor_totals", "side_files", "summary",
           "text", "track_job", "validate", "write_tracks"]
