"""Each command-line option declared once, as a field of its job's options dataclass.

A field's ``option(...)`` holds its flags, help, unit, range or choices and default; from them come the
argparse option (``add_options``), the options object a parsed command line makes (``from_args``), the
range and choice checks every job runs before decoding (``check_declared``) and the command's options table
in the docs (``options_table``; ``python -m msdc.pipeline.jobs.options --write-docs`` rewrites the guide's
tables). The checks that relate options (``--max-coast`` against ``--step``, one aircraft selection...) stay
in the jobs. Kept free of heavy imports: ``msdc --help`` builds its parser from here.
"""

from __future__ import annotations

import argparse
import dataclasses
import datetime as dt
import math
import numbers
import sys
import typing
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path

from msdc.asterix.categories import DECODABLE, MEASUREMENT_CATEGORIES
from msdc.pipeline.live.monitor import Thresholds
from msdc.pipeline.meta import (
    ADSB_SIGMA_RANGE_M,
    FILLS,
    FORMATS,
    METHODS,
    PAIRS,
    REFERENCES,
    REPLAYED_FORMATS,
    SMOOTHERS,
    TABLE_MODES,
)


class OptionError(ValueError):
    """An option, the sensor file or an output path is not usable: one line naming it and what is allowed.
    ``status`` is the exit status a command line should use (2: usage)."""

    def __init__(self, message: str, status: int = 2):
        super().__init__(message)
        self.status = status


# ---------------------------------------------------------------------------------------------------------
# Ranges and choices only the options take (those the steps share are in pipeline.meta)

CATEGORIES = tuple(sorted(DECODABLE))  # decode --category: any category msdc decodes
DEFAULT_CATEGORIES = tuple(sorted(MEASUREMENT_CATEGORIES))  # decoded when no --category is given
# ingested when no --category is given: every one but CAT001, the jobs on a dataset reading theirs (evaluate:
# the CAT034/CAT002 north markers for the scan period, the CAT062 tracks under test). CAT001 plots take their
# time from the CAT002 messages before them, so asking for them decodes a raw stream in one pass, not in
# windows on --workers (asterix.stream.can_pool): --category 1 asks
INGEST_CATEGORIES = tuple(c for c in CATEGORIES if c != 1)
CHUNK_RANGE_MB = (0.1, 4096.0)
GAP_RANGE_S = (0.1, 86400.0)
SLOT_RANGE_S = (0.1, 3600.0)  # below 0.1 s the slot count and the lag tables explode
INDICATOR_RANGE = (0, 11)  # NIC and NACp values
STEP_RANGE_S = (1e-3, 3600.0)  # below 1 ms the grid explodes (a day would be 86 M rows per aircraft)
MAX_COAST_RANGE_S = (0.0, 86400.0)  # its lower bound is --step (check_tracking)
SOURCES = ("radar", "adsb")  # track and conflicts fuse these by default
SOURCE_KINDS = (*SOURCES, "mlat", "smr")  # and may fuse these: multilateration, surface radar (CAT010/020)
# --noise: the sensor file's sigmas and NACp; estimated from residuals (one isotropic ADS-B sigma per
# class); estimated with an ADS-B along-track timing term as well (docs/tracker.md: fewer gated reports
# and track segments on the real recording, predictions through gaps no better on the mean)
NOISE = ("declared", "estimate", "timing")
ESTIMATED = ("estimate", "timing")
HORIZON_RANGE_S = (1.0, 3600.0)
RADIUS_RANGE_NM = (0.01, 100.0)
VERTICAL_RANGE_FT = (1.0, 100_000.0)
VERTICAL_TOLERANCE_RANGE_FT = (0.0, 500.0)
VERTICAL_MODELS = ("gate", "gaussian")
SURFACE_MODES = ("exclude", "include")  # pairs with an aircraft on the surface (pipeline.conflict.surface)
MIN_FL_RANGE = (-20.0, 1000.0)  # --min-fl: below the lowest aerodrome to above any aircraft
# --max-report-gap: losses are measured between reports at most this far apart (pipeline.conflict.reported)
REPORT_GAP_RANGE_S = (0.1, 3600.0)
# --figures-limit: a reader looks at tens of per-aircraft or per-alert figures, not hundreds, and each costs
# ~0.2-0.4 s of a core: 50 take ~10 s on two cores, the real hour's 181 aircraft ~45 s, its 728 alerts ~3 min
FIGURES_LIMIT = 50
FIGURES_LIMIT_RANGE = (0, 100_000)
WORKERS_RANGE = (1, 256)  # --workers: ingest's decoding processes, a local Dask cluster's workers

# Where an option stands in --help and in the docs table: by section, then in declaration order
SECTIONS = ("selection", "output", "command", "tracking", "measurements", "reading")


# ---------------------------------------------------------------------------------------------------------
# The declaration


@dataclass(frozen=True)
class Spec:
    """How a field appears on the command line and in the docs, and what values it takes."""

    flags: tuple[str, ...]  # ("-o", "--output"); () for the positional argument, named by metavar
    help: str
    unit: str = ""  # after a range in messages and the docs table: "s", "m", "MB"
    range: tuple[float, float] | None = None  # inclusive; each item of a tuple value
    choices: tuple | None = None
    parser_choices: bool = True  # argparse refuses other values and its usage lists them; else the job does
    metavar: str | None = None
    required: bool = False  # argparse requires it (the jobs say so for the library)
    optional: bool = False  # the positional argument may be left out (another option names the input)
    repeat: bool = False  # the flag may be given several times: a tuple of values
    parse: Callable[[str], object] | None = None  # argparse's type=, when not the field's own type
    group: str | None = None  # flags of one group are mutually exclusive and one of them is required
    section: str = "command"  # one of SECTIONS
    doc: str = ""  # the docs table's meaning (Markdown) when it says more than the help

    @property
    def name(self) -> str:
        """The flag a message names: the long one, or the metavar of the positional argument."""
        return self.flags[-1] if self.flags else (self.metavar or "")

    @property
    def value_name(self) -> str:
        """What --help calls its value: the metavar, or the flag as argparse names it (--max-coast MAX_COAST;
        the field's name may differ: max_coast_s)."""
        return self.metavar or self.name.lstrip("-").replace("-", "_").upper()


def option(default: object, *flags: str, help: str = "", **spec: typing.Any) -> typing.Any:
    """A dataclass field declaring its command-line option (see Spec for the keywords)."""
    if isinstance(default, list | dict | set):
        raise TypeError("option defaults are immutable: use a tuple")
    if spec.get("section", "command") not in SECTIONS:
        raise ValueError(f"section {spec['section']!r}: expected one of {', '.join(SECTIONS)}")
    return dataclasses.field(default=default, metadata={"option": Spec(tuple(flags), help, **spec)})


def declared(options_cls: type) -> Iterator[tuple[dataclasses.Field, Spec, type]]:
    """Each declared field of an options class with its Spec and its value type (``float`` for ``float |
    None``, ``str`` for ``tuple[str, ...]``), by section and then in declaration order."""
    hints = typing.get_type_hints(options_cls)
    fields = [(f, f.metadata["option"]) for f in dataclasses.fields(options_cls) if "option" in f.metadata]
    for f, spec in sorted(fields, key=lambda item: SECTIONS.index(item[1].section)):
        yield f, spec, _value_type(hints[f.name])


def _value_type(hint: object) -> type:
    """The type of one value of a field annotated ``hint``: Optional and tuples unwrapped."""
    args = [a for a in typing.get_args(hint) if a is not type(None) and a is not Ellipsis]
    if args:
        return _value_type(args[0])
    return hint if isinstance(hint, type) else str


# ---------------------------------------------------------------------------------------------------------
# argparse


def date_argument(text: str) -> dt.date:
    """--date: a YYYY-MM-DD day, else argparse's usage error."""
    try:
        return dt.date.fromisoformat(text)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(f"not a date (YYYY-MM-DD): {text!r}") from exc


def edition_argument(text: str) -> str:
    """--edition: CAT=EDITION with the category as a number ("21=0.26"), else argparse's usage error."""
    cat, sep, ed = text.partition("=")
    if not sep or not cat.strip().isdigit() or not ed:
        raise argparse.ArgumentTypeError(f"expected CAT=EDITION (e.g. 21=0.26 or 21=auto), got {text!r}")
    return f"{int(cat)}={ed.strip()}"


def add_options(parser: argparse.ArgumentParser, options_cls: type) -> None:
    """Add the declared options of ``options_cls`` to ``parser`` (declared's order); a group's flags go into
    one required mutually exclusive group. An option left out stays None in the namespace (from_args then
    takes the field's default)."""
    groups: dict[str, typing.Any] = {}
    for f, spec, kind in declared(options_cls):
        target = parser
        if spec.group is not None:
            if spec.group not in groups:
                groups[spec.group] = parser.add_mutually_exclusive_group(required=True)
            target = groups[spec.group]
        target.add_argument(*(spec.flags or (f.name,)), **_argparse_keywords(f, spec, kind))


def _argparse_keywords(f: dataclasses.Field, spec: Spec, kind: type) -> dict[str, object]:
    """add_argument's keywords for one field."""
    if not spec.flags:  # the positional argument: one or more values (or none: Spec.optional)
        return {"nargs": "*" if spec.optional else "+", "metavar": spec.metavar, "help": spec.help or None}
    kw: dict[str, object] = {"dest": f.name, "help": _with_default(spec.help, f.default)}
    if kind is bool:
        return kw | {"action": "store_true"}
    value_type = spec.parse or (kind if kind in (int, float) else None)
    if value_type is not None:
        kw["type"] = value_type
    if spec.choices is not None and spec.parser_choices:
        kw["choices"] = list(spec.choices)  # its usage shows them
    else:
        kw["metavar"] = spec.value_name
    if spec.required:
        kw["required"] = True
    kw["action"] = "append" if spec.repeat else _Once
    return kw


class _Once(argparse.Action):
    """An option that takes one value: given twice it is refused (``--area A --area B`` is not their union,
    and keeping the last silently would evaluate another area than the user meant)."""

    def __call__(self, parser, namespace, values, option_string=None):
        before = getattr(namespace, self.dest, None)
        if before is not None:
            parser.error(f"{option_string} given twice ({_shown(before)} and {_shown(values)}): give it once")
        setattr(namespace, self.dest, values)


def _shown(value: object) -> str:
    """A parsed option value as a user would write it: a date as 2019-03-01, not datetime.date(2019, 3, 1);
    text quoted."""
    if isinstance(value, str):
        return repr(value)
    if isinstance(value, float):
        return f"{value:g}"
    iso = getattr(value, "isoformat", None)
    return iso() if callable(iso) else str(value)


def _with_default(text: str | None, default: object) -> str | None:
    """An option's help with its default, where it has one worth saying and the help does not say it."""
    if not text or default in (None, False, (), dataclasses.MISSING):
        return text
    shown = f"{default:g}" if isinstance(default, float) else str(default)
    if "default" in text or text.endswith(f"({shown})"):
        return text
    return f"{text} (default: {shown})"


def from_args(options_cls: type, args: argparse.Namespace, **extra: object) -> typing.Any:
    """The options object of a parsed command line: every declared option given (repeated flags and the
    inputs as tuples; those left out take the field's default), then ``extra``."""
    values: dict[str, object] = {}
    for f, _, _ in declared(options_cls):
        value = getattr(args, f.name, None)
        if value is not None:
            values[f.name] = tuple(value) if isinstance(value, list) else value
    return options_cls(**values | extra)


def command_args(options: object, **changed: object) -> list[str]:
    """The command-line arguments that give ``options`` (with ``changed`` fields replaced): every declared
    option that differs from its default, then the inputs; from_args of them parses back to the same
    options."""
    values = dataclasses.replace(options, **changed) if changed else options  # type: ignore[type-var]
    args: list[str] = []
    for f, spec, kind in declared(type(values)):
        value = getattr(values, f.name)
        if not spec.flags or value == f.default or value is None:
            continue
        flag = spec.flags[-1]
        if kind is bool:
            args += [flag] if value else []
        elif spec.repeat:
            args += [a for item in value for a in (flag, str(item))]
        elif isinstance(value, tuple):
            args += [flag, ",".join(_arg_text(v) for v in value)]
        else:
            args += [flag, _arg_text(value)]
    return [str(p) for p in getattr(values, "inputs", ())] + args


def _arg_text(value: object) -> str:
    """One option value as typed: dates ISO, floats short but exact (20, 0.1, 0.123456789)."""
    if isinstance(value, dt.date):
        return value.isoformat()
    if isinstance(value, float):
        return f"{value:g}" if float(f"{value:g}") == value else repr(value)
    return str(value)


# ---------------------------------------------------------------------------------------------------------
# Checks


def check_declared(options: object) -> None:
    """Every declared range and choice of ``options`` holds (each item of a tuple), else OptionError naming
    the option. Unset (None) options are not checked, but None for one that cannot be unset is refused."""
    hints = typing.get_type_hints(type(options))
    for f, spec, kind in declared(type(options)):
        value = getattr(options, f.name)
        if value is None and f.default is not None and type(None) not in typing.get_args(hints[f.name]):
            raise OptionError(f"{spec.name} None: must be given a value (leave it out for the default "
                              f"{_shown(f.default)})")
        if value is None or isinstance(value, dict):  # a dict: editions as {category: edition}
            continue
        items = value if isinstance(value, tuple | list) else (value,)
        for item in items:
            if kind is bool and not isinstance(item, bool):  # "no" would read as true
                raise OptionError(f"{spec.name} {item!r}: must be True or False, not {type(item).__name__}")
            if kind is str and isinstance(item, numbers.Number):  # sensors=5 failed in os.fspath
                raise OptionError(f"{spec.name} {item!r}: expected text (a path, a name or a value), not "
                                  f"{type(item).__name__}")
            if spec.range is not None and kind is int:
                check_integer(spec.name, item, int(spec.range[0]), int(spec.range[1]))
            elif spec.range is not None:
                check_number(spec.name, item, *spec.range, f" {spec.unit}" if spec.unit else "")
            if spec.choices is not None and item not in spec.choices:
                raise OptionError(f"{spec.name} {item!r}: must be {_one_of(spec.choices)}")


def _one_of(choices: tuple) -> str:
    """'a or b', 'one of a, b, c'."""
    names = [str(c) for c in choices]
    return " or ".join(names) if len(names) == 2 else f"one of {', '.join(names)}"


def check_installed(option: str, what: str, modules: tuple[str, ...], extra: str) -> None:
    """OptionError naming ``option`` when a package ``what`` needs is not installed (looked up, not
    imported), before anything is read: an optional extra found missing after decoding cost the run."""
    import importlib.util

    missing = [m for m in modules if importlib.util.find_spec(m) is None]
    if missing:
        verb = "is" if len(missing) == 1 else "are"
        raise OptionError(f"{option}: {what} needs {' and '.join(missing)}, which {verb} not installed: "
                          f"pip install 'msdc[{extra}]'")


def check_number(name: str, value: float | None, lo: float, hi: float, unit: str = "") -> None:
    """A finite number within [lo, hi], else OptionError naming the option."""
    if value is None:
        return
    if not isinstance(value, int | float) or not math.isfinite(value) or not lo <= value <= hi:
        raise OptionError(f"{name} {value!r}: must be a finite number from {lo:g} to {hi:g}{unit}")


def check_integer(name: str, value: int | None, lo: int, hi: int) -> None:
    """An integer within [lo, hi], else OptionError naming the option."""
    if value is not None and not (isinstance(value, int) and lo <= value <= hi):
        raise OptionError(f"{name} {value!r}: must be an integer from {lo} to {hi}")


# ---------------------------------------------------------------------------------------------------------
# The options of each command

class OneOrMany:
    """Base of every options class: a repeatable or positional option given one value (a path, a query, an
    id, a category number) is that value alone, and a tuple option given None or a list its default or the
    list's tuple, as ``read()`` takes them (a string was read letter by letter: --udp '1')."""

    def __post_init__(self) -> None:
        for f in dataclasses.fields(self):
            spec = f.metadata.get("option")
            if spec is None or not isinstance(f.default, tuple):
                continue
            value = getattr(self, f.name)
            one = spec.repeat or not spec.flags  # else a text is comma-separated (--sources, --horizon)
            if value is None:
                value = f.default
            elif isinstance(value, list):
                value = tuple(value)
            elif isinstance(value, numbers.Number) or (one and isinstance(value, str | Path | dt.date)):
                value = (value,)
            object.__setattr__(self, f.name, value)


SENSORS_HELP = "sensor positions (TOML [[sensor]] tables)"
SENSORS_OPTIONAL_HELP = ("sensor positions (TOML [[sensor]] tables); needed when radar plots are used, "
                         "not for ADS-B alone")


def adsb_sigma_option(used: str, doc: str = "") -> typing.Any:
    """--adsb-sigma: the accuracy the user declares for ADS-B reports that carry no NACp; ``used`` says what
    the command uses it for."""
    return option(None, "--adsb-sigma", metavar="M", range=ADSB_SIGMA_RANGE_M, unit="m",
                  section="measurements", doc=doc,
                  help="1-sigma position error per axis (m, 0.5-20000) declared for ADS-B reports without "
                       f"NACp (CAT021 0.2x: its figure of merit is not read as NACp){used}; reports with "
                       "NACp keep theirs, NACp 0 (unknown) stays untracked. Without it such reports are "
                       "not tracked")


@dataclass(frozen=True)
class DecodingOptions(OneOrMany):
    """How to read the inputs (shared by every job)."""

    inputs: tuple[str, ...] = option((), metavar="INPUT", section="selection",
                                     doc="the recordings")
    from_time: str | None = option(
        None, "--from", metavar="TIME", section="selection",
        help="read only reports at or after this UTC time: an ISO date-time (2023-05-02T08:10:00) or a time "
             "of day (08:10, 08:10:30.5) on the recording's day",
        doc="read only reports at or after this UTC time: an ISO date-time (`2023-05-02T08:10:00`, `Z` or "
            "`+00:00` allowed) or a time of day (`08:10`, `08:10:30.5`) on the recording's day "
            "([Selecting reports](selection.md))")
    to_time: str | None = option(
        None, "--to", metavar="TIME", section="selection",
        help="read only reports before this UTC time (as --from; --to itself is left out)",
        doc="read only reports before this UTC time, written as `--from` (the instant itself is left out: "
            "consecutive windows share no report) ([Selecting reports](selection.md))")
    area: str | None = option(
        None, "--area", metavar="AREA", section="selection",
        help="read only reports inside this area: a GeoJSON file of polygons, or SENSOR:A-Bnm:C-Ddeg, a "
             "slant range and azimuth window of a sensor in --sensors (e.g. 20/129:0-60nm:30-120deg)",
        doc="read only reports inside this area: a GeoJSON file (`.geojson`, `.json`) of Polygons or "
            "MultiPolygons, or `SENSOR:A-Bnm:C-Ddeg`, slant range A to B NM and azimuth C to D degrees "
            "clockwise from north from the site of SENSOR in `--sensors` (e.g. `20/129:0-60nm:30-120deg`; "
            "`300-60deg` wraps through north) ([Selecting reports](selection.md))")
    fl: str | None = option(
        None, "--fl", metavar="MIN:MAX", section="selection",
        help="read only reports whose own flight level is from MIN to MAX (e.g. 100:245, 245: or :100); "
             "reports without one are left out",
        doc="read only reports whose own flight level is from MIN to MAX, both included (`100:245`, `245:`, "
            "`:100`); a report without a flight level is left out ([Selecting reports](selection.md))")
    sensor_ids: tuple[str, ...] = option(
        (), "--sensor", repeat=True, metavar="ID", section="selection",
        help="read only this sensor's reports (repeatable): SAC/SIC (every category), CCC:SAC/SIC or "
             "010:SAC/SIC:mlat, as the outputs' sensor_id names it",
        doc="read only this sensor's reports (repeatable): `SAC/SIC` (any category), `CCC:SAC/SIC` (e.g. "
            "`048:20/129`) or `010:SAC/SIC:mlat`, as the outputs' `sensor_id` names it "
            "([Selecting reports](selection.md))")
    editions: tuple[str, ...] = option(  # "CAT=EDITION"
        (), "--edition", repeat=True, parse=edition_argument, metavar="CAT=ED", section="reading",
        help="pin a category edition, e.g. 21=0.26 or 48=1.27 (repeatable; a category whose editions walk "
             "differently, CAT021, is read with auto unless pinned)",
        doc="pin a category edition, e.g. `21=0.26` or `48=1.27` (repeatable); a category whose editions "
            "walk differently (CAT021) is read with `auto` unless pinned "
            "([Editions](../decoding/editions.md))")
    date: dt.date | None = option(
        None, "--date", parse=date_argument, section="reading",
        help="UTC day (YYYY-MM-DD) of a recording that carries no date (raw, final, gps, oradis)")
    format: str | None = option(None, "--format", choices=FORMATS, section="reading",
                                help="container format (default: detected)",
                                doc="container format (default: detected; "
                                    "[Containers](../decoding/containers.md))")
    sensors: str | None = option(None, "--sensors", section="selection",
                                 help="sensor positions (TOML [[sensor]] tables); needed by --area with a "
                                      "sensor window or radar plots",
                                 doc="the sensors' positions ([the sensor file](sensors.md)); needed by "
                                     "`--area` with a sensor window, or to place radar plots in a polygon")


@dataclass(frozen=True)
class DecodeOptions(DecodingOptions):
    """Everything ``decode_job`` needs."""

    output: str | None = option(None, "-o", "--output", section="output",
                                help="OUT.csv or OUT.parquet (one file per category: stem_cat048...)")
    categories: tuple[int, ...] = option((), "--category", repeat=True, choices=CATEGORIES,
                                         help="only this category (repeatable; default: the measurement "
                                              "categories 48, 21, 10 and 20)",
                                         doc="decode only this category, any msdc decodes (repeatable: "
                                             "`--category 62 --category 63`); without it the measurement "
                                             "categories CAT048, CAT021, CAT010 and CAT020 are decoded")
    strict: bool = option(False, "--strict", help="stop at the first bad block")
    lenient: bool = option(False, "--lenient",
                           help="write what decodes even when an input is mostly not ASTERIX or its records "
                                "implausible (said as a warning; else an error, nothing written)",
                           doc="write what decodes even when an input is mostly not ASTERIX or its records "
                               "implausible (said as a warning; else an error and nothing is written: "
                               "[Bad input](../decoding/bad-input.md#not-asterix))")
    chunk_mb: float = option(64.0, "--chunk-mb", range=CHUNK_RANGE_MB, unit="MB",
                             help="streaming chunk size (MB)")


@dataclass(frozen=True)
class DatasetOptions(OneOrMany):
    """--dataset: a dataset made by ``msdc ingest`` as the input instead of recordings, declared once for
    the commands that read one (listed first among a command's bases, so that its inputs keep their place;
    ``jobs.common.check_decoding`` opens it)."""

    inputs: tuple[str, ...] = option((), metavar="INPUT", section="selection", optional=True,
                                     help="the recordings (or --dataset)", doc="the recordings")
    dataset: str | None = option(
        None, "--dataset", metavar="DIR", section="selection",
        help="read a dataset made by 'msdc ingest' instead of INPUT files: only its committed parts, and "
             "only the days, categories and sensors --from/--to and --sensor can keep",
        doc="read a dataset made by `msdc ingest` instead of INPUT files: only the parts its manifest lists, "
            "and only the partitions `--from`/`--to` (given as date-times) and `--sensor` can keep "
            "([Large recordings](large-recordings.md#the-jobs-on-a-dataset))")
    scheduler: str | None = option(
        None, "--scheduler", metavar="ADDRESS", section="selection",
        help="where the per-aircraft and per-partition work runs: 'local' (the default with --dataset: a "
             "Dask cluster of --workers processes on this machine), 'none' (threads in this process, the "
             "default on recordings) or a Dask scheduler's address tcp://HOST:PORT",
        doc="where the per-aircraft and per-partition work runs: `local` (the default with `--dataset`: a "
            "Dask LocalCluster of `--workers` processes on this machine), `none` (threads in this process, "
            "the default on recordings) or the address of a running Dask scheduler, `tcp://HOST:PORT` "
            "([Large recordings](large-recordings.md#on-a-cluster))")
    workers: int | None = option(None, "--workers", metavar="N", range=WORKERS_RANGE, section="selection",
                                 help="worker processes of the local Dask cluster (default: the machine's "
                                      "cores)")


@dataclass(frozen=True)
class StatsOptions(DatasetOptions, DecodingOptions):
    """Everything ``stats_job`` needs."""

    chunk_mb: float = option(64.0, "--chunk-mb", range=CHUNK_RANGE_MB, unit="MB",  # peak memory follows it
                             help="streaming chunk size (MB); memory follows it, not the file")


@dataclass(frozen=True)
class AircraftOptions(DatasetOptions, DecodingOptions):
    """Inputs, the sensor file and the aircraft selection (call sign, address or all); the outputs and
    --adsb-sigma, whose help each command words, are declared by the commands."""

    sensors: str | None = option(None, "--sensors", section="selection", help=SENSORS_OPTIONAL_HELP,
                                 doc="the radars' positions and sigmas ([the sensor file](sensors.md)); not "
                                     "needed for ADS-B alone")
    callsign: str | None = option(None, "--callsign", group="aircraft", section="selection",
                                  help="call sign (case and spaces ignored)")
    address: str | None = option(None, "--address", group="aircraft", section="selection",
                                 help="24-bit aircraft address in hex")
    all_aircraft: bool = option(False, "--all", group="aircraft", section="selection", help="every aircraft")
    output: str | None = None
    json: str | None = None
    adsb_sigma_m: float | None = None  # declared sigma (m per axis) for ADS-B reports without NACp


ADSB_SIGMA_DOC = ("ADS-B sigma for reports without NACp, used by {used} "
                  "([track](track.md#ads-b-without-nacp-adsb-sigma))")


def _indicator_gate(flag: str, indicator: str, *, reference_only: bool = False) -> typing.Any:
    """An ADS-B quality-indicator minimum (0 to 11): reports below it dropped (correlate, quality), or only
    left out of the reference (evaluate: the reports under test keep theirs)."""
    if not reference_only:
        said = f"drop ADS-B reports with {indicator} below N"
        return option(None, flag, range=INDICATOR_RANGE, section="measurements", help=said,
                      doc=f"{said} ([filters](quality.md#filters))")
    said = f"leave ADS-B reports with {indicator} below N out of the reference"
    return option(None, flag, range=INDICATOR_RANGE, section="measurements", help=said,
                  doc=f"{said} (the reports under test keep theirs; [reference gates](../methods/evaluate.md"
                      "#how-msdc-builds-the-reference))")


@dataclass(frozen=True)
class ReferenceFilterOptions(OneOrMany):
    """The ADS-B report filters (pipeline.quality.filters), declared once for the commands that take them:
    correlate (before slotting) and quality (the reference of radar accuracy and biases); evaluate
    redeclares their help (its reference gates: the reports under test keep theirs). Listed first among a
    command's bases, so that its inputs keep their place."""

    drop_jumps: bool = option(False, "--drop-jumps", section="measurements",
                              help="remove detected ADS-B position jumps first",
                              doc="remove detected ADS-B position jumps (correlate: before slotting; "
                                  "quality: from the reference) (off by default, so the thesis numbers stay "
                                  "reproducible; [filters](quality.md#filters))")
    min_nic: int | None = _indicator_gate("--min-nic", "NUCp/NIC")
    min_nacp: int | None = _indicator_gate("--min-nacp", "NACp")


@dataclass(frozen=True)
class CorrelateOptions(ReferenceFilterOptions, AircraftOptions):
    """Everything ``correlate_job`` needs; see ``msdc correlate --help`` for the meaning of each option."""

    sensors: str | None = option(None, "--sensors", required=True, section="selection", help=SENSORS_HELP,
                                 doc="the radars' positions ([the sensor file](sensors.md))")
    all_aircraft: bool = option(False, "--all", group="aircraft", section="selection",
                                help="every aircraft seen by both sensors")
    output: str | None = option(None, "-o", "--output", section="output",
                                help="Excel report (.xlsx); the track figure is written beside it",
                                doc="the workbook (`.xlsx`), with the track figure `report_tracks.png` "
                                    "beside it ([Report](#report))")
    json: str | None = option(None, "--json", section="output", help="window summary as JSON",
                              doc="the windows as JSON ([JSON](#json))")
    slot_s: float = option(10.0, "--slot", range=SLOT_RANGE_S, unit="s",
                           help="slot width D in seconds (default 10)", doc="slot width D in seconds")
    gap_s: float = option(180.0, "--gap", range=GAP_RANGE_S, unit="s",
                          help="gap G in seconds that ends a period (180)",
                          doc="a sensor's track is split where consecutive measurements are more than G "
                              "seconds apart")
    pairs: str = option("radar-adsb", "--pairs", choices=PAIRS,
                        help="sensor pairs to correlate per aircraft: each radar against ADS-B (default), "
                             "each two radars, all (both), multilateration against ADS-B, or surface "
                             "radar against multilateration; plots of two radars are never mixed",
                        doc="`radar-adsb` (each radar against the ADS-B source), `radar-radar` (each two "
                            "radars that saw the aircraft), `all` (both), `mlat-adsb` (each "
                            "multilateration system against ADS-B) or `smr-mlat` (each surface movement "
                            "radar against multilateration); plots of two sensors are never mixed "
                            "([sensor pairs](../methods/correlation.md#sensor-pairs))")
    split_adsb: bool = option(False, "--split-adsb",
                              help="keep ADS-B ground stations apart (default: one ADS-B source per "
                                   "aircraft)",
                              doc="keep ADS-B ground stations apart (default: one ADS-B source per aircraft "
                                  "after deduplication)")
    quality: bool = option(False, "--quality",
                           help="add the quality sheets (Quality, Update intervals, Gaps, Jumps, ADS-B "
                                "quality, Radar accuracy, Radar biases, Figures) and their PNGs",
                           doc="add the quality sheets and their PNGs ([quality](quality.md)) and the "
                               "slotting and lag figures per window")
    fill: str = option("hold", "--fill", choices=FILLS,
                       help="empty slots: hold the previous slot (default, the thesis) or take the tracker's "
                            "prediction",
                       doc="empty slots: `hold` the previous slot's value (the thesis) or `predict` the "
                           "sensor's own track ([Filling empty "
                           "slots](#filling-empty-slots-with-the-tracker))")
    tables: str = option("auto", "--tables", choices=TABLE_MODES,
                         help="slot and lag tables: in the workbook (xlsx), as STEM_slots.parquet and "
                              "STEM_correlation.parquet beside it (parquet), or Parquet past 5,000 rows "
                              "(auto)",
                         doc="slot and lag tables in the workbook (`xlsx`), as Parquet beside it "
                             "(`parquet`), or Parquet past 5,000 rows (`auto`; [Long tables go to "
                             "Parquet](#long-tables-go-to-parquet))")
    adsb_sigma_m: float | None = adsb_sigma_option("; used by --fill predict",
                                                   ADSB_SIGMA_DOC.format(used="`--fill predict`"))


@dataclass(frozen=True)
class QualityOptions(ReferenceFilterOptions, AircraftOptions):
    """Everything ``quality_job`` needs."""

    output: str | None = option(None, "-o", "--output", section="output",
                                help="Excel workbook (.xlsx); figures are written beside it",
                                doc="the workbook (`.xlsx`), with its figures as PNGs beside it "
                                    "([Workbook](#workbook))")
    json: str | None = option(None, "--json", section="output", help="the tables as JSON")
    gap_s: float = option(180.0, "--gap", range=GAP_RANGE_S, unit="s",
                          help="gap in seconds reported as a discontinuity (180)",
                          doc="a gap in seconds reported as a discontinuity")
    reference: str = option("adsb", "--reference", choices=REFERENCES,
                            help="radar accuracy against ADS-B interpolated linearly (default) or against "
                                 "the smoothed ADS-B-only IMM track",
                            doc="radar accuracy against ADS-B interpolated linearly (`adsb`) or against the "
                                "smoothed ADS-B-only IMM track (`track`; [Against a tracked "
                                "reference](#against-a-tracked-reference))")
    adsb_sigma_m: float | None = adsb_sigma_option("; used by --reference track",
                                                   ADSB_SIGMA_DOC.format(used="`--reference track`"))


MAX_COAST_HELP = "seconds a track is predicted after its last report before it ends (default 60)"



@dataclass(frozen=True)
class TrackOptions(AircraftOptions):
    """Everything ``track_job`` needs; see ``msdc track --help`` for the meaning of each option. The
    inputs, sensor file, aircraft selection and outputs are the other jobs'."""

    output: str | None = option(None, "-o", "--output", section="output",
                                help="track table: tracks.csv or tracks.parquet",
                                doc="the track table: CSV or Parquet ([The track table](#the-track-table))")
    json: str | None = option(None, "--json", section="output",
                              help="per-aircraft and per-sensor summary as JSON",
                              doc="the per-aircraft and per-sensor summary ([JSON and "
                                  "terminal](#json-and-terminal))")
    figures: str | None = option(None, "--figures", metavar="DIR", section="tracking",
                                 help="one PNG per aircraft in this directory",
                                 doc="one PNG per aircraft in DIR (`track_<callsign>_<id>.png`)")
    figures_limit: int = option(
        FIGURES_LIMIT, "--figures-limit", metavar="N", range=FIGURES_LIMIT_RANGE, section="tracking",
        help=f"draw at most N figures (default {FIGURES_LIMIT}; 0: all); the others are listed in "
             "DIR/figures_not_drawn.txt with the command that draws each",
        doc=f"draw at most N figures: the first N aircraft in the order of their ids (`track`) or alert "
            f"events in the Alerts table's order (`conflicts`) (default {FIGURES_LIMIT}, about 10 s on two "
            "cores; `0`: all); the others are listed in `DIR/figures_not_drawn.txt`, each with the "
            "command that draws it ([How many figures](track.md#how-many-figures))")
    figures_only: str | None = option(
        None, "--figures-only", metavar="NAMES", section="tracking",
        help="draw only these figures, comma-separated file names (as figures_not_drawn.txt lists them); "
             "--figures-limit does not apply",
        doc="draw only these figures: their file names, comma-separated, with or without `.png` (as "
            "`figures_not_drawn.txt` lists them); `--figures-limit` does not apply "
            "([How many figures](track.md#how-many-figures))")
    step_s: float = option(
        1.0, "--step", range=STEP_RANGE_S, unit="s", section="tracking",
        help="output grid in seconds (default 1)",
        doc="output grid in seconds (whole multiples of S since UTC midnight), plus one row per report "
            "time; after decoding, a run whose tracks would need more than 4,000,000 rows (about 570 bytes "
            "each in memory; for `conflicts` also its predictions, grid rows times horizons) is refused "
            "naming `--step`")
    max_coast_s: float = option(60.0, "--max-coast", unit="s", section="tracking", help=MAX_COAST_HELP,
                                doc="seconds predicted after the last report before the segment ends "
                                    "(from `--step` to 86400)")
    smooth: bool = option(False, "--smooth", section="tracking",
                          help="backward (RTS) pass: reference trajectories",
                          doc="a backward (RTS) pass: reference trajectories instead of real-time estimates")
    smoother: str = option(  # with smooth: "rts" (combined estimate) or "imm" (two-filter IMM smoother)
        "rts", "--smoother", choices=SMOOTHERS, section="tracking",
        help="implies --smooth: RTS on the combined estimate (default) or the IMM smoother (smoothed mode "
             "probabilities too; better on straight legs, worse in most manoeuvres in our validations)",
        doc="implies `--smooth`: `rts` (RTS on the combined estimate) or `imm` (an IMM smoother: also "
            "smooths the mode probabilities; better on straight legs, worse in most manoeuvres in our "
            "validations: [Tracker](../tracker.md))")
    tpm: str | None = option(  # None: the tracker's default (expm:150,20)
        None, "--tpm", section="tracking",
        help="mode transition law: fixed:P, dynamic, dynamic:A,B or expm:TAU[,TAU2] (default expm:150,20)",
        doc="mode transition law: `expm:150,20` (default: mean 150 s in CV, 20 s in a turn), `fixed:P`, "
            "`dynamic` (the dynamic-TPM paper's p(T)), `dynamic:A,B`; p(T) = min(0.995, A − B·T) must stay "
            "above 0 for every interval up to `--max-coast` (the paper's law ends at 200 s), sojourn times "
            "run from 0.01 s to 10⁷ s. `expm:82,45` ties the best fixed p at every manoeuvre peak of the "
            "paper's 3-radar scenario, where the default loses one by 10 %, but predicts worse through gaps "
            "(real data: +17-32 % at 30-60 s): [Tracker](../tracker.md)")
    sources: tuple[str, ...] = option(SOURCES, "--sources", section="tracking",
                                      help="sensor kinds to fuse, comma-separated: radar, adsb (the default "
                                           "radar,adsb), mlat (multilateration), smr (surface radar)",
                                      doc="which sensor kinds to fuse, comma-separated: `radar`, `adsb` (the "
                                          "default `radar,adsb`), `mlat` (multilateration, CAT010/CAT020), "
                                          "`smr` (surface movement radar, CAT010)")
    noise: str = option(  # pipeline.track.noise estimates; "declared": as given
        "estimate", "--noise", choices=NOISE, parser_choices=False, section="tracking",
        help="measurement noise: estimate (default: each sensor's sigmas from the tracker's residuals, a few "
             "extra passes), timing (the same, and an ADS-B along-track time-stamp sigma) or declared (the "
             "sensor file's sigmas, ADS-B from NACp)",
        doc="`estimate`: each sensor's sigmas measured from the tracker's own residuals before the final "
            "pass (ADS-B on the surface, below 50 kt, apart from airborne; multilateration and surface radar "
            "also stationary, below 1 kt, apart; never below the rounding of the item the positions are "
            "written in; raised where the gate would "
            "reject more than 1 % of the residuals, per class and, on the surface, per aircraft); `timing`: "
            "the same, and for ADS-B an along-track time-stamp sigma (R = σ²I + σₜ² v vᵀ, v the report's own "
            "ground vector; fewer gated reports and track segments on the real recording, gap predictions "
            "no better on the mean: [Tracker](../tracker.md)); `declared`: the sensor file's sigmas and NACp "
            "as they are ([Measurement noise](../methods/tracking.md#measurement-noise))")
    adsb_sigma_m: float | None = adsb_sigma_option(
        "; with --noise estimate it is then refined from the residuals",
        "1-sigma position error per axis (m) declared for ADS-B reports that carry no NACp, such as CAT021 "
        "0.2x ([ADS-B without NACp](track.md#ads-b-without-nacp-adsb-sigma)); reports with NACp keep theirs; "
        "with `--noise estimate` it is only the starting value")


@dataclass(frozen=True)
class SelectionOptions(OneOrMany):
    """Which aircraft samples an analysis counts (``pipeline.model.selection``), declared once: ``msdc
    conflicts`` takes them, and a command that analyses the same traffic inherits them (listed first among
    its bases, so that its inputs keep their place). ``jobs.common.check_selection`` makes the Selection."""

    min_fl: float | None = option(
        None, "--min-fl", metavar="FL", range=MIN_FL_RANGE, unit="FL", section="selection",
        help="count only aircraft samples at or above this flight level (the tracked level; a sample "
             "without one is left out)",
        doc="count only aircraft samples at or above this flight level (the tracked level at the time; a "
            "sample without a level is left out) ([Selection](#selection))")
    exclude_mode_a_only: bool = option(
        False, "--exclude-mode-a-only", section="selection",
        help="leave out Mode-A-only targets: no report gave them a 24-bit address or a call sign",
        doc="leave out Mode-A-only targets (`M3A:` identities: no report gave them a 24-bit address or a "
            "call sign) ([Selection](#selection))")
    exclude_codes: str | tuple[str, ...] | None = option(
        None, "--exclude-codes", metavar="CODES", section="selection",
        help="leave out aircraft while they squawk one of these Mode 3/A codes, comma-separated (e.g. "
             "7000 and the VFR conspicuity codes of the airspace)",
        doc="leave out aircraft while they squawk one of these Mode 3/A codes, comma-separated four octal "
            "digits (e.g. `7000`, `2000`, the airspace's VFR conspicuity codes) ([Selection](#selection))")


@dataclass(frozen=True)
class ConflictOptions(SelectionOptions, TrackOptions):
    """Everything ``conflict_job`` needs; see ``msdc conflicts --help``. Every aircraft is tracked."""

    callsign: str | None = None
    address: str | None = None
    all_aircraft: bool = True
    output: str | None = option(None, "-o", "--output", required=True, section="output",
                                help="conflicts.csv (losses and warning times beside it) or conflicts.xlsx",
                                doc="the tables: `conflicts.csv` (losses and warning times beside it) or "
                                    "`conflicts.xlsx` ([Outputs](#outputs))")
    json: str | None = option(None, "--json", section="output", help="counts and the tables as JSON",
                              doc="counts and the tables as JSON ([Outputs](#outputs))")
    figures: str | None = option(None, "--figures", metavar="DIR", section="tracking",
                                 help="one PNG per alert event in this directory",
                                 doc="one PNG per alert event in DIR ([Outputs](#outputs))")
    step_s: float = option(1.0, "--step", range=STEP_RANGE_S, unit="s", section="tracking",
                           help="output step in seconds (default 1)",
                           doc="output step in seconds; the bound on output rows (as "
                               "[track's](track.md#options)) counts the predictions too (grid rows times "
                               "horizons)")
    smooth: bool = False
    smoother: str = "rts"
    tpm: str | None = option(None, "--tpm", section="tracking",
                             help="mode transition law of the IMM (default expm:150,20)",
                             doc="mode transition law of the IMM: `expm:150,20` (default: mean 150 s in CV, "
                                 "20 s in a turn) or another, as [track's](track.md#options)")
    noise: str = option(  # the conflict validations used declared noise; "estimate" as msdc track
        "declared", "--noise", choices=NOISE, parser_choices=False, section="tracking",
        help="measurement noise: declared (default: the sensor file's sigmas, ADS-B from NACp or "
             "--adsb-sigma; what the conflict validations used), estimate or timing (each sensor's sigmas "
             "from the tracker's residuals first, as msdc track)",
        doc="`declared`: the sensor file's sigmas, ADS-B from NACp or `--adsb-sigma` (what the conflict "
            "validations and the calibration benchmark used); `estimate` or `timing`: each sensor's sigmas "
            "from the tracker's residuals first, as `msdc track` ([Measurement "
            "noise](../methods/tracking.md#measurement-noise))")
    horizons_s: tuple[float, ...] = option((20.0, 60.0, 120.0), "--horizon", parse=str,
                                           range=HORIZON_RANGE_S, unit="s",
                                           help="look-aheads in seconds (default 20,60,120)",
                                           doc="look-aheads in seconds, comma-separated, whole multiples "
                                               "of `--step`")
    radius_nm: float = option(5.0, "--radius-nm", range=RADIUS_RANGE_NM, unit="NM",
                              help="horizontal separation minimum (default 5)",
                              doc="horizontal separation minimum")
    vertical_ft: float = option(1000.0, "--vertical-ft", range=VERTICAL_RANGE_FT, unit="ft",
                                help="vertical separation minimum (default 1000)",
                                doc="vertical separation minimum")
    vertical_tolerance_ft: float = option(
        25.0, "--vertical-tolerance-ft", range=VERTICAL_TOLERANCE_RANGE_FT, unit="ft",
        help="levels closer than --vertical-ft by at most this are separated: the 25 ft quantum of reported "
             "levels (default 25)",
        doc="levels closer than `--vertical-ft` by at most this are separated: the 25 ft quantum of "
            "reported levels; less than `--vertical-ft`")
    max_report_gap_s: float = option(
        15.0, "--max-report-gap", range=REPORT_GAP_RANGE_S, unit="s",
        help="losses of separation are measured only where both aircraft are reported: between two reports "
             "of a track at most this many seconds apart (default 15), never on a coasted stretch",
        doc="losses of separation are measured only where both aircraft are reported: between two reports "
            "of a track at most this many seconds apart, at positions interpolated between them; never on "
            "a coasted stretch ([What a loss is](#what-the-tables-count))")
    threshold: float = option(0.2, "--threshold", help="PC above which an alert is raised (default 0.2)",
                              doc="PC above which an alert is raised, strictly between 0 and 1")
    method: str = option("exact", "--method", choices=METHODS, parser_choices=False,
                         help="PC method: exact (default), one-block, blocks or midpoint",
                         doc="PC method ([Conflict analysis](../conflict.md))")
    vertical: str = option(  # "gaussian": PC times P(|dz| < vertical_ft) from the vertical filter's sigma
        "gate", "--vertical", choices=VERTICAL_MODELS, parser_choices=False,
        help="vertical proximity: gate (predicted levels closer than --vertical-ft, default) or gaussian (PC "
             "times the probability from the vertical filter's sigma)",
        doc="vertical proximity: `gate` (predicted levels closer than `--vertical-ft`) or `gaussian` (PC "
            "times the probability from the vertical filter's sigma; [Conflicts]"
            "(../methods/conflicts.md#vertical-proximity))")
    surface: str = option(  # pairs with an aircraft on the surface out of losses and alerts; or "include"
        "exclude", "--surface", choices=SURFACE_MODES, parser_choices=False,
        help="pairs with an aircraft on the aerodrome surface (as its reports say, else below 50 kt): "
             "exclude (default: separation minima apply between airborne aircraft) or include them in the "
             "losses and alerts; counted either way",
        doc="pairs with an aircraft on the aerodrome surface: `exclude` (separation minima apply between "
            "airborne aircraft) or `include` them in the losses and alerts; counted either way ([Aircraft "
            "on the surface](#aircraft-on-the-surface))")


REFERENCE_BUILDS = ("leave-one-out", "adsb")  # evaluate --reference (build_reference)
WINDOW_RANGE_MIN = (1.0, 44_640.0)  # evaluate --window: a minute to 31 days
SIL_RANGE = (0, 3)


@dataclass(frozen=True)
class EvaluateOptions(ReferenceFilterOptions, DatasetOptions, DecodingOptions):
    """Everything ``evaluate_job`` needs; see ``msdc evaluate --help``. Every aircraft is evaluated."""

    sensors: str | None = option(None, "--sensors", required=True, section="selection", help=SENSORS_HELP,
                                 doc="the sensors' positions and optional coverage limits ([the sensor "
                                     "file](sensors.md))")
    preset: str | None = option(None, "--preset", required=True, metavar="NAME|FILE", section="command",
                                help="the standard's requirements: a shipped preset (eurocontrol-1997-ssr, "
                                     "ed117a, ...; see docs) or a TOML file of your own",
                                doc="the standard's requirements: a shipped preset by name or a TOML file "
                                    "of your own ([Presets](../methods/evaluate.md#presets-the-standards-"
                                    "as-data))")
    sectors: str | None = option(None, "--sectors", metavar="FILE", section="command",
                                 help="GeoJSON sectors (name, optional area and flight-level band): every "
                                      "figure is also given per sector, and a preset's area requirements on "
                                      "the sectors of that area",
                                 doc="GeoJSON sectors: every figure is also given per sector, and a "
                                     "requirement with an `area` on the sectors of that area ([Sectors]"
                                     "(sectors.md))")
    reference: str = option("leave-one-out", "--reference", choices=REFERENCE_BUILDS, section="command",
                            help="the reference: every other sensor tracked and smoothed (leave-one-out, "
                                 "default) or ADS-B alone",
                            doc="`leave-one-out`: per aircraft the smoothed IMM track of every sensor but "
                                "the one under test; `adsb`: of ADS-B alone ([The reference]"
                                "(../methods/evaluate.md#how-msdc-builds-the-reference))")
    reference_file: str | None = option(None, "--reference-file", metavar="CSV", section="command",
                                        help="an external reference instead (time, latitude, longitude, "
                                             "altitude per aircraft, e.g. a flight trial's GPS)",
                                        doc="an external reference instead of a built one ([How msdc builds "
                                            "the reference](../methods/evaluate.md#how-msdc-builds-the-"
                                            "reference))")
    test_sensors: tuple[str, ...] = option(
        (), "--test", repeat=True, metavar="ID", section="command",
        help="judge only this sensor (repeatable; as the outputs' sensor_id names it); the others still "
             "build the reference. Default: every sensor the preset applies to",
        doc="judge only this sensor (repeatable: `048:20/129`); the others still build the reference. "
            "Default: every sensor the preset applies to")
    window_minutes: float | None = option(
        None, "--window", metavar="MINUTES", range=WINDOW_RANGE_MIN, unit="min", section="command",
        help="evaluate the --from/--to span window by window, each of MINUTES read with its margin, and pool "
             "the windows' figures: memory stays about that of one window over a day",
        doc="evaluate the `--from`/`--to` span window by window, each of MINUTES (the last may be shorter) "
            "read with its margin as `--from`/`--to` of it alone would be, and pool the windows' figures: "
            "memory stays about that of one window over a day; on a Dask cluster each window is a task of "
            "its own, the windows side by side; the outputs add a scorecard per window "
            "([A long span, window by window](#a-long-span-window-by-window))")
    drop_jumps: bool = option(False, "--drop-jumps", section="measurements",
                              help="leave detected ADS-B position jumps out of the reference",
                              doc="leave detected ADS-B position jumps out of the reference (the reports "
                                  "under test keep theirs; [reference gates](../methods/evaluate.md#how-"
                                  "msdc-builds-the-reference))")
    min_nic: int | None = _indicator_gate("--min-nic", "NUCp/NIC", reference_only=True)
    min_nacp: int | None = _indicator_gate("--min-nacp", "NACp", reference_only=True)
    min_sil: int | None = option(None, "--min-sil", range=SIL_RANGE, section="measurements",
                                 help="leave ADS-B reports with SIL below N out of the reference",
                                 doc="leave ADS-B reports with SIL below N out of the reference")
    output: str | None = option(None, "-o", "--output", section="output",
                                help="the workbook (.xlsx): the scorecard first, then the tables",
                                doc="the workbook (`.xlsx`): the scorecard first, then the tables "
                                    "([Outputs](evaluate-outputs.md))")
    json: str | None = option(None, "--json", section="output",
                              help="the results and the tables as JSON (the map: --html)",
                              doc="the results and the tables as JSON, the map points left to the HTML "
                                  "report ([JSON](evaluate-outputs.md#json))")
    html: str | None = option(None, "--html", section="output",
                              help="one self-contained HTML report (works offline)",
                              doc="one self-contained HTML report, working offline ([HTML]"
                                  "(evaluate-outputs.md#html))")
    adsb_sigma_m: float | None = adsb_sigma_option("; used by the reference",
                                                   ADSB_SIGMA_DOC.format(used="the reference"))
    sources: str = "radar,adsb,mlat,smr"  # every sensor kind is read
    max_coast_s: float = 60.0  # the reference tracker's (build_reference)


@dataclass(frozen=True)
class IngestOptions(OneOrMany):
    """Everything ``ingest_job`` needs."""

    inputs: tuple[str, ...] = option((), metavar="INPUT", section="selection", doc="the recordings")
    dataset: str | None = option(None, "--dataset", metavar="DIR", required=True, section="output",
                                 help="the dataset folder (made if absent; an existing one is added to)")
    workers: int = option(1, "--workers", metavar="N", range=WORKERS_RANGE, section="command",
                          help="processes: with at least N inputs to ingest, each ingests whole inputs; "
                               "else a raw recording's windows are decoded in parallel (the rows are those "
                               "of one process)")
    categories: tuple[int, ...] = option((), "--category", repeat=True, choices=CATEGORIES,
                                         help="only this category (repeatable; default: every category "
                                              "msdc decodes but CAT001)",
                                         doc="ingest only this category (repeatable); without it every "
                                             "category msdc decodes but CAT001 is ingested, the service "
                                             "messages and system tracks the jobs on a dataset read included")
    lenient: bool = option(False, "--lenient",
                           help="ingest what decodes even when an input is mostly not ASTERIX (said as a "
                                "warning; else an error and that input is not ingested)")
    chunk_mb: float = option(8.0, "--chunk-mb", range=CHUNK_RANGE_MB, unit="MB",  # ~50 MB of memory a MB
                             help="streaming chunk size (MB): the memory of each process follows it")
    editions: tuple[str, ...] = option(
        (), "--edition", repeat=True, parse=edition_argument, metavar="CAT=ED", section="reading",
        help="pin a category edition, e.g. 21=0.26 or 48=1.27 (repeatable)",
        doc="pin a category edition, e.g. `21=0.26` or `48=1.27` (repeatable; "
            "[Editions](../decoding/editions.md))")
    date: dt.date | None = option(
        None, "--date", parse=date_argument, section="reading",
        help="UTC day (YYYY-MM-DD) of a recording that carries no date (raw, final, gps, oradis): needed, "
             "the partitions are UTC days")
    format: str | None = option(None, "--format", choices=FORMATS, section="reading",
                                help="container format (default: detected)",
                                doc="container format (default: detected; "
                                    "[Containers](../decoding/containers.md))")


@dataclass(frozen=True)
class SqlOptions(OneOrMany):
    """Everything ``sql_job`` needs."""

    query: tuple[str, ...] = option((), metavar="SQL", section="selection",
                                    doc="a DuckDB query over the views `cat048`, `cat021`... (one per "
                                        "category; several words are joined by spaces)")
    dataset: str | None = option(None, "--dataset", metavar="DIR", required=True, section="selection",
                                 help="the dataset folder ('msdc ingest' makes it)")
    output: str | None = option(None, "-o", "--output", section="output",
                                help="OUT.csv or OUT.parquet (default: a table on the terminal)")
    limit: int = option(50, "--limit", metavar="N", range=(1, 1_000_000), section="output",
                        help="rows printed on the terminal at most (-o writes every row)")


QUEUE_RANGE = (1, 10_000_000)  # listen --queue: datagrams waiting per feed
DURATION_RANGE_S = (0.1, 1e7)
SPEED_RANGE = (0.001, 1e6)  # replay --speed: a 3 h recording in 10 ms at most
TTL_RANGE = (0, 255)
ALARM_FRACTION_RANGE = (0.0, 1.0)
ALARM_SECONDS_RANGE = (1.0, 86400.0)
_T = Thresholds  # the monitor's alarm thresholds: their defaults are said in the listen options' help


@dataclass(frozen=True)
class ListenOptions(OneOrMany):
    """Everything ``listen_job`` needs (docs/guide/live.md)."""

    udp: tuple[str, ...] = option(
        (), "--udp", repeat=True, metavar="ADDR:PORT", required=True, section="selection",
        help="a feed: a multicast group (joined) or a unicast address of this machine, and a UDP port "
             "(repeatable: one receiving thread per feed)")
    iface: str | None = option(
        None, "--iface", metavar="IP", section="selection",
        help="the IPv4 address of the interface the multicast groups are joined on (default: the kernel's "
             "choice by its routes)")
    sensors: str | None = option(None, "--sensors", section="selection",
                                 help="sensor positions (TOML [[sensor]] tables): places radar plots on the "
                                      "monitor page (without it they are counted, shown without position)",
                                 doc="sensor positions ([the sensor file](sensors.md)): radar plots get "
                                     "their latitude and longitude for the monitor page; without it they "
                                     "are counted and shown without a position")
    record: str | None = option(
        None, "--record", metavar="DIR", section="output",
        help="record every datagram received, byte for byte, as pcapng files in DIR (made if absent)")
    dataset: str | None = option(
        None, "--dataset", metavar="DIR", section="output",
        help="also ingest each recording file, once closed, into this dataset ('msdc ingest' layout); needs "
             "--record",
        doc="also ingest each recording file, once closed (every `--rotate` and at the end), into this "
            "dataset, as `msdc ingest` does ([ingest](ingest.md)); needs `--record`")
    rotate: str = option(
        "1h", "--rotate", metavar="EVERY", section="output",
        help="start a new recording file every period (30s, 15m, 1h, 1d: aligned to the UTC clock) or at a "
             "size (500MB, 2GB)")
    http: str | None = option(
        None, "--http", metavar="HOST:PORT", section="output",
        help="serve the monitor page at http://HOST:PORT (e.g. 127.0.0.1:8080)")
    alarm_silent_s: float | None = option(
        None, "--alarm-silent", metavar="SECONDS", range=ALARM_SECONDS_RANGE, unit="s", section="output",
        help=f"monitor: a sensor with no report for this long is silent (default: {_T.silent_s:g} s)")
    alarm_min_pd: float | None = option(
        None, "--alarm-min-pd", metavar="P", range=ALARM_FRACTION_RANGE, section="output",
        help=f"monitor: a live probability of update below this is degraded (default: {_T.min_pd:g})")
    alarm_min_mode3a_valid: float | None = option(
        None, "--alarm-min-mode3a-valid", metavar="P", range=ALARM_FRACTION_RANGE, section="output",
        help=f"monitor: a share of valid Mode 3/A codes below this raises an alarm (default: "
             f"{_T.min_mode3a_valid:g})")
    alarm_min_modec_valid: float | None = option(
        None, "--alarm-min-modec-valid", metavar="P", range=ALARM_FRACTION_RANGE, section="output",
        help=f"monitor: a share of valid Mode C codes below this raises an alarm (default: "
             f"{_T.min_modec_valid:g})")
    window_s: float | None = option(
        None, "--window", metavar="SECONDS", range=ALARM_SECONDS_RANGE, unit="s", section="output",
        help=f"monitor: the sliding window of the live figures (default: {_T.window_s:g} s)")
    queue: int = option(
        50_000, "--queue", metavar="N", range=QUEUE_RANGE,
        help="datagrams each feed's queue holds while the decoding thread catches up; when full, datagrams "
             "are dropped, counted and said")
    duration_s: float | None = option(
        None, "--duration", metavar="SECONDS", range=DURATION_RANGE_S, unit="s",
        help="stop after this many seconds (default: run until Ctrl-C)")
    editions: tuple[str, ...] = option(
        (), "--edition", repeat=True, parse=edition_argument, metavar="CAT=ED", section="reading",
        help="pin a category edition, e.g. 21=0.26 or 48=1.27 (repeatable)",
        doc="pin a category edition, e.g. `21=0.26` or `48=1.27` (repeatable; "
            "[Editions](../decoding/editions.md))")


@dataclass(frozen=True)
class ReplayOptions(OneOrMany):
    """Everything ``replay_job`` needs (docs/guide/live.md)."""

    inputs: tuple[str, ...] = option((), metavar="RECORDING", section="selection",
                                     doc="the recordings (raw, pcap, pcapng, final, gps), merged by time")
    to: str | None = option(
        None, "--to", metavar="ADDR:PORT", required=True, section="output",
        help="where the datagrams go: a multicast group or a unicast address, and a UDP port")
    iface: str | None = option(
        None, "--iface", metavar="IP", section="output",
        help="the IPv4 address of the interface the datagrams leave from (multicast: IP_MULTICAST_IF)")
    ttl: int = option(1, "--ttl", metavar="N", range=TTL_RANGE, section="output",
                      help="multicast time to live (0: this machine only; 1: the local network)")
    speed: float = option(1.0, "--speed", metavar="X", range=SPEED_RANGE,
                          help="how many times faster than recorded (10: a 3 h recording in 18 min)")
    loop: bool = option(False, "--loop", help="start again at the end (until Ctrl-C or --duration)")
    duration_s: float | None = option(
        None, "--duration", metavar="SECONDS", range=DURATION_RANGE_S, unit="s",
        help="stop after this many seconds (default: at the end of the recordings, or never with --loop)")
    format: str | None = option(None, "--format", choices=REPLAYED_FORMATS, section="reading",
                                help="container format (default: detected)",
                                doc="container format (default: detected; "
                                    "[Containers](../decoding/containers.md))")


# the options of each command, in the order msdc --help lists the commands
COMMAND_OPTIONS: dict[str, type] = {"decode": DecodeOptions, "stats": StatsOptions,
                                    "correlate": CorrelateOptions, "quality": QualityOptions,
                                    "track": TrackOptions, "conflicts": ConflictOptions,
                                    "evaluate": EvaluateOptions, "ingest": IngestOptions,
                                    "sql": SqlOptions, "listen": ListenOptions, "replay": ReplayOptions}
# the guide page holding a command's options table, when not docs/guide/COMMAND.md
COMMAND_PAGES = {"listen": "live", "replay": "live"}


# ---------------------------------------------------------------------------------------------------------
# The docs: each command's options table in docs/guide/COMMAND.md, between its markers

GUIDE = Path(__file__).resolve().parents[2] / "docs" / "guide"  # in a checkout
TABLE_START, TABLE_END = "<!-- options: {command} -->", "<!-- /options -->"
_NUMBERS = {float: "number", int: "integer"}


def options_table(options_cls: type) -> str:
    """The options of a job as a Markdown table (option, values, default, meaning), then a line per group
    of which one option is required."""
    rows = ["| option | values | default | meaning |", "|---|---|---|---|"]
    groups: dict[str, list[str]] = {}
    for f, spec, kind in declared(options_cls):
        flags = ", ".join(f"`{flag}`" for flag in spec.flags) or f"`{spec.metavar}`"
        meaning = (spec.doc or spec.help).replace("|", "\\|")
        rows.append(f"| {flags} | {_values(spec, kind)} | {_default(f, spec)} | {meaning} |")
        if spec.group is not None:
            groups.setdefault(spec.group, []).append(f"`{spec.name}`")
    notes = [f"\nExactly one of {', '.join(names[:-1])} and {names[-1]} is required."
             for names in groups.values()]
    return "\n".join(rows + notes) + "\n"


def _values(spec: Spec, kind: type) -> str:
    """What an option takes, for the docs table."""
    unit = f" {spec.unit}" if spec.unit else ""
    if not spec.flags:
        return "one or more, or none with `--dataset`" if spec.optional else "one or more"
    if kind is bool:
        return "flag"
    if spec.choices is not None:
        values = ", ".join(f"`{c}`" for c in spec.choices)
    elif spec.range is not None:  # an integer's bounds in digits: "1e+07" is no value --queue takes
        lo, hi = spec.range
        values = f"{lo} to {hi}{unit}" if kind is int else f"{lo:g} to {hi:g}{unit}"
    elif kind in (float, int):
        values = _NUMBERS[kind] + (f" ({spec.unit})" if spec.unit else "")
    else:
        values = spec.value_name
    return values + (", repeatable" if spec.repeat else "")


def _default(f: dataclasses.Field, spec: Spec) -> str:
    """An option's default for the docs table: "required", or the value as given on the command line."""
    if spec.required:
        return "required"
    value = f.default
    if value is None or value is False or value == ():
        return ""
    items = value if isinstance(value, tuple) else (value,)
    return "`" + ",".join(f"{v:g}" if isinstance(v, float) else str(v) for v in items) + "`"


def page_with_table(text: str, command: str) -> str:
    """A guide page's text with the options table of ``command`` between its markers (ValueError when the
    page lacks them)."""
    start, end = TABLE_START.format(command=command), TABLE_END
    head, found, rest = text.partition(start)
    if not found or end not in rest:
        raise ValueError(f"no {start} ... {end} markers")
    return f"{head}{start}\n{options_table(COMMAND_OPTIONS[command])}{end}{rest.partition(end)[2]}"


def write_docs(guide: Path = GUIDE, *, check: bool = False) -> list[Path]:
    """Rewrite the options table of every command's guide page (``check``: only say which differ); the
    pages that differed."""
    stale = []
    for command in COMMAND_OPTIONS:
        page = guide / f"{COMMAND_PAGES.get(command, command)}.md"
        text = page.read_text()
        new = page_with_table(text, command)
        if new != text:
            if page not in stale:
                stale.append(page)
            if not check:
                page.write_text(new)
    return stale


def main(argv: list[str] | None = None) -> int:
    """``python -m msdc.pipeline.jobs.options --write-docs`` (or ``--check``): the guide's options tables."""
    parser = argparse.ArgumentParser(prog="python -m msdc.pipeline.jobs.options", description=main.__doc__)
    what = parser.add_mutually_exclusive_group(required=True)
    what.add_argument("--write-docs", action="store_true", help="rewrite the tables that differ")
    what.add_argument("--check", action="store_true", help="list the pages whose table differs (exit 1)")
    check = parser.parse_args(argv).check
    stale = write_docs(check=check)
    for page in stale:
        print(f"{page}: {'differs from the declared options' if check else 'rewritten'}")
    return 1 if stale and check else 0


if __name__ == "__main__":
    sys.exit(main())
