"""Inertia for the explicit integration: critical timestep, mass scaling, local damping.

Critical timestep. The central-difference scheme is stable for dt < 2 / omega_max
(omega_max the highest natural frequency). For a block i touched by springs of
stiffness k_s = max(kn, ks) A_s at lever arms r_s from its centroid, a spring moves
the point with inverse mass 1/m + r_s^2 / I_min, and the partner block adds at most as
much again (Gershgorin bound), so

    omega_i^2 <= 2 sum_s k_s (1/m_i + r_s^2 / I_min,i) = 2 (K_t / m_i + K_r / I_min,i)

and dt = safety * 2 / max_i omega_i (Cundall & Strack 1979; Itasca 3DEC manual,
"Timestep determination").

Mass scaling (statics only: inertia does not change the equilibrium). Each free
block gets the fictitious mass m' = C K_t and isotropic inertia I' = C K_r with
C = (dt / safety)^2, so every block is critical at the same dt: the slow, heavy
modes no longer wait for the stiff, light ones (Underwood 1983, "Dynamic relaxation";
3DEC's density scaling). Gravity still acts on the true mass.
"""

from __future__ import annotations

from typing import NamedTuple

import numba
import numpy as np

from drydem.contacts import SubContacts


class BlockArrays(NamedTuple):
    """Per-block constants for the kernels (nb blocks).

    mass : (nb,) kg, true mass (gravity). inv_mass : (nb,) 1/kg, of the mass used for
    the motion (scaled or true). inertia_body, inv_inertia_body : (nb, 3, 3) kg m2 and its
    inverse, about the centroid in the body frame. free : (nb, 6) 1.0 where the degree of
    freedom (x, y, z, rx, ry, rz) moves, 0.0 where fixed. radius : (nb,) m, largest
    distance from the centroid to a vertex.
    """

    mass: np.ndarray
    inv_mass: np.ndarray
    inertia_body: np.ndarray
    inv_inertia_body: np.ndarray
    free: np.ndarray
    radius: np.ndarray


def contact_stiffness(sub: SubContacts, kn: float, ks: float, n_blocks: int) -> tuple[np.ndarray, np.ndarray]:
    """Per-block translational K_t (N/m) and rotational K_r (N m) sums of its sub-contact springs."""
    k = max(kn, ks) * sub.area
    k_t = np.bincount(sub.block_ref, k, n_blocks) + np.bincount(sub.block_inc, k, n_blocks)
    r_ref = np.einsum("ni,ni->n", sub.point_ref_body, sub.point_ref_body)
    r_inc = np.einsum("ni,ni->n", sub.point_inc_body, sub.point_inc_body)
    k_r = np.bincount(sub.block_ref, k * r_ref, n_blocks) + np.bincount(sub.block_inc, k * r_inc, n_blocks)
    return k_t, k_r


def critical_timestep(mass: np.ndarray, inertia_body: np.ndarray, movable: np.ndarray, k_t: np.ndarray, k_r: np.ndarray) -> float:
    """2 / omega_max with omega_i^2 = 2 (K_t / m + K_r / I_min), s (inf if nothing is sprung)."""
    i_min = np.linalg.eigvalsh(inertia_body)[:, 0]
    omega_sq = 2.0 * (k_t / mass + k_r / i_min)
    omega_sq = omega_sq[movable]
    if omega_sq.size == 0 or omega_sq.max() <= 0:
        return np.inf
    return float(2.0 / np.sqrt(omega_sq.max()))


def scaled_inertia(
    mass: np.ndarray, inertia_body: np.ndarray, k_t: np.ndarray, k_r: np.ndarray, timestep: float, safety: float
) -> tuple[np.ndarray, np.ndarray]:
    """Fictitious masses m' = C K_t and inertias I' = C K_r 1, C = (dt / safety)^2 (see module docstring).

    Blocks without springs keep their true mass and inertia (free flight is dynamics).
    """
    c = (timestep / safety) ** 2
    sprung = (k_t > 0) & (k_r > 0)
    m = np.where(sprung, c * k_t, mass)
    inertia = np.where(sprung[:, None, None], c * k_r[:, None, None] * np.eye(3), inertia_body)
    return m, inertia


@numba.njit(cache=True, inline="always")
def local_damping(force: float, velocity: float, alpha: float) -> float:
    """Damped force F - alpha |F| sign(v) of one degree of freedom (paper Eq. 4; Cundall 1987)."""
    if velocity > 0.0:
        return force - alpha * abs(force)
    if velocity < 0.0:
        return force + alpha * abs(force)
    return force
