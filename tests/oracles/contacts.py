"""The narrow phase and the shear carry-over in plain Python, one pair at a time: the tests' oracles
of :mod:`drydem.engine.narrow_phase` and :func:`drydem.engine.refresh.merge`.

Two convex blocks touch where a face of one (the *reference* face) lies within
the contact tolerance of the other block. The reference face is the one of
least penetration among both blocks' faces (separating-axis test restricted to
face normals); the *incident* face is the other block's face most opposed to
it. The incident face, projected on the reference plane and clipped by the
reference face, is the contact polygon.

The polygon is discretised into sub-contacts as 3DEC's contact points: a
tensor grid whose spacing puts ``points_per_length`` points along the full
length of the smaller face, ends included, each point carrying its trapezoid
share of the area (the areas sum to the polygon's area); see :func:`_grid`.
In-plane models need only 1 point across the width, on the mid-plane (:class:`drydem.model.parameters.ContactDensity`).
Each sub-contact is a pair of material points (one on each block, the incident one on the incident face
straight above the reference one) and the reference normal, all stored in the
blocks' body frames, so rocking opens or closes them as the blocks turn.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from drydem.engine.contacts import SubContacts, world_points
from drydem.engine.narrow_phase import SLIVER_FRACTION, Found, assemble
from drydem.model.geometry import ConvexPolyhedron, best_separation
from drydem.model.parameters import ContactDensity
from oracles import polygon


def concatenate(first: SubContacts, second: SubContacts) -> SubContacts:
    """Both sets of contacts in one SubContacts (``first``'s contacts first); with :func:`subset`
    and :func:`carry_over`, the NumPy oracle of :func:`drydem.engine.refresh.merge`."""
    start = np.concatenate([first.start, second.start[1:] + first.start[-1]])
    joined = {name: np.concatenate([getattr(first, name), getattr(second, name)]) for name in SubContacts._fields if name != "start"}
    return SubContacts(start=start, **joined)


@dataclass(frozen=True)
class _FaceContact:
    ref: int
    inc: int
    points: np.ndarray  # (k, 3) world points on the reference face
    gaps: np.ndarray  # (k,) m, distance along the normal to the incident face
    areas: np.ndarray  # (k,) m2
    normal: np.ndarray  # (3,) reference outward normal, world


def face_contact(
    a: ConvexPolyhedron, b: ConvexPolyhedron, ia: int, ib: int, *, tolerance: float, density: ContactDensity
) -> tuple[_FaceContact | None, float]:
    """Sub-contact points between blocks ``ia`` and ``ib`` (None if they do not touch), and their
    separation along the best face normal, m (a lower bound on their distance when positive)."""
    separation, ref_is_a, f_ref = best_separation(a, b)
    if separation > tolerance:
        return None, separation
    ref, inc, i_ref, i_inc = (a, b, ia, ib) if ref_is_a else (b, a, ib, ia)
    n = ref.face_normals[f_ref]
    f_inc = int(np.argmin(inc.face_normals @ n))
    n_inc = inc.face_normals[f_inc]
    if np.dot(n_inc, n) >= -1e-6:
        return None, separation
    ref_poly3 = ref.face_polygon(f_ref)
    origin = ref_poly3[0]
    edges = np.roll(ref_poly3, -1, axis=0) - ref_poly3
    u = edges[np.argmax(np.einsum("ij,ij->i", edges, edges))]
    u = u / np.linalg.norm(u)
    v = np.cross(n, u)
    basis = np.stack([u, v])
    ref_poly = polygon.counter_clockwise((ref_poly3 - origin) @ basis.T)
    inc_poly = polygon.counter_clockwise((inc.face_polygon(f_inc) - origin) @ basis.T)
    overlap = polygon.clip(inc_poly, ref_poly)
    small = min(ref.size, inc.size)
    if len(overlap) < 3 or polygon.signed_area(overlap) <= 1e-8 * small**2:
        return None, separation
    counts = _PointCounts(density, basis @ np.asarray(density.across_axis))
    sliver = SLIVER_FRACTION * min(polygon.signed_area(ref_poly), polygon.signed_area(inc_poly))
    uv, areas = _grid(overlap, ref_poly, inc_poly, counts, 1e-9 * small, sliver)
    points = origin + uv @ basis
    # distance from each point, along n, to the incident face plane
    gaps = (n_inc @ inc.face_polygon(f_inc)[0] - points @ n_inc) / np.dot(n_inc, n)
    keep = (gaps <= tolerance) & (areas > sliver)
    if not np.any(keep):
        return None, separation
    return _FaceContact(i_ref, i_inc, points[keep], gaps[keep], areas[keep], n), separation


class _PointCounts:
    """Points over a full face length along a grid direction (2D, in the reference plane)."""

    def __init__(self, density: ContactDensity, across_2d: np.ndarray):
        self.along, self.across, self.across_2d = density.along, density.across, across_2d

    def __call__(self, direction: np.ndarray) -> int:
        return self.across if abs(float(direction @ self.across_2d)) > 0.999 else self.along


def _grid(
    overlap: np.ndarray, face_a: np.ndarray, face_b: np.ndarray, counts: _PointCounts, tol: float, sliver: float
) -> tuple[np.ndarray, np.ndarray]:
    """Grid nodes (k, 2) and their tributary areas (k,) on the contact polygon ``overlap``.

    Along each grid direction the spacing is the smaller face's extent / (n - 1), n from
    ``counts``; the overlap is split into the fewest equal intervals not longer than that (at
    most n, see :func:`_intervals`), with nodes at both ends (trapezoid rule). A quadrilateral
    overlap (the usual face-on-face case, also when the blocks are turned or rocking) gets a
    bilinear grid between its corners, so the corners are always points and an affine image of
    a face maps back to the same material points. Other polygons get an axis-aligned lumped grid
    (:func:`_lumped_grid`): points where its lines cross inside the polygon, where they cross its
    sides and at its corners, so that the points span the whole polygon (a block rocks on its
    outermost corner) and give its area and first moments (less dropped slivers; across an axis
    of one point, its points lie on the middle line). n = 1 in both directions: one node at the
    polygon's centroid.

    A node of at most ``sliver`` m2 is a sliver (:data:`oracles.SLIVER_FRACTION`), which
    :func:`face_contact` drops; a piece of the lumped grid that small is left out here already.
    """
    if counts.along == 1 and counts.across == 1:
        return polygon.centroid(overlap)[None, :], np.array([polygon.signed_area(overlap)])
    corners = polygon.without_collinear(overlap, tol)
    if len(corners) == 4:
        return _bilinear_grid(corners, face_a, face_b, counts)
    return _lumped_grid(overlap, face_a, face_b, counts, tol, sliver)


def _intervals(length: float, direction: np.ndarray, face_a: np.ndarray, face_b: np.ndarray, n: int) -> int:
    """Fewest equal intervals over ``length`` with spacing <= smaller face extent along ``direction`` / (n - 1),
    and at most n; 0 for n = 1 (a single point in the middle).

    An overlap is no longer than the faces along a direction, so n - 1 intervals span it. A side
    of a quadrilateral overlap can be longer than the faces' extent along the bilinear grid's
    direction (the mean of two opposite sides): a little where the blocks are turned a little
    (n intervals), much where the quadrilateral is skewed. The cap at n bounds a contact's points
    (:func:`drydem.engine.narrow_phase.max_points`) and leaves the first case as it was."""
    if n == 1:
        return 0
    extent = min(np.ptp(face_a @ direction), np.ptp(face_b @ direction))
    return max(1, math.ceil(min(length / (extent / (n - 1)) - 1e-6, n)))


def _trapezoid(intervals: int) -> tuple[np.ndarray, np.ndarray]:
    """Nodes in [0, 1] and trapezoid weights (summing to 1); no interval: the midpoint."""
    if intervals == 0:
        return np.array([0.5]), np.array([1.0])
    weights = np.full(intervals + 1, 1.0 / intervals)
    weights[[0, -1]] *= 0.5
    return np.linspace(0.0, 1.0, intervals + 1), weights


def _bilinear_grid(quad: np.ndarray, face_a: np.ndarray, face_b: np.ndarray, counts: _PointCounts) -> tuple[np.ndarray, np.ndarray]:
    """X(s, t) = (1-s)(1-t) P0 + s(1-t) P1 + s t P2 + (1-s) t P3; areas w_s w_t |X_s x X_t|, scaled to the exact area."""
    p0, p1, p2, p3 = quad
    axes = []
    for a0, a1, b0, b1 in ((p0, p1, p3, p2), (p0, p3, p1, p2)):
        length = max(np.linalg.norm(a1 - a0), np.linalg.norm(b1 - b0))
        direction = (a1 - a0 + b1 - b0) / np.linalg.norm(a1 - a0 + b1 - b0)
        axes.append(_trapezoid(_intervals(length, direction, face_a, face_b, counts(direction))))
    (s, ws), (t, wt) = axes
    s, t = np.meshgrid(s, t, indexing="ij")
    s, t = s.ravel()[:, None], t.ravel()[:, None]
    nodes = (1 - s) * (1 - t) * p0 + s * (1 - t) * p1 + s * t * p2 + (1 - s) * t * p3
    dx_ds = (1 - t) * (p1 - p0) + t * (p2 - p3)
    dx_dt = (1 - s) * (p3 - p0) + s * (p2 - p1)
    jacobian = np.abs(dx_ds[:, 0] * dx_dt[:, 1] - dx_ds[:, 1] * dx_dt[:, 0])
    areas = np.outer(ws, wt).ravel() * jacobian
    return nodes, areas * (polygon.signed_area(quad) / areas.sum())


def _lumped_grid(
    overlap: np.ndarray, face_a: np.ndarray, face_b: np.ndarray, counts: _PointCounts, tol: float, sliver: float
) -> tuple[np.ndarray, np.ndarray]:
    """Grid lines through the trapezoid nodes of each axis cut the polygon into pieces; each
    piece's area goes to its vertices (:func:`oracles.polygon.vertex_shares`); vertices within
    ``tol`` of each other are one point. An axis of one point (n = 1) has its two ends as lines,
    and its points move to the middle."""
    lo, hi = overlap.min(0), overlap.max(0)
    lines, middle = [], []
    for k in range(2):
        direction = np.eye(2)[k]
        intervals = _intervals(hi[k] - lo[k], direction, face_a, face_b, counts(direction))
        nodes = _trapezoid(intervals)[0] if intervals else np.array([0.0, 1.0])
        lines.append(np.r_[lo[k] + nodes[:-1] * (hi[k] - lo[k]), hi[k]])  # the outer lines on the polygon's extremes
        middle.append(np.nan if intervals else 0.5 * (lo[k] + hi[k]))
    points, areas = [], []
    for i, j in itertools.product(range(len(lines[0]) - 1), range(len(lines[1]) - 1)):
        piece = polygon.clip(overlap, polygon.rectangle(lines[0][i], lines[0][i + 1], lines[1][j], lines[1][j + 1]))
        if polygon.signed_area(piece) <= sliver:
            continue
        for vertex, share in zip(piece, polygon.vertex_shares(piece)):
            point = np.where(np.isnan(middle), vertex, middle)
            near = [p for p, q in enumerate(points) if np.abs(q - point).max() <= tol]
            if near:
                areas[near[0]] += share
            else:
                points.append(point)
                areas.append(share)
    return np.array(points).reshape(-1, 2), np.array(areas)


def narrow_phase(
    shapes: dict[int, ConvexPolyhedron],
    candidates: np.ndarray,
    position: np.ndarray,
    rotation: np.ndarray,
    *,
    tolerance: float,
    density: ContactDensity,
) -> tuple[SubContacts, np.ndarray]:
    """Sub-contacts of the candidate block pairs (k, 2), from the blocks' world geometry
    ``shapes`` (by block index, at centroids ``position`` (nb, 3) and rotations (nb, 3, 3)).
    Shear forces start at zero (see :func:`carry_over`). Also returns each candidate pair's
    separation (k,), m (see :func:`face_contact`).

    Plain Python, one pair at a time: the oracle of :func:`drydem.engine.narrow_phase.narrow_phase`.
    """
    faces = []
    separations = np.empty(len(candidates))
    for k, (ia, ib) in enumerate(candidates):
        fc, separations[k] = face_contact(shapes[ia], shapes[ib], int(ia), int(ib), tolerance=tolerance, density=density)
        if fc is not None:
            faces.append(fc)
    found = Found.empty(len(faces), max([len(fc.areas) for fc in faces], default=0))
    for k, fc in enumerate(faces):
        n = len(fc.areas)
        found.count[k], found.ref[k], found.inc[k], found.normal[k] = n, fc.ref, fc.inc, fc.normal
        found.points[k, :n], found.gaps[k, :n], found.areas[k, :n] = fc.points, fc.gaps, fc.areas
    return SubContacts(*assemble(found, position, rotation)), separations


def carry_over(old: SubContacts, new: SubContacts, position: np.ndarray, rotation: np.ndarray) -> None:
    """Copy shear stress (N/m2) and intact flags from ``old`` to the nearest ``new`` sub-contact
    of the same block pair, projected on the new tangent plane (the oracle of
    :func:`drydem.engine.refresh.merge`, which the simulation uses; this one looks among the 8 nearest
    old points only).

    Shear force is stored as the force on the incident block, so it changes sign where the two
    blocks swapped roles. Sub-contacts with no old neighbour of their pair start with zero shear.
    """
    if not (old.count and new.count):
        return
    x_old, _, _ = world_points(old, position, rotation)
    x_new, _, n_new = world_points(new, position, rotation)
    nb = len(position)
    key_old, key_new = old.pair_keys(nb)[old.contact], new.pair_keys(nb)[new.contact]
    k = min(8, old.count)
    _, idx = cKDTree(x_old).query(x_new, k=k)
    idx = idx.reshape(len(x_new), k)
    match = key_old[idx] == key_new[:, None]
    has = match.any(axis=1)
    first = idx[np.arange(len(idx)), np.argmax(match, axis=1)][has]
    sign = np.where(old.block_inc[first] == new.block_inc[has], 1.0, -1.0)
    stress = old.shear_force[first] / old.area[first, None] * sign[:, None]
    n = n_new[has]
    stress -= np.einsum("ni,ni->n", stress, n)[:, None] * n
    new.shear_force[has] = stress * new.area[has, None]
    new.intact[has] = old.intact[first]
