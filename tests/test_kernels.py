"""The numba cycle against the plain NumPy reference (drydem.reference) on a brick wall."""

import numpy as np
import pytest

import drydem as dd
from drydem import kernels, reference
from drydem.joints import JointArrays
from conftest import layout_blocks, tilted_gravity


def copies(sim):
    """Independent copies of what one step reads and writes."""
    return sim.state.copy(), sim.contacts.copy()


def run_step(step, sim, state, sub, gravity, joint):
    nb = sim.model.n_blocks
    force, moment, rot = np.empty((nb, 3)), np.empty((nb, 3)), np.empty((nb, 3, 3))
    stats = step(state, sim._blocks, sub, joint, gravity, sim.timestep, 0.8, rot, force, moment)
    return force, stats


@pytest.fixture(scope="module")
def loaded_wall(benchmark_wall):
    """The benchmark wall settled under gravity and then tilted 12 deg for a while: shear in
    every joint, some slipping, some open, some rocking."""
    sim = dd.Simulation(benchmark_wall)
    sim.cycle_to_equilibrium()
    sim.cycle(300, gravity=tilted_gravity(12.0))
    return sim


@pytest.mark.parametrize("cohesion, tension", [(0.0, 0.0), (50.0, 20.0)])
def test_one_step_gives_the_same_forces_and_motion(loaded_wall, cohesion, tension):
    sim = loaded_wall
    joint = JointArrays.of(dd.JointMaterial(kn=3e7, ks=3e7, friction=0.5, cohesion=cohesion, tension=tension))
    gravity = tilted_gravity(12.0)
    state_nb, sub_nb = copies(sim)
    state_ref, sub_ref = copies(sim)
    force_nb, stats_nb = run_step(kernels.step, sim, state_nb, sub_nb, gravity, joint)
    force_ref, stats_ref = run_step(reference.step, sim, state_ref, sub_ref, gravity, joint)
    scale = np.abs(force_ref).max()
    np.testing.assert_allclose(force_nb, force_ref, rtol=0, atol=1e-12 * scale)
    np.testing.assert_allclose(sub_nb.normal_force, sub_ref.normal_force, rtol=0, atol=1e-12 * scale)
    np.testing.assert_allclose(sub_nb.shear_force, sub_ref.shear_force, rtol=0, atol=1e-12 * scale)
    np.testing.assert_array_equal(sub_nb.intact, sub_ref.intact)
    np.testing.assert_allclose(stats_nb, stats_ref, rtol=1e-10)
    # velocities come from nearly cancelling contact forces (and angular ones are divided by
    # inertias of ~1e-8 kg m2): compare each array to round-off of its own scale
    for a, b in zip(state_nb, state_ref):
        np.testing.assert_allclose(a, b, rtol=0, atol=1e-10 * np.abs(b).max())
    assert (sub_ref.normal_force == 0).any() and (sub_ref.normal_force > 0).any()  # open and closed joints


def test_many_cycles_with_redetection_stay_together():
    """Both engines through the whole Simulation on a small perforated wall (4 bricks x 8 courses,
    a lintel over one opening): 400 cycles at 30 deg (the wall is collapsing,
    so contacts are re-detected). Undamped: local damping's sign(v) is discontinuous at v = 0,
    so with it a block at rest may be pushed either way by round-off (the one-step test above
    covers damping). A collapsing wall amplifies round-off (measured 2e-8 of the largest
    displacement after 500 cycles): stated tolerance 1e-7."""
    blocks = layout_blocks("""
        bBBBb
        BBBB
        bLb
        B....B
        bb....bb
        B....B
        bBBBb
        BBBB
    """)
    model = dd.build_model(blocks, density=1800.0, supports=dd.Supports(fix_y=True), solver=dd.SolverSettings(damping=0.0))
    runs = {}
    for engine in ("numba", "reference"):
        sim = dd.Simulation(model, engine=engine)
        sim.cycle(100)
        result = sim.cycle(400, gravity=tilted_gravity(30.0))
        runs[engine] = (sim, result)
    (fast, r_fast), (slow, r_slow) = runs["numba"], runs["reference"]
    assert r_fast.detections == r_slow.detections > 0
    moved = np.abs(fast.state.position - model.block_centroid).max()
    np.testing.assert_allclose(fast.state.position, slow.state.position, rtol=0, atol=1e-7 * moved)
    # the same contacts carry the same load (sub-contact order may differ: a polygon's first
    # corner depends on round-off)
    totals = []
    for sim in (fast, slow):
        c = sim.contacts
        per_contact = np.bincount(c.contact, c.normal_force, len(c.pairs))
        totals.append(dict(zip(c.pair_keys(model.n_blocks).tolist(), per_contact)))
    assert totals[0].keys() == totals[1].keys()
    for key, load in totals[0].items():
        assert load == pytest.approx(totals[1][key], rel=0, abs=1e-7 * max(totals[0].values()))


def test_compiled_contact_stiffness_and_timestep_match_their_numpy_oracles(benchmark_wall):
    from drydem import motion

    sim = dd.Simulation(benchmark_wall)
    m = benchmark_wall
    fast = motion.contact_stiffness(sim.contacts, 3e7, 1e7, m.n_blocks)
    slow = motion.contact_stiffness_reference(sim.contacts, 3e7, 1e7, m.n_blocks)
    np.testing.assert_allclose(fast[0], slow[0], rtol=1e-12)
    np.testing.assert_allclose(fast[1], slow[1], rtol=0, atol=1e-12 * np.abs(slow[1]).max())
    args = (m.block_mass, m.block_inertia_whitening, m.block_movable, *fast)
    assert motion.critical_timestep(*args) == pytest.approx(motion.critical_timestep_reference(*args), rel=1e-10)


def test_closed_form_largest_eigenvalue_of_symmetric_3x3():
    # Smith (1961) against LAPACK, including repeated and zero eigenvalues
    from drydem.motion import _largest_eigenvalue

    rng = np.random.default_rng(7)
    cases = [np.diag([2.0, 2.0, 2.0]), np.diag([0.0, 0.0, 5.0]), np.diag([3.0, 1.0, 1.0])]
    for _ in range(200):
        q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
        cases.append(q @ np.diag(rng.uniform(0, 10, 3) ** rng.integers(1, 4)) @ q.T)
    for a in cases:
        a = 0.5 * (a + a.T)
        assert _largest_eigenvalue(a) == pytest.approx(np.linalg.eigvalsh(a)[-1], rel=1e-9, abs=1e-12)
