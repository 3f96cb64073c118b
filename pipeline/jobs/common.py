"""What the command modules share: the errors (``JobError``; ``OptionError`` is the options'), the checks
that relate options (one aircraft selection, --max-coast against --step...), the inputs, outputs and sensor
file checked before anything is decoded (``Checked``), decoding the inputs with the warnings about them, and
the steps two commands run (the quality step; the tracker's measurements, row limit and noise estimate).
The options themselves, their ranges and choices are declared in ``pipeline.jobs.options``."""

from __future__ import annotations

import datetime as dt
import difflib
import math
import os
import shlex
import time
from collections.abc import Iterable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import pandas as pd

from msdc.asterix.categories import MEASUREMENT_CATEGORIES, REGISTRY
from msdc.pipeline.jobs.options import (
    MAX_COAST_RANGE_S,
    SOURCE_KINDS,
    STEP_RANGE_S,
    AircraftOptions,
    CorrelateOptions,
    DecodingOptions,
    OptionError,
    QualityOptions,
    ReferenceFilterOptions,
    TrackOptions,
    check_number,
    command_args,
)
from msdc.pipeline.meta import ADSB_SIGMA_RANGE_M as ADSB_SIGMA_RANGE_M  # re-exported, as before
from msdc.pipeline.meta import software_version
from msdc.pipeline.model import editions as edition_notes
from msdc.pipeline.model.heap import release_free_memory
from msdc.pipeline.model.identity import normalise_address, normalise_callsign
from msdc.pipeline.model.load import (
    Loaded,
    NoRecords,
    load,
    load_measurements,
    sha256,
)
from msdc.pipeline.model.sources import path_text
from msdc.pipeline.model.time import utc_text
from msdc.pipeline.progress import Progress
from msdc.pipeline.report.transaction import output_problem, side_pattern, target

if TYPE_CHECKING:  # the steps are imported where they run: msdc stats imports none of them
    from msdc.pipeline.dataset.cluster import DaskDistributor
    from msdc.pipeline.dataset.inputs import DatasetInputs
    from msdc.pipeline.jobs.options import SelectionOptions
    from msdc.pipeline.model.report_selection import ReportSelection
    from msdc.pipeline.model.selection import Selection
    from msdc.pipeline.quality.quality_run import QualityResult
    from msdc.pipeline.report.transaction import OutputTransaction


RAISED_SHOWN = 10  # aircraft listed on stdout whose sigma the per-aircraft guard raised; the JSON has all


class JobError(RuntimeError):
    """The data do not allow the job (no radar, no such aircraft, no overlap...); exit status 1."""

    def __init__(self, message: str, status: int = 1):
        super().__init__(message)
        self.status = status


@contextmanager
def carrying(said: Iterable[str] = ()) -> Iterator[list[str]]:
    """The list where a job (or a step of one) collects its warnings, starting with ``said``: an error
    leaving the block carries them as ``job_warnings``, before those of the step that failed, so that the
    command prints them ahead of the error (one may name its cause); a job that succeeds returns them."""
    warnings = list(said)
    try:
        yield warnings
    except Exception as exc:
        exc.job_warnings = [*warnings, *getattr(exc, "job_warnings", [])]
        raise


# ---------------------------------------------------------------------------------------------------------
# Validation helpers, one per kind of value (the declared ranges and choices: options.check_declared)


def select_chunk(rec, selection, sensors, left_out: dict[str, int], path) -> tuple[int, int]:
    """Keep the records of one decoded chunk that the report selection keeps (``rec.frames`` replaced), the
    counts left out added to ``left_out``: (records read, records kept). OptionError naming the input when a
    time cannot be placed on the recording's day."""
    from msdc.pipeline.model.decoded_reports import select_decoded

    try:
        rec.frames, n = select_decoded(rec.frames, selection, rec.date, sensors, left_out)
    except ValueError as exc:
        raise OptionError(f"{exc} ({path})") from None
    return n, sum(len(f) for f in rec.frames.values())


def _editions(editions: list[str] | dict | None) -> dict[int, str]:
    """CAT=EDITION pins checked against the shipped tables, or "auto" (any category: asterix.families)."""
    from msdc.asterix.tables import available, resolve_edition

    items = editions.items() if isinstance(editions, dict) else (
        str(e).partition("=")[::2] for e in (editions or []))
    out = {}
    for cat, ed in items:
        if not str(cat).strip().isdigit() or int(cat) not in available():
            raise OptionError(f"--edition {cat}={ed}: category must be one of "
                              f"{', '.join(str(c) for c in sorted(available()))}")
        cat = int(cat)
        if not isinstance(ed, str):  # {48: 1.30} is 1.3, and 2.7 no table name
            raise OptionError(f"--edition {cat}={ed!r}: a {type(ed).__name__}; give the edition as text, as "
                              "the tables name it ('1.30': a float cannot hold 1.30)")
        if ed != "auto":
            try:
                resolve_edition(cat, ed)
            except ValueError as exc:
                raise OptionError(f"--edition {cat}={ed}: {exc}") from None
        if out.get(cat, ed) != ed:
            raise OptionError(f"--edition {cat}={ed}: CAT{cat:03d} is already pinned to {out[cat]}; give one "
                              "edition per category")
        out[cat] = ed
    return out


def pinned_editions(editions: list[str] | dict | None) -> dict[int, str]:
    """--edition CAT=EDITION pins, checked (OptionError naming a bad one): for jobs that read no file."""
    return _editions(editions)


def input_files(paths: list[str | Path]) -> tuple[list[Path], list[str]]:
    """The input files, checked (OptionError naming a missing or unreadable one), and a warning for each
    skipped because its content was given before."""
    paths, warnings, _ = _inputs(paths)
    return paths, warnings


def nonempty_path(name: str, value) -> None:
    """OptionError for an empty path (an unset shell variable): Path("") is the current directory."""
    if value is not None and not str(value).strip():
        raise OptionError(f"{name} {str(value)!r}: an empty path")


def _not_a_file(p: Path, noun: str, thing: str) -> str | None:
    """Why ``p`` cannot be read as a file (missing, a directory, a FIFO or device), None when it can:
    ``noun`` names it ("input"), ``thing`` what it should be ("a recording file")."""
    if not p.exists():
        return f"{noun} file does not exist"
    if p.is_dir():
        return f"{noun} is a directory, not {thing}"
    if not p.is_file():  # reading a FIFO blocks, and its bytes could be read only once
        return f"{noun} is not a regular file (a FIFO, socket or device); give {thing}"
    return None


def _inputs(paths: list[str | Path]) -> tuple[list[Path], list[str], dict[Path, str]]:
    """Readable input files, a warning for each skipped because its content was given before, and each
    file's SHA-256."""
    if not paths:
        raise OptionError("no input file given")
    for p in paths:
        nonempty_path("input", p)
    out, seen, warnings = [], {}, []
    for p in map(Path, paths):
        problem = _not_a_file(p, "input", "a recording file")
        if problem:
            raise OptionError(f"{p}: {problem}")
        if not os.access(p, os.R_OK):
            raise OptionError(f"{p}: input file is not readable")
        digest = sha256(p)
        if digest in seen:
            warnings.append(f"{p}: same content as {seen[digest]} (SHA-256); skipped")
            continue
        seen[digest] = p
        out.append(p)
    return out, warnings, {p: d for d, p in seen.items()}


def output_path(name: str, path: str | Path | None, suffixes: tuple[str, ...]) -> Path | None:
    """An output path with an allowed suffix, not a directory, FIFO or device, in a writable directory (for
    a symbolic link: the directory of the file it points to, which is replaced)."""
    if path is None:
        return None
    nonempty_path(name, path)
    p = Path(path)
    if p.suffix.lower() not in suffixes:
        raise OptionError(f"{name} {p}: must end in {' or '.join(suffixes)}")
    problem = output_problem(p)
    if problem:
        raise OptionError(f"{name} {p}: {problem}")
    parent = real_output(p).parent if str(p.parent) else Path(".")
    if parent.exists() and not parent.is_dir():
        raise OptionError(f"{name} {p}: {parent} is a file, not a directory")
    if not parent.is_dir():
        raise OptionError(f"{name} {p}: directory {parent} does not exist")
    writable = os.access(parent, os.W_OK) and (not p.exists() or os.access(p, os.W_OK))
    if not writable or not _can_create(parent):
        raise OptionError(f"{name} {p}: not writable (directory {parent})")
    return p


def real_output(path: Path) -> Path:
    """The file an output really is: the one a symbolic link points to (the link is kept), else ``path`` as
    given. The files written beside an output are named after it and go beside it."""
    return target(path) if path.is_symlink() else path


def check_beside(option: str, out: Path, files: Iterable[tuple[str, Path]]) -> None:
    """OptionError when a file written beside the output ``out`` (``(noun, path)`` pairs) cannot be: a
    directory, FIFO or device, or an existing file that is not writable."""
    for noun, path in files:
        problem = output_problem(path)
        if problem is None and path.exists() and not os.access(path, os.W_OK):
            problem = "is not writable"
        if problem:
            raise OptionError(f"{option} {out}: its {noun} {path} {problem}")


def spare_inputs(options, outputs: list[tuple[str, Path | None]]) -> None:
    """OptionError when an output (a ``(what, path)`` pair: the option and the file or folder it writes) is
    one of the options' inputs, by any path or link (writing it would destroy the recording before or while
    it is read), or lies inside their ``--dataset`` folder (it would overwrite the manifest or a part)."""
    dataset = getattr(options, "dataset", None)
    if dataset is not None:
        spare_dataset(dataset, outputs)
    inputs = options.inputs
    inputs = [inputs] if isinstance(inputs, str | Path) else inputs  # one path is one input
    given = [(Path(p), "the input", "the recording") for p in inputs if Path(p).is_file()]
    for flag in OPTION_FILES:  # the files other options read (a sectors file overwritten by --json)
        value = getattr(options, flag.removeprefix("--").replace("-", "_"), None)
        if isinstance(value, str | Path) and Path(value).is_file():
            given.append((Path(value), f"the {flag} file", "it"))
    for what, out in outputs:
        if out is None or not Path(out).is_file():
            continue
        for p, role, lost in given:
            if os.path.samefile(out, p):
                also = "" if what.endswith(str(out)) else f" (it writes {out})"
                raise OptionError(f"{what}{also}: is {role} {p}; writing it would destroy {lost}")


# options naming a file a job reads besides its recordings (a preset or an area given by name is no file)
OPTION_FILES = ("--sensors", "--sectors", "--reference-file", "--area", "--preset")


def writable_dataset(dataset: str | Path) -> Path:
    """The --dataset folder an ingest writes (made if missing): OptionError when it is a file, its parent
    folder is missing or it cannot be written."""
    root = Path(dataset)
    if root.exists() and not root.is_dir():
        raise OptionError(f"--dataset {root}: is a file, not a folder")
    parent = root if root.exists() else root.parent
    if not parent.is_dir():
        raise OptionError(f"--dataset {root}: folder {parent} does not exist")
    if not os.access(parent, os.W_OK):
        raise OptionError(f"--dataset {root}: not writable")
    return root


# A folder a run made (ingest's --dataset, listen's --record) is removed again when the run ends holding no
# file in it: a stopped or failed run leaves the output folder as it was, absent.
def first_missing(folder: Path) -> Path | None:
    """The outermost folder of ``folder``'s path that does not exist yet (what ``mkdir(parents=True)`` makes
    first); None when ``folder`` exists."""
    if folder.exists():
        return None
    made = folder
    while not made.parent.exists() and made.parent != made:
        made = made.parent
    return made


def holds_files(root: Path, besides: tuple[str, ...] = ()) -> bool:
    """Whether the folder holds a file, at any depth, but those named in ``besides`` (ingest's lock)."""
    return any(p.is_file() and p.name not in besides for p in root.rglob("*"))


def remove_if_empty(root: Path | None, besides: tuple[str, ...] = ()) -> None:
    """Remove the folder a run made (None: it made none) when it holds no file but ``besides``: those files,
    then its folders, deepest first; one holding anything else stays."""
    if root is None or not root.is_dir() or holds_files(root, besides):
        return
    for name in besides:
        for p in root.rglob(name):
            p.unlink(missing_ok=True)
    for d in sorted((p for p in root.rglob("*") if p.is_dir()), key=lambda p: len(p.parts), reverse=True):
        try:
            d.rmdir()
        except OSError:
            return
    try:
        root.rmdir()
    except OSError:
        pass


def spare_dataset(dataset: str | Path, outputs: list[tuple[str, Path | None]]) -> None:
    """OptionError when an output lies inside the dataset folder, by any path or link: it could overwrite
    the manifest or a part (the dataset's folder is ingest's alone)."""
    root = Path(dataset).resolve()
    for what, out in outputs:
        if out is not None and Path(out).resolve().is_relative_to(root):
            raise OptionError(f"{what}: is inside the dataset {dataset}; writing there would change the "
                              "dataset: write it elsewhere")


def _can_create(directory: Path) -> bool:
    """Whether a file can really be created here (permission bits do not stop root; read-only mounts,
    ACLs and pseudo file systems do): a temporary file is created and removed at once."""
    import tempfile

    try:
        with tempfile.NamedTemporaryFile(dir=directory, prefix=".msdc-probe-"):
            return True
    except OSError:
        return False


def sensor_table(path: str | Path | None, *, required: bool = True) -> pd.DataFrame:
    """The sensor table of --sensors; without the option an empty table where it is optional (track and
    conflicts on ADS-B alone: a radar plot then stops the run naming --sensors), else an OptionError."""
    if path is None and not required:
        from msdc.pipeline.model.sensors import no_sensors

        return no_sensors()
    if path is None:
        raise OptionError("--sensors: the sensor file (TOML [[sensor]] tables) is required")
    nonempty_path("--sensors", path)
    from msdc.pipeline.model.sensors import read_sensors

    p = Path(path)
    problem = _not_a_file(p, "sensor", "a TOML sensor file")
    if problem:
        raise OptionError(f"--sensors {p}: {problem}")
    try:
        return read_sensors(p)
    except OSError as exc:
        raise OptionError(f"--sensors {p}: cannot be read ({exc.strerror})") from None
    except ValueError as exc:
        raise OptionError(str(exc).replace("\n", " ")) from None


def check_figures_dir(path, *, writable: bool = False) -> None:
    """--figures: a directory, or one that can be made in an existing directory (``writable``: that directory
    must be writable); OptionError otherwise."""
    nonempty_path("--figures", path)
    d = Path(path)
    if d.exists() and not d.is_dir():
        raise OptionError(f"--figures {d}: exists and is not a directory")
    parent = d if d.exists() else (d.parent if str(d.parent) else Path("."))
    if not parent.is_dir():
        raise OptionError(f"--figures {d}: directory {d.parent} does not exist")
    if writable and not (os.access(parent, os.W_OK) and _can_create(parent)):  # root: a real probe too
        raise OptionError(f"--figures {d}: directory {parent} is not writable")


# ---------------------------------------------------------------------------------------------------------
# Checks of options shared by several commands


def check_decoding(o: DecodingOptions) -> Checked:
    """The options every job shares (--date, the inputs, --edition; --format is a declared choice): the
    inputs to read, the editions pinned and the warnings about the inputs; OptionError if bad. The jobs run
    it after check_declared: a bad option is found before the inputs are read and hashed."""
    if o.date is not None:
        from msdc.asterix.reader import parse_date  # the rule asterix.read and load apply to date=

        try:
            parse_date(o.date, "--date")
        except (TypeError, ValueError) as exc:
            raise OptionError(str(exc)) from None
    inputs = [o.inputs] if isinstance(o.inputs, str | Path) else list(o.inputs)  # one path is one input
    editions = o.editions if isinstance(o.editions, dict) else [o.editions] if isinstance(
        o.editions, str) else list(o.editions)  # {21: "0.26"} as asterix.read takes it, or "21=0.26"
    selection = check_report_selection(o)
    dataset = getattr(o, "dataset", None)
    check_scheduler(o)
    if dataset is not None:
        asked = (("--edition", editions), ("--date", o.date), ("--format", o.format))
        decoding = [flag for flag, given in asked if given]
        if decoding:
            raise OptionError(f"--dataset {dataset} with {', '.join(decoding)}: these say how to decode "
                              "recordings, and the dataset's were decoded by msdc ingest (its manifest keeps "
                              "the options each input was ingested with); give them to msdc ingest")
        source = check_dataset(dataset, inputs, selection)
        return Checked(source.paths, _editions(editions), selection=selection, dataset=source)
    paths, warnings, digests = _inputs(inputs)
    return Checked(paths, _editions(editions), warnings=warnings, selection=selection, digests=digests)


def check_scheduler(o) -> None:
    """--scheduler (local, none or tcp://HOST:PORT) and --workers (only for a local cluster); OptionError."""
    from msdc.pipeline.dataset.cluster import LOCAL, scheduler_problem

    scheduler, workers = getattr(o, "scheduler", None), getattr(o, "workers", None)
    if scheduler is not None:
        why = scheduler_problem(scheduler)
        if why:
            raise OptionError(f"--scheduler {scheduler!r}: {why}")
    if workers is not None and effective_scheduler(o) != LOCAL:
        raise OptionError(f"--workers {workers}: sizes the local Dask cluster, which runs with --dataset or "
                          "--scheduler local (not with --scheduler "
                          f"{effective_scheduler(o)})")


def effective_scheduler(o) -> str:
    """Where a job's distributable work runs: --scheduler as given, else local with --dataset, else none."""
    from msdc.pipeline.dataset.cluster import LOCAL, NONE

    given = getattr(o, "scheduler", None)
    if given is not None:
        return given
    return LOCAL if getattr(o, "dataset", None) is not None else NONE


@contextmanager
def distributed(o, progress: Progress | None = None) -> Iterator[DaskDistributor | None]:
    """The job's distributor installed for the block (pipeline.parallel.distributed_by), closed after it;
    None (threads) for --scheduler none. A cluster that cannot be reached is a JobError naming it; a task
    that failed on every try is a JobError naming its aircraft or partition."""
    from msdc.pipeline.dataset.cluster import NONE, ClusterUnavailable, DaskDistributor, TaskFailed
    from msdc.pipeline.parallel import distributed_by

    where = effective_scheduler(o)
    if where == NONE:
        yield None
        return
    distributor = DaskDistributor(where, getattr(o, "workers", None), progress)
    try:
        with distributed_by(distributor):
            yield distributor
    except (ClusterUnavailable, TaskFailed) as exc:
        raise JobError(str(exc)) from None
    finally:
        distributor.close()


def check_dataset(root, inputs: list, selection: ReportSelection) -> DatasetInputs:
    """--dataset as the inputs (pipeline.dataset.inputs), pruned by the report selection; OptionError (exit
    2) naming the folder when it is no dataset or its manifest cannot be read, or when INPUT files are
    given too."""
    from msdc.pipeline.dataset.inputs import open_inputs, pruning
    from msdc.pipeline.dataset.manifest import ManifestError
    from msdc.pipeline.dataset.reader import NotADataset

    nonempty_path("--dataset", root)
    if inputs:
        given = ", ".join(map(str, inputs))
        raise OptionError(f"--dataset {root} and INPUT files ({given}) both given: read either the "
                          "recordings or the dataset made of them")
    try:
        source = open_inputs(root)
    except (NotADataset, ManifestError) as exc:
        raise OptionError(f"--dataset {exc}") from None
    if not source.records:
        raise OptionError(f"--dataset {root}: the dataset holds no input yet (its manifest lists none)")
    source.pruning = pruning(selection)
    return source


def no_sensor_kind(selection: ReportSelection | None, command: str) -> None:
    """OptionError for a --sensor naming a CAT010 kind in a command that reads records before their kind is
    worked out (decode, stats): it kept nothing, said only as "the selection left no record"."""
    for ref in () if selection is None else selection.sensors:
        if ref.kind is not None:
            plain = ref.text.rsplit(":", 1)[0]
            raise OptionError(f"--sensor {ref.text}: {command} reads CAT010 records before their kind "
                              f"({ref.kind}) is worked out (when measurements are built): name the sensor "
                              f"without it, --sensor {plain}")


def check_report_selection(o: DecodingOptions) -> ReportSelection:
    """--from, --to, --area, --fl and --sensor as a ReportSelection (pipeline.model.report_selection), the
    polygon file read and a sensor window's site looked up in --sensors; OptionError naming the option and
    value. A time of day is placed on the recording's day once it is known (ReportSelection.window)."""
    from msdc.pipeline.model import report_selection as rs
    from msdc.pipeline.model.polygons import read_polygons

    try:
        start = rs.parse_time(o.from_time, "--from") if o.from_time is not None else None
        end = rs.parse_time(o.to_time, "--to") if o.to_time is not None else None
        if start is not None and end is not None and (start.instant is None) == (end.instant is None):
            rs.check_order(start, end)  # said now; a time of day and a date-time: once placed
        fl = rs.parse_fl(o.fl) if o.fl is not None else None
        ids = (o.sensor_ids,) if isinstance(o.sensor_ids, str) else tuple(o.sensor_ids or ())
        sensors = tuple(dict.fromkeys(rs.parse_sensor(s) for s in ids))
    except ValueError as exc:
        raise OptionError(str(exc)) from None
    area = None
    if o.area is not None:
        nonempty_path("--area", o.area)
        text = str(o.area)
        if text.lower().endswith((".geojson", ".json")) or Path(text).exists():
            problem = _not_a_file(Path(text), "--area", "a GeoJSON file")
            if problem:
                raise OptionError(f"--area {text}: {problem}")
            try:
                area = read_polygons(text)
            except ValueError as exc:
                raise OptionError(f"--area {exc}") from None
        else:
            try:
                window = rs.parse_window(text)
                table = sensor_table(o.sensors, required=False)
                area = rs.with_site(window, table, None if o.sensors is None else str(o.sensors))
            except ValueError as exc:
                raise OptionError(str(exc)) from None
    return rs.ReportSelection(start=start, end=end, area=area, area_text=None if o.area is None else str(
        o.area), fl=fl, fl_text=o.fl, sensors=sensors)


def check_aircraft(o: AircraftOptions) -> None:
    """The aircraft selection: exactly one of --callsign, --address and --all, each well formed."""
    chosen = [o.callsign is not None, o.address is not None, bool(o.all_aircraft)]
    if sum(chosen) != 1:
        raise OptionError("choose exactly one of --callsign, --address or --all")
    if o.callsign is not None and not (normalise_callsign(o.callsign) or "").isalnum():
        raise OptionError(f"--callsign {o.callsign!r}: must be letters and digits (spaces ignored)")
    if o.address is not None:
        text = (normalise_address(o.address) or "")
        if len(text) != 6 or any(c not in "0123456789ABCDEF" for c in text):
            raise OptionError(f"--address {o.address!r}: must be a 24-bit hex address (up to 6 hex digits)")


def parse_sources(value) -> tuple[str, ...]:
    """--sources as a tuple of SOURCE_KINDS ("radar,adsb" or a sequence); OptionError naming the option if
    bad."""
    items = tuple(value.split(",")) if isinstance(value, str) else tuple(value or ())
    items = tuple(s.strip().lower() for s in items)
    if not items or any(s not in SOURCE_KINDS for s in items) or len(set(items)) != len(items):
        raise OptionError(f"--sources {','.join(items) if items else value!r}: must be a comma-separated "
                          f"subset of {','.join(SOURCE_KINDS)} without repeats")
    return items


def check_tracking(options: TrackOptions) -> float:
    """The tracker's options shared by track and conflicts (--step, --max-coast, --tpm), checked before
    check_declared: --max-coast relates to --step, and --step's own messages come first; OptionError if
    bad, else the step (s)."""
    from msdc.pipeline.track import check_tpm

    step = options.step_s
    if not isinstance(step, int | float) or not math.isfinite(step) or not step > 0.0:
        raise OptionError(f"--step {step!r}: must be a finite number of seconds > 0")
    check_number("--step", step, *STEP_RANGE_S, " s")
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
    return step


def check_selection(options: SelectionOptions) -> Selection:
    """The samples an analysis counts (--min-fl, --exclude-mode-a-only, --exclude-codes), checked before
    decoding: OptionError naming the option (check_declared checks --min-fl's range)."""
    from msdc.pipeline.model.selection import Selection, parse_codes

    try:
        codes = parse_codes(options.exclude_codes) if options.exclude_codes is not None else ()
    except ValueError as exc:
        raise OptionError(str(exc)) from None
    if options.exclude_codes is not None and not codes:
        raise OptionError("--exclude-codes: give at least one Mode 3/A code, e.g. 7000")
    return Selection(min_fl=None if options.min_fl is None else float(options.min_fl),
                     exclude_mode_a_only=bool(options.exclude_mode_a_only), exclude_codes=codes)


@dataclass
class Checked:
    """Options after validation: the inputs to read (duplicates dropped), editions, sensor table, outputs."""

    inputs: list[Path]
    editions: dict[int, str]
    sensors: pd.DataFrame | None = None
    output: Path | None = None
    json: Path | None = None
    warnings: list[str] = field(default_factory=list)
    selection: ReportSelection | None = None  # --from, --to, --area, --fl, --sensor (check_report_selection)
    dataset: DatasetInputs | None = None  # --dataset: the inputs read from it (check_dataset)
    digests: dict[Path, str] = field(default_factory=dict)  # each input's SHA-256, hashed to find duplicates


def check_workbook(options: AircraftOptions, checked: Checked, *, figure_windows: int | None,
                   sensors_required: bool = True) -> list[str]:
    """What correlate and quality check after -o (``checked.output``): --json, the sensor file, the figures
    beside the workbook (``figure_windows``: _figures_beside), no output an input; sets ``checked.json`` and
    ``checked.sensors`` and returns the warnings about the sensor file (implausible site altitudes)."""
    from msdc.pipeline.model.sensors import implausible_altitudes
    from msdc.pipeline.report.tables import TABLE_FILES, parquet_path

    checked.json = output_path("--json", options.json, (".json",))
    checked.sensors = sensor_table(options.sensors, required=sensors_required)
    out = checked.output
    if out is not None:
        base = real_output(out)
        figures = _figures_beside(base, checked.sensors, figure_windows)
        check_beside("-o", out, [("figure", png) for png in figures])
        beside = [base.with_name(f"{base.stem}_tracks.png"), *(parquet_path(base, n) for n in TABLE_FILES),
                  *figures]
        spare_inputs(options, [(f"-o {out}", out)] + [(f"-o {out}", p) for p in beside])
    spare_inputs(options, [(f"--json {checked.json}", checked.json)])
    return implausible_altitudes(checked.sensors, options.sensors)


def _figures_beside(out: Path, sensors: pd.DataFrame, windows: int | None) -> list[Path]:
    """The quality figures a run may write beside its workbook: none when ``windows`` is None (correlate
    without --quality), else the update intervals, each declared radar's errors and the slotting and lag
    figures of the first ``windows`` windows (correlate --quality: FIGURE_WINDOWS; quality: 0)."""
    if windows is None:
        return []
    names = [f"{out.stem}_intervals.png"] + [f"{out.stem}_radar_errors_{sac}_{sic}.png"
                                             for sac, sic in zip(sensors["sac"], sensors["sic"], strict=True)]
    names += [f"{out.stem}_{kind}_{i + 1}.png" for kind in ("slotting", "lags") for i in range(windows)]
    return [out.with_name(n) for n in names]


# ---------------------------------------------------------------------------------------------------------
# Decoding the inputs


def load_inputs(options: DecodingOptions, checked: Checked, progress: Progress | None, extra_columns=(),
                extra_categories=()) -> tuple[Loaded, list[str]]:
    """Decode the inputs for measurements (only the columns build_measurements reads, and
    ``extra_columns``; the measurement categories and ``extra_categories``), with the warnings about
    them."""
    import warnings as python_warnings

    from msdc.asterix.categories import MEASUREMENT_CATEGORIES
    from msdc.asterix.errors import ContentWarning, EditionWarning, UnreadableInput
    from msdc.pipeline.dataset.inputs import UnreadablePart
    from msdc.pipeline.model.measurements import DECODED_COLUMNS, impossible_positions

    reading_window(checked)
    try:
        with python_warnings.catch_warnings():  # a wrong edition is said below, with its --edition; what
            python_warnings.simplefilter("ignore", EditionWarning)  # the inputs are, in loaded.warnings
            python_warnings.simplefilter("ignore", ContentWarning)
            python_warnings.filterwarnings("ignore", r".*: date=\S+ ignored, the capture time dates",
                                           UserWarning)  # date_ignored says it, naming --date
            loaded = load(checked.inputs, editions=checked.editions or None, date=options.date,
                          format=options.format, columns=(*DECODED_COLUMNS, *extra_columns),
                          categories=(sorted({*MEASUREMENT_CATEGORIES, *extra_categories})
                                      if extra_categories else None), progress=progress,
                          dataset=checked.dataset)
    except (UnreadableInput, UnreadablePart) as exc:
        raise JobError(str(exc), 2) from exc
    return loaded, [*_empty_inputs(loaded, checked.dataset), *_wrong_editions(loaded),
                    *order_warnings(read_paths(checked, loaded), loaded.spans),
                    *date_ignored(options, loaded.inputs),
                    *format_hints(options, loaded.inputs, read_paths(checked, loaded)),
                    *impossible_positions(loaded.frames.get(21)), *loaded.warnings]


def read_paths(checked: Checked, loaded: Loaded) -> list[Path]:
    """The inputs the run decoded, in order (loaded.spans' order): of a dataset, those with a part the run
    read, which may be fewer than it holds."""
    return list(checked.inputs) if checked.dataset is None else [Path(i["path"]) for i in loaded.inputs]


def reading_window(checked: Checked) -> None:
    """A dataset's read narrowed to the records a measurement job builds from: those within the time
    window's margin (report_selection.MarginCut), when the window is given as instants."""
    from msdc.pipeline.dataset.inputs import reading_pruning

    if checked.dataset is not None:
        checked.dataset.pruning = reading_pruning(checked.dataset.pruning, checked.selection)


def undated_warning(loaded: Loaded, outputs: str) -> list[str]:
    """A warning when no input carries a date and --date was not given: ``outputs`` then place their times
    on 1970-01-01 (pipeline.model.time.UNDATED_DAY); the times of day are right."""
    if loaded.date is not None:
        return []
    return [f"the inputs carry no date and --date was not given: {outputs} are placed on 1970-01-01 (the "
            "times of day are right); give --date YYYY-MM-DD"]


def order_warnings(paths: list[Path], spans: list[dict[str, tuple[pd.Timestamp, pd.Timestamp]]]
                   ) -> list[str]:
    """A warning for each input whose records of a data source (category, SAC, SIC) start before the end
    of that source in an earlier input: one sensor's recording given out of order. Two sensors recorded
    side by side (two radars' files) overlap in time as they should."""
    warnings, last = [], {}
    for path, by_source in zip(paths, spans, strict=True):
        for source, (lo, hi) in sorted(by_source.items()):
            if source in last and lo < last[source][0]:
                warnings.append(f"{path}: {source} starts at {lo}, before the end of its records in "
                                f"{last[source][1]} ({last[source][0]}): inputs run backwards in time")
            last[source] = (hi, str(path))
    return warnings


def format_hints(options: DecodingOptions, inputs: list[dict], paths: list[Path] | None = None) -> list[str]:
    """format_hint for each input, unless --format was given; ``paths``: the inputs' files (their ``path``
    is text, a name that is not UTF-8 escaped: no file of that name), else their ``path``."""
    if options.format is not None:
        return []
    paths = [info["path"] for info in inputs] if paths is None else paths
    hints = (format_hint(p, info["format"], info["skipped_blocks"])
             for p, info in zip(paths, inputs, strict=True))
    return [hint for hint in hints if hint]


def format_hint(path, fmt: str | None, skipped_blocks: int) -> str:
    """A hint to give --format when detection read a file as raw, blocks were skipped, and the file reads as a
    recorder file (final, gps, oradis) but for its first frame (asterix.containers.recorder_hint); else ''."""
    from msdc.asterix.containers import DETECT_BYTES, recorder_hint
    from msdc.asterix.verdict import recorder_words

    if fmt != "raw" or not skipped_blocks:
        return ""
    try:
        with open(path, "rb") as file:
            guess = recorder_hint(file.read(DETECT_BYTES))
    except OSError:  # a dataset's input, moved since it was ingested: no hint
        return ""
    return "" if guess is None else recorder_words(path_text(path), skipped_blocks, guess)


def date_ignored(options: DecodingOptions, inputs: list[dict]) -> list[str]:
    """A warning per pcap input when --date was given: its capture time dates it."""
    if options.date is None:
        return []
    return [f"{info['path']}: --date ignored, the capture time dates a {info['format']} file"
            for info in inputs if info["format"] in ("pcap", "pcapng")]


def _load_measurements(options: AircraftOptions, checked: Checked, progress: Progress | None,
                       stage: str, *, either: bool = False, columns=None, needs=None
                       ) -> tuple[Loaded, pd.DataFrame, list[str]]:
    """Decode the inputs chunk by chunk straight into radar and ADS-B measurements (load_measurements),
    with the user-facing errors for unreadable inputs, missing data and sensors (stray radar records are
    left out with a warning: model.sensors.stray_verdict). ``stage`` is the progress stage shown once the
    inputs are read (before a missing-data or missing-sensor error too). ``either`` (quality): one category
    is enough, the other's absence is a warning saying which sheets stay empty. ``needs``: the categories
    the job needs (load_measurements; CAT048 and CAT021 when None). Returns the warnings too."""
    from msdc.asterix.errors import UnreadableInput
    from msdc.pipeline.dataset.inputs import UnreadablePart
    from msdc.pipeline.model.load import RADAR_AND_ADSB
    from msdc.pipeline.model.report_selection import WindowError

    if columns is not None and checked.selection is not None and checked.selection.active:
        from msdc.pipeline.model.report_selection import SELECTION_INPUTS
        from msdc.pipeline.model.schema import column_names

        columns = column_names(set(columns) | set(SELECTION_INPUTS))
    reading_window(checked)
    try:
        loaded, meas = load_measurements(checked.inputs, checked.sensors, editions=checked.editions or None,
                                         date=options.date, format=options.format,
                                         adsb_sigma_m=options.adsb_sigma_m, progress=progress, either=either,
                                         columns=columns, needs=needs or RADAR_AND_ADSB,
                                         dataset=checked.dataset, selection=checked.selection)
    except (UnreadableInput, UnreadablePart) as exc:
        raise JobError(str(exc), 2) from exc
    except WindowError as exc:
        raise OptionError(str(exc)) from None
    except NoRecords as exc:
        if progress:
            progress.stage(stage)
        error = _no_records(exc, lambda cats: in_the_inputs(options, checked, cats))
        error.job_warnings = inputs_said(options, checked, exc.loaded)  # said before the error
        raise error from exc
    if progress:
        progress.stage(stage)
    meas, warnings = selected_reports(meas, checked, loaded)
    if len(loaded.stray_radar):
        from msdc.pipeline.model.sensors import UnknownRadar, stray_verdict

        n_cat048 = sum(info["records"].get(48, 0) for info in loaded.inputs)
        try:
            warnings += stray_verdict(loaded.stray_radar, n_cat048, sensors_path(options))
        except UnknownRadar as exc:
            raise unknown_radar_error(exc.missing, sensors_path(options),
                                      leave_out="by giving the ADS-B recordings alone") from exc
    if len(loaded.unplaced):
        warnings += unplaced_warnings(loaded, options)
    warnings += inputs_said(options, checked, loaded)
    warnings += _wrong_editions(loaded, but=absent_categories(loaded))
    warnings += [f"no {REGISTRY[cat].noun} (CAT{cat:03d}) records {in_the_inputs(options, checked, (cat,))}"
                 f"{_all_failed(loaded, cat)}: "
                 f"{QUALITY_WITHOUT[cat]}" for cat in absent_categories(loaded)
                 if needs is None or any(cat in group for group in needs)]
    warnings += order_warnings(read_paths(checked, loaded), loaded.spans)
    warnings += date_ignored(options, loaded.inputs)
    warnings += list(meas.attrs.get("coverage_warnings", ()))
    warnings += list(meas.attrs.get("identity_warnings", ()))
    return loaded, meas, warnings


def inputs_said(options: DecodingOptions, checked: Checked, loaded: Loaded) -> list[str]:
    """What the inputs turned out to be, each named, said before what they lack: those of which no record
    decoded, a recorder file read as raw (its --format), and what reading found (not ASTERIX at all...)."""
    return [*_empty_inputs(loaded, checked.dataset),
            *format_hints(options, loaded.inputs, read_paths(checked, loaded)), *loaded.warnings]


def selected_reports(meas: pd.DataFrame, checked: Checked, loaded: Loaded) -> tuple[pd.DataFrame, list[str]]:
    """The measurements the report selection keeps (pipeline.model.report_selection), before anything is
    computed from them, with what it kept and left out recorded in ``loaded.selection`` (run_parameters
    records it), and a warning per kind of sensor the inputs hold of which it keeps no report; OptionError
    when a time cannot be placed on the recording's day, JobError when no report is left."""
    from msdc.pipeline.model.report_selection import describe, recorded, select_reports

    selection = checked.selection
    if selection is None or not selection.active:
        return meas, []
    try:
        keep, left_out = select_reports(meas, selection, loaded.date)
    except ValueError as exc:
        raise OptionError(str(exc)) from None
    read = len(meas)
    if loaded.cut is not None:  # the reports cut beyond the window's margin were read and left out too
        read += loaded.cut.reports
        left_out = {k: v + loaded.cut.left_out.get(k, 0) for k, v in left_out.items()}
    loaded.selection = recorded(selection, loaded.date, read, int(keep.sum()), left_out)
    if not keep.any():
        raise JobError(f"{describe(loaded.selection)}: no report is left to analyse")
    attrs = dict(meas.attrs)
    read_kinds = _kind_counts(meas)
    meas = meas[keep].reset_index(drop=True)
    meas.attrs = attrs
    kept_kinds = _kind_counts(meas)
    gone = sorted(k for k in read_kinds if k not in kept_kinds)
    nouns = {"radar": "radar (CAT048)", "adsb": "ADS-B (CAT021)", "mlat": "multilateration (CAT010/CAT020)",
             "smr": "surface radar (CAT010)"}
    return meas, [f"the report selection keeps no {nouns.get(k, k)} report of the {read_kinds[k]} "
                  "in the inputs: what needs them is empty" for k in gone]


def _kind_counts(meas: pd.DataFrame) -> dict[str, int]:
    """Reports per sensor kind present, counted by the column's codes (no text made per row)."""
    if "sensor_kind" not in meas:
        return {}
    counts = meas["sensor_kind"].value_counts(dropna=False)
    return {str(k): int(n) for k, n in counts.items() if n}


def unplaced_warnings(loaded: Loaded, options: AircraftOptions) -> list[str]:
    """The warnings for CAT010/CAT020 reports left unplaced for want of a reference point (too few of a
    sensor: damage); a JobError with the sensor-file lines when a sensor has enough of them to be one."""
    from msdc.pipeline.model.measurements import unplaced_verdict
    from msdc.pipeline.model.sensors import UnknownReferencePoint

    counts = {cat: sum(info["records"].get(cat, 0) for info in loaded.inputs) for cat in (10, 20)}
    try:
        return unplaced_verdict(loaded.unplaced, counts)
    except UnknownReferencePoint as exc:
        raise unknown_reference_error(exc.missing, sensors_path(options)) from exc


def unknown_reference_error(missing: list[tuple[int, str, int, int]], path: str | None) -> JobError:
    """The error for multilateration or surface radar reports whose reference point the sensor file lacks,
    with the TOML lines."""
    from msdc.pipeline.model.sensors import KIND_NOUN, reference_toml_snippet

    lines = "\n\n".join(reference_toml_snippet(*m) for m in missing)
    names = ", ".join(f"CAT{c:03d} {KIND_NOUN[k]} SAC/SIC {a}/{b}" for c, k, a, b in missing)
    where = ("no --sensors file was given: give --sensors S.toml with these lines" if path is None
             else f"not in {path}; add it")
    return JobError(f"{names}: Cartesian positions need the system's reference point, and {where}:"
                    f"\n\n{lines}")


def _no_records(exc: NoRecords, where=lambda categories: "in the inputs") -> JobError:
    """The user-facing error for inputs without radar or ADS-B records: every absent category, those whose
    blocks failed to decode first, with how many failed and the edition to pin (an ADS-B recording under a
    wrong edition is why there is no record at all, not a missing radar). ``where``: in_the_inputs."""
    if exc.category not in QUALITY_WITHOUT:  # a multilateration or surface radar category the job needs
        names = " or ".join(f"CAT{c:03d}" for c in exc.alternatives)
        nouns = "multilateration" if len(exc.alternatives) > 1 else REGISTRY[exc.category].noun
        return JobError(f"no {nouns} ({names}) records {where(exc.alternatives)}{unread_inputs(exc.loaded)}")
    absent = absent_categories(exc.loaded) or [exc.category]
    failed = {cat: why[2:] for cat in absent if (why := _all_failed(exc.loaded, cat))}
    absent.sort(key=lambda cat: cat not in failed)
    names = " or ".join(f"{REGISTRY[cat].noun} (CAT{cat:03d})" for cat in absent)
    why = f": {'; '.join(failed.values())}" if failed else ""
    return JobError(f"no {names} records {where(absent)}{why}{unread_inputs(exc.loaded)}")


def unread_inputs(loaded: Loaded) -> str:
    """The inputs holding categories the command does not read, a line each, said after an error for what
    the inputs lack (a CAT001 radar given where CAT048 is read), or ''."""
    pairs = zip(loaded.inputs, _unread_of(loaded), strict=True)
    said = [f"{info['path']}: {words}" for info, ignored in pairs if (words := _not_read(ignored))]
    return "".join(f"\n  {line}" for line in said)


def absent_categories(loaded: Loaded) -> list[int]:
    """Which of the measurement categories the jobs need (CAT048 radar and CAT021 ADS-B, those of
    QUALITY_WITHOUT) no input holds a record of."""
    held = {cat for info in loaded.inputs for cat, n in info["records"].items() if n}
    return [cat for cat in MEASUREMENT_CATEGORIES if cat in QUALITY_WITHOUT and cat not in held]


def sensors_path(options: AircraftOptions) -> str | None:
    """--sensors as text for messages and the JSON, None when it was not given (track, conflicts)."""
    return None if options.sensors is None else str(options.sensors)


def unknown_radar_error(missing: list[tuple[int, int]], sensors_path: str | None, *,
                        leave_out: str = "with --sources adsb") -> JobError:
    """The error for radars the sensor file lacks (or with no sensor file given, saying how to ``leave_out``
    the radars), with the TOML lines."""
    from msdc.pipeline.model.sensors import sensor_toml_snippet

    lines = "\n\n".join(sensor_toml_snippet(sac, sic) for sac, sic in missing)
    pairs = ", ".join(f"{a}/{b}" for a, b in missing)
    if sensors_path is None:
        return JobError(f"radar plots from SAC/SIC {pairs} need the radar's position, and no --sensors file "
                        f"was given: give --sensors S.toml with these lines, or leave the radars out "
                        f"{leave_out}:\n\n{lines}")
    return JobError(f"radar SAC/SIC {pairs} not in {sensors_path}; add its position:\n\n{lines}")


# What a quality run without one of the categories cannot fill (the others need only the sensor's own reports)
QUALITY_WITHOUT = {48: "the Radar accuracy and Radar biases sheets are empty",
                   21: "the ADS-B quality sheets are empty, and so are Radar accuracy and Radar biases "
                       "(ADS-B is their reference)"}


def _empty_inputs(loaded: Loaded, dataset: DatasetInputs | None = None) -> list[str]:
    """A warning for each input of which no record decoded (a file that is not a recording, or another
    category): the run goes on with the others, but it should not be silent. Of a dataset, an input whose
    records the partition pruning left out (its manifest lists rows) is not said."""
    held = set() if dataset is None else {rec["path"] for rec in dataset.records if any(rec["rows"].values())}
    said = []
    for info, ignored in zip(loaded.inputs, _unread_of(loaded), strict=True):
        if any(info["records"].values()) or info["path"] in held:
            continue
        if unread := _not_read(ignored):
            said.append(f"{info['path']}: {unread}")
        elif dataset is not None:  # what the dataset kept of it, not the recording, which it may not be
            kept = next((rec.get("options", {}).get("categories") for rec in dataset.records
                         if rec["path"] == info["path"]), None)
            asked = f" (its ingest kept {', '.join(f'CAT{int(c):03d}' for c in kept)})" if kept else ""
            said.append(f"{info['path']}: the dataset holds no CAT021 or CAT048 record of it{asked}")
        elif info["skipped_blocks"]:
            said.append(f"{info['path']}: no record decoded ({info['skipped_blocks']} block(s) skipped; "
                        "'msdc stats' lists them)")
        else:
            said.append(f"{info['path']}: no CAT021 or CAT048 record in it")
    return said


def _unread_of(loaded: Loaded) -> list[dict[int, int]]:
    """Loaded.unread, or no block for each input when the load did not say (a dataset's)."""
    return loaded.unread if len(loaded.unread) == len(loaded.inputs) else [{} for _ in loaded.inputs]


def _not_read(held: dict[int, int]) -> str:
    """What an input holds of categories the command does not read (``held``: blocks per category, as
    Loaded.unread), 'it holds CAT001 (4,000 blocks) and CAT002 (4,000 blocks), which ...', or '': a radar's
    CAT001 plots or a tracker's CAT062 tracks given where CAT048 and CAT021 are read should not look like an
    empty file."""
    if not held:
        return ""
    parts = [f"CAT{c:03d} ({n:,} block{'' if n == 1 else 's'})" for c, n in held.items()]
    listed = parts[0] if len(parts) == 1 else ", ".join(parts[:-1]) + " and " + parts[-1]
    decoded = [c for c in held if c in REGISTRY]
    how = (" ('msdc decode' and 'msdc stats' decode "
           f"{'them' if len(decoded) == len(held) else ', '.join(f'CAT{c:03d}' for c in decoded)})"
           if decoded else " (categories msdc does not decode)")
    return f"it holds {listed}, which this command does not read{how}"


def _wrong_editions(loaded: Loaded, but: list[int] | tuple[int, ...] = ()) -> list[str]:
    """A warning per input and category whose blocks mostly failed under a wrong edition, but for the
    categories in ``but`` (those whose own message says so: _all_failed)."""
    notes = edition_notes.notes_of(loaded.recordings)
    return edition_notes.warnings({key: note for key, note in notes.items() if key[1] not in but})


def _all_failed(loaded: Loaded, cat: int) -> str:
    """What to add when a category has no record: how many of its blocks failed, and under which edition
    (a wrong pin fails every block: nothing on the wire says which CAT021 edition a stream uses)."""
    errors = loaded.errors
    failed = int((errors["category"] == cat).sum()) if "category" in errors else 0
    if not failed:
        return ""
    edition = loaded.editions.get(cat)
    fits = edition_notes.fits_of(edition_notes.notes_of(loaded.recordings), cat)
    if not edition:
        hint = ""
    elif fits:  # the editions every failed block walks under
        hint = f" under edition {edition}{edition_notes.advice(cat, fits)}"
    elif cat == 21:
        hint = (f" under edition {edition}; if that edition is wrong, pin the right one or try "
                "--edition 21=auto")
    else:
        hint = f" under edition {edition}"
    return f": {failed} CAT{cat:03d} block(s) could not be decoded{hint} ('msdc stats' lists them)"


def marked_measurements(options: AircraftOptions, checked: Checked, progress: Progress | None, stage: str,
                        *, split_adsb: bool = False, either: bool = False, columns=None,
                        flags: list[str] | None = None, needs=None) -> tuple[Loaded, pd.DataFrame, list[str]]:
    """The inputs and their measurements with the duplicate and jump flags (once per job; correlate counts
    each window's jumps; ``attrs["mixed_pairs"]``: the aircraft and sensors whose reports switch between
    two places, pipeline.model.mixed), and the warnings about them; decoded columns are held one chunk at a
    time (see _load_measurements). ``stage`` is the progress stage shown once the inputs are read;
    ``columns`` and ``flags``: only those measurement columns and jump columns (every one when None);
    ``needs``: the categories the job needs (load_measurements)."""
    from msdc.pipeline.model.dedup import repeated_aircraft
    from msdc.pipeline.model.marks import mark_once
    from msdc.pipeline.model.mixed import mixed_identities, mixed_pairs, mixed_text

    loaded, meas, warnings = _load_measurements(options, checked, progress, stage, either=either,
                                                columns=columns, needs=needs)
    meas = mark_once(meas, split_adsb=split_adsb, flags=flags)
    release_free_memory()
    dup = meas["duplicate"].to_numpy(bool)
    found = mixed_identities(meas[~dup])
    meas.attrs["mixed_pairs"] = mixed_pairs(found)  # correlate's window verdicts say them too
    return loaded, meas, warnings + repeated_aircraft(meas, dup) + mixed_text(found)


def tracker_inputs(options: TrackOptions, checked: Checked, progress: Progress | None, times: str
                   ) -> tuple[Loaded, pd.DataFrame, list[str]]:
    """What track and conflicts track: the inputs decoded (their decoded frames then freed), the
    measurements of tracker_measurements, and the warnings about them with the site and undated warnings
    (``times``: what an undated run places on 1970-01-01)."""
    from msdc.pipeline.model.site_check import site_warnings

    with carrying() as warnings:
        if progress:
            progress.stage("Processing data files")
        loaded, said = load_inputs(options, checked, progress)
        warnings += said
        if progress:
            progress.stage("Tracking")
        meas, said = tracker_measurements(loaded, checked, options)
    warnings += said
    warnings += site_warnings(meas, checked.sensors, str(sensors_path(options)))
    warnings += undated_warning(loaded, times)
    loaded.drop_frames()  # the measurements hold what tracking needs: a day's decoded frames are ~0.5 GB
    return loaded, meas, warnings


def tracker_measurements(loaded, checked: Checked, options: TrackOptions) -> tuple[pd.DataFrame, list[str]]:
    """Measurements of the requested sources (one of them must be present), repeated reports dropped, and
    the warnings about them (stray radar records, coverage, identity)."""
    meas, warnings = source_measurements(loaded, checked, options)
    out = tracked_reports(meas, options.max_coast_s)
    return out, (warnings + out.attrs.get("repeated", []) + out.attrs.get("mixed", [])
                 + short_coast(out, options.max_coast_s))


def tracked_reports(meas: pd.DataFrame, max_coast_s: float) -> pd.DataFrame:
    """What the tracker takes of the measurements: reports joined by track number, repeats and reports no
    identity places on an aircraft left out (counted in attrs, with the warnings about aircraft left out
    whole, "repeated", and about two targets under one identity, "mixed", whose aircraft and sensors are
    "mixed_pairs")."""
    from msdc.pipeline.model.dedup import duplicate_mask, repeated_aircraft
    from msdc.pipeline.model.mixed import mixed_identities, mixed_pairs, mixed_text
    from msdc.pipeline.track.associate import join_by_track_number

    meas, joined = join_by_track_number(meas, max_gap_s=float(max_coast_s))
    dup = duplicate_mask(meas.sort_values("time", kind="stable")).reindex(meas.index).to_numpy(bool)
    known = meas["aircraft_id"].notna().to_numpy(bool)
    repeated = repeated_aircraft(meas, dup)
    out = meas[~dup & known].reset_index(drop=True)
    out.attrs["joined_by_track_number"] = joined
    out.attrs["unidentified"] = int((~dup & ~known).sum())
    out.attrs["repeated"] = repeated
    found = mixed_identities(out)
    out.attrs["mixed"] = mixed_text(found)
    out.attrs["mixed_pairs"] = mixed_pairs(found)
    return out


def _has_flag(options, flag: str) -> bool:
    """Whether the options' command line has ``flag`` (evaluate reads every source, with no --sources)."""
    import dataclasses

    return any(flag in getattr(f.metadata.get("option"), "flags", ()) for f in dataclasses.fields(options))


def source_measurements(loaded, checked: Checked, options) -> tuple[pd.DataFrame, list[str]]:
    """Every measurement of the requested sources (``options.sources``; one must be present) after the
    report selection, repeats and unidentified reports kept, and the warnings about them (stray radar
    records, coverage, identity)."""
    import warnings as python_warnings

    from msdc.pipeline.model.measurements import (
        IdentityWarning,
        LeftOutWarning,
        OffEarthWarning,
        OutOfCoverageWarning,
        build_measurements,
    )
    from msdc.pipeline.model.sensors import UnknownRadar, UnknownReferencePoint, declared_radar

    sources = parse_sources(options.sources)
    radar = loaded.frames.get(48) if "radar" in sources else None
    adsb = loaded.frames.get(21) if "adsb" in sources else None
    radar = radar if radar is not None and len(radar) else None
    adsb = adsb if adsb is not None and len(adsb) else None
    local = {"mlat", "smr"} & set(sources)
    cat010 = loaded.frames.get(10) if local else None
    cat020 = loaded.frames.get(20) if "mlat" in local else None
    cat010, cat020 = (f if f is not None and len(f) else None for f in (cat010, cat020))
    if radar is None and adsb is None and cat010 is None and cat020 is None:
        names = {"radar": "radar (CAT048)", "adsb": "ADS-B (CAT021)", "mlat": "multilateration (CAT010 or "
                 "CAT020)", "smr": "surface radar (CAT010)"}
        cats = {"radar": (48,), "adsb": (21,), "mlat": (10, 20), "smr": (10,)}
        wanted = " or ".join(names[s] for s in sources)
        failed = "; ".join(why[2:] for cat in dict.fromkeys(c for s in sources for c in cats[s])
                           if (why := _all_failed(loaded, cat)))
        where = in_the_inputs(options, checked, [c for s in sources for c in cats[s]])
        given = f" (--sources {','.join(sources)})" if _has_flag(options, "--sources") else ""
        raise JobError(f"no {wanted} records {where}{given}" + (f": {failed}" if failed else ""))
    try:
        radar, stray = declared_radar(radar, checked.sensors, sensors_path(options))
    except UnknownRadar as exc:
        raise unknown_radar_error(exc.missing, sensors_path(options)) from exc
    selection = checked.selection
    if selection is not None and selection.timed:
        from msdc.pipeline.model.report_selection import MarginCut, WindowError

        try:
            loaded.cut = MarginCut(selection, loaded.date)
        except WindowError as exc:
            raise OptionError(str(exc)) from None
    with carrying(stray) as warnings:
        try:
            with python_warnings.catch_warnings(record=True) as said:  # load_inputs has said it, per file
                python_warnings.simplefilter("ignore", OffEarthWarning)
                python_warnings.simplefilter("ignore", OutOfCoverageWarning)  # said below, from attrs
                python_warnings.simplefilter("ignore", IdentityWarning)  # said below, from attrs
                python_warnings.simplefilter("always", LeftOutWarning)
                meas = build_measurements(radar, adsb, checked.sensors, date=loaded.date,
                                          adsb_sigma_m=options.adsb_sigma_m, cat010=cat010, cat020=cat020,
                                          cut=loaded.cut)
            warnings += [str(w.message) for w in said if issubclass(w.category, LeftOutWarning)]
        except UnknownRadar as exc:
            raise unknown_radar_error(exc.missing, sensors_path(options)) from exc
        except UnknownReferencePoint as exc:
            raise unknown_reference_error(exc.missing, sensors_path(options)) from exc
    meas, said = selected_reports(meas, checked, loaded)
    warnings += said
    warnings += list(meas.attrs.get("coverage_warnings", ()))
    warnings += list(meas.attrs.get("identity_warnings", ()))
    if local and local != {"mlat", "smr"} and len(meas):  # CAT010 holds both kinds: the one not asked goes
        from msdc.pipeline.model.schema import equals_text

        (unasked,) = {"mlat", "smr"} - local
        meas = meas[~equals_text(meas["sensor_kind"], unasked)].reset_index(drop=True)
    return meas, warnings


def short_coast(meas: pd.DataFrame, max_coast_s: float) -> list[str]:
    """A warning when --max-coast is below every sensor's median update interval (track.feasibility): a
    track segment then ends at each gap between reports, and an aircraft falls apart into segments of one
    report (--max-coast 0.001 made 3,281 of one aircraft)."""
    return below_updates(meas, "--max-coast", max_coast_s, "a track segment ends at each gap between "
                         "reports, so nearly every report starts a segment of its own", 60.0)


def below_updates(meas: pd.DataFrame, flag: str, value_s: float, consequence: str, default_s: float
                  ) -> list[str]:
    """A warning when an option's seconds are below every sensor's median update interval
    (track.feasibility), saying the ``consequence`` and what to give."""
    from msdc.pipeline.track.feasibility import update_intervals

    intervals = update_intervals(meas)
    if intervals.empty or value_s >= intervals.iloc[0]:
        return []
    fastest, slowest = intervals.index[0], intervals.index[-1]
    return [f"{flag} {value_s:g} s is below every sensor's median update interval (the shortest: "
            f"{fastest}, {intervals.iloc[0]:.3g} s): {consequence}; give more than the slowest sensor's "
            f"interval ({slowest}, {intervals.iloc[-1]:.3g} s; default {default_s:g} s)"]


# ---------------------------------------------------------------------------------------------------------
# Steps two commands run


def run_parameters(options: AircraftOptions, loaded: Loaded, started: float, command: str) -> dict:
    """The parameters every measurement job's outputs record: software, command, run time, editions, sensor
    file, date and declared ADS-B sigma."""
    return {"software": f"msdc {software_version()}", "command": command,
            "run_utc": utc_text(dt.datetime.now(dt.UTC)),
            "run_time_s": round(time.monotonic() - started, 3), "editions": {
                f"CAT{c:03d}": e for c, e in sorted(loaded.editions.items())},
            "sensors": sensors_path(options), "date": loaded.date.isoformat() if loaded.date else None,
            "adsb_sigma_m": options.adsb_sigma_m,
            **({"report_selection": loaded.selection} if loaded.selection else {})}


def quality_inputs(reference: str) -> list[str]:
    """The measurement columns the quality step reads: the quality tables, the radar errors against the
    ``reference`` ("adsb" or "track": the tracker's and track_reference's inputs as well), the aircraft
    selection and mark_once."""
    from msdc.pipeline.model.dedup import DEDUP_KEYS
    from msdc.pipeline.model.jumps import JUMP_INPUTS
    from msdc.pipeline.quality.accuracy import ACCURACY_INPUTS
    from msdc.pipeline.quality.reference_offset import OFFSET_INPUTS
    from msdc.pipeline.quality.tables import QUALITY_INPUTS

    need = [*QUALITY_INPUTS, *ACCURACY_INPUTS, *DEDUP_KEYS, *JUMP_INPUTS, *OFFSET_INPUTS, "sensor_kind",
            "sensor_id", "aircraft_id", "callsign", "address"]
    if reference == "track":
        from msdc.pipeline.quality.track_reference import TRACK_REFERENCE_INPUTS
        from msdc.pipeline.track.tracker import FILTER_INPUTS, REQUIRED

        need += [*REQUIRED, *FILTER_INPUTS, *TRACK_REFERENCE_INPUTS]  # the tracker's optional ones too
    return need


def quality_step(meas: pd.DataFrame, sensors: pd.DataFrame, options: CorrelateOptions | QualityOptions,
                 reference_meas: pd.DataFrame | None = None) -> QualityResult:
    """The quality tables and radar accuracy of the selected aircraft (quality_run), the reference built from
    ``reference_meas`` (the ADS-B filters applied) when given, two targets under one identity as
    marked_measurements found them; JobError when no sensor saw the aircraft."""
    from msdc.pipeline.model.aircraft import NoSuchAircraft
    from msdc.pipeline.quality.quality_run import quality_run

    try:
        return quality_run(meas, sensors, callsign=options.callsign, address=options.address,
                           gap_s=options.gap_s, reference=getattr(options, "reference", "adsb"),
                           reference_meas=reference_meas, mixed=meas.attrs.get("mixed_pairs"))
    except NoSuchAircraft as exc:
        raise JobError(str(exc) + selection_note(options)) from exc


def selection_flags(options: DecodingOptions) -> list[str]:
    """The report selection's options given (--from, --to, --area, --fl, --sensor)."""
    return [flag for flag, value in (("--from", options.from_time), ("--to", options.to_time),
                                     ("--area", options.area), ("--fl", options.fl),
                                     ("--sensor", options.sensor_ids)) if value]


def selection_note(options: DecodingOptions) -> str:
    """What to add to "not seen" when a report selection was given: it may be why."""
    given = selection_flags(options)
    return (f" (among the reports the selection keeps: {', '.join(given)})" if given else "")


def in_the_inputs(options: DecodingOptions, checked: Checked, categories) -> str:
    """Where no record of ``categories`` was found: "in the inputs" (on a dataset, "in the dataset"), or, on
    a dataset that holds some but not in the partitions the report selection keeps, those partitions (the
    selection is why)."""
    source = checked.dataset
    held = 0 if source is None else sum(int(n) for rec in source.records
                                        for c, n in rec.get("rows", {}).items() if int(c) in set(categories))
    if not held:
        return "in the inputs" if source is None else "in the dataset"
    given = ", ".join(selection_flags(options))
    return f"in the dataset's partitions the report selection keeps ({given}; it holds {held:,})"


def filters_asked(options: ReferenceFilterOptions) -> bool:
    """Whether any ADS-B filter (--drop-jumps, --min-nic, --min-nacp) was asked for."""
    return bool(options.drop_jumps) or options.min_nic is not None or options.min_nacp is not None


def filters_removed(options: ReferenceFilterOptions, removed: dict[str, int]) -> dict[str, int]:
    """The counts of pipeline.quality.filters.apply_filters of the filters asked for (none asked: {})."""
    asked = {"jumps": options.drop_jumps, "nic_below_min": options.min_nic is not None,
             "nic_missing_kept": options.min_nic is not None, "nacp_below_min": options.min_nacp is not None,
             "nacp_missing_kept": options.min_nacp is not None}
    return {k: v for k, v in removed.items() if asked.get(k, True)}


def filter_parameters(options: ReferenceFilterOptions, removed: dict[str, int]) -> dict:
    """What a run's outputs record of the ADS-B filters: those asked for and what each removed."""
    return {"drop_jumps": options.drop_jumps, "min_nic": options.min_nic, "min_nacp": options.min_nacp,
            "removed": filters_removed(options, removed)}


QUALITY_FIGURE_GLOBS = ("_intervals.png", "_radar_errors_*_*.png")  # quality_figures' names, as globs


def side_files_beside(output: Path | None, globs: Iterable[str]) -> list[Path]:
    """The globs of the side files named after ``output`` (``globs``: what follows its stem, e.g.
    ``_lags_*.png``), beside the file it really is; none without an output. The command lists the files
    they match that a run did not write (report.transaction.left_beside)."""
    if output is None:
        return []
    base = real_output(output)
    return [side_pattern(base, g) for g in globs]


def quality_figures(result: QualityResult, out_dir: Path, stem: str, tx: OutputTransaction | None = None
                    ) -> dict[str, Path]:
    """Update-interval histogram and, per radar, range/azimuth error against range and time (PNG), drawn in
    ``out_dir`` (a staging folder of ``tx``: the result records their final paths)."""
    from msdc.pipeline.report.quality_figures import interval_histogram_figure, radar_error_figure

    out_dir.mkdir(parents=True, exist_ok=True)
    figs = {"Update intervals": interval_histogram_figure(result.sheets["Update intervals"],
                                                          out_dir / f"{stem}_intervals.png")}
    biases = result.sheets.get("Radar biases")
    if len(result.errors):
        for (sac, sic), g in result.errors.groupby(["sac", "sic"], sort=True):
            row = biases[(biases["sac"] == sac) & (biases["sic"] == sic)] if biases is not None else None
            figs[f"Radar errors {sac}/{sic}"] = radar_error_figure(
                g, out_dir / f"{stem}_radar_errors_{sac}_{sic}.png", row)
    result.figures.update({k: tx.final(p) if tx else p for k, p in figs.items()})
    return figs


def check_output_rows(meas: pd.DataFrame, options: TrackOptions, per_row: int = 1, what: str = "", *,
                      grid_only: bool = False) -> None:
    """pipeline.track.feasibility.check_track_rows, its TooManyRows an OptionError naming --step."""
    from msdc.pipeline.track import feasibility

    try:
        feasibility.check_track_rows(meas, options.step_s, options.max_coast_s, per_row, what,
                                     grid_only=grid_only)
    except feasibility.TooManyRows as exc:
        raise OptionError(f"--step {options.step_s:g}: {exc}; use a longer --step or fewer aircraft") from exc


def estimated_noise(meas: pd.DataFrame, sensors: pd.DataFrame, options: TrackOptions):
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


def noise_text(noise) -> str:
    """The declared and estimated sigmas of --noise estimate, or nothing."""
    if noise is None or not len(noise):
        return ""
    cols = [c for c in ("sensor_id", "component", "motion", "unit", "declared_from", "declared_sigma",
                        "estimated_sigma", "residuals", "estimated") if c in noise]
    if "at_resolution" in noise and noise["at_resolution"].any():  # the column only where it says something
        cols.append("at_resolution")
    text = (f"\n\nMeasurement noise estimated from the residuals ({noise.attrs.get('passes')} passes):\n"
            + noise[cols].to_string(index=False, float_format=lambda v: f"{v:.4g}"))
    if "at_resolution" in cols:
        text += ("\nat_resolution: the estimate stopped at the rounding of the item the positions are "
                 "written in\n(its step / sqrt(12)); the residuals say only that the noise is no larger")
    raised = pd.DataFrame(noise.attrs.get("aircraft", []))
    if len(raised):
        shown = raised.sort_values("estimated_sigma_m", ascending=False).head(RAISED_SHOWN)
        more = len(raised) - len(shown)
        text += (f"\n\nSigma raised for {len(raised)} aircraft: at its class's sigma over 1 % of the "
                 "aircraft's own residuals lay beyond the gate:\n"
                 + shown.to_string(index=False, float_format=lambda v: f"{v:.4g}")
                 + (f"\n... and {more} more in the JSON summary" if more else ""))
    return text


# ---------------------------------------------------------------------------------------------------------
# Which per-item figures a run draws (--figures-limit, --figures-only; track and conflicts) and the list of
# those it does not draw, each with the command that draws it (figures_not_drawn.txt beside them)

NOT_DRAWN = "figures_not_drawn.txt"


@dataclass(frozen=True)
class FigureChoice:
    """The figures a run has (file names, in order) and which of them it draws (indices)."""

    names: list[str]
    drawn: list[int]

    @property
    def not_drawn(self) -> list[str]:
        """The names left out, in order."""
        chosen = set(self.drawn)
        return [n for i, n in enumerate(self.names) if i not in chosen]


def only_names(text: str | None) -> list[str]:
    """--figures-only's names, each ending in .png; OptionError when it names none."""
    if text is None:
        return []
    names = [n.strip() for n in str(text).split(",") if n.strip()]
    if not names:
        raise OptionError(f"--figures-only {text!r}: give figure file names, comma-separated")
    return [n if n.lower().endswith(".png") else f"{n}.png" for n in names]


def choose(names: list[str], limit: int, only: str | None) -> FigureChoice:
    """The figures to draw: those --figures-only names (OptionError naming one this run does not have, with
    the closest it has), else the first ``limit`` (0: all)."""
    wanted = only_names(only)
    if wanted:
        where = {n: i for i, n in enumerate(names)}
        for name in wanted:
            if name not in where:
                close = difflib.get_close_matches(name, names, n=3, cutoff=0.5)
                hint = f"closest: {', '.join(close)}" if close else f"this run has {len(names)} figure(s)"
                raise OptionError(f"--figures-only {name}: no such figure in this run; {hint}")
        return FigureChoice(names, sorted({where[n] for n in wanted}))
    count = len(names) if limit == 0 else min(int(limit), len(names))
    return FigureChoice(names, list(range(count)))


def draw_command(command: str, options: object, name: str) -> str:
    """The shell command that draws figure ``name`` of this run: the same options (so the same tracks and
    alerts), with --figures-only naming it; track's without -o and --json (not needed with --figures)."""
    changed = {"output": None, "json": None} if command == "track" else {}
    args = command_args(options, figures_only=name.removesuffix(".png"), **changed)
    return shlex.join(["msdc", command, *_without(args, "--figures-limit")])


def _without(args: list[str], flag: str) -> list[str]:
    """args with ``flag`` and its value left out."""
    out, skip = [], False
    for a in args:
        if skip:
            skip = False
        elif a == flag:
            skip = True
        else:
            out.append(a)
    return out


def not_drawn_text(command: str, options: object, choice: FigureChoice) -> str:
    """figures_not_drawn.txt: why, how to draw them all, then one line per figure left out with the
    command that draws it."""
    left = choice.not_drawn
    every = shlex.join(["msdc", command, *command_args(options, figures_limit=0)])
    lines = [f"# {len(left)} of {len(choice.names)} figures not drawn (--figures-limit "
             f"{getattr(options, 'figures_limit', '')}); all of them: {every}",
             "# each line: the figure, then the command that draws it alone (the same run, --figures-only)"]
    lines += [f"{name}\t{draw_command(command, options, name)}" for name in left]
    return "\n".join(lines) + "\n"


def write_not_drawn(folder: Path, command: str, options: object, choice: FigureChoice) -> Path | None:
    """Write figures_not_drawn.txt in ``folder`` (the staged figures folder) when --figures-limit left
    figures out (not after --figures-only: its run draws what was asked for); its path, else None."""
    if not choice.not_drawn or getattr(options, "figures_only", None) is not None:
        return None
    path = Path(folder) / NOT_DRAWN
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(not_drawn_text(command, options, choice), encoding="utf-8")
    return path


def check_figure_options(options: object) -> None:
    """--figures-limit and --figures-only need --figures; --figures-only names something. OptionError."""
    if getattr(options, "figures", None) is None:
        for flag, value, default in (("--figures-limit", options.figures_limit, type(options).figures_limit),
                                     ("--figures-only", options.figures_only, None)):
            if value != default:
                raise OptionError(f"{flag} {value}: only with --figures DIR")
    only_names(options.figures_only)
