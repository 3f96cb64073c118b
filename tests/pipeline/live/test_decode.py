"""Batches of datagrams decoded into the LiveState (pipeline.live.decode, pipeline.live.state), on records
built by hand from the CAT048 and CAT034 specifications: what is counted where, what a damaged datagram
keeps, status messages and the recent reports' validity flags."""

from __future__ import annotations

import math

import pandas as pd
from asterix_bytes import block
from live_bytes import cat034_north_marker, cat048_record

from msdc.pipeline.jobs.common import sensor_table
from msdc.pipeline.live.decode import BatchDecoder, Datagram
from msdc.pipeline.live.state import LiveState
from msdc.pipeline.model.schema import MEASUREMENT_COLUMNS

FEEDS = ["udp:239.1.2.3:8600", "udp:239.1.2.4:8600"]
WALL = 1_700_000_000.0  # 2023-11-14 22:13:20 UTC
SENSORS = "fixtures/sensors.toml"  # KLIA MSSR, SAC 25 SIC 201


def _state_and_decoder(**kw) -> tuple[LiveState, BatchDecoder]:
    state = LiveState(FEEDS, clock=lambda: WALL + 1)
    return state, BatchDecoder(state, FEEDS, **kw)


def test_damaged_datagrams_are_counted_and_what_frames_is_kept():
    good = block(48, cat048_record(25, 201, 80000.0), cat048_record(25, 201, 80000.5))  # 2 records
    second = block(48, cat048_record(25, 201, 80001.0))
    state, decoder = _state_and_decoder()
    decoder.decode([
        Datagram(0, WALL, good),
        Datagram(0, WALL, second + second[:-4]),  # a whole block, then one cut short: 1 record kept
        Datagram(1, WALL, b"this is not ASTERIX at all"),  # garbage
        Datagram(1, WALL, good[:2]),  # shorter than a block header
    ])
    c = state.counters()
    assert c[FEEDS[0]]["records"] == {"048:25/201": 3} and c[FEEDS[0]]["unframed"] == 1
    assert c[FEEDS[1]]["records"] == {} and c[FEEDS[1]]["unframed"] == 2
    assert c[FEEDS[0]]["decode_errors"] == c[FEEDS[1]]["decode_errors"] == 0


def test_a_block_that_frames_but_does_not_decode_is_a_decode_error():
    # FSPEC with FRN 1 only (SAC/SIC), then one byte where two are due: the record runs past its block
    bad = block(48, bytes([0x80, 25]))
    state, decoder = _state_and_decoder()
    decoder.decode([Datagram(0, WALL, bad), Datagram(0, WALL, block(48, cat048_record(25, 201, 1.0)))])
    c = state.counters()[FEEDS[0]]
    assert c["decode_errors"] == 1 and c["unframed"] == 0 and c["records"] == {"048:25/201": 1}


def test_two_feeds_with_the_same_sac_sic_are_kept_apart():
    one = block(48, cat048_record(25, 201, 100.0))
    state, decoder = _state_and_decoder()
    decoder.decode([Datagram(0, WALL, one), Datagram(1, WALL, one), Datagram(1, WALL, one)])
    c = state.counters()
    assert c[FEEDS[0]]["records"] == {"048:25/201": 1} and c[FEEDS[1]]["records"] == {"048:25/201": 2}
    assert state.clashes() == {"048:25/201": FEEDS}


def test_a_north_marker_times_its_radar():
    state, decoder = _state_and_decoder()
    decoder.decode([Datagram(0, WALL + 0.25, cat034_north_marker(20, 129, 100.0)),
                    Datagram(0, WALL + 0.5, cat034_north_marker(20, 129, 104.0))])
    assert state.status_times() == {"034:20/129": WALL + 0.5, "048:20/129": WALL + 0.5}
    assert state.counters()[FEEDS[0]]["records"] == {"034:20/129": 2}


def test_recent_reports_carry_the_validity_bits_and_positions():
    # 22:13:20 UTC is 80000 s after midnight: reports at 79999 s and 80000 s of 2023-11-14
    records = [cat048_record(25, 201, 79999.0, mode3a_v=1), cat048_record(25, 201, 80000.0, modec_v=1),
               cat048_record(30, 1, 80000.0)]
    for sensors, placed in ((None, [False, False, False]), (sensor_table(SENSORS), [True, True, False])):
        state, decoder = _state_and_decoder(sensors=sensors)
        decoder.decode([Datagram(1, WALL - 0.5, block(48, *records))])
        recent = state.recent(60.0)
        assert set(MEASUREMENT_COLUMNS) <= set(recent.columns)
        assert list(recent["sensor_id"].astype(str)) == ["048:25/201", "048:25/201", "048:30/1"]
        assert list(recent["mode3a_valid"]) == [False, True, True]
        assert list(recent["modec_valid"]) == [True, False, True]
        assert list(recent["latitude"].notna()) == placed
        assert list(recent["feed"]) == [FEEDS[1]] * 3 and list(recent["wall_s"]) == [WALL - 0.5] * 3
        assert list(recent["time"]) == [pd.Timestamp("2023-11-14 22:13:19", tz="UTC"),
                                        pd.Timestamp("2023-11-14 22:13:20", tz="UTC"),
                                        pd.Timestamp("2023-11-14 22:13:20", tz="UTC")]
        assert list(recent["mode3a"].astype(str)) == ["1234"] * 3
        assert math.isclose(recent["rho_nm"].iloc[0], 50.0)
        assert math.isclose(recent["flight_level"].iloc[2], 350)
        assert len(state.recent(0.4)) == 0  # arrived 1.5 s before the clock's now


def test_old_reports_leave_the_ring():
    now = [WALL]
    state = LiveState(FEEDS, keep_s=10.0, clock=lambda: now[0])
    decoder = BatchDecoder(state, FEEDS)
    decoder.decode([Datagram(0, WALL, block(48, cat048_record(25, 201, 80000.0)))])
    now[0] = WALL + 11
    decoder.decode([Datagram(0, WALL + 11, block(48, cat048_record(25, 201, 80011.0)))])
    assert len(state.recent(3600.0)) == 1 and state.counters()[FEEDS[0]]["records"] == {"048:25/201": 2}
