"""The 3D building (drydem.masonry.building): counts, no overlaps, support, bonded corners,
volume, a 3D model with only the base fixed, refused specs."""

import dataclasses
import re

import numpy as np
import pytest

from drydem.errors import ModelError
from drydem.io.model_file import load_model, save_model
from drydem.masonry.building import LARGE, SMALL, BuildingSpec, building_blocks, building_model, course_pieces
from drydem.model.parameters import Supports


@pytest.fixture(scope="module")
def small():
    return building_model(SMALL)


@pytest.fixture(scope="module")
def large():
    return building_model(LARGE)


def corners(model):
    """(n, 3) min and max corners of every block's bounding box (all blocks are boxes), m."""
    return (np.array([s.vertices.min(0) for s in model.block_shape]),
            np.array([s.vertices.max(0) for s in model.block_shape]))


def wall_of(name: str) -> int:
    return int(re.fullmatch(r"s\d+w(\d)c\d+[bl]\d+", name).group(1))


def test_block_counts_are_the_documented_ones(small, large):
    assert small.n_blocks == 1936 and large.n_blocks == 19853
    assert 1800 <= small.n_blocks <= 2200 and 18_000 <= large.n_blocks <= 22_000


def test_names_unique_and_building_deterministic():
    first, again = building_blocks(SMALL), building_blocks(SMALL)
    assert first[0].name == "base" and first[0].fixed and not any(b.fixed for b in first[1:])
    assert [b.name for b in first] == [b.name for b in again]
    assert all(np.array_equal(a.shape.vertices, b.shape.vertices) for a, b in zip(first, again))
    assert all(wall_of(b.name) in range(4) for b in first[1:])


def test_no_initial_overlap_pairwise(small):
    """Box intersection volumes of every pair of SMALL, against a tolerance of round-off."""
    lo, hi = corners(small)
    depth = np.clip(np.minimum(hi[:, None], hi[None]) - np.maximum(lo[:, None], lo[None]), 0.0, None)
    volume = depth.prod(axis=2)
    np.fill_diagonal(volume, 0.0)
    h = SMALL.brick_height_m
    assert volume.max() <= 1e-9 * h ** 3


def supported_share(model, index: int, lo, hi, x_range=None) -> bool:
    """Whether block ``index``'s bottom face (within ``x_range`` of its along-wall extent, if
    given) overlaps in plan the top face of a block ending at its bottom z."""
    tol = 1e-9 * SMALL.brick_height_m
    a0, a1 = lo[index].copy(), hi[index].copy()
    if x_range is not None:
        axis = 0 if a1[0] - a0[0] > a1[1] - a0[1] else 1
        a0[axis], a1[axis] = x_range(a0[axis], a1[axis])
    below = np.abs(hi[:, 2] - lo[index, 2]) <= tol
    overlap = (np.minimum(hi[below, :2], a1[:2]) - np.maximum(lo[below, :2], a0[:2])).clip(0).prod(axis=1)
    return bool(overlap.max(initial=0.0) > 1e-6 * SMALL.brick_height_m ** 2)


def test_every_block_rests_on_one_below_and_lintels_bear_on_both_sides(small):
    lo, hi = corners(small)
    assert all(supported_share(small, i, lo, hi) for i in range(1, small.n_blocks))
    bearing = 0.5 * SMALL.brick_length_m
    lintels = [i for i, name in enumerate(small.block_name) if re.fullmatch(r"s\d+w\dc\d+l\d+", name)]
    assert len(lintels) == 4 * SMALL.storeys * SMALL.windows_per_wall
    for i in lintels:
        assert supported_share(small, i, lo, hi, lambda a, b: (a, a + bearing))
        assert supported_share(small, i, lo, hi, lambda a, b: (b - bearing, b))


def test_corners_alternate_the_through_wall(small):
    lo, hi = corners(small)
    t, h = SMALL.brick_width_m, SMALL.brick_height_m
    for cx in (0.5 * t, SMALL.length_m - 0.5 * t):
        for cy in (0.5 * t, SMALL.width_m - 0.5 * t):
            walls = []
            for course in range(SMALL.courses):
                point = np.array([cx, cy, (course + 0.5) * h])
                inside = np.flatnonzero(np.all((lo <= point) & (point <= hi), axis=1))
                assert len(inside) == 1
                walls.append(wall_of(small.block_name[inside[0]]) % 2)
            assert walls == [course % 2 for course in range(SMALL.courses)]


def test_running_bond_no_joint_continues_over_two_courses():
    """Without openings, the vertical joints of consecutive courses of a wall never meet, for
    walls of whole bricks and with a half brick over (closers)."""
    spec = dataclasses.replace(SMALL, windows_per_wall=0, door_height_courses=0)
    assert spec.wall_cells(0) % 4 == 0 and spec.wall_cells(1) % 4 == 2
    for wall in range(4):
        joints = [{a for a, _ in course_pieces(spec, wall, 0, c)[0][1:]} for c in range(spec.storey_height_courses)]
        assert all(not (j & k) for j, k in zip(joints, joints[1:]))
        pieces = [b - a for c in range(spec.storey_height_courses) for a, b in course_pieces(spec, wall, 0, c)[0]]
        assert min(pieces) >= 2 and max(pieces) <= 4


def test_volume_is_walls_less_openings(small, large):
    for spec, model in ((SMALL, small), (LARGE, large)):
        volume = sum(s.volume for s in model.block_shape[1:])
        assert volume == pytest.approx(spec.wall_volume_m3(), rel=1e-12)


def test_model_is_3d_with_only_the_base_fixed(small, large):
    for model in (small, large):
        assert not model.in_plane and model.supports == Supports()
        assert model.block_fixed[0].all() and not model.block_fixed[1:].any()


def test_model_file_round_trip(small, tmp_path):
    save_model(small, tmp_path / "building.toml")
    again = load_model(tmp_path / "building.toml")
    assert again.block_name == small.block_name and not again.in_plane


@pytest.mark.parametrize("change, words", [
    (dict(length_m=-1.5), "length_m = -1.5: must be a number"),
    (dict(storeys=True), "storeys = True: must be an integer"),
    (dict(brick_height_m=0.0), "brick_height_m = 0.0"),
    (dict(width_m=1.23), "width_m = 1.23: must be a whole number of half bricks"),
    (dict(windows_per_wall=4), "the openings do not fit in width_m"),
    (dict(window_height_courses=14), "sill_courses + window_height_courses + 1 (the lintel) = 21"),
    (dict(door_height_courses=20), "door_height_courses + 1 (the lintel) = 21"),
    (dict(length_m=500.0, width_m=500.0), "must be at most 200,000 blocks"),
])
def test_bad_specs_are_refused(change, words):
    with pytest.raises(ModelError, match=re.escape(words)):
        dataclasses.replace(SMALL, **change)


def test_spec_fields_are_keyword_only():
    with pytest.raises(TypeError):
        BuildingSpec(1.5, 1.25, 2, 20, 0.1, 0.05)


def test_block_count_is_counted_without_building(small, large):
    assert SMALL.block_count == small.n_blocks and LARGE.block_count == large.n_blocks


def test_the_overlap_check_gives_the_pairwise_penetration_depths(small):
    """drydem.model.assembly.penetration_depths, vectorised over the candidate pairs, against
    drydem.model.geometry.penetration_depth pair by pair (boxes, and turned hulls padded to the
    most vertices and faces), and a building with one brick pushed into another refused, named."""
    from drydem.model.assembly import Block, build_model, penetration_depths
    from drydem.model.boxes import bounds, overlapping_pairs
    from drydem.model.geometry import convex_hull, penetration_depth

    shapes = list(small.block_shape)
    pairs = overlapping_pairs(*bounds(shapes), small.block_movable, 0.0)
    depth = penetration_depths(shapes, pairs)
    assert np.array_equal(depth, [penetration_depth(shapes[i], shapes[j]) for i, j in pairs])
    rng = np.random.default_rng(3)
    def prism(n):  # an n-sided prism, turned and moved at random, near the others
        a = 2 * np.pi * np.arange(n) / n
        ring = np.column_stack([0.05 * np.cos(a), 0.05 * np.sin(a)])
        points = np.vstack([np.column_stack([ring, np.zeros(n)]), np.column_stack([ring, np.full(n, 0.04)])])
        turn, _ = np.linalg.qr(rng.normal(size=(3, 3)))
        return convex_hull(points @ turn.T + rng.normal(size=3) * 0.03)

    hulls = [prism(n) for n in (3, 5, 8, 12, 4)]
    mixed = [*hulls, *shapes[:3]]
    every = np.array([(i, j) for i in range(len(mixed)) for j in range(i + 1, len(mixed))])
    np.testing.assert_allclose(penetration_depths(mixed, every), [penetration_depth(mixed[i], mixed[j]) for i, j in every],
                               rtol=1e-12, atol=1e-15)
    blocks = building_blocks(dataclasses.replace(SMALL, storeys=1, storey_height_courses=12, window_height_courses=4, door_height_courses=0))
    k = next(k for k, b in enumerate(blocks) if b.name == "s0w0c3b2")
    blocks[k] = Block(name=blocks[k].name, shape=blocks[k].shape.transformed(np.eye(3), np.array([0.01, 0.0, 0.0])))
    with pytest.raises(ModelError, match=r"blocks 's0w0c3b2' and 's0w0c3b3' overlap by 0.01 m at the start"):
        build_model(blocks, density=1800.0)


@pytest.mark.parametrize("chunk", [1, 7, 1 << 14])
def test_the_first_overlap_is_named_whichever_chunk_of_candidate_pairs_holds_it(monkeypatch, chunk):
    # the pairs are found and checked a chunk at a time, up to the first overlap (coincident blocks
    # were all paired before one was named): the same pair, first in the sweep along x, at any chunk size
    import drydem.model.assembly as assembly
    from drydem.model.assembly import Block, build_model

    monkeypatch.setattr(assembly, "OVERLAP_PAIRS", chunk)
    blocks = building_blocks(dataclasses.replace(SMALL, storeys=1, storey_height_courses=12, window_height_courses=4, door_height_courses=0))
    for name in ("s0w0c3b2", "s0w1c4b1"):
        k = next(k for k, b in enumerate(blocks) if b.name == name)
        blocks[k] = Block(name=name, shape=blocks[k].shape.transformed(np.eye(3), np.array([0.01, 0.0, 0.0])))
    with pytest.raises(ModelError, match=r"blocks 's0w0c3b2' and 's0w0c3b3' overlap by 0.01 m at the start"):
        build_model(blocks, density=1800.0)


def test_thirty_thousand_coincident_cubes_are_refused_within_a_bounded_memory(tmp_path):
    """All the candidate pairs of 30,000 coincident cubes are 450 million (a MemoryError in 2.5 GB
    of address space before the pairs were found a chunk at a time); refused, naming the first
    two, in a process limited to 2.5 GB."""
    import resource
    import subprocess
    import sys

    script = tmp_path / "cubes.py"
    script.write_text(
        "import drydem as dd\n"
        "cube = dd.box([0, 0, 0], [0.1, 0.1, 0.1])\n"
        "blocks = [dd.Block(name='base', shape=dd.box([-1, -1, -0.1], [1, 1, 0]), fixed=True)]\n"
        "blocks += [dd.Block(name=f'c{k}', shape=cube) for k in range(30000)]\n"
        "try:\n"
        "    dd.build_model(blocks, density=2000.0)\n"
        "except dd.ModelError as error:\n"
        "    print(error)\n")
    limit = 2_500_000_000
    done = subprocess.run([sys.executable, str(script)], capture_output=True, text=True, timeout=300,
                          preexec_fn=lambda: resource.setrlimit(resource.RLIMIT_AS, (limit, limit)))
    assert done.returncode == 0, done.stderr[-2000:]
    assert "blocks 'c0' and 'c1' overlap by 0.1 m at the start" in done.stdout
