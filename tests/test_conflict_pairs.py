"""Pair pre-filter against brute force over every pair, and the separation geometry against closed forms."""

import math

import numpy as np
import pandas as pd
import pytest

from pipeline.conflict import (
    candidate_pairs,
    closing_margin_m,
    conflict_probability,
    horizontal_distance_nm,
    pair_probabilities,
    pairs_per_step,
)

A = 6378137.0


def brute_pairs(pos, alt, radius, vertical):
    n = len(pos)
    i, j = np.triu_indices(n, 1)
    ok = (np.linalg.norm(pos[i] - pos[j], axis=1) <= radius) & (np.abs(alt[i] - alt[j]) <= vertical)
    return {(int(a), int(b)) for a, b in zip(i[ok], j[ok], strict=True)}


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("radius, vertical", [(9260.0, 1000.0), (30000.0, 3000.0), (5000.0, 0.0)])
def test_candidate_pairs_equal_brute_force(dim, radius, vertical):
    rng = np.random.default_rng(dim * 7 + int(radius))
    for _ in range(5):
        pos = rng.uniform(0, 300_000, (400, dim))
        alt = rng.integers(250, 410, 400) * 100.0  # flight levels, many exactly 1000 ft or 0 ft apart
        got = candidate_pairs(pos, alt, radius, vertical)
        assert {tuple(map(int, p)) for p in got} == brute_pairs(pos, alt, radius, vertical)
        assert np.all(got[:, 0] < got[:, 1])


def test_candidate_pairs_edge_cases():
    assert candidate_pairs(np.zeros((1, 2)), [0.0], 10.0, 10.0).shape == (0, 2)
    pos = np.array([[0.0, 0.0], [np.nan, 0.0], [3.0, 4.0]])
    assert candidate_pairs(pos, [0.0, 0.0, 0.0], 5.0, 0.0).tolist() == [[0, 2]]  # 5 m: on the edge counts
    with pytest.raises(ValueError, match=r"altitude_ft: expected shape \(3,\)"):
        candidate_pairs(pos, [0.0], 5.0, 0.0)
    with pytest.raises(ValueError, match="radius_m: must be a finite non-negative distance, got -1"):
        candidate_pairs(pos, [0.0, 0.0, 0.0], -1, 0.0)


def test_closing_margin():
    assert closing_margin_m(600.0, 120.0) == pytest.approx(2 * 600 * 1852 / 3600 * 120)


def test_horizontal_distance_against_closed_forms():
    # along the equator the surface is a circle of radius A: chord 2 A sin(dlon / 2)
    dlon = np.array([0.01, 0.1, 0.5])
    got = horizontal_distance_nm(0.0, 10.0, 0.0, 10.0 + dlon)
    assert got == pytest.approx(2 * A * np.sin(np.radians(dlon) / 2) / 1852, rel=1e-12)
    # along a meridian: within 1 cm of the meridian arc (numerically integrated radius of curvature) at 10 NM
    f = 1 / 298.257223563
    e2 = f * (2 - f)
    lat = np.linspace(45.0, 45.0 + 10 / 60, 20001)
    m_radius = A * (1 - e2) / (1 - e2 * np.sin(np.radians(lat)) ** 2) ** 1.5
    arc = np.trapezoid(m_radius, np.radians(lat))
    assert abs(horizontal_distance_nm(45.0, 3.0, lat[-1], 3.0) * 1852 - arc) < 0.01


def random_tracks(rng, n_aircraft=60, n_steps=5):
    t0 = pd.Timestamp("2024-05-01 10:00", tz="UTC")
    rows = []
    for k in range(n_steps):
        lat = 3.0 + rng.uniform(-1, 1, n_aircraft)
        lon = 101.0 + rng.uniform(-1, 1, n_aircraft)
        fl = rng.integers(300, 310, n_aircraft).astype(float) + rng.choice([0, 0.5], n_aircraft)
        rows.append(pd.DataFrame({"aircraft_id": [f"AC{i:03d}" for i in range(n_aircraft)],
                                  "time": t0 + pd.Timedelta(seconds=k), "latitude": lat,
                                  "longitude": lon, "flight_level": fl}))
    return pd.concat(rows, ignore_index=True)


def test_pairs_per_step_equal_brute_force():
    tracks = random_tracks(np.random.default_rng(1)).sample(frac=0.9, random_state=2)  # some absent
    got = pairs_per_step(tracks, radius_nm=10.0, vertical_ft=1000.0)
    found = set(got.itertuples(index=False, name=None))
    expected = set()
    for t, g in tracks.groupby("time"):
        g = g.sort_values("aircraft_id")
        ids, la, lo, fl = (g[c].to_numpy() for c in ("aircraft_id", "latitude", "longitude", "flight_level"))
        i, j = np.triu_indices(len(g), 1)
        ok = horizontal_distance_nm(la[i], lo[i], la[j], lo[j]) <= 10.0
        ok &= np.abs(fl[i] - fl[j]) * 100 <= 1000
        expected |= {(t, ids[a], ids[b]) for a, b in zip(i[ok], j[ok], strict=True)}
    assert len(expected) > 20 and found == expected


def test_pair_probabilities_keep_every_pair_above_eps():
    rng = np.random.default_rng(4)
    n = 80
    rows = []
    for h in (20, 60):
        sig = rng.uniform(200, 2000, n)
        rows.append(pd.DataFrame({
            "aircraft_id": np.arange(n), "time": pd.Timestamp("2024-05-01", tz="UTC"), "horizon_s": h,
            "east_m": rng.uniform(0, 150_000, n), "north_m": rng.uniform(0, 150_000, n),
            "var_east_m2": sig**2, "cov_east_north_m2": 0.3 * sig**2, "var_north_m2": (0.8 * sig) ** 2,
            "flight_level": rng.choice([330.0, 340.0, 335.0], n)}))
    pred = pd.concat(rows, ignore_index=True)
    got = pair_probabilities(pred, radius_nm=5.0, vertical_ft=1000.0, eps=1e-6)
    # the same pairs when every pair is handed in (the closing-distance pre-filter's path)
    i, j = np.triu_indices(n, 1)
    everything = pd.DataFrame({"time": pred["time"].iloc[0], "aircraft_a": j, "aircraft_b": i})  # b < a
    given = pair_probabilities(pred, radius_nm=5.0, vertical_ft=1000.0, eps=1e-6, pairs=everything)
    key = ["horizon_s", "aircraft_a", "aircraft_b"]
    pd.testing.assert_frame_equal(given.sort_values(key).reset_index(drop=True),
                                  got.sort_values(key).reset_index(drop=True))
    assert isinstance(got["time"].dtype, pd.DatetimeTZDtype)
    got = got.set_index(key)["pc"]
    for h, g in pred.groupby("horizon_s"):
        i, j = np.triu_indices(n, 1)
        e, no, fl = g["east_m"].to_numpy(), g["north_m"].to_numpy(), g["flight_level"].to_numpy()
        cov = np.stack([np.stack([g["var_east_m2"], g["cov_east_north_m2"]], -1),
                        np.stack([g["cov_east_north_m2"], g["var_north_m2"]], -1)], -2)
        pc = conflict_probability(np.column_stack([e[i] - e[j], no[i] - no[j]]), cov[i] + cov[j], 5 * 1852.0)
        pc = np.where(np.abs(fl[i] - fl[j]) * 100 < 1000, pc, 0.0)
        keep = pc > 1e-6
        assert keep.sum() > 5
        index = pd.MultiIndex.from_arrays([np.full(keep.sum(), h), i[keep], j[keep]])
        expected = pd.Series(pc[keep], index=index)
        assert got.loc[h].sort_index().to_numpy() == pytest.approx(expected.loc[h].sort_index().to_numpy())
        assert list(got.loc[h].sort_index().index) == list(expected.loc[h].sort_index().index)


def test_pair_probabilities_vertical_probability():
    base = dict(time=pd.Timestamp("2024-05-01", tz="UTC"), horizon_s=60, east_m=[0.0, 1000.0], north_m=0.0,
                var_east_m2=1e6, cov_east_north_m2=0.0, var_north_m2=1e6, flight_level=[350.0, 360.0])
    pred = pd.DataFrame({"aircraft_id": ["A", "B"], **base, "sigma_alt_ft": [300.0, 400.0]})
    got = pair_probabilities(pred, vertical_tolerance_ft=0.0)
    horizontal = conflict_probability((-1000.0, 0.0), 2e6 * np.eye(2), 5 * 1852.0)
    # altitude difference N(-1000, 500^2): P(|dz| < 1000) = Phi(4) - Phi(0)
    assert got["pc"].item() == pytest.approx(horizontal * (0.99996832875816688 - 0.5), rel=1e-9)
    # with the default 25 ft tolerance, P(|dz| < 975) = Phi(1975 / 500) - Phi(25 / 500)
    phi = [0.5 * (1.0 + math.erf(x / math.sqrt(2.0))) for x in (3.95, 0.05)]
    assert pair_probabilities(pred)["pc"].item() == pytest.approx(horizontal * (phi[0] - phi[1]), rel=1e-9)
    hard = pair_probabilities(pred.drop(columns="sigma_alt_ft"))
    assert hard.empty  # exactly 1000 ft apart: separated


def test_pair_probabilities_vertical_gate_tolerance():
    # two predictions 1 km apart: the gate passes levels closer than 1000 ft less the tolerance
    def pc_at(fl_b, **kw):
        pred = pd.DataFrame({"aircraft_id": ["A", "B"], "time": pd.Timestamp("2024-05-01", tz="UTC"),
                             "horizon_s": 60, "east_m": [0.0, 1000.0], "north_m": 0.0, "var_east_m2": 1e6,
                             "cov_east_north_m2": 0.0, "var_north_m2": 1e6, "flight_level": [350.0, fl_b]})
        return pair_probabilities(pred, **kw)["pc"].sum()

    horizontal = conflict_probability((-1000.0, 0.0), 2e6 * np.eye(2), 5 * 1852.0)
    assert pc_at(359.9) == 0.0  # 990 ft: within the 25 ft quantum of the minimum
    assert pc_at(359.9, vertical_tolerance_ft=0.0) == pytest.approx(horizontal, rel=1e-12)
    assert pc_at(359.74) == pytest.approx(horizontal, rel=1e-12)  # 974 ft
    with pytest.raises(ValueError, match="vertical_tolerance_ft"):
        pc_at(359.74, vertical_tolerance_ft=-1.0)
