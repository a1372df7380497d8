"""Limit analysis: closed forms, a small wall by hand, LA-NA <= LA-A, and the DEM with stiff joints."""

import math
import re

import numpy as np
import pytest

import drydem as dd
from drydem.analysis import limit as la
from drydem.analysis.limit import LimitAnalysisError, LimitSettings, limit_analysis
from drydem.analysis.tilt import TiltSettings, tilt_analysis
from drydem.io.target import load_target
from conftest import layout_blocks, prism_model, stack_model

NA = LimitSettings(non_associative=True)
#: relative accuracy of lambda: in-plane models, HiGHS's vertex (crossover), ~1e-12; 3D models, Clarabel's interior
#: point on the exact cones, which stops at a relative duality gap of 1e-8 (measured: 0.3 + 4.8e-10, 0.7 - 3e-8)
IN_PLANE, IN_3D = 1e-9, 1e-7


def rel(model: dd.Model) -> float:
    return IN_PLANE if model.in_plane else IN_3D


def in_plane_wall(courses: str, mu: float, kn: float = 1e10) -> dd.Model:
    return dd.build_model(layout_blocks(courses), density=1800.0, joint=dd.JointMaterial(kn=kn, ks=kn, friction=mu),
                          supports=dd.Supports(fix_y=True))


def slender(heights, **kw):
    """10 mm wide blocks stacked 40 mm high in all, mu = 1: toppling at tan = 1/4, not sliding."""
    return stack_model(heights, size_xy=(0.01, 0.012), joint=dd.JointMaterial(kn=1e10, ks=1e10, friction=1.0), **kw)


@pytest.mark.parametrize("mu", [0.3, 0.5, 0.8])
@pytest.mark.parametrize("supports", [dd.Supports(), dd.Supports(fix_y=True)], ids=["3D", "in-plane"])
def test_a_squat_block_slides_at_lambda_mu(mu, supports):
    # a brick 25 mm long, 5.5 mm high: rocking needs lambda = 25 / 5.5 = 4.5; sliding lambda = mu
    model = stack_model([0.0055], joint=dd.JointMaterial(friction=mu), supports=supports)
    for settings in (LimitSettings(), NA):
        result = limit_analysis(model, settings)
        assert result.load_multiplier == pytest.approx(mu, rel=rel(model))
        assert result.collapse_angle_deg == pytest.approx(math.degrees(math.atan(mu)))
    # the associative mechanism dilates: it slides up at the friction angle (normality)
    v = limit_analysis(model).velocity[1]
    assert v[2] / v[0] == pytest.approx(mu, rel=1e-6)


@pytest.mark.parametrize("sides", [6, 40])
def test_a_polygonal_prism_topples_about_its_outermost_corner_at_lambda_r_over_half_its_height(sides):
    # the corner along the live load is the pivot: lambda = 0.02 / 0.06 (the contact grid before
    # the lumped one gave 8.04 deg instead of atan(1/3) = 18.43 for 40 sides)
    model = prism_model(sides, 0.02, 0.12)
    for settings in (LimitSettings(), NA):
        assert limit_analysis(model, settings).load_multiplier == pytest.approx(1 / 3, rel=IN_3D)


@pytest.mark.parametrize("heights", [[0.04], [0.01] * 4], ids=["one block", "stack of four"])
def test_a_slender_block_and_a_stack_topple_at_lambda_b_over_h(heights):
    # b / h = 10 / 40 for one block, and for four stacked (one rigid body of the full height)
    for supports in (dd.Supports(), dd.Supports(fix_y=True)):
        model = slender(heights, supports=supports)
        result = limit_analysis(model)
        assert result.load_multiplier == pytest.approx(0.25, rel=rel(model))
        # the mechanism: every block turns about y at the same rate, none slides
        turn = result.angular_velocity[1:, 1]
        assert np.allclose(turn, turn[0]) and abs(turn[0]) > 0


def test_a_square_balanced_on_its_corner_has_a_multiplier_of_plus_zero():
    """A 10 mm square prism turned 45 deg on its corner: its weight acts through the corner, the least
    push topples it, lambda = 0 (it solved to -0.0, printed as -0.0000, a collapse angle of -0.00 deg)."""
    r = 0.01 / math.sqrt(2.0)
    section = [(0.05, 0.0), (0.05 - r, r), (0.05 + r, r), (0.05, 2 * r)]
    diamond = dd.convex_hull([[x, y, z] for x, z in section for y in (-0.006, 0.006)])
    base = dd.box([-0.05, -0.006, -0.01], [0.25, 0.006, 0.0])
    model = dd.build_model([dd.Block(name="base", shape=base, fixed=True), dd.Block(name="diamond", shape=diamond)], density=1800.0,
                           supports=dd.Supports(fix_y=True))
    result = limit_analysis(model)
    assert result.load_multiplier == 0.0 and math.copysign(1.0, result.load_multiplier) == 1.0


def test_a_small_running_bond_wall_solved_by_hand():
    """A wall 2 bricks long (B = 50 mm) and 6 courses high (H = 33 mm) in running bond.

    mu = 0.5: rocking of the whole wall about its downhill toe needs the overturning moment
    lambda W H/2 to reach the restoring W B/2, lambda = B/H = 1.515; sliding of any course
    over the one below (or of the wall on the base) needs lambda W_above = mu W_above,
    lambda = mu = 0.5: it slides. mu = 2 > B/H: it rocks as one body, lambda = 50/33.
    (Partial mechanisms would have to slide along the vertical joints, against friction
    and the horizontal thrust, or tip a corner piece whose own b/h = 12.5/5.5 = 2.27 > 50/33.)
    """
    courses = "bBb\nBB\n" * 3
    assert limit_analysis(in_plane_wall(courses, 0.5)).load_multiplier == pytest.approx(0.5, rel=1e-9)
    rocking = limit_analysis(in_plane_wall(courses, 2.0))
    assert rocking.load_multiplier == pytest.approx(50 / 33, rel=1e-9)
    turn = rocking.angular_velocity[1:, 1]
    assert np.allclose(turn, turn[0])


CASES = {
    "sliding block": lambda: stack_model([0.0055], joint=dd.JointMaterial(friction=0.5)),
    "toppling stack": lambda: slender([0.01] * 4),
    "2 x 6 wall, mu 0.5": lambda: in_plane_wall("bBb\nBB\n" * 3, 0.5),
    "2 x 6 wall, mu 2": lambda: in_plane_wall("bBb\nBB\n" * 3, 2.0),
    "WD1": lambda: load_target("WD1").model,
    "WD6": lambda: load_target("WD6").model,
    # cohesion and tension: points in tension keep less than c A of shear (c + mu N, N < 0); LA-NA
    # gave 11.16 against LA-A's 10.80 here when it kept c A at every point in tension
    "sliding block, cohesion and tension": lambda: stack_model([0.0055], joint=dd.JointMaterial(friction=0.5, cohesion=1e3, tension=1e3),
                                                               supports=dd.Supports(fix_y=True)),
    "sliding block in 3D, cohesion and tension": lambda: stack_model([0.0055], joint=dd.JointMaterial(friction=0.5, cohesion=1e3,
                                                                                                     tension=1e3)),
}


@pytest.mark.parametrize("case", CASES)
def test_non_associative_never_exceeds_associative(case):
    model = CASES[case]()
    associative, non_associative = limit_analysis(model), limit_analysis(model, NA)
    assert non_associative.converged and non_associative.method == "non-associative"
    assert non_associative.load_multiplier <= associative.load_multiplier * (1 + rel(model))
    assert non_associative.history[0] == pytest.approx(associative.load_multiplier)


@pytest.mark.parametrize("supports", [dd.Supports(), dd.Supports(fix_y=True)], ids=["3D", "in-plane"])
def test_a_tension_beyond_the_coulomb_apex_adds_nothing_associative_or_not(supports):
    """|T| <= c A + mu N holds no shear at N < -c A / mu, so a tension strength counts up to c / mu
    (README, Joint law). Found by a hunt: LA-NA took the whole tension, 25 % above b / h for a
    slender block without cohesion, and never converged. Without cohesion: b / h = 0.25, the
    closed form of toppling; with it, the multiplier of t = 3 c / mu is that of t = c / mu."""
    for cohesion, tensions in ((0.0, (0.0, 1e3)), (500.0, (500.0, 1500.0))):
        joints = [dd.JointMaterial(kn=1e10, ks=1e10, friction=1.0, cohesion=cohesion, tension=t) for t in tensions]
        results = [limit_analysis(stack_model([0.04], size_xy=(0.01, 0.012), joint=joint, supports=supports), settings)
                   for joint in joints for settings in (LimitSettings(), NA)]
        assert all(result.converged for result in results)
        lams = [result.load_multiplier for result in results]
        assert lams == pytest.approx([lams[0]] * 4, rel=1e-6)
        if cohesion == 0.0:
            assert lams[0] == pytest.approx(0.25, rel=1e-6)
        else:
            assert lams[0] > 0.25 * 1.2  # the capped tension holds the heel down


def test_friction_without_dilatancy_lowers_the_capacity_of_a_competition_wall():
    # the paper's Table 2: LA-NA is below LA-A for six of the seven walls; for the WD6
    # reconstruction the piers' sliding under the lintel costs 2.7 deg (measured: 14.5 -> 11.8)
    associative, non_associative = limit_analysis(load_target("WD6").model), limit_analysis(load_target("WD6").model, NA)
    assert non_associative.collapse_angle_deg < associative.collapse_angle_deg - 1.0


@pytest.mark.slow
def test_stiff_dem_lands_near_limit_analysis():
    # kn = 1e10: the DEM is close to rigid. Where friction governs (the 2 x 6 wall sliding, mu
    # 0.5) it lands within 1 deg of LA-NA; where the mechanism is pure rocking (a pier of 8
    # bricks, 25 x 44 mm, mu 0.8), near LA-A = atan(25/44) = 29.6 deg.
    sliding = in_plane_wall("bBb\nBB\n" * 3, 0.5)
    dem = tilt_analysis(sliding, TiltSettings(increment_deg=0.1, adaptive=True)).collapse_angle_deg
    assert abs(dem - limit_analysis(sliding, NA).collapse_angle_deg) < 1.0
    pier = stack_model([0.0055] * 8, joint=dd.JointMaterial(kn=1e10, ks=1e10, friction=0.8), supports=dd.Supports(fix_y=True))
    dem = tilt_analysis(pier, TiltSettings(increment_deg=0.1, adaptive=True)).collapse_angle_deg
    associative = limit_analysis(pier).collapse_angle_deg
    assert associative == pytest.approx(math.degrees(math.atan(25 / 44)))
    assert associative - 0.5 < dem <= associative


def blocks_of(model: dd.Model) -> list[dd.Block]:
    """The blocks of ``model`` again, as built."""
    return [dd.Block(name=n, shape=s, fixed=bool(f.all())) for n, s, f in zip(model.block_name, model.block_shape, model.block_fixed)]


def test_bad_input_is_a_clear_error():
    floating = dd.build_model(
        [dd.Block(name="base", shape=dd.box([0, 0, -0.01], [0.1, 0.012, 0]), fixed=True),
         dd.Block(name="cloud", shape=dd.box([0, 0, 0.05], [0.025, 0.012, 0.0555]))], density=1800.0)
    with pytest.raises(LimitAnalysisError, match=r"block\(s\) 'cloud' touch no other block: nothing holds them up"):
        limit_analysis(floating)
    # beside a brick resting on the base, the cloud made the problem infeasible, named nowhere
    beside = dd.build_model([*blocks_of(floating), dd.Block(name="brick", shape=dd.box([0.05, 0, 0], [0.075, 0.012, 0.0055]))],
                            density=1800.0)
    with pytest.raises(LimitAnalysisError, match=r"block\(s\) 'cloud' touch no other block"):
        limit_analysis(beside)
    # a block whose centroid is beyond the edge of its support: no multiplier holds it
    overhang = dd.build_model(
        [dd.Block(name="base", shape=dd.box([-0.1, 0, -0.01], [0.0, 0.012, 0]), fixed=True),
         dd.Block(name="overhang", shape=dd.box([-0.01, 0, 0], [0.03, 0.012, 0.0055]))], density=1800.0)
    with pytest.raises(LimitAnalysisError, match="unstable under its dead load alone: no contact forces hold"):
        limit_analysis(overhang)
    # with mu = 5 a push of lambda = -(10 mm) / (2.75 mm) = -3.64 towards the base would hold it
    rough = overhang.replace(joint=dd.JointMaterial(friction=5.0))
    with pytest.raises(LimitAnalysisError, match=r"unstable under its dead load alone: lambda = -3.636 < 0"):
        limit_analysis(rough)


def test_an_unconverged_non_associative_run_says_so():
    result = limit_analysis(load_target("WD6").model, LimitSettings(non_associative=True, max_iterations=2))
    assert not result.converged and result.iterations == 3 and len(result.history) == 3


def test_progress_names_each_stage_as_it_starts():
    stages = []
    result = limit_analysis(load_target("WD6").model, LimitSettings(non_associative=True, max_iterations=2), on_progress=stages.append)
    assert [stage.split(" (")[0] for stage in stages] == [
        "finding the contacts of 166 blocks", "assembling the equilibrium matrix", "solving the associative LP with HiGHS",
        "non-associative iteration 1 of at most 2: solving the LP with HiGHS", "non-associative iteration 2 of at most 2: solving the LP with HiGHS",
    ]
    assert stages[-1].endswith(f"(lambda {result.history[1]:.4f} so far)")


@pytest.mark.parametrize("setting, value, rule", [
    ("relaxation", 0.0, "limit setting relaxation = 0.0: must be a number in (0, 1]"),
    ("relaxation", 1.5, "limit setting relaxation = 1.5: must be a number in (0, 1]"),
    ("max_iterations", 0, "limit setting max_iterations = 0: must be an integer in [1, 1e+04]"),
    ("max_iterations", 2.5, "limit setting max_iterations = 2.5: must be an integer in [1, 1e+04]"),
    ("max_iterations", True, "limit setting max_iterations = True: must be an integer in [1, 1e+04]"),
    ("tolerance", -1e-4, "limit setting tolerance = -0.0001: must be a number in (0, 1)"),
    ("tolerance", float("nan"), "limit setting tolerance = nan: must be a number in (0, 1)"),
    ("relaxation", True, "limit setting relaxation = True: must be a number in (0, 1]"),
    ("non_associative", 1, "limit setting non_associative = 1: must be true or false"),
    ("non_associative", "yes", "limit setting non_associative = 'yes': must be true or false"),
])
def test_a_bad_limit_setting_is_a_model_error_naming_it_and_its_range(setting, value, rule):
    with pytest.raises(dd.ModelError) as refused:
        LimitSettings(**{setting: value})
    assert str(refused.value) == rule


def test_every_bad_limit_setting_is_named_at_once():
    with pytest.raises(dd.ModelError, match=r"max_iterations = 0: .*; limit setting tolerance = 0: "):
        LimitSettings(max_iterations=0, tolerance=0)


@pytest.mark.parametrize("mu", [0.3, 0.8])
def test_along_y_a_squat_block_slides_at_mu_and_a_slender_one_topples_at_b_y_over_h(mu):
    # tilt axis x: the live load along y. A brick 25 x 12 mm, 5.5 mm high: toppling about its long
    # edge needs lambda = 12 / 5.5 = 2.18 > mu: it slides, lambda = mu
    squat = stack_model([0.0055], joint=dd.JointMaterial(friction=mu))
    assert limit_analysis(squat, LimitSettings(tilt_axis="x")).load_multiplier == pytest.approx(mu, rel=IN_3D)
    # 10 x 12 mm, 40 mm high, mu = 1: along x b/h = 10/40, along y 12/40 (one block, or four stacked)
    for heights in ([0.04], [0.01] * 4):
        model = slender(heights)
        assert limit_analysis(model).load_multiplier == pytest.approx(10 / 40, rel=IN_3D)
        along_y = limit_analysis(model, LimitSettings(tilt_axis="x"))
        assert along_y.load_multiplier == pytest.approx(12 / 40, rel=IN_3D)
        turn = along_y.angular_velocity[1:, 0]  # every block turns about x at the same rate
        assert np.allclose(turn, turn[0]) and abs(turn[0]) > 0
        assert np.allclose(along_y.angular_velocity[1:, 1:], 0.0, atol=1e-9)
        assert limit_analysis(model, LimitSettings(tilt_axis="x", non_associative=True)).load_multiplier <= 12 / 40 * (1 + IN_3D)


def test_a_load_along_y_on_an_in_plane_model_is_a_clear_error():
    with pytest.raises(LimitAnalysisError, match="no block may move along y, the live load's direction .tilt axis x.: \\[supports\\] fix_y holds every block in y"):
        limit_analysis(in_plane_wall("bBb\nBB\n", 0.5), LimitSettings(tilt_axis="x"))


@pytest.mark.parametrize("value", ["z", "X", 1, None])
def test_a_bad_tilt_axis_is_a_model_error(value):
    with pytest.raises(dd.ModelError, match=r"limit setting tilt_axis = .*: must be one of \('y', 'x'\)"):
        LimitSettings(tilt_axis=value)


def test_the_limit_command_takes_a_tilt_axis(tmp_path):
    import json

    from click.testing import CliRunner

    from drydem.cli import main
    from drydem.io.model_file import save_model

    path = tmp_path / "pier.toml"
    save_model(slender([0.04]), path)
    result = CliRunner().invoke(main, ["limit", str(path), "--tilt-axis", "x", "--out", str(tmp_path / "la")])
    assert result.exit_code == 0, result.output
    assert "LA-A load multiplier (along y) 0.3000" in result.output
    summary = json.loads((tmp_path / "la" / "summary.json").read_text())
    assert summary["analysis"]["tilt_axis"] == "x" and summary["load_multiplier"] == pytest.approx(0.3, rel=IN_3D)
    # the stages, with the LP's size, on stderr
    assert "assembling the equilibrium matrix" in result.stderr and " rows x " in result.stderr
    refused = CliRunner().invoke(main, ["limit", "WD2", "--tilt-axis", "x", "--out", str(tmp_path / "wd2")])
    assert refused.exit_code != 0 and "no block may move along y, the live load's direction (tilt axis x): [supports] fix_y " \
        "holds every block in y" in refused.output
    held_x = slender([0.04], supports=dd.Supports(fix_x=True, fix_y=True))  # found by a hunt: it said "held in y"
    with pytest.raises(dd.DrydemError, match=re.escape("no block may move along x, the live load's direction (tilt axis y): "
                                                       "[supports] fix_x holds every block in x")):
        limit_analysis(held_x)
    assert CliRunner().invoke(main, ["limit", "WD2", "--tilt-axis", "z"]).exit_code == 2


def block_on_a_slope(slope_deg: float, mu: float) -> dd.Model:
    """A squat block (25 x 25 x 5 mm) on a fixed slab inclined ``slope_deg`` about x (rising along y)."""
    from scipy.spatial.transform import Rotation

    from conftest import box_vertices

    tilt = Rotation.from_euler("x", slope_deg, degrees=True).as_matrix().T
    base = dd.convex_hull(box_vertices([-0.05, -0.05, -0.01], [0.075, 0.075, 0.0]) @ tilt)
    block = dd.convex_hull(box_vertices([0.0, 0.0, 0.0], [0.025, 0.025, 0.005]) @ tilt)
    return dd.build_model([dd.Block(name="slope", shape=base, fixed=True), dd.Block(name="block", shape=block)],
                          density=1800.0, joint=dd.JointMaterial(kn=1e10, ks=1e10, friction=mu))


def test_the_exact_cone_finds_the_closed_form_of_a_block_sliding_across_a_slope(monkeypatch):
    # On a slope alpha (normal (0, -sin, cos)), the load lambda W along x is in the contact plane and
    # the friction must also hold the down-slope weight W sin alpha: the shear (lambda, sin alpha) W
    # reaches the cone mu W cos alpha at lambda = sqrt(mu^2 cos^2 - sin^2) (the block is too squat to
    # rock). The shear points between two vertices of the 16-sided pyramid (at 27 deg from its vertex
    # along x), where the pyramid falls short of the cone: its lambda is where the line of shear
    # (., sin alpha) crosses the 16-gon of circumradius mu cos alpha, 1.6 % lower here.
    alpha, mu = math.radians(20.0), 0.8
    model = block_on_a_slope(20.0, mu)
    exact = math.sqrt((mu * math.cos(alpha)) ** 2 - math.sin(alpha) ** 2)
    cone = limit_analysis(model)
    assert cone.load_multiplier == pytest.approx(exact, rel=IN_3D)
    assert cone.status.startswith("Clarabel")
    # the mechanism: the block slides along its shear and lifts off the slope at the friction angle (normality);
    # the interior point's duals are accurate to ~1e-5 (measured 4e-5 on the direction)
    v = cone.velocity[1]
    normal = np.array([0.0, -math.sin(alpha), math.cos(alpha)])
    shear = v - (v @ normal) * normal
    assert v @ normal == pytest.approx(mu * np.linalg.norm(shear), rel=1e-4)
    upslope = np.array([0.0, math.cos(alpha), math.sin(alpha)])
    assert shear @ upslope / shear[0] == pytest.approx(-math.sin(alpha) / exact, rel=1e-4)  # along the applied shear
    # the pyramid's lambda (HiGHS), below the cone's
    angles = np.arange(17) * 2 * np.pi / 16
    corner = mu * math.cos(alpha) * np.stack([np.cos(angles), np.sin(angles)], axis=1)
    s = int(np.flatnonzero((corner[:-1, 1] <= math.sin(alpha)) & (corner[1:, 1] > math.sin(alpha)))[0])
    share = (math.sin(alpha) - corner[s, 1]) / (corner[s + 1, 1] - corner[s, 1])
    polygon = corner[s, 0] + share * (corner[s + 1, 0] - corner[s, 0])
    monkeypatch.setattr(la, "EXACT_CONE", False)
    pyramid = limit_analysis(model).load_multiplier
    assert pyramid == pytest.approx(polygon, rel=1e-9)
    assert pyramid < exact * 0.99


def running_bond_2x6(mu: float) -> dd.Model:
    """2 bricks of 0.2 x 0.1 m a course, 6 courses, the odd ones ended by half bricks, on a fixed base."""
    blocks = [dd.Block(name="base", shape=dd.box([-0.5, -0.05, -0.1], [0.9, 0.05, 0.0]), fixed=True)]
    for course in range(6):
        edges = [0.0, 0.1, 0.3, 0.4] if course % 2 else [0.0, 0.2, 0.4]
        blocks += [dd.Block(name=f"c{course}b{k}", shape=dd.box([x0, -0.05, 0.1 * course], [x1, 0.05, 0.1 * (course + 1)]))
                   for k, (x0, x1) in enumerate(zip(edges[:-1], edges[1:]))]
    return dd.build_model(blocks, density=2000.0, joint=dd.JointMaterial(kn=1e10, ks=1e10, friction=mu),
                          supports=dd.Supports(fix_y=True))


def test_non_associative_iterates_above_the_associative_multiplier_are_passed_to_the_rigid_mechanism():
    """Found by a hunt: with mu = 1.0 two LA-NA iterates gave lambda 0.6667, above LA-A's
    0.6522 (impossible: friction without dilatancy carries no more than with it), and the scheme
    stopped there. It goes on to the rigid mechanism's multiplier: the upper courses but the
    left end turn about the top right corner P = (0.4, 0.1) of the first course's right brick,
    their head joints sliding at no normal force (free without dilatancy), whatever mu; by
    virtual work lambda = sum W (x_P - x) / sum W (z - z_P) over the turning bricks = 0.5349
    (the DEM with kn = 1e10 collapses at 28.1 deg = atan 0.534, measured by the hunt)."""
    model = running_bond_2x6(1.0)
    index = [model.block_name.index(name) for name in ("c1b2", "c2b1", "c3b1", "c3b2", "c4b0", "c4b1", "c5b0", "c5b1", "c5b2")]
    weight, centroid = model.block_mass[index], model.block_centroid[index]
    mechanism = float(np.sum(weight * (0.4 - centroid[:, 0])) / np.sum(weight * (centroid[:, 2] - 0.1)))
    assert mechanism == pytest.approx(0.023 / 0.043, rel=1e-12)
    associative, non_associative = limit_analysis(model), limit_analysis(model, NA)
    assert max(non_associative.history) > associative.load_multiplier  # the iterates the scheme stopped on
    # the scheme stops once lambda changes by less than 1e-4 (relative): it approaches by halves (the relaxation 0.5)
    assert non_associative.converged and non_associative.load_multiplier == pytest.approx(mechanism, rel=2 * NA.tolerance)
