"""Two radars over the same traffic (fixtures.multiradar): each radar is correlated on its own, and its
windows, counts and slot positions match its own truth; mixing the two radars would not."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from fixtures import geodesy as geo
from fixtures.multiradar import simulate_two_radars
from fixtures.simulate import _segments
from msdc.asterix.encode import encode_frame
from msdc.pipeline.correlate.correlation import correlate
from msdc.pipeline.model.load import load
from msdc.pipeline.model.measurements import build_measurements
from msdc.pipeline.model.sensors import read_sensors

# one worker runs the module: the two-radar run made once, not on each worker
pytestmark = pytest.mark.xdist_group("two_radars")

R1, R2, ADSB = "048:25/201", "048:25/202", "021:0/1"
LSB = 128  # ToD units per second
SLOT_S = 10.0


@pytest.fixture(scope="module")
def two(tmp_path_factory):
    """Real bytes: both radars interleaved in time in one CAT048 file, ADS-B in another."""
    m = simulate_two_radars()
    tmp = tmp_path_factory.mktemp("two_radars")
    radar = pd.concat([m.sim.radar, m.radar2], ignore_index=True)
    radar = radar.iloc[np.lexsort((radar["sic"], radar["time_of_day"] + 86400 * radar["day"]))]
    (tmp / "radar.ast").write_bytes(encode_frame(48, radar, edition=None))
    (tmp / "adsb.ast").write_bytes(encode_frame(21, m.sim.adsb, edition=None))
    (tmp / "sensors.toml").write_text(m.sensors_toml())
    loaded = load([tmp / "radar.ast", tmp / "adsb.ast"], date="2019-03-01")
    meas = build_measurements(loaded.frames[48], loaded.frames[21], read_sensors(tmp / "sensors.toml"),
                              date=loaded.date)
    return m, meas


def _spans(run, radar_sensor, reference=ADSB):
    return sorted((w.summary["callsign"], w.summary["start_tod"], w.summary["end_tod"]) for w in run.windows
                  if w.summary["radar_sensor"] == radar_sensor and w.summary["reference_sensor"] == reference)


def test_each_radar_gets_its_own_truth_windows(two):
    m, meas = two
    run = correlate(meas, all_aircraft=True)
    assert {w.summary["radar_sensor"] for w in run.windows} == {R1, R2}
    truth1 = sorted((w["callsign"], w["start_s"], w["end_s"]) for w in m.sim.truth["overlap_windows"])
    truth2 = sorted((w["callsign"], w["start_s"], w["end_s"]) for w in m.windows2)
    assert _spans(run, R1) == truth1
    assert _spans(run, R2) == truth2
    # counts: radar 2 has no duplicates, so every truth row of the window is a report before slotting
    rows2 = {(w["callsign"], w["start_s"]): w["radar_rows"] for w in m.windows2}
    for w in run.windows:
        s = w.summary
        if s["radar_sensor"] == R2:
            assert s["radar_before"] == rows2[(s["callsign"], s["start_tod"])]
            assert s["radar_duplicates"] == 0
    # window numbers restart for each sensor pair of an aircraft
    for cs in {w.summary["callsign"] for w in run.windows}:
        for sensor in (R1, R2):
            numbers = [w.summary["window"] for w in run.windows
                       if w.summary["callsign"] == cs and w.summary["radar_sensor"] == sensor]
            assert numbers == list(range(1, len(numbers) + 1))


def test_mixing_the_radars_would_give_other_windows(two):
    """The windows of the two radars' plots taken together differ from both radars' truth: a pipeline that
    averaged the radars into one series would fail the test above."""
    m, _ = two
    tt = m.sim.truth_tracks
    adsb = tt[tt["sensor"] == "adsb"]
    radar1 = tt[tt["sensor"] == "radar"]
    own = [sorted((w["callsign"], w["start_s"], w["end_s"]) for w in windows)
           for windows in (m.sim.truth["overlap_windows"], m.windows2)]
    mixed = []
    for i, ac in enumerate(m.sim.aircraft):
        tr = np.sort(np.concatenate([radar1.loc[radar1["aircraft"] == i, "t_s"],
                                     m.truth2.loc[m.truth2["aircraft"] == i, "t_s"]]))
        ta = np.sort(adsb.loc[adsb["aircraft"] == i, "t_s"].to_numpy())
        mixed += [(ac.spec.callsign, max(a, c), min(b, d)) for a, b in _segments(tr) for c, d in _segments(ta)
                  if max(a, c) <= min(b, d)]
    assert sorted(mixed) != own[0] and sorted(mixed) != own[1]


def test_slot_positions_come_from_one_radar_only(two):
    """Each radar slot mean lies at the mean true position of THAT radar's plots in the slot, within its
    own noise; the other radar's plots, taken at other instants of the slot, are not in it."""
    m, meas = two
    run = correlate(meas, all_aircraft=True)
    truth = {R1: m.sim.truth_tracks[m.sim.truth_tracks["sensor"] == "radar"], R2: m.truth2}
    sigma_m = {R1: (70.0, 0.08), R2: (m.second.sigma_range_m, m.second.sigma_azimuth_deg)}
    checked = {R1: 0, R2: 0}
    for res in run.windows:
        s = res.summary
        sensor = s["radar_sensor"]
        if s["reference_sensor"] != ADSB:
            continue
        ac = next(i for i, a in enumerate(m.sim.aircraft) if a.spec.callsign == s["callsign"])
        tt = truth[sensor]
        tt = tt[(tt["aircraft"] == ac) & ~tt["duplicate"]]
        t = np.round(tt["t_s"].to_numpy() * LSB).astype(np.int64)
        start, end = round(s["start_tod"] * LSB), round(s["end_tod"] * LSB)
        inside = (t >= start) & (t <= end)
        k = (t[inside] - start) // int(SLOT_S * LSB)
        lat, lon = tt["latitude"].to_numpy()[inside], tt["longitude"].to_numpy()[inside]
        for slot in res.slots[~res.slots["radar_filled"]].itertuples():
            sel = k == slot.slot
            assert sel.sum() == slot.radar_count
            e, n, _ = geo.ecef_to_enu(geo.geodetic_to_ecef(slot.radar_lat, slot.radar_lon, 0.0),
                                      lat[sel].mean(), lon[sel].mean(), 0.0)
            # plot noise: range sigma, and azimuth sigma at up to 250 NM; the slot mean of n plots
            bound_m = 5.0 * np.hypot(sigma_m[sensor][0], np.radians(sigma_m[sensor][1]) * 250 * 1852.0)
            assert np.hypot(e, n) < bound_m / np.sqrt(sel.sum()) + 50.0, (sensor, s["callsign"], slot.slot)
            checked[sensor] += 1
    assert checked[R1] > 500 and checked[R2] > 200


def test_radar_radar_pairs_and_split_adsb(two):
    _, meas = two
    rr = correlate(meas, all_aircraft=True, pairs="radar-radar")
    assert rr.windows
    assert {(w.summary["radar_sensor"], w.summary["reference_sensor"]) for w in rr.windows} == {(R1, R2)}
    both = correlate(meas, all_aircraft=True, pairs="all")
    assert len(both.windows) == len(rr.windows) + len(correlate(meas, all_aircraft=True).windows)
    # two ground stations: one source by default, apart with split_adsb
    adsb = meas["sensor_kind"] == "adsb"
    station = meas["sensor_id"].astype("string").where(~adsb | (meas.index % 2 == 0), "021:0/2")
    half = meas.assign(sensor_id=station.astype("category"))
    merged = correlate(half, callsign="MAS72")
    assert {w.summary["reference_sensor"] for w in merged.windows} == {"021:0/1+021:0/2"}
    split = correlate(half, callsign="MAS72", split_adsb=True)
    assert {w.summary["reference_sensor"] for w in split.windows} == {"021:0/1", "021:0/2"}
    with pytest.raises(ValueError, match="pairs must be one of"):
        correlate(meas, all_aircraft=True, pairs="adsb-adsb")


def _same_runs(a, b) -> None:
    assert [w.summary for w in a.windows] == [w.summary for w in b.windows]
    for x, y in zip(a.windows, b.windows, strict=True):
        pd.testing.assert_frame_equal(x.slots, y.slots, check_exact=True)
        pd.testing.assert_frame_equal(x.lags, y.lags, check_exact=True)
    assert a.skipped == b.skipped


@pytest.mark.parametrize("split", [False, True])
def test_job_wide_flags_give_the_windows_of_flags_worked_out_per_source(two, split):
    """correlate() reads the duplicate and jump flags mark_once computed once for the job when the frame
    carries them, else works them out per sensor source; with a second ground station relaying every third
    ADS-B report and jumps put into the ADS-B track, both must give the same windows, counts and tables."""
    from msdc.pipeline.model.marks import mark_once

    _, meas = two
    adsb = (meas["sensor_kind"] == "adsb").to_numpy()
    relay = meas[adsb & (np.arange(len(meas)) % 3 == 0)].assign(sensor_id="021:0/2")
    both = pd.concat([meas, relay], ignore_index=True).sort_values("time", kind="stable")
    both = both.assign(sensor_id=both["sensor_id"].astype("string").astype("category")).reset_index(drop=True)
    hit = np.flatnonzero((both["sensor_kind"] == "adsb").to_numpy())[100::997]
    both.loc[hit, "latitude"] += 0.1  # about 11 km off the track
    per_source = correlate(both, all_aircraft=True, pairs="all", split_adsb=split)
    job_wide = correlate(mark_once(both, split_adsb=split, flags=["jump"]), all_aircraft=True, pairs="all",
                         split_adsb=split)
    _same_runs(per_source, job_wide)
    summaries = [w.summary for w in job_wide.windows if w.summary["reference_sensor"].startswith("021")]
    assert sum(s["adsb_jumps"] for s in summaries) >= len(hit) // 2
    if split:  # each station a source of its own
        assert {s["reference_sensor"] for s in summaries} == {ADSB, "021:0/2"}
    else:  # one source, where every third ADS-B report is a repeat of the other station's
        assert {s["reference_sensor"] for s in summaries} == {ADSB + "+021:0/2"}
        assert sum(s["adsb_duplicates"] for s in summaries) > len(relay) // 2


def test_two_unbiased_radars_lead_with_their_noise_not_the_slotting(two):
    """Radar 1 against radar 2 (neither biased): each radar report against radar 2 interpolated to its
    time differs by both radars' noise, RMS^2 = E|e1|^2 + 2/3 E|e2|^2 (linear interpolation between two
    independent plots, uniform in time, keeps (1-f)^2 + f^2 = 2/3 of one plot's variance on average),
    the truth's errors of each radar's reports in the window; the lead RMS is that within 10 % and no
    window shows a systematic offset. The thesis's slot separation is 500-1,200 m in median, mostly the
    slotting of two radars whose plots fall at different moments in a slot."""
    from msdc.pipeline.model.geodesy import distance_m
    from msdc.pipeline.model.time import with_clock

    m, meas = two
    clocked = with_clock(meas)
    run = correlate(meas, all_aircraft=True, pairs="radar-radar")
    assert {(w.summary["radar_sensor"], w.summary["reference_sensor"]) for w in run.windows} == {(R1, R2)}

    def truth_error_m(sensor: str, callsign: str, start_s: float, end_s: float) -> np.ndarray:
        g = clocked[(clocked["sensor_id"].astype(str) == sensor) & (clocked["callsign"] == callsign)
                    & clocked["time_of_day"].between(start_s, end_s)]
        st = m.sim.aircraft_by_callsign(callsign).truth(g["time_of_day"].to_numpy(float))
        return distance_m(g["latitude"].to_numpy(float), g["longitude"].to_numpy(float), st.latitude,
                          st.longitude)

    for res in run.windows:
        w = res.summary
        e1 = truth_error_m(R1, w["callsign"], w["start_tod"], w["end_tod"])
        e2 = truth_error_m(R2, w["callsign"], w["start_tod"], w["end_tod"])
        predicted = np.sqrt(np.mean(e1**2) + 2.0 / 3.0 * np.mean(e2**2))
        assert w["matched_sep_rms_m"] == pytest.approx(predicted, rel=0.1), w["callsign"]
        assert w["verdict"].startswith("no systematic offset beyond the noise"), w["verdict"]
        assert w["sep_median_m"] > w["matched_sep_median_m"]
    medians = [w.summary["sep_median_m"] for w in run.windows]
    assert 450.0 < min(medians) and max(medians) < 1300.0


def test_two_radars_without_adsb_are_correlated_by_the_command(two, tmp_path, capsys):
    """--pairs radar-radar needs no ADS-B: the command refused two radars alone ("no ADS-B (CAT021) records
    in the inputs"); it now gives the pairs the same frame with its ADS-B gives."""
    import json

    from msdc.pipeline.cli import main

    m, meas = two
    radar = pd.concat([m.sim.radar, m.radar2], ignore_index=True)
    radar = radar.iloc[np.lexsort((radar["sic"], radar["time_of_day"] + 86400 * radar["day"]))]
    (tmp_path / "radar.ast").write_bytes(encode_frame(48, radar, edition=None))
    (tmp_path / "sensors.toml").write_text(m.sensors_toml())
    out = tmp_path / "rr.json"
    assert main(["correlate", str(tmp_path / "radar.ast"), "--sensors", str(tmp_path / "sensors.toml"),
                 "--date", "2019-03-01", "--all", "--pairs", "radar-radar", "--json", str(out)]) == 0, \
        capsys.readouterr().err
    got = [(w["callsign"], w["radar_sensor"], w["reference_sensor"], w["slots"])
           for w in json.loads(out.read_text())["windows"]]
    keys = ("callsign", "radar_sensor", "reference_sensor", "slots")
    want = [tuple(w.summary[k] for k in keys)
            for w in correlate(meas, all_aircraft=True, pairs="radar-radar").windows]
    assert got == want and got
