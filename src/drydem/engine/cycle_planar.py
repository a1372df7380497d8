"""The explicit cycle of in-plane models, compiled: 3 degrees of freedom per block.

An in-plane model (:attr:`drydem.model.assembly.Model.in_plane`, the paper's walls: blocks held in y,
prisms across y symmetric about one plane) moves in the x-z plane: every force lies in it and
every rotation is about y. Its blocks' quaternions stay (cos phi/2, 0, sin phi/2, 0), so

    R = [[c, 0, s], [0, 1, 0], [-s, 0, c]],   c = 1 - 2 q_y^2,  s = 2 q_w q_y,

angular velocities are omega (0, w, 0), the world inertia about y is the body's I_yy (a
y-prism has no products of inertia with y), and the gyroscopic term omega x I omega vanishes.
The cycle is :mod:`drydem.engine.cycle3d`' one (same joint law, damping, exact rotation update,
equilibrium and re-detection loop) with those simplifications: about half its cost per
sub-contact, a fifth per cycle with one point across the width (benchmarks/bench_step.py).
It reads and writes the same :class:`~drydem.model.state.State` and :class:`~drydem.engine.contacts.SubContacts`
(shear forces as vectors with y = 0), so everything else (detection, snapshots, output) is
shared; the 3D kernel is its oracle in the tests. Like it, it runs on numba's threads, with the
same numbers, bit for bit, on any count (:mod:`drydem.engine.threads`).
"""

from __future__ import annotations

import numba
import numpy as np

from drydem import compiled_cache
from drydem.engine.damping import dashpot_force, dashpot_per_area, has_dashpots, local_damping
from drydem.engine.joints import normal_law, shear_law, stiffer_than_timestep, touch_slack
from drydem.engine.loop import FASTMATH, block_maxima, cycle_loop, workspace
from drydem.model.rotation import rotate_about_y

#: below this turn of a contact normal in one cycle (rad), 1 / cos t = 1 + t^2 / 2 + 5 t^4 / 24 and
#: tan^2 t = t^2 + 2 t^4 / 3 (the next terms, 61 t^6 / 720 and 17 t^6 / 45, are below 1e-18)
TURN_SERIES = 1e-3
#: a shear force lay along the last tangent when its squared normal part is that of the turn to
#: this fraction of its squared tangential part (the round-off of both is ~1e-16)
ALIGNED = 1e-14


@numba.njit(cache=True, inline="always")
def _cos_sin(q):
    """cos and sin of the rotation angle about y of the quaternion q = (w, 0, y, 0)."""
    return 1.0 - 2.0 * q[2] * q[2], 2.0 * q[0] * q[2]


#: numbers per contact in :class:`~drydem.engine.loop.Workspace` ``contribution``: its force sums
#: on the incident block b (F_x, F_z), its moment about y on b (sum r x F), and the moment taken
#: from a, (d x F + sum r x F)_y
CONTRIBUTION = 4


@numba.njit(cache=True, fastmath=FASTMATH, parallel=True)
def contact_forces(state, inv_mass, sub, joint, closure_limit, damping, dt, contribution, stiffer):
    """Every sub-contact's forces (as :func:`drydem.engine.cycle3d.contact_forces`, in parallel over
    the contacts), in the x-z plane: each contact's sums into its row of ``contribution``
    (nc, CONTRIBUTION), N and N m about y (:func:`gather` adds them to the blocks). A point's arm r = R_b p and the centroid offset d give the gap
    (d + r) . n - offset and the relative velocity v_b - v_a - w_a x d + (w_b - w_a) x r, with
    w x r = w (r_z, 0, -r_x); the moment about y of F at r is r_z F_x - r_x F_z.

    The previous shear force F_s is turned into the current tangent t = (n_z, -n_x) with its
    magnitude kept, as in the 3D kernel. The normal, fixed in the reference block a, has turned
    since the last cycle by a's last rotation w_a dt; F_s lay along the tangent then, so
    (F_s . t) / cos(w_a dt) is its signed magnitude: no square root per sub-contact (1 / cos
    and tan^2 by their series below TURN_SERIES rad, exact to round-off there). Where F_s did
    not lie along the last tangent (after a re-detection or a predictor move), which
    (F_s . n)^2 = (F_s . t)^2 tan^2(w_a dt) tells to round-off, the magnitude is
    sqrt((F_s . t)^2 + (F_s . n)^2). Viscous ``damping`` and what it returns: as in the 3D kernel."""
    # every array read off its NamedTuple out here (numba's parallel loops lose what is written into
    # a NamedTuple's array in their bodies: :func:`drydem.engine.cycle3d.contact_forces`)
    pos, vel, omega, quat = state.position, state.velocity, state.angular_velocity, state.quaternion
    point, area, intact, shear, normal = sub.point_inc_body, sub.area, sub.intact, sub.shear_force, sub.normal_force
    pairs, start, normal_body, offset = sub.pairs, sub.start, sub.normal_body, sub.offset
    viscous = has_dashpots(damping)
    for c in numba.prange(pairs.shape[0]):
        a, b = pairs[c, 0], pairs[c, 1]
        dashpot = dashpot_per_area(start[c], start[c + 1], area, inv_mass[a], inv_mass[b], joint.kn, damping) if viscous else 0.0
        ca, sa = _cos_sin(quat[a])
        cb, sb = _cos_sin(quat[b])
        nbx, nbz = normal_body[c, 0], normal_body[c, 2]
        nx, nz = ca * nbx + sa * nbz, ca * nbz - sa * nbx
        dx, dz = pos[b, 0] - pos[a, 0], pos[b, 2] - pos[a, 2]
        base_gap = dx * nx + dz * nz - offset[c]
        slack = touch_slack(dx, 0.0, dz, offset[c])
        wa = omega[a, 1]
        dw = omega[b, 1] - wa
        v0x = vel[b, 0] - vel[a, 0] - wa * dz
        v0z = vel[b, 2] - vel[a, 2] + wa * dx
        turn_sq = (wa * dt) ** 2
        if turn_sq < TURN_SERIES * TURN_SERIES:
            secant = 1.0 + turn_sq * (0.5 + turn_sq * (5.0 / 24.0))
            tangent_sq = turn_sq * (1.0 + turn_sq * (2.0 / 3.0))
        else:
            secant = 1.0 / np.cos(wa * dt)
            tangent_sq = secant * secant - 1.0
        fx_sum = fz_sum = my_sum = 0.0
        closing = False
        for s in range(start[c], start[c + 1]):
            rx, rz = cb * point[s, 0] + sb * point[s, 2], cb * point[s, 2] - sb * point[s, 0]
            closure = -(base_gap + rx * nx + rz * nz)
            fn, carries = normal_law(closure, area[s], intact[s], joint, slack)
            if not carries:
                normal[s] = 0.0
                shear[s, 0] = shear[s, 2] = 0.0
                intact[s] = False
                continue
            closing |= stiffer_than_timestep(closure, (v0x + dw * rz) * nx + (v0z - dw * rx) * nz, dt, closure_limit, s, joint)
            # tangential displacement and previous shear force along t = (n_z, -n_x)
            du = ((v0x + dw * rz) * nz - (v0z - dw * rx) * nx) * dt
            along, across = shear[s, 0] * nz - shear[s, 2] * nx, shear[s, 0] * nx + shear[s, 2] * nz
            if abs(across * across - along * along * tangent_sq) <= ALIGNED * along * along:
                along *= secant
            else:
                magnitude = np.sqrt(along * along + across * across)
                along = magnitude if along > 0.0 else -magnitude if along < 0.0 else 0.0
            sx, _, sz, intact[s] = shear_law(fn, du * nz, 0.0, -du * nx, along * nz, 0.0, -along * nx, area[s], intact[s], joint)
            normal[s] = fn
            shear[s, 0], shear[s, 2] = sx, sz
            if viscous:
                fn += dashpot_force(fn, (v0x + dw * rz) * nx + (v0z - dw * rx) * nz, dashpot * area[s])
            fx, fz = fn * nx + sx, fn * nz + sz
            fx_sum += fx
            fz_sum += fz
            my_sum += rz * fx - rx * fz
        out = contribution[c]
        out[0], out[1], out[2] = fx_sum, fz_sum, my_sum
        out[3] = dz * fx_sum - dx * fz_sum + my_sum
        stiffer[c] = closing
    return stiffer.any()


@numba.njit(cache=True)
def gather(i, mass, gravity, work, force, moment):
    """Block i's force in x and z and moment about y (N, N m): its body force plus its contacts'
    sums, added in increasing contact order, as :func:`drydem.engine.cycle3d.gather` (not fast-math,
    and called, not inlined, from the fast-math :func:`integrate`: the order is the result)."""
    fx, fz, my = mass * gravity[0], mass * gravity[2], 0.0
    contribution, incidence = work.contribution, work.incidence
    for e in range(work.incidence_start[i], work.incidence_start[i + 1]):
        code = incidence[e]
        q = contribution[code >> 1]
        if code & 1:  # the incident block b
            fx += q[0]
            fz += q[1]
            my += q[2]
        else:  # the reference block a
            fx -= q[0]
            fz -= q[1]
            my -= q[3]
    force[i, 0], force[i, 2], moment[i, 1] = fx, fz, my


@numba.njit(cache=True, fastmath=FASTMATH, parallel=True)
def integrate(state, blocks, force, moment, damping, dt, velocity_dt, gravity, work):
    """Each block's forces (:func:`gather`), damped velocities, positions and rotations of x, z and
    the rotation about y, in parallel over the blocks (as :func:`drydem.engine.cycle3d.integrate`,
    which returns the same two measures; the velocities step by ``velocity_dt``, the positions by
    ``dt``)."""
    local, drag = damping.local, damping.mass_proportional
    measures = work.measures
    position, velocity, omega, quaternion = state.position, state.velocity, state.angular_velocity, state.quaternion
    inv_mass, free, inv_inertia, radius = blocks.inv_mass, blocks.free, blocks.inv_inertia_body, blocks.radius
    for i in numba.prange(position.shape[0]):
        gather(i, blocks.mass[i], gravity, work, force, moment)
        if inv_mass[i] == 0.0:
            measures[i, 2] = -1.0
            continue
        free_x, free_z, free_ry = free[i, 0], free[i, 2], free[i, 4]
        v, p = velocity[i], position[i]
        fx, fz, my = force[i, 0] * free_x, force[i, 2] * free_z, moment[i, 1] * free_ry
        w = omega[i, 1]
        if drag != 0.0:  # Rayleigh's mass term, explicit: a branch, so that statics round as before it
            v[0], v[2], w = v[0] * (1.0 - drag * velocity_dt), v[2] * (1.0 - drag * velocity_dt), w * (1.0 - drag * velocity_dt)
        v[0] = (v[0] + local_damping(fx, v[0], local) * inv_mass[i] * velocity_dt) * free_x
        v[2] = (v[2] + local_damping(fz, v[2], local) * inv_mass[i] * velocity_dt) * free_z
        w += local_damping(my, w, local) * inv_inertia[i, 1, 1] * velocity_dt * free_ry
        omega[i, 1] = w
        p[0] += v[0] * dt
        p[2] += v[2] * dt
        rotate_about_y(quaternion[i], w * dt)
        speed = np.sqrt(v[0] * v[0] + v[2] * v[2]) + abs(w) * radius[i]
        if not speed < np.inf:  # NaN counts as infinitely fast
            speed = np.inf
        arm_moment = my / radius[i]
        measures[i, 0] = fx * fx + fz * fz
        measures[i, 1] = arm_moment * arm_moment
        measures[i, 2] = speed
    unbalanced_sq, speed = block_maxima(measures)
    return np.sqrt(unbalanced_sq), speed


@numba.njit(cache=True)
def energies(state, blocks):
    """:func:`drydem.engine.cycle3d.energies` in the plane: 1/2 (m v^2 + I_yy w^2) and sum m |x - x_origin|."""
    kinetic = 0.0
    travel = 0.0
    for i in range(state.position.shape[0]):
        if blocks.inv_mass[i] == 0.0:
            continue
        v, p, o, w = state.velocity[i], state.position[i], blocks.origin[i], state.angular_velocity[i, 1]
        kinetic += 0.5 * ((v[0] * v[0] + v[2] * v[2]) / blocks.inv_mass[i] + blocks.inertia_body[i, 1, 1] * w * w)
        travel += blocks.mass[i] * np.sqrt((p[0] - o[0]) ** 2 + (p[1] - o[1]) ** 2 + (p[2] - o[2]) ** 2)
    return kinetic, travel


@numba.njit(cache=True)
def step(state, blocks, sub, joint, closure_limit, gravity, dt, velocity_dt, damping, rot, force, moment, measure, work=None):
    """One cycle of an in-plane model (``rot`` unused: the signature is
    :func:`drydem.engine.cycle3d.step`'s, so that both share the cycling loop; ``work`` the
    :class:`~drydem.engine.loop.Workspace` of ``sub``, made here where not given). Every thread
    count gives the same numbers, bit for bit."""
    if work is None:
        scratch = workspace(sub.pairs, state.position.shape[0], CONTRIBUTION)
    else:
        scratch = work
    stiffer = contact_forces(state, blocks.inv_mass, sub, joint, closure_limit, damping, dt, scratch.contribution, scratch.stiffer)
    unbalanced, speed = integrate(state, blocks, force, moment, damping, dt, velocity_dt, gravity, scratch)
    kinetic, travel = energies(state, blocks) if measure else (0.0, 0.0)
    return unbalanced, speed, kinetic, travel, stiffer


@numba.njit(cache=True)
def run_cycles(state, blocks, sub, joint, loop, broad_state, neighbours):
    """:func:`drydem.engine.loop.cycle_loop` around the planar :func:`step`, with one
    :class:`~drydem.engine.loop.Workspace` for the call."""
    work = workspace(sub.pairs, state.position.shape[0], CONTRIBUTION)
    return cycle_loop(step, state, blocks, sub, joint, loop, broad_state, neighbours, work)


compiled_cache.check(__name__)  # last: none of the functions above is loaded from a stale cache
