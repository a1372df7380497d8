"""The narrow phase, compiled with numba: the sub-contacts of many candidate block pairs at once.

Two convex blocks touch where a feature of one lies within the contact tolerance of the other.
As in 3DEC (Cundall 1988, "Formulation of a three-dimensional distinct element model - Part I",
Int. J. Rock Mech. Min. Sci. 25(3): the contact type is the dimension of what each block has
within the tolerance of the common plane), a contact is one of four kinds, :data:`FACE_FACE`,
:data:`EDGE_FACE`, :data:`VERTEX_FACE` or :data:`EDGE_EDGE` (``Found.kind``, :func:`contact_kinds`).

**Finding the contact plane.** The separating-axis test over both blocks' face normals (the face
of least penetration is the *reference* face, ties to the first block) and over the cross
products of an edge of each block that make a face of the two blocks' Minkowski difference
(a Gauss-map test; edges within :data:`PARALLEL_SINE` of parallel skipped). An edge-pair axis
wins only when it separates the blocks more than every face normal does (by 1e-9 of the smaller
block's size, so round-off never turns a face contact into an edge one): two crossed edges, e.g.
crossed prisms resting apex edge on apex edge, whose face normals would report a wrong, deep
face contact. Nearly parallel faces (:data:`FACE_COSINE`) penetrating less than the tolerance
skip the edge axes (a bed joint is a face contact; the edges are looked at where the faces'
separation is deeper than the tolerance, or the faces are not parallel).

**Face-face.** When the incident block's most opposed face is within :data:`FACE_COSINE` of
parallel to the reference face (a face contact stays one while its blocks rock a few degrees,
its open part simply beyond the tolerance), or when the incident vertices within the tolerance of
the reference plane span an area: the contact polygon is discretised into sub-contacts as 3DEC's
contact points: a tensor grid whose spacing puts ``points_per_length`` points along the full
length of the smaller face, ends included, each point carrying its share of the area (trapezoid
on a quadrilateral; the areas sum to the polygon's area, less dropped slivers); in-plane models
need only 1 point across the width. The
algorithm (the tests hold it to a plain-Python oracle written one pair at a time): most opposed
incident face, Sutherland-Hodgman overlap in the reference plane, sub-contact grid (bilinear on
quadrilaterals, trapezoid areas; a lumped grid on other polygons: the grid's lines cut the
polygon into pieces whose areas go to their corners, :func:`_vertex_shares`, so every corner of
the polygon is a point and a block rocks on its outermost one, as on a quadrilateral's), gaps
along the normal, points beyond the tolerance or with a sliver's area (:data:`SLIVER_FRACTION`)
dropped.

**Edge-face and vertex-face.** Otherwise the incident vertices within the tolerance of the
reference plane are the touching feature: one vertex (vertex-face: one point, where it projects
inside the reference face) or an edge (edge-face: the segment, clipped to the reference face,
with points along it at the spacing of a face grid).

**Crossed edges.** One point, at the closest point of the reference block's edge to the other's,
the normal the edge-pair axis; unless one edge runs along one face of the other edge's (within
0.2 rad of its plane, the face's normal within 0.2 rad of the axis, as :data:`FACE_COSINE`): that
is an edge-face contact whose face normal lost to the edge axis only because the edge's block
reaches past the face and below its plane (a slab's edge under a block's tilted bed face), and
the edge clipped to that face is the contact (:func:`_edge_along_face`).

**Nominal areas of point-like contacts.** A sub-contact's normal force is kn x area x closure, so
the area given to a contact without one sets its stiffness. The rule: *a point-like contact
carries what the same point would carry in the face grid it would get had it landed*: the grid of
the reference face and the incident block's landing face, whose spacing puts n points per length
over the smaller face's extent, h(n) = extent / (n - 1) (the extent for n = 1, where the one
point stands for the whole length; :func:`_grid_lengths`: the landing face's extents in its own
plane, along an edge of it and across, the reference face's along their projections), and whose
end row carries a width w(n) = h(n) / 2 (the whole extent for n = 1). A vertex-face contact is a
grid's corner point: area w(along) w(across) (the landing face's longest edge giving the grid's
direction), the quarter cell a face grid's corner point carries. An edge-face contact is a grid's
edge row: points at spacing h(along) along the segment (``along``, or ``across`` along the
model's across axis), each its trapezoid share of the segment's length times w(across). Which
face lands is a blend: every face of the incident block turned less than square to the reference
plane, by angle phi, weighs w = 1 / (phi - 0.2) - 1 / (pi/2 - 0.2) (:func:`_landing_weight`),
so the face at the face-face limit (0.2 rad, where the face grid hands over) takes it all, and
the blend changes continuously as the block turns, also where its most opposed face changes (a
box on its edge at 45 deg, half bed and half side: a jump of the side's extent over the bed's
with the most opposed face alone, found by a hunt). Crossed edges are the corner of the grid of
their faces most along and most opposed to the edge-pair axis. So a block turning off its bed
face onto its edge keeps, at the turn, the stiffness of the same row of points, whatever its
height: a column of bed a x b (edge b) carries its weight on its edge with a closure
W / (kn b h / 2), h = a / (n - 1). (The nominal length was first the smaller block's
circumradius', 2 R / sqrt(3): a slender block's edge row then carried 2.4 to 3.4 times its bed
face's, and the force jumped at the turn. Itasca's documentation, searched, gives no published
rule for the contact area of 3DEC's vertex-face and edge-edge contacts; this one is ours.)

Geometry comes flattened (:class:`drydem.model.geometry.FlatGeometry`), so one call handles every
stale pair of a re-detection, in parallel over chunks of candidates (each chunk with its own
scratch buffers; each pair writes only its own row of :class:`Found`, so the result does not
depend on the thread count). Polygon buffers are sized from the model's largest face and grow
where round-off needs it; every other buffer write is bounds-checked; no input writes past one.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numba
import numpy as np

from drydem import compiled_cache
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

#: contact kinds (``Found.kind``): a face on a face, an edge on a face, a vertex on a face, two crossed edges
FACE_FACE, EDGE_FACE, VERTEX_FACE, EDGE_EDGE = 0, 1, 2, 3
KIND_NAMES = ("face-face", "edge-face", "vertex-face", "edge-edge")

#: the incident face is a face contact's when its normal is within this cosine of opposite to the
#: reference face's: 0.2 rad (11.5 deg). A block rocking on its bed joint stays in face contact up to
#: there, its open part beyond the tolerance (its sub-contacts keep their places, as in 3DEC's
#: face-face contacts); beyond it, only its edge or vertex touches and the contact is of that type.
#: Measured, not derived: at 0.1 rad a brick rocking a few degrees past it switched between its
#: face grid and the point contacts' nominal areas, whose corner areas differ (h^2/4 here, the face
#: grid's cell quarter there), and each switch of a closed point changed its elastic energy (26 %
#: of the drop energy in tests/test_energy.py's 3D rocking drop; 4.4 % at 0.2 rad, 3.9 % before the
#: point contacts); at 0.35 rad a cube falling off its edge landed with 55 % of the rigid body's
#: angular velocity (tests/test_contact_types.py; not understood yet), at 0.2 rad within 0.5 %.
FACE_COSINE = math.cos(0.2)
#: an edge within this sine of a face's plane runs along it (the same 0.2 rad): :func:`_edge_along_face`
FACE_SINE = math.sin(0.2)

#: two edges whose directions are within this sine of parallel give no edge-pair axis (1e-3 rad):
#: their cross product is the direction of round-off, and the face normals cover parallel edges
PARALLEL_SINE = 1e-3


class Found(NamedTuple):
    """Per candidate pair k: count[k] points (0: no contact), ref/inc block, normal (3,) world,
    separation m; points (k, M, 3) world on the reference face, gaps (k, M) m, areas (k, M) m2;
    kind (k,) the contact's kind (:data:`FACE_FACE`, :data:`EDGE_FACE`, :data:`VERTEX_FACE`,
    :data:`EDGE_EDGE`; meaningful where count > 0)."""

    count: np.ndarray
    ref: np.ndarray
    inc: np.ndarray
    normal: np.ndarray
    separation: np.ndarray
    points: np.ndarray
    gaps: np.ndarray
    areas: np.ndarray
    kind: np.ndarray

    @classmethod
    def empty(cls, k: int, m: int) -> Found:
        """Room for ``k`` pairs of at most ``m`` points each, none found yet."""
        return cls(
            count=np.zeros(k, np.int64), ref=np.zeros(k, np.int64), inc=np.zeros(k, np.int64), normal=np.zeros((k, 3)),
            separation=np.zeros(k), points=np.zeros((k, m, 3)), gaps=np.zeros((k, m)), areas=np.zeros((k, m)),
            kind=np.zeros(k, np.int64),
        )


@numba.njit(cache=True)
def max_points(along, across, largest_face):
    """Upper bound on the points of one contact between faces of at most ``largest_face``
    vertices: at most n intervals, so n + 1 lines, per direction (:func:`_intervals`); a
    lumped grid's points (:func:`_lumped`) are where the lines cross, where they cross the
    contact polygon's sides (2 per line) and its corners (at most both faces' vertices)."""
    n = max(along, across) + 1
    return n * n + 4 * n + 2 * largest_face


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
    """The shoelace formula, relative to the first vertex (a small polygon far from the frame's
    origin keeps its digits)."""
    if count < 3:
        return 0.0
    ox, oy = poly[0, 0], poly[0, 1]
    total = 0.0
    for i in range(count):
        j = (i + 1) % count
        total += (poly[i, 0] - ox) * (poly[j, 1] - oy) - (poly[j, 0] - ox) * (poly[i, 1] - oy)
    return 0.5 * total


@numba.njit(cache=True)
def _centroid(poly, count):
    """The area centroid, relative to the first vertex as :func:`_area`."""
    ox, oy = poly[0, 0], poly[0, 1]
    a, cx, cy = 0.0, 0.0, 0.0
    for i in range(count):
        j = (i + 1) % count
        xi, yi, xj, yj = poly[i, 0] - ox, poly[i, 1] - oy, poly[j, 0] - ox, poly[j, 1] - oy
        cross = xi * yj - xj * yi
        a += cross
        cx += (xi + xj) * cross
        cy += (yi + yj) * cross
    return ox + cx / (3.0 * a), oy + cy / (3.0 * a)


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
def _axis_lines(overlap, count, c, face_a, na, face_b, nb, along, across, au, av):
    """The lumped grid's lines along in-plane axis ``c`` (0: u, 1: v) over the polygon's extent,
    through the trapezoid nodes, and the coordinate its points collapse to: NaN, none; with no
    interval (one point across) the two ends are the lines and the points go to the middle."""
    lo, hi = np.inf, -np.inf
    for i in range(count):
        lo, hi = min(lo, overlap[i, c]), max(hi, overlap[i, c])
    dx, dy = (1.0, 0.0) if c == 0 else (0.0, 1.0)
    intervals = _intervals(hi - lo, dx, dy, face_a, na, face_b, nb, _count(dx, dy, au, av, along, across))
    if intervals == 0:
        return np.array([lo, hi]), 0.5 * (lo + hi)
    t, _ = _trapezoid(intervals)
    lines = lo + t * (hi - lo)
    lines[-1] = hi  # lo + (hi - lo) may round off it, and cut the polygon's side there at a point of round-off
    return lines, np.nan


@numba.njit(cache=True)
def _vertex_shares(poly, count, out):
    """Each vertex's share of the convex polygon's area into ``out``: the triangles (g, v_i,
    v_(i+1)) from its area centroid g, of areas T_i, each half to each of its two corners,
    share_i = (T_(i-1) + T_i) / 2.

    Exact for a linear function: the shares sum to the area A, and their first moment is
    sum_i T_i (v_i + v_(i+1)) / 2 = A g, since each triangle's centroid (g + v_i + v_(i+1)) / 3
    averages to g. A vertex repeated by round-off, or on a side, takes a share from its
    neighbours that vanishes with its distance to them (a rule through the vertices' mean would
    jump), and each corner of a rectangle, or of a triangle, gets an equal share."""
    gx, gy = _centroid(poly, count)
    for i in range(count):
        out[i] = 0.0
    for i in range(count):
        j = (i + 1) % count
        half = 0.25 * ((poly[i, 0] - gx) * (poly[j, 1] - gy) - (poly[i, 1] - gy) * (poly[j, 0] - gx))
        out[i] += half
        out[j] += half


@numba.njit(cache=True, inline="always")
def _near(uv, start, end, x, y, tol):
    """The first of points [start, end) within ``tol`` of (x, y) in both coordinates; -1 for none."""
    for p in range(start, end):
        if abs(uv[p, 0] - x) <= tol and abs(uv[p, 1] - y) <= tol:
            return p
    return -1


@numba.njit(cache=True)
def _add_point(uv, area, count, x, y, share, tol, first, i, j, ny, apart):
    """``share`` m2 onto the point within ``tol`` of (x, y), a vertex of piece (i, j) of the lumped
    grid, or onto a new one. Where the grid's lines are ``apart`` by more than twice ``tol``, a
    point it shares is one of pieces (i - 1, j - 1 ... j + 1), (i, j - 1) or its own (``first``:
    each piece's first point, pieces in order (0, 0), (0, 1), ..., ``ny`` a column), and only
    theirs are looked at; else all. Returns the buffers (grown when full) and the number of points."""
    p = -1 if apart else _near(uv, 0, count, x, y, tol)
    if apart and i > 0:
        p = _near(uv, first[(i - 1) * ny + max(j - 1, 0)], first[(i - 1) * ny + min(j + 1, ny - 1) + 1], x, y, tol)
    if apart and p < 0:
        p = _near(uv, first[i * ny + max(j - 1, 0)], count, x, y, tol)
    if p >= 0:
        area[p] += share
        return uv, area, count
    uv = _append(uv, count, x, y)
    if area.shape[0] < uv.shape[0]:
        larger = np.empty(uv.shape[0])
        larger[:count] = area[:count]
        area = larger
    area[count] = share
    return uv, area, count + 1


@numba.njit(cache=True)
def _lumped(overlap, count, face_a, na, face_b, nb, along, across, au, av, tol, sliver, uv, area):
    """As _lumped_grid of the plain-Python oracle (tests/oracles/contacts.py), which looks for a
    vertex's point among all (here among the neighbouring pieces', :func:`_add_point`); returns
    the number of points and the ``uv``, ``area`` buffers (grown if the points outgrew them)."""
    xs, middle_x = _axis_lines(overlap, count, 0, face_a, na, face_b, nb, along, across, au, av)
    ys, middle_y = _axis_lines(overlap, count, 1, face_a, na, face_b, nb, along, across, au, av)
    apart = min(xs[1] - xs[0], ys[1] - ys[0]) > 2.0 * tol  # the lines equally spaced
    rect = np.empty((4, 2))
    piece = np.empty((count + 4, 2))  # a rectangle adds 4 vertices at most
    shares = np.empty(count + 4)
    ny = ys.shape[0] - 1
    first = np.zeros((xs.shape[0] - 1) * ny + 1, np.int64)  # each piece's first point
    points = 0
    for i in range(xs.shape[0] - 1):
        for j in range(ny):
            first[i * ny + j] = points
            rect[0, 0], rect[0, 1] = xs[i], ys[j]
            rect[1, 0], rect[1, 1] = xs[i + 1], ys[j]
            rect[2, 0], rect[2, 1] = xs[i + 1], ys[j + 1]
            rect[3, 0], rect[3, 1] = xs[i], ys[j + 1]
            piece, m = _clip(overlap, count, rect, 4, piece)
            if _area(piece, m) <= sliver:
                continue
            if shares.shape[0] < m:
                shares = np.empty(piece.shape[0])
            _vertex_shares(piece, m, shares)
            for p in range(m):
                x = piece[p, 0] if np.isnan(middle_x) else middle_x
                y = piece[p, 1] if np.isnan(middle_y) else middle_y
                uv, area, points = _add_point(uv, area, points, x, y, shares[p], tol, first, i, j, ny, apart)
    return points, uv, area


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
def _longest_edge(geom, block, face, verts):
    """The unit direction of the longest edge of face ``face`` of ``block`` (world vertices ``verts``), a 3-tuple."""
    g0 = geom.block_face_start[block] + face
    first, count = geom.face_start[g0], geom.face_start[g0 + 1] - geom.face_start[g0]
    best, direction = -1.0, (1.0, 0.0, 0.0)
    for i in range(count):
        p0, p1 = verts[geom.face_vertex[first + i]], verts[geom.face_vertex[first + (i + 1) % count]]
        e0, e1, e2 = p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]
        length = e0 * e0 + e1 * e1 + e2 * e2
        if length > best:
            scale = 1.0 / math.sqrt(length)
            best, direction = length, (e0 * scale, e1 * scale, e2 * scale)
    return direction


@numba.njit(cache=True)
def _face_frame(geom, block, face, verts, n, u, v):
    """The reference face's in-plane frame: ``u`` along its longest edge, ``v`` = n x u (written
    into ``u``, ``v``); returns the origin, the face's first vertex."""
    u[0], u[1], u[2] = _longest_edge(geom, block, face, verts)
    v[0], v[1], v[2] = n[1] * u[2] - n[2] * u[1], n[2] * u[0] - n[0] * u[2], n[0] * u[1] - n[1] * u[0]
    return verts[geom.face_vertex[geom.face_start[geom.block_face_start[block] + face]]]


@numba.njit(cache=True)
def _grid(overlap, n_overlap, corners, face_a, na, face_b, nb, along, across, au, av, tol, sliver, uv, area):
    """The sub-contact nodes of the overlap polygon into ``uv`` and ``area`` (one at its centroid,
    a bilinear grid on a quadrilateral, the lumped grid otherwise); returns their number and the
    ``corners``, ``uv`` and ``area`` buffers (grown if the polygon or its points outgrew them)."""
    if along == 1 and across == 1:
        uv[0, 0], uv[0, 1] = _centroid(overlap, n_overlap)
        area[0] = _area(overlap, n_overlap)
        return 1, corners, uv, area
    if corners.shape[0] < n_overlap:
        corners = np.empty((overlap.shape[0], 2))
    corners[:n_overlap] = overlap[:n_overlap]
    if _without_collinear(corners, n_overlap, tol) == 4:
        return _bilinear(corners, face_a, na, face_b, nb, along, across, au, av, uv, area), corners, uv, area
    nodes, uv, area = _lumped(overlap, n_overlap, face_a, na, face_b, nb, along, across, au, av, tol, sliver, uv, area)
    return nodes, corners, uv, area


@numba.njit(cache=True)
def _keep_points(found, k, nodes, uv, area, origin, u, v, n_inc, plane, cos_ni, tolerance, sliver):
    """The nodes in world coordinates with their gaps along the reference normal to the incident
    face's plane (n_inc . x = plane), those within ``tolerance`` and above a sliver's area into
    ``found``'s row ``k``; returns how many, or -1 when they outgrow the row (:func:`find` retries
    with a wider one)."""
    kept = 0
    for i in range(nodes):
        p0 = origin[0] + uv[i, 0] * u[0] + uv[i, 1] * v[0]
        p1 = origin[1] + uv[i, 0] * u[1] + uv[i, 1] * v[1]
        p2 = origin[2] + uv[i, 0] * u[2] + uv[i, 1] * v[2]
        gap = (plane - (n_inc[0] * p0 + n_inc[1] * p1 + n_inc[2] * p2)) / cos_ni
        if gap <= tolerance and area[i] > sliver:
            if kept == found.points.shape[1]:
                return -1
            found.points[k, kept, 0], found.points[k, kept, 1], found.points[k, kept, 2] = p0, p1, p2
            found.gaps[k, kept] = gap
            found.areas[k, kept] = area[i]
            kept += 1
    return kept


@numba.njit(cache=True)
def _edges(geom, block, out):
    """The edges of ``block`` into ``out`` (rows: its two vertex numbers within the block, the
    lower first, and its two faces' numbers within the block: the one whose loop runs from the
    lower to the higher, then the other, -1 if none); returns their number."""
    count = 0
    f0 = geom.block_face_start[block]
    for f in range(f0, geom.block_face_start[block + 1]):
        first, n = geom.face_start[f], geom.face_start[f + 1] - geom.face_start[f]
        for i in range(n):
            a, b = geom.face_vertex[first + i], geom.face_vertex[first + (i + 1) % n]
            if a < b and count < out.shape[0]:
                out[count, 0], out[count, 1], out[count, 2], out[count, 3] = a, b, f - f0, -1
                count += 1
    for f in range(f0, geom.block_face_start[block + 1]):
        first, n = geom.face_start[f], geom.face_start[f + 1] - geom.face_start[f]
        for i in range(n):
            a, b = geom.face_vertex[first + i], geom.face_vertex[first + (i + 1) % n]
            if a > b:
                for e in range(count):
                    if out[e, 0] == b and out[e, 1] == a:
                        out[e, 3] = f - f0
                        break
    return count


@numba.njit(cache=True)
def _range(verts, count, x, y, z):
    lo, hi = np.inf, -np.inf
    for j in range(count):
        s = x * verts[j, 0] + y * verts[j, 1] + z * verts[j, 2]
        lo, hi = min(lo, s), max(hi, s)
    return lo, hi


@numba.njit(cache=True, inline="always")
def _dot_cross(x, a, b):
    """x . (a x b) of three 3-vectors."""
    return x[0] * (a[1] * b[2] - a[2] * b[1]) + x[1] * (a[2] * b[0] - a[0] * b[2]) + x[2] * (a[0] * b[1] - a[1] * b[0])


@numba.njit(cache=True, inline="always")
def _minkowski_face(a, b, c, d):
    """The arcs a-b (an edge of A: its faces' normals) and c-d (an edge of B: minus its faces'
    normals) cross on the Gauss map: the edge pair is a face of the Minkowski difference, so its
    axis can separate (Gregorius, "The separating axis test between convex polyhedra", GDC 2013)."""
    cba, dba = _dot_cross(c, b, a), _dot_cross(d, b, a)
    adc, bdc = _dot_cross(a, d, c), _dot_cross(b, d, c)
    return cba * dba < 0.0 and adc * bdc < 0.0 and cba * bdc > 0.0


@numba.njit(cache=True)
def _edge_axes(va, nva, na, ea, nea, vb, nvb, nb, eb, neb, eps, best_axis):
    """Separating-axis test over the cross products of an edge of A and an edge of B that make a
    face of the Minkowski difference (:func:`_minkowski_face`; edges within PARALLEL_SINE of
    parallel skipped: their axes are the face normals' business). The axis of largest separation
    whose two edges realise both blocks' supports along it (within ``eps``, checked over every
    vertex), oriented from A to B, into ``best_axis``; returns (separation, edge of A, edge of B),
    -inf and -1 when no axis qualifies."""
    best, best_i, best_j = -np.inf, -1, -1
    mc, md = np.empty(3), np.empty(3)
    for i in range(nea):
        if ea[i, 3] < 0:
            continue
        p, q = va[ea[i, 0]], va[ea[i, 1]]
        e0, e1, e2 = q[0] - p[0], q[1] - p[1], q[2] - p[2]
        la = e0 * e0 + e1 * e1 + e2 * e2
        fa1, fa2 = na[ea[i, 2]], na[ea[i, 3]]
        for j in range(neb):
            if eb[j, 3] < 0:
                continue
            for c in range(3):
                mc[c], md[c] = -nb[eb[j, 2], c], -nb[eb[j, 3], c]
            if not _minkowski_face(fa1, fa2, mc, md):
                continue
            r, t = vb[eb[j, 0]], vb[eb[j, 1]]
            f0, f1, f2 = t[0] - r[0], t[1] - r[1], t[2] - r[2]
            x, y, z = e1 * f2 - e2 * f1, e2 * f0 - e0 * f2, e0 * f1 - e1 * f0
            norm_sq = x * x + y * y + z * z
            if norm_sq <= PARALLEL_SINE * PARALLEL_SINE * la * (f0 * f0 + f1 * f1 + f2 * f2):
                continue
            scale = 1.0 / math.sqrt(norm_sq)
            x, y, z = x * scale, y * scale, z * scale
            if x * (fa1[0] + fa2[0]) + y * (fa1[1] + fa2[1]) + z * (fa1[2] + fa2[2]) < 0.0:  # out of A's edge
                x, y, z = -x, -y, -z
            if x * (r[0] - p[0]) + y * (r[1] - p[1]) + z * (r[2] - p[2]) <= best:  # the edges' own separation bounds the axis's
                continue
            lo_a, hi_a = _range(va, nva, x, y, z)
            lo_b, hi_b = _range(vb, nvb, x, y, z)
            separation = lo_b - hi_a
            if separation <= best:
                continue
            # the two edges must be the supporting features, not parallel edges elsewhere
            if x * p[0] + y * p[1] + z * p[2] < hi_a - eps or x * r[0] + y * r[1] + z * r[2] > lo_b + eps:
                continue
            best, best_i, best_j = separation, i, j
            best_axis[0], best_axis[1], best_axis[2] = x, y, z
    return best, best_i, best_j


@numba.njit(cache=True, inline="always")
def _dot(a, b):
    """a . b of two 3-vectors (arrays or tuples)."""
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


@numba.njit(cache=True)
def _extent(geom, block, face, verts, x, y, z):
    """The extent of face ``face`` of ``block`` (world vertices ``verts``) along the unit direction (x, y, z), m."""
    g0 = geom.block_face_start[block] + face
    lo, hi = np.inf, -np.inf
    for i in range(geom.face_start[g0], geom.face_start[g0 + 1]):
        w = verts[geom.face_vertex[i]]
        s = x * w[0] + y * w[1] + z * w[2]
        lo, hi = min(lo, s), max(hi, s)
    return hi - lo


@numba.njit(cache=True)
def _grid_lengths(geom, ref, f_ref, vr, n, inc, f_inc, vi, m, d):
    """The lengths the face grid of the reference face ``f_ref`` (normal ``n``) and the incident
    block's landing face ``f_inc`` (normal ``m``) would span along ``d``, a unit direction of the
    landing face (an edge of it), and across it, m, had the landing face landed: each the smaller
    face's extent, the landing face's in its own plane (d, and m x d), the reference face's along
    their projections on its plane. A direction nearly along ``n`` counts the landing face only."""
    along = _extent(geom, inc, f_inc, vi, d[0], d[1], d[2])
    across = _extent(geom, inc, f_inc, vi, m[1] * d[2] - m[2] * d[1], m[2] * d[0] - m[0] * d[2], m[0] * d[1] - m[1] * d[0])
    dn = _dot(d, n)
    px, py, pz = d[0] - dn * n[0], d[1] - dn * n[1], d[2] - dn * n[2]
    norm = math.sqrt(px * px + py * py + pz * pz)
    if norm > 1e-6:
        px, py, pz = px / norm, py / norm, pz / norm
        along = min(along, _extent(geom, ref, f_ref, vr, px, py, pz))
        across = min(across, _extent(geom, ref, f_ref, vr, n[1] * pz - n[2] * py, n[2] * px - n[0] * pz, n[0] * py - n[1] * px))
    return along, across


#: the angle between a face of the incident block and the reference plane past which it no longer
#: lands (:func:`_landing_weight`), rad: square to the plane
LANDING_LIMIT_RAD = 0.5 * math.pi


@numba.njit(cache=True)
def _landing_weight(cosine):
    """The weight of an incident face whose normal has ``cosine`` with the reference normal in the
    blend of :func:`_blended_lengths`: w = 1 / (phi - 0.2) - 1 / (pi/2 - 0.2), phi the face's angle
    to the reference plane, so that the face at the face-face limit (0.2 rad, :data:`FACE_COSINE`)
    takes it all (inf) and a face turned square to the plane or away nothing; continuous in phi,
    so the nominal areas change smoothly as a block turns, also where its most opposed face
    changes (a box on its edge at 45 deg)."""
    phi = math.acos(min(1.0, max(-1.0, -cosine)))
    if phi >= LANDING_LIMIT_RAD:
        return 0.0
    face_limit = math.acos(FACE_COSINE)
    if phi <= face_limit:
        return np.inf
    return 1.0 / (phi - face_limit) - 1.0 / (LANDING_LIMIT_RAD - face_limit)


@numba.njit(cache=True)
def _landing_weights(ni, nfi, n, weights):
    """:func:`_landing_weight` of each of the incident block's faces (normals ``ni``, ``nfi`` of
    them) into ``weights``; returns (face, total): the face that takes it all (one at the
    face-face limit; the most opposed one when none faces the plane, round-off at a square face)
    and 0, or -1 and the weights' total, which they share."""
    total = 0.0
    for f in range(nfi):
        weights[f] = _landing_weight(_dot(ni[f], n))
        if weights[f] == np.inf:
            return f, 0.0
        total += weights[f]
    if total == 0.0:
        f, _ = _most_opposed(ni, nfi, n)
        return f, 0.0
    return -1, total


@numba.njit(cache=True)
def _blended_lengths(geom, ref, f_ref, vr, n, inc, vi, ni, nfi, d):
    """:func:`_grid_lengths` along ``d`` and across, blended over the incident block's faces that
    may land (normals ``ni``, ``nfi`` of them) by :func:`_landing_weights`, m."""
    weights = np.empty(nfi)
    alone, total = _landing_weights(ni, nfi, n, weights)
    if alone >= 0:
        return _grid_lengths(geom, ref, f_ref, vr, n, inc, alone, vi, ni[alone], d)
    along, across = 0.0, 0.0
    for f in range(nfi):
        if weights[f] > 0.0:
            length_d, length_c = _grid_lengths(geom, ref, f_ref, vr, n, inc, f, vi, ni[f], d)
            along, across = along + weights[f] * length_d, across + weights[f] * length_c
    return along / total, across / total


@numba.njit(cache=True)
def _spacing(length, n):
    """Grid spacing of ``n`` points along ``length``, ends included (the whole length for 1)."""
    return length / (n - 1) if n > 1 else length


@numba.njit(cache=True)
def _end_share(length, n):
    """The width a face grid's end row carries across a face of ``length`` with ``n`` points
    across it, m: half a spacing, or the whole length for one point, which stands for all of it."""
    return 0.5 * length / (n - 1) if n > 1 else length


@numba.njit(cache=True)
def _corner_area(geom, ref, f_ref, vr, n, inc, f_inc, vi, m, along, across, across_axis):
    """The corner point's area of the face grid of the reference face and the landing face
    ``f_inc`` (:func:`_grid_lengths` along the landing face's longest edge and across it), m2:
    _end_share along x _end_share across (a quarter cell), the counts as :func:`_count`."""
    d = _longest_edge(geom, inc, f_inc, vi)
    length_d, length_c = _grid_lengths(geom, ref, f_ref, vr, n, inc, f_inc, vi, m, d)
    cx, cy, cz = m[1] * d[2] - m[2] * d[1], m[2] * d[0] - m[0] * d[2], m[0] * d[1] - m[1] * d[0]
    # the counts by the directions' cosines with the across axis (_count's rule)
    n_d = _count(_dot(d, across_axis), 0.0, 1.0, 0.0, along, across)
    n_c = _count(_dot((cx, cy, cz), across_axis), 0.0, 1.0, 0.0, along, across)
    return _end_share(length_d, n_d) * _end_share(length_c, n_c)


@numba.njit(cache=True)
def _point_area(geom, ref, f_ref, vr, n, inc, vi, ni, nfi, along, across, across_axis):
    """Nominal area of a vertex-face contact, m2: :func:`_corner_area` blended over the incident
    block's faces that may land (:func:`_landing_weights`)."""
    weights = np.empty(nfi)
    alone, total = _landing_weights(ni, nfi, n, weights)
    if alone >= 0:
        return _corner_area(geom, ref, f_ref, vr, n, inc, alone, vi, ni[alone], along, across, across_axis)
    area = 0.0
    for f in range(nfi):
        if weights[f] > 0.0:
            area += weights[f] * _corner_area(geom, ref, f_ref, vr, n, inc, f, vi, ni[f], along, across, across_axis)
    return area / total


@numba.njit(cache=True)
def _put(found, k, kept, x, y, z, gap, area):
    """One point into row ``k`` of ``found`` at ``kept``, if there is room; returns the new count."""
    if kept >= found.gaps.shape[1]:
        return kept
    found.points[k, kept, 0], found.points[k, kept, 1], found.points[k, kept, 2] = x, y, z
    found.gaps[k, kept] = gap
    found.areas[k, kept] = area
    return kept + 1


@numba.njit(cache=True)
def _crossed_edges(found, k, va, ea, i, vb, eb, j, n, tolerance, area):
    """Crossed edges (edge i of A, edge j of B, axis ``n`` from A to B): one point at the closest
    point of A's edge to B's, its gap along ``n``; returns 1, or 0 beyond the tolerance."""
    p, q, r, t = va[ea[i, 0]], va[ea[i, 1]], vb[eb[j, 0]], vb[eb[j, 1]]
    d1 = np.empty(3)
    d2 = np.empty(3)
    w = np.empty(3)
    for c in range(3):
        d1[c], d2[c], w[c] = q[c] - p[c], t[c] - r[c], p[c] - r[c]
    a = d1[0] * d1[0] + d1[1] * d1[1] + d1[2] * d1[2]
    b = d1[0] * d2[0] + d1[1] * d2[1] + d1[2] * d2[2]
    c_ = d2[0] * d2[0] + d2[1] * d2[1] + d2[2] * d2[2]
    d = d1[0] * w[0] + d1[1] * w[1] + d1[2] * w[2]
    e = d2[0] * w[0] + d2[1] * w[1] + d2[2] * w[2]
    den = a * c_ - b * b  # > 0: the edges are not parallel (_edge_axes)
    s = min(1.0, max(0.0, (b * e - c_ * d) / den))
    u = min(1.0, max(0.0, (a * e - b * d) / den))
    x0, x1, x2 = p[0] + s * d1[0], p[1] + s * d1[1], p[2] + s * d1[2]
    gap = n[0] * (r[0] + u * d2[0] - x0) + n[1] * (r[1] + u * d2[1] - x1) + n[2] * (r[2] + u * d2[2] - x2)
    if gap > tolerance:
        return 0
    return _put(found, k, 0, x0, x1, x2, gap, area)


@numba.njit(cache=True)
def _features(found, k, geom, ref, f_ref, vr, n, inc, vi, nvi, ni, nfi, touching, tolerance, along, across, across_axis, u, v, face_a,
              small):
    """Vertex-face or edge-face contact of the incident block (world vertices ``vi``) on the
    reference face ``f_ref`` of normal ``n``: its vertices within the tolerance of the face's
    plane are the touching feature. One vertex: a point (:func:`_point_area`) where it projects
    inside the face; an edge (vertices on a line): the segment clipped to the face
    (:func:`_segment_on_face`); the grid's lengths are the reference face's and the incident
    block's faces' that may land (normals ``ni``, ``nfi`` faces). Returns (points, kind); kind FACE_FACE when
    the touching vertices span an area (the face-face path is the one for them)."""
    origin = _face_frame(geom, ref, f_ref, vr, n, u, v)
    plane = n[0] * origin[0] + n[1] * origin[1] + n[2] * origin[2]
    t = 0
    for j in range(nvi):
        if n[0] * vi[j, 0] + n[1] * vi[j, 1] + n[2] * vi[j, 2] - plane <= tolerance and t < touching.shape[0]:
            touching[t] = j
            t += 1
    if t == 0:
        return 0, VERTEX_FACE
    # the two touching vertices farthest apart in the face plane, and how far the others lie off their line
    ip, iq, longest = touching[0], touching[0], 0.0
    for a in range(t):
        for b in range(a + 1, t):
            pa, pb = vi[touching[a]], vi[touching[b]]
            du = (pb[0] - pa[0]) * u[0] + (pb[1] - pa[1]) * u[1] + (pb[2] - pa[2]) * u[2]
            dv = (pb[0] - pa[0]) * v[0] + (pb[1] - pa[1]) * v[1] + (pb[2] - pa[2]) * v[2]
            if du * du + dv * dv > longest:
                ip, iq, longest = touching[a], touching[b], du * du + dv * dv
    longest = math.sqrt(longest)
    p, q = vi[ip], vi[iq]
    p2u = (p[0] - origin[0]) * u[0] + (p[1] - origin[1]) * u[1] + (p[2] - origin[2]) * u[2]
    p2v = (p[0] - origin[0]) * v[0] + (p[1] - origin[1]) * v[1] + (p[2] - origin[2]) * v[2]
    q2u = (q[0] - origin[0]) * u[0] + (q[1] - origin[1]) * u[1] + (q[2] - origin[2]) * u[2]
    q2v = (q[0] - origin[0]) * v[0] + (q[1] - origin[1]) * v[1] + (q[2] - origin[2]) * v[2]
    if longest > 0.0:
        for a in range(t):
            w = vi[touching[a]]
            wu = (w[0] - origin[0]) * u[0] + (w[1] - origin[1]) * u[1] + (w[2] - origin[2]) * u[2]
            wv = (w[0] - origin[0]) * v[0] + (w[1] - origin[1]) * v[1] + (w[2] - origin[2]) * v[2]
            off = abs((q2u - p2u) * (wv - p2v) - (q2v - p2v) * (wu - p2u)) / longest
            if 0.5 * off * longest > 1e-8 * small * small:  # a triangle of touching vertices with an area: a face
                return 0, FACE_FACE
    n_ref = _face_2d(geom, ref, f_ref, vr, origin, u, v, face_a)
    tol2d = 1e-9 * small
    if longest <= tol2d:  # one vertex
        deepest = ip
        for a in range(t):
            w = vi[touching[a]]
            if n[0] * w[0] + n[1] * w[1] + n[2] * w[2] < n[0] * vi[deepest, 0] + n[1] * vi[deepest, 1] + n[2] * vi[deepest, 2]:
                deepest = touching[a]
        w = vi[deepest]
        wu = (w[0] - origin[0]) * u[0] + (w[1] - origin[1]) * u[1] + (w[2] - origin[2]) * u[2]
        wv = (w[0] - origin[0]) * v[0] + (w[1] - origin[1]) * v[1] + (w[2] - origin[2]) * v[2]
        if not _inside(face_a, n_ref, wu, wv, tol2d):
            return 0, VERTEX_FACE
        gap = n[0] * w[0] + n[1] * w[1] + n[2] * w[2] - plane
        kept = _put(found, k, 0, w[0] - gap * n[0], w[1] - gap * n[1], w[2] - gap * n[2], gap,
                    _point_area(geom, ref, f_ref, vr, n, inc, vi, ni, nfi, along, across, across_axis))
        return kept, VERTEX_FACE
    kept = _segment_on_face(found, k, geom, ref, f_ref, vr, inc, vi, ni, nfi, p, q, origin, u, v, n, plane, face_a, n_ref, tol2d, tolerance,
                            along, across, across_axis)
    return kept, EDGE_FACE


@numba.njit(cache=True)
def _segment_on_face(found, k, geom, ref, f_ref, vr, inc, vi, ni, nfi, p, q, origin, u, v, n, plane, face_a, n_ref, tol2d, tolerance,
                     along, across, across_axis):
    """Edge-face points of the segment p-q (an edge of block ``inc``, of face normals ``ni``,
    ``nfi`` faces) on the reference face ``f_ref`` of block ``ref`` (``face_a``, its
    ``n_ref`` corners in the frame ``origin``, ``u``, ``v``; plane n . x = ``plane``): the segment
    clipped to the face (Cyrus-Beck), points along it at the spacing of the faces' grid
    (:func:`_blended_lengths`), each its trapezoid share of the clipped length times the end row's
    width across (:func:`_end_share`), those within ``tolerance`` of the plane kept; returns how many."""
    p2u = (p[0] - origin[0]) * u[0] + (p[1] - origin[1]) * u[1] + (p[2] - origin[2]) * u[2]
    p2v = (p[0] - origin[0]) * v[0] + (p[1] - origin[1]) * v[1] + (p[2] - origin[2]) * v[2]
    du = (q[0] - p[0]) * u[0] + (q[1] - p[1]) * u[1] + (q[2] - p[2]) * u[2]
    dv = (q[0] - p[0]) * v[0] + (q[1] - p[1]) * v[1] + (q[2] - p[2]) * v[2]
    longest = math.sqrt(du * du + dv * dv)
    if not longest > tol2d:  # a segment along the normal: no length on the face
        return 0
    s0, s1 = 0.0, 1.0
    for e in range(n_ref):
        ax, ay = face_a[e, 0], face_a[e, 1]
        ex, ey = face_a[(e + 1) % n_ref, 0] - ax, face_a[(e + 1) % n_ref, 1] - ay
        c0 = ex * (p2v - ay) - ey * (p2u - ax) + tol2d * math.sqrt(ex * ex + ey * ey)  # inside: c0 + s c1 >= 0
        c1 = ex * dv - ey * du
        if c1 == 0.0:
            if c0 < 0.0:
                return 0
        elif c1 > 0.0:
            s0 = max(s0, -c0 / c1)
        else:
            s1 = min(s1, -c0 / c1)
    length = (s1 - s0) * longest
    if not (tol2d < length < np.inf):  # nothing left of it (or not a number: no contact)
        return 0
    dx, dy = du / longest, dv / longest
    axis_u = across_axis[0] * u[0] + across_axis[1] * u[1] + across_axis[2] * u[2]
    axis_v = across_axis[0] * v[0] + across_axis[1] * v[1] + across_axis[2] * v[2]
    if abs(dx * axis_u + dy * axis_v) > 0.999:  # along the model's across axis (as _count)
        n_along, n_width = across, along
    else:
        n_along, n_width = along, across
    edge = math.sqrt((q[0] - p[0]) ** 2 + (q[1] - p[1]) ** 2 + (q[2] - p[2]) ** 2)
    direction = ((q[0] - p[0]) / edge, (q[1] - p[1]) / edge, (q[2] - p[2]) / edge)
    length_along, length_across = _blended_lengths(geom, ref, f_ref, vr, n, inc, vi, ni, nfi, direction)
    width = _end_share(length_across, n_width)
    # points at the face grid's spacing, at most as many as the row has room for
    intervals = 0 if n_along == 1 else int(max(1.0, min(math.ceil(length / _spacing(length_along, n_along) - 1e-6), found.gaps.shape[1] - 1.0)))
    nodes, weights = _trapezoid(intervals)
    kept = 0
    for i in range(nodes.shape[0]):
        s = s0 + nodes[i] * (s1 - s0)
        x0, x1, x2 = p[0] + s * (q[0] - p[0]), p[1] + s * (q[1] - p[1]), p[2] + s * (q[2] - p[2])
        gap = n[0] * x0 + n[1] * x1 + n[2] * x2 - plane
        if gap <= tolerance:
            kept = _put(found, k, kept, x0 - gap * n[0], x1 - gap * n[1], x2 - gap * n[2], gap, weights[i] * length * width)
    return kept


@numba.njit(cache=True)
def _crossed_area(geom, ia, ib, va, na, vb, nb, ea, eb, edge_a, edge_b, axis, along, across, across_axis):
    """Nominal area of crossed edges (``edge_a`` of A, ``edge_b`` of B, ``axis`` from A to B), m2:
    :func:`_corner_area` of A's face of the edge most along the axis and B's most opposed to it."""
    f_ref, f_inc = ea[edge_a, 2], eb[edge_b, 2]
    if _dot(na[ea[edge_a, 3]], axis) > _dot(na[f_ref], axis):
        f_ref = ea[edge_a, 3]
    if _dot(nb[eb[edge_b, 3]], axis) < _dot(nb[f_inc], axis):
        f_inc = eb[edge_b, 3]
    return _corner_area(geom, ia, f_ref, va, na[f_ref], ib, f_inc, vb, nb[f_inc], along, across, across_axis)


@numba.njit(cache=True)
def _edge_along_face(found, k, geom, ia, ib, va, vb, na, nb, nfa, nfb, ea, eb, edge_a, edge_b, axis, tolerance, along, across,
                     across_axis, u, v, face_a, small):
    """Crossed edges (``edge_a`` of A, ``edge_b`` of B, edge-pair ``axis`` from A to B) where one
    edge runs along a face of the other's are an edge-face contact: that face the reference, the
    edge clipped to it (:func:`_segment_on_face`). E.g. a slab's top edge under a block's tilted
    bed face, running past it on both sides: the face normals' separation is the deep one of the
    slab's far corners, the edge axis wins, and one crossed-edge point would leave the edge's
    other crossing of the face unseen. Along a face: the edge within :data:`FACE_SINE` of its
    plane and the face's outward normal within 0.2 rad (:data:`FACE_COSINE`) of the axis (two
    nearly parallel ridges crossing would otherwise pass with any face, and a normal 45 deg off).
    An edge along both faces of the other edge crosses a shallow ridge: crossed edges (either
    face would tilt the normal by the ridge's slope, to a side round-off picks). The edge and
    face most nearly parallel; written into row ``k`` (kind, reference, normal, points); returns whether it was one."""
    best_sine, best_side, best_face = FACE_SINE, -1, -1
    for side in range(2):
        verts, edges, edge = (va, ea, edge_a) if side == 0 else (vb, eb, edge_b)
        normals, other_edges, other_edge = (nb, eb, edge_b) if side == 0 else (na, ea, edge_a)
        outward = -1.0 if side == 0 else 1.0  # the reference face's outward normal is along -axis on B, +axis on A
        p, q = verts[edges[edge, 0]], verts[edges[edge, 1]]
        length = math.sqrt((q[0] - p[0]) ** 2 + (q[1] - p[1]) ** 2 + (q[2] - p[2]) ** 2)
        along_faces = 0
        for j in range(2, 4):
            f = other_edges[other_edge, j]
            m = normals[f]
            sine = abs(_dot(m, (q[0] - p[0], q[1] - p[1], q[2] - p[2]))) / length
            facing = outward * _dot(m, axis)
            if sine <= FACE_SINE and facing >= FACE_COSINE:
                along_faces += 1
                if sine <= best_sine:
                    best_sine, best_side, best_face = sine, side, f
        if along_faces == 2:
            return False
    if best_side < 0:
        return False
    if best_side == 0:
        ref, inc, vr, vi, ni, nfi, n, p, q = ib, ia, vb, va, na, nfa, nb[best_face], va[ea[edge_a, 0]], va[ea[edge_a, 1]]
    else:
        ref, inc, vr, vi, ni, nfi, n, p, q = ia, ib, va, vb, nb, nfb, na[best_face], vb[eb[edge_b, 0]], vb[eb[edge_b, 1]]
    origin = _face_frame(geom, ref, best_face, vr, n, u, v)
    plane = n[0] * origin[0] + n[1] * origin[1] + n[2] * origin[2]
    n_ref = _face_2d(geom, ref, best_face, vr, origin, u, v, face_a)
    kept = _segment_on_face(found, k, geom, ref, best_face, vr, inc, vi, ni, nfi, p, q, origin, u, v, n, plane, face_a, n_ref, 1e-9 * small,
                            tolerance, along, across, across_axis)
    if kept == 0:
        return False
    found.count[k], found.kind[k] = kept, EDGE_FACE
    found.ref[k], found.inc[k] = ref, inc
    found.normal[k] = n
    return True


@numba.njit(cache=True)
def _pair(geom, position, rotation, k, ia, ib, tolerance, along, across, across_axis, found, uv, area, face_a, face_b, overlap, corners,
          va, vb, na, nb, ea, eb, touching, u, v, axis):
    """The contact of candidate pair ``k`` (blocks ia, ib) into row ``k`` of ``found`` (module
    docstring; a count of -1: its points outgrew the row); the scratch buffers are the caller's.
    Returns the ``overlap``, ``corners``, ``uv`` and ``area`` buffers (grown if a polygon or its
    points outgrew them)."""
    found.count[k] = 0
    found.kind[k] = FACE_FACE
    nva, nfa = _world(geom, ia, position, rotation, va, na)
    nvb, nfb = _world(geom, ib, position, rotation, vb, nb)
    fa, sa = _separations(geom, ia, va, na, nfa, vb, nvb)
    fb, sb = _separations(geom, ib, vb, nb, nfb, va, nva)
    small = min(geom.size[ia], geom.size[ib])
    if sa >= sb - 1e-9 * small:
        ref, inc, vr, nr, vi, ni, nvi, nfi, f_ref, separation = ia, ib, va, na, vb, nb, nvb, nfb, fa, sa
    else:
        ref, inc, vr, nr, vi, ni, nvi, nfi, f_ref, separation = ib, ia, vb, nb, va, na, nva, nfa, fb, sb
    found.separation[k] = separation
    if separation > tolerance:
        return overlap, corners, uv, area
    n = nr[f_ref]
    f_inc, cos_ni = _most_opposed(ni, nfi, n)
    # crossed edges: the edge-pair axes of the separating-axis test. Not needed for nearly
    # parallel faces penetrating less than the tolerance (a face contact, the common case: a
    # bed joint), only where the faces' separation may be a wrong deep one (shallow crossed roofs)
    parallel_faces = cos_ni <= -FACE_COSINE
    edge_wins, s_edge, edge_a, edge_b = False, -np.inf, -1, -1
    if not parallel_faces or separation < -tolerance:
        nea, neb = _edges(geom, ia, ea), _edges(geom, ib, eb)
        s_edge, edge_a, edge_b = _edge_axes(va, nva, na, ea, nea, vb, nvb, nb, eb, neb, 1e-9 * small, axis)
        edge_wins = s_edge > separation + 1e-9 * small
        if parallel_faces and edge_wins and s_edge > separation + tolerance:
            parallel_faces = False
    if not parallel_faces and edge_wins:
        found.separation[k] = s_edge
        found.kind[k] = EDGE_EDGE
        if s_edge > tolerance:
            return overlap, corners, uv, area
        if _edge_along_face(found, k, geom, ia, ib, va, vb, na, nb, nfa, nfb, ea, eb, edge_a, edge_b, axis, tolerance, along, across,
                            across_axis, u, v, face_a, small):
            return overlap, corners, uv, area
        area_m2 = _crossed_area(geom, ia, ib, va, na, vb, nb, ea, eb, edge_a, edge_b, axis, along, across, across_axis)
        found.count[k] = _crossed_edges(found, k, va, ea, edge_a, vb, eb, edge_b, axis, tolerance, area_m2)
        found.ref[k], found.inc[k] = ia, ib
        for c in range(3):
            found.normal[k, c] = axis[c]
        return overlap, corners, uv, area
    if not parallel_faces:
        kept, kind = _features(found, k, geom, ref, f_ref, vr, n, inc, vi, nvi, ni, nfi, touching, tolerance, along, across, across_axis,
                               u, v, face_a, small)
        if kind != FACE_FACE:
            found.kind[k] = kind
            found.count[k] = kept
            found.ref[k], found.inc[k] = ref, inc
            found.normal[k] = n
            return overlap, corners, uv, area
    # face-face
    if cos_ni >= -1e-6:
        return overlap, corners, uv, area
    origin = _face_frame(geom, ref, f_ref, vr, n, u, v)
    n_ref_2d = _face_2d(geom, ref, f_ref, vr, origin, u, v, face_a)
    n_inc_2d = _face_2d(geom, inc, f_inc, vi, origin, u, v, face_b)
    overlap, n_overlap = _clip(face_b, n_inc_2d, face_a, n_ref_2d, overlap)
    if n_overlap < 3 or _area(overlap, n_overlap) <= 1e-8 * small * small:
        return overlap, corners, uv, area
    sliver = SLIVER_FRACTION * min(_area(face_a, n_ref_2d), _area(face_b, n_inc_2d))
    au = across_axis[0] * u[0] + across_axis[1] * u[1] + across_axis[2] * u[2]
    av = across_axis[0] * v[0] + across_axis[1] * v[1] + across_axis[2] * v[2]
    nodes, corners, uv, area = _grid(overlap, n_overlap, corners, face_a, n_ref_2d, face_b, n_inc_2d, along, across, au, av, 1e-9 * small, sliver, uv, area)
    n_inc = ni[f_inc]
    inc_first = vi[geom.face_vertex[geom.face_start[geom.block_face_start[inc] + f_inc]]]
    plane = n_inc[0] * inc_first[0] + n_inc[1] * inc_first[1] + n_inc[2] * inc_first[2]
    found.count[k] = _keep_points(found, k, nodes, uv, area, origin, u, v, n_inc, plane, cos_ni, tolerance, sliver)
    found.ref[k], found.inc[k] = ref, inc
    found.normal[k] = n
    return overlap, corners, uv, area


#: candidate pairs per parallel chunk of :func:`find_sub_contacts` (each chunk allocates its own scratch buffers once)
CHUNK = 64


@numba.njit(cache=True, parallel=True)
def find_sub_contacts(geom, position, rotation, candidates, tolerance, along, across, across_axis, found):
    """Fill ``found`` (a :class:`Found` with room for the candidates and :func:`max_points`
    points each) for every candidate pair (i < j), in parallel over chunks of :data:`CHUNK`
    pairs; each pair writes only its own row, so the result is the same for any thread count.
    Rows of at least ``max_points(along, across, 0)`` (a bilinear grid's points); a pair whose
    points outgrew its row (a lumped grid's, :func:`find` sizes the rows for them) has count -1."""
    # polygons: a face as large as the largest, an overlap of two (at most both faces' vertices)
    largest = _largest(geom.face_start)
    m = found.gaps.shape[1]
    if found.count.shape[0] < candidates.shape[0] or m < max_points(along, across, 0):
        raise ValueError("found has too little room for the candidates' points")
    # the two blocks' world geometry, in buffers for the largest block (no allocation per pair)
    largest_v, largest_f = _largest(geom.vertex_start), _largest(geom.block_face_start)
    largest_e = 0  # face-loop entries of the block with most: at least twice its edges
    for b in range(geom.block_face_start.shape[0] - 1):
        largest_e = max(largest_e, geom.face_start[geom.block_face_start[b + 1]] - geom.face_start[geom.block_face_start[b]])
    n = candidates.shape[0]
    for chunk in numba.prange((n + CHUNK - 1) // CHUNK):
        uv, area = np.empty((m, 2)), np.empty(m)
        face_a, face_b = np.empty((largest, 2)), np.empty((largest, 2))
        overlap, corners = np.empty((2 * largest, 2)), np.empty((2 * largest, 2))
        va, vb = np.empty((largest_v, 3)), np.empty((largest_v, 3))
        na, nb = np.empty((largest_f, 3)), np.empty((largest_f, 3))
        ea, eb = np.empty((largest_e, 4), np.int64), np.empty((largest_e, 4), np.int64)
        touching = np.empty(largest_v, np.int64)
        u, v, axis = np.empty(3), np.empty(3), np.empty(3)
        for k in range(chunk * CHUNK, min(n, (chunk + 1) * CHUNK)):
            overlap, corners, uv, area = _pair(geom, position, rotation, k, candidates[k, 0], candidates[k, 1], tolerance, along, across,
                                               across_axis, found, uv, area, face_a, face_b, overlap, corners, va, vb, na, nb, ea, eb,
                                               touching, u, v, axis)


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
        if found.count[k] <= 0:
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


def find(
    geometry: FlatGeometry, candidates: np.ndarray, position: np.ndarray, rotation: np.ndarray, *, tolerance: float,
    density: ContactDensity,
) -> Found:
    """The :class:`Found` of the candidate block pairs (k, 2) at centroids ``position`` (nb, 3) m
    and rotations (nb, 3, 3): one compiled call (:func:`find_sub_contacts`), again with rows twice
    as wide where a contact's points outgrew :func:`max_points` (round-off; not seen)."""
    pairs = np.ascontiguousarray(candidates, dtype=np.int64).reshape(-1, 2)
    width = max_points(density.along, density.across, _largest_face(geometry, pairs))
    while True:
        found = Found.empty(len(candidates), width)
        find_sub_contacts(
            geometry, np.ascontiguousarray(position, dtype=float), np.ascontiguousarray(rotation, dtype=float),
            pairs, tolerance, density.along, density.across, np.asarray(density.across_axis, dtype=float), found,
        )
        if (found.count >= 0).all():
            return found
        width *= 2


def _largest_face(geometry: FlatGeometry, pairs: np.ndarray) -> int:
    """The most vertices of a face of the blocks of ``pairs`` (k, 2); 0 for none (the rows of a
    re-detection of bricks stay narrow in a model with one many-sided drum)."""
    if not len(pairs):
        return 0
    per_block = np.maximum.reduceat(np.diff(geometry.face_start), geometry.block_face_start[:-1])
    return int(per_block[pairs].max())


def contact_kinds(found: Found) -> np.ndarray:
    """(nc,) the kind of each contact of ``found`` with points, in the order of :func:`assemble`'s contacts."""
    return found.kind[found.count > 0].copy()


def kind_counts(
    geometry: FlatGeometry, pairs: np.ndarray, position: np.ndarray, rotation: np.ndarray, *, tolerance: float,
    density: ContactDensity,
) -> dict[str, int]:
    """How many of the contacts of block ``pairs`` (k, 2) at centroids ``position`` (nb, 3) m and
    rotations (nb, 3, 3) are of each kind, by :data:`KIND_NAMES`."""
    kinds = contact_kinds(find(geometry, pairs, position, rotation, tolerance=tolerance, density=density))
    return {name: int((kinds == kind).sum()) for kind, name in enumerate(KIND_NAMES)}


def narrow_phase(
    geometry: FlatGeometry, candidates: np.ndarray, position: np.ndarray, rotation: np.ndarray, *, tolerance: float,
    density: ContactDensity,
) -> tuple[SubContacts, np.ndarray]:
    """Sub-contacts of the candidate block pairs (k, 2) at centroids ``position`` (nb, 3) m and
    rotations (nb, 3, 3), in one compiled call (:func:`find_sub_contacts`), and each pair's
    separation along its best separating axis (k,) m (a lower bound on their distance when positive).
    Shear forces start at zero (:func:`drydem.engine.refresh.merge` carries them over)."""
    found = find(geometry, candidates, position, rotation, tolerance=tolerance, density=density)
    return SubContacts(*assemble(found, position, rotation)), found.separation


compiled_cache.check(__name__)  # last: none of the functions above is loaded from a stale cache
