"""The model layer's values through the Python API: a Model and its blocks' polyhedra are frozen,
arrays included; names are texts a file can hold; NumPy values count as the Python ones they
equal; a joint law is a table of [joint] keys. (Other hostile inputs: test_api_inputs.py.)"""

import numpy as np
import pytest
from conftest import BRICK, stack_model

import drydem as dd
from drydem.analysis.tilt import TiltSettings
from drydem.errors import ModelError
from drydem.io.model_file import load_model, save_model

FIELDS = ("block_density", "block_mass", "block_inertia", "block_fixed", "block_radius", "block_centroid")


@pytest.mark.parametrize("field", FIELDS)
def test_a_model_s_arrays_are_read_only(field):
    # block_mass[1] = -5 made total_mass -5; block_fixed[:] = True made a model build_model refuses
    model = stack_model([BRICK[2]])
    with pytest.raises(ValueError, match="read-only"):
        getattr(model, field)[...] = 0


def test_a_block_s_polyhedron_is_read_only_and_the_model_still_cycles():
    model = stack_model([BRICK[2]])
    shape = model.block_shape[1]
    for array in (shape.vertices, shape.face_normals, shape.centroid, shape.second_moment, shape.faces[0]):
        with pytest.raises(ValueError, match="read-only"):
            array[...] = 0
    result = dd.Simulation(model).cycle_to_equilibrium()  # the kernels take writable copies
    assert result.converged


def test_a_polyhedron_made_of_the_caller_s_arrays_leaves_them_writable_and_holds_its_own():
    shape = dd.box([0, 0, 0], BRICK)
    vertices, normals = shape.vertices.copy(), shape.face_normals.copy()
    made = dd.ConvexPolyhedron(vertices, shape.faces, normals, shape.volume, shape.centroid.copy(), shape.second_moment.copy())
    vertices[0] = 99.0  # the caller's array is still its own
    assert made.vertices[0].tolist() == shape.vertices[0].tolist() and not made.vertices.flags.writeable


def test_numpy_texts_are_the_texts_they_equal():
    # np.str_('x') was refused as "must be one of ('y', 'x')", and kept, would be written as np.str_('x')
    settings = TiltSettings(tilt_axis=np.str_("x"))
    assert settings.tilt_axis == "x" and type(settings.tilt_axis) is str
    assert type(dd.SolverSettings(criterion=np.str_("velocity")).criterion) is str


def test_a_source_that_is_no_utf8_file_name_is_a_text():
    # a Latin-1 file name read on Linux (s\xe9isme.toml as 's\udce9isme.toml') names a model
    blocks = [dd.Block(name="base", shape=dd.box([0, 0, -0.01], [0.1, 0.1, 0]), fixed=True), dd.Block(name="b", shape=dd.box([0, 0, 0], BRICK))]
    assert dd.build_model(blocks, density=1800.0, source="s\udce9isme.toml").source == "s\udce9isme.toml"


def test_a_block_name_utf8_cannot_write_is_refused_before_any_file(tmp_path):
    # a lone surrogate made a model that save_model and write_mesh failed on with a UnicodeEncodeError
    with pytest.raises(ModelError, match=r"block '\\ud800' name = '\\ud800': must be a non-empty text on one line, of printable "
                                         "characters UTF-8 can write"):
        dd.Block(name="\ud800", shape=dd.box([0, 0, 0], BRICK))
    # found by a hunt: a NUL went raw into OBJ and 3DEC files, U+2028 broke a 3DEC group name's line
    for name in ("a\x00b", "a\x0bb", "a\u2028b", "a\tb", "two\nlines", "a\x7fb"):
        with pytest.raises(ModelError, match="must be a non-empty text on one line, of printable characters"):
            dd.Block(name=name, shape=dd.box([0, 0, 0], BRICK))
    assert dd.Block(name="pierre n° 3 (é)", shape=dd.box([0, 0, 0], BRICK)).name == "pierre n° 3 (é)"
    model = stack_model([BRICK[2]])
    save_model(model, tmp_path / "m.toml")
    assert load_model(tmp_path / "m.toml").block_name == model.block_name


def test_a_joint_law_that_is_not_a_table_is_refused_naming_it():
    with pytest.raises(ModelError, match="joint_law = 'power': must be a mapping of \\[joint\\] keys"):
        stack_model([BRICK[2]]).overridden(joint_law="power")


@pytest.mark.parametrize("make", [lambda name: dd.box([0, 0, 0], BRICK, name=name),
                                  lambda name: dd.convex_hull(dd.box([0, 0, 0], BRICK).vertices, name=name)])
def test_a_polyhedron_s_name_must_be_a_text(make):
    with pytest.raises(dd.DrydemError, match=r"name = \['x'\]: must be a text \(the block's name in messages\)"):
        make(["x"])


def test_save_model_writes_only_a_toml_path(tmp_path):
    from drydem.io.model_file import save_model

    model = dd.build_model([dd.Block(name="base", shape=dd.box([0, 0, -1], [1, 1, 0]), fixed=True),
                            dd.Block(name="b", shape=dd.box([0, 0, 0], [1, 1, 1]))], density=1800.0)
    with pytest.raises(dd.ModelError, match=r"save_model path = '.*x\.obj': a model file is TOML, its name ends in \.toml"):
        save_model(model, tmp_path / "x.obj")  # found by a hunt: TOML was written into x.obj without a word
    assert not (tmp_path / "x.obj").exists()
    save_model(model, tmp_path / "X.TOML")
