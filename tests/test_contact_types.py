"""The contact kinds of 3DEC besides face-face (edge-face, vertex-face, crossed edges) against the
exact intersection of two convex polyhedra (tests/oracles/polyhedra.py), and their mechanics: a
prism resting edge on edge on a crossed one, a cube falling off its edge onto its face, shear
history kept when a contact changes kind."""

from __future__ import annotations

import math

import numba
import numpy as np
import pytest
from scipy.spatial import ConvexHull
from scipy.spatial.transform import Rotation

import drydem as dd
from drydem.engine import narrow_phase as npm
from drydem.engine import refresh
from drydem.engine.damping import Damping
from drydem.model.geometry import FlatGeometry
from drydem.model.parameters import ContactDensity
from drydem.model.state import State
from oracles import polyhedra

#: overlap depth of the placed pairs, m, blocks of about 1 m: far below the contact tolerance and
#: far above round-off (1e-16 m), so the oracle's intersection is thin but well resolved
DEPTH = 1e-7
TOLERANCE = 1e-3
DENSITY = ContactDensity(along=4, across=4)
#: kinds of the compiled narrow phase by the oracle's names
KIND = {npm.FACE_FACE: polyhedra.FACE_FACE, npm.EDGE_FACE: polyhedra.EDGE_FACE, npm.VERTEX_FACE: polyhedra.VERTEX_FACE,
        npm.EDGE_EDGE: polyhedra.EDGE_EDGE}
#: a placed feature is clean when every face of the placed block is tilted at least this far
#: from the face it rests on (rad), beyond the face-face limit of 0.2 rad (narrow_phase.FACE_COSINE)
CLEAN_TILT = 0.45


def random_block(rng) -> dd.ConvexPolyhedron:
    """A box (half the time) or the convex hull of 12 random points, about 1 m across, centred."""
    if rng.random() < 0.5:
        half = rng.uniform(0.2, 0.6, 3)
        shape = dd.box(-half, half)
    else:
        points = rng.normal(scale=0.4, size=(12, 3))
        shape = dd.convex_hull(points[ConvexHull(points).vertices])
    return dd.convex_hull(shape.vertices - shape.centroid)


def turning(w, target, spin) -> np.ndarray:
    """The rotation taking unit ``w`` to unit ``target``, then ``spin`` rad about ``target``."""
    axis = np.cross(w, target)
    s, c = np.linalg.norm(axis), float(np.dot(w, target))
    if s < 1e-12:  # (anti)parallel: any axis across w
        across = np.cross(w, np.eye(3)[np.argmin(np.abs(w))])
        first = np.eye(3) if c > 0 else Rotation.from_rotvec(np.pi * across / np.linalg.norm(across)).as_matrix()
    else:
        first = Rotation.from_rotvec(axis / s * math.atan2(s, c)).as_matrix()
    return Rotation.from_rotvec(spin * np.asarray(target)).as_matrix() @ first


def edge_faces(shape):
    """{(a, b): [faces]} of the shape's edges (a < b)."""
    out: dict[tuple[int, int], list[int]] = {}
    for f, loop in enumerate(shape.faces):
        for i in range(len(loop)):
            a, b = int(loop[i]), int(loop[(i + 1) % len(loop)])
            out.setdefault((min(a, b), max(a, b)), []).append(f)
    return out


def vertex_faces(shape, vertex):
    return [f for f, loop in enumerate(shape.faces) if vertex in loop]


def clean_support(shape, feature, w) -> bool:
    """``feature`` (vertex numbers) is the shape's support along ``w``, every other vertex at
    least 0.05 m behind it (far beyond the tolerance), and every face tilted CLEAN_TILT from -w."""
    x = shape.vertices @ w
    top = x[list(feature)].max()
    others = np.delete(x, list(feature))
    cosines = shape.face_normals @ w
    return others.max() < top - 0.05 and cosines.max() < math.cos(CLEAN_TILT)


def resting_face(rng, a):
    """A face of ``a`` of at least a fifth of its largest face's area: (normal, centroid)."""
    areas = np.array([a.face_area(f) for f in range(len(a.faces))])
    f = rng.choice(np.flatnonzero(areas > 0.2 * areas.max()))
    return a.face_normals[f], a.vertices[a.faces[f]].mean(axis=0)


def place(rng, kind: str, depth: float = DEPTH):
    """Two blocks (world vertices A, B) touching by ``kind`` with overlap ``depth`` (negative: a
    gap), A turned at random about its centroid at the origin; and the expected normal (A to B)."""
    while True:
        a = random_block(rng)
        a = dd.convex_hull(a.vertices @ Rotation.random(random_state=rng).as_matrix().T)
        b = random_block(rng)
        spin = rng.uniform(0, 2 * np.pi)
        if kind in (polyhedra.VERTEX_FACE, polyhedra.EDGE_FACE):
            n, p = resting_face(rng, a)
            if kind == polyhedra.VERTEX_FACE:
                v = int(rng.integers(len(b.vertices)))
                feature = [v]
                w = b.face_normals[vertex_faces(b, v)].sum(axis=0)
            else:
                edges = [e for e, fs in edge_faces(b).items() if len(fs) == 2 and b.face_normals[fs[0]] @ b.face_normals[fs[1]] < math.cos(0.4)]
                e = edges[int(rng.integers(len(edges)))]
                feature = list(e)
                f1, f2 = edge_faces(b)[e]
                lam = rng.uniform(0.3, 0.7)
                w = lam * b.face_normals[f1] + (1 - lam) * b.face_normals[f2]
            w /= np.linalg.norm(w)
            if not clean_support(b, feature, w):
                continue
            r = turning(w, -n, spin)
            vb = b.vertices @ r.T
            vb += p - depth * n - vb[feature].mean(axis=0)
            return a.vertices, vb, n
        if kind == polyhedra.EDGE_EDGE:
            pairs = []
            for shape in (a, b):
                edges = [e for e, fs in edge_faces(shape).items() if len(fs) == 2 and shape.face_normals[fs[0]] @ shape.face_normals[fs[1]] < math.cos(0.4)]
                e = edges[int(rng.integers(len(edges)))]
                f1, f2 = edge_faces(shape)[e]
                w = shape.face_normals[f1] + shape.face_normals[f2]
                pairs.append((list(e), w / np.linalg.norm(w)))
            (ea, wa), (eb, wb) = pairs
            if not (clean_support(a, ea, wa) and clean_support(b, eb, wb)):
                continue
            r = turning(wb, -wa, 0.0)
            vb = b.vertices @ r.T
            da, db = a.vertices[ea[1]] - a.vertices[ea[0]], vb[eb[1]] - vb[eb[0]]
            # spin B about wa so that the edges cross at 40 to 90 deg
            angle = math.atan2(np.dot(np.cross(db, da), wa), np.dot(db, da)) + rng.choice([-1, 1]) * rng.uniform(math.radians(40), math.radians(90))
            vb = vb @ Rotation.from_rotvec(angle * wa).as_matrix().T
            vb += a.vertices[ea].mean(axis=0) - depth * wa - vb[eb].mean(axis=0)
            return a.vertices, vb, wa
        # face on face: a face of B turned onto a face of A, centroid on centroid
        n, p = resting_face(rng, a)
        g = int(rng.integers(len(b.faces)))
        r = turning(b.face_normals[g], -n, spin)
        vb = b.vertices @ r.T
        vb += p - depth * n - vb[b.faces[g]].mean(axis=0)
        return a.vertices, vb, n


def detect(placements, density=DENSITY, tolerance=TOLERANCE):
    """The compiled narrow phase's Found for the placed pairs (A, B, ...), in one call, each pair
    moved 10 m from the last (their own candidates only)."""
    shapes = []
    for k, (va, vb, _) in enumerate(placements):
        shift = np.array([10.0 * k, 0.0, 0.0])
        shapes += [dd.convex_hull(va + shift), dd.convex_hull(vb + shift)]
    candidates = np.arange(len(shapes)).reshape(-1, 2)
    position, rotation = np.array([s.centroid for s in shapes]), np.repeat(np.eye(3)[None], len(shapes), 0)
    return npm.find(FlatGeometry.of(shapes), candidates, position, rotation, tolerance=tolerance, density=density)


def placements(seed, kind, count=24, depth=DEPTH):
    rng = np.random.default_rng(seed)
    return [place(rng, kind, depth) for _ in range(count)]


@pytest.mark.parametrize("kind", [polyhedra.VERTEX_FACE, polyhedra.EDGE_FACE, polyhedra.EDGE_EDGE, polyhedra.FACE_FACE])
@pytest.mark.parametrize("seed", range(2))
def test_touching_blocks_are_found_with_the_oracles_kind_and_normal(kind, seed):
    placed = placements(seed, kind)
    found = detect(placed)
    for k, (va, vb, expected_normal) in enumerate(placed):
        exact = polyhedra.contact(va, vb, DEPTH)
        assert exact.touching and exact.kind == kind, (k, exact)
        # the oracle's least-penetration normal is the placement's: to round-off (qhull, 1e-9)
        assert np.dot(exact.normal, expected_normal) > math.cos(1e-6)
        assert exact.depth == pytest.approx(DEPTH, rel=1e-3)
        assert found.count[k] > 0, (k, kind)
        assert KIND[found.kind[k]] == exact.kind, (k, found.kind[k])
        # normal from the reference block to the incident one: a face normal (or an edge-pair
        # cross product) rotated, against qhull's facet: the same to 1e-6 rad
        normal = found.normal[k] if found.ref[k] == 2 * k else -found.normal[k]
        assert np.dot(normal, exact.normal) > math.cos(1e-6)
        # the overlap depth is every point's gap (placed features sit flat on the reference face;
        # crossed edges meet in one point), to round-off of block coordinates of 1 m
        np.testing.assert_allclose(found.gaps[k, :found.count[k]], -DEPTH, rtol=0, atol=1e-12)
        areas = found.areas[k, :found.count[k]]
        assert np.isfinite(areas).all() and (areas > 0).all()
        if kind == polyhedra.FACE_FACE:
            # the faces' overlap polygon against the projected intersection, which overhangs it by
            # d cot(dihedral) along its perimeter (a few m, the merged faces' dihedrals down to
            # ~0.01 rad: ~1e-4 m2 at d = 1e-7 m): absolute tolerance 1e-3 of the 1 m2 scale
            assert areas.sum() == pytest.approx(exact.area, rel=0, abs=1e-3)
        if kind == polyhedra.EDGE_FACE:
            # the segment's length (first to last point) against the sliver's, which overhangs
            # the segment by d cot(angle) at each end: 1e-4 m
            points = found.points[k, :found.count[k]]
            length = np.linalg.norm(points[:, None] - points[None], axis=2).max()
            assert length == pytest.approx(exact.length, rel=0, abs=1e-4)


@pytest.mark.parametrize("kind", [polyhedra.VERTEX_FACE, polyhedra.EDGE_FACE, polyhedra.EDGE_EDGE, polyhedra.FACE_FACE])
def test_blocks_apart_by_more_than_the_tolerance_are_not_in_contact_and_nearer_ones_are(kind):
    far = placements(7, kind, count=16, depth=-2 * TOLERANCE)
    found = detect(far)
    for k, (va, vb, _) in enumerate(far):
        assert not polyhedra.contact(va, vb, DEPTH).touching
        assert found.count[k] == 0
        # a lower bound on the distance, tight for the placed feature: the gap itself
        assert found.separation[k] == pytest.approx(2 * TOLERANCE, rel=1e-9)
    near = placements(7, kind, count=16, depth=-0.5 * TOLERANCE)
    found = detect(near)
    for k in range(len(near)):
        assert found.count[k] > 0 and KIND[found.kind[k]] == kind
        np.testing.assert_allclose(found.gaps[k, :found.count[k]], 0.5 * TOLERANCE, rtol=1e-9)


def test_found_is_the_same_whatever_the_thread_count():
    placed = [p for kind in (polyhedra.VERTEX_FACE, polyhedra.EDGE_FACE, polyhedra.EDGE_EDGE, polyhedra.FACE_FACE) for p in placements(3, kind, count=20)]
    threads = numba.get_num_threads()
    try:
        numba.set_num_threads(1)
        one = detect(placed)
        numba.set_num_threads(min(2, numba.config.NUMBA_NUM_THREADS))
        two = detect(placed)
    finally:
        numba.set_num_threads(threads)
    for name in npm.Found._fields:
        np.testing.assert_array_equal(getattr(one, name), getattr(two, name), err_msg=name)


def test_point_contacts_carry_a_corner_cells_area_and_edge_contacts_an_edge_rows():
    """The nominal areas of the module docstring, for a 0.2 m cube (L = its edge) with 4 points
    per length (h = L / 3): on a vertex, h^2 / 4; on its edge, the edge's length times h / 2."""
    ground = dd.box([-1, -1, -0.2], [1, 1, 0])
    cube = dd.box([-0.1, -0.1, -0.1], [0.1, 0.1, 0.1])
    h = 0.2 / 3
    on_edge = cube.vertices @ Rotation.from_euler("y", 30, degrees=True).as_matrix().T
    on_vertex = cube.vertices @ turning(np.ones(3) / math.sqrt(3), np.array([0.0, 0.0, -1.0]), 0.3).T
    placed = [(ground.vertices, v - [0, 0, v[:, 2].min() + DEPTH], None) for v in (on_edge, on_vertex)]
    found = detect(placed)
    assert [found.kind[0], found.kind[1]] == [npm.EDGE_FACE, npm.VERTEX_FACE]
    assert found.count[0] == 4  # 4 points along the 0.2 m edge, spacing h
    assert found.areas[0, :4].sum() == pytest.approx(0.2 * h / 2, rel=1e-12)
    assert found.count[1] == 1 and found.areas[1, 0] == pytest.approx(h * h / 4, rel=1e-12)


def landing_weight(phi):
    """The module docstring's weight of a face at angle ``phi`` (rad) to the reference plane."""
    return 1.0 / (phi - 0.2) - 1.0 / (math.pi / 2 - 0.2) if phi < math.pi / 2 else 0.0


def edge_and_corner(size, tilt, density=DENSITY):
    """Found of a box of ``size`` (a, b, c along x, y, z) turned ``tilt`` rad about y onto the
    edge along y of its bed, and ``tilt`` about y then 0.3 rad about x onto a corner, on a slab."""
    a, b, c = size
    ground = dd.box([-1, -1, -0.2], [1, 1, 0])
    block = dd.box([-a / 2, -b / 2, -c / 2], [a / 2, b / 2, c / 2])
    on_edge = block.vertices @ Rotation.from_euler("y", tilt).as_matrix().T
    on_corner = block.vertices @ Rotation.from_euler("yx", [tilt, 0.3]).as_matrix().T
    placed = [(ground.vertices, v - [0, 0, v[:, 2].min() + DEPTH], None) for v in (on_edge, on_corner)]
    return detect(placed, density=density)


SIZES = [(0.1, 0.1, 0.4), (0.2, 0.1, 0.05), (0.05, 0.3, 0.1)]


@pytest.mark.parametrize("size", SIZES)
def test_a_block_turned_off_its_bed_carries_its_bed_face_grids_edge_row_whatever_its_height(size):
    """A slender column, a brick and a flat slab of bed a x b (x, y), 4 points per length, just
    past the face-face limit (0.2 rad) onto the bed's edge along y: the edge contact's areas sum
    to the edge row of the bed face's grid, b x (a / 3) / 2 (the nominal length was first the
    circumradius', which gave the 0.1 x 0.1 x 0.4 column 2.4 times its bed's edge row, so a force
    that jumped as the column turned off its bed onto its edge); also with one point across
    (y, in-plane walls), the one point standing for the whole edge."""
    a, b, _ = size
    for density in (DENSITY, ContactDensity(along=4, across=1)):
        found = edge_and_corner(size, 0.2 + 1e-9, density)
        assert found.kind[0] == npm.EDGE_FACE
        # the side face's weight beside the bed's: 1e-9 of it
        assert found.areas[0, :found.count[0]].sum() == pytest.approx(b * a / 3 / 2, rel=1e-7)


@pytest.mark.parametrize("size", SIZES)
def test_a_block_on_its_edge_blends_its_bed_and_side_faces_grids_by_their_angles(size):
    """On its edge at 0.3 rad the row's width across blends the bed's (a) and the side face's (c)
    with the module docstring's weights, w = 1 / (phi - 0.2) - 1 / (pi/2 - 0.2), phi each face's
    angle to the slab: 0.3 and pi/2 - 0.3; at 45 deg half and half, (a + c) / 2, and the same
    just either side of it (the landing face changes there: a jump of c / a before the blend,
    found by a hunt); and a corner's area is finite and positive."""
    a, b, c = size
    w_bed, w_side = landing_weight(0.3), landing_weight(math.pi / 2 - 0.3)
    across = (w_bed * a + w_side * c) / (w_bed + w_side)
    found = edge_and_corner(size, 0.3)
    assert [found.kind[0], found.kind[1]] == [npm.EDGE_FACE, npm.VERTEX_FACE]
    assert found.areas[0, :found.count[0]].sum() == pytest.approx(b * across / 3 / 2, rel=1e-12)
    assert found.count[1] == 1 and 0 < found.areas[1, 0] < a * b
    for tilt in (math.pi / 4 - 1e-6, math.pi / 4, math.pi / 4 + 1e-6):
        found = edge_and_corner(size, tilt)
        assert found.areas[0, :found.count[0]].sum() == pytest.approx(b * (a + c) / 2 / 3 / 2, rel=1e-5)


def cube_on_ground(tilt_deg, a=0.2):
    """FlatGeometry of a fixed ground slab and an a-cube (body frame axis-aligned), and the cube's
    position and rotation resting on its edge along y at x = 0, its face turned ``tilt_deg``."""
    shapes = [dd.box([-1, -1, -0.2], [1, 1, 0]), dd.box([-a / 2, -a / 2, -a / 2], [a / 2, a / 2, a / 2])]
    r = Rotation.from_euler("y", -tilt_deg, degrees=True).as_matrix()  # lifts the +x side
    corner = r @ np.array([-a / 2, 0, -a / 2])  # the resting edge, from the centroid
    position = np.array([[0, 0, -0.1], -corner + [0, 0, -DEPTH]])
    return FlatGeometry.of(shapes), position, np.array([np.eye(3), r])


def test_shear_stress_is_kept_when_an_edge_contact_turns_into_a_face_contact():
    """A cube on its edge (25 deg) with a shear stress tau along x at its sub-contacts, turned
    about that edge onto its face and re-detected: the new face-face sub-contacts carry the
    same shear stress (merge: nearest old sub-contact's stress times the new area); and back."""
    tau = 1234.5
    geometry, position, rotation = cube_on_ground(25.0)
    pair = np.array([[0, 1]])
    edge, _ = npm.narrow_phase(geometry, pair, position, rotation, tolerance=TOLERANCE, density=DENSITY)
    assert list(npm.contact_kinds(npm.find(geometry, pair, position, rotation, tolerance=TOLERANCE, density=DENSITY))) == [npm.EDGE_FACE]
    edge.shear_force[:] = tau * edge.area[:, None] * [1.0, 0.0, 0.0]
    _, flat_position, flat_rotation = cube_on_ground(0.0)
    found = npm.find(geometry, pair, flat_position, flat_rotation, tolerance=TOLERANCE, density=DENSITY)
    assert list(npm.contact_kinds(found)) == [npm.FACE_FACE]
    face, _ = npm.narrow_phase(geometry, pair, flat_position, flat_rotation, tolerance=TOLERANCE, density=DENSITY)
    merged = refresh.merge(edge, np.zeros(1, bool), face, flat_position, flat_rotation)
    assert merged.count == 16
    np.testing.assert_allclose(merged.shear_force / merged.area[:, None], np.tile([tau, 0, 0], (16, 1)), rtol=1e-12, atol=1e-9 * tau)
    # and back onto the edge: the face's stress again
    back = refresh.merge(merged, np.zeros(1, bool), edge._replace(shear_force=np.zeros_like(edge.shear_force)), position, rotation)
    np.testing.assert_allclose(back.shear_force / back.area[:, None], np.tile([tau, 0, 0], (back.count, 1)), rtol=1e-12, atol=1e-9 * tau)


def prisms(lift=0.0):
    """A fixed triangular prism (section base 0.2 m, height 0.1 m, 0.4 m long along x, apex edge
    up at z = 0) and the same prism upside down, along y, apex edge at z = ``lift``."""
    section = np.array([[-0.1, -0.1], [0.1, -0.1], [0.0, 0.0]])
    lower = np.array([[x, s, t] for x in (-0.2, 0.2) for s, t in section])
    upper = np.array([[s, y, lift - t] for y in (-0.2, 0.2) for s, t in section])
    return [dd.Block(name="lower", shape=dd.convex_hull(lower), fixed=True), dd.Block(name="upper", shape=dd.convex_hull(upper))]


def test_a_prism_resting_edge_on_edge_on_a_crossed_one_carries_its_weight_with_the_elastic_closure():
    """The upper prism, apex edge down across the lower one's apex edge at 90 deg, balanced: one
    crossed-edge contact (normal z), carrying the weight W at rest with the closure
    W / (kn A), A the nominal point area h^2 / 4 of the corner of the roof faces' grid (h = L / 3,
    L = 0.1 sqrt(2) m, the slant of the 0.4 m long roof faces, the smaller extent along and across
    whichever way the grid runs). Built touching (the model's overlap check finds the crossed edges' depth 0:
    tests/test_geometry.py)."""
    kn = 1e9
    model = dd.build_model(prisms(lift=0.0), density=2400.0, joint=dd.JointMaterial(kn=kn, ks=kn, friction=0.8))
    start = State.at_rest(model.block_centroid)
    sim = dd.Simulation(model, state=start)
    assert sim.contacts.count == 1
    np.testing.assert_allclose(np.abs(sim.contacts.normal_body[0]), [0, 0, 1], atol=1e-12)
    result = sim.cycle_to_equilibrium()
    weight = model.block_mass[1] * dd.G
    h = 0.1 * math.sqrt(2) / (model.contact_density.along - 1)
    closure = weight / (kn * h * h / 4)
    assert result.converged
    assert sim.contacts.count == 1
    # the equilibrium criterion (unbalanced force ratio) leaves the reaction that close to W
    assert sim.contacts.normal_force.sum() == pytest.approx(weight, rel=1e-3)
    sink = start.position[1, 2] - sim.state.position[1, 2]
    # rigid blocks: the sinking is the joint's closure, to 1 % (the equilibrium criterion leaves
    # ~1e-3 of the weight unbalanced at most; measured sink / closure = 0.99983)
    assert sink == pytest.approx(closure, rel=1e-2)
    assert sink < model.contact_tolerance


def octagonal_prism_over_a_slab_edge(tilt, roll, depth=DEPTH):
    """World vertices of a fixed slab (top z = 0, its top edge along y at x = 8 mm, 0.2 m long) and
    of an octagonal prism (circumradius 20 mm, 60 mm high) whose bed face lies across that edge:
    turned ``tilt`` rad about it (its overhang down) and ``roll`` rad about x, so the slab's
    edge crosses the bed face, and runs past it on both sides, ``depth`` into it at y = 0; and the
    bed face's outward normal."""
    slab = dd.box([-0.1, -0.1, -0.01], [0.008, 0.1, 0.0]).vertices
    angles = 0.2 + np.arange(8) * np.pi / 4
    ring = 0.02 * np.c_[np.cos(angles), np.sin(angles)]
    prism = np.r_[np.c_[ring, np.zeros(8)], np.c_[ring, np.full(8, 0.06)]]
    edge = np.array([0.008, 0.0, 0.0])
    turn = Rotation.from_rotvec([roll, 0.0, 0.0]) * Rotation.from_rotvec([0.0, tilt, 0.0])
    prism = (prism - edge) @ turn.as_matrix().T + edge
    normal = turn.apply([0.0, 0.0, -1.0])  # the bed face's outward normal
    return slab, prism + depth * normal, normal


@pytest.mark.parametrize("tilt", [0.25, 0.5])
@pytest.mark.parametrize("roll", [1e-5, -1e-5])
def test_a_slab_edge_running_under_a_tilted_bed_face_is_an_edge_face_contact_along_it(tilt, roll):
    """The slab's top edge lies on the prism's bed face, tilted past the face-face limit and
    rolled a little, so that the slab's far corners (0.1 m out) sink 1 um below the bed face's
    plane: the face normals' separation is that deep one and the edge-pair axis wins. The contact
    is still the edge on the face (Cundall 1988's edge-face kind): the slab's edge clipped to the
    octagon, its points at both crossings, the chord of the octagon at x = 8 mm, each with its
    gap to the bed face. (One crossed-edge point at one crossing, as before, let the other
    crossing sink unseen; at its re-detection 32 um closed at kn = 1e12, a tilt diverged.)"""
    slab, prism, normal = octagonal_prism_over_a_slab_edge(tilt, roll)
    found = detect([(slab, prism, None)], density=ContactDensity(along=2, across=2))
    assert found.kind[0] == npm.EDGE_FACE and found.count[0] == 2
    # within 1e-9 rad of the bed face's normal, by the sine (cos(1e-9) is 1.0 in doubles)
    assert found.ref[0] == 1 and np.dot(found.normal[0], normal) > 0 and np.linalg.norm(np.cross(found.normal[0], normal)) < 1e-9
    # the chord of the octagon at x = 8 mm, the prism's own frame: where the line crosses its sides
    angles = 0.2 + np.arange(9) * np.pi / 4
    ring = 0.02 * np.c_[np.cos(angles), np.sin(angles)]
    crossings = [a[1] + (0.008 - a[0]) / (b[0] - a[0]) * (b[1] - a[1]) for a, b in zip(ring[:-1], ring[1:]) if (a[0] - 0.008) * (b[0] - 0.008) < 0]
    points = found.points[0, :2]
    # the roll moves the crossings by ~roll x 20 mm along the edge: 2e-7 m
    np.testing.assert_allclose(np.sort(points[:, 1]), np.sort(crossings), rtol=0, atol=1e-6)
    # each point's gap is the slab edge's distance to the bed face's plane there (x on the face's plane)
    bed = prism[0]
    on_edge = np.c_[np.full(2, 0.008), points[:, 1], np.zeros(2)]
    np.testing.assert_allclose(found.gaps[0, :2], (on_edge - bed) @ normal, rtol=0, atol=1e-12)


def crossed_ridges(slope_rad, crossing_rad, depth=DEPTH):
    """World vertices of two triangular prisms 0.4 m long, roofs of ``slope_rad`` either side of
    their ridge, 0.1 m half-wide: the lower ridge up along x at z = 0, the upper one down, turned
    ``crossing_rad`` from it about z, ``depth`` into the lower one where they cross at the origin."""
    rise = 0.1 * math.tan(slope_rad)
    lower = np.array([[x, y, z] for x in (-0.2, 0.2) for y, z in ((-0.1, -rise), (0.1, -rise), (0.0, 0.0))])
    upper = lower * [1.0, 1.0, -1.0] @ Rotation.from_rotvec([0.0, 0.0, crossing_rad]).as_matrix().T - [0.0, 0.0, depth]
    return lower, upper


@pytest.mark.parametrize("slope, crossing", [(math.pi / 4, 0.1), (math.pi / 4, 0.05), (0.1, math.pi / 2), (0.19, math.pi / 2)])
def test_crossed_ridges_stay_crossed_edges_however_shallow_or_nearly_parallel(slope, crossing):
    """Two ridges crossing nearly parallel (each edge then lies within 0.2 rad of either face of
    the other), or shallow roofs crossing square (an edge along both faces of the other ridge):
    one crossed-edge point, normal along z (the oracle's), gap the overlap. Taken for an edge on
    one of those faces, as the first version of the edge-along-face rule did (found by a review),
    the normal was 45 deg off for the nearly parallel ridges, and tilted by the roof's slope, to
    a side round-off picked, for the shallow ones."""
    lower, upper = crossed_ridges(slope, crossing)
    exact = polyhedra.contact(lower, upper, DEPTH)
    assert exact.touching and np.dot(exact.normal, [0.0, 0.0, 1.0]) > math.cos(1e-6)
    found = detect([(lower, upper, None)])
    assert found.kind[0] == npm.EDGE_EDGE and found.count[0] == 1
    normal = found.normal[0] if found.ref[0] == 0 else -found.normal[0]
    assert np.dot(normal, exact.normal) > math.cos(1e-6)
    assert found.gaps[0, 0] == pytest.approx(-DEPTH, rel=0, abs=1e-12)


def test_check_counts_the_contacts_by_kind(tmp_path):
    # the crossed prisms touch apex edge on apex edge: one contact, of crossed edges (check
    # called every contact a face contact)
    from click.testing import CliRunner

    from drydem.cli import main
    from drydem.io.model_file import save_model

    save_model(dd.build_model(prisms(), density=2400.0), tmp_path / "crossed.toml")
    run = CliRunner().invoke(main, ["check", str(tmp_path / "crossed.toml")])
    assert run.exit_code == 0, run.output
    assert "contacts        1 (1 edge-edge), 1 sub-contacts" in run.output


def test_a_cube_falling_off_its_edge_lands_with_the_rigid_bodys_angular_velocity():
    """An a = 0.2 m cube on a fixed slab, on its edge with its face tilted 43 deg (2 deg past the
    balance point of 45 deg), released undamped: it pivots about the edge (friction 1, no slip)
    onto its face. Just before the face lands its angular velocity is the rigid block's about a
    fixed edge (Housner 1963): m g (h0 - h1) = I_edge omega^2 / 2, I_edge = 2 m a^2 / 3,
    h = (a / sqrt 2) sin(phi + 45 deg)."""
    a, tilt = 0.2, 43.0
    r = Rotation.from_euler("y", -tilt, degrees=True).as_matrix()
    cube = dd.box([-a / 2, -a / 2, -a / 2], [a / 2, a / 2, a / 2]).vertices @ r.T
    cube -= [0, 0, cube[:, 2].min()]  # resting on its edge at z = 0
    blocks = [dd.Block(name="ground", shape=dd.box([-1, -1, -0.2], [1, 1, 0]), fixed=True), dd.Block(name="cube", shape=dd.convex_hull(cube))]
    model = dd.build_model(blocks, density=2400.0, joint=dd.JointMaterial(kn=1e10, ks=1e10, friction=1.0))
    sim = dd.Simulation(model, damping=Damping(0.0))
    assert list(np.abs(sim.contacts.normal_body[0])) == pytest.approx([0, 0, 1])
    m = model.block_mass[1]
    h0 = a / math.sqrt(2) * math.sin(math.radians(tilt + 45))
    h1 = a / 2
    omega_exact = math.sqrt(2 * m * dd.G * (h0 - h1) / (2 * m * a * a / 3))

    def face_angle():
        # the lifted bottom face's tilt, from the cube's turn about y since the start
        q = sim.state.quaternion[1]
        turn = Rotation.from_quat([q[1], q[2], q[3], q[0]]).as_rotvec()[1]
        return tilt - math.degrees(turn)

    history = []
    while face_angle() > 0.0 and sim.cycles < 2_000_000:
        history.append((face_angle(), abs(sim.state.angular_velocity[1, 1])))
        sim.cycle(10)
    (phi0, w0), phi1, w1 = history[-1], face_angle(), abs(sim.state.angular_velocity[1, 1])
    omega = w0 + (w1 - w0) * phi0 / (phi0 - phi1)  # at the landing angle 0, interpolated
    # 0.5 %: the rigid theory leaves out the pivot's elastic closure and the contact's change of
    # kind on the way (edge-face points, then at 0.2 rad the face grid's edge row), and the
    # explicit integrator (second order) takes ~2000 steps of 2.7e-4 s for the fall; measured 6.5e-4
    assert omega == pytest.approx(omega_exact, rel=5e-3)


@pytest.mark.parametrize("along, across", [(1, 1), (2, 2), (4, 1), (8, 8)])
def test_any_overlap_gives_bounded_finite_contacts(along, across):
    """Blocks thrown together anyhow (overlapping deeply, coincident, one far smaller, one at a
    position not a number): every contact within its row's room, with finite positive areas."""
    rng = np.random.default_rng(along * 10 + across)
    shapes = []
    for k in range(60):
        a, b = random_block(rng), random_block(rng)
        scale = 1e-3 if k % 7 == 0 else 1.0
        turn = Rotation.random(random_state=rng).as_matrix()
        offset = np.zeros(3) if k % 5 == 0 else rng.uniform(-0.8, 0.8, 3)
        shapes += [dd.convex_hull(a.vertices + [10.0 * k, 0, 0]), dd.convex_hull(scale * b.vertices @ turn.T + offset + [10.0 * k, 0, 0])]
    candidates = np.arange(len(shapes)).reshape(-1, 2)
    position, rotation = np.array([s.centroid for s in shapes]), np.repeat(np.eye(3)[None], len(shapes), 0)
    position[-1] = np.nan
    density = ContactDensity(along=along, across=across)
    found = npm.find(FlatGeometry.of(shapes), candidates, position, rotation, tolerance=TOLERANCE, density=density)
    largest_face = np.diff(FlatGeometry.of(shapes).face_start).max()
    assert (found.count <= npm.max_points(along, across, largest_face)).all() and (found.count >= 0).all()
    assert found.count[:-1].sum() > 0
    for k in np.flatnonzero(found.count):
        areas = found.areas[k, :found.count[k]]
        assert np.isfinite(areas).all() and (areas > 0).all()
        assert found.kind[k] in (npm.FACE_FACE, npm.EDGE_FACE, npm.VERTEX_FACE, npm.EDGE_EDGE)


@pytest.mark.parametrize("tilt_deg, kind, count", [(0.0, npm.FACE_FACE, 16), (1e-3, npm.FACE_FACE, 16), (3.0, npm.FACE_FACE, 4), (25.0, npm.EDGE_FACE, 4)])
def test_almost_parallel_faces_stay_a_face_contact(tilt_deg, kind, count):
    """A cube on a slab, its face lifted about an edge: flat or nearly (the far side within the
    tolerance) all 4 x 4 points; rocked 3 deg (below the 0.2 rad face-face limit) still a face
    contact, the grid's edge row touching; at 25 deg an edge-face contact, 4 points along it."""
    geometry, position, rotation = cube_on_ground(tilt_deg)
    found = npm.find(geometry, np.array([[0, 1]]), position, rotation, tolerance=TOLERANCE, density=DENSITY)
    assert found.kind[0] == kind and found.count[0] == count
    np.testing.assert_allclose(found.normal[0], [0, 0, 1], atol=1e-15)


def test_a_bed_joint_of_bricks_stored_in_float32_far_out_is_found_whole():
    """Two bricks (0.2 x 0.1 x 0.05 m, the upper one 0.05 m along) turned anyhow, 100 m from
    the origin and stored in float32 as STL stores them: their corners are off by up to 8e-6 m,
    folding each face by ~1e-4 rad. Their faces are joined again (geometry.FOLD_ANGLE_RAD), and
    the contact is the whole overlap of the beds, 0.15 x 0.1 m (found by a review: the faces
    came out as triangles, and the contact had 19 to 63 % of it)."""
    rng = np.random.default_rng(0)
    lower, upper = dd.box([0, 0, -0.05], [0.2, 0.1, 0]).vertices, dd.box([0.05, 0, 0], [0.25, 0.1, 0.05]).vertices
    for _ in range(10):
        turn = Rotation.random(random_state=rng).as_matrix()
        shapes = [dd.convex_hull((v @ turn.T + 100.0).astype(np.float32).astype(float)) for v in (lower, upper)]
        assert [len(s.faces) for s in shapes] == [6, 6]
        position, rotation = np.array([s.centroid for s in shapes]), np.repeat(np.eye(3)[None], 2, 0)
        found = npm.find(FlatGeometry.of(shapes), np.array([[0, 1]]), position, rotation, tolerance=TOLERANCE, density=DENSITY)
        assert found.kind[0] == npm.FACE_FACE
        # float32's spacing at 100 m is 7.6e-6 m: the overlap's sides are that uncertain
        assert found.areas[0, :found.count[0]].sum() == pytest.approx(0.015, abs=7.6e-6 * 0.5)  # times its perimeter
