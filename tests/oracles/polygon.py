"""Planar convex polygons as (k, 2) arrays of counter-clockwise vertices (m): the geometry of the
plain-Python narrow phase (:mod:`oracles.contacts`)."""

from __future__ import annotations

import numpy as np


def signed_area(poly: np.ndarray) -> float:
    """Shoelace formula, positive for counter-clockwise vertices, m2.

    Plain Python: contact polygons have 3 to 8 vertices, where NumPy's call overhead dominates."""
    if len(poly) < 3:
        return 0.0
    pts = (np.asarray(poly) - poly[0]).tolist()  # relative to a vertex: a small polygon far from the origin keeps its digits
    total = 0.0
    x0, y0 = pts[-1]
    for x1, y1 in pts:
        total += x0 * y1 - x1 * y0
        x0, y0 = x1, y1
    return 0.5 * total


def centroid(poly: np.ndarray) -> np.ndarray:
    """Area centroid of a polygon with non-zero area, m (computed relative to a vertex)."""
    x, y = (np.asarray(poly) - poly[0]).T
    xn, yn = np.roll(x, -1), np.roll(y, -1)
    cross = x * yn - xn * y
    a = 3.0 * cross.sum()
    return poly[0] + np.array([((x + xn) * cross).sum() / a, ((y + yn) * cross).sum() / a])


def counter_clockwise(poly: np.ndarray) -> np.ndarray:
    """The same polygon with its vertices counter-clockwise."""
    return poly if signed_area(poly) >= 0 else poly[::-1]


def clip(subject: np.ndarray, clipper: np.ndarray) -> np.ndarray:
    """Intersection of two convex counter-clockwise polygons (Sutherland-Hodgman).

    Sutherland & Hodgman (1974), "Reentrant polygon clipping", CACM 17(1).
    Returns a (k, 2) array, k = 0 when they do not intersect.
    """
    out = [tuple(p) for p in subject]
    k = len(clipper)
    for i in range(k):
        if not out:
            break
        ax, ay = clipper[i]
        bx, by = clipper[(i + 1) % k]
        ex, ey = bx - ax, by - ay
        pts, out = out, []
        prev = pts[-1]
        prev_in = ex * (prev[1] - ay) - ey * (prev[0] - ax)
        for cur in pts:
            cur_in = ex * (cur[1] - ay) - ey * (cur[0] - ax)
            if cur_in >= 0:
                if prev_in < 0:
                    out.append(_crossing(prev, cur, prev_in, cur_in))
                out.append(cur)
            elif prev_in >= 0:
                out.append(_crossing(prev, cur, prev_in, cur_in))
            prev, prev_in = cur, cur_in
    return np.array(out, dtype=float).reshape(-1, 2)


def _crossing(p, q, dp: float, dq: float) -> tuple[float, float]:
    t = dp / (dp - dq)
    return (p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1]))


def rectangle(u0: float, u1: float, v0: float, v1: float) -> np.ndarray:
    """Axis-aligned rectangle [u0, u1] x [v0, v1], counter-clockwise."""
    return np.array([[u0, v0], [u1, v0], [u1, v1], [u0, v1]])


def without_collinear(poly: np.ndarray, tol: float) -> np.ndarray:
    """The polygon's corners: vertices closer than ``tol`` to the line through their
    neighbours, or to the previous vertex, are dropped (clipping leaves such vertices)."""
    corners = list(poly)
    changed = True
    while changed and len(corners) > 3:
        changed = False
        for i in range(len(corners)):
            prev, cur, nxt = corners[i - 1], corners[i], corners[(i + 1) % len(corners)]
            edge = nxt - prev
            length = np.hypot(*edge)
            off_line = abs(edge[0] * (cur[1] - prev[1]) - edge[1] * (cur[0] - prev[0])) / length if length > 0 else 0.0
            if off_line <= tol or np.hypot(*(cur - prev)) <= tol:
                del corners[i]
                changed = True
                break
    return np.array(corners)


def vertex_shares(poly: np.ndarray) -> np.ndarray:
    """Each vertex's share of the convex polygon's area (m2): half of each of its two triangles
    with the polygon's area centroid, in NumPy (the oracle of the compiled loop
    :func:`drydem.engine.narrow_phase._vertex_shares`)."""
    to_this = poly - centroid(poly)
    to_next = np.roll(to_this, -1, axis=0)
    triangles = 0.5 * (to_this[:, 0] * to_next[:, 1] - to_this[:, 1] * to_next[:, 0])
    return 0.5 * (triangles + np.roll(triangles, 1))
