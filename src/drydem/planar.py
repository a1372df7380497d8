"""The explicit cycle of in-plane models, compiled: 3 degrees of freedom per block.

An in-plane model (:attr:`drydem.model.Model.in_plane`, the paper's walls: blocks held in y,
prisms across y symmetric about one plane) moves in the x-z plane: every force lies in it and
every rotation is about y. Its blocks' quaternions stay (cos phi/2, 0, sin phi/2, 0), so

    R = [[c, 0, s], [0, 1, 0], [-s, 0, c]],   c = 1 - 2 q_y^2,  s = 2 q_w q_y,

angular velocities are omega (0, w, 0), the world inertia about y is the body's I_yy (a
y-prism has no products of inertia with y), and the gyroscopic term omega x I omega vanishes.
The cycle is :mod:`drydem.kernels`' one (same joint law, damping, exact rotation update,
equilibrium and re-detection loop) with those simplifications: about half its cost per
sub-contact, a quarter per cycle with one point across the width (benchmarks/bench_step.py).
It reads and writes the same :class:`~drydem.state.State` and :class:`~drydem.contacts.SubContacts`
(shear forces as vectors with y = 0), so everything else (detection, snapshots, output) is
shared; the 3D kernel is its oracle in the tests.
"""

from __future__ import annotations

import numba
import numpy as np

from drydem.joints import normal_law, shear_law
from drydem.kernels import FASTMATH, make_run_cycles
from drydem.motion import local_damping
from drydem.rotation import rotate_by_vector


@numba.njit(cache=True, inline="always")
def _cos_sin(q):
    """cos and sin of the rotation angle about y of the quaternion q = (w, 0, y, 0)."""
    return 1.0 - 2.0 * q[2] * q[2], 2.0 * q[0] * q[2]


@numba.njit(cache=True, fastmath=FASTMATH)
def contact_forces(state, sub, joint, dt, force, moment):
    """Every sub-contact's forces (as :func:`drydem.kernels.contact_forces`), in the x-z plane:
    forces summed into ``force[:, 0]``, ``force[:, 2]`` (N) and moments about y into
    ``moment[:, 1]`` (N m). A point's arm r = R_b p and the centroid offset d give the gap
    (d + r) . n - offset and the relative velocity v_b - v_a - w_a x d + (w_b - w_a) x r, with
    w x r = w (r_z, 0, -r_x); the moment about y of F at r is r_z F_x - r_x F_z."""
    pos, vel, omega, quat = state.position, state.velocity, state.angular_velocity, state.quaternion
    for c in range(sub.pairs.shape[0]):
        a, b = sub.pairs[c, 0], sub.pairs[c, 1]
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
        fx_sum = fz_sum = my_sum = 0.0
        for s in range(sub.start[c], sub.start[c + 1]):
            p = sub.point_inc_body[s]
            rx, rz = cb * p[0] + sb * p[2], cb * p[2] - sb * p[0]
            fn, carries = normal_law(-(base_gap + rx * nx + rz * nz), sub.area[s], sub.intact[s], joint)
            fs = sub.shear_force[s]
            if not carries:
                sub.normal_force[s] = 0.0
                fs[0] = fs[2] = 0.0
                sub.intact[s] = False
                continue
            vx = v0x + dw * rz
            vz = v0z - dw * rx
            vn = vx * nx + vz * nz
            dux, duz = (vx - vn * nx) * dt, (vz - vn * nz) * dt
            # previous shear force turned into the current tangent t = (n_z, -n_x), magnitude kept
            sx, sz = fs[0], fs[2]
            if sx * nx + sz * nz != 0.0:
                along = sx * nz - sz * nx
                magnitude = np.sqrt(sx * sx + sz * sz) if along > 0.0 else -np.sqrt(sx * sx + sz * sz) if along < 0.0 else 0.0
                sx, sz = magnitude * nz, -magnitude * nx
            sx, _, sz, intact = shear_law(fn, dux, 0.0, duz, sx, 0.0, sz, sub.area[s], sub.intact[s], joint)
            sub.normal_force[s] = fn
            fs[0], fs[2] = sx, sz
            sub.intact[s] = intact
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


@numba.njit(cache=True, fastmath=FASTMATH)
def integrate(state, blocks, force, moment, damping, dt):
    """Damped velocities, positions and rotations of x, z and the rotation about y (as
    :func:`drydem.kernels.integrate`, which returns the same two measures)."""
    max_unbalanced_sq = 0.0
    max_speed = 0.0
    for i in range(state.position.shape[0]):
        if blocks.inv_mass[i] == 0.0:
            continue
        free_x, free_z, free_ry = blocks.free[i, 0], blocks.free[i, 2], blocks.free[i, 4]
        v, p = state.velocity[i], state.position[i]
        fx, fz, my = force[i, 0] * free_x, force[i, 2] * free_z, moment[i, 1] * free_ry
        v[0] = (v[0] + local_damping(fx, v[0], damping) * blocks.inv_mass[i] * dt) * free_x
        v[2] = (v[2] + local_damping(fz, v[2], damping) * blocks.inv_mass[i] * dt) * free_z
        w = state.angular_velocity[i, 1]
        w += local_damping(my, w, damping) * blocks.inv_inertia_body[i, 1, 1] * dt * free_ry
        state.angular_velocity[i, 1] = w
        p[0] += v[0] * dt
        p[2] += v[2] * dt
        rotate_by_vector(state.quaternion[i], 0.0, w * dt, 0.0)
        speed = np.sqrt(v[0] * v[0] + v[2] * v[2]) + abs(w) * blocks.radius[i]
        if not speed < np.inf:  # NaN counts as infinitely fast
            speed = np.inf
        max_speed = max(max_speed, speed)
        arm_moment = my / blocks.radius[i]
        max_unbalanced_sq = max(max_unbalanced_sq, fx * fx + fz * fz, arm_moment * arm_moment)
    return np.sqrt(max_unbalanced_sq), max_speed


@numba.njit(cache=True)
def energies(state, blocks):
    """:func:`drydem.kernels.energies` in the plane: 1/2 (m v^2 + I_yy w^2) and sum m |x - x_origin|."""
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
def step(state, blocks, sub, joint, gravity, dt, damping, rot, force, moment, measure):
    """One cycle of an in-plane model (``rot`` unused: the signature is
    :func:`drydem.kernels.step`'s, so that both share the cycling loop)."""
    for i in range(state.position.shape[0]):
        force[i, 0] = blocks.mass[i] * gravity[0]
        force[i, 2] = blocks.mass[i] * gravity[2]
        moment[i, 1] = 0.0
    contact_forces(state, sub, joint, dt, force, moment)
    unbalanced, speed = integrate(state, blocks, force, moment, damping, dt)
    kinetic, travel = energies(state, blocks) if measure else (0.0, 0.0)
    return unbalanced, speed, kinetic, travel


run_cycles = make_run_cycles(step, jit=True)
