"""compas JSON in and out (drydem.io.compas_json): files written by compas and compas_dem run in
drydem, and drydem's export loads in compas with the model's names, vertices and faces.

drydem reads the files without compas; the tests that build or load files with compas itself
skip when compas is not installed (it is in the ``test`` extra). tests/data/compas_dem_blocks.json
was written by :func:`compas_dem_blocks` with compas_dem 0.6.0, compas 2.15.1 and compas_model
0.9.3 (``compas.json_dump(compas_dem_blocks(), path, pretty=True)``), so that the reader is
checked on a file compas_dem wrote even where compas_dem (which needs compas_cgal) is missing.
"""

import json
import math
import re
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from drydem.cli import main
from drydem.errors import DrydemError
from drydem.io.compas_json import read_compas, write_compas
from drydem.io.target import load_target

COMPAS_DEM_BLOCKS = Path(__file__).parent / "data" / "compas_dem_blocks.json"


def compas_dem_blocks():
    """A compas_dem BlockModel: a support slab 'ground'; 'turned', a 0.4 x 0.2 x 0.3 m box turned
    90 deg about z and moved 0.2 m along x by its element transformation; 'top', its child in
    the model's tree, a 0.4 x 0.2 x 0.1 box lifted 0.3 m by its own transformation (then
    placed by its parent's); two unnamed 0.2 x 0.2 x 0.3 boxes, the first of stone at 2100 kg/m3."""
    from compas.geometry import Box, Frame, Rotation, Translation
    from compas_dem.elements import Block
    from compas_dem.material.stone import Stone
    from compas_dem.models import BlockModel

    model = BlockModel()
    ground = model.add_element(Block.from_box(Box(1.0, 0.4, 0.1, Frame([0, 0, -0.05]))))
    ground.is_support, ground.name = True, "ground"
    turned = Block.from_box(Box(0.4, 0.2, 0.3, Frame([0, 0, 0.15])))
    turned.transformation = Translation.from_vector([0.2, 0, 0]) * Rotation.from_axis_and_angle([0, 0, 1], math.pi / 2)
    turned.name = "turned"
    model.add_element(turned)
    top = Block.from_box(Box(0.4, 0.2, 0.1, Frame([0, 0, 0.05])))
    top.transformation, top.name = Translation.from_vector([0, 0, 0.3]), "top"
    model.add_element(top, parent=turned)
    stone = Stone(fck=20, density=2100)
    model.add_material(stone)
    model.assign_material(stone, element=model.add_element(Block.from_box(Box(0.2, 0.2, 0.3, Frame([-0.2, 0, 0.15])))))
    model.add_element(Block.from_box(Box(0.2, 0.2, 0.3, Frame([-0.4, 0, 0.15]))))
    return model


def box_meshes(boxes):
    """compas Meshes of boxes ((name, centre, size, support) each), made by compas itself."""
    from compas.datastructures import Mesh
    from compas.geometry import Box, Frame

    meshes = []
    for name, centre, size, support in boxes:
        mesh = Mesh.from_shape(Box(*size, Frame(centre)))
        mesh.name, mesh.attributes["is_support"] = name, support
        meshes.append(mesh)
    return meshes


def test_a_compas_dem_block_model_reads_with_its_supports_transformations_tree_and_materials():
    blocks, notes = read_compas(COMPAS_DEM_BLOCKS)
    # graph-node order; the two unnamed blocks (compas_dem names both 'Block') get their graph node
    assert [(b.name, b.fixed) for b in blocks] == [("ground", True), ("turned", False), ("top", False),
                                                   ("Block-3", False), ("Block-4", False)]
    assert notes == [f"{COMPAS_DEM_BLOCKS}: 2 blocks share the names 'Block': each is named NAME-N after its position "
                     "in the file (graph node or list index)"]
    # the extents compas_model's Element.modelgeometry gives (see compas_dem_blocks' docstring)
    extents = {"ground": ([-0.5, -0.2, -0.1], [0.5, 0.2, 0.0]), "turned": ([0.1, -0.2, 0.0], [0.3, 0.2, 0.3]),
               "top": ([0.1, -0.2, 0.3], [0.3, 0.2, 0.4]), "Block-3": ([-0.3, -0.1, 0.0], [-0.1, 0.1, 0.3]),
               "Block-4": ([-0.5, -0.1, 0.0], [-0.3, 0.1, 0.3])}
    for block in blocks:
        lo, hi = extents[block.name]
        np.testing.assert_allclose(block.shape.vertices.min(0), lo, atol=1e-12)
        np.testing.assert_allclose(block.shape.vertices.max(0), hi, atol=1e-12)
    assert [b.density for b in blocks] == [None, None, None, 2100.0, None]
    model = load_target(str(COMPAS_DEM_BLOCKS)).model  # the support is the only fixed block: no base added
    assert model.n_blocks == 5 and model.block_mass[3] == pytest.approx(2100 * 0.2 * 0.2 * 0.3)


def test_a_block_model_without_its_inheritance_list_reads_by_its_dtype(tmp_path):
    data = json.loads(COMPAS_DEM_BLOCKS.read_text())
    assert data["dtype"] == "compas_dem.models/BlockModel"
    data.pop("inheritance", None)
    path = tmp_path / "hand_written.json"
    path.write_text(json.dumps(data))
    assert [b.name for b in read_compas(path)[0]] == [b.name for b in read_compas(COMPAS_DEM_BLOCKS)[0]]


def test_a_block_model_compas_dem_writes_now_reads_as_compas_dem_places_it(tmp_path):
    compas = pytest.importorskip("compas")
    pytest.importorskip("compas_dem")
    model = compas_dem_blocks()
    path = tmp_path / "blocks.json"
    compas.json_dump(model, path)
    blocks, _ = read_compas(path)
    elements = sorted(model.elements(), key=lambda e: e.graphnode)
    for block, element in zip(blocks, elements):
        points = np.array(element.modelgeometry.vertices_attributes("xyz"))
        assert block.fixed == element.is_support
        np.testing.assert_allclose(np.sort(block.shape.vertices, axis=0), np.sort(points, axis=0), atol=1e-12)


def test_drydem_export_builds_a_compas_dem_block_model_with_its_supports(tmp_path):
    compas = pytest.importorskip("compas")
    pytest.importorskip("compas_dem")
    from compas_dem.models import BlockModel

    path = tmp_path / "WD3.json"
    write_compas(load_target("WD3").model, path)
    model = BlockModel()
    for mesh in compas.json_load(path):  # as drydem.io.compas_json's docstring says
        (model.add_support_from_mesh if mesh.attributes["is_support"] else model.add_block_from_mesh)(mesh)
    assert [len(list(model.supports())), len(list(model.blocks()))] == [1, load_target("WD3").model.n_blocks - 1]


def element_guid(data, name):
    return next(guid for guid, element in data["data"]["elements"].items() if element["data"]["name"] == name)


def untransformable(data):
    data["data"]["elements"][element_guid(data, "turned")]["data"]["transformation"]["data"]["matrix"][0][3] = True
    return f"element {element_guid(data, 'turned')}: transformation: matrix: true is not a finite number"


def ragged(data):
    data["data"]["elements"][element_guid(data, "turned")]["data"]["transformation"]["data"]["matrix"][1].append(0.0)
    return f"element {element_guid(data, 'turned')}: transformation: the matrix must be 4 x 4, not rows of 4, 5, 4, 4"


def projected(data):
    data["data"]["elements"][element_guid(data, "turned")]["data"]["transformation"]["data"]["matrix"][3] = [0, 0, 0, 0]
    return (f"element {element_guid(data, 'turned')}: transformation: the matrix's last row is \\[0.0, 0.0, 0.0, 0.0\\], "
            r"not \[0, 0, 0, 1\]: a block is placed by an affine transformation")


def modified(data):
    data["data"]["graph"]["edge"]["0"] = {"1": {"modifiers": [{"dtype": "compas_model.modifiers/BooleanModifier"}]}}
    return r"graph edge 0-1 has modifiers \(cuts of one element by another\)"


def lost_element(data):
    data["data"]["elements"].pop(element_guid(data, "top"))
    return r"the tree names the element '[0-9a-f-]+', which is not in the model's elements"


@pytest.mark.parametrize("spoil", [untransformable, ragged, projected, modified, lost_element])
def test_a_bad_compas_dem_model_is_refused_naming_the_file_and_the_element(tmp_path, spoil):
    data = json.loads(COMPAS_DEM_BLOCKS.read_text())
    message = spoil(data)
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(data))
    with pytest.raises(DrydemError, match=f"^{re.escape(str(path))}: {message}"):
        read_compas(path)


def test_a_box_stack_written_by_compas_checks_in_drydem(tmp_path):
    compas = pytest.importorskip("compas")
    meshes = box_meshes([("ground", [0, 0, -0.05], (1.0, 0.4, 0.1), True),
                                 ("lower", [0, 0, 0.1], (0.4, 0.2, 0.2), False), ("upper", [0, 0, 0.3], (0.4, 0.2, 0.2), False)])
    path = tmp_path / "stack.json"
    compas.json_dump(meshes, path)
    result = CliRunner().invoke(main, ["check", str(path)])
    assert result.exit_code == 0, result.output
    assert "blocks          3 (2 movable, 1 fixed)" in result.output
    assert "mass            57.6 kg" in result.output  # 2 x 0.4 x 0.2 x 0.2 m3 at the default 1800 kg/m3
    # an object of meshes names its blocks by its keys
    compas.json_dump({"a": meshes[0], "b": meshes[1]}, path)
    assert load_target(str(path)).model.block_name == ("a", "b")


def slender_compas_file(tmp_path) -> Path:
    """A 10 mm wide (x), 40 mm tall block saved by compas, no support marked."""
    compas = pytest.importorskip("compas")
    (mesh,) = box_meshes([("slender", [0.005, 0.006, 0.02], (0.01, 0.012, 0.04), False)])
    path = tmp_path / "slender.json"
    compas.json_dump(mesh, path)
    return path


def test_limit_analysis_of_a_slender_compas_block_gives_b_over_h(tmp_path):
    # friction 1: rigid toppling at lambda = b / h = 0.25 (tests/test_limit.py)
    path = slender_compas_file(tmp_path)
    out = tmp_path / "limit"
    result = CliRunner().invoke(main, ["limit", str(path), "--friction", "1.0", "--out", str(out)])
    assert result.exit_code == 0, result.output
    # within the 3D solver tolerance of tests/test_limit.py (IN_3D)
    assert json.loads((out / "summary.json").read_text())["load_multiplier"] == pytest.approx(0.25, rel=1e-7)


@pytest.mark.slow
def test_a_slender_compas_block_topples_at_atan_b_over_h(tmp_path):
    # 10 mm wide (x), 40 mm tall: the weight passes the downhill edge at tan(theta) = 1/4, 14.04 deg;
    # friction 1 so it cannot slide first, stiff joints so that the elastic rotation is negligible
    # (tests/test_tilt.py); no support marked: drydem stands it on an added base, which reaches 50 mm
    # beyond it, so that the toppled block lies on it: the collapse is where it has moved 10 mm
    path = slender_compas_file(tmp_path)
    out = tmp_path / "results"
    result = CliRunner().invoke(main, ["tilt", str(path), "--increment", "0.5", "--kn", "1e10", "--ks", "1e10",
                                       "--friction", "1.0", "--stop-displacement", "0.01", "--out", str(out)])
    assert result.exit_code == 0, result.output
    angle = json.loads((out / "summary.json").read_text())["collapse_angle_deg"]
    exact = math.degrees(math.atan(0.25))
    assert exact - 0.5 - 1e-9 <= angle <= exact + 1e-9  # the last equilibrium before toppling, within a step


def test_drydem_export_loads_in_compas_with_the_models_names_vertices_and_faces(tmp_path):
    compas = pytest.importorskip("compas")
    model = load_target("WD3").model
    path = tmp_path / "WD3.json"
    result = CliRunner().invoke(main, ["export", "WD3", str(path)])
    assert result.exit_code == 0, result.output
    meshes = compas.json_load(path)
    assert [m.name for m in meshes] == list(model.block_name)
    assert [m.attributes["is_support"] for m in meshes] == model.block_fixed.all(axis=1).tolist()
    for mesh, shape in zip(meshes, model.block_shape):
        vertices, faces = mesh.to_vertices_and_faces()
        assert vertices == shape.vertices.tolist() and faces == [face.tolist() for face in shape.faces]
        # drydem's faces run counter-clockwise seen from outside, as compas expects
        np.testing.assert_allclose([mesh.face_normal(f) for f in mesh.faces()], shape.face_normals, atol=1e-12)


def test_drydem_reads_its_own_compas_export_back_to_the_same_blocks(tmp_path):
    model = load_target("WD3").model
    path = tmp_path / "WD3.json"
    write_compas(model, path)
    found = load_target(str(path))
    back = found.model
    # the old base comes back fixed, so no second base is added under it; nothing to note
    assert back.block_name == model.block_name and found.notes == ()
    np.testing.assert_array_equal(back.block_fixed, model.block_fixed.all(axis=1)[:, None].repeat(6, axis=1))
    for mine, theirs in zip(back.block_shape, model.block_shape):
        assert mine.vertices.tolist() == theirs.vertices.tolist() and mine.volume == pytest.approx(theirs.volume, rel=1e-12)


def mesh_json(name, points, faces, **attributes):
    """A compas Mesh as Mesh.__data__ lays it out (compas/datastructures/mesh/mesh.py)."""
    vertex = {str(i): dict(zip("xyz", p)) for i, p in enumerate(points)}
    return {"dtype": "compas.datastructures/Mesh", "name": name,
            "data": {"attributes": attributes, "default_vertex_attributes": {"x": 0.0, "y": 0.0, "z": 0.0},
                     "vertex": vertex, "face": {str(f): face for f, face in enumerate(faces)}}}


CUBE = [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]]
CUBE_FACES = [[0, 3, 2, 1], [4, 5, 6, 7], [0, 1, 5, 4], [1, 2, 6, 5], [2, 3, 7, 6], [3, 0, 4, 7]]
#: an L-shaped prism, 3 m3: its reflex corner (1, 1) lies on the bottom and top faces of its 3.5 m3 hull
ELL = [[0, 0], [2, 0], [2, 1], [1, 1], [1, 2], [0, 2]]
ELL_POINTS = [[x, y, 0] for x, y in ELL] + [[x, y, 1] for x, y in ELL]
ELL_FACES = [[5, 4, 3, 2, 1, 0], [6, 7, 8, 9, 10, 11]] + [[i, (i + 1) % 6, (i + 1) % 6 + 6, i + 6] for i in range(6)]


@pytest.mark.parametrize("content, message", [
    ("{", r"not JSON: Expecting property name enclosed in double quotes at line 1, column 2"),
    (42, r"the file holds a JSON number; drydem reads a compas Mesh"),
    ([], r"no mesh: the file holds no block"),
    ({"collapse_angle_deg": 21.0}, r"mesh 'collapse_angle_deg': not a compas object \(no 'dtype'\)"),
    ({"dtype": "compas.geometry/Box", "data": {"xsize": 1}},
     r"the file holds a 'compas.geometry/Box', not a 'compas.datastructures/Mesh' or a 'compas_model.models/Model'"),
    ([{"dtype": "compas.geometry/Point", "data": [0, 0, 0]}],
     r"mesh 0: a 'compas.geometry/Point', not a 'compas.datastructures/Mesh'"),
    ([mesh_json("ell", ELL_POINTS, ELL_FACES)],
     r"mesh 0 'ell': the surface is not convex: it encloses 3 m3, its convex hull 3.5 m3"),
    ([mesh_json("lid off", CUBE, CUBE_FACES[1:])], r"mesh 0 'lid off': the surface is not closed"),
    ([mesh_json("flipped", CUBE, [CUBE_FACES[0][::-1], *CUBE_FACES[1:]])],
     r"mesh 0 'flipped': the faces do not wind consistently: the edge \[.+\] - \[.+\] runs the same way in both its faces \(4 such edges"),
    ([mesh_json("cube", [[True, 0, 0], *CUBE[1:]], CUBE_FACES)], r"mesh 0 'cube': vertex 0: x: true is not a finite number"),
    ([mesh_json("cube", CUBE, [*CUBE_FACES[:-1], [3, 0, 4, 8]])],
     r"mesh 0 'cube': face 5 refers to vertex 8, which the mesh does not have"),
    ([mesh_json("cube", CUBE, CUBE_FACES, is_support=1)], r"mesh 0 'cube': is_support: 1 is not true or false"),
])
def test_bad_compas_json_is_refused_naming_the_file_and_the_mesh(tmp_path, content, message):
    path = tmp_path / "bad.json"
    path.write_text(content if isinstance(content, str) else json.dumps(content))
    with pytest.raises(DrydemError, match=f"^{re.escape(str(path))}: {message}"):
        load_target(str(path))
    result = CliRunner().invoke(main, ["check", str(path)])  # a message, not a traceback
    assert result.exit_code == 1 and f"Error: {path}: " in result.output and "Traceback" not in result.output
