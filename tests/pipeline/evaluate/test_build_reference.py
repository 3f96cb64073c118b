"""The reference builders (pipeline/evaluate/build_reference.py) against the two-radar simulation's truth, the
reference gates counted on reports whose indicators are set by hand, the sigma gate on a hand-made reference,
and the external reference file refused line by line."""

from __future__ import annotations

import re
import warnings

import numpy as np
import pandas as pd
import pytest

from fixtures.multiradar import simulate_two_radars
from msdc.pipeline.evaluate.build_reference import BUILT_COLUMNS, adsb_reference, leave_one_out
from msdc.pipeline.evaluate.external_reference import ExternalReferenceError, read_external_reference
from msdc.pipeline.evaluate.reference import associate, local_distance_m
from msdc.pipeline.evaluate.reference_gates import Gates, gate_reports, independent_reference, sigma_gate
from msdc.pipeline.model.measurements import build_measurements
from msdc.pipeline.model.sensors import read_sensors

RADAR_A, RADAR_B, ADSB = "048:25/201", "048:25/202", "021:0/1"
EPOCH = pd.Timestamp("2019-03-01", tz="UTC")
WINDOW = pd.Timedelta(minutes=15)


@pytest.fixture(scope="module")
def two_radars(tmp_path_factory):
    """The two-radar simulation and its measurements, one aircraft (MAS72, sim aircraft 0) over 15 minutes."""
    m = simulate_two_radars()
    path = tmp_path_factory.mktemp("sensors") / "sensors.toml"
    path.write_text(m.sensors_toml())
    radar = pd.concat([m.sim.radar, m.radar2], ignore_index=True)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        meas = build_measurements(radar, m.sim.adsb, read_sensors(path), date=EPOCH.date())
    address = m.sim.aircraft[0].spec.address_hex
    meas = meas[(meas["aircraft_id"] == address) & (meas["time"] < meas["time"].min() + WINDOW)]
    return m, meas.reset_index(drop=True)


def truth_error_m(m, frame: pd.DataFrame) -> np.ndarray:
    """Horizontal distance of each reference row from sim aircraft 0's true position at its time."""
    st = m.sim.aircraft[0].truth(frame["t_s"].to_numpy(float))
    return local_distance_m(frame["latitude"].to_numpy(float), frame["longitude"].to_numpy(float),
                            st.latitude, st.longitude)


def test_leave_one_out_is_built_without_the_sensor_and_lies_near_the_truth(two_radars):
    m, meas = two_radars
    ref = leave_one_out(meas, RADAR_A, epoch=EPOCH).frame
    assert list(ref.columns) == list(BUILT_COLUMNS)
    independent = independent_reference(ref)
    assert len(independent) > 500 and len(independent) < len(ref)
    assert not independent["built_by"].str.contains(RADAR_A, regex=False).any()
    assert set(independent["built_by"]) <= {ADSB, RADAR_B, f"{ADSB} + {RADAR_B}"}
    # the self-reference rows are the radar's own track, where neither ADS-B nor radar B covers the aircraft
    assert (ref.loc[ref["self_reference"], "built_by"] == RADAR_A).all()
    # updated rows are exactly at the times of the reports that built them (the others are the tracker's
    # 1 s steps between reports): what coasting_correct judges a coasting flag by
    t_rep = (meas["time"] - EPOCH).dt.total_seconds().to_numpy()
    others = (meas["sensor_id"].astype(str) != RADAR_A).to_numpy()
    for own, built_by in ((False, others), (True, ~others)):
        rows = ref[(ref["self_reference"] == own) & ref["updated"]]
        assert len(rows) > 40
        assert np.abs(rows["t_s"].to_numpy()[:, None] - t_rep[built_by][None, :]).min(axis=1).max() < 1e-6
    assert 0.2 < independent["updated"].mean() < 0.8
    # within a few of its own sigmas of the simulator's truth, and well inside the radars' noise
    err = truth_error_m(m, independent)
    ratio = err / independent["sigma_m"].to_numpy(float)
    assert np.quantile(ratio, 0.99) < 4.0 and ratio.max() < 6.0
    # sigma_m is the major axis: the 2-D error's RMS is at most sqrt(2) sigma for an honest sigma
    assert np.sqrt(np.mean(ratio**2)) < np.sqrt(2.0)
    # where ADS-B builds it (sigma a few metres) the error is a few metres; through the 479 s ADS-B gap,
    # radar B alone (10 s scans, 120 m in range) builds it, and its sigma grows to 100 m and more
    precise = independent["sigma_m"].to_numpy(float) < 10.0
    assert precise.sum() > 500 and np.sqrt(np.mean(err[precise] ** 2)) < 10.0
    assert independent["sigma_m"].max() > 80.0
    # the identity comes from the reports that built it
    assert set(independent["callsign"]) == {m.sim.aircraft[0].spec.callsign}


def test_leave_one_out_ignores_the_sensor_under_test(two_radars):
    """Radar A's plots moved 5 km north: the independent reference does not move at all."""
    _, meas = two_radars
    moved = meas.copy()
    a = (moved["sensor_id"] == RADAR_A).to_numpy()
    moved.loc[a, "latitude"] += 5000.0 / 111_000.0
    before = leave_one_out(meas, RADAR_A, epoch=EPOCH).frame
    after = leave_one_out(moved, RADAR_A, epoch=EPOCH).frame
    pd.testing.assert_frame_equal(before[~before["self_reference"]].reset_index(drop=True),
                                  after[~after["self_reference"]].reset_index(drop=True))
    # while the reference of radar B, which radar A builds, does move
    b_before = leave_one_out(meas, RADAR_B, epoch=EPOCH, fallback=False).frame
    b_after = leave_one_out(moved, RADAR_B, epoch=EPOCH, fallback=False).frame
    both = b_before.merge(b_after, on="t_s")
    assert local_distance_m(both["latitude_x"], both["longitude_x"], both["latitude_y"],
                            both["longitude_y"]).max() > 1000.0


def test_adsb_reference_is_built_by_adsb_alone(two_radars):
    m, meas = two_radars
    ref = adsb_reference(meas, RADAR_A, epoch=EPOCH, fallback=False).frame
    assert (ref["built_by"] == ADSB).all() and not ref["self_reference"].any()
    err = truth_error_m(m, ref)
    assert np.quantile(err / ref["sigma_m"].to_numpy(float), 0.99) < 4.0


def test_single_radar_falls_back_to_its_own_track_flagged(two_radars):
    m, meas = two_radars
    alone = meas[meas["sensor_id"] == RADAR_A]
    built = leave_one_out(alone, RADAR_A, epoch=EPOCH)
    ref = built.frame
    assert len(ref) > 500 and ref["self_reference"].all() and (ref["built_by"] == RADAR_A).all()
    assert built.notes and "self-reference" in built.notes[0]
    assert independent_reference(ref).empty
    # position accuracy may not use it: every associated report is excluded as self-referenced
    reports = ref.iloc[100:110][["t_s", "latitude", "longitude"]].reset_index(drop=True)
    gate = sigma_gate(reports, ref, tolerance_m=1000.0)
    assert gate.counts["self_reference"] == 10 and gate.counts["judged"] == 0
    # detection and codes may: without the independence rule the same reports are judged
    assert sigma_gate(reports, ref, tolerance_m=1000.0, independent=False).counts["judged"] == 10
    assert not leave_one_out(alone, RADAR_A, epoch=EPOCH, fallback=False).frame.shape[0]


def test_unknown_sensor_is_refused(two_radars):
    _, meas = two_radars
    with pytest.raises(ValueError, match="048:99/1.*present: 021:0/1"):
        leave_one_out(meas, "048:99/1")


def test_gates_remove_and_count_exactly(two_radars):
    """Every ADS-B report set to NACp 9, NIC 8, SIL 3, then chosen ones lowered or blanked by hand."""
    _, meas = two_radars
    meas = meas.copy()
    adsb = np.flatnonzero((meas["sensor_kind"] == "adsb").to_numpy())
    meas["nacp"] = meas["nacp"].astype(float)
    meas["nucp_nic"] = meas["nucp_nic"].astype(float)
    meas["sil"] = meas["sil"].astype(float)
    meas.loc[adsb, ["nacp", "nucp_nic", "sil"]] = [9.0, 8.0, 3.0]
    low_nic, low_nacp, no_nacp = adsb[0:5], adsb[10:27], adsb[30:33]
    low_sil, no_sil = adsb[40:51], adsb[60:62]
    meas.loc[low_nic, "nucp_nic"] = 6.0
    meas.loc[low_nacp, "nacp"] = 7.0
    meas.loc[no_nacp, "nacp"] = np.nan
    meas.loc[low_sil, "sil"] = 1.0
    meas.loc[no_sil, "sil"] = np.nan
    meas.loc[low_sil[:2], "nacp"] = 5.0  # below both: counted once, by NACp, which runs first
    kept, counts = gate_reports(meas, Gates(min_nacp=8, min_nic=7, min_sil=2))
    assert counts["nic_below_min"] == 5
    assert counts["nacp_below_min"] == 17 + 2 and counts["nacp_missing_kept"] == 3
    assert counts["sil_below_min"] == 9 and counts["sil_missing_kept"] == 2
    assert len(kept) == len(meas) - 5 - 19 - 9
    assert (kept["sensor_kind"] == "radar").sum() == (meas["sensor_kind"] == "radar").sum()
    built = leave_one_out(meas, RADAR_A, epoch=EPOCH, gates=Gates(min_nacp=8, min_nic=7, min_sil=2))
    assert built.gate_counts == counts


def test_jumps_dropped_are_the_simulated_jumps(two_radars):
    """The simulator's ADS-B position jumps (hundreds of km, flagged in its truth) are the ones dropped."""
    m, meas = two_radars
    truth = m.sim.truth_tracks
    t0 = EPOCH + pd.to_timedelta(truth["t_s"], unit="s")
    mine = truth[(truth["sensor"] == "adsb") & (truth["aircraft"] == 0) & (t0 >= meas["time"].min())
                 & (t0 <= meas["time"].max())]
    jumps = int(mine["jump"].sum())
    if jumps == 0:
        pytest.skip("no simulated ADS-B jump in this aircraft's window")
    _, counts = gate_reports(meas, Gates(drop_jumps=True))
    assert counts["jumps"] == jumps


def hand_reference() -> pd.DataFrame:
    """Aircraft A flying north along longitude 0 at 100 m/s from t = 0 to 500 s: sigma 10 m before 100 s,
    50 m from 100 to 200 s, 10 m and self-referenced from 200 to 300 s, unknown from 300 s."""
    t = np.arange(0.0, 501.0, 1.0)
    sigma = np.where(t < 100, 10.0, np.where(t < 200, 50.0, np.where(t < 300, 10.0, np.nan)))
    return pd.DataFrame({"aircraft": "A", "t_s": t, "latitude": t * 100.0 / 111_000.0, "longitude": 0.0,
                         "sigma_m": sigma, "self_reference": (t >= 200) & (t < 300)})


def test_sigma_gate_counts_each_exclusion():
    ref = hand_reference()
    times = np.array([10.5, 50.0, 99.0, 150.0, 160.0, 250.0, 350.0, 400.0, 420.0])
    reports = pd.DataFrame({"t_s": np.append(times, 60.0),
                            "latitude": np.append(times * 100.0 / 111_000.0, 0.0),
                            "longitude": np.append(np.zeros(times.size), 1.0)})  # the last one 111 km off
    gate = sigma_gate(reports, ref, tolerance_m=60.0)  # a third of 60 m: sigma below 20 m
    assert gate.counts == {"reports": 10, "judged": 3, "no_reference": 1, "self_reference": 1,
                           "sigma_unknown": 3, "sigma_too_large": 2}
    np.testing.assert_array_equal(gate.judged, [True] * 3 + [False] * 7)
    # a tolerance of 300 m lets sigma 50 m in (below 100 m)
    assert sigma_gate(reports, ref, tolerance_m=300.0).counts["judged"] == 5
    # the bracketing samples at 99 and 100 s are 10 and 50 m: at 99.5 s, 30 m, too large for 60 m
    between = pd.DataFrame({"t_s": [99.5], "latitude": [99.5 * 100.0 / 111_000.0], "longitude": [0.0]})
    assert sigma_gate(between, ref, tolerance_m=60.0).counts["sigma_too_large"] == 1
    wider = sigma_gate(between, ref, tolerance_m=60.0, parameters={"sigma_fraction": 0.6})
    assert wider.counts["judged"] == 1
    # reports already associated are not associated again
    assert sigma_gate(associate(reports, ref), ref, tolerance_m=60.0).counts == gate.counts
    with pytest.raises(ValueError, match="tolerance"):
        sigma_gate(reports, ref, tolerance_m=0.0)


GOOD = ("aircraft,time,latitude,longitude,altitude_ft,callsign\n"
        "TRIAL1,2019-03-01T08:00:00Z,3.1,101.5,12000,FLT01\n"
        "TRIAL1,2019-03-01T08:00:01.5+00:00,3.1005,101.5,12010,FLT01\n"
        "TRIAL2,2019-03-01T09:00:00+01:00,3.2,101.6,,\n")


def test_external_reference_reads_a_good_file(tmp_path):
    path = tmp_path / "gps.csv"
    path.write_text(GOOD.replace(",,\n", ",,\n").replace("101.6,,", "101.6,5000,"))
    ref = read_external_reference(path, EPOCH, sigma_m=3.0)
    assert list(ref["aircraft"]) == ["TRIAL1", "TRIAL1", "TRIAL2"]
    np.testing.assert_allclose(ref["t_s"], [28800.0, 28801.5, 28800.0])  # 09:00+01:00 is 08:00 UTC
    np.testing.assert_allclose(ref["altitude_ft"], [12000.0, 12010.0, 5000.0])
    assert (ref["sigma_m"] == 3.0).all() and (ref["built_by"] == "external").all()
    assert not ref["self_reference"].any() and ref["updated"].all() and ref["callsign"].iloc[0] == "FLT01"
    assert pd.isna(ref["callsign"].iloc[2])


@pytest.mark.parametrize("text, line, reason", [
    ("", 1, "empty file"),
    ("aircraft,time,latitude\nA,2019-03-01T08:00:00Z,3\n", 1, "missing column.*longitude.*altitude_ft or"),
    ("aircraft,time,latitude,longitude,height_m\n", 2, "no data line"),
    ("aircraft,time,latitude,longitude,height_m\nA,2019-03-01T08:00:00Z,3,101,100\nA,yesterday,3,101,100\n",
     3, "time 'yesterday' is not an ISO 8601 time"),
    ("aircraft,time,latitude,longitude,height_m\nA,2019-03-01T08:00:00,3,101,100\n", 2, "has no zone"),
    ("aircraft,time,latitude,longitude,height_m\nA,2019-03-01T08:00:00Z,93,101,100\n", 2,
     "latitude '93' is outside -90 to 90"),
    ("aircraft,time,latitude,longitude,height_m\nA,2019-03-01T08:00:00Z,3,east,100\n", 2,
     "longitude 'east' is not a number"),
    ("aircraft,time,latitude,longitude,height_m\nA,2019-03-01T08:00:00Z,3,101\n", 2, "4 field.*header has 5"),
    ("aircraft,time,latitude,longitude,height_m\n,2019-03-01T08:00:00Z,3,101,100\n", 2, "aircraft is empty"),
    ("aircraft,time,latitude,longitude,height_m\nA,2019-03-01T08:00:00Z,3,101,\n", 2, "no altitude"),
    ("aircraft,time,latitude,longitude,height_m\nA,2019-03-01T08:00:02Z,3,101,1\nB,2019-03-01T08:00:00Z,3,101,1\n"
     "A,2019-03-01T08:00:02Z,3,101,1\n", 4, "aircraft A's time does not increase"),
    ("aircraft,time,latitude,longitude,height_m\nA,2019-03-01T08:00:00Z,3,101,nan\n", 2, "height_m 'nan'"),
    # a code no transponder sends judged every report's code wrong (mode3a_correct 0 %, a fail)
    ("aircraft,time,latitude,longitude,height_m,mode3a\nA,2019-03-01T08:00:00Z,3,101,1,9999\n", 2,
     "mode3a '9999' is not four octal digits"),
    ("aircraft,time,latitude,longitude,height_m,address\nA,2019-03-01T08:00:00Z,3,101,1,75031\n", 2,
     "address '75031' is not six hexadecimal digits"),
])
def test_external_reference_refuses_a_bad_file(tmp_path, text, line, reason):
    path = tmp_path / "gps.csv"
    path.write_text(text)
    with pytest.raises(ExternalReferenceError, match=f"^{re.escape(str(path))}:{line}: .*{reason}"):
        read_external_reference(path, EPOCH)


def test_external_reference_refuses_a_bad_declared_sigma(tmp_path):
    path = tmp_path / "gps.csv"
    path.write_text(GOOD)
    with pytest.raises(ExternalReferenceError, match="gps.csv: declared sigma_m -1.0"):
        read_external_reference(path, EPOCH, sigma_m=-1.0)


def test_external_reference_refuses_unreadable_files(tmp_path):
    with pytest.raises(ExternalReferenceError, match="missing.csv: cannot read"):
        read_external_reference(tmp_path / "missing.csv", EPOCH)
    path = tmp_path / "binary.csv"
    path.write_bytes(b"aircraft,time\n\xff\xfe\x00")
    with pytest.raises(ExternalReferenceError, match="binary.csv: cannot read"):
        read_external_reference(path, EPOCH)


def test_an_adsb_sensor_under_test_is_told_its_reference_shares_its_navigation(two_radars):
    _, meas = two_radars
    second = meas[meas["sensor_id"] == ADSB].assign(sensor_id="021:0/2").iloc[::7]
    both = pd.concat([meas, second], ignore_index=True)
    built = leave_one_out(both, "021:0/2", epoch=EPOCH)
    assert any("021:0/1" in n and "not independent" in n for n in built.notes)
    assert not any("not independent" in n for n in leave_one_out(meas, ADSB, epoch=EPOCH).notes)


def test_a_naive_epoch_is_refused(two_radars, tmp_path):
    _, meas = two_radars
    with pytest.raises(ValueError, match="epoch .*naive"):
        leave_one_out(meas, RADAR_A, epoch=pd.Timestamp("2019-03-01"))
    path = tmp_path / "gps.csv"
    path.write_text(GOOD)
    with pytest.raises(ValueError, match="epoch .*naive"):
        read_external_reference(path, pd.Timestamp("2019-03-01"))


def test_a_self_reference_code_is_the_established_one_not_the_report_own(two_radars):
    """A single wrong Mode 3/A code in a radar's own track is judged against the code the aircraft's
    reports keep giving (the simulator's code), not against itself; the next report's code is too."""
    m, meas = two_radars
    alone = meas[meas["sensor_id"] == RADAR_A].sort_values("time").reset_index(drop=True)
    code = m.sim.aircraft[0].spec.mode3a
    assert (alone["mode3a"].astype(str) == code).all()
    alone["mode3a"] = alone["mode3a"].astype(object)
    wrong = len(alone) // 2
    alone.loc[wrong, "mode3a"] = "7777"
    ref = leave_one_out(alone, RADAR_A, epoch=EPOCH).frame
    assert ref["self_reference"].all()
    t_s = (alone["time"] - EPOCH).dt.total_seconds().to_numpy()
    for k in (wrong, wrong + 1):
        at = ref[np.isclose(ref["t_s"], t_s[k], atol=1e-6)]
        assert len(at) == 1 and at["mode3a"].iloc[0] == code, (k, at["mode3a"].tolist())


def test_the_reference_level_between_updates_is_interpolated_not_predicted():
    """Between two updates 40 s apart the rows take the straight line between the updates' levels (by
    hand: 240 at 0 s, 220 at 40 s, so 235 at 10 s), whatever the vertical filter predicted there."""
    from msdc.pipeline.evaluate.build_reference import _level_between_updates

    t = np.array([0.0, 10.0, 20.0, 40.0, 41.0, 10.0, 20.0, 30.0])
    level = np.array([240.0, 239.0, 238.0, 220.0, 219.9, 100.0, 120.0, 140.0])
    updated = np.array([True, False, False, True, True, True, False, False])
    segment = np.array([0, 0, 0, 0, 0, 1, 1, 1])  # the second segment has one update: nothing to join
    np.testing.assert_allclose(_level_between_updates(level, t, updated, segment),
                               [240.0, 235.0, 230.0, 220.0, 219.9, 100.0, 120.0, 140.0])


def test_the_adsb_reference_of_two_radars_is_built_once(two_radars, monkeypatch):
    """Radars A and B judged against ADS-B in a row: the second reuses the first's reconstruction (one
    tracking run instead of two), and gets the reference it would build alone; leave-one-out builds anew."""
    from msdc.pipeline.evaluate import build_reference

    _, meas = two_radars
    alone = adsb_reference(meas, RADAR_B, epoch=EPOCH, fallback=False).frame
    calls = []
    real = build_reference.reconstruct
    monkeypatch.setattr(build_reference, "reconstruct", lambda *a, **k: calls.append(1) or real(*a, **k))
    cache: dict = {}
    adsb_reference(meas, RADAR_A, epoch=EPOCH, fallback=False, cache=cache)
    reused = adsb_reference(meas, RADAR_B, epoch=EPOCH, fallback=False, cache=cache).frame
    assert len(calls) == 1
    pd.testing.assert_frame_equal(reused, alone)
    leave_one_out(meas, RADAR_A, epoch=EPOCH, fallback=False, cache=cache)
    leave_one_out(meas, RADAR_B, epoch=EPOCH, fallback=False, cache=cache)  # other builders: built again
    assert len(calls) == 3


@pytest.mark.parametrize("keys, times", [("text", "int"), ("codes", "int"), ("codes", "float"),
                                          ("codes", "nanoseconds")])
def test_latest_at_is_the_latest_row_at_or_before_else_the_first_of_the_key(keys, times):
    """_latest_at (the reference's identity and on-ground rule) against its definition, row by row: with
    text keys or integer codes (reconstruct's), and times as integers, floats or a day's nanoseconds."""
    from msdc.pipeline.evaluate.build_reference import _latest_at

    rng = np.random.default_rng(1)
    names = np.array(list("abcde"), dtype=object) if keys == "text" else np.arange(5)
    scale = {"int": 1, "float": 0.5, "nanoseconds": 60_000_000_000}[times]
    base = 1_764_288_000_000_000_000 if times == "nanoseconds" else 0
    for _ in range(200):
        nr, nl = rng.integers(0, 30), rng.integers(0, 30)
        rk, rt = rng.choice(names[:4], nr), base + rng.integers(0, 10, nr) * scale
        order = np.lexsort((rt, rk))
        rk, rt = rk[order], rt[order]
        lk, lt = rng.choice(names, nl), base + rng.integers(-2, 12, nl) * scale
        got = _latest_at(lk, lt, rk, rt)
        for i in range(nl):
            same = [j for j in range(nr) if rk[j] == lk[i]]
            before = [j for j in same if rt[j] <= lt[i]]
            assert got[i] == (before[-1] if before else same[0] if same else -1)


@pytest.mark.parametrize("dtype", [object, "str", "category"])
def test_in_order_is_what_a_stable_sort_by_aircraft_and_time_leaves(dtype):
    from msdc.pipeline.evaluate.reference import in_order

    cases = [(["A", "A", "B", "B"], [1.0, 2.0, 0.0, 0.0], True),  # equal times keep their order
             (["A", "B", "A"], [1.0, 2.0, 3.0], False),  # an aircraft back after another
             (["A", "A"], [2.0, 1.0], False),  # time going back
             (["B", "A"], [0.0, 1.0], False), (["AB", "B"], [5.0, 0.0], True), (["X"], [1.0], True)]
    for ids, t, expected in cases:
        s = pd.Series(ids, dtype=dtype)
        assert in_order(s, np.array(t)) is expected, (ids, t)
        frame = pd.DataFrame({"aircraft": s, "t_s": t})
        moved = frame.sort_values(["aircraft", "t_s"], kind="stable").index.tolist() != list(range(len(ids)))
        assert moved is not expected  # pandas' own sort agrees with the hand's verdict


def _brute_association(reports: pd.DataFrame, reference: pd.DataFrame, gate_m: float, vertical_ft: float,
                       max_gap_s: float) -> tuple[np.ndarray, np.ndarray]:
    """The association by exhaustion: every report measured against every aircraft, in order, the first
    nearest kept (the nearest within the vertical gate first, as associate's rule says)."""
    from msdc.pipeline.evaluate.reference import check_reference, local_distance_m, trajectories

    t, lat, lon = (reports[c].to_numpy(float) for c in ("t_s", "latitude", "longitude"))
    mode_c_ft = reports["flight_level"].to_numpy(float) * 100.0
    best, level = np.full(len(t), np.inf), np.full(len(t), np.inf)
    index, level_index = np.full(len(t), -1), np.full(len(t), -1)
    for k, tr in enumerate(trajectories(check_reference(reference))):
        r_lat, r_lon, _, r_alt = tr.at(t, max_gap_s)
        d = np.nan_to_num(local_distance_m(lat, lon, r_lat, r_lon), nan=np.inf)
        closer = d < best
        best[closer], index[closer] = d[closer], k
        with np.errstate(invalid="ignore"):
            closer = ~(np.abs(mode_c_ft - r_alt) > vertical_ft) & (d < level)
        level[closer], level_index[closer] = d[closer], k
    index = np.where(level <= gate_m, level_index, np.where(best <= gate_m, index, -1))
    return index, np.where(np.isfinite(lat) & np.isfinite(lon), best, np.nan)


@pytest.mark.parametrize("gate_m", [3704.0, 500.0, 20000.0])
def test_association_equals_the_exhaustive_search(gate_m):
    """The pruned association (aircraft measured only against the reports their box may hold nearer) gives
    exactly the exhaustive search's aircraft and distances: aircraft close together at different levels,
    two aircraft flying the same samples (the first of equals wins), one across the antimeridian, reports
    far from all, reports without a position or a Mode C, and gaps in the reference."""
    from msdc.pipeline.evaluate.reference import associate

    rng = np.random.default_rng(11)
    rows = []
    for k in range(12):
        lat0, lon0 = 60.0 + rng.normal(0, 0.05), 10.0 + rng.normal(0, 0.1)
        t = np.arange(0.0, 120.0, 2.0)
        t = t[(t < 40) | (t > 80)] if k == 3 else t  # a 40 s gap: unknown in between
        for tt in t:
            rows.append((f"A{k:02d}", tt, lat0 + 1e-4 * tt * (k % 3 - 1), lon0 + 2e-4 * tt, 10000 + 1500 * k))
    twin = [r for r in rows if r[0] == "A05"]
    rows += [("A05b", *r[1:]) for r in twin]  # the same samples under another label (sorted after A05)
    rows += [("Z", tt, 0.5, 179.99 + 0.0002 * tt - (360.0 if tt > 60 else 0.0), 20000)  # antimeridian
             for tt in range(0, 120, 2)]
    reference = pd.DataFrame(rows, columns=["aircraft", "t_s", "latitude", "longitude", "altitude_ft"])
    n = 600
    pick = reference.sample(n, replace=True, random_state=3).reset_index(drop=True)
    reports = pd.DataFrame({"t_s": pick["t_s"] + rng.uniform(-1, 1, n),
                            "latitude": pick["latitude"] + rng.normal(0, 0.01, n),
                            "longitude": pick["longitude"] + rng.normal(0, 0.02, n),
                            "flight_level": pick["altitude_ft"] / 100.0 + rng.normal(0, 20, n)})
    reports.loc[::37, ["latitude", "longitude"]] = np.nan
    reports.loc[::11, "flight_level"] = np.nan
    reports.loc[::13, "latitude"] += 3.0  # far from every aircraft
    reports.loc[::17, ["latitude", "longitude"]] = pick.loc[::17, ["latitude", "longitude"]].to_numpy()
    params = {"gate_m": gate_m, "vertical_gate_ft": 3000.0, "reference_max_gap_s": 30.0}
    got = associate(reports, reference, params)
    index, distance = _brute_association(reports, reference, gate_m, 3000.0, 30.0)
    assert got["ref_index"].tolist() == index.tolist()
    np.testing.assert_array_equal(got["ref_distance_m"].to_numpy(float), distance)
    assert 50 < (index >= 0).sum() < n and (np.isinf(distance)).sum() > 0
    assert (distance[index < 0] > gate_m).sum() > 20  # reports beyond the gate, measured to the nearest
    labels = sorted(reference["aircraft"].unique())
    assert "A05b" not in set(got["ref_aircraft"].dropna()) and labels.index("A05") in set(index)


def test_a_sensors_own_track_goes_in_where_a_sort_of_both_would_put_it():
    """The reference with a sensor's own track merged in (build_reference._merged) is the two frames one
    after the other sorted stably by aircraft and time (pandas' sort): own rows after the reconstruction's
    of the same aircraft and time, aircraft the reconstruction lacks between its others, at either end."""
    from msdc.pipeline.evaluate.build_reference import _blocks, _merged

    built = pd.DataFrame({"aircraft": pd.array(["B", "B", "B", "D", "D"], dtype="str"),
                          "t_s": [0.0, 5.0, 10.0, 1.0, 2.0], "self_reference": False})
    own = pd.DataFrame({"aircraft": pd.array(["A", "B", "B", "B", "C", "D", "E"], dtype="str"),
                        "t_s": [3.0, 5.0, 6.0, 11.0, 0.0, 2.0, 9.0], "self_reference": True})
    got = _merged(built, own, _blocks(built, {}))
    assert list(zip(got["aircraft"], got["t_s"], got["self_reference"], strict=True)) == [
        ("A", 3.0, True), ("B", 0.0, False), ("B", 5.0, False), ("B", 5.0, True), ("B", 6.0, True),
        ("B", 10.0, False), ("B", 11.0, True), ("C", 0.0, True), ("D", 1.0, False), ("D", 2.0, False),
        ("D", 2.0, True), ("E", 9.0, True)]
    both = pd.concat([built, own], ignore_index=True).sort_values(["aircraft", "t_s"], kind="stable",
                                                                   ignore_index=True)
    pd.testing.assert_frame_equal(got, both, check_exact=True)


@pytest.mark.parametrize("established", [False, True])
def test_a_reference_rows_identity_is_its_aircrafts_latest_reported_text(established):
    """build_reference._identity by hand: per row the aircraft's latest value at or before it (before the
    first, the first), empty and missing values saying nothing, an aircraft without any: missing; with
    ``established``, a value counts only where the aircraft's previous report gave it too."""
    from msdc.pipeline.evaluate.build_reference import _identity

    reports = pd.DataFrame({
        "callsign": np.array(["AB1", "", None, "XY"], dtype=object),
        "mode3a": pd.Categorical(["1234", "1234", "7000", None])})
    rep_key, rep_t = np.array([0, 0, 0, 1]), np.array([0, 10, 20, 5])
    left_key, left_t = np.array([0, 0, 0, 1, 2]), np.array([-5, 5, 25, 6, 0])
    got = _identity(left_key, left_t, rep_key, rep_t, reports, established=established)

    def texts(column) -> list:
        return [None if pd.isna(v) else v for v in pd.Series(column).tolist()]

    if established:  # only aircraft 0's second 1234 repeats its previous report's value
        assert texts(got["callsign"]) == [None] * 5
        assert texts(got["mode3a"]) == ["1234", "1234", "1234", None, None]
    else:
        assert texts(got["callsign"]) == ["AB1", "AB1", "AB1", "XY", None]
        assert texts(got["mode3a"]) == ["1234", "1234", "7000", None, None]
    assert texts(got["address"]) == [None] * 5  # no such column in the reports


def test_a_lone_report_of_the_sensor_is_no_reference_of_itself(two_radars):
    """One plot of another Mode 3/A identity 30 km off the aircraft (a false plot with its own code): the
    sensor's own track of it would be one row at the plot itself, which would never let it count as false.
    It gets no self-reference row; the aircraft's own track keeps all of its rows."""
    m, meas = two_radars
    alone = meas[meas["sensor_id"] == RADAR_A].sort_values("time").reset_index(drop=True)
    lone = alone.iloc[[len(alone) // 2]].copy()
    lone["aircraft_id"] = "M3A:4445"
    lone["mode3a"] = "4445"
    lone["latitude"] = lone["latitude"] + 30_000.0 / 111_320.0
    with_lone = pd.concat([alone, lone], ignore_index=True).sort_values("time", kind="stable")
    ref = leave_one_out(with_lone, RADAR_A, epoch=EPOCH).frame
    before = leave_one_out(alone, RADAR_A, epoch=EPOCH).frame
    assert "M3A:4445" not in set(ref["aircraft"].astype(str))
    assert len(ref) == len(before)
    t_s = (lone["time"] - EPOCH).dt.total_seconds().to_numpy()
    reports = pd.DataFrame({"t_s": t_s, "latitude": lone["latitude"].to_numpy(),
                            "longitude": lone["longitude"].to_numpy()})
    assert (associate(reports, ref)["ref_index"] < 0).all()  # no aircraft within the 2 NM gate: false
    # the same lone plot of an aircraft known by its Mode S address (a parked aircraft the radar hears once a
    # minute) is its own reference: real, and not a neighbour's report with a wrong address
    addressed = pd.concat([alone, lone.assign(aircraft_id="3C0FFE", address="3C0FFE")], ignore_index=True)
    ref = leave_one_out(addressed.sort_values("time", kind="stable"), RADAR_A, epoch=EPOCH).frame
    assert (ref["aircraft"].astype(str) == "3C0FFE").sum() == 1 and len(ref) == len(before) + 1


def test_a_one_report_segment_beside_others_of_its_aircraft_stays_a_reference():
    """Segments (group) of own-track rows (updated or not): A's one-report segment 1 lies 4 s after A's
    segment 0 (the tracker starts one at each plot its gate rejects): kept. B's lone report and C's two
    reports 40 s apart (over the 30 s gap) are each alone: no reference."""
    from msdc.pipeline.evaluate.build_reference import _supported

    s = 1_000_000_000
    key = np.array([0, 0, 0, 0, 0, 1, 2, 2])
    t_ns = np.array([0, 4, 8, 9, 12, 100, 200, 240]) * s
    group = np.array([0, 0, 0, 0, 1, 2, 3, 4])
    updated = np.array([True, True, True, False, True, True, True, True])
    assert _supported(key, t_ns, group, updated, 5).tolist() == [True, True, False, False, False]


def test_a_reference_row_is_on_the_surface_by_a_report_s_say_else_by_its_tracked_speed():
    """build_reference._on_ground by hand: aircraft 0's latest report says nothing and gives 0 kt (a radar's
    zero speed at FL 180: the bundled radar fixture has 86 such plots), its track flies at 250 kt: airborne
    (the reported 0 kt made it "surface"); aircraft 1's latest report says on the ground (GBS) at 120 kt
    tracked: surface, and so is its row before its first report (the first's say); aircraft 2 says nothing
    and its track moves at 12 kt: surface; aircraft 3 has no report: unknown."""
    from msdc.pipeline.evaluate.build_reference import _on_ground

    reports = pd.DataFrame({"on_ground": pd.array([pd.NA, pd.NA, True, pd.NA], dtype="boolean"),
                            "ground_speed_kt": [250.0, 0.0, 120.0, np.nan]})
    key, t = np.array([0, 0, 1, 2]), np.array([0, 10, 20, 0])
    key_ref, t_ref = np.array([0, 1, 1, 2, 3]), np.array([15, 5, 25, 5, 5])
    speed_kt = np.array([250.0, 120.0, 120.0, 12.0, 10.0])
    got = _on_ground(key_ref, t_ref, key, t, reports, speed_kt)
    assert [None if pd.isna(v) else bool(v) for v in got] == [False, True, True, True, None]
