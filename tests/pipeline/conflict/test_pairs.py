"""Pair pre-filter against brute force over every pair, and the separation geometry against closed forms."""

import math

import numpy as np
import pandas as pd
import pytest

from msdc.pipeline.conflict import (
    candidate_pairs,
    closing_margin_m,
    conflict_probability,
    horizontal_distance_nm,
    pair_probabilities,
    pairs_pc,
    pairs_per_step,
    pc_upper_bound,
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
    for rows in (1, 70):  # a time per chunk, chunks of a few whole times: the same pairs in the same order
        pd.testing.assert_frame_equal(pairs_per_step(tracks, 10.0, 1000.0, chunk_rows=rows), got)


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


def crowded_predictions(rng, sigma_alt=False):
    """25 aircraft at 4 times and 2 horizons within 60 km: several close pairs in every (horizon, time),
    some rows without a position, covariances from 50 m to 3 km."""
    rows = []
    t0 = pd.Timestamp("2024-05-01 10:00", tz="UTC")
    for h in (60.0, 20.0):  # not in sorted order
        for k in (3, 0, 2, 1):
            n = 25
            sig, ratio = rng.uniform(50, 3000, n), rng.uniform(0.2, 1.0, n)
            frame = pd.DataFrame({
                "aircraft_id": [f"AC{i:02d}" for i in rng.permutation(n)],
                "time": t0 + pd.Timedelta(seconds=k), "horizon_s": h,
                "east_m": rng.uniform(0, 60_000, n), "north_m": rng.uniform(0, 60_000, n),
                "var_east_m2": sig**2, "cov_east_north_m2": rng.uniform(-0.9, 0.9, n) * ratio * sig**2,
                "var_north_m2": (ratio * sig) ** 2,
                "flight_level": rng.choice([330.0, 335.0, 340.0, 339.8], n)})
            frame.loc[rng.integers(0, n), "east_m"] = np.nan
            if sigma_alt:
                frame["sigma_alt_ft"] = rng.uniform(20, 400, n)
            rows.append(frame)
    return pd.concat(rows, ignore_index=True)


def reference_pair_probabilities(pred, radius_nm=5.0, vertical_ft=975.0, eps=1e-6):
    """The method written out: per (horizon, time), candidate_pairs within the radius widened by the PC
    margin of twice the largest variance (vertically by that of sqrt(2) times the largest sigma), the
    bound, then the exact PC of all the pairs the bound leaves in one call."""
    frame = pred.sort_values(["horizon_s", "time", "aircraft_id"], kind="stable").reset_index(drop=True)
    wide = math.sqrt(2.0 * math.log(1.0 / eps))
    cov = np.stack([np.stack([frame["var_east_m2"], frame["cov_east_north_m2"]], -1),
                    np.stack([frame["cov_east_north_m2"], frame["var_north_m2"]], -1)], -2)
    pos, alt = frame[["east_m", "north_m"]].to_numpy(), frame["flight_level"].to_numpy() * 100.0
    pairs = []
    for _, g in frame.groupby(["horizon_s", "time"], sort=True):
        lam = np.linalg.eigvalsh(cov[g.index]).max()
        v = vertical_ft + (wide * math.sqrt(2.0) * g["sigma_alt_ft"].max() if "sigma_alt_ft" in g else 0.0)
        r = radius_nm * 1852.0 + wide * math.sqrt(2.0 * lam)
        found = candidate_pairs(pos[g.index], alt[g.index], r, v)
        pairs.append(found + g.index[0])
    i, j = np.concatenate(pairs).T
    rel, rel_cov, dz = pos[i] - pos[j], cov[i] + cov[j], alt[i] - alt[j]
    if "sigma_alt_ft" in frame:
        s = np.hypot(frame["sigma_alt_ft"].to_numpy()[i], frame["sigma_alt_ft"].to_numpy()[j])
        vertical = np.array([0.5 * (math.erf((vertical_ft - z) / (q * math.sqrt(2.0)))
                                    - math.erf((-vertical_ft - z) / (q * math.sqrt(2.0))))
                             for z, q in zip(dz, s, strict=True)])
    else:
        vertical = (np.abs(dz) < vertical_ft).astype(float)
    todo = pc_upper_bound(rel, rel_cov, radius_nm * 1852.0) * vertical > eps
    pc = np.zeros(len(i))
    pc[todo] = conflict_probability(rel[todo], rel_cov[todo], radius_nm * 1852.0) * vertical[todo]
    ids = frame["aircraft_id"].to_numpy()
    out = pd.DataFrame({"time": frame["time"].array.take(i), "aircraft_a": ids[i], "aircraft_b": ids[j],
                        "horizon_s": frame["horizon_s"].to_numpy()[i], "pc": pc,
                        "horizontal_nm": np.hypot(rel[:, 0], rel[:, 1]) / 1852.0, "vertical_ft": np.abs(dz)})
    return out[pc > eps].reset_index(drop=True), len(i), int(todo.sum())


@pytest.mark.parametrize("sigma_alt", [False, True])
def test_pair_probabilities_in_chunks_equal_the_method_in_one_pass(sigma_alt, monkeypatch):
    """Chunks of 1 row (one (horizon, time) group each), 60 rows (groups of 25 rows cut at group edges)
    and all rows give the PC of every pair of the method done in one pass, the same rows in the same
    order (bit for bit with the gate; to 1e-12 with the vertical sigma); with exact-PC batches of 7
    pairs (the pairs of one chunk spread over several batches, a batch over several chunks) the chunks
    still agree with each other bit for bit and the reference to 1e-9."""
    pred = crowded_predictions(np.random.default_rng(11), sigma_alt)
    expected, n_pairs, n_todo = reference_pair_probabilities(pred)
    assert n_pairs > 40 and n_todo > 20 and len(expected) > 10 and (expected["pc"] < 0.5).any()
    got = {rows: pair_probabilities(pred, chunk_rows=rows) for rows in (1, 60, len(pred))}
    for frame in got.values():
        pd.testing.assert_frame_equal(frame.drop(columns="pc"), expected.drop(columns="pc"), check_exact=True)
        if sigma_alt:  # the reference's vertical factor from math.erf, the code's from scipy's ndtr
            assert frame["pc"].to_numpy() == pytest.approx(expected["pc"].to_numpy(), rel=1e-12, abs=0)
        else:
            assert frame["pc"].to_numpy().tobytes() == expected["pc"].to_numpy().tobytes()
    monkeypatch.setattr(pairs_pc, "_CHUNK", 7)
    small = {rows: pair_probabilities(pred, chunk_rows=rows) for rows in (1, 60, len(pred))}
    for frame in small.values():
        pd.testing.assert_frame_equal(frame, small[1], check_exact=True)
        assert frame["pc"].to_numpy() == pytest.approx(expected["pc"].to_numpy(), rel=1e-9, abs=1e-12)


def test_pair_probabilities_given_pairs_in_chunks_and_a_nan_variance():
    pred = crowded_predictions(np.random.default_rng(12))
    pred = pred[np.isfinite(pred["east_m"])]  # a given pair without a position is refused, not skipped
    i, j = np.triu_indices(25, 1)
    ids = np.array([f"AC{k:02d}" for k in range(25)])
    everything = pd.concat([pd.DataFrame({"time": t, "aircraft_a": ids[j], "aircraft_b": ids[i]})
                            for t in pred["time"].unique()], ignore_index=True)
    whole = pair_probabilities(pred, pairs=everything, chunk_rows=10**9)
    assert len(whole) > 10
    for rows in (1, 13):
        pd.testing.assert_frame_equal(pair_probabilities(pred, pairs=everything, chunk_rows=rows), whole,
                                      check_exact=True)
    bad = pred.copy()
    bad.loc[30, "var_north_m2"] = np.nan  # a group's margin is then not a distance: refused as before
    with pytest.raises(ValueError, match="radius_m: must be a finite non-negative distance, got nan"):
        pair_probabilities(bad, chunk_rows=1)


def test_closing_margin_refuses_negative_speed_or_horizon():
    with pytest.raises(ValueError, match=r"max_speed_kt: must be finite and not negative, got -500"):
        closing_margin_m(-500, 60)
    with pytest.raises(ValueError, match=r"horizon_s: must be finite and not negative, got -60"):
        closing_margin_m(500, -60)
    assert closing_margin_m(500, 0) == 0.0


def _two_predictions(east_b_m: float) -> pd.DataFrame:
    return pd.DataFrame({"aircraft_id": ["A", "B"], "time": pd.Timestamp("2024-05-01", tz="UTC"),
                         "horizon_s": 60, "east_m": [0.0, east_b_m], "north_m": 0.0, "var_east_m2": 1e4,
                         "cov_east_north_m2": 0.0, "var_north_m2": 1e4, "flight_level": 350.0})


@pytest.mark.parametrize("radius", [0, 0.0, -5.0, float("nan"), "5"])
def test_pair_probabilities_refuse_a_radius_that_is_not_positive(radius):
    error, words = ((TypeError, "must be a number of NM, not str") if isinstance(radius, str)
                    else (ValueError, "must be a finite number of NM > 0"))
    with pytest.raises(error, match=rf"radius_nm {radius!r}: {words}"):
        pair_probabilities(_two_predictions(1000.0), radius_nm=radius)


def test_pair_probabilities_given_pairs_all_ruled_out_give_an_empty_frame():
    # B 100 km from A with 100 m sigmas: the bound leaves nothing to compute exactly
    pairs = pd.DataFrame({"time": [pd.Timestamp("2024-05-01", tz="UTC")], "aircraft_a": ["A"],
                          "aircraft_b": ["B"]})
    got = pair_probabilities(_two_predictions(100_000.0), pairs=pairs)
    assert got.empty and list(got.columns) == list(pairs_pc.PC_COLUMNS)


def test_pair_probabilities_gaussian_vertical_with_an_aircraft_without_level():
    # an aircraft with no level (and so no level sigma) at the same time is never paired, and does not
    # stop the others' PC (it made the group's vertical limit NaN: "vertical_ft: ... got nan")
    base = dict(time=pd.Timestamp("2024-05-01", tz="UTC"), horizon_s=60, north_m=0.0, var_east_m2=1e6,
                cov_east_north_m2=0.0, var_north_m2=1e6)
    pred = pd.DataFrame({"aircraft_id": ["A", "B", "C"], **base, "east_m": [0.0, 1000.0, 500.0],
                         "flight_level": [350.0, 360.0, np.nan], "sigma_alt_ft": [300.0, 400.0, np.nan]})
    got = pair_probabilities(pred, vertical_tolerance_ft=0.0)
    horizontal = conflict_probability((-1000.0, 0.0), 2e6 * np.eye(2), 5 * 1852.0)
    # altitude difference N(-1000, 500^2): P(|dz| < 1000) = Phi(4) - Phi(0)
    assert got[["aircraft_a", "aircraft_b"]].values.tolist() == [["A", "B"]]
    assert got["pc"].item() == pytest.approx(horizontal * (0.99996832875816688 - 0.5), rel=1e-9)
    with pytest.raises(ValueError, match=r"predictions: sigma_alt_ft nan at a flight level \(aircraft 'B'"):
        pair_probabilities(pred.assign(sigma_alt_ft=[300.0, np.nan, np.nan]))
