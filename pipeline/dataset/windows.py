"""A raw recording's windows (asterix.stream.plan_windows) decoded and written in pool processes: each
window's parts are its own (``part-ID-WWWWW-NNNNN.parquet``), renamed into place by the process that wrote
them; the input is committed by its manifest record as a whole, as ever."""

from __future__ import annotations

from pathlib import Path

from msdc.pipeline.dataset.writer import InputWriter
from msdc.pipeline.report.record_schema import record_schema

KEPT_COLUMNS = ("day", "time_of_day", "offset")  # what the main process's tallies read of a window's records


def write_window(path: str, plan, window, label: str, root: Path, input_id: str, categories: list[int]
                 ) -> tuple[list[dict], dict[int, int], object]:
    """Decode one window and write its parts (in a pool process): their records, the records per category,
    and the decoded Recording with only KEPT_COLUMNS (for the warnings the main process folds)."""
    from msdc.asterix.stream import decode_window

    rec = decode_window(path, plan, window)
    schemas = {c: record_schema(c).arrow() for c in categories}
    writer = InputWriter(root, f"{input_id}-{window.index:05d}", schemas)
    try:
        rows = writer.add_recording(rec, label)
        parts = writer.finish()
    except BaseException:
        writer.abort()
        raise
    rec.frames = {c: f[[k for k in KEPT_COLUMNS if k in f.columns]] for c, f in rec.frames.items()}
    return parts, rows, rec
