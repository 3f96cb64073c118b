"""The jobs: decode, stats, correlate and quality as library calls that the CLI, notebooks and any other
front end share.

Each job takes validated options (``*Options.validate()`` checks every option, the sensor file and the
output paths before anything is decoded, each failure an ``OptionError`` naming the option or file and
what is allowed) and returns a result object; writing reports is a separate call. Duplicate flags and
ADS-B jump flags are computed once per job (``mark_once``) and reused by every step after.
"""

from __future__ import annotations

import datetime as dt
import hashlib
import math
import os
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import pandas as pd

from msdc.pipeline.meta import FORMATS, software_version
from msdc.pipeline.model import editions as edition_notes
from msdc.pipeline.model.identity import normalise_address, normalise_callsign
from msdc.pipeline.model.load import (
    Loaded,
    NoRecords,
    load,
    load_measurements,
    release_free_memory,
    time_spans,
    widen_spans,
)
from msdc.pipeline.progress import Progress
from msdc.pipeline.report.outputs import Background, BackgroundFailed, Prepared, all_or_nothing
from msdc.pipeline.report.textguard import guard_frame

if TYPE_CHECKING:  # the steps are imported by the jobs that run them: msdc stats imports none of them
    from msdc.pipeline.correlate.results import CorrelationRun
    from msdc.pipeline.quality.quality_run import QualityResult

SLOT_RANGE_S = (0.1, 3600.0)  # below 0.1 s the slot count and the lag tables explode
FIGURE_WINDOWS = 6  # correlate --quality: slotting and lag figures of the first windows only
GAP_RANGE_S = (0.1, 86400.0)
# --adsb-sigma: 1-sigma error per axis declared for ADS-B reports without NACp (CAT021 0.2x)
ADSB_SIGMA_RANGE_M = (0.5, 20000.0)
INDICATOR_RANGE = (0, 11)  # NIC and NACp values
CHUNK_RANGE_MB = (0.1, 4096.0)


class OptionError(ValueError):
    """An option, the sensor file or an output path is not usable: one line naming it and what is allowed.
    ``status`` is the exit status a command line should use (2: usage)."""

    def __init__(self, message: str, status: int = 2):
        super().__init__(message)
        self.status = status


class JobError(RuntimeError):
    """The data do not allow the job (no radar, no such aircraft, no overlap...); exit status 1."""

    def __init__(self, message: str, status: int = 1):
        super().__init__(message)
        self.status = status


# ---------------------------------------------------------------------------------------------------------
# Validation helpers, one per kind of value


def _number(name: str, value: float | None, lo: float, hi: float, unit: str = "") -> None:
    """A finite number within [lo, hi], else OptionError naming the option."""
    if value is None:
        return
    if not isinstance(value, int | float) or not math.isfinite(value) or not lo <= value <= hi:
        raise OptionError(f"{name} {value!r}: must be a finite number from {lo:g} to {hi:g}{unit}")


def _integer(name: str, value: int | None, lo: int, hi: int) -> None:
    if value is not None and not (isinstance(value, int) and lo <= value <= hi):
        raise OptionError(f"{name} {value!r}: must be an integer from {lo} to {hi}")


def _editions(editions: list[str] | dict | None) -> dict[int, str]:
    """CAT=EDITION pins checked against the shipped tables ("auto" for CAT021)."""
    from msdc.asterix.tables import available, resolve_edition

    items = editions.items() if isinstance(editions, dict) else (
        str(e).partition("=")[::2] for e in (editions or []))
    out = {}
    for cat, ed in items:
        if not str(cat).strip().isdigit() or int(cat) not in available():
            raise OptionError(f"--edition {cat}={ed}: category must be one of "
                              f"{', '.join(str(c) for c in sorted(available()))}")
        cat = int(cat)
        if not (cat == 21 and ed == "auto"):
            try:
                resolve_edition(cat, ed)
            except ValueError as exc:
                raise OptionError(f"--edition {cat}={ed}: {exc}") from None
        if out.get(cat, ed) != ed:
            raise OptionError(f"--edition {cat}={ed}: CAT{cat:03d} is already pinned to {out[cat]}; give one "
                              "edition per category")
        out[cat] = ed
    return out


def _sha256(path: Path, chunk: int = 1 << 20) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        while block := fh.read(chunk):
            h.update(block)
    return h.hexdigest()


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


def _inputs(paths: list[str | Path], warnings: list[str]) -> list[Path]:
    """Readable input files; the same content given twice is skipped with a warning."""
    if not paths:
        raise OptionError("no input file given")
    for p in paths:
        nonempty_path("input", p)
    out, seen = [], {}
    for p in map(Path, paths):
        problem = _not_a_file(p, "input", "a recording file")
        if problem:
            raise OptionError(f"{p}: {problem}")
        if not os.access(p, os.R_OK):
            raise OptionError(f"{p}: input file is not readable")
        digest = _sha256(p)
        if digest in seen:
            warnings.append(f"{p}: same content as {seen[digest]} (SHA-256); skipped")
            continue
        seen[digest] = p
        out.append(p)
    return out


def _output(name: str, path: str | Path | None, suffixes: tuple[str, ...]) -> Path | None:
    """An output path with an allowed suffix, not a directory, in a writable directory."""
    if path is None:
        return None
    nonempty_path(name, path)
    p = Path(path)
    if p.suffix.lower() not in suffixes:
        raise OptionError(f"{name} {p}: must end in {' or '.join(suffixes)}")
    if p.is_dir():
        raise OptionError(f"{name} {p}: is a directory")
    parent = p.parent if str(p.parent) else Path(".")
    if parent.exists() and not parent.is_dir():
        raise OptionError(f"{name} {p}: {parent} is a file, not a directory")
    if not parent.is_dir():
        raise OptionError(f"{name} {p}: directory {parent} does not exist")
    writable = os.access(parent, os.W_OK) and (not p.exists() or os.access(p, os.W_OK))
    if not writable or not _can_create(parent):
        raise OptionError(f"{name} {p}: not writable (directory {parent})")
    return p


def spare_inputs(inputs, outputs: list[tuple[str, Path | None]]) -> None:
    """OptionError when an output (a ``(what, path)`` pair: the option and the file it writes) is one of the
    inputs, by any path or link: writing it would destroy the recording before or while it is read."""
    inputs = [inputs] if isinstance(inputs, str | Path) else inputs  # one path is one input
    given = [Path(p) for p in inputs if Path(p).is_file()]
    for what, out in outputs:
        if out is None or not Path(out).is_file():
            continue
        for p in given:
            if os.path.samefile(out, p):
                also = "" if what.endswith(str(out)) else f" (it writes {out})"
                raise OptionError(f"{what}{also}: is the input {p}; writing it would destroy the recording")


def _can_create(directory: Path) -> bool:
    """Whether a file can really be created here (permission bits do not stop root; read-only mounts,
    ACLs and pseudo file systems do): a temporary file is created and removed at once."""
    import tempfile

    try:
        with tempfile.NamedTemporaryFile(dir=directory, prefix=".msdc-probe-"):
            return True
    except OSError:
        return False


def _sensors(path: str | Path | None, *, required: bool = True) -> pd.DataFrame:
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
        raise OptionError(str(exc).replace("\n", " "), status=1) from None


# ---------------------------------------------------------------------------------------------------------
# Options


@dataclass(frozen=True)
class DecodingOptions:
    """How to read the inputs (shared by every job)."""

    inputs: tuple[str, ...] = ()
    editions: tuple[str, ...] = ()  # "CAT=EDITION"
    date: dt.date | None = None
    format: str | None = None


def _check_decoding(o: DecodingOptions, warnings: list[str]) -> tuple[list[Path], dict[int, str]]:
    if o.format is not None and o.format not in FORMATS:
        raise OptionError(f"--format {o.format!r}: must be one of {', '.join(FORMATS)}")
    if o.date is not None:
        from msdc.asterix.reader import parse_date  # the rule asterix.read and load apply to date=

        try:
            parse_date(o.date, "--date")
        except (TypeError, ValueError) as exc:
            raise OptionError(str(exc)) from None
    inputs = [o.inputs] if isinstance(o.inputs, str | Path) else list(o.inputs)  # one path is one input
    editions = o.editions if isinstance(o.editions, dict) else [o.editions] if isinstance(
        o.editions, str) else list(o.editions)  # {21: "0.26"} as asterix.read takes it, or "21=0.26"
    return _inputs(inputs, warnings), _editions(editions)


@dataclass(frozen=True)
class AircraftOptions(DecodingOptions):
    """Inputs, the sensor file and the aircraft selection (call sign, address or all)."""

    sensors: str | None = None
    callsign: str | None = None
    address: str | None = None
    all_aircraft: bool = False
    output: str | None = None
    json: str | None = None
    gap_s: float = 180.0
    adsb_sigma_m: float | None = None  # declared sigma (m per axis) for ADS-B reports without NACp


def _check_aircraft(o: AircraftOptions) -> None:
    chosen = [o.callsign is not None, o.address is not None, bool(o.all_aircraft)]
    if sum(chosen) != 1:
        raise OptionError("choose exactly one of --callsign, --address or --all")
    if o.callsign is not None and not (normalise_callsign(o.callsign) or "").isalnum():
        raise OptionError(f"--callsign {o.callsign!r}: must be letters and digits (spaces ignored)")
    if o.address is not None:
        text = (normalise_address(o.address) or "")
        if len(text) != 6 or any(c not in "0123456789ABCDEF" for c in text):
            raise OptionError(f"--address {o.address!r}: must be a 24-bit hex address (up to 6 hex digits)")
    _number("--gap", o.gap_s, *GAP_RANGE_S, " s")
    _number("--adsb-sigma", o.adsb_sigma_m, *ADSB_SIGMA_RANGE_M, " m")


@dataclass(frozen=True)
class CorrelateOptions(AircraftOptions):
    """Everything ``correlate_job`` needs; see the CLI for the meaning of each option."""

    slot_s: float = 10.0
    pairs: str = "radar-adsb"
    split_adsb: bool = False
    quality: bool = False
    drop_jumps: bool = False
    min_nic: int | None = None
    min_nacp: int | None = None
    fill: str = "hold"  # empty slots: "hold" the previous slot (thesis) or "predict" by the tracker
    tables: str = "auto"  # slot and lag tables: in the workbook ("xlsx"), as Parquet beside it, or "auto"


@dataclass(frozen=True)
class QualityOptions(AircraftOptions):
    """Everything ``quality_job`` needs."""

    reference: str = "adsb"  # radar accuracy against "adsb" (interpolated reports) or "track" (smoothed)


@dataclass(frozen=True)
class StatsOptions(DecodingOptions):
    """Everything ``stats_job`` needs."""

    chunk_mb: float = 64.0  # streaming chunk: peak memory follows it, not the file size


@dataclass(frozen=True)
class DecodeOptions(DecodingOptions):
    """Everything ``decode_job`` needs."""

    output: str | None = None
    categories: tuple[int, ...] = ()
    strict: bool = False
    chunk_mb: float = 64.0


@dataclass
class Checked:
    """Options after validation: the inputs to read (duplicates dropped), editions, sensor table, outputs."""

    inputs: list[Path]
    editions: dict[int, str]
    sensors: pd.DataFrame | None = None
    output: Path | None = None
    json: Path | None = None
    warnings: list[str] = field(default_factory=list)


def validate(options) -> Checked:
    """Check every option, the sensor file and the output paths, before any decoding; OptionError if bad."""
    warnings: list[str] = []
    inputs, editions = _check_decoding(options, warnings)
    checked = Checked(inputs, editions, warnings=warnings)
    if isinstance(options, AircraftOptions):
        from msdc.pipeline.report.tables import TABLE_FILES, TABLE_MODES, parquet_path

        _check_aircraft(options)
        if isinstance(options, CorrelateOptions):
            from msdc.pipeline.correlate.correlation import PAIRS

            _number("--slot", options.slot_s, *SLOT_RANGE_S, " s")
            if options.pairs not in PAIRS:
                raise OptionError(f"--pairs {options.pairs!r}: must be one of {', '.join(PAIRS)}")
            _integer("--min-nic", options.min_nic, *INDICATOR_RANGE)
            _integer("--min-nacp", options.min_nacp, *INDICATOR_RANGE)
            if options.fill not in ("hold", "predict"):
                raise OptionError(f"--fill {options.fill!r}: must be hold or predict")
            if options.tables not in TABLE_MODES:
                raise OptionError(f"--tables {options.tables!r}: must be one of {', '.join(TABLE_MODES)}")
            if options.tables == "parquet" and options.output is None:
                raise OptionError("--tables parquet: needs -o (the tables are written beside the workbook)")
        if isinstance(options, QualityOptions) and options.reference not in ("adsb", "track"):
            raise OptionError(f"--reference {options.reference!r}: must be adsb or track")
        checked.output = _output("-o", options.output, (".xlsx",))
        if checked.output is not None and isinstance(options, CorrelateOptions):  # the figure beside it
            png = checked.output.with_name(f"{checked.output.stem}_tracks.png")
            if png.is_dir():
                raise OptionError(f"-o {checked.output}: its track figure {png} is a directory")
            if options.tables != "xlsx":  # the tables that may go to Parquet beside it
                for name in TABLE_FILES:
                    table = parquet_path(checked.output, name)
                    if table.is_dir():
                        raise OptionError(f"-o {checked.output}: its {name} table {table} is a directory")
                    if table.exists() and not os.access(table, os.W_OK):
                        raise OptionError(f"-o {checked.output}: its {name} table {table} is not writable")
        checked.json = _output("--json", options.json, (".json",))
        checked.sensors = _sensors(options.sensors, required=not isinstance(options, QualityOptions))
        if checked.output is not None:
            for png in _figures_beside(checked.output, options, checked.sensors):
                if png.is_dir():
                    raise OptionError(f"-o {checked.output}: its figure {png} is a directory")
        if checked.output is not None:
            out = checked.output
            beside = [out.with_name(f"{out.stem}_tracks.png"), *(parquet_path(out, n) for n in TABLE_FILES),
                      *_figures_beside(out, options, checked.sensors)]
            spare_inputs(options.inputs, [(f"-o {out}", out)] + [(f"-o {out}", p) for p in beside])
        spare_inputs(options.inputs, [(f"--json {checked.json}", checked.json)])
        from msdc.pipeline.model.sensors import implausible_altitudes

        warnings += implausible_altitudes(checked.sensors, options.sensors)
    if isinstance(options, DecodeOptions | StatsOptions):
        _number("--chunk-mb", options.chunk_mb, *CHUNK_RANGE_MB, " MB")
    if isinstance(options, DecodeOptions):
        checked.output = _output("-o", options.output, (".csv", ".parquet"))
        bad = [c for c in options.categories if c not in (21, 48)]
        if bad:
            raise OptionError(f"--category {bad[0]}: must be 21 or 48")
        if checked.output is not None:
            out = checked.output
            spare_inputs(options.inputs, [(f"-o {out}", p) for p in (
                out, *(category_output(out, c) for c in (21, 48)))])
            cats = sorted(set(options.categories or (21, 48)))
            for cat in cats if len(cats) > 1 else ():  # written when several categories decode
                each = category_output(out, cat)
                if each.is_dir():
                    raise OptionError(f"-o {out}: its CAT{cat:03d} file {each} is a directory")
                if each.exists() and not os.access(each, os.W_OK):
                    raise OptionError(f"-o {out}: its CAT{cat:03d} file {each} is not writable")
    return checked


# ---------------------------------------------------------------------------------------------------------
# Shared steps


def _load(options: DecodingOptions, checked: Checked, progress: Progress | None) -> Loaded:
    """Decode the inputs for measurements: only the columns build_measurements reads are decoded."""
    import warnings as python_warnings

    from msdc.asterix.errors import EditionWarning, UnreadableInput
    from msdc.pipeline.model.measurements import DECODED_COLUMNS, impossible_positions

    try:
        with python_warnings.catch_warnings():  # a wrong edition is said below, with its --edition
            python_warnings.simplefilter("ignore", EditionWarning)
            loaded = load(checked.inputs, editions=checked.editions or None, date=options.date,
                          format=options.format, columns=DECODED_COLUMNS, progress=progress)
    except UnreadableInput as exc:
        raise JobError(str(exc), 2) from exc
    spans = [time_spans(rec.frames, loaded.date) for rec in loaded.recordings]
    checked.warnings += _empty_inputs(loaded)
    checked.warnings += _wrong_editions(loaded)
    checked.warnings += _order_warnings(checked.inputs, spans)
    checked.warnings += _date_ignored(options, loaded.inputs)
    checked.warnings += _format_hints(options, loaded.inputs)
    checked.warnings += impossible_positions(loaded.frames.get(21))
    checked.warnings += loaded.warnings
    return loaded


def undated_warning(loaded: Loaded, outputs: str) -> list[str]:
    """A warning when no input carries a date and --date was not given: ``outputs`` then place their times
    on 1970-01-01 (pipeline.model.time.UNDATED_DAY); the times of day are right."""
    if loaded.date is not None:
        return []
    return [f"the inputs carry no date and --date was not given: {outputs} are placed on 1970-01-01 (the "
            "times of day are right); give --date YYYY-MM-DD"]


def _order_warnings(paths: list[Path], spans: list[dict[str, tuple[pd.Timestamp, pd.Timestamp]]]
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


def _format_hints(options: DecodingOptions, inputs: list[dict]) -> list[str]:
    """format_hint for each input, unless --format was given."""
    if options.format is not None:
        return []
    hints = (format_hint(info["path"], info["format"], info["skipped_blocks"]) for info in inputs)
    return [hint for hint in hints if hint]


def format_hint(path, fmt: str | None, skipped_blocks: int) -> str:
    """A hint to give --format when detection read a file as raw, blocks were skipped, and the file reads as a
    recorder file (final, gps, oradis) but for its first frame (asterix.containers.recorder_hint); else ''."""
    from msdc.asterix.containers import DETECT_BYTES, recorder_hint

    if fmt != "raw" or not skipped_blocks:
        return ""
    with open(path, "rb") as file:
        guess = recorder_hint(file.read(DETECT_BYTES))
    if guess is None:
        return ""
    return (f"{path}: read as a raw ASTERIX stream ({skipped_blocks} block(s) skipped), but past its first "
            f"frame it reads as a {guess} recording (its first frame damaged?): if it is one, give "
            f"--format {guess}")


def _date_ignored(options: DecodingOptions, inputs: list[dict]) -> list[str]:
    if options.date is None:
        return []
    return [f"{info['path']}: --date ignored, the capture time dates a {info['format']} file"
            for info in inputs if info["format"] in ("pcap", "pcapng")]


def _load_measurements(options: AircraftOptions, checked: Checked, progress: Progress | None,
                       stage: str, *, either: bool = False, columns=None) -> tuple[Loaded, pd.DataFrame]:
    """Decode the inputs chunk by chunk straight into radar and ADS-B measurements (load_measurements),
    with the user-facing errors for unreadable inputs, missing data and sensors (stray radar records are
    left out with a warning: _stray_verdict). ``stage`` is the progress stage shown once the inputs are
    read (before a missing-data or missing-sensor error too). ``either`` (quality): one category is
    enough, the other's absence is a warning saying which sheets stay empty."""
    from msdc.asterix.errors import UnreadableInput

    try:
        loaded, meas = load_measurements(checked.inputs, checked.sensors, editions=checked.editions or None,
                                         date=options.date, format=options.format,
                                         adsb_sigma_m=options.adsb_sigma_m, progress=progress, either=either,
                                         columns=columns)
    except UnreadableInput as exc:
        raise JobError(str(exc), 2) from exc
    except NoRecords as exc:
        if progress:
            progress.stage(stage)
        raise _no_records(exc) from exc
    if progress:
        progress.stage(stage)
    if len(loaded.stray_radar):
        from msdc.pipeline.model.sensors import UnknownRadar, stray_verdict

        n_cat048 = sum(info["records"].get(48, 0) for info in loaded.inputs)
        try:
            checked.warnings += stray_verdict(loaded.stray_radar, n_cat048, sensors_path(options))
        except UnknownRadar as exc:
            raise unknown_radar_error(exc.missing, sensors_path(options),
                                      leave_out="by giving the ADS-B recordings alone") from exc
    checked.warnings += _empty_inputs(loaded)
    checked.warnings += _wrong_editions(loaded, but=absent_categories(loaded))
    checked.warnings += [f"no {name} (CAT{cat:03d}) records in the inputs{_all_failed(loaded, cat)}: "
                         f"{_WITHOUT[cat]}" for cat, name in ((48, "radar"), (21, "ADS-B"))
                         if cat in absent_categories(loaded)]
    checked.warnings += _order_warnings(checked.inputs, loaded.spans)
    checked.warnings += _date_ignored(options, loaded.inputs)
    checked.warnings += _format_hints(options, loaded.inputs)
    checked.warnings += loaded.warnings
    checked.warnings += list(meas.attrs.get("coverage_warnings", ()))
    checked.warnings += list(meas.attrs.get("identity_warnings", ()))
    return loaded, meas


def _no_records(exc: NoRecords) -> JobError:
    """The user-facing error for inputs without radar or ADS-B records: every absent category, those whose
    blocks failed to decode first, with how many failed and the edition to pin (an ADS-B recording under a
    wrong edition is why there is no record at all, not a missing radar)."""
    absent = absent_categories(exc.loaded) or [exc.category]
    failed = {cat: why[2:] for cat in absent if (why := _all_failed(exc.loaded, cat))}
    absent.sort(key=lambda cat: cat not in failed)
    names = " or ".join(f"{'radar' if cat == 48 else 'ADS-B'} (CAT{cat:03d})" for cat in absent)
    why = f": {'; '.join(failed.values())}" if failed else ""
    return JobError(f"no {names} records in the inputs{why}")


def absent_categories(loaded: Loaded) -> list[int]:
    """Which of CAT048 and CAT021 no input holds a record of."""
    return [cat for cat in (48, 21) if not any(info["records"].get(cat) for info in loaded.inputs)]


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
_WITHOUT = {48: "the Radar accuracy and Radar biases sheets are empty",
            21: "the ADS-B quality sheets are empty, and so are Radar accuracy and Radar biases (ADS-B is "
                "their reference)"}


def _empty_inputs(loaded: Loaded) -> list[str]:
    """A warning for each input of which no record decoded (a file that is not a recording, or another
    category): the run goes on with the others, but it should not be silent."""
    return [f"{info['path']}: no record decoded ({info['skipped_blocks']} block(s) skipped; 'msdc stats' "
            "lists them)" if info["skipped_blocks"] else f"{info['path']}: no CAT021 or CAT048 record in it"
            for info in loaded.inputs if not any(info["records"].values())]


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


def _parameters(options: AircraftOptions, loaded: Loaded, started: float, command: str) -> dict:
    return {"software": f"msdc {software_version()}", "command": command,
            "run_utc": dt.datetime.now(dt.UTC).strftime("%Y-%m-%dT%H:%M:%SZ"),
            "run_time_s": round(time.monotonic() - started, 3), "editions": {
                f"CAT{c:03d}": e for c, e in sorted(loaded.editions.items())},
            "sensors": sensors_path(options), "date": loaded.date.isoformat() if loaded.date else None,
            "adsb_sigma_m": options.adsb_sigma_m}


def _quality(meas: pd.DataFrame, sensors: pd.DataFrame, options: AircraftOptions) -> QualityResult:
    from msdc.pipeline.model.aircraft import NoSuchAircraft
    from msdc.pipeline.quality.quality_run import quality_run

    try:
        return quality_run(meas, sensors, callsign=options.callsign, address=options.address,
                           gap_s=options.gap_s, reference=getattr(options, "reference", "adsb"))
    except NoSuchAircraft as exc:
        raise JobError(str(exc)) from exc


# ---------------------------------------------------------------------------------------------------------
# Jobs


@dataclass
class CorrelateResult:
    """A correlation run, the measurements it used (the columns ``correlate_columns`` names), the quality
    result (with ``quality``) and warnings."""

    options: CorrelateOptions
    checked: Checked
    run: CorrelationRun
    measurements: pd.DataFrame
    loaded: Loaded
    quality: QualityResult | None = None


def _filtered_away(exc, meas_all: pd.DataFrame, options: CorrelateOptions) -> str | None:
    """The message when the aircraft's ADS-B reports exist but the quality filters removed them all."""
    from msdc.pipeline.model.measurements import select

    asked = [f for f, on in ((f"--min-nic {options.min_nic}", options.min_nic is not None),
                             (f"--min-nacp {options.min_nacp}", options.min_nacp is not None),
                             ("--drop-jumps", options.drop_jumps)) if on]
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


def _marked_measurements(options: AircraftOptions, checked: Checked, progress: Progress | None, stage: str,
                         *, split_adsb: bool = False, either: bool = False, columns=None,
                         flags: list[str] | None = None) -> tuple[Loaded, pd.DataFrame]:
    """The inputs and their measurements with the duplicate and jump flags (once per job; correlate counts
    each window's jumps); decoded columns are held one chunk at a time (see _load_measurements).
    ``stage`` is the progress stage shown once the inputs are read; ``columns`` and ``flags``: only those
    measurement columns and jump columns (every one when None)."""
    from msdc.pipeline.model.marks import mark_once

    loaded, meas = _load_measurements(options, checked, progress, stage, either=either, columns=columns)
    meas = mark_once(meas, split_adsb=split_adsb, flags=flags)
    release_free_memory()
    return loaded, meas


# the measurement columns correlate --quality's slotting figures read (pipeline.report.quality_figures)
SLOTTING_FIGURE_INPUTS = ["time", "sensor_kind", "sensor_id", "aircraft_id", "callsign", "address",
                          "latitude", "longitude"]


def correlate_columns(options: CorrelateOptions) -> list[str]:
    """The measurement columns a correlate job builds, in schema order: what correlate, mark_once, the
    filters asked for and far_separations read, with ``fill`` "predict" what the tracker reads, and with
    ``quality`` what the quality step (``quality_columns``) and its slotting figures read. Half the bytes
    of a row on a large recording."""
    from msdc.pipeline.correlate.correlation import CORRELATION_INPUTS
    from msdc.pipeline.model.dedup import DEDUP_KEYS
    from msdc.pipeline.model.jumps import JUMP_INPUTS
    from msdc.pipeline.model.schema import MEASUREMENT_COLUMNS, column_names
    from msdc.pipeline.model.site_check import FAR_SEPARATION_INPUTS

    need = {*CORRELATION_INPUTS, *DEDUP_KEYS, "sensor_kind", "sensor_id", *JUMP_INPUTS,
            *FAR_SEPARATION_INPUTS}
    if options.fill == "predict":
        from msdc.pipeline.track.tracker import FILTER_INPUTS

        need |= set(FILTER_INPUTS)
    need |= {"nucp_nic"} if options.min_nic is not None else set()
    need |= {"nacp"} if options.min_nacp is not None else set()
    if options.quality:  # (the ADS-B reference: correlate has no --reference)
        need |= set(_quality_inputs("adsb")) | set(SLOTTING_FIGURE_INPUTS)
    return column_names(need & set(MEASUREMENT_COLUMNS))  # the job-wide flags are added by mark_once


def _quality_inputs(reference: str) -> list[str]:
    """The measurement columns the quality step reads: the quality tables, the radar errors against the
    ``reference`` ("adsb" or "track": the tracker's and track_reference's inputs as well), the aircraft
    selection and mark_once."""
    from msdc.pipeline.model.dedup import DEDUP_KEYS
    from msdc.pipeline.model.jumps import JUMP_INPUTS
    from msdc.pipeline.quality.accuracy import ACCURACY_INPUTS
    from msdc.pipeline.quality.tables import QUALITY_INPUTS

    need = [*QUALITY_INPUTS, *ACCURACY_INPUTS, *DEDUP_KEYS, *JUMP_INPUTS, "sensor_kind", "sensor_id",
            "aircraft_id", "callsign", "address"]
    if reference == "track":
        from msdc.pipeline.quality.track_reference import TRACK_REFERENCE_INPUTS
        from msdc.pipeline.track.tracker import FILTER_INPUTS, REQUIRED

        need += [*REQUIRED, *FILTER_INPUTS, *TRACK_REFERENCE_INPUTS]  # the tracker's optional ones too
    return need


def quality_columns(options: QualityOptions) -> list[str]:
    """The measurement columns a quality job builds, in schema order: what the quality tables, the radar
    errors against the reference (with ``reference="track"`` the tracker's inputs), mark_once and the
    aircraft selection read. Two thirds of the bytes of a row with the ADS-B reference."""
    from msdc.pipeline.model.schema import MEASUREMENT_COLUMNS, column_names
    from msdc.pipeline.model.site_check import SITE_CHECK_INPUTS

    need = set(_quality_inputs(options.reference)) | set(SITE_CHECK_INPUTS)
    return column_names(need & set(MEASUREMENT_COLUMNS))  # the job-wide flags are added by mark_once


def correlate_job(options: CorrelateOptions, *, progress: Progress | None = None,
                  checked: Checked | None = None, command: str = "correlate") -> CorrelateResult:
    """Validate, decode, build measurements, filter, correlate (and assess quality); nothing is written."""
    from msdc.pipeline.correlate.correlation import NoOverlap, TooManySlots, correlate
    from msdc.pipeline.model.aircraft import NoSuchAircraft
    from msdc.pipeline.quality.filters import apply_filters, filter_warnings

    started = time.monotonic()
    checked = checked or validate(options)
    if progress:
        progress.stage("Processing data files")
    columns = correlate_columns(options)
    loaded, meas_all = _marked_measurements(options, checked, progress, "Pre-processing data",
                                            split_adsb=options.split_adsb, columns=columns,
                                            flags=None if options.quality or columns is None else ["jump"])
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
        raise JobError(_filtered_away(exc, meas_all, options) or str(exc)) from exc
    except NoOverlap as exc:
        raise JobError(str(exc)) from exc
    except TooManySlots as exc:
        raise OptionError(f"--slot {options.slot_s:g}: the overlap windows would need more than "
                          f"{exc.limit:,} slots (at least {exc.slots:,}); use a longer --slot") from exc
    asked = {"jumps": options.drop_jumps, "nic_below_min": options.min_nic is not None,
             "nic_missing_kept": options.min_nic is not None,
             "nacp_below_min": options.min_nacp is not None,
             "nacp_missing_kept": options.min_nacp is not None}
    run.inputs = loaded.inputs
    run.filters = {k: v for k, v in removed.items() if asked.get(k, True)}
    checked.warnings += filter_warnings(removed, options.min_nic, options.min_nacp)
    run.parameters = {**run.parameters, **_parameters(options, loaded, started, command),
                      "filters": {"drop_jumps": options.drop_jumps, "min_nic": options.min_nic,
                                  "min_nacp": options.min_nacp, "removed": run.filters}}
    from msdc.pipeline.model.site_check import far_separations

    checked.warnings += far_separations([w.summary for w in run.windows], meas, checked.sensors,
                                        str(options.sensors))
    checked.warnings += _nothing_correlated(run, options)
    result = CorrelateResult(options, checked, run, meas, loaded)
    if options.quality:
        if progress:
            progress.stage("Analysing data quality")
        result.quality = _quality(meas_all, checked.sensors, options)
        run.extra_sheets.update(result.quality.sheets)
    return result


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


def _figures_beside(out: Path, options, sensors: pd.DataFrame) -> list[Path]:
    """The quality figures a run may write beside its workbook: the update intervals, each declared radar's
    errors and, for correlate --quality, the first FIGURE_WINDOWS windows' slotting and lag figures."""
    if not (isinstance(options, QualityOptions) or getattr(options, "quality", False)):
        return []
    names = [f"{out.stem}_intervals.png"] + [f"{out.stem}_radar_errors_{sac}_{sic}.png"
                                             for sac, sic in zip(sensors["sac"], sensors["sic"], strict=True)]
    if isinstance(options, CorrelateOptions):
        names += [f"{out.stem}_{kind}_{i + 1}.png" for kind in ("slotting", "lags")
                  for i in range(FIGURE_WINDOWS)]
    return [out.with_name(n) for n in names]


def figure_windows_note(n_windows: int, max_windows: int | None = None) -> str | None:
    """What correlate --quality leaves out of its per-window figures (said on the Figures sheet and the
    terminal), None when every window has its figures; ``max_windows`` FIGURE_WINDOWS unless given."""
    max_windows = FIGURE_WINDOWS if max_windows is None else max_windows
    if n_windows <= max_windows:
        return None
    return (f"slotting and lag figures for the first {max_windows} of {n_windows} windows only (the Lag "
            "charts and Slot charts sheets chart more)")


def quality_figures(result: QualityResult, out_dir: Path, stem: str) -> dict[str, Path]:
    """Update-interval histogram and, per radar, range/azimuth error against range and time (PNG)."""
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
    result.figures.update(figs)
    return figs


def _track_figure(run: CorrelationRun, png: Path, sensors: pd.DataFrame) -> None:
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
    from msdc.pipeline.model.geodesy import _geod
    from msdc.pipeline.report.figures import new_figure

    _geod()
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
                      max_windows: int | None = None, prepared: Prepared | None = None) -> dict[str, Path]:
    """Write what the options ask for: JSON summary, workbook with its track figure (and, with quality,
    the quality and per-window figures), all or nothing. Returns what was written, by kind. ``prepared``
    (prepare_correlation_writers) draws the track figure; it is used up or closed here."""
    release_free_memory()  # what the job freed (the CLI lets go of the measurements), before the tables
    try:
        with all_or_nothing(result.checked.json, result.checked.output):
            shown = FIGURE_WINDOWS if max_windows is None else max_windows
            return _write_correlation(result, progress, shown, prepared)
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


def _write_correlation(result: CorrelateResult, progress: Progress | None,
                       max_windows: int, prepared: Prepared | None = None) -> dict[str, Path]:
    from msdc.pipeline.report.tables import parquet_tables, table_length

    written: dict[str, Path] = {}
    run, checked = result.run, result.checked
    drawing = None
    if checked.output:  # the child starts first: the map takes it longest
        out, mode = checked.output, result.options.tables
        png = out.with_name(out.stem + "_tracks.png")
        in_child = [name for name in parquet_tables(run, mode) if name in CHILD_TABLES]
        rows = table_length(run, "slots") + table_length(run, "correlation")
        if rows > CHILD_MAX_TABLE_ROWS:  # a long run's tables are written here, in batches
            in_child = []
        args = (_track_run(run), png, checked.sensors, out, in_child)
        drawing = prepared.start(*args) if prepared is not None else Background(_track_figure_and_tables,
                                                                                 *args)
    try:
        from msdc.pipeline.report.summary import write_json

        if checked.json:
            write_json(run, checked.json)
            written["json"] = checked.json
        if drawing is not None:
            written.update(_write_workbook(result, progress, max_windows, drawing, png, in_child))
    finally:
        if drawing is not None:
            drawing.cancel()  # only still running when writing failed
    return written


def _write_workbook(result: CorrelateResult, progress: Progress | None, max_windows: int,
                    drawing: Background, png: Path, in_child: list[str]) -> dict[str, Path]:
    """The workbook (and with quality its figures) while ``drawing`` writes the map and the Parquet tables
    ``in_child``; the other Parquet tables are written here."""
    from msdc.pipeline.report.excel import write_report
    from msdc.pipeline.report.tables import parquet_path

    run, out = result.run, result.checked.output
    if progress:
        progress.stage("Writing report")
    images = None
    if result.quality is not None:
        from msdc.pipeline.report.figures import lag_figure
        from msdc.pipeline.report.quality_figures import slotting_figure
        from msdc.pipeline.report.summary import window_label

        images = dict(quality_figures(result.quality, out.parent, out.stem))
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
    files = [parquet_path(out, name) for name in in_child]
    note = figure_windows_note(len(run.windows), max_windows) if images is not None else None
    tables = write_report(run, out, figure_png=png, images=images, images_note=note or "",
                          tables=result.options.tables,
                          figure_ready=lambda: _drawn(drawing, png, files),
                          tables_written=(lambda: _drawn(drawing, png, files)) if in_child else None,
                          elsewhere=in_child)
    written = {"report": out, "figure": png}
    written.update((f"image {name}", Path(path)) for name, path in (images or {}).items())
    written.update((f"table {p.stem.removeprefix(out.stem + '_')}", p) for p in tables)
    return written


@dataclass
class QualityJobResult:
    """Quality tables and radar accuracy of a run, with its parameters and inputs."""

    options: QualityOptions
    checked: Checked
    quality: QualityResult
    parameters: dict
    loaded: Loaded


def quality_job(options: QualityOptions, *, progress: Progress | None = None, checked: Checked | None = None,
                command: str = "quality") -> QualityJobResult:
    """Validate, decode, build measurements and compute the quality and accuracy tables."""
    started = time.monotonic()
    checked = checked or validate(options)
    if progress:
        progress.stage("Processing data files")
    loaded, meas = _marked_measurements(options, checked, progress, "Analysing data quality", either=True,
                                        columns=quality_columns(options))
    from msdc.pipeline.model.site_check import site_warnings

    absent = absent_categories(loaded)
    checked.warnings += site_warnings(meas, checked.sensors, str(sensors_path(options)))
    quality = _quality(meas, checked.sensors, options)
    params = {**_parameters(options, loaded, started, command), "callsign": options.callsign,
              "address": options.address, "gap_s": options.gap_s,
              "notes": [f"no CAT{cat:03d} records in the inputs: {_WITHOUT[cat]}" for cat in absent]}
    return QualityJobResult(options, checked, quality, params, loaded)


def write_quality(result: QualityJobResult) -> dict[str, Path]:
    """Write the JSON tables and/or the workbook with its figures, as the options ask, all or nothing."""
    with all_or_nothing(result.checked.json, result.checked.output):
        return _write_quality(result)


def _write_quality(result: QualityJobResult) -> dict[str, Path]:
    import json

    from msdc.pipeline.report.excel import write_tables
    from msdc.pipeline.report.summary import table_records

    written: dict[str, Path] = {}
    if result.checked.json:
        doc = {"parameters": result.parameters, "inputs": result.loaded.inputs,
               "tables": {name: table_records(t) for name, t in result.quality.sheets.items()}}
        result.checked.json.write_text(json.dumps(doc, indent=1, default=str))
        written["json"] = result.checked.json
    if result.checked.output:
        out = result.checked.output
        images = quality_figures(result.quality, out.parent, out.stem)
        # the sheet lists the bins that hold intervals (every 0.1 s bin up to the longest interval printed
        # 18 pages on the real radar); the DataFrame and the JSON keep every bin
        sheets = dict(result.quality.sheets)
        bins = sheets["Update intervals"]
        sheets["Update intervals"] = bins[bins["intervals"] > 0] if "intervals" in bins else bins
        write_tables(sheets, out, images=images,
                     parameters={**result.parameters, "inputs": result.loaded.inputs})
        written["report"] = out
        written.update((f"image {name}", Path(path)) for name, path in images.items())
    return written


@dataclass
class StatsResult:
    """What the recordings hold: the stats tables, and per input its format, records per category, skipped
    blocks, editions and how an 'auto' edition was chosen (``edition_choice``)."""

    tables: dict[str, pd.DataFrame]
    inputs: list[dict]
    warnings: list[str]

    @property
    def records(self) -> int:
        """Records decoded over every input and category."""
        return sum(n for info in self.inputs for n in info["records"].values())


def stats_job(options: StatsOptions, *, progress: Progress | None = None) -> StatsResult:
    """Validate, then stream every input in chunks of ``chunk_mb`` (asterix.iter_read) and fold the tables of
    records, sources, aircraft and skipped blocks chunk by chunk: memory is bounded by the chunk, not
    the file."""
    import msdc.asterix as asterix
    from msdc.asterix.errors import UnreadableInput
    from msdc.pipeline.model.sources import file_labels
    from msdc.pipeline.model.time import UNDATED_DAY, FirstDayTally
    from msdc.pipeline.quality.inventory import STATS_COLUMNS, StatsAccumulator

    checked = validate(options)
    if progress:
        progress.stage("Processing data files")
    acc = StatsAccumulator()
    failed: dict[tuple[str, int], edition_notes.Failed] = {}
    inputs: list[dict] = []
    spans: list[dict[int, tuple[pd.Timestamp, pd.Timestamp]]] = []
    chunk = max(int(options.chunk_mb * 1e6), 1)
    early_start: list[str] = []  # FirstDayTally's warnings
    labels = file_labels(checked.inputs)
    for i, path in enumerate(checked.inputs):
        if progress:
            progress.step(f"{path.name} ({i + 1}/{len(checked.inputs)})")
        info = {"path": str(path), "bytes": 0, "format": None, "records": {}, "skipped_blocks": 0,
                "editions": {}, "edition_choice": {}, "date": None}
        by_source: dict[str, tuple[pd.Timestamp, pd.Timestamp]] = {}
        tally = FirstDayTally()
        try:
            for rec in asterix.iter_read(path, chunk=chunk, editions=checked.editions or None,
                                         date=options.date, format=options.format, columns=STATS_COLUMNS):
                acc.add(rec.frames, rec.errors, rec.ignored)
                tally.add(rec.frames)
                edition_notes.fold(failed, rec)
                info["bytes"], info["format"] = rec.size_bytes, rec.format
                info["date"] = info["date"] or rec.date
                for cat, frame in rec.frames.items():
                    info["records"][cat] = info["records"].get(cat, 0) + len(frame)
                info["skipped_blocks"] += len(rec.errors)
                info["editions"].update(rec.editions)
                info["edition_choice"] = {**rec.edition_choice, **info["edition_choice"]}
                by_source = widen_spans(by_source, time_spans(rec.frames, rec.date))
        except UnreadableInput as exc:
            raise JobError(str(exc), 2) from exc
        early_start += tally.warning(labels[i], info["date"], info["format"])
        inputs.append(info)
        spans.append(by_source)
    dates = [info["date"] for info in inputs if info["date"] is not None]
    if dates:  # undated inputs are dated by the earliest known date, as load() does
        shift = pd.Timestamp(min(dates), tz="UTC") - UNDATED_DAY
        spans = [s if info["date"] else {c: (lo + shift, hi + shift) for c, (lo, hi) in s.items()}
                 for info, s in zip(inputs, spans, strict=True)]
    checked.warnings += edition_notes.warnings(failed)
    checked.warnings += _order_warnings(checked.inputs, spans)
    checked.warnings += _date_ignored(options, inputs)
    checked.warnings += _format_hints(options, inputs)
    checked.warnings += early_start
    return StatsResult(acc.tables(), inputs, checked.warnings)


@dataclass
class DecodeResult:
    """Records per category, the files written, and every skipped block (path, offset, reason)."""

    counts: dict[int, int]
    outputs: dict[int, Path]
    skipped: list[tuple[str, int, str]]
    warnings: list[str]
    notes: list[str] = field(default_factory=list)
    held: dict[str, dict[int, int]] = field(default_factory=dict)  # per input: data blocks per category

    def nothing_decoded(self, categories: tuple[int, ...] = ()) -> str:
        """Why no record decoded, naming what each input holds (a --category the inputs lack, most often)."""
        asked = f" with --category {','.join(str(c) for c in categories)}" if categories else ""
        def listed(cats: dict[int, int]) -> str:
            return ", ".join(f"CAT{c:03d} ({n} block(s))" for c, n in sorted(cats.items())) or "no data block"

        holds = "; ".join(f"{path} holds {listed(cats)}" for path, cats in self.held.items())
        return f"nothing could be decoded{asked}" + (f": {holds}" if holds else "")


def decode_job(options: DecodeOptions, *, on_chunk: Callable[[int, int, str], None] | None = None
               ) -> DecodeResult:
    """Stream every input in chunks and write CSV or Parquet: one file, or one per category when records
    of several categories decoded (decided from what decoded, at the end). Each output is written to a
    temporary file beside it and moved into place only when the whole run succeeded: a failed or
    interrupted run writes nothing, nor does a run in which nothing decodes. ``on_chunk(done_bytes, size,
    name)`` reports progress. Raises asterix DecodeError in strict mode, JobError for unreadable input."""
    import msdc.asterix as asterix
    from msdc.asterix.errors import UnreadableInput
    from msdc.asterix.reader import categories_in
    from msdc.pipeline.model.sources import file_labels
    from msdc.pipeline.model.time import FirstDayTally
    from msdc.pipeline.report.outputs import Staging

    checked = validate(options)
    out = checked.output
    early_start: list[str] = []  # FirstDayTally's warnings
    counts: dict[int, int] = {}
    outputs: dict[int, Path] = {}
    skipped: list[tuple[str, int, str]] = []
    failed: dict[tuple[str, int], edition_notes.Failed] = {}
    notes: list[str] = []
    cats = list(options.categories) or None
    csv = out is not None and out.suffix.lower() == ".csv"
    with Staging() as staging:
        staged: dict[int, Path] = {}  # category -> its temporary file
        writers: dict[int, object] = {}
        try:
            for path, label in zip(checked.inputs, file_labels(checked.inputs), strict=True):
                size = path.stat().st_size
                chunk = max(int(options.chunk_mb * 1e6), 1)
                tally, date, fmt, chosen = FirstDayTally(), None, None, {}
                for rec in asterix.iter_read(path, chunk=chunk, editions=checked.editions or None,
                                             date=options.date, format=options.format, categories=cats,
                                             strict=options.strict):
                    tally.add(rec.frames)
                    date, fmt, chosen = date or rec.date, rec.format, {**rec.edition_choice, **chosen}
                    skipped += [(str(path), int(e.offset), str(e.reason)) for e in rec.errors.itertuples()]
                    edition_notes.fold(failed, rec)
                    for cat, frame in rec.frames.items():
                        counts[cat] = counts.get(cat, 0) + len(frame)
                        if out is not None and len(frame):
                            if cat not in staged:
                                staged[cat] = staging.temporary(category_output(out, cat))
                            _write_chunk(staged[cat], cat, frame.assign(file=label), writers, csv)
                    done = max((int(f["offset"].max()) for f in rec.frames.values() if len(f)), default=0)
                    if on_chunk:
                        on_chunk(done, size, path.name)
                if on_chunk:  # the last record's offset is not the file's end: close the bar at 100 %
                    on_chunk(size, size, path.name)
                early_start += tally.warning(label, date, fmt)
                notes += [f"{path}: CAT{cat:03d} --edition auto {why}" for cat, why in sorted(chosen.items())]
                early_start += _format_hints(options, [{"path": path, "format": fmt, "skipped_blocks": sum(
                    1 for p, _, _ in skipped if p == str(path))}])
        except UnreadableInput as exc:
            raise JobError(str(exc), 2) from exc
        finally:
            for w in writers.values():
                if hasattr(w, "close"):
                    w.close()
        several = len(staged) > 1
        for cat in sorted(staged):
            outputs[cat] = category_output(out, cat) if several else out
            if several:
                notes.append(f"several categories: writing {outputs[cat]}")
        staging.commit({staged[cat]: outputs[cat] for cat in staged})
    held = {} if sum(counts.values()) else {str(p): categories_in(p, format=options.format)
                                              for p in checked.inputs}
    warnings = checked.warnings + early_start + edition_notes.warnings(failed)
    return DecodeResult(counts, outputs, skipped, warnings, notes, held)


def category_output(out: Path, cat: int) -> Path:
    """Where decode writes one category's records when several decode: ``OUT_cat048.csv`` beside ``OUT``."""
    return out.with_name(f"{out.stem}_cat{cat:03d}{out.suffix}")


def _write_chunk(path: Path, cat: int, frame: pd.DataFrame, writers: dict, csv: bool) -> None:
    """Append one chunk of a category to its (temporary) output file, CSV or Parquet, opening it on first
    use."""
    if csv:
        frame = guard_frame(frame.assign(timestamp=frame["timestamp"].dt.strftime("%Y-%m-%dT%H:%M:%S.%fZ")))
        frame.to_csv(path, mode="a" if cat in writers else "w", header=cat not in writers, index=False)
        writers[cat] = True
    else:
        import pyarrow as pa
        import pyarrow.parquet as pq

        table = pa.Table.from_pandas(frame, preserve_index=False)
        if cat not in writers:
            writers[cat] = pq.ParquetWriter(path, table.schema)
        writers[cat].write_table(table.cast(writers[cat].schema))


__all__ = ["CorrelateOptions", "DecodeOptions", "JobError", "OptionError", "QualityOptions", "StatsOptions",
           "correlate_job", "decode_job", "quality_job", "stats_job", "validate",
           "write_correlation", "write_quality"]
