"""The two long tables of a correlation run (every window's slots and lags) as DataFrames, and where they go.

The workbook's Slots and Correlation sheets are written from these frames; a table longer than a sheet
is worth (``--tables``: ``auto`` past AUTO_MAX_ROWS rows, ``parquet`` always) goes to Parquet beside the
workbook instead (``STEM_slots.parquet``, ``STEM_correlation.parquet``), the sheet then naming the file,
its rows and columns. Columns (one row per slot, resp. per window and lag):

* ``window``, ``callsign``, ``address``, ``radar_sensor``, ``reference_sensor``: the window;
* Slots: ``slot``, ``time_utc`` (slot start, UTC; ``time_of_day`` in seconds when the recording is
  undated), then ``radar_lat`` .. ``sep_m`` (pipeline.correlate.results.SLOT_COLUMNS);
* Correlation: ``lag`` (slots), ``lag_s``, ``ncc_lat``, ``ncc_lon``, ``pearson_lat``, ``pearson_lon``.

The sheets have the same window columns: window numbers restart for every sensor pair of an aircraft.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pandas as pd

from msdc.pipeline.correlate.results import LAG_COLUMNS, SLOT_COLUMNS, CorrelationRun, WindowResult
from msdc.pipeline.meta import TABLE_MODES
from msdc.pipeline.report.files import named
from msdc.pipeline.report.summary import slot_seconds

# auto: longer tables go to Parquet. At the ~150,000 cells/s openpyxl writes here on a quiet machine
# (about 35,000 under load), 5,000 rows of the 15-column slot table cost 0.5 s (2 s loaded) and
# 100 printed pages, while Parquet writes a million rows in well under a second; nobody reads
# thousands of rows in a sheet, the charts and the Summary are the human view.
AUTO_MAX_ROWS = 5_000
TABLE_FILES = ("slots", "correlation")  # STEM_NAME.parquet
IDENT_COLUMNS = ["window", "callsign", "address", "radar_sensor", "reference_sensor"]
CHART_MAX_POINTS = 250  # per chart, in the excerpt a workbook keeps for its charts when a table is Parquet
COLUMN_NOTES = {
    "window": "window number (per aircraft and sensor pair)", "callsign": "call sign",
    "address": "24-bit address (hex)", "radar_sensor": "radar of the pair (sensor_id)",
    "reference_sensor": "ADS-B source or second radar of the pair", "slot": "slot number in the window",
    "time_utc": "slot start, UTC", "time_of_day": "slot start, seconds after midnight (undated recording)",
    "radar_lat": "radar latitude, slot mean (deg)", "radar_lon": "radar longitude, slot mean (deg)",
    "adsb_lat": "reference latitude, slot mean (deg)", "adsb_lon": "reference longitude, slot mean (deg)",
    "radar_count": "radar reports in the slot", "adsb_count": "reference reports in the slot",
    "radar_filled": "radar slot empty, filled", "adsb_filled": "reference slot empty, filled",
    "sep_m": "radar to reference distance (m)", "lag": "lag d (slots): radar x[i] paired with y[i - d]",
    "lag_s": "lag (s)", "ncc_lat": "NCC of latitude", "ncc_lon": "NCC of longitude",
    "pearson_lat": "Pearson coefficient of latitude over the overlap",
    "pearson_lon": "Pearson coefficient of longitude over the overlap",
}


def window_id(window: WindowResult, index: int) -> object:
    """The window's number (its ``window`` summary field), else its position in the run."""
    value = window.summary.get("window")
    return index if value is None else value


def _text(value: object) -> object:
    return None if value is None or value is pd.NA or (isinstance(value, float) and np.isnan(value)) \
        else str(value)


def _ident(window: WindowResult, index: int, n: int) -> dict[str, object]:
    s = window.summary
    return {"window": np.full(n, window_id(window, index), dtype=object),
            **{k: np.full(n, _text(s.get(k)), dtype=object) for k in IDENT_COLUMNS[1:]}}


def _extra(frames: list[pd.DataFrame], known: list[str]) -> list[str]:
    extra: dict[str, None] = {}
    for frame in frames:
        extra.update((str(c), None) for c in frame.columns if str(c) not in known)
    return list(extra)


def is_dated(run: CorrelationRun) -> bool:
    """Whether every slot has a UTC time (else the tables carry clock seconds)."""
    return all("timestamp" in w.slots and w.slots["timestamp"].notna().all() for w in run.windows)


def slot_table(run: CorrelationRun, part: range | None = None) -> pd.DataFrame:
    """Every window's slots, windows in run order (module docstring for the columns); ``part``: only the
    windows at these positions, with the columns and types of the whole table."""
    dated = is_dated(run)
    extra = _extra([w.slots for w in run.windows], SLOT_COLUMNS)
    values = SLOT_COLUMNS[3:] + extra
    pieces = []
    for i in range(len(run.windows)) if part is None else part:
        w = run.windows[i]
        n = len(w.slots)
        piece = {**_ident(w, i, n), "slot": w.slots["slot"].to_numpy() if "slot" in w.slots else np.arange(n)}
        if dated:  # int64 ns, a datetime column again in _concat
            stamps = pd.DatetimeIndex(pd.to_datetime(w.slots["timestamp"], utc=True))
            piece["time_utc"] = stamps.as_unit("ns").asi8
        else:
            tod = w.slots["time_of_day"] if "time_of_day" in w.slots else pd.Series(np.nan, w.slots.index)
            piece["time_of_day"] = pd.to_numeric(tod, errors="coerce").to_numpy(dtype=float)
        for c in values:
            piece[c] = w.slots[c].to_numpy() if c in w.slots else np.full(n, None, dtype=object)
        pieces.append(piece)
    columns = [*IDENT_COLUMNS, "slot", "time_utc" if dated else "time_of_day", *values]
    return _concat(pieces, columns, {"time_utc": "datetime64[ns, UTC]"} if dated else {})


def correlation_table(run: CorrelationRun, part: range | None = None) -> pd.DataFrame:
    """Every window's lags d = -(N-1)..N-1 in increasing order, with the lag in seconds; ``part`` as for
    slot_table."""
    extra = _extra([w.lags for w in run.windows], LAG_COLUMNS)
    pieces = []
    for i in range(len(run.windows)) if part is None else part:
        w = run.windows[i]
        lags = lag_frame(w)
        n = len(lags)
        lag = pd.to_numeric(lags["lag"], errors="coerce") if "lag" in lags else pd.Series(np.nan, lags.index)
        piece = {**_ident(w, i, n), "lag": lag.to_numpy(),
                 "lag_s": (lag.to_numpy(dtype=float) * slot_seconds(w, run.parameters))}
        for c in [*LAG_COLUMNS[1:], *extra]:
            piece[c] = lags[c].to_numpy() if c in lags else np.full(n, None, dtype=object)
        pieces.append(piece)
    return _concat(pieces, [*IDENT_COLUMNS, "lag", "lag_s", *LAG_COLUMNS[1:], *extra], {})


TABLE_BUILDERS = {"slots": slot_table, "correlation": correlation_table}
# A long table goes to Parquet built this many rows (whole windows) at a time, so a run of millions of slots
# never holds its whole table (about 150 bytes a row, and more while pandas builds its text columns); a
# table up to this size is written in one piece, as before
TABLE_BATCH_ROWS = 262_144


def lag_frame(window: WindowResult) -> pd.DataFrame:
    """A window's lag table in increasing lag (the table itself when already in that order, as correlate
    gives it: the writers ask for it several times a window)."""
    lags = window.lags
    if "lag" not in lags.columns or lags["lag"].is_monotonic_increasing:
        return lags
    return lags.sort_values("lag", kind="stable")


def _concat(pieces: list[dict[str, np.ndarray]], columns: list[str], dtypes: dict[str, str]) -> pd.DataFrame:
    """One frame from the windows' column arrays (one concatenation per column, not a frame per window)."""
    if not pieces:
        return pd.DataFrame({c: pd.Series([], dtype=dtypes.get(c, object)) for c in columns})
    data = {}
    for c in columns:  # each window's array is dropped once joined: the pieces and the result never
        data[c] = np.concatenate([p.pop(c) for p in pieces])  # both whole at once
    if "time_utc" in data:
        data["time_utc"] = pd.to_datetime(data["time_utc"], unit="ns", utc=True).array
    return pd.DataFrame(data, columns=columns, copy=False)  # the joined arrays as they are, not a copy


def to_parquet(run: CorrelationRun, mode: str) -> dict[str, pd.DataFrame]:
    """The tables (by file suffix: ``slots``, ``correlation``) that go to Parquet under ``mode``."""
    return {name: TABLE_BUILDERS[name](run) for name in parquet_tables(run, mode)}


def parquet_tables(run: CorrelationRun, mode: str) -> list[str]:
    """The names of the tables (``slots``, ``correlation``) that go to Parquet under ``mode``, unbuilt: a
    writer can build, write and drop them one at a time."""
    if mode not in TABLE_MODES:
        raise ValueError(f"tables must be one of {', '.join(TABLE_MODES)}, got {mode!r}")
    if mode == "xlsx":
        return []
    rows = {name: table_length(run, name) for name in ("slots", "correlation")}
    return [name for name, n in rows.items() if mode == "parquet" or n > AUTO_MAX_ROWS]


def window_rows(run: CorrelationRun, name: str) -> list[int]:
    """The rows each window gives table ``name`` (``slots``: a slot a row; ``correlation``: a lag a row),
    counted without building it."""
    return [len(w.slots) if name == "slots" else len(w.lags) for w in run.windows]


def table_length(run: CorrelationRun, name: str) -> int:
    """The rows of table ``name`` (window_rows), counted without building it."""
    return sum(window_rows(run, name))


def parquet_path(workbook: str | os.PathLike[str], name: str) -> Path:
    """Where table ``name`` (``slots``, ``correlation``) goes beside the workbook: STEM_NAME.parquet."""
    workbook = Path(workbook)
    return workbook.with_name(f"{workbook.stem}_{name}.parquet")


def _batches(run: CorrelationRun, name: str, batch_rows: int) -> list[range]:
    """Window positions in runs of whole windows of at most ``batch_rows`` rows of table ``name`` (a window
    longer than that on its own)."""
    sizes = window_rows(run, name)
    out, start, rows = [], 0, 0
    for i, n in enumerate(sizes):
        if rows and rows + n > batch_rows:
            out.append(range(start, i))
            start, rows = i, 0
        rows += n
    return [*out, range(start, len(sizes))]


def write_table_parquet(run: CorrelationRun, name: str, path: str | os.PathLike[str],
                        batch_rows: int = TABLE_BATCH_ROWS):
    """Table ``name`` (``slots``, ``correlation``) of the run written to ``path`` as Parquet, built and
    written ``batch_rows`` rows of whole windows at a time through one writer: the same columns, types and
    rows as ``write_parquet`` of the whole table. Returns its row count and its pyarrow schema."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    build = TABLE_BUILDERS[name]
    extra = _extra([w.slots if name == "slots" else w.lags for w in run.windows],
                   SLOT_COLUMNS if name == "slots" else LAG_COLUMNS)
    parts = _batches(run, name, batch_rows)
    if len(parts) == 1 or extra:  # extra columns may be all None in one part: their type needs every row
        frame = build(run)
        write_parquet(frame, path)
        return len(frame), pa.Schema.from_pandas(frame, preserve_index=False)
    rows, schema, writer = 0, None, None
    with named(path):
        try:
            for part in parts:
                frame = build(run, part)
                table = pa.Table.from_pandas(frame, preserve_index=False)
                if writer is None:
                    schema = pa.Schema.from_pandas(frame, preserve_index=False)
                    writer = pq.ParquetWriter(path, table.schema)
                writer.write_table(table)
                rows += len(frame)
                del frame, table
        finally:
            if writer is not None:
                writer.close()
    return rows, schema


def write_parquet(frame: pd.DataFrame, path: str | os.PathLike[str],
                  slice_rows: int = TABLE_BATCH_ROWS) -> Path:
    """The table as Parquet (text columns as strings, nulls kept), converted to Arrow
    slice_rows rows at a time under the whole frame's schema: the same columns, types and rows as one
    conversion, without a second copy of a large table (a day's tracks are ~0.35 GB)."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    schema = pa.Schema.from_pandas(frame, preserve_index=False)  # types from every row, no conversion
    with named(path), pq.ParquetWriter(path, schema) as writer:
        for start in range(0, max(len(frame), 1), slice_rows):
            writer.write_table(pa.Table.from_pandas(frame.iloc[start:start + slice_rows], schema=schema,
                                                    preserve_index=False))
    return Path(path)
