"""Seeing the collapse: the VTK time series, videos, and nothing written unless asked."""

import csv

import numpy as np
import pytest
from click.testing import CliRunner

import drydem as dd
from drydem.analysis.tilt import TiltSettings, tilt_analysis
from drydem.cli import main
from drydem.io.model_file import save_model
from drydem.io.vtk import VtkSeries
from conftest import layout_blocks

#: a 2-brick x 6-course running-bond wall that slides at atan(0.5) = 26.6 deg; 5-degree steps
SETTINGS = TiltSettings(increment_deg=5.0)


@pytest.fixture(scope="module")
def wall() -> dd.Model:
    return dd.build_model(layout_blocks("bBb\nBB\n" * 3), density=1800.0, joint=dd.JointMaterial(kn=1e8, ks=1e8, friction=0.5),
                          supports=dd.Supports(fix_y=True))


@pytest.fixture(scope="module")
def run(wall, tmp_path_factory):
    folder = tmp_path_factory.mktemp("series")
    series = VtkSeries(folder, wall)
    return tilt_analysis(wall, SETTINGS, on_frame=series), folder


def frames(folder):
    with (folder / "frames.csv").open() as f:
        return list(csv.DictReader(f))


def test_the_series_has_every_equilibrium_then_the_collapse(run):
    result, folder = run
    rows = frames(folder)
    equilibria = [r for r in rows if r["kind"] == "equilibrium"]
    assert [float(r["tilt_deg"]) for r in equilibria] == [r.tilt_deg for r in result.records] == [0, 5, 10, 15, 20, 25]
    past = [r for r in rows if r["kind"] == "past collapse"]
    assert len(past) >= 2 and all(float(r["tilt_deg"]) == 30.0 for r in past)
    assert rows == equilibria + past
    for name in ("blocks.pvd", "contacts.pvd"):
        assert (folder / name).read_text().count("<DataSet") == len(rows)


def test_block_files_read_back_with_the_runs_displacements(run, wall):
    import meshio

    result, folder = run
    last_equilibrium = max(int(r["frame"]) for r in frames(folder) if r["kind"] == "equilibrium")
    mesh = meshio.read(folder / f"blocks_{last_equilibrium:04d}.vtu")
    assert sum(len(c.data) for c in mesh.cells) == wall.n_blocks
    assert len(mesh.points) == sum(len(s.vertices) for s in wall.block_shape)
    fields = {name: np.concatenate(values) for name, values in mesh.cell_data.items()}
    assert {"block_id", "displacement", "displacement_magnitude", "rotation", "velocity", "angular_velocity"} <= set(fields)
    moved = result.collapse_state.position - wall.block_centroid
    np.testing.assert_allclose(fields["displacement"], moved, rtol=0, atol=1e-15)
    np.testing.assert_allclose(fields["displacement_magnitude"], np.linalg.norm(moved, axis=1), rtol=0, atol=1e-15)


def test_contact_files_carry_the_weight_on_the_base(run, wall):
    # under vertical gravity (frame 0) the sub-contacts on the base carry the whole weight
    import meshio

    _, folder = run
    mesh = meshio.read(folder / "contacts_0000.vtu")
    data = mesh.point_data
    assert {"normal_force", "shear_force", "shear_force_magnitude", "slip", "gap"} <= set(data)
    on_base = (data["block_ref"] == 0) | (data["block_inc"] == 0)
    assert data["normal_force"][on_base].sum() == pytest.approx(wall.total_mass * dd.G, rel=1e-4)
    assert set(np.unique(data["slip"])) <= {0, 1, 2}


def test_saving_frames_does_not_change_the_analysis(run, wall):
    result, _ = run
    plain = tilt_analysis(wall, SETTINGS)
    assert plain.collapse_angle_deg == result.collapse_angle_deg and plain.cycles == result.cycles
    np.testing.assert_array_equal(plain.final_state.position, result.final_state.position)


def test_save_every_keeps_every_other_equilibrium(wall, tmp_path):
    series = VtkSeries(tmp_path, wall, every=2)
    tilt_analysis(wall, SETTINGS, on_frame=series)
    assert [float(r["tilt_deg"]) for r in frames(tmp_path) if r["kind"] == "equilibrium"] == [0, 10, 20]


@pytest.mark.slow
def test_drydem_tilt_video_and_animate(wall, tmp_path):
    import imageio.v2 as imageio

    model_file = tmp_path / "wall.toml"
    save_model(wall, model_file)
    out = tmp_path / "run"
    # a short collapse (stopped at 5 mm) keeps the video short
    result = CliRunner().invoke(main, ["tilt", str(model_file), "--increment", "10", "--stop-displacement", "0.005", "--video", "--out", str(out)])
    assert result.exit_code == 0, result.output
    count = len(frames(out / "vtk"))
    reader = imageio.get_reader(out / "collapse.mp4")
    assert reader.count_frames() == count and reader.get_meta_data()["size"] == (1280, 720)
    result = CliRunner().invoke(main, ["animate", str(out), "--out", str(tmp_path / "again.gif")])
    assert result.exit_code == 0, result.output
    gif = imageio.mimread(tmp_path / "again.gif")
    assert len(gif) == count and gif[0].shape[:2] == (720, 1280)


def test_nothing_is_written_without_the_flags(wall, tmp_path):
    model_file = tmp_path / "wall.toml"
    save_model(wall, model_file)
    out = tmp_path / "run"
    result = CliRunner().invoke(main, ["tilt", str(model_file), "--increment", "10", "--out", str(out)])
    assert result.exit_code == 0, result.output
    assert sorted(p.name for p in out.iterdir()) == ["checkpoint.npz", "mechanism.png", "pushover.csv", "pushover.png", "summary.json"]


def test_animate_names_a_folder_without_a_series(tmp_path):
    result = CliRunner().invoke(main, ["animate", str(tmp_path)])
    assert result.exit_code == 1 and "no frames.csv: not a VTK series" in result.output


def test_without_ffmpeg_the_video_falls_back_to_a_gif(run, tmp_path, monkeypatch):
    import imageio.v2 as imageio

    from drydem.report.animation import render_video

    import shutil

    _, folder = run
    short = tmp_path / "three"  # the first three frames of the series
    short.mkdir()
    for k in range(3):
        shutil.copy(folder / f"blocks_{k:04d}.vtu", short)
    lines = (folder / "frames.csv").read_text().splitlines()[:4]
    (short / "frames.csv").write_text("\n".join(lines) + "\n")

    def no_ffmpeg(*args, **kwargs):
        raise RuntimeError("no ffmpeg here")

    monkeypatch.setattr(imageio, "get_writer", no_ffmpeg)
    written = render_video(short, tmp_path / "collapse.mp4", fps=4)
    assert written == tmp_path / "collapse.gif" and len(imageio.mimread(written)) == 3


def test_a_series_says_which_way_its_load_acts_and_one_written_before_that_is_read_as_x(wall, run, tmp_path):
    """frames.csv's load_direction column (x for this in-plane wall) sets the side a 3D model is
    seen from; a series without it (written by an older drydem) is read as loaded along x, and
    a direction that is neither x nor y is named with its file and line; a series is given 0 or 1."""
    from drydem.errors import DrydemError
    from drydem.report.animation import series_frames

    _, folder = run
    assert {row["load_direction"] for row in frames(folder)} == {"x"}
    lines = (folder / "frames.csv").read_text().splitlines()
    older = tmp_path / "older"
    older.mkdir()
    (older / "blocks_0000.vtu").write_bytes((folder / "blocks_0000.vtu").read_bytes())
    (older / "frames.csv").write_text("\n".join(line.rpartition(",")[0] for line in lines[:2]) + "\n")
    (frame,) = series_frames(older)
    assert frame.load_direction == 0 and frame.caption == "equilibrium: tilt 0.00 deg, monitored ux 0.00 mm"
    (older / "frames.csv").write_text(f"{lines[0]}\n{lines[1].rpartition(',')[0]},z\n")
    with pytest.raises(DrydemError, match=r"frames.csv: line 2: not a frame of drydem tilt or shake --vtk \(ValueError\(\"load_direction 'z': "
                                          r"must be one of x, y"):
        series_frames(older)
    for bad in (-1, 2, True, 1.0):
        with pytest.raises(DrydemError, match=r"VtkSeries load_direction = .+: must be an integer in \[0, 1\]"):
            VtkSeries(tmp_path / "refused", wall, load_direction=bad)


def test_a_resumed_run_keeps_the_frames_already_written_and_goes_on_after_them(wall, run, tmp_path):
    # interrupted at the third equilibrium, before its frame and checkpoint were written (as a
    # kill could be), then resumed: the series is the uninterrupted run's, frame for frame
    folder, checkpoint = tmp_path / "vtk", tmp_path / "checkpoint.npz"
    series = VtkSeries(folder, wall)

    def interrupt(record):
        if record.tilt_deg >= 10.0:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        tilt_analysis(wall, SETTINGS, on_frame=series, on_record=interrupt, checkpoint=checkpoint)
    assert [row["tilt_deg"] for row in frames(folder)] == ["0.000000", "5.000000"]
    tilt_analysis(wall, SETTINGS, on_frame=VtkSeries(folder, wall, resume=True), checkpoint=checkpoint, resume=True)
    resumed, uninterrupted = frames(folder), frames(run[1])
    assert [(r["frame"], r["kind"], r["tilt_deg"]) for r in resumed] == [(r["frame"], r["kind"], r["tilt_deg"]) for r in uninterrupted]
