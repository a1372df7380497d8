"""The cycling loop shared by the compiled cycles (:mod:`drydem.engine.cycle3d`,
:mod:`drydem.engine.cycle_planar`) and the NumPy oracle: what one call is to do
(:class:`LoopSettings`), when it ends (equilibrium, re-detection, divergence, max cycles), and
the Verlet-list test that says when contacts must be re-detected.
"""

from __future__ import annotations

from typing import NamedTuple

import numba
import numpy as np

from drydem import compiled_cache
from drydem.engine.damping import Damping

#: kinetic energy above this many times the work gravity can have done means a blow-up
DIVERGENCE_FACTOR = 10.0
#: the energy test of divergence runs every this many cycles (a NaN is caught at every cycle)
ENERGY_CHECK_EVERY = 16
#: run_cycles exit codes (STIFFENED: a stress-dependent joint about to outgrow the timestep)
RUNNING, CONVERGED, REDETECT, DIVERGED, STIFFENED = 0, 1, 2, 3, 4
#: criterion codes
RATIO, VELOCITY = 0, 1
#: LLVM fast-math flags for the contact loops: reassociation and fused multiply-add, but
#: NaN and infinity keep their meaning (the divergence guard relies on them)
FASTMATH = {"contract", "reassoc", "arcp", "nsz"}


@numba.njit(cache=True, inline="always")
def _relative_quaternion(q, q0):
    """q (x) q0^-1 for unit quaternions: the rotation since detection."""
    return (
        q[0] * q0[0] + q[1] * q0[1] + q[2] * q0[2] + q[3] * q0[3],
        -q[0] * q0[1] + q[1] * q0[0] - q[2] * q0[3] + q[3] * q0[2],
        -q[0] * q0[2] + q[1] * q0[3] + q[2] * q0[0] - q[3] * q0[1],
        -q[0] * q0[3] - q[1] * q0[2] + q[2] * q0[1] + q[3] * q0[0],
    )


@numba.njit(cache=True, inline="always")
def _angle_bound(cos_half):
    """Upper bound 2 tan(theta / 2) >= theta of a rotation angle from |cos(theta / 2)|
    (tight to O(theta^3); no arccos in the per-cycle test)."""
    c = min(cos_half, 1.0)
    if c <= 0.5:
        return np.pi
    return 2.0 * np.sqrt(1.0 - c * c) / c


@numba.njit(cache=True, inline="always")
def _pair_motion(state, neighbours, k, radius):
    """Bound on the displacement of any point of block i relative to block j since the pair's
    snapshot (i, j = neighbours.pairs[k]), m:

        |dx_i - dx_j - (Q_j - 1)(c_i0 - c_j0)| + theta_ij max(r_i, r_j)

    with Q the rotations since the snapshot and theta_ij the angle of Q_i Q_j^T. Blocks moving
    together as one rigid body give zero.
    """
    i, j = neighbours.pairs[k, 0], neighbours.pairs[k, 1]
    ci0, cj0 = neighbours.position[k, 0], neighbours.position[k, 1]
    wi, xi, yi, zi = _relative_quaternion(state.quaternion[i], neighbours.quaternion[k, 0])
    w, ux, uy, uz = _relative_quaternion(state.quaternion[j], neighbours.quaternion[k, 1])
    # (Q_j - 1) v with v = c_i0 - c_j0, by v' = v + 2 w (u x v) + 2 u x (u x v)
    vx, vy, vz = ci0[0] - cj0[0], ci0[1] - cj0[1], ci0[2] - cj0[2]
    cx, cy, cz = uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx
    qx = 2.0 * w * cx + 2.0 * (uy * cz - uz * cy)
    qy = 2.0 * w * cy + 2.0 * (uz * cx - ux * cz)
    qz = 2.0 * w * cz + 2.0 * (ux * cy - uy * cx)
    dx = state.position[i, 0] - ci0[0] - state.position[j, 0] + cj0[0] - qx
    dy = state.position[i, 1] - ci0[1] - state.position[j, 1] + cj0[1] - qy
    dz = state.position[i, 2] - ci0[2] - state.position[j, 2] + cj0[2] - qz
    cos_half = abs(wi * w + xi * ux + yi * uy + zi * uz)
    return np.sqrt(dx * dx + dy * dy + dz * dz) + _angle_bound(cos_half) * max(radius[i], radius[j])


@numba.njit(cache=True)
def pair_motions(state, neighbours, radius, out):
    """:func:`_pair_motion` of every neighbour pair into ``out`` (nn,), m."""
    for k in range(neighbours.pairs.shape[0]):
        out[k] = _pair_motion(state, neighbours, k, radius)


@numba.njit(cache=True)
def detection_slack(state, broad_state, neighbours, radius, absolute_limit, slack):
    """How far (m) each block's points may still move before a re-detection may be needed, into
    ``slack`` (nb,); returns the smallest: <= 0, re-detect now (a Verlet-list test).

    Absolute: a block point moved more than ``absolute_limit`` (|dx| + theta r) since the
    State ``broad_state`` of the last broad phase, so a block outside the neighbour list may
    have come close. Relative: a neighbour pair moved more than its ``neighbours.limit``
    relative to each other since its snapshot (:func:`_pair_motion`), so its contact may have
    changed; half of what is left goes to each of its blocks. Angles are bounded by
    2 tan(theta / 2).
    """
    for i in range(state.position.shape[0]):
        w, _, _, _ = _relative_quaternion(state.quaternion[i], broad_state.quaternion[i])
        d = state.position[i] - broad_state.position[i]
        slack[i] = absolute_limit - np.sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]) - _angle_bound(abs(w)) * radius[i]
    for k in range(neighbours.pairs.shape[0]):
        left = 0.5 * (neighbours.limit[k] - _pair_motion(state, neighbours, k, radius))
        i, j = neighbours.pairs[k, 0], neighbours.pairs[k, 1]
        slack[i] = min(slack[i], left)
        slack[j] = min(slack[j], left)
    return slack.min() if slack.shape[0] else np.inf


@numba.njit(cache=True)
def accumulate_motion(state, lever, dt, moved, slack):
    """Add to ``moved`` (nb,) a bound on how far each block's points moved this cycle, m, and
    say whether one has used up its ``slack`` (:func:`detection_slack`).

    The bound, 1.25 (|v|_1 + |omega|_1 lever) dt with lever = 4 r_max, covers what one cycle adds
    to :func:`_pair_motion` from either of the pair's blocks: the translation, the turn of the
    centroid offset (at most 2 r_max plus the neighbour margin) and the relative angle times
    max(r_i, r_j); the 1.25 covers the angle bound 2 tan(theta / 2), and L1 norms bound the
    Euclidean ones without square roots. A block far from the others uses up only its own slack.
    """
    used_up = False
    for i in range(moved.shape[0]):
        v, w = state.velocity[i], state.angular_velocity[i]
        moved[i] += 1.25 * (abs(v[0]) + abs(v[1]) + abs(v[2]) + (abs(w[0]) + abs(w[1]) + abs(w[2])) * lever) * dt
        used_up |= moved[i] >= slack[i]
    return used_up


class Workspace(NamedTuple):
    """The scratch arrays of a compiled cycle that runs on several threads, made once per call of
    ``run_cycles`` (:func:`workspace`): the contacts change only between calls.

    incidence_start (nb + 1,), incidence (2 nc,) int64: each block's contacts in increasing order,
    CSR-style (those of block i are ``incidence[incidence_start[i]:incidence_start[i + 1]]``), each
    as 2 c + 1 where the block is contact c's incident block b, 2 c where it is its reference
    block a. contribution (nc, width): what each contact adds to its blocks (the kernel's layout).
    stiffer (nc,) bool: a contact's stress-dependent joint about to outgrow the timestep.
    measures (nb, 3): each block's unbalanced force and unbalanced moment / radius (N; squared,
    N2, in the planar kernel) and point speed (m/s), speed -1 for a block that does not move:
    their maxima are taken after the parallel loop, in block order.
    """

    incidence_start: np.ndarray
    incidence: np.ndarray
    contribution: np.ndarray
    stiffer: np.ndarray
    measures: np.ndarray


@numba.njit(cache=True)
def block_incidence(pairs, nb):
    """Each of ``nb`` blocks' contacts (``pairs`` (nc, 2): reference, incident block), in increasing
    order: (start (nb + 1,), entries (2 nc,)) as :class:`Workspace` ``incidence``; a counting sort."""
    nc = pairs.shape[0]
    start = np.zeros(nb + 1, np.int64)
    for c in range(nc):
        start[pairs[c, 0] + 1] += 1
        start[pairs[c, 1] + 1] += 1
    for i in range(nb):
        start[i + 1] += start[i]
    fill = start[:nb].copy()
    entries = np.empty(2 * nc, np.int64)
    for c in range(nc):
        a, b = pairs[c, 0], pairs[c, 1]
        entries[fill[a]] = 2 * c
        fill[a] += 1
        entries[fill[b]] = 2 * c + 1
        fill[b] += 1
    return start, entries


@numba.njit(cache=True)
def workspace(pairs, nb, width):
    """A :class:`Workspace` for the contacts ``pairs`` (nc, 2) of ``nb`` blocks, ``width`` numbers per contact."""
    start, entries = block_incidence(pairs, nb)
    nc = pairs.shape[0]
    return Workspace(start, entries, np.empty((nc, width)), np.zeros(nc, np.bool_), np.empty((nb, 3)))


@numba.njit(cache=True)
def block_maxima(measures):
    """The largest unbalanced measure (columns 0 and 1: force and moment / radius, or their
    squares) and the largest speed (column 2) of the moving blocks (speed >= 0) in a
    :class:`Workspace`'s ``measures``, in block order: serial, so that a NaN goes through ``max``
    exactly as it did in the serial kernels."""
    max_unbalanced = 0.0
    max_speed = 0.0
    for i in range(measures.shape[0]):
        if measures[i, 2] < 0.0:  # not moving
            continue
        max_speed = max(max_speed, measures[i, 2])
        max_unbalanced = max(max_unbalanced, measures[i, 0], measures[i, 1])
    return max_unbalanced, max_speed


class LoopSettings(NamedTuple):
    """What one call of a kernel's ``run_cycles`` is to do (:func:`cycle_loop`).

    gravity : (3,) m/s2. dt : timestep, s. damping : a :class:`~drydem.engine.damping.Damping`.
    max_cycles : cycles at most. criterion, limit : RATIO (max unbalanced force / force_scale <
    limit) or VELOCITY (max block point speed < limit, m/s). force_scale : N. energy_slack_j :
    J, of the divergence test. absolute_limit : m, of :func:`detection_slack`.
    ground_acceleration : (n, 3) m/s2, the table's acceleration a_g at each cycle (the body
    force of cycle k is m (g - a_g[k]): the blocks move in the frame of the table; the call
    ends after n cycles if n < max_cycles), or (0, 3) for a table at rest. closure_limit : (ns,)
    m, the closure of each sub-contact up to which ``dt`` is stable
    (:func:`drydem.engine.inertia.stiffness_bound`), or (0,) for a joint of constant stiffness.
    first_velocity_dt : s, the velocity step of the call's first cycle: (dt_old + dt) / 2 right
    after the timestep changed from dt_old (variable-step leapfrog: v(t + dt/2) = v(t - dt_old/2)
    + a(t) (dt_old + dt) / 2, second order; a plain dt there is a first-order error that a stiff
    impact turns into energy), else dt.
    """

    gravity: np.ndarray
    dt: float
    damping: Damping
    max_cycles: int
    criterion: int
    limit: float
    force_scale: float
    energy_slack_j: float
    absolute_limit: float
    ground_acceleration: np.ndarray
    closure_limit: np.ndarray
    first_velocity_dt: float


@numba.njit(cache=True, inline="always")
def cycle_loop(step_function, state, blocks, sub, joint, loop, broad_state, neighbours, work=None):
    """The cycling loop around ``step_function`` (a kernel's ``step``), shared by every engine,
    with the :class:`LoopSettings` ``loop``; a compiled kernel passes its :class:`Workspace`
    ``work`` (made once per call: the contacts do not change within it) on to its step.

    It cycles until converged, re-detection needed, diverged, a stress-dependent joint about to
    outgrow the timestep (the step says so) or ``loop.max_cycles``, and returns
    (cycles run, exit code, unbalanced-force ratio and max point speed of the last cycle) as
    plain numbers: boxing a NamedTuple on return calls Python, and a pending Ctrl-C raised
    there crashes numba. ``broad_state`` and ``neighbours`` go to :func:`detection_slack`, which
    runs only once a block may have used up its slack (:func:`accumulate_motion`).

    A shaking table (``loop.ground_acceleration``) adds the inertial body force -m a_g of the
    table's frame, cycle by cycle: for a rigid table translating without turning this is exact,
    and the blocks' positions and velocities are those relative to the table.

    Divergence: a NaN, or more kinetic energy than the body forces can have supplied. Damping
    only removes energy, so the kinetic energy stays below their work, at most
    g_max sum m |x - x_origin| (x_origin where the cycling started) with g_max = |g| + max |a_g|;
    above DIVERGENCE_FACTOR times that plus ``energy_slack_j`` (J: the energy the cycling started
    with, the settling at the start, the farthest travel so far and the table's work:
    :meth:`drydem.engine.simulation.Simulation._energy_slack_j`) the integration has blown up.
    A block falling freely for any time does not trigger it. The energies are measured every ENERGY_CHECK_EVERY cycles
    (they cost a third of the motion update); a blow-up takes far longer to matter.

    Each compiled kernel has a cached ``run_cycles`` of its own into which this loop is inlined
    with its ``step``: a numba function passed as an argument is a new type in every process,
    so a loop compiled for it (or a closure over it) would never be served from numba's cache
    and would cost seconds at every start. :mod:`oracles.cycle` runs its Python form.
    """
    gravity, dt, damping, criterion, limit = loop.gravity, loop.dt, loop.damping, loop.criterion, loop.limit
    nb = state.position.shape[0]
    rot = np.empty((nb, 3, 3))
    force = np.empty((nb, 3))
    moment = np.empty((nb, 3))
    ratio, speed = np.inf, np.inf
    ground = loop.ground_acceleration
    shaking = ground.shape[0] > 0
    body = gravity.copy()
    g = np.sqrt(gravity[0] ** 2 + gravity[1] ** 2 + gravity[2] ** 2)
    max_cycles = loop.max_cycles
    if shaking:
        g += np.sqrt((ground * ground).sum(axis=1)).max()
        max_cycles = min(max_cycles, ground.shape[0])  # never read past the series
    lever = 4.0 * blocks.radius.max()
    slack = np.full(nb, -1.0)  # unknown: look at the first cycle
    moved = np.zeros(nb)
    for cycle in range(max_cycles):
        measure = cycle % ENERGY_CHECK_EVERY == 0
        if shaking:
            for k in range(3):
                body[k] = gravity[k] - ground[cycle, k]
        velocity_dt = loop.first_velocity_dt if cycle == 0 else dt
        unbalanced, speed, kinetic, travel, stiffer = step_function(state, blocks, sub, joint, loop.closure_limit, body, dt, velocity_dt,
                                                                    damping, rot, force, moment, measure, work)
        ratio = unbalanced / loop.force_scale
        if not (speed < np.inf and (not measure or kinetic <= DIVERGENCE_FACTOR * (g * travel + loop.energy_slack_j))):
            return cycle + 1, DIVERGED, ratio, speed
        if (criterion == RATIO and ratio < limit) or (criterion == VELOCITY and speed < limit):
            return cycle + 1, CONVERGED, ratio, speed
        if stiffer:
            return cycle + 1, STIFFENED, ratio, speed
        if accumulate_motion(state, lever, dt, moved, slack):
            moved[:] = 0.0
            if detection_slack(state, broad_state, neighbours, blocks.radius, loop.absolute_limit, slack) <= 0.0:
                return cycle + 1, REDETECT, ratio, speed
    return max_cycles, RUNNING, ratio, speed


compiled_cache.check(__name__)  # last: none of the functions above is loaded from a stale cache
