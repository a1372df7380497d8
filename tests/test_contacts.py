"""Contact detection: sub-contact grids, and broad + narrow phase against an all-pairs oracle."""

import itertools

import numpy as np
import pytest
from scipy.spatial import ConvexHull, cKDTree
from scipy.spatial.transform import Rotation

import drydem as dd
from drydem.engine import contacts
from drydem.engine import narrow_phase as npm
from drydem.engine.narrow_phase import SLIVER_FRACTION, narrow_phase
from drydem.model.boxes import bounds, overlapping_pairs, pair_chunks
from drydem.model.geometry import FlatGeometry
from drydem.model.parameters import ContactDensity
from oracles import contacts as oracle
from oracles import polygon
from conftest import BRICK, box_vertices, layout_blocks, prism_model


def detect_boxes(boxes, *, points, tolerance, rotation=np.eye(3)):
    shapes = [dd.convex_hull(box_vertices(lo, hi) @ rotation.T) for lo, hi in boxes]
    n = len(shapes)
    candidates = overlapping_pairs(*bounds(shapes), np.ones(n, bool), 0.5 * tolerance)
    sub, _ = oracle.narrow_phase(
        dict(enumerate(shapes)), candidates, np.array([s.centroid for s in shapes]), np.repeat(np.eye(3)[None], n, 0),
        tolerance=tolerance, density=ContactDensity(along=points, across=points),
    )
    return sub


def bed_joint(offset_x, points):
    """A brick on another, shifted ``offset_x`` along its length."""
    lx, ly, lz = BRICK
    return detect_boxes([([0, 0, 0], [lx, ly, lz]), ([offset_x, 0, lz], [offset_x + lx, ly, 2 * lz])], points=points, tolerance=1e-4)


@pytest.mark.parametrize("points", [2, 3, 4, 8])
def test_full_bed_joint_gets_n_by_n_points_with_trapezoid_areas(points):
    sub = bed_joint(0.0, points)
    lx, ly, _ = BRICK
    assert sub.count == points * points
    assert sub.area.sum() == pytest.approx(lx * ly, rel=1e-12)
    # trapezoid weights: a corner point carries a quarter cell, an interior point a full cell
    cell = (lx / (points - 1)) * (ly / (points - 1))
    assert sub.area.min() == pytest.approx(cell / 4)
    if points > 2:
        assert sub.area.max() == pytest.approx(cell)
    x = sub.point_ref_body[:, 0] + 0.5 * lx  # reference points in the bottom brick's frame
    np.testing.assert_allclose(np.unique(x.round(12)), np.linspace(0, lx, points), atol=1e-12)


def test_corner_points_only_with_two_points_per_length():
    sub = bed_joint(0.0, 2)
    lx, ly, _ = BRICK
    corners = np.abs(sub.point_ref_body[:, :2])
    np.testing.assert_allclose(corners, np.tile([lx / 2, ly / 2], (4, 1)), atol=1e-12)


def test_single_point_sits_at_the_contact_centroid():
    sub = bed_joint(0.5 * BRICK[0], 1)
    assert sub.count == 1
    assert sub.area[0] == pytest.approx(0.5 * BRICK[0] * BRICK[1])
    assert sub.point_ref_body[0, 0] == pytest.approx(0.25 * BRICK[0])


def test_half_overlap_of_running_bond_keeps_the_spacing_and_both_ends():
    # 4 points along 25 mm: spacing 8.33 mm; a 12.5 mm overlap needs 2 intervals -> 3 points
    sub = bed_joint(0.5 * BRICK[0], 4)
    x = np.unique(sub.point_ref_body[:, 0].round(12))
    np.testing.assert_allclose(x, [0.0, 0.25 * BRICK[0], 0.5 * BRICK[0]], atol=1e-12)
    assert sub.area.sum() == pytest.approx(0.5 * BRICK[0] * BRICK[1])


def test_non_rectangular_overlap_areas_sum_to_the_polygon():
    # a brick turned 30 deg about z on a larger slab: the contact polygon is the turned rectangle
    rot = Rotation.from_euler("z", 30, degrees=True).as_matrix()
    slab = dd.box([-0.1, -0.1, -0.01], [0.1, 0.1, 0.0])
    brick = dd.convex_hull(box_vertices([-0.0125, -0.006, 0.0], [0.0125, 0.006, 0.0055]) @ rot.T)
    fc, separation = oracle.face_contact(slab, brick, 0, 1, tolerance=1e-4, density=ContactDensity(along=4, across=4))
    assert separation == pytest.approx(0.0, abs=1e-15)
    assert fc.areas.sum() == pytest.approx(BRICK[0] * BRICK[1], rel=1e-9)
    assert fc.ref == 0 and np.allclose(fc.normal, [0, 0, 1])


def random_box_cloud(rng, n=5):
    """Boxes on a jittered n^3 lattice, each side pulled in by 0, a gap within or beyond the
    tolerance, or a lot; about a third of the cells empty. Returns boxes and the tolerance."""
    tolerance = 1e-3
    lines = [np.cumsum(rng.uniform(0.5, 1.5, n + 1)) for _ in range(3)]
    pulls = np.array([0.0, 0.0, 0.3 * tolerance, 0.45 * tolerance, 3 * tolerance, 0.2])
    boxes = {}
    for cell in itertools.product(range(n), repeat=3):
        if rng.random() < 0.35:
            continue
        lo = np.array([lines[k][cell[k]] for k in range(3)]) + rng.choice(pulls, 3)
        hi = np.array([lines[k][cell[k] + 1] for k in range(3)]) - rng.choice(pulls, 3)
        boxes[cell] = (lo, hi)
    return boxes, tolerance


def oracle_contact_areas(boxes, tolerance):
    """All pairs: boxes touch through a face if their gap along one axis is <= tolerance and
    they overlap (with positive area) in the other two; the contact area is that overlap."""
    areas = {}
    cells = list(boxes)
    for i, j in itertools.combinations(range(len(cells)), 2):
        (lo_a, hi_a), (lo_b, hi_b) = boxes[cells[i]], boxes[cells[j]]
        overlap = np.minimum(hi_a, hi_b) - np.maximum(lo_a, lo_b)  # negative = gap
        for axis in range(3):
            others = [k for k in range(3) if k != axis]
            if -tolerance <= overlap[axis] <= 1e-12 and np.all(overlap[others] > 0):
                areas[(i, j)] = float(np.prod(overlap[others]))
    return areas


@pytest.mark.parametrize("seed", range(6))
def test_detection_matches_all_pairs_oracle_on_random_clouds(seed):
    rng = np.random.default_rng(seed)
    boxes, tolerance = random_box_cloud(rng)
    expected = oracle_contact_areas(boxes, tolerance)
    assert len(expected) > 20  # the cloud really has contacts
    rotation = Rotation.random(random_state=rng).as_matrix()  # detection is frame invariant
    sub = detect_boxes(list(boxes.values()), points=2, tolerance=tolerance, rotation=rotation)
    found = {}
    for k, (a, b) in enumerate(sub.pairs):
        found[(min(a, b), max(a, b))] = sub.area[sub.contact == k].sum()
    assert set(found) == set(expected)
    for pair, area in expected.items():
        assert found[pair] == pytest.approx(area, rel=1e-9)
    assert np.all(np.bincount(sub.contact) == 4)  # rectangles: corner points only


@pytest.mark.parametrize("most", [0, 1, 50, 10**9])  # 0: taken as 1 (a chunk of no pair would never move on)
def test_the_pairs_in_chunks_are_all_the_pairs_each_once(most):
    """drydem.model.boxes.pair_chunks: the chunks hold the pairs of overlapping_pairs, each once,
    and every chunk but the last reaches ``most``, so that a caller stopping at its first chunk
    holds about ``most`` pairs (plus one block's), not all."""
    rng = np.random.default_rng(11)
    lo = rng.uniform(0, 5, (200, 3))
    shapes = [dd.box(l, l + rng.uniform(0.1, 1.5, 3)) for l in lo]
    movable = rng.random(200) < 0.8
    chunks = list(pair_chunks(*bounds(shapes), movable, 0.05, most))
    every = np.concatenate(chunks)
    assert sorted(map(tuple, every.tolist())) == sorted(map(tuple, overlapping_pairs(*bounds(shapes), movable, 0.05).tolist()))
    assert len({tuple(p) for p in every.tolist()}) == len(every)
    assert all(len(c) >= most for c in chunks[:-1]) and (most > 1 or len(chunks) > 1)


def test_broad_phase_matches_all_pairs_bounding_box_test():
    rng = np.random.default_rng(7)
    lo = rng.uniform(0, 10, (300, 3))
    shapes = [dd.box(l, l + rng.uniform(0.1, 1.5, 3)) for l in lo]
    movable = rng.random(300) < 0.8
    found = {tuple(p) for p in overlapping_pairs(*bounds(shapes), movable, 0.05)}
    lo_b = np.array([s.vertices.min(0) for s in shapes]) - 0.05
    hi_b = np.array([s.vertices.max(0) for s in shapes]) + 0.05
    expected = {
        (i, j)
        for i, j in itertools.combinations(range(300), 2)
        if (movable[i] or movable[j]) and np.all(lo_b[i] <= hi_b[j]) and np.all(lo_b[j] <= hi_b[i])
    }
    assert found == expected and len(expected) > 50


def test_redetection_keeps_shear_stress_of_the_same_pair():
    model = dd.build_model(
        [dd.Block(name="base", shape=dd.box([-0.1, -0.1, -0.01], [0.1, 0.1, 0]), fixed=True),
         dd.Block(name="b", shape=dd.box([0, 0, 0], [0.025, 0.012, 0.0055]))],
        density=1800.0,
    )
    sim = dd.Simulation(model)
    sim.contacts.shear_force[:, 0] = 2.0 * sim.contacts.area  # 2 Pa of shear stress on the block
    sim.contacts.intact[0] = False
    sim.state.position[1, 0] += 1e-4  # slid a little: the grid moves with the overlap
    sim.detect_contacts()
    np.testing.assert_allclose(sim.contacts.shear_force[:, 0] / sim.contacts.area, 2.0)
    assert (~sim.contacts.intact).sum() == 1


def test_compiled_merge_carries_shear_over_as_the_numpy_oracle(benchmark_wall):
    """drydem.engine.refresh.merge against subset + carry_over (scipy cKDTree) + concatenate: the
    benchmark wall tilted 15 deg for 300 cycles (shear everywhere, blocks moved since their
    contacts were made), half of the contacts re-made by the narrow phase."""
    from conftest import tilted_gravity
    from drydem.engine import refresh
    from drydem.model.rotation import matrices

    sim = dd.Simulation(benchmark_wall)
    sim.cycle_to_equilibrium()
    sim.cycle(300, gravity=tilted_gravity(15.0))
    old, state, m = sim.contacts, sim.state, benchmark_wall
    rotation = matrices(state.quaternion)
    keep = np.random.default_rng(0).random(len(old.pairs)) < 0.5
    stale = old.pairs[~keep]
    fresh, _ = narrow_phase(m.geometry, stale, state.position, rotation, tolerance=m.contact_tolerance, density=m.contact_density)
    fast = refresh.merge(old, keep, fresh, state.position, rotation)
    oracle_fresh = fresh.copy()
    oracle.carry_over(contacts.subset(old, ~keep), oracle_fresh, state.position, rotation)
    slow = oracle.concatenate(contacts.subset(old, keep), oracle_fresh)
    for name in contacts.SubContacts._fields:
        np.testing.assert_allclose(getattr(fast, name), getattr(slow, name), rtol=0, atol=1e-12 * np.abs(getattr(slow, name)).max(), err_msg=name)
    assert np.abs(fast.shear_force[fast.start[keep.sum()]:]).max() > 0 and (~fast.intact).any()  # carried, some slipped


@pytest.mark.parametrize("everything", [False, True])
def test_compiled_pair_matching_agrees_with_set_operations(everything):
    """drydem.engine.refresh.match_pairs against NumPy set operations on random neighbour lists."""
    from drydem.engine import refresh

    rng = np.random.default_rng(5)
    nb = 40

    def sorted_pairs(n):
        i, j = np.triu_indices(nb, 1)
        chosen = np.sort(rng.choice(len(i), n, replace=False))
        return np.stack([i[chosen], j[chosen]], axis=1).astype(np.int64)

    old_pairs, pairs = sorted_pairs(200), sorted_pairs(200)
    limit, motion = rng.random(200), rng.random(200)
    contact_pairs = np.concatenate([old_pairs[::3], pairs[1::4]])
    contact_pairs[::2] = contact_pairs[::2, ::-1]  # contacts list (ref, inc) in either order
    where, kept, keep_contact = refresh.match_pairs(old_pairs, limit, motion, pairs, contact_pairs, nb, everything=everything)
    old_keys, keys = contacts.pair_keys(old_pairs, nb), contacts.pair_keys(pairs, nb)
    known = np.isin(keys, old_keys)
    np.testing.assert_array_equal(where[known], np.searchsorted(old_keys, keys[known]))
    assert (where[~known] == -1).all() and known.sum() > 10
    expected = known & (not everything)
    expected[known] &= motion[where[known]] <= 0.5 * limit[where[known]]
    np.testing.assert_array_equal(kept, expected)
    np.testing.assert_array_equal(keep_contact, np.isin(contacts.pair_keys(contact_pairs, nb), keys[expected]))


def at_rest(shapes):
    """Positions (the centroids) and rotations (none) of blocks given by their world shapes."""
    return np.array([s.centroid for s in shapes]), np.repeat(np.eye(3)[None], len(shapes), 0)


def smaller_face_area(shapes, ref, inc, normal):
    """Area of the smaller of a contact's two faces (shapes at rest: body normal = world normal), m2."""
    f_ref, f_inc = np.argmax(shapes[ref].face_normals @ normal), np.argmin(shapes[inc].face_normals @ normal)
    return min(shapes[ref].face_area(f_ref), shapes[inc].face_area(f_inc))


def compare_narrow_phases(shapes, candidates, tolerance, density):
    """The compiled narrow phase against the plain-Python one, field by field."""
    position, rotation = at_rest(shapes)
    fast, fast_sep = narrow_phase(FlatGeometry.of(shapes), candidates, position, rotation, tolerance=tolerance, density=density)
    return assert_as_the_python_narrow_phase(fast, fast_sep, shapes, candidates, tolerance, density)


def assert_as_the_python_narrow_phase(fast, fast_sep, shapes, candidates, tolerance, density):
    """The compiled narrow phase's sub-contacts ``fast`` and separations ``fast_sep`` (shapes at
    rest) against the plain-Python one's, field by field; returns the latter."""
    position, rotation = at_rest(shapes)
    slow, slow_sep = oracle.narrow_phase(dict(enumerate(shapes)), candidates, position, rotation, tolerance=tolerance, density=density)
    np.testing.assert_allclose(fast_sep, slow_sep, rtol=0, atol=1e-12 * np.abs(position).max())
    np.testing.assert_array_equal(fast.pairs, slow.pairs)
    np.testing.assert_array_equal(fast.start, slow.start)
    scale = max(s.size for s in shapes)
    np.testing.assert_allclose(fast.normal_body, slow.normal_body, rtol=0, atol=1e-12)
    np.testing.assert_allclose(fast.offset, slow.offset, rtol=0, atol=1e-9 * scale)
    # within a contact the same points, maybe in another order: a polygon vertex lying on a
    # clipping edge can come out first in one and not the other; and where clipping leaves two
    # vertices ~1e-8 m apart at a corner of a rocked brick, round-off picks which one is kept
    # (measured 1.2e-8 m; the grid spacing is millimetres): stated tolerance 1e-6 of the block size.
    # Areas agree to a sliver (SLIVER_FRACTION of the smaller face, measured 2e-15 of it): a
    # difference finer than the smallest area a sub-contact may have means nothing, and no
    # sub-contact is a sliver (a grid cell grazed by the contact polygon)
    for k in range(len(slow.pairs)):
        rows = slice(slow.start[k], slow.start[k + 1])
        tree = cKDTree(slow.point_ref_body[rows])
        distance, match = tree.query(fast.point_ref_body[rows])
        assert distance.max() <= 1e-6 * scale
        np.testing.assert_allclose(fast.point_inc_body[rows], slow.point_inc_body[rows][match], rtol=0, atol=1e-6 * scale)
        sliver = SLIVER_FRACTION * smaller_face_area(shapes, *slow.pairs[k], slow.normal_body[k])
        np.testing.assert_allclose(fast.area[rows], slow.area[rows][match], rtol=0, atol=sliver)
        assert slow.area[rows].min() > sliver
    return slow


@pytest.mark.parametrize("seed", range(3))
def test_compiled_narrow_phase_matches_the_python_one_on_random_clouds(seed):
    rng = np.random.default_rng(seed)
    boxes, tolerance = random_box_cloud(rng)
    rotation = Rotation.random(random_state=rng).as_matrix()
    shapes = [dd.convex_hull(box_vertices(lo, hi) @ rotation.T) for lo, hi in boxes.values()]
    candidates = overlapping_pairs(*bounds(shapes), np.ones(len(shapes), bool), 0.5 * tolerance)
    sub = compare_narrow_phases(shapes, candidates, tolerance, ContactDensity(along=3, across=3))
    assert sub.count > 50


@pytest.mark.parametrize("along, across", [(1, 1), (2, 2), (4, 2), (4, 1), (8, 8)])
def test_compiled_narrow_phase_matches_on_a_wall_with_turned_and_rocked_bricks(along, across):
    # every brick of a small wall turned a little about random axes: contact polygons that are
    # not rectangles (lumped grid), rocking gaps, points dropped beyond the tolerance
    rng = np.random.default_rng(along * 10 + across)
    # 4 bricks x 6 courses, a 2 x 2 half-brick opening under a lintel
    blocks = layout_blocks("""
        BBBB
        bBBBb
        bLb
        B__B
        bb__bb
        BBBB
    """)
    shapes = []
    for b in blocks:
        turn = np.eye(3) if b.fixed else Rotation.from_rotvec(rng.normal(scale=0.01, size=3)).as_matrix()
        c = b.shape.centroid
        shapes.append(dd.convex_hull((b.shape.vertices - c) @ turn.T + c))
    candidates = overlapping_pairs(*bounds(shapes), np.ones(len(shapes), bool), 2e-4)
    sub = compare_narrow_phases(shapes, candidates, 2e-4, ContactDensity(along=along, across=across))
    assert sub.count > 0


def stacked_prisms(sides, radius=0.1, height=0.05):
    """A fixed regular prism of ``sides`` sides (circumradius ``radius``, axis z, top at z = 0)
    and a free one on it turned half a side: their contact is the regular polygon of 2 ``sides``
    sides whose apothem is the prisms' own (imported column drums, rounded stones)."""

    def prism(z0, z1, turn):
        angle = 2 * np.pi * np.arange(sides) / sides + turn
        ring = radius * np.stack([np.cos(angle), np.sin(angle)], axis=1)
        return dd.convex_hull(np.concatenate([np.c_[ring, np.full(sides, z0)], np.c_[ring, np.full(sides, z1)]]))

    return [dd.Block(name="base", shape=prism(-height, 0.0, 0.0), fixed=True), dd.Block(name="drum", shape=prism(0.0, height, np.pi / sides))]


def skewed_prism_on_a_slab():
    """A prism standing on a fixed slab, its section the convex quadrilateral (0, 0), (1, -3),
    (1, 3.2), (0, 0.2) x 20 mm: two opposite sides lean 72 deg either way from their mean
    direction x, so they are 3.2 times longer than the prism is wide along it."""
    section = 0.02 * np.array([[0.0, 0.0], [1.0, -3.0], [1.0, 3.2], [0.0, 0.2]])
    prism = dd.convex_hull(np.concatenate([np.c_[section, np.zeros(4)], np.c_[section, np.full(4, 0.02)]]))
    return [dd.Block(name="slab", shape=dd.box([-0.1, -0.1, -0.02], [0.1, 0.1, 0.0]), fixed=True), dd.Block(name="prism", shape=prism)]


#: run in a subprocess by :func:`detect_and_settle` (argv: tests folder, Python expression for
#: the blocks, .npz file out)
DETECT_AND_SETTLE = """
import json, sys
import numpy as np
sys.path.insert(0, sys.argv[1])
import drydem as dd
from drydem.engine.narrow_phase import narrow_phase
import test_contacts

model = dd.build_model(eval(sys.argv[2], vars(test_contacts)), density=2400.0)
position, rotation = test_contacts.at_rest(model.block_shape)
fast, separation = narrow_phase(
    model.geometry, np.array([[0, 1]]), position, rotation, tolerance=model.contact_tolerance, density=model.contact_density
)
np.savez(sys.argv[3], separation=separation, **fast._asdict())
sim = dd.Simulation(model)
result = sim.cycle_to_equilibrium()
print(json.dumps({"converged": result.converged, "displacement": (sim.state.position[1] - position[1]).tolist(),
                  "normal_force": float(sim.contacts.normal_force.sum())}))
"""


def detect_and_settle(blocks, tmp_path):
    """Two blocks (the Python expression ``blocks``, evaluated in this module; density 2400
    kg/m3, default joint and contacts) at rest: the compiled narrow phase's sub-contacts, held
    to the Python one's, then the model cycled to equilibrium under gravity, both in a
    subprocess, so that a crash of compiled code fails the test instead of killing pytest.
    Returns the model, the sub-contacts and the second block's state at rest (dict:
    converged, displacement (3,) m, normal_force N)."""
    import json
    import pathlib
    import subprocess
    import sys

    found = tmp_path / "found.npz"
    run = subprocess.run(
        [sys.executable, "-c", DETECT_AND_SETTLE, str(pathlib.Path(__file__).parent), blocks, str(found)],
        capture_output=True, text=True, timeout=600,
    )
    assert run.returncode == 0, run.stderr[-3000:]
    model = dd.build_model(eval(blocks), density=2400.0)
    with np.load(found) as saved:
        fast = contacts.SubContacts(**{name: saved[name] for name in contacts.SubContacts._fields})
        separation = saved["separation"]
    assert_as_the_python_narrow_phase(
        fast, separation, list(model.block_shape), np.array([[0, 1]]), model.contact_tolerance, model.contact_density
    )
    return model, fast, json.loads(run.stdout)


@pytest.mark.parametrize("sides", [40, 100])
def test_many_sided_prisms_touch_over_their_whole_common_polygon_and_settle(sides, tmp_path):
    model, fast, settled = detect_and_settle(f"stacked_prisms({sides})", tmp_path)
    apothem = 0.1 * np.cos(np.pi / sides)
    polygon_area = 2 * sides * apothem**2 * np.tan(np.pi / (2 * sides))
    assert fast.area.sum() == pytest.approx(polygon_area, rel=1e-9)
    # at rest on the whole polygon, carrying the drum's weight: it sinks by the joint's closure
    # W / (kn A), straight down (the points' areas have the polygon's centroid, so the drum does
    # not tilt: measured 3.6e-5 and 4.4e-5 from W / (kn A), the equilibrium criterion's residue;
    # 6e-4 before the lumped grid)
    weight = model.block_mass[1] * dd.G
    closure = weight / (model.joint.kn * polygon_area)
    assert settled["converged"]
    assert settled["normal_force"] == pytest.approx(weight, rel=1e-3)
    assert -settled["displacement"][2] == pytest.approx(closure, rel=1e-3)
    assert np.abs(settled["displacement"][:2]).max() < 1e-6 * closure


def test_skewed_quadrilateral_contact_gets_at_most_n_plus_one_points_per_direction(tmp_path):
    # the spacing rule alone would put 11 points along the leaning sides (3.2 x 3 intervals):
    # n + 1 along them, n along the others (4 by default)
    model, fast, settled = detect_and_settle("skewed_prism_on_a_slab()", tmp_path)
    along = model.contact_density.along
    assert fast.count == (along + 1) * along
    assert fast.area.sum() == pytest.approx(0.02 * 0.02 * 3.2, rel=1e-12)  # the section's area
    assert settled["converged"] and settled["normal_force"] == pytest.approx(model.block_mass[1] * dd.G, rel=1e-3)


@pytest.mark.parametrize("seed", range(3))
def test_vertex_shares_give_the_polygon_s_area_and_first_moments_and_a_repeated_vertex_changes_nothing(seed):
    rng = np.random.default_rng(seed)
    cloud = 0.01 * rng.uniform(-1, 1, (12, 2))
    poly = cloud[ConvexHull(cloud).vertices]  # counter-clockwise
    shares = np.empty(len(poly))
    npm._vertex_shares(poly, len(poly), shares)
    area = polygon.signed_area(poly)
    assert (shares > 0).all() and shares.sum() == pytest.approx(area, rel=1e-12)
    # exact for a linear function: the first moments are the polygon's (to round-off of area x size)
    np.testing.assert_allclose(shares @ poly, area * polygon.centroid(poly), rtol=0, atol=1e-12 * area * 0.01)
    np.testing.assert_allclose(shares, polygon.vertex_shares(poly), rtol=0, atol=1e-12 * area)
    # a vertex repeated (round-off of clipping): the two copies, merged into one point, carry what it did
    repeated = np.insert(poly, 2, poly[2], axis=0)
    twice = np.empty(len(repeated))
    npm._vertex_shares(repeated, len(repeated), twice)
    np.testing.assert_allclose(np.r_[twice[:2], twice[2] + twice[3], twice[4:]], shares, rtol=0, atol=1e-12 * area)
    # a thin piece 10 m from the frame's origin (a large slab's face, its first vertex far away):
    # a third to each corner still, to the digits its coordinates have there (1e-15 m of 1e-9 m;
    # computed from the origin, the shares were +-1e4 times the area)
    thin = np.array([[0.0, 0.0], [0.05, 0.0], [0.05, 1e-9]]) + 10.0
    thirds = np.empty(3)
    npm._vertex_shares(thin, 3, thirds)
    np.testing.assert_allclose(thirds, 0.5 * 0.05 * 1e-9 / 3, rtol=1e-5)
    # each corner of a rectangle a quarter
    rectangle = np.empty(4)
    npm._vertex_shares(polygon.rectangle(0.0, 0.02, 0.0, 0.01), 4, rectangle)
    np.testing.assert_allclose(rectangle, 0.25 * 0.02 * 0.01, rtol=1e-12)


@pytest.mark.parametrize("points", [2, 4, 16])
@pytest.mark.parametrize("sides", [5, 40])
def test_a_polygon_contact_has_a_point_at_each_corner_and_the_polygon_s_area_and_centroid(sides, points):
    # a regular prism on a slab: the contact polygon is its base. A block rocks about the
    # outermost points of its contact, so they must be the corners (the grid before the lumped
    # one moved the points of cut cells to the cells' centroids, inside the corners: a 40-sided
    # prism toppled at 14.5 deg instead of atan(1/3) = 18.43, tests/test_tilt.py)
    model = prism_model(sides, 0.02, 0.12, points=points)
    shapes = list(model.block_shape)
    sub = compare_narrow_phases(shapes, np.array([[0, 1]]), model.contact_tolerance, model.contact_density)
    position, rotation = at_rest(shapes)
    x, gap, _ = contacts.world_points(sub, position, rotation)
    corners = shapes[1].vertices[shapes[1].vertices[:, 2] < 0.06]
    distance, _ = cKDTree(x).query(corners)
    assert distance.max() <= 1e-9 * 0.02  # the geometric tolerance: 1e-9 of the block's size
    area = 0.5 * sides * 0.02**2 * np.sin(2 * np.pi / sides)
    assert sub.area.sum() == pytest.approx(area, rel=1e-12)
    np.testing.assert_allclose(sub.area @ x[:, :2], 0.0, rtol=0, atol=1e-12 * area * 0.02)  # centred on the axis
    np.testing.assert_allclose(gap, 0.0, rtol=0, atol=1e-12 * 0.02)


def test_a_contact_whose_points_outgrow_its_row_is_flagged_and_found_again_in_a_wider_one():
    # a 40-sided base at 4 points per length has 52 points (its 40 corners, 12 grid points): more
    # than a row sized for a bilinear grid (45); find sizes rows for the pairs' largest face
    model = prism_model(40, 0.02, 0.12)
    position, rotation = at_rest(list(model.block_shape))
    pairs, density = np.array([[0, 1]]), model.contact_density
    narrow = npm.Found.empty(1, npm.max_points(density.along, density.across, 0))
    npm.find_sub_contacts(model.geometry, position, rotation, pairs, model.contact_tolerance, density.along, density.across,
                          np.asarray(density.across_axis, dtype=float), narrow)
    assert narrow.count[0] == -1  # flagged, not cut short
    found = npm.find(model.geometry, pairs, position, rotation, tolerance=model.contact_tolerance, density=density)
    assert found.count[0] == 52 and found.areas[0, :52].sum() == pytest.approx(0.5 * 40 * 0.02**2 * np.sin(2 * np.pi / 40), rel=1e-12)

