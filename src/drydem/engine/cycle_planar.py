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
shared; the 3D kernel is its oracle in the tests.
"""

from __future__ import annotations

import numba
import numpy as np

from drydem.engine.damping import dashpot_force, dashpot_per_area, has_dashpots, local_damping
from drydem.engine.joints import normal_law, shear_law, stiffer_than_timestep
from drydem.engine.loop import FASTMATH, cycle_loop
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


@numba.njit(cache=True, fastmath=FASTMATH)
def contact_forces(state, inv_mass, sub, joint, closure_limit, damping, dt, force, moment):
    """Every sub-contact's forces (as :func:`drydem.engine.cycle3d.contact_forces`), in the x-z plane:
    forces summed into ``force[:, 0]``, ``force[:, 2]`` (N) and moments about y into
    ``moment[:, 1]`` (N m). A point's arm r = R_b p and the centroid offset d give the gap
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
    pos, vel, omega, quat = state.position, state.velocity, state.angular_velocity, state.quaternion
    point, area, intact, shear, normal = sub.point_inc_body, sub.area, sub.intact, sub.shear_force, sub.normal_force
    viscous = has_dashpots(damping)
    stiffer = False
    for c in range(sub.pairs.shape[0]):
        a, b = sub.pairs[c, 0], sub.pairs[c, 1]
        dashpot = dashpot_per_area(sub.start[c], sub.start[c + 1], area, inv_mass[a], inv_mass[b], joint.kn, damping) if viscous else 0.0
        ca, sa = _cos_sin(quat[a])
        cb, sb = _cos_sin(quat[b])
        nbx, nbz = sub.normal_body[c, 0], sub.normal_body[c, 2]
        nx, nz = ca * nbx + sa * nbz, ca * nbz - sa * nbx
        dx, dz = pos[b, 0] - pos[a, 0], pos[b, 2] - pos[a, 2]
        base_gap = dx * nx + dz * nz - sub.offset[c]
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
        for s in range(sub.start[c], sub.start[c + 1]):
            rx, rz = cb * point[s, 0] + sb * point[s, 2], cb * point[s, 2] - sb * point[s, 0]
            closure = -(base_gap + rx * nx + rz * nz)
            fn, carries = normal_law(closure, area[s], intact[s], joint)
            if not carries:
                normal[s] = 0.0
                shear[s, 0] = shear[s, 2] = 0.0
                intact[s] = False
                continue
            stiffer |= stiffer_than_timestep(closure, (v0x + dw * rz) * nx + (v0z - dw * rx) * nz, dt, closure_limit, s, joint)
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
        force[b, 0] += fx_sum
        force[b, 2] += fz_sum
        moment[b, 1] += my_sum
        force[a, 0] -= fx_sum
        force[a, 2] -= fz_sum
        moment[a, 1] -= dz * fx_sum - dx * fz_sum + my_sum
    return stiffer


@numba.njit(cache=True, fastmath=FASTMATH)
def integrate(state, blocks, force, moment, damping, dt, velocity_dt):
    """Damped velocities, positions and rotations of x, z and the rotation about y (as
    :func:`drydem.engine.cycle3d.integrate`, which returns the same two measures; the velocities
    step by ``velocity_dt``, the positions by ``dt``)."""
    local, drag = damping.local, damping.mass_proportional
    max_unbalanced_sq = 0.0
    max_speed = 0.0
    for i in range(state.position.shape[0]):
        if blocks.inv_mass[i] == 0.0:
            continue
        free_x, free_z, free_ry = blocks.free[i, 0], blocks.free[i, 2], blocks.free[i, 4]
        v, p = state.velocity[i], state.position[i]
        fx, fz, my = force[i, 0] * free_x, force[i, 2] * free_z, moment[i, 1] * free_ry
        w = state.angular_velocity[i, 1]
        if drag != 0.0:  # Rayleigh's mass term, explicit: a branch, so that statics round as before it
            v[0], v[2], w = v[0] * (1.0 - drag * velocity_dt), v[2] * (1.0 - drag * velocity_dt), w * (1.0 - drag * velocity_dt)
        v[0] = (v[0] + local_damping(fx, v[0], local) * blocks.inv_mass[i] * velocity_dt) * free_x
        v[2] = (v[2] + local_damping(fz, v[2], local) * blocks.inv_mass[i] * velocity_dt) * free_z
        w += local_damping(my, w, local) * blocks.inv_inertia_body[i, 1, 1] * velocity_dt * free_ry
        state.angular_velocity[i, 1] = w
        p[0] += v[0] * dt
        p[2] += v[2] * dt
        rotate_about_y(state.quaternion[i], w * dt)
        speed = np.sqrt(v[0] * v[0] + v[2] * v[2]) + abs(w) * blocks.radius[i]
        if not speed < np.inf:  # NaN counts as infinitely fast
            speed = np.inf
        max_speed = max(max_speed, speed)
        arm_moment = my / blocks.radius[i]
        max_unbalanced_sq = max(max_unbalanced_sq, fx * fx + fz * fz, arm_moment * arm_moment)
    return np.sqrt(max_unbalanced_sq), max_speed


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
def step(state, blocks, sub, joint, closure_limit, gravity, dt, velocity_dt, damping, rot, force, moment, measure):
    """One cycle of an in-plane model (``rot`` unused: the signature is
    :func:`drydem.engine.cycle3d.step`'s, so that both share the cycling loop)."""
    for i in range(state.position.shape[0]):
        force[i, 0] = blocks.mass[i] * gravity[0]
        force[i, 2] = blocks.mass[i] * gravity[2]
        moment[i, 1] = 0.0
    stiffer = contact_forces(state, blocks.inv_mass, sub, joint, closure_limit, damping, dt, force, moment)
    unbalanced, speed = integrate(state, blocks, force, moment, damping, dt, velocity_dt)
    kinetic, travel = energies(state, blocks) if measure else (0.0, 0.0)
    return unbalanced, speed, kinetic, travel, stiffer


@numba.njit(cache=True)
def run_cycles(state, blocks, sub, joint, loop, broad_state, neighbours):
    """:func:`drydem.engine.loop.cycle_loop` around the planar :func:`step`."""
    return cycle_loop(step, state, blocks, sub, joint, loop, broad_state, neighbours)
