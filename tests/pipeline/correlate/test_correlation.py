"""NCC and lagged Pearson against hand values and synthetic truth; the correlate() orchestration."""

import math

import numpy as np
import pandas as pd
import pytest
from measurement_frames import meas_frame

from msdc.pipeline.correlate.correlation import (
    PEARSON_MIN_OVERLAP,
    NoOverlap,
    NoSuchAircraft,
    correlate,
    lag_signal,
    ncc,
    peak_lag,
    pearson_by_lag,
    pearson_max_lag,
    separation_stats,
)
from msdc.pipeline.correlate.results import LAG_COLUMNS, SLOT_COLUMNS, SUMMARY_KEYS
from msdc.pipeline.report.summary import window_note


def test_ncc_hand_computed_three_elements():
    # x = (1, 2, 3), y = (4, 5, 6); r(d) = sum_i x[i] y[i-d] / sqrt(14 * 77) = . / sqrt(1078)
    # d = -2: x0 y2 = 6;  d = -1: x0 y1 + x1 y2 = 5 + 12 = 17;  d = 0: 4 + 10 + 18 = 32
    # d = +1: x1 y0 + x2 y1 = 8 + 15 = 23;  d = +2: x2 y0 = 12
    lags, r = ncc([1.0, 2.0, 3.0], [4.0, 5.0, 6.0])
    assert lags.tolist() == [-2, -1, 0, 1, 2]
    assert r == pytest.approx(np.array([6, 17, 32, 23, 12]) / math.sqrt(1078))


def test_identical_series_peak_at_zero():
    x = np.sin(np.linspace(0, 7, 50)) + 3.0
    lags, r = ncc(x, x)
    assert r[lags == 0][0] == pytest.approx(1.0)
    assert peak_lag(lags, r) == 0
    lags, p = pearson_by_lag(x, x)
    assert p[lags == 0][0] == pytest.approx(1.0)
    assert peak_lag(lags, p, pearson_max_lag(50)) == 0


def test_shift_by_three_slots():
    # convention: x[i] ~ y[i - d] at the peak. Build x[i] = y[i - 3] (radar 3 slots behind ADS-B) -> +3
    s = np.cumsum(np.random.default_rng(5).normal(size=63))
    y, x = s[3:], s[:-3]  # y[j] = s[j + 3], so y[i - 3] = s[i] = x[i]
    lags, p = pearson_by_lag(x, y)
    assert peak_lag(lags, p, pearson_max_lag(60)) == 3
    assert p[lags == 3][0] == pytest.approx(1.0)
    lags, p = pearson_by_lag(y, x)
    assert peak_lag(lags, p, pearson_max_lag(60)) == -3
    # unrestricted, 2-point overlaps (always r = +-1) compete with the true peak
    assert pearson_max_lag(60) == 30


def test_pearson_hand_values_and_nan():
    # x = (1, 2, 3), y = (1, 2, 4).
    # d = 0: centred x (-1, 0, 1), y (-4/3, -1/3, 5/3): cov 3, sxx 2, syy 42/9 -> 3 / sqrt(84/9) = 0.98198
    # d = +1: pairs (x1, y0), (x2, y1) = (2, 1), (3, 2) -> 1;  d = -1: (1, 2), (2, 4) -> 1
    # d = +-2: a single pair -> NaN
    lags, p = pearson_by_lag([1.0, 2.0, 3.0], [1.0, 2.0, 4.0])
    assert lags.tolist() == [-2, -1, 0, 1, 2]
    assert np.isnan(p[0]) and np.isnan(p[4])
    assert p[1:4] == pytest.approx([1.0, 0.98198, 1.0], abs=1e-5)
    # ties: the first (most negative) lag wins; NaN ignored; the search can be limited to |lag| <= 0
    assert peak_lag(lags, p) == -1
    assert peak_lag(lags, p, max_abs_lag=0) == 0
    # a constant side has no Pearson coefficient
    _, p = pearson_by_lag([1.0, 1.0, 1.0], [1.0, 2.0, 4.0])
    assert np.isnan(p).all()
    assert peak_lag(lags, p) is None


def test_a_side_constant_but_for_rounding_has_no_pearson_coefficient():
    """A parked aircraft's held position whose slot means differ in their last bit (the real LEBL hour's
    4CA1C3 gave a Pearson "peak" at +4 slots, 0.13, from one unit in the last place): no coefficient at
    any lag, as for an exactly constant side; a step at a sensor's finest resolution is still a signal."""
    n = 72
    y = 41.298337 + 2.1e-5 * np.random.default_rng(5).integers(0, 3, n)  # ADS-B, jittering by its LSB
    x = np.full(n, 41.29832531)
    x[-1] = np.nextafter(x[-1], np.inf)  # one unit in the last place
    lags, p = pearson_by_lag(x, y, PEARSON_MIN_OVERLAP)
    assert np.isnan(p).all() and peak_lag(lags, p) is None
    x[-1] = x[0] + 180.0 / 2**30  # CAT021's finest latitude LSB: a real (if tiny) movement
    _, p = pearson_by_lag(x, y, PEARSON_MIN_OVERLAP)
    for d in (0, 5):  # overlaps x[d:] holding the moved slot: np.corrcoef of the pairs
        assert p[lags == d][0] == pytest.approx(np.corrcoef(x[d:], y[: n - d])[0, 1], abs=1e-9)
    assert np.isnan(p[lags == -5][0])  # x[:67] leaves the moved slot out: constant


def test_ncc_rejects_unequal_lengths():
    with pytest.raises(ValueError):
        ncc([1.0, 2.0], [1.0])


def test_separation_stats_hand():
    # (3, 4): mean 3.5, RMS sqrt((9 + 16) / 2) = 3.5355, p95 by linear interpolation 3 + 0.95 = 3.95
    stats = separation_stats([3.0, 4.0])
    assert stats == pytest.approx({"sep_mean_m": 3.5, "sep_rms_m": math.sqrt(12.5), "sep_p95_m": 3.95,
                                   "sep_max_m": 4.0})


def frame(sensor, times, lat, lon, callsign="MAS72", address="750123"):
    n = len(times)
    return pd.DataFrame({
        "sensor": sensor, "time_of_day": np.asarray(times, float),
        "timestamp": pd.Series(pd.NaT, index=range(n), dtype="datetime64[ns, UTC]"),
        "latitude": np.asarray(lat, float), "longitude": np.asarray(lon, float), "flight_level": 350.0,
        "ground_speed_kt": 450.0, "heading_deg": 45.0,
        "callsign": pd.Series([callsign] * n, dtype="str"), "address": pd.Series([address] * n, dtype="str"),
        "sac": pd.array([1] * n, dtype="Int64"), "sic": pd.array([2] * n, dtype="Int64"),
    })


def corr(radar, adsb, date=None, **kw):
    """correlate() on hand-made radar and ADS-B reports (dated ``date``, else undated)."""
    return correlate(meas_frame(pd.concat([radar, adsb], ignore_index=True), day=date), **kw)


def weave(t):
    """A weaving, non-periodic track, so lagged Pearson has a single clear peak."""
    w = 2 * np.pi * (t - 36000.0)
    return (1.3 + 0.02 * np.sin(w / 2900.0) + 0.01 * np.sin(w / 1300.0 + 1.0),
            103.8 + 0.03 * np.cos(w / 3100.0) + 0.01 * np.sin(w / 1100.0))


def test_correlate_identical_tracks_two_windows():
    t = np.concatenate([np.arange(36000.0, 36600.0, 4.0), np.arange(40000.0, 40300.0, 4.0)])
    lat, lon = weave(t)
    radar = frame("radar", t, lat, lon, callsign=None)  # radar without I048/240: joined by address
    adsb = frame("adsb", t, lat, lon)
    # two repeated ADS-B reports in the first window, one repeated radar report in the second
    adsb = pd.concat([adsb, adsb.iloc[[3, 10]]], ignore_index=True)
    radar = pd.concat([radar, radar.iloc[[-1]]], ignore_index=True)
    run = corr(radar, adsb, callsign="mas 72", date="2019-03-01")
    assert [w.summary["window"] for w in run.windows] == [1, 2]
    first, second = (w.summary for w in run.windows)
    assert list(first) == SUMMARY_KEYS
    assert (first["callsign"], first["address"]) == ("MAS72", "750123")
    # window 1: [36000, 36596] -> floor(596 / 10) + 1 = 60 slots; 150 reports each after dedup
    assert (first["start_tod"], first["end_tod"], first["slots"]) == (36000.0, 36596.0, 60)
    assert (first["radar_before"], first["adsb_before"]) == (150, 150)
    assert (first["radar_after"], first["adsb_after"]) == (60, 60)
    assert (first["adsb_duplicates"], first["radar_duplicates"]) == (2, 0)
    assert (second["adsb_duplicates"], second["radar_duplicates"]) == (0, 1)
    assert first["start"] == pd.Timestamp("2019-03-01T10:00:00", tz="UTC")
    assert first["ncc0_lat"] == pytest.approx(1.0) and first["pearson0_lon"] == pytest.approx(1.0)
    assert first["pearson_peak_lag_lat"] == 0 and first["ncc_peak_lag_lon"] == 0
    assert first["sep_max_m"] == pytest.approx(0.0, abs=1e-6)
    w = run.windows[0]
    assert list(w.slots.columns) == SLOT_COLUMNS and len(w.slots) == 60
    assert list(w.lags.columns) == LAG_COLUMNS and w.lags["lag"].tolist() == list(range(-59, 60))
    assert w.slots["timestamp"].iloc[1] == pd.Timestamp("2019-03-01T10:00:10", tz="UTC")
    assert w.slots["timestamp"].dtype == "datetime64[ns, UTC]"
    assert run.skipped == []


def test_correlate_detects_a_30_s_delay():
    # radar reports the ADS-B position 30 s late = 3 slots of 10 s -> peak lag +3 (radar lags)
    t = np.arange(36000.0, 37800.0, 2.0)
    radar = frame("radar", t, *weave(t - 30.0))
    adsb = frame("adsb", t, *weave(t))
    (w,) = corr(radar, adsb, address="750123").windows
    assert w.summary["pearson_peak_lag_lat"] == 3 and w.summary["pearson_peak_lag_lon"] == 3
    assert w.summary["start"] is None and w.slots["timestamp"].isna().all()
    assert w.slots["timestamp"].dtype == "datetime64[ns, UTC]"
    # 30 s along the weave moves the point by a few hundred metres at most (~0.005 deg)
    assert 100.0 < w.summary["sep_max_m"] < 2000.0


def test_correlate_across_midnight_and_short_window():
    # day 0 86300..86399 and day 1 (86400 + 0..200): one window spanning midnight, plus a 5 s window
    t = np.concatenate([np.arange(86300.0, 86600.0, 5.0), [90000.0, 90005.0]])
    lat, lon = weave(t)
    run = corr(frame("radar", t, lat, lon), frame("adsb", t, lat, lon), callsign="MAS72", date="2019-03-01")
    (w,) = run.windows
    assert (w.summary["start_tod"], w.summary["end_tod"]) == (86300.0, 86595.0)
    assert w.summary["end"] == pd.Timestamp("2019-03-02T00:03:15", tz="UTC")
    (skip,) = run.skipped
    assert (skip.start_tod, skip.end_tod) == (90000.0, 90005.0) and "shorter than one slot" in skip.reason


def test_no_such_aircraft_suggests_close_callsigns():
    t = np.arange(0.0, 100.0, 5.0)
    radar = pd.concat([frame("radar", t, *weave(t)), frame("radar", t, *weave(t), "SIA321", "76CD01")])
    adsb = pd.concat([frame("adsb", t, *weave(t)), frame("adsb", t, *weave(t), "SIA321", "76CD01")])
    with pytest.raises(NoSuchAircraft) as info:
        corr(radar, adsb, callsign="MAS 27")
    assert "MAS72" in str(info.value)
    assert info.value.missing_in == ["radar", "ADS-B"]


def test_no_such_aircraft_suggests_names_of_every_sensor():
    """VLG130 asked, VLG1306 seen by ADS-B alone: it is suggested, saying that radar lacks it (the
    suggestions were taken from the names both sensors saw only: "nothing similar is present")."""
    t = np.arange(0.0, 100.0, 5.0)
    radar = pd.concat([frame("radar", t, *weave(t)), frame("radar", t, *weave(t), "AFR12", "3944F1")])
    adsb = pd.concat([frame("adsb", t, *weave(t)), frame("adsb", t, *weave(t), "VLG1306", "3443C5")])
    with pytest.raises(NoSuchAircraft) as info:
        corr(radar, adsb, callsign="VLG130")
    assert "closest present: VLG1306 (ADS-B only)" in str(info.value)
    assert "nothing similar" not in str(info.value)
    with pytest.raises(NoSuchAircraft) as info:
        corr(radar, adsb, callsign="AFR123")
    assert "AFR12 (radar only)" in str(info.value)


def test_no_overlap_gives_both_spans():
    radar = frame("radar", np.arange(0.0, 100.0, 5.0), 1.0, 103.0)
    adsb = frame("adsb", np.arange(1000.0, 1100.0, 5.0), 1.0, 103.0)
    with pytest.raises(NoOverlap) as info:
        corr(radar, adsb, callsign="MAS72")
    # undated: clock times (95 s = 00:01:35, 1000 s = 00:16:40, 1095 s = 00:18:15), not seconds of day
    assert "00:00:00 to 00:01:35" in str(info.value) and "00:16:40 to 00:18:15" in str(info.value)


def test_all_aircraft_needs_both_sensors():
    # MAS72 in both; SIA321's radar plots lack the call sign; AXM1's radar plots lack the address;
    # QFA1 only in ADS-B; BAW9 only by call sign in both sensors
    t = np.arange(0.0, 200.0, 5.0)

    def sensor(name, ids):
        return pd.concat([frame(name, t, *weave(t), cs, addr) for cs, addr in ids], ignore_index=True)

    radar = sensor("radar", [("MAS72", "750123"), (None, "76CD01"), ("AXM1", None), ("BAW9", None)])
    adsb = sensor("adsb", [("MAS72", "750123"), ("SIA321", "76CD01"), ("AXM1", "75008F"), ("QFA1", "7C0001"),
                           ("BAW9", None)])
    run = corr(radar, adsb, all_aircraft=True)
    assert [(w.summary["callsign"], w.summary["address"]) for w in run.windows] == [
        ("AXM1", "75008F"), ("BAW9", ""), ("MAS72", "750123"), ("SIA321", "76CD01")]
    assert all(w.summary["radar_before"] == 40 and w.summary["adsb_before"] == 40 for w in run.windows)
    with pytest.raises(NoSuchAircraft, match="no aircraft is seen by both"):
        corr(radar.iloc[:0], adsb, all_aircraft=True)


def test_times_count_from_the_first_midnight_of_the_data():
    t = np.arange(36000.0, 36100.0, 5.0)
    radar, adsb = frame("radar", t, *weave(t)), frame("adsb", t, *weave(t))
    run = corr(radar, adsb, date="2019-03-01", callsign="MAS72")
    (w,) = run.windows
    assert w.summary["start"] == pd.Timestamp("2019-03-01T10:00:00", tz="UTC")
    assert w.summary["start_tod"] == 36000.0
    assert run.parameters["date"] == "2019-03-01"
    assert corr(radar, adsb, callsign="MAS72").parameters["date"] is None  # undated


def test_ncc_and_pearson_match_their_definitions():
    rng = np.random.default_rng(11)
    for n in (1, 2, 5, 17):
        x, y = rng.normal(size=n) + 2, rng.normal(size=n) - 1
        lags, r = ncc(x, y)
        _, p = pearson_by_lag(x, y)
        for d, r_d, p_d in zip(lags, r, p, strict=True):
            pairs = [(x[i], y[i - d]) for i in range(n) if 0 <= i - d < n]
            a, b = np.array(pairs).T
            assert r_d == pytest.approx(np.sum(a * b) / np.sqrt(np.sum(x**2) * np.sum(y**2)))
            if len(pairs) < 2:
                assert np.isnan(p_d)
            else:
                assert p_d == pytest.approx(np.corrcoef(a, b)[0, 1])


def _direct_by_lag(x, y):
    """O(N^2) reference written from the definitions: NCC by the sum of products, Pearson by
    np.corrcoef of each overlap (NaN for fewer than 2 pairs or a constant side)."""
    n = len(x)
    lags = np.arange(-(n - 1), n)
    r, p = np.empty(lags.size), np.full(lags.size, np.nan)
    norm = math.sqrt(np.sum(x**2) * np.sum(y**2))
    for j, d in enumerate(lags):
        idx = np.arange(max(d, 0), min(n, n + d))
        a, b = x[idx], y[idx - d]
        r[j] = np.sum(a * b) / norm
        if a.size >= 2 and np.ptp(a) > 0 and np.ptp(b) > 0:
            p[j] = np.corrcoef(a, b)[0, 1]
    return lags, r, p


@pytest.mark.parametrize("n", [3, 64, 257, 1000])
def test_fft_correlations_match_a_direct_computation(n):
    rng = np.random.default_rng(n)
    # latitude-like series: a large offset and a small walk, the case where cancellation would hurt
    x = 3.1 + 1e-3 * np.cumsum(rng.normal(size=n))
    y = 3.1 + 1e-3 * np.cumsum(rng.normal(size=n))
    # held (filled) slots give exactly constant runs at both ends: their short overlaps have no Pearson
    k = max(1, n // 10)
    x[:k], y[:k], y[-k:] = x[k], y[k], y[-k - 1]  # x prefix: lags < 0; y prefix: lags > 0
    lags, r_ref, p_ref = _direct_by_lag(x, y)
    got_lags, r = ncc(x, y)
    _, p = pearson_by_lag(x, y)
    assert got_lags.tolist() == lags.tolist()
    np.testing.assert_allclose(r, r_ref, rtol=0, atol=1e-12)
    assert np.array_equal(np.isnan(p), np.isnan(p_ref))
    if n > 3:  # the constant ends do remove some lags, on both sides of zero
        assert np.isnan(p[: k]).all() and np.isnan(p[-k:]).all() and not np.isnan(p[n - 1])
    ok = ~np.isnan(p_ref) & (np.abs(lags) <= pearson_max_lag(n))  # where the peak is searched
    np.testing.assert_allclose(p[ok], p_ref[ok], rtol=0, atol=1e-7)
    assert peak_lag(lags, p, pearson_max_lag(n)) == peak_lag(lags, p_ref, pearson_max_lag(n))


def test_fft_correlations_hold_on_long_series():
    """10^5 slots (the O(N^2) loop took minutes; its speed is benchmarks' business, not a test's): the
    delay found and its coefficient 1, with no cancellation over the long sums."""
    s = np.cumsum(np.random.default_rng(3).normal(size=100_005))
    x, y = s[:-5], s[5:]  # y[i - 5] = s[i] = x[i]: radar 5 slots behind
    lags, p = pearson_by_lag(x, y)
    assert peak_lag(lags, p, pearson_max_lag(x.size)) == 5
    assert p[lags == 5][0] == pytest.approx(1.0)


def test_slot_count_cap_counts_every_window_slot(monkeypatch):
    import msdc.pipeline.correlate.correlation as correlation

    # one window 36000-36095 s; at 0.1 s it has floor(95 / 0.1) + 1 = 951 slots
    t = np.arange(36000.0, 36100.0, 5.0)
    radar, adsb = frame("radar", t, *weave(t)), frame("adsb", t, *weave(t))
    monkeypatch.setattr(correlation, "MAX_SLOTS", 951)
    (w,) = corr(radar, adsb, callsign="MAS72", slot_s=0.1).windows
    assert w.summary["slots"] == 951
    monkeypatch.setattr(correlation, "MAX_SLOTS", 950)
    with pytest.raises(correlation.TooManySlots) as exc:
        corr(radar, adsb, callsign="MAS72", slot_s=0.1)
    assert exc.value.slots == 951


def test_slot_limit_is_the_table_budget_over_measured_row_sizes():
    """MAX_SLOTS is the table budget over what a slot costs in memory: its slot row plus two lag rows,
    measured here on a real window's tables (pandas' own byte count, no index)."""
    import msdc.pipeline.correlate.correlation as correlation

    t = np.arange(36000.0, 36100.0, 5.0)
    radar, adsb = frame("radar", t, *weave(t)), frame("adsb", t, *weave(t))
    (w,) = corr(radar, adsb, callsign="MAS72", slot_s=1.0).windows
    n = len(w.slots)  # 96 slots, 191 lag rows
    slot_row = w.slots.memory_usage(index=False).sum() / n
    lag_row = w.lags.memory_usage(index=False).sum() / (2 * n - 1)
    assert (slot_row, lag_row) == (correlation.SLOT_ROW_BYTES, correlation.LAG_ROW_BYTES) == (82, 40)
    assert correlation.MAX_SLOTS == 512 * 2**20 // 162 == 3_314_017
    assert correlation.MAX_SLOTS * 162 <= 512 * 2**20


def test_too_many_slots_is_one_line_naming_slot_and_writes_nothing(monkeypatch, tmp_path, capsys):
    import msdc.pipeline.correlate.correlation as correlation
    from msdc.pipeline.cli import main

    monkeypatch.setattr(correlation, "MAX_SLOTS", 10)
    out = tmp_path / "report.xlsx"
    fx = "fixtures/"
    status = main(["correlate", fx + "radar.ast", fx + "adsb.ast", "--sensors", fx + "sensors.toml",
                   "--callsign", "MAS72", "--date", "2019-03-01", "--slot", "0.5", "-o", str(out)])
    err = capsys.readouterr().err.strip().splitlines()[-1]  # after the progress stages
    assert status == 2 and not out.exists() and list(tmp_path.iterdir()) == []
    assert err.startswith("msdc correlate: --slot 0.5: ") and "more than 10 slots" in err


M_PER_DEG = 111_195.0  # metres per degree of a great circle on the 6,371 km sphere (flat enough over 30 min)


def flight(t, turning: bool):
    """Latitude and longitude at times t (s) of an aircraft at 230 m/s near the equator: a straight leg at
    heading 045, or one whose heading swings +-60 deg about 045 with a 900 s period (integrated by hand)."""
    v, t0 = 230.0, 36000.0
    if turning:  # heading h(t) = 45 + 60 sin(w s); position = integral of v (sin h, cos h), by fine sums
        fine = np.arange(t0, t.max() + 1.0, 0.5)
        h = np.radians(45.0 + 60.0 * np.sin(2 * np.pi * (fine - t0) / 900.0))
        east, north = np.cumsum(v * np.sin(h)) * 0.5, np.cumsum(v * np.cos(h)) * 0.5
        east, north = np.interp(t, fine, east), np.interp(t, fine, north)
    else:
        east = north = v * math.sqrt(0.5) * (t - t0)
    return 1.0 + north / M_PER_DEG, 103.0 + east / M_PER_DEG


def noisy_pair(seed: int, turning: bool, late_s: float = 30.0):
    """Radar plots every 4.7 s with 150 m noise per axis, reporting the position of late_s earlier; ADS-B
    every 1 s with 10 m noise; 30 min."""
    rng = np.random.default_rng(seed)
    tr, ta = np.arange(36000.0, 37800.0, 4.7), np.arange(36000.0, 37800.0, 1.0)
    lat_r, lon_r = flight(tr - late_s, turning)
    lat_a, lon_a = flight(ta, turning)
    radar = frame("radar", tr, lat_r + rng.normal(0, 150.0, tr.size) / M_PER_DEG,
                  lon_r + rng.normal(0, 150.0, tr.size) / M_PER_DEG)
    adsb = frame("adsb", ta, lat_a + rng.normal(0, 10.0, ta.size) / M_PER_DEG,
                 lon_a + rng.normal(0, 10.0, ta.size) / M_PER_DEG)
    return radar, adsb


@pytest.mark.parametrize("seed", range(5))
def test_pearson_lag_is_recovered_on_a_turning_leg(seed):
    """Radar 30 s late = +3 slots of 10 s; the heading swings +-60 deg, so the series are far from straight
    lines and the lag is identified on both axes."""
    (w,) = corr(*noisy_pair(seed, turning=True), address="750123").windows
    s = w.summary
    assert (s["pearson_peak_lag_lat"], s["pearson_peak_lag_lon"]) == (3, 3)
    assert (s["pearson_lag_unidentified_lat"], s["pearson_lag_unidentified_lon"]) == (False, False)


@pytest.mark.parametrize("seed", range(5))
def test_pearson_lag_is_withheld_on_a_straight_leg(seed):
    """The same radar delay on a straight constant-speed leg: a delayed line is the line plus a constant,
    which Pearson removes, so the curve is flat within noise and its peak says nothing: no lag (null), a
    flag and a note."""
    (w,) = corr(*noisy_pair(seed, turning=False), address="750123").windows
    s = w.summary
    assert (s["pearson_peak_lag_lat"], s["pearson_peak_lag_lon"]) == (None, None)
    assert (s["pearson_lag_unidentified_lat"], s["pearson_lag_unidentified_lon"]) == (True, True)
    assert s["pearson_peak_at_limit_lat"] is False
    note = window_note(s)
    assert "Pearson latitude and longitude peak lag not identified" in note


def test_lag_signal_of_a_line_is_zero_and_its_noise_is_the_added_noise():
    """A straight, evenly stepped reference has no manoeuvre energy (its steps are all equal); white noise
    of sigma 2.0 added to the radar side is read back by the third differences (20 sigma^2) within 5 %."""
    rng = np.random.default_rng(7)
    y = 5.0 + 0.25 * np.arange(20000)
    signal, sigma = lag_signal(y + rng.normal(0.0, 2.0, y.size), y)
    assert signal == 0.0
    assert sigma == pytest.approx(2.0, rel=0.05)
    # a parabola: steps 2 a i + const, so E1 = sum (2 a (i - mean i))^2 over the N - 1 steps
    n, a = 50, 0.3
    par = a * np.arange(n, dtype=float) ** 2
    steps = np.arange(n - 1, dtype=float)
    expected = math.sqrt(np.sum((2 * a * (steps - steps.mean())) ** 2))
    assert lag_signal(par, par)[0] == pytest.approx(expected, rel=1e-9)
