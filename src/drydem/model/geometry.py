"""Convex polyhedra: faces, volume, centroid and inertia tensor.

A block is the convex hull of its vertices (computed with Qhull through
``scipy.spatial.ConvexHull``); coplanar hull triangles are merged into polygonal
faces whose vertices run counter-clockwise seen from outside, so every face has
an outward unit normal. An axis-aligned box (:func:`box`: every brick of a wall
file, and vertices that are a box's 8 corners, :func:`box_corners`) is built in
closed form, with the hull's faces and no Qhull.

Mass properties are exact for the polyhedron: it is split into tetrahedra
(centroid of the vertices, and a fan of each face), and each tetrahedron with
vertices v0..v3 and volume V contributes the second moment

    integral x x^T dV = V / 20 (sum_i v_i v_i^T + s s^T),   s = sum_i v_i

(e.g. Tonon 2004, J. Math. Stat. 1, "Explicit exact formulas for the 3-D
tetrahedron inertia tensor"). The inertia tensor about the centroid is
I = rho (trace(C) 1 - C) with C the second moment about the centroid.
"""

from __future__ import annotations

import math
from dataclasses import InitVar, dataclass, field
from functools import cached_property
from typing import TYPE_CHECKING, NamedTuple

import numpy as np

from drydem.errors import GeometryError
from drydem.model.parameters import is_number, shown

if TYPE_CHECKING:
    from scipy.spatial import ConvexHull

#: fraction of a block's size (its bounding box's diagonal) within which a point is on the hull,
#: on a face's plane or on an edge (:func:`convex_hull`, :func:`face_interior_points`)
HULL_TOLERANCE = 1e-6
#: a face folded by its corners' rounding is one face: hull triangles whose normals differ from
#: the face's largest triangle's by less than FOLD_ANGLE_RAD and whose corners lie within
#: FOLD_TOLERANCE of the block's size (1e-4: 0.02 mm on a 0.2 m brick) of its plane are joined
#: to it (:func:`_coplanar_groups`).
#: A brick turned anyhow and stored in float32, as STL is, 100 m from the origin has its
#: corners 8e-6 m off (1e-4 rad on a 0.1 m face); its faces came out as triangles, and a contact
#: found on one of them had 19 to 63 % of the bed's area. The sides of a 1000-sided prism (the
#: most MAX_BLOCK_VERTICES allows) turn 6.3e-3 rad, and stay apart
FOLD_ANGLE_RAD = 1e-3
FOLD_TOLERANCE = 1e-4
#: the largest coordinate of a vertex, m: 1,000 km; beyond it a model is in another unit (its
#: squares and cubes, areas and volumes, would also leave floating point's range near 1e100)
MAX_COORDINATE_M = 1e6
#: the smallest block, m across (its bounding box's diagonal): a micrometre, a thousandth of the
#: paper's smallest brick dimension; below it a model is in another unit
MIN_BLOCK_SIZE_M = 1e-6
#: the least mean thickness of a block, m, its volume over its size squared: a tenth of
#: MIN_BLOCK_SIZE_M (a cube a third of a micrometre across has it); a brick 0.1 um thick was
#: taken, and its tilt ran on for minutes at a timestep of 0.3 us
MIN_THICKNESS_M = 1e-7
#: the most vertices a block is given by: a 1000-sided prism, 0.1 s to build; masonry units
#: have tens. The hull's check of every vertex against every face is n x 2n numbers (20,000
#: vertices asked 24 GB), and past ~1000 sides the faces of a round block lie closer than
#: HULL_TOLERANCE to one plane and merge (a 5000-sided unit prism came out at 7.3 m3, not 3.14)
MAX_BLOCK_VERTICES = 2000
#: how far from 1 a hand-made polyhedron's face normal may be long (:func:`_faces_problem`): round-off
UNIT_TOLERANCE = 1e-6
#: how far, relatively, a hand-made polyhedron's volume, centroid and second moment may be from
#: those its vertices and faces enclose (:func:`_mass_problem`): round-off, and six digits given
MASS_TOLERANCE = 1e-6


@dataclass(frozen=True, eq=False)
class ConvexPolyhedron:
    """A convex polyhedron in world coordinates (m), frozen (its arrays are read-only).

    Attributes
    ----------
    vertices : (nv, 3) float array, m
        Hull vertices.
    faces : tuple of int arrays
        Each face's vertex indices, counter-clockwise seen from outside.
    face_normals : (nf, 3) float array
        Outward unit normals.
    volume : float, m3
    centroid : (3,) float array, m
    second_moment : (3, 3) float array, m5
        integral (x - c)(x - c)^T dV about the centroid.
    """

    vertices: np.ndarray
    faces: tuple[np.ndarray, ...]
    face_normals: np.ndarray
    volume: float
    centroid: np.ndarray
    second_moment: np.ndarray = field(repr=False)
    #: True where the maker vouches that the faces bound a convex polyhedron of the vertices and
    #: enclose the given volume, centroid and second moment, as :func:`box`, :func:`convex_hull`
    #: and :meth:`transformed` do by construction: those checks (a few hundred microseconds, which
    #: 20,000 bricks would take seconds for) are skipped, not the others
    consistent: InitVar[bool] = False

    def __post_init__(self, consistent: bool):
        problem = _polyhedron_problem(self, consistent)
        if problem is not None:
            raise GeometryError(f"ConvexPolyhedron: {problem} (drydem.box and drydem.convex_hull make a block's polyhedron)")
        object.__setattr__(self, "faces", tuple(map(frozen_array, self.faces)))
        for name in ("vertices", "face_normals", "centroid", "second_moment"):
            object.__setattr__(self, name, frozen_array(getattr(self, name)))

    @cached_property
    def size(self) -> float:
        """Diagonal of the axis-aligned bounding box, m."""
        return float(np.linalg.norm(self.vertices.max(0) - self.vertices.min(0)))

    @cached_property
    def edges(self) -> tuple[np.ndarray, np.ndarray]:
        """The vertex numbers at the tail and head of every face's edges, face by face, each
        edge of a face from a corner to the next counter-clockwise (every edge twice: once in
        each of its two faces)."""
        tails, heads, _ = face_corners(self.faces)
        return tails, heads

    @cached_property
    def edge_directions(self) -> np.ndarray:
        """(E, 3) unit directions of the edges, each direction once (its sign chosen so that its
        first non-zero component is positive; of two that round alike to 1e-9, the first kept
        as it is; a repeat left by round-off changes no separation)."""
        tails, heads = self.edges
        d = self.vertices[heads] - self.vertices[tails]
        d /= np.linalg.norm(d, axis=1)[:, None]
        first = np.argmax(np.abs(d) > 1e-9, axis=1)
        d *= np.sign(d[np.arange(len(d)), first])[:, None]
        _, first_of_each = np.unique(np.round(d, 9), axis=0, return_index=True)
        return d[np.sort(first_of_each)]

    def inertia_tensor(self, density: float) -> np.ndarray:
        """Inertia tensor about the centroid, kg m2: rho (trace(C) 1 - C)."""
        c = self.second_moment
        return density * (np.trace(c) * np.eye(3) - c)

    def face_polygon(self, face: int) -> np.ndarray:
        """(k, 3) vertices of one face, counter-clockwise seen from outside."""
        return self.vertices[self.faces[face]]

    def face_area(self, face: int) -> float:
        """Area of one face, m2 (shoelace formula in 3D)."""
        p = self.face_polygon(face)
        return 0.5 * float(np.linalg.norm(np.cross(p, np.roll(p, -1, axis=0)).sum(0)))

    def transformed(self, rotation: np.ndarray, translation: np.ndarray) -> ConvexPolyhedron:
        """The same polyhedron moved rigidly: x -> R x + t."""
        return ConvexPolyhedron(
            vertices=self.vertices @ rotation.T + translation,
            faces=self.faces,
            face_normals=self.face_normals @ rotation.T,
            volume=self.volume,
            centroid=rotation @ self.centroid + translation,
            second_moment=rotation @ self.second_moment @ rotation.T,
            consistent=True,
        )


def _polyhedron_problem(p: ConvexPolyhedron, consistent: bool) -> str | None:
    """What breaks the invariants of a :class:`ConvexPolyhedron` (one made by hand: the cycles
    would divide by its volume and index its vertices by its faces), None if nothing does.
    Every polyhedron is checked as it is made (:func:`box` makes one per brick of a building), so
    these checks cost a few array passes, no hull: at least 4 finite
    vertices, (n, 3) floats; at least 4 faces of at least 3 vertex numbers each, in range; as many
    finite face normals (3,); a volume above 0 and within the vertices' bounding box; a finite
    centroid (3,) and second moment (3, 3); then, unless ``consistent``, a block's size
    (:func:`_size_problem`), faces that bound a convex polyhedron (:func:`_faces_problem`) and
    the mass properties they enclose (:func:`_mass_problem`)."""
    v = p.vertices
    if not (_floats(v) and v.ndim == 2 and v.shape[0] >= 4 and v.shape[1] == 3):
        return f"vertices must be an (n >= 4, 3) array of finite floats, m, got {described(v)}"
    faces = p.faces
    if not (isinstance(faces, tuple) and len(faces) >= 4 and all(isinstance(f, np.ndarray) and f.dtype.kind in "iu" and f.shape[0] >= 3
                                                                  and f.ndim == 1 for f in faces)):
        return "faces must be a tuple of at least 4 integer arrays, each of at least 3 vertex numbers"
    corners = np.concatenate(faces)
    if corners.min() < 0 or corners.max() >= len(v):
        return f"faces must number vertices 0 to {len(v) - 1}, got {corners.min()} to {corners.max()}"
    if not (_floats(p.face_normals) and p.face_normals.shape == (len(faces), 3)):
        return f"face_normals must be a ({len(faces)}, 3) array of finite floats, got {described(p.face_normals)}"
    side = (v.max(0) - v.min(0)).tolist()
    extent = side[0] * side[1] * side[2]
    if not (is_number(p.volume) and 0.0 < p.volume <= extent * (1.0 + 1e-9)):
        return f"volume = {shown(p.volume)}: must be a number above 0 and at most the vertices' bounding box ({extent:.4g} m3)"
    if not (_floats(p.centroid) and p.centroid.shape == (3,) and _floats(p.second_moment) and p.second_moment.shape == (3, 3)):
        return (f"centroid must be a (3,) and second_moment a (3, 3) array of finite floats, "
                f"got {described(p.centroid)}, {described(p.second_moment)}")
    return None if consistent else _size_problem(v) or _faces_problem(p) or _mass_problem(p)


def _faces_problem(p: ConvexPolyhedron) -> str | None:
    """What makes the faces of ``p`` (its other parts well formed) no convex polyhedron's, within
    FOLD_TOLERANCE of its size (a face :func:`convex_hull` joined of triangles folded by its
    corners' rounding is not quite plane): a normal not of unit length, a face's corners off the plane of
    its normal through its first corner, a vertex outside a face's plane (a normal pointing
    inward, or a polyhedron not convex), a face with no area or running clockwise about its
    normal (found by a hunt: inward normals, zero normals and repeated corners were taken, and
    the block sank through its base or cycled at a timestep of 0)."""
    v, normals = p.vertices, p.face_normals
    length = np.linalg.norm(normals, axis=1)
    k = int(np.argmax(np.abs(length - 1.0)))
    if abs(length[k] - 1.0) > UNIT_TOLERANCE:
        return f"face_normals[{k}] is {length[k]:.6g} long: face normals must be unit vectors"
    tails, heads, face = face_corners(p.faces)
    closure = _closure_problem(tails, heads, face, len(v))
    if closure is not None:
        return closure
    tol = FOLD_TOLERANCE * p.size
    starts = np.flatnonzero(np.diff(face, prepend=-1))  # where each face's corners begin
    first = v[tails[starts]]
    offset = np.einsum("ij,ij->i", normals, first)
    off_plane = np.abs(np.einsum("ij,ij->i", normals[face], v[tails]) - offset[face])
    if off_plane.max() > tol:
        k = int(face[np.argmax(off_plane)])
        return f"face {k}'s corners lie up to {off_plane.max():.3g} m off its plane: a face must be plane, its normal perpendicular to it"
    outside = v @ normals.T - offset
    i, k = np.unravel_index(np.argmax(outside), outside.shape)
    if outside[i, k] > tol:
        return (f"vertex {i} lies {outside[i, k]:.3g} m outside face {k}'s plane: face normals must point outward "
                "and the polyhedron be convex")
    twice_area = np.add.reduceat(np.cross(v[tails] - first[face], v[heads] - first[face]), starts)
    area = 0.5 * np.einsum("ij,ij->i", twice_area, normals)
    k = int(np.argmin(area))
    if area[k] <= 0.0:
        return (f"face {k} has an area of {area[k]:.3g} m2 along its normal: a face's corners must be distinct and run "
                "counter-clockwise seen from outside")
    return None


def _closure_problem(tails: np.ndarray, heads: np.ndarray, face: np.ndarray, count: int) -> str | None:
    """Why faces of corners ``tails`` to ``heads`` (:func:`face_corners`; vertices 0 to ``count``
    - 1) do not close a polyhedron: a face with a corner twice, or an edge not run once each way,
    by two faces (found by a review: a corner repeated in a face gave edges of no direction, NaN;
    a face left out, a surface with a hole); None if they do."""
    corner = face * count + tails
    order = np.argsort(corner, kind="stable")
    again = np.flatnonzero(np.diff(corner[order]) == 0)
    if again.size:
        j = order[again[0] + 1]
        return f"face {face[j]} has vertex {tails[j]} as a corner twice: a face's corners must be distinct"
    edge = tails * count + heads
    _, which, runs = np.unique(edge, return_inverse=True, return_counts=True)
    unclosed = (runs[which] > 1) | ~np.isin(heads * count + tails, edge)
    if not unclosed.any():
        return None
    j = int(np.argmax(unclosed))
    return (f"face {face[j]}'s edge from vertex {tails[j]} to {heads[j]} is not run the other way by one other face: "
            "the faces must close the polyhedron, each edge shared by two faces")


def _mass_problem(p: ConvexPolyhedron) -> str | None:
    """Where the volume, centroid or second moment of ``p`` (its faces well formed) differ from
    those its vertices and faces enclose (:func:`_mass_properties`) by more than
    :data:`MASS_TOLERANCE` of them (the centroid: of its size), or its volume is a sheet's or a
    film's (:func:`_flatness_problem`); None if they do not (found by a hunt: a volume of 1e-300
    cycled at a timestep of 1e-151 s, a centroid 1,000 km from the vertices was taken)."""
    volume, centroid, second = _mass_properties(p.vertices, p.faces)
    flat = _flatness_problem(volume, p.size)
    if flat is not None:
        return flat
    if abs(p.volume - volume) > MASS_TOLERANCE * volume:
        return f"volume = {shown(p.volume)}: its vertices and faces enclose {volume:.9g} m3"
    if np.abs(p.centroid - centroid).max() > MASS_TOLERANCE * p.size:
        return f"centroid = {shown(p.centroid.tolist())}: its vertices and faces have theirs at {shown(centroid.tolist())} m"
    off = float(np.abs(p.second_moment - second).max())
    if off > MASS_TOLERANCE * float(np.abs(second).max()):
        diagonal = ", ".join(f"{x:.4g}" for x in np.diag(second))
        return f"second_moment is off that of its vertices and faces by up to {off:.3g} m5 (theirs: diagonal {diagonal} m5)"
    return None


def _floats(value) -> bool:
    """An array of finite floats."""
    return isinstance(value, np.ndarray) and value.dtype.kind == "f" and bool(np.isfinite(value).all())


def given(value) -> str:
    """``value`` as given, for a message: an array by its shape and dtype (:func:`described`),
    anything else itself, shortened (a list of three numbers is better shown than shaped)."""
    return described(value) if isinstance(value, np.ndarray) else shown(value)


def described(value) -> str:
    """What ``value`` is, for a message: an array's shape and dtype, a list's shape, another
    value itself (shortened: it may be a megabyte of numbers)."""
    if isinstance(value, np.ndarray):
        return f"shape {value.shape} {value.dtype}"
    if isinstance(value, (list, tuple)):
        try:
            return f"a {type(value).__name__} of shape {np.shape(value)}"
        except ValueError:
            return f"a ragged {type(value).__name__}"
    return shown(value)


def real_array(value) -> np.ndarray | None:
    """``value`` (an array, or nested lists of numbers) as a new C-ordered float64 array; None
    where it is no array of real numbers: texts, booleans (no number here, though NumPy would
    make True 1.0), complex numbers (NumPy would drop their imaginary parts), objects, ragged
    lists, a masked array with masked values (missing ones, which NumPy would read as the data
    under the mask; found by a hunt)."""
    if np.ma.is_masked(value):
        return None
    try:
        array = np.asarray(value)
    except (TypeError, ValueError):  # ragged lists
        return None
    if array.dtype.kind not in "iuf" or _booleans_in(value):
        return None
    return np.array(array, dtype=np.float64, order="C")


def _booleans_in(value) -> bool:
    """Whether nested lists hold a boolean (NumPy would turn it into a number)."""
    if isinstance(value, (list, tuple)):
        return any(_booleans_in(item) for item in value)
    return isinstance(value, (bool, np.bool_))


def far_vertex_problem(points: np.ndarray) -> str | None:
    """Why ``points`` ((n, 3) finite, m) cannot be a model's vertices: one farther than
    MAX_COORDINATE_M from the origin (``a vertex is ... m from the origin: ...``); None if none is."""
    far = float(np.abs(points).max(initial=0.0))
    if far <= MAX_COORDINATE_M:
        return None
    return (f"a vertex is {far:.3g} m from the origin: coordinates must be within {MAX_COORDINATE_M:g} m "
            "(a model in another unit than metres? a model file is in metres; --unit scales imported geometry)")


def convex_hull(points, *, name: str = "block") -> ConvexPolyhedron:
    """The convex polyhedron spanned by ``points`` ((n, 3), m).

    Raises GeometryError naming ``name`` if the points are degenerate (fewer than
    four, coplanar, collinear) or if a point lies inside the hull of the others by more than
    FOLD_TOLERANCE of the size, i.e. the vertex set does not describe a convex block.
    Triangles of Qhull's hull within the tolerances of one plane are one face
    (:func:`_coplanar_groups`).
    """
    _check_name(name)
    pts = real_array(points)
    if pts is None:
        raise GeometryError(f"{name}: vertices must be a list of [x, y, z] numbers")
    if pts.ndim != 2 or pts.shape[1] != 3:
        raise GeometryError(f"{name}: vertices must be a list of [x, y, z] points, got shape {pts.shape}")
    if not np.all(np.isfinite(pts)):
        raise GeometryError(f"{name}: vertices contain NaN or infinite coordinates")
    if len(pts) < 4:
        raise GeometryError(f"{name}: a block needs at least 4 vertices, got {len(pts)}")
    if len(pts) > MAX_BLOCK_VERTICES:
        raise GeometryError(f"{name}: {len(pts)} vertices: a block has at most {MAX_BLOCK_VERTICES} (a scanned surface? simplify "
                            "it into a convex block of fewer vertices)")
    scale = _block_scale(pts, name)
    corners = box_corners(pts)
    if corners is not None:  # most bricks: in closed form, without Qhull nor scipy.spatial's import
        return box(*corners, name=name)
    from scipy.spatial import ConvexHull, QhullError  # here: scipy.spatial takes a fifth of a second to import

    tol = HULL_TOLERANCE * scale
    kept = _without_twins(pts, tol)
    pts = pts[kept]
    try:
        hull = ConvexHull(pts)
    except QhullError:  # its text is Qhull's own (QH6013 qhull input error: ...; found by a hunt)
        raise GeometryError(f"{name}: degenerate block: its vertices are coplanar or collinear, it has no volume") from None
    _refuse_flat(hull.volume, scale, name)
    fold = FOLD_TOLERANCE * scale
    depth = -(pts @ hull.equations[:, :3].T + hull.equations[:, 3]).max(axis=1)
    inside = np.flatnonzero(depth > fold)  # nearer, a hair in: rounding, as a face's fold (found by a review)
    if inside.size:
        i = int(inside[np.argmax(depth[inside])])
        raise GeometryError(
            f"{name}: vertex {kept[i]} {pts[i].tolist()} lies {depth[i]:.3g} m inside the hull of the others; "
            "the block is not convex (split it into convex blocks)"
        )
    # hull stays the given points' for the check below (found by a review: checked against the
    # hull of the points left, a cube gone pyramid passed)
    try:
        pts, _, faces, normals = _closed_faces(pts, hull, tol, fold)
    except QhullError:
        raise GeometryError(f"{name}: degenerate block: its vertices are coplanar or collinear, it has no volume") from None
    used = np.unique(np.concatenate(faces))
    remap = np.full(len(pts), -1)
    remap[used] = np.arange(len(used))
    vertices = pts[used]
    faces = tuple(remap[f] for f in faces)
    volume, centroid, second = _mass_properties(vertices, faces)
    # merging moves the surface by at most fold: a sheet of fold over the hull's area. More, and
    # faces overlap or leave gaps (found by a review: points just past the tolerance)
    if abs(volume - hull.volume) > fold * hull.area:
        raise GeometryError(f"{name}: its faces, merged within {fold:.3g} m, enclose {volume:.6g} m3 where its hull holds "
                            f"{hull.volume:.6g} m3: vertices a hair apart (round-off twins?); merge them")
    return ConvexPolyhedron(vertices, faces, normals, volume, centroid, second, consistent=True)


def _without_twins(pts: np.ndarray, tol: float) -> np.ndarray:
    """The indices of ``pts`` ((n, 3), m) but those within ``tol`` (m) of an earlier point: a
    mesh's round-off twins, whose hull has faces that mix the twins and slivers ``tol`` wide
    between them (found by a hunt: a cube's corners given twice, 1e-7 m apart, made faces of
    one corner and a GeometryError naming neither the block nor the rule)."""
    from scipy.spatial import cKDTree

    pairs = cKDTree(pts).query_pairs(tol, output_type="ndarray")  # each pair (i, j) with i < j
    twin = np.zeros(len(pts), dtype=bool)
    twin[pairs[:, 1]] = True
    return np.flatnonzero(~twin)


def box_corners(pts: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """The min and max corners of the axis-aligned box whose 8 corners ``pts`` ((n, 3), m) are,
    each coordinate equal to the min or max one exactly and every corner present (some perhaps
    given twice), else None: the vertices of a brick as a model file, OBJ, STL or compas file
    gives them, whose hull :func:`box` builds in closed form."""
    lower, upper = pts.min(axis=0), pts.max(axis=0)
    if not ((pts == lower) | (pts == upper)).all():
        return None
    corner = (pts == upper) @ np.array([4, 2, 1])  # 4 ix + 2 iy + iz: a flat box has fewer than 8
    return (lower, upper) if len(np.unique(corner)) == 8 else None


def frozen_array(array: np.ndarray) -> np.ndarray:
    """``array`` if it is read-only already (shared, as :data:`BOX_FACES`), else a read-only
    copy of it: a frozen object's arrays, which the caller's own array does not change."""
    if not array.flags.writeable:
        return array
    array = array.copy()
    array.flags.writeable = False
    return array


def _check_name(name) -> None:
    """GeometryError unless ``name``, the block's name in messages, is a text."""
    if not isinstance(name, str):
        raise GeometryError(f"name = {shown(name)}: must be a text (the block's name in messages)")


def _block_scale(pts: np.ndarray, name: str) -> float:
    """The size of a block of vertices ``pts`` ((n, 3) finite, m), its bounding box's diagonal;
    GeometryError naming ``name`` if :func:`_size_problem` finds one."""
    problem = _size_problem(pts)
    if problem is not None:
        raise GeometryError(f"{name}: {problem}")
    return float(np.linalg.norm(pts.max(0) - pts.min(0)))


def _size_problem(pts: np.ndarray) -> str | None:
    """Why vertices ``pts`` ((n, 3) finite, m) cannot be a block's: one beyond MAX_COORDINATE_M
    (:func:`far_vertex_problem`) or a block smaller than MIN_BLOCK_SIZE_M (a model in another
    unit); None if they can."""
    far = far_vertex_problem(pts)
    if far is not None:
        return far
    scale = float(np.linalg.norm(pts.max(0) - pts.min(0)))
    if scale < MIN_BLOCK_SIZE_M:
        return (f"{scale:.3g} m across: a block must be at least {MIN_BLOCK_SIZE_M:g} m across "
                "(a model in another unit than metres? a model file is in metres; --unit scales imported geometry)")
    return None


def _refuse_flat(volume: float, scale: float, name: str) -> None:
    """GeometryError naming ``name`` if :func:`_flatness_problem` finds one."""
    problem = _flatness_problem(volume, scale)
    if problem is not None:
        raise GeometryError(f"{name}: {problem}")


def _flatness_problem(volume: float, scale: float) -> str | None:
    """Why a block of ``volume`` (m3) and size ``scale`` (m) cannot be: at most 1e-9 of its size
    cubed, a sheet or a needle, whose inertia the cycles would divide by; or thinner on average
    than :data:`MIN_THICKNESS_M` (volume / size^2): a film, whose joints' timestep (it goes as
    the square root of the mass) would keep a run from ending. None if it can."""
    if volume <= 1e-9 * scale**3:
        return f"degenerate block (volume {volume:.3g} m3 for size {scale:.3g} m)"
    if volume < MIN_THICKNESS_M * scale**2:
        return (f"{volume / scale**2:.3g} m thick on average (volume {volume:.3g} m3 over its size {scale:.3g} m "
                f"squared): a block must be at least {MIN_THICKNESS_M:g} m thick (a model in another unit than metres?)")
    return None


def face_interior_points(points: np.ndarray, shape: ConvexPolyhedron) -> np.ndarray:
    """Indices of the ``points`` ((n, 3), m; their hull is ``shape``, which :func:`convex_hull`
    refuses for a point inside it) farther than :data:`HULL_TOLERANCE` from every edge of
    ``shape``: points inside a face, which the hull drops, as opposed to its corners and to
    points on its edges (an edge split in two, as a mesh generator may leave)."""
    if box_corners(points) is not None:  # a box's corners: every one a corner (nor is scipy.spatial imported)
        return np.zeros(0, dtype=np.intp)
    from scipy.spatial import cKDTree

    tol = HULL_TOLERANCE * shape.size
    off_corners = np.flatnonzero(cKDTree(shape.vertices).query(points)[0] > tol)  # few: a tree, not a points x vertices table
    tails, heads = shape.edges
    a, edge = shape.vertices[tails], shape.vertices[heads] - shape.vertices[tails]
    p = points[off_corners, None, :]
    along = np.clip(np.einsum("pej,ej->pe", p - a, edge) / np.einsum("ej,ej->e", edge, edge), 0.0, 1.0)
    distance = np.linalg.norm(p - (a + along[..., None] * edge), axis=2).min(axis=1, initial=np.inf)
    return off_corners[distance > tol]


def box(lower, upper, *, name: str = "block") -> ConvexPolyhedron:
    """Axis-aligned box between corners ``lower`` and ``upper`` (m), in closed form (no hull: Qhull
    took 2.5 ms a brick): sides a, b, c, volume a b c, centroid the middle,
    second moment about it a b c / 12 diag(a^2, b^2, c^2). GeometryError naming ``name`` and the
    corner (min, max) that is not [x, y, z], three finite numbers, or the rule of
    :func:`convex_hull` that the box breaks (too far, too small, too flat)."""
    _check_name(name)
    lo, hi = real_array(lower), real_array(upper)
    for corner, given, key in ((lo, lower, "min"), (hi, upper, "max")):
        if corner is None or corner.shape != (3,) or not np.isfinite(corner).all():
            raise GeometryError(f"{name}: box {key} = {shown(given)}: must be [x, y, z], three finite numbers (m)")
    if np.any(hi <= lo):
        raise GeometryError(f"{name}: box max {hi.tolist()} must exceed min {lo.tolist()} in every coordinate")
    corners = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])
    scale = _block_scale(corners, name)
    side = hi - lo
    volume = float(side[0] * side[1] * side[2])
    _refuse_flat(volume, scale, name)
    return ConvexPolyhedron(corners, BOX_FACES, BOX_NORMALS, volume, 0.5 * (lo + hi), np.diag(volume / 12.0 * side**2), consistent=True)


#: the faces of :func:`box`'s corners (numbered 4 ix + 2 iy + iz, i = 0 at the min corner),
#: counter-clockwise seen from outside, in Qhull's order for a box: -z, -y, +x, -x, +y, +z
BOX_FACES = tuple(np.array(f) for f in ((4, 0, 2, 6), (5, 1, 0, 4), (7, 5, 4, 6), (2, 0, 1, 3), (6, 2, 3, 7), (7, 3, 1, 5)))
BOX_NORMALS = np.array([[0.0, 0.0, -1.0], [0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])
for _shared in (*BOX_FACES, BOX_NORMALS):  # every box holds these arrays: none may change them
    _shared.setflags(write=False)


def _closed_faces(pts: np.ndarray, hull: ConvexHull, tol: float, fold: float) -> tuple[np.ndarray, ConvexHull, list[np.ndarray], np.ndarray]:
    """The points, hull, faces and normals of :func:`_merge_coplanar`, once its faces close: a
    vertex that one face leaves out (within ``tol`` of its neighbours' chord there, or a hair
    out of its plane) while another keeps it as a corner would leave a gap, and the volume
    would be wrong; such vertices are dropped from all faces, and the hull taken again (found
    by CI: a point 1e-6 m above a face of four made it a dart on one side of it, a corner on
    the other)."""
    from scipy.spatial import ConvexHull

    while True:
        faces, normals, left_out = _merge_coplanar(pts, hull, tol, fold)
        stray = np.intersect1d(left_out, np.concatenate(faces))
        if not stray.size:
            return pts, hull, faces, normals
        pts = np.delete(pts, stray, axis=0)
        hull = ConvexHull(pts)


def _merge_coplanar(pts: np.ndarray, hull: ConvexHull, tol: float, fold: float) -> tuple[list[np.ndarray], np.ndarray, np.ndarray]:
    """Hull triangles joined into faces (:func:`_coplanar_groups`); each face's vertices ordered
    counter-clockwise about its normal, the triangles' area-weighted mean; leave out the faces
    whose corners are fewer than 3 (:func:`_corners_only`): slivers along an edge, points
    within ``tol`` of it having made them. Also the vertices some face or sliver left out."""
    faces: list[np.ndarray] = []
    normals: list[np.ndarray] = []
    left_out: list[int] = []
    group, face_normals = _coplanar_groups(pts, hull, tol, fold)
    first = np.full(len(face_normals), len(group))  # each face's first triangle in Qhull's order:
    np.minimum.at(first, group, np.arange(len(group)))  # the faces in the order they had before
    for g in np.argsort(first).tolist():  # (a damped tilt's path is not indifferent to it)
        n = face_normals[g]
        members = np.flatnonzero(group == g)
        ring = np.unique(hull.simplices[members])
        corners = _corners_only(*_counter_clockwise(pts, ring, n), tol)
        if len(corners) >= 3:
            faces.append(corners)
            normals.append(n)
        else:
            corners = _sliver_ends(pts, ring)
        left_out += set(ring.tolist()).difference(corners.tolist())
    return faces, np.array(normals), np.array(left_out, dtype=np.int64)


def _sliver_ends(pts: np.ndarray, ring: np.ndarray) -> np.ndarray:
    """The two points of ``ring`` (indices of ``pts``, m) farthest apart: the ends of the edge
    that a sliver face (points within the tolerance of it) runs along; its other points are a
    hair off the edge (found by a review: a sliver's Graham pass kept one point, and the cube
    corner it left out was dropped)."""
    p = pts[ring]
    far = np.linalg.norm(p[:, None] - p[None], axis=2)
    return ring[list(np.unravel_index(np.argmax(far), far.shape))]


def _coplanar_groups(pts: np.ndarray, hull: ConvexHull, tol: float, fold: float) -> tuple[np.ndarray, np.ndarray]:
    """The face each hull triangle is part of, and each face's unit normal (its triangles'
    area-weighted mean). Faces grow from the largest triangle not yet in one (its plane the best
    defined) over neighbouring triangles whose corners lie within ``tol`` (m) of that seed's
    plane, or within ``fold`` (m) with their normals within :data:`FOLD_ANGLE_RAD` of it. Against
    the seed's plane, not a neighbour's (found by a review: a sliver along an edge, within tol of
    both faces' planes, joined them into one), and by corners, not the planes' offsets (found by
    CI: 160 m out, two planes 3e-6 rad apart differ by 4e-4 m in offset)."""
    corners = pts[hull.simplices]  # (t, 3, 3)
    twice_area = np.linalg.norm(np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]), axis=1)
    group = [-1] * len(corners)
    normals = []
    fitting = _Fitting(corners.tolist(), hull.equations.tolist(), hull.neighbors.tolist(), tol, fold)
    for seed in np.argsort(-twice_area, kind="stable").tolist():
        if group[seed] < 0:
            members = fitting.grown(seed, group)
            for t in members:
                group[t] = len(normals)
            normal = twice_area[members] @ hull.equations[members, :3]
            normals.append(normal / np.linalg.norm(normal))
    return np.array(group), np.array(normals)


class _Fitting(NamedTuple):
    """Hull triangles as Python lists (a face grows one neighbour at a time: numpy's calls on three
    numbers would take most of a hull's time): their ``corners`` (t, 3, 3), ``equations`` (t, 4:
    unit normal, offset) and ``neighbors`` (t, 3); the tolerances ``tol`` and ``fold``, m."""

    corners: list
    equations: list
    neighbors: list
    tol: float
    fold: float

    def grown(self, seed: int, group: list[int]) -> list[int]:
        """The triangles in no face yet (``group`` -1) reached from ``seed`` through neighbours,
        each of whose corners lie within ``tol`` of the seed's plane, or within ``fold`` with its
        normal within :data:`FOLD_ANGLE_RAD` of the seed's."""
        a, b, c, d = self.equations[seed]
        least = math.cos(FOLD_ANGLE_RAD)
        members, stack, seen = [seed], [seed], {seed}
        while stack:
            for t in self.neighbors[stack.pop()]:
                if t in seen or group[t] >= 0:
                    continue
                seen.add(t)
                off = max(abs(a * x + b * y + c * z + d) for x, y, z in self.corners[t])
                e = self.equations[t]
                if off <= self.tol or (off <= self.fold and a * e[0] + b * e[1] + c * e[2] >= least):
                    members.append(t)
                    stack.append(t)
        return members


def _corners_only(ring: np.ndarray, xy: np.ndarray, tol: float) -> np.ndarray:
    """The corners of the face polygon ``ring`` (indices, counter-clockwise about its normal; ``xy``
    (k, 2), m, their coordinates in its plane): its vertices but those within ``tol`` of the
    segment between their neighbours (on an edge) or turning the wrong way (inside the face).
    Qhull keeps a point a hair off a face as a vertex of its own; in the ring it makes a dent,
    and the polygon would not be convex (the volume and centroid wrong). A pass of Graham's scan
    from the ring's farthest vertex from its centre (a corner), each vertex kept while it turns
    left by more than ``tol``."""
    start = int(np.argmax(np.hypot(*(xy - xy.mean(0)).T)))
    order = np.roll(np.arange(len(ring)), -start)
    p = xy.tolist()  # Python floats: a turn of numpy's 3-vectors took 100 us, most of a hull's time
    kept: list[int] = []
    for k in [*order.tolist(), int(order[0])]:
        while len(kept) >= 2 and _left_turn(p[kept[-2]], p[kept[-1]], p[k]) <= tol:
            kept.pop()
        kept.append(k)
    return ring[np.sort(kept[:-1])]  # in the ring's order from its first vertex


def _left_turn(a: list[float], b: list[float], c: list[float]) -> float:
    """m: how far ``b`` lies out beyond the chord from ``a`` to ``c`` (points [x, y] of a plane, m),
    where a path a, b, c turning left has its corner: positive at a convex corner of a ring
    counter-clockwise, negative at a dent: (b - a) x (c - a) / |c - a|."""
    cx, cy = c[0] - a[0], c[1] - a[1]
    return ((b[0] - a[0]) * cy - (b[1] - a[1]) * cx) / max(math.hypot(cx, cy), 1e-300)


def _counter_clockwise(pts: np.ndarray, idx: np.ndarray, normal: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Vertex indices of a planar convex polygon sorted counter-clockwise about ``normal``, and
    their coordinates (k, 2), m, along axes u, v of its plane, u x v = ``normal``: u across the
    normal from the world axis least along it (found by a review: u from the first vertex, over
    the face's centre, was the normal itself, and the face lost its corners). The angles count
    from the first vertex's way from the centre, as they did from u before: the ring starts
    where it did (a damped tilt's path is not indifferent to it)."""
    u = _cross(normal, np.eye(3)[np.argmin(np.abs(normal))])
    u /= np.linalg.norm(u)
    xy = pts[idx] @ np.column_stack([u, _cross(normal, u)])
    xy -= xy.mean(0)
    angle = np.arctan2(xy[:, 1], xy[:, 0])
    order = np.argsort(-((angle[0] - angle + np.pi) % (2 * np.pi) - np.pi))  # angle - angle[0] in (-pi, pi]
    return idx[order], xy[order]


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """a x b of two 3-vectors (np.cross takes 20 us)."""
    return a[[1, 2, 0]] * b[[2, 0, 1]] - a[[2, 0, 1]] * b[[1, 2, 0]]


def face_corners(faces: tuple[np.ndarray, ...]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Every face's corners in turn: the vertex number of each corner, of the corner after it
    (counter-clockwise; a face's last corner is followed by its first) and the face it is of."""
    tails = np.concatenate(faces)
    sides = np.fromiter((len(f) for f in faces), dtype=np.int64, count=len(faces))
    after = np.arange(1, len(tails) + 1)
    after[np.cumsum(sides) - 1] -= sides
    return tails, tails[after], np.repeat(np.arange(len(faces)), sides)


def _mass_properties(vertices: np.ndarray, faces: tuple[np.ndarray, ...]) -> tuple[float, np.ndarray, np.ndarray]:
    """Volume, centroid and second moment about the centroid (see module docstring): the
    tetrahedra of each face's fan, (first corner, corner k, corner k + 1), are its edges but the
    two at its first corner."""
    apex = vertices.mean(0)
    tails, heads, face = face_corners(faces)
    first = tails[np.flatnonzero(np.diff(face, prepend=-1))][face]
    fan = (tails != first) & (heads != first)
    t = vertices[np.stack([first[fan], tails[fan], heads[fan]], axis=1)] - apex  # (nt, 3, 3): relative to the apex (the fourth vertex, at 0)
    vol = np.einsum("ij,ij->i", t[:, 0], np.cross(t[:, 1], t[:, 2])) / 6.0
    volume = float(vol.sum())
    s = t.sum(1)
    centroid_rel = (vol[:, None] * s / 4.0).sum(0) / volume
    moment = np.einsum("t,tij->ij", vol / 20.0, np.einsum("tki,tkj->tij", t, t) + np.einsum("ti,tj->tij", s, s))
    second = moment - volume * np.outer(centroid_rel, centroid_rel)
    return volume, apex + centroid_rel, second


def face_separations(ref: ConvexPolyhedron, other: ConvexPolyhedron) -> np.ndarray:
    """Signed distance of ``other``'s deepest vertex from each face plane of ``ref``, m."""
    offsets = np.einsum("fi,fi->f", ref.face_normals, ref.vertices[[f[0] for f in ref.faces]])
    return (other.vertices @ ref.face_normals.T).min(0) - offsets


def best_separation(a: ConvexPolyhedron, b: ConvexPolyhedron) -> tuple[float, bool, int]:
    """(separation m, reference is a, reference face): the face of least penetration over both
    blocks' face normals (separating-axis test restricted to face normals), ties to ``a``."""
    sa, sb = face_separations(a, b), face_separations(b, a)
    fa, fb = int(np.argmax(sa)), int(np.argmax(sb))
    tie = 1e-9 * min(a.size, b.size)
    if sa[fa] >= sb[fb] - tie:
        return float(sa[fa]), True, fa
    return float(sb[fb]), False, fb


def edge_separation(a: ConvexPolyhedron, b: ConvexPolyhedron) -> float:
    """The largest gap between two convex blocks along the cross products of their edge
    directions (the axes of the separating-axis theorem besides the face normals, Gottschalk et
    al. 1996), m: max over axes n of the gap between their projections on n, max(min_b - max_a,
    min_a - max_b); -inf where every pair of edges is parallel."""
    axes = np.cross(a.edge_directions[:, None], b.edge_directions[None]).reshape(-1, 3)
    length = np.linalg.norm(axes, axis=1)
    axes = axes[length > PARALLEL_SINE] / length[length > PARALLEL_SINE, None]
    pa, pb = a.vertices @ axes.T, b.vertices @ axes.T
    gaps = np.maximum(pb.min(0) - pa.max(0), pa.min(0) - pb.max(0))
    return float(gaps.max(initial=-np.inf))


#: edges whose directions' cross product is shorter than this (the sine of their angle) are parallel: no axis
PARALLEL_SINE = 1e-9


def penetration_depth(a: ConvexPolyhedron, b: ConvexPolyhedron) -> float:
    """Least overlap of two convex blocks, m (negative: separated): minus the largest separation
    over the axes of the separating-axis theorem, their face normals (:func:`best_separation`)
    and the cross products of their edges (:func:`edge_separation`). Exact for convex blocks:
    two crossed edges touching (a prism on a crossed prism) overlap by 0, not by what the face
    normals alone would say."""
    return -max(best_separation(a, b)[0], edge_separation(a, b))


class FlatGeometry(NamedTuple):
    """Every block's polyhedron in its body frame, flattened for the compiled contact detection (nb blocks).

    vertex (V, 3) m relative to the centroid, block b's rows vertex_start[b]:vertex_start[b+1];
    face_vertex (I,) vertex numbers within the block, face f's entries face_start[f]:face_start[f+1];
    block b's faces block_face_start[b]:block_face_start[b+1]; face_normal (F, 3) outward unit
    normals; size (nb,) m, bounding-box diagonal.
    """

    vertex: np.ndarray
    vertex_start: np.ndarray
    face_vertex: np.ndarray
    face_start: np.ndarray
    block_face_start: np.ndarray
    face_normal: np.ndarray
    size: np.ndarray

    @classmethod
    def of(cls, shapes) -> FlatGeometry:
        """From a sequence of :class:`ConvexPolyhedron` (in the body frame = as given)."""
        vertex = np.concatenate([s.vertices - s.centroid for s in shapes])
        vertex_start = np.concatenate([[0], np.cumsum([len(s.vertices) for s in shapes])])
        faces = [f for s in shapes for f in s.faces]
        return cls(
            vertex=vertex,
            vertex_start=vertex_start.astype(np.int64),
            face_vertex=np.concatenate(faces).astype(np.int64),
            face_start=np.concatenate([[0], np.cumsum([len(f) for f in faces])]).astype(np.int64),
            block_face_start=np.concatenate([[0], np.cumsum([len(s.faces) for s in shapes])]).astype(np.int64),
            face_normal=np.concatenate([s.face_normals for s in shapes]),
            size=np.array([s.size for s in shapes]),
        )
