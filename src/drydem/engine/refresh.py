"""Contact re-detection bookkeeping, compiled: which contacts are kept, and the merge of the kept
ones with the re-detected ones, shear history carried over.

A re-detection (:meth:`drydem.engine.tracker.ContactTracker.detect`) keeps the contacts of the block pairs
that have hardly moved relative to each other and makes the others again with the narrow
phase. The new sub-contacts inherit the shear stress (N/m2) and the intact flag of the nearest
old sub-contact of the same block pair, projected on the new tangent plane; the shear force is
stored as the force on the incident block, so it changes sign where the blocks swapped roles.
A sub-contact whose pair had none starts with no shear. The plain-Python carry_over of tests/oracles/contacts.py
(scipy's cKDTree over the world points) is the oracle of the tests.

In flows (blocks rocking and sliding near collapse) re-detections come every few tens of cycles,
so this runs in one compiled call rather than a few dozen NumPy ones.
"""

from __future__ import annotations

import numba
import numpy as np

from drydem import compiled_cache
from drydem.engine.contacts import SubContacts
from drydem.model.rotation import mat_vec


@numba.njit(cache=True, inline="always")
def _pair_key(i, j, n_blocks):
    """The unordered pair (i, j) of blocks as one integer, min * n_blocks + max."""
    return min(i, j) * n_blocks + max(i, j)


def match_pairs(
    old_pairs: np.ndarray, old_limit: np.ndarray, motion: np.ndarray, pairs: np.ndarray, contact_pairs: np.ndarray, n_blocks: int, *, everything: bool
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Which neighbour pairs keep their contacts.

    ``old_pairs`` (no, 2) and ``pairs`` (k, 2): the last and the new neighbour lists' pairs
    (i < j, sorted); ``old_limit`` and ``motion`` (no,): each old pair's limit and relative
    motion since its snapshot, m; ``contact_pairs`` (nc, 2): the current contacts' blocks.
    Returns ``where`` (k,), each new pair's row in the old list (-1 if new); ``kept`` (k,), the
    pairs known before that moved less than half their limit (none if ``everything``); and
    ``keep_contact`` (nc,), the contacts of kept pairs.
    """
    return _match_pairs(old_pairs, old_limit, motion, pairs, contact_pairs, n_blocks, everything)


@numba.njit(cache=True)
def _match_pairs(old_pairs, old_limit, motion, pairs, contact_pairs, n_blocks, everything):
    k = pairs.shape[0]
    where = np.full(k, -1, np.int64)
    kept = np.zeros(k, np.bool_)
    row = 0
    for p in range(k):  # both lists sorted: one merge walk
        key = _pair_key(pairs[p, 0], pairs[p, 1], n_blocks)
        while row < old_pairs.shape[0] and _pair_key(old_pairs[row, 0], old_pairs[row, 1], n_blocks) < key:
            row += 1
        if row < old_pairs.shape[0] and _pair_key(old_pairs[row, 0], old_pairs[row, 1], n_blocks) == key:
            where[p] = row
            kept[p] = not everything and motion[row] <= 0.5 * old_limit[row]
    kept_keys = np.empty(k, np.int64)
    n_kept = 0
    for p in range(k):
        if kept[p]:
            kept_keys[n_kept] = _pair_key(pairs[p, 0], pairs[p, 1], n_blocks)
            n_kept += 1
    kept_keys = kept_keys[:n_kept]
    keep_contact = np.zeros(contact_pairs.shape[0], np.bool_)
    for c in range(contact_pairs.shape[0]):
        key = _pair_key(contact_pairs[c, 0], contact_pairs[c, 1], n_blocks)
        i = np.searchsorted(kept_keys, key)
        keep_contact[c] = i < n_kept and kept_keys[i] == key
    return where, kept, keep_contact


def merge(old: SubContacts, keep: np.ndarray, fresh: SubContacts, position: np.ndarray, rotation: np.ndarray) -> SubContacts:
    """The contacts of ``old`` where ``keep`` (nc,) is true, untouched, then those of ``fresh``
    with their shear carried over from ``old`` (module docstring), at block centroids
    ``position`` (nb, 3) m and rotations (nb, 3, 3)."""
    return SubContacts(*_merge(old, np.ascontiguousarray(keep, dtype=np.bool_), fresh, position, rotation))


@numba.njit(cache=True, inline="always")
def _world_point(position, rotation, block, p):
    """x = position[block] + R[block] p, m."""
    x, y, z = mat_vec(rotation[block], p[0], p[1], p[2])
    return position[block, 0] + x, position[block, 1] + y, position[block, 2] + z


@numba.njit(cache=True, inline="always")
def _copy_contact(source, c, out, c_out, s_out):
    """Contact ``c`` of ``source``, its sub-contacts and their state into row ``c_out`` (and
    sub-contact rows from ``s_out``) of ``out`` (SubContacts' arrays); returns the next sub-contact row."""
    pairs, normal_body, offset, start, point_ref_body, point_inc_body, area, shear_force, normal_force, intact = out
    # element by element: numba's row assignment goes through broadcasting, ten times slower
    pairs[c_out, 0], pairs[c_out, 1] = source.pairs[c, 0], source.pairs[c, 1]
    for k in range(3):
        normal_body[c_out, k] = source.normal_body[c, k]
    offset[c_out] = source.offset[c]
    for s in range(source.start[c], source.start[c + 1]):
        for k in range(3):
            point_ref_body[s_out, k] = source.point_ref_body[s, k]
            point_inc_body[s_out, k] = source.point_inc_body[s, k]
            shear_force[s_out, k] = source.shear_force[s, k]
        area[s_out] = source.area[s]
        normal_force[s_out] = source.normal_force[s]
        intact[s_out] = source.intact[s]
        s_out += 1
    start[c_out + 1] = s_out
    return s_out


@numba.njit(cache=True)
def _merge(old, keep, fresh, position, rotation):
    nb = position.shape[0]
    kept_contacts = 0
    kept_points = 0
    for c in range(old.pairs.shape[0]):
        if keep[c]:
            kept_contacts += 1
            kept_points += old.start[c + 1] - old.start[c]
    nc = kept_contacts + fresh.pairs.shape[0]
    ns = kept_points + fresh.area.shape[0]
    out = (
        np.empty((nc, 2), np.int64), np.empty((nc, 3)), np.empty(nc), np.zeros(nc + 1, np.int64), np.empty((ns, 3)),
        np.empty((ns, 3)), np.empty(ns), np.empty((ns, 3)), np.empty(ns), np.empty(ns, np.bool_),
    )
    shear_force, intact = out[7], out[9]
    c_out = s_out = 0
    for c in range(old.pairs.shape[0]):  # the kept contacts, as they are
        if keep[c]:
            s_out = _copy_contact(old, c, out, c_out, s_out)
            c_out += 1

    # old contacts by unordered pair key, to find a fresh contact's predecessors
    keys = np.empty(old.pairs.shape[0], np.int64)
    for c in range(old.pairs.shape[0]):
        keys[c] = _pair_key(old.pairs[c, 0], old.pairs[c, 1], nb)
    order = np.argsort(keys)
    sorted_keys = keys[order]
    old_world = np.empty((old.area.shape[0], 3))  # incident points of a fresh contact's predecessors

    for c in range(fresh.pairs.shape[0]):
        a, b = fresh.pairs[c, 0], fresh.pairs[c, 1]
        key = _pair_key(a, b, nb)
        first = np.searchsorted(sorted_keys, key)
        last = np.searchsorted(sorted_keys, key, side="right")
        for k in range(first, last):
            oc = order[k]
            for so in range(old.start[oc], old.start[oc + 1]):
                old_world[so, 0], old_world[so, 1], old_world[so, 2] = _world_point(position, rotation, old.pairs[oc, 1], old.point_inc_body[so])
        nx, ny, nz = mat_vec(rotation[a], fresh.normal_body[c, 0], fresh.normal_body[c, 1], fresh.normal_body[c, 2])
        row = s_out
        s_out = _copy_contact(fresh, c, out, c_out, s_out)
        c_out += 1
        for s in range(fresh.start[c], fresh.start[c + 1]):
            x, y, z = _world_point(position, rotation, b, fresh.point_inc_body[s])
            nearest, nearest_contact, nearest_sq = -1, -1, np.inf
            for k in range(first, last):
                oc = order[k]
                for so in range(old.start[oc], old.start[oc + 1]):
                    d_sq = (x - old_world[so, 0]) ** 2 + (y - old_world[so, 1]) ** 2 + (z - old_world[so, 2]) ** 2
                    if d_sq < nearest_sq:
                        nearest, nearest_contact, nearest_sq = so, oc, d_sq
            if nearest >= 0:
                scale = (1.0 if old.pairs[nearest_contact, 1] == b else -1.0) / old.area[nearest]
                sx, sy, sz = old.shear_force[nearest, 0] * scale, old.shear_force[nearest, 1] * scale, old.shear_force[nearest, 2] * scale
                along = sx * nx + sy * ny + sz * nz
                shear_force[row, 0] = (sx - along * nx) * fresh.area[s]
                shear_force[row, 1] = (sy - along * ny) * fresh.area[s]
                shear_force[row, 2] = (sz - along * nz) * fresh.area[s]
                intact[row] = old.intact[nearest]
            row += 1
    return out


compiled_cache.check(__name__)  # last: none of the functions above is loaded from a stale cache
