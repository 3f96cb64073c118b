"""The track job: fused IMM tracks per aircraft from every radar and ADS-B report (``msdc track``).

Options are validated before anything is decoded (``validate``: one-line ``OptionError`` naming the
option); ``track_job`` decodes, builds the measurement model (radar covariances from the sensor file's
sigmas, ADS-B from NACp), drops repeated reports, selects the aircraft and sources, and runs
``pipeline.track.track``; ``write_tracks`` writes the table (CSV or Parquet), the JSON summary and the
per-aircraft figures. It lives beside ``pipeline.jobs`` and reuses its helpers.
"""

from __future__ import annotations

import json
import math
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from msdc.pipeline import jobs
from msdc.pipeline.jobs import AircraftOptions, Checked, JobError, OptionError
from msdc.pipeline.progress import Progress

SOURCES = ("radar", "adsb")
# --noise: the sensor file's sigmas and NACp; estimated from residuals (one isotropic ADS-B sigma per
# class); estimated with an ADS-B along-track timing term as well (docs/tracker.md: fewer gated reports
# and track segments on the real recording, predictions through gaps no better on the mean)
NOISE = ("declared", "estimate", "timing")
ESTIMATED = ("estimate", "timing")
STEP_RANGE_S = (1e-3, 3600.0)  # below 1 ms the grid explodes (a day would be 86 M rows per aircraft)
MAX_COAST_RANGE_S = (0.0, 86400.0)
# the columns of the track table, in order (issue 10); the tracker's other columns follow
TRACK_COLUMNS = ["aircraft_id", "callsign", "address", "time", "time_of_day", "latitude", "longitude",
                 "flight_level", "speed_kt", "track_deg", "turn_rate_dps", "sigma_major_m", "sigma_minor_m",
                 "mode_cv", "mode_turn_left", "mode_turn_right", "coasted", "sources"]


# decimals of the track CSV's float columns (Parquet keeps full precision): below what any sensor resolves
# (1e-7 deg is 1.1 cm; 1 us; 0.01 ft of level, 0.01 kt, 1e-4 deg/s), so that the filter's round-off
# (turn rates of 1.7e-17) and 17-digit floats do not reach the file; mode_* columns take MODE_DECIMALS
CSV_DECIMALS = {"time_of_day": 6, "latitude": 7, "longitude": 7, "flight_level": 2, "vertical_rate_fpm": 1,
                "speed_kt": 2, "track_deg": 3, "turn_rate_dps": 4, "sigma_major_m": 2, "sigma_minor_m": 2,
                "ellipse_orientation_deg": 2, "age_s": 6}
MODE_DECIMALS = 4


def csv_rounded(tracks: pd.DataFrame) -> pd.DataFrame:
    """The track table with its float columns rounded to CSV_DECIMALS (mode probabilities to MODE_DECIMALS),
    a negative zero written as 0, values below 1e-4 as fixed-point text; the other columns as they are (not
    copied)."""
    rounded = {}
    for name in tracks.columns:
        places = CSV_DECIMALS.get(name, MODE_DECIMALS if name.startswith("mode_") else None)
        if places is not None and tracks[name].dtype.kind == "f":
            # + 0.0: a negative zero becomes 0.0
            values = np.round(tracks[name].to_numpy(float, na_value=np.nan), places) + 0.0
            tiny = (values != 0.0) & (np.abs(values) < 1e-4)  # Python writes these as 4.48e-05: fixed instead
            if tiny.any():
                values = values.astype(object)
                values[tiny] = [f"{v:.{places}f}" for v in values[tiny]]
            rounded[name] = values
    return tracks.assign(**rounded)


# printed under the terminal's table of tracks: what its columns mean
TRACK_LEGEND = (
    "reports = updates + gated + invalid (no usable position or covariance) + out_of_range (3000 km off)\n"
    "tracked_s: first to last update of each segment, summed; update_interval_s: the slowest sensor's\n"
    "median interval between its updates; coasted_s: time without any update beyond that interval, in gaps\n"
    "longer than 1.5 intervals (a missed 4 s scan counts 4 s); after its last update a segment is coasted\n"
    "--max-coast s more, counted in neither")


@dataclass(frozen=True)
class TrackOptions(AircraftOptions):
    """Everything ``track_job`` needs; see ``msdc track --help`` for the meaning of each option. The
    inputs, sensor file, aircraft selection and outputs are the other jobs' (``gap_s`` is unused here)."""

    figures: str | None = None  # directory for one PNG per aircraft
    step_s: float = 1.0
    max_coast_s: float = 60.0
    smooth: bool = False
    smoother: str = "rts"  # with smooth: "rts" (combined estimate) or "imm" (two-filter IMM smoother)
    tpm: str | None = None  # None: the tracker's default (expm:150,20)
    sources: tuple[str, ...] = SOURCES
    noise: str = "estimate"  # one of NOISE (pipeline.track.noise estimates; "declared": as given)


def _sources(value) -> tuple[str, ...]:
    items = tuple(value.split(",")) if isinstance(value, str) else tuple(value or ())
    items = tuple(s.strip().lower() for s in items)
    if not items or any(s not in SOURCES for s in items) or len(set(items)) != len(items):
        raise OptionError(f"--sources {','.join(items) if items else value!r}: must be a comma-separated "
                          f"subset of {','.join(SOURCES)} without repeats")
    return items


def check_tracking(options: TrackOptions) -> float:
    """The tracker's options shared by track and conflicts (--step, --max-coast, --tpm, --noise); OptionError
    if bad, else the step (s)."""
    from msdc.pipeline.track import check_tpm

    step = options.step_s
    if not isinstance(step, int | float) or not math.isfinite(step) or not step > 0.0:
        raise OptionError(f"--step {step!r}: must be a finite number of seconds > 0")
    jobs._number("--step", step, *STEP_RANGE_S, " s")
    coast = options.max_coast_s
    if not isinstance(coast, int | float) or not math.isfinite(coast) or coast < step:
        raise OptionError(f"--max-coast {coast!r}: must be a finite number of seconds >= --step ({step:g})")
    if coast > MAX_COAST_RANGE_S[1]:  # the lower bound is --step, checked above
        raise OptionError(f"--max-coast {coast!r}: must be a finite number of seconds from --step ({step:g}) "
                          f"to {MAX_COAST_RANGE_S[1]:g}")
    if options.tpm is not None:  # every update interval in use: up to --max-coast, coasting cycles of 1 s
        try:
            check_tpm(str(options.tpm), max(float(coast), float(step), 1.0))
        except ValueError as exc:
            raise OptionError(f"--tpm {options.tpm!r}: {str(exc).partition(': ')[2]}") from None
    if options.noise not in NOISE:
        raise OptionError(f"--noise {options.noise!r}: must be one of {', '.join(NOISE)}")
    return step


def check_track_rows(meas: pd.DataFrame, options: TrackOptions, per_row: int = 1, what: str = "", *,
                     grid_only: bool = False) -> None:
    """pipeline.track.feasibility.check_track_rows as an OptionError naming --step."""
    from msdc.pipeline.track import feasibility

    try:
        feasibility.check_track_rows(meas, options.step_s, options.max_coast_s, per_row, what,
                                     grid_only=grid_only)
    except feasibility.TooManyRows as exc:
        raise OptionError(f"--step {options.step_s:g}: {exc}; use a longer --step or fewer aircraft") from exc


def validate(options: TrackOptions, *, require_output: bool = False) -> Checked:
    """Check every option, the sensor file and the output paths before any decoding; OptionError if bad.
    ``require_output`` (the command): at least one of -o, --json and --figures; track_job returns the table
    whatever is written."""
    from msdc.pipeline.track.plane import SMOOTHERS

    warnings: list[str] = []
    inputs, editions = jobs._check_decoding(options, warnings)
    checked = Checked(inputs, editions, warnings=warnings)
    jobs._check_aircraft(options)
    check_tracking(options)
    if options.smoother not in SMOOTHERS:
        raise OptionError(f"--smoother {options.smoother!r}: must be one of {', '.join(SMOOTHERS)}")
    _sources(options.sources)
    checked.output = jobs._output("-o", options.output, (".csv", ".parquet"))
    checked.json = jobs._output("--json", options.json, (".json",))
    jobs.spare_inputs(options.inputs, [(f"-o {checked.output}", checked.output),
                                       (f"--json {checked.json}", checked.json)])
    if options.figures is not None:
        jobs.nonempty_path("--figures", options.figures)
        d = Path(options.figures)
        if d.exists() and not d.is_dir():
            raise OptionError(f"--figures {d}: exists and is not a directory")
        if not (d if d.exists() else (d.parent if str(d.parent) else Path("."))).is_dir():
            raise OptionError(f"--figures {d}: directory {d.parent} does not exist")
    if require_output and checked.output is None and checked.json is None and options.figures is None:
        raise OptionError("give at least one output: -o tracks.csv|tracks.parquet, --json or --figures")
    checked.sensors = jobs._sensors(options.sensors, required=False)
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


def _measurements(loaded, checked: Checked, options: TrackOptions) -> pd.DataFrame:
    """Measurements of the requested sources (one of them must be present), repeated reports dropped."""
    import warnings as python_warnings

    from msdc.pipeline.model.dedup import duplicate_mask
    from msdc.pipeline.model.measurements import (
        IdentityWarning,
        OffEarthWarning,
        OutOfCoverageWarning,
        build_measurements,
    )
    from msdc.pipeline.model.sensors import UnknownRadar, declared_radar

    sources = _sources(options.sources)
    radar = loaded.frames.get(48) if "radar" in sources else None
    adsb = loaded.frames.get(21) if "adsb" in sources else None
    radar = radar if radar is not None and len(radar) else None
    adsb = adsb if adsb is not None and len(adsb) else None
    if radar is None and adsb is None:
        wanted = " or ".join({"radar": "radar (CAT048)", "adsb": "ADS-B (CAT021)"}[s] for s in sources)
        failed = "; ".join(why[2:] for cat in ({"radar": 48, "adsb": 21}[s] for s in sources)
                           if (why := jobs._all_failed(loaded, cat)))
        raise JobError(f"no {wanted} records in the inputs (--sources {','.join(sources)})"
                       + (f": {failed}" if failed else ""))
    try:
        radar, stray = declared_radar(radar, checked.sensors, jobs.sensors_path(options))
    except UnknownRadar as exc:
        raise jobs.unknown_radar_error(exc.missing, jobs.sensors_path(options)) from exc
    checked.warnings += stray
    try:
        with python_warnings.catch_warnings():  # jobs._load has said it, naming each file
            python_warnings.simplefilter("ignore", OffEarthWarning)
            python_warnings.simplefilter("ignore", OutOfCoverageWarning)  # said below, from attrs
            python_warnings.simplefilter("ignore", IdentityWarning)  # said below, from attrs
            meas = build_measurements(radar, adsb, checked.sensors, date=loaded.date,
                                      adsb_sigma_m=options.adsb_sigma_m)
    except UnknownRadar as exc:
        raise jobs.unknown_radar_error(exc.missing, jobs.sensors_path(options)) from exc
    checked.warnings += list(meas.attrs.get("coverage_warnings", ()))
    checked.warnings += list(meas.attrs.get("identity_warnings", ()))
    from msdc.pipeline.track.associate import join_by_track_number

    meas, joined = join_by_track_number(meas, max_gap_s=float(options.max_coast_s))
    dup = duplicate_mask(meas.sort_values("time", kind="stable")).reindex(meas.index).to_numpy(bool)
    known = meas["aircraft_id"].notna().to_numpy(bool)
    out = meas[~dup & known].reset_index(drop=True)
    out.attrs["joined_by_track_number"] = joined
    out.attrs["unidentified"] = int((~dup & ~known).sum())
    return out


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
    from msdc.pipeline.model.site_check import site_warnings
    from msdc.pipeline.track import track
    from msdc.pipeline.track.feasibility import untrackable

    started = time.monotonic()
    checked = checked or validate(options)
    if progress:
        progress.stage("Processing data files")
    loaded = jobs._load(options, checked, progress)
    if progress:
        progress.stage("Tracking")
    meas = _measurements(loaded, checked, options)
    checked.warnings += site_warnings(meas, checked.sensors, str(jobs.sensors_path(options)))
    checked.warnings += jobs.undated_warning(loaded, "the tracks' times")
    loaded.drop_frames()  # the measurements hold what tracking needs: a day's decoded frames are ~0.5 GB
    joined = int(meas.attrs.get("joined_by_track_number", 0))
    unidentified = int(meas.attrs.get("unidentified", 0))
    if unidentified and options.all_aircraft:
        checked.warnings.append(f"{unidentified} report(s) with no identity (no address, call sign or "
                                "Mode 3/A code, nor a radar track number joining them to an aircraft), "
                                "not tracked")
    meas = _select(meas, options)
    check_track_rows(meas, options)
    noise = None
    if options.noise in ESTIMATED:
        meas, noise = _estimate_noise(meas, checked.sensors, options)
    result = track(meas, step_s=float(options.step_s), max_coast_s=float(options.max_coast_s),
                   tpm=options.tpm, smooth=options.smooth, smoother=options.smoother)
    if result.tracks.empty:
        raise JobError(untrackable(meas))
    labels = aircraft_labels(meas)
    tracks = with_labels(result.tracks, labels)
    params = {**jobs._parameters(options, loaded, started, command), **result.parameters,
              "sources": list(_sources(options.sources)), "callsign": options.callsign,
              "address": options.address, "all": bool(options.all_aircraft),
              "radar_plots_joined_by_track_number": joined, "unidentified_reports_not_tracked": unidentified,
              "noise": options.noise}
    return TrackJobResult(options, checked, result, tracks, meas, labels, params, loaded, noise)


def with_labels(tracks: pd.DataFrame, labels: pd.DataFrame) -> pd.DataFrame:
    """The tracker's table with each aircraft's call sign and address ("" when none), TRACK_COLUMNS first;
    the other columns are not copied (a day's table is ~0.35 GB)."""
    by_id = labels.set_index("aircraft_id")
    named = {c: tracks["aircraft_id"].map(by_id[c]).fillna("") for c in ("callsign", "address")}
    out = tracks.assign(**named)
    return out[TRACK_COLUMNS + [c for c in out.columns if c not in TRACK_COLUMNS]]


def _estimate_noise(meas: pd.DataFrame, sensors: pd.DataFrame, options: TrackOptions):
    """The measurements with each sensor's covariance rescaled to its residual scatter, and the table of
    declared against estimated sigmas (radar range m and azimuth deg from the sensor file; ADS-B m per
    NACp level, and its along-track timing sigma s, declared 0)."""
    from msdc.pipeline.model.measurements import sensor_id
    from msdc.pipeline.track.noise import AZIMUTH, RANGE, TIMING, estimate_noise

    ids = sensor_id(48, sensors["sac"], sensors["sic"]).to_numpy()
    sites = {str(i): (float(r.latitude), float(r.longitude))
             for i, r in zip(ids, sensors.itertuples(), strict=True)}
    est = estimate_noise(meas, sites=sites, max_coast_s=float(options.max_coast_s), tpm=options.tpm,
                         timing=options.noise == "timing")
    table = est.sensors.rename(columns={"declared_sigma_m": "declared_sigma",
                                        "estimated_sigma_m": "estimated_sigma"})
    table.insert(3, "unit", "m")
    by_id = dict(zip(ids, sensors.itertuples(), strict=True))
    for i, row in table.iterrows():
        site = by_id.get(row["sensor_id"])
        if site is not None and row["component"] in (RANGE, AZIMUTH):
            declared = site.sigma_range_m if row["component"] == RANGE else site.sigma_azimuth_deg
            table.loc[i, ["declared_sigma", "unit"]] = [declared, "m" if row["component"] == RANGE else "deg"]
    table["estimated_sigma"] = table["declared_sigma"] * table["scale"]
    timing = table["component"] == TIMING  # the ADS-B along-track time-stamp sigma, declared as none
    table.loc[timing, ["unit", "declared_sigma"]] = ["s", 0.0]
    table.loc[timing, "estimated_sigma"] = table.loc[timing, "estimated_sigma_s"]
    table = table.drop(columns="estimated_sigma_s")
    table.attrs["passes"] = est.passes
    table.attrs["aircraft"] = est.aircraft.to_dict("records")  # the per-aircraft guard's raises
    return est.measurements, table


def summary(result: TrackJobResult) -> dict:
    """The JSON document: parameters, inputs, and per aircraft its span, coasted time and per-sensor
    reports, updates, gated reports and NIS mean."""
    from msdc.pipeline.report.summary import json_value

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
    out_of_range, and the NIS mean over every update (each aircraft's mean weighted by its updates)."""
    s = sensors.assign(nis_sum=sensors["nis_mean"].fillna(0.0) * sensors["updates"])
    out = s.groupby("sensor_id", sort=True).agg(
        aircraft=("aircraft_id", "nunique"), reports=("reports", "sum"), updates=("updates", "sum"),
        gated=("gated", "sum"), invalid=("invalid", "sum"), out_of_range=("out_of_range", "sum"),
        nis_sum=("nis_sum", "sum")).reset_index()
    with np.errstate(invalid="ignore", divide="ignore"):
        nis = out["nis_sum"].to_numpy(float) / out["updates"].to_numpy(float)
    return out.drop(columns="nis_sum").assign(nis_mean=np.where(out["updates"] > 0, nis, np.nan))


def write_tracks(result: TrackJobResult) -> dict[str, Path]:
    """Write the track table (CSV: times as ISO 8601 UTC; Parquet: tz-aware timestamps), the JSON and
    the figures, as the options ask; each file is written whole to a temporary name and then renamed,
    so a failure leaves nothing behind. Returns what was written, by kind."""
    written: dict[str, Path] = {}
    out, js = result.checked.output, result.checked.json
    if out is not None:
        from msdc.pipeline.report.summary import write_atomically
        from msdc.pipeline.report.tables import write_parquet

        if out.suffix.lower() == ".csv":
            times = result.tracks["time"].dt.strftime("%Y-%m-%dT%H:%M:%S.%fZ")
            table = csv_rounded(result.tracks).assign(time=times)
            write_atomically(out, lambda tmp: table.to_csv(tmp, index=False))
        else:
            write_parquet(result.tracks, out)
        written["tracks"] = out
    if js is not None:
        js.write_text(json.dumps(summary(result), indent=1, default=str))
        written["json"] = js
    if result.options.figures is not None:
        from msdc.pipeline.report.track_figures import track_figures

        d = Path(result.options.figures)
        d.mkdir(exist_ok=True)
        written.update({f"figure {k}": p for k, p in track_figures(result, d).items()})
    return written


__all__ = ["TRACK_COLUMNS", "TrackJobResult", "TrackOptions", "sensor_totals", "summary", "track_job",
           "validate", "write_tracks"]
