"""Damping: local damping for statics, viscous damping for dynamics.

Local damping (3DEC's default for statics): a force opposing the motion of each degree of
freedom, proportional to the unbalanced force, so that the blocks come to rest without the
viscous drag that would slow a rigid-body motion (Cundall 1987, "Distinct element models of
rock and soil structure", in Analytical and Computational Methods in Engineering Rock Mechanics).
It is a relaxation device, not physics: a time history runs without it.

Viscous damping (dynamics; Itasca 3DEC manual, "Mechanical damping"): a dashpot beside the
normal spring of every sub-contact, c = A (2 zeta sqrt(kn m_ab / A_c) + beta kn), N s/m, with
A the sub-contact's area, A_c the contact's and m_ab = m_a m_b / (m_a + m_b) the pair's
reduced mass (a fixed block counts as infinitely heavy): ``contact_ratio`` zeta is the
critical-damping ratio of the contact's bounce (the pair on its joint, k = kn A_c), the way
impacts lose energy (a coefficient of restitution, :mod:`drydem.analysis.shake.restitution`);
``stiffness_proportional`` beta (s) is Rayleigh's stiffness term on the joints. The dashpot
acts only while the sub-contact is closed, and never pulls (the normal force stays >= 0:
Vlachakis, Giouvanidis, Mehrotra & Lourenco 2021, J. Eng. Mech. 147(11), 04021089, on damping
that acts only at impact). Rayleigh's mass term ``mass_proportional`` alpha (1/s) is a force
-alpha m v on every block (and -alpha I omega), in the frame of the table.
"""

from __future__ import annotations

from typing import NamedTuple

import numba
import numpy as np

from drydem import compiled_cache
from drydem.model.parameters import Range


class Damping(NamedTuple):
    """The damping a cycle applies (see module docstring).

    local : local damping coefficient (paper Eq. 4), 0 <= alpha < 1. contact_ratio : zeta,
    critical-damping ratio of the contacts' normal dashpots. stiffness_proportional : beta, s,
    Rayleigh's stiffness-proportional coefficient on the normal springs. mass_proportional :
    alpha_R, 1/s, Rayleigh's mass-proportional coefficient.
    """

    local: float
    contact_ratio: float = 0.0
    stiffness_proportional: float = 0.0
    mass_proportional: float = 0.0


#: the range of each viscous coefficient of :class:`Damping` (drydem shake's options are held to
#: the same): a contact damping ratio up to 10, Rayleigh's stiffness term up to 1 s and its mass
#: term up to 1e6 1/s; beyond them the timestep they need (:func:`timestep_factor`,
#: :func:`drag_timestep`) shrinks towards nothing (a ratio of 1e8 gave a timestep of 0, and the
#: cycles moved nothing)
VISCOUS_RULES = {"contact_ratio": Range(0.0, 10.0, unit="(ratio of critical)"), "stiffness_proportional": Range(0.0, 1.0, unit="s"),
                 "mass_proportional": Range(0.0, 1e6, unit="1/s")}


@numba.njit(cache=True, inline="always")
def has_dashpots(damping) -> bool:
    """Whether the contacts of a :class:`Damping` have dashpots."""
    return damping.contact_ratio > 0.0 or damping.stiffness_proportional > 0.0


def timestep_factor(damping: Damping, critical_timestep: float) -> float:
    """The factor on the undamped critical timestep that keeps the central differences stable
    with the dashpots: dt_crit = (2 / omega) (sqrt(1 + z^2) - z) for an oscillator of damping
    ratio z (Belytschko & Hughes 1983, "Computational Methods for Transient Analysis", Ch. 2).

    The ratio at the highest frequency omega_max = 2 / dt_crit is bounded by
    z = 2 zeta + beta / dt_crit: Rayleigh's stiffness term gives beta omega_max / 2; a dashpot
    proportional to its spring damps each mode in proportion to its frequency, and the rocking
    mode of a rectangular block (2b x 2h) on its bed joint is at most sqrt(3) times as fast as
    its bounce (omega_rock^2 / omega_bounce^2 = (b^2 + 3 h^2) / (b^2 + h^2) <= 3), so a contact's
    ratio zeta, set for the bounce, is less than doubled there; Rayleigh's mass term alpha adds
    alpha / (2 omega_max) = alpha dt_crit / 4 (and :func:`drag_timestep` bounds it apart)."""
    z = 2.0 * damping.contact_ratio + damping.stiffness_proportional / critical_timestep + damping.mass_proportional * critical_timestep / 4
    return float(np.sqrt(1.0 + z * z) - z)


#: the most of its velocity Rayleigh's mass term takes from a block in one step, alpha dt
#: (:func:`drag_timestep`)
MASS_DRAG_PER_STEP = 0.1


def drag_timestep(damping: Damping) -> float:
    """The longest timestep, s, that resolves Rayleigh's mass term alpha, applied explicitly (each
    velocity times 1 - alpha dt, springs or none): alpha dt <= :data:`MASS_DRAG_PER_STEP`, so the
    velocity decays at the rate -ln(1 - alpha dt) / dt, within 5 % of alpha (at alpha dt > 1
    the drag reversed the velocity every step, beyond 2 it grew: a one-sine pulse on a block
    diverged at alpha = 2e4 1/s, alpha dt = 1.3, before this bound); infinite without it."""
    return MASS_DRAG_PER_STEP / damping.mass_proportional if damping.mass_proportional > 0.0 else np.inf


@numba.njit(cache=True, inline="always")
def local_damping(force: float, velocity: float, alpha: float) -> float:
    """Damped force F - alpha |F| sign(v) of one degree of freedom (paper Eq. 4; Cundall 1987)."""
    if velocity > 0.0:
        return force - alpha * abs(force)
    if velocity < 0.0:
        return force + alpha * abs(force)
    return force


@numba.njit(cache=True, inline="always")
def dashpot_per_area(start, end, area, inv_mass_a, inv_mass_b, kn, damping):
    """c / A (N s/m3) of the sub-contacts start..end-1 of one contact: 2 zeta sqrt(kn m_ab / A_c)
    + beta kn (module docstring); 0 when both blocks are held."""
    inv_sum = inv_mass_a + inv_mass_b
    if inv_sum == 0.0:
        return 0.0
    contact_area = 0.0
    for s in range(start, end):
        contact_area += area[s]
    if contact_area <= 0.0:
        return 0.0
    return 2.0 * damping.contact_ratio * np.sqrt(kn / (inv_sum * contact_area)) + damping.stiffness_proportional * kn


@numba.njit(cache=True, inline="always")
def dashpot_force(normal_force: float, opening_speed: float, coefficient: float) -> float:
    """The dashpot's normal force, N, for a normal spring force ``normal_force`` (N, compression
    > 0) and opening speed v_n (m/s): -c v_n, but no more pull than the spring pushes, so the
    sum stays >= 0 (a dashpot does not glue an opening joint)."""
    return max(-coefficient * opening_speed, -max(normal_force, 0.0))


compiled_cache.check(__name__)  # last: none of the functions above is loaded from a stale cache
