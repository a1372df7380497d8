"""The 3D building (drydem.masonry.building) analysed: a small building tilted about x, which
loads its long walls (0 and 2, along x) out of their plane; its mechanism picture in 3D and
its VTK series; the built-in buildings as TARGETs of the commands (check, export, tilt)."""

import json
import math
import re

import numpy as np
import pytest
from click.testing import CliRunner

from drydem.analysis.tilt import TiltSettings, monitored_block, tilt_analysis
from drydem.cli import main
from drydem.errors import ModelError
from drydem.io.model_file import load_model, save_model
from drydem.io.target import load_target
from drydem.io.vtk import VtkSeries
from drydem.masonry.building import (
    BUILDING_JOINT, BUILDINGS, FULL_SCALE_JOINT, LARGE, SMALL, BuildingSpec, buckling_joint_stiffness, building_model,
)
from drydem.model.parameters import JointMaterial
from drydem.report.plots import frame_3d, is_wall_like, mechanism_figure

#: a one-storey building of 185 blocks: 0.8 m x 0.5 m in plan, 0.4 m tall (8 courses of 100 x 50 x
#: 50 mm bricks, walls 50 mm thick), a window a wall
TINY = BuildingSpec(length_m=0.8, width_m=0.5, storeys=1, storey_height_courses=8, brick_length_m=0.1,
                    brick_height_m=0.05, windows_per_wall=1, window_width_bricks=1, window_height_courses=3, sill_courses=2)
#: coarse: adaptive steps from 8 deg down to 1 deg, a stop displacement of 2 cm
SETTINGS = TiltSettings(increment_deg=1.0, adaptive=True, refinements=3, tilt_axis="x", stop_displacement_m=0.02)


def wall_of(name: str) -> int:
    return int(re.fullmatch(r"s\d+w(\d)c\d+[bl]\d+", name).group(1))


@pytest.fixture(scope="module")
def tiny():
    """TINY with the walls' soft default joint (kn = 3e7 Pa/m; it stands, one storey high): a
    few times fewer cycles than the buildings' stiff default (BUILDING_JOINT)."""
    return building_model(TINY, joint=JointMaterial())


@pytest.fixture(scope="module")
def tilted(tiny, tmp_path_factory):
    """The tiny building tilted about x, its frames written as a VTK series (which records that
    the load acts along y, as drydem tilt's does)."""
    folder = tmp_path_factory.mktemp("tilted")
    series = VtkSeries(folder / "vtk", tiny, load_direction=SETTINGS.load_direction)
    return tilt_analysis(tiny, SETTINGS, on_frame=series), series, folder


def test_the_monitored_block_is_on_the_leeward_wall_loaded_out_of_plane(tiny):
    assert tiny.n_blocks == TINY.block_count == 185
    # tilting about x the load acts along +y: the top block nearest the middle in x of the
    # north wall (2), which the load pushes out of its plane and away from the building
    name = tiny.block_name[monitored_block(tiny, "x")]
    assert wall_of(name) == 2 and re.fullmatch(r"s0w2c7b\d+", name)
    assert abs(tiny.block_centroid[tiny.block_index(name), 0] - 0.5 * TINY.length_m) <= 0.5 * TINY.brick_length_m
    # about y (today's default), the x-middle rule as before
    assert wall_of(tiny.block_name[monitored_block(tiny)]) in (0, 2)


def test_tilted_about_x_the_building_collapses_out_of_plane(tiny, tilted):
    result, _, _ = tilted
    assert result.stable_under_gravity and result.ended_by in ("stop displacement", "monitored block fell")
    # physically plausible: above 0, below the sliding bound atan(mu); measured 6.0 deg at 0.5 deg
    # steps with these soft joints (kn = 3e7 Pa/m; 5.5 deg before the contact polygons' corners
    # were points), below the 7.1 deg of a rigid free-standing leaf 50 mm thick and 0.4 m tall
    # (atan(t / h)): the window and the joints' flexibility weaken it more than the bonded
    # returns hold it
    mu = tiny.joint.friction
    assert 0.0 < result.collapse_angle_deg < math.degrees(math.atan(mu))
    # the blocks that moved most, along the load (y), are in the north wall, pushed out of its
    # plane, or are the returns' bricks bonded to it at its corners, which it drags along
    # (measured: the two top corner bricks among the 20, 10 mm beside its top's 21 mm)
    moved = result.final_state.position[:, 1] - tiny.block_centroid[:, 1]
    most = np.argsort(-np.abs(moved))[:20]
    by_the_north_wall = tiny.block_centroid[:, 1] > TINY.width_m - TINY.brick_length_m
    assert all(wall_of(tiny.block_name[b]) == 2 or by_the_north_wall[b] for b in most)
    # the monitored displacement is the one along y, and it is what stopped the run
    monitor = tiny.block_index(result.monitored_block)
    assert result.records[-1].ux_m == pytest.approx(result.collapse_state.position[monitor, 1] - tiny.block_centroid[monitor, 1])
    assert result.settings.tilt_axis == "x"


def test_the_mechanism_is_drawn_in_3d_and_the_vtk_series_written(tiny, tilted):
    result, series, folder = tilted
    assert not is_wall_like(tiny)
    states = [("last equilibrium", result.collapse_state, frozenset()), ("past collapse", result.final_state, frozenset())]
    path = mechanism_figure(tiny, states, folder / "mechanism.png", monitored=result.monitored_block, load_direction=1)
    assert path.stat().st_size > 20_000
    assert (series.folder / "blocks.pvd").is_file() and (series.folder / "contacts.pvd").is_file()
    frames = (series.folder / "frames.csv").read_text().splitlines()
    assert len(frames) - 1 == len(series.rows) > len(result.records)
    assert any(",past collapse," in row for row in frames)


def test_the_built_in_buildings_are_targets():
    assert set(BUILDINGS) == {"building-small", "building-large"}
    found = load_target("building-small")
    assert found.name == "building-small" and found.model.n_blocks == SMALL.block_count == 1936
    assert found.model.source == "building-small" and found.model.joint == BUILDING_JOINT
    result = CliRunner().invoke(main, ["designs"])
    assert result.exit_code == 0 and "building-small" in result.output and "19853" in result.output



def test_building_large_joints_are_stiff_enough_for_its_walls_to_stand():
    # its 9.6 m leaf, 0.12 m thick, buckles as a free column below 2.1e10 Pa/m (Greenhill,
    # tests/test_statics.py checks the engine agrees): the walls' 1e9 was 20 times too soft
    height = LARGE.courses * LARGE.brick_height_m
    critical = buckling_joint_stiffness(height, LARGE.brick_height_m, LARGE.brick_width_m)
    assert critical == pytest.approx(2.08e10, rel=0.01)  # 12 rho g L^3 / (1.986^3 h t^2), by hand
    assert BUILDINGS["building-large"].joint == FULL_SCALE_JOINT and FULL_SCALE_JOINT.kn >= 2 * critical > 2 * BUILDING_JOINT.kn

@pytest.mark.parametrize("arguments, words", [
    ((True, 0.06, 0.12), "buckling_joint_stiffness height_m = True: must be a number in (0, 1000] m"),
    ((9.6, -1.0, 0.12), "buckling_joint_stiffness course_m = -1.0: must be"),
    ((9.6, 0.06, float("nan")), "buckling_joint_stiffness thickness_m = nan: must be"),
    ((9.6, 0.06, 0.12, "1800"), "buckling_joint_stiffness density = '1800': must be"),
])
def test_the_buckling_stiffness_refuses_what_is_no_length_or_density(arguments, words):
    """Found by a hunt: True, -1 and NaN gave numbers (-3.1e7 for a negative course), a text a TypeError."""
    with pytest.raises(ModelError, match=re.escape(words)):
        buckling_joint_stiffness(*arguments)


def test_a_building_exported_is_read_back_the_same(tmp_path):
    model = building_model(TINY)
    save_model(model, tmp_path / "tiny.toml")
    again = load_model(tmp_path / "tiny.toml")
    assert again.block_name == model.block_name and not again.in_plane
    for a, b in zip(model.block_shape, again.block_shape):
        np.testing.assert_allclose(a.vertices, b.vertices, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(again.block_fixed, model.block_fixed)
    np.testing.assert_allclose(again.block_mass, model.block_mass, rtol=1e-12)
    assert (again.joint, again.contacts, again.solver, again.supports) == (model.joint, model.contacts, model.solver, model.supports)


def test_drydem_export_and_tilt_a_built_in_building(tmp_path):
    exported = tmp_path / "building.toml"
    result = CliRunner().invoke(main, ["export", "building-small", str(exported)])
    assert result.exit_code == 0, result.output
    again, small = load_model(exported), load_target("building-small").model
    assert again.block_name == small.block_name
    assert all(np.allclose(a.vertices, b.vertices, rtol=0, atol=1e-12) for a, b in zip(again.block_shape, small.block_shape))


def test_drydem_tilt_about_x_writes_its_axis_mechanism_and_vtk(tiny, tmp_path):
    save_model(tiny, tmp_path / "tiny.toml")
    out = tmp_path / "out"
    result = CliRunner().invoke(main, ["tilt", str(tmp_path / "tiny.toml"), "--tilt-axis", "x", "--increment", "1",
                                       "--max-angle", "2", "--vtk", "--out", str(out)])
    assert result.exit_code == 0, result.output
    assert "tilting about x: the lateral load acts along y" in result.output and "no collapse up to 2.00 deg" in result.output
    summary = json.loads((out / "summary.json").read_text())
    assert summary["analysis"]["tilt_axis"] == "x" and wall_of(summary["monitored_block"]) == 2
    assert (out / "mechanism.png").stat().st_size > 20_000 and (out / "pushover.png").is_file()
    assert (out / "vtk" / "blocks.pvd").is_file()
    # a resume with the other axis is refused, naming it
    again = CliRunner().invoke(main, ["tilt", str(tmp_path / "tiny.toml"), "--increment", "1", "--max-angle", "3", "--vtk",
                                      "--out", str(out), "--resume"])
    assert again.exit_code == 1 and "tilt setting tilt_axis: 'x' in the checkpoint, 'y' now" in again.output


def test_an_in_plane_wall_is_not_tilted_about_x_by_the_cli():
    result = CliRunner().invoke(main, ["tilt", "perforated_wall", "--tilt-axis", "x"])
    assert result.exit_code == 1 and "out of its plane, but it is an in-plane model" in result.output


def test_the_video_of_a_building_is_drawn_in_3d(tilted, tmp_path, monkeypatch):
    """A building's collapse video (drydem tilt --video, drydem animate) shows it in 3D, as its
    mechanism.png does, not by its projection on the x-z plane (where its walls hide each other),
    seen from the side the load pushes towards (here y: tilted about x) with the displacement
    along it in the caption; a wall's stays in its plane (tests/test_vtk_series.py)."""
    import shutil

    import imageio.v2 as imageio

    from drydem.report import animation

    _, series, _ = tilted
    short = tmp_path / "three"  # the first three frames of the series
    short.mkdir()
    for k in range(3):
        shutil.copy(series.folder / f"blocks_{k:04d}.vtu", short)
    (short / "frames.csv").write_text("\n".join((series.folder / "frames.csv").read_text().splitlines()[:4]) + "\n")
    drawn = {"3d": 0, "flat": 0}

    def counted(kind, draw):
        def spy(*args, **kwargs):
            drawn[kind] += 1
            return draw(*args, **kwargs)
        return spy

    monkeypatch.setattr(animation, "draw_faces_3d", counted("3d", animation.draw_faces_3d))
    monkeypatch.setattr(animation, "draw_displacements", counted("flat", animation.draw_displacements))
    views = []
    monkeypatch.setattr(animation, "frame_3d", lambda ax, *args, **kwargs: views.append(kwargs["load_direction"]) or frame_3d(ax, *args, **kwargs))
    written = animation.render_video(short, tmp_path / "collapse.gif", fps=4)
    frames = imageio.mimread(written)
    assert drawn == {"3d": 3, "flat": 0} and len(frames) == 3 and frames[0].shape[:2] == (720, 1280)
    assert views == [1, 1, 1]  # each frame's box framed from the y side (plots.VIEW_AZIMUTH)
    first = animation.series_frames(short)[0]
    assert len(first.blocks) == 185 and all(len(faces) == 6 for faces in first.blocks)  # every brick, by its 6 faces
    assert first.load_direction == 1 and ", monitored uy " in first.caption
    assert all(row.endswith(",y") for row in (short / "frames.csv").read_text().splitlines()[1:])
