"""Limit analysis of rigid blocks: the static (lower-bound) problem, associative and
non-associative friction; in-plane models, a linear program solved with HiGHS
(scipy.optimize.linprog); 3D models, a second-order cone program solved with Clarabel.

Associative (LA-A; Livesley 1978, Gilbert & Melbourne 1994): at every contact point k of the
model's contact polygons (their corners: 2 points per length), a normal force N_k >= -t A_k
(t the tensile strength, 0 by default) and a shear force T_k inside the Coulomb cone,
|T_k| <= c A_k + mu N_k (in-plane models: one tangent, a linear program, exact; 3D: two
tangents, the exact cone, a second-order cone per point, :data:`EXACT_CONE`; or, as before, the
16-sided pyramid inscribed in it with a vertex along the live load, whose lambda is lower by up to
2 % where the shear points between two vertices). Every free degree of freedom of every movable block is in equilibrium under its
weight W (dead load, vertical) plus lambda W horizontal along x (live load: the tilting table's
lateral component; along y with ``tilt_axis = "x"``, the table tilting about x)::

    maximise lambda  subject to  B f + lambda L = -D,  f admissible,

B the equilibrium matrix (contact forces to block forces and moments about the centroids).
Corner forces are exact for rigid blocks: any compressive stress field on a convex polygon
has its resultant inside the polygon, a convex combination of the corners. The duals of the
equilibrium rows are the blocks' virtual velocities at collapse: the mechanism. For tilting,
the collapse angle is atan(lambda).

Non-associative (LA-NA): friction without dilatancy, by the iterative scheme of Gilbert,
Casapulla & Ahmed (2006, Computers & Structures 84, 873-887): solve LA-A; then, repeatedly,
replace each point's friction limit by a fixed shear capacity max(c A_k + mu N_k, 0) taken from the previous
solution (a "pseudo-cohesion", whose flow rule has no normal dilatancy; in 3D a disc |T_k| <=
c A_k + mu N_k^prev, a second-order cone with a constant first entry, by Clarabel) and solve again,
relaxing the normal forces between iterations, until lambda settles at or below LA-A's. Its
limits, as the authors state: the non-associative problem has no unique solution and this
scheme is not guaranteed to find the lowest multiplier (nor to converge; then the last iterate
is reported with ``converged = False``). A lambda above LA-A's is no solution (friction without
dilatancy carries no more than with it: Radenkovic's theorem; its shear forces exceed Coulomb's
limit at their own normal forces), so the iteration goes on past it (found by a hunt: on a
2 x 6 running-bond wall with mu = 1.0 two iterates gave 0.6667 against LA-A's 0.6522 and the
scheme stopped, where it goes on down to 0.5349, the rigid mechanism's and the DEM's, 28.1
deg). The same wall with mu = 1.5 shows the other limit: LA-A's own forces (0.6667, the whole
wall toppling) are a fixed point of the scheme, a solution, but not the lowest: the wall
collapses at 0.5349 (its head joints slide at no normal force, for free without dilatancy).
LA-NA is an upper estimate there, 25 % above; the DEM tilt finds the lower mechanism.

The LP handed to HiGHS writes each point's admissible forces by the generators of the pyramid
(its edges) rather than its facets: the same feasible set, so the same lambda, with only the
equilibrium rows as rows (:func:`_solve`).

Why the cone and Clarabel in 3D (measured, benchmarks/bench_limit.py, 2 shared cores): the
pyramid's LP has 16 columns per point and HiGHS's interior point (with crossover) scales badly on
it: the 115-block house takes 6-15 s, SMALL (1,936 blocks, 21,716 points) did not finish in 25
minutes and LARGE (19,853 blocks, 229,192 points: 119,112 rows x 3,667,073 columns) is out of
reach. The exact cone needs 3 variables per point (N, T1, T2) and Clarabel's interior point
(QDLDL) converges in 35-45 iterations whatever the size: the house in 0.1 s, SMALL in 6 s
(76,758 rows x 65,149 columns), LARGE in ~220 s (806,688 rows x 687,577 columns, ~5.3 s per
iteration, nearly all in the sparse factorisation; the goal of 60 s is not reached). The cone's lambda is at least the pyramid's
(its set of admissible forces holds the pyramid's) and at most that of the pyramid of friction
and cohesion 1 / cos(pi / 16) = 1.0196 times larger (which holds the cone): the house, 0.4838
against the pyramid's 0.4799 (tilting about y) and 0.4523 against 0.4498 (about x); walls
sliding or toppling along a pyramid vertex, equal. The interior point has no crossover: lambda is
a lower bound below the optimum by ~2e-4 on SMALL but ~1 % on LARGE (its lambda: 0.07294 and
0.07347 at Clarabel's default gap 1e-8, with and without the redundant rows N >= 0; 0.07434 at
1e-9, :data:`CONE_SETTINGS`), and the mechanism (the duals) is accurate to ~1e-5, not a vertex's.

Units: the LP (and the cone program) is solved in units of the mean block weight and the mean block size (HiGHS can
return wrong optima on badly scaled input; bricks weigh ~0.03 N).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import clarabel
import numpy as np
from scipy.optimize import linprog
from scipy.sparse import coo_matrix, csc_matrix, hstack, vstack
from scipy.spatial.transform import Rotation

from drydem.engine.contacts import world_points
from drydem.engine.tracker import ContactTracker
from drydem.errors import DrydemError, ModelError
from drydem.model.assembly import Model
from drydem.model.parameters import (CALLBACK, FLAG, G, LOAD_DIRECTION, TILT_AXES, ContactSettings, InstanceOf, OneOf, Range, check_arguments,
                                     check_fields)
from drydem.model.geometry import MAX_COORDINATE_M
from drydem.model.state import State

#: sides of the linearised friction pyramid for 3D contacts
PYRAMID_SIDES = 16
#: HiGHS's method (scipy.optimize.linprog), chosen by measurement (benchmarks/bench_limit.py; 2 shared
#: cores, the generator form): the interior point method (IPX, with crossover to a vertex, whose
#: duals are the mechanism) is 4 to 6 times faster than the dual simplex, which needs ~10 pivots
#: per row on these degenerate LPs (a 20 x 20 brick wall: 0.3 s against 1.2 s, 10,000 pivots for
#: 1,230 rows; a 115-block house in 3D: 6-8 s against 45 s; primal simplex 12 s); presolve
#: removes nothing from the generator form (on or off: the same time, within the noise)
METHOD = "highs-ipm"
#: the non-associative iterations' method: each iteration's capacities come from the normal
#: forces of the last solution, one of many optimal ones, so the LA-NA path depends on the
#: method; the dual simplex keeps the published and earlier results (WD6: lambda 0.2085 as
#: before, 0.2174 with the interior point; WD2 0.2998 as before, 0.3022 after 74 iterations),
#: and these LPs have no pyramid (shear bounded by a fixed capacity), far fewer degenerate pivots
NA_METHOD = "highs-ds"
OPTIONS: dict = {}
#: 3D models: the exact Coulomb cone (a second-order cone per contact point, solved by Clarabel,
#: :func:`_solve_cone`); False: the 16-sided pyramid's LP by HiGHS (:func:`_solve`), as before
EXACT_CONE = True
#: Clarabel's settings, chosen by measurement (benchmarks/bench_limit.py, 2 shared cores): its
#: QDLDL factorisation is 4 times faster than the default ("auto": faer) on SMALL (5 s against
#: 22 s, the same 37 iterations; faer on 2 threads is no faster on LARGE either, ~6 s an
#: iteration against 5.3 s). Every iterate is statically admissible (equilibrium to ~1e-13,
#: forces inside the cones), so lambda is a lower bound that creeps up to the optimum in the last
#: iterations; the duality gap tolerance sets how close: on SMALL (optimum 0.176726, 300
#: iterations at 1e-12), 1e-8 (Clarabel's default) stops at 0.17653 (-1.1e-3, 35 iterations),
#: 1e-9 at 0.17669 (-2e-4, 43), 1e-10 at 0.17672 (-5e-5, 51)
CONE_SETTINGS: dict = {"direct_solve_method": "qdldl", "verbose": False, "tol_gap_abs": 1e-9, "tol_gap_rel": 1e-9}
SOLVER_NAMES = {"highs": "HiGHS's choice", "highs-ds": "dual simplex", "highs-ipm": "interior point"}
#: equilibrium coefficients below this (round-off of the cross products, in the LP's units) are
#: left out: HiGHS ignores |values| <= 1e-9 anyway, with a warning
ZERO = 1e-9
#: m, the displacement of a mechanism's fastest point that :meth:`LimitResult.mechanism_state`
#: draws: finite, either way, within the coordinates a model may have (MAX_COORDINATE_M)
MECHANISM_DISPLACEMENT = Range(-MAX_COORDINATE_M, MAX_COORDINATE_M, unit="m")


class LimitAnalysisError(DrydemError):
    """The limit analysis has no answer: unstable under dead load, no free block, solver failure."""


#: the rule of each field of :class:`LimitSettings`: at most 10,000 iterations, each a linear
#: program (minutes for a large wall); the tolerance is a relative change, a change of 100 %
#: would end the iteration after any step; a relaxation of 0 would never change the forces
LIMIT_RULES = {
    "non_associative": FLAG,
    "max_iterations": Range(1, 10_000, integer=True),
    "tolerance": Range(0.0, 1.0, low_open=True, high_open=True),
    "relaxation": Range(0.0, 1.0, low_open=True),
    "tilt_axis": OneOf(TILT_AXES),
}


@dataclass(frozen=True, kw_only=True)
class LimitSettings:
    """non_associative : run the Gilbert et al. (2006) iteration after the associative LP.
    max_iterations : of that iteration. tolerance : relative change of lambda that ends it.
    relaxation : share of the new normal forces mixed into the old ones, 0 < r <= 1.
    tilt_axis : "y" (default), the live load lambda W along x; "x", along y (:data:`TILT_AXES`).
    Checked when created (:data:`LIMIT_RULES`): ModelError naming each bad setting and its range."""

    non_associative: bool = False
    max_iterations: int = 100
    tolerance: float = 1e-4
    relaxation: float = 0.5
    tilt_axis: str = "y"

    def __post_init__(self):
        check_fields(self, LIMIT_RULES, "limit setting")


@dataclass(frozen=True)
class LimitResult:
    """load_multiplier : lambda at collapse. collapse_angle_deg : atan(lambda) in degrees.
    method : "associative" or "non-associative". status : the solver's message. iterations : the
    solves, LA-A's and the non-associative scheme's after it (1 for LA-A; at most max_iterations + 1);
    converged : of the scheme (True for LA-A); history : lambda per solve. velocity : (nb, 3) m/s and angular_velocity : (nb, 3) rad/s, the mechanism,
    normalised so that the fastest point of a block moves at 1 m/s. normal_force : (np,) N."""

    load_multiplier: float
    method: str
    status: str
    iterations: int
    converged: bool
    history: list[float]
    velocity: np.ndarray = field(repr=False)
    angular_velocity: np.ndarray = field(repr=False)
    normal_force: np.ndarray = field(repr=False)

    @property
    def collapse_angle_deg(self) -> float:
        return math.degrees(math.atan(self.load_multiplier))

    def mechanism_state(self, model: Model, displacement_m: float) -> State:
        """The blocks moved along the mechanism so that the fastest point moves ``displacement_m``
        (:data:`MECHANISM_DISPLACEMENT`; negative: the other way), ``model`` the one analysed (its
        block count checked). ModelError naming the argument that is not what it must be."""
        check_arguments("LimitResult.mechanism_state", {"model": InstanceOf(Model), "displacement_m": MECHANISM_DISPLACEMENT},
                        model=model, displacement_m=displacement_m)
        if model.n_blocks != len(self.velocity):
            raise ModelError(f"LimitResult.mechanism_state model: {model.source} has {model.n_blocks} blocks, the result is of a "
                             f"model of {len(self.velocity)}: give the model that was analysed")
        position = model.block_centroid + self.velocity * displacement_m
        quaternion = np.roll(Rotation.from_rotvec(self.angular_velocity * displacement_m).as_quat(), 1, axis=1)  # (w, x, y, z)
        return State(position, quaternion, np.zeros_like(position), np.zeros_like(position))


@dataclass(frozen=True)
class _Problem:
    """The LP in scaled units: equilibrium (rows: free dofs) over forces (N, T1[, T2] per point)."""

    equilibrium: object  # scipy sparse (n_rows, n_vars)
    live: np.ndarray  # (n_rows,)
    dead: np.ndarray  # (n_rows,)
    rows: np.ndarray  # (n_rows, 2): block, dof (0..5)
    n_points: int
    n_tangents: int
    area: np.ndarray  # (np,) m2
    weight: float  # N, force unit
    length: float  # m, length unit
    source: str  # the model's, for messages


def limit_analysis(model: Model, settings: LimitSettings = LimitSettings(), *,
                   on_progress: Callable[[str], None] | None = None) -> LimitResult:
    """LA-A (and LA-NA with ``settings.non_associative``) of ``model`` (see module docstring).

    ``on_progress(stage)`` is called as each stage starts (finding the contacts, assembling the
    equilibrium matrix, each problem solved, by HiGHS (in-plane: an LP) or Clarabel (3D: a
    second-order cone program): the associative one with the solver, its method and size, then
    each non-associative iteration with the last lambda), with a line that says it, so
    that a command can show where it is; nothing is reported without it. On a large model
    nearly all the time is in the LP (a 60 x 60 brick wall, 3,631 blocks, 2 shared cores:
    contacts and assembly ~1 s, the associative LP ~90 s; it took ~15 min in the facet form; the
    3D building SMALL, 1,936 blocks: ~6 s by Clarabel, LARGE, 19,853 blocks: ~4 min)."""
    check_arguments("limit_analysis", {"model": InstanceOf(Model), "settings": InstanceOf(LimitSettings), "on_progress": CALLBACK},
                    model=model, settings=settings, on_progress=on_progress)
    progress = on_progress or (lambda stage: None)
    problem = _assemble(model, settings.tilt_axis, progress)
    joint, weight = model.joint, problem.weight
    friction = joint.friction
    cohesion = joint.cohesion * problem.area / weight
    # the Coulomb cone's apex: a tension beyond c / mu leaves no shear capacity, so no point holds
    # more (found by a hunt: LA-NA took the uncapped tension, 7.8-25 % above LA-A)
    tension = np.minimum(joint.tension * problem.area / weight, cohesion / friction)

    cone = EXACT_CONE and problem.n_tangents == 2
    solve, program, solver = (_solve_cone, "SOCP", "Clarabel") if cone else (_solve, "LP", "HiGHS")

    def announce(rows: int, columns: int) -> None:
        kind = (f"exact Coulomb cones, interior point: {rows} rows x {columns} columns, {problem.n_points} second-order cones"
                if cone else f"{SOLVER_NAMES[METHOD]}: {rows} rows x {columns} columns, {problem.n_points} contact points")
        progress(f"solving the associative {program} with {solver} ({kind})")

    lam, normal, duals, status = solve(problem, friction=friction, cohesion=cohesion, tension=tension, capacity=None,
                                       announce=announce)
    forces = normal
    history, converged, iterations = [lam], True, 1
    if settings.non_associative:
        associative, converged = lam, False
        for iterations in range(2, settings.max_iterations + 2):
            progress(f"non-associative iteration {iterations - 1} of at most {settings.max_iterations}: "
                     f"solving the {program} with {solver} (lambda {lam:.4f} so far)")
            capacity = np.maximum(cohesion + friction * normal, 0.0)  # Coulomb at the last normal force, a tension lowering it
            lam_new, forces_new, duals_new, status = solve(problem, friction=friction, cohesion=cohesion, tension=tension, capacity=capacity,
                                                           method=NA_METHOD)
            history.append(lam_new)
            normal = (1 - settings.relaxation) * normal + settings.relaxation * forces_new
            change = abs(lam_new - lam) / max(abs(lam), 1e-12)
            lam, forces, duals = lam_new, forces_new, duals_new
            if change < settings.tolerance and lam <= associative * (1 + settings.tolerance):
                converged = True
                break
    velocity, angular = _mechanism(model, problem, duals)
    return LimitResult(  # lam + 0.0: a balance on a knife edge solves to -0.0, which reads as 0
        load_multiplier=lam + 0.0, method="non-associative" if settings.non_associative else "associative", status=status,
        iterations=iterations, converged=converged, history=history, velocity=velocity, angular_velocity=angular,
        normal_force=forces * weight,
    )


def _assemble(model: Model, tilt_axis: str, progress: Callable[[str], None]) -> _Problem:
    """Contact points at the contact polygons' corners, and the equilibrium rows of the free dofs."""
    movable = model.block_movable
    if not movable.any():
        raise LimitAnalysisError(f"{model.source}: no movable block to analyse")
    load = LOAD_DIRECTION[tilt_axis]
    free = ~model.block_fixed & movable[:, None]
    if not free[:, load].any():
        axis = "xy"[load]
        held = f": [supports] fix_{axis} holds every block in {axis}" if model.supports.mask[load] else ""  # not "held in y" for x
        raise LimitAnalysisError(f"{model.source}: no block may move along {axis}, the live load's direction (tilt axis {tilt_axis}){held}")
    progress(f"finding the contacts of {model.n_blocks} blocks")
    corners = model.replace(contacts=ContactSettings(points_per_length=2, points_across=model.contacts.points_across,
                                                     tolerance=model.contacts.tolerance))
    at_rest = State.at_rest(model.block_centroid)
    sub = ContactTracker(corners, at_rest).contacts
    _refuse_untouched(model, sub)
    progress(f"assembling the equilibrium matrix ({sub.count} contact points)")
    rotation = np.repeat(np.eye(3)[None], model.n_blocks, axis=0)
    point, _, normal = world_points(sub, at_rest.position, rotation)
    # in-plane models (the paper's walls, Model.in_plane): every contact normal lies in the x-z
    # plane and only x, z and the rotation about y are in equilibrium (the others are held)
    in_plane = model.in_plane
    tangents = _tangents(normal, in_plane, load)
    weight = float(model.block_mass[movable].mean() * G)
    geometry = model.geometry  # vertices relative to the centroids, block by block
    starts = geometry.vertex_start[:-1]
    extent = np.maximum.reduceat(geometry.vertex, starts) - np.minimum.reduceat(geometry.vertex, starts)
    length = float(extent.max(axis=1).mean())
    centroid = model.block_centroid / length
    point = point / length

    row_of = -np.ones((model.n_blocks, 6), dtype=np.int64)
    row_of[free] = np.arange(free.sum())
    rows = np.argwhere(free)
    directions = [normal, *tangents]  # per point: the unit vector of each force variable
    i, j, v = [], [], []
    n_points = sub.count
    for var, direction in enumerate(directions):
        column = var * n_points + np.arange(n_points)
        for block, sign in ((sub.block_inc, 1.0), (sub.block_ref, -1.0)):
            arm = point - centroid[block]
            moment = np.cross(arm, direction)
            for dof in range(6):
                value = sign * (direction[:, dof] if dof < 3 else moment[:, dof - 3])
                row = row_of[block, dof]
                keep = (row >= 0) & (np.abs(value) > ZERO)
                i.append(row[keep]), j.append(column[keep]), v.append(value[keep])
    equilibrium = coo_matrix((np.concatenate(v), (np.concatenate(i), np.concatenate(j))),
                             shape=(len(rows), len(directions) * n_points)).tocsr()
    mass = model.block_mass[rows[:, 0]] * G / weight
    dead = np.where(rows[:, 1] == 2, -mass, 0.0)
    live = np.where(rows[:, 1] == load, mass, 0.0)
    # moments of the loads about the centroid vanish: they act at the centroid
    return _Problem(equilibrium, live, dead, rows, n_points, len(tangents), sub.area, weight, length, model.source)


def _tangents(normal: np.ndarray, in_plane: bool, load: int = 0) -> list[np.ndarray]:
    """Unit tangents per point: in-plane, the one in the x-z plane; in 3D, t1 along the live
    load (axis ``load``, x or y) projected on the contact plane (z where the normal is along
    the load), t2 = n x t1."""
    if in_plane:
        t = np.cross(normal, [0.0, 1.0, 0.0])
        return [t / np.linalg.norm(t, axis=1)[:, None]]
    axis = np.where(np.abs(normal[:, [load]]) < 0.9, np.eye(3)[[load]], [[0.0, 0.0, 1.0]])
    t1 = axis - np.sum(axis * normal, axis=1)[:, None] * normal
    t1 /= np.linalg.norm(t1, axis=1)[:, None]
    return [t1, np.cross(normal, t1)]


def _solve(problem: _Problem, *, friction: float, cohesion: np.ndarray, tension: np.ndarray, capacity: np.ndarray | None,
           announce: Callable[[int, int], None] | None = None, method: str | None = None):
    """max lambda: returns (lambda, normal forces (np,) in weight units, duals of the equilibrium rows, status).

    Shear limits: T inside the polygon (2 sides in-plane, :data:`PYRAMID_SIDES` in 3D, a vertex
    along t1) of circumradius cohesion + friction N, N >= -tension; or, with ``capacity``, of
    circumradius capacity (fixed: no dependence on N, no dilatancy), N >= -tension; ``tension``
    at most cohesion / friction (the cone's apex, as :func:`limit_analysis` caps it).

    The admissible set of each point is written by its generators rather than its facets (the
    same set, so the same LP optimum; only the equilibrium rows are rows): a point's force is

        f = -floor n + sum_s beta_s (n + friction v_s) + w,   beta_s >= 0,  w in radius * polygon,

    v_s the polygon's unit vertices; floor = tension; associative: radius = cohesion - friction
    floor >= 0; non-associative: one ray n, radius = capacity. In-plane, w is one column
    bounded by +-radius; in 3D, w = sum_s gamma_s v_s, gamma_s >= 0, sum_s gamma_s <= radius (one
    row per point with radius > 0: none with the default zero cohesion and tension). The facet
    form had 2 (3D: 16) inequality rows per point besides the ~3 (6) equilibrium rows per block:
    a 20 x 20 brick wall, 5,910 rows (1,230 here); its LP took 1.8 s (dual simplex), now 0.3 s
    (interior point, :data:`METHOD`); a 60 x 60 wall ~15 min, now ~90 s; a 115-block house in
    3D, 684 rows x 18,945 columns here, ~190 s in the facet form, now 6-15 s (2 shared cores)."""
    n, k = problem.n_points, problem.n_tangents
    sides = 2 if k == 1 else PYRAMID_SIDES
    angles = np.arange(sides) * 2 * np.pi / sides  # the polygon's vertices: 0 (and pi in-plane), one along t1
    vertex = np.stack([np.cos(angles), np.sin(angles)], axis=1)
    vertex[np.abs(vertex) < 1e-12] = 0.0
    equilibrium = problem.equilibrium.tocsc()  # by columns: sliced and stacked by columns, HiGHS's format
    b_normal = equilibrium[:, :n]
    b_tangent = [equilibrium[:, (1 + i) * n:(2 + i) * n] for i in range(k)]

    def along(s: int, scale: float, cols=None):  # the equilibrium columns of the shear vertex s (times scale)
        parts = [b_tangent[i] * (scale * vertex[s, i]) for i in range(k) if vertex[s, i] != 0.0]
        total = parts[0]
        for part in parts[1:]:
            total = total + part
        return total if cols is None else total[:, cols]

    floor = tension
    if capacity is None:
        radius = np.maximum(cohesion - friction * floor, 0.0)
        rays = [b_normal + along(s, friction) for s in range(sides)]
    else:
        radius = capacity
        rays = [b_normal]
    n_rays = len(rays)
    sheared = np.flatnonzero(radius > 0)
    m = len(sheared)
    columns = list(rays)
    lower = [np.zeros(n * n_rays)]
    upper = [np.full(n * n_rays, np.inf)]
    a_ub = b_ub = None
    if m and k == 1:
        columns.append(b_tangent[0][:, sheared])
        lower.append(-radius[sheared]), upper.append(radius[sheared])
    elif m:
        columns += [along(s, 1.0, sheared) for s in range(sides)]
        lower.append(np.zeros(m * sides)), upper.append(np.full(m * sides, np.inf))
        pick = coo_matrix((np.ones(m * sides), (np.tile(np.arange(m), sides), np.arange(m * sides))), shape=(m, m * sides))
        a_ub = hstack([coo_matrix((m, n * n_rays)), pick, coo_matrix((m, 1))], format="csc")
        b_ub = radius[sheared]
    columns.append(coo_matrix(problem.live[:, None]).tocsc())
    lower.append([-np.inf]), upper.append([np.inf])  # free: a negative lambda is reported
    a_eq = hstack(columns, format="csc")
    b_eq = -problem.dead + b_normal @ floor
    cost = np.zeros(a_eq.shape[1])
    cost[-1] = -1.0
    bounds = np.stack([np.concatenate(lower), np.concatenate(upper)], axis=1)
    if announce is not None:
        announce(a_eq.shape[0] + (0 if a_ub is None else a_ub.shape[0]), a_eq.shape[1])
    res = linprog(cost, A_ub=a_ub, b_ub=b_ub, A_eq=a_eq, b_eq=b_eq, bounds=bounds, method=method or METHOD, options=OPTIONS)
    outcome = {0: SOLVED, 2: INFEASIBLE, 3: UNBOUNDED}.get(res.status, FAILED)
    _check_outcome(problem.source, outcome, res.x[-1] if outcome == SOLVED else None, f"HiGHS failed: {res.message}")
    normal = res.x[: n * n_rays].reshape(n_rays, n).sum(axis=0) - floor
    return float(res.x[-1]), normal, res.eqlin.marginals, res.message


def _solve_cone(problem: _Problem, *, friction: float, cohesion: np.ndarray, tension: np.ndarray, capacity: np.ndarray | None,
                announce: Callable[[int, int], None] | None = None, method: str | None = None):
    """:func:`_solve` for 3D points with the exact Coulomb cone, by Clarabel (``method`` unused).

    Variables: N_k, (T_k1, T_k2) per point, lambda; Clarabel's form ``A x + s = b``, s in cones:
    the equilibrium rows ``B f + lambda L = -D`` (zero cone: their duals are the mechanism);
    ``(c A_k + mu N_k, T_k1, T_k2)`` in a second-order cone of dimension 3 (|T_k| <= c A_k + mu N_k)
    and ``N_k + t A_k >= 0`` (nonnegative cone; left out where the cone implies it, t A_k >= c A_k / mu:
    all points for the default c = t = 0). Non-associative (``capacity``): ``(capacity_k, T_k)``
    in the cone, a constant first entry (no dependence on N, no dilatancy); points of zero
    capacity have no shear variables (a cone with an empty interior stalls the interior point)."""
    n = problem.n_points
    equilibrium = problem.equilibrium.tocsc()
    if capacity is None:
        sheared = np.arange(n)
        top, slope = cohesion, friction
        bounded = np.flatnonzero(tension < cohesion / friction)  # N >= -t not implied by the cone
    else:
        sheared = np.flatnonzero(capacity > 0)
        top, slope = capacity[sheared], 0.0
        bounded = np.arange(n)
    m = len(sheared)
    columns = [equilibrium[:, :n], equilibrium[:, n:2 * n][:, sheared], equilibrium[:, 2 * n:][:, sheared],
               csc_matrix(problem.live[:, None])]
    a_eq = hstack(columns, format="csc")
    n_vars = a_eq.shape[1]
    # the cones: rows 3 j, 3 j + 1, 3 j + 2 of the j-th sheared point: -(slope N), -T1, -T2
    j = np.arange(m)
    rows = np.concatenate([3 * j, 3 * j + 1, 3 * j + 2])
    cols = np.concatenate([sheared, n + j, n + m + j])
    values = np.concatenate([np.full(m, -slope), -np.ones(2 * m)])
    keep = values != 0.0
    a_cone = coo_matrix((values[keep], (rows[keep], cols[keep])), shape=(3 * m, n_vars))
    b_cone = np.zeros(3 * m)
    b_cone[3 * j] = top
    a_floor = coo_matrix((-np.ones(len(bounded)), (np.arange(len(bounded)), bounded)), shape=(len(bounded), n_vars))
    a = vstack([a_eq, a_floor, a_cone], format="csc")
    b = np.concatenate([-problem.dead, tension[bounded], b_cone])
    cones = [clarabel.ZeroConeT(a_eq.shape[0])] + ([clarabel.NonnegativeConeT(len(bounded))] if len(bounded) else [])
    cones += [clarabel.SecondOrderConeT(3)] * m
    cost = np.zeros(n_vars)
    cost[-1] = -1.0
    settings = clarabel.DefaultSettings()
    for key, value in CONE_SETTINGS.items():
        setattr(settings, key, value)
    if announce is not None:
        announce(a.shape[0], n_vars)
    solution = _clarabel(csc_matrix((n_vars, n_vars)), cost, a, b, cones, settings)
    status = str(solution.status)
    outcome = CLARABEL_OUTCOMES.get(status, FAILED)
    x = np.asarray(solution.x)
    _check_outcome(problem.source, outcome, x[-1] if outcome == SOLVED else None,
                   f"Clarabel failed: {status} after {solution.iterations} iterations")
    duals = np.asarray(solution.z)[:a_eq.shape[0]]
    return float(x[-1]), x[:n].copy(), duals, f"Clarabel: {status} ({solution.iterations} iterations)"


def _refuse_untouched(model: Model, sub) -> None:
    """LimitAnalysisError naming the movable blocks that touch no other block (floating: nothing
    can hold them up, and the solver would only say the problem is infeasible)."""
    touched = np.zeros(model.n_blocks, dtype=bool)
    touched[sub.block_ref] = touched[sub.block_inc] = True
    alone = [model.block_name[b] for b in np.flatnonzero(model.block_movable & ~touched)]
    if alone:
        more = f" (and {len(alone) - 5} more)" if len(alone) > 5 else ""
        raise LimitAnalysisError(f"{model.source}: block(s) {', '.join(map(repr, alone[:5]))}{more} touch no other block: nothing "
                                 "holds them up (drydem check names them too)")


#: how a solve ended (:func:`_check_outcome`), and Clarabel's statuses for them (any other: FAILED)
SOLVED, INFEASIBLE, UNBOUNDED, FAILED = "solved", "infeasible", "unbounded", "failed"
CLARABEL_OUTCOMES = {"Solved": SOLVED, "AlmostSolved": SOLVED, "PrimalInfeasible": INFEASIBLE, "AlmostPrimalInfeasible": INFEASIBLE,
                     "DualInfeasible": UNBOUNDED, "AlmostDualInfeasible": UNBOUNDED}


def _check_outcome(source: str, outcome: str, lam: float | None, failure: str) -> None:
    """Raise LimitAnalysisError naming ``source`` unless the solve ended SOLVED with lambda >= 0:
    infeasible (no forces hold the dead load), unbounded (no mechanism), ``failure`` (the
    solver's own words) or a negative ``lam`` (the blocks stand only if pushed the other way)."""
    if outcome == INFEASIBLE:
        raise LimitAnalysisError(f"{source}: unstable under its dead load alone: no contact forces hold the blocks up "
                                 "for any load multiplier (a block floating, or resting beyond the edge of its support)")
    if outcome == UNBOUNDED:
        raise LimitAnalysisError(f"{source}: the load multiplier is unbounded: no mechanism can form under the horizontal load")
    if outcome != SOLVED:
        raise LimitAnalysisError(f"{source}: {failure}")
    if lam < 0:
        raise LimitAnalysisError(f"{source}: unstable under its dead load alone: lambda = {lam:.4g} < 0 "
                                 "(the blocks stand only if pushed the other way)")


def _clarabel(p, q, a, b, cones, settings):
    """Clarabel's solution of min q x + x P x / 2 subject to A x + s = b, s in ``cones`` (timed apart by the benchmark)."""
    return clarabel.DefaultSolver(p, q, a, b, cones, settings).solve()


def _mechanism(model: Model, problem: _Problem, duals: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Block velocities from the equilibrium duals (virtual work: power of the loads > 0),
    scaled so that the fastest block point moves at 1 m/s."""
    nb = model.n_blocks
    generalised = np.zeros((nb, 6))
    scale = np.where(problem.rows[:, 1] < 3, 1.0, 1.0 / problem.length)
    generalised[problem.rows[:, 0], problem.rows[:, 1]] = duals * scale
    if problem.live @ duals < 0:
        generalised = -generalised
    velocity, angular = generalised[:, :3], generalised[:, 3:]
    geometry = model.geometry  # every vertex relative to its block's centroid
    block = np.repeat(np.arange(nb), np.diff(geometry.vertex_start))
    fastest = float(np.linalg.norm(velocity[block] + np.cross(angular[block], geometry.vertex), axis=1).max())
    if fastest > 0:
        velocity, angular = velocity / fastest, angular / fastest
    return velocity, angular
