"""Read several recordings into one frame per category, with their provenance (SHA-256, format)."""

from __future__ import annotations

import datetime as dt
import hashlib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

import msdc.asterix as asterix
from msdc.asterix.reader import Recording
from msdc.asterix.verdict import Tally, head_of
from msdc.pipeline.model.heap import release_free_memory
from msdc.pipeline.model.odd_sources import drop_odd_sources, odd_source_texts
from msdc.pipeline.model.sources import file_labels, pair_codes, pair_of, path_text, source_id
from msdc.pipeline.model.time import NAT_NS, UNDATED_DAY, DayTally, absolute_time
from msdc.pipeline.progress import Progress

# Measurement jobs decode their inputs in chunks of about this many bytes: the decoded columns of one chunk
# are turned into measurement rows and dropped before the next is read, so a recording of any size never
# has all its decoded columns in memory at once (a file up to this size is decoded in one piece).
MEASUREMENT_CHUNK_BYTES = 32_000_000

Span = tuple[pd.Timestamp, pd.Timestamp]


@dataclass
class Loaded:
    """Frames of all inputs by category, the recordings they came from (their errors, editions and counts:
    their own frames are let go once joined into ``frames``), and what each input was."""

    frames: dict[int, pd.DataFrame]
    recordings: list[Recording]
    inputs: list[dict] = field(default_factory=list)
    date: dt.date | None = None
    spans: list[dict[str, Span]] | None = None  # per input: earliest and latest instant per data source
    warnings: list[str] = field(default_factory=list)  # about the data, e.g. reports left out as damaged
    # CAT048 records of SAC/SIC pairs the sensor table lacks, left out (sensors.undeclared_radars' table)
    stray_radar: pd.DataFrame = field(default_factory=pd.DataFrame)
    # CAT010/CAT020 reports with Cartesian positions and no reference point, left out
    # (multilateration.UNPLACED_COLUMNS, for measurements.unplaced_verdict)
    unplaced: pd.DataFrame = field(default_factory=pd.DataFrame)
    # the report selection's record (pipeline.model.report_selection.recorded), None when none was given
    selection: dict | None = None
    # the reports cut beyond the window's margin before the measurements were finished (report_selection.
    # MarginCut), None when no time window was given
    cut: object | None = None
    # per input (as ``inputs``): blocks per category of the file that the load did not decode (a CAT001
    # radar's plots given to a command reading CAT048), {} for a dataset's input
    unread: list[dict[int, int]] = field(default_factory=list)

    @property
    def errors(self) -> pd.DataFrame:
        """Every input's skipped-bytes account, one frame."""
        frames = [r.errors for r in self.recordings if len(r.errors)]
        return pd.concat(frames, ignore_index=True) if frames else self.recordings[0].errors.iloc[:0]

    def drop_frames(self) -> None:
        """Free the decoded frames (each input's and their concatenation) once the measurements are built
        from them; the inputs, errors, editions and date stay."""
        self.frames = {}
        for rec in self.recordings:
            rec.frames = {}

    @property
    def editions(self) -> dict[int, str]:
        out: dict[int, str] = {}
        for r in self.recordings:
            out.update(r.editions)
        return out


def sha256(path: Path, chunk: int = 1 << 20) -> str:
    """Hex SHA-256 of a file, read in chunks."""
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        while block := fh.read(chunk):
            h.update(block)
    return h.hexdigest()


def _concat(parts: list[pd.DataFrame]) -> pd.DataFrame:
    """Concatenate frames of one category, keeping text columns categorical with merged labels."""
    if len(parts) == 1:
        return parts[0]
    cats = [c for c in parts[0].columns if isinstance(parts[0][c].dtype, pd.CategoricalDtype)]
    labels = {c: pd.Index(sorted(set().union(*(p[c].cat.categories for p in parts))), dtype=object)
              for c in cats}
    parts = [p.assign(**{c: p[c].cat.set_categories(labels[c]) for c in cats}) for p in parts]
    return pd.concat(parts, ignore_index=True)


def input_paths(paths) -> list[Path]:
    """The input paths as a list: one str or Path is one input (not a sequence of characters); TypeError for
    what is neither a path nor a sequence of paths."""
    if isinstance(paths, str | Path):
        return [Path(paths)]
    if not hasattr(paths, "__iter__") or isinstance(paths, bytes):
        raise TypeError(f"paths {paths!r}: give a recording's path or a list of paths")
    out = []
    for p in paths:
        if not isinstance(p, str | Path):
            raise TypeError(f"paths: {p!r} is not a path (str or pathlib.Path)")
        out.append(Path(p))
    return out


def _digests(paths: list[Path]) -> list[str]:
    """Each input's SHA-256; ValueError when two inputs hold the same content (its records would count
    twice: every report a duplicate, every rate doubled)."""
    digests, seen = [], {}
    for p in paths:
        digest = sha256(p)
        if digest in seen:
            raise ValueError(f"paths: {p} has the same content as {seen[digest]} (SHA-256); give each "
                             "recording once")
        seen[digest] = p
        digests.append(digest)
    return digests


def check_dataset(dataset: object) -> None:
    """TypeError for a ``dataset`` argument that is not a dataset's inputs (read by its records and parts)."""
    if not (hasattr(dataset, "records") and hasattr(dataset, "touched")):
        raise TypeError(f"dataset {dataset!r:.40}: not a dataset's inputs ({type(dataset).__name__}); give "
                        "pipeline.dataset.inputs.open_inputs(folder) of a folder msdc ingest wrote")


def load(paths: list[str | Path] | str | Path, *, editions=None, date=None, format: str | None = None,
         categories=None, columns=None, progress: Progress | None = None, dataset=None) -> Loaded:
    """Decode every input into one frame per category, each row tagged with its file (``columns``: only
    those decoded columns, see asterix.read). ``paths``: one path or a list; ValueError when two hold the
    same content. A likely wrong edition is said by asterix.read's ``asterix.EditionWarning``.

    Records keep their own ``timestamp``; ``Loaded.date`` (the earliest known date) dates the records of
    inputs that have none (pipeline.model.time.absolute_time).

    ``dataset`` (pipeline.dataset.inputs.DatasetInputs): its inputs are read from the dataset's parts
    instead (``paths``, ``editions``, ``date`` and ``format`` unused: the ingest applied them).
    """
    if dataset is not None:
        return _load_dataset(dataset, categories, columns, progress)
    paths = input_paths(paths)
    recs: list[Recording] = []
    inputs: list[dict] = []
    unread: list[dict[int, int]] = []
    warnings: list[str] = []
    digests = _digests(paths)
    labels = file_labels(paths)
    for i, p in enumerate(paths):
        if progress:
            progress.step(f"{p.name} ({i + 1}/{len(paths)})")
        rec = asterix.read(p, editions=editions, date=date, format=format, categories=categories,
                           columns=columns)
        recs.append(rec)
        content = Tally(str(p))
        content.add(rec)
        warnings += content.warnings(head_of(p), hint=False, detected=format is None)
        tally = DayTally()
        tally.add(rec.frames)
        warnings += tally.warning(labels[i], rec.date, rec.format)
        inputs.append({"path": path_text(p), "sha256": digests[i], "bytes": rec.size_bytes,
                       "format": rec.format, "records": {int(c): len(f) for c, f in rec.frames.items()},
                       "skipped_blocks": len(rec.errors), "editions": dict(rec.editions)})
        unread.append(dict(sorted((int(c), int(n)) for c, n in rec.ignored_blocks.items())))
    dates = [r.date for r in recs if r.date is not None]
    first = min(dates) if dates else None
    unsourced: list[pd.DataFrame] = []
    frames, spans = _joined(recs, labels, first, unsourced)
    warnings += odd_source_texts(pd.concat(unsourced, ignore_index=True) if unsourced else None)
    return Loaded(frames, recs, inputs, first, spans, warnings=warnings, unread=unread)


def _joined(recs: list[Recording], labels: list[str], date: dt.date | None,
            unsourced: list[pd.DataFrame] | None = None
            ) -> tuple[dict[int, pd.DataFrame], list[dict[str, Span]]]:
    """Each category's records of every input in one frame (its ``file`` column added) and each input's
    time spans (time_spans, undated records on ``date``); each recording's frames are let go once copied,
    so the records are held once, not twice (its errors, editions and counts stay). Records naming another
    data source than their block are left out, their rows added to ``unsourced`` (odd_sources)."""
    by_cat: dict[int, list[pd.DataFrame]] = {}
    spans = []
    for label, rec in zip(labels, recs, strict=True):
        drop_odd_sources(rec.frames, label, [] if unsourced is None else unsourced)
        spans.append(time_spans(rec.frames, date))
        for cat, frame in rec.frames.items():
            by_cat.setdefault(cat, []).append(frame.assign(file=_label_column(label, len(frame))))
        rec.frames = {}
    frames = {cat: _concat(parts) for cat, parts in by_cat.items()}
    del by_cat
    release_free_memory()
    return frames, spans


def _label_column(label: str, n: int) -> pd.Categorical:
    """``n`` rows of one text label as a categorical, from codes (no list of ``n`` strings to factorize);
    no rows: no category, as pandas makes of an empty list."""
    if not n:
        return pd.Categorical([])
    return pd.Categorical.from_codes(np.zeros(n, np.int8), categories=pd.Index([label]))


def _load_dataset(dataset, categories, columns, progress: Progress | None) -> Loaded:
    """``load`` of a dataset's inputs (pipeline.dataset.inputs.DatasetInputs): those with a part the run
    reads (an input of other days, sensors or categories is neither listed in the outputs nor dates the
    run; all of them when none has), in ingest order."""
    check_dataset(dataset)
    read = _touched(dataset, categories)
    paths, recs, inputs = dataset.paths, [], []
    for n, i in enumerate(read):
        if progress:
            progress.step(f"{paths[i].name} ({n + 1}/{len(read)})")
        recs.append(dataset.read(i, categories=categories, columns=columns))
        inputs.append(dataset_info(dataset, i, recs[-1]))
    dates = [r.date for r in recs if r.date is not None]
    first = min(dates) if dates else None
    unsourced: list[pd.DataFrame] = []
    frames, spans = _joined(recs, [dataset.labels[i] for i in read], first, unsourced)
    warnings = odd_source_texts(pd.concat(unsourced, ignore_index=True) if unsourced else None)
    return Loaded(frames, recs, inputs, first, spans, warnings=warnings)


def _touched(dataset, categories=None) -> list[int]:
    """The dataset's inputs with a part the run reads, in ingest order (all of them when none has: an
    input of other days, sensors or categories is neither listed in the outputs nor dates the run)."""
    read = [i for i in range(len(dataset.records)) if dataset.touched(i, categories)]
    return read or list(range(len(dataset.records)))


def dataset_info(dataset, i: int, rec: Recording) -> dict:
    """An input's provenance as ``load`` gives it, from the dataset's manifest (records: those read)."""
    record = dataset.records[i]
    return {"path": record["path"], "sha256": record["sha256"], "bytes": int(record["size_bytes"]),
            "format": record.get("format"), "records": {int(c): len(f) for c, f in rec.frames.items()},
            "skipped_blocks": int(record.get("skipped_blocks", 0)), "editions": dict(rec.editions)}


def time_spans(frames: dict[int, pd.DataFrame], date: dt.date | None) -> dict[str, Span]:
    """Earliest and latest UTC instant per data source ("048:25/201", as the measurements' sensor_id) of
    one input (``date`` dates undated records)."""
    out = {}
    for cat, frame in frames.items():
        ns = absolute_time(frame, date).to_numpy("datetime64[ns]").view("int64")
        ok = ns != NAT_NS
        if not ok.any():
            continue
        none = pd.Series(pd.NA, index=frame.index)
        codes = pair_codes(frame.get("sac", none), frame.get("sic", none))[ok]
        pairs, which = np.unique(codes, return_inverse=True)
        lo, hi = np.full(len(pairs), np.iinfo(np.int64).max), np.full(len(pairs), np.iinfo(np.int64).min)
        np.minimum.at(lo, which, ns[ok])
        np.maximum.at(hi, which, ns[ok])
        for pair, first, last in zip(pairs, lo, hi, strict=True):
            out[source_id(cat, *pair_of(pair))] = (pd.Timestamp(first, tz="UTC"),
                                                   pd.Timestamp(last, tz="UTC"))
    return out


def widen_spans(spans: dict[str, Span], more: dict[str, Span]) -> dict[str, Span]:
    """The spans of two chunks of one input, per data source."""
    out = dict(spans)
    for source, (lo, hi) in more.items():
        out[source] = (min(lo, out[source][0]), max(hi, out[source][1])) if source in out else (lo, hi)
    return out


class NoRecords(LookupError):
    """The inputs hold no record of a category the job needs (of any of ``alternatives``, when given)."""

    def __init__(self, category: int, loaded: Loaded, alternatives: tuple[int, ...] = ()):
        self.category, self.loaded = category, loaded  # what was read: its skipped blocks and editions
        self.alternatives = alternatives or (category,)
        super().__init__(f"no {' or '.join(f'CAT{c:03d}' for c in self.alternatives)} records in the inputs")


# The categories a measurement job needs by default: one of each group (CAT048 radar, CAT021 ADS-B)
RADAR_AND_ADSB: tuple[tuple[int, ...], ...] = ((48,), (21,))


def load_measurements(paths: list[str | Path], sensors: pd.DataFrame, *, editions=None, date=None,
                      format: str | None = None, adsb_sigma_m: float | None = None,
                      chunk: int = MEASUREMENT_CHUNK_BYTES, progress: Progress | None = None,
                      either: bool = False, columns=None,
                      needs: tuple[tuple[int, ...], ...] = RADAR_AND_ADSB, dataset=None, selection=None
                      ) -> tuple[Loaded, pd.DataFrame]:
    """Decode every input in chunks (asterix.iter_read, only DECODED_COLUMNS) straight into measurement
    rows, and join them into one validated measurement frame (rows as build_measurements orders them:
    every input's radar rows, then every input's ADS-B rows, then the CAT010/CAT020 ones). The Loaded has
    no frames but the inputs, errors, editions, date and time spans that ``load`` gives. ``columns``: only
    those measurement columns (a job's narrower frame, see pipeline.model.schema.validate), each chunk's
    rows keeping only what they need; every column when None.

    NoRecords when the inputs hold no record of one of the ``needs`` groups (by default CAT048, and
    CAT021; with ``either``, only when they hold none of any group). Records of a radar the sensor table
    lacks are left out and listed in ``Loaded.stray_radar`` (per pair and file: records, first offset),
    for the job to judge; so are CAT010/CAT020 reports to place from a reference point it lacks
    (``Loaded.unplaced``, measurements.unplaced_verdict). Records
    without a timestamp of their own are dated by ``Loaded.date``, as with ``load``. ``dataset``
    (pipeline.dataset.inputs.DatasetInputs): its inputs are read from the dataset's parts instead, each
    as one chunk (``paths``, ``editions``, ``date`` and ``format`` unused: the ingest applied them).
    ``selection`` (report_selection.ReportSelection): only the rows within its margin of the time window are
    kept (report_selection.MarginCut, in ``Loaded.cut``): chunk by chunk when the window is given as
    instants, so a long recording's rows beyond it are never held; WindowError when it cannot be placed.
    """
    from msdc.pipeline.model.measurements import (
        DECODED_COLUMNS,
        finish_measurements,
        impossible_positions,
        impossible_times,
    )
    from msdc.pipeline.model.report_selection import MarginCut

    recs: list[Recording] = []
    inputs: list[dict] = []
    unread: list[dict[int, int]] = []  # Loaded.unread
    off_earth: list[pd.DataFrame] = []  # the CAT021 reports with a position off the Earth (damaged bytes)
    untimely: list[pd.DataFrame] = []  # records with a time of day outside 0-24 h (damaged bytes)
    unsourced: list[pd.DataFrame] = []  # records naming another data source than their block (damaged bytes)
    spans: list[dict[str, Span]] = []
    dates: list[dt.date | None] = []
    radar: list[tuple[int, pd.DataFrame]] = []  # (input number, rows)
    adsb: list[tuple[int, pd.DataFrame]] = []
    local: list[tuple[int, pd.DataFrame]] = []  # CAT010/CAT020 rows
    unplaced: list[pd.DataFrame] = []  # their reports without a reference point, per chunk
    other_kinds: dict[int, int] = {}  # CAT010 target reports of other kinds, per input (reset below)
    stray: list[pd.DataFrame] = []  # undeclared_radars' table per chunk
    early_start: list[str] = []  # DayTally's warnings
    timed = selection is not None and selection.timed
    cut: MarginCut | None = None  # made at the first dated chunk when the window is given as instants
    if dataset is None:
        paths = input_paths(paths)
        digests = _digests(paths)
        labels = file_labels(paths)
        order = list(range(len(paths)))
    else:
        check_dataset(dataset)
        paths, digests, labels = dataset.paths, dataset.digests, dataset.labels
        order = _touched(dataset)
    for n, i in enumerate(order):  # n: the input's place in the outputs, i: its place in paths
        p = paths[i]
        if progress:
            progress.step(f"{p.name} ({n + 1}/{len(order)})")
        info = {"path": path_text(p), "sha256": digests[i], "bytes": 0, "format": None, "records": {},
                "skipped_blocks": 0, "editions": {}}
        ignored: dict[int, int] = {}
        by_source: dict[str, Span] = {}
        first = True
        tally = DayTally()
        other_kinds = {}
        no_plots: dict = {}  # records measuring no real aircraft, per input (measurements.no_plot_counts)
        content = Tally(str(p))
        chunks = (asterix.iter_read(p, chunk=chunk, editions=editions, date=date, format=format,
                                    columns=DECODED_COLUMNS) if dataset is None
                  else _dataset_chunks(dataset, i, DECODED_COLUMNS))
        for rec in chunks:
            if first:
                dates.append(rec.date)
                first = False
            tally.add(rec.frames)
            content.add(rec)
            info["bytes"], info["format"] = rec.size_bytes, rec.format
            for cat, frame in rec.frames.items():
                info["records"][int(cat)] = info["records"].get(int(cat), 0) + len(frame)
            info["skipped_blocks"] += len(rec.errors)
            info["editions"].update(rec.editions)
            for cat, n in rec.ignored_blocks.items():
                ignored[int(cat)] = ignored.get(int(cat), 0) + int(n)
            frames, rec.frames = rec.frames, {}
            drop_odd_sources(frames, labels[i], unsourced)
            # undated records are placed on UNDATED_DAY here and moved to Loaded.date below
            by_source = widen_spans(by_source, time_spans(frames, None))
            r, a = _rows(frames, labels[i], sensors, adsb_sigma_m, stray, off_earth, no_plots, columns,
                         untimely)
            more = _local_rows(frames, sensors, unplaced, other_kinds, columns)
            del frames
            if timed and selection.placed and dates[-1] is not None:  # an undated input's times move below
                cut = cut or MarginCut(selection, dates[-1])
                r, a = (None if x is None else cut.keep(x) for x in (r, a))
                more = [cut.keep(x) for x in more]
            radar += [(n, r)] if r is not None else []
            adsb += [(n, a)] if a is not None else []
            local += [(n, part) for part in more]
            recs.append(rec)
        if first:  # nothing at all in the file: iter_read yields no chunk
            dates.append(None)
        early_start += tally.warning(labels[i], dates[-1], info["format"])
        from msdc.pipeline.model.multilateration import other_kinds_warning

        early_start += other_kinds_warning(labels[i], other_kinds)
        from msdc.pipeline.model.measurements import no_plot_warning

        early_start += no_plot_warning(no_plots, labels[i])
        if dataset is None:  # a dataset's were said when it was ingested
            early_start += content.warnings(head_of(p), hint=False, detected=format is None)
        else:
            info["skipped_blocks"] = int(dataset.records[i].get("skipped_blocks", 0))
        info["records"] = dict(sorted(info["records"].items()))
        info["editions"] = dict(sorted(info["editions"].items()))
        inputs.append(info)
        unread.append(dict(sorted(ignored.items())))
        spans.append(by_source)
    known = [d for d in dates if d is not None]
    first_date = min(known) if known else None
    if first_date is not None:  # undated inputs are dated by the earliest known date
        shift = pd.Timestamp(first_date, tz="UTC") - UNDATED_DAY
        undated = {i for i, d in enumerate(dates) if d is None}
        for i, part in radar + adsb + local:
            if i in undated and "time" in part:
                part["time"] = part["time"] + shift
        spans = [{c: (lo + shift, hi + shift) for c, (lo, hi) in s.items()} if i in undated else s
                 for i, s in enumerate(spans)]
    held = {cat for info in inputs for cat, n in info["records"].items() if n}
    absent = [group for group in needs if not held & set(group)]
    if absent and not (either and len(absent) < len(needs)):
        raise NoRecords(absent[0][0], Loaded({}, recs, inputs, first_date, spans, early_start, unread=unread),
                        absent[0])
    if timed:  # every row now on its day: the rows an early cut kept pass again untouched
        cut = cut or MarginCut(selection, first_date)
        radar, adsb, local = ([(i, cut.keep(part)) for i, part in group] for group in (radar, adsb, local))
    parts = [part for _, part in radar + adsb + local]
    radar.clear()
    adsb.clear()
    local.clear()
    release_free_memory()  # what the chunks' decoding freed, before the join needs room
    meas = finish_measurements(parts, columns)
    release_free_memory()
    damaged = pd.concat(off_earth, ignore_index=True) if off_earth else None
    warnings = early_start + impossible_positions(damaged) + impossible_times(
        pd.concat(untimely, ignore_index=True) if untimely else None) + odd_source_texts(
        pd.concat(unsourced, ignore_index=True) if unsourced else None)
    stray_radar = _stray_table(stray)
    unplaced_table = _unplaced_table(unplaced)
    return Loaded({}, recs, inputs, first_date, spans, warnings, stray_radar, unplaced_table, cut=cut,
                  unread=unread), meas


def _dataset_chunks(dataset, i: int, columns):
    """Input ``i`` of a dataset as one chunk (its records in file order), none when it holds no record (as
    iter_read yields none for an empty file)."""
    rec = dataset.read(i, columns=columns)
    if rec.frames:
        yield rec


def _unplaced_table(parts: list[pd.DataFrame]) -> pd.DataFrame:
    """The chunks' unplaced CAT010/CAT020 tables as one (records summed, the first offset)."""
    from msdc.pipeline.model.multilateration import UNPLACED_COLUMNS

    if not parts:
        return pd.DataFrame(columns=UNPLACED_COLUMNS)
    table = pd.concat(parts, ignore_index=True)
    groups = table.groupby(["category", "kind", "sac", "sic", "file"], dropna=False, sort=False)
    return groups.agg(records=("records", "sum"), offset=("offset", "first")).reset_index()[UNPLACED_COLUMNS]


def _local_rows(frames: dict[int, pd.DataFrame], sensors: pd.DataFrame, unplaced: list[pd.DataFrame],
                other_kinds: dict[int, int], columns=None) -> list[pd.DataFrame]:
    """The CAT010/CAT020 measurement rows of one decoded chunk (its frames carry ``file`` already, _rows),
    their unplaced reports added to ``unplaced`` and their other kinds counted in ``other_kinds``."""
    from msdc.pipeline.model.measurements import local_measurement_rows

    cat010, cat020 = frames.get(10), frames.get(20)
    if (cat010 is None or not len(cat010)) and (cat020 is None or not len(cat020)):
        return []
    local = local_measurement_rows(cat010, cat020, sensors, columns=columns)
    if len(local.unplaced):
        unplaced.append(local.unplaced)
    for typ, n in local.other_kinds.items():
        other_kinds[typ] = other_kinds.get(typ, 0) + n
    return local.parts


def _stray_table(parts: list[pd.DataFrame]) -> pd.DataFrame:
    """The chunks' undeclared_radars tables as one: per SAC/SIC pair and file, records summed and the first
    offset, in order of first appearance."""
    if not parts:
        return pd.DataFrame(columns=["sac", "sic", "file", "records", "offset"])
    table = pd.concat(parts, ignore_index=True)
    groups = table.groupby(["sac", "sic", "file"], dropna=False, sort=False)
    return groups.agg(records=("records", "sum"), offset=("offset", "first")).reset_index()


def _rows(frames: dict[int, pd.DataFrame], name: str, sensors: pd.DataFrame, adsb_sigma_m: float | None,
          stray: list[pd.DataFrame], off_earth: list[pd.DataFrame], no_plots: dict, columns=None,
          untimely: list[pd.DataFrame] | None = None) -> tuple[pd.DataFrame | None, pd.DataFrame | None]:
    """Measurement rows of one decoded chunk, undated records on UNDATED_DAY; the records of radars the
    sensor table lacks are left out and their undeclared_radars table added to ``stray``, CAT021 reports
    with a position off the Earth (left out of the rows) to ``off_earth``, records of any category with a
    time of day outside 0-24 h to ``untimely``, the records measuring no real aircraft counted in
    ``no_plots``."""
    untimely = [] if untimely is None else untimely
    from msdc.pipeline.model.measurements import (
        impossible_time_rows,
        measurement_rows,
        no_plot_counts,
        off_earth_rows,
    )
    from msdc.pipeline.model.sensors import undeclared_radars

    for frame in frames.values():
        frame["file"] = pd.Categorical.from_codes(np.zeros(len(frame), np.int8), [name])
    bad = off_earth_rows(frames.get(21))
    if len(bad):
        off_earth.append(bad)
    for cat, frame in frames.items():
        late = impossible_time_rows(frame, int(cat))
        if len(late):
            untimely.append(late)
    cat048 = frames.get(48)
    if cat048 is not None and len(cat048):
        unknown = undeclared_radars(cat048, sensors)
        if len(unknown):
            stray.append(unknown)
            keys = pd.MultiIndex.from_arrays([cat048["sac"].astype("Int64"), cat048["sic"].astype("Int64")])
            cat048 = cat048[keys.isin(pd.MultiIndex.from_frame(sensors[["sac", "sic"]].astype("Int64")))]
    no_plot_counts(frames.get(21), 21, no_plot_counts(cat048, 48, no_plots))
    return measurement_rows(cat048, frames.get(21), sensors, adsb_sigma_m=adsb_sigma_m, columns=columns)
