"""Imperfect bricks (drydem.masonry.imperfections): heights, tilted bed faces and misalignment
drawn from a seed, built course on course without overlaps; zero amplitude is the perfect wall."""

import math
import re

import numpy as np
import pytest
from click.testing import CliRunner

from drydem.cli import main
from drydem.errors import ModelError
from drydem.io.target import load_target
from drydem.masonry.imperfections import (
    DRAWN_THICKNESS_FRACTION, Imperfections, exaggerated_model, imperfect_blocks, imperfect_model, placement,
)
from drydem.masonry.walls import wall_from_dict
from drydem.model.boxes import bounds, overlapping_pairs
from drydem.model.geometry import penetration_depth

WALLS = [f"WD{k}" for k in range(1, 8)]
#: the seed paper's brick (Savalle et al. 2022): length, height, width, m
L, H, W = 0.025, 0.0055, 0.012
#: every kind at the largest amplitudes allowed for that brick (10 % and 5 % of its height, a quarter of its length)
LARGEST = Imperfections(height_sd_mm=0.55, flatness_sd_mm=0.275, misalignment_sd_mm=6.25)
#: every kind at realistic amplitudes
REALISTIC = Imperfections(height_sd_mm=0.1, flatness_sd_mm=0.05, misalignment_sd_mm=0.2)


def small_wall(courses: str):
    """A wall of the seed paper's bricks laid as ``courses`` (drydem.masonry.layout), density 1800."""
    data = {"brick": {"length_m": L, "height_m": H, "width_m": W}, "supports": {"fix_y": True}, "layout": {"courses": courses}}
    return wall_from_dict(data, source="small.toml")


def unit_draws(seed: int, n: int):
    """The documented draws (module docstring): one stream per kind from SeedSequence(seed).spawn(3)."""
    heights, flatness, misalignment = (np.random.default_rng(s) for s in np.random.SeedSequence(seed).spawn(3))
    return heights.standard_normal(n), flatness.standard_normal((n, 2)), misalignment.standard_normal(n)


def course_of(name: str) -> int:
    """A block's course from its name (c{course}b{k}); the base is course -1."""
    return -1 if name == "base" else int(re.match(r"c(\d+)b", name).group(1))


def deepest_overlaps(model) -> tuple[float, np.ndarray]:
    """The deepest overlap of two blocks of ``model``, m, and for each block the smallest
    separation from a block of a lower course (the base counts as lower), m (inf for the base)."""
    shapes = list(model.block_shape)
    courses = [course_of(name) for name in model.block_name]
    deepest, resting = -math.inf, np.full(len(shapes), math.inf)
    for i, j in overlapping_pairs(*bounds(shapes), np.ones(len(shapes), dtype=bool), 1e-6):
        depth = penetration_depth(shapes[i], shapes[j])
        deepest = max(deepest, depth)
        upper = i if courses[i] > courses[j] else j if courses[j] > courses[i] else None
        if upper is not None:
            resting[upper] = min(resting[upper], -depth)
    return deepest, resting


def same_geometry(a, b) -> bool:
    return len(a) == len(b) and all(x.name == y.name and np.array_equal(x.shape.vertices, y.shape.vertices) for x, y in zip(a, b))


@pytest.mark.parametrize("name", WALLS)
def test_zero_amplitude_gives_the_perfect_wall_bit_for_bit(name):
    perfect = load_target(name)
    model = imperfect_model(perfect.wall, Imperfections(height_distribution="uniform"), seed=7)
    assert model.block_name == perfect.model.block_name
    for a, b in zip(model.block_shape, perfect.model.block_shape):
        assert np.array_equal(a.vertices, b.vertices) and all(np.array_equal(f, g) for f, g in zip(a.faces, b.faces))
    for field in ("block_mass", "block_centroid", "block_inertia", "block_fixed", "block_radius"):
        assert np.array_equal(getattr(model, field), getattr(perfect.model, field)), field
    assert model.contact_tolerance == perfect.model.contact_tolerance and model.in_plane == perfect.model.in_plane


def test_the_same_seed_gives_the_same_wall_and_another_seed_another():
    wall = load_target("WD3").wall
    first = imperfect_blocks(wall, REALISTIC, seed=3)
    assert same_geometry(first, imperfect_blocks(wall, REALISTIC, seed=3))
    assert not same_geometry(first, imperfect_blocks(wall, REALISTIC, seed=4))


@pytest.mark.parametrize("name", WALLS)
def test_no_wall_has_initial_overlaps_and_every_brick_rests_on_what_is_below(name):
    wall = load_target(name).wall
    model = imperfect_model(wall, LARGEST, seed=WALLS.index(name))  # build_model refuses overlaps deeper than 1e-6 m
    assert model.block_name == ("base", *wall.layout.block_names())
    deepest, resting = deepest_overlaps(model)
    assert deepest <= 1e-9 * H
    assert np.all(np.abs(resting[1:]) <= 1e-9 * H)  # each brick touches what it was laid on


@pytest.mark.parametrize("seed", range(25))
def test_no_initial_overlaps_over_many_seeds_with_headers_lintel_voids_and_honeycomb(seed):
    wall = small_wall("bBBBb\nB,bHb,B\nL.b\nbB.B.b\n,B,B,B,\nbBBBb\nBBBB")
    imperfections = LARGEST if seed % 2 else Imperfections(height_sd_mm=0.55, height_distribution="uniform", flatness_sd_mm=0.1,
                                                           misalignment_sd_mm=1.0)
    deepest, resting = deepest_overlaps(imperfect_model(wall, imperfections, seed))
    assert deepest <= 1e-9 * H
    assert np.all(np.abs(resting[1:]) <= 1e-9 * H)


def test_a_height_deviation_changes_each_bricks_mass_and_the_column_height_as_drawn():
    """A column of three bricks: brick k is h + dh_k high, dh_k = height_sd z_k (the documented
    draws), its mass 1800 L W (h + dh_k), and it stands on the one below."""
    wall = small_wall("B\nB\nB")
    model = imperfect_model(wall, Imperfections(height_sd_mm=0.3), seed=11)
    dh = 0.3e-3 * unit_draws(11, 3)[0]
    assert np.allclose(model.block_mass[1:], 1800.0 * L * W * (H + dh), rtol=1e-12, atol=0.0)
    tops = np.cumsum(H + dh)
    for k, shape in enumerate(model.block_shape[1:]):
        z = shape.vertices[:, 2]
        assert z.min() == pytest.approx(tops[k] - (H + dh[k]), abs=1e-15) and z.max() == pytest.approx(tops[k], abs=1e-15)


def test_height_deviations_change_the_mass_of_every_block_of_a_wall_as_computed():
    found = load_target("WD3")
    model = imperfect_model(found.wall, Imperfections(height_sd_mm=0.2), seed=5)
    dh = 0.2e-3 * unit_draws(5, len(found.wall.layout.solid_units))[0]
    assert np.allclose(model.block_mass[1:], found.model.block_mass[1:] * (H + dh) / H, rtol=1e-12, atol=0.0)


def test_flatness_tilts_the_bed_faces_as_drawn_and_keeps_the_volume():
    wall = small_wall("B\nB")
    model = imperfect_model(wall, Imperfections(flatness_sd_mm=0.2), seed=2)
    edge = 0.2e-3 * unit_draws(2, 2)[1]  # right edge above the face's mid-line: bottom, top
    for k, shape in enumerate(model.block_shape[1:]):
        assert shape.volume == pytest.approx(L * W * H, rel=1e-12)
        v = shape.vertices
        left, right = v[v[:, 0] < L / 2], v[v[:, 0] > L / 2]
        assert right[:, 2].min() - left[:, 2].min() == pytest.approx(2 * edge[k, 0], abs=1e-15)
        assert right[:, 2].max() - left[:, 2].max() == pytest.approx(2 * edge[k, 1], abs=1e-15)
    assert model.in_plane  # tilted along the wall only: the blocks stay prisms across it


def test_misalignment_moves_bricks_as_drawn_but_never_into_their_left_neighbour():
    shift = 1.0e-3 * unit_draws(4, 2)[2]
    apart = placement(small_wall("B_B"), Imperfections(misalignment_sd_mm=1.0), seed=4)
    assert np.allclose(apart.x_start, [0.0, 2 * L] + shift, rtol=0.0, atol=1e-18)
    butted = placement(small_wall("BB"), Imperfections(misalignment_sd_mm=1.0), seed=4)
    assert butted.x_start[1] == max(L + shift[1], butted.x_end[0])
    assert np.allclose(butted.x_end - butted.x_start, L, rtol=1e-12)


@pytest.mark.parametrize("distribution", ["normal", "uniform"])
def test_height_draws_have_the_standard_deviation_asked_and_uniform_ones_stay_in_bounds(distribution):
    wall = load_target("WD2").wall
    dh = placement(wall, Imperfections(height_sd_mm=0.4, height_distribution=distribution), seed=1).height
    assert np.std(dh) == pytest.approx(0.4e-3, rel=0.15)  # 192 bricks: sampling error about 5 %
    if distribution == "uniform":
        assert np.abs(dh).max() <= math.sqrt(3.0) * 0.4e-3
        assert np.abs(dh).max() > 0.9 * math.sqrt(3.0) * 0.4e-3  # spread over the whole interval


def test_scaled_multiplies_every_amplitude_and_scales_the_same_draws():
    imperfections = Imperfections(height_sd_mm=0.1, height_distribution="uniform", flatness_sd_mm=0.02, misalignment_sd_mm=0.3)
    assert imperfections.scaled(3.0) == Imperfections(height_sd_mm=0.1 * 3.0, height_distribution="uniform", flatness_sd_mm=0.02 * 3.0,
                                                      misalignment_sd_mm=0.3 * 3.0)
    assert imperfections.scaled(0.0).is_zero and not imperfections.is_zero
    wall = load_target("WD3").wall
    one, three = placement(wall, imperfections, 9), placement(wall, imperfections.scaled(3.0), 9)
    for field in ("height", "bottom_slope", "top_slope"):
        assert np.allclose(getattr(three, field), 3.0 * getattr(one, field), rtol=1e-14, atol=0.0)


def test_exaggerated_drawing_keeps_every_brick_at_least_half_its_height():
    wall = load_target("WD3").wall
    model, factor = exaggerated_model(wall, Imperfections(height_sd_mm=0.2), seed=0, factor=10.0)
    assert 1.0 < factor < 10.0
    heights = [np.ptp(s.vertices[:, 2]) for s in model.block_shape[1:]]
    assert min(heights) >= DRAWN_THICKNESS_FRACTION * H * (1 - 1e-12)
    assert exaggerated_model(wall, Imperfections(height_sd_mm=0.01), seed=0, factor=2.0)[1] == 2.0


@pytest.mark.parametrize("fields, named", [
    ({"height_sd_mm": -1.0}, "imperfections height_sd_mm = -1.0: must be a number in [0, inf) mm"),
    ({"flatness_sd_mm": math.nan}, "imperfections flatness_sd_mm = nan"),
    ({"misalignment_sd_mm": True}, "imperfections misalignment_sd_mm = True"),
    ({"height_distribution": "lognormal"}, "imperfections height_distribution = 'lognormal': must be one of ('normal', 'uniform')"),
])
def test_bad_amplitudes_are_refused_naming_the_field_and_the_rule(fields, named):
    with pytest.raises(ModelError, match=re.escape(named)):
        Imperfections(**fields)


@pytest.mark.parametrize("fields, named", [
    ({"height_sd_mm": 0.6}, "small.toml: imperfections height_sd_mm = 0.6: must be at most 0.55 mm, 10% of the brick height (5.5 mm)"),
    ({"flatness_sd_mm": 0.3}, "small.toml: imperfections flatness_sd_mm = 0.3: must be at most 0.275 mm, 5% of the brick height"),
    ({"misalignment_sd_mm": 7.0}, "small.toml: imperfections misalignment_sd_mm = 7.0: must be at most 6.25 mm, 25% of the brick length"),
])
def test_amplitudes_too_large_for_the_brick_are_refused_naming_the_wall(fields, named):
    with pytest.raises(ModelError, match=re.escape(named)):
        imperfect_blocks(small_wall("BB"), Imperfections(**fields), seed=0)


@pytest.mark.parametrize("seed", [-1, 1.5, True])
def test_a_bad_seed_is_refused(seed):
    with pytest.raises(ModelError, match=re.escape(f"small.toml: seed = {seed!r}: must be a non-negative integer")):
        imperfect_blocks(small_wall("BB"), REALISTIC, seed=seed)


def test_show_draws_an_imperfect_wall_exaggerated(tmp_path):
    out = tmp_path / "tmp.png"
    result = CliRunner().invoke(main, ["show", "WD3", "--height-sd", "0.2", "--exaggerate", "10", "--out", str(out)])
    assert result.exit_code == 0, result.output
    assert out.stat().st_size > 0


@pytest.mark.parametrize("arguments, message", [
    (["--height-sd", "-1"], "Invalid value for '--height-sd': -1.0: must be a finite number >= 0 (mm)"),
    (["--height-sd", "nan"], "Invalid value for '--height-sd': nan: must be a finite number >= 0 (mm)"),
    (["--misalignment-sd", "inf"], "Invalid value for '--misalignment-sd': inf: must be a finite number >= 0 (mm)"),
    (["--height-sd", "0.1", "--exaggerate", "0"], "Invalid value for '--exaggerate': 0.0: must be a finite number > 0"),
    (["--height-sd", "2"], "--height-sd = 2.0: must be at most 0.55 mm, 10% of the brick height (5.5 mm)"),
    # it drew the perfect wall and said nothing
    (["--exaggerate", "5"], "--exaggerate scales the imperfections' deviations: give --height-sd, --flatness-sd or --misalignment-sd"),
])
def test_show_refuses_bad_imperfections_naming_the_option(tmp_path, arguments, message):
    result = CliRunner().invoke(main, ["show", "WD3", *arguments, "--out", str(tmp_path / "x.png")])
    assert result.exit_code != 0 and isinstance(result.exception, SystemExit)
    assert message in result.output and "Traceback" not in result.output
    assert not (tmp_path / "x.png").exists()


def test_show_refuses_imperfections_for_a_model_file(tmp_path):
    path = tmp_path / "blocks.toml"
    path.write_text("[[block]]\nbox = { min = [0, 0, 0], max = [0.1, 0.1, 0.1] }\n")
    result = CliRunner().invoke(main, ["show", str(path), "--height-sd", "0.1", "--out", str(tmp_path / "x.png")])
    assert result.exit_code == 1
    assert "imperfect bricks (--height-sd, --flatness-sd, --misalignment-sd) need a brick layout" in result.output
