"""Inertia for the explicit integration: critical timestep, mass scaling, local damping.

Critical timestep. The central-difference scheme is stable for dt < 2 / omega_max
(omega_max the highest natural frequency). Block i is touched by springs of stiffness
k_s = max(kn, ks) A_s at lever arms r_s from its centroid; they give it the translational
stiffness K_t = sum_s k_s (N/m) and the rotational stiffness matrix
K_r = sum_s k_s (|r_s|^2 1 - r_s r_s^T) (N m). The block alone on fixed partners has
omega^2 <= K_t / m + lambda_max(I^-1 K_r) (a positive block matrix is bounded by the sum
of its diagonal blocks), and moving partners at most double it (Gershgorin), so

    omega_i^2 <= 2 (K_t / m_i + lambda_max(I_i^-1 K_r,i))

and dt = safety * 2 / max_i omega_i (Cundall & Strack 1979; Itasca 3DEC manual,
"Timestep determination").

Mass scaling (statics only: inertia does not change the equilibrium). Each sprung
block gets the fictitious mass m' = C K_t and inertia I' = C K_r with C = (dt / safety)^2,
so every block is critical at the same dt: the slow, heavy modes no longer wait for
the stiff, light ones (Underwood 1983, "Dynamic relaxation"; 3DEC's density scaling).
Gravity still acts on the true mass.
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
    origin: np.ndarray


def contact_stiffness(sub: SubContacts, kn: float, ks: float, n_blocks: int) -> tuple[np.ndarray, np.ndarray]:
    """Per-block K_t (nb,) N/m and K_r (nb, 3, 3) N m of its sub-contact springs (body frame):
    K_t = sum_s k_s, K_r = trace(S) 1 - S with S = sum_s k_s r_s r_s^T, k_s = max(kn, ks) A_s.
    Compiled (it runs at every re-detection); :func:`contact_stiffness_reference` is the oracle."""
    return _contact_stiffness(sub.pairs, sub.start, sub.point_ref_body, sub.point_inc_body, sub.area, max(kn, ks), n_blocks)


@numba.njit(cache=True)
def _contact_stiffness(pairs, start, point_ref_body, point_inc_body, area, k_per_area, n_blocks):
    k_t = np.zeros(n_blocks)
    second = np.zeros((n_blocks, 3, 3))
    for c in range(pairs.shape[0]):
        for s in range(start[c], start[c + 1]):
            k = k_per_area * area[s]
            for side in range(2):
                b = pairs[c, side]
                arm = point_ref_body[s] if side == 0 else point_inc_body[s]
                k_t[b] += k
                for i in range(3):
                    for j in range(3):
                        second[b, i, j] += k * arm[i] * arm[j]
    k_r = -second
    for b in range(n_blocks):
        trace = second[b, 0, 0] + second[b, 1, 1] + second[b, 2, 2]
        for i in range(3):
            k_r[b, i, i] += trace
    return k_t, k_r


def contact_stiffness_reference(sub: SubContacts, kn: float, ks: float, n_blocks: int) -> tuple[np.ndarray, np.ndarray]:
    """The same as :func:`contact_stiffness`, with NumPy weighted bincounts."""
    k = max(kn, ks) * sub.area
    k_t = np.bincount(sub.block_ref, k, n_blocks) + np.bincount(sub.block_inc, k, n_blocks)
    second = np.zeros((n_blocks, 3, 3))
    for block, arm in ((sub.block_ref, sub.point_ref_body), (sub.block_inc, sub.point_inc_body)):
        for a in range(3):
            for b in range(a, 3):
                moment = np.bincount(block, k * arm[:, a] * arm[:, b], n_blocks)
                second[:, a, b] += moment
                if a != b:
                    second[:, b, a] += moment
    k_r = np.trace(second, axis1=1, axis2=2)[:, None, None] * np.eye(3) - second
    return k_t, k_r


def critical_timestep(mass: np.ndarray, whitening: np.ndarray, movable: np.ndarray, k_t: np.ndarray, k_r: np.ndarray) -> float:
    """2 / omega_max with omega_i^2 = 2 (K_t / m + lambda_max(I^-1 K_r)), s (inf if nothing is
    sprung); ``whitening`` is L^-1 for the inertias I = L L^T (Model.block_inertia_whitening), so
    that lambda(I^-1 K_r) = lambda(L^-1 K_r L^-T), a symmetric 3 x 3 eigenproblem, solved in
    closed form (compiled; :func:`critical_timestep_reference` uses LAPACK)."""
    omega_sq = _largest_omega_sq(mass, whitening, movable, k_t, k_r)
    return np.inf if omega_sq <= 0 else float(2.0 / np.sqrt(omega_sq))


@numba.njit(cache=True)
def _largest_omega_sq(mass, whitening, movable, k_t, k_r):
    largest = 0.0
    wk = np.empty((3, 3))
    a = np.empty((3, 3))
    for b in range(mass.shape[0]):
        if not movable[b]:
            continue
        w, k = whitening[b], k_r[b]
        for i in range(3):  # a = W K W^T, without temporaries (this runs at every re-detection)
            for j in range(3):
                wk[i, j] = w[i, 0] * k[0, j] + w[i, 1] * k[1, j] + w[i, 2] * k[2, j]
        for i in range(3):
            for j in range(3):
                a[i, j] = wk[i, 0] * w[j, 0] + wk[i, 1] * w[j, 1] + wk[i, 2] * w[j, 2]
        largest = max(largest, 2.0 * (k_t[b] / mass[b] + _largest_eigenvalue(a)))
    return largest


@numba.njit(cache=True, inline="always")
def _largest_eigenvalue(a):
    """Largest eigenvalue of a symmetric 3 x 3 matrix, trigonometric closed form (Smith 1961,
    "Eigenvalues of a symmetric 3 x 3 matrix", Comm. ACM 4(4), 168)."""
    off = a[0, 1] ** 2 + a[0, 2] ** 2 + a[1, 2] ** 2
    q = (a[0, 0] + a[1, 1] + a[2, 2]) / 3.0
    p2 = (a[0, 0] - q) ** 2 + (a[1, 1] - q) ** 2 + (a[2, 2] - q) ** 2 + 2.0 * off
    if p2 <= 1e-30 * max(q * q, 1e-300):
        return q
    p = np.sqrt(p2 / 6.0)
    # det of B = (A - q 1) / p, A symmetric
    b00, b11, b22 = (a[0, 0] - q) / p, (a[1, 1] - q) / p, (a[2, 2] - q) / p
    b01, b02, b12 = a[0, 1] / p, a[0, 2] / p, a[1, 2] / p
    det = b00 * (b11 * b22 - b12 * b12) - b01 * (b01 * b22 - b12 * b02) + b02 * (b01 * b12 - b11 * b02)
    r = min(max(det / 2.0, -1.0), 1.0)
    return q + 2.0 * p * np.cos(np.arccos(r) / 3.0)


def critical_timestep_reference(mass, whitening, movable, k_t, k_r) -> float:
    """The same as :func:`critical_timestep`, with numpy.linalg.eigvalsh."""
    rotational = np.linalg.eigvalsh(whitening @ k_r @ whitening.transpose(0, 2, 1))[:, -1]
    omega_sq = (2.0 * (k_t / mass + rotational))[movable]
    if omega_sq.size == 0 or omega_sq.max() <= 0:
        return np.inf
    return float(2.0 / np.sqrt(omega_sq.max()))


def scaled_inertia(
    mass: np.ndarray, inertia_body: np.ndarray, k_t: np.ndarray, k_r: np.ndarray, timestep: float, safety: float
) -> tuple[np.ndarray, np.ndarray]:
    """Fictitious masses m' = C K_t and inertias I' = C (K_r + delta 1), C = (dt / safety)^2 (see
    module docstring); delta = 1e-3 trace(K_r) / 3 keeps I' invertible where the springs do not
    hold every rotation (a block rocking on one edge) and leaves every block stable at dt.
    Blocks without springs keep their true mass and inertia (free flight is dynamics)."""
    c = (timestep / safety) ** 2
    sprung = k_t > 0
    delta = 1e-3 * np.trace(k_r, axis1=1, axis2=2) / 3.0
    m = np.where(sprung, c * k_t, mass)
    inertia = np.where(sprung[:, None, None], c * (k_r + delta[:, None, None] * np.eye(3)), inertia_body)
    return m, inertia


@numba.njit(cache=True, inline="always")
def local_damping(force: float, velocity: float, alpha: float) -> float:
    """Damped force F - alpha |F| sign(v) of one degree of freedom (paper Eq. 4; Cundall 1987)."""
    if velocity > 0.0:
        return force - alpha * abs(force)
    if velocity < 0.0:
        return force + alpha * abs(force)
    return force
