"""A block on a tilted support: sliding at atan(mu), toppling at atan(b/h), in any frame.

The tilt is applied through the gravity vector g (sin theta, 0, -cos theta) (paper Eq. 5),
as on the tilting table. Closed forms: a rigid block slides when tan(theta) > mu
(Coulomb) and topples about its downhill edge when tan(theta) > b/h (moment of the
weight about that edge; e.g. Housner 1963 / any statics text).
"""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import drydem as dd
from conftest import stack_model, tilted_gravity

MARGIN_DEG = 0.5
#: cycles allowed to reach equilibrium; a block that holds needs a few hundred
MAX_CYCLES = 20_000


def settle(model, theta_deg, turn_deg=0.0, max_cycles=MAX_CYCLES):
    """Equilibrium under vertical gravity, then at the tilt; returns (converged, sim)."""
    sim = dd.Simulation(model)
    assert sim.cycle_to_equilibrium(gravity=tilted_gravity(0.0, turn_deg)).converged
    result = sim.cycle_to_equilibrium(gravity=tilted_gravity(theta_deg, turn_deg), max_cycles=max_cycles)
    return result.converged, sim


def downhill_displacement(sim, turn_deg=0.0):
    moved = sim.state.position[1] - sim.model.block_centroid[1]
    return float(moved @ Rotation.from_euler("z", turn_deg, degrees=True).apply([1.0, 0.0, 0.0]))


def squat_block(mu, turn_deg=0.0):
    # 25 mm long, 5.5 mm high: toppling needs tan(theta) > 4.5, far beyond sliding
    joint = dd.JointMaterial(kn=1e8, ks=1e8, friction=mu)
    return stack_model([0.0055], joint=joint, turn_deg=turn_deg)


@pytest.mark.parametrize("mu", [0.3, 0.5, 0.8, 1.2])
def test_block_holds_below_and_slides_above_atan_mu(mu):
    critical = np.degrees(np.arctan(mu))
    held, sim = settle(squat_block(mu), critical - MARGIN_DEG)
    assert held
    assert abs(downhill_displacement(sim)) < 1e-4  # only elastic shear: W sin / (ks A) ~ 1e-6 m
    held, sim = settle(squat_block(mu), critical + MARGIN_DEG)
    assert not held
    assert downhill_displacement(sim) > 1e-3  # slid down the slope (re-detected many times)


def slender_block(turn_deg=0.0, points=4):
    # b = 10 mm, h = 40 mm: topples at tan(theta) = b / h = 0.25 (14.04 deg); mu = 1 (45 deg) cannot slide first.
    # kn = 1e10 Pa/m: the rocking edge sinks by ~1e-8 m, so the rigid-block angle applies.
    joint = dd.JointMaterial(kn=1e10, ks=1e10, friction=1.0)
    return stack_model([0.04], size_xy=(0.01, 0.012), joint=joint, turn_deg=turn_deg, points=points)


def rotation_deg(sim) -> float:
    return 2 * np.degrees(np.arccos(min(1.0, abs(sim.state.quaternion[1, 0]))))


@pytest.mark.parametrize("points", [2, 4])
def test_slender_block_topples_at_atan_b_over_h(points):
    critical = np.degrees(np.arctan(0.01 / 0.04))
    held, sim = settle(slender_block(points=points), critical - MARGIN_DEG)
    assert held
    held, sim = settle(slender_block(points=points), critical + MARGIN_DEG, max_cycles=500)
    assert not held
    # keep cycling until it has turned 2 deg: it turns about its downhill bottom edge
    model = sim.model
    downhill_edge = model.block_shape[1].vertices[:, 0].max(), model.block_shape[1].vertices[:, 2].min()
    for _ in range(100):
        if rotation_deg(sim) > 2.0:
            break
        sim.cycle(500, gravity=tilted_gravity(critical + MARGIN_DEG))
    assert rotation_deg(sim) > 2.0
    rot = Rotation.from_quat(sim.state.quaternion[1, [1, 2, 3, 0]])
    edge_body = np.array([downhill_edge[0], 0.006, downhill_edge[1]]) - model.block_centroid[1]
    edge_now = sim.state.position[1] + rot.apply(edge_body)
    assert np.linalg.norm(edge_now - model.block_centroid[1] - edge_body) < 1e-5  # the pivot stayed put


@pytest.mark.parametrize(
    "case, theta_deg",
    [("slide", np.degrees(np.arctan(0.5)) - MARGIN_DEG), ("slide", np.degrees(np.arctan(0.5)) + MARGIN_DEG),
     ("topple", np.degrees(np.arctan(0.25)) - MARGIN_DEG), ("topple", np.degrees(np.arctan(0.25)) + MARGIN_DEG)],
)
def test_turning_support_block_and_gravity_30_deg_about_z_changes_nothing(case, theta_deg):
    """Equilibria and the hold / move answer are frame invariant. Paths of a moving block are
    only nearly so: local damping (paper Eq. 4) acts on each global degree of freedom,
    F - alpha |F_k| sign(v_k), which mixes differently in turned axes (as in 3DEC)."""
    build = {"slide": squat_block, "topple": slender_block}[case]
    model_args = {"mu": 0.5} if case == "slide" else {}
    # 3000 cycles: long enough to tell holding from moving, short of falling off the base
    held, sim = settle(build(**model_args), theta_deg, max_cycles=3000)
    held_turned, sim_turned = settle(build(turn_deg=30.0, **model_args), theta_deg, turn_deg=30.0, max_cycles=3000)
    assert held == held_turned
    back = Rotation.from_euler("z", -30.0, degrees=True).as_matrix()
    moved = sim.state.position[1] - sim.model.block_centroid[1]
    moved_turned = back @ (sim_turned.state.position[1] - sim_turned.model.block_centroid[1])
    if held:  # the same equilibrium up to the path-dependent micro-slip of sub-contacts near mu
        np.testing.assert_allclose(moved_turned, moved, rtol=0, atol=2e-5)
    else:  # the same mechanism: same direction, similar distance (damped paths: measured 12 %)
        cosine = moved @ moved_turned / (np.linalg.norm(moved) * np.linalg.norm(moved_turned))
        assert cosine > np.cos(np.radians(2.0))
        assert np.linalg.norm(moved_turned) == pytest.approx(np.linalg.norm(moved), rel=0.25)


def test_undamped_sliding_is_the_same_in_turned_axes():
    # without local damping nothing depends on the axes: the slid distances agree (measured 0.2 %)
    theta = np.degrees(np.arctan(0.5)) + MARGIN_DEG
    distances = []
    for turn in (0.0, 30.0):
        model = squat_block(0.5, turn_deg=turn).replace(solver=dd.SolverSettings(damping=0.0))
        sim = dd.Simulation(model)
        sim.cycle_to_equilibrium(gravity=tilted_gravity(0.0, turn))
        sim.cycle(3000, gravity=tilted_gravity(theta, turn))
        distances.append(downhill_displacement(sim, turn))
    assert distances[0] > 1e-2
    assert distances[1] == pytest.approx(distances[0], rel=0.01)
