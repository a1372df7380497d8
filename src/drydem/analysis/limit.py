"""Limit analysis of rigid blocks: the static (lower-bound) linear program, associative and
non-associative friction, solved with HiGHS (scipy.optimize.linprog).

Associative (LA-A; Livesley 1978, Gilbert & Melbourne 1994): at every contact point k of the
model's contact polygons (their corners: 2 points per length), a normal force N_k >= -t A_k
(t the tensile strength, 0 by default) and a shear force T_k inside the linearised Coulomb
cone, |T_k| <= c A_k + mu N_k (in-plane models: one tangent, exact; 3D: a 16-sided pyramid
inscribed in the cone, with a vertex along the live load). Every free degree of freedom of every movable block is in equilibrium under its
weight W (dead load, vertical) plus lambda W horizontal along x (live load: the tilting table's
lateral component)::

    maximise lambda  subject to  B f + lambda L = -D,  f admissible,

B the equilibrium matrix (contact forces to block forces and moments about the centroids).
Corner forces are exact for rigid blocks: any compressive stress field on a convex polygon
has its resultant inside the polygon, a convex combination of the corners. The duals of the
equilibrium rows are the blocks' virtual velocities at collapse: the mechanism. For tilting,
the collapse angle is atan(lambda).

Non-associative (LA-NA): friction without dilatancy, by the iterative scheme of Gilbert,
Casapulla & Ahmed (2006, Computers & Structures 84, 873-887): solve LA-A; then, repeatedly,
replace each point's friction limit by a fixed shear capacity mu N_k taken from the previous
solution (a "pseudo-cohesion", whose flow rule has no normal dilatancy) and solve again,
relaxing the normal forces between iterations, until lambda settles. Its limits, as the
authors state: the non-associative problem has no unique solution and this scheme is not
guaranteed to find the lowest multiplier (nor to converge; then the last iterate is
reported with ``converged = False``).

Units: the LP is solved in units of the mean block weight and the mean block size (HiGHS can
return wrong optima on badly scaled input; bricks weigh ~0.03 N).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import linprog
from scipy.sparse import coo_matrix, hstack, identity, vstack
from scipy.spatial.transform import Rotation

from drydem.engine.contacts import world_points
from drydem.engine.tracker import ContactTracker
from drydem.errors import DrydemError
from drydem.model.assembly import Model
from drydem.model.parameters import FLAG, G, ContactSettings, Range, check_fields
from drydem.model.state import State

#: sides of the linearised friction pyramid for 3D contacts
PYRAMID_SIDES = 16


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
}


@dataclass(frozen=True, kw_only=True)
class LimitSettings:
    """non_associative : run the Gilbert et al. (2006) iteration after the associative LP.
    max_iterations : of that iteration. tolerance : relative change of lambda that ends it.
    relaxation : share of the new normal forces mixed into the old ones, 0 < r <= 1.
    Checked when created (:data:`LIMIT_RULES`): ModelError naming each bad setting and its range."""

    non_associative: bool = False
    max_iterations: int = 100
    tolerance: float = 1e-4
    relaxation: float = 0.5

    def __post_init__(self):
        check_fields(self, LIMIT_RULES, "limit setting")


@dataclass(frozen=True)
class LimitResult:
    """load_multiplier : lambda at collapse. collapse_angle_deg : atan(lambda) in degrees.
    method : "associative" or "non-associative". status : HiGHS's message. iterations and
    converged : of the non-associative scheme (1 and True for LA-A); history : lambda per
    iteration. velocity : (nb, 3) m/s and angular_velocity : (nb, 3) rad/s, the mechanism,
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
        """The blocks moved along the mechanism so that the fastest point moves ``displacement_m``."""
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
    equilibrium matrix, each LP solved by HiGHS: the associative one, then each non-associative
    iteration with the last lambda), with a line that says it and its size, so that a command
    can show where it is: on a large wall nearly all the time is in the LP (a 60 x 60 brick
    wall, 3631 blocks: contacts 0.1 s, assembly 0.6 s, the associative LP 15 min)."""
    progress = on_progress or (lambda stage: None)
    problem = _assemble(model, progress)
    joint, weight = model.joint, problem.weight
    friction = joint.friction
    cohesion = joint.cohesion * problem.area / weight
    tension = joint.tension * problem.area / weight
    rows, columns = problem.equilibrium.shape
    progress(f"solving the associative LP with HiGHS ({rows} equilibrium rows, {columns} contact forces)")
    lam, forces, duals, status = _solve(problem, friction=friction, cohesion=cohesion, tension=tension, capacity=None)
    history, converged, iterations = [lam], True, 1
    if settings.non_associative:
        converged = False
        normal = forces[: problem.n_points]
        for iterations in range(2, settings.max_iterations + 2):
            progress(f"non-associative iteration {iterations - 1} of at most {settings.max_iterations}: "
                     f"solving the LP with HiGHS (lambda {lam:.4f} so far)")
            capacity = cohesion + friction * np.maximum(normal, 0.0)
            lam_new, forces_new, duals_new, status = _solve(problem, friction=0.0, cohesion=cohesion, tension=tension, capacity=capacity)
            history.append(lam_new)
            normal = (1 - settings.relaxation) * normal + settings.relaxation * forces_new[: problem.n_points]
            change = abs(lam_new - lam) / max(abs(lam), 1e-12)
            lam, forces, duals = lam_new, forces_new, duals_new
            if change < settings.tolerance:
                converged = True
                break
    velocity, angular = _mechanism(model, problem, duals)
    return LimitResult(
        load_multiplier=lam, method="non-associative" if settings.non_associative else "associative", status=status,
        iterations=iterations, converged=converged, history=history, velocity=velocity, angular_velocity=angular,
        normal_force=forces[: problem.n_points] * weight,
    )


def _assemble(model: Model, progress: Callable[[str], None]) -> _Problem:
    """Contact points at the contact polygons' corners, and the equilibrium rows of the free dofs."""
    movable = model.block_movable
    if not movable.any():
        raise LimitAnalysisError(f"{model.source}: no movable block to analyse")
    progress(f"finding the contacts of {model.n_blocks} blocks")
    corners = model.replace(contacts=ContactSettings(points_per_length=2, points_across=model.contacts.points_across,
                                                     tolerance=model.contacts.tolerance))
    at_rest = State.at_rest(model.block_centroid)
    sub = ContactTracker(corners, at_rest).contacts
    if sub.count == 0:
        raise LimitAnalysisError(f"{model.source}: no contacts: the blocks do not touch")
    progress(f"assembling the equilibrium matrix ({sub.count} contact points)")
    rotation = np.repeat(np.eye(3)[None], model.n_blocks, axis=0)
    point, _, normal = world_points(sub, at_rest.position, rotation)
    # in-plane models (the paper's walls, Model.in_plane): every contact normal lies in the x-z
    # plane and only x, z and the rotation about y are in equilibrium (the others are held)
    in_plane = model.in_plane
    tangents = _tangents(normal, in_plane)
    weight = float(model.block_mass[movable].mean() * G)
    length = float(np.mean([np.ptp(s.vertices, axis=0).max() for s in model.block_shape]))
    centroid = model.block_centroid / length
    point = point / length

    free = ~model.block_fixed & movable[:, None]
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
                keep = (row >= 0) & (value != 0.0)
                i.append(row[keep]), j.append(column[keep]), v.append(value[keep])
    equilibrium = coo_matrix((np.concatenate(v), (np.concatenate(i), np.concatenate(j))),
                             shape=(len(rows), len(directions) * n_points)).tocsr()
    mass = model.block_mass[rows[:, 0]] * G / weight
    dead = np.where(rows[:, 1] == 2, -mass, 0.0)
    live = np.where(rows[:, 1] == 0, mass, 0.0)
    # moments of the loads about the centroid vanish: they act at the centroid
    return _Problem(equilibrium, live, dead, rows, n_points, len(tangents), sub.area, weight, length, model.source)


def _tangents(normal: np.ndarray, in_plane: bool) -> list[np.ndarray]:
    """Unit tangents per point: in-plane, the one in the x-z plane; in 3D, t1 along the live
    load (x) projected on the contact plane (another axis where the normal is along x), t2 = n x t1."""
    if in_plane:
        t = np.cross(normal, [0.0, 1.0, 0.0])
        return [t / np.linalg.norm(t, axis=1)[:, None]]
    axis = np.where(np.abs(normal[:, [0]]) < 0.9, [[1.0, 0.0, 0.0]], [[0.0, 0.0, 1.0]])
    t1 = axis - np.sum(axis * normal, axis=1)[:, None] * normal
    t1 /= np.linalg.norm(t1, axis=1)[:, None]
    return [t1, np.cross(normal, t1)]


def _solve(problem: _Problem, *, friction: float, cohesion: np.ndarray, tension: np.ndarray, capacity: np.ndarray | None):
    """max lambda: returns (lambda, forces in weight units, duals of the equilibrium rows, status).

    Shear limits: |T . e| <= cohesion + friction N along every pyramid side e, or, with
    ``capacity``, <= capacity (fixed; no dependence on N: no dilatancy)."""
    n, k = problem.n_points, problem.n_tangents
    sides = 2 if k == 1 else PYRAMID_SIDES
    # facet normals between the vertices, so that a vertex (full capacity) lies along t1, the live load
    angles = (np.arange(sides) + (0.5 if k == 2 else 0.0)) * 2 * np.pi / sides
    facet = np.cos(np.pi / sides) if k == 2 else 1.0  # inscribed polygon's facet distance
    eye = identity(n, format="csr")
    blocks, bounds_rhs = [], []
    for angle in angles:
        shear = [eye * (np.cos(angle) if k == 2 else (1.0 if angle == 0 else -1.0))]
        if k == 2:
            shear.append(eye * np.sin(angle))
        normal_part = eye * (-friction * facet) if capacity is None else eye * 0.0
        blocks.append(hstack([normal_part, *shear, coo_matrix((n, 1))]))
        bounds_rhs.append(facet * (cohesion if capacity is None else capacity))
    a_ub = vstack(blocks).tocsr()
    b_ub = np.concatenate(bounds_rhs)
    a_eq = hstack([problem.equilibrium, coo_matrix(problem.live[:, None])]).tocsr()
    b_eq = problem.dead * -1.0
    cost = np.zeros(a_eq.shape[1])
    cost[-1] = -1.0
    bounds = [(-t, None) for t in tension] + [(None, None)] * (k * n) + [(None, None)]
    res = linprog(cost, A_ub=a_ub, b_ub=b_ub, A_eq=a_eq, b_eq=b_eq, bounds=bounds, method="highs")
    if res.status == 2:
        raise LimitAnalysisError(f"{problem.source}: unstable under its dead load alone: no contact forces hold the blocks up "
                                 "for any load multiplier (a block floating, or resting beyond the edge of its support)")
    if res.status == 3:
        raise LimitAnalysisError(f"{problem.source}: the load multiplier is unbounded: no mechanism can form under the horizontal load")
    if res.status != 0:
        raise LimitAnalysisError(f"{problem.source}: HiGHS failed: {res.message}")
    if res.x[-1] < 0:
        raise LimitAnalysisError(f"{problem.source}: unstable under its dead load alone: lambda = {res.x[-1]:.4g} < 0 "
                                 "(the blocks stand only if pushed the other way)")
    return float(res.x[-1]), res.x[:-1], res.eqlin.marginals, res.message


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
    fastest = 0.0
    for b, shape in enumerate(model.block_shape):
        arm = shape.vertices - shape.centroid
        fastest = max(fastest, float(np.linalg.norm(velocity[b] + np.cross(angular[b], arm), axis=1).max()))
    if fastest > 0:
        velocity, angular = velocity / fastest, angular / fastest
    return velocity, angular
