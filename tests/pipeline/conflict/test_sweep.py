"""The sort-and-sweep box pair search against every pair of every group tested one by one."""

import numpy as np

from msdc.pipeline.conflict.sweep import grouped_box_pairs


def brute_box_pairs(coords, edges, half_width):
    out = set()
    for g in range(len(edges) - 1):
        for i in range(edges[g], edges[g + 1]):
            for j in range(i + 1, edges[g + 1]):
                if np.all(np.abs(coords[i] - coords[j]) <= half_width[g]):
                    out.add((i, j))
    return out


def test_grouped_box_pairs_equal_brute_force():
    rng = np.random.default_rng(5)
    sizes = [0, 1, 2, 7, 40, 0, 33, 3]
    edges = np.r_[0, np.cumsum(sizes)]
    # whole numbers: many differences fall exactly on the box's edge, which counts; ties along the sweep axis
    coords = rng.integers(0, 6, (edges[-1], 3)).astype(float)
    half_width = rng.integers(0, 4, (len(sizes), 3)).astype(float)
    got = grouped_box_pairs(coords, edges, half_width)
    expected = brute_box_pairs(coords, edges, half_width)
    assert len(expected) > 80
    assert got.dtype == np.int64 and np.all(got[:, 0] < got[:, 1])
    assert {tuple(map(int, p)) for p in got} == expected and len(got) == len(expected)


def test_grouped_box_pairs_more_than_first_room():
    # every pair of one group of 200 inside the box: 19,900 pairs, more than the first buffer holds
    coords = np.zeros((200, 2))
    got = grouped_box_pairs(coords, np.array([0, 200]), np.array([[1.0, 1.0]]))
    assert {tuple(map(int, p)) for p in got} == {(i, j) for i in range(200) for j in range(i + 1, 200)}
    assert grouped_box_pairs(np.empty((0, 2)), np.array([0]), np.empty((0, 2))).shape == (0, 2)
