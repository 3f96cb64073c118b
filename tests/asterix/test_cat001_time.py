"""CAT001's truncated time of day (I001/141, modulo 512 s) made whole from the same radar's CAT002 I002/030.

The times below are worked by hand: 36000 = 70 * 512 + 160, 35840 = 70 * 512, 86016 = 168 * 512 (the
day's last window holds 384 s: 86400 is not a multiple of 512).
"""

from __future__ import annotations

import datetime as dt
import warnings

import numpy as np
import pandas as pd
import pytest
from asterix_bytes import block, decode_bytes, fspec
from budget import examples
from hypothesis import given, settings
from hypothesis import strategies as st

import msdc.asterix as asterix
from msdc.asterix.cat001_time import NO_REFERENCE, NO_SOURCE, NO_TIME, STALE, TOO_FAR, whole_time

R1, R2 = (25, 201), (25, 202)


def sector(radar: tuple[int, int], tod_s: float) -> bytes:
    """CAT002 sector crossing: FRN 1 I002/010, 2 I002/000 = 2, 4 I002/030 (24 bits, 1/128 s)."""
    return fspec(1, 2, 4) + bytes([*radar, 2]) + round(tod_s * 128).to_bytes(3, "big")


def plot(radar: tuple[int, int] | None, truncated_s: float | None) -> bytes:
    """CAT001 plot: FRN 1 I001/010 (when a radar), 2 I001/020 TYP 0, 7 I001/141 (when a time, 1/128 s)."""
    frns = [f for f, on in ((1, radar is not None), (2, True), (7, truncated_s is not None)) if on]
    tod = b"" if truncated_s is None else round(truncated_s * 128).to_bytes(2, "big")
    return fspec(*frns) + bytes(radar or ()) + b"\x00" + tod


@pytest.mark.parametrize(("truncated", "reference", "whole"), [
    (161.5, 36000.0, 36001.5),  # 35840 + 161.5, 1.5 s after the sector crossing
    (159.0, 36000.0, 35999.0),  # 35840 + 159, a plot 1 s before its sector message
    (1.0, 35839.5, 35841.0),  # the reference at 35328 + 511.5: the plot is in the next window
    (511.0, 35841.0, 35839.0),  # and back: 35328 + 511
    (0.5, 86399.0, 0.5),  # across midnight: 00:00:00.5 of the next day, not 86016.5
    (383.5, 1.0, 86399.5),  # back across midnight: 86016 + 383.5 of the day before, not 383.5
])
def test_whole_time_worked_by_hand(truncated: float, reference: float, whole: float) -> None:
    tod, d = whole_time(np.array([truncated]), np.array([reference]))
    assert tod[0] == whole
    assert abs(d[0]) <= 2  # the signed distance on the continuous time line


@settings(max_examples=examples(200), deadline=None)
@given(true=st.integers(0, 86400 * 128 - 1), ahead=st.integers(-32 * 128, 32 * 128))
def test_whole_time_gives_back_any_time_within_32_s_of_its_reference(true: int, ahead: int) -> None:
    true_s, ahead_s = true / 128, ahead / 128
    reference = (true_s - ahead_s) % 86400  # on the day before or after when it crosses midnight
    tod, d = whole_time(np.array([true_s % 512]), np.array([reference]))
    assert tod[0] == true_s and d[0] == ahead_s


def offsets(*blocks: bytes) -> list[int]:
    """Offset of each record of these blocks: 3 header bytes, then the records in turn."""
    return list(np.cumsum([0, *(len(b) for b in blocks)])[:-1])


def stream_a() -> tuple[bytes, list[int], list[float], list[str]]:
    """Two radars; every reason a record may stay undated; a reference refreshed. Returns the bytes, the
    CAT001 record offsets, their expected times of day and reasons ("" where dated)."""
    recs = [  # (category, record, expected time, reason)
        (1, plot(R1, 10.0), np.nan, NO_REFERENCE),  # before any CAT002 of its radar
        (2, sector(R1, 36000.0), None, None),
        (1, plot(R1, 161.5), 36001.5, ""),
        (1, plot(R2, 5.0), np.nan, NO_REFERENCE),  # radar 2 sends no CAT002
        (1, plot(R1, None), np.nan, NO_TIME),
        (1, plot(None, 161.5), np.nan, NO_SOURCE),
        (1, plot(R1, 200.0), np.nan, TOO_FAR),  # 35840 + 200 = 36040: 40 s after 36000
        (1, plot(R1, 161.75), np.nan, STALE),  # near, but the reference went stale
        (2, sector(R1, 36100.0), None, None),
        (1, plot(R1, 260.25), 36100.25, ""),  # 35840 + 260.25
    ]
    data, offs, times, reasons = b"", [], [], []
    for cat, rec, t, why in recs:  # one block per record: chunks can cut between any two
        if cat == 1:
            offs.append(len(data) + 3)
            times.append(t)
            reasons.append(why)
        data += block(cat, rec)
    return data, offs, times, reasons


def test_every_reason_and_a_refreshed_reference() -> None:
    data, offs, times, reasons = stream_a()
    rec = decode_bytes(data, categories=[1, 2])
    f = rec.frames[1]
    assert rec.errors.empty and f.offset.tolist() == offs
    np.testing.assert_array_equal(f.time_of_day.to_numpy(), times)
    undated = [(o, why) for o, why in zip(offs, reasons, strict=True) if why]
    assert list(zip(rec.untimed.offset, rec.untimed.reason, strict=True)) == undated
    assert rec.untimed.category.tolist() == [1] * 6
    assert rec.untimed.sac.tolist()[:2] == [25, 25] and pd.isna(rec.untimed.sic.iloc[3])  # no I001/010
    assert rec.frames[2].time_of_day.tolist() == [36000.0, 36100.0]


def test_cat002_is_walked_when_only_cat001_is_decoded() -> None:
    data, offs, times, _ = stream_a()
    rec = decode_bytes(data, categories=[1])
    np.testing.assert_array_equal(rec.frames[1].time_of_day.to_numpy(), times)
    assert list(rec.frames) == [1] and rec.ignored_blocks == {2: 2}
    assert rec.decoded_bytes + rec.ignored_bytes == len(data)


def test_a_cat002_block_that_does_not_walk_dates_nothing_and_is_not_an_error_unless_decoded() -> None:
    bad = fspec(1, 2, 4) + bytes([*R1, 2, 0x46])  # I002/030 cut short: the block does not walk
    data = block(2, bad) + block(1, plot(R1, 161.5))
    rec = decode_bytes(data, categories=[1])
    assert rec.errors.empty and rec.untimed.reason.tolist() == [NO_REFERENCE]
    assert len(decode_bytes(data, categories=[1, 2]).errors) == 1


def test_a_cat002_time_past_midnight_is_no_reference() -> None:
    # I002/030 0xFFFFFF = 131071.99 s: no time of day; the reference stays the one before it
    data = (block(2, sector(R1, 36000.0)) + block(2, fspec(1, 2, 4) + bytes([*R1, 2]) + b"\xff\xff\xff")
            + block(1, plot(R1, 161.5)))
    assert decode_bytes(data, categories=[1]).frames[1].time_of_day.tolist() == [36001.5]


def test_midnight_days_and_timestamps() -> None:
    data = (block(2, sector(R1, 86399.0)) + block(1, plot(R1, 383.5), plot(R1, 0.25))
            + block(2, sector(R1, 0.5)) + block(1, plot(R1, 1.0), plot(R1, 383.875)))
    rec = decode_bytes(data, categories=[1, 2], date="2019-03-01")
    f = rec.frames[1]
    # 86016 + 383.5; 0.25 the next day; 1.0; and a late plot of the day before (86016 + 383.875)
    assert f.time_of_day.tolist() == [86399.5, 0.25, 1.0, 86399.875]
    assert f.day.tolist() == [0, 1, 1, 0]
    assert f.timestamp.tolist() == [pd.Timestamp(t, tz="UTC") for t in (
        "2019-03-01 23:59:59.5", "2019-03-02 00:00:00.25", "2019-03-02 00:00:01", "2019-03-01 23:59:59.875")]
    assert rec.frames[2].day.tolist() == [0, 1] and rec.date == dt.date(2019, 3, 1)


def test_read_warns_with_counts_and_offsets(tmp_path) -> None:
    data, offs, _, _ = stream_a()
    path = tmp_path / "radar.ast"
    path.write_bytes(data)
    with pytest.warns(asterix.UntimedWarning) as caught:
        rec = asterix.read(path, categories=[1])
    texts = [str(w.message) for w in caught if issubclass(w.category, asterix.UntimedWarning)]
    assert f"{path}: 2 CAT001 record(s) have no time of day: {NO_REFERENCE} (offsets {offs[0]}, {offs[2]};" \
           in texts[0]
    assert len(texts) == 5 and len(rec.untimed) == 6
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        asterix.read(path)  # CAT001 not decoded: nothing to say


@pytest.mark.parametrize("chunk", [1, 20, 45, 1000])
def test_iter_read_dates_records_as_read_does(tmp_path, chunk: int) -> None:
    data, _, times, reasons = stream_a()
    data += block(1, plot(R1, 260.5))  # the refreshed reference carries on
    path = tmp_path / "radar.ast"
    path.write_bytes(data)
    whole = asterix.decode_buffer(np.frombuffer(data, np.uint8),
                                  asterix.reader.read_segments(np.frombuffer(data, np.uint8), "raw"),
                                  path=str(path), categories=[1])
    parts = list(asterix.iter_read(path, chunk=chunk, categories=[1]))
    assert len(parts) > 1 or chunk == 1000
    frames = pd.concat([p.frames[1] for p in parts if 1 in p.frames], ignore_index=True)
    np.testing.assert_array_equal(frames.time_of_day.to_numpy(), [*times, 36100.5])
    np.testing.assert_array_equal(frames.time_of_day.to_numpy(), whole.frames[1].time_of_day.to_numpy())
    untimed = pd.concat([p.untimed for p in parts], ignore_index=True)
    assert untimed.offset.tolist() == whole.untimed.offset.tolist()
    assert untimed.reason.tolist() == [r for r in reasons if r]


def test_a_column_selection_keeps_the_time() -> None:
    # the truncated time of day is decoded whatever the selection: the whole time is made from it
    data, _, times, _ = stream_a()
    rec = decode_bytes(data, categories=[1], columns=["rho_nm"])
    f = rec.frames[1]
    np.testing.assert_array_equal(f.time_of_day.to_numpy(), times)
    assert "truncated_time_of_day" in f and "typ" not in f


def test_cat002_auto_when_only_cat001_is_decoded() -> None:
    data, _, times, _ = stream_a()
    rec = decode_bytes(data, categories=[1], editions={2: "auto"})
    np.testing.assert_array_equal(rec.frames[1].time_of_day.to_numpy(), times)
