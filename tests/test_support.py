"""Load paths and the settlement the joints' elastic closure explains (drydem.analysis.support), and the
fall criterion built on them: a tall or soft wall settles, it does not fall."""

import numpy as np
import pytest
from click.testing import CliRunner

import drydem as dd
from drydem.analysis.support import elastic_settlement, load_paths, own_weight_closures, too_soft_joints
from drydem.analysis.tilt import NO_EQUILIBRIUM_UNDER_GRAVITY, STOP_DISPLACEMENT, UNSTABLE_UNDER_GRAVITY, TiltSettings, tilt_analysis
from drydem.analysis.tilt.run import TiltRun
from drydem.analysis.tilt.settings import FELL
from drydem.cli import main
from drydem.model.geometry import convex_hull
from drydem.model.rotation import matrices
from conftest import BRICK, stack_model


def longest_paths_reference(lower, upper, closure, n_blocks):
    """Plain recursion: s(b) = max over contacts (a under b) of s(a) + closure, 0 on nothing."""

    def s(b):
        into = [s(a) + c for a, u, c in zip(lower, upper, closure) if u == b]
        return max(into, default=0.0)

    return np.array([s(b) for b in range(n_blocks)])


def test_compiled_settlement_matches_the_recursion_on_a_random_layered_graph():
    rng = np.random.default_rng(7)
    layers = [list(range(k * 5, k * 5 + 5)) for k in range(6)]
    lower, upper = [], []
    for below, above in zip(layers, layers[1:]):
        for b in above:
            for a in rng.choice(below, size=rng.integers(1, 4), replace=False):
                lower.append(a)
                upper.append(b)
    lower, upper = np.array(lower), np.array(upper)
    closure = rng.uniform(0.0, 1e-4, len(lower))
    height = np.repeat(np.arange(6.0), 5) + rng.uniform(0, 0.1, 30)
    expected = longest_paths_reference(lower, upper, closure, 30)
    np.testing.assert_allclose(elastic_settlement(lower, upper, closure, height), expected, rtol=0, atol=1e-15)


def test_settlement_of_a_stack_is_the_sum_of_its_joints_closures():
    # a column of n equal blocks on springs kn A: joint k (from the bottom) closes by
    # (n - k) W / (kn A); the top settles by W / (kn A) n (n + 1) / 2 (springs in series)
    n, kn = 6, 1e7
    model = stack_model([BRICK[2]] * n, joint=dd.JointMaterial(kn=kn, ks=kn, friction=0.5))
    sim = dd.Simulation(model)
    assert sim.cycle_to_equilibrium().converged
    paths = load_paths(sim.contacts, sim.state.position, matrices(sim.state.quaternion))
    settlement = elastic_settlement(*paths, sim.state.position[:, 2])
    closure = model.block_mass[1] * dd.G / (kn * BRICK[0] * BRICK[1])
    expected = closure * np.cumsum(np.arange(n, 0, -1))
    np.testing.assert_allclose(settlement[1:], expected, rtol=1e-3)
    drop = model.block_centroid[1:, 2] - sim.state.position[1:, 2]
    np.testing.assert_allclose(drop, expected, rtol=1e-3)


def pier(courses: int, kn: float, **solver) -> dd.Model:
    """A column of the paper's bricks, held in y, on a fixed base."""
    return stack_model([BRICK[2]] * courses, joint=dd.JointMaterial(kn=kn, ks=kn, friction=0.5),
                       supports=dd.Supports(fix_y=True), solver=dd.SolverSettings(**solver))


def test_a_tall_soft_pier_settles_more_than_two_brick_heights_and_still_stands():
    # 50 courses at kn = 1e7: the top settles W/(kn A) 50 * 51 / 2 = 12.4 mm > 2 x 5.5 mm, which
    # the drawn-place rule took for a fall ("cannot stand under its own weight")
    courses, kn = 50, 1e7
    model = pier(courses, kn)
    top = model.block_mass[1] * dd.G / (kn * BRICK[0] * BRICK[1]) * courses * (courses + 1) / 2
    assert top > 2 * BRICK[2]
    result = tilt_analysis(model, TiltSettings(increment_deg=0.5, max_angle_deg=0.5))
    assert result.stable_under_gravity is True and result.lost_blocks == []
    assert result.records[0].uz_m == pytest.approx(-top, rel=1e-3)


def test_a_competition_wall_with_very_soft_joints_settles_and_stands():
    # WD3 at kn = 3e6 Pa/m settles by more than two brick heights at its top: it was called
    # unable to stand; vertical gravity only (one step of 0.5 deg)
    from drydem.io.target import load_target

    model = load_target("WD3").model.overridden(kn=3e6, ks=3e6)
    result = tilt_analysis(model, TiltSettings(increment_deg=0.5, max_angle_deg=0.5))
    assert result.stable_under_gravity is True and result.lost_blocks == []
    assert -result.records[0].uz_m > 2 * BRICK[2]


def test_a_block_floating_above_the_wall_is_named_as_falling():
    base = dd.Block(name="base", shape=dd.box([-0.05, 0.0, -0.01], [0.1, 0.012, 0.0]), fixed=True)
    brick = dd.Block(name="brick", shape=dd.box([0.0, 0.0, 0.0], [0.025, 0.012, 0.0055]))
    floater = dd.Block(name="floater", shape=dd.box([0.0, 0.0, 0.5], [0.025, 0.012, 0.5055]))
    model = dd.build_model([base, brick, floater], density=1800.0)
    result = tilt_analysis(model, TiltSettings(monitor="brick"))
    assert result.stable_under_gravity is False and result.ended_by == "unstable under gravity"
    assert [name for name, _ in result.lost_blocks] == ["floater"]


@pytest.mark.parametrize("kn, sinks", [(1e4, True), (2e4, False)])
def test_a_brick_sinks_through_joints_closing_more_than_its_thickness_under_its_own_weight(kn, sinks):
    # W / (kn A) = rho g h / kn on its bed: 9.71 mm at kn = 1e4 Pa/m, more than the 5.5 mm
    # brick; 4.86 mm at 2e4, less (it stands and slides at atan mu: test_tilt). A box closes
    # the same fraction rho g / kn of its width on each face (its ends: 44 mm of 25 mm at 1e4)
    model = stack_model([0.0055], joint=dd.JointMaterial(kn=kn, ks=kn, friction=0.5), supports=dd.Supports(fix_y=True))
    closure, width, area = own_weight_closures(model, 1)
    assert model.in_plane and len(closure) == 4  # bed, top and ends: the faces across y do not bear
    assert closure / width == pytest.approx(np.full(4, 1800.0 * dd.G / kn), rel=1e-9)
    assert closure[np.argmax(area)] == pytest.approx(1800.0 * dd.G * 0.0055 / kn, rel=1e-9)
    assert ("closes its joint by 9.71 mm on its largest face" in too_soft_joints(model, [1])) is sinks


def test_a_stiffening_joint_law_carries_a_brick_a_soft_constant_one_lets_sink():
    # affine law kn + b sigma: u(sigma) = ln(1 + b sigma / kn) / b (drydem.engine.joints), at the
    # brick's bed stress rho g h = 97.1 Pa with kn = 1e4 Pa/m and b = 1e3 /m: 4.23 mm < 5.5 mm
    law = dd.JointMaterial(kn=1e4, ks=1e4, friction=0.5, model="affine", kn_per_stress=1e3)
    model = stack_model([0.0055], joint=law, supports=dd.Supports(fix_y=True))
    closure, width, area = own_weight_closures(model, 1)
    sigma = 1800.0 * dd.G * 0.0055
    assert closure[np.argmax(area)] == pytest.approx(np.log1p(1e3 * sigma / 1e4) / 1e3, rel=1e-9)
    assert too_soft_joints(model, [1]) == ""


def test_tilting_a_brick_on_joints_too_soft_to_carry_it_says_why_it_cannot_stand(tmp_path):
    path = tmp_path / "soft.toml"
    path.write_text("[material]\ndensity = 1800.0\n[joint]\nkn = 1e4\nks = 1e4\nfriction = 0.5\n[supports]\nfix_y = true\n"
                    "[[block]]\nname = \"base\"\nfixed = true\nbox = { min = [-0.05, -0.006, -0.01], max = [0.25, 0.006, 0.0] }\n"
                    "[[block]]\nname = \"brick\"\nbox = { min = [0.0, -0.006, 0.0], max = [0.025, 0.006, 0.0055] }\n")
    result = CliRunner().invoke(main, ["tilt", str(path), "--out", str(tmp_path / "out")])
    assert result.exit_code == 0, result.output
    assert "the model cannot stand under its own weight: 'brick' fell" in result.output
    assert "'brick' closes its joint by 9.71 mm on its largest face (u(W / A) of the joint law), more than the 5.5 mm" in result.output


def brick_on_a_slope(slope_deg: float, kn: float, ks: float) -> dd.Model:
    """A brick (25 x 12 x 5.5 mm) resting on the face of a fixed wedge that rises along x at
    ``slope_deg``, held in y, friction 1 (it does not slide: tan 20 deg = 0.36)."""
    a = np.radians(slope_deg)
    along, normal = np.array([np.cos(a), 0.0, np.sin(a)]), np.array([-np.sin(a), 0.0, np.cos(a)])
    wedge = [[0, y, 0] for y in (-0.006, 0.006)] + [[0.1, y, 0] for y in (-0.006, 0.006)] + [[0.1, y, 0.1 * np.tan(a)] for y in (-0.006, 0.006)]
    foot = 0.03 * along
    brick = [foot + u * along + v * normal + [0, y, 0] for u in (0, 0.025) for v in (0, 0.0055) for y in (-0.006, 0.006)]
    blocks = [dd.Block(name="wedge", shape=convex_hull(np.array(wedge, float)), fixed=True),
              dd.Block(name="brick", shape=convex_hull(np.array(brick)))]
    return dd.build_model(blocks, density=1800.0, joint=dd.JointMaterial(kn=kn, ks=ks, friction=1.0), supports=dd.Supports(fix_y=True))


def test_a_brick_on_a_soft_slope_comes_to_rest_where_its_joints_closure_and_shear_put_it():
    """Soft joints on a 20 deg slope: the brick's weight W = 0.029 N closes its joint (area A =
    3e-4 m2) by W cos a / (kn A) and shears it down the slope by W sin a / (ks A), which moves it
    along x by sin a cos a (W / A) (1 / ks - 1 / kn) = 0.28 mm with kn = 1e6, ks = 1e5 Pa/m (the
    joint's two springs; friction 1 > tan 20 deg holds it). A stop displacement of 0.1 mm
    makes that a fall under its own weight, not a standing model."""
    model = brick_on_a_slope(20.0, 1e6, 1e5)
    a, weight, area = np.radians(20.0), model.block_mass[1] * dd.G, 0.025 * 0.012
    expected = np.sin(a) * np.cos(a) * weight / area * (1 / 1e5 - 1 / 1e6)
    standing = tilt_analysis(model, TiltSettings(max_angle_deg=1.0, increment_deg=0.5))
    assert standing.stable_under_gravity is True and -standing.records[0].ux_m == pytest.approx(expected, rel=0.02)
    result = tilt_analysis(model, TiltSettings(stop_displacement_m=1e-4, max_angle_deg=1.0, increment_deg=0.5))
    assert result.stable_under_gravity is False and result.ended_by == UNSTABLE_UNDER_GRAVITY
    assert result.collapse_angle_deg is None and result.records == []


def test_a_block_that_comes_to_rest_beyond_the_stop_displacement_under_its_own_weight_has_fallen():
    """The rule itself, where the equilibrium is reached before the stop displacement is looked
    at: a brick put down 20 um along x from where it was drawn (too little for a re-detection,
    at which the stop displacement is also looked at) settles at once. With a stop displacement
    of 10 um that counted as standing, and the first tilt step then "collapsed"."""
    run = TiltRun(pier(1, 1e8), TiltSettings(stop_displacement_m=1e-5), None)
    run.sim.state.position[run.monitor, 0] += 2e-5
    assert run.equilibrate(0.0, vertical=True)[0] == FELL
    assert run.equilibrate(1.0)[0] == STOP_DISPLACEMENT


@pytest.mark.parametrize("solver", [dict(max_cycles=10), dict(damping=0.0, max_cycles=5_000)])
def test_no_equilibrium_under_gravity_is_its_own_outcome_not_a_fall(solver):
    # too few cycles, or no damping to take the bounce out: no verdict on stability
    result = tilt_analysis(pier(4, 1e8, **solver), TiltSettings())
    assert result.stable_under_gravity is None and result.ended_by == NO_EQUILIBRIUM_UNDER_GRAVITY
    assert result.collapse_angle_deg is None and result.lost_blocks == []
