"""The narrow phase, compiled with numba: the sub-contacts of many candidate block pairs at once.

Two convex blocks touch where a face of one (the *reference* face) lies within the contact
tolerance of the other block. The contact polygon is discretised into sub-contacts as 3DEC's
contact points: a tensor grid whose spacing puts ``points_per_length`` points along the full
length of the smaller face, ends included, each point carrying its trapezoid share of the area
(the areas sum to the polygon's area); in-plane models need only 1 point across the width.

The algorithm (the tests hold it to a plain-Python oracle written one pair at a time): reference face of least penetration (separating axis over face
normals, ties to the first block), most opposed incident face, Sutherland-Hodgman overlap in
the reference plane, sub-contact grid (bilinear on quadrilaterals, clipped cells otherwise,
trapezoid areas), gaps along the normal, points beyond the tolerance or with a sliver's area
(:data:`SLIVER_FRACTION`) dropped. Geometry comes flattened (:class:`drydem.model.geometry.FlatGeometry`),
so one call handles every stale pair of a re-detection. Polygon buffers are sized from the
model's largest face and grow where round-off needs it; no input writes past one.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numba
import numpy as np

from drydem.engine.contacts import SubContacts
from drydem.model.geometry import FlatGeometry
from drydem.model.parameters import ContactDensity
from drydem.model.rotation import mat_t_vec

#: A sub-contact whose area is at most this fraction of the smaller of its contact's two faces
#: is a sliver, dropped by both narrow phases. Slivers come where a contact polygon grazes a grid
#: cell (turned or rocked blocks): 1e-16 m2 beside cells of 1e-8 m2, their very existence
#: decided by round-off. Relative to the face, not to the overlap, so the rule is the same for a
#: full joint and a thin rocking strip. 1e-9 of a face is a strip as wide as the geometric
#: tolerance (1e-9 of the block size, within which vertices are merged, :func:`_without_collinear`)
#: along the face; it carries 1e-9 of the joint's stiffness, and it is still about a million
#: times the round-off of an area (eps L^2 for a face of size L), so both phases drop the same cells.
SLIVER_FRACTION = 1e-9


class Found(NamedTuple):
    """Per candidate pair k: count[k] points (0: no contact), ref/inc block, normal (3,) world,
    separation m; points (k, M, 3) world on the reference face, gaps (k, M) m, areas (k, M) m2."""

    count: np.ndarray
    ref: np.ndarray
    inc: np.ndarray
    normal: np.ndarray
    separation: np.ndarray
    points: np.ndarray
    gaps: np.ndarray
    areas: np.ndarray

    @classmethod
    def empty(cls, k: int, m: int) -> Found:
        """Room for ``k`` pairs of at most ``m`` points each, none found yet."""
        return cls(
            count=np.zeros(k, np.int64), ref=np.zeros(k, np.int64), inc=np.zeros(k, np.int64), normal=np.zeros((k, 3)),
            separation=np.zeros(k), points=np.zeros((k, m, 3)), gaps=np.zeros((k, m)), areas=np.zeros((k, m)),
        )


@numba.njit(cache=True)
def max_points(along, across):
    """Upper bound on the points of one contact: at most n intervals, so n + 1 points, per
    direction (:func:`_intervals`)."""
    n = max(along, across) + 1
    return n * n


@numba.njit(cache=True)
def _world(geom, block, position, rotation, verts, normals):
    """World vertices and face normals of one block into the first rows of ``verts`` and
    ``normals`` (buffers as large as the largest block's); returns their numbers."""
    v0, v1 = geom.vertex_start[block], geom.vertex_start[block + 1]
    f0, f1 = geom.block_face_start[block], geom.block_face_start[block + 1]
    r, x = rotation[block], position[block]
    for i in range(v1 - v0):
        p = geom.vertex[v0 + i]
        for k in range(3):
            verts[i, k] = x[k] + r[k, 0] * p[0] + r[k, 1] * p[1] + r[k, 2] * p[2]
    for f in range(f1 - f0):
        p = geom.face_normal[f0 + f]
        for k in range(3):
            normals[f, k] = r[k, 0] * p[0] + r[k, 1] * p[1] + r[k, 2] * p[2]
    return v1 - v0, f1 - f0


@numba.njit(cache=True)
def _separations(geom, block, verts, normals, n_faces, other, n_other):
    """Signed distance of ``other``'s deepest vertex (of its first ``n_other``) from each face
    plane of ``block`` (``n_faces`` of them); returns the face of the largest and that distance."""
    f0 = geom.block_face_start[block]
    best, best_face = -np.inf, 0
    for f in range(n_faces):
        first = verts[geom.face_vertex[geom.face_start[f0 + f]]]
        n = normals[f]
        lowest = np.inf
        for j in range(n_other):
            lowest = min(lowest, n[0] * other[j, 0] + n[1] * other[j, 1] + n[2] * other[j, 2])
        separation = lowest - (n[0] * first[0] + n[1] * first[1] + n[2] * first[2])
        if separation > best:
            best, best_face = separation, f
    return best_face, best


@numba.njit(cache=True)
def _face_2d(geom, block, face, verts, origin, u, v, out):
    """The face's vertices in the (u, v) frame at ``origin``, counter-clockwise; returns their number."""
    f0 = geom.block_face_start[block] + face
    count = geom.face_start[f0 + 1] - geom.face_start[f0]
    for i in range(count):
        p = verts[geom.face_vertex[geom.face_start[f0] + i]]
        d0, d1, d2 = p[0] - origin[0], p[1] - origin[1], p[2] - origin[2]
        out[i, 0] = d0 * u[0] + d1 * u[1] + d2 * u[2]
        out[i, 1] = d0 * v[0] + d1 * v[1] + d2 * v[2]
    if _area(out, count) < 0.0:
        for i in range(count // 2):
            for k in range(2):
                out[i, k], out[count - 1 - i, k] = out[count - 1 - i, k], out[i, k]
    return count


@numba.njit(cache=True)
def _area(poly, count):
    total = 0.0
    for i in range(count):
        j = (i + 1) % count
        total += poly[i, 0] * poly[j, 1] - poly[j, 0] * poly[i, 1]
    return 0.5 * total if count >= 3 else 0.0


@numba.njit(cache=True)
def _centroid(poly, count):
    a, cx, cy = 0.0, 0.0, 0.0
    for i in range(count):
        j = (i + 1) % count
        cross = poly[i, 0] * poly[j, 1] - poly[j, 0] * poly[i, 1]
        a += cross
        cx += (poly[i, 0] + poly[j, 0]) * cross
        cy += (poly[i, 1] + poly[j, 1]) * cross
    return cx / (3.0 * a), cy / (3.0 * a)


@numba.njit(cache=True, inline="always")
def _append(poly, count, x, y):
    """``poly`` with (x, y) as vertex ``count``: the same buffer, or, when it is full, a larger
    one (2 count + 4 rows) with the ``count`` vertices before copied."""
    if count == poly.shape[0]:
        larger = np.empty((2 * count + 4, 2))
        larger[:count] = poly[:count]
        poly = larger
    poly[count, 0], poly[count, 1] = x, y
    return poly


@numba.njit(cache=True)
def _clip(subject, n_subject, clipper, n_clipper, out):
    """Sutherland-Hodgman: ``subject`` clipped by the convex ``clipper``; returns the clipped
    polygon's buffer and size.

    The buffer is ``out`` when it has room (callers size it for the exact intersection of two
    convex polygons, at most n_subject + n_clipper vertices), else a larger one: round-off can
    put a vertex lying on a clipping edge on either side of it, and an edge adds a crossing
    then, so no count is certain beforehand."""
    n = n_subject
    for i in range(n):
        out = _append(out, i, subject[i, 0], subject[i, 1])
    work = np.empty((out.shape[0], 2))
    for e in range(n_clipper):
        if n == 0:
            break
        ax, ay = clipper[e, 0], clipper[e, 1]
        ex, ey = clipper[(e + 1) % n_clipper, 0] - ax, clipper[(e + 1) % n_clipper, 1] - ay
        if work.shape[0] < n:
            work = np.empty((out.shape[0], 2))
        for i in range(n):
            work[i, 0], work[i, 1] = out[i, 0], out[i, 1]
        m = 0
        px, py = work[n - 1, 0], work[n - 1, 1]
        p_in = ex * (py - ay) - ey * (px - ax)
        for i in range(n):
            cx, cy = work[i, 0], work[i, 1]
            c_in = ex * (cy - ay) - ey * (cx - ax)
            if c_in >= 0.0:
                if p_in < 0.0:
                    t = p_in / (p_in - c_in)
                    out = _append(out, m, px + t * (cx - px), py + t * (cy - py))
                    m += 1
                out = _append(out, m, cx, cy)
                m += 1
            elif p_in >= 0.0:
                t = p_in / (p_in - c_in)
                out = _append(out, m, px + t * (cx - px), py + t * (cy - py))
                m += 1
            px, py, p_in = cx, cy, c_in
        n = m
    return out, n


@numba.njit(cache=True)
def _without_collinear(poly, count, tol):
    """Drop vertices within ``tol`` of the line through their neighbours or of the previous one."""
    changed = True
    while changed and count > 3:
        changed = False
        for i in range(count):
            p, c, q = poly[(i - 1) % count], poly[i], poly[(i + 1) % count]
            ex, ey = q[0] - p[0], q[1] - p[1]
            length = math.sqrt(ex * ex + ey * ey)
            off = abs(ex * (c[1] - p[1]) - ey * (c[0] - p[0])) / length if length > 0.0 else 0.0
            if off <= tol or math.sqrt((c[0] - p[0]) ** 2 + (c[1] - p[1]) ** 2) <= tol:
                for j in range(i, count - 1):
                    poly[j, 0], poly[j, 1] = poly[j + 1, 0], poly[j + 1, 1]
                count -= 1
                changed = True
                break
    return count


@numba.njit(cache=True)
def _intervals(length, dx, dy, face_a, na, face_b, nb, n):
    """As _intervals of the plain-Python oracle (tests/oracles/contacts.py): 0 for n = 1, else the fewest intervals of spacing <= extent / (n - 1), at most n."""
    if n == 1:
        return 0
    extent = np.inf
    for face, count in ((face_a, na), (face_b, nb)):
        lo, hi = np.inf, -np.inf
        for i in range(count):
            s = face[i, 0] * dx + face[i, 1] * dy
            lo, hi = min(lo, s), max(hi, s)
        extent = min(extent, hi - lo)
    return max(1, int(math.ceil(min(length / (extent / (n - 1)) - 1e-6, n))))


@numba.njit(cache=True)
def _trapezoid(intervals):
    if intervals == 0:
        return np.array([0.5]), np.array([1.0])
    nodes = np.linspace(0.0, 1.0, intervals + 1)
    weights = np.full(intervals + 1, 1.0 / intervals)
    weights[0] *= 0.5
    weights[-1] *= 0.5
    return nodes, weights


@numba.njit(cache=True)
def _count(dx, dy, across_u, across_v, along, across):
    return across if abs(dx * across_u + dy * across_v) > 0.999 else along


@numba.njit(cache=True)
def _bilinear(quad, face_a, na, face_b, nb, along, across, au, av, out_uv, out_area):
    """As _bilinear_grid of the plain-Python oracle (tests/oracles/contacts.py); returns the number of nodes written."""
    axes_nodes = []
    axes_weights = []
    for a0, a1, b0, b1 in ((0, 1, 3, 2), (0, 3, 1, 2)):
        l1 = math.sqrt((quad[a1, 0] - quad[a0, 0]) ** 2 + (quad[a1, 1] - quad[a0, 1]) ** 2)
        l2 = math.sqrt((quad[b1, 0] - quad[b0, 0]) ** 2 + (quad[b1, 1] - quad[b0, 1]) ** 2)
        dx = quad[a1, 0] - quad[a0, 0] + quad[b1, 0] - quad[b0, 0]
        dy = quad[a1, 1] - quad[a0, 1] + quad[b1, 1] - quad[b0, 1]
        norm = math.sqrt(dx * dx + dy * dy)
        dx, dy = dx / norm, dy / norm
        n = _count(dx, dy, au, av, along, across)
        nodes, weights = _trapezoid(_intervals(max(l1, l2), dx, dy, face_a, na, face_b, nb, n))
        axes_nodes.append(nodes)
        axes_weights.append(weights)
    s_nodes, t_nodes = axes_nodes[0], axes_nodes[1]
    ws, wt = axes_weights[0], axes_weights[1]
    k = 0
    total = 0.0
    for i in range(s_nodes.shape[0]):
        for j in range(t_nodes.shape[0]):
            s, t = s_nodes[i], t_nodes[j]
            for c in range(2):
                out_uv[k, c] = (1 - s) * (1 - t) * quad[0, c] + s * (1 - t) * quad[1, c] + s * t * quad[2, c] + (1 - s) * t * quad[3, c]
            dsx = (1 - t) * (quad[1, 0] - quad[0, 0]) + t * (quad[2, 0] - quad[3, 0])
            dsy = (1 - t) * (quad[1, 1] - quad[0, 1]) + t * (quad[2, 1] - quad[3, 1])
            dtx = (1 - s) * (quad[3, 0] - quad[0, 0]) + s * (quad[2, 0] - quad[1, 0])
            dty = (1 - s) * (quad[3, 1] - quad[0, 1]) + s * (quad[2, 1] - quad[1, 1])
            out_area[k] = ws[i] * wt[j] * abs(dsx * dty - dsy * dtx)
            total += out_area[k]
            k += 1
    exact = _area(quad, 4)
    for i in range(k):
        out_area[i] *= exact / total
    return k


@numba.njit(cache=True)
def _inside(poly, count, x, y, tol):
    for i in range(count):
        j = (i + 1) % count
        ex, ey = poly[j, 0] - poly[i, 0], poly[j, 1] - poly[i, 1]
        if ex * (y - poly[i, 1]) - ey * (x - poly[i, 0]) < -tol * math.sqrt(ex * ex + ey * ey):
            return False
    return True


@numba.njit(cache=True)
def _clipped(overlap, count, face_a, na, face_b, nb, along, across, au, av, tol, sliver, out_uv, out_area):
    """As _clipped_grid of the plain-Python oracle (tests/oracles/contacts.py); returns the number of nodes written."""
    lo = np.array([np.inf, np.inf])
    hi = np.array([-np.inf, -np.inf])
    for i in range(count):
        for c in range(2):
            lo[c], hi[c] = min(lo[c], overlap[i, c]), max(hi[c], overlap[i, c])
    nodes = []
    low = []
    high = []
    for c in range(2):
        dx, dy = (1.0, 0.0) if c == 0 else (0.0, 1.0)
        n = _count(dx, dy, au, av, along, across)
        t, _ = _trapezoid(_intervals(hi[c] - lo[c], dx, dy, face_a, na, face_b, nb, n))
        x = lo[c] + t * (hi[c] - lo[c])
        half = 0.5 * (hi[c] - lo[c]) / max(x.shape[0] - 1, 0.5)
        nodes.append(x)
        low.append(np.minimum(np.maximum(x - half, lo[c]), hi[c]))
        high.append(np.minimum(np.maximum(x + half, lo[c]), hi[c]))
    rect = np.empty((4, 2))
    cell = np.empty((count + 4, 2))  # a rectangle adds 4 vertices at most
    k = 0
    for i in range(nodes[0].shape[0]):
        for j in range(nodes[1].shape[0]):
            rect[0, 0], rect[0, 1] = low[0][i], low[1][j]
            rect[1, 0], rect[1, 1] = high[0][i], low[1][j]
            rect[2, 0], rect[2, 1] = high[0][i], high[1][j]
            rect[3, 0], rect[3, 1] = low[0][i], high[1][j]
            cell, m = _clip(overlap, count, rect, 4, cell)
            area = _area(cell, m)
            if area <= sliver:
                continue
            x, y = nodes[0][i], nodes[1][j]
            if not _inside(overlap, count, x, y, tol):
                x, y = _centroid(cell, m)
            out_uv[k, 0], out_uv[k, 1] = x, y
            out_area[k] = area
            k += 1
    return k


@numba.njit(cache=True)
def _largest(start):
    """The largest count in a CSR ``start`` array (faces' vertices, blocks' vertices or faces)."""
    largest = 0
    for i in range(start.shape[0] - 1):
        largest = max(largest, start[i + 1] - start[i])
    return largest


@numba.njit(cache=True, inline="always")
def _most_opposed(normals, count, n):
    """The face of the first ``count`` ``normals`` most opposed to ``n``, and the cosine between them."""
    face, cosine = 0, np.inf
    for f in range(count):
        along_n = normals[f, 0] * n[0] + normals[f, 1] * n[1] + normals[f, 2] * n[2]
        if along_n < cosine:
            face, cosine = f, along_n
    return face, cosine


@numba.njit(cache=True)
def _face_frame(geom, block, face, verts, n, u, v):
    """The reference face's in-plane frame: ``u`` along its longest edge, ``v`` = n x u (written
    into ``u``, ``v``); returns the origin, the face's first vertex."""
    g0 = geom.block_face_start[block] + face
    first, count = geom.face_start[g0], geom.face_start[g0 + 1] - geom.face_start[g0]
    best = -1.0
    for i in range(count):
        p0, p1 = verts[geom.face_vertex[first + i]], verts[geom.face_vertex[first + (i + 1) % count]]
        e0, e1, e2 = p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]
        length = e0 * e0 + e1 * e1 + e2 * e2
        if length > best:
            best, scale = length, 1.0 / math.sqrt(length)
            u[0], u[1], u[2] = e0 * scale, e1 * scale, e2 * scale
    v[0], v[1], v[2] = n[1] * u[2] - n[2] * u[1], n[2] * u[0] - n[0] * u[2], n[0] * u[1] - n[1] * u[0]
    return verts[geom.face_vertex[first]]


@numba.njit(cache=True)
def _grid(overlap, n_overlap, corners, face_a, na, face_b, nb, along, across, au, av, tol, sliver, uv, area):
    """The sub-contact nodes of the overlap polygon into ``uv`` and ``area`` (one at its centroid,
    a bilinear grid on a quadrilateral, clipped cells otherwise); returns their number and the
    ``corners`` buffer (grown if the overlap outgrew it)."""
    if along == 1 and across == 1:
        uv[0, 0], uv[0, 1] = _centroid(overlap, n_overlap)
        area[0] = _area(overlap, n_overlap)
        return 1, corners
    if corners.shape[0] < n_overlap:
        corners = np.empty((overlap.shape[0], 2))
    corners[:n_overlap] = overlap[:n_overlap]
    if _without_collinear(corners, n_overlap, tol) == 4:
        return _bilinear(corners, face_a, na, face_b, nb, along, across, au, av, uv, area), corners
    return _clipped(overlap, n_overlap, face_a, na, face_b, nb, along, across, au, av, tol, sliver, uv, area), corners


@numba.njit(cache=True)
def _keep_points(found, k, nodes, uv, area, origin, u, v, n_inc, plane, cos_ni, tolerance, sliver):
    """The nodes in world coordinates with their gaps along the reference normal to the incident
    face's plane (n_inc . x = plane), those within ``tolerance`` and above a sliver's area into
    ``found``'s row ``k``; returns how many."""
    kept = 0
    for i in range(nodes):
        p0 = origin[0] + uv[i, 0] * u[0] + uv[i, 1] * v[0]
        p1 = origin[1] + uv[i, 0] * u[1] + uv[i, 1] * v[1]
        p2 = origin[2] + uv[i, 0] * u[2] + uv[i, 1] * v[2]
        gap = (plane - (n_inc[0] * p0 + n_inc[1] * p1 + n_inc[2] * p2)) / cos_ni
        if gap <= tolerance and area[i] > sliver:
            found.points[k, kept, 0], found.points[k, kept, 1], found.points[k, kept, 2] = p0, p1, p2
            found.gaps[k, kept] = gap
            found.areas[k, kept] = area[i]
            kept += 1
    return kept


@numba.njit(cache=True)
def find_sub_contacts(geom, position, rotation, candidates, tolerance, along, across, across_axis, found):
    """Fill ``found`` (a :class:`Found` with room for the candidates and :func:`max_points`
    points each) for every candidate pair (i < j)."""
    m = found.gaps.shape[1]
    if found.count.shape[0] < candidates.shape[0] or m < max_points(along, across):
        raise ValueError("found has too little room for the candidates' points")
    uv, area = np.empty((m, 2)), np.empty(m)
    # polygons: a face as large as the largest, an overlap of two (at most both faces' vertices)
    largest = _largest(geom.face_start)
    face_a, face_b = np.empty((largest, 2)), np.empty((largest, 2))
    overlap, corners = np.empty((2 * largest, 2)), np.empty((2 * largest, 2))
    # the two blocks' world geometry, in buffers for the largest block (no allocation per pair)
    largest_v, largest_f = _largest(geom.vertex_start), _largest(geom.block_face_start)
    va, vb = np.empty((largest_v, 3)), np.empty((largest_v, 3))
    na, nb = np.empty((largest_f, 3)), np.empty((largest_f, 3))
    u, v = np.empty(3), np.empty(3)
    for k in range(candidates.shape[0]):
        found.count[k] = 0
        ia, ib = candidates[k, 0], candidates[k, 1]
        nva, nfa = _world(geom, ia, position, rotation, va, na)
        nvb, nfb = _world(geom, ib, position, rotation, vb, nb)
        fa, sa = _separations(geom, ia, va, na, nfa, vb, nvb)
        fb, sb = _separations(geom, ib, vb, nb, nfb, va, nva)
        small = min(geom.size[ia], geom.size[ib])
        if sa >= sb - 1e-9 * small:
            ref, inc, vr, nr, vi, ni, nfi, f_ref, separation = ia, ib, va, na, vb, nb, nfb, fa, sa
        else:
            ref, inc, vr, nr, vi, ni, nfi, f_ref, separation = ib, ia, vb, nb, va, na, nfa, fb, sb
        found.separation[k] = separation
        if separation > tolerance:
            continue
        n = nr[f_ref]
        f_inc, cos_ni = _most_opposed(ni, nfi, n)
        if cos_ni >= -1e-6:
            continue
        origin = _face_frame(geom, ref, f_ref, vr, n, u, v)
        n_ref_2d = _face_2d(geom, ref, f_ref, vr, origin, u, v, face_a)
        n_inc_2d = _face_2d(geom, inc, f_inc, vi, origin, u, v, face_b)
        overlap, n_overlap = _clip(face_b, n_inc_2d, face_a, n_ref_2d, overlap)
        if n_overlap < 3 or _area(overlap, n_overlap) <= 1e-8 * small * small:
            continue
        sliver = SLIVER_FRACTION * min(_area(face_a, n_ref_2d), _area(face_b, n_inc_2d))
        au = across_axis[0] * u[0] + across_axis[1] * u[1] + across_axis[2] * u[2]
        av = across_axis[0] * v[0] + across_axis[1] * v[1] + across_axis[2] * v[2]
        nodes, corners = _grid(overlap, n_overlap, corners, face_a, n_ref_2d, face_b, n_inc_2d, along, across, au, av, 1e-9 * small, sliver, uv, area)
        n_inc = ni[f_inc]
        inc_first = vi[geom.face_vertex[geom.face_start[geom.block_face_start[inc] + f_inc]]]
        plane = n_inc[0] * inc_first[0] + n_inc[1] * inc_first[1] + n_inc[2] * inc_first[2]
        found.count[k] = _keep_points(found, k, nodes, uv, area, origin, u, v, n_inc, plane, cos_ni, tolerance, sliver)
        found.ref[k], found.inc[k] = ref, inc
        found.normal[k] = n


@numba.njit(cache=True)
def assemble(found, position, rotation):
    """The arrays of :class:`drydem.engine.contacts.SubContacts` (in its field order) from the pairs of
    ``found`` with points, in order: each contact's normal and plane offset, and its material
    points, in the two blocks' body frames (the incident point lies on the incident face, ``gap``
    along the normal from the reference one); shear and normal forces zero, intact."""
    nc = 0
    ns = 0
    for k in range(found.count.shape[0]):
        if found.count[k] > 0:
            nc += 1
            ns += found.count[k]
    pairs = np.empty((nc, 2), np.int64)
    normal_body = np.empty((nc, 3))
    offset = np.empty(nc)
    start = np.zeros(nc + 1, np.int64)
    point_ref_body = np.empty((ns, 3))
    point_inc_body = np.empty((ns, 3))
    area = np.empty(ns)
    c = 0
    s = 0
    for k in range(found.count.shape[0]):
        if found.count[k] == 0:
            continue
        ref, inc = found.ref[k], found.inc[k]
        pairs[c, 0], pairs[c, 1] = ref, inc
        r_ref, r_inc, n, x_ref, x_inc = rotation[ref], rotation[inc], found.normal[k], position[ref], position[inc]
        normal_body[c, 0], normal_body[c, 1], normal_body[c, 2] = mat_t_vec(r_ref, n[0], n[1], n[2])
        for j in range(found.count[k]):
            p, gap = found.points[k, j], found.gaps[k, j]
            point_ref_body[s, 0], point_ref_body[s, 1], point_ref_body[s, 2] = mat_t_vec(r_ref, p[0] - x_ref[0], p[1] - x_ref[1], p[2] - x_ref[2])
            point_inc_body[s, 0], point_inc_body[s, 1], point_inc_body[s, 2] = mat_t_vec(
                r_inc, p[0] + gap * n[0] - x_inc[0], p[1] + gap * n[1] - x_inc[1], p[2] + gap * n[2] - x_inc[2]
            )
            area[s] = found.areas[k, j]
            s += 1
        first = start[c]
        offset[c] = normal_body[c, 0] * point_ref_body[first, 0] + normal_body[c, 1] * point_ref_body[first, 1] + normal_body[c, 2] * point_ref_body[first, 2]
        c += 1
        start[c] = s
    return (pairs, normal_body, offset, start, point_ref_body, point_inc_body, area, np.zeros((ns, 3)), np.zeros(ns), np.ones(ns, np.bool_))


def narrow_phase(
    geometry: FlatGeometry, candidates: np.ndarray, position: np.ndarray, rotation: np.ndarray, *, tolerance: float,
    density: ContactDensity,
) -> tuple[SubContacts, np.ndarray]:
    """Sub-contacts of the candidate block pairs (k, 2) at centroids ``position`` (nb, 3) m and
    rotations (nb, 3, 3), in one compiled call (:func:`find_sub_contacts`), and each pair's
    separation along its best face normal (k,) m (a lower bound on their distance when positive).
    Shear forces start at zero (:func:`drydem.engine.refresh.merge` carries them over)."""
    found = Found.empty(len(candidates), max_points(density.along, density.across))
    find_sub_contacts(
        geometry, position, rotation, np.ascontiguousarray(candidates, dtype=np.int64), tolerance, density.along, density.across,
        np.asarray(density.across_axis, dtype=float), found,
    )
    return SubContacts(*assemble(found, position, rotation)), found.separation
