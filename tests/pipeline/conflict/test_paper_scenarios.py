"""tracking.md 4.4 with IMM prediction: the numpy IMM of fixtures/paper_imm.py predicts as msdc's kernel does
(so the heading-aligned CA noise it adds is compared like for like), and what proved robust in
benchmarks/conflict_paper_scenarios.py: scenario 2's one block over-estimating most with the small
covariance and CV prediction erring least on straight flight; scenario 1's CV over-estimating in the
turn more than the IMM."""

from __future__ import annotations

import numpy as np
import pytest

from fixtures import paper_imm
from fixtures.paper_imm import PaperMode
from fixtures.paper_scenarios import scenario1, scenario2, standard
from msdc.pipeline.conflict.predict import propagate_state
from msdc.pipeline.track import ImmState, Mode, Plane, TrackerConfig


def test_numpy_imm_prediction_equals_the_kernel_from_the_same_posterior():
    rng = np.random.default_rng(5)
    modes = (PaperMode("cv", 0.5), PaperMode("ca", 1.0))
    mu = np.array([0.7, 0.3])
    x = np.array([[100.0, 200.0, 0.0, -50.0, 30.0, 0.0], [110.0, 195.0, 1.5, -45.0, 35.0, 2.0]])
    a = rng.normal(size=(2, 6, 6))
    P = a @ np.swapaxes(a, 1, 2) * 50.0 + np.eye(6) * 10.0
    P[0, 2, :] = P[0, :, 2] = 0.0  # CV carries no acceleration
    cfg = TrackerConfig(modes=(Mode("cv", "cv", 0.5), Mode("ca", "ca", 1.0)), tpm="fixed:0.9")
    state = ImmState("A", None, Plane(0.0, 0.0), cfg, mu, x, P)
    means, covs = propagate_state(state, [20.0, 60.0], 1.0)
    PI = paper_imm.tpm_fixed(0.9, 2)
    for k, h in enumerate((20.0, 60.0)):
        m, c = paper_imm.propagate(modes, PI, mu, x, P, h)
        np.testing.assert_allclose(m, means[k], rtol=1e-10, atol=1e-8)
        np.testing.assert_allclose(c, covs[k], rtol=1e-9, atol=1e-6)


def test_heading_aligned_ca_noise_by_hand():
    # heading north-east: along u = (1, 1)/sqrt 2, across c = (-1, 1)/sqrt 2; sigma_along 2, across 1:
    # Sigma = 4 u u^T + c c^T = [[2.5, 1.5], [1.5, 2.5]]; Q = Sigma (x) g g^T with g = [1/2, 1, 1] for T = 1
    F, Q = paper_imm.transition(PaperMode("ca", 2.0, 1.0), 1.0, (100.0, 100.0))
    g = np.array([0.5, 1.0, 1.0])
    np.testing.assert_allclose(Q[:3, :3], 2.5 * np.outer(g, g))
    np.testing.assert_allclose(Q[:3, 3:], 1.5 * np.outer(g, g))
    np.testing.assert_allclose(Q[3:, 3:], 2.5 * np.outer(g, g))
    np.testing.assert_allclose(F[0], [1.0, 1.0, 0.5, 0.0, 0.0, 0.0])


@pytest.fixture(scope="module")
def s2():
    return {nav: scenario2(standard(), 450.0, 350.0, nav, seed=0) for nav in (1.0, 0.1)}


def test_scenario2_truth_peak_is_the_reference_table(s2):
    # closest approach: relative mean (0, 2) NM, radius 2 NM: tracking.md 4.6 gives 0.3965 and 0.4684
    assert s2[1.0]["truth"]["peak_pc"] == pytest.approx(0.3965, abs=1e-4)
    assert s2[0.1]["truth"]["peak_pc"] == pytest.approx(0.4684, abs=1e-4)


def test_scenario2_one_block_over_estimates_most_with_the_small_covariance(s2):
    for name in ("cv", "ca", "imm"):
        big, small = s2[1.0][name], s2[0.1][name]
        assert big["one_block_excess_max"] > 0.05 and small["one_block_excess_max"] > 0.05
        assert small["one_block_excess_max"] > 2.0 * big["one_block_excess_max"]
        # covering blocks converge from above: 16 of them err far less than one
        assert 0.0 <= small["n16_excess_max"] < 0.5 * small["one_block_excess_max"]


def test_scenario2_straight_flight_cv_errs_least_ca_most(s2):
    # no manoeuvre: every mode beyond CV only adds spread (the benchmark: mae 0.002 / 0.006 / 0.03 at I)
    for nav in (1.0, 0.1):
        r = s2[nav]
        assert r["cv"]["mae"] < r["imm"]["mae"] < r["ca"]["mae"]


def test_scenario1_cv_over_estimates_in_the_turn_more_than_the_imm():
    # 250 kt, the benchmark's settings: turn bias CV 0.085 > IMM 0.041 > 0 over 5 seeds; CA-only stays
    # positive too (0.023): the paper's CA under-estimate did not appear with any setting tried
    r = scenario1(standard(), 250.0, seed=1)
    assert r["cv"]["turn_bias"] > 1.5 * r["imm"]["turn_bias"] > 0.0
    assert r["cv"]["bias"] > r["imm"]["bias"] > 0.0
    assert r["ca"]["turn_bias"] > 0.0


def test_scenario1_paper_ordering_appears_with_a_large_ca_noise():
    # Reading the paper's 52-72 s as the predictions' target times (its plot is shifted +20 s): with CA
    # jerk noise 10 m/s^3 the CA-only predicted covariance is about 5 km wide at 20 s and spreads PC
    # out of the 2 NM disc: CA under-estimates, the IMM over-estimates less than CV (benchmark, 5 seeds
    # at 420 kt: CV +0.074, IMM +0.043, CA -0.120). With CA at 1 m/s^3 CA over-estimates (+0.04).
    big = scenario1(standard(sigma_ca=10.0), 420.0, seed=1)
    bias = {k: big[k]["target_turn_bias"] for k in ("cv", "imm", "ca")}
    assert bias["cv"] > bias["imm"] > 0.0 > -0.05 > bias["ca"]
    small = scenario1(standard(sigma_ca=1.0)[1:2], 420.0, seed=1)
    assert small["ca"]["target_turn_bias"] > 0.0
