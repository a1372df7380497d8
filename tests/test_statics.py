"""Free fall and elastic settlement against closed forms."""

import numpy as np
import pytest

import drydem as dd
from conftest import BRICK, stack_model

UNDAMPED = dd.SolverSettings(damping=0.0)


def test_free_fall_follows_the_central_difference_parabola():
    # a block 1 m above the base, never touching it in 200 cycles. With v(-dt/2) = 0 the scheme
    # gives z_n = z_0 - g dt^2 n (n + 1) / 2 exactly (paper Eq. 2), i.e. g t^2 / 2 + O(dt).
    model = stack_model([0.0055], lift=1.0, solver=UNDAMPED)
    sim = dd.Simulation(model)
    assert sim.contacts.count == 0
    z0, dt, n = sim.state.position[1, 2], sim.timestep, 200
    result = sim.cycle(n)
    assert result.cycles == n
    drop = z0 - sim.state.position[1, 2]
    assert drop == pytest.approx(dd.G * dt * dt * n * (n + 1) / 2, rel=1e-12)
    assert sim.state.velocity[1, 2] == pytest.approx(-dd.G * dt * n, rel=1e-12)


@pytest.mark.parametrize("kn", [1e7, 3e7, 1e9])
def test_single_block_settles_by_weight_over_kn_area(kn):
    # closure u = W / (kn A): uniform pressure on a rigid block (paper Eq. 1 with sigma = W / A)
    model = stack_model([BRICK[2]], joint=dd.JointMaterial(kn=kn, ks=kn), solver=dd.SolverSettings(criterion="ratio", ratio=1e-8))
    sim = dd.Simulation(model)
    result = sim.cycle_to_equilibrium()
    assert result.converged
    weight = model.block_mass[1] * dd.G
    closure = model.block_centroid[1, 2] - sim.state.position[1, 2]
    assert closure == pytest.approx(weight / (kn * BRICK[0] * BRICK[1]), rel=1e-6)
    np.testing.assert_allclose(sim.reactions(1), [0, 0, weight], rtol=1e-6, atol=1e-9 * weight)


def test_stack_settles_joint_by_joint_and_reactions_equal_weights():
    # joint k carries the weight of the blocks above it: u_k = W_above / (kn A);
    # the base pushes up with the total weight
    heights = [0.0055, 0.011, 0.0055, 0.022]
    kn = 2e7
    model = stack_model(heights, joint=dd.JointMaterial(kn=kn, ks=kn), solver=dd.SolverSettings(ratio=1e-8))
    sim = dd.Simulation(model)
    assert sim.cycle_to_equilibrium().converged
    area = BRICK[0] * BRICK[1]
    weights = model.block_mass[1:] * dd.G
    above = np.cumsum(weights[::-1])[::-1]  # weight on joint k (block k and those above)
    expected_drop = np.cumsum(above / (kn * area))
    drop = model.block_centroid[1:, 2] - sim.state.position[1:, 2]
    np.testing.assert_allclose(drop, expected_drop, rtol=1e-5)
    base_reaction = -sim.reactions(0)
    assert base_reaction[2] == pytest.approx(weights.sum(), rel=1e-6)


def test_mass_scaling_reaches_the_same_equilibrium():
    heights = [0.0055] * 5
    plain = dd.Simulation(stack_model(heights, solver=dd.SolverSettings(ratio=1e-9)))
    scaled = dd.Simulation(stack_model(heights, solver=dd.SolverSettings(ratio=1e-9, mass_scaling=True)))
    assert plain.cycle_to_equilibrium().converged and scaled.cycle_to_equilibrium().converged
    np.testing.assert_allclose(scaled.state.position, plain.state.position, rtol=0, atol=1e-10)
