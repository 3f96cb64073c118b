"""The ``msdc`` command: argparse over the jobs, one module of pipeline.jobs per command, imported only when
its command runs; options are validated there, before any decoding, and every failure is one line on stderr
with exit status 2 (usage) or 1 (data)."""

from __future__ import annotations

import argparse
import atexit
import contextlib
import functools
import gc
import importlib
import os
import sys
from typing import TYPE_CHECKING

from msdc.pipeline.jobs.options import COMMAND_OPTIONS, add_options, from_args
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


DESCRIPTION = ("Multi-Sensor Data Correlator: ASTERIX decoding (radar, ADS-B, multilateration, surface "
               "radar, system tracks, status), sensor correlation, quality, IMM reference tracks, conflicts "
               "and evaluation against the surveillance standards, recorded or live.")
COMMAND_HELP = {
    "decode": "decode recordings to CSV or Parquet",
    "stats": "what the recordings hold",
    "correlate": "correlate two sensors per aircraft, radar against ADS-B by default (thesis algorithm; "
                 "radar pairs, multilateration, surface radar)",
    "quality": "sensor data quality, radar accuracy and biases against ADS-B, reference points",
    "track": "fused IMM tracks per aircraft from radar, ADS-B, multilateration and surface radar reports",
    "conflicts": "conflict probability from IMM-predicted tracks: alerts, losses of separation, warning "
                 "times, false alerts",
    "evaluate": "every sensor against a surveillance standard's requirements: scorecard with intervals and "
                "verdicts",
    "ingest": "decode recordings into a Parquet dataset by UTC day, category and sensor (resumable)",
    "sql": "a DuckDB query over a dataset 'msdc ingest' made",
    "listen": "receive live ASTERIX feeds over UDP: count, record as pcapng, serve the monitor page",
    "replay": "send recordings as UDP with their original timing scaled (simulate a live feed)",
}


def build_parser() -> argparse.ArgumentParser:
    """The msdc argument parser: one subcommand per job, its options those its options dataclass declares
    (pipeline.jobs.options)."""
    parser = argparse.ArgumentParser(prog="msdc", description=DESCRIPTION)
    parser.add_argument("--version", action=_Version)
    sub = parser.add_subparsers(dest="command", required=True)
    for command, summary in COMMAND_HELP.items():
        add_options(sub.add_parser(command, help=summary), COMMAND_OPTIONS[command])
    return parser


@functools.cache
def _parser() -> argparse.ArgumentParser:
    """build_parser's parser, built once a process (parsing leaves it as it was; tests run main hundreds
    of times in one process)."""
    return build_parser()


def _warn(command: str, warnings: list[str]) -> None:
    for w in warnings:
        print(f"msdc {command}: warning: {w}", file=sys.stderr)


def _report_skipped(name: str, loaded_errors: pd.DataFrame) -> None:
    if len(loaded_errors):
        skipped = int(loaded_errors["length"].sum())
        print(f"msdc {name}: {len(loaded_errors)} block(s) skipped ({skipped} bytes); 'msdc stats' lists "
              "them", file=sys.stderr)


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
    options = from_args(decode.DecodeOptions, args)
    try:
        with transaction.staged() as tx:
            result = decode.decode_job(options, tx=tx,
                                       on_chunk=lambda done, size, name: progress.bar(done, size, name))
    except asterix_errors.DecodeError as exc:
        raise CliError(f"strict: {exc}") from exc
    for line in result.notes + decode.skipped_lines(result):
        print(f"msdc decode: {line}", file=sys.stderr)
    _warn("decode", result.warnings)  # after the skipped blocks: a wrong edition's advice stays in view
    if not result.outputs:
        for cat, n in sorted(result.counts.items()):
            print(f"CAT{cat:03d}: {n} records")
    else:
        for cat, p in sorted(result.outputs.items()):
            print(f"CAT{cat:03d}: {result.counts.get(cat, 0)} records -> {p}")
    if result.skipped:
        print(f"msdc decode: {len(result.skipped)} block(s) skipped", file=sys.stderr)
    if result.selection is not None:
        print(_selection_line(result.selection).replace(" reports ", " records "))
    kinds = {f"CAT{cat:03d} records": p for cat, p in result.outputs.items()}
    if result.selection_file is not None:
        kinds["selection record"] = result.selection_file
    _list_written("decode", kinds, tx.written, decode.side_files(result.output))
    if sum(result.counts.values()) == 0:
        print(f"msdc decode: {result.nothing_decoded(options.categories)}", file=sys.stderr)
        return 1
    return 0


def cmd_stats(args) -> int:
    """msdc stats: what the inputs hold, printed as tables; the exit status."""
    from msdc.pipeline.jobs import stats
    from msdc.pipeline.quality.inventory import format_stats

    _numba_without_scipy()
    options = from_args(stats.StatsOptions, args)
    progress = Progress()
    with common.distributed(options, progress) as cluster:  # a dataset's partitions are its tasks
        result = stats.stats_job(options, progress=progress)
    _said_cluster("stats", options, cluster)
    _warn("stats", result.warnings)
    if result.selection is not None:
        print(_selection_line(result.selection).replace(" reports ", " records "))
    print(format_stats(result.tables), end="")
    for info in result.inputs:
        for cat, why in info["edition_choice"].items():
            print(f"{info['path']}: CAT{cat:03d} edition auto {why}")
    if not result.records:
        left = result.selection is not None and result.selection["reports"]
        read = ", ".join(_size_said(info) for info in result.inputs)
        if left:
            said = "the selection left no record"
        elif options.dataset is not None:  # the ingest decoded them: the dataset kept none of theirs
            said = f"--dataset {options.dataset} holds no record" + (f" of {read}" if read else "")
        else:
            said = "nothing could be decoded" + (f" from {read}" if read else "")
        print(f"msdc stats: {said}", file=sys.stderr)
        return 1
    return 0


def _size_said(info: dict) -> str:
    """An input and its size, for a run that decoded nothing from it: "radar.ast (empty)"."""
    size = int(info.get("bytes") or 0)
    return f"{info['path']} ({f'{size:,} bytes' if size else 'empty'})"


def _selection_line(record: dict) -> str:
    """The report selection's line on the terminal (report_selection.describe)."""
    from msdc.pipeline.model.report_selection import describe

    return describe(record)


def cmd_correlate(args) -> int:
    """msdc correlate: correlate radar against ADS-B and write the report; the exit status."""
    from msdc.pipeline.jobs import correlate

    progress = Progress()
    options = from_args(correlate.CorrelateOptions, args)
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
    _list_written("correlate", written, tx.written, correlate.side_files(result.checked))
    note = correlate.figure_windows_note(len(result.run.windows)) if options.quality else None
    if "report" in written and note:
        print(f"Figures: {note}", file=sys.stderr)
    return 0


def cmd_quality(args) -> int:
    """msdc quality: sensor quality and radar accuracy and biases, written as a workbook; the exit status."""
    from msdc.pipeline.jobs import quality

    _numba_without_scipy()
    options = from_args(quality.QualityOptions, args)
    with transaction.staged() as tx:
        result = _run_job("quality", quality.validate, quality.quality_job, options, Progress())
        print(quality.text(result))
        written = quality.write_quality(result, tx=tx)
    _list_written("quality", written, tx.written, quality.side_files(result.checked))
    return 0


# what each kind of file a job returns is, as the list of written files says it
KINDS = {"json": "JSON", "figures not drawn": "list of the figures not drawn",
         "report": "workbook", "workbook": "workbook", "figure": "track figure",
         "tracks": "track table", "alerts": "alerts table", "losses": "losses table",
         "warnings": "warning times table"}


def _list_written(command: str, kinds: dict[str, Path], written: list, beside: list | tuple = ()) -> None:
    """Every file the run put in place (``written``: the transaction's Written rows), on stderr beside the
    other notes (stdout holds the results scripts read): what it is (``kinds``: the job's kind -> path) and
    whether it replaced a file that was there; then the files matching the globs ``beside`` (the side files
    the command may write) that the run did not write: an earlier run's, left as they were."""
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
    earlier = transaction.left_beside(beside, written)
    if earlier:
        print(f"msdc {command}: {len(earlier)} earlier file(s) left as they were (named like this run's "
              "outputs, not written by it):", file=sys.stderr)
        for path in earlier:
            print(f"  {path}", file=sys.stderr)


def cmd_track(args) -> int:
    """msdc track: fused tracks of the selected aircraft, written as Parquet or CSV; the exit status."""
    from msdc.pipeline.jobs import track

    options = from_args(track.TrackOptions, args, smooth=args.smooth or args.smoother is not None)
    progress = Progress()
    with transaction.staged() as tx:
        result = _run_job("track", lambda o: track.validate(o, require_output=True), track.track_job, options,
                          progress)
        print(track.text(result))
        written = track.write_tracks(result, tx=tx, progress=progress)
    _list_written("track", written, tx.written, track.side_files(options))
    _figures_left_out("track", result.figures, written.get("figures not drawn"))
    return 0


def _figures_left_out(command: str, choice, listed: Path | None) -> None:
    """Say how many figures --figures-limit left out and where they are listed with their commands."""
    if choice is None or listed is None:
        return
    print(f"msdc {command}: {len(choice.drawn)} of {len(choice.names)} figures drawn (--figures-limit); the "
          f"other {len(choice.not_drawn)} are listed in {listed} with the command that draws each "
          "(--figures-limit 0 draws all)", file=sys.stderr)


def cmd_conflicts(args) -> int:
    """msdc conflicts: losses of separation and conflict alerts from the fused tracks; the exit status."""
    from msdc.pipeline.jobs import conflicts
    from msdc.pipeline.jobs.common import noise_text

    options = from_args(conflicts.ConflictOptions, args)
    progress = Progress()
    with transaction.staged() as tx:
        result = _run_job("conflicts", conflicts.validate, conflicts.conflict_job, options, progress)
        print(conflicts.text(result) + noise_text(result.noise))
        written = conflicts.write_conflicts(result, tx=tx, progress=progress)
    _list_written("conflicts", written, tx.written, conflicts.side_files(result.checked, options))
    _figures_left_out("conflicts", result.figures, written.get("figures not drawn"))
    if args.figures is not None and not len(result.alerts):
        print(f"figures: none (no alert events), {args.figures} left as it was", file=sys.stderr)
    return 0


def cmd_evaluate(args) -> int:
    """msdc evaluate: every sensor's performance against a preset's requirements; the exit status."""
    from msdc.pipeline.jobs import evaluate

    _numba_without_scipy()
    options = from_args(evaluate.EvaluateOptions, args)
    with transaction.staged() as tx:
        result = _run_job("evaluate", evaluate.validate, evaluate.evaluate_job, options, Progress())
        print(evaluate.text(result))
        written = evaluate.write_evaluation(result, tx=tx)
    _list_written("evaluate", written, tx.written, [])
    return 0


def cmd_ingest(args) -> int:
    """msdc ingest: the inputs not in the dataset yet decoded into it; the exit status."""
    from msdc.pipeline.jobs import ingest

    _numba_without_scipy()
    progress = Progress()
    options = from_args(ingest.IngestOptions, args)
    result = ingest.ingest_job(options, on_chunk=lambda done, size, name: progress.bar(done, size, name))
    if result.discarded:
        print(f"msdc ingest: removed {len(result.discarded)} file(s) an interrupted ingest left in "
              f"{result.dataset} (its inputs are ingested again now)", file=sys.stderr)
    for line in ingest.skipped_lines(result):
        print(f"msdc ingest: {line}", file=sys.stderr)
    _warn("ingest", result.warnings)  # after the skipped blocks, as msdc decode says them
    for line in ingest.summary_lines(result):
        print(line)
    if not result.ingested:
        print(f"msdc ingest: nothing to do: every input is already in {result.dataset}")
    return 0


def cmd_sql(args) -> int:
    """msdc sql: a DuckDB query over a dataset, printed or written with -o; the exit status."""
    from msdc.pipeline.jobs import sql

    options = from_args(sql.SqlOptions, args)
    with transaction.staged() as tx:
        result = sql.sql_job(options, tx=tx)
    _warn("sql", result.warnings)
    if result.output is not None:
        print(f"{result.rows_written} row(s) -> {result.output}")
    elif result.head is not None:
        print(result.head.to_string(index=False) if len(result.head.columns) else "(no column)")
        if result.more:
            print(f"msdc sql: only the first {len(result.head)} rows are shown (--limit; -o writes every "
                  "row)", file=sys.stderr)
    return 0


def cmd_listen(args) -> int:
    """msdc listen: receive the feeds until Ctrl-C (or --duration), then print the counts; exit 0 once the
    recording is closed, whatever ended the run."""
    from msdc.pipeline.jobs import listen

    _numba_without_scipy()
    options = from_args(listen.ListenOptions, args)
    names = ", ".join(options.udp)
    line = f"msdc listen: receiving {names} (Ctrl-C ends)"
    with _live_log_said("listen"):
        result = listen.listen_job(options, ready=lambda state: print(line, file=sys.stderr, flush=True),
                                   ingest=_ingester(options.dataset, options.editions))
    with listen.signals_held():  # the counts said whole, whatever signal follows the one that ended it
        _warn("listen", result.warnings)
        for line in listen.summary_lines(result):
            print(line)
        if result.decoding_failure:
            print(f"msdc listen: decoding stopped: {result.decoding_failure}", file=sys.stderr)
            return 1
    return 0


@contextlib.contextmanager
def _live_log_said(name: str):
    """The live package's log lines (a feed's socket failing, a batch that would not decode, the monitor's
    failures) said on stderr as msdc's warnings, a line each, inside the block: without a handler Python's
    fallback printed them bare, and a traceback with them."""
    import logging

    class Line(logging.Formatter):
        def format(self, record: logging.LogRecord) -> str:
            return f"msdc {name}: warning: {record.getMessage()}"

    handler = logging.StreamHandler(sys.stderr)
    handler.setFormatter(Line())
    logger = logging.getLogger("msdc.live")
    logger.addHandler(handler)
    try:
        yield
    finally:
        logger.removeHandler(handler)


def _ingester(dataset: str | None, editions: tuple[str, ...]):
    """listen --dataset: each closed recording ingested as 'msdc ingest FILE --dataset DIR' would; the
    lines it says. None without --dataset."""
    if dataset is None:
        return None
    from msdc.pipeline.jobs import ingest

    def run(path) -> list[str]:
        result = ingest.ingest_job(ingest.IngestOptions(inputs=(str(path),), dataset=dataset, lenient=True,
                                                        editions=editions))
        return [*ingest.skipped_lines(result), *result.warnings, *ingest.summary_lines(result)]

    return run


def cmd_replay(args) -> int:
    """msdc replay: send the recordings as UDP; the exit status (Ctrl-C: 130, with what was sent said)."""
    from msdc.pipeline.jobs import replay

    _numba_without_scipy()
    options = from_args(replay.ReplayOptions, args)
    early: list[str] = []

    def said(warnings: list[str]) -> None:  # before the first datagram goes: a long replay's start
        early.extend(warnings)
        _warn("replay", warnings)

    result = replay.replay_job(options, before_sending=said)
    _warn("replay", result.warnings[len(early):])
    ended = "" if result.interrupted is None else f"; {str(result.interrupted) or 'interrupted by Ctrl-C'}"
    print(f"{result.datagrams} datagrams ({result.bytes} bytes) sent to {options.to} in "
          f"{result.wall_s:.2f} s ({result.passes} pass(es) over {result.scheduled} datagrams spanning "
          f"{result.span_s:.1f} s of recording; at most {result.late_s * 1000:.1f} ms late{ended})")
    return 0 if result.interrupted is None else _interrupted(result.interrupted)


def _run_job(name: str, validate, job, options, progress: Progress):
    """Validate (warnings first), run the job, then print its later warnings (its result's, after
    validation's) and the skipped blocks. A job that fails prints the warnings it collected before its error
    (the error carries them: jobs.common.carrying): one may name the cause (a first day of plots before
    midnight explains "never overlap in time")."""
    checked = validate(options)
    _warn(name, checked.warnings)
    seen = len(checked.warnings)
    try:
        with common.distributed(options, progress) as cluster:
            result = job(options, progress=progress, checked=checked, command=" ".join(sys.argv[1:]) or name)
    except (CliError, common.OptionError, common.JobError, asterix_errors.AsterixError, OSError) as exc:
        _warn(name, getattr(exc, "job_warnings", [])[seen:])  # main() prints the error after them
        raise
    _said_cluster(name, options, cluster)
    _warn(name, result.warnings[seen:])
    _report_skipped(name, result.loaded.errors)
    if result.loaded.selection is not None:
        print(f"msdc {name}: {_selection_line(result.loaded.selection)}", file=sys.stderr)
    return result


def _said_cluster(name: str, options, cluster) -> None:
    """What ran on the Dask cluster, or that a --scheduler given was not used (nothing was distributed)."""
    if cluster is not None and cluster.summary():
        print(f"msdc {name}: {cluster.summary()}", file=sys.stderr)
    if cluster is not None and not cluster.used and getattr(options, "scheduler", None) is not None:
        print(f"msdc {name}: warning: --scheduler {options.scheduler}: not used: this run had no "
              "per-aircraft or per-partition work to distribute", file=sys.stderr)


COMMANDS = {"decode": cmd_decode, "stats": cmd_stats, "correlate": cmd_correlate, "quality": cmd_quality,
            "track": cmd_track, "conflicts": cmd_conflicts, "evaluate": cmd_evaluate, "ingest": cmd_ingest,
            "sql": cmd_sql, "listen": cmd_listen, "replay": cmd_replay}


def main(argv: list[str | os.PathLike] | None = None) -> int:
    """Run msdc with argv (the process's when None; a path object is its text) and return the exit status;
    never a traceback. SIGTERM and SIGHUP end the run as Ctrl-C does (report.transaction.Terminated: every
    staged output removed), with status 128 + the signal's number (Ctrl-C: 130)."""
    if argv is not None:  # argparse takes text only: a pathlib.Path from a library caller is its path
        argv = [os.fspath(a) if isinstance(a, os.PathLike) else a for a in argv]
    args = _parser().parse_args(argv)
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
    with contextlib.suppress(AttributeError, ValueError):  # a file name's bytes that are not UTF-8: escaped
        sys.stdout.reconfigure(errors="backslashreplace")
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
