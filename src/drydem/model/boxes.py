"""Axis-aligned bounding boxes of blocks and which of them overlap (sort and sweep).

The model checks its blocks for initial overlaps with them, and the engine's broad phase
(:func:`drydem.engine.broad_phase.broad_phase`) finds its candidate pairs with them.
"""

from __future__ import annotations

import numba
import numpy as np

from drydem import compiled_cache
from drydem.model.geometry import ConvexPolyhedron


def bounds(polyhedra: list[ConvexPolyhedron]) -> tuple[np.ndarray, np.ndarray]:
    """(n, 3) lower and upper corners of the blocks' axis-aligned bounding boxes, m."""
    return np.array([p.vertices.min(0) for p in polyhedra]), np.array([p.vertices.max(0) for p in polyhedra])


def overlapping_pairs(lower: np.ndarray, upper: np.ndarray, movable: np.ndarray, margin: float) -> np.ndarray:
    """Pairs (i < j), sorted, whose bounding boxes ``lower``/``upper`` (n, 3) m, grown by
    ``margin`` m, overlap; pairs of two immovable blocks are left out (compiled sort and sweep)."""
    (pairs,) = pair_chunks(lower, upper, movable, margin, np.iinfo(np.int64).max)
    return pairs


def pair_chunks(lower: np.ndarray, upper: np.ndarray, movable: np.ndarray, margin: float, most: int):
    """The pairs of :func:`overlapping_pairs` in chunks, each sorted: the pairs of the next
    blocks in the sweep's order (along x) until a chunk holds ``most`` (at least 1) or more. A
    caller that stops early never holds them all: 30,000 coincident cubes make 450 million pairs (7 GB)."""
    most = max(int(most), 1)  # a chunk of no pair would never move on
    lo, hi = np.ascontiguousarray(lower, dtype=np.float64), np.ascontiguousarray(upper, dtype=np.float64)
    movable, order, start = np.ascontiguousarray(movable), np.argsort(lo[:, 0], kind="stable"), 0
    while True:
        pairs, start = _sort_and_sweep(lo, hi, movable, float(margin), order, start, most)
        yield pairs[np.lexsort((pairs[:, 1], pairs[:, 0]))]
        if start >= len(order):
            return


@numba.njit(cache=True)
def _sort_and_sweep(lo, hi, movable, margin, order, start, most):
    """Pairs (i < j) whose boxes grown by ``margin`` overlap, at least one movable, of the blocks
    ``order[start:]`` (sorted by their lower x) up to the first whose pairs make the count reach
    ``most``; and where the next chunk starts. Sort and sweep along x (Baraff 1992; Cohen et al.
    1995, I-COLLIDE), then y and z."""
    found = []
    a = start
    while a < order.shape[0] and len(found) < most:
        i = order[a]
        for c in range(a + 1, order.shape[0]):
            j = order[c]
            if lo[j, 0] - margin > hi[i, 0] + margin:
                break
            if not (movable[i] or movable[j]):
                continue
            if lo[j, 1] - margin <= hi[i, 1] + margin and hi[j, 1] + margin >= lo[i, 1] - margin and \
                    lo[j, 2] - margin <= hi[i, 2] + margin and hi[j, 2] + margin >= lo[i, 2] - margin:
                found.append((min(i, j), max(i, j)))
        a += 1
    pairs = np.empty((len(found), 2), np.int64)
    for k in range(len(found)):
        pairs[k, 0], pairs[k, 1] = found[k]
    return pairs, a


compiled_cache.check(__name__)  # last: none of the functions above is loaded from a stale cache
