"""The compiled cycles against their oracles on brick walls: the 3D numba kernel against the plain
NumPy reference (oracles.cycle), the planar kernel (drydem.engine.cycle_planar) against the 3D one."""

import numpy as np
import pytest

import drydem as dd
from drydem.engine import cycle3d
from drydem.engine import cycle_planar
from oracles import cycle as reference
from drydem.engine.damping import Damping
from drydem.engine.joints import kernel_joint
from conftest import layout_blocks, tilted_gravity


def copies(sim):
    """Independent copies of what one step reads and writes."""
    return sim.state.copy(), sim.contacts.copy()


def run_step(step, sim, state, sub, gravity, joint, damping, closure_limit):
    nb = sim.model.n_blocks
    force, moment, rot = np.empty((nb, 3)), np.empty((nb, 3)), np.empty((nb, 3, 3))
    stats = step(state, sim.blocks, sub, joint, closure_limit, gravity, sim.timestep, sim.timestep, damping, rot, force, moment, True)
    return force, stats


@pytest.fixture(scope="module")
def loaded_wall(benchmark_wall):
    """The benchmark wall (in-plane) settled under gravity and then tilted 12 deg for a while:
    shear in every joint, some slipping, some open, some rocking."""
    sim = dd.Simulation(benchmark_wall)
    sim.cycle_to_equilibrium()
    sim.cycle(300, gravity=tilted_gravity(12.0))
    return sim


@pytest.fixture(scope="module")
def loaded_wall_3d(benchmark_wall):
    """The benchmark wall free in y (so in 3D, 4 x 4 points a face), settled, then tilted 12 deg
    along a direction 30 deg out of its plane for a while: all six degrees of freedom move."""
    sim = dd.Simulation(benchmark_wall.replace(supports=dd.Supports()))
    sim.cycle_to_equilibrium()
    sim.cycle(300, gravity=tilted_gravity(12.0, turn_deg=30.0))
    return sim


def assert_same_cycle(step, oracle, sim, joint, gravity, components=(0, 1, 2), damping=Damping(0.8), closure_limit=np.zeros(0)):
    """One cycle of ``step`` and of its ``oracle`` from copies of the same state: block forces
    (``components`` of them), sub-contact forces and slip and the cycle's measures to round-off;
    the motion to round-off of each array's own scale (velocities come from nearly cancelling
    contact forces, and angular ones are divided by inertias of ~1e-8 kg m2). Returns the
    oracle's sub-contacts."""
    (state, sub), (state_oracle, sub_oracle) = copies(sim), copies(sim)
    force, stats = run_step(step, sim, state, sub, gravity, joint, damping, closure_limit)
    force_oracle, stats_oracle = run_step(oracle, sim, state_oracle, sub_oracle, gravity, joint, damping, closure_limit)
    scale = np.abs(force_oracle).max()
    np.testing.assert_allclose(force[:, components], force_oracle[:, components], rtol=0, atol=1e-12 * scale)
    np.testing.assert_allclose(sub.normal_force, sub_oracle.normal_force, rtol=0, atol=1e-12 * scale)
    np.testing.assert_allclose(sub.shear_force, sub_oracle.shear_force, rtol=0, atol=1e-12 * scale)
    np.testing.assert_array_equal(sub.intact, sub_oracle.intact)
    np.testing.assert_allclose(stats, stats_oracle, rtol=1e-10)
    for a, b in zip(state, state_oracle):
        np.testing.assert_allclose(a, b, rtol=0, atol=1e-10 * np.abs(b).max())
    return sub_oracle


@pytest.mark.parametrize("cohesion, tension", [(0.0, 0.0), (50.0, 20.0)])
def test_one_step_gives_the_same_forces_and_motion(loaded_wall_3d, cohesion, tension):
    joint = kernel_joint(dd.JointMaterial(kn=3e7, ks=3e7, friction=0.5, cohesion=cohesion, tension=tension))
    assert not loaded_wall_3d.model.in_plane and np.abs(loaded_wall_3d.state.angular_velocity[:, [0, 2]]).max() > 0
    sub = assert_same_cycle(cycle3d.step, reference.step, loaded_wall_3d, joint, tilted_gravity(12.0, turn_deg=30.0))
    assert (sub.normal_force == 0).any() and (sub.normal_force > 0).any()  # open and closed joints


def test_planar_step_gives_the_3d_kernels_forces_and_motion(loaded_wall):
    """An in-plane wall (the benchmark wall): one planar cycle against one 3D cycle from the same
    state, to round-off; the 3D kernel leaves y, rx and rz untouched there (they are held)."""
    assert loaded_wall.model.in_plane
    joint = kernel_joint(loaded_wall.model.joint)
    sub = assert_same_cycle(cycle_planar.step, cycle3d.step, loaded_wall, joint, tilted_gravity(12.0), components=[0, 2])
    assert (sub.shear_force != 0).any() and (sub.normal_force == 0).any()


#: stress-dependent joints whose stiffness ranges over decades within the loaded walls' stresses
#: (kn at 1 kPa = 3e7 Pa/m; the affine law's slope the seed paper's 17.52 per mm)
STRESS_JOINTS = [
    dict(model="power", kn=3e7, ks=2e7, kn_exponent=0.8, ks_exponent=0.5, stress_ref=1e3, kn_min=1e5, kn_max=1e10),
    dict(model="affine", kn=1e6, ks=1e6, kn_per_stress=17520.0, ks_per_stress=8000.0, kn_max=1e9),
]


@pytest.mark.parametrize("law", STRESS_JOINTS, ids=lambda law: law["model"])
def test_stress_dependent_joint_gives_the_oracles_forces_and_motion(loaded_wall_3d, loaded_wall, law):
    """kn(sigma), ks(sigma): the 3D kernel against the NumPy oracle (its shear stiffness from
    oracles.joints), the planar kernel against the 3D one, one cycle from the same states."""
    joint = kernel_joint(dd.JointMaterial(friction=0.5, **law))
    for sim, step, oracle, gravity, components in [
        (loaded_wall_3d, cycle3d.step, reference.step, tilted_gravity(12.0, turn_deg=30.0), [0, 1, 2]),
        (loaded_wall, cycle_planar.step, cycle3d.step, tilted_gravity(12.0), [0, 2]),
    ]:
        # closure limits below and above every sub-contact's closure: the step says whether one closes past its own
        for limit, stiffer in [(0.0, True), (1.0, False)]:
            closure_limit = np.full(sim.contacts.count, limit)
            assert_same_cycle(step, oracle, sim, joint, gravity, components=components, closure_limit=closure_limit)
            assert run_step(step, sim, *copies(sim), gravity, joint, Damping(0.8), closure_limit)[1][-1] is stiffer


#: dynamics' damping: no local damping, contact dashpots (ratio and Rayleigh's stiffness term) and
#: Rayleigh's mass term, each large enough to change the forces well above round-off
VISCOUS = Damping(0.0, contact_ratio=0.3, stiffness_proportional=1e-4, mass_proportional=2.0)


def test_viscous_damping_gives_the_oracles_forces_and_motion(loaded_wall_3d, loaded_wall):
    """The dashpots and the mass-proportional drag: the 3D kernel against the NumPy oracle, the
    planar kernel against the 3D one, one cycle from the same moving states."""
    joint = kernel_joint(loaded_wall_3d.model.joint)
    assert_same_cycle(cycle3d.step, reference.step, loaded_wall_3d, joint, tilted_gravity(12.0, turn_deg=30.0), damping=VISCOUS)
    joint = kernel_joint(loaded_wall.model.joint)
    assert_same_cycle(cycle_planar.step, cycle3d.step, loaded_wall, joint, tilted_gravity(12.0), components=[0, 2], damping=VISCOUS)


def test_many_cycles_with_redetection_stay_together():
    """The three engines (numba: planar here; numba-3d; reference) through the whole Simulation on a small perforated wall (4 bricks x 8 courses,
    a lintel over one opening): 400 cycles at 30 deg (the wall is collapsing,
    so contacts are re-detected). Undamped: local damping's sign(v) is discontinuous at v = 0,
    so with it a block at rest may be pushed either way by round-off (the one-step test above
    covers damping). A collapsing wall amplifies round-off (measured 3e-9 of the largest
    displacement after 500 cycles): stated tolerance 1e-7; on contact loads 1e-6 of the largest,
    what kn A (2e3 N/m a point) makes of 1e-7 of the displacement (1e-10 m) against a 0.16 N load."""
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
    assert model.in_plane
    runs = {}
    for engine in ("numba", "numba-3d", "reference"):
        sim = dd.Simulation(model, engine=reference.run_cycles if engine == "reference" else engine)
        sim.cycle(100)
        result = sim.cycle(400, gravity=tilted_gravity(30.0))
        runs[engine] = (sim, result)
    slow, r_slow = runs["reference"]
    moved = np.abs(slow.state.position - model.block_centroid).max()
    totals = {}
    for engine, (sim, result) in runs.items():
        assert result.detections == r_slow.detections > 0
        np.testing.assert_allclose(sim.state.position, slow.state.position, rtol=0, atol=1e-7 * moved)
        # the same contacts carry the same load (sub-contact order may differ: a polygon's
        # first corner depends on round-off)
        c = sim.contacts
        per_contact = np.bincount(c.contact, c.normal_force, len(c.pairs))
        totals[engine] = dict(zip(c.pair_keys(model.n_blocks).tolist(), per_contact))
    for engine in ("numba", "numba-3d"):
        assert totals[engine].keys() == totals["reference"].keys()
        for key, load in totals[engine].items():
            assert load == pytest.approx(totals["reference"][key], rel=0, abs=1e-6 * max(totals["reference"].values()))


def test_compiled_contact_stiffness_and_timestep_match_their_numpy_oracles(benchmark_wall):
    from drydem.engine import inertia
    from oracles.inertia import contact_stiffness_reference, critical_timestep_reference

    sim = dd.Simulation(benchmark_wall)
    m = benchmark_wall
    # per sub-contact stiffness varying over two decades, as a stress-dependent joint's
    stiffness = np.geomspace(1e7, 1e9, sim.contacts.count)
    fast = inertia.contact_stiffness(sim.contacts, stiffness, m.n_blocks)
    slow = contact_stiffness_reference(sim.contacts, stiffness, m.n_blocks)
    np.testing.assert_allclose(fast[0], slow[0], rtol=1e-12)
    np.testing.assert_allclose(fast[1], slow[1], rtol=0, atol=1e-12 * np.abs(slow[1]).max())
    args = (m.block_mass, m.block_inertia_whitening, m.block_movable, *fast)
    assert inertia.critical_timestep(*args) == pytest.approx(critical_timestep_reference(*args), rel=1e-10)


def _tiny_building() -> dd.Model:
    from drydem.masonry.building import BuildingSpec, building_model

    return building_model(BuildingSpec(length_m=0.8, width_m=0.5, storeys=1, storey_height_courses=8, brick_length_m=0.1,
                                       brick_height_m=0.05, windows_per_wall=1, window_width_bricks=1, window_height_courses=3,
                                       sill_courses=2))


@pytest.mark.parametrize("name", ["brick on a fixed base", "brick held in y", "three blocks turned 17 deg", "benchmark wall",
                                  "one-storey building"])
def test_the_timestep_keeps_local_damping_stable_at_the_highest_natural_frequency(benchmark_wall, name):
    """Central differences are stable for omega_max dt < 2 (Cundall & Strack 1979), and with
    local damping alpha only below 2 / sqrt(1 + alpha): the damped force F - alpha |F| sign(v)
    is (1 + alpha) F when the motion opposes it, a stiffness 1.8 times the spring's at 0.8
    (measured 2026-11-27: a brick on a fixed base, cycled at the exact omega_max, settles in 38-80
    cycles up to omega dt = 1.48 and rattles at a ratio of 0.5 for 10^5 cycles from 1.50). The
    engine's timestep, from its blockwise bound and the safety 0.8, keeps omega_max dt, with
    omega_max of the assembled springs (tests/oracles/inertia.py), at 1.00-1.13 on these models:
    a bound 1.5 times tighter (the 6 x 6 block with fixed partners counted once, tried that
    day) gave 1.6 on the brick, and it never settled."""
    from drydem.engine.inertia import stiffness_bound
    from drydem.engine.joints import kernel_joint
    from oracles.inertia import highest_omega_sq

    from conftest import stack_model

    model = {"brick on a fixed base": lambda: stack_model([0.05]),
             "brick held in y": lambda: stack_model([0.05], supports=dd.Supports(fix_y=True)),
             "three blocks turned 17 deg": lambda: stack_model([0.05, 0.03, 0.08], turn_deg=17.0),
             "benchmark wall": lambda: benchmark_wall, "one-storey building": _tiny_building}[name]()
    sim = dd.Simulation(model)
    springs = stiffness_bound(kernel_joint(model.joint), sim.contacts, 1.0).stiffness
    omega_max = np.sqrt(highest_omega_sq(model, sim.state, sim.contacts, springs, model.block_movable))
    assert 0.9 <= omega_max * sim.timestep <= 2.0 / np.sqrt(1.0 + model.solver.damping)


def test_shear_force_turned_into_the_new_tangent_plane_keeps_its_magnitude():
    """F_s at an angle theta out of the new tangent plane, its normal part taken out and the rest
    scaled by magnitude_kept(sin^2 theta): |F_s| back to a few ulps times the problem's condition
    number 1 / cos^2 theta (x = sin^2 theta carries a rounding of its own, which 1 / sqrt(1 - x)
    amplifies by 1 / (2 (1 - x)); at theta = 1.5 rad, 61 ulps, a bound of 4 ulps failing on a
    fresh install), on both sides of the series' threshold (theta^2 = OUT_OF_PLANE_SERIES); the
    factor equals 1 / sqrt(1 - x) in extended precision to 2 ulps; F_s along n gives nothing to keep."""
    rng = np.random.default_rng(11)
    angles = np.concatenate([np.geomspace(1e-9, 1.5, 60), np.sqrt(cycle3d.OUT_OF_PLANE_SERIES) * np.array([0.999, 1.0, 1.001])])
    for theta in angles:
        n = rng.normal(size=3)
        n /= np.linalg.norm(n)
        t = np.cross(n, rng.normal(size=3))
        t /= np.linalg.norm(t)
        force = 250.0 * (np.cos(theta) * t + np.sin(theta) * n)
        fsn = force @ n
        x = fsn * fsn / (force @ force)
        scale = cycle3d.magnitude_kept(x)
        conditioned = 4.0 * np.finfo(float).eps / np.cos(theta) ** 2
        assert np.linalg.norm((force - fsn * n) * scale) == pytest.approx(250.0, rel=conditioned)
        exact = 1.0 / np.sqrt(np.longdouble(1.0) - np.longdouble(x))
        assert abs(np.longdouble(scale) - exact) <= 2 * np.spacing(scale)
    assert cycle3d.magnitude_kept(1.0) == 0.0


def test_closed_formlargest_eigenvalue_of_symmetric_3x3():
    # Smith (1961) against LAPACK, including repeated and zero eigenvalues
    from drydem.engine.inertia import largest_eigenvalue

    rng = np.random.default_rng(7)
    cases = [np.diag([2.0, 2.0, 2.0]), np.diag([0.0, 0.0, 5.0]), np.diag([3.0, 1.0, 1.0])]
    for _ in range(200):
        q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
        cases.append(q @ np.diag(rng.uniform(0, 10, 3) ** rng.integers(1, 4)) @ q.T)
    for a in cases:
        a = 0.5 * (a + a.T)
        assert largest_eigenvalue(a) == pytest.approx(np.linalg.eigvalsh(a)[-1], rel=1e-9, abs=1e-12)


def test_walls_held_in_y_are_in_plane_and_other_models_are_not():
    """Model.in_plane: held in y, prisms across y, one mid-plane. In-plane walls also hold rx and rz
    and get one sub-contact across the width; the others keep what their supports say."""
    from conftest import stack_model

    from drydem.io.target import load_target

    wall = load_target("WD3").model
    assert wall.in_plane and wall.contact_density.across == 1
    movable = wall.block_movable
    assert wall.block_fixed[movable][:, [1, 3, 5]].all() and not wall.block_fixed[movable][:, [0, 2, 4]].any()
    held = dd.Supports(fix_y=True)
    assert stack_model([0.0055], supports=held).in_plane
    assert not stack_model([0.0055]).in_plane  # free in y
    turned = stack_model([0.0055], supports=held, turn_deg=30.0)  # faces oblique to y
    assert not turned.in_plane and not turned.block_fixed[1, [3, 5]].any() and turned.contact_density.across == 2
    blocks = [
        dd.Block(name="base", shape=dd.box([-0.01, 0.0, -0.01], [0.035, 0.012, 0.0]), fixed=True),
        dd.Block(name="brick", shape=dd.box([0.0, 0.0, 0.0], [0.025, 0.012, 0.0055])),
        dd.Block(name="narrow", shape=dd.box([0.0, 0.0, 0.0055], [0.025, 0.006, 0.011])),  # off the mid-plane
    ]
    assert dd.build_model(blocks[:2], density=1800.0, supports=held).in_plane
    assert not dd.build_model(blocks, density=1800.0, supports=held).in_plane


def test_compiled_cycling_loops_are_loaded_from_the_cache_in_a_new_process():
    """numba's on-disk cache must serve the cycling loops: a loop compiled in every process costs
    seconds at every start (it did while the loop was a closure over the step function)."""
    import os
    import subprocess
    import sys

    script = (
        "import drydem as dd, numpy as np\n"
        "wall = dd.build_model([dd.Block(name='base', shape=dd.box([-0.1, 0, -0.01], [0.1, 0.012, 0]), fixed=True),\n"
        "    dd.Block(name='brick', shape=dd.box([0, 0, 0], [0.025, 0.012, 0.0055]))], density=1800.0, supports=dd.Supports(fix_y=True))\n"
        "assert wall.in_plane\n"
        "for engine in ('numba', 'numba-3d'):\n"
        "    dd.Simulation(wall, engine=engine).cycle(10)\n"
    )
    env = dict(os.environ, NUMBA_DEBUG_CACHE="1")
    runs = [subprocess.run([sys.executable, "-c", script], env=env, capture_output=True, text=True, check=True) for _ in range(2)]
    saved = [line for line in runs[1].stdout.splitlines() if "data saved" in line and "run_cycles" in line]
    loaded = [line for line in runs[1].stdout.splitlines() if "data loaded" in line and "run_cycles" in line]
    assert not saved and len(loaded) == 2, runs[1].stdout[-2000:]
