"""Load paths: which block rests on which, and how far the joints' elastic closure lets a block
settle. A block has *fallen* only when it sits lower than that explains.

A contact whose world normal points up (``n . z >= SUPPORT_COSINE``) carries its upper block on
its lower one. The joints' elastic closure explains a settlement of each block

    s(b) = max over the contacts (a under b) of  s(a) + closure(a, b),   s = 0 on nothing,

with closure(a, b) the deepest penetration of the contact's sub-contacts (m, the springs'
u_n): the sum of the closures down the deepest load path to a fixed block (for a stack of
equal blocks on area A, s = sum_k W_above_k / (kn A), the settlement of a column of springs).
A block resting on nothing (in flight, or on a side contact only) has s = 0: its whole drop is
a rigid-body drop. ``rigid_drop = drop - s`` is what a fall is judged by, so a tall or soft
wall's elastic settlement is never taken for a fall (Savalle et al. 2022 soften the joints
to kn = 3e7 Pa/m, where a 100-course pier settles by three brick heights).
"""

from __future__ import annotations

import numba
import numpy as np

from drydem import compiled_cache
from drydem.engine.contacts import SubContacts, world_points
from drydem.engine.joints import StressJoint, kernel_joint, normal_closures
from drydem.model.parameters import G
from drydem.model.rotation import matrices, turns_from_drawn

#: a contact carries its upper block when its normal is within 60 deg of the vertical
SUPPORT_COSINE = 0.5


def load_paths(contacts: SubContacts, position: np.ndarray, rotation: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The supporting contacts at the current state: lower block, upper block (each (k,) int)
    and elastic closure (k,) m, the contact's deepest sub-contact penetration (0 if open)."""
    if contacts.count == 0:
        empty = np.zeros(0, np.int64)
        return empty, empty, np.zeros(0)
    _, gap, normal = world_points(contacts, position, rotation)
    closure = np.maximum.reduceat(np.maximum(-gap, 0.0), contacts.start[:-1])
    normal_z = normal[contacts.start[:-1], 2]
    ref, inc = contacts.pairs[:, 0], contacts.pairs[:, 1]
    up, down = normal_z >= SUPPORT_COSINE, normal_z <= -SUPPORT_COSINE
    lower = np.concatenate([ref[up], inc[down]])
    upper = np.concatenate([inc[up], ref[down]])
    return lower, upper, np.concatenate([closure[up], closure[down]])


def unsupported(model, contacts: SubContacts) -> np.ndarray:
    """Blocks that touch nothing (no contact within the tolerance) yet are free to move down:
    under gravity they fall (block indices, int)."""
    touching = np.zeros(model.n_blocks, dtype=bool)
    touching[contacts.pairs.ravel()] = True
    return np.flatnonzero(model.block_movable & ~model.block_fixed[:, 2] & ~touching)


def lost_drops(model, lost_drop_heights: float) -> np.ndarray:
    """(nb,) m: the drop past which each block has fallen out of the model, ``lost_drop_heights``
    of its own height (:func:`dropped_out`)."""
    return lost_drop_heights * np.array([np.ptp(shape.vertices[:, 2]) for shape in model.block_shape])


def dropped_out(model, state, contacts: SubContacts, active: np.ndarray, lost_drop: np.ndarray) -> np.ndarray:
    """(nb,) bool: the block, still in the analysis (``active``), has a rigid-body drop beyond its
    ``lost_drop`` (nb,) m: its centroid is lower than where it was drawn by more than that plus
    the settlement its joints' elastic closure explains (:func:`elastic_settlement`; the load
    paths are looked for only when some such block has dropped that far at all). The rule by
    which the tilting and shaking analyses take a block for fallen out of the model."""
    position = state.position
    drop = model.block_centroid[:, 2] - position[:, 2]
    if not np.any((drop > lost_drop) & active):
        return np.zeros(model.n_blocks, dtype=bool)
    paths = load_paths(contacts, position, matrices(state.quaternion))
    return (drop - elastic_settlement(*paths, position[:, 2]) > lost_drop) & active


def elastic_settlement(lower: np.ndarray, upper: np.ndarray, closure: np.ndarray, height: np.ndarray) -> np.ndarray:
    """(nb,) m: s(b) of the module docstring, the contacts taken from the lowest lower block up
    (``height`` (nb,) m orders the blocks: their centroids' heights now). A supporter that is
    not below the block it carries (blocks tumbling in a collapse) may be taken after it: its
    path is then missed and s underestimated, so a fall is never missed for it."""
    order = np.argsort(height[lower], kind="stable")
    return _longest_paths(lower[order], upper[order], closure[order], len(height))


@numba.njit(cache=True)
def _longest_paths(lower, upper, closure, n_blocks):
    """s[upper] = max(s[upper], s[lower] + closure), one pass over contacts sorted bottom-up."""
    settlement = np.zeros(n_blocks)
    for k in range(lower.shape[0]):
        settlement[upper[k]] = max(settlement[upper[k]], settlement[lower[k]] + closure[k])
    return settlement


def own_weight_closures(model, block: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """How far ``block``'s own weight alone closes the joint it rests on, resting on each face f
    (those in the plane of motion only, for an in-plane model): the closure u(W / A_f) of the
    joint law (W / (kn A_f) for a constant kn), m; the block's width across f, m; and A_f, m2.

    Joints that close by more than a block's width on every face cannot carry it: penalty
    contacts let it sink through its base, and its fall is the joints' doing, not the
    structure's. For a constant kn and a box, the closure is rho g / kn of the width on every
    face (A_f w_f = V): a 5.5 mm brick on kn = 1e4 Pa/m closes 9.7 mm, while on 2e4 it closes
    4.86 mm and stands."""
    shape = model.block_shape[block]
    faces = [f for f in range(len(shape.faces)) if not (model.in_plane and abs(shape.face_normals[f, 1]) > SUPPORT_COSINE)]
    area = np.array([shape.face_area(f) for f in faces])
    heights = shape.vertices @ shape.face_normals[faces].T
    return joint_closures(model, model.block_mass[block] * G / area), heights.max(axis=0) - heights.min(axis=0), area


def joint_closures(model, stress: np.ndarray) -> np.ndarray:
    """u(sigma), m, of the model's joint law at each normal stress (n,) Pa >= 0: sigma / kn for a
    constant kn (:func:`~drydem.engine.joints.normal_closures` for a stress-dependent law)."""
    joint = kernel_joint(model.joint)
    return normal_closures(stress, joint) if isinstance(joint, StressJoint) else stress / joint.kn


#: a joint closed by more than this fraction of the thinner of its two blocks has left the small
#: closures the zero-thickness joint stands for (found by a hunt: five 0.2 m blocks on kn = 1e5
#: settled "converged" 19 % below the sum of W / (kn A), the bottom joint closed 196 of 200 mm)
LARGE_CLOSURE_FRACTION = 0.1


#: a turn (rad) and a sideways move (fraction of the block's radius) under the model's own weight
#: beyond any joint's elastic give: the block toppled or slid into another position
RIGID_TURN_RAD = np.radians(5.0)
RIGID_MOVE_FRACTION = 0.1


def moved_rigidly(model, state) -> tuple[int, float, float]:
    """The movable block that turned or moved sideways the most, relative to :data:`RIGID_TURN_RAD`
    and :data:`RIGID_MOVE_FRACTION` of its radius, from where it was drawn to ``state``, with its
    turn (rad) and horizontal move (m); block -1 where none went past either (found by a hunt: a
    cube drawn on its edge toppled 44 deg onto its face under its own weight, and check --settle
    called that a settlement of 20.7 mm)."""
    turn = turns_from_drawn(state.quaternion)
    move = np.hypot(*(state.position[:, :2] - model.block_centroid[:, :2]).T)
    excess = np.maximum(turn / RIGID_TURN_RAD, move / (RIGID_MOVE_FRACTION * model.block_radius)) * model.block_movable
    k = int(np.argmax(excess)) if excess.size else -1
    return (k, float(turn[k]), float(move[k])) if k >= 0 and excess[k] > 1.0 else (-1, 0.0, 0.0)


def largest_closure(model, contacts: SubContacts) -> tuple[float, int]:
    """The largest closure of a loaded sub-contact of ``contacts`` (u(F_n / A) of the joint law)
    over the thickness of the thinner movable block it joins (its least extent along x, y or z),
    and that block; (0.0, -1) if none is loaded."""
    closure = joint_closures(model, np.maximum(contacts.normal_force, 0.0) / contacts.area)
    thickness = np.array([np.ptp(shape.vertices, axis=0).min() for shape in model.block_shape])
    thickness[~model.block_movable] = np.inf
    ref, inc = contacts.block_ref, contacts.block_inc
    thinner = np.where(thickness[ref] <= thickness[inc], ref, inc)
    fraction = closure / thickness[thinner]
    if not fraction.size or fraction.max() <= 0.0:
        return 0.0, -1
    k = int(np.argmax(fraction))
    return float(fraction[k]), int(thinner[k])


def too_soft_joints(model, blocks) -> str:
    """Words for the ``blocks`` (indices) whose joints cannot carry even their own weight on any
    face (:func:`own_weight_closures`), quoting the first on its largest face; "" for none."""
    sinking = []
    for b in blocks:
        closure, width, area = own_weight_closures(model, b)
        if np.all(closure >= width):
            sinking.append((b, closure[np.argmax(area)], width[np.argmax(area)]))
    if not sinking:
        return ""
    b, closure, width = sinking[0]
    more = f" (and {len(sinking) - 1} more blocks)" if len(sinking) > 1 else ""
    return (f"the joints are too soft to carry it: under its own weight alone, {model.block_name[b]!r} closes its joint by "
            f"{closure * 1e3:.3g} mm on its largest face (u(W / A) of the joint law), more than the {width * 1e3:.3g} mm it is "
            f"thick there, and as much on every face{more}, so it sinks through its base; stiffen [joint] kn")


def roundoff_ratio(model) -> float:
    """About the smallest unbalanced-force ratio (the largest unbalanced force over the mean
    block weight, [solver] ratio) that round-off lets the cycles reach: positions are known to
    the spacing of doubles at the model's farthest coordinate, which a joint of stiffness kn
    under a block's largest face A turns into a force of kn A spacing. Found by a hunt: a 1 um
    cube of density 1 on kn = 1e15 Pa/m (about 2 %), or a brick 10 m up on kn = 1e15 (about
    1 %), never reaches 1e-5, and was told to raise max_cycles; WD3 on kn = 1e10 is at 1e-8."""
    movable = [model.block_shape[b] for b in np.flatnonzero(model.block_movable)]
    farthest = max(float(np.abs(shape.vertices).max()) for shape in movable)
    area = max(shape.face_area(f) for shape in movable for f in range(len(shape.faces)))
    weight = float(model.block_mass[model.block_movable].mean()) * G
    return model.joint.kn * area * float(np.spacing(farthest)) / weight


compiled_cache.check(__name__)  # last: none of the functions above is loaded from a stale cache
