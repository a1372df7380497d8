"""The tilting-table protocol (paper Section 3) against closed forms, and its variants.

Closed forms for rigid blocks on a tilting table: sliding when tan(theta) = mu, toppling when
tan(theta) = b / h (the weight's line of action passes the downhill edge). The protocol
reports the last tilt at which equilibrium was found, so with steps of d deg the collapse
angle lies in (theta_c - d, theta_c]; with stiff joints (kn = 1e10) the elastic rotation
moves theta_c by less than 0.01 deg (stated discretisation error: 0).
"""

import math
import re
import time

import numpy as np
import pytest

import drydem as dd
from drydem.analysis.drift import drift_limit_angles
from drydem.analysis.tilt import TiltSettings, monitored_block, tilt_analysis, wall_height
from conftest import BRICK, prism_model, stack_model

STEP = 0.5


def within_one_step_below(angle, exact):
    return exact - STEP - 1e-9 <= angle <= exact + 1e-9


def test_single_block_slides_at_atan_mu():
    model = stack_model([0.0055], joint=dd.JointMaterial(kn=1e8, ks=1e8, friction=0.5))
    result = tilt_analysis(model, TiltSettings(increment_deg=STEP))
    assert within_one_step_below(result.collapse_angle_deg, math.degrees(math.atan(0.5)))
    # it slides off the end of its 125 mm base before it has moved 10 cm, and falls
    assert result.ended_by == "monitored block fell" and result.stable_under_gravity
    assert result.final_state.position[1, 0] - model.block_centroid[1, 0] > 0.05


def slender(heights, kn=1e10):
    # 10 mm wide, 40 mm tall in all: tan(theta) = 1/4 (14.04 deg); mu = 1 so it cannot slide first
    return stack_model(heights, size_xy=(0.01, 0.012), joint=dd.JointMaterial(kn=kn, ks=kn, friction=1.0))


@pytest.mark.parametrize("increment_deg, max_angle_deg", [(1.0, 30.0), (6.0, 80.0)])
def test_adaptive_steps_past_the_maximum_angle_are_refined_and_the_block_still_slides_at_atan_mu(increment_deg, max_angle_deg):
    """The first adaptive step, 16 increments (32 and 96 deg here), passes the maximum angle: it is
    halved, as a failed trial is, not the end of the run ("no collapse up to 30 deg" before, for
    a brick sliding at atan 0.5 = 26.57 deg)."""
    model = stack_model([0.0055], joint=dd.JointMaterial(kn=1e8, ks=1e8, friction=0.5))
    result = tilt_analysis(model, TiltSettings(increment_deg=increment_deg, adaptive=True, max_angle_deg=max_angle_deg))
    exact = math.degrees(math.atan(0.5))
    assert exact - increment_deg - 1e-9 <= result.collapse_angle_deg <= exact + 1e-9 and result.ended_by == "monitored block fell"


def test_no_collapse_below_the_maximum_angle_ends_at_the_last_increment_within_it():
    """A brick sliding at 26.57 deg tilted in 1 deg steps up to 20.5 deg: the last equilibrium is 20 deg, the last step within it."""
    model = stack_model([0.0055], joint=dd.JointMaterial(kn=1e8, ks=1e8, friction=0.5))
    for adaptive in (False, True):
        result = tilt_analysis(model, TiltSettings(increment_deg=1.0, adaptive=adaptive, max_angle_deg=20.5))
        assert (result.ended_by, result.collapse_angle_deg, result.last_equilibrium_deg) == ("maximum angle", None, 20.0)


def test_an_equilibrium_beyond_the_stop_displacement_ends_the_run_at_the_one_before():
    """The stop displacement ends the run when the monitored point reaches it at rest too (a
    brick shearing its joint elastically, ~0.1 um a degree): before, only a step that did not
    settle was tested, and 1e-8 m was accepted and never acted (the run went on to max_angle)."""
    model = stack_model([0.0055], joint=dd.JointMaterial(kn=1e8, ks=1e8, friction=0.5))
    elastic = tilt_analysis(model, TiltSettings(increment_deg=1.0, max_angle_deg=3.0))
    ux = {r.tilt_deg: r.ux_m for r in elastic.records}
    assert 0.0 < ux[1.0] < ux[2.0] < ux[3.0] < 1e-6
    stop = 0.5 * (ux[2.0] + ux[3.0])
    result = tilt_analysis(model, TiltSettings(increment_deg=1.0, max_angle_deg=5.0, stop_displacement_m=stop))
    assert (result.ended_by, result.collapse_angle_deg) == ("stop displacement", 2.0)
    assert max(abs(r.ux_m) for r in result.records) < stop


def test_a_brick_on_joints_closing_most_of_its_height_settles_by_w_over_kn_a_and_slides_at_atan_mu():
    """kn = 2e4 Pa/m, the brick 5.5 mm high: it settles by rho g h / kn = 4.855 mm (W / (kn A)),
    then slides at atan 0.5 = 26.57 deg. Its critical timestep (17 ms) let it fall through its
    joint in 2 cycles, before the spring acted, and it was called unable to stand; the free-flight
    bound (drydem.engine.inertia.free_flight_timestep) keeps each cycle's fall within the tolerance."""
    kn = 2e4
    model = stack_model([0.0055], joint=dd.JointMaterial(kn=kn, ks=kn, friction=0.5), supports=dd.Supports(fix_y=True))
    sim = dd.Simulation(model)
    assert sim.cycle_to_equilibrium().converged
    settlement = model.block_centroid[1, 2] - sim.state.position[1, 2]
    assert settlement == pytest.approx(1800.0 * dd.G * 0.0055 / kn, rel=1e-3)
    result = tilt_analysis(model, TiltSettings(increment_deg=1.0))
    assert result.stable_under_gravity and 26.57 - 1.0 <= result.collapse_angle_deg <= 26.57


def test_slender_block_topples_at_atan_b_over_h():
    result = tilt_analysis(slender([0.04]), TiltSettings(increment_deg=STEP))
    assert within_one_step_below(result.collapse_angle_deg, math.degrees(math.atan(0.25)))


def test_stack_of_blocks_topples_as_one_body_of_the_full_height():
    result = tilt_analysis(slender([0.01] * 4), TiltSettings(increment_deg=STEP))
    assert within_one_step_below(result.collapse_angle_deg, math.degrees(math.atan(0.25)))
    # it rotated as one body: every block moved downhill, the top most
    moved = result.final_state.position[1:, 0] - slender([0.01] * 4).block_centroid[1:, 0]
    assert np.all(np.diff(moved) > 0)


@pytest.mark.parametrize("sides", [6, 40])
def test_a_polygonal_prism_topples_about_its_outermost_corner_at_atan_r_over_half_its_height(sides):
    # circumradius 20 mm, 120 mm high, a corner downhill: tan = 0.02 / 0.06 = 1/3, 18.43 deg (a
    # contact grid whose points stopped short of the corners gave 14.5 deg for 40 sides). Near
    # tipping, the corner's point, of a small area, takes the weight and closes more than a face's
    # edge row would: the block turns on it, and topples earlier the softer the joint (0.1 deg
    # steps, 40 sides: 17.8 deg at kn = 1e10 Pa/m, 18.2 at 1e11, 18.3 at 1e12; measured)
    angles = [tilt_analysis(prism_model(sides, 0.02, 0.12, kn=kn), TiltSettings(increment_deg=STEP)).collapse_angle_deg for kn in (1e10, 1e12)]
    assert angles[0] <= angles[1]
    assert within_one_step_below(angles[1], math.degrees(math.atan(1 / 3)))


def test_a_prism_overhanging_its_slabs_edge_topples_about_that_edge():
    # an octagonal prism (circumradius 20 mm, 60 mm high, turned 0.2 rad) on a slab that ends
    # under its bed face at x = 8 mm: it pivots on the slab's edge, tan = 8 / 30, 14.93 deg. Turning
    # on it, the bed face lies on the edge, which runs past the face on both sides (an edge-face
    # contact: tests/test_contact_types.py); taken for one crossed-edge point, its other crossing
    # sank unseen, and the step to 15 deg diverged at kn = 1e12 Pa/m
    model = prism_model(8, 0.02, 0.06, points=2, kn=1e12, turn_rad=0.2, slab_end_x=0.008)
    result = tilt_analysis(model, TiltSettings(increment_deg=STEP))
    assert result.ended_by == "monitored block toppled"
    assert within_one_step_below(result.collapse_angle_deg, math.degrees(math.atan(8 / 30)))


def test_a_cohesive_joint_collapses_near_its_first_slip_converging_with_more_points():
    """Elastic-brittle cohesion (lost for good where a sub-contact slips): the brick's joint
    first slips where the linear normal stress W / A (1 - 3 lambda h / b) is least, at
    lambda = (mu + c A / W) / (1 + 3 mu h / b) = 0.6015 (31.0 deg; README, "Limit analysis"),
    below the rigid-plastic limit lambda = mu + c A / W = 0.8 (38.66 deg); the tilt converges on
    the first slip as the points per length grow (35.7 deg at 2, 31.8 at 16 in 0.1 deg steps, 2026-11-28)."""
    b, _, h = BRICK
    weight_per_area = 1800.0 * dd.G * h
    joint = dd.JointMaterial(kn=1e9, ks=1e9, friction=0.5, cohesion=0.3 * weight_per_area)
    first_slip = math.degrees(math.atan((0.5 + 0.3) / (1 + 3 * 0.5 * h / b)))
    angles = [tilt_analysis(stack_model([h], joint=joint, points=points, supports=dd.Supports(fix_y=True)),
                            TiltSettings(increment_deg=STEP, adaptive=True, loading="multiplier")).collapse_angle_deg
              for points in (2, 16)]
    assert first_slip - STEP <= angles[1] < angles[0] < math.degrees(math.atan(0.8))
    assert angles[1] - first_slip < 1.0


def test_multiplier_loading_gives_lambda_equal_to_mu():
    # horizontal lambda W against friction mu W: lambda = mu, i.e. the same tilt equivalent
    model = stack_model([0.0055], joint=dd.JointMaterial(kn=1e8, ks=1e8, friction=0.5))
    result = tilt_analysis(model, TiltSettings(increment_deg=STEP, loading="multiplier"))
    assert within_one_step_below(result.collapse_angle_deg, math.degrees(math.atan(0.5)))
    assert result.load_multiplier == pytest.approx(math.tan(math.radians(result.collapse_angle_deg)))
    assert result.load_multiplier <= 0.5 + 1e-12


def pier(kn):
    """8 stacked bricks, 25 mm wide, 44 mm tall, in-plane, mu = 0.8 (rigid toppling at 29.6 deg)."""
    return stack_model([0.0055] * 8, joint=dd.JointMaterial(kn=kn, ks=kn, friction=0.8), supports=dd.Supports(fix_y=True))


@pytest.mark.slow
def test_softer_joints_lower_the_collapse_angle():
    # the paper's finding (Section 4.3, Table 4): joint flexibility lowers the capacity; with
    # stiffer joints the pier tends to the rigid atan(25 / 44) = 29.6 deg.
    # Measured: 24.0, 27.5, 29.0, 29.5 deg for kn = 1e7, 3e7, 1e8, 1e9 Pa/m.
    angles = [tilt_analysis(pier(kn), TiltSettings(increment_deg=STEP)).collapse_angle_deg for kn in (1e7, 1e8, 1e9)]
    assert angles[0] < angles[1] < angles[2] <= math.degrees(math.atan(25 / 44))
    assert angles[2] > math.degrees(math.atan(25 / 44)) - 2 * STEP


@pytest.mark.slow
@pytest.mark.parametrize("model", [slender([0.04]), pier(3e7)], ids=["rigid block", "soft pier"])
def test_fixed_and_adaptive_protocols_agree_within_one_increment(model):
    fixed = tilt_analysis(model, TiltSettings(increment_deg=STEP))
    adaptive = tilt_analysis(model, TiltSettings(increment_deg=STEP, adaptive=True))
    assert abs(fixed.collapse_angle_deg - adaptive.collapse_angle_deg) <= STEP + 1e-9
    assert len(adaptive.records) < len(fixed.records)


def test_the_predictor_saves_cycles_and_keeps_the_pushover_curve():
    # each step starts from the last two equilibria extrapolated; the same equilibria are found
    # (to the equilibrium tolerance: measured 5e-4 of the top displacement) with fewer cycles
    # (measured 31.9k against 44.3k in the equilibrium steps of the soft pier at 0.5 deg)
    predicted = tilt_analysis(pier(3e7), TiltSettings(increment_deg=STEP))
    plain = tilt_analysis(pier(3e7), TiltSettings(increment_deg=STEP, predictor=False))
    assert predicted.collapse_angle_deg == plain.collapse_angle_deg
    np.testing.assert_allclose([r.ux_m for r in predicted.records], [r.ux_m for r in plain.records], rtol=2e-3, atol=1e-9)
    assert sum(r.cycles for r in predicted.records) < 0.8 * sum(r.cycles for r in plain.records)


def test_the_predictor_extrapolates_an_elastic_trend_and_not_a_jump():
    # equilibria at 1.0, 1.1 and 1.2 deg (made up): the block moved 1 um per step, so the
    # step to 1.3 deg starts 1 um further; after a 10 um jump (a slip, 10x the trend per degree)
    # the next step starts where the jump left it: friction would keep what it is given
    from drydem.analysis.tilt import TiltRun

    model = stack_model([0.0055], supports=dd.Supports(fix_y=True))
    run = TiltRun(model, TiltSettings(), on_progress=None)
    run.sim.cycle_to_equilibrium()
    start = run.sim.state.copy()

    def at(theta, dx):
        state = start.copy()
        state.position[1, 0] += dx
        return theta, state

    for jump, expected in [(1e-6, 1e-6), (1e-5, 0.0)]:
        run.equilibria, run.trends = [], []
        for theta, dx in [(1.0, 0.0), (1.1, 1e-6), (1.2, 1e-6 + jump)]:
            run.remember(*at(theta, dx))
        run.sim.state = at(1.2, 1e-6 + jump)[1]
        run.predict(1.3)
        moved = run.sim.state.position[1, 0] - start.position[1, 0] - 1e-6 - jump
        assert moved == pytest.approx(expected, rel=1e-6, abs=1e-12)


def test_the_predictor_moves_at_most_its_cap_in_elastic_closures():
    # a brick on its base closes its joint by m g / (kn A) under its own weight (9.7e-7 m here);
    # an elastic trend of 1 mm per step is extrapolated by predictor_cap_closures of those only
    from drydem.analysis.tilt import TiltRun

    model = stack_model([0.0055], supports=dd.Supports(fix_y=True))
    closure = model.block_mass[1] * dd.G / (model.joint.kn * BRICK[0] * BRICK[1])
    run = TiltRun(model, TiltSettings(), on_progress=None)
    assert run.elastic_closure == pytest.approx(closure, rel=1e-9)
    run.sim.cycle_to_equilibrium()
    start = run.sim.state.copy()
    for k, theta in enumerate([1.0, 1.1, 1.2]):
        state = start.copy()
        state.position[1, 0] += k * 1e-3
        run.remember(theta, state)
    run.sim.state = run.equilibria[-1][1].copy()
    run.predict(1.3)
    moved = run.sim.state.position[1, 0] - start.position[1, 0] - 2e-3
    assert moved == pytest.approx(TiltSettings().predictor_cap_closures * closure, rel=1e-6)


def test_a_model_that_cannot_stand_is_reported_with_its_state():
    # a block with its centroid beyond the edge of the base falls under its own weight
    base = dd.Block(name="base", shape=dd.box([-0.1, 0.0, -0.01], [0.0, 0.012, 0.0]), fixed=True)
    block = dd.Block(name="overhang", shape=dd.box([-0.01, 0.0, 0.0], [0.03, 0.012, 0.0055]))
    model = dd.build_model([base, block], density=1800.0, solver=dd.SolverSettings(max_cycles=20_000))
    result = tilt_analysis(model, TiltSettings(increment_deg=STEP))
    assert not result.stable_under_gravity and result.collapse_angle_deg is None
    assert result.ended_by == "unstable under gravity" and result.records == []
    assert result.final_state.position[1, 2] < model.block_centroid[1, 2] - 1e-3


def test_a_block_falling_out_is_taken_out_and_the_wall_goes_on():
    # a squat block in the middle of the base (slides at 26.6 deg) and a slender one on its
    # downhill end (topples at 14 deg, over the edge): the slender one falls off the base and
    # is taken out; the analysis goes on and still finds the slide
    base = dd.Block(name="base", shape=dd.box([-0.05, 0.0, -0.01], [0.1, 0.012, 0.0]), fixed=True)
    block = dd.Block(name="block", shape=dd.box([0.0, 0.0, 0.0], [0.025, 0.012, 0.0055]))
    loose = dd.Block(name="loose", shape=dd.box([0.09, 0.0, 0.0], [0.1, 0.012, 0.04]))
    model = dd.build_model([base, block, loose], density=1800.0, joint=dd.JointMaterial(kn=1e8, ks=1e8, friction=0.5))
    result = tilt_analysis(model, TiltSettings(increment_deg=STEP, monitor="block", stop_displacement_m=0.02))
    assert [name for name, _ in result.lost_blocks] == ["loose"]
    # it fell at the first step past its toppling angle: atan(1/4) = 14.04 deg for a rigid
    # block, a little less on these joints (measured 13.5)
    assert 12.5 <= result.lost_blocks[0][1] <= math.degrees(math.atan(0.25)) + STEP
    assert within_one_step_below(result.collapse_angle_deg, math.degrees(math.atan(0.5)))


def test_drift_limit_angles_are_interpolated_on_the_pushover_curve():
    # synthetic curve: drift = theta / 1000 up to 6 deg, then 0.3 % per degree
    theta = np.arange(0.0, 10.0, 0.5)
    drift = np.where(theta <= 6, theta / 1000, 0.006 + (theta - 6) * 0.003)
    angles = drift_limit_angles(theta, drift)
    assert angles[0.005] == pytest.approx(5.0)
    assert angles[0.0075] == pytest.approx(6.5)
    assert angles[0.01] == pytest.approx(6 + 4 / 3)
    assert drift_limit_angles(theta, drift / 100)[0.01] is None


@pytest.mark.parametrize("angles, drift, limits, words", [
    ([0.0, 1.0], [0.0, 0.02, 0.03], (0.01,), "must be 1-D arrays of finite numbers of one length"),
    ([0.0, math.nan], [0.0, 0.02], (0.01,), "must be 1-D arrays of finite numbers of one length"),
    ("ab", [0.0, 0.02], (0.01,), "must be 1-D arrays of finite numbers of one length"),
    ([1.0, 0.0], [0.0, 0.02], (0.01,), "the angles of the states must not decrease"),
    ([0.0, 1.0], [0.0, 0.02], (True,), "drift_limit_angles limit = True: must be a number in (0, 1]"),
])
def test_drift_limit_angles_refuse_what_is_no_pushover_curve(angles, drift, limits, words):
    """Found by a hunt: arrays of two lengths, NaN, decreasing angles and a limit True gave answers."""
    with pytest.raises(dd.ModelError, match=re.escape(words)):
        drift_limit_angles(angles, drift, limits)


def test_monitored_block_is_the_top_block_nearest_the_middle(benchmark_wall):
    name = benchmark_wall.block_name[monitored_block(benchmark_wall)]
    assert name.startswith("c26")  # top course
    assert wall_height(benchmark_wall) == pytest.approx(27 * 0.0055)


@pytest.mark.parametrize("name", ["WD3", "WD6"])
def test_an_imperfect_wall_monitors_the_perfect_walls_top_middle_block(name):
    """Found by a hunt: with scattered brick heights the monitored block was the tallest brick
    of the top course, anywhere along it (an end half-brick in 2 seeds of 20), so each Monte
    Carlo sample measured its drift on another brick."""
    from drydem.masonry import designs
    from drydem.masonry.walls import load_wall
    from drydem.masonry.imperfections import Imperfections, imperfect_model

    wall = load_wall(designs.find(name))
    perfect = wall.model()
    expected = perfect.block_name[monitored_block(perfect)]
    for seed in range(20):
        imperfect = imperfect_model(wall, Imperfections(height_sd_mm=0.1, flatness_sd_mm=0.05), seed)
        assert imperfect.block_name[monitored_block(imperfect)] == expected, seed


class Killed(Exception):
    """Stands for the run being killed."""


def test_an_interrupted_run_resumes_to_the_same_result(tmp_path):
    model, settings = slender([0.01] * 4, kn=1e8), TiltSettings(increment_deg=STEP)
    whole = tilt_analysis(model, settings)
    checkpoint = tmp_path / "checkpoint.npz"

    def kill_at_8_deg(record):
        if record.tilt_deg >= 8.0:
            raise Killed

    with pytest.raises(Killed):
        tilt_analysis(model, settings, checkpoint=checkpoint, checkpoint_every_s=0.0, on_record=kill_at_8_deg)
    resumed = tilt_analysis(model, settings, checkpoint=checkpoint, resume=True)
    assert resumed.collapse_angle_deg == whole.collapse_angle_deg
    assert resumed.cycles == whole.cycles  # the shear history came back too: the same path
    np.testing.assert_array_equal([r.ux_m for r in resumed.records], [r.ux_m for r in whole.records])


def test_a_resumed_run_s_runtime_counts_the_time_up_to_its_checkpoint(tmp_path):
    """Found by a hunt: interrupted after 19 s and resumed, a run reported 11.7 s, its resumed
    part alone. Each equilibrium before the interruption takes 50 ms more here (a slow
    callback): the runtime of the resumed run holds the time of those in its checkpoint."""
    model, settings = slender([0.01] * 4, kn=1e8), TiltSettings(increment_deg=STEP)
    checkpoint, pause_s, kept = tmp_path / "checkpoint.npz", 0.05, []

    def slow_then_killed_at_8_deg(record):
        if record.tilt_deg >= 8.0:
            raise Killed
        time.sleep(pause_s)
        kept.append(record)

    with pytest.raises(Killed):
        tilt_analysis(model, settings, checkpoint=checkpoint, checkpoint_every_s=0.0, on_record=slow_then_killed_at_8_deg)
    resumed = tilt_analysis(model, settings, checkpoint=checkpoint, resume=True)
    assert resumed.runtime_s >= pause_s * len(kept)


def test_an_adaptive_run_whose_first_step_passes_90_deg_resumes_from_its_checkpoint(tmp_path):
    """The first checkpoint is written at the stage 1 equilibrium with the first adaptive step
    next, 16 increments: 96 deg for 6 deg ones; it was refused as out of (0, 90) on resume."""
    model = stack_model([0.0055], joint=dd.JointMaterial(kn=1e8, ks=1e8, friction=0.5))
    settings = TiltSettings(increment_deg=6.0, adaptive=True)
    checkpoint = tmp_path / "checkpoint.npz"
    first = tilt_analysis(model, settings, checkpoint=checkpoint, checkpoint_every_s=1e9)  # only the stage 1 one is written
    again = tilt_analysis(model, settings, checkpoint=checkpoint, resume=True)
    assert again.collapse_angle_deg == first.collapse_angle_deg and again.ended_by == first.ended_by


def test_a_checkpoint_of_another_protocol_is_refused(tmp_path):
    model = slender([0.04], kn=1e8)
    checkpoint = tmp_path / "checkpoint.npz"
    tilt_analysis(model, TiltSettings(increment_deg=STEP, max_angle_deg=2.0), checkpoint=checkpoint)
    with pytest.raises(dd.ModelError, match="another model or protocol"):
        tilt_analysis(model, TiltSettings(increment_deg=1.0), checkpoint=checkpoint, resume=True)


def test_one_point_across_an_in_plane_wall_gives_the_same_collapse_as_four():
    # every block fixed in y, symmetric across the width: contact forces are uniform across it,
    # so 1 point on the mid-plane integrates them as exactly as 4 (trapezoid rule), at a quarter
    # of the cost
    model = slender([0.01] * 4, kn=1e8).replace(supports=dd.Supports(fix_y=True))
    four = model.replace(contacts=dd.ContactSettings(points_per_length=4, points_across=4))
    one = tilt_analysis(model, TiltSettings(increment_deg=STEP))
    both = tilt_analysis(four, TiltSettings(increment_deg=STEP))
    assert dd.Simulation(model).contacts.count * 4 == dd.Simulation(four).contacts.count
    assert one.collapse_angle_deg == both.collapse_angle_deg
    # equal to the equilibrium tolerance (the timestep bound differs, so the damped paths do):
    # measured 5e-4
    np.testing.assert_allclose([r.ux_m for r in one.records], [r.ux_m for r in both.records], rtol=2e-3, atol=1e-9)


def test_a_coarse_adaptive_trial_is_given_up_once_its_motion_is_not_elastic():
    # the last two equilibria moved 1 mm per degree: a 1.6 deg trial expects 1.6 mm, and is
    # abandoned past 4 x 1.6 mm (TiltSettings.trial_growth), or at once if a block falls out
    from drydem.analysis.tilt import Record, trial_limit

    class Run:
        lost: list = []
        ux = 0.010

        def displacement(self):
            return self.ux, 0.0

    run = Run()
    records = [Record(8.0, 0.008, 0.0, 0.0, 100), Record(10.0, 0.010, 0.0, 0.0, 100)]
    give_up = trial_limit(run, records, 1.6, TiltSettings(adaptive=True))
    run.ux = 0.010 + 6.3e-3
    assert not give_up()
    run.ux = 0.010 + 6.5e-3
    assert give_up()
    run.ux, run.lost = 0.011, [("c3b1", 11.6)]
    assert give_up()


def test_a_step_without_equilibrium_nor_collapse_gives_no_collapse_angle():
    # 200 cycles a step: enough for the elastic steps, not for the slide past atan(0.5) = 26.6
    # deg to reach the stop displacement: no equilibrium, no collapse, so no collapse angle
    model = stack_model([BRICK[2]] * 3, joint=dd.JointMaterial(kn=1e8, ks=1e8, friction=0.5), solver=dd.SolverSettings(max_cycles=200))
    result = tilt_analysis(model, TiltSettings(increment_deg=5.0))
    assert result.ended_by == "no equilibrium within max_cycles" and result.stable_under_gravity
    assert result.last_equilibrium_deg == 25.0 and result.collapse_angle_deg is None and result.load_multiplier is None


#: cycles a step made to diverge runs before it does (:func:`diverging_past`)
CYCLES_BEFORE_DIVERGING = 50


def diverging_past(monkeypatch, angle_deg):
    """Make every cycling at a tilt above ``angle_deg`` blow up after CYCLES_BEFORE_DIVERGING
    cycles, its state ruined (NaN speeds) and DivergenceError raised, as the step an octagonal
    prism toppled off its slab's edge in did at kn = 1e12 Pa/m (a hunt's)."""
    real = dd.Simulation.cycle_to_equilibrium

    def cycle_to_equilibrium(self, *args, gravity=(0.0, 0.0, -dd.G), **kwargs):
        if math.degrees(math.atan2(abs(gravity[0]), -gravity[2])) > angle_deg:
            self.cycle(CYCLES_BEFORE_DIVERGING, gravity=gravity)
            self.state.velocity[:] = np.nan
            raise dd.DivergenceError("the integration diverged (made to, by the test)")
        return real(self, *args, gravity=gravity, **kwargs)

    monkeypatch.setattr(dd.Simulation, "cycle_to_equilibrium", cycle_to_equilibrium)


@pytest.mark.parametrize("refinements", [0, 2])
def test_a_step_that_diverges_ends_the_tilt_without_a_verdict_and_keeps_its_equilibria(monkeypatch, refinements):
    # a block sliding at atan 0.5 = 26.6 deg, made to diverge above 2.5 deg: no collapse, the
    # equilibria up to 2 deg reported (the error stopped the analysis, and they were lost); an
    # adaptive coarse step of 4 deg that diverges is undone and halved, as one that fails
    diverging_past(monkeypatch, 2.5)
    model = stack_model([0.0055], joint=dd.JointMaterial(kn=1e8, ks=1e8, friction=0.5))
    result = tilt_analysis(model, TiltSettings(increment_deg=1.0, adaptive=refinements > 0, refinements=refinements))
    assert result.ended_by == "integration diverged" and result.stable_under_gravity
    assert result.last_equilibrium_deg == 2.0 and result.collapse_angle_deg is None
    assert [r.tilt_deg for r in result.records][-1] == 2.0
    # the diverged cycles counted; the state reported is the last equilibrium's, not the ruined one
    assert result.cycles >= sum(r.cycles for r in result.records) + CYCLES_BEFORE_DIVERGING * (1 + (refinements > 0))
    assert np.isfinite(result.final_state.velocity).all()
    assert np.array_equal(result.final_state.position, result.collapse_state.position)


# --- the table turned about x (TiltSettings.tilt_axis): the lateral load along y -----------------


@pytest.mark.parametrize("axis", ["y", "x"])
@pytest.mark.parametrize("loading", ["tilt", "multiplier"])
def test_single_block_slides_at_atan_mu_about_either_axis(axis, loading):
    model = stack_model([0.0055], joint=dd.JointMaterial(kn=1e8, ks=1e8, friction=0.5))
    settings = TiltSettings(increment_deg=STEP, tilt_axis=axis, loading=loading)
    result = tilt_analysis(model, settings)
    assert within_one_step_below(result.collapse_angle_deg, math.degrees(math.atan(0.5)))
    # it slid along the load direction only, off the end of its base (which reaches two block
    # widths past it), and the monitored displacement is measured along it
    moved = result.final_state.position[1] - model.block_centroid[1]
    along, across = (0, 1) if axis == "y" else (1, 0)
    assert moved[along] > 2 * BRICK[along] and abs(moved[across]) < 1e-3 * moved[along]
    assert all(r.ux_m >= -1e-9 for r in result.records) and result.records[-1].ux_m > 0


def test_a_block_topples_at_atan_of_its_width_along_the_load_over_its_height():
    """A block 10 mm along x, 16 mm along y and 64 mm tall (mu = 1: it cannot slide first)
    topples when the weight's line of action passes its downhill edge: tan(theta) = b / h with
    b its width along the load, 10 mm (8.88 deg) tilting about y, 16 mm (14.04 deg) about x."""
    model = stack_model([0.064], size_xy=(0.01, 0.016), joint=dd.JointMaterial(kn=1e10, ks=1e10, friction=1.0))
    for axis, b in (("y", 0.01), ("x", 0.016)):
        result = tilt_analysis(model, TiltSettings(increment_deg=STEP, tilt_axis=axis))
        assert within_one_step_below(result.collapse_angle_deg, math.degrees(math.atan(b / 0.064))), axis


@pytest.mark.parametrize("axis", ["y", "x"])
def test_a_block_turned_45_deg_topples_about_its_corner(axis):
    """A square block b = 10 mm wide, h = 40 mm tall, turned 45 deg about z: its footprint is a
    diamond with a corner pointing along x and along y, at the half-diagonal b / sqrt(2) from
    the centre. The tilt's lateral load g sin(theta) along x (or y) and the normal g cos(theta)
    put the weight's line of action through the base at (h / 2) tan(theta) from the point under
    the centroid; it reaches the downhill corner, about which the block topples (mu = 1: it
    cannot slide first), when (h / 2) tan(theta) = b / sqrt(2), i.e. tan(theta) = b' / h with
    b' = 2 b / sqrt(2) = sqrt(2) b, the block's diagonal: its width along the load. Here
    atan(sqrt(2) / 4) = 19.47 deg, against atan(1 / 4) = 14.04 deg unturned; the same about
    either axis (the diamond is symmetric). Toppled, the block can come to rest on its side on
    the wide base, a new equilibrium: the run ends once its centroid has moved 10 mm (a quarter of
    its height; it moves microns while it stands)."""
    model = stack_model([0.04], size_xy=(0.01, 0.01), turn_deg=45.0, joint=dd.JointMaterial(kn=1e10, ks=1e10, friction=1.0))
    result = tilt_analysis(model, TiltSettings(increment_deg=STEP, tilt_axis=axis, stop_displacement_m=0.01))
    assert within_one_step_below(result.collapse_angle_deg, math.degrees(math.atan(math.sqrt(2.0) * 0.01 / 0.04)))


def test_a_multiplier_protocol_ends_where_its_load_is_the_largest_acceleration_a_simulation_takes():
    """g (tan theta, -1), of magnitude g / cos theta, reaches MAX_ACCELERATION_M_S2 at
    acos(9.81 / 1000) = 89.4379 deg: a max_angle beyond it is refused up front, and the gravity
    at any angle within it is one a Simulation cycles with (tilting the gravity is bounded anyway)."""
    from drydem.analysis.tilt.settings import STEEPEST_MULTIPLIER_DEG

    model = stack_model([0.0055], joint=dd.JointMaterial(kn=1e8, ks=1e8, friction=0.5))
    steepest = math.floor(STEEPEST_MULTIPLIER_DEG * 1e9) / 1e9
    gravity = TiltSettings(loading="multiplier", max_angle_deg=steepest).gravity(steepest)
    assert dd.Simulation(model).cycle(1, gravity=gravity).cycles == 1
    with pytest.raises(dd.ModelError, match=rf"max_angle_deg = {steepest + 1e-6!r}: with loading = 'multiplier' at most 89.4379"):
        TiltSettings(loading="multiplier", max_angle_deg=steepest + 1e-6)
    assert TiltSettings(max_angle_deg=89.9).max_angle_deg == 89.9


def test_tilt_axis_sets_the_gravity_direction_and_is_checked():
    t = math.radians(30.0)
    np.testing.assert_allclose(TiltSettings(tilt_axis="x").gravity(30.0), dd.G * np.array([0.0, math.sin(t), -math.cos(t)]))
    np.testing.assert_allclose(TiltSettings(tilt_axis="x", loading="multiplier").gravity(30.0),
                               dd.G * np.array([0.0, math.tan(t), -1.0]))
    np.testing.assert_array_equal(TiltSettings().gravity(30.0), dd.G * np.array([math.sin(t), 0.0, -math.cos(t)]))
    assert TiltSettings().load_direction == 0 and TiltSettings(tilt_axis="x").load_direction == 1
    with pytest.raises(dd.ModelError, match=r"tilt_axis = 'z': must be one of \('y', 'x'\)"):
        TiltSettings(tilt_axis="z")


def test_an_in_plane_model_is_not_tilted_about_x():
    model = stack_model([0.0055], supports=dd.Supports(fix_y=True))
    assert model.in_plane
    with pytest.raises(dd.ModelError, match="out of its plane, but it is an in-plane model"):
        tilt_analysis(model, TiltSettings(increment_deg=STEP, tilt_axis="x"))


def test_a_checkpoint_of_another_tilt_axis_is_refused(tmp_path):
    model = slender([0.04], kn=1e8)
    checkpoint = tmp_path / "checkpoint.npz"
    tilt_analysis(model, TiltSettings(increment_deg=STEP, max_angle_deg=1.0), checkpoint=checkpoint)
    with pytest.raises(dd.ModelError, match="tilt setting tilt_axis: 'y' in the checkpoint, 'x' now"):
        tilt_analysis(model, TiltSettings(increment_deg=STEP, max_angle_deg=1.0, tilt_axis="x"), checkpoint=checkpoint, resume=True)


def test_a_blank_monitor_name_is_refused_when_the_settings_are_made():
    from drydem.analysis.tilt import TiltSettings

    with pytest.raises(dd.ModelError, match=r"tilt setting monitor = '': must be a block name"):
        TiltSettings(monitor="")  # found by a hunt: refused only later, as "no block named ''"


def test_the_drift_is_the_displacement_since_the_wall_stood_under_its_own_weight():
    """A tilting table's transducers are zeroed once the wall stands, and 3DEC's displacements
    reset after the initial equilibrium: the drift (and the EC8 angles read from it) is the
    displacement the tilt caused. WD1 (kn 3e7) settles ~0.1 mm back under its own weight, its
    pushover's first row, which the drift was measured past (found by a hunt: an imperfect
    pier that settled 0.66 mm sideways reached every drift limit at 0 deg)."""
    from drydem.io.target import load_target

    result = tilt_analysis(load_target("WD1").model, TiltSettings(increment_deg=2.0, adaptive=False))
    tilt, ux = np.array([[r.tilt_deg, r.ux_m] for r in result.records]).T
    assert abs(ux[0]) > 5e-5  # the settlement under its own weight moved the monitored block sideways
    since = (ux - ux[0]) / result.wall_height_m
    assert result.records[0].drift == 0.0
    np.testing.assert_allclose([r.drift for r in result.records], since, rtol=0.0, atol=1e-15)
    assert result.drift_limit_angles_deg == drift_limit_angles(tilt, since)
