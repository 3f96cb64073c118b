"""The decode job (``msdc decode``): every input streamed in chunks to CSV or Parquet, one file or one per
category, written all or nothing (report.transaction); ``skipped_lines`` lists the skipped blocks for the
terminal."""

from __future__ import annotations

import glob
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import pandas as pd

from msdc.pipeline.jobs.common import (
    Checked,
    JobError,
    check_beside,
    check_decoding,
    date_ignored,
    format_hints,
    no_sensor_kind,
    output_path,
    real_output,
    select_chunk,
    sensor_table,
    spare_inputs,
)
from msdc.pipeline.jobs.options import (
    CATEGORIES,
    DEFAULT_CATEGORIES,
    DecodeOptions,
    check_declared,
)
from msdc.pipeline.model import editions as edition_notes
from msdc.pipeline.model.report_selection import describe, recorded
from msdc.pipeline.model.sources import path_text
from msdc.pipeline.report.files import named, write_csv, write_json
from msdc.pipeline.report.transaction import OutputTransaction, side_pattern, staged

SKIPPED_SHOWN = 20  # skipped blocks decode lists one per line, per input; the rest are counted


def validate(options: DecodeOptions) -> Checked:
    """Check every option and the output paths before any decoding; OptionError if bad."""
    check_declared(options)
    checked = check_decoding(options)
    no_sensor_kind(checked.selection, "decode")
    checked.output = output_path("-o", options.output, (".csv", ".parquet"))
    if checked.output is not None:
        out, base = checked.output, real_output(checked.output)
        spare_inputs(options, [(f"-o {out}", p) for p in (
            out, *(category_output(base, c) for c in CATEGORIES))])
        cats = sorted(set(options.categories or DEFAULT_CATEGORIES))
        # written when several categories decode
        check_beside("-o", out, [(f"CAT{cat:03d} file", category_output(base, cat)) for cat in cats
                                 if len(cats) > 1])
        if checked.selection is not None and checked.selection.active:
            spare_inputs(options, [(f"-o {out}", selection_output(base))])
            check_beside("-o", out, [("selection file", selection_output(base))])
    checked.sensors = None if options.sensors is None else sensor_table(options.sensors)  # for --area
    return checked


@dataclass
class DecodeResult:
    """Records per category, the files written, and every skipped block (path, offset, reason)."""

    counts: dict[int, int]
    outputs: dict[int, Path]
    skipped: list[tuple[str, int, str]]
    warnings: list[str]
    notes: list[str] = field(default_factory=list)
    held: dict[str, dict[int, int]] = field(default_factory=dict)  # per input: data blocks per category
    output: Path | None = None  # -o as validated
    selection: dict | None = None  # what the report selection kept and left out (report_selection.recorded)
    selection_file: Path | None = None  # where it is recorded (selection_output), as -o is given

    def nothing_decoded(self, categories: tuple[int, ...] = ()) -> str:
        """Why no record decoded, naming what each input holds (a --category the inputs lack, most often)."""
        asked = f" with --category {','.join(str(c) for c in categories)}" if categories else ""
        def listed(cats: dict[int, int]) -> str:
            return ", ".join(f"CAT{c:03d} ({n} block(s))" for c, n in sorted(cats.items())) or "no data block"

        holds = "; ".join(f"{path} holds {listed(cats)}" for path, cats in self.held.items())
        from msdc.pipeline.jobs.options import CATEGORIES, DEFAULT_CATEGORIES

        asked_for = categories or DEFAULT_CATEGORIES
        others = sorted({c for cats in self.held.values() for c in cats if c in CATEGORIES} - set(asked_for))
        hint = ("; msdc decodes " + ", ".join(f"CAT{c:03d}" for c in others) + " with "
                + " ".join(f"--category {c}" for c in others)
                + ("" if categories else " (without --category: the measurement categories "
                   + ", ".join(f"CAT{c:03d}" for c in DEFAULT_CATEGORIES) + ")")) if others else ""
        return f"nothing could be decoded{asked}" + (f": {holds}" if holds else "") + hint


def decode_job(options: DecodeOptions, *, on_chunk: Callable[[int, int, str], None] | None = None,
               tx: OutputTransaction | None = None) -> DecodeResult:
    """Stream every input in chunks and write CSV or Parquet: one file, or one per category when records
    of several categories decoded (decided from what decoded, at the end). The files are staged in ``tx``
    (the caller commits it with the rest of its run; without one, a transaction of the job's own is
    committed at the end): a failed or interrupted run writes nothing, nor does a run in which nothing
    decodes. ``on_chunk(done_bytes, size, label)`` reports progress through each pass over a file
    (asterix.iter_read's ``progress``: checking the block chain, framing, decoding). Raises asterix
    DecodeError in strict mode, JobError for unreadable input."""
    import msdc.asterix as asterix
    from msdc.asterix.errors import UnreadableInput
    from msdc.asterix.reader import categories_in
    from msdc.asterix.verdict import Tally, compressed, head_of, sniff
    from msdc.pipeline.model.sources import file_labels
    from msdc.pipeline.model.time import DayTally

    checked = validate(options)
    out = checked.output
    early_start: list[str] = []  # DayTally's warnings
    counts: dict[int, int] = {}
    outputs: dict[int, Path] = {}
    skipped: list[tuple[str, int, str]] = []
    failed: dict[tuple[str, int], edition_notes.Failed] = {}
    notes: list[str] = []
    cats = list(options.categories) or None
    csv = out is not None and out.suffix.lower() == ".csv"
    selection = checked.selection if checked.selection is not None and checked.selection.active else None
    left_out: dict[str, int] = {}
    read = kept = 0
    day = None  # the first dated input's day, recorded with the selection
    content: list[str] = []  # what the inputs turned out to be, when not sound (asterix.verdict)
    sniffed = set()  # inputs said to be not ASTERIX at once (decoded with --lenient)
    odd_records: list[str] = []  # records no real report would be, too few to doubt an input (Tally.notes)
    for path in checked.inputs:  # a file that is not ASTERIX at all is said at once
        try:
            said = sniff(path, options.format)
        except UnreadableInput as exc:
            raise JobError(str(exc), 2) from exc
        if said and not options.lenient:
            if compressed(head_of(path)):  # decoding it anyway is no help: decompressing it is
                raise JobError(f"{said}; nothing written")
            raise JobError(f"{said}; nothing written (--lenient decodes it anyway)")
        if said:
            content.append(said)
            sniffed.add(path)
    with staged(tx) as stage:
        files: dict[int, Path] = {}  # category -> its staged file, named as when several categories decode
        writers: dict[int, object] = {}
        try:
            for path, label in zip(checked.inputs, file_labels(checked.inputs), strict=True):
                size = path.stat().st_size
                chunk = max(int(options.chunk_mb * 1e6), 1)
                tally, date, fmt, chosen, account = DayTally(), None, None, {}, Tally(str(path))
                bar = (lambda done, total, what, name=path.name: on_chunk(done, total, f"{name}: {what}")
                       ) if on_chunk else None
                for rec in asterix.iter_read(path, chunk=chunk, editions=checked.editions or None,
                                             date=options.date, format=options.format, categories=cats,
                                             strict=options.strict, progress=bar):
                    tally.add(rec.frames)
                    account.add(rec)
                    date, fmt, chosen = date or rec.date, rec.format, {**rec.edition_choice, **chosen}
                    if selection is not None:
                        day = day or rec.date
                        n, k = select_chunk(rec, selection, checked.sensors, left_out, path)
                        read, kept = read + n, kept + k
                    skipped += [(str(path), int(e.offset), str(e.reason)) for e in rec.errors.itertuples()]
                    edition_notes.fold(failed, rec)
                    for cat, frame in rec.frames.items():
                        counts[cat] = counts.get(cat, 0) + len(frame)
                        if out is not None and len(frame):
                            if cat not in files:  # named after the file the output really is
                                files[cat] = category_output(stage.path(out), cat)
                            with named(_shown(out, files, cat, stage), instead_of=files[cat]):
                                _write_chunk(files[cat], cat, labelled(frame, label), writers, csv)
                if on_chunk:  # the decoding's bar ends where the last block does: close it at 100 %
                    on_chunk(size, size, f"{path.name}: decoding")
                early_start += tally.warning(label, date, fmt)
                early_start += date_ignored(options, [{"path": path, "format": fmt}])
                notes += [f"{path}: CAT{cat:03d} edition auto {why}" for cat, why in sorted(chosen.items())]
                if path not in sniffed:
                    content += account.warnings(head_of(path), hint=False,  # format_hints says that
                                                detected=options.format is None)
                    odd_records += account.notes()
                early_start += format_hints(options, [{"path": path, "format": fmt, "skipped_blocks": sum(
                    1 for p, _, _ in skipped if p == str(path))}])
        except UnreadableInput as exc:
            raise JobError(str(exc), 2) from exc
        finally:
            for cat, w in writers.items():
                if hasattr(w, "close"):
                    with named(_shown(out, files, cat, stage), instead_of=files[cat]):
                        w.close()
        record = recorded(selection, day, read, kept, left_out) if selection is not None else None
        if record is not None and read and not kept:
            raise JobError(f"{describe(record)}: no record is left to write; nothing written")
        several = len(files) > 1
        for cat in sorted(files):
            outputs[cat] = stage.final(files[cat]) if several else out
            if several:
                notes.append(f"several categories: writing {outputs[cat]}")
            else:  # one category: its file is the output itself
                files[cat].rename(stage.path(out))
        if content and not options.lenient:
            raise JobError("; ".join(content) + "; nothing written (--lenient writes what decodes anyway)")
        side = None
        if record is not None and out is not None and files:
            staged_side = stage.path(out).with_name(selection_output(out).name)
            _write_selection(staged_side, record, options)
            side = stage.final(staged_side)  # named as the data files are
            notes.append(f"selection recorded in {side}")
    held = {} if sum(counts.values()) else {str(p): categories_in(p, format=options.format)
                                              for p in checked.inputs}
    warnings = checked.warnings + content + odd_records + early_start + edition_notes.warnings(failed)
    counts = {cat: n for cat, n in counts.items() if n or selection is None}
    return DecodeResult(counts, outputs, skipped, warnings, notes, held, out, record, side)


def selection_output(out: Path) -> Path:
    """Where decode records its report selection: ``OUT_selection.json`` beside ``OUT``."""
    return out.with_name(f"{out.stem}_selection.json")


def _write_selection(path: Path, record: dict, options: DecodeOptions) -> None:
    """The selection file (written as every JSON output: report.files.write_json): the software, the
    command's selection and what it kept and left out."""
    from msdc.pipeline.meta import software_version

    doc = {"software": f"msdc {software_version()}", "inputs": [str(p) for p in options.inputs],
           "report_selection": record}
    write_json(doc, path)


def category_output(out: Path, cat: int) -> Path:
    """Where decode writes one category's records when several decode: ``OUT_cat048.csv`` beside ``OUT``."""
    return out.with_name(f"{out.stem}_cat{cat:03d}{out.suffix}")


def side_files(output: Path | None) -> list[Path]:
    """The files decode -o ``output`` may write, as globs (report.transaction.left_beside lists those an
    earlier run left): the output itself and the per-category files beside it."""
    if output is None:
        return []
    base = real_output(output)
    return [side_pattern(base, glob.escape(base.suffix)),
            side_pattern(base, f"_cat[0-9][0-9][0-9]{glob.escape(base.suffix)}"),
            side_pattern(base, "_selection.json")]


def _shown(out: Path, files: dict[int, Path], cat: int, stage: OutputTransaction) -> Path:
    """The file an error writing category ``cat`` names: the output while it is the only category."""
    return out if len(files) == 1 else stage.final(files[cat])


def labelled(frame: pd.DataFrame, label: str) -> pd.DataFrame:
    """``frame`` with its input's label as the ``file`` column: categorical, one copy of the text."""
    import numpy as np

    return frame.assign(file=pd.Categorical.from_codes(np.zeros(len(frame), np.int8), categories=[label]))


def _write_chunk(path: Path, cat: int, frame: pd.DataFrame, writers: dict, csv: bool) -> None:
    """Append one chunk of a category to its (staged) output file, CSV or Parquet, opening it on first
    use: every chunk of every input under the category's one schema (report.record_schema), so a later
    chunk or input can neither overflow a type nor put its values under another column's header."""
    from msdc.pipeline.report.record_schema import record_schema

    schema = record_schema(cat)
    rows = schema.conform(frame)
    if csv:
        write_csv(rows, path, append=cat in writers)
        writers[cat] = True
    else:
        import pyarrow as pa
        import pyarrow.parquet as pq

        if cat not in writers:
            writers[cat] = ParquetSink(pq.ParquetWriter(path, schema.arrow()))
        writers[cat].add(pa.Table.from_pandas(rows, schema=writers[cat].writer.schema, preserve_index=False))


ROW_GROUP_BYTES = 32 << 20  # Arrow bytes of chunks gathered into one Parquet row group


class ParquetSink:
    """Chunks of one category gathered into row groups of about ROW_GROUP_BYTES: the writer keeps every row
    group's metadata until it closes (~75 kB a group of 87 columns), so small chunks (--chunk-mb below
    about 1) would each add theirs. An 8 MB chunk of CAT048 (~360 Arrow bytes a record) is a group alone:
    its metadata is what decode's memory still grows by with the file (issue #27 item 6)."""

    def __init__(self, writer) -> None:
        self.writer, self.pending, self.pending_bytes = writer, [], 0

    def add(self, table) -> None:
        """Hold a chunk's rows; write them with those held when they reach ROW_GROUP_BYTES."""
        self.pending.append(table)
        self.pending_bytes += table.nbytes
        if self.pending_bytes >= ROW_GROUP_BYTES:
            self.flush()

    def flush(self) -> None:
        """Write the rows held as one row group."""
        if self.pending:
            import pyarrow as pa

            table = pa.concat_tables(self.pending)
            self.pending, self.pending_bytes = [], 0
            self.writer.write_table(table, row_group_size=max(table.num_rows, 1))

    def close(self) -> None:
        """Write what is held and close the file."""
        try:
            self.flush()
        finally:
            self.writer.close()


def skipped_lines(result: DecodeResult) -> list[str]:
    """The skipped blocks, one line each (path, offset, reason) up to SKIPPED_SHOWN per input, then how many
    more per input."""
    lines, shown = [], {}
    for name, offset, reason in result.skipped:
        path = path_text(name)  # a name that is not UTF-8 as its escape, as every output writes it
        shown[path] = shown.get(path, 0) + 1
        if shown[path] <= SKIPPED_SHOWN:
            lines.append(f"{path}: offset {offset}: {reason}")
    for path, n in shown.items():
        if n > SKIPPED_SHOWN:
            lines.append(f"{path}: {n - SKIPPED_SHOWN} more skipped block(s) ('msdc stats' groups them by "
                         "reason)")
    return lines


__all__ = ["DecodeOptions", "DecodeResult", "category_output", "decode_job", "side_files", "skipped_lines",
           "validate"]
