"""The dry-joint constitutive law of one sub-contact (paper Eqs. 1 and 3; 3DEC's Coulomb slip joint).

With closure u_n (m, positive when the blocks interpenetrate), shear displacement
increment du_s (m, tangential, incident block relative to the reference block) and
tributary area A (m2):

    F_n = k_n A u_n                          compression positive
    F_s <- F_s - k_s A du_s                  incremental, force on the incident block
    |F_s| <= max(c A + mu F_n, 0)            Mohr-Coulomb, scaled back to the limit when exceeded

No tension by default: F_n = 0 and F_s = 0 once the joint opens. With a tensile
strength T and cohesion c, F_n >= -T A while the sub-contact is intact; it fails
(intact = False, c and T lost for good) when F_n < -T A or when it slips (Itasca
3DEC, "Coulomb slip joint model with residual strength").
"""

from __future__ import annotations

from typing import NamedTuple

import numba
import numpy as np

from drydem.parameters import JointMaterial


class JointArrays(NamedTuple):
    """The joint material as plain floats for the kernels (units as in :class:`JointMaterial`)."""

    kn: float
    ks: float
    friction: float
    cohesion: float
    tension: float

    @classmethod
    def of(cls, joint: JointMaterial) -> JointArrays:
        return cls(float(joint.kn), float(joint.ks), float(joint.friction), float(joint.cohesion), float(joint.tension))


@numba.njit(cache=True, inline="always")
def joint_law(closure, dus_x, dus_y, dus_z, fs_x, fs_y, fs_z, area, intact, joint):
    """One sub-contact's new (F_n, F_s x, F_s y, F_s z, intact); see module docstring.

    ``fs_*`` is the previous shear force already rotated into the current tangent plane.
    """
    fn = joint.kn * area * closure
    tension_limit = joint.tension * area if intact else 0.0
    if fn < -tension_limit:  # open beyond the tensile strength (any opening when T = 0 or failed)
        return 0.0, 0.0, 0.0, 0.0, False
    shear_scale = joint.ks * area
    fs_x -= shear_scale * dus_x
    fs_y -= shear_scale * dus_y
    fs_z -= shear_scale * dus_z
    limit = max((joint.cohesion * area if intact else 0.0) + joint.friction * fn, 0.0)
    magnitude = np.sqrt(fs_x * fs_x + fs_y * fs_y + fs_z * fs_z)
    if magnitude > limit:
        scale = limit / magnitude
        return fn, fs_x * scale, fs_y * scale, fs_z * scale, False
    return fn, fs_x, fs_y, fs_z, intact
