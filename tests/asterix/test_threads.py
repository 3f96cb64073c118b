"""A large decode's records split over threads (asterix/threads.py): the ranges cover every record once, the
thread count follows the CPUs and OMP_NUM_THREADS, a decode split into ranges that do not fall on the
kernel's chunks gives every value the encoder was given, and flags (gathered into int8) are at most 7 bits."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from asterix_bytes import decode_bytes

from msdc.asterix import kernel, threads
from msdc.asterix.encode import encode_frame


@pytest.mark.parametrize(("n", "k", "expected"), [
    (0, 4, [(0, 0)]),
    (99_999, 4, [(0, 99_999)]),  # one thread's minimum twice over is 100,000 records
    (100_000, 4, [(0, 50_000), (50_000, 100_000)]),
    (150_001, 2, [(0, 75_000), (75_000, 150_001)]),
    (1_000_000, 3, [(0, 333_333), (333_333, 666_666), (666_666, 1_000_000)]),
])
def test_ranges_cover_the_records_once(n: int, k: int, expected: list) -> None:
    assert threads.ranges(n, k) == expected


def test_byte_groups_split_the_blocks_by_their_bytes() -> None:
    """Ten blocks, the first five of 100 bytes and the rest of 25 (625 bytes): two groups cut before the block
    that passes half of them (block 3 ends at 400 > 312.5), of 300 and 325 bytes; one group for a small
    decode or a single block."""
    lens = np.array([100] * 5 + [25] * 5)
    assert threads.byte_groups(lens, 100_000, 2) == [slice(0, 3), slice(3, 10)]
    assert threads.byte_groups(lens, 99_999, 2) == [slice(0, 10)]
    assert threads.byte_groups(lens[:1], 1_000_000, 4) == [slice(0, 1)]


@pytest.mark.parametrize(("value", "expected"), [("1", 1), ("2", 2), ("", 64), ("0", 64), ("two", 64)])
def test_omp_num_threads_caps_the_threads(monkeypatch, value: str, expected: int) -> None:
    """Dask's workers set OMP_NUM_THREADS=1 (one process per core already); a value that is not a positive
    number is ignored."""
    monkeypatch.setattr(threads.os, "sched_getaffinity", lambda _pid: set(range(64)), raising=False)
    monkeypatch.setenv("OMP_NUM_THREADS", value)
    assert threads.decode_threads() == expected


N = 3_001
PER_BLOCK = 17


def _tracks() -> pd.DataFrame:
    """CAT062 tracks on their items' LSB grids; every seventh without I062/136, every fifth without /105."""
    i = np.arange(N)
    return pd.DataFrame({
        "sac": 25, "sic": 100, "time_of_day": i / 128,  # I062/070 LSB 1/128 s
        "track_number": i % 4096,
        "flight_level": np.where(i % 7 == 0, np.nan, (i % 1600) / 4),  # I062/136 LSB 1/4 FL
        "latitude": np.where(i % 5 == 0, np.nan, (i % 1000) * 180 / 2**25),  # I062/105 LSB 180/2^25 deg
        "longitude": np.where(i % 5 == 0, np.nan, -(i % 999) * 180 / 2**25),
        "x_m": (i - 1500) * 0.5, "y_m": (1500 - i) * 0.5,  # I062/100 LSB 0.5 m
        "mon": i % 2, "spi": (i // 2) % 2, "cnf": (i // 3) % 2,
    })


def _decode_counting_gathers(monkeypatch, data: bytes):
    """The CAT062 decode of data with 3 threads, and the records each kernel.gather call filled."""
    calls: list[tuple[int, int]] = []
    gather = kernel.gather

    def counting(*args):  # (..., start, stop, out0): records start..stop into columns from start + out0
        calls.append((args[-3] + args[-1], args[-2] + args[-1]))
        return gather(*args)

    monkeypatch.setattr(kernel, "gather", counting)
    monkeypatch.setattr(threads, "decode_threads", lambda: 3)
    return decode_bytes(data, categories=[62]), sorted(calls)


def _assert_values(got: pd.DataFrame, truth: pd.DataFrame) -> None:
    for name in ("time_of_day", "flight_level", "latitude", "longitude", "x_m", "y_m"):
        np.testing.assert_array_equal(got[name].to_numpy(float), truth[name].to_numpy(float), err_msg=name)
    for name in ("track_number", "mon", "spi", "cnf"):
        assert got[name].astype("int64").tolist() == truth[name].tolist(), name


def test_a_decode_gathered_in_ranges_keeps_every_value(monkeypatch) -> None:
    """The blocks walked in one piece, its 3,001 records gathered in three ranges of about 1,000 (the
    kernel works 1,024 at a time, so the ranges end inside its chunks)."""
    truth = _tracks()
    monkeypatch.setattr(threads, "MIN_RECORDS_PER_THREAD", 1_000)
    monkeypatch.setattr(threads, "byte_groups", lambda lens, _records: [slice(0, len(lens))])
    rec, calls = _decode_counting_gathers(monkeypatch, encode_frame(62, truth, records_per_block=PER_BLOCK))
    assert calls == [(0, 1_000), (1_000, 2_000), (2_000, 3_001)]
    _assert_values(rec.frames[62], truth)


def test_blocks_walked_in_groups_side_by_side_keep_every_value_and_error(monkeypatch) -> None:
    """The 177 blocks walked in three groups of about equal bytes, each group's records gathered in a thread
    of its own; block 100 (in the second group) has an empty FSPEC as its first record: that block alone is
    lost and reported, the others' 2,984 records keep their values."""
    truth = _tracks()
    data = bytearray(encode_frame(62, truth, records_per_block=PER_BLOCK))
    starts = [0]
    while starts[-1] < len(data):
        starts.append(starts[-1] + int.from_bytes(data[starts[-1] + 1:starts[-1] + 3], "big"))
    starts.pop()
    assert len(starts) == 177
    data[starts[100] + 3] = 0x00  # the first record's FSPEC
    monkeypatch.setattr(threads, "MIN_RECORDS_PER_THREAD", 300)
    rec, calls = _decode_counting_gathers(monkeypatch, bytes(data))
    assert len(calls) == 3 and calls[0][0] == 0 and calls[-1][1] == N - PER_BLOCK
    assert all(a[1] == b[0] for a, b in zip(calls, calls[1:], strict=False))  # contiguous, none twice
    kept = truth.drop(index=range(100 * PER_BLOCK, 101 * PER_BLOCK)).reset_index(drop=True)
    _assert_values(rec.frames[62], kept)
    blocks = np.delete(np.arange(N) // PER_BLOCK, range(100 * PER_BLOCK, 101 * PER_BLOCK))
    assert rec.frames[62]["block"].tolist() == blocks.tolist()  # each record's block in the recording
    assert rec.errors["offset"].tolist() == [starts[100]]  # the block lost


def test_a_flag_column_wider_than_its_int8_matrix_is_refused(monkeypatch) -> None:
    """Flags are gathered into int8 (-1 absent): a table giving a flag column the 8 bits of I048/010 SAC
    would wrap 200 to -56, so the layout is refused, naming the column and its width."""
    from msdc.asterix import layout
    from msdc.asterix.columns.base import Column

    wide = Column("sac", (("010", ("SAC",)),), "flag")
    monkeypatch.setattr(layout, "columns_for", lambda _cat, _ed: (wide,))
    with pytest.raises(ValueError, match=r"sac: a flag column of 8 bits \(at most 7\)"):
        layout.compile_layout.__wrapped__(48, "1.32", None)


def test_groups_whose_arrays_are_too_small_are_walked_again(monkeypatch) -> None:
    """Record arrays sized for 8 records: each group's walk stops short and is walked again with twice the
    room until it fits (eight walks a group of about 1,000 records: room for 8, 16, ... 1,024), and every
    value is kept."""
    from msdc.asterix import reader

    truth = _tracks()
    monkeypatch.setattr(reader, "_record_guess", lambda *_args: 8)
    monkeypatch.setattr(threads, "MIN_RECORDS_PER_THREAD", 300)
    walks: list[int] = []
    scan = kernel.scan

    def counting(*args):
        out = scan(*args)
        walks.append(out[2])
        return out

    monkeypatch.setattr(kernel, "scan", counting)
    rec, calls = _decode_counting_gathers(monkeypatch, encode_frame(62, truth, records_per_block=PER_BLOCK))
    assert len(calls) == 3 and walks.count(-1) == 3 * 7  # 8 -> 16 -> ... -> 1,024: seven walks too small
    _assert_values(rec.frames[62], truth)
