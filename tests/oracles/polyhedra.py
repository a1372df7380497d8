"""Exact contact geometry of two slightly overlapping convex polyhedra, brute force: the tests'
oracle of the contact kinds of :mod:`drydem.engine.narrow_phase`.

Blocks placed touching with a small known overlap depth d (far below the contact tolerance)
intersect in a thin convex polytope. Every vertex of the intersection A n B lies on an edge of A
or of B (it is the meeting point of three face planes, two of which belong to the same block),
so the intersection's vertices are the parts of each block's edges inside the other block: a
segment clip of every edge against the other block's half-spaces, nothing else. From them:

* touching: the intersection has a point;
* the contact normal: the direction of least penetration, the facet of the Minkowski difference
  B - A (qhull over all differences of vertices) nearest the origin, pointing from A to B;
* the kind: the intersection projected on the plane across the normal is a polygon of
  macroscopic width (face-face), a sliver along a segment (edge-face: length far beyond d, width
  of the order of d) or a blob of the order of d (a point: vertex-face when a vertex of one block
  lies inside the other, crossed edges when none does);
* the face-face contact area: the projected polygon's area (the overlap of the two faces, to O(d)).

Nothing here shares code with the narrow phase.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial import ConvexHull

FACE_FACE, EDGE_FACE, VERTEX_FACE, EDGE_EDGE = "face-face", "edge-face", "vertex-face", "edge-edge"


def halfspaces(vertices: np.ndarray) -> np.ndarray:
    """(F, 4) outward unit normals and offsets n . x + c <= 0 of the convex hull of ``vertices``."""
    return ConvexHull(vertices).equations


def edges(vertices: np.ndarray) -> np.ndarray:
    """(E, 2) vertex pairs of the hull's edges: the sides of its triangulated facets whose two
    facets are not coplanar (so the diagonals of a triangulated face drop out)."""
    hull = ConvexHull(vertices)
    seen: dict[tuple[int, int], list[int]] = {}
    for f, simplex in enumerate(hull.simplices):
        for a, b in ((0, 1), (1, 2), (2, 0)):
            key = (min(simplex[a], simplex[b]), max(simplex[a], simplex[b]))
            seen.setdefault(key, []).append(f)
    out = []
    for key, facets in seen.items():
        n0, n1 = hull.equations[facets[0], :3], hull.equations[facets[1], :3]
        if np.dot(n0, n1) < 1.0 - 1e-10:
            out.append(key)
    return np.array(out, dtype=np.int64)


def clip_segment(p: np.ndarray, q: np.ndarray, planes: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """The part of segment p-q inside all ``planes`` (n . x + c <= 0), or None."""
    s0, s1 = 0.0, 1.0
    d = q - p
    for n0, n1, n2, c in planes:
        f0 = n0 * p[0] + n1 * p[1] + n2 * p[2] + c
        f1 = n0 * d[0] + n1 * d[1] + n2 * d[2]
        if f1 == 0.0:
            if f0 > 0.0:
                return None
        elif f1 > 0.0:
            s1 = min(s1, -f0 / f1)
        else:
            s0 = max(s0, -f0 / f1)
        if s0 > s1:
            return None
    return p + s0 * d, p + s1 * d


def intersection_points(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(k, 3) the vertices (with repeats) of the intersection of the convex hulls of ``a`` and ``b``."""
    points = []
    for first, second in ((a, b), (b, a)):
        planes = halfspaces(second)
        for i, j in edges(first):
            part = clip_segment(first[i], first[j], planes)
            if part is not None:
                points.extend(part)
    return np.array(points).reshape(-1, 3)


def least_penetration_normal(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, float]:
    """Unit normal (from A to B) and depth of least penetration: the facet of the Minkowski
    difference B - A nearest the origin (the depth is the origin's distance to it)."""
    difference = (b[:, None, :] - a[None, :, :]).reshape(-1, 3)
    eq = ConvexHull(difference).equations
    nearest = int(np.argmax(eq[:, 3]))  # offsets are -distance when the origin is inside
    return -eq[nearest, :3], float(-eq[nearest, 3])


@dataclass(frozen=True)
class Contact:
    touching: bool
    normal: np.ndarray | None  # unit, from A to B
    depth: float
    kind: str | None
    area: float  # m2, the projected intersection's area (the contact area of a face-face contact)
    length: float  # m, the projected intersection's largest extent


def contact(a: np.ndarray, b: np.ndarray, depth: float) -> Contact:
    """The contact of the convex hulls of vertices ``a`` and ``b`` (world, m), placed so they
    overlap by about ``depth`` (m): kind thresholds 100 ``depth`` (a macroscopic extent is far
    beyond the depth, a point's blob is a few depths across for the contact angles the tests use)."""
    points = intersection_points(a, b)
    if len(points) == 0:
        return Contact(False, None, 0.0, None, 0.0, 0.0)
    normal, penetration = least_penetration_normal(a, b)
    u = np.cross(normal, [1.0, 0.0, 0.0] if abs(normal[0]) < 0.9 else [0.0, 1.0, 0.0])
    u /= np.linalg.norm(u)
    v = np.cross(normal, u)
    flat = np.c_[points @ u, points @ v]
    flat = flat - flat.mean(axis=0)
    length = float(np.max(np.linalg.norm(flat[:, None] - flat[None], axis=2)))
    try:
        area = float(ConvexHull(flat).volume)
    except Exception:  # noqa: BLE001 - qhull refuses a degenerate (collinear or point) set: no area
        area = 0.0
    width = area / length if length > 0 else 0.0
    big = 100.0 * depth
    if width > big:
        kind = FACE_FACE
    elif length > big:
        kind = EDGE_FACE
    else:
        planes_a, planes_b = halfspaces(a), halfspaces(b)
        slack = 1e-12 * max(np.ptp(a, axis=0).max(), np.ptp(b, axis=0).max())
        inside = sum(int((planes_b[:, :3] @ p + planes_b[:, 3] <= slack).all()) for p in a)
        inside += sum(int((planes_a[:, :3] @ p + planes_a[:, 3] <= slack).all()) for p in b)
        kind = VERTEX_FACE if inside else EDGE_EDGE
    return Contact(True, normal, penetration, kind, area, length)
