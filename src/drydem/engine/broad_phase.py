"""The broad phase: candidate block pairs whose bounding boxes, at the current state, are close."""

from __future__ import annotations

import numba
import numpy as np

from drydem import compiled_cache
from drydem.model.boxes import overlapping_pairs
from drydem.model.geometry import FlatGeometry


def broad_phase(geometry: FlatGeometry, position: np.ndarray, rotation: np.ndarray, movable: np.ndarray, margin: float) -> np.ndarray:
    """Candidate pairs (i < j), sorted, of blocks at centroids ``position`` (nb, 3) m and
    rotations (nb, 3, 3) whose world bounding boxes, grown by ``margin`` m, overlap; pairs of two
    immovable blocks are left out."""
    lower, upper = bounding_boxes(geometry, position, rotation)
    return overlapping_pairs(lower, upper, movable, margin)


@numba.njit(cache=True)
def bounding_boxes(geom, position, rotation):
    """(nb, 3) lower and upper corners of every block's axis-aligned bounding box, world, m."""
    nb = position.shape[0]
    lo = np.full((nb, 3), np.inf)
    hi = np.full((nb, 3), -np.inf)
    for b in range(nb):
        r, x = rotation[b], position[b]
        for i in range(geom.vertex_start[b], geom.vertex_start[b + 1]):
            p = geom.vertex[i]
            for k in range(3):
                w = x[k] + r[k, 0] * p[0] + r[k, 1] * p[1] + r[k, 2] * p[2]
                lo[b, k] = min(lo[b, k], w)
                hi[b, k] = max(hi[b, k], w)
    return lo, hi


compiled_cache.check(__name__)  # last: none of the functions above is loaded from a stale cache
