"""Stress-dependent joints (issue 17): kn(sigma) and ks(sigma), power and affine laws.

Closed forms: with d sigma = kn(sigma) d u_n from the unloaded joint, the closure under a stress
sigma is u(sigma) = int_0^sigma ds / kn(s). For the affine law kn = k0 + a sigma that is
u = ln(1 + a sigma / k0) / a, so a block of weight W on area A settles by
u = ln(1 + a W / (k0 A)) / a; for the power law the integral is taken by quadrature
(oracles.joints). A stack of blocks settles by the sum of its joints' closures, each under the
weight above it.
"""

import json
import math

import numpy as np
import pytest

import drydem as dd
from drydem.engine.damping import Damping
from drydem.engine.joints import JointConstants, StressJoint, kernel_joint, normal_energies, normal_stress
from drydem.errors import ModelError
from drydem.io.model_file import model_from_dict
from drydem.model.assembly import Block, build_model
from drydem.model.geometry import box
from drydem.model.parameters import G, JointMaterial
from oracles.joints import closure_of_stress, stress_of_closure

#: block edge, m, and density, kg/m3: a 0.1 m cube weighs 19.6 N, 1.96 kPa on its face
EDGE, DENSITY = 0.1, 2000.0
#: the seed paper's joint-closure fit, kn = 17.52 sigma per mm (Savalle et al. 2022, Section 4.3), 1/m
PAPER_SLOPE = 17_520.0
LAWS = {
    "affine": dict(model="affine", kn=1e6, ks=1e6, kn_per_stress=PAPER_SLOPE),
    "affine clamped": dict(model="affine", kn=1e6, ks=1e6, kn_per_stress=PAPER_SLOPE, kn_max=2e7),
    "power 0.3": dict(model="power", kn=3e7, ks=3e7, kn_exponent=0.3, stress_ref=1e3, kn_min=1e5, kn_max=1e9),
    "power 1": dict(model="power", kn=3e7, ks=3e7, kn_exponent=1.0, stress_ref=1e3, kn_min=1e5, kn_max=1e9),
    "power 1.7": dict(model="power", kn=3e7, ks=3e7, kn_exponent=1.7, stress_ref=1e3, kn_min=1e5, kn_max=1e9),
}


def stack(law: dict, courses: int = 1, *, ratio: float = 1e-10) -> dd.Model:
    """``courses`` cubes of EDGE on a fixed base, joints of ``law``."""
    blocks = [Block(name="base", shape=box([-EDGE, -EDGE, -0.02], [EDGE, EDGE, 0.0]), fixed=True)]
    blocks += [Block(name=f"c{k}", shape=box([-EDGE / 2, -EDGE / 2, k * EDGE], [EDGE / 2, EDGE / 2, (k + 1) * EDGE]))
               for k in range(courses)]
    return build_model(blocks, density=DENSITY, joint=JointMaterial(**law), solver=dd.SolverSettings(ratio=ratio), source="stack")


def settle(model: dd.Model) -> dd.Simulation:
    sim = dd.Simulation(model)
    assert sim.cycle_to_equilibrium().converged
    return sim


def weight_stress(courses_above: int) -> float:
    """Pa: the weight of ``courses_above`` cubes over one cube's face."""
    return courses_above * DENSITY * G * EDGE


@pytest.mark.parametrize("name", LAWS)
def test_closed_form_stress_equals_the_integrated_compliance(name):
    """sigma(u) of the kernels' closed forms against the inverse of u = int ds / kn(s) by
    quadrature, from 1e-8 m to 1 mm of closure, opening included (the stiffness at zero stress)."""
    joint = kernel_joint(JointMaterial(**LAWS[name]))
    for closure in [-1e-6, 1e-8, 1e-7, 1e-6, 1e-5, 1e-4, 1e-3]:
        assert normal_stress(closure, joint) == pytest.approx(stress_of_closure(closure, joint), rel=1e-10)


def test_affine_block_settles_by_the_log_law():
    """u = ln(1 + a W / (k0 A)) / a = 0.257 mm for the paper's slope on k0 = 1e6 Pa/m (against
    W / (k0 A) = 1.96 mm for the linear spring)."""
    law = LAWS["affine"]
    sim = settle(stack(law))
    a, k0 = law["kn_per_stress"], law["kn"]
    expected = math.log1p(a * weight_stress(1) / k0) / a
    assert EDGE / 2 - sim.state.position[1, 2] == pytest.approx(expected, rel=1e-6)


@pytest.mark.parametrize("name", ["power 0.3", "power 1", "power 1.7", "affine clamped"])
def test_stack_settles_by_the_sum_of_its_joints_closures(name):
    """Three cubes: the top one settles by u(3 W / A) + u(2 W / A) + u(W / A), each joint's
    closure the integral of its compliance (oracles.joints)."""
    joint = kernel_joint(JointMaterial(**LAWS[name]))
    sim = settle(stack(LAWS[name], courses=3))
    expected = sum(closure_of_stress(weight_stress(k), joint) for k in (1, 2, 3))
    assert 2.5 * EDGE - sim.state.position[3, 2] == pytest.approx(expected, rel=1e-6)


@pytest.mark.parametrize("law", [dict(model="affine", kn_per_stress=0.0), dict(model="power", kn_exponent=0.0, stress_ref=1e3, kn_min=1e6)],
                         ids=["affine a=0", "power e=0"])
def test_zero_slope_or_exponent_is_the_constant_law_exactly(law):
    """a = 0 or e = 0 is kn, ks constant: the kernels get the constant joint and a settling wall's
    state is the same bit for bit."""
    assert kernel_joint(JointMaterial(**law)) == kernel_joint(JointMaterial())
    assert isinstance(kernel_joint(JointMaterial(**law)), JointConstants)
    states = []
    for joint in (JointMaterial(), JointMaterial(**law)):
        sim = dd.Simulation(stack(dict(vars(joint)), courses=2))
        sim.cycle(400)
        states.append(np.concatenate([sim.state.position.ravel(), sim.contacts.normal_force]))
    np.testing.assert_array_equal(*states)


def test_tiny_slope_approaches_the_constant_law():
    """The closed form stays accurate as the law tends to the constant one (no cancellation):
    a = 1e-3 /m against k0 u (1 + a u / 2 + (a u)^2 / 6), its series, to round-off."""
    joint = kernel_joint(JointMaterial(model="affine", kn=1e7, kn_per_stress=1e-3))
    assert isinstance(joint, StressJoint)
    for closure in (1e-6, 1e-4):
        au = 1e-3 * closure
        assert normal_stress(closure, joint) == pytest.approx(1e7 * closure * (1 + au / 2 + au * au / 6), rel=1e-15)


def oscillation(law: dict, timestep: float, duration_s: float = 0.1) -> tuple[np.ndarray, np.ndarray]:
    """A cube released on its unloaded joint, no damping, at a fixed ``timestep``: it sinks to
    twice its static closure and back, loading and unloading the joint over and over. Returns
    the total energy (kinetic + gravitational + the joint's int sigma du), J, and the closure,
    m, after every cycle."""
    sim = dd.Simulation(stack(law), damping=Damping(0.0), timestep=timestep)
    energy, closure = [], []
    for _ in range(round(duration_s / timestep)):
        sim.cycle(1)
        energy.append(sum(sim.energy().values()))
        closure.append(EDGE / 2 - sim.state.position[1, 2])
    return np.array(energy), np.array(closure)


@pytest.mark.parametrize("name", ["affine", "power 1"])
def test_no_energy_is_created_over_load_unload_cycles(name):
    """Over ~20 load-unload cycles the total energy only swings as the leapfrog's O(dt^2) error
    (it starts at 0): under 1 % of the oscillation's energy m g u_max at dt = 0.2 ms, four
    times less at half the timestep (measured 4.00 and 4.01), and its mean over the last tenth of
    the run is that over the first tenth within 1e-3 of m g u_max (no energy gained or lost).
    A fixed timestep: a change of timestep costs a leapfrog first-order error of its own."""
    swings = []
    for timestep in (2e-4, 1e-4):
        energy, closure = oscillation(LAWS[name], timestep)
        scale = DENSITY * EDGE**3 * G * closure.max()
        swings.append(np.abs(energy).max() / scale)
        tenth = len(closure) // 10
        assert abs(energy[-tenth:].mean() - energy[:tenth].mean()) < 1e-3 * scale
    assert swings[0] < 0.01
    assert swings[0] / swings[1] == pytest.approx(4.0, rel=0.1)


@pytest.mark.parametrize("name", [*LAWS, "power 2"])
def test_normal_energy_is_the_integral_of_the_stress(name):
    """w(u) = int_0^u sigma du' in closed form against quadrature of sigma(u), across every
    piece of the clamp (up to 1 mm of closure), to 1e-9."""
    from scipy.integrate import quad

    law = LAWS.get(name, dict(model="power", kn=3e7, kn_exponent=2.0, stress_ref=1e3, kn_min=1e5, kn_max=1e10))
    joint = kernel_joint(JointMaterial(**law))
    closure = np.array([1e-7, 1e-6, 1e-5, 1e-4, 3e-4, 1e-3])
    expected = [sum(quad(lambda u: normal_stress(u, joint), lo, hi, epsabs=0.0, epsrel=1e-12, limit=200)[0]
                    for lo, hi in zip(np.concatenate([[0.0], np.geomspace(1e-9, c, 40)[:-1]]), np.geomspace(1e-9, c, 40))) for c in closure]
    np.testing.assert_allclose(normal_energies(closure, joint), expected, rtol=1e-9)


def test_timestep_follows_the_stiffness_reached():
    """A 5-cube stack on the linear power law (kn = 3e7 Pa/m at 1 kPa): loading from nothing,
    the bottom joint stiffens ~10x; the timestep is recomputed as it does (every sub-contact's
    closure stays below the limit its timestep holds to), the run does not blow up and ends
    stiffer, with a shorter timestep than at the start."""
    from drydem.engine.contacts import world_points
    from drydem.model.rotation import matrices

    sim = dd.Simulation(stack(LAWS["power 1"], courses=5))
    first = sim.timestep
    assert sim.cycle_to_equilibrium().converged
    assert sim.timestep < first
    _, gap, _ = world_points(sim.contacts, sim.state.position, matrices(sim.state.quaternion))
    assert np.all(-gap <= sim.closure_limit)
    bottom = sim.contacts.normal_force[sim.contacts.block_inc == 1].sum() / EDGE**2
    assert bottom == pytest.approx(weight_stress(5), rel=1e-6)


def test_joint_laws_from_the_model_file():
    blocks = [{"name": "base", "box": {"min": [-0.2, -0.05, -0.02], "max": [0.2, 0.05, 0.0]}, "fixed": True},
              {"name": "b", "box": {"min": [-0.05, -0.05, 0.0], "max": [0.05, 0.05, 0.1]}}]
    law = {"model": "power", "kn": 3e7, "kn_exponent": 0.5, "stress_ref": 2e3, "kn_min": 1e6}
    joint = model_from_dict({"block": blocks, "joint": law}, source="m.toml").joint
    assert (joint.model, joint.ks_exponent, joint.law_value("ks_exponent"), joint.law_value("kn_max")) == ("power", None, 0.5, 1e15)
    assert joint.changed(kn_exponent=1.0).law_value("ks_exponent") == 1.0  # ks follows kn unless given
    assert joint.changed(model="affine", kn_per_stress=1e4) == JointMaterial(kn=3e7, model="affine", kn_per_stress=1e4)
    model = model_from_dict({"block": blocks, "joint": law}, source="m.toml")
    assert model.overridden(joint_law={"model": "constant"}, kn=1e8).joint == JointMaterial(kn=1e8)
    bad = [
        ({"model": "power", "kn_exponent": 0.5}, "needs stress_ref; .* needs kn_min"),
        ({"model": "power"}, "needs kn_exponent; .* needs stress_ref; .* needs kn_min"),
        ({"model": "power", "ks_exponent": 2.0, "stress_ref": 1e3, "kn_min": 1e6}, "needs kn_exponent"),
        ({"model": "power", "kn_exponent": 1.5, "stress_ref": 1e3, "kn_min": 1e6}, "kn_exponent = 1.5 > 1 needs kn_max"),
        ({"model": "power", "kn_exponent": 1.0, "ks_exponent": 2.0, "stress_ref": 1e3, "kn_min": 1e6}, "ks_exponent = 2.0 > 1 needs kn_max"),
        ({"model": "affine", "kn_per_stress": 1e4, "kn_exponent": 0.5}, "kn_exponent applies to model = 'power'"),
        ({"kn_per_stress": 1e4}, "applies to model = 'affine', not 'constant'"),
        ({"model": "power", "kn_exponent": 4.0, "stress_ref": 1e3, "kn_min": 1e6}, r"kn_exponent = 4.0: must be a number in \[0, 3\]"),
        ({"model": "affine", "kn_per_stress": True}, "kn_per_stress = True: must be a number"),
        ({"model": "affine", "kn_per_stress": 1e4, "kn_min": 1e8}, "kn = 3e\\+07 Pa/m: must lie within"),
        ({"model": "power", "kn_exponent": 1, "stress_ref": 1e3, "kn_min": 1e9, "kn_max": 1e8}, "kn_min = 1e\\+09 exceeds kn_max"),
        ({"model": "linear"}, "model = 'linear': must be one of"),
    ]
    for joint, message in bad:
        with pytest.raises(ModelError, match=message):
            model_from_dict({"block": blocks, "joint": joint}, source="m.toml")


def test_joint_law_from_the_command_line(tmp_path):
    """`drydem tilt --joint-model power ...` runs the law (summary.json records it); a law missing
    a key, a key of another law and a boolean stop with the rule, no traceback."""
    from click.testing import CliRunner

    from drydem.cli import main

    law = ["--joint-model", "power", "--kn-exponent", "1", "--stress-ref", "1000", "--joint-kn-min", "1e6"]
    out = tmp_path / "run"
    result = CliRunner().invoke(main, ["tilt", "WD5", *law, "--adaptive", "--increment", "1", "--out", str(out)])
    assert result.exit_code == 0, result.output
    assert "power law: kn (sigma / 1000 Pa)^1" in result.output
    joint = json.loads((out / "summary.json").read_text())["model"]["joint"]
    assert (joint["model"], joint["kn_exponent"], joint["stress_ref"], joint["kn_min"]) == ("power", 1.0, 1000.0, 1e6)
    for bad, message in [(["--joint-model", "power", "--kn-exponent", "1", "--joint-kn-min", "1e6"], "needs stress_ref"),
                         (["--joint-model", "power"], "model = 'power' needs kn_exponent"),
                         (["--kn-per-stress", "100"], "kn_per_stress applies to model = 'affine', not 'constant'"),
                         (["--joint-model", "affine", "--kn-per-stress", "true"], "'true' is not a valid float"),
                         (["--joint-model", "affine", "--kn-per-stress", "-1"], "Invalid value for '--kn-per-stress': -1.0: must be a number in [0, 1e+07] 1/m ([joint] kn_per_stress)")]:
        result = CliRunner().invoke(main, ["tilt", "WD5", *bad, "--out", str(tmp_path / "bad")])
        assert result.exit_code != 0 and message in result.output and "Traceback" not in result.output, result.output


def test_a_runs_joint_law_reaches_its_model_and_id():
    """RunSpec.joint_law (JSON of [joint] keys) replaces the target's law; the run's id says so;
    calibrate refuses a law that cannot take the ends of its kn range."""
    from drydem.parametric.calibrate import StiffnessSearch
    from drydem.parametric.study import RunSpec, joint_law_text

    law = {"model": "affine", "kn_per_stress": PAPER_SLOPE}
    spec = RunSpec(analysis="tilt", target="WD5", protocol="adaptive", kn=1e6, ks=1e6, joint_law=joint_law_text(law))
    assert spec.model().joint == JointMaterial(kn=1e6, ks=1e6, **law)
    assert "-affine-kn1e+06-" in spec.id
    assert RunSpec(analysis="tilt", target="WD5", protocol="adaptive", kn=1e6, ks=1e6).id != spec.id
    problems = StiffnessSearch(("WD5",), 1e6, 1e8, joint_law=law | {"kn_max": 1e7}).problems()
    assert problems and "kn = 1e+08" in problems[0] and "must lie within [kn_min, kn_max]" in problems[0]


def drop(law: dict, height_m: float, cycles: int = 3000) -> tuple[dd.Simulation, float, np.ndarray]:
    """A cube dropped from ``height_m`` onto a joint of ``law``, no damping: the simulation, its
    first timestep (s) and the cube's height above its drawn place after every 10 cycles (m)."""
    model = stack(law)
    state = dd.State.at_rest(model.block_centroid)
    state.position[1, 2] += height_m
    sim = dd.Simulation(model, state=state, damping=Damping(0.0))
    first = sim.timestep
    heights = []
    for _ in range(cycles // 10):
        sim.cycle(10)
        heights.append(sim.state.position[1, 2] - EDGE / 2)
    return sim, first, np.array(heights)


@pytest.mark.parametrize("height_m", [2e-4, 5e-3])
@pytest.mark.parametrize("name", ["affine", "power 1"])
def test_a_cube_dropped_on_a_stiffening_joint_bounces_back_to_its_height(name, height_m):
    """Dropped 0.2 mm, and 5 mm (0.31 m/s at impact, 90 um a cycle at the timestep it falls
    with, while the linear power law's stress grows e-fold every 33 um of closure): the timestep
    is renewed on the way in, short enough to be stable at the stiffness about to be reached
    and to resolve the stiffening (a step closes the joint by at most a quarter of sigma / kn);
    each bounce reaches the drop height within 5 % (measured 0.977 to 1.029; no energy created,
    little lost to the steps' first-order error across changes of timestep; a 1 mm drop on the
    affine law came to 0.85). Without the resolution bound, the 5 mm drop bounced 2.6 times as
    high; without the renewal ahead of the impact, the runs blew up."""
    sim, first, heights = drop(LAWS[name], height_m, cycles=4000)
    assert heights.min() < 0  # it landed
    assert max(heights[20:]) == pytest.approx(height_m, rel=0.05)


def test_dashpots_on_a_stress_dependent_joint_are_refused():
    """Contact dashpots are sized for a constant kn: with a law whose kn follows the stress,
    neither the damping ratio nor the timestep's bound would hold, so dynamics with them stop
    with that reason instead of running on a wrong damping."""
    model = stack(LAWS["affine"])
    with pytest.raises(ModelError, match="contact dashpots .* stress-dependent joint .* not supported"):
        dd.Simulation(model, damping=Damping(0.0, contact_ratio=0.5))
    dd.Simulation(model, damping=Damping(0.0, mass_proportional=1.0))  # Rayleigh's mass term needs no kn


def test_a_shake_of_a_stress_dependent_joint_with_the_default_dashpots_says_how_to_run_it():
    """Found by a hunt: shake's default damping ratio (0.5) on such a joint failed after the
    settling with the engine's message, naming neither the default nor the options."""
    from drydem.analysis.shake import ShakeSettings, pulse, shake_analysis

    motion = pulse("one-sine", amplitude_m_s2=1.0, frequency_hz=2.0, direction="x")
    with pytest.raises(ModelError, match=r"the contacts' damping ratio is 0.5 \(the default\); give --damping-ratio 0"):
        shake_analysis(stack(LAWS["affine"]), ShakeSettings(motion=motion))
    with pytest.raises(ModelError, match=r"calibrated to the restitution \(--restitution\)"):
        shake_analysis(stack(LAWS["affine"]), ShakeSettings(motion=motion, restitution="housner"))
