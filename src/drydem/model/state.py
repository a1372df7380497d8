"""The time-varying state of the blocks, as a struct of arrays (nb blocks)."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from drydem.errors import ModelError
from drydem.model.geometry import described, real_array
from drydem.model.parameters import shown

#: a given quaternion's norm may differ from 1 by this much (it is then normalised): a rotation
#: written with 7 digits; one farther off, or zero, is no rotation (or another convention)
QUATERNION_TOLERANCE = 1e-6
#: norms within this of 1 are left as they are (the cycles keep them so, to round-off), so that a
#: state handed back (a snapshot restored) goes on bit for bit
ROUND_OFF = 1e-12
#: the largest |entry| a given state may hold, by field (m, m/s, rad/s): far past any block's
#: reach (vertices lie within 1e6 m of the origin, and a block falling out is taken out of the
#: analysis after at most 1,000 of its heights), so that an absurd state is refused rather than
#: cycled (found by a hunt: a block at x = 1e300 m ran 50,000 cycles with its corners merged into
#: one point; a speed of 1e200 m/s overflowed and was blamed on the timestep)
STATE_BOUNDS = {"position": 1e12, "velocity": 1e8, "angular_velocity": 1e8}
STATE_UNITS = {"position": "m", "velocity": "m/s", "angular_velocity": "rad/s"}


class State(NamedTuple):
    """Block kinematics; the arrays are updated in place by the kernels.

    position : (nb, 3) m, centroid in the world frame.
    quaternion : (nb, 4) unit quaternion (w, x, y, z), body frame -> world frame
        (the body frame is the block's orientation in the model file).
    velocity : (nb, 3) m/s, centroid velocity at the last half step.
    angular_velocity : (nb, 3) rad/s, world frame, at the last half step.
    """

    position: np.ndarray
    quaternion: np.ndarray
    velocity: np.ndarray
    angular_velocity: np.ndarray

    @classmethod
    def at_rest(cls, position: np.ndarray) -> State:
        """Blocks at ``position`` in their model-file orientation, not moving."""
        nb = len(position)
        quaternion = np.zeros((nb, 4))
        quaternion[:, 0] = 1.0
        return cls(np.array(position, dtype=float), quaternion, np.zeros((nb, 3)), np.zeros((nb, 3)))

    def copy(self) -> State:
        return State(*(a.copy() for a in self))


def block_array(value, shape: tuple[int, int], where: str) -> np.ndarray:
    """``value`` as a new C-ordered float64 array, the type the compiled cycles are built for
    (an int or float32 array converted); ModelError naming ``where`` unless it is an array (or
    nested lists) of ``shape``, finite real numbers: another shape would be read out of bounds or
    fail deep in the kernels, and texts, booleans, complex numbers and objects are no coordinates."""
    array = real_array(value)
    if array is None or array.shape != shape:
        raise ModelError(f"{where} must be a {shape} array of finite numbers, got {described(value)}")
    bad = np.argwhere(~np.isfinite(array))
    if bad.size:
        raise ModelError(f"{where} must be a {shape} array of finite numbers, got {array[tuple(bad[0])]} at {tuple(bad[0].tolist())}"
                         + (f" ({len(bad)} entries are not finite)" if len(bad) > 1 else ""))
    return array


def checked_state(state, n_blocks: int, where: str) -> State:
    """A copy of ``state`` fit for the cycles of ``n_blocks`` blocks: each array as
    :func:`block_array` makes it, (nb, 3) and the quaternions (nb, 4), these of unit norm within
    :data:`QUATERNION_TOLERANCE` (normalised; one farther off is refused). ModelError naming
    ``where`` and the field (``state.quaternion``)."""
    if not isinstance(state, State):
        raise ModelError(f"{where} state = {shown(state)}: must be a State (State.at_rest(positions) makes one)")
    arrays = [block_array(value, (n_blocks, 4 if field == "quaternion" else 3), f"{where} state.{field}")
              for field, value in zip(State._fields, state)]
    for field, array in zip(State._fields, arrays):
        bound = STATE_BOUNDS.get(field)
        if bound is not None and array.size and np.abs(array).max() > bound:
            row = int(np.argmax(np.abs(array).max(axis=1)))
            raise ModelError(f"{where} state.{field}[{row}] = {array[row].tolist()}: its entries must be within +-{bound:g} "
                             f"({STATE_UNITS[field]}), far past any block's reach")
    return State(arrays[0], _unit(arrays[1], f"{where} state.quaternion"), *arrays[2:])


def _unit(quaternion: np.ndarray, where: str) -> np.ndarray:
    """``quaternion`` (nb, 4) with the rows whose norm is off 1 by more than :data:`ROUND_OFF`
    normalised; ModelError naming the first row off by more than :data:`QUATERNION_TOLERANCE`."""
    norm = np.linalg.norm(quaternion, axis=1)
    off = np.abs(norm - 1.0)
    bad = np.flatnonzero(off > QUATERNION_TOLERANCE)
    if bad.size:
        more = f" ({bad.size} rows are off)" if bad.size > 1 else ""
        raise ModelError(f"{where}[{bad[0]}] = {quaternion[bad[0]].tolist()}: must be a unit quaternion (w, x, y, z), its norm "
                         f"1 within {QUATERNION_TOLERANCE:g}, not {norm[bad[0]]:.6g}{more}")
    rows = off > ROUND_OFF
    quaternion[rows] /= norm[rows, None]
    return quaternion
