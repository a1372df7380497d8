"""The contacts of a model as its blocks move: detection, the neighbour list, re-detection.

A :class:`ContactTracker` holds the current :class:`~drydem.engine.contacts.SubContacts`, the
:class:`~drydem.engine.contacts.NeighbourList` (block pairs watched for re-detection, a Verlet
list) and which blocks are still in the analysis. Contacts are re-detected whenever two
neighbouring blocks may have moved half the contact tolerance relative to each other (separated
ones: their separation) since their pair was last looked at, or any block may have moved far
enough for a block outside its neighbour list to reach it (bounds on every point's
displacement, so no new touch is missed: :func:`drydem.engine.loop.detection_slack`).
"""

from __future__ import annotations

import numpy as np

from drydem.engine import loop, refresh
from drydem.engine.broad_phase import broad_phase
from drydem.engine.contacts import NeighbourList, SubContacts, subset
from drydem.engine.narrow_phase import narrow_phase
from drydem.model.assembly import Model
from drydem.model.rotation import matrices
from drydem.model.state import State

#: neighbour-list margin in contact tolerances: blocks whose bounding boxes are this close are
#: watched for relative motion; any block moving (margin - tolerance) / 2 re-detects everything
NEIGHBOUR_MARGIN = 10.0


class ContactTracker:
    """The contacts of ``model``'s blocks, detected at ``state``.

    contacts : the sub-contacts with their shear history. neighbours : the watched pairs.
    broad_state : the State at the last broad phase. active : (nb,) bool, the blocks still in the
    analysis (:meth:`remove`). detections : detections so far.
    """

    def __init__(self, model: Model, state: State):
        self.model = model
        self.contacts = SubContacts.empty()
        self.neighbours = NeighbourList.empty()
        self.active = np.ones(model.n_blocks, dtype=bool)
        #: (nb,) m, the blocks' radii as the compiled kernels take them (the model's are read-only)
        self.radius_m = model.block_radius.copy()
        self.broad_state = state.copy()
        self.detections = 0
        self.detect(state, everything=True)

    @property
    def absolute_limit(self) -> float:
        """m: a block point moving this far since the last broad phase re-runs it."""
        return 0.5 * (NEIGHBOUR_MARGIN - 1.0) * self.model.contact_tolerance

    def detect(self, state: State, *, everything: bool = False) -> None:
        """Refresh the contacts at ``state`` (:func:`drydem.engine.loop.detection_slack` said so,
        or ``everything``: every pair looked at again).

        Neighbour pairs that moved less than half their limit relative to each other since their
        snapshot keep their sub-contacts and shear history untouched; the others go through the
        narrow phase again, inheriting shear stress from their old sub-contacts
        (:func:`drydem.engine.refresh.merge`). The broad phase runs again only when some block
        has moved far from where the last one saw it.
        """
        m, tol = self.model, self.model.contact_tolerance
        rot = matrices(state.quaternion)
        old_list, old = self.neighbours, self.contacts
        motion = np.empty(len(old_list.pairs))
        loop.pair_motions(state, old_list, self.radius_m, motion)
        if everything or self._moved_far(state):
            pairs = broad_phase(m.geometry, state.position, rot, m.block_movable, 0.5 * NEIGHBOUR_MARGIN * tol)
            pairs = pairs[self.active[pairs].all(axis=1)]
            self.broad_state = state.copy()
        else:
            pairs = old_list.pairs
        where, kept, keep_contact = refresh.match_pairs(old_list.pairs, old_list.limit, motion, pairs, old.pairs, m.n_blocks, everything=everything)
        fresh, separation = narrow_phase(m.geometry, pairs[~kept], state.position, rot, tolerance=tol, density=m.contact_density)
        self.contacts = refresh.merge(old, keep_contact, fresh, state.position, rot)
        self.neighbours = _neighbour_list(state, pairs, old_list, where, kept, separation, tol)
        self.detections += 1

    def _moved_far(self, state: State) -> bool:
        """Some block point moved (margin - tolerance) / 2 since the last broad phase."""
        slack = np.empty(self.model.n_blocks)
        return loop.detection_slack(state, self.broad_state, NeighbourList.empty(), self.radius_m, self.absolute_limit, slack) <= 0.0

    def remove(self, blocks) -> None:
        """Take ``blocks`` (indices) out of the analysis: their contacts and neighbour pairs go."""
        self.active[np.asarray(blocks, dtype=np.int64)] = False
        self.contacts = subset(self.contacts, self.active[self.contacts.pairs].all(axis=1))
        self.neighbours = NeighbourList(*(a[self.active[self.neighbours.pairs].all(axis=1)] for a in self.neighbours))


def _neighbour_list(state: State, pairs, old_list: NeighbourList, where, kept, separation, tolerance: float) -> NeighbourList:
    """The watched ``pairs`` with their snapshots: those ``kept`` keep theirs (at ``where`` in
    ``old_list``); the others are snapshotted at ``state``, with the limit half the tolerance when
    touching, else their ``separation`` less half the tolerance."""
    snapshot_position, snapshot_quaternion = state.position[pairs], state.quaternion[pairs]
    snapshot_position[kept] = old_list.position[where[kept]]
    snapshot_quaternion[kept] = old_list.quaternion[where[kept]]
    limit = np.empty(len(pairs))
    limit[kept] = old_list.limit[where[kept]]
    limit[~kept] = np.maximum(0.5 * tolerance, separation - 0.5 * tolerance)
    return NeighbourList(pairs, snapshot_position, snapshot_quaternion, limit)
