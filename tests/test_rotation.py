"""Quaternion kernels against scipy's Rotation (an independent implementation)."""

import numpy as np
from scipy.spatial.transform import Rotation

from drydem.model.rotation import matrices, rotate_by_vector


def test_quaternion_matrices_match_scipy():
    rng = np.random.default_rng(1)
    rotations = Rotation.random(50, random_state=rng)
    q = rotations.as_quat()[:, [3, 0, 1, 2]]  # scipy is scalar-last
    np.testing.assert_allclose(matrices(q), rotations.as_matrix(), atol=1e-14)


def test_finite_rotation_update_is_exact_for_large_angles():
    rng = np.random.default_rng(2)
    for _ in range(20):
        start = Rotation.random(random_state=rng)
        phi = rng.normal(size=3) * 2.0  # up to several radians: no small-angle approximation
        q = start.as_quat()[[3, 0, 1, 2]].copy()
        rotate_by_vector(q, *phi)
        expected = (Rotation.from_rotvec(phi) * start).as_matrix()
        np.testing.assert_allclose(matrices(q[None])[0], expected, atol=1e-13)
        assert abs(np.linalg.norm(q) - 1.0) < 1e-15


def test_small_rotations_by_series_are_exact_to_round_off():
    """Below SERIES_ANGLE the update uses Taylor series of cos and sin (to x^4, error < x^6/720):
    against scipy at angles from 1e-12 rad to just over the switch, to 1e-15."""
    from drydem.model.rotation import SERIES_ANGLE

    rng = np.random.default_rng(3)
    for angle in np.concatenate([np.geomspace(1e-12, SERIES_ANGLE, 25), [SERIES_ANGLE * 1.01]]):
        axis = rng.normal(size=3)
        phi = angle * axis / np.linalg.norm(axis)
        start = Rotation.random(random_state=rng)
        q = start.as_quat()[[3, 0, 1, 2]].copy()
        rotate_by_vector(q, *phi)
        expected = (Rotation.from_rotvec(phi) * start).as_quat()[[3, 0, 1, 2]]
        np.testing.assert_allclose(q * np.sign(q[0] * expected[0]), expected, rtol=0, atol=1e-15)


def test_rotation_vectors_undo_the_update():
    from drydem.model.rotation import rotation_vectors, turn_angles

    rng = np.random.default_rng(4)
    start = Rotation.random(10, random_state=rng).as_quat()[:, [3, 0, 1, 2]]
    phi = rng.normal(size=(10, 3)) * 0.5
    end = start.copy()
    for q, p in zip(end, phi):
        rotate_by_vector(q, *p)
    np.testing.assert_allclose(rotation_vectors(start, end), phi, atol=1e-13)
    np.testing.assert_allclose(turn_angles(start, end), np.linalg.norm(phi, axis=1), atol=1e-7)  # arccos: ~1e-8 near 0
    np.testing.assert_allclose(turn_angles(start, -end), np.linalg.norm(phi, axis=1), atol=1e-7)  # q and -q: one rotation


def test_rotation_about_y_of_in_plane_blocks_is_the_general_update():
    """The planar kernel's update of q = (w, 0, y, 0) against rotate_by_vector with phi = (0, phi_y, 0),
    across the series switch and up to several radians."""
    from drydem.model.rotation import SERIES_ANGLE, rotate_about_y

    rng = np.random.default_rng(5)
    for angle in np.concatenate([[0.0], np.geomspace(1e-12, SERIES_ANGLE, 15), [SERIES_ANGLE * 1.01, 0.3, 2.5]]):
        for sign in (1.0, -1.0):
            half = rng.uniform(-np.pi, np.pi) / 2
            general = np.array([np.cos(half), 0.0, np.sin(half), 0.0])
            planar = general.copy()
            rotate_by_vector(general, 0.0, sign * angle, 0.0)
            rotate_about_y(planar, sign * angle)
            np.testing.assert_allclose(planar, general, rtol=0, atol=1e-15)
