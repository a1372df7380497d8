"""Eurocode 8 drift limits on a pushover curve.

The drift of a wall is the horizontal displacement of its monitored point since the tilt began
(from its equilibrium under its own weight, at 0 deg) divided by the wall's height
(:class:`drydem.analysis.tilt.Record`). EN 1998-1 (4.4.3.2) limits the interstorey drift at
the damage limitation state to 0.5 %, 0.75 % or 1 % depending on the non-structural elements;
Savalle et al. (2022, Section 5) read the tilt angles at which each is first reached, the 1 %
one being their DLS angle.
"""

from __future__ import annotations

import numpy as np

from drydem.errors import ModelError
from drydem.model.geometry import given, real_array
from drydem.model.parameters import Range

#: EN 1998-1 4.4.3.2 drift limits (the paper's Section 5)
EC8_DRIFT_LIMITS = (0.005, 0.0075, 0.01)
#: what each of :data:`EC8_DRIFT_LIMITS` is for, EN 1998-1 4.4.3.2 (1) a) to c): the buildings whose
#: damage limitation state it is; the 1 % one is the DLS of Savalle et al. (2022, Section 5)
EC8_DRIFT_MEANINGS = {
    0.005: "brittle non-structural elements attached",
    0.0075: "ductile non-structural elements",
    0.01: "non-structural elements not interfering, or none (the DLS of Savalle et al. 2022)",
}
#: the drift whose angle is the DLS angle (Savalle et al. 2022, Section 5); summary.json's key for
#: it is ``repr(DLS_DRIFT)``, "0.01"
DLS_DRIFT = 0.01
#: a drift limit: a fraction of the height, at most all of it
DRIFT_LIMIT = Range(0.0, 1.0, low_open=True)


def drifts(ux_m, height_m: float) -> np.ndarray:
    """The drift of each equilibrium state of a pushover curve, (ux - ux_0) / height: its
    monitored displacements ``ux_m`` (m, from as drawn) since the first, the equilibrium under
    the wall's own weight, over the wall's ``height_m`` (m)."""
    ux = np.asarray(ux_m, dtype=float)
    return (ux - ux[0]) / height_m if ux.size else ux


def drift_limit_angles(angle_deg, drift, limits=EC8_DRIFT_LIMITS) -> dict[float, float | None]:
    """Angle at which ``drift`` first reaches each limit, linearly interpolated between the
    recorded equilibrium states (``angle_deg`` increasing); None where it never does.
    Keys are the limits as numbers (0.005, 0.0075, 0.01); the summary file, JSON, writes them
    as the strings "0.005", "0.0075", "0.01". ModelError unless ``angle_deg`` and ``drift`` are
    1-D arrays of finite numbers of one length, the angles never decreasing, and each limit a
    number in (0, 1] (found by a hunt: NaN, decreasing angles and a limit True gave answers)."""
    angle, d = real_array(angle_deg), real_array(drift)
    finite = angle is not None and d is not None and np.isfinite(angle).all() and np.isfinite(d).all()
    if not finite or angle.ndim != 1 or angle.shape != d.shape:
        raise ModelError(f"drift_limit_angles angle_deg = {given(angle_deg)}, drift = {given(drift)}: must be 1-D arrays of finite "
                         "numbers of one length")
    if (np.diff(angle) < 0).any():
        raise ModelError(f"drift_limit_angles angle_deg = {given(angle_deg)}: the angles of the states must not decrease")
    for limit in limits:
        DRIFT_LIMIT.check(limit, "drift_limit_angles limit")
    result: dict[float, float | None] = {}
    for limit in limits:
        reached = np.flatnonzero(d >= limit)
        if reached.size == 0:
            result[limit] = None
            continue
        k = int(reached[0])
        if k == 0:
            result[limit] = float(angle[0])
            continue
        t = (limit - d[k - 1]) / (d[k] - d[k - 1])
        result[limit] = float(angle[k - 1] + t * (angle[k] - angle[k - 1]))
    return result
