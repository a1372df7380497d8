"""Contacts as struct-of-arrays: face-to-face contacts, their sub-contacts and the neighbour list.

Two convex blocks touch where a face of one (the *reference* face) lies within the contact
tolerance of the other block (:mod:`drydem.engine.narrow_phase` finds them). The contact
polygon is discretised into sub-contacts as 3DEC's contact points; each sub-contact is a pair
of material points (one on each block, the incident one on the incident face straight above
the reference one) and the reference normal, all stored in the blocks' body frames, so rocking
opens or closes them as the blocks turn.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from drydem.model.geometry import described


class SubContacts(NamedTuple):
    """Struct-of-arrays of the contacts (face pairs, nc) and their sub-contacts (ns), CSR-style:
    the sub-contacts of contact k are ``start[k]:start[k + 1]``. A NamedTuple, so the numba
    kernels take it as it is; the state arrays are updated in place.

    Per contact (fixed between detections): pairs (nc, 2) int64, reference and incident block;
    normal_body (nc, 3), unit normal of the reference face in the reference block's body frame,
    pointing towards the incident block; offset (nc,) m, that face's plane n . x = offset in the
    same frame; start (nc + 1,) int64.
    Per sub-contact: point_ref_body, point_inc_body (ns, 3) m, the two material points relative
    to each block's centroid in its body frame; area (ns,) m2. State: shear_force (ns, 3) N,
    world frame, force on the incident block; normal_force (ns,) N, compression positive;
    intact (ns,) bool, cohesion and tension still available.
    """

    pairs: np.ndarray
    normal_body: np.ndarray
    offset: np.ndarray
    start: np.ndarray
    point_ref_body: np.ndarray
    point_inc_body: np.ndarray
    area: np.ndarray
    shear_force: np.ndarray
    normal_force: np.ndarray
    intact: np.ndarray

    @property
    def count(self) -> int:
        return len(self.area)

    @property
    def contact(self) -> np.ndarray:
        """(ns,) index of each sub-contact's contact."""
        return np.repeat(np.arange(len(self.pairs)), np.diff(self.start))

    @property
    def block_ref(self) -> np.ndarray:
        return self.pairs[self.contact, 0]

    @property
    def block_inc(self) -> np.ndarray:
        return self.pairs[self.contact, 1]

    def copy(self) -> SubContacts:
        return SubContacts(*(a.copy() for a in self))

    def pair_keys(self, n_blocks: int) -> np.ndarray:
        """(nc,) unordered block-pair key of each contact (see :func:`pair_keys`)."""
        return pair_keys(self.pairs, n_blocks)

    @classmethod
    def empty(cls) -> SubContacts:
        v, s = np.zeros((0, 3)), np.zeros(0)
        return cls(np.zeros((0, 2), np.int64), v, s, np.zeros(1, np.int64), v, v.copy(), s.copy(), v.copy(), s.copy(), np.zeros(0, bool))


class NeighbourList(NamedTuple):
    """The block pairs watched for re-detection (a Verlet list), each with the state of its two
    blocks when its sub-contacts were last made: pairs (nn, 2) int64 (i < j); position
    (nn, 2, 3) m, the two centroids; quaternion (nn, 2, 4), the two orientations; limit (nn,)
    m, the relative motion after which the pair must be looked at again (half the tolerance
    for touching pairs; for separated ones, their separation less half the tolerance)."""

    pairs: np.ndarray
    position: np.ndarray
    quaternion: np.ndarray
    limit: np.ndarray

    def copy(self) -> NeighbourList:
        return NeighbourList(*(a.copy() for a in self))

    @classmethod
    def empty(cls) -> NeighbourList:
        return cls(np.zeros((0, 2), np.int64), np.zeros((0, 2, 3)), np.zeros((0, 2, 4)), np.zeros(0))


#: each field's dtype and shape ("c": contacts, "s": sub-contacts, "n": neighbour pairs, numbers as they are)
_SUB_FIELDS = {"pairs": ("i", ("c", 2)), "normal_body": ("f", ("c", 3)), "offset": ("f", ("c",)), "start": ("i", ("c+1",)),
               "point_ref_body": ("f", ("s", 3)), "point_inc_body": ("f", ("s", 3)), "area": ("f", ("s",)),
               "shear_force": ("f", ("s", 3)), "normal_force": ("f", ("s",)), "intact": ("b", ("s",))}
_NEIGHBOUR_FIELDS = {"pairs": ("i", ("n", 2)), "position": ("f", ("n", 2, 3)), "quaternion": ("f", ("n", 2, 4)), "limit": ("f", ("n",))}
_DTYPES = {"i": np.int64, "f": np.float64, "b": np.bool_}


def snapshot_problem(contacts: SubContacts, neighbours: NeighbourList, active: np.ndarray, n_blocks: int) -> str | None:
    """What keeps ``contacts``, ``neighbours`` and ``active`` (of a snapshot, which may come
    from a file) from being cycled with ``n_blocks`` blocks, None if nothing does: each field an
    array of its dtype (int64, float64, bool) and shape, finite; ``active`` (n_blocks,) bool;
    block numbers within 0..n_blocks - 1, neighbour pairs (i < j) once each; the sub-contacts'
    ``start`` rising from 0 to their count; every contact's blocks a neighbour pair. The compiled
    kernels index by these without bounds checks: a block number of 10**9 in a checkpoint
    crashed the interpreter."""
    fields = [(f"{part}.{name}", getattr(value, name, None), kind, shape)
              for part, value, rules in (("contacts", contacts, _SUB_FIELDS), ("neighbours", neighbours, _NEIGHBOUR_FIELDS))
              for name, (kind, shape) in rules.items()]
    counts = {key: _common_length([array for _, array, _, shape in fields if shape[0] == key]) for key in ("c", "s", "n")}
    counts["c+1"], counts["b"] = counts["c"] + 1, n_blocks
    for where, array, kind, shape in [*fields, ("active", active, "b", ("b",))]:
        expected = tuple(counts.get(n, n) for n in shape)
        if not (isinstance(array, np.ndarray) and array.dtype == _DTYPES[kind] and array.shape == expected):
            dtype = np.dtype(_DTYPES[kind]).name
            return f"{where}: must be {'an' if dtype[0] in 'aeiou' else 'a'} {dtype} array of shape {expected}, not {described(array)}"
        if kind == "f" and not np.isfinite(array).all():
            return f"{where}: not all finite numbers"
    for part, pairs in (("contacts", contacts.pairs), ("neighbours", neighbours.pairs)):
        if pairs.size and not (pairs.min() >= 0 and pairs.max() < n_blocks):
            return f"{part}.pairs: block numbers {pairs.min()} to {pairs.max()}, not within 0 to {n_blocks - 1}"
    start = contacts.start
    if start[0] != 0 or start[-1] != counts["s"] or np.any(np.diff(start) < 0):
        return f"contacts.start: must rise from 0 to the {counts['s']} sub-contacts"
    keys = pair_keys(neighbours.pairs, n_blocks)
    if np.any(neighbours.pairs[:, 0] >= neighbours.pairs[:, 1]) or len(np.unique(keys)) != len(keys):
        return "neighbours.pairs: each pair (i, j) must have i < j and be listed once"
    if not np.isin(pair_keys(contacts.pairs, n_blocks), keys).all():
        return "contacts.pairs: a contact's blocks are not a neighbour pair"
    return None


def _common_length(arrays: list) -> int:
    """The length most of ``arrays`` have (so that the one that differs is the one named)."""
    lengths = [len(a) if isinstance(a, np.ndarray) and a.ndim else -1 for a in arrays]
    return max(set(lengths), key=lengths.count)


def pair_keys(pairs: np.ndarray, n_blocks: int) -> np.ndarray:
    """Unordered key min(i, j) * n_blocks + max(i, j) of block pairs (n, 2)."""
    return np.minimum(pairs[:, 0], pairs[:, 1]) * n_blocks + np.maximum(pairs[:, 0], pairs[:, 1])


def subset(sub: SubContacts, keep: np.ndarray) -> SubContacts:
    """The contacts where ``keep`` (nc,) is true, with their sub-contacts and state."""
    rows = np.repeat(keep, np.diff(sub.start))
    counts = np.diff(sub.start)[keep]
    return SubContacts(
        pairs=sub.pairs[keep], normal_body=sub.normal_body[keep], offset=sub.offset[keep],
        start=np.concatenate([[0], np.cumsum(counts)]).astype(np.int64),
        point_ref_body=sub.point_ref_body[rows], point_inc_body=sub.point_inc_body[rows], area=sub.area[rows],
        shear_force=sub.shear_force[rows], normal_force=sub.normal_force[rows], intact=sub.intact[rows],
    )


def world_points(sub: SubContacts, position: np.ndarray, rotation: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """World incident points, gaps (m, distance from the reference plane along the normal,
    negative when penetrating) and normals of every sub-contact."""
    ref, inc = sub.block_ref, sub.block_inc
    x_inc = position[inc] + np.einsum("nij,nj->ni", rotation[inc], sub.point_inc_body)
    normal = np.einsum("nij,nj->ni", rotation[ref], sub.normal_body[sub.contact])
    gap = np.einsum("ni,ni->n", x_inc - position[ref], normal) - sub.offset[sub.contact]
    return x_inc, gap, normal


def closing_motion(sub: SubContacts, state, rotation: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(ns,) m and (ns,) m/s: each sub-contact's closure (-gap) and its closing speed (the normal
    relative velocity of its two material points at the incident point, positive when closing)."""
    x_inc, gap, normal = world_points(sub, state.position, rotation)
    ref, inc = sub.block_ref, sub.block_inc
    v = state.velocity[inc] + np.cross(state.angular_velocity[inc], x_inc - state.position[inc])
    v -= state.velocity[ref] + np.cross(state.angular_velocity[ref], x_inc - state.position[ref])
    return -gap, -np.einsum("ni,ni->n", v, normal)
