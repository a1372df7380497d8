"""The cycle of :mod:`drydem.engine.cycle3d` written again in vectorised NumPy: the tests' oracle.

Same arguments, same physics, same results to round-off; written independently (one row
per sub-contact, the gap from both material points rather than the plane offset, array
expressions, ``np.add.at`` scatter, scipy's ``Rotation`` for quaternion algebra) so that
an indexing or sign slip in the compiled kernels shows up as a difference. About 20-50x
slower than the kernels (see ``benchmarks/bench_step.py``).
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from drydem.engine.cycle3d import cycle_loop
from drydem.engine.joints import CLOSING_CYCLES, TOUCH_ROUND_OFF, StressJoint, normal_stress
from oracles.joints import shear_stiffness


def _apply(rot: np.ndarray, vec: np.ndarray) -> np.ndarray:
    return np.einsum("nij,nj->ni", rot, vec)


def _world_tensor_apply(rot: np.ndarray, tensor: np.ndarray, vec: np.ndarray) -> np.ndarray:
    """R T R^T v for each block: a body-frame tensor (inertia or its inverse) in the world frame."""
    return _apply(rot, _apply(tensor, _apply(rot.transpose(0, 2, 1), vec)))


def _norm(vec: np.ndarray) -> np.ndarray:
    return np.sqrt(np.einsum("ni,ni->n", vec, vec))


def _damped(force: np.ndarray, velocity: np.ndarray, alpha: float) -> np.ndarray:
    return force - alpha * np.abs(force) * np.sign(velocity)


def step(state, blocks, sub, joint, closure_limit, gravity, dt, velocity_dt, damping, rot, force, moment, measure, work=None):
    """One cycle; see :func:`drydem.engine.cycle3d.step` (it always measures the energies; ``work``, the
    compiled kernels' scratch, is not needed here)."""
    pos, vel, omega = state.position, state.velocity, state.angular_velocity
    rot[:] = Rotation.from_quat(state.quaternion[:, [1, 2, 3, 0]]).as_matrix()
    force[:] = blocks.mass[:, None] * np.asarray(gravity)
    moment[:] = 0.0

    # sub-contact kinematics, one row per sub-contact
    a, b = sub.block_ref, sub.block_inc
    n = _apply(rot[a], sub.normal_body[sub.contact])
    arm_b = _apply(rot[b], sub.point_inc_body)
    x_b = pos[b] + arm_b
    arm_a = x_b - pos[a]
    gap = np.einsum("ni,ni->n", x_b - pos[a] - _apply(rot[a], sub.point_ref_body), n)
    v_rel = vel[b] + np.cross(omega[b], arm_b) - vel[a] - np.cross(omega[a], arm_a)
    dus = (v_rel - np.einsum("ni,ni->n", v_rel, n)[:, None] * n) * dt
    fs = sub.shear_force
    old = _norm(fs)
    fs_t = fs - np.einsum("ni,ni->n", fs, n)[:, None] * n
    new = _norm(fs_t)
    fs_t *= np.divide(old, new, out=np.ones_like(old), where=new > 0)[:, None]

    # joint law
    area = sub.area
    if isinstance(joint, StressJoint):
        # the law's values from the closed form (itself held to oracles.joints' quadrature);
        # the shear stiffness from oracles.joints at each sub-contact's stress
        fn = np.array([normal_stress(u, joint) for u in -gap]) * area
        shear_scale = np.array([shear_stiffness(sigma, joint) for sigma in fn / area]) * area
    else:
        fn = joint.kn * area * -gap
        shear_scale = joint.ks * area
    opened = fn < -np.where(sub.intact, joint.tension * area, 0.0)
    # an intact bond opened by no more than the round-off of its coordinates is touching, at -T A
    round_off = TOUCH_ROUND_OFF * (np.abs(pos[b] - pos[a]).sum(axis=1) + np.abs(sub.offset[sub.contact]))
    touching = opened & sub.intact & (joint.cohesion > 0 or joint.tension > 0) & (-gap >= -round_off)
    fn = np.where(touching, -joint.tension * area, fn)
    opened &= ~touching
    # a stress-dependent joint closing past its limit within CLOSING_CYCLES cycles at its speed
    closing = -gap - CLOSING_CYCLES * np.minimum(np.einsum("ni,ni->n", v_rel, n), 0.0) * dt
    stiffer = isinstance(joint, StressJoint) and bool((closing > closure_limit)[~opened].any())
    fs_new = fs_t - shear_scale[:, None] * dus
    limit = np.maximum(np.where(sub.intact, joint.cohesion * area, 0.0) + joint.friction * fn, 0.0)
    magnitude = _norm(fs_new)
    slip = magnitude > limit
    fs_new[slip] *= (limit[slip] / magnitude[slip])[:, None]
    fn[opened] = 0.0
    fs_new[opened] = 0.0
    sub.normal_force[:] = fn
    sub.shear_force[:] = fs_new
    sub.intact[:] = sub.intact & ~slip & ~opened

    # normal dashpots (drydem.engine.damping): c = A (2 zeta sqrt(kn m_ab / A_c) + beta kn), no pull
    push = np.where(opened, 0.0, fn + _dashpot(sub, blocks, joint, damping, n, v_rel, fn))

    # forces on the incident (+) and reference (-) blocks at the incident point
    f = push[:, None] * n + fs_new
    np.add.at(force, b, f)
    np.add.at(moment, b, np.cross(arm_b, f))
    np.add.at(force, a, -f)
    np.add.at(moment, a, -np.cross(arm_a, f))

    # damped motion of the blocks with a free degree of freedom
    moving = blocks.free.max(axis=1) > 0
    free_t, free_r = blocks.free[:, :3], blocks.free[:, 3:]
    f_free, m_free = force * free_t, moment * free_r
    unbalanced = np.maximum(_norm(f_free), _norm(m_free) / blocks.radius)
    drag = damping.mass_proportional
    vel += (_damped(f_free, vel, damping.local) * blocks.inv_mass[:, None] - drag * vel) * velocity_dt * moving[:, None]
    torque = _damped(m_free, omega, damping.local)
    spin = _world_tensor_apply(rot, blocks.inertia_body, omega)
    accel = _world_tensor_apply(rot, blocks.inv_inertia_body, torque - np.cross(omega, spin) - drag * spin)
    omega += accel * velocity_dt * free_r * moving[:, None]
    vel *= free_t
    pos += vel * dt * moving[:, None]
    turned = Rotation.from_rotvec(omega * dt) * Rotation.from_quat(state.quaternion[:, [1, 2, 3, 0]])
    state.quaternion[moving] = turned.as_quat()[moving][:, [3, 0, 1, 2]]

    speed = _norm(vel) + _norm(omega) * blocks.radius
    speed = np.where(speed < np.inf, speed, np.inf)  # NaN counts as infinitely fast
    # omega . I_w omega after the update, I_w with the rotation at the start of the cycle
    rotational = np.einsum("ni,ni->n", omega, _world_tensor_apply(rot, blocks.inertia_body, omega))
    kinetic = 0.5 * (np.einsum("ni,ni->n", vel, vel) / np.where(moving, blocks.inv_mass, 1.0) + rotational)[moving].sum()
    travel = (blocks.mass * _norm(pos - blocks.origin))[moving].sum()
    if not moving.any():
        return 0.0, 0.0, 0.0, 0.0, stiffer
    return float(unbalanced[moving].max()), float(speed[moving].max()), float(kinetic), float(travel), stiffer


def _dashpot(sub, blocks, joint, damping, n, v_rel, fn):
    """The dashpots' normal forces (n_sub,), N: -c v_n, at most cancelling a compression."""
    inv_sum = (blocks.inv_mass[sub.block_ref] + blocks.inv_mass[sub.block_inc])
    contact_area = np.bincount(sub.contact, weights=sub.area, minlength=len(sub.pairs))[sub.contact]
    reduced = np.divide(1.0, inv_sum, out=np.zeros_like(inv_sum), where=inv_sum > 0)
    per_area = 2.0 * damping.contact_ratio * np.sqrt(joint.kn * reduced / contact_area) + damping.stiffness_proportional * joint.kn
    per_area = np.where(inv_sum > 0, per_area, 0.0)
    opening = np.einsum("ni,ni->n", v_rel, n)
    return np.where(fn > 0, np.maximum(-per_area * sub.area * opening, -fn), np.maximum(-per_area * sub.area * opening, 0.0))


def run_cycles(state, blocks, sub, joint, loop, broad_state, neighbours):
    """The shared cycling loop (:func:`drydem.engine.cycle3d.cycle_loop`, in Python) around this :func:`step`."""
    return cycle_loop.py_func(step, state, blocks, sub, joint, loop, broad_state, neighbours)
