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

from drydem.model.parameters import JointMaterial


class JointConstants(NamedTuple):
    """The joint material as plain floats for the kernels (units as in :class:`JointMaterial`)."""

    kn: float
    ks: float
    friction: float
    cohesion: float
    tension: float

    @classmethod
    def of(cls, joint: JointMaterial) -> JointConstants:
        return cls(float(joint.kn), float(joint.ks), float(joint.friction), float(joint.cohesion), float(joint.tension))


@numba.njit(cache=True, inline="always")
def normal_law(closure, area, intact, joint):
    """(F_n, carries): the normal force and whether the sub-contact carries load at all.

    It does not once opened beyond its tensile strength (any opening when T = 0 or failed);
    then F_n = F_s = 0 and the sub-contact has failed."""
    fn = joint.kn * area * closure
    return fn, fn >= -(joint.tension * area if intact else 0.0)


@numba.njit(cache=True, inline="always")
def shear_law(fn, dus_x, dus_y, dus_z, fs_x, fs_y, fs_z, area, intact, joint):
    """New (F_s x, F_s y, F_s z, intact) of a loaded sub-contact; see module docstring.

    ``fs_*`` is the previous shear force already rotated into the current tangent plane."""
    shear_scale = joint.ks * area
    fs_x -= shear_scale * dus_x
    fs_y -= shear_scale * dus_y
    fs_z -= shear_scale * dus_z
    limit = max((joint.cohesion * area if intact else 0.0) + joint.friction * fn, 0.0)
    magnitude_sq = fs_x * fs_x + fs_y * fs_y + fs_z * fs_z
    if magnitude_sq > limit * limit:
        scale = limit / np.sqrt(magnitude_sq)
        return fs_x * scale, fs_y * scale, fs_z * scale, False
    return fs_x, fs_y, fs_z, intact
