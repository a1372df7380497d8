"""The brick-layout format: tokens to exact block coordinates, and clear errors."""

import numpy as np
import pytest

from drydem.masonry.brief import PAPER_BRICK
from drydem.errors import ModelError
from drydem.masonry.layout import MAX_FACE_BRICKS, BrickSize, parse_layout

L, H, W = 0.025, 0.0055, 0.012  # the paper's brick (Section 2): length, height, width, m


def corners(model_or_blocks):
    return {b.name: (b.shape.vertices.min(0), b.shape.vertices.max(0)) for b in model_or_blocks}


def test_a_small_wall_gets_exact_coordinates():
    # top course first: headers at the ends, a lintel over a 4-cell opening, stretchers and
    # half bricks at the bottom; expected corners worked out by hand from the token widths
    layout = parse_layout("""
        HB2bBH      # H(0) B(1,2) b(3) b(4) B(5,6) H(7)
        bLb         # lintel over cells 1..6
        b....bbb    # void over cells 1..4
        B2bBbb      # B(0,1) b(2) b(3) B(4,5) b(6) b(7)
    """, PAPER_BRICK)
    blocks = corners(layout.blocks(PAPER_BRICK))
    assert np.allclose(blocks["c0b0"], ([0, -W / 2, 0], [L, W / 2, H]))
    assert np.allclose(blocks["c0b1"], ([L, -W / 2, 0], [1.5 * L, W / 2, H]))
    assert np.allclose(blocks["c0b3"], ([2 * L, -W / 2, 0], [3 * L, W / 2, H]))
    assert np.allclose(blocks["c0b5"], ([3.5 * L, -W / 2, 0], [4 * L, W / 2, H]))
    assert np.allclose(blocks["c1b1"], ([2.5 * L, -W / 2, H], [3 * L, W / 2, 2 * H]))
    # the lintel: 3 brick lengths
    assert np.allclose(blocks["c2b1"], ([0.5 * L, -W / 2, 2 * H], [3.5 * L, W / 2, 3 * H]))
    # a header: its width along the wall, centred in its half-brick cell, its length across
    middle = 0.25 * L
    assert np.allclose(blocks["c3b0"], ([middle - W / 2, -L / 2, 3 * H], [middle + W / 2, L / 2, 4 * H]))
    assert np.allclose(blocks["c3b4"], ([2.5 * L, -W / 2, 3 * H], [3.5 * L, W / 2, 4 * H]))
    # the base: under the wall, 50 mm beyond each end, as deep across as the widest block (the header)
    assert np.allclose(blocks["base"], ([-0.05, -L / 2, -0.01], [4 * L + 0.05, L / 2, 0.0]))
    assert layout.void_ratio == pytest.approx(2 / 16)
    assert layout.kinds() == ["base", "brick", "half", "half", "brick", "half", "half", "half", "half", "half",
                              "half", "half", "lintel", "half", "header", "brick", "half", "half", "brick", "header"]


def test_repeat_counts_and_the_brick_long_void_are_shorthands():
    a = parse_layout("8B\nb7Bb\n2B_B._.2B\n", PAPER_BRICK)
    b = parse_layout("BBBBBBBB\nbBBBBBBBb\nBB..B....BB\n", PAPER_BRICK)
    assert a.solid_units == b.solid_units and a.void_ratio == b.void_ratio and a.cells_per_course == 32


def test_quarter_brick_voids_offset_a_honeycomb_course():
    # honeycomb bond: each brick of the upper course bears on the ends of two bricks below,
    # a quarter brick on each, over a half-brick void
    layout = parse_layout("B,B.B,B\nbB.B.Bb\n", PAPER_BRICK)
    blocks = corners(layout.blocks(PAPER_BRICK))
    assert np.allclose(blocks["c1b1"][0][0], 1.25 * L) and np.allclose(blocks["c1b1"][1][0], 2.25 * L)
    below = [blocks["c0b1"], blocks["c0b2"]]
    assert np.isclose(below[0][1][0], 1.5 * L) and np.isclose(below[1][0][0], 2.0 * L)
    assert layout.unsupported() == []


def test_blocks_are_named_by_course_from_the_bottom():
    layout = parse_layout("BB\nb_b\nBB\n", PAPER_BRICK)
    assert layout.block_names() == ["c0b0", "c0b1", "c1b0", "c1b1", "c2b0", "c2b1"]


def test_the_example_wall_has_its_174_blocks_and_a_third_of_voids():
    from wall_fixtures import benchmark_wall

    model = benchmark_wall()
    assert model.n_blocks == 174 and model.block_name[0] == "base"
    # four openings of 4 half bricks x 9 courses in a 16 x 27 grid (drydem/designs/perforated_wall.toml)
    from drydem.masonry import designs
    from drydem.masonry.walls import load_wall

    assert load_wall(designs.find("perforated_wall")).layout.void_ratio == pytest.approx(4 * 2 * 9 / (8 * 27))


def test_a_course_of_the_wrong_length_names_its_line_and_both_lengths():
    with pytest.raises(ModelError, match=r"wall.txt, line 3: the course is 7.5 bricks long \(0.1875 m\); the wall is 8 \(0.2 m\), set by the top course on line 1"):
        parse_layout("8B\nb7Bb\nb7B\n", PAPER_BRICK, source="wall.txt")


def test_an_unknown_token_is_named_with_its_line():
    with pytest.raises(ModelError, match=r"line 12: unknown token 'X' in 'BBXB'"):
        parse_layout("BBXB", PAPER_BRICK, first_line=12)


def test_a_lintel_that_is_not_whole_half_bricks_is_refused():
    with pytest.raises(ModelError, match=r"lintel_length_m = 0.07: must be a whole number of quarter bricks"):
        BrickSize(length_m=L, height_m=H, width_m=W, lintel_length_m=0.07)


def test_a_lintel_is_at_least_a_brick_long():
    # the shortest opening is a half brick ('.'), and the lintel bears a quarter brick on each side
    assert BrickSize(length_m=L, height_m=H, width_m=W, lintel_length_m=L).lintel_cells == 4
    with pytest.raises(ModelError, match=r"lintel_length_m = 0.01875: must be at least a brick long \(0.025 m\)"):
        BrickSize(length_m=L, height_m=H, width_m=W, lintel_length_m=0.01875)  # three quarter bricks


@pytest.mark.parametrize("size", [1e-4, 20.0])
def test_bricks_at_the_ends_of_the_size_range_make_exact_blocks(size):
    brick = BrickSize(length_m=size, height_m=size, width_m=size)
    blocks = corners(parse_layout("bLb\nB._.B\n4B\n", brick).blocks(brick))
    assert np.allclose(blocks["c2b1"], ([0.5 * size, -0.5 * size, 2 * size], [3.5 * size, 0.5 * size, 3 * size]))


def test_a_wall_of_the_largest_face_is_read_and_one_course_more_is_refused():
    # MAX_FACE_BRICKS = 100,000: 100 courses of 1,000 bricks, then a 101st; checked before the
    # courses are expanded
    assert MAX_FACE_BRICKS == 100 * 1000
    layout = parse_layout("1000B\n" * 100, PAPER_BRICK)
    assert len(layout.courses) == 100 and len(layout.solid_units) == MAX_FACE_BRICKS
    with pytest.raises(ModelError, match=r"line 101: '1000B' takes the wall past 100,000 bricks of face"):
        parse_layout("1000B\n" * 101, PAPER_BRICK)


def test_blocks_with_nothing_under_them_are_found():
    # the brick over the 2-cell void rests on nothing; the half bricks beside it on their bricks
    layout = parse_layout("bBBb\nB_B\nBBB\n", PAPER_BRICK)
    assert layout.unsupported() == []
    layout = parse_layout("BBB\nB_B\nBBB\n", PAPER_BRICK)
    assert layout.unsupported() == ["c2b1"]
