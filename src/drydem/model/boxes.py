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
    pairs = _sort_and_sweep(np.ascontiguousarray(lower), np.ascontiguousarray(upper), np.ascontiguousarray(movable), float(margin))
    return pairs[np.lexsort((pairs[:, 1], pairs[:, 0]))]


@numba.njit(cache=True)
def _sort_and_sweep(lo, hi, movable, margin):
    """Pairs (i < j) whose boxes grown by ``margin`` overlap, at least one movable: sort and
    sweep along x (Baraff 1992; Cohen et al. 1995, I-COLLIDE), then y and z."""
    order = np.argsort(lo[:, 0], kind="mergesort")
    found = []
    for a in range(order.shape[0]):
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
    pairs = np.empty((len(found), 2), np.int64)
    for k in range(len(found)):
        pairs[k, 0], pairs[k, 1] = found[k]
    return pairs


compiled_cache.check(__name__)  # last: none of the functions above is loaded from a stale cache
