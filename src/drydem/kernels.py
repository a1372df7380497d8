"""The explicit cycle, compiled with numba.

One cycle (paper Eq. 2 and 4; Itasca 3DEC's calculation cycle) reads like the physics:

1. rotation matrices of the blocks at time t;
2. body forces: gravity m g at every centroid;
3. sub-contact kinematics (gap, shear increment over the last step from v(t - dt/2))
   and the joint law -> forces on both blocks, applied at the incident material point;
4. per degree of freedom: local damping, velocity v(t + dt/2) = v(t - dt/2) + F_d / m dt,
   angular velocity in the world frame with the gyroscopic term
   I_w d(omega)/dt = M_d - omega x I_w omega (I_w = R I_body R^T);
5. positions x(t + dt) = x(t) + v dt and exact rotations q <- exp(omega dt / 2) q.

``run_cycles`` repeats it until the equilibrium criterion holds, the blocks have moved
far enough to need new contacts, the integration diverges, or ``max_cycles`` is reached.
:mod:`drydem.reference` implements the same ``step`` in vectorised NumPy, as the oracle
the tests hold this one to, and shares the loop (:func:`cycle_loop`).
"""

from __future__ import annotations

from typing import NamedTuple

import numba
import numpy as np

from drydem.joints import normal_law, shear_law
from drydem.motion import local_damping
from drydem.rotation import mat_t_vec, mat_vec, quaternion_to_matrix, rotate_by_vector

#: kinetic energy above this many times the work gravity can have done means a blow-up
DIVERGENCE_FACTOR = 10.0
#: the energy test of divergence runs every this many cycles (a NaN is caught at every cycle)
ENERGY_CHECK_EVERY = 16
#: run_cycles exit codes
RUNNING, CONVERGED, REDETECT, DIVERGED = 0, 1, 2, 3
#: criterion codes
RATIO, VELOCITY = 0, 1
#: LLVM fast-math flags for the contact loop: reassociation and fused multiply-add, but
#: NaN and infinity keep their meaning (the divergence guard relies on them)
FASTMATH = {"contract", "reassoc", "arcp", "nsz"}


@numba.njit(cache=True, inline="always")
def _world_tensor_apply(r, tensor, v0, v1, v2):
    """R T R^T v: a body-frame tensor ``tensor`` (inertia or its inverse) applied in the world frame."""
    b0, b1, b2 = mat_t_vec(r, v0, v1, v2)
    t0, t1, t2 = mat_vec(tensor, b0, b1, b2)
    return mat_vec(r, t0, t1, t2)


@numba.njit(cache=True, fastmath=FASTMATH)
def contact_forces(state, rot, sub, joint, dt, force, moment):
    """Step 3: update every sub-contact's forces and add them to ``force`` and ``moment`` (N, N m).

    Per contact (blocks a = reference, b = incident, normal n = R_a n_body, d = vector from
    a's centroid to b's): each sub-contact's incident arm r = R_b p_inc gives
    gap = (d + r) . n - offset (every reference point lies on the plane n . x = offset), and
    relative velocity v_b - v_a - w_a x d + (w_b - w_a) x r. The forces F act at x_b on b
    and -F on a; the contact's sums are scattered once: moment on b sum r x F, on a
    -(d x sum F + sum r x F).
    """
    pos, vel, omega = state.position, state.velocity, state.angular_velocity
    for c in range(sub.pairs.shape[0]):
        a, b = sub.pairs[c, 0], sub.pairs[c, 1]
        nx, ny, nz = mat_vec(rot[a], sub.normal_body[c, 0], sub.normal_body[c, 1], sub.normal_body[c, 2])
        dx, dy, dz = pos[b, 0] - pos[a, 0], pos[b, 1] - pos[a, 1], pos[b, 2] - pos[a, 2]
        base_gap = dx * nx + dy * ny + dz * nz - sub.offset[c]
        wa, wb = omega[a], omega[b]
        v0x = vel[b, 0] - vel[a, 0] - (wa[1] * dz - wa[2] * dy)
        v0y = vel[b, 1] - vel[a, 1] - (wa[2] * dx - wa[0] * dz)
        v0z = vel[b, 2] - vel[a, 2] - (wa[0] * dy - wa[1] * dx)
        dwx, dwy, dwz = wb[0] - wa[0], wb[1] - wa[1], wb[2] - wa[2]
        rb = rot[b]
        fx_sum = fy_sum = fz_sum = 0.0
        mx_sum = my_sum = mz_sum = 0.0
        for s in range(sub.start[c], sub.start[c + 1]):
            p = sub.point_inc_body[s]
            rx, ry, rz = mat_vec(rb, p[0], p[1], p[2])
            fn, carries = normal_law(-(base_gap + rx * nx + ry * ny + rz * nz), sub.area[s], sub.intact[s], joint)
            fs = sub.shear_force[s]
            if not carries:
                sub.normal_force[s] = 0.0
                fs[0] = fs[1] = fs[2] = 0.0
                sub.intact[s] = False
                continue
            # relative velocity of b with respect to a at x_b, tangential part times dt
            vx = v0x + dwy * rz - dwz * ry
            vy = v0y + dwz * rx - dwx * rz
            vz = v0z + dwx * ry - dwy * rx
            vn = vx * nx + vy * ny + vz * nz
            dux, duy, duz = (vx - vn * nx) * dt, (vy - vn * ny) * dt, (vz - vn * nz) * dt
            # previous shear force rotated into the current tangent plane, magnitude kept
            sx, sy, sz = fs[0], fs[1], fs[2]
            fsn = sx * nx + sy * ny + sz * nz
            if fsn != 0.0:
                old_sq = sx * sx + sy * sy + sz * sz
                new_sq = old_sq - fsn * fsn  # |F_s - (F_s . n) n|^2
                scale = np.sqrt(old_sq / new_sq) if new_sq > 0.0 else 0.0
                sx, sy, sz = (sx - fsn * nx) * scale, (sy - fsn * ny) * scale, (sz - fsn * nz) * scale
            sx, sy, sz, intact = shear_law(fn, dux, duy, duz, sx, sy, sz, sub.area[s], sub.intact[s], joint)
            sub.normal_force[s] = fn
            fs[0], fs[1], fs[2] = sx, sy, sz
            sub.intact[s] = intact
            fx, fy, fz = fn * nx + sx, fn * ny + sy, fn * nz + sz
            fx_sum += fx
            fy_sum += fy
            fz_sum += fz
            mx_sum += ry * fz - rz * fy
            my_sum += rz * fx - rx * fz
            mz_sum += rx * fy - ry * fx
        force[b, 0] += fx_sum
        force[b, 1] += fy_sum
        force[b, 2] += fz_sum
        moment[b, 0] += mx_sum
        moment[b, 1] += my_sum
        moment[b, 2] += mz_sum
        force[a, 0] -= fx_sum
        force[a, 1] -= fy_sum
        force[a, 2] -= fz_sum
        moment[a, 0] -= dy * fz_sum - dz * fy_sum + mx_sum
        moment[a, 1] -= dz * fx_sum - dx * fz_sum + my_sum
        moment[a, 2] -= dx * fy_sum - dy * fx_sum + mz_sum


@numba.njit(cache=True)
def integrate(state, rot, blocks, force, moment, damping, dt):
    """Steps 4-5: damped velocities, positions and rotations. Returns (max unbalanced force
    or moment / radius over the free degrees of freedom, N; max block point speed, m/s)."""
    max_unbalanced = 0.0
    max_speed = 0.0
    for i in range(state.position.shape[0]):
        free = blocks.free[i]
        if free.max() == 0.0:
            continue
        r = rot[i]
        f2 = 0.0
        m2 = 0.0
        for k in range(3):
            f = force[i, k] * free[k]
            f2 += f * f
            state.velocity[i, k] += local_damping(f, state.velocity[i, k], damping) * blocks.inv_mass[i] * dt
            m = moment[i, k] * free[3 + k]
            m2 += m * m
            moment[i, k] = local_damping(m, state.angular_velocity[i, k], damping)
        # world inertia I_w = R I_body R^T applied to omega, and the gyroscopic moment omega x I_w omega
        w = state.angular_velocity[i]
        lx, ly, lz = _world_tensor_apply(r, blocks.inertia_body[i], w[0], w[1], w[2])
        tx = moment[i, 0] - (w[1] * lz - w[2] * ly)
        ty = moment[i, 1] - (w[2] * lx - w[0] * lz)
        tz = moment[i, 2] - (w[0] * ly - w[1] * lx)
        ax, ay, az = _world_tensor_apply(r, blocks.inv_inertia_body[i], tx, ty, tz)
        w[0] += ax * dt * free[3]
        w[1] += ay * dt * free[4]
        w[2] += az * dt * free[5]
        for k in range(3):
            state.velocity[i, k] *= free[k]
            state.position[i, k] += state.velocity[i, k] * dt
        rotate_by_vector(state.quaternion[i], w[0] * dt, w[1] * dt, w[2] * dt)
        v = state.velocity[i]
        speed = np.sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]) + np.sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]) * blocks.radius[i]
        if not speed < np.inf:  # NaN counts as infinitely fast
            speed = np.inf
        max_speed = max(max_speed, speed)
        max_unbalanced = max(max_unbalanced, np.sqrt(f2), np.sqrt(m2) / blocks.radius[i])
    return max_unbalanced, max_speed


@numba.njit(cache=True)
def energies(state, rot, blocks):
    """The measures of the divergence test, over the moving blocks: kinetic energy with the
    masses used for the motion, J (rotations with the world inertia R I_body R^T, R from the
    start of the cycle), and sum m |x - x_origin|, kg m. A pass of its own, every
    ENERGY_CHECK_EVERY cycles: inside :func:`integrate`, even a branch never taken cost a third
    of it."""
    kinetic = 0.0
    travel = 0.0
    for i in range(state.position.shape[0]):
        if blocks.free[i].max() == 0.0:
            continue
        v, w, r = state.velocity[i], state.angular_velocity[i], rot[i]
        lx, ly, lz = _world_tensor_apply(r, blocks.inertia_body[i], w[0], w[1], w[2])
        kinetic += 0.5 * (w[0] * lx + w[1] * ly + w[2] * lz + (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]) / blocks.inv_mass[i])
        o, p = blocks.origin[i], state.position[i]
        travel += blocks.mass[i] * np.sqrt((p[0] - o[0]) ** 2 + (p[1] - o[1]) ** 2 + (p[2] - o[2]) ** 2)
    return kinetic, travel


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


@numba.njit(cache=True)
def step(state, blocks, sub, joint, gravity, dt, damping, rot, force, moment, measure):
    """One cycle, steps 1-5 (``rot``, ``force``, ``moment`` are scratch arrays).

    Returns what :func:`integrate` returns (kinetic energy and travel if ``measure``)."""
    for i in range(state.position.shape[0]):
        quaternion_to_matrix(state.quaternion[i], rot[i])
        for k in range(3):
            force[i, k] = blocks.mass[i] * gravity[k]
            moment[i, k] = 0.0
    contact_forces(state, rot, sub, joint, dt, force, moment)
    unbalanced, speed = integrate(state, rot, blocks, force, moment, damping, dt)
    kinetic, travel = energies(state, rot, blocks) if measure else (0.0, 0.0)
    return unbalanced, speed, kinetic, travel


class LoopSettings(NamedTuple):
    """What one call of a kernel's ``run_cycles`` is to do (:func:`cycle_loop`).

    gravity : (3,) m/s2. dt : timestep, s. damping : local damping coefficient. max_cycles :
    cycles at most. criterion, limit : RATIO (max unbalanced force / force_scale < limit) or
    VELOCITY (max block point speed < limit, m/s). force_scale : N. travel_slack : kg m, of the
    divergence test. absolute_limit : m, of :func:`detection_slack`.
    """

    gravity: np.ndarray
    dt: float
    damping: float
    max_cycles: int
    criterion: int
    limit: float
    force_scale: float
    travel_slack: float
    absolute_limit: float


@numba.njit(cache=True, inline="always")
def cycle_loop(step_function, state, blocks, sub, joint, loop, broad_state, neighbours):
    """The cycling loop around ``step_function`` (a kernel's ``step``), shared by every engine,
    with the :class:`LoopSettings` ``loop``.

    It cycles until converged, re-detection needed, diverged or ``loop.max_cycles``, and returns
    (cycles run, exit code, unbalanced-force ratio and max point speed of the last cycle) as
    plain numbers: boxing a NamedTuple on return calls Python, and a pending Ctrl-C raised
    there crashes numba. ``broad_state`` and ``neighbours`` go to :func:`detection_slack`, which
    runs only once a block may have used up its slack (:func:`accumulate_motion`).

    Divergence: a NaN, or more kinetic energy than gravity can have supplied. Damping only
    removes energy, so the kinetic energy stays below the work of gravity, at most
    |g| sum m |x - x_origin|; above DIVERGENCE_FACTOR times that (plus ``travel_slack``, kg m,
    for the settling at the start) the integration has blown up. A block falling freely for
    any time does not trigger it. The energies are measured every ENERGY_CHECK_EVERY cycles
    (they cost a third of the motion update); a blow-up takes far longer to matter.

    Each compiled kernel has a cached ``run_cycles`` of its own into which this loop is inlined
    with its ``step``: a numba function passed as an argument is a new type in every process,
    so a loop compiled for it (or a closure over it) would never be served from numba's cache
    and would cost seconds at every start. :mod:`drydem.reference` runs its Python form.
    """
    gravity, dt, damping, criterion, limit = loop.gravity, loop.dt, loop.damping, loop.criterion, loop.limit
    nb = state.position.shape[0]
    rot = np.empty((nb, 3, 3))
    force = np.empty((nb, 3))
    moment = np.empty((nb, 3))
    ratio, speed = np.inf, np.inf
    g = np.sqrt(gravity[0] ** 2 + gravity[1] ** 2 + gravity[2] ** 2)
    lever = 4.0 * blocks.radius.max()
    slack = np.full(nb, -1.0)  # unknown: look at the first cycle
    moved = np.zeros(nb)
    for cycle in range(loop.max_cycles):
        measure = cycle % ENERGY_CHECK_EVERY == 0
        unbalanced, speed, kinetic, travel = step_function(state, blocks, sub, joint, gravity, dt, damping, rot, force, moment, measure)
        ratio = unbalanced / loop.force_scale
        if not (speed < np.inf and (not measure or kinetic <= DIVERGENCE_FACTOR * g * (travel + loop.travel_slack))):
            return cycle + 1, DIVERGED, ratio, speed
        if (criterion == RATIO and ratio < limit) or (criterion == VELOCITY and speed < limit):
            return cycle + 1, CONVERGED, ratio, speed
        if accumulate_motion(state, lever, dt, moved, slack):
            moved[:] = 0.0
            if detection_slack(state, broad_state, neighbours, blocks.radius, loop.absolute_limit, slack) <= 0.0:
                return cycle + 1, REDETECT, ratio, speed
    return loop.max_cycles, RUNNING, ratio, speed


@numba.njit(cache=True)
def run_cycles(state, blocks, sub, joint, loop, broad_state, neighbours):
    """:func:`cycle_loop` around the 3D :func:`step`."""
    return cycle_loop(step, state, blocks, sub, joint, loop, broad_state, neighbours)
