"""Geometry in and out: VRML import, OBJ/STL round trips, VTK export for ParaView."""

import textwrap

import numpy as np
import pytest

from drydem.errors import ModelError
from drydem.io.mesh import STL_TRIANGLE, read_mesh, write_mesh
from drydem.io.target import load_target
from drydem.io.vrml import read_vrml
from drydem.io.vtk import write_vtu
from drydem.model.state import State
from wall_fixtures import benchmark_wall

#: two 20 x 12 x 10 mm boxes in millimetres, as Rhino writes them: an IndexedFaceSet under a
#: Transform, and a Box under a Transform turned 90 deg about z (its 12 x 20 footprint becomes 20 x 12)
TWO_BOXES = """\
#VRML V2.0 utf8
WorldInfo { title "two boxes" info [ "written by the test" ] }
DEF left Transform {
  translation 10 0 5
  children [
    Shape {
      appearance Appearance { material Material { diffuseColor 0.8 0.4 0.2 } }
      geometry IndexedFaceSet {
        coord Coordinate { point [ -10 -6 -5, 10 -6 -5, 10 6 -5, -10 6 -5,
                                   -10 -6 5, 10 -6 5, 10 6 5, -10 6 5 ] }
        coordIndex [ 0 3 2 1 -1, 4 5 6 7 -1, 0 1 5 4 -1, 1 2 6 5 -1, 2 3 7 6 -1, 3 0 4 7 -1 ]
      }
    }
  ]
}
Transform {
  translation 30 0 5
  rotation 0 0 1 1.5707963267948966
  children DEF right Shape { geometry Box { size 12 20 10 } }
}
"""


def write(tmp_path, text, name="wall.wrl"):
    path = tmp_path / name
    path.write_text(textwrap.dedent(text))
    return path


def extent(block):
    return block.shape.vertices.min(0), block.shape.vertices.max(0)


def test_vrml_boxes_under_transforms_import_to_the_right_blocks(tmp_path):
    blocks, _ = read_vrml(write(tmp_path, TWO_BOXES), unit_m=1e-3)
    assert [b.name for b in blocks] == ["left", "right"]
    for block, x0 in zip(blocks, (0.0, 0.02)):
        assert block.shape.volume == pytest.approx(0.02 * 0.012 * 0.01)
        lo, hi = extent(block)
        np.testing.assert_allclose(lo, [x0, -0.006, 0.0], atol=1e-12)
        np.testing.assert_allclose(hi, [x0 + 0.02, 0.006, 0.01], atol=1e-12)


def test_vrml_transform_applies_scale_about_its_centre_and_use_repeats_a_node(tmp_path):
    # ISO/IEC 14772-1, 6.52: P' = T C R SR S SR^-1 C^-1 P; a unit cube scaled x2 in x about
    # the centre (1, 0, 0) spans x in [-1.5, 0.5] - 1 + ... worked out: x' = 2 (x - 1) + 1
    text = """\
    #VRML V2.0 utf8
    Transform { scale 2 1 1 center 1 0 0 children DEF cube Shape { geometry Box { size 1 1 1 } } }
    Transform { translation 0 0 5 children USE cube }
    """
    path = write(tmp_path, text)
    (scaled, moved), notes = read_vrml(path)
    lo, hi = extent(scaled)
    np.testing.assert_allclose(lo, [2 * (-0.5 - 1) + 1, -0.5, -0.5])
    np.testing.assert_allclose(hi, [2 * (0.5 - 1) + 1, 0.5, 0.5])
    assert (scaled.name, moved.name) == ("cube", "cube-2")
    assert notes == [f"{path}: 2 shapes share the name 'cube' (a USE copy, or a DEF given twice): they are the blocks 'cube', "
                     "'cube-2' in file order"]  # found by a hunt: the OBJ and compas readers said so, VRML did not
    np.testing.assert_allclose(moved.shape.centroid, [0, 0, 5])


def test_a_vrml_name_the_file_gives_is_not_taken_by_a_repeated_one(tmp_path):
    text = ("#VRML V2.0 utf8\nDEF a Shape { geometry Box { size 1 1 1 } }\n"
            "Transform { translation 0 0 5 children DEF a Shape { geometry Box { size 1 1 1 } } }\n"
            "Transform { translation 0 0 10 children DEF a-2 Shape { geometry Box { size 1 1 1 } } }\n")
    blocks, notes = read_vrml(write(tmp_path, text))
    assert [b.name for b in blocks] == ["a", "a-3", "a-2"] and len(notes) == 1 and "'a', 'a-3' in file order" in notes[0]


@pytest.mark.parametrize("text, message", [
    ("#VRML V1.0 ascii\n", r"line 1: not a VRML 2.0 / VRML97 file"),
    ("#VRML V2.0 utf8\nShape {\n geometry Sphere { radius 1 }\n}\n", r"line 3: unsupported geometry node 'Sphere'"),
    ("#VRML V2.0 utf8\nPROTO Brick [] { Group {} }\n", r"line 2: PROTO is not supported"),
    ("#VRML V2.0 utf8\nTransform {\n children [ Shape { geometry Box { size 1 1 1 } }\n", r"unexpected end of file"),
    ("#VRML V2.0 utf8\nTransform { translation 1 2 children [] }\n", r"line 2: Transform.translation must be 3 numbers"),
    ("#VRML V2.0 utf8\nTransform { translation TRUE 0 0.5 children [] }\n",  # found by a hunt: shown as [True]
     r"line 2: Transform.translation must be 3 numbers, got 'TRUE'"),
    ("#VRML V2.0 utf8\nShape { geometry IndexedFaceSet {\n coord Coordinate { point [0 0 0, 1 0 0, 0 1 0, 0 0 1] }\n"
     " coordIndex [0 2 1 -1, 0 1 3 -1, 1 2 3 -1] } }\n", r"line 2: Shape 'shape0': the surface is not closed"),
])
def test_bad_vrml_is_named_with_its_line(tmp_path, text, message):
    path = write(tmp_path, text)
    with pytest.raises(ModelError, match=message) as caught:
        read_vrml(path)
    assert str(caught.value).startswith(str(path))


def test_overlapping_imported_blocks_are_named(tmp_path):
    text = TWO_BOXES.replace("translation 30 0 5", "translation 25 0 5")  # 5 mm into the left box
    with pytest.raises(ModelError, match=r"'left' and 'right' overlap by 0.005 m"):
        load_target(str(write(tmp_path, text)), unit_m=1e-3)


def test_a_non_convex_vrml_shape_is_refused(tmp_path):
    # an L-shaped prism: its inner corner lies on the hull's top and bottom faces, so only its
    # volume (3 of the hull's 3.5) gives it away
    points = [[0, 0, 0], [2, 0, 0], [2, 1, 0], [1, 1, 0], [1, 2, 0], [0, 2, 0]]
    top = [[x, y, 1] for x, y, _ in points]
    coords = ", ".join(" ".join(map(str, p)) for p in points + top)
    sides = ", ".join(f"{i} {(i + 1) % 6} {(i + 1) % 6 + 6} {i + 6} -1" for i in range(6))
    text = (f"#VRML V2.0 utf8\nDEF ell Shape {{ geometry IndexedFaceSet {{ coord Coordinate {{ point [{coords}] }}\n"
            f"coordIndex [5 4 3 2 1 0 -1, 6 7 8 9 10 11 -1, {sides}] }} }}\n")
    with pytest.raises(ModelError, match=r"Shape 'ell': the surface is not convex: it encloses 3 m3, its convex hull 3.5 m3"):
        read_vrml(write(tmp_path, text))


@pytest.mark.parametrize("suffix", [".obj", ".stl"])
def test_mesh_round_trip_keeps_names_fixed_blocks_and_shapes(tmp_path, suffix):
    model = load_target("WD3").model
    path = tmp_path / f"wall{suffix}"
    write_mesh(model, path)
    found = load_target(str(path))
    back = found.model
    # the old base comes back fixed, so no second base is added under it; nothing to note
    assert back.block_name == model.block_name and found.notes == ()
    np.testing.assert_array_equal(back.block_fixed.all(axis=1), model.block_fixed.all(axis=1))
    size = min(s.size for s in model.block_shape)
    np.testing.assert_allclose(back.block_centroid, model.block_centroid, rtol=0, atol=1e-9 * size)
    np.testing.assert_allclose([s.volume for s in back.block_shape], [s.volume for s in model.block_shape], rtol=1e-9)


def binary_stl(model, path):
    """The blocks' faces as a binary STL (float32 coordinates, no names), as CAD programs write it."""
    triangles = [shape.vertices[[face[0], face[i], face[i + 1]]]
                 for shape in model.block_shape for face in shape.faces for i in range(1, len(face) - 1)]
    records = np.zeros(len(triangles), dtype=STL_TRIANGLE)
    records["vertices"] = triangles
    path.write_bytes(b"solid (binary files may start so too)".ljust(80) + np.uint32(len(triangles)).tobytes() + records.tobytes())
    return path


def test_a_binary_stl_comes_back_in_file_order_and_says_what_it_cannot_know(tmp_path):
    wall = load_target("WD3").model
    path = binary_stl(wall, tmp_path / "wall.stl")
    blocks, notes = read_mesh(path)
    assert [b.name for b in blocks] == [f"part{k}" for k in range(wall.n_blocks)] and not any(b.fixed for b in blocks)
    # float32 coordinates: 6e-8 relative to the wall's 0.3 m extent
    np.testing.assert_allclose([b.shape.centroid for b in blocks], wall.block_centroid, rtol=0, atol=1e-7)
    assert notes == [f"{path}: a binary STL names no block: {wall.n_blocks} block(s) are named part0, part1, ... in file order"]
    found = load_target(str(path))
    assert found.notes[-1] == f"{path}: no block is marked fixed: the blocks stand on an added fixed block 'base'"
    assert found.model.block_name[0] == "base" and found.model.block_fixed[0].all()


def test_obj_groups_name_the_blocks_of_a_file_without_objects(tmp_path):
    cube = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n"
    faces = "f -8 -5 -6 -7\nf -4 -3 -2 -1\nf -8 -7 -3 -4\nf -7 -6 -2 -3\nf -6 -5 -1 -2\nf -5 -8 -4 -1\n"
    lifted = "".join(f"v {x} {y} {z + 1}\n" for x, y, z in [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1)])
    path = tmp_path / "groups.obj"
    path.write_text(f"g ground\nusemtl Fixed\n{cube}{faces}g top stone\nusemtl stone\n{lifted}{faces}")
    blocks, notes = read_mesh(path)
    assert [(b.name, b.fixed) for b in blocks] == [("ground", True), ("top stone", False)] and notes == []
    assert blocks[1].shape.centroid.tolist() == [0.5, 0.5, 1.5]


def cube_obj(lift: int) -> str:
    """An OBJ unit cube lifted by ``lift`` m: its 8 vertices and 6 faces (relative indices)."""
    corners = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1)]
    faces = "f -8 -5 -6 -7\nf -4 -3 -2 -1\nf -8 -7 -3 -4\nf -7 -6 -2 -3\nf -6 -5 -1 -2\nf -5 -8 -4 -1\n"
    return "".join(f"v {x} {y} {z + 2 * lift}\n" for x, y, z in corners) + faces


def test_the_blocks_of_an_object_of_several_take_names_no_object_has(tmp_path):
    # object 'A' holds two closed surfaces and the file has an object 'A-2': its second block was
    # named 'A-2' too, and the model refused "duplicate block names ['A-2']", a name given once;
    # unnamed faces skip an object named 'part0' alike
    path = tmp_path / "runs.obj"
    path.write_text(f"o A\n{cube_obj(0)}{cube_obj(1)}o A-2\n{cube_obj(2)}o part0\n{cube_obj(3)}")
    blocks, _ = read_mesh(path)
    assert [b.name for b in blocks] == ["A", "A-3", "A-2", "part0"]
    path.write_text(f"{cube_obj(0)}{cube_obj(1)}o part0\n{cube_obj(2)}o part2\n{cube_obj(3)}")
    blocks, notes = read_mesh(path)
    assert [b.name for b in blocks] == ["part1", "part3", "part0", "part2"] and notes[0].endswith("2 block(s) are named part0, part1, ... in file order, skipping the names of the file's objects")


def test_an_obj_object_named_twice_is_noted_with_the_names_of_its_blocks(tmp_path):
    # two statements 'o A' add their faces to one object, read as 'A' and 'A-2' without a word
    path = tmp_path / "twice.obj"
    path.write_text(f"o A\n{cube_obj(0)}o A\n{cube_obj(1)}")
    blocks, notes = read_mesh(path)
    assert [b.name for b in blocks] == ["A", "A-2"]
    assert notes == [f"{path}: the object 'A' is named on lines 1, 16 (the name occurs 2 times in the file): its faces "
                     "close 2 surfaces, read as 2 blocks named 'A', 'A-2'"]
    path.write_text(f"o A\n{cube_obj(0)}{cube_obj(1)}o B\n{cube_obj(2)}")
    blocks, notes = read_mesh(path)
    assert [b.name for b in blocks] == ["A", "A-2", "B"]
    assert notes == [f"{path}: the object 'A' (line 1): its faces close 2 surfaces, read as 2 blocks named 'A', 'A-2'"]
    path.write_text("g default\n" + "".join(cube_obj(k) for k in range(12)))  # as exporters write: one group
    blocks, notes = read_mesh(path)
    assert len(blocks) == 12 and notes == [f"{path}: the group 'default' (line 1): its faces close 12 surfaces, read as 12 blocks "
                                           "named 'default', 'default-2', 'default-3', 'default-4', 'default-5', ... (7 more)"]


def test_obj_texture_and_normal_indices_and_a_named_endsolid_are_read(tmp_path):
    path = tmp_path / "refs.obj"
    path.write_text("o A\n" + cube_obj(0).replace("f -8 -5 -6 -7", "f -8/1 -5/2/3 -6//4 -7/-1/"))
    assert [b.name for b in read_mesh(path)[0]] == ["A"]
    stl = tmp_path / "named.stl"
    triangle = "facet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\n"
    for end in ("endsolid", "endsolid  a [fixed] ", "ENDSOLID a [fixed]", "endsolid a  [fixed]"):
        stl.write_text(f"solid a [fixed]\n{triangle}{end}\n")
        with pytest.raises(ModelError, match="'a' \\(from line 2\\) is not a closed surface"):  # read to the end
            read_mesh(stl)
    stl.write_text(f"solid\n{triangle}endsolid Mesh\n")  # a nameless solid closed by a named endsolid
    with pytest.raises(ModelError, match="is not a closed surface"):  # read to the end, not refused at endsolid
        read_mesh(stl)


def test_an_imported_mesh_stands_on_a_fixed_base(tmp_path):
    path = tmp_path / "boxes.wrl"
    path.write_text(TWO_BOXES)
    model = load_target(str(path), unit_m=1e-3).model
    assert model.block_name == ("base", "left", "right")
    assert model.block_fixed[0].all() and not model.block_fixed[1:].any()
    assert model.block_shape[0].vertices[:, 2].max() == pytest.approx(0.0)


def test_a_mesh_block_named_base_stands_on_an_added_base_of_another_name(tmp_path):
    # the added support was always "base": a file's own block of that name made the model
    # "duplicate block names ['base']"
    path = tmp_path / "named.obj"
    corners = [(x, y, z) for z in (0, 1) for y in (0, 1) for x in (0, 1)]
    faces = ["1 3 4 2", "5 6 8 7", "1 2 6 5", "3 7 8 4", "1 5 7 3", "2 4 8 6"]
    path.write_text("o base\n" + "".join(f"v {x} {y} {z}\n" for x, y, z in corners) + "".join(f"f {f}\n" for f in faces))
    loaded = load_target(str(path))
    assert loaded.model.block_name == ("base-2", "base") and loaded.model.block_fixed[0].all()


def test_an_open_mesh_names_its_free_edge(tmp_path):
    path = tmp_path / "open.obj"
    path.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 2 3 4\n")
    with pytest.raises(ModelError, match=r"open.obj: 'part0' \(from line 5\) is not a closed surface: 3 edge\(s\) are not in exactly two faces"):
        read_mesh(path)


def test_a_mesh_vertex_beyond_a_thousand_kilometres_is_named_as_such(tmp_path):
    # vertices are merged within a fraction of the model's size: at 1e11 m that swallowed the
    # unit cube's corners, and the cube was called "not a closed surface"
    path = tmp_path / "far.obj"
    corners = [(x, y, z) for z in (0, 1) for y in (0, 1) for x in (0, 1)]
    faces = ["1 3 4 2", "5 6 8 7", "1 2 6 5", "3 7 8 4", "1 5 7 3", "2 4 8 6"]
    path.write_text("".join(f"v {1e11 + x} {y} {z}\n" for x, y, z in corners) + "".join(f"f {f}\n" for f in faces))
    with pytest.raises(ModelError, match=r"far.obj: a vertex is 1e\+11 m from the origin: coordinates must be within 1e\+06 m"):
        read_mesh(path)
    near = tmp_path / "near.obj"
    near.write_text(path.read_text().replace("100000000000.0", "0.0").replace("100000000001.0", "1.0"))
    assert read_mesh(near)[0][0].shape.volume == pytest.approx(1.0, rel=1e-12)


def test_vtk_export_reads_back_with_its_cells_points_and_fields(tmp_path):
    import meshio

    model = benchmark_wall()
    state = State.at_rest(model.block_centroid)
    state.position[5] += [1e-3, 0.0, -2e-3]
    mesh = meshio.read(write_vtu(model, tmp_path / "wall.vtu", state))
    assert sum(len(c.data) for c in mesh.cells) == model.n_blocks
    assert len(mesh.points) == sum(len(s.vertices) for s in model.block_shape)
    fields = {name: np.concatenate(values) for name, values in mesh.cell_data.items()}
    assert set(fields) == {"block_id", "fixed", "active", "mass", "displacement", "displacement_magnitude", "rotation",
                           "velocity", "angular_velocity"}
    np.testing.assert_array_equal(fields["block_id"], np.arange(model.n_blocks))
    np.testing.assert_allclose(fields["displacement"][5], [1e-3, 0.0, -2e-3])
    np.testing.assert_allclose(fields["mass"], model.block_mass)
    assert fields["fixed"].tolist() == [1] + [0] * (model.n_blocks - 1)
    # the points of block 5 moved with it
    first = sum(len(s.vertices) for s in model.block_shape[:5])
    np.testing.assert_allclose(mesh.points[first:first + 8], model.block_shape[5].vertices + [1e-3, 0.0, -2e-3])
