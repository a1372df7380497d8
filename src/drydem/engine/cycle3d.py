"""The explicit cycle of a 3D model (six degrees of freedom per block), compiled with numba.

One cycle (paper Eq. 2 and 4; Itasca 3DEC's calculation cycle) reads like the physics:

1. rotation matrices of the blocks at time t;
2. body forces: gravity m g at every centroid;
3. sub-contact kinematics (gap, shear increment over the last step from v(t - dt/2))
   and the joint law -> forces on both blocks, applied at the incident material point;
4. per degree of freedom: local damping, velocity v(t + dt/2) = v(t - dt/2) + F_d / m dt,
   angular velocity in the world frame with the gyroscopic term
   I_w d(omega)/dt = M_d - omega x I_w omega (I_w = R I_body R^T);
5. positions x(t + dt) = x(t) + v dt and exact rotations q <- exp(omega dt / 2) q.

Steps 1, 3 and 2 with 4-5 each run in parallel on numba's threads (:mod:`drydem.engine.threads`):
over the blocks, the contacts (each writing its own sums), and the blocks again (each adding its
contacts' sums in contact order, :func:`gather`), so that every thread count gives the serial
loop's numbers, bit for bit.

``run_cycles`` repeats it until the equilibrium criterion holds, the blocks have moved
far enough to need new contacts, the integration diverges, or ``max_cycles`` is reached.
:mod:`oracles.cycle` implements the same ``step`` in vectorised NumPy, as the oracle
the tests hold this one to, and shares the loop (:func:`drydem.engine.loop.cycle_loop`).
"""

from __future__ import annotations

import numba
import numpy as np

from drydem import compiled_cache
from drydem.engine.damping import dashpot_force, dashpot_per_area, has_dashpots, local_damping
from drydem.engine.joints import normal_law, shear_law, stiffer_than_timestep, touch_slack
from drydem.engine.loop import FASTMATH, block_maxima, cycle_loop, workspace
from drydem.model.rotation import mat_t_vec, mat_vec, quaternion_to_matrix, rotate_by_vector



@numba.njit(cache=True, inline="always")
def _world_tensor_apply(r, tensor, v0, v1, v2):
    """R T R^T v: a body-frame tensor ``tensor`` (inertia or its inverse) applied in the world frame."""
    b0, b1, b2 = mat_t_vec(r, v0, v1, v2)
    t0, t1, t2 = mat_vec(tensor, b0, b1, b2)
    return mat_vec(r, t0, t1, t2)


#: numbers per contact in :class:`~drydem.engine.loop.Workspace` ``contribution``: its force and
#: moment sums on the incident block b (F, sum r x F), and d x F + sum r x F, the moment taken from a
CONTRIBUTION = 9


#: below this x, :func:`magnitude_kept` takes 1 + x / 2 + 3 x^2 / 8 (the next term, 5 x^3 / 16,
#: is below 1e-18): a contact turning 1e-3 rad in one cycle
OUT_OF_PLANE_SERIES = 1e-6


@numba.njit(cache=True, inline="always")
def magnitude_kept(out_sq):
    """The factor 1 / sqrt(1 - x) that gives the shear force its magnitude back once its part
    along the new normal is taken out, |F_s| / |F_s - (F_s . n) n|, with x = (F_s . n)^2 / |F_s|^2
    the squared sine of its angle out of the new tangent plane; 0 for x >= 1 (F_s along n).
    By its series below OUT_OF_PLANE_SERIES, to round-off: a division and no square root in the
    common case, where F_s turns by a cycle's rotation (the exact form cost 12 % of the 3D cycle)."""
    if out_sq < OUT_OF_PLANE_SERIES:
        return 1.0 + out_sq * (0.5 + 0.375 * out_sq)
    return 1.0 / np.sqrt(1.0 - out_sq) if out_sq < 1.0 else 0.0


@numba.njit(cache=True, fastmath=FASTMATH, parallel=True)
def contact_forces(state, rot, inv_mass, sub, joint, closure_limit, damping, dt, contribution, stiffer):
    """Step 3: update every sub-contact's forces and write each contact's sums into
    ``contribution`` (nc, CONTRIBUTION), N and N m; in parallel over the contacts, each writing
    only its own rows (:func:`gather`, not this, adds them to the blocks).

    Per contact (blocks a = reference, b = incident, normal n = R_a n_body, d = vector from
    a's centroid to b's): each sub-contact's incident arm r = R_b p_inc gives
    gap = (d + r) . n - offset (every reference point lies on the plane n . x = offset), and
    relative velocity v_b - v_a - w_a x d + (w_b - w_a) x r. The forces F act at x_b on b
    and -F on a; the contact's sums: force sum F and moment sum r x F on b, -sum F and
    -(d x sum F + sum r x F) on a. With viscous ``damping``, a normal dashpot beside each spring
    (:mod:`drydem.engine.damping`, ``inv_mass`` (nb,) 1/kg giving the pairs' reduced masses).
    Returns whether a sub-contact of a stress-dependent joint is about to close past its
    ``closure_limit`` (:func:`drydem.engine.joints.stiffer_than_timestep`), each contact's
    answer in ``stiffer`` (nc,).
    """
    # every array read off its NamedTuple out here: numba's parallel loops lose what is written into
    # sub.normal_force[s] in their bodies (numba issues 5872, 7135, 10338), not into these names
    pos, vel, omega = state.position, state.velocity, state.angular_velocity
    pairs, start, normal_body, offset, point, area = sub.pairs, sub.start, sub.normal_body, sub.offset, sub.point_inc_body, sub.area
    shear, normal, intact_now = sub.shear_force, sub.normal_force, sub.intact
    viscous = has_dashpots(damping)
    for c in numba.prange(pairs.shape[0]):
        a, b = pairs[c, 0], pairs[c, 1]
        dashpot = dashpot_per_area(start[c], start[c + 1], area, inv_mass[a], inv_mass[b], joint.kn, damping) if viscous else 0.0
        nx, ny, nz = mat_vec(rot[a], normal_body[c, 0], normal_body[c, 1], normal_body[c, 2])
        dx, dy, dz = pos[b, 0] - pos[a, 0], pos[b, 1] - pos[a, 1], pos[b, 2] - pos[a, 2]
        base_gap = dx * nx + dy * ny + dz * nz - offset[c]
        slack = touch_slack(dx, dy, dz, offset[c])
        wa, wb = omega[a], omega[b]
        v0x = vel[b, 0] - vel[a, 0] - (wa[1] * dz - wa[2] * dy)
        v0y = vel[b, 1] - vel[a, 1] - (wa[2] * dx - wa[0] * dz)
        v0z = vel[b, 2] - vel[a, 2] - (wa[0] * dy - wa[1] * dx)
        dwx, dwy, dwz = wb[0] - wa[0], wb[1] - wa[1], wb[2] - wa[2]
        rb = rot[b]
        fx_sum = fy_sum = fz_sum = 0.0
        mx_sum = my_sum = mz_sum = 0.0
        closing = False
        for s in range(start[c], start[c + 1]):
            p = point[s]
            rx, ry, rz = mat_vec(rb, p[0], p[1], p[2])
            fn, carries = normal_law(-(base_gap + rx * nx + ry * ny + rz * nz), area[s], intact_now[s], joint, slack)
            fs = shear[s]
            if not carries:
                normal[s] = 0.0
                fs[0] = fs[1] = fs[2] = 0.0
                intact_now[s] = False
                continue
            # relative velocity of b with respect to a at x_b, tangential part times dt
            vx = v0x + dwy * rz - dwz * ry
            vy = v0y + dwz * rx - dwx * rz
            vz = v0z + dwx * ry - dwy * rx
            vn = vx * nx + vy * ny + vz * nz
            closing |= stiffer_than_timestep(-(base_gap + rx * nx + ry * ny + rz * nz), vn, dt, closure_limit, s, joint)
            dux, duy, duz = (vx - vn * nx) * dt, (vy - vn * ny) * dt, (vz - vn * nz) * dt
            # previous shear force rotated into the current tangent plane, magnitude kept
            sx, sy, sz = fs[0], fs[1], fs[2]
            fsn = sx * nx + sy * ny + sz * nz
            if fsn != 0.0:
                scale = magnitude_kept(fsn * fsn / (sx * sx + sy * sy + sz * sz))
                sx, sy, sz = (sx - fsn * nx) * scale, (sy - fsn * ny) * scale, (sz - fsn * nz) * scale
            sx, sy, sz, intact = shear_law(fn, dux, duy, duz, sx, sy, sz, area[s], intact_now[s], joint)
            normal[s] = fn
            fs[0], fs[1], fs[2] = sx, sy, sz
            intact_now[s] = intact
            push = fn + dashpot_force(fn, vn, dashpot * area[s]) if viscous else fn
            fx, fy, fz = push * nx + sx, push * ny + sy, push * nz + sz
            fx_sum += fx
            fy_sum += fy
            fz_sum += fz
            mx_sum += ry * fz - rz * fy
            my_sum += rz * fx - rx * fz
            mz_sum += rx * fy - ry * fx
        out = contribution[c]
        out[0], out[1], out[2] = fx_sum, fy_sum, fz_sum
        out[3], out[4], out[5] = mx_sum, my_sum, mz_sum
        out[6] = dy * fz_sum - dz * fy_sum + mx_sum
        out[7] = dz * fx_sum - dx * fz_sum + my_sum
        out[8] = dx * fy_sum - dy * fx_sum + mz_sum
        stiffer[c] = closing
    return stiffer.any()


@numba.njit(cache=True)
def gather(i, mass, gravity, work, force, moment):
    """Block i's force and moment (N, N m): its body force ``mass`` g plus what its contacts
    contribute (:func:`contact_forces`), added in increasing contact order, as a serial loop over
    the contacts adds them: the same numbers, bit for bit, whatever the threads. Not fast-math:
    the order is the result."""
    f0, f1, f2 = mass * gravity[0], mass * gravity[1], mass * gravity[2]
    m0 = m1 = m2 = 0.0
    contribution, incidence = work.contribution, work.incidence
    for e in range(work.incidence_start[i], work.incidence_start[i + 1]):
        code = incidence[e]
        q = contribution[code >> 1]
        if code & 1:  # the incident block b
            f0 += q[0]
            f1 += q[1]
            f2 += q[2]
            m0 += q[3]
            m1 += q[4]
            m2 += q[5]
        else:  # the reference block a
            f0 -= q[0]
            f1 -= q[1]
            f2 -= q[2]
            m0 -= q[6]
            m1 -= q[7]
            m2 -= q[8]
    force[i, 0], force[i, 1], force[i, 2] = f0, f1, f2
    moment[i, 0], moment[i, 1], moment[i, 2] = m0, m1, m2


@numba.njit(cache=True, parallel=True)
def integrate(state, rot, blocks, force, moment, damping, dt, velocity_dt, gravity, work):
    """Steps 2 and 4-5, in parallel over the blocks: each block's body force and contact forces
    (:func:`gather`, into ``force`` and ``moment``), damped velocities, positions and rotations
    (local damping, and Rayleigh's mass-proportional term -alpha_R m v, -alpha_R I_w omega:
    :mod:`drydem.engine.damping`); the velocities step by ``velocity_dt``
    (:data:`~drydem.engine.loop.LoopSettings`), the positions by ``dt``.
    Returns (max unbalanced force or moment / radius over the free degrees of freedom, N;
    max block point speed, m/s), the maxima taken in block order after the parallel loop."""
    local, drag = damping.local, damping.mass_proportional
    measures = work.measures
    position, velocity, omega, quaternion = state.position, state.velocity, state.angular_velocity, state.quaternion
    for i in numba.prange(position.shape[0]):
        gather(i, blocks.mass[i], gravity, work, force, moment)
        free = blocks.free[i]
        if free.max() == 0.0:
            measures[i, 2] = -1.0
            continue
        r = rot[i]
        f2 = 0.0
        m2 = 0.0
        for k in range(3):
            f = force[i, k] * free[k]
            f2 += f * f
            if drag != 0.0:  # Rayleigh's mass term, explicit: a branch, so that statics round as before it
                velocity[i, k] *= 1.0 - drag * velocity_dt
            velocity[i, k] += local_damping(f, velocity[i, k], local) * blocks.inv_mass[i] * velocity_dt
            m = moment[i, k] * free[3 + k]
            m2 += m * m
            moment[i, k] = local_damping(m, omega[i, k], local)
        # world inertia I_w = R I_body R^T applied to omega, and the gyroscopic moment omega x I_w omega
        w = omega[i]
        lx, ly, lz = _world_tensor_apply(r, blocks.inertia_body[i], w[0], w[1], w[2])
        tx = moment[i, 0] - (w[1] * lz - w[2] * ly)
        ty = moment[i, 1] - (w[2] * lx - w[0] * lz)
        tz = moment[i, 2] - (w[0] * ly - w[1] * lx)
        if drag != 0.0:
            tx, ty, tz = tx - drag * lx, ty - drag * ly, tz - drag * lz
        ax, ay, az = _world_tensor_apply(r, blocks.inv_inertia_body[i], tx, ty, tz)
        w[0] += ax * velocity_dt * free[3]
        w[1] += ay * velocity_dt * free[4]
        w[2] += az * velocity_dt * free[5]
        for k in range(3):
            velocity[i, k] *= free[k]
            position[i, k] += velocity[i, k] * dt
        rotate_by_vector(quaternion[i], w[0] * dt, w[1] * dt, w[2] * dt)
        v = velocity[i]
        speed = np.sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]) + np.sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]) * blocks.radius[i]
        if not speed < np.inf:  # NaN counts as infinitely fast
            speed = np.inf
        measures[i, 0] = np.sqrt(f2)
        measures[i, 1] = np.sqrt(m2) / blocks.radius[i]
        measures[i, 2] = speed
    return block_maxima(measures)


#: below this many blocks :func:`rotations` runs serially: starting a parallel loop costs ~1-2 us,
#: the rotations of ~200 blocks (numba.get_num_threads() is no test here: a function that asks it
#: cannot be cached)
SERIAL_ROTATIONS = 1024


@numba.njit(cache=True, parallel=True)
def rotations(quaternion, rot):
    """Step 1: the rotation matrix of every block, in parallel for many blocks on several threads
    (the same numbers either way: one block's matrix is one strict, not fast-math, computation)."""
    n = quaternion.shape[0]
    if n < SERIAL_ROTATIONS:
        for i in range(n):
            quaternion_to_matrix(quaternion[i], rot[i])
    else:
        for i in numba.prange(n):
            quaternion_to_matrix(quaternion[i], rot[i])


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


@numba.njit(cache=True)
def step(state, blocks, sub, joint, closure_limit, gravity, dt, velocity_dt, damping, rot, force, moment, measure, work=None):
    """One cycle, steps 1-5 (``rot``, ``force``, ``moment`` are scratch arrays; ``work`` the
    :class:`~drydem.engine.loop.Workspace` of ``sub``, made here where not given).

    Returns what :func:`integrate` returns, kinetic energy and travel if ``measure``, and what
    :func:`contact_forces` returns (a stress-dependent joint about to outgrow the timestep).
    Every thread count gives the same numbers, bit for bit: each contact writes its own sums,
    each block adds its contacts' in contact order (:func:`gather`)."""
    if work is None:
        scratch = workspace(sub.pairs, state.position.shape[0], CONTRIBUTION)
    else:
        scratch = work
    rotations(state.quaternion, rot)
    stiffer = contact_forces(state, rot, blocks.inv_mass, sub, joint, closure_limit, damping, dt, scratch.contribution, scratch.stiffer)
    unbalanced, speed = integrate(state, rot, blocks, force, moment, damping, dt, velocity_dt, gravity, scratch)
    kinetic, travel = energies(state, rot, blocks) if measure else (0.0, 0.0)
    return unbalanced, speed, kinetic, travel, stiffer


@numba.njit(cache=True)
def run_cycles(state, blocks, sub, joint, loop, broad_state, neighbours):
    """:func:`cycle_loop` around the 3D :func:`step`, with one :class:`~drydem.engine.loop.Workspace`
    for the call (numba's threads: :mod:`drydem.engine.threads`)."""
    work = workspace(sub.pairs, state.position.shape[0], CONTRIBUTION)
    return cycle_loop(step, state, blocks, sub, joint, loop, broad_state, neighbours, work)


compiled_cache.check(__name__)  # last: none of the functions above is loaded from a stale cache
