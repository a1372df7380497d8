"""Unit quaternions q = (w, x, y, z) for exact finite rotations, as numba functions.

A block's orientation is the quaternion taking its body frame (its orientation in
the model file) to the world frame. A constant angular velocity omega (world frame)
held for dt rotates it by the rotation vector phi = omega dt:

    q(t + dt) = exp(phi / 2) (x) q(t),   exp(phi / 2) = (cos |phi|/2, sin(|phi|/2) phi/|phi|)

which is exact for any |phi| (no small-angle update, so collapse with large
rotations keeps rigid blocks rigid). Below |phi| = SERIES_ANGLE (every cycle but the
fastest) cos and sin(x)/x of x = |phi|/2 come from their Taylor series to x^4, whose
error, under x^6 / 720 < 2e-17, is below rounding: exact and without trigonometric calls.
"""

from __future__ import annotations

import numba
import numpy as np

from drydem import compiled_cache

#: rotation angle (rad) below which the update uses the series of cos and sin (module docstring)
SERIES_ANGLE = 0.01


@numba.njit(cache=True, inline="always")
def quaternion_to_matrix(q: np.ndarray, out: np.ndarray) -> None:
    """Rotation matrix of the unit quaternion ``q`` written into ``out`` (3, 3)."""
    w, x, y, z = q[0], q[1], q[2], q[3]
    out[0, 0] = 1 - 2 * (y * y + z * z)
    out[0, 1] = 2 * (x * y - w * z)
    out[0, 2] = 2 * (x * z + w * y)
    out[1, 0] = 2 * (x * y + w * z)
    out[1, 1] = 1 - 2 * (x * x + z * z)
    out[1, 2] = 2 * (y * z - w * x)
    out[2, 0] = 2 * (x * z - w * y)
    out[2, 1] = 2 * (y * z + w * x)
    out[2, 2] = 1 - 2 * (x * x + y * y)


@numba.njit(cache=True, inline="always")
def mat_vec(r, v0, v1, v2):
    """R v for a 3 x 3 ``r`` and a vector given by its components (a tuple back, no array)."""
    return (
        r[0, 0] * v0 + r[0, 1] * v1 + r[0, 2] * v2,
        r[1, 0] * v0 + r[1, 1] * v1 + r[1, 2] * v2,
        r[2, 0] * v0 + r[2, 1] * v1 + r[2, 2] * v2,
    )


@numba.njit(cache=True, inline="always")
def mat_t_vec(r, v0, v1, v2):
    """R^T v, as :func:`mat_vec` (for a rotation, from the world frame to the body frame)."""
    return (
        r[0, 0] * v0 + r[1, 0] * v1 + r[2, 0] * v2,
        r[0, 1] * v0 + r[1, 1] * v1 + r[2, 1] * v2,
        r[0, 2] * v0 + r[1, 2] * v1 + r[2, 2] * v2,
    )


@numba.njit(cache=True, inline="always")
def rotate_by_vector(q: np.ndarray, phi_x: float, phi_y: float, phi_z: float) -> None:
    """q <- exp(phi / 2) (x) q in place, then renormalised (phi a rotation vector, rad; q a unit
    quaternion to round-off)."""
    angle_sq = phi_x * phi_x + phi_y * phi_y + phi_z * phi_z
    if angle_sq == 0.0:
        return
    cos_half, s = _half_angle(angle_sq)
    dw, dx, dy, dz = cos_half, s * phi_x, s * phi_y, s * phi_z
    w, x, y, z = q[0], q[1], q[2], q[3]
    nw = dw * w - dx * x - dy * y - dz * z
    nx = dw * x + dx * w + dy * z - dz * y
    ny = dw * y - dx * z + dy * w + dz * x
    nz = dw * z + dx * y - dy * x + dz * w
    # renormalised by one Newton step for 1 / sqrt(n) about n = 1: |q|^2 = 1 + e with e of the
    # order of round-off (q and exp(phi / 2) are unit to round-off), so the error is e^2
    inv_norm = 1.5 - 0.5 * (nw * nw + nx * nx + ny * ny + nz * nz)
    q[0], q[1], q[2], q[3] = nw * inv_norm, nx * inv_norm, ny * inv_norm, nz * inv_norm


@numba.njit(cache=True, inline="always")
def rotate_about_y(q: np.ndarray, phi_y: float) -> None:
    """:func:`rotate_by_vector` for q = (w, 0, y, 0) and phi = (0, phi_y, 0) (in-plane blocks,
    drydem.engine.cycle_planar): q <- (c w - s y, 0, c y + s w, 0) with c, s = cos, sin(phi_y / 2)."""
    cos_half, s = _half_angle(phi_y * phi_y)
    sin_half = s * phi_y
    w, y = q[0], q[2]
    nw, ny = cos_half * w - sin_half * y, cos_half * y + sin_half * w
    inv_norm = 1.5 - 0.5 * (nw * nw + ny * ny)  # as in rotate_by_vector
    q[0], q[2] = nw * inv_norm, ny * inv_norm


@numba.njit(cache=True, inline="always")
def _half_angle(angle_sq: float) -> tuple[float, float]:
    """cos(|phi| / 2) and sin(|phi| / 2) / |phi| from |phi|^2 (series below SERIES_ANGLE)."""
    if angle_sq < SERIES_ANGLE * SERIES_ANGLE:
        x2 = 0.25 * angle_sq  # (|phi| / 2)^2
        return 1.0 - x2 / 2.0 * (1.0 - x2 / 12.0), 0.5 * (1.0 - x2 / 6.0 * (1.0 - x2 / 20.0))
    angle = np.sqrt(angle_sq)
    return np.cos(0.5 * angle), np.sin(0.5 * angle) / angle


@numba.njit(cache=True)
def matrices(quaternion: np.ndarray) -> np.ndarray:
    """(n, 3, 3) rotation matrices of (n, 4) unit quaternions."""
    out = np.empty((quaternion.shape[0], 3, 3))
    for i in range(quaternion.shape[0]):
        quaternion_to_matrix(quaternion[i], out[i])
    return out


def rotation_vectors(q_from: np.ndarray, q_to: np.ndarray) -> np.ndarray:
    """(n, 3) world-frame rotation vectors phi (rad) with q_to = exp(phi / 2) (x) q_from (the
    convention of :func:`rotate_by_vector`), for (n, 4) unit quaternions (scipy's Rotation)."""
    from scipy.spatial.transform import Rotation

    scalar_last = [1, 2, 3, 0]
    return (Rotation.from_quat(q_to[:, scalar_last]) * Rotation.from_quat(q_from[:, scalar_last]).inv()).as_rotvec()


def turn_angles(q_from: np.ndarray, q_to: np.ndarray) -> np.ndarray:
    """(n,) angles (rad, in [0, pi]) of the rotations from q_from to q_to, (n, 4) unit quaternions:
    2 arccos |q_from . q_to|. Cheap, for comparing turns with a threshold (arccos loses digits
    below ~1e-8 rad; :func:`rotation_vectors` does not)."""
    return 2.0 * np.arccos(np.minimum(np.abs(np.einsum("ni,ni->n", q_from, q_to)), 1.0))


def turns_from_drawn(quaternion: np.ndarray) -> np.ndarray:
    """(n,) angles (rad) of the rotations (n, 4) ``quaternion`` from the blocks' orientation as
    drawn, the identity: :func:`turn_angles` from it, 2 arccos |w|."""
    return turn_angles(np.broadcast_to([1.0, 0.0, 0.0, 0.0], quaternion.shape), quaternion)


compiled_cache.check(__name__)  # last: none of the functions above is loaded from a stale cache
