"""Limit analysis at scale: the LP in generator form (drydem.analysis.limit._solve) against the
facet form it replaced (the reference below, the LP as first written), on walls and a small
building, in-plane and 3D, both load directions, with cohesion and tension; in 3D, the exact
Coulomb cone (Clarabel, drydem.analysis.limit._solve_cone) against the pyramid; the stages reported."""

import math

import numpy as np
import pytest
from scipy.optimize import linprog
from scipy.sparse import coo_matrix, hstack, identity, vstack

import drydem as dd
from drydem.analysis import limit as la
from drydem.analysis.limit import LimitSettings, limit_analysis
from drydem.masonry.brief import PAPER_BRICK
from drydem.masonry.building import BuildingSpec, building_model
from drydem.masonry.layout import parse_layout


def brick_wall(bricks: int, courses: int, mu: float, *, in_plane: bool = True, **joint) -> dd.Model:
    """``courses`` courses of running bond, ``bricks`` bricks long, of the paper's bricks, on a fixed base."""
    text = "".join(f"{bricks}B\n" if c % 2 else f"b{bricks - 1}Bb\n" for c in range(courses))
    return dd.build_model(parse_layout(text, PAPER_BRICK).blocks(PAPER_BRICK), density=1800.0,
                          joint=dd.JointMaterial(kn=1e10, ks=1e10, friction=mu, **joint),
                          supports=dd.Supports(fix_y=in_plane))


def facet_lambda(model: dd.Model, tilt_axis: str = "y") -> float:
    """The associative LP as first written: forces (N, T1[, T2]) per point, the friction pyramid by its facets
    (2 rows per point in-plane, 16 in 3D), HiGHS's default method."""
    problem = la._assemble(model, tilt_axis, lambda stage: None)
    n, k = problem.n_points, problem.n_tangents
    weight, mu = problem.weight, model.joint.friction
    cohesion, tension = model.joint.cohesion * problem.area / weight, model.joint.tension * problem.area / weight
    sides = 2 if k == 1 else la.PYRAMID_SIDES
    angles = (np.arange(sides) + (0.5 if k == 2 else 0.0)) * 2 * np.pi / sides
    facet = np.cos(np.pi / sides) if k == 2 else 1.0
    eye = identity(n, format="csr")
    blocks = []
    for angle in angles:
        shear = [eye * np.cos(angle)] + ([eye * np.sin(angle)] if k == 2 else [])
        blocks.append(hstack([eye * (-mu * facet), *shear, coo_matrix((n, 1))]))
    a_ub = vstack(blocks).tocsr()
    b_ub = np.concatenate([facet * cohesion] * sides)
    a_eq = hstack([problem.equilibrium, coo_matrix(problem.live[:, None])]).tocsr()
    cost = np.zeros(a_eq.shape[1])
    cost[-1] = -1.0
    bounds = [(-t, None) for t in tension] + [(None, None)] * (k * n + 1)
    res = linprog(cost, A_ub=a_ub, b_ub=b_ub, A_eq=a_eq, b_eq=-problem.dead, bounds=bounds, method="highs")
    assert res.status == 0, res.message
    return float(res.x[-1])


SMALL_HOUSE = BuildingSpec(length_m=0.6, width_m=0.5, storeys=1, storey_height_courses=6, brick_length_m=0.1,
                           brick_height_m=0.05, windows_per_wall=1, window_width_bricks=1, window_height_courses=2,
                           sill_courses=2, door_height_courses=0)

CASES = {
    "20 x 20 wall, mu 0.6": lambda: (brick_wall(20, 20, 0.6), "y"),
    "12 x 12 wall, mu 1.2": lambda: (brick_wall(12, 12, 1.2), "y"),
    "12 x 12 wall, mu 0.8, cohesion and tension": lambda: (brick_wall(12, 12, 0.8, cohesion=2000.0, tension=500.0), "y"),
    "8 x 8 wall in 3D, in its plane": lambda: (brick_wall(8, 8, 0.7, in_plane=False), "y"),
    "8 x 8 wall in 3D, out of its plane": lambda: (brick_wall(8, 8, 0.7, in_plane=False), "x"),
    "8 x 8 wall in 3D, out of plane, cohesion": lambda: (brick_wall(8, 8, 0.7, in_plane=False, cohesion=300.0, tension=100.0), "x"),
    "small house about y": lambda: (building_model(SMALL_HOUSE, joint=dd.JointMaterial(friction=0.7)), "y"),
    "small house about x": lambda: (building_model(SMALL_HOUSE, joint=dd.JointMaterial(friction=0.7)), "x"),
}


#: the 3D cases: the facet form's 16 rows per point make the reference slow (20-200 s on 2 shared cores)
SLOW = {case for case in CASES if "3D" in case or "house" in case}


@pytest.mark.parametrize("case", [pytest.param(case, marks=[pytest.mark.slow] if case in SLOW else []) for case in CASES])
def test_the_generator_form_finds_the_lambda_of_the_facet_form(case, monkeypatch):
    monkeypatch.setattr(la, "EXACT_CONE", False)  # in 3D: the pyramid's LP by HiGHS, as the facet form
    model, axis = CASES[case]()
    result = limit_analysis(model, LimitSettings(tilt_axis=axis))
    assert result.load_multiplier == pytest.approx(facet_lambda(model, axis), rel=1e-6, abs=1e-9)
    assert result.load_multiplier > 0
    # equilibrium of the normal forces reported: compressive where the joint has no tension
    assert result.normal_force.min() >= -model.joint.tension * 1e-3 - 1e-9 * result.normal_force.max()


def lambda_of(model: dd.Model, axis: str, *, cone: bool, scale: float = 1.0) -> float:
    """LA-A's lambda with the exact cone (Clarabel) or the 16-sided pyramid (HiGHS), friction and cohesion times ``scale``."""
    joint = dd.JointMaterial(kn=model.joint.kn, ks=model.joint.ks, friction=model.joint.friction * scale,
                             cohesion=model.joint.cohesion * scale, tension=model.joint.tension)
    previous = la.EXACT_CONE
    la.EXACT_CONE = cone
    try:
        return limit_analysis(model.replace(joint=joint), LimitSettings(tilt_axis=axis)).load_multiplier
    finally:
        la.EXACT_CONE = previous


@pytest.mark.parametrize("case", [case for case in CASES if case in SLOW])
def test_the_exact_cone_lies_between_the_pyramid_and_its_inscribed_cone(case):
    # The pyramid (16 sides, circumradius c A + mu N) holds the cone of friction mu cos(pi/16) and cohesion
    # c cos(pi/16) (its inscribed circle) and lies inside the exact cone (mu, c); lambda grows with the set
    # of admissible forces, so lambda_cone(0.981 mu, 0.981 c) <= lambda_pyramid <= lambda_cone(mu, c).
    # Measured: the 8 x 8 walls, equal (the shear along a pyramid vertex); the house, cone 0.4838 against
    # pyramid 0.4799 (about y) and 0.4523 against 0.4498 (about x): +0.8 % and +0.6 %.
    model, axis = CASES[case]()
    cone, pyramid = lambda_of(model, axis, cone=True), lambda_of(model, axis, cone=False)
    inscribed = lambda_of(model, axis, cone=True, scale=math.cos(math.pi / la.PYRAMID_SIDES))
    slack = 1e-7 * cone  # Clarabel's relative gap, 1e-8, with a margin
    assert inscribed - slack <= pyramid <= cone + slack  # all equal where friction does not govern (toppling)


def test_a_wall_of_400_bricks_slides_at_mu():
    model = brick_wall(20, 20, 0.6)
    assert model.n_blocks == 411
    result = limit_analysis(model)
    assert result.load_multiplier == pytest.approx(0.6, rel=1e-6)
    assert np.abs(result.velocity).max() > 0


def test_the_progress_callback_names_the_stages_with_the_lp_size():
    stages = []
    model = brick_wall(10, 10, 0.6)
    limit_analysis(model, LimitSettings(non_associative=True, max_iterations=3), on_progress=stages.append)
    assert stages[0] == f"finding the contacts of {model.n_blocks} blocks"
    assert stages[1].startswith("assembling the equilibrium matrix (") and "contact points" in stages[1]
    assert stages[2].startswith("solving the associative LP with HiGHS (") and " rows x " in stages[2]
    assert all(stage.startswith(f"non-associative iteration {i} of at most 3") for i, stage in enumerate(stages[3:], 1))
    assert 1 <= len(stages[3:]) <= 3
    # no callback: nothing printed, the same answer
    assert limit_analysis(model).load_multiplier == pytest.approx(0.6, rel=1e-6)
