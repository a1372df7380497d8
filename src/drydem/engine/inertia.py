"""Inertia for the explicit integration: the blocks' constants, the critical timestep, mass scaling.

Critical timestep. The central-difference scheme is stable for dt < 2 / omega_max
(omega_max the highest natural frequency). Block i is touched by springs of stiffness
k_s = max(kn, ks) A_s (for a stress-dependent joint, at a stress above the one reached:
:func:`stiffness_bound`) at lever arms r_s from its centroid; they give it the translational
stiffness K_t = sum_s k_s (N/m) and the rotational stiffness matrix
K_r = sum_s k_s (|r_s|^2 1 - r_s r_s^T) (N m). The block alone on fixed partners has
omega^2 <= K_t / m + lambda_max(I^-1 K_r) (a positive block matrix is bounded by the sum
of its diagonal blocks), and moving partners at most double it (Gershgorin), so

    omega_i^2 <= 2 (K_t / m_i + lambda_max(I_i^-1 K_r,i))

and dt = safety * 2 / max_i omega_i (Cundall & Strack 1979; Itasca 3DEC manual,
"Timestep determination").

Mass scaling (statics only: inertia does not change the equilibrium). Each sprung
block gets the fictitious mass m' = C K_t and inertia I' = C K_r with C = (dt / safety)^2,
so every block is critical at the same dt: the slow, heavy modes no longer wait for
the stiff, light ones (Underwood 1983, "Dynamic relaxation"; 3DEC's density scaling).
Gravity still acts on the true mass.
"""

from __future__ import annotations

from typing import NamedTuple

import numba
import numpy as np

from drydem import compiled_cache
from drydem.engine.contacts import SubContacts
from drydem.engine.damping import Damping, drag_timestep, timestep_factor
from drydem.engine.joints import (
    CLOSING_CYCLES, JointConstants, StressJoint, kernel_joint, normal_closures, normal_stiffness, normal_stress, shear_stiffness,
)
from drydem.errors import ModelError
from drydem.model.assembly import Model
from drydem.model.parameters import G
from drydem.model.state import State
from drydem.model.rotation import matrices


class BlockConstants(NamedTuple):
    """Per-block constants for the kernels (nb blocks).

    mass : (nb,) kg, true mass (gravity). inv_mass : (nb,) 1/kg, of the mass used for
    the motion (scaled or true). inertia_body, inv_inertia_body : (nb, 3, 3) kg m2 and its
    inverse, about the centroid in the body frame. free : (nb, 6) 1.0 where the degree of
    freedom (x, y, z, rx, ry, rz) moves, 0.0 where fixed. radius : (nb,) m, largest
    distance from the centroid to a vertex. origin : (nb, 3) m, the centroids where the cycling
    started (the divergence test's travel is measured from them).
    """

    mass: np.ndarray
    inv_mass: np.ndarray
    inertia_body: np.ndarray
    inv_inertia_body: np.ndarray
    free: np.ndarray
    radius: np.ndarray
    origin: np.ndarray


#: a stress-dependent joint's timestep holds until a sub-contact's normal stress exceeds this
#: many times its stress when the timestep was computed (plus STRESS_FLOOR_WEIGHTS)
STRESS_HEADROOM = 2.0
#: ... plus this many times the mean stress of the free blocks' weight over all the sub-contacts
#: (a joint just made, at zero stress, may load up to it before the timestep is recomputed)
STRESS_FLOOR_WEIGHTS = 1.0
#: a step may close a stress-dependent joint by at most this fraction of its stiffening length
#: sigma / kn(sigma) (:func:`stiffness_bound`): its stress then grows by about that fraction a cycle
RESOLUTION = 0.25


class JointBound(NamedTuple):
    """What a stress-dependent joint allows the timestep (:func:`stiffness_bound`): the stiffness
    per area each sub-contact is counted with, (ns,) Pa/m; the closure up to which that holds,
    (ns,) m ((0,) for a constant joint); the longest timestep that resolves the joints'
    stiffening at their closing speeds, s (inf when none closes)."""

    stiffness: np.ndarray
    closure_limit: np.ndarray
    resolved_timestep: float


def stiffness_bound(joint: JointConstants | StressJoint, sub: SubContacts, weight_n: float,
                    closure_ahead: np.ndarray | None = None, closing_speed: np.ndarray | None = None) -> JointBound:
    """The joint's bound on the timestep (:class:`JointBound`); a constant joint: max(kn, ks)
    always.

    Stress-dependent laws: from the stress sigma at ``closure_ahead`` (ns,) m, the closure each
    sub-contact may reach before the timestep is next looked at (u + CLOSING_CYCLES v dt,
    :func:`timestep_and_blocks`; None: the stress each carries), the stress limit
    sigma_lim = STRESS_HEADROOM sigma + STRESS_FLOOR_WEIGHTS ``weight_n`` / sum A (N over m2: the free
    blocks' weight spread over every sub-contact), the stiffness max(kn(sigma_lim), ks(sigma_lim)),
    both laws growing with sigma, and the closure limit u(sigma_lim). The cycles stop
    (:data:`drydem.engine.loop.STIFFENED`) as soon as a sub-contact is about to close past it
    (:func:`drydem.engine.joints.stiffer_than_timestep`), and the timestep is computed again.

    Stability is not enough where a joint closes fast (an impact): a step that closes it by more
    than its stiffening length l = sigma / kn(sigma) (the closure over which its stress grows
    e-fold, for the linear power law) jumps across the law and creates energy. So the timestep
    is also at most RESOLUTION l / v over the sub-contacts closing at ``closing_speed`` v (ns,)
    m/s (:func:`drydem.engine.contacts.closing_motion`), at sigma_lim.
    """
    if isinstance(joint, JointConstants):
        return JointBound(np.full(sub.count, max(joint.kn, joint.ks)), np.zeros(0), np.inf)
    stress = sub.normal_force / sub.area if closure_ahead is None else _law_stresses(closure_ahead, joint)
    floor = STRESS_FLOOR_WEIGHTS * weight_n / max(float(sub.area.sum()), 1e-300)
    limit = STRESS_HEADROOM * np.maximum(stress, 0.0) + floor
    normal, stiffness = _law_stiffnesses(limit, joint)
    resolved = np.inf
    if closing_speed is not None and (closing_speed > 0).any():
        closing = closing_speed > 0
        resolved = float(RESOLUTION * np.min(limit[closing] / normal[closing] / closing_speed[closing]))
    return JointBound(stiffness, normal_closures(limit, joint), resolved)


@numba.njit(cache=True)
def _law_stresses(closure, joint):
    """sigma(u) of each closure (ns,) m, Pa (:func:`drydem.engine.joints.normal_stress`)."""
    out = np.empty_like(closure)
    for s in range(closure.shape[0]):
        out[s] = normal_stress(closure[s], joint)
    return out


@numba.njit(cache=True)
def _law_stiffnesses(stress, joint):
    """kn(sigma) and max(kn(sigma), ks(sigma)) of each stress (ns,) Pa, Pa/m."""
    normal = np.empty_like(stress)
    largest = np.empty_like(stress)
    for s in range(stress.shape[0]):
        normal[s] = normal_stiffness(stress[s], joint)
        largest[s] = max(normal[s], shear_stiffness(stress[s], joint))
    return normal, largest


def contact_stiffness(sub: SubContacts, stiffness: np.ndarray, n_blocks: int) -> tuple[np.ndarray, np.ndarray]:
    """Per-block K_t (nb,) N/m and K_r (nb, 3, 3) N m of its sub-contact springs (body frame):
    K_t = sum_s k_s, K_r = trace(S) 1 - S with S = sum_s k_s r_s r_s^T, k_s = ``stiffness``_s A_s
    (``stiffness`` (ns,) Pa/m: :func:`stiffness_bound`). Compiled (it runs at every
    re-detection); the tests hold it to a NumPy oracle."""
    return _contact_stiffness(sub.pairs, sub.start, sub.point_ref_body, sub.point_inc_body, sub.area, stiffness, n_blocks)


@numba.njit(cache=True)
def _contact_stiffness(pairs, start, point_ref_body, point_inc_body, area, stiffness, n_blocks):
    k_t = np.zeros(n_blocks)
    second = np.zeros((n_blocks, 3, 3))
    for c in range(pairs.shape[0]):
        for s in range(start[c], start[c + 1]):
            k = stiffness[s] * area[s]
            for side in range(2):
                b = pairs[c, side]
                arm = point_ref_body[s] if side == 0 else point_inc_body[s]
                k_t[b] += k
                for i in range(3):
                    for j in range(3):
                        second[b, i, j] += k * arm[i] * arm[j]
    k_r = -second
    for b in range(n_blocks):
        trace = second[b, 0, 0] + second[b, 1, 1] + second[b, 2, 2]
        for i in range(3):
            k_r[b, i, i] += trace
    return k_t, k_r


def critical_timestep(mass: np.ndarray, whitening: np.ndarray, movable: np.ndarray, k_t: np.ndarray, k_r: np.ndarray) -> float:
    """2 / omega_max with omega_i^2 = 2 (K_t / m + lambda_max(I^-1 K_r)), s (inf if nothing is
    sprung); ``whitening`` is L^-1 for the inertias I = L L^T (Model.block_inertia_whitening), so
    that lambda(I^-1 K_r) = lambda(L^-1 K_r L^-T), a symmetric 3 x 3 eigenproblem, solved in
    closed form (compiled; the tests hold it to LAPACK's eigvalsh)."""
    omega_sq = _largest_omega_sq(mass, whitening, movable, k_t, k_r)
    return np.inf if omega_sq <= 0 else float(2.0 / np.sqrt(omega_sq))


@numba.njit(cache=True)
def _largest_omega_sq(mass, whitening, movable, k_t, k_r):
    largest = 0.0
    wk = np.empty((3, 3))
    a = np.empty((3, 3))
    for b in range(mass.shape[0]):
        if not movable[b]:
            continue
        w, k = whitening[b], k_r[b]
        for i in range(3):  # a = W K W^T, without temporaries (this runs at every re-detection)
            for j in range(3):
                wk[i, j] = w[i, 0] * k[0, j] + w[i, 1] * k[1, j] + w[i, 2] * k[2, j]
        for i in range(3):
            for j in range(3):
                a[i, j] = wk[i, 0] * w[j, 0] + wk[i, 1] * w[j, 1] + wk[i, 2] * w[j, 2]
        largest = max(largest, 2.0 * (k_t[b] / mass[b] + largest_eigenvalue(a)))
    return largest


@numba.njit(cache=True, inline="always")
def largest_eigenvalue(a):
    """Largest eigenvalue of a symmetric 3 x 3 matrix, trigonometric closed form (Smith 1961,
    "Eigenvalues of a symmetric 3 x 3 matrix", Comm. ACM 4(4), 168)."""
    off = a[0, 1] ** 2 + a[0, 2] ** 2 + a[1, 2] ** 2
    q = (a[0, 0] + a[1, 1] + a[2, 2]) / 3.0
    p2 = (a[0, 0] - q) ** 2 + (a[1, 1] - q) ** 2 + (a[2, 2] - q) ** 2 + 2.0 * off
    if p2 <= 1e-30 * max(q * q, 1e-300):
        return q
    p = np.sqrt(p2 / 6.0)
    # det of B = (A - q 1) / p, A symmetric
    b00, b11, b22 = (a[0, 0] - q) / p, (a[1, 1] - q) / p, (a[2, 2] - q) / p
    b01, b02, b12 = a[0, 1] / p, a[0, 2] / p, a[1, 2] / p
    det = b00 * (b11 * b22 - b12 * b12) - b01 * (b01 * b22 - b12 * b02) + b02 * (b01 * b12 - b11 * b02)
    r = min(max(det / 2.0, -1.0), 1.0)
    return q + 2.0 * p * np.cos(np.arccos(r) / 3.0)


def scaled_inertia(
    mass: np.ndarray, inertia_body: np.ndarray, k_t: np.ndarray, k_r: np.ndarray, timestep: float, safety: float
) -> tuple[np.ndarray, np.ndarray]:
    """Fictitious masses m' = C K_t and inertias I' = C (K_r + delta 1), C = (dt / safety)^2 (see
    module docstring); delta = 1e-3 trace(K_r) / 3 keeps I' invertible where the springs do not
    hold every rotation (a block rocking on one edge) and leaves every block stable at dt.
    Blocks without springs keep their true mass and inertia (free flight is dynamics)."""
    c = (timestep / safety) ** 2
    sprung = k_t > 0
    delta = 1e-3 * np.trace(k_r, axis1=1, axis2=2) / 3.0
    m = np.where(sprung, c * k_t, mass)
    inertia = np.where(sprung[:, None, None], c * (k_r + delta[:, None, None] * np.eye(3)), inertia_body)
    return m, inertia


class Inertia(NamedTuple):
    """What the cycles run with for a set of contacts: the timestep, s; the blocks' constants;
    the closure (ns,) m up to which the timestep holds ((0,): always; :func:`stiffness_bound`)."""

    timestep: float
    blocks: BlockConstants
    closure_limit: np.ndarray


def timestep_and_blocks(
    model: Model, contacts: SubContacts, active: np.ndarray, *, fixed_timestep: float | None, scaled_timestep: float | None,
    damping: Damping, origin: np.ndarray, closing: tuple[np.ndarray, np.ndarray, float] | None = None,
    point_speed_m_s: np.ndarray | None = None,
) -> Inertia:
    """The timestep (s), the blocks' constants with ``contacts``, blocks not ``active`` held, and
    the closure limit of a stress-dependent joint (:func:`stiffness_bound`, with ``closing``: each
    sub-contact's closure, m, and closing speed, m/s, and the timestep they were taken at, s).
    ``origin`` (nb, 3) m: the centroids where the cycling started (:class:`BlockConstants`).

    The timestep is ``fixed_timestep`` (ModelError if above the critical one), else
    ``solver.timestep_safety`` times the critical one (:func:`critical_timestep`, reduced for
    the dashpots of a viscous ``damping``: :func:`drydem.engine.damping.timestep_factor`, and at
    most :func:`drydem.engine.damping.drag_timestep`), at most the free flight one
    (:func:`free_flight_timestep` at the largest ``point_speed_m_s``, (nb,) m/s, of the blocks
    without springs; None: at rest), and at most the one that resolves a stress-dependent
    joint's stiffening (a fixed one is only held to stability). The free flight bound is the
    only one where nothing is sprung: on soft joints the critical timestep is long enough for a
    block released in contact to fall through its joint in a cycle or two, before the spring
    acts, and be called fallen (a brick on kn = 2e4 Pa/m fell through in 2 cycles of 17 ms).
    With mass scaling, the masses and inertias are the fictitious ones (:func:`scaled_inertia`)
    for ``scaled_timestep`` (s; None: for this timestep,
    which is then the one to keep).
    """
    solver = model.solver
    movable = model.block_movable & active
    weight = G * float(model.block_mass[movable].sum())
    if closing is None:
        bound = stiffness_bound(kernel_joint(model.joint), contacts, weight)
    else:
        closure, speed, previous = closing
        ahead = closure + CLOSING_CYCLES * np.maximum(speed, 0.0) * previous  # an opening joint: where it is
        bound = stiffness_bound(kernel_joint(model.joint), contacts, weight, ahead, speed)
    stiffness = bound.stiffness
    k_t, k_r = contact_stiffness(contacts, stiffness, model.n_blocks)
    flying = movable & (k_t == 0.0)
    flight_speed = 0.0 if point_speed_m_s is None else float(point_speed_m_s[flying].max(initial=0.0))
    critical = critical_timestep(model.block_mass, model.block_inertia_whitening, movable, k_t, k_r)
    critical *= timestep_factor(damping, critical) if np.isfinite(critical) else 1.0
    critical = min(critical, drag_timestep(damping))
    if fixed_timestep is not None:
        if fixed_timestep > critical:
            raise ModelError(
                f"{model.source}: timestep {fixed_timestep:.3g} s exceeds the critical timestep "
                f"{critical:.3g} s (joint stiffness up to {stiffness.max(initial=0.0):.3g} Pa/m); the run would blow up"
            )
        dt = fixed_timestep
    else:
        dt = min(solver.timestep_safety * critical, free_flight_timestep(model.contact_tolerance, flight_speed), bound.resolved_timestep)
    mass, inertia = model.block_mass, model.block_inertia
    if solver.mass_scaling:
        dt = dt if scaled_timestep is None else scaled_timestep
        mass, inertia = scaled_inertia(mass, inertia, k_t, k_r, dt, solver.timestep_safety)
    return Inertia(float(dt), BlockConstants(  # the model's arrays are read-only: the kernels are built for writable ones
        mass=model.block_mass.copy(),
        inv_mass=np.where(movable, 1.0 / mass, 0.0),
        inertia_body=np.array(inertia),
        inv_inertia_body=np.linalg.inv(inertia) if solver.mass_scaling else model.block_inertia_inverse,
        free=(~model.block_fixed & movable[:, None]).astype(float),
        radius=model.block_radius.copy(),
        origin=origin,
    ), bound.closure_limit)


def free_flight_timestep(tolerance: float, speed_m_s: float = 0.0) -> float:
    """Timestep with no springs, s: a tenth of the time to fall through the contact
    ``tolerance`` (m) from rest, and of the time a block point moving at ``speed_m_s`` (m/s)
    takes to travel it,

        dt = 0.1 min(sqrt(2 tolerance / g), tolerance / v).

    A pair of blocks is re-detected before its separation falls below half the tolerance
    (:mod:`drydem.engine.tracker`: its limit is the separation less half the tolerance), so a
    flying block's contact is found before it touches, and its landing is run at the contact's
    timestep (the speed is the one the block may reach before its next re-detection:
    :meth:`drydem.engine.simulation.Simulation._flight_reach_m_s`). Bounding only the fall from
    rest, a cube dropped 20 mm (0.63 m/s) flew 1.4 mm a cycle at 2.3 ms, found its base 0.14 mm
    deep, and the variable step's first velocity step, (dt_old + dt) / 2, gave that spring's
    force 30 times its cycle: the bounce lost 39 % of the drop energy; a brick falling at 15 m/s
    flew 40 tolerances a cycle. Now the cube's 11 bounces reach the drop height within 0.04 % at
    timestep safety 0.05 (within 1.7 % at 0.2: the impacts' own error, first order in dt). The
    cost: a long fall takes ~200 times the cycles of the bound from rest alone (a brick falling
    1.5 s, tolerance 0.28 mm: 410,000 cycles, 5 s, against 2,003)."""
    moving = bool(np.isfinite(speed_m_s) and speed_m_s > 0.0)  # a speed of NaN or inf is the divergence test's to catch
    return 0.1 * min(float(np.sqrt(2.0 * tolerance / G)), tolerance / speed_m_s if moving else np.inf)


def point_speed_m_s(state: State, radius: np.ndarray) -> np.ndarray:
    """(nb,) m/s, a bound on the speed of each block's points: |v| + |omega| r (r the block's radius, m)."""
    return np.linalg.norm(state.velocity, axis=1) + np.linalg.norm(state.angular_velocity, axis=1) * radius


def keep_kinetic_energy(state: State, old: BlockConstants, new: BlockConstants) -> None:
    """Rescale ``state``'s velocities in place when fictitious masses change from ``old`` to
    ``new``, so that each block keeps its kinetic energy (a change of fictitious inertia must not
    create or destroy energy)."""
    old_mass = np.divide(1.0, old.inv_mass, out=np.zeros_like(old.inv_mass), where=old.inv_mass > 0)
    mass = np.divide(1.0, new.inv_mass, out=np.zeros_like(new.inv_mass), where=new.inv_mass > 0)
    state.velocity[:] *= np.sqrt(np.divide(old_mass, mass, out=np.ones_like(mass), where=mass > 0))[:, None]
    rot = matrices(state.quaternion)
    omega_body = np.einsum("nji,nj->ni", rot, state.angular_velocity)
    before = np.einsum("ni,nij,nj->n", omega_body, old.inertia_body, omega_body)
    after = np.einsum("ni,nij,nj->n", omega_body, new.inertia_body, omega_body)
    state.angular_velocity[:] *= np.sqrt(np.divide(before, after, out=np.ones_like(after), where=after > 0))[:, None]


compiled_cache.check(__name__)  # last: none of the functions above is loaded from a stale cache
