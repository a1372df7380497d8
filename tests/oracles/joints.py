"""The stress-dependent joint laws of :mod:`drydem.engine.joints`, by numerical integration: the
tests' oracle of the closed forms.

The normal law is d sigma = kn(sigma) d u_n from the unloaded joint, so the closure at a stress
is the integral of the compliance, u(sigma) = int_0^sigma d s / kn(s) (scipy's adaptive
quadrature), and the stress at a closure its inverse (Brent's method). Written from the law's
definition alone (the clamped power or affine stiffness), without the breakpoints or inversions
the compiled code uses.
"""

from __future__ import annotations

import numpy as np
from scipy.integrate import quad
from scipy.optimize import brentq

from drydem.engine.joints import AFFINE, POWER


def stiffness(stress: float, k: float, exponent: float, per_stress: float, joint) -> float:
    """The clamped stiffness of the law of ``joint`` (a StressJoint) at ``stress`` >= 0, Pa/m."""
    if joint.law == POWER:
        value = k * (stress / joint.stress_ref) ** exponent
    else:
        assert joint.law == AFFINE
        value = k + per_stress * stress
    return float(np.clip(value, joint.k_min, joint.k_max))


def normal_stiffness(stress: float, joint) -> float:
    return stiffness(max(stress, 0.0), joint.kn, joint.exponent_n, joint.per_stress_n, joint)


def shear_stiffness(stress: float, joint) -> float:
    return stiffness(max(stress, 0.0), joint.ks, joint.exponent_s, joint.per_stress_s, joint)


def closure_of_stress(stress: float, joint) -> float:
    """u(sigma) = int_0^sigma ds / kn(s), m: quadrature over the pieces of a geometric grid from
    1e-16 sigma up (a kink of the clamp, however close to zero, lies within one short piece)."""
    if stress <= 0.0:
        return 0.0
    edges = np.concatenate([[0.0], np.geomspace(1e-16 * stress, stress, 65)])
    return sum(quad(lambda s: 1.0 / normal_stiffness(s, joint), lo, hi, epsabs=0.0, epsrel=1e-13, limit=200)[0]
               for lo, hi in zip(edges[:-1], edges[1:]))


def stress_of_closure(closure: float, joint) -> float:
    """sigma(u), Pa: the inverse of :func:`closure_of_stress` (the stiffness at zero stress in opening)."""
    if closure <= 0.0:
        return normal_stiffness(0.0, joint) * closure
    high = joint.k_min * closure  # the softest spring gives the least stress; the stiffest...
    while closure_of_stress(high, joint) < closure:
        high *= 2.0
    return brentq(lambda s: closure_of_stress(s, joint) - closure, 0.0, high, xtol=1e-300, rtol=1e-14)


def stresses_of_closures(closure: np.ndarray, joint) -> np.ndarray:
    return np.array([stress_of_closure(u, joint) for u in np.asarray(closure, float)])
