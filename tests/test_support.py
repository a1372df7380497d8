"""Load paths and the settlement the joints' elastic closure explains (drydem.analysis.support), and the
fall criterion built on them: a tall or soft wall settles, it does not fall."""

import numpy as np
import pytest

import drydem as dd
from drydem.analysis.tilt import NO_EQUILIBRIUM_UNDER_GRAVITY, TiltSettings, tilt_analysis
from drydem.model.rotation import matrices
from drydem.analysis.support import elastic_settlement, load_paths
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


@pytest.mark.parametrize("solver", [dict(max_cycles=10), dict(damping=0.0, max_cycles=5_000)])
def test_no_equilibrium_under_gravity_is_its_own_outcome_not_a_fall(solver):
    # too few cycles, or no damping to take the bounce out: no verdict on stability
    result = tilt_analysis(pier(4, 1e8, **solver), TiltSettings())
    assert result.stable_under_gravity is None and result.ended_by == NO_EQUILIBRIUM_UNDER_GRAVITY
    assert result.collapse_angle_deg is None and result.lost_blocks == []
