"""The per-block contact stiffness and critical timestep of :mod:`drydem.engine.inertia`, with
NumPy weighted bincounts and LAPACK's eigvalsh: the tests' oracles of the compiled ones."""

from __future__ import annotations

import numpy as np

from drydem.engine.contacts import SubContacts


def contact_stiffness_reference(sub: SubContacts, stiffness: np.ndarray, n_blocks: int) -> tuple[np.ndarray, np.ndarray]:
    """The same as :func:`contact_stiffness` (``stiffness`` (ns,) Pa/m), with NumPy weighted bincounts."""
    k = stiffness * sub.area
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


def critical_timestep_reference(mass, whitening, movable, k_t, k_r) -> float:
    """The same as :func:`critical_timestep`, with numpy.linalg.eigvalsh."""
    rotational = np.linalg.eigvalsh(whitening @ k_r @ whitening.transpose(0, 2, 1))[:, -1]
    omega_sq = (2.0 * (k_t / mass + rotational))[movable]
    if omega_sq.size == 0 or omega_sq.max() <= 0:
        return np.inf
    return float(2.0 / np.sqrt(omega_sq.max()))
