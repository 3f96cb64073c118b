"""Pairs of points within a box, group by group, by sort and sweep (one numba pass over all groups).

The points of each group are sorted along the first coordinate; each point is compared with the points
after it until the first coordinate differs by more than the box's half-width, and a pair is kept when
every coordinate differs by at most the group's half-width. Few points per group (a time's aircraft) and
many groups (every time of a day) cost one kernel call instead of one k-d tree per group. Callers apply
their exact test to the pairs found: the box must hold every pair that test wants.
"""

from __future__ import annotations

import numpy as np
from numba import njit


def grouped_box_pairs(coords: np.ndarray, edges: np.ndarray, half_width: np.ndarray) -> np.ndarray:
    """Index pairs (i, j), i < j, of rows of coords (n, d) in the same group [edges[g], edges[g + 1])
    whose coordinates all differ by at most half_width[g] (G, d); unordered. Coordinates must be finite."""
    coords = np.asarray(coords, dtype=float)
    edges = np.ascontiguousarray(edges, dtype=np.int64)
    half_width = np.ascontiguousarray(half_width, dtype=float)
    if len(edges) < 2 or not len(coords):
        return np.empty((0, 2), dtype=np.int64)
    group = np.repeat(np.arange(len(edges) - 1), np.diff(edges))
    order = np.lexsort((coords[:, 0], group))  # by group, then along the first coordinate
    ordered = np.ascontiguousarray(coords[order])
    found = np.empty((len(coords) + 1024, 2), dtype=np.int64)  # room for most calls' pairs
    count = _sweep(ordered, order, edges, half_width, found)
    if count > len(found):  # counted but not all written: again with room for them all
        found = np.empty((count, 2), dtype=np.int64)
        _sweep(ordered, order, edges, half_width, found)
    return found[:count]


@njit(cache=True)
def _sweep(coords, order, edges, half_width, out):
    """Number of box pairs of the sorted coords, the first len(out) of them written into out as rows of
    the unsorted ones (coords[k] is row order[k]), the smaller first."""
    room = out.shape[0]
    n_dim = coords.shape[1]
    k = 0
    for g in range(len(edges) - 1):
        w0 = half_width[g, 0]
        for i in range(edges[g], edges[g + 1]):
            for j in range(i + 1, edges[g + 1]):
                if coords[j, 0] - coords[i, 0] > w0:
                    break
                inside = True
                for d in range(1, n_dim):
                    if abs(coords[j, d] - coords[i, d]) > half_width[g, d]:
                        inside = False
                        break
                if inside:
                    if k < room:
                        out[k, 0] = min(order[i], order[j])
                        out[k, 1] = max(order[i], order[j])
                    k += 1
    return k
