"""Batches of datagrams decoded into the LiveState (pipeline.live.decode, pipeline.live.state), on records
built by hand from the CAT048 and CAT034 specifications (and CAT010/CAT020/CAT062 by msdc's encoder): what is
counted where, what a damaged datagram keeps, status messages and the recent reports' validity flags."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
from asterix_bytes import block
from live_bytes import cat034_north_marker, cat048_record
from pyproj import Geod

from msdc.asterix.encode import encode_frame
from msdc.pipeline.jobs.common import sensor_table
from msdc.pipeline.live.decode import BatchDecoder, Datagram
from msdc.pipeline.live.health import Thresholds, lookback_s, snapshot
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


def test_an_empty_datagram_is_counted_empty_and_the_packets_add_up():
    """An empty datagram counted as a packet but as neither unframed nor framed nor an error: a feed's
    packets did not add up. Each of these 5 datagrams is one of framed (2 whole blocks), unframed (the cut
    one, the garbage) or empty (1)."""
    good = block(48, cat048_record(25, 201, 80000.0))
    batch = [Datagram(0, WALL, good), Datagram(0, WALL, b""), Datagram(0, WALL, good + good[:-4]),
             Datagram(1, WALL, good), Datagram(1, WALL, b"not ASTERIX")]
    state, decoder = _state_and_decoder()
    for d in batch:  # as the receiving threads count them
        state.received(FEEDS[d.feed], len(d.data), d.wall_s)
    _, memory = snapshot(state.recent(60.0), state.counters(), {}, WALL, WALL - 10, Thresholds())
    decoder.decode(batch)
    c = state.counters()
    split = {f: {k: c[f][k] for k in ("packets", "framed", "unframed", "empty", "dropped", "decode_errors")}
             for f in FEEDS}
    assert split == {FEEDS[0]: {"packets": 3, "framed": 1, "unframed": 1, "empty": 1, "dropped": 0,
                                "decode_errors": 0},
                     FEEDS[1]: {"packets": 2, "framed": 1, "unframed": 1, "empty": 0, "dropped": 0,
                                "decode_errors": 0}}
    assert c[FEEDS[0]]["records"] == {"048:25/201": 2}
    snap, _ = snapshot(state.recent(60.0), c, {}, WALL + 1, WALL - 10, Thresholds(), memory)
    assert [(f["empty"], f["waiting"]) for f in snap["feeds"]] == [(1, 0), (0, 0)]
    assert [a["kind"] for a in snap["alarms"] if "feed" in a] == ["unframed", "unframed"]  # empty: no warning


def test_a_batch_the_decoder_fails_on_still_adds_up(monkeypatch):
    """A batch the kernel raises on: each of its 2 datagrams with bytes is a decode error and, never framed,
    unframed; the empty one is empty."""
    import msdc.asterix

    def broken(*args, **kwargs):
        raise RuntimeError("broken on purpose")

    monkeypatch.setattr(msdc.asterix, "decode_buffer", broken)
    state, decoder = _state_and_decoder()
    decoder.decode([Datagram(0, WALL, b"\x30\x00\x03"), Datagram(0, WALL, b""), Datagram(0, WALL, b"x")])
    c = state.counters()[FEEDS[0]]
    assert (c["decode_errors"], c["unframed"], c["empty"], c["framed"]) == (2, 2, 1, 0)


def test_a_block_that_frames_but_does_not_decode_is_a_decode_error():
    # FSPEC with FRN 1 only (SAC/SIC), then one byte where two are due: the record runs past its block
    bad = block(48, bytes([0x80, 25]))
    state, decoder = _state_and_decoder()
    decoder.decode([Datagram(0, WALL, bad), Datagram(0, WALL, block(48, cat048_record(25, 201, 1.0)))])
    c = state.counters()[FEEDS[0]]
    assert c["decode_errors"] == 1 and c["unframed"] == 0 and c["records"] == {"048:25/201": 1}


def test_records_naming_a_made_up_sensor_are_no_sensor_of_the_page():
    """A block of three plots of 25/201 whose last record names 7/9 (no block's sensor: damage inside the
    block): 7/9 got counters of its own, a sensor no feed has. The record is left out and its block counted
    as a decode error; the two plots before it are kept."""
    odd = block(48, cat048_record(25, 201, 100.0), cat048_record(25, 201, 100.5), cat048_record(7, 9, 101.0))
    state, decoder = _state_and_decoder()
    decoder.decode([Datagram(0, WALL, odd), Datagram(0, WALL, block(48, cat048_record(25, 201, 102.0)))])
    c = state.counters()[FEEDS[0]]
    assert c["records"] == {"048:25/201": 3} and c["decode_errors"] == 1


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
        decoder.decode([Datagram(1, WALL - 0.5, block(48, *records[:2])),  # a block per radar, as radars send
                        Datagram(1, WALL - 0.5, block(48, records[2]))])
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


def _snapshot(state: LiveState, now: float) -> dict:
    thresholds = Thresholds()
    frame = state.recent(lookback_s(thresholds))
    snap, _ = snapshot(frame, state.counters(), state.status_times(), now, WALL - 10, thresholds)
    return snap


def test_a_tracker_feed_is_heard_though_its_tracks_make_no_reports():
    """CAT062 system tracks are counted, not measured, live: their sensor is heard by their arrival (it
    raised a 'silent' alarm while its tracks arrived) and its figures say why they are withheld."""
    tracks = pd.DataFrame({"sac": [1] * 3, "sic": [2] * 3, "time_of_day": [79990.0, 79991.0, 79992.0],
                           "latitude": [45.0, 45.001, 45.002], "longitude": [5.0] * 3,
                           "track_number": [7] * 3})
    now = [WALL + 1]
    state = LiveState(FEEDS, clock=lambda: now[0])
    BatchDecoder(state, FEEDS).decode([Datagram(0, WALL - 0.4, encode_frame(62, tracks))])
    snap = _snapshot(state, now[0])
    (panel,) = snap["sensors"]
    assert (panel["sensor_id"], panel["records_total"], panel["reports_in_window"]) == ("062:1/2", 3, 0)
    assert math.isclose(panel["last_report_age_s"], 1.4, abs_tol=1e-6)
    assert snap["alarms"] == [] and panel["reports_per_s"] is None
    assert panel["pd"]["state"] == "withheld" and "counted, not measured" in panel["pd"]["note"]
    now[0] = WALL - 0.4 + Thresholds().silent_s + 1  # then nothing more for longer than silent_s
    assert [a["kind"] for a in _snapshot(state, now[0])["alarms"]] == ["silent"]


SENSOR_FILE = """
[[sensor]]
name = "SMR"
category = 10
kind = "smr"
sac = 0
sic = 7
latitude = 45.0
longitude = 5.0
altitude_m = 0.0
"""


def test_multilateration_and_surface_radar_reports_are_measured_live(tmp_path):
    """CAT020 reports placed by their WGS-84 position, CAT010 surface radar reports by x/y from the sensor
    file's reference point (checked with pyproj's geodesic), each with its sensor's panel, its validity bits
    and its targets on the map; a CAT010 status message gives the surface radar its last status."""
    path = tmp_path / "sensors.toml"
    path.write_text(SENSOR_FILE)
    wam = pd.DataFrame({"sac": [25] * 3, "sic": [10] * 3, "time_of_day": [79990.0, 79991.0, 79992.0],
                        "latitude": [45.0, 45.01, 45.02], "longitude": [5.5] * 3, "track_number": [7] * 3,
                        "mode3a": ["1234"] * 3, "mode3a_v": [0, 1, 0]})
    smr = pd.DataFrame({"sac": [0] * 3, "sic": [7] * 3, "message_type": [1] * 3, "typ": [3] * 3,
                        "time_of_day": [79990.0, 79991.0, 79992.0], "x_m": [1000.0, 1010.0, 1020.0],
                        "y_m": [2000.0] * 3, "track_number": [12] * 3})
    status = pd.DataFrame({"sac": [0], "sic": [7], "message_type": [3], "time_of_day": [79992.5]})
    state = LiveState(FEEDS, clock=lambda: WALL + 1)
    decoder = BatchDecoder(state, FEEDS, sensors=sensor_table(path))
    decoder.decode([Datagram(0, WALL - 0.5, encode_frame(20, wam)),
                    Datagram(1, WALL - 0.3, encode_frame(10, smr)),
                    Datagram(1, WALL - 0.2, encode_frame(10, status))])
    recent = state.recent(60.0)
    assert sorted(recent["sensor_id"].astype(str)) == ["010:0/7:smr"] * 3 + ["020:25/10"] * 3
    by = {k: g.sort_values("time") for k, g in recent.groupby(recent["sensor_id"].astype(str))}
    assert by["020:25/10"]["sensor_kind"].astype(str).tolist() == ["mlat"] * 3
    assert by["010:0/7:smr"]["sensor_kind"].astype(str).tolist() == ["smr"] * 3
    lsb = 180 / 2**25  # I020/041
    assert np.allclose(by["020:25/10"]["latitude"], [45.0, 45.01, 45.02], atol=lsb)
    assert by["020:25/10"]["mode3a_valid"].tolist() == [True, False, True]
    geod = Geod(ellps="WGS84")
    for (x, y), (lat, lon) in zip(smr[["x_m", "y_m"]].to_numpy(),
                                  by["010:0/7:smr"][["latitude", "longitude"]].to_numpy(), strict=True):
        want_lon, want_lat, _ = geod.fwd(5.0, 45.0, math.degrees(math.atan2(x, y)), math.hypot(x, y))
        assert abs(lat - want_lat) < 1e-6 and abs(lon - want_lon) < 1e-6  # 0.1 m
    snap = _snapshot(state, WALL + 1)
    panels = {p["sensor_id"]: p for p in snap["sensors"]}
    assert set(panels) == {"020:25/10", "010:0/7:smr"}  # the status message makes no panel of its own
    assert panels["010:0/7:smr"]["records_total"] == 3 and panels["010:0/7:smr"]["kind"] == "smr"
    assert math.isclose(panels["010:0/7:smr"]["last_status_age_s"], 1.2, abs_tol=1e-6)
    assert panels["020:25/10"]["reports_in_window"] == 3 and panels["020:25/10"]["kind"] == "mlat"
    assert {t["sensor_id"] for t in snap["targets"]} == {"020:25/10", "010:0/7:smr"}
    assert snap["alarms"] == []


def test_reports_without_a_track_beside_tracked_ones_leave_the_figures_standing(tmp_path):
    """A sensor whose reports carry no track number (here CAT020 without I020/161; the real CAT021 0.23
    ADS-B feed of LEBL) beside one whose reports do: its figures are withheld, the other's are measured
    (the snapshot failed on the mix: a missing key read back as NaN); the map draws both."""
    path = tmp_path / "sensors.toml"
    path.write_text(SENSOR_FILE)
    times = [79990.0 + i for i in range(12)]
    wam = pd.DataFrame({"sac": 25, "sic": 10, "time_of_day": times, "latitude": 45.0, "longitude": 5.5,
                        "address": "4CA123"})
    smr = pd.DataFrame({"sac": 0, "sic": 7, "message_type": 1, "typ": 3, "time_of_day": times,
                        "x_m": [1000.0 + 10 * i for i in range(12)], "y_m": 2000.0, "track_number": 12})
    state = LiveState(FEEDS, clock=lambda: WALL + 1)
    BatchDecoder(state, FEEDS, sensors=sensor_table(path)).decode(
        [Datagram(0, WALL - 0.5, encode_frame(20, wam)), Datagram(1, WALL - 0.3, encode_frame(10, smr))])
    snap = _snapshot(state, WALL + 1)
    panels = {p["sensor_id"]: p for p in snap["sensors"]}
    assert panels["020:25/10"]["pd"]["state"] == "withheld"
    assert panels["020:25/10"]["update_interval_s"] is None
    assert math.isclose(panels["010:0/7:smr"]["update_interval_s"], 1.0, rel_tol=1e-3)  # one report a second
    # the map follows the untracked reports by their Mode S address, the tracked ones by their track
    assert sorted(t["id"] for t in snap["targets"]) == ["010:0/7:smr|T12", "020:25/10|A:4CA123"]


def test_a_garbled_code_is_not_valid_live_as_in_the_evaluation():
    """I048/070 and I048/090 bit 15 (G, garbled) set with V clear: not valid, as the evaluation's
    mode3a_valid and modec_valid count it ("validated and not garbled")."""
    records = [cat048_record(25, 201, 80000.0, mode3a_g=1), cat048_record(25, 201, 80001.0, modec_g=1),
               cat048_record(25, 201, 80002.0)]
    state, decoder = _state_and_decoder()
    decoder.decode([Datagram(0, WALL - 0.5, block(48, *records))])
    recent = state.recent(60.0)
    assert list(recent["mode3a_valid"]) == [False, True, True]
    assert list(recent["modec_valid"]) == [True, False, True]
    assert list(recent["mode3a"].astype(str)) == ["1234"] * 3  # the code itself still read


def test_the_map_leaves_out_an_adsb_position_no_ground_station_receives():
    """The real LEBL ADS-B hour holds a few positions 1,000-2,400 NM away (IBK2PU at FL315); drawn, they
    set the map's scale to rings of 1,000 NM. As the measurements do (model.coverage: beyond 500 NM and
    three times the source's 99th percentile distance from its median position), the map leaves them out."""
    n = 200  # 20 aircraft near Barcelona, 10 reports each, and one report from 60 N 40 E (about 1,700 NM)
    times = [80000.0 + i / 10 for i in range(n)]
    near = pd.DataFrame({"sac": 0, "sic": 107, "time_reception_position": times,
                         "latitude": [41.3 + (i % 20) * 0.01 for i in range(n)], "longitude": 2.08,
                         "address": [f"3451{i % 20:02X}" for i in range(n)]})
    stray = pd.DataFrame({"sac": 0, "sic": 107, "time_reception_position": [80020.0], "latitude": [60.0],
                          "longitude": [40.0], "address": ["3451FF"]})
    state, decoder = _state_and_decoder()
    decoder.decode([Datagram(0, WALL - 0.5, encode_frame(21, pd.concat([near, stray], ignore_index=True)))])
    snap = _snapshot(state, WALL + 1)
    drawn = {t["track"] for t in snap["targets"]}
    assert drawn == {f"A:3451{k:02X}" for k in range(20)}
    assert abs(snap["centre"]["latitude"] - 41.395) < 0.01 and abs(snap["centre"]["longitude"] - 2.08) < 1e-4


def test_an_adsb_probability_of_update_is_shown_not_judged():
    """ADS-B reports follow the squitters a station receives (the real LEBL feed keyed by address: a 0.55 s
    'period' and 71 % of its updates): against the radar threshold that was a standing 'degraded' alarm.
    Ten tracks at 0.5 s with every fourth report lost: a figure below the threshold, shown unjudged, no
    alarm."""
    t = np.arange(0.0, 30.0, 0.5)
    kept = t[np.arange(len(t)) % 4 != 3]
    adsb = pd.DataFrame({"sac": 0, "sic": 1, "time_reception_position": np.tile(79970.0 + kept, 10),
                         "track_number": np.repeat(np.arange(1, 11), len(kept)),
                         "latitude": np.repeat(41.0 + np.arange(10) * 0.1, len(kept)), "longitude": 2.0,
                         "address": np.repeat([f"3400{k:02X}" for k in range(10)], len(kept))})
    state, decoder = _state_and_decoder()
    decoder.decode([Datagram(0, WALL - 0.5, encode_frame(21, adsb))])
    snap = _snapshot(state, WALL + 1)
    (panel,) = snap["sensors"]
    assert panel["kind"] == "adsb" and panel["pd"]["state"] == "unjudged"
    assert panel["pd"]["value"] < 0.97 <= panel["pd"]["threshold"]  # below the radar threshold: no alarm
    assert "not judged" in panel["pd"]["note"] and snap["alarms"] == [] and panel["alarms"] == []
