"""One input's records written into the dataset's partitions: a Parquet part per (day, category, sensor),
written under a hidden temporary name and renamed into place when the input is done, with memory bounded
by a budget of rows held for row groups, not by the input."""

from __future__ import annotations

import datetime as dt
import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from msdc.pipeline.dataset.integrity import part_checksum
from msdc.pipeline.dataset.layout import part_name, partition_dir, relative, sensor_key, temp_path

ROW_GROUP_BYTES = 16 << 20  # Arrow bytes of a partition's rows gathered into one Parquet row group
# ... and at most this span of record timestamps (UTC slots from midnight): a job reading a time window (a
# 10-minute window and its margins read 40 minutes) reads the row groups of those minutes only; a radar's
# 16 MB held 15-19 hours, so every window of a day read most of each radar's day to keep 40 minutes of it
ROW_GROUP_SPAN_NS = 20 * 60 * 10**9
HELD_BYTES = 64 << 20  # all partitions' rows held at most this much: past it the largest is written out
PART_ROWS = 8_000_000  # a part holding this many rows is closed and the partition's next rows start another
# Parquet min/max statistics are written for these columns only (those a query filters on): statistics of
# all 87 CAT048 columns took half the writing time
STATISTICS = ("day", "timestamp", "time_of_day", "block", "offset", "sac", "sic", "address", "callsign",
              "mode3a", "track_number", "flight_level")
WRITES_AHEAD = 2  # row groups handed to the writing thread and not yet written, at most
# Parquet encodings (they change the files' bytes, never the values read back): zstd level 1 (smaller files
# than snappy and as fast to write), dictionary pages for the text columns only (trying one for every float
# column, and giving up past 1 MB, took a third of the writing time) and byte-stream-split float columns
# (zstd compresses their split bytes better)
COMPRESSION, COMPRESSION_LEVEL = "zstd", 1


@dataclass
class _Open:
    """A partition's part being written: its writer, temporary and final paths, rows held and written, and
    the offsets of its first and last record."""

    writer: object
    tmp: Path
    final: Path
    key: tuple[dt.date, int, str]
    held: list = field(default_factory=list)
    held_bytes: int = 0
    rows: int = 0
    offset_min: int = -1
    offset_max: int = -1
    slot: int = -1  # the latest time slot (ROW_GROUP_SPAN_NS) of the rows held; -1: none yet


def time_slots(timestamps: pd.Series) -> np.ndarray:
    """Each record's ROW_GROUP_SPAN_NS slot of the UTC timeline (-1: no timestamp)."""
    ns = pd.DatetimeIndex(timestamps).as_unit("ns").asi8
    known = ns != np.iinfo(np.int64).min
    return np.where(known, ns // ROW_GROUP_SPAN_NS, -1)


class Undated(ValueError):
    """Records of a recording that carries no date (a raw stream without --date): no UTC day to file them
    under."""


class InputWriter:
    """The parts of one input (named by its id), written as its chunks come: ``add`` each category's
    conformed chunk with the UTC date of each row, ``finish`` to close and rename every part (their records
    for the manifest), ``abort`` to remove every file of the input."""

    def __init__(self, root: Path, input_id: str, schemas: dict) -> None:
        from concurrent.futures import ThreadPoolExecutor

        self.root, self.input_id, self.schemas = root, input_id, schemas  # category -> Arrow schema
        self.open: dict[tuple[dt.date, int, str], _Open] = {}
        self.done: list[dict] = []
        self.seq = 0
        self.held_bytes = 0
        self.files: list[Path] = []  # every file made, temporary or final: what abort removes
        # Parquet encoding (pyarrow, without the GIL) overlaps the decoding of the next chunk: one thread,
        # so each part's row groups are written in order
        self.thread = ThreadPoolExecutor(1, thread_name_prefix="msdc-parquet")
        self.writing: list = []  # the thread's tasks not yet waited for

    def add_recording(self, rec, label: str) -> dict[int, int]:
        """Add every category's records of a decoded chunk (asterix Recording) with ``label`` as their
        ``file``, on the UTC day of their ``day`` after the recording's date; the records added per category.
        Undated when records come without a date."""
        from msdc.pipeline.report.record_schema import record_schema

        rows = {}
        for cat, frame in rec.frames.items():
            if not len(frame):
                continue
            if rec.date is None:
                raise Undated(f"a {rec.format} recording carries no date")
            days = np.datetime64(rec.date, "D") + frame["day"].to_numpy(np.int64)
            file = pd.Categorical.from_codes(np.zeros(len(frame), np.int8), categories=[label])
            self.add(cat, record_schema(cat).conform(frame.assign(file=file)), days)
            rows[cat] = len(frame)
        return rows

    def add(self, category: int, rows: pd.DataFrame, dates: np.ndarray) -> None:
        """Add a chunk of one category (its rows in the category's schema; ``dates``: each row's UTC day as
        datetime64[D]), split by day and sensor, in file order within each."""
        import pyarrow as pa

        if not len(rows):
            return
        table = pa.Table.from_pandas(rows, schema=self.schemas[category], preserve_index=False)
        sac = rows["sac"].astype("Int64").fillna(-1).to_numpy(np.int64)
        sic = rows["sic"].astype("Int64").fillna(-1).to_numpy(np.int64)
        day = dates.astype("datetime64[D]").astype(np.int64)
        offsets = rows["offset"].to_numpy()
        slots = time_slots(rows["timestamp"]) if "timestamp" in rows.columns else np.full(len(rows), -1)
        if (day == day[0]).all() and (sac == sac[0]).all() and (sic == sic[0]).all():
            groups = {(day[0], sac[0], sic[0]): None}  # one partition (a sensor's own recording): no copy
        else:
            keys = pd.DataFrame({"day": day, "sac": sac, "sic": sic})
            groups = keys.groupby(["day", "sac", "sic"], sort=True).indices
        for (d, a, c), idx in groups.items():
            sensor = sensor_key(None if a < 0 else a, None if c < 0 else c)
            date = dt.date(1970, 1, 1) + dt.timedelta(days=int(d))
            idx = None if idx is None else np.sort(idx)
            part = table if idx is None else table.take(pa.array(idx))
            held = offsets if idx is None else offsets[idx]
            self._hold_slots((date, category, sensor), part, held, slots if idx is None else slots[idx])
        while self.held_bytes > HELD_BYTES:  # the partition holding most is written out
            self._flush(max(self.open.values(), key=lambda o: o.held_bytes))

    def _hold_slots(self, key: tuple[dt.date, int, str], part, offsets: np.ndarray, slots: np.ndarray
                    ) -> None:
        """Hold a partition's rows, a row group written before each row of a later time slot than those
        held (a record out of time order, or without a timestamp, stays in the group it comes in)."""
        o = self.open.get(key) or self._start(key)
        reach = np.maximum.accumulate(np.maximum(slots, o.slot))  # the latest slot so far, row by row
        later = np.flatnonzero(reach > np.r_[o.slot, reach[:-1]])
        start = 0
        for i in (int(k) for k in later):
            if i > start:
                self._hold(key, part.slice(start, i - start), int(offsets[start:i].min()),
                           int(offsets[start:i].max()))
                start = i
            o = self.open.get(key) or self._start(key)  # a part closed for its rows starts another
            self._flush(o)
            o.slot = int(reach[i])
        if start < part.num_rows:
            self._hold(key, part.slice(start), int(offsets[start:].min()), int(offsets[start:].max()))

    def _hold(self, key: tuple[dt.date, int, str], part, offset_min: int, offset_max: int) -> None:
        o = self.open.get(key) or self._start(key)
        o.held.append(part)
        o.held_bytes += part.nbytes
        self.held_bytes += part.nbytes
        o.rows += part.num_rows
        o.offset_min = offset_min if o.offset_min < 0 else min(o.offset_min, offset_min)
        o.offset_max = max(o.offset_max, offset_max)
        if o.held_bytes >= ROW_GROUP_BYTES:
            self._flush(o)
        if o.rows >= PART_ROWS:
            self._close(o)

    def _start(self, key: tuple[dt.date, int, str]) -> _Open:
        import pyarrow as pa
        import pyarrow.parquet as pq

        folder = partition_dir(self.root, *key)
        folder.mkdir(parents=True, exist_ok=True)
        final = folder / part_name(self.input_id, self.seq)
        self.seq += 1
        tmp = temp_path(final)
        self.files += [tmp, final]
        schema = self.schemas[key[1]]
        stats = [c for c in STATISTICS if c in schema.names]
        text = [f.name for f in schema if pa.types.is_dictionary(f.type)]
        floats = [f.name for f in schema if pa.types.is_floating(f.type)]
        o = _Open(pq.ParquetWriter(tmp, schema, write_statistics=stats, compression=COMPRESSION,
                                   compression_level=COMPRESSION_LEVEL, use_dictionary=text,
                                   use_byte_stream_split=floats, write_page_checksum=True), tmp, final, key)
        self.open[key] = o
        return o

    def _flush(self, o: _Open) -> None:
        """Write a partition's held rows as one row group."""
        import pyarrow as pa

        if o.held:
            table = pa.concat_tables(o.held)
            self.held_bytes -= o.held_bytes
            o.held, o.held_bytes = [], 0
            self._write(o.writer.write_table, table, row_group_size=max(table.num_rows, 1))

    def _write(self, fn, *args, **kw) -> None:
        """Run a write on the writing thread, waiting for the oldest when WRITES_AHEAD are pending (its
        error raised here)."""
        self.writing.append(self.thread.submit(fn, *args, **kw))
        while len(self.writing) > WRITES_AHEAD:
            self.writing.pop(0).result()

    def _drain(self) -> None:
        """Wait for every pending write (the first error raised)."""
        while self.writing:
            self.writing.pop(0).result()

    def _close(self, o: _Open) -> None:
        """Write what the part holds, close it and rename it into place."""
        self._flush(o)
        self._drain()
        o.writer.close()
        size_bytes, crc = part_checksum(o.tmp)  # what a query checks the part against (dataset.integrity)
        os.replace(o.tmp, o.final)
        del self.open[o.key]
        date, category, sensor = o.key
        self.done.append({"path": relative(self.root, o.final), "date": date.isoformat(),
                          "category": category, "sensor": sensor, "rows": o.rows, "offset_min": o.offset_min,
                          "offset_max": o.offset_max, "size_bytes": size_bytes, "crc32": crc})

    def finish(self) -> list[dict]:
        """Close every part still open (in the order they were started) and return all the parts' records:
        path (relative to the root), date, category, sensor, rows, the first and last record's offset, and
        the file's size and CRC-32."""
        for o in sorted(self.open.values(), key=lambda o: o.final.name):
            self._flush(o)
        self._drain()
        for o in sorted(self.open.values(), key=lambda o: o.final.name):
            self._close(o)
        self.thread.shutdown()
        return sorted(self.done, key=lambda p: p["path"].rsplit("/", 1)[1])

    def abort(self) -> None:
        """Close and remove every file of this input (its partition folders left empty are removed by the
        caller: manifest.prune_empty)."""
        self.thread.shutdown(wait=True, cancel_futures=True)
        for o in list(self.open.values()):
            try:
                o.writer.close()
            except Exception:  # noqa: BLE001 - removing it anyway
                pass
        self.open.clear()
        for p in self.files:
            p.unlink(missing_ok=True)
