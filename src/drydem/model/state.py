"""The time-varying state of the blocks, as a struct of arrays (nb blocks)."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np


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
