"""Local damping (3DEC's default for statics): a force opposing the motion of each degree of
freedom, proportional to the unbalanced force, so that the blocks come to rest without the
viscous drag that would slow a rigid-body motion (Cundall 1987, "Distinct element models of
rock and soil structure", in Analytical and Computational Methods in Engineering Rock Mechanics)."""

from __future__ import annotations

import numba


@numba.njit(cache=True, inline="always")
def local_damping(force: float, velocity: float, alpha: float) -> float:
    """Damped force F - alpha |F| sign(v) of one degree of freedom (paper Eq. 4; Cundall 1987)."""
    if velocity > 0.0:
        return force - alpha * abs(force)
    if velocity < 0.0:
        return force + alpha * abs(force)
    return force
