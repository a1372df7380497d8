"""Wall files, the built-in designs WD1-WD7 and the competition brief."""

import re

import numpy as np
import pytest
from click.testing import CliRunner

from drydem.masonry import designs
from drydem.masonry.brief import COMPETITION, brief_violations
from drydem.cli import main
from drydem.errors import ModelError
from drydem.io.target import load_target
from drydem.masonry.walls import load_wall

COMPETITION_WALLS = [f"WD{k}" for k in range(1, 8)]
#: the teams, seed paper Table 2 (Savalle et al. 2022)
TEAMS = {"WD1": "Newcastle", "WD2": "Leeds", "WD3": "Lyon", "WD4": "Pavia", "WD5": "Leuven", "WD6": "Yildiz", "WD7": "Munich"}

WALL_FILE = '''\
[wall]
title = "a test wall"
[brick]
length_m = 0.025
height_m = 0.0055
width_m = 0.012
[joint]
kn = 1e8
[supports]
fix_y = true
[layout]
courses = """
BB
b_b
BB
"""
'''


def write(tmp_path, text, name="wall.toml"):
    path = tmp_path / name
    path.write_text(text)
    return path


def test_the_built_in_walls_are_the_seven_designs_and_the_example():
    assert designs.names() == [*COMPETITION_WALLS, "perforated_wall"]
    assert designs.find("wd3") == designs.find("WD3") != None  # noqa: E711


@pytest.mark.parametrize("name", COMPETITION_WALLS)
def test_every_competition_wall_meets_the_brief_and_says_it_is_a_reconstruction(name):
    wall = load_target(name).wall
    assert brief_violations(wall) == []
    assert wall.layout.void_ratio >= COMPETITION.min_void_ratio
    assert TEAMS[name] in wall.title and "reconstruction" in wall.title
    assert wall.description.startswith("Reconstruction, not the original drawing")
    assert "NOT THE ORIGINAL DRAWING" in designs.find(name).read_text()
    assert (wall.joint.kn, wall.joint.friction, wall.supports.fix_y) == (3e7, 0.5, True)  # the paper's Section 3


@pytest.mark.parametrize("name", ["WD2", "WD5"])
def test_the_weak_walls_with_the_most_voids_have_31_5_percent(name):
    # seed paper, Section 2: "max 31.5% for wall designs WD 2 and WD 5"
    assert load_target(name).wall.layout.void_ratio == pytest.approx(0.315, abs=0.0005)


def test_wd6_is_stack_bonded_at_the_bottom():
    # seed paper, Section 4.2: in WD6's bottom part "the contacts are half of the time only
    # between two bricks": in stack bond every brick has exactly one brick under it
    layout = load_target("WD6").wall.layout
    for course in layout.courses[1:15]:
        for unit in course:
            if unit.kind == "brick":
                below = [u for u in layout.courses[unit.course - 1] if not u.is_void
                         and u.start < unit.start + unit.cells and unit.start < u.start + u.cells]
                assert [(u.start, u.cells) for u in below] == [(unit.start, unit.cells)]


@pytest.mark.parametrize("name", ["WD1", "WD3"])
def test_wd1_and_wd3_spread_their_voids_over_the_whole_wall(name):
    # seed paper, Section 5: WD1 and WD3 have their voids evenly distributed; here every course
    # but the first, the top and the lintel's has voids in both halves of the wall (honeycomb bond)
    layout = load_target(name).wall.layout
    middle = layout.cells_per_course // 2
    for course in layout.courses[1:-1]:
        if any(u.kind == "lintel" for u in course):
            continue
        voids = [u for u in course if u.is_void]
        assert any(u.start < middle for u in voids) and any(u.start + u.cells > middle for u in voids)


def test_a_wall_file_builds_its_model_with_its_options(tmp_path):
    target = load_target(str(write(tmp_path, WALL_FILE)))
    assert target.name == "wall" and target.wall.title == "a test wall"
    model = target.model
    assert model.block_name == ("base", "c0b0", "c0b1", "c1b0", "c1b1", "c2b0", "c2b1")
    assert model.joint.kn == 1e8 and model.supports.fix_y
    assert model.block_mass[1] == pytest.approx(1800 * 0.025 * 0.012 * 0.0055)  # default density


def test_a_kilometre_long_wall_stands_on_a_base_deep_enough_to_be_a_block(tmp_path):
    # 2000 half-metre bricks: a 1 cm base 1 km long was refused as a degenerate (flat) block,
    # volume <= 1e-9 size^3; the base is now a thousandth of its length deep (1.1 m here)
    path = write(tmp_path, "[brick]\nlength_m = 0.5\nheight_m = 0.05\nwidth_m = 0.1\n[layout]\ncourses = \"2000B\"\n")
    model = load_wall(path).model()
    base = model.block_shape[model.block_index("base")]
    assert np.ptp(base.vertices[:, 2]) == pytest.approx(1e-3 * (1000.0 + 0.1), rel=1e-12)
    assert model.n_blocks == 2001


def test_layout_errors_give_the_wall_file_line(tmp_path):
    path = write(tmp_path, WALL_FILE.replace("b_b", "b__b"))
    with pytest.raises(ModelError, match=rf"{path}, line 14: the course is 3 bricks long"):
        load_wall(path)


LAYOUT = 'courses = """\nBB\nb_b\nBB\n"""'  # the layout of WALL_FILE, on its lines 12-16


def with_courses(*lines: str) -> tuple[str, str]:
    """The change of WALL_FILE that draws ``lines`` as its courses, from line 13 on."""
    return LAYOUT, 'courses = """\n' + "".join(f"{line}\n" for line in lines) + '"""'


@pytest.mark.parametrize("layout, where", [
    ('courses = """\nBB\nbXb\n"""', "line 14"),  # a multi-line string starts on the line after its key
    ("courses = '''\nBB\nbXb\n'''", "line 14"),
    ('courses = """BB\nbXb\n"""', "line 13"),
    ("courses = 'bXb'", "line 12"),
    (r'courses = "BB\nbXb"', r"\[layout\] courses, line 2"),  # escapes: the file does not hold the text as read
])
def test_layout_errors_name_the_file_line_whatever_the_string_quotes(tmp_path, layout, where):
    path = write(tmp_path, WALL_FILE.replace(LAYOUT, layout))
    with pytest.raises(ModelError, match=rf"{where}: unknown token 'X'"):
        load_wall(path)


@pytest.mark.parametrize("change, message", [
    pytest.param(("[wall]", "[wall]\nauthor = 'me'"), r"unknown key\(s\) \['author'\] in \[wall\]", id="unknown [wall] key"),
    pytest.param(("width_m = 0.012\n", ""), r"\[brick\] needs width_m", id="missing brick width"),
    pytest.param(("length_m = 0.025", "length_m = -0.025"), r"\[brick\] length_m = -0.025: must be a number in \[0.0001, 20\] m",
                 id="negative brick length"),
    pytest.param(("height_m = 0.0055", "height_m = 0"), r"\[brick\] height_m = 0: must be a number in \[0.0001, 20\] m", id="zero brick height"),
    pytest.param(("height_m = 0.0055", "height_m = true"), r"\[brick\] height_m = True: must be a number", id="boolean brick height"),
    pytest.param(("width_m = 0.012", "width_m = '12 mm'"), r"\[brick\] width_m = '12 mm': must be a number", id="text brick width"),
    pytest.param(("width_m = 0.012", "width_m = 1e300"), r"\[brick\] width_m = 1e\+300: must be a number in \[0.0001, 20\] m",
                 id="astronomic brick width"),
    pytest.param(("width_m = 0.012", "width_m = nan"), r"\[brick\] width_m = nan: must be a number", id="nan brick width"),
    pytest.param(("width_m = 0.012", "width_m = 0.012\nlintel_length_m = 0.0125"),
                 r"\[brick\] lintel_length_m = 0.0125: must be at least a brick long \(0.025 m\)", id="lintel shorter than a brick"),
    pytest.param(("width_m = 0.012", "width_m = 0.012\ncolour = 'red'"), r"unknown key\(s\) \['colour'\] in \[brick\]", id="unknown [brick] key"),
    pytest.param(("kn = 1e8", "kn = 0"), r"\[joint\] kn = 0: must be", id="zero stiffness"),
    pytest.param(('courses = """', 'rows = """'), r"unknown key\(s\) \['rows'\] in \[layout\]", id="unknown [layout] key"),
    pytest.param(("[layout]\n" + LAYOUT, ""), r"a wall file needs a \[layout\] table with courses = \"\"\"...\"\"\"", id="no [layout]"),
    pytest.param((LAYOUT, "courses = 3"), r'\[layout\] needs courses = """..."""', id="courses a number"),
    pytest.param((LAYOUT, "courses = ['BB', 'BB']"), r'\[layout\] needs courses = """..."""', id="courses a list"),
    pytest.param((LAYOUT, 'courses = ""'), r"the layout has no courses", id="empty courses"),
    pytest.param(with_courses("# nothing but a comment"), r"the layout has no courses", id="courses only comments"),
    pytest.param(with_courses("__", "._.", "__"), r"lines 13-15: the layout has only voids; a wall needs at least one brick", id="only voids"),
    # the base rose to the first bricks and the wall stood a course lower than drawn, while check said it cannot be built
    pytest.param(with_courses("BB", "__"), r"line 14: the bottom course is all voids: the base is drawn under the bottom course",
                 id="bottom course of voids"),
    pytest.param(with_courses("BB", "bXb", "BB"), r"line 14: unknown token 'X' in 'bXb'", id="unknown token"),
    pytest.param(with_courses("BB", "bB２b"), r"line 14: unknown token '２'", id="non-ASCII digit"),
    pytest.param(with_courses("BB", "0B"), r"line 14: repeat count 0 before 'B' must be at least 1", id="zero repeat"),
    pytest.param(with_courses("1000000B"), r"line 13: '1000000B' takes the wall past 100,000 bricks of face \(its length in bricks "
                 r"times its courses, voids included\), the most drydem takes", id="huge repeat"),
    pytest.param(with_courses("9" * 5000 + "B"), r"line 13: '9{40}'... \(5,001 characters\) takes the wall past 100,000 bricks",
                 id="repeat count of 5000 digits"),
    pytest.param(("[wall]", "[wall]\nname = 5"), r"\[wall\] name = 5: must be a string", id="name a number"),
    pytest.param(("[wall]", "[wall]\nname = '../../x'"), r"\[wall\] name = '../../x': must be a non-empty name without /",
                 id="name a path"),
])
def test_a_bad_wall_file_stops_drydem_check_with_the_file_and_the_rule(tmp_path, change, message):
    path = write(tmp_path, WALL_FILE.replace(*change))
    assert path.read_text() != WALL_FILE
    result = CliRunner().invoke(main, ["check", str(path)])
    assert result.exit_code == 1 and isinstance(result.exception, SystemExit)  # a message, no traceback
    assert result.output.startswith(f"Error: {path}")
    assert re.search(message, result.output), result.output


def test_the_brief_checker_reports_every_violation(tmp_path):
    courses = "\n".join(["bBBB..BBBb"] + ["BBBBBBBB"] * 25 + [".BBBBBBB."]) + "\n"
    text = WALL_FILE.replace('"""\nBB\nb_b\nBB\n"""', f'"""\n{courses}"""')
    violations = brief_violations(load_wall(write(tmp_path, text)))
    assert violations == [
        "voids are 0.9% of the face, less than 30%",
        "course 0 (from the bottom) has a void at the wall's edge",
        "the top course has a void",
        "0 lintels, not 1",
    ]
    text = WALL_FILE.replace("length_m = 0.025", "length_m = 0.03")
    assert brief_violations(load_wall(write(tmp_path, text)))[:3] == [
        "bricks are not 25 x 5.5 x 12 mm with a 75 mm lintel", "the wall is 2 bricks long, not 8", "the wall has 3 courses, not 27",
    ]


@pytest.mark.slow
@pytest.mark.parametrize("name", COMPETITION_WALLS)
def test_every_competition_wall_stands_under_its_own_weight_at_the_papers_stiffness(name):
    # the paper's walls stand at kn = 3e7 (Section 4, Table 3): so must the reconstructions;
    # the settlement is of the order of the joint closures, 27 joints x rho g h / kn ~ 1.2 mm
    from drydem.engine.simulation import Simulation

    model = load_target(name).model
    sim = Simulation(model)
    assert sim.cycle_to_equilibrium().converged
    moved = np.linalg.norm(sim.state.position - model.block_centroid, axis=1)
    assert moved.max() < 4e-3
