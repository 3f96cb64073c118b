"""ADS-B position-jump detection: simulator recall and false alarms; hand-made tracks (ends, runs, turns)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pandas as pd
import pytest
from measurement_frames import meas_frame

from fixtures.scenario import default_scenario
from fixtures.simulate import simulate
from msdc.pipeline.model import jumps
from msdc.pipeline.model.geodesy import distance_m, ecef_to_geodetic, enu_to_ecef
from msdc.pipeline.model.identity import assign_aircraft_id
from msdc.pipeline.model.jumps import JUMP_COLUMNS, detect_jumps, jump_flags, jump_table
from msdc.pipeline.model.measurements import adsb_measurements

LAT0, LON0 = 3.0, 101.5


def track(t_s, *, speed_ms=230.0, track_deg=60.0, turn_dps=0.0, noise_m=5.0, seed=0, address="750001",
          callsign="TEST1", lat0=LAT0, lon0=LON0) -> pd.DataFrame:
    """ADS-B measurements of one aircraft flying a constant-rate turn (or straight line) at FL 300."""
    t = np.asarray(t_s, dtype=float)
    rel = t - t[0]
    if turn_dps:
        w = np.radians(turn_dps)
        psi0 = np.radians(track_deg)
        e = speed_ms / w * (np.cos(psi0) - np.cos(psi0 + w * rel))
        n = speed_ms / w * (np.sin(psi0 + w * rel) - np.sin(psi0))
        trk = np.degrees(psi0 + w * rel) % 360.0
    else:
        e = speed_ms * rel * np.sin(np.radians(track_deg))
        n = speed_ms * rel * np.cos(np.radians(track_deg))
        trk = np.full(t.size, track_deg)
    rng = np.random.default_rng(seed)
    e, n = e + rng.normal(0, noise_m, t.size), n + rng.normal(0, noise_m, t.size)
    lat, lon, _ = ecef_to_geodetic(*enu_to_ecef(e, n, np.zeros(t.size), lat0, lon0, 9144.0))
    return meas_frame(pd.DataFrame({
        "sensor": "adsb", "time_of_day": t, "latitude": lat, "longitude": lon,
        "flight_level": 300.0, "ground_speed_kt": speed_ms * 3600 / 1852, "heading_deg": trk,
        "callsign": callsign, "address": address, "sac": 0, "sic": 1, "nucp_nic": 8, "nacp": 9}))


def shift(frame: pd.DataFrame, rows, d_east_m: float, d_north_m: float) -> pd.DataFrame:
    """A copy with the given rows moved by (east, north) metres (local flat approximation)."""
    out = frame.copy()
    lat = np.radians(out.loc[rows, "latitude"])
    out.loc[rows, "latitude"] += np.degrees(d_north_m / 6.371e6)
    out.loc[rows, "longitude"] += np.degrees(d_east_m / (6.371e6 * np.cos(lat)))
    return out


def flagged(frame: pd.DataFrame, **kw) -> list[int]:
    return np.flatnonzero(detect_jumps(frame, **kw).to_numpy()).tolist()


# ---------------------------------------------------------------------------------------------------------
# Simulator: recall and false alarms against the injected jumps


def _sim_scores(sc, seed: int) -> tuple[int, int, int, int]:
    sim = simulate(sc, seed)
    adsb = adsb_measurements(sim.adsb)
    truth = sim.truth_tracks.query("sensor == 'adsb'").sort_values("row")["jump"].to_numpy()
    found = detect_jumps(adsb).to_numpy()
    return int(truth.sum()), int((found & truth).sum()), int((~truth).sum()), int((found & ~truth).sum())


@pytest.mark.parametrize("case", ["default", "many_jumps"])
def test_simulated_jumps_are_found_with_few_false_alarms(case):
    if case == "default":
        sc, seeds = default_scenario(), [2019]
    else:  # 3 % jumps (many runs of 2-3), more low-NIC episodes (sigma 100 m) and more dropouts
        sc = replace(default_scenario(), adsb_jump_fraction=0.03, adsb_low_quality_episodes=8,
                     adsb_short_dropouts_per_hour=10.0)
        seeds = [1, 2]
    n_jumps = hits = n_clean = false = 0
    for seed in seeds:
        a, b, c, d = _sim_scores(sc, seed)
        n_jumps, hits, n_clean, false = n_jumps + a, hits + b, n_clean + c, false + d
    assert n_jumps >= 30
    assert hits / n_jumps >= 0.95
    assert false / n_clean <= 0.01
    print(f"{case}: recall {hits}/{n_jumps}, false alarms {false}/{n_clean}")


def test_jump_table_sizes_match_the_injected_offsets():
    sim = simulate(default_scenario(), 2019)
    adsb = adsb_measurements(sim.adsb)
    tt = sim.truth_tracks.query("sensor == 'adsb'").set_index("row").sort_index()
    table = jump_table(adsb)
    assert list(table.columns) == JUMP_COLUMNS
    assert table["time_of_day"].is_monotonic_increasing
    truth = tt.loc[table["row"]]
    assert truth["jump"].all()
    # the injected offset, measured from where the aircraft really was
    size = distance_m(truth["latitude"], truth["longitude"], truth["latitude"] + truth["jump_dlat_deg"],
                      truth["longitude"] + truth["jump_dlon_deg"])
    np.testing.assert_allclose(table["jump_size_m"], size, rtol=0.01, atol=100.0)
    assert set(table["callsign"]) <= {a.spec.callsign for a in sim.aircraft}


# ---------------------------------------------------------------------------------------------------------
# Hand-made tracks


def test_clean_straight_track_has_no_jumps():
    assert flagged(track(np.arange(300.0))) == []


def test_isolated_jump_only_condemns_itself():
    t = track(np.arange(100.0))
    assert flagged(shift(t, [50], 20_000.0, 0.0)) == [50]
    # a jump smaller than the speed limit allows in 1 s but far from the local fit
    assert flagged(shift(t, [50], 0.0, 2_500.0)) == [50]


def test_jumps_at_start_and_end_of_track():
    t = shift(track(np.arange(100.0)), [0, 99], 30_000.0, -10_000.0)
    assert flagged(t) == [0, 99]
    t = shift(track(np.arange(100.0)), [0, 1], 50_000.0, 0.0)  # a run at the start
    t = shift(t, [1], 0.0, 40_000.0)
    assert flagged(t) == [0, 1]


@pytest.mark.parametrize("run", [[40, 41], [60, 61, 62]])
def test_runs_of_consecutive_scattered_jumps(run):
    t = track(np.arange(120.0), turn_dps=1.5)
    for k, row in enumerate(run):
        t = shift(t, [row], 15_000.0 * (k + 1) * (-1) ** k, 9_000.0 * (k + 2))
    assert flagged(t) == run


@pytest.mark.parametrize("run", [[40, 41], [60, 61, 62]])
def test_runs_of_jumps_to_the_same_place(run):
    t = track(np.arange(120.0))
    bad = t.loc[run[0]].copy()
    for row in run:  # a frozen, far position repeated (e.g. a stale decode)
        t.loc[row, ["latitude", "longitude"]] = bad["latitude"] + 0.2, bad["longitude"] - 0.1
    assert flagged(t) == run


def test_turning_track_with_dropouts_and_irregular_intervals_has_no_jumps():
    rng = np.random.default_rng(4)
    times = np.cumsum(rng.uniform(0.5, 1.5, 900))
    dropouts = ((200, 260), (500, 600), (700, 705))
    keep = ~np.any([(times > a) & (times < b) for a, b in dropouts], axis=0)
    for turn in (-3.0, 1.0, 3.0):
        t = track(times[keep], turn_dps=turn, speed_ms=240.0, noise_m=30.0)
        assert flagged(t) == [], turn


def test_noisy_low_integrity_positions_are_not_jumps():
    t = track(np.arange(0.0, 400.0, 0.8), noise_m=150.0, seed=3)  # NACp 6-like scatter
    assert flagged(t) == []


def test_a_jump_next_to_a_gap_is_found():
    times = np.concatenate([np.arange(0.0, 50.0), np.arange(90.0, 150.0)])
    t = track(times, turn_dps=1.0)
    assert flagged(shift(t, [50], 0.0, 25_000.0)) == [50]  # first report after a 40 s gap


def test_aircraft_are_judged_separately_and_index_is_kept():
    a = track(np.arange(0.0, 100.0), address="750001", callsign="A1")
    b = track(np.arange(0.5, 100.5), address="750002", callsign="B2", lat0=4.5, lon0=100.0)
    b = shift(b, [30], 20_000.0, 0.0)
    both = pd.concat([a, b]).sort_values("time_of_day")
    both.index = np.arange(1000, 1000 + len(both))[::-1]
    jumps = detect_jumps(both)
    assert jumps.index.equals(both.index)
    hit = both[jumps.to_numpy()]
    assert len(hit) == 1 and hit["address"].iloc[0] == "750002" and hit["time_of_day"].iloc[0] == 30.5
    # without addresses the call sign groups the reports (identity rule)
    anonymous = both.assign(address=pd.NA)
    assert detect_jumps(anonymous.assign(aircraft_id=assign_aircraft_id(anonymous))).sum() == 1


def test_segments_are_judged_alone_whatever_the_batching(monkeypatch):
    # A ends with a jump and B (sorted next to it) starts with a bigger one: each aircraft's verdicts and
    # fits are those it gets alone, and searching segment by segment (batches of one segment) or all at
    # once gives the same columns
    a = shift(track(np.arange(0.0, 60.0), address="750001", callsign="A1"), [58], 12_000.0, 0.0)
    b = track(np.arange(0.0, 60.0), address="750002", callsign="B2", turn_dps=2.0)
    b = shift(b, [1], -40_000.0, 30_000.0)
    c = track(np.arange(0.0, 300.0, 1.0), address="750003", callsign="C3", noise_m=40.0, seed=7)
    c = c[(c["time_of_day"] < 100) | (c["time_of_day"] > 250)]  # two segments (gap over 120 s)
    c = shift(c.reset_index(drop=True), [99, 100], 9_000.0, -9_000.0)
    both = pd.concat([a, b, c], ignore_index=True)
    whole = jump_flags(both)
    monkeypatch.setattr(jumps, "JUMP_BATCH_REPORTS", 1)
    pd.testing.assert_frame_equal(jump_flags(both), whole)
    alone = pd.concat([jump_flags(a), jump_flags(b), jump_flags(c)], ignore_index=True)
    pd.testing.assert_frame_equal(alone, whole)
    assert whole["jump"].sum() >= 3 and bool(whole["jump"].iloc[58]) and bool(whole["jump"].iloc[61])


def test_unidentified_rows_are_not_judged_and_duplicates_do_no_harm():
    t = track(np.arange(100.0))
    t = pd.concat([t, t.iloc[[10, 20, 30]]]).sort_values("time_of_day", kind="stable")
    assert detect_jumps(t).sum() == 0
    anon = shift(t, [50], 50_000.0, 0.0).assign(aircraft_id=pd.NA)
    assert detect_jumps(anon).sum() == 0


def test_tracks_crossing_the_antimeridian():
    t = track(np.arange(200.0), track_deg=90.0, lat0=-15.0, lon0=179.9)
    t["longitude"] = (t["longitude"] + 180.0) % 360.0 - 180.0
    assert (t["longitude"] < 0).any() and (t["longitude"] > 0).any()
    assert flagged(t) == []
    assert flagged(shift(t, [120], 0.0, 30_000.0)) == [120]


def test_parameters_and_empty_input():
    t = shift(track(np.arange(60.0)), [30], 0.0, 3_000.0)
    assert flagged(t) == [30]
    assert flagged(t, robust_threshold_m=5_000.0, max_speed_kt=20_000.0) == []
    assert detect_jumps(t.iloc[:0]).empty
    assert jump_table(t.iloc[:0]).empty
    with pytest.raises(ValueError):
        detect_jumps(t, robust_window=2)


def test_duplicate_index_labels():
    t = track(np.arange(80.0))
    t.loc[40, "latitude"] += 0.5
    t = pd.concat([t, t.iloc[[5, 6]]])  # labels 5 and 6 now appear twice
    assert detect_jumps(t).sum() == 1
    table = jump_table(t)
    assert table["row"].tolist() == [40] and table["jump_size_m"].iloc[0] == pytest.approx(55_300, rel=0.01)


def test_theil_sen_kernel_matches_a_plain_median_of_pairwise_slopes():
    """The compiled fit against statistics.median over the neighbours' pairwise slopes, with missing
    neighbours (-1) and repeated times (pairs of equal time give no slope)."""
    import statistics

    from msdc.pipeline.model.jumps import _theil_sen

    rng = np.random.default_rng(8)
    n = 200
    t = np.round(rng.uniform(0, 60, n))  # rounded: many equal times
    lat, lon = rng.normal(40, 0.1, n), rng.normal(2, 0.1, n)
    idx = rng.integers(0, n, (n, 6))
    idx[rng.random((n, 6)) < 0.3] = -1
    rows = np.arange(n)
    fit_lat, fit_lon, dt_b, dt_a, far, count = _theil_sen(t, lat, lon, idx, rows)
    for i in range(n):
        j = [k for k in idx[i] if k >= 0]
        assert count[i] == len(j)
        dts = [t[k] - t[i] for k in j]
        before, after = [-d for d in dts if d < 0], [d for d in dts if d > 0]
        assert dt_b[i] == (min(before) if before else np.nan) or (not before and np.isnan(dt_b[i]))
        assert dt_a[i] == (min(after) if after else np.nan) or (not after and np.isnan(dt_a[i]))
        for y, fitted in ((lat, fit_lat), (lon, fit_lon)):
            slopes = [(y[b] - y[a]) / (t[b] - t[a])
                      for p, a in enumerate(j) for b in j[p + 1:] if t[b] != t[a]]
            slope = statistics.median(slopes) if slopes else 0.0
            expect = statistics.median([y[k] - slope * (t[k] - t[i]) for k in j]) if j else np.nan
            assert fitted[i] == pytest.approx(expect, rel=1e-12, abs=1e-12, nan_ok=True)


def test_refitting_only_changed_neighbourhoods_equals_refitting_everything(monkeypatch):
    """After its first pass the search scores again only the reports near a flipped one, and re-fits only
    those whose neighbours changed; scoring and re-fitting every report every pass must give the same jumps
    and fits (runs of jumps need several passes; a rejected report is reinstated)."""
    from msdc.pipeline.model import jumps

    meas = pd.concat([track(np.arange(0, 600, 4.0), seed=s, address=f"75000{s}", callsign=f"T{s}")
                      for s in range(3)], ignore_index=True)
    meas.loc[[20, 21, 22, 90, 200, 201, 300], "latitude"] += [0.1, 0.12, -0.1, 0.2, 0.05, -0.05, 0.3]
    # 40 more reports moved 1-5 km at random: with this seed one rejected report is reinstated
    rng = np.random.default_rng(15)
    hit = rng.choice(len(meas), 40, replace=False)
    meas.loc[hit, "latitude"] += rng.choice([-1, 1], 40) * rng.uniform(0.01, 0.05, 40)
    meas["aircraft_id"] = assign_aircraft_id(meas)
    passes, reinstated = [], []
    search, rejected = jumps._Tracks.search, jumps._Tracks._rejected

    def counted(self, *args):
        calls = []
        rescore = self.rescore
        self.rescore = lambda accepted, rows, *a: (calls.append(rows.size), rescore(accepted, rows, *a))
        out = search(self, *args)
        passes.append(calls)
        return out

    def rejected_and_reinstated(self, accepted):
        reinstated.append(int((~accepted & (self.score <= 1.0)).sum()))
        return rejected(self, accepted)

    monkeypatch.setattr(jumps._Tracks, "search", counted)
    monkeypatch.setattr(jumps._Tracks, "_rejected", rejected_and_reinstated)
    incremental = jumps.jump_flags(meas)
    first, *later = passes[0]  # later passes score fewer reports, the last a few
    assert len(later) >= 2 and max(later) < first and later[-1] < first / 4
    assert sum(reinstated) >= 1

    fit = jumps._Tracks.fit

    def fit_all(self, i, idx, threshold_m):
        self._fit = None
        return fit(self, i, idx, threshold_m)

    monkeypatch.setattr(jumps._Tracks, "fit", fit_all)
    monkeypatch.setattr(jumps._Tracks, "affected", lambda self, kept, changed: np.arange(self.n))
    everything = jumps.jump_flags(meas)
    assert incremental["jump"].sum() >= 5
    pd.testing.assert_frame_equal(incremental, everything, check_exact=True)


def test_jump_flags_of_some_columns_equal_those_of_all():
    """A job that reads only the jump verdict asks for that column alone (the fit distances are then not
    worked out); the verdicts and fits it gets are those of the full call."""
    from msdc.pipeline.model import jumps

    meas = track(np.arange(0, 600, 4.0), seed=3, address="750003", callsign="T3")
    meas.loc[[20, 21, 90], "latitude"] += [0.1, 0.12, 0.2]
    meas["aircraft_id"] = assign_aircraft_id(meas)
    full = jumps.jump_flags(meas)
    assert full["jump"].sum() >= 3
    for columns in (["jump"], ["fit_latitude", "jump"], []):
        got = jumps.jump_flags(meas, columns=columns)
        want = [c for c in jumps.JUMP_FLAG_COLUMNS if c in columns]
        assert list(got.columns) == want
        pd.testing.assert_frame_equal(got, full[want], check_exact=True)
