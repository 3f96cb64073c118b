"""The ``msdc`` command: argparse over the jobs, one module of pipeline.jobs per command, imported only when
its command runs; options are validated there, before any decoding, and every failure is one line on stderr
with exit status 2 (usage) or 1 (data)."""

from __future__ import annotations

import argparse
import atexit
import datetime as dt
import gc
import importlib
import os
import sys
from typing import TYPE_CHECKING

from msdc.pipeline.meta import FORMATS as _FORMATS
from msdc.pipeline.meta import software_version
from msdc.pipeline.progress import Progress

if TYPE_CHECKING:
    from pathlib import Path

    import pandas as pd


class _Lazy:
    """A module imported at its first attribute use, so ``msdc --help`` and each command import only what
    they use (pandas, numba, scipy, openpyxl and matplotlib come in with the jobs that need them)."""

    def __init__(self, name: str):
        self._name = name

    def __getattr__(self, attr: str):
        return getattr(importlib.import_module(self._name), attr)


common = _Lazy("msdc.pipeline.jobs.common")  # the jobs' errors, caught in main()
asterix_errors = _Lazy("msdc.asterix.errors")
transaction = _Lazy("msdc.pipeline.report.transaction")  # every file of a run is written through one
FORMATS = list(_FORMATS)


class CliError(Exception):
    """A user-facing failure: printed without a traceback, exit status 1 (2 for unreadable input)."""

    def __init__(self, message: str, status: int = 1):
        super().__init__(message)
        self.status = status


class _Version(argparse.Action):
    """--version: the installed version is looked up only when asked (importlib.metadata costs every command
    about 30 ms)."""

    def __init__(self, option_strings, dest=argparse.SUPPRESS, default=argparse.SUPPRESS):
        super().__init__(option_strings, dest=dest, default=default, nargs=0,
                         help="show the version and exit")

    def __call__(self, parser, namespace, values, option_string=None):
        print(f"msdc {software_version()}")
        parser.exit()


def _date(text: str) -> dt.date:
    try:
        return dt.date.fromisoformat(text)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(f"not a date (YYYY-MM-DD): {text!r}") from exc


def _edition(text: str) -> str:
    cat, sep, ed = text.partition("=")
    if not sep or not cat.strip().isdigit() or not ed:
        raise argparse.ArgumentTypeError(f"expected CAT=EDITION (e.g. 21=0.26 or 21=auto), got {text!r}")
    return f"{int(cat)}={ed.strip()}"


def _decoding_options(p: argparse.ArgumentParser) -> None:
    p.add_argument("--edition", action="append", type=_edition, default=[], metavar="CAT=ED",
                   help="pin a category edition, e.g. 21=0.26, 48=1.27, or 21=auto (repeatable)")
    p.add_argument("--date", type=_date,
                   help="UTC day (YYYY-MM-DD) of a recording that carries no date (raw, final, gps, oradis)")
    p.add_argument("--format", choices=FORMATS, help="container format (default: detected)")


SENSORS_HELP = "sensor positions (TOML [[sensor]] tables)"
SENSORS_OPTIONAL_HELP = ("sensor positions (TOML [[sensor]] tables); needed when radar plots are used, "
                         "not for ADS-B alone")


def _aircraft_options(p: argparse.ArgumentParser, all_help: str, *, sensors_required: bool = True) -> None:
    """Inputs, the sensor file and the aircraft selection shared by correlate, quality and track."""
    p.add_argument("inputs", nargs="+", metavar="INPUT")
    p.add_argument("--sensors", required=sensors_required,
                   help=SENSORS_HELP if sensors_required else SENSORS_OPTIONAL_HELP)
    who = p.add_mutually_exclusive_group(required=True)
    who.add_argument("--callsign", help="call sign (case and spaces ignored)")
    who.add_argument("--address", help="24-bit aircraft address in hex")
    who.add_argument("--all", action="store_true", help=all_help)


def _adsb_sigma_option(p: argparse.ArgumentParser, used: str) -> None:
    """--adsb-sigma: the accuracy the user declares for ADS-B reports that carry no NACp."""
    p.add_argument("--adsb-sigma", type=float, metavar="M",
                   help="1-sigma position error per axis (m, 0.5-20000) declared for ADS-B reports without "
                        f"NACp (CAT021 0.2x: its figure of merit is not read as NACp){used}; reports with "
                        "NACp keep theirs, NACp 0 (unknown) stays untracked. Without it such reports are "
                        "not tracked")


def _sources_option(p: argparse.ArgumentParser) -> None:
    """--sources: the sensor kinds the tracker fuses (track and conflicts)."""
    p.add_argument("--sources", default="radar,adsb", help="sensor kinds to fuse: radar, adsb or radar,adsb")


def build_parser() -> argparse.ArgumentParser:
    """The msdc argument parser: one subcommand per job, options as docs/guide/ lists them."""
    parser = argparse.ArgumentParser(prog="msdc", description="Multi-Sensor Data Correlator: ASTERIX "
                                     "CAT048/CAT021 decoding and radar/ADS-B correlation.")
    parser.add_argument("--version", action=_Version)
    sub = parser.add_subparsers(dest="command", required=True)

    d = sub.add_parser("decode", help="decode recordings to CSV or Parquet")
    d.add_argument("inputs", nargs="+", metavar="INPUT")
    d.add_argument("-o", "--output", help="OUT.csv or OUT.parquet (one file per category: stem_cat048...)")
    d.add_argument("--category", type=int, action="append", choices=[21, 48], help="only this category")
    d.add_argument("--strict", action="store_true", help="stop at the first bad block")
    d.add_argument("--chunk-mb", type=float, default=64.0, help="streaming chunk size (MB)")
    _decoding_options(d)

    s = sub.add_parser("stats", help="what the recordings hold")
    s.add_argument("inputs", nargs="+", metavar="INPUT")
    s.add_argument("--chunk-mb", type=float, default=64.0,
                   help="streaming chunk size (MB); memory follows it, not the file")
    _decoding_options(s)

    c = sub.add_parser("correlate", help="correlate radar against ADS-B per aircraft (thesis algorithm)")
    _aircraft_options(c, "every aircraft seen by both sensors")
    c.add_argument("-o", "--output", help="Excel report (.xlsx); the track figure is written beside it")
    c.add_argument("--json", help="window summary as JSON")
    c.add_argument("--slot", type=float, default=10.0, help="slot width D in seconds (default 10)")
    c.add_argument("--gap", type=float, default=180.0, help="gap G in seconds that ends a period (180)")
    c.add_argument("--pairs", choices=["radar-adsb", "radar-radar", "all"], default="radar-adsb",
                   help="sensor pairs to correlate per aircraft: each radar against ADS-B (default), each "
                        "two radars, or both; plots of two radars are never mixed")
    c.add_argument("--split-adsb", action="store_true",
                   help="keep ADS-B ground stations apart (default: one ADS-B source per aircraft)")
    c.add_argument("--quality", action="store_true",
                   help="add the quality sheets (Quality, Update intervals, Gaps, Jumps, ADS-B quality, "
                        "Radar accuracy, Radar biases, Figures) and their PNGs")
    c.add_argument("--drop-jumps", action="store_true", help="remove detected ADS-B position jumps first")
    c.add_argument("--min-nic", type=int, help="drop ADS-B reports with NUCp/NIC below N")
    c.add_argument("--min-nacp", type=int, help="drop ADS-B reports with NACp below N")
    c.add_argument("--fill", choices=["hold", "predict"], default="hold",
                   help="empty slots: hold the previous slot (default, the thesis) or take the tracker's "
                        "prediction")
    c.add_argument("--tables", choices=["auto", "xlsx", "parquet"], default="auto",
                   help="slot and lag tables: in the workbook (xlsx), as STEM_slots.parquet and "
                        "STEM_correlation.parquet beside it (parquet), or Parquet past 5,000 rows (auto)")
    _adsb_sigma_option(c, "; used by --fill predict")
    _decoding_options(c)

    q = sub.add_parser("quality", help="sensor data quality and radar accuracy against ADS-B")
    _aircraft_options(q, "every aircraft", sensors_required=False)
    q.add_argument("-o", "--output", help="Excel workbook (.xlsx); figures are written beside it")
    q.add_argument("--json", help="the tables as JSON")
    q.add_argument("--gap", type=float, default=180.0,
                   help="gap in seconds reported as a discontinuity (180)")
    q.add_argument("--reference", choices=["adsb", "track"], default="adsb",
                   help="radar accuracy against ADS-B interpolated linearly (default) or against the "
                        "smoothed ADS-B-only IMM track")
    _adsb_sigma_option(q, "; used by --reference track")
    _decoding_options(q)

    t = sub.add_parser("track", help="fused IMM tracks per aircraft from every radar and ADS-B report")
    _aircraft_options(t, "every aircraft", sensors_required=False)
    t.add_argument("-o", "--output", help="track table: tracks.csv or tracks.parquet")
    t.add_argument("--json", help="per-aircraft and per-sensor summary as JSON")
    t.add_argument("--figures", metavar="DIR", help="one PNG per aircraft in this directory")
    t.add_argument("--step", type=float, default=1.0, help="output grid in seconds (default 1)")
    t.add_argument("--max-coast", type=float, default=60.0,
                   help="seconds a track is predicted after its last report before it ends (default 60)")
    t.add_argument("--smooth", action="store_true", help="backward (RTS) pass: reference trajectories")
    t.add_argument("--smoother", choices=["rts", "imm"],
                   help="implies --smooth: RTS on the combined estimate (default) or the IMM smoother "
                        "(smoothed mode probabilities too; better on straight legs, worse in most "
                        "manoeuvres in our validations)")
    t.add_argument("--tpm", help="mode transition law: fixed:P, dynamic, dynamic:A,B or expm:TAU[,TAU2] "
                                 "(default expm:150,20)")
    _sources_option(t)
    t.add_argument("--noise", default="estimate",
                   help="measurement noise: estimate (default: each sensor's sigmas from the tracker's "
                        "residuals, a few extra passes), timing (the same, and an ADS-B along-track "
                        "time-stamp sigma) or declared (the sensor file's sigmas, ADS-B from NACp)")
    _adsb_sigma_option(t, "; with --noise estimate it is then refined from the residuals")
    _decoding_options(t)

    k = sub.add_parser("conflicts", help="conflict probability from IMM-predicted tracks: alerts, losses of "
                                         "separation, warning times, false alerts")
    k.add_argument("inputs", nargs="+", metavar="INPUT")
    k.add_argument("--sensors", help=SENSORS_OPTIONAL_HELP)
    k.add_argument("-o", "--output", required=True,
                   help="conflicts.csv (losses and warning times beside it) or conflicts.xlsx")
    k.add_argument("--json", help="counts and the tables as JSON")
    k.add_argument("--horizon", default="20,60,120", help="look-aheads in seconds (default 20,60,120)")
    k.add_argument("--radius-nm", type=float, default=5.0, help="horizontal separation minimum (default 5)")
    k.add_argument("--vertical-ft", type=float, default=1000.0,
                   help="vertical separation minimum (default 1000)")
    k.add_argument("--vertical-tolerance-ft", type=float, default=25.0,
                   help="levels closer than --vertical-ft by at most this are separated: the 25 ft quantum "
                        "of reported levels (default 25)")
    k.add_argument("--threshold", type=float, default=0.2,
                   help="PC above which an alert is raised (default 0.2)")
    k.add_argument("--method", default="exact",
                   help="PC method: exact (default), one-block, blocks or midpoint")
    k.add_argument("--vertical", default="gate",
                   help="vertical proximity: gate (predicted levels closer than --vertical-ft, default) or "
                        "gaussian (PC times the probability from the vertical filter's sigma)")
    k.add_argument("--surface", default="exclude",
                   help="pairs with an aircraft on the aerodrome surface (as its reports say, else below "
                        "50 kt): exclude (default: separation minima apply between airborne aircraft) or "
                        "include them in the losses and alerts; counted either way")
    k.add_argument("--figures", metavar="DIR", help="one PNG per alert event in this directory")
    k.add_argument("--step", type=float, default=1.0, help="output step in seconds (default 1)")
    k.add_argument("--max-coast", type=float, default=60.0,
                   help="seconds a track is predicted after its last report before it ends (default 60)")
    k.add_argument("--tpm", help="mode transition law of the IMM (default expm:150,20)")
    _sources_option(k)
    k.add_argument("--noise", default="declared",
                   help="measurement noise: declared (default: the sensor file's sigmas, ADS-B from NACp "
                        "or --adsb-sigma; what the conflict validations used), estimate or timing "
                        "(each sensor's sigmas from the tracker's residuals first, as msdc track)")
    _adsb_sigma_option(k, "; with --noise estimate it is then refined from the residuals")
    _decoding_options(k)
    return parser


def _decoding(args) -> dict:
    return {"inputs": tuple(args.inputs), "editions": tuple(args.edition), "date": args.date,
            "format": args.format}


def _aircraft(args) -> dict:
    return {**_decoding(args), "sensors": args.sensors, "callsign": args.callsign, "address": args.address,
            "all_aircraft": args.all, "output": args.output, "json": args.json, "gap_s": args.gap,
            "adsb_sigma_m": args.adsb_sigma}


def _warn(command: str, warnings: list[str]) -> None:
    for w in warnings:
        print(f"msdc {command}: warning: {w}", file=sys.stderr)


def _report_skipped(loaded_errors: pd.DataFrame) -> None:
    if len(loaded_errors):
        print(f"msdc: {len(loaded_errors)} block(s) skipped ({int(loaded_errors['length'].sum())} bytes); "
              "'msdc stats' lists them", file=sys.stderr)


def _numba_without_scipy() -> None:
    """Start numba's CPU target (its first kernel would) without importing scipy.linalg: numba imports
    scipy.linalg.cython_blas at start-up only to choose BLAS or a loop for np.correlate and np.convolve,
    which no msdc kernel calls, and that import costs 0.1-0.3 s (scipy clones numpy's namespace, importing
    numpy.f2py). Hidden while numba starts, numba takes the loop; np.dot imports it when compiled."""
    if "scipy.linalg" in sys.modules:
        return
    try:
        from numba.core.registry import cpu_target

        context = cpu_target.target_context
    except (ImportError, AttributeError):  # numba's internals moved: it starts the usual way, on first use
        return
    sys.modules["scipy.linalg.cython_blas"] = None  # importing it now raises ImportError
    try:
        context.refresh()
    except ImportError:
        pass  # a numba that wants BLAS at start-up: started normally below
    finally:
        del sys.modules["scipy.linalg.cython_blas"]
    context.refresh()  # nothing left to do when the first call succeeded


def cmd_decode(args) -> int:
    """msdc decode: decode the inputs to CSV or Parquet, listing skipped blocks; the exit status."""
    from msdc.pipeline.jobs import decode

    _numba_without_scipy()
    progress = Progress()
    options = decode.DecodeOptions(**_decoding(args), output=args.output,
                                   categories=tuple(args.category or ()), strict=args.strict,
                                   chunk_mb=args.chunk_mb)
    try:
        with transaction.staged() as tx:
            result = decode.decode_job(options, tx=tx,
                                       on_chunk=lambda done, size, name: progress.bar(done, size, name))
    except asterix_errors.DecodeError as exc:
        raise CliError(f"strict: {exc}") from exc
    for line in result.notes + decode.skipped_lines(result):
        print(f"msdc: {line}", file=sys.stderr)
    _warn("decode", result.warnings)  # after the skipped blocks: a wrong edition's advice stays in view
    if not result.outputs:
        for cat, n in sorted(result.counts.items()):
            print(f"CAT{cat:03d}: {n} records")
    else:
        for cat, p in sorted(result.outputs.items()):
            print(f"CAT{cat:03d}: {result.counts.get(cat, 0)} records -> {p}")
    if result.skipped:
        print(f"msdc: {len(result.skipped)} block(s) skipped", file=sys.stderr)
    _list_written("decode", {f"CAT{cat:03d} records": p for cat, p in result.outputs.items()}, tx.written)
    if sum(result.counts.values()) == 0:
        print(f"msdc: {result.nothing_decoded(options.categories)}", file=sys.stderr)
        return 1
    return 0


def cmd_stats(args) -> int:
    """msdc stats: what the inputs hold, printed as tables; the exit status."""
    from msdc.pipeline.jobs import stats
    from msdc.pipeline.quality.inventory import format_stats

    _numba_without_scipy()
    options = stats.StatsOptions(**_decoding(args), chunk_mb=args.chunk_mb)
    result = stats.stats_job(options, progress=Progress())
    _warn("stats", result.warnings)
    print(format_stats(result.tables), end="")
    for info in result.inputs:
        for cat, why in info["edition_choice"].items():
            print(f"{info['path']}: CAT{cat:03d} --edition auto {why}")
    if not result.records:
        print("msdc: nothing could be decoded", file=sys.stderr)
        return 1
    return 0


def cmd_correlate(args) -> int:
    """msdc correlate: correlate radar against ADS-B and write the report; the exit status."""
    from msdc.pipeline.jobs import correlate

    progress = Progress()
    options = correlate.CorrelateOptions(
        **_aircraft(args), slot_s=args.slot, pairs=args.pairs, split_adsb=args.split_adsb,
        quality=args.quality, drop_jumps=args.drop_jumps, min_nic=args.min_nic, min_nacp=args.min_nacp,
        fill=args.fill, tables=args.tables)
    prepared = correlate.prepare_correlation_writers(options)  # gets ready on the other core meanwhile
    try:
        return _correlate(options, progress, prepared)
    finally:
        if prepared is not None:
            prepared.close()


def _correlate(options, progress: Progress, prepared) -> int:
    """Run the correlate job and write what it asks for, with ``prepared`` drawing the map."""
    from msdc.pipeline.jobs import correlate

    _numba_without_scipy()
    with transaction.staged() as tx:
        result = _run_job("correlate", correlate.validate, correlate.correlate_job, options, progress)
        for name, n in result.run.filters.items():
            print(f"filter {name}: {n} of the input's ADS-B reports", file=sys.stderr)
        from msdc.pipeline.report.summary import summary_table

        print(summary_table(result.run))
        if not options.quality:  # only --quality's figures read the measurements again; the other writers
            result.measurements = result.measurements.iloc[:0]  # need the run alone: the frame goes first
        written = correlate.write_correlation(result, progress, prepared=prepared, tx=tx)
    _list_written("correlate", written, tx.written)
    note = correlate.figure_windows_note(len(result.run.windows)) if options.quality else None
    if "report" in written and note:
        print(f"Figures: {note}", file=sys.stderr)
    return 0


def cmd_quality(args) -> int:
    """msdc quality: sensor quality and radar accuracy and biases, written as a workbook; the exit status."""
    from msdc.pipeline.jobs import quality

    _numba_without_scipy()
    options = quality.QualityOptions(**_aircraft(args), reference=args.reference)
    with transaction.staged() as tx:
        result = _run_job("quality", quality.validate, quality.quality_job, options, Progress())
        print(quality.text(result))
        written = quality.write_quality(result, tx=tx)
    _list_written("quality", written, tx.written)
    return 0


# what each kind of file a job returns is, as the list of written files says it
KINDS = {"json": "JSON", "report": "workbook", "workbook": "workbook", "figure": "track figure",
         "tracks": "track table", "alerts": "alerts table", "losses": "losses table",
         "warnings": "warning times table"}


def _list_written(command: str, kinds: dict[str, Path], written: list) -> None:
    """Every file the run put in place (``written``: the transaction's Written rows), on stderr beside the
    other notes (stdout holds the results scripts read): what it is (``kinds``: the job's kind -> path) and
    whether it replaced a file that was there."""
    if not written:
        return
    named = {transaction.target(path): (path, kind) for kind, path in kinds.items()}
    order = list(named)
    rows = sorted(written, key=lambda w: order.index(w.path) if w.path in named else len(order))
    replaced = sum(w.replaced for w in written)
    print(f"msdc {command}: {len(written)} file(s) written" + (f" ({replaced} replaced earlier files)"
                                                              if replaced else "") + ":", file=sys.stderr)
    for w in rows:
        path, kind = named.get(w.path, (w.path, "file"))
        what = "figure" if kind.startswith(("image ", "figure ")) else KINDS.get(
            kind, f"{kind.removeprefix('table ')} table (Parquet)" if kind.startswith("table ") else kind)
        print(f"  {path} ({what}{', replaced' if w.replaced else ''})", file=sys.stderr)


def cmd_track(args) -> int:
    """msdc track: fused tracks of the selected aircraft, written as Parquet or CSV; the exit status."""
    from msdc.pipeline.jobs import track

    options = track.TrackOptions(
        **_decoding(args), sensors=args.sensors, callsign=args.callsign, address=args.address,
        all_aircraft=args.all, output=args.output, json=args.json, figures=args.figures, step_s=args.step,
        max_coast_s=args.max_coast, smooth=args.smooth or args.smoother is not None,
        smoother=args.smoother or "rts", tpm=args.tpm, sources=args.sources, noise=args.noise,
        adsb_sigma_m=args.adsb_sigma)
    with transaction.staged() as tx:
        result = _run_job("track", lambda o: track.validate(o, require_output=True), track.track_job, options,
                          Progress())
        print(track.text(result))
        written = track.write_tracks(result, tx=tx)
    _list_written("track", written, tx.written)
    return 0


def cmd_conflicts(args) -> int:
    """msdc conflicts: losses of separation and conflict alerts from the fused tracks; the exit status."""
    from msdc.pipeline.jobs import conflicts
    from msdc.pipeline.jobs.common import noise_text

    options = conflicts.ConflictOptions(
        **_decoding(args), sensors=args.sensors, output=args.output, json=args.json, step_s=args.step,
        max_coast_s=args.max_coast, tpm=args.tpm, horizons_s=args.horizon, radius_nm=args.radius_nm,
        vertical_ft=args.vertical_ft, vertical_tolerance_ft=args.vertical_tolerance_ft,
        threshold=args.threshold, method=args.method, vertical=args.vertical,
        surface=args.surface, figures=args.figures, noise=args.noise, adsb_sigma_m=args.adsb_sigma,
        sources=args.sources)
    with transaction.staged() as tx:
        result = _run_job("conflicts", conflicts.validate, conflicts.conflict_job, options, Progress())
        print(conflicts.text(result) + noise_text(result.noise))
        written = conflicts.write_conflicts(result, tx=tx)
    _list_written("conflicts", written, tx.written)
    if args.figures is not None and not len(result.alerts):
        print(f"figures: none (no alert events), {args.figures} left as it was", file=sys.stderr)
    return 0


def _run_job(name: str, validate, job, options, progress: Progress):
    """Validate (warnings first), run the job, then print its later warnings (its result's, after
    validation's) and the skipped blocks. A job that fails prints the warnings it collected before its error
    (the error carries them: jobs.common.carrying): one may name the cause (a first day of plots before
    midnight explains "never overlap in time")."""
    checked = validate(options)
    _warn(name, checked.warnings)
    seen = len(checked.warnings)
    try:
        result = job(options, progress=progress, checked=checked, command=" ".join(sys.argv[1:]) or name)
    except (CliError, common.OptionError, common.JobError, asterix_errors.AsterixError, OSError) as exc:
        _warn(name, getattr(exc, "job_warnings", [])[seen:])  # main() prints the error after them
        raise
    _warn(name, result.warnings[seen:])
    _report_skipped(result.loaded.errors)
    return result


COMMANDS = {"decode": cmd_decode, "stats": cmd_stats, "correlate": cmd_correlate, "quality": cmd_quality,
            "track": cmd_track, "conflicts": cmd_conflicts}


def main(argv: list[str] | None = None) -> int:
    """Run msdc with argv (the process's when None) and return the exit status; never a traceback. SIGTERM
    and SIGHUP end the run as Ctrl-C does (report.transaction.Terminated: every staged output removed),
    with status 128 + the signal's number (Ctrl-C: 130)."""
    args = build_parser().parse_args(argv)
    handlers = transaction.raise_on_termination()
    try:
        return COMMANDS[args.command](args)
    except (CliError, common.OptionError, common.JobError) as exc:
        print(f"msdc {args.command}: {exc}", file=sys.stderr)
        return exc.status
    except asterix_errors.AsterixError as exc:
        print(f"msdc {args.command}: {exc}", file=sys.stderr)
        return 2
    except OSError as exc:  # writing outputs: disk full, permissions changed during the run
        print(f"msdc {args.command}: {exc.filename or ''}: {exc.strerror or exc}", file=sys.stderr)
        return 1
    except (KeyboardInterrupt, transaction.Terminated) as exc:
        return _interrupted(exc)
    except Exception as exc:  # Ctrl-C inside numba's cache loader surfaces as its SystemError
        if _interrupted(exc):
            return _interrupted(exc)
        raise
    finally:
        transaction.restore_handlers(handlers)


def _interrupted(exc: BaseException) -> int | None:
    """The exit status of an interrupt among the exceptions that caused or preceded ``exc`` (Ctrl-C: 130,
    SIGTERM or SIGHUP: 128 + the signal's number); None when there is none."""
    seen: set[int] = set()
    while exc is not None and id(exc) not in seen:
        if isinstance(exc, KeyboardInterrupt):
            return 130
        if isinstance(exc, transaction.Terminated):
            return 128 + exc.signum
        seen.add(id(exc))
        exc = exc.__cause__ or exc.__context__
    return None


# The command's automatic garbage collection waits for this many new container objects instead of Python's
# 700: msdc makes almost no reference cycles (collection frees about 700 objects in a 3 h correlate and
# 1,900 in a day's), while the collector's passes over pandas', numba's and openpyxl's objects cost 0.2-0.3 s
# of a 3 h run and 0.6 s of a day's. Cycles are still collected, about every million new objects.
GC_THRESHOLD = 1_000_000


def run() -> None:
    """The ``msdc`` command: main() with rare garbage collection (GC_THRESHOLD), then the exit handlers, and
    leave without the interpreter's teardown (numba's LLVM state takes 0.2-0.3 s of CPU to dismantle, a
    sixth of a short run). Every output is closed by then; if the standard streams cannot be flushed,
    Python exits the usual way and says so."""
    gc.set_threshold(GC_THRESHOLD, *gc.get_threshold()[1:])
    status = main()
    try:
        sys.stdout.flush()
        sys.stderr.flush()
    except (OSError, ValueError):  # a closed pipe (msdc ... | head): the interpreter reports it as before
        sys.exit(status)
    atexit._run_exitfuncs()  # openpyxl's temporary files, logging: what a normal exit would run
    os._exit(status)


if __name__ == "__main__":
    run()
