"""What a cycled model's state means physically: its energies and the forces on a block."""

from __future__ import annotations

import numpy as np

from drydem.engine.contacts import SubContacts, world_points
from drydem.engine.joints import StressJoint, kernel_joint, normal_energies, shear_stiffness
from drydem.model.assembly import Model
from drydem.model.rotation import matrices, rotate_by_vector
from drydem.model.state import State


def energies(model: Model, state: State, contacts: SubContacts, timestep: float, gravity: np.ndarray) -> dict[str, float]:
    """Kinetic, gravitational and elastic (joint spring) energy, J, all at the half step.

    The velocities are those of t - dt/2 in leapfrog terms, so the positions are rewound
    by half a ``timestep`` (x - v dt/2, rotations by -omega dt/2) before the potentials are
    evaluated. Kinetic: sum 1/2 m v^2 + 1/2 omega . I_w omega (true masses);
    gravitational: -sum m g . (x - x_model_file) for ``gravity`` (3,) m/s2; elastic:
    sum 1/2 kn A u_n^2 over closed sub-contacts plus 1/2 |F_s|^2 / (ks A) (no-tension joints);
    for a stress-dependent joint, A integral of sigma du_n (:func:`drydem.engine.joints.normal_energies`)
    and ks the tangent at the sub-contact's stress (the shear term is then an estimate: an
    incremental shear spring whose stiffness changed along the way stores no unique energy).
    """
    half = -0.5 * timestep
    position = state.position + half * state.velocity
    quaternion = state.quaternion.copy()
    for q, w in zip(quaternion, state.angular_velocity):
        rotate_by_vector(q, *(half * w))
    rot = matrices(quaternion)
    inertia_world = np.einsum("nij,njk,nlk->nil", rot, model.block_inertia, rot)
    kinetic = 0.5 * (model.block_mass * np.einsum("ni,ni->n", state.velocity, state.velocity)).sum()
    kinetic += 0.5 * np.einsum("ni,nij,nj->", state.angular_velocity, inertia_world, state.angular_velocity)
    gravitational = -float((model.block_mass * ((position - model.block_centroid) @ np.asarray(gravity, float))).sum())
    _, gap, _ = world_points(contacts, position, rot)
    closure = np.maximum(-gap, 0.0)
    joint = kernel_joint(model.joint)
    if isinstance(joint, StressJoint):
        elastic = float((normal_energies(closure, joint) * contacts.area).sum())
        shear = np.array([shear_stiffness(stress, joint) for stress in contacts.normal_force / contacts.area])
    else:
        elastic = 0.5 * (joint.kn * contacts.area * closure**2).sum()
        shear = joint.ks
    elastic += 0.5 * (np.einsum("ni,ni->n", contacts.shear_force, contacts.shear_force) / (shear * contacts.area)).sum()
    return {"kinetic": float(kinetic), "gravitational": gravitational, "elastic": float(elastic)}


def reactions(state: State, contacts: SubContacts, block: int) -> np.ndarray:
    """Total contact force (N, world frame) that the other blocks exert on ``block``."""
    _, _, normal = world_points(contacts, state.position, matrices(state.quaternion))
    f = contacts.normal_force[:, None] * normal + contacts.shear_force
    return f[contacts.block_inc == block].sum(0) - f[contacts.block_ref == block].sum(0)
