"""The per-block contact stiffness and critical timestep of :mod:`drydem.engine.inertia`, with
NumPy weighted bincounts and LAPACK's eigvalsh, and the highest natural frequency of the
assembled springs that the timestep bounds (SciPy's Lanczos): the tests' oracles."""

from __future__ import annotations

import numpy as np

from drydem.engine.contacts import SubContacts
from drydem.model.rotation import matrices


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


def skew(v: np.ndarray) -> np.ndarray:
    """(..., 3, 3) [v]x, the matrix of v x ."""
    out = np.zeros(v.shape[:-1] + (3, 3))
    out[..., 0, 1], out[..., 0, 2], out[..., 1, 2] = -v[..., 2], v[..., 1], -v[..., 0]
    return out - np.swapaxes(out, -1, -2)


def highest_omega_sq(model, state, sub: SubContacts, stiffness: np.ndarray, movable: np.ndarray) -> float:
    """lambda_max(M^-1 K), 1/s2: the highest natural frequency squared of the blocks ``movable``
    on the sub-contacts ``sub``, each an isotropic spring ``stiffness`` (ns,) Pa/m times its
    area (as the timestep bound counts them). K = sum k G^T G over the springs, G (3 x 12) the
    map of the two blocks' motions (translation; rotation about the centroid, in the body
    frame) to the relative displacement of the spring's point, in the whitened coordinates
    sqrt(m) u and L^T theta (I = L L^T); its largest eigenvalue by SciPy's eigsh."""
    import scipy.sparse as sp
    from scipy.sparse.linalg import eigsh

    ref, inc = sub.block_ref, sub.block_inc
    rotation = matrices(state.quaternion)
    whitening = model.block_inertia_whitening

    def motion_map(block, arm):
        translation = np.broadcast_to(np.eye(3), (len(block), 3, 3)) / np.sqrt(model.block_mass[block])[:, None, None]
        turn = -rotation[block] @ skew(arm) @ whitening[block].transpose(0, 2, 1)
        return np.concatenate([translation, turn], axis=2) * movable[block][:, None, None]

    g = np.concatenate([-motion_map(ref, sub.point_ref_body), motion_map(inc, sub.point_inc_body)], axis=2)
    g *= np.sqrt(stiffness * sub.area)[:, None, None]
    dofs = np.concatenate([6 * ref[:, None] + np.arange(6), 6 * inc[:, None] + np.arange(6)], axis=1)
    blocks = np.einsum("sij,sik->sjk", g, g)
    rows, cols = np.repeat(dofs, 12, axis=1).ravel(), np.tile(dofs, (1, 12)).ravel()
    k = sp.coo_matrix((blocks.ravel(), (rows, cols)), shape=(6 * model.n_blocks,) * 2).tocsr()
    return float(eigsh(k, k=1, which="LA", return_eigenvectors=False)[0])
