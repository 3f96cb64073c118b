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


@pytest.mark.parametrize(("value", "expected"), [("1", 1), ("2", 2), ("", 64), ("0", 64), ("two", 64)])
def test_omp_num_threads_caps_the_threads(monkeypatch, value: str, expected: int) -> None:
    """Dask's workers set OMP_NUM_THREADS=1 (one process per core already); a value that is not a positive
    number is ignored."""
    monkeypatch.setattr(threads.os, "sched_getaffinity", lambda _pid: set(range(64)), raising=False)
    monkeypatch.setenv("OMP_NUM_THREADS", value)
    assert threads.decode_threads() == expected


def test_a_decode_split_over_threads_keeps_every_value(monkeypatch) -> None:
    """3,001 CAT062 tracks in three ranges of about 1,000 records (the kernel works 1,024 at a time, so the
    ranges end inside its chunks); every seventh record without I062/136 and every fifth without I062/105."""
    n = 3_001
    i = np.arange(n)
    truth = pd.DataFrame({
        "sac": 25, "sic": 100, "time_of_day": i / 128,  # I062/070 LSB 1/128 s
        "track_number": i % 4096,
        "flight_level": np.where(i % 7 == 0, np.nan, (i % 1600) / 4),  # I062/136 LSB 1/4 FL
        "latitude": np.where(i % 5 == 0, np.nan, (i % 1000) * 180 / 2**25),  # I062/105 LSB 180/2^25 deg
        "longitude": np.where(i % 5 == 0, np.nan, -(i % 999) * 180 / 2**25),
        "x_m": (i - 1500) * 0.5, "y_m": (1500 - i) * 0.5,  # I062/100 LSB 0.5 m
        "mon": i % 2, "spi": (i // 2) % 2, "cnf": (i // 3) % 2,
    })
    data = encode_frame(62, truth, records_per_block=17)
    calls: list[tuple[int, int]] = []
    gather = kernel.gather

    def counting(*args):
        calls.append((args[-2], args[-1]))
        return gather(*args)

    monkeypatch.setattr(kernel, "gather", counting)
    monkeypatch.setattr(threads, "MIN_RECORDS_PER_THREAD", 1_000)
    monkeypatch.setattr(threads, "decode_threads", lambda: 3)
    got = decode_bytes(data, categories=[62]).frames[62]
    assert sorted(calls) == [(0, 1_000), (1_000, 2_000), (2_000, 3_001)]
    for name in ("time_of_day", "flight_level", "latitude", "longitude", "x_m", "y_m"):
        np.testing.assert_array_equal(got[name].to_numpy(float), truth[name].to_numpy(float), err_msg=name)
    for name in ("track_number", "mon", "spi", "cnf"):
        assert got[name].astype("int64").tolist() == truth[name].tolist(), name


def test_a_flag_column_wider_than_its_int8_matrix_is_refused(monkeypatch) -> None:
    """Flags are gathered into int8 (-1 absent): a table giving a flag column the 8 bits of I048/010 SAC
    would wrap 200 to -56, so the layout is refused, naming the column and its width."""
    from msdc.asterix import layout
    from msdc.asterix.columns.base import Column

    wide = Column("sac", (("010", ("SAC",)),), "flag")
    monkeypatch.setattr(layout, "columns_for", lambda _cat, _ed: (wide,))
    with pytest.raises(ValueError, match=r"sac: a flag column of 8 bits \(at most 7\)"):
        layout.compile_layout.__wrapped__(48, "1.32", None)
