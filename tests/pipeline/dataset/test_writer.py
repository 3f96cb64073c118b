"""A partition's Parquet row groups (dataset.writer): cut at the time slots a windowed job reads by."""

import datetime as dt

import numpy as np
import pandas as pd
import pyarrow.parquet as pq

from msdc.pipeline.dataset.writer import ROW_GROUP_SPAN_NS, InputWriter
from msdc.pipeline.report.record_schema import record_schema


def _plots(minutes: np.ndarray) -> pd.DataFrame:
    """CAT048 records of one radar at these minutes after midnight of 2026-11-28, in file order."""
    n = len(minutes)
    stamps = pd.Timestamp("2026-11-28", tz="UTC") + pd.to_timedelta(minutes, unit="min")
    frame = pd.DataFrame({"day": np.zeros(n, np.int64), "timestamp": stamps, "block": np.arange(n),
                          "offset": np.arange(n) * 10, "sac": pd.array([20] * n, dtype="Int64"),
                          "sic": pd.array([1] * n, dtype="Int64")})
    return record_schema(48).conform(frame)


def test_row_groups_hold_one_time_slot_each_and_every_row_in_file_order(tmp_path):
    span_min = ROW_GROUP_SPAN_NS / 60e9
    # three chunks over 2.5 slots; a late record (out of time order) and one without a time come in between
    minutes = np.concatenate([np.arange(0, 30, 0.5), [5.0], np.arange(30, 50, 0.5)]) * span_min / 20
    rows = _plots(minutes)
    rows.loc[70, "timestamp"] = pd.NaT
    writer = InputWriter(tmp_path, "abc", {48: record_schema(48).arrow()})
    dates = np.full(len(rows), np.datetime64("2026-11-28"), "datetime64[D]")
    for part in np.array_split(np.arange(len(rows)), 3):
        writer.add(48, rows.iloc[part], dates[part])
    (done,) = writer.finish()
    parquet = pq.ParquetFile(tmp_path / done["path"])
    offsets = parquet.read(columns=["offset"]).column("offset").to_pylist()
    assert offsets == (np.arange(len(rows)) * 10).tolist()  # every row, in file order
    midnight = pd.Timestamp("2026-11-28", tz="UTC").value // ROW_GROUP_SPAN_NS
    groups = []
    for i in range(parquet.metadata.num_row_groups):
        stamps = parquet.read_row_group(i, columns=["timestamp"]).column("timestamp").to_pandas()
        slot = stamps.dropna().astype("int64") // ROW_GROUP_SPAN_NS - midnight
        groups.append((len(stamps), sorted(set(slot.tolist()))))
    # by hand, in twentieths of a slot: slot 0's 40 rows (0-19.5); slot 1's from 20, with the late record at
    # 5 that came after them and the one without a time (60 + 1 rows); slot 2's 20 rows (40-49.5)
    assert groups == [(40, [0]), (41, [0, 1]), (20, [2])]
    assert done["date"] == dt.date(2026, 11, 28).isoformat() and done["rows"] == len(rows)


def test_each_part_is_recorded_with_its_size_and_crc32(tmp_path):
    """The part's record carries the size and CRC-32 of the file renamed into place (read back whole here:
    what a query checks it against), in two parts of two days."""
    import zlib

    rows = _plots(np.arange(40.0))
    dates = np.repeat(np.array(["2026-11-28", "2026-11-29"], "datetime64[D]"), 20)
    writer = InputWriter(tmp_path, "abc", {48: record_schema(48).arrow()})
    writer.add(48, rows, dates)
    done = writer.finish()
    assert [d["date"] for d in done] == ["2026-11-28", "2026-11-29"]
    for d in done:
        data = (tmp_path / d["path"]).read_bytes()
        assert d["size_bytes"] == len(data) and d["crc32"] == f"{zlib.crc32(data):08x}"
