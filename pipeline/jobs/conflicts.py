"""The conflicts job (``msdc conflicts``): post-event conflict analysis of recorded traffic.

Options are validated before anything is decoded (``validate``: one-line ``OptionError`` naming the
option). ``conflict_job`` decodes and builds the measurements as ``msdc track`` does, tracks every
aircraft with the IMM, predicts each track at every output step and look-ahead
(`pipeline.conflict.predict`), computes PC for every close pair, and derives the alert events, the
losses of separation (geometric proximities below the minima where both aircraft are reported, not
separation infringements), the warning time per loss and horizon, and which alerts were false; the
aircraft samples counted are those the selection options keep (`pipeline.model.selection`), and every
table names each aircraft by call sign and Mode 3/A code as well as address. ``write_conflicts`` writes
CSV (alerts; losses and warning times in files named beside it) or an xlsx workbook, all files staged
and moved into place together (report.transaction).
"""

from __future__ import annotations

import glob
import math
import time
from collections.abc import Iterator
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np
import pandas as pd

from msdc.pipeline.jobs.common import (
    NOT_DRAWN,
    Checked,
    FigureChoice,
    JobError,
    OptionError,
    below_updates,
    carrying,
    check_beside,
    check_decoding,
    check_figure_options,
    check_figures_dir,
    check_output_rows,
    check_selection,
    check_tracking,
    choose,
    estimated_noise,
    output_path,
    parse_sources,
    real_output,
    run_parameters,
    sensor_table,
    spare_inputs,
    tracker_inputs,
    write_not_drawn,
)
from msdc.pipeline.jobs.options import ESTIMATED, ConflictOptions, check_declared
from msdc.pipeline.progress import Progress
from msdc.pipeline.report.figure_pool import FigureTask
from msdc.pipeline.report.files import json_value, write_csv, write_json
from msdc.pipeline.report.transaction import OutputTransaction, staged

# aircraft are tracked again for their predictions in batches of about this many reports, each batch's
# filter histories (~1.4 kB a report) held at a time: ~0.35 GB
PREDICTION_BATCH_REPORTS = 250_000


def parse_horizons(value) -> tuple[float, ...]:
    """'20,60,120' (seconds) -> (20.0, 60.0, 120.0); OptionError naming the bad item."""
    items = value.split(",") if isinstance(value, str) else list(value or ())
    whole = value if isinstance(value, str) else ",".join(str(v) for v in items)
    out = []
    for i, item in enumerate(items):
        try:
            h = float(item)
        except (TypeError, ValueError):
            which = f"item {i + 1} " if len(items) > 1 else ""
            text = "is empty" if not str(item).strip() else f"{str(item).strip()!r} is not a number"
            raise OptionError(f"--horizon {whole!r}: {which}{text}; give look-aheads in seconds, "
                              "e.g. 20,60,120") from None
        out.append(h)
    if not out:
        raise OptionError("--horizon: give at least one look-ahead in seconds, e.g. 20,60,120")
    if len(set(out)) != len(out):
        raise OptionError(f"--horizon {value!r}: a look-ahead is repeated")
    return tuple(sorted(out))


def validate(options: ConflictOptions) -> Checked:
    """Check every option, the sensor file and the output paths before any decoding; OptionError if bad."""
    step = check_tracking(options)
    horizons = parse_horizons(options.horizons_s)
    check_declared(replace(options, horizons_s=horizons))
    check_selection(options)
    checked = check_decoding(options)
    for h in horizons:
        if abs(h / step - round(h / step)) > 1e-9:
            raise OptionError(f"--horizon {h:g}: must be a whole multiple of --step ({step:g} s)")
    tol = options.vertical_tolerance_ft
    if not tol < options.vertical_ft:
        raise OptionError(f"--vertical-tolerance-ft {tol!r}: must be less than --vertical-ft "
                          f"({options.vertical_ft:g})")
    t = options.threshold
    if not isinstance(t, int | float) or not math.isfinite(t) or not 0.0 < t < 1.0:
        raise OptionError(f"--threshold {t!r}: must be a probability strictly between 0 and 1")
    parse_sources(options.sources)
    checked.output = output_path("-o", options.output, (".csv", ".xlsx"))
    checked.json = output_path("--json", options.json, (".json",))
    if (options.callsign, options.address, options.all_aircraft) != (None, None, True):
        raise OptionError("callsign, address, all_aircraft: msdc conflicts tracks every aircraft (their "
                          "pairs are the point); leave them out")
    beside = []
    if checked.output is not None:  # the command requires -o; from Python, whatever is given is written
        csv = checked.output.suffix.lower() == ".csv"
        companions = companion_paths(real_output(checked.output)) if csv else {}
        check_beside("-o", checked.output, [(COMPANION_NOUNS[k], path) for k, path in companions.items()])
        beside = [checked.output, *companions.values()]
    spare_inputs(options, [(f"-o {checked.output}", p) for p in beside]
                 + [(f"--json {checked.json}", checked.json)])
    if options.figures is not None:
        check_figures_dir(options.figures, writable=True)
        spare_inputs(options, [(f"--figures {options.figures}", Path(options.figures))])
    check_figure_options(options)
    checked.sensors = sensor_table(options.sensors, required=False)
    return checked


def _without_lone_reports(meas: pd.DataFrame) -> tuple[pd.DataFrame, list[str]]:
    """The measurements without the aircraft reported once in the whole run, and a warning naming them: one
    report gives no velocity to predict from, and a damaged address makes such a ghost beside its aircraft
    (a one-report '3D0312' under MAS72's call sign alerted against MAS72 with a PC of 1)."""
    counts = meas["aircraft_id"].astype(str).value_counts()
    lone = counts.index[counts.to_numpy() == 1]
    if not len(lone) or len(lone) == len(counts):
        return meas, []
    gone = meas["aircraft_id"].astype(str).isin(lone).to_numpy(bool)
    named = meas.loc[gone, ["aircraft_id", "callsign"]].astype(str).to_numpy() if "callsign" in meas else [
        (a, "") for a in meas.loc[gone, "aircraft_id"].astype(str)]
    shown = ", ".join(f"{a} ({c})" if c not in ("", "nan", "<NA>", "None") else a for a, c in named[:5])
    more = f" and {len(lone) - 5} more" if len(lone) > 5 else ""
    return meas[~gone].reset_index(drop=True), [
        f"{len(lone)} aircraft reported once in the run left out: one report gives no velocity to predict "
        f"or measure a loss on, and a damaged address makes such a ghost beside its aircraft: {shown}{more}"]


COMPANION_NOUNS = {"losses": "losses table", "warnings": "warning times table"}  # as messages name them


def companion_paths(csv: Path) -> dict[str, Path]:
    """The files written beside a CSV output: losses and warning times."""
    return {"losses": csv.with_name(csv.stem + "_losses.csv"),
            "warnings": csv.with_name(csv.stem + "_warning_times.csv")}


@dataclass
class ConflictJobResult:
    """Tracks, predictions' PC, and the derived tables of one run."""

    options: ConflictOptions
    checked: Checked
    tracks: pd.DataFrame
    pc: pd.DataFrame  # time, aircraft_a, aircraft_b, horizon_s, pc, horizontal_nm, vertical_ft
    alerts: pd.DataFrame  # alert events with loss_start and false_alert
    losses: pd.DataFrame
    warning_times: pd.DataFrame  # per loss and horizon: how long before the loss an alert was raised
    parameters: dict
    loaded: object
    counts: dict = field(default_factory=dict)
    predictions: pd.DataFrame | None = None  # predict_tracks' frame (for the figures)
    noise: pd.DataFrame | None = None  # --noise estimate or timing: declared and estimated sigmas
    warnings: list[str] = field(default_factory=list)  # the run's, validation's first
    figures: FigureChoice | None = None  # the figures --figures drew and left out, once written


def conflict_job(options: ConflictOptions, *, progress: Progress | None = None,
                 checked: Checked | None = None, command: str = "conflicts") -> ConflictJobResult:
    """Validate, decode, track every aircraft, predict, PC per pair/step/horizon, events; writes nothing."""
    from msdc.pipeline.conflict import pair_probabilities
    from msdc.pipeline.conflict.grid import on_grid
    from msdc.pipeline.conflict.reported import report_rows
    from msdc.pipeline.conflict.surface import on_surface
    from msdc.pipeline.model.selection import identity_timeline, selected_samples
    from msdc.pipeline.track import Plane, track
    from msdc.pipeline.track.feasibility import untrackable, unused_adsb
    from msdc.pipeline.track.noise import SURFACE_SPEED_KT

    started = time.monotonic()
    checked = checked or validate(options)
    horizons = parse_horizons(options.horizons_s)
    step = float(options.step_s)
    selection = check_selection(options)
    with carrying(checked.warnings) as warnings:
        loaded, meas, said = tracker_inputs(options, checked, progress,
                                            "the times of the alerts, losses and tracks")
        warnings += said
        warnings += below_updates(meas, "--max-report-gap", float(options.max_report_gap_s),
                                  "no two reports of an aircraft are that close, so no time is reported "
                                  "for both aircraft of a pair: no loss can be found and every alert counts "
                                  "as false", 15.0)
        meas, said = _without_lone_reports(meas)
        warnings += said
        check_output_rows(meas, options)
        # predictions start from the grid rows only, not from the report times
        check_output_rows(meas, options, len(horizons),
                          f"predictions ({len(horizons)} horizon(s) a grid row)", grid_only=True)
        noise = None
        if options.noise in ESTIMATED:
            meas, noise = estimated_noise(meas, checked.sensors, options)
        result = track(meas, step_s=step, max_coast_s=float(options.max_coast_s), tpm=options.tpm)
        tracks = result.tracks
        if tracks.empty:
            raise JobError(untrackable(meas))
        warnings += unused_adsb(meas)
        grid_at = np.flatnonzero(on_grid(tracks, step))  # the tracker's report-time rows are not the grid
        plane = Plane.around(tracks["latitude"].to_numpy(float), tracks["longitude"].to_numpy(float))
        epoch, tracker_parameters = result.epoch, result.parameters
        # where each aircraft is reported: the accepted reports a loss is measured between
        reports = report_rows(tracks, meas, result.rejected, float(options.max_report_gap_s))
        del result
        # the grid rows are what follows needs: the full table (~0.35 GB on a day at 1 s) freed as they are
        # taken
        grid = _take_rows(tracks, grid_at)
        del tracks, grid_at
        timeline = identity_timeline(meas)
        if progress:
            progress.stage("Predicting and computing PC")
        predictions = _predictions(meas, epoch, plane, horizons, options)
        pc = pair_probabilities(predictions, options.radius_nm, options.vertical_ft, method=options.method,
                                vertical_tolerance_ft=options.vertical_tolerance_ft)
        grid["on_surface"], by_speed = on_surface(grid)
        grid["selected"], left_out = selected_samples(grid, selection, timeline)
        tables = _tables(grid, reports, pc, timeline, options, horizons)
        counts = {"aircraft": int(grid["aircraft_id"].nunique()), **tables.counts,
                  "selection": {"active": selection.active, "samples": len(grid),
                                "left_out": int((~grid["selected"]).sum()), **left_out,
                                "losses_without": (tables.losses_without if tables.losses_without is not None
                                                   or not selection.active else len(tables.losses))},
                  "surface": _surface_counts(grid, by_speed, tables.at_surface, tables.lost, tables.events,
                                             options, tables.pc)}
        params = {**run_parameters(options, loaded, started, command), **tracker_parameters,
                  "horizons_s": list(horizons), "radius_nm": options.radius_nm,
                  "vertical_ft": options.vertical_ft, "vertical_tolerance_ft": options.vertical_tolerance_ft,
                  "max_report_gap_s": options.max_report_gap_s,
                  "threshold": options.threshold, "method": options.method,
                  "vertical": options.vertical, "noise": options.noise, "surface": options.surface,
                  "surface_speed_kt": SURFACE_SPEED_KT, **selection.parameters(),
                  "sources": list(parse_sources(options.sources))}
        return ConflictJobResult(options, checked, grid, pc, tables.alerts, tables.losses, tables.warnings,
                                 params, loaded, counts, predictions, noise, warnings)


@dataclass
class _Tables:
    """The tables of one run and what the counts need of them."""

    alerts: pd.DataFrame
    losses: pd.DataFrame
    warnings: pd.DataFrame
    counts: dict
    lost: dict  # the loss runs of each kind of pairs (airborne, all, surface)
    events: dict  # the alert events with and without the surface pairs (airborne, all)
    pc: pd.DataFrame  # the selected samples' PC
    at_surface: np.ndarray  # per row of pc: an aircraft on the surface
    losses_without: int | None  # losses without the selection (None: it left no sample out)


def _tables(grid: pd.DataFrame, reports: pd.DataFrame, pc: pd.DataFrame, timeline: pd.DataFrame,
            options: ConflictOptions, horizons: tuple[float, ...]) -> _Tables:
    """Losses on the reported samples the selection keeps, their closest points, alert events of the
    selected samples' PC, the alerts scored against the losses, warning times, each table labelled."""
    from msdc.pipeline.conflict import alert_events, classify_alerts, warning_times
    from msdc.pipeline.conflict.approach import closest_approach
    from msdc.pipeline.conflict.events import losses_by_pairs
    from msdc.pipeline.conflict.geometry import vertical_limit_ft
    from msdc.pipeline.conflict.labels import ordered, with_identities, with_position
    from msdc.pipeline.conflict.loss_minimum import loss_minima
    from msdc.pipeline.conflict.reported import reported_samples
    from msdc.pipeline.conflict.surface import surface_pairs

    step, tol, gap = float(options.step_s), options.vertical_tolerance_ft, float(options.max_report_gap_s)
    kept = "airborne" if options.surface == "exclude" else "all"
    samples = reported_samples(grid[grid["selected"].to_numpy(bool)], reports, gap)
    # both surface modes' tables are counted, so that the terminal can say what the other would give
    lost = losses_by_pairs(samples, options.radius_nm, options.vertical_ft, tol,
                           kinds=("airborne", "all", "surface"), step_s=step)
    losses_without = None
    if not grid["selected"].all():
        every = reported_samples(grid, reports, gap)
        losses_without = len(losses_by_pairs(every, options.radius_nm, options.vertical_ft, tol,
                                             kinds=(kept,), step_s=step)[kept])
    limit = vertical_limit_ft(options.vertical_ft, tol)
    losses = loss_minima(lost[kept], reports, options.radius_nm, limit, gap)
    pc = pc[~surface_pairs(pc, grid.assign(left_out=~grid["selected"].to_numpy(bool)), "left_out")]
    at_surface = surface_pairs(pc, grid)
    events = {"airborne": alert_events(pc[~at_surface], options.threshold, step_s=step),
              "all": alert_events(pc, options.threshold, step_s=step)}
    alerts = closest_approach(classify_alerts(events[kept], losses), grid)
    warn = warning_times(losses, events[kept], horizons)
    warn = warn.merge(losses[["aircraft_a", "aircraft_b", "start", "began_inside"]].rename(
        columns={"start": "loss_start"}), on=["aircraft_a", "aircraft_b", "loss_start"], how="left")
    counts = {"losses": len(losses), "began_inside": int(losses["began_inside"].sum()),
              "alerts": len(alerts), "false_alerts": int(alerts["false_alert"].sum()) if len(alerts) else 0,
              "missed": {f"{h:g}": int(warn.loc[warn["horizon_s"] == h, "warning_s"].isna().sum())
                         for h in horizons},
              "warning": _warning_counts(warn, horizons), "reported_samples": len(samples),
              "selected_samples": int(grid["selected"].sum())}
    alerts = ordered(with_identities(with_position(alerts, "start", grid), "start", timeline), "start")
    losses = with_identities(losses, "start", timeline)
    losses = ordered(losses, "time_of_min")
    order = ["aircraft_a", "aircraft_b", "loss_start", "began_inside", "horizon_s", "alert_start",
             "warning_s"]
    warn = with_identities(with_position(warn[order], "loss_start", samples), "loss_start", timeline)
    warn = ordered(warn, "loss_start")
    return _Tables(alerts, losses, warn, counts, lost, events, pc, at_surface, losses_without)


def _warning_counts(warn: pd.DataFrame, horizons: tuple[float, ...]) -> dict:
    """Per horizon, over the losses that began outside the minimum (an alert could have warned of them):
    how many, alerted in advance (warning > 0 s), at or after the start, missed, and the median warning of
    those alerted."""
    out = {}
    for h in horizons:
        s = warn.loc[(warn["horizon_s"] == h) & ~warn["began_inside"].astype(bool), "warning_s"]
        out[f"{h:g}"] = {"losses": len(s), "in_advance": int((s > 0).sum()), "late": int((s <= 0).sum()),
                         "missed": int(s.isna().sum()),
                         "median_warning_s": float(s.median()) if s.notna().any() else None}
    return out


def _surface_counts(grid: pd.DataFrame, by_speed: np.ndarray, at_surface: np.ndarray, lost: dict,
                    events: dict, options: ConflictOptions, pc: pd.DataFrame) -> dict:
    """What the surface rule touched: grid rows and aircraft on the surface (by the reports, by speed alone);
    the losses and alert events found among pair samples with an aircraft on the surface alone; and the
    losses and alert events the tables hold with --surface exclude and with include (a run that goes on
    from airborne samples to surface ones is one run with include, and one on each side in the first two
    counts: these do not add up to include's)."""
    from msdc.pipeline.conflict import alert_events

    surface = grid["on_surface"].to_numpy(bool)
    alone = alert_events(pc[at_surface], options.threshold, step_s=float(options.step_s))
    return {"excluded": options.surface == "exclude", "rows": int(surface.sum()),
            "rows_by_speed": int(by_speed.sum()),
            "aircraft": int(grid.loc[surface, "aircraft_id"].nunique()),
            "losses": len(lost["surface"]), "alerts": len(alone), "pc_samples": int(at_surface.sum()),
            "exclude": {"losses": len(lost["airborne"]), "alerts": len(events["airborne"])},
            "include": {"losses": len(lost["all"]), "alerts": len(events["all"])}}


def _take_rows(frame: pd.DataFrame, rows: np.ndarray) -> pd.DataFrame:
    """frame.take(rows) with a new range index, a column at a time, each column dropped from frame once
    taken (frame ends empty): with one block per column, as the tracker's tables, the whole and the part
    are not held at once."""
    out = {c: frame.pop(c).take(rows).reset_index(drop=True) for c in list(frame.columns)}
    return pd.DataFrame(out, copy=False)


def _predictions(meas: pd.DataFrame, epoch: pd.Timestamp, plane, horizons: tuple[float, ...],
                 options: ConflictOptions) -> pd.DataFrame:
    """predict_tracks for every aircraft of `meas`, in `plane`, in batches of aircraft tracked with their
    filter histories kept (about 1.4 kB a report: 1.4 GB for a day of traffic at once), one batch's at a
    time, with the `epoch` of the run without histories: the same predictions, in the same order."""
    from msdc.pipeline.conflict.predict import predict_tracks
    from msdc.pipeline.track import track
    from msdc.pipeline.track.tracker import concat_columns

    per_aircraft = meas.groupby("aircraft_id", sort=True, observed=True).size()
    batch = np.cumsum(per_aircraft.to_numpy()) // PREDICTION_BATCH_REPORTS
    parts = []
    for b in np.unique(batch):
        ids = per_aircraft.index[batch == b]
        sub = meas[meas["aircraft_id"].isin(ids).to_numpy(bool)]
        run = track(sub, step_s=float(options.step_s), max_coast_s=float(options.max_coast_s),
                    tpm=options.tpm, keep_states=True, epoch=epoch)
        if not run.tracks.empty:  # a batch of untrackable aircraft (no usable covariance) predicts nothing
            parts.append(_own_columns(predict_tracks(run, horizons, step_s=float(options.step_s), plane=plane,
                                                     sigma_alt=options.vertical == "gaussian")))
        del run, sub
    return concat_columns(parts)  # a day's predictions at 1 s are 0.23 GB: not held twice


def _own_columns(frame: pd.DataFrame) -> dict[str, pd.Series]:
    """The frame's columns, each in an array of its own (a float column copied out of the frame's shared
    block), so that `concat_columns` can free them one by one."""
    own = {}
    for c in frame.columns:
        column = frame[c]
        own[c] = pd.Series(column.to_numpy(copy=True) if isinstance(column.dtype, np.dtype) else column.array,
                           copy=False)
    return own


def summary(result: ConflictJobResult) -> dict:
    """The JSON document: parameters, inputs, counts and the three tables as records."""
    def records(frame: pd.DataFrame) -> list[dict]:
        return [{k: json_value(v) for k, v in row.items()} for row in frame.to_dict("records")]

    doc = {"parameters": result.parameters, "inputs": result.loaded.inputs, "counts": result.counts,
           "alerts": records(result.alerts), "losses": records(result.losses),
           "warning_times": records(result.warning_times)}
    if result.noise is not None:
        doc["noise"] = {"passes": result.noise.attrs.get("passes"), "sensors": records(result.noise)}
    return doc


def text(result: ConflictJobResult) -> str:
    """What the run found, in a few lines (says so when there is no loss and no alert)."""
    c = result.counts
    o = result.options
    speed_kt = result.parameters["surface_speed_kt"]
    lines = [f"{c['aircraft']} aircraft tracked; {c['losses']} loss(es) of separation "
             f"(< {o.radius_nm:g} NM and < {o.vertical_ft:g} ft less {o.vertical_tolerance_ft:g} ft, "
             f"both aircraft reported, reports at most {o.max_report_gap_s:g} s apart), "
             f"{c['began_inside']} of them begun inside the minimum; {c['alerts']} alert event(s), "
             f"{c['false_alerts']} false",
             "the losses are geometric proximities in the tracked data, not separation infringements: msdc "
             "knows no clearance, airspace or minimum that applied (aerodrome traffic, VFR flights and "
             "visual separation count here)"]
    sel = c["selection"]
    if sel["active"]:
        labels = {"below_min_fl": f"below FL {o.min_fl:g}" if o.min_fl is not None else "",
                  "mode_a_only": "of Mode-A-only targets", "excluded_codes": "squawking an excluded code"}
        why = ", ".join(f"{sel[key]} {label}" for key, label in labels.items() if key in sel)
        lines.append(f"selection: {sel['left_out']} of {sel['samples']} aircraft samples left out ({why}); "
                     f"without it {sel['losses_without']} loss(es)")
    g = c["surface"]
    if g["rows"]:
        other = "include" if g["excluded"] else "exclude"
        where = "left out of the tables" if g["excluded"] else "kept in the tables (--surface include)"
        lines.append(f"on the surface: {g['aircraft']} aircraft in {g['rows']} track sample(s) "
                     f"({g['rows_by_speed']} by a speed below {speed_kt:g} kt alone, the others as their "
                     f"reports said); pairs with an aircraft on the surface are {where}: --surface {other} "
                     f"would give {g[other]['losses']} loss(es) and {g[other]['alerts']} alert event(s) "
                     f"instead of {c['losses']} and {c['alerts']} ({g['losses']} loss(es) and {g['alerts']} "
                     "alert event(s) among the surface pairs' samples alone; a run going on between airborne "
                     "and surface samples is one with include)")
    if not c["losses"] and not c["alerts"]:
        lines.append("no loss of separation and no alert: the tables are written empty, with their headers")
    if c["losses"]:
        if c["began_inside"]:
            lines.append(f"{c['began_inside']} loss(es) began inside the minimum (the pair entered the "
                         "analysis already closer: a track starting, taking off or entering the selection): "
                         "no alert could warn of them, so they are left out of the warning times below")
        for h, w in c["warning"].items():
            if not w["losses"]:
                lines.append(f"horizon {h} s: no loss began outside the minimum")
                continue
            median = (f"; median warning of the alerted {w['median_warning_s']:g} s"
                      if w["median_warning_s"] is not None else "")
            lines.append(f"horizon {h} s: of {w['losses']} loss(es) begun outside the minimum, "
                         f"{w['in_advance']} alerted in advance (warning > 0 s), {w['late']} at or after the "
                         f"loss's start, {w['missed']} missed{median}")
    return "\n".join(lines)


def write_conflicts(result: ConflictJobResult, *, tx: OutputTransaction | None = None,
                    progress: Progress | None = None, workers: int | None = None) -> dict[str, Path]:
    """Write the tables (CSV: alerts at -o, losses and warning times beside it; xlsx: one workbook), the
    JSON and one figure per alert (--figures, its folder made only when there is one), each when given,
    staged in ``tx`` (committed by the caller; without one, the files are committed together here); the
    figures on ``workers`` processes (None: every core). Returns the final paths, by kind."""
    from msdc.pipeline.report.conflict_excel import write_conflict_workbook

    out, js = result.checked.output, result.checked.json
    targets: dict[str, Path] = {}
    with staged(tx) as stage:
        if out is None:
            pass
        elif out.suffix.lower() == ".csv":
            targets["alerts"] = out
            write_csv(result.alerts, stage.path(out))
            for kind, path in companion_paths(stage.path(out)).items():
                targets[kind] = stage.final(path)
                write_csv(result.losses if kind == "losses" else result.warning_times, path)
        else:
            targets["workbook"] = out
            write_conflict_workbook(result.alerts, result.losses, result.warning_times, result.parameters,
                                    stage.path(out))
        if js is not None:
            targets["json"] = js
            write_json(summary(result), stage.path(js))
        if result.options.figures is not None and len(result.alerts):
            targets.update(_alert_figures(result, stage.folder(result.options.figures), stage, progress,
                                          workers))
    return targets


def _alert_figures(result: ConflictJobResult, folder: Path, stage: OutputTransaction,
                   progress: Progress | None, workers: int | None) -> dict[str, Path]:
    """The chosen alert events' figures (--figures-limit, --figures-only) drawn in ``folder`` (staged), the
    others listed in figures_not_drawn.txt: their final paths, by kind."""
    from msdc.pipeline.report.conflict_figures import figure_name
    from msdc.pipeline.report.figure_pool import FigureError, render

    alerts = result.alerts
    names = [figure_name(int(i), alert) for i, alert in alerts.iterrows()]
    choice = choose(names, result.options.figures_limit, result.options.figures_only)
    result.figures = choice
    if progress:
        progress.stage(f"Drawing {len(choice.drawn)} of {len(names)} alert figures")
    try:
        paths = render(_alert_tasks(result, folder, choice.drawn), len(choice.drawn), workers=workers,
                       progress=progress)
    except FigureError as exc:
        raise JobError(f"--figures {result.options.figures}: {exc}; nothing written") from exc
    drawn = {f"figure {path.stem}": stage.final(path) for path in paths}
    listed = write_not_drawn(folder, "conflicts", result.options, choice)
    if listed is not None:
        drawn["figures not drawn"] = stage.final(listed)
    return drawn


def _alert_tasks(result: ConflictJobResult, folder: Path, rows: list[int]) -> Iterator[FigureTask]:
    """One task per chosen row of the Alerts table, made when the pool takes it: that alert's pair's
    tracks, predictions and PC only (conflict_figures.AlertData)."""
    from msdc.pipeline.conflict.surface import surface_pairs
    from msdc.pipeline.report.conflict_figures import AlertData, alert_figure, figure_name

    alerts = result.alerts
    involved = set(alerts["aircraft_a"]) | set(alerts["aircraft_b"])
    tracks = result.tracks[result.tracks["aircraft_id"].isin(involved)]
    pred = result.predictions
    pred = pred[pred["aircraft_id"].isin(involved) & pred["time"].isin(alerts["start"])]
    pc = result.pc[result.pc["aircraft_a"].isin(involved)]
    # the samples the events were found in: those the selection keeps, without the surface pairs' (exclude)
    grid = result.tracks
    pc = pc[~surface_pairs(pc, grid.assign(left_out=~grid["selected"].to_numpy(bool)), "left_out")]
    if result.options.surface == "exclude":
        pc = pc[~surface_pairs(pc, grid)]
    threshold, step = result.options.threshold, float(result.options.step_s)
    data = AlertData(tracks, pred, pc)
    for row in rows:
        alert = alerts.iloc[row]
        name = figure_name(int(alerts.index[row]), alert)
        yield FigureTask(name, alert_figure, {**data(alert), "threshold": threshold, "path": folder / name,
                                              "step_s": step})


def side_files(checked: Checked, options: ConflictOptions) -> list[Path]:
    """The files conflicts may write beside its outputs, as globs: the losses and warning times beside a
    CSV -o, one figure per alert in --figures DIR."""
    out, beside = checked.output, []
    if out is not None and out.suffix.lower() == ".csv":
        beside = [p.with_name(glob.escape(p.name)) for p in companion_paths(real_output(out)).values()]
    return beside + ([] if options.figures is None else [Path(options.figures) / "alert_*.png",
                                                          Path(options.figures) / NOT_DRAWN])


__all__ = ["ConflictJobResult", "ConflictOptions", "conflict_job", "parse_horizons", "side_files", "summary",
           "text", "validate", "write_conflicts"]
