"""Mass properties of convex polyhedra against closed forms."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import drydem as dd
from conftest import box_vertices


def test_box_mass_properties_match_closed_form():
    # solid cuboid a x b x c: V = abc, I_xx = m (b^2 + c^2) / 12 (any statics textbook)
    a, b, c, rho = 0.025, 0.012, 0.0055, 1800.0
    shape = dd.box([1.0, 2.0, 3.0], [1.0 + a, 2.0 + b, 3.0 + c])
    m = rho * a * b * c
    assert shape.volume == pytest.approx(a * b * c, rel=1e-12)
    np.testing.assert_allclose(shape.centroid, [1 + a / 2, 2 + b / 2, 3 + c / 2], rtol=1e-12)
    expected = np.diag([m * (b * b + c * c) / 12, m * (a * a + c * c) / 12, m * (a * a + b * b) / 12])
    np.testing.assert_allclose(shape.inertia_tensor(rho), expected, rtol=1e-10, atol=1e-20)
    assert len(shape.faces) == 6 and all(len(f) == 4 for f in shape.faces)


def test_tetrahedron_mass_properties_match_closed_form():
    # unit right tetrahedron: V = 1/6, centroid (1/4, 1/4, 1/4),
    # products of inertia about the centroid: I_xx = 1/80 rho ... (Tonon 2004, eq. for the corner tetrahedron):
    # about the origin integral x^2 dV = 1/60, integral xy dV = 1/120
    shape = dd.convex_hull([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
    assert shape.volume == pytest.approx(1 / 6)
    np.testing.assert_allclose(shape.centroid, [0.25] * 3)
    c_origin = np.full((3, 3), 1 / 120) + np.eye(3) * (1 / 60 - 1 / 120)
    expected = c_origin - (1 / 6) * np.outer(shape.centroid, shape.centroid)
    np.testing.assert_allclose(shape.second_moment, expected, atol=1e-15)


def test_rotated_polyhedron_inertia_is_r_i_rt():
    rot = Rotation.from_euler("xyz", [10, 20, 30], degrees=True).as_matrix()
    straight = dd.box([0, 0, 0], [0.3, 0.2, 0.1])
    turned = dd.convex_hull(box_vertices([0, 0, 0], [0.3, 0.2, 0.1]) @ rot.T)
    np.testing.assert_allclose(turned.inertia_tensor(1.0), rot @ straight.inertia_tensor(1.0) @ rot.T, atol=1e-15)


def test_faces_are_counter_clockwise_with_outward_normals():
    shape = dd.convex_hull([[0, 0, 0], [2, 0, 0], [2, 1, 0], [0, 1, 0], [0.5, 0.5, 1.0], [1.5, 0.5, 1.0]])
    for f, normal in enumerate(shape.face_normals):
        p = shape.face_polygon(f)
        area_vector = 0.5 * np.cross(p, np.roll(p, -1, axis=0)).sum(0)
        assert np.dot(area_vector, normal) > 0  # counter-clockwise seen from outside
        assert np.dot(p.mean(0) - shape.centroid, normal) > 0  # outward
    total_area_vector = sum(shape.face_area(f) * n for f, n in enumerate(shape.face_normals))
    np.testing.assert_allclose(total_area_vector, 0, atol=1e-12)  # closed surface


def test_non_convex_vertex_set_is_rejected_naming_the_block():
    points = box_vertices([0, 0, 0], [1, 1, 1]).tolist() + [[0.5, 0.5, 0.5]]
    with pytest.raises(dd.GeometryError, match=r"pier.*vertex 8.*not convex"):
        dd.convex_hull(points, name="pier")


@pytest.mark.parametrize(
    "points, reason",
    [
        ([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]], "coplanar"),
        ([[0, 0, 0], [1, 0, 0], [0, 1, 0]], "at least 4"),
        ([[0, 0, 0], [1, 0, 0], [0, 1], [1, 1, 1]], "list of"),
    ],
)
def test_degenerate_blocks_are_rejected(points, reason):
    with pytest.raises(dd.GeometryError, match=reason):
        dd.convex_hull(points, name="flat")


def test_inverted_box_is_rejected():
    with pytest.raises(dd.GeometryError, match="max .* must exceed min"):
        dd.box([0, 0, 0], [1, -1, 1], name="upside")
