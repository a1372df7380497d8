"""Bad arguments to the public API of the analyses, the readers and writers and the masonry
builders: each is refused up front by drydem's own error naming the argument and its rule,
never a bare Python exception from inside drydem, a silent acceptance or a NaN result."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import drydem as dd
from drydem.analysis.dataframes import data_frame
from drydem.analysis.limit import limit_analysis
from drydem.analysis.shake.motion import GroundMotion, pulse
from drydem.analysis.shake.run import shake_analysis
from drydem.analysis.shake.settings import ShakeSettings
from drydem.analysis.tilt import TiltSettings, tilt_analysis
from drydem.errors import DrydemError, ModelError
from drydem.io.compas_json import read_compas, write_compas
from drydem.io.mesh import read_mesh, write_mesh
from drydem.io.model_file import load_model, save_model
from drydem.io.target import load_target
from drydem.io.vrml import read_vrml
from drydem.io.vtk import write_vtu
from drydem.masonry.building import BuildingSpec, building_blocks, building_model
from drydem.masonry.imperfections import Imperfections


def brick_model(**options) -> dd.Model:
    """A 0.1 m brick on a wider fixed base (the README's model)."""
    base = dd.Block(name="base", shape=dd.box([-0.1, 0, -0.05], [0.2, 0.1, 0]), fixed=True)
    brick = dd.Block(name="brick", shape=dd.box([0, 0, 0], [0.1, 0.1, 0.05]))
    return dd.build_model([base, brick], density=2000.0, **options)


def refused(call, *fragments, error=ModelError):
    """``call()`` raises ``error`` (drydem's own) whose message holds every fragment."""
    with pytest.raises(error) as raised:
        call()
    for fragment in fragments:
        assert fragment in str(raised.value), str(raised.value)


@pytest.fixture(scope="module")
def model() -> dd.Model:
    return brick_model()


SETTINGS = TiltSettings(increment_deg=1.0, adaptive=True)
MOTION = pulse("one-sine", amplitude_m_s2=1.0, frequency_hz=5.0)


# -- the analyses' callbacks (f07) -----------------------------------------------------------

@pytest.mark.parametrize("name", ["on_record", "on_progress", "on_frame"])
def test_tilt_analysis_refuses_a_callback_that_is_no_function_before_the_work(model, name):
    refused(lambda: tilt_analysis(model, SETTINGS, **{name: 5}), f"tilt_analysis {name} = 5: must be None or a function")


def test_limit_analysis_refuses_an_on_progress_that_is_no_function(model):
    refused(lambda: limit_analysis(model, on_progress=5), "limit_analysis on_progress = 5: must be None or a function")


@pytest.mark.parametrize("name", ["on_progress", "on_frame"])
def test_shake_analysis_refuses_a_callback_that_is_no_function(model, name):
    refused(lambda: shake_analysis(model, ShakeSettings(motion=MOTION, duration_s=0.05), **{name: "x"}),
            f"shake_analysis {name} = 'x': must be None or a function")


# -- tilt_analysis's checkpoint arguments (f11) ----------------------------------------------

@pytest.mark.parametrize("arguments, message", [
    (dict(checkpoint=123), "tilt_analysis checkpoint = 123: must be a file path"),
    (dict(checkpoint=b"run.npz"), "tilt_analysis checkpoint = b'run.npz': must be a file path"),
    (dict(checkpoint=""), "tilt_analysis checkpoint = '': must be a file path"),
    (dict(resume=True), "tilt_analysis resume = True needs a checkpoint"),
    (dict(checkpoint="c.npz", checkpoint_every_s="x"), "tilt_analysis checkpoint_every_s = 'x': must be a number in [0, inf) s"),
    (dict(checkpoint="c.npz", checkpoint_every_s=-1), "tilt_analysis checkpoint_every_s = -1: must be a number in [0, inf) s"),
    (dict(checkpoint="c.npz", checkpoint_every_s=math.inf), "tilt_analysis checkpoint_every_s = inf"),
    (dict(checkpoint="c.npz", checkpoint_every_s=True), "tilt_analysis checkpoint_every_s = True"),
    (dict(checkpoint="c.npz", resume="yes"), "tilt_analysis resume = 'yes': must be true or false"),
    (dict(checkpoint="c.npz", resume=1), "tilt_analysis resume = 1: must be true or false"),
])
def test_tilt_analysis_checks_its_checkpoint_arguments_before_the_work(model, tmp_path, monkeypatch, arguments, message):
    monkeypatch.chdir(tmp_path)
    refused(lambda: tilt_analysis(model, SETTINGS, **arguments), message)
    assert not list(tmp_path.iterdir())  # nothing was run, nothing saved


def test_tilt_analysis_names_every_bad_argument_at_once(model):
    refused(lambda: tilt_analysis(model, SETTINGS, on_record=5, checkpoint_every_s=-1.0),
            "tilt_analysis on_record = 5", "; tilt_analysis checkpoint_every_s = -1.0")


def test_tilt_analysis_takes_a_checkpoint_given_as_text(model, tmp_path):
    result = tilt_analysis(model, TiltSettings(increment_deg=5.0, max_angle_deg=10.0), checkpoint=str(tmp_path / "run.npz"))
    assert (tmp_path / "run.npz").is_file() and result.records


# -- DataFrames hold copies (f12) ------------------------------------------------------------

def test_a_data_frames_attrs_are_copies_of_the_results_lists():
    pytest.importorskip("pandas")
    lost = [("brick", 10.0)]
    frame = data_frame({"tilt_deg": [0.0]}, {"lost_blocks": lost})
    frame.attrs["lost_blocks"].append(("junk", 1.0))
    assert lost == [("brick", 10.0)]


def test_editing_a_tilt_results_dataframe_leaves_the_result_as_it_was(model):
    pytest.importorskip("pandas")
    result = tilt_analysis(model, TiltSettings(increment_deg=5.0, max_angle_deg=10.0))
    frame = result.to_dataframe()
    frame.attrs["lost_blocks"].append(("junk", 1.0))
    frame.attrs["drift_limit_angles_deg"] = None
    assert result.lost_blocks == []


# -- save_model and load_model (f15) ---------------------------------------------------------

@pytest.mark.parametrize("call, message", [
    (lambda m, folder: save_model(m, folder / "h.toml", header=5), "save_model header = 5: must be a str"),
    (lambda m, folder: save_model(m, None), "save_model path = None: must be a file path"),
    (lambda m, folder: save_model({"a": 1}, folder / "x.toml"), "save_model model = {'a': 1}: must be a Model"),
    (lambda m, folder: load_model(5), "load_model path = 5: must be a file path"),
    (lambda m, folder: load_model(b"/tmp/h.toml"), "load_model path = b'/tmp/h.toml': must be a file path"),
    (lambda m, folder: load_model(None), "load_model path = None: must be a file path"),
])
def test_save_model_and_load_model_name_a_bad_argument(model, tmp_path, call, message):
    refused(lambda: call(model, tmp_path), message)


def test_save_model_to_a_folder_says_it_is_a_folder(model, tmp_path):
    refused(lambda: save_model(model, tmp_path), str(tmp_path), "is a folder", error=DrydemError)


def test_save_model_writes_any_block_name_in_utf8_and_reads_it_back(tmp_path):
    base = dd.Block(name="base", shape=dd.box([-0.1, 0, -0.05], [0.2, 0.1, 0]), fixed=True)
    brick = dd.Block(name="brique-\u00e9t\u00e9", shape=dd.box([0, 0, 0], [0.1, 0.1, 0.05]))
    save_model(dd.build_model([base, brick], density=2000.0), str(tmp_path / "m.toml"), header="made by a test")
    assert load_model(tmp_path / "m.toml").block_name[1] == "brique-\u00e9t\u00e9"


# -- write_vtu (f16) -------------------------------------------------------------------------

def test_write_vtu_takes_active_as_a_list_of_booleans(model, tmp_path):
    pytest.importorskip("meshio")
    assert write_vtu(model, tmp_path / "a.vtu", active=[True, False]).is_file()


@pytest.mark.parametrize("arguments, message", [
    (dict(state="x"), "write_vtu state = 'x': must be a State"),
    (dict(state=dd.State.at_rest(np.zeros((5, 3)))), "write_vtu state.position must be a (2, 3) array"),
    (dict(active=np.ones(7, bool)), "write_vtu active must be a (2,) array of booleans, one per block"),
    (dict(active=[1, 0]), "write_vtu active must be a (2,) array of booleans"),
    (dict(active="yes"), "write_vtu active must be a (2,) array of booleans"),
])
def test_write_vtu_checks_its_state_and_active_blocks(model, tmp_path, arguments, message):
    pytest.importorskip("meshio")
    refused(lambda: write_vtu(model, tmp_path / "a.vtu", **arguments), message)
    assert not (tmp_path / "a.vtu").exists()


def test_write_vtu_refuses_a_path_that_is_no_vtu_file(model, tmp_path):
    """Found by a hunt: VTU's XML was written to x.txt without a word."""
    refused(lambda: write_vtu(model, tmp_path / "x.txt"), "write_vtu path = ", "x.txt'", "the suffix '.txt' is no VTU file's")
    assert list(tmp_path.iterdir()) == []


# -- the readers' unit_m (f17) ---------------------------------------------------------------

BAD_UNITS = [True, -1, 0, 0.0, math.nan, math.inf, "1", 1j, None]
VRML_BOX = "#VRML V2.0 utf8\nShape { geometry Box { size 0.1 0.1 0.05 } }\n"


@pytest.fixture(scope="module")
def geometry(model, tmp_path_factory) -> Path:
    folder = tmp_path_factory.mktemp("geometry")
    write_mesh(model, folder / "m.obj")
    write_mesh(model, folder / "m.stl")
    write_compas(model, folder / "m.json")
    (folder / "m.wrl").write_text(VRML_BOX)
    return folder


@pytest.mark.parametrize("unit", BAD_UNITS, ids=repr)
@pytest.mark.parametrize("reader, file", [(read_mesh, "m.obj"), (read_mesh, "m.stl"), (read_compas, "m.json"), (read_vrml, "m.wrl")],
                         ids=["obj", "stl", "compas", "vrml"])
def test_every_reader_refuses_a_unit_that_is_no_positive_finite_number(geometry, reader, file, unit):
    refused(lambda: reader(geometry / file, unit_m=unit), f"{reader.__name__} unit_m = {unit!r}: must be a number in (0, inf) m")


@pytest.mark.parametrize("unit", BAD_UNITS, ids=repr)
def test_load_target_refuses_a_unit_that_is_no_positive_finite_number(geometry, unit):
    refused(lambda: load_target(str(geometry / "m.obj"), unit_m=unit), f"load_target unit_m = {unit!r}: must be a number in (0, inf) m")


def test_the_readers_still_scale_by_a_good_unit(geometry):
    blocks, _ = read_mesh(geometry / "m.obj", unit_m=1e-3)
    assert np.allclose(blocks[1].shape.centroid, [0.05e-3, 0.05e-3, 0.025e-3])
    assert load_target(str(geometry / "m.json"), unit_m=np.float64(2.0)).model.n_blocks == 2


@pytest.mark.parametrize("target", [5, None, b"m.obj"], ids=repr)
def test_load_target_refuses_a_target_that_is_no_text(target):
    refused(lambda: load_target(target), f"load_target target = {target!r}: must be a non-empty text")


# -- write_mesh's suffix (f18) ---------------------------------------------------------------

@pytest.mark.parametrize("name", ["x.xyz", "x", "x.ply"])
def test_write_mesh_refuses_a_suffix_it_does_not_write(model, tmp_path, name):
    refused(lambda: write_mesh(model, tmp_path / name), "write_mesh path", ".obj, .stl")
    assert not (tmp_path / name).exists()


def test_write_mesh_writes_the_format_its_suffix_says_whatever_the_case(model, tmp_path):
    write_mesh(model, tmp_path / "x.OBJ")
    write_mesh(model, tmp_path / "x.Stl")
    assert (tmp_path / "x.OBJ").read_text().splitlines()[0].startswith(("#", "o ", "mtllib"))
    assert (tmp_path / "x.Stl").read_text().startswith("solid ")


@pytest.mark.parametrize("write, name", [(lambda m, path: write_mesh(m, path), "out.stl"), (lambda m, path: write_compas(m, path), "out.json"),
                                         (lambda m, path: write_vtu(m, path), "out.vtu")], ids=["mesh", "compas", "vtu"])
def test_the_writers_say_a_path_that_is_a_folder_is_one(model, tmp_path, write, name):
    pytest.importorskip("meshio")
    folder = tmp_path / name
    folder.mkdir()
    refused(lambda: write(model, folder), str(folder), "is a folder", error=DrydemError)
    refused(lambda: write(model, None), "path = None: must be a file path")


# -- LimitResult.mechanism_state (f19) -------------------------------------------------------

@pytest.fixture(scope="module")
def limit_result(model):
    return limit_analysis(model)


@pytest.mark.parametrize("displacement", [math.nan, math.inf, "x", True, 1e300, None], ids=repr)
def test_mechanism_state_refuses_a_displacement_that_is_no_finite_number(model, limit_result, displacement):
    refused(lambda: limit_result.mechanism_state(model, displacement),
            f"LimitResult.mechanism_state displacement_m = {displacement!r}: must be a number in [-1e+06, 1e+06] m")


def test_mechanism_state_refuses_a_model_of_another_block_count(limit_result):
    other = dd.build_model([dd.Block(name="base", shape=dd.box([-1, 0, -1], [1, 1, 0]), fixed=True)]
                           + [dd.Block(name=f"b{i}", shape=dd.box([0, 0, i], [1, 1, i + 1])) for i in range(3)], density=2000)
    refused(lambda: limit_result.mechanism_state(other, 0.01), "LimitResult.mechanism_state model", "has 4 blocks", "of 2")
    refused(lambda: limit_result.mechanism_state({"a": 1}, 0.01), "LimitResult.mechanism_state model = {'a': 1}: must be a Model")


def test_mechanism_state_moves_the_blocks_by_a_good_displacement(model, limit_result):
    state = limit_result.mechanism_state(model, np.float64(0.01))
    assert np.isfinite(state.position).all()


# -- building_model (f21) --------------------------------------------------------------------

SPEC = BuildingSpec(length_m=0.5, width_m=0.5, storeys=1, storey_height_courses=10, brick_length_m=0.1, brick_height_m=0.05,
                    windows_per_wall=0, door_height_courses=0)


@pytest.mark.parametrize("arguments, message", [
    (dict(contacts={}), "building_model contacts = {}: must be a ContactSettings"),
    (dict(contacts=0), "building_model contacts = 0: must be a ContactSettings"),
    (dict(solver=""), "building_model solver = '': must be a SolverSettings"),
    (dict(solver=False), "building_model solver = False: must be a SolverSettings"),
    (dict(joint={"kn": 1e8}), "building_model joint = {'kn': 100000000.0}: must be a JointMaterial"),
])
def test_building_model_uses_the_defaults_only_for_none_and_checks_the_types(arguments, message):
    refused(lambda: building_model(SPEC, **arguments), message)


def test_building_model_and_blocks_refuse_a_spec_that_is_no_building_spec():
    refused(lambda: building_model({"length_m": 1}), "building_model spec = {'length_m': 1}: must be a BuildingSpec")
    refused(lambda: building_blocks("small"), "building_blocks spec = 'small': must be a BuildingSpec")


def test_building_model_takes_its_settings_and_none_for_the_defaults():
    contacts = dd.ContactSettings(points_per_length=2)
    model = building_model(SPEC, contacts=contacts, solver=None)
    assert model.contacts == contacts and model.solver == dd.SolverSettings()


# -- GroundMotion (f22) ----------------------------------------------------------------------

ZERO_ONE = [[0, 0, 0], [1, 0, 0]]


@pytest.mark.parametrize("arguments, message", [
    (dict(time_s=[False, True], acceleration_m_s2=ZERO_ONE), "m: time_s must be an array of real numbers"),
    (dict(time_s=np.array([False, True]), acceleration_m_s2=ZERO_ONE), "m: time_s must be an array of real numbers"),
    (dict(time_s=["0", "1"], acceleration_m_s2=ZERO_ONE), "m: time_s must be an array of real numbers"),
    (dict(time_s=[0, 1], acceleration_m_s2=[["0", "0", "0"], ["1", "0", "0"]]), "m: acceleration_m_s2 must be an array of real numbers"),
    (dict(time_s=[0, 1], acceleration_m_s2=[[0, 0, 0], [True, 0, 0]]), "m: acceleration_m_s2 must be an array of real numbers"),
    (dict(time_s=[0, 1], acceleration_m_s2=np.array([[0, 0, 0], [1 + 5j, 0, 0]])),
     "m: acceleration_m_s2 must be an array of real numbers (no texts, booleans, complex numbers or masked values), got shape (2, 3) complex128"),
    (dict(time_s=[0, 1, [2]], acceleration_m_s2=ZERO_ONE + [[0, 0, 0]]), "m: time_s must be an array of real numbers"),
    (dict(time_s=[0, 1], acceleration_m_s2=ZERO_ONE, name=5), "GroundMotion name = 5: must be a non-empty text"),
    (dict(time_s=[0, 1], acceleration_m_s2=ZERO_ONE, name=" "), "GroundMotion name = ' ': must be a non-empty text"),
    (dict(time_s=[0, 1], acceleration_m_s2=ZERO_ONE, notes="abc"), "GroundMotion notes = 'abc': must be a tuple of texts"),
    (dict(time_s=[0, 1], acceleration_m_s2=ZERO_ONE, notes=(1,)), "GroundMotion notes = (1,): must be a tuple of texts"),
    (dict(time_s=[0, 1], acceleration_m_s2=ZERO_ONE, source=5), "GroundMotion source = 5: must be a non-empty text"),
])
def test_ground_motion_refuses_samples_that_are_no_real_numbers_and_a_bad_description(arguments, message):
    refused(lambda: GroundMotion(**({"name": "m"} | arguments)), message)


def test_ground_motion_takes_integer_lists_and_a_list_of_notes():
    motion = GroundMotion([0, 1], ZERO_ONE, "m", notes=["shifted"])
    assert motion.time_s.dtype == np.float64 and motion.notes == ("shifted",)
    assert motion.acceleration_m_s2[1, 0] == 1.0


# -- shake_analysis's model and settings (f23) -----------------------------------------------

def test_shake_analysis_checks_its_model_and_settings_as_tilt_analysis_does(model):
    refused(lambda: shake_analysis(model, {"motion": MOTION}), "shake_analysis settings = ", "must be a ShakeSettings")
    refused(lambda: shake_analysis({"a": 1}, ShakeSettings(motion=MOTION)), "shake_analysis model = {'a': 1}: must be a Model")
    refused(lambda: shake_analysis(None, None), "shake_analysis model = None: must be a Model", "settings = None: must be a ShakeSettings")


# -- Imperfections.scaled (f25) --------------------------------------------------------------

@pytest.mark.parametrize("factor", [1e308, -1.0, math.nan, math.inf, True, "2"], ids=repr)
def test_imperfections_scaled_names_its_factor(factor):
    refused(lambda: Imperfections(height_sd_mm=2.0).scaled(factor), f"Imperfections.scaled factor = {factor!r}: must be a number in [0, ")


def test_imperfections_scaled_takes_any_finite_factor_of_zero_amplitudes_and_a_plain_one():
    assert Imperfections().scaled(1e308).is_zero
    assert Imperfections(height_sd_mm=2.0).scaled(np.float64(1.5)).height_sd_mm == 3.0
