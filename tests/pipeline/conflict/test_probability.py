"""Probability of conflict against references that share nothing with the code under test: the
noncentral chi-square (isotropic covariances), adaptive 2-D quadrature of the density over the disc in
polar coordinates, Monte Carlo with a stated error, and the reference rows of tracking.md 4.6."""

import numpy as np
import pytest
from scipy.stats import ncx2

from fixtures.conflict_reference import polar_reference, rotated
from msdc.pipeline.conflict import conflict_probability, pc_margin, pc_upper_bound, probability

# mean, covariance, radius: isotropic and anisotropic, on and off the axes, covariance small and large
# against the zone, mean inside, on the edge and outside
CASES = [
    ((0.0, 2.0), rotated(1.0, 1.0, 0.0), 2.0),
    ((1.5, 2.0), rotated(0.3, 0.3, 0.0), 2.0),
    ((3.0, 0.0), rotated(2.0, 0.5, 0.0), 2.0),
    ((0.0, 3.0), rotated(2.0, 0.5, 0.0), 2.0),
    ((1.2, -1.7), rotated(1.0, 0.2, 0.7), 2.0),
    ((-0.4, 0.3), rotated(0.05, 0.01, 2.1), 1.0),
    ((0.7, 0.72), rotated(0.03, 0.03, 0.0), 1.0),
    ((4.0, 4.0), rotated(3.0, 1.0, -0.4), 5.0),
    ((10.0, -3.0), rotated(40.0, 15.0, 1.0), 5.0),
    ((0.0, 0.0), rotated(100.0, 1.0, 0.3), 5.0),
    ((1.01, 0.0), rotated(1e-2, 1e-4, 0.3), 1.0),
    ((-2.0, 1.0), rotated(1.0, 1e-3, 1.2), 2.0),
]


@pytest.fixture(scope="module")
def references():
    return np.array([polar_reference(m, p, d) for m, p, d in CASES])


def batch():
    m = np.array([c[0] for c in CASES])
    p = np.array([c[1] for c in CASES])
    d = np.array([c[2] for c in CASES])
    return m, p, d


def test_reference_rows_of_tracking_md_4_6():
    # tracking.md 4.6: d = 2 NM, m = (0, 2) NM, relative covariance I and 0.1 I
    rows = {1.0: [0.3965, 0.4772, 0.4485, 0.4281, 0.4141, 0.4058, 0.3963],
            0.1: [0.4684, 0.5000, 0.4995, 0.4906, 0.4828, 0.4768, 0.4667]}
    for s, expected in rows.items():
        p = s * np.eye(2)
        got = [conflict_probability((0, 2), p, 2.0), conflict_probability((0, 2), p, 2.0, "one-block")]
        got += [conflict_probability((0, 2), p, 2.0, "blocks", n=n) for n in (4, 8, 16, 32)]
        got += [conflict_probability((0, 2), p, 2.0, "midpoint", n=16)]
        assert np.round(got, 4).tolist() == expected


def test_exact_matches_noncentral_chi_square_for_isotropic_covariances():
    # |r|^2 / s is noncentral chi-square with 2 degrees of freedom and noncentrality |m|^2 / s
    rng = np.random.default_rng(11)
    k = 4000
    s = 10 ** rng.uniform(-5, 3, k)
    d = 10 ** rng.uniform(-1, 1, k)
    angle = rng.uniform(0, 2 * np.pi, k)
    r = d * rng.uniform(0, 1.5, k) + np.sqrt(s) * rng.normal(size=k)
    m = np.column_stack([r * np.cos(angle), r * np.sin(angle)])
    truth = ncx2.cdf(d**2 / s, 2, (m**2).sum(1) / s)
    got = conflict_probability(m, s[:, None, None] * np.eye(2), d)
    assert np.max(np.abs(got - truth)) < 1e-9
    # one block and covering strips never fall below the truth
    assert np.all(conflict_probability(m, s[:, None, None] * np.eye(2), d, "one-block") >= truth - 1e-12)
    assert np.all(conflict_probability(m, s[:, None, None] * np.eye(2), d, "blocks", n=5) >= truth - 1e-12)


def test_exact_matches_adaptive_quadrature(references):
    m, p, d = batch()
    got = conflict_probability(m, p, d)
    assert np.max(np.abs(got - references)) < 1e-8
    assert references.min() < 1e-3 and references.max() > 0.9  # the cases span the range of PC


def test_exact_in_blocks_of_a_few_pairs_equals_one_pass_bit_for_bit(references, monkeypatch):
    """The quadrature is evaluated a few thousand pairs at a time to bound its memory, with the graded
    levels of the whole call: with blocks of 1 and 3 pairs every PC is the one of a single pass, bit for
    bit (computed alone, with its own levels, some pairs differ in the last digits: what the blocks must
    not do), and the reference cases stay within 1e-8 of the reference quadrature."""
    rng = np.random.default_rng(3)
    k = 60
    sig1 = rng.uniform(10, 3000, k)
    cov = np.array([rotated(a, a * 10 ** rng.uniform(-4, 0), rng.uniform(0, np.pi)) for a in sig1])
    mean = rng.normal(0, 8000, (k, 2))
    whole = conflict_probability(mean, cov, 9260.0)
    alone = np.array([conflict_probability(mean[i], cov[i], 9260.0) for i in range(k)])
    assert (alone != whole).any() and np.abs(alone - whole).max() < 1e-9
    m, p, d = batch()
    for nodes in (1, 3 * 200):  # a pair takes at least (4 + 5) x 10 nodes: blocks of 1 and 3 pairs
        monkeypatch.setattr(probability, "_EXACT_NODES", nodes)
        assert conflict_probability(mean, cov, 9260.0).tobytes() == whole.tobytes()
        assert np.max(np.abs(conflict_probability(m, p, d) - references)) < 1e-8


def test_blocks_bound_and_converge_from_above(references):
    m, p, d = batch()
    one = conflict_probability(m, p, d, "one-block")
    assert np.all(one >= references - 1e-10)
    previous, excess = one, {}
    for n in (2, 4, 8, 16, 32, 64, 128, 256, 512):
        blocks = conflict_probability(m, p, d, "blocks", n=n)
        assert np.all(blocks >= references - 1e-10)
        assert np.all(blocks <= previous + 1e-12)  # halving every strip can only shrink the cover
        previous, excess[n] = blocks, blocks - references
    # first-order convergence: the excess shrinks about as 1/n (slowly for the needles, cases 6 and 10)
    assert np.all(excess[512] <= 0.1 * excess[8] + 1e-9)
    moderate = [0, 1, 2, 3, 4, 7, 8, 9]
    assert np.max(excess[128][moderate]) < 0.005
    # the midpoint strips are not a bound but converge much faster
    midpoint = conflict_probability(m, p, d, "midpoint", n=128)
    assert np.max(np.abs(midpoint - references)[moderate]) < 3e-4


def test_extreme_anisotropy_against_monte_carlo():
    # a needle 1e-4 wide across the edge of the disc; 4e6 samples: standard error below 2.5e-4
    rng = np.random.default_rng(5)
    m, p = np.array([0.0, 1.0]), rotated(1.0, 1e-4, 0.3)
    z = rng.standard_normal((4_000_000, 2)) @ np.linalg.cholesky(p).T + m
    hits = ((z**2).sum(1) <= 1.0).mean()
    stderr = np.sqrt(hits * (1 - hits) / len(z))
    assert abs(conflict_probability(m, p, 1.0) - hits) < 4 * stderr


def test_paper_one_block_overestimates_most_with_the_small_covariance():
    # scenario 2 of Baek & Bang: the relative position passes at exactly d = 2 NM lateral clearance
    x = np.linspace(-6, 6, 121)
    m = np.column_stack([x, np.full_like(x, 2.0)])
    excess = {}
    for s in (1.0, 0.1):
        p = s * np.eye(2)
        truth = ncx2.cdf(4.0 / s, 2, (m**2).sum(1) / s)
        one = conflict_probability(m, p, 2.0, "one-block")
        blocks = conflict_probability(m, p, 2.0, "blocks", n=16)
        assert np.all(one >= truth - 1e-12) and np.all(blocks <= one + 1e-12)
        excess[s] = (one - truth).max()
    assert excess[0.1] > 3 * excess[1.0]  # 0.42 against 0.11 near the corners of the block


def test_broadcasting_shapes_and_scalars():
    p = rotated(1.0, 0.5, 0.3)
    one = conflict_probability((0.5, 0.5), p, 1.0)
    assert isinstance(one, float)
    many = conflict_probability(np.tile([0.5, 0.5], (3, 1)), p, [1.0, 1.0, 1.0])
    assert many.shape == (3,) and np.allclose(many, one)
    grid = conflict_probability(np.zeros((2, 3, 2)), np.broadcast_to(p, (2, 3, 2, 2)), 1.0, "one-block")
    assert grid.shape == (2, 3)
    assert conflict_probability((0, 0), p, 0.0) == 0.0


def test_upper_bound_and_margin_hold():
    rng = np.random.default_rng(3)
    m = rng.normal(size=(500, 2)) * 5
    p = np.array([rotated(s, s * r, a) for s, r, a in zip(rng.uniform(0.2, 2, 500), rng.uniform(0.1, 1, 500),
                                                          rng.uniform(0, 3, 500), strict=True)])
    truth = np.array([polar_reference(mi, pi, 1.0) for mi, pi in zip(m[:15], p[:15], strict=True)])
    assert np.all(pc_upper_bound(m[:15], p[:15], 1.0) >= truth - 1e-12)
    sigma_max = np.sqrt(np.linalg.eigvalsh(p)[:, -1])
    far = np.hypot(m[:, 0], m[:, 1]) > 1.0 + pc_margin(sigma_max, 1e-6)
    assert far.any() and np.all(conflict_probability(m[far], p[far], 1.0) <= 1e-6)


@pytest.mark.parametrize("kwargs, match", [
    (dict(mean=(0, 0), cov=[[1, 2], [2, 1]], radius=1), r"cov: not positive definite at pair 0"),
    (dict(mean=(0, 0), cov=[[1, 0], [0, 0]], radius=1), r"cov: not positive definite"),
    (dict(mean=(0, 0), cov=[[1, 0.5], [0.2, 1]], radius=1), r"cov: not symmetric"),
    (dict(mean=(0, 0), cov=np.eye(2), radius=-1), r"radius: must not be negative, got -1.0"),
    (dict(mean=(0, 0, 0), cov=np.eye(2), radius=1), r"mean: expected shape \(\.\.\., 2\)"),
    (dict(mean=np.zeros((3, 2)), cov=np.zeros((4, 2, 2)) + np.eye(2), radius=1), r"do not broadcast"),
    (dict(mean=(0, np.nan), cov=np.eye(2), radius=1), r"mean: not finite at pair 0"),
    (dict(mean=(0, 0), cov=np.eye(2), radius=1, method="two-block"), r"method: unknown method 'two-block'"),
    (dict(mean=(0, 0), cov=np.eye(2), radius=1, method="blocks", n=0), r"n: .* positive integer, got 0"),
    (dict(mean=(0, 0), cov=np.eye(2), radius=1, method="exact", n=8), r"n: only the 'blocks'"),
])
def test_bad_input_is_named(kwargs, match):
    with pytest.raises(ValueError, match=match):
        conflict_probability(**kwargs)


@pytest.mark.parametrize("method", ["exact", "one-block", "blocks", "midpoint"])
def test_no_pairs_give_an_empty_result(method):
    assert conflict_probability(np.zeros((0, 2)), np.zeros((0, 2, 2)), 1.0, method=method).shape == (0,)
    assert conflict_probability(np.zeros((0, 3, 2)), np.eye(2), 1.0, method=method).shape == (0, 3)
    assert pc_upper_bound(np.zeros((0, 2)), np.zeros((0, 2, 2)), 1.0).shape == (0,)


def test_pc_margin_refuses_a_negative_sigma():
    with pytest.raises(ValueError, match=r"sigma_max: .* must not be negative, got -1.0"):
        pc_margin(-1.0)
    with pytest.raises(ValueError, match=r"sigma_max: .* got -2.0"):
        pc_margin([3.0, -2.0])
    assert pc_margin(0.0) == 0.0
