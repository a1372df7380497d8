"""Seeing the collapse: the VTK time series, videos, and nothing written unless asked."""

import csv
import re

import meshio
import numpy as np
import pytest
from click.testing import CliRunner

import drydem as dd
from drydem.analysis.tilt import TiltSettings, tilt_analysis
from drydem.cli import main
from drydem.errors import DrydemError
from drydem.files import WRITING, lock_exclusively, partial_name, unlock
from drydem.io.model_file import save_model
from drydem.io.results import RUN_MARK
from drydem.engine.checkpoint import load_checkpoint
from drydem.io.vtk import VtkSeries, write_vtu
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


def test_save_every_keeps_every_other_equilibrium_and_the_last(wall, tmp_path):
    """The last equilibrium, at the collapse angle (25 deg), is kept before the states past
    collapse whatever N (found by a hunt: the series jumped from 20 deg to past collapse); a run
    that ends at its maximum angle has no states past collapse, and keeps every N-th only."""
    series = VtkSeries(tmp_path, wall, every=2)
    result = tilt_analysis(wall, SETTINGS, on_frame=series)
    assert [float(r["tilt_deg"]) for r in frames(tmp_path) if r["kind"] == "equilibrium"] == [0, 10, 20, 25]
    assert result.collapse_angle_deg == 25.0 and frames(tmp_path)[4]["kind"] == "past collapse"


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
    assert sorted(p.name for p in out.iterdir()) == [RUN_MARK, "checkpoint.npz", "mechanism.png", "pushover.csv", "pushover.png",
                                                     "summary.json"]


def test_animate_names_a_folder_without_a_series(tmp_path):
    result = CliRunner().invoke(main, ["animate", str(tmp_path)])
    assert result.exit_code == 1 and "no frames.csv: not a VTK series" in result.output


def first_frames(run, folder, count=3):
    """``folder`` holding the first ``count`` frames of the run's series (a short video)."""
    import shutil

    folder.mkdir()
    for k in range(count):
        shutil.copy(run[1] / f"blocks_{k:04d}.vtu", folder)
    lines = (run[1] / "frames.csv").read_text().splitlines()[:count + 1]
    (folder / "frames.csv").write_text("\n".join(lines) + "\n")
    return folder


def no_ffmpeg(monkeypatch):
    """imageio cannot write an MP4 (as without the ffmpeg binary)."""
    import imageio.v2 as imageio

    def refused(*args, **kwargs):
        raise RuntimeError("no ffmpeg here")

    monkeypatch.setattr(imageio, "get_writer", refused)


def test_without_ffmpeg_the_video_falls_back_to_a_gif_at_the_frame_rate_asked(run, tmp_path, monkeypatch):
    import imageio.v2 as imageio
    from PIL import Image

    from drydem.report.animation import render_video

    short = first_frames(run, tmp_path / "three")
    no_ffmpeg(monkeypatch)
    written = render_video(short, tmp_path / "collapse.mp4", fps=4)
    assert written == tmp_path / "collapse.gif" and len(imageio.mimread(written)) == 3
    with Image.open(written) as gif:
        assert gif.info["duration"] == 250  # ms a frame: 4 frames per second


def test_the_gif_an_mp4_falls_back_to_is_not_overwritten_either(run, tmp_path, monkeypatch):
    from drydem.errors import DrydemError
    from drydem.report.animation import render_video

    short = first_frames(run, tmp_path / "three")
    no_ffmpeg(monkeypatch)
    (tmp_path / "collapse.gif").write_bytes(b"an earlier video")
    with pytest.raises(DrydemError, match=r"collapse.gif: exists; pass --overwrite to replace it, or another --out"):
        render_video(short, tmp_path / "collapse.mp4", fps=4)
    assert (tmp_path / "collapse.gif").read_bytes() == b"an earlier video"


def test_animate_keeps_an_existing_video_unless_told_to_overwrite_it(run, tmp_path, monkeypatch):
    import imageio.v2 as imageio

    from drydem.report import animation

    short = first_frames(run, tmp_path / "three")
    video = tmp_path / "collapse.gif"
    video.write_bytes(b"an earlier video")
    drawn, draw = [], animation._image

    def counted(*args, **kwargs):
        drawn.append(1)
        return draw(*args, **kwargs)

    monkeypatch.setattr(animation, "_image", counted)
    result = CliRunner().invoke(main, ["animate", str(short), "-o", str(video)])
    assert result.exit_code == 1 and f"{video}: exists; pass --overwrite to replace it, or another --out" in result.output
    assert video.read_bytes() == b"an earlier video" and not drawn  # refused before any frame is drawn
    result = CliRunner().invoke(main, ["animate", str(short), "-o", str(video), "--overwrite"])
    assert result.exit_code == 0, result.output
    assert len(imageio.mimread(video)) == len(drawn) == 3


def test_overwrite_replaces_a_video_file_not_a_link_there(run, tmp_path):
    link = tmp_path / "collapse.gif"
    link.symlink_to(tmp_path / "elsewhere.gif")
    result = CliRunner().invoke(main, ["animate", str(run[1]), "-o", str(link), "--overwrite"])
    assert result.exit_code == 1
    assert f"{link}: exists and is not a regular file (a link, a pipe or a device): --overwrite replaces files only" in result.output
    assert link.is_symlink()


@pytest.mark.parametrize("fps", ["nan", "inf", "-inf", "0", "0.05", "101"])
def test_animate_refuses_a_frame_rate_that_is_not_finite_or_out_of_range(run, tmp_path, fps):
    result = CliRunner().invoke(main, ["animate", str(run[1]), "-o", str(tmp_path / "collapse.gif"), "--fps", fps])
    assert result.exit_code == 2
    assert f"Invalid value for '--fps': {float(fps)!r} frames per second: must be a finite number from 0.1 to 100" in result.output
    assert not (tmp_path / "collapse.gif").exists()


def test_the_fps_help_states_the_range_render_video_enforces():
    from drydem.report.animation import FPS_RANGE

    result = CliRunner().invoke(main, ["animate", "--help"])
    assert result.exit_code == 0 and "{:g} to {:g}".format(*FPS_RANGE) in " ".join(result.output.split())


def test_animate_names_a_frames_csv_that_is_not_text(tmp_path):
    (tmp_path / "frames.csv").write_bytes(b"frame\xf9\x00\xff,kind\n")
    result = CliRunner().invoke(main, ["animate", str(tmp_path), "-o", str(tmp_path / "collapse.gif")])
    assert result.exit_code == 1
    assert f"{tmp_path / 'frames.csv'}: not a text file (byte 5 is not UTF-8); frames.csv of drydem tilt or shake --vtk is CSV text" in result.output


def test_animate_names_the_line_of_a_frame_whose_tilt_is_not_finite(run, tmp_path):
    short = first_frames(run, tmp_path / "three")
    lines = (short / "frames.csv").read_text().splitlines()
    lines[2] = lines[2].replace(lines[2].split(",")[2], "nan", 1)
    (short / "frames.csv").write_text("\n".join(lines) + "\n")
    result = CliRunner().invoke(main, ["animate", str(short), "-o", str(tmp_path / "collapse.gif")])
    assert result.exit_code == 1
    assert "frames.csv: line 3: not a frame of drydem tilt or shake --vtk (tilt_deg 'nan': must be a finite number" in result.output
    lines[2] = lines[2].replace("nan", "1e300", 1)  # found by a hunt: drawn as a caption
    (short / "frames.csv").write_text("\n".join(lines) + "\n")
    result = CliRunner().invoke(main, ["animate", str(short), "-o", str(tmp_path / "collapse.gif")])
    assert result.exit_code == 1 and "line 3: not a frame of drydem tilt or shake --vtk (tilt_deg '1e300': must be a " \
        "finite number in [0, 90]" in result.output, result.output


def _frame(line, number):
    """A row of frames.csv with its frame number replaced by ``number``."""
    return f"{number},{line.partition(',')[2]}"


def _with_column(lines):
    """frames.csv with a column drydem does not write."""
    return [lines[0] + ",extra", *(line + ",1" for line in lines[1:])]


@pytest.mark.parametrize("edit, message", [
    (lambda lines: [*lines[:3], _frame(lines[3], 1)],
     "line 4: frame 1 is not after frame 1 (line 3): frame numbers must increase strictly"),
    (lambda lines: [lines[0], lines[1], lines[3], lines[2]],
     "line 4: frame 1 is not after frame 2 (line 3): frame numbers must increase strictly"),
    (_with_column, "line 1: unknown columns 'extra'; drydem writes the columns frame, kind, tilt_deg, ux_m, load_direction "
                   "(tilt --vtk) or frame, time_s, ux_m, load_direction (shake --vtk)"),
    (lambda lines: [",".join(lines[0].split(",")[:2] + lines[0].split(",")[3:]), *lines[1:]],
     "line 1: missing columns 'tilt_deg'"),
    (lambda lines: [lines[0].replace("load_direction", "ux_m"), *lines[1:]], "line 1: columns named twice: 'ux_m'; drydem writes each once"),
    (lambda lines: [lines[0], lines[1], lines[2] + ",1", lines[3]],
     "line 3: not a frame of drydem tilt or shake --vtk (6 values; the header has 5 columns)"),
    (lambda lines: [lines[0], lines[1], _frame(lines[2], "+1"), lines[3]],
     "line 3: not a frame of drydem tilt or shake --vtk (frame '+1': must be written in the digits 0-9"),
    (lambda lines: [lines[0], lines[1], _frame(lines[2], "9" * 400), lines[3]],
     "line 3: not a frame of drydem tilt or shake --vtk (frame '99999999999999999...99999999999999999' "
     "(402 characters): must be at most 999999999"),
], ids=["listed-twice", "out-of-order", "unknown-column", "missing-column", "column-twice", "extra-value", "plus-sign", "400-digits"])
def test_animate_refuses_a_frames_csv_not_as_drydem_writes_it_naming_the_line_and_the_rule(run, tmp_path, edit, message):
    """The findings: a frame listed twice (only noted: a frame on disk left out), frames listed
    backwards, an unknown column and a column named twice (the row kept its last value) were
    drawn; a 400-digit frame number was echoed whole."""
    short = first_frames(run, tmp_path / "three")
    lines = (short / "frames.csv").read_text().splitlines()
    (short / "frames.csv").write_text("\n".join(edit(lines)) + "\n")
    result = CliRunner().invoke(main, ["animate", str(short), "-o", str(tmp_path / "collapse.gif")])
    assert result.exit_code == 1 and f"Error: {short / 'frames.csv'}: {message}" in result.output, result.output
    assert "9" * 40 not in result.output and not (tmp_path / "collapse.gif").exists()


def test_a_video_another_process_is_writing_is_neither_written_nor_replaced_by_a_gif(run, tmp_path):
    """Found by a review: that refusal was taken for ffmpeg failing, and a GIF written instead."""
    short = first_frames(run, tmp_path / "three")
    video = tmp_path / "collapse.mp4"
    lock = partial_name(video, WRITING)
    held = lock_exclusively(lock)
    try:
        result = CliRunner().invoke(main, ["animate", str(short), "-o", str(video)])
    finally:
        unlock(lock, held)
    assert result.exit_code == 1 and "collapse.mp4: another drydem process is writing it" in result.output, result.output
    assert sorted(p.name for p in tmp_path.iterdir()) == ["three"]


def spoiled(run, tmp_path, spoil):
    """A one-frame series whose blocks_0000.vtu ``spoil`` (a function of the meshio mesh) changed."""
    import meshio

    short = first_frames(run, tmp_path / "spoiled", count=1)
    mesh = meshio.read(short / "blocks_0000.vtu")
    spoil(mesh)
    meshio.write(short / "blocks_0000.vtu", mesh, file_format="vtu")
    return short


def _set(mesh, field, value):
    for values in mesh.cell_data[field]:
        values[:] = value


def _replace(mesh, field, value):
    """``field`` of every block set to the float ``value`` (a flag's integers would not hold it)."""
    mesh.cell_data[field] = [np.full(len(values), value) for values in mesh.cell_data[field]]


@pytest.mark.parametrize("spoil, message", [
    (lambda mesh: _set(mesh, "active", 0), "no block in the analysis (active = 0 for every block): nothing to draw"),
    (lambda mesh: _set(mesh, "displacement_magnitude", np.nan), "displacement_magnitude: not all finite numbers >= 0: not a frame drydem writes"),
    (lambda mesh: _set(mesh, "displacement_magnitude", -1.0), "displacement_magnitude: not all finite numbers >= 0: not a frame drydem writes"),
    (lambda mesh: mesh.points.__setitem__((0, 2), np.inf), "points: not all finite numbers within 1e+07 m of the origin"),
    # found by a hunt, each a traceback in matplotlib or Qhull: a point 1e300 m away, a magnitude
    # of three components, triangles for blocks, flags that are neither 0 nor 1
    (lambda mesh: mesh.points.__imul__(1e300), "points: not all finite numbers within 1e+07 m of the origin"),
    (lambda mesh: mesh.cell_data.__setitem__("displacement_magnitude", [np.ones((len(v), 3)) for v in mesh.cell_data["active"]]),
     "displacement_magnitude: shape ("),
    (lambda mesh: setattr(mesh, "cells", [meshio.CellBlock("triangle", np.array([[0, 1, 2]] * len(mesh.cell_data["active"][0])))]),
     "cells triangle: not a frame drydem writes (one polyhedron a block)"),
    (lambda mesh: _replace(mesh, "active", 0.5), "active: values other than 0 and 1"),
    (lambda mesh: _replace(mesh, "fixed", np.nan), "fixed: values other than 0 and 1"),
], ids=["no-active-block", "nan-magnitude", "negative-magnitude", "inf-point", "far-point", "vector-magnitude", "triangles",
        "half-active", "nan-fixed"])
def test_animate_names_a_frame_it_cannot_draw_and_the_rule(run, tmp_path, spoil, message):
    short = spoiled(run, tmp_path, spoil)
    result = CliRunner().invoke(main, ["animate", str(short), "-o", str(tmp_path / "collapse.gif")])
    assert result.exit_code == 1 and f"Error: {short / 'blocks_0000.vtu'}: {message}" in result.output
    assert not (tmp_path / "collapse.gif").exists()


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
    with pytest.raises(DrydemError, match=r"frames.csv: line 2: not a frame of drydem tilt or shake --vtk \(load_direction 'z': "
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
    kept = load_checkpoint(checkpoint)[1]["records"][:, 0]
    tilt_analysis(wall, SETTINGS, on_frame=VtkSeries(folder, wall, resumed_tilts_deg=kept), checkpoint=checkpoint, resume=True)
    resumed, uninterrupted = frames(folder), frames(run[1])
    assert [(r["frame"], r["kind"], r["tilt_deg"]) for r in resumed] == [(r["frame"], r["kind"], r["tilt_deg"]) for r in uninterrupted]


def interrupted_series(wall, folder, checkpoint):
    """A series and checkpoint of the run interrupted at its third equilibrium (two frames,
    0 and 5 deg); the checkpoint's equilibrium tilts."""
    def interrupt(record):
        if record.tilt_deg >= 10.0:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        tilt_analysis(wall, SETTINGS, on_frame=VtkSeries(folder, wall), on_record=interrupt, checkpoint=checkpoint, checkpoint_every_s=0.0)
    return load_checkpoint(checkpoint)[1]["records"][:, 0]


def shifted_tilt(folder):
    text = (folder / "frames.csv").read_text()
    (folder / "frames.csv").write_text(text.replace(",5.000000,", ",4.000000,"))


def cut_short(folder):
    (folder / "frames.csv").write_text("".join((folder / "frames.csv").read_text().splitlines(keepends=True)[:2]))


@pytest.mark.parametrize("tamper, problem", [
    (shifted_tilt, "its frame 1 is at 4 deg where the run's equilibrium is at 5 deg"),
    (cut_short, "it lists 1 of the 2 equilibrium frames the run's checkpoint has reached"),
    (lambda folder: (folder / "contacts_0001.vtu").unlink(), "contacts_0001.vtu, which frames.csv lists, is missing"),
], ids=["another-run", "cut-short", "file-deleted"])
def test_a_resumed_series_that_is_not_the_run_s_is_refused_naming_what_differs(wall, tmp_path, tamper, problem):
    """Found by a hunt: another run's series copied in, a frames.csv cut short and a frame's file
    deleted were each spliced into the resumed series without a word."""
    folder = tmp_path / "vtk"
    tilts = interrupted_series(wall, folder, tmp_path / "checkpoint.npz")
    tamper(folder)
    with pytest.raises(DrydemError, match=re.escape(f"{folder}: its VTK series is not this run's ({problem}): pass --overwrite")):
        VtkSeries(folder, wall, resumed_tilts_deg=tilts)


def test_a_series_folder_that_is_a_link_is_refused(wall, tmp_path):
    # found by a hunt: a resumed run wrote its frames into the other run's series the link led to
    (tmp_path / "other").mkdir()
    (tmp_path / "vtk").symlink_to(tmp_path / "other")
    for resumed in (None, [0.0]):
        with pytest.raises(DrydemError, match=re.escape(f"{tmp_path / 'vtk'}: is a link; a run writes its VTK series in a folder of its own")):
            VtkSeries(tmp_path / "vtk", wall, resumed_tilts_deg=resumed)
    assert list((tmp_path / "other").iterdir()) == []


def test_a_caption_shows_a_round_off_below_a_hundredth_of_a_millimetre_as_zero():
    from drydem.report.animation import _caption

    row = {"kind": "equilibrium", "tilt_deg": "0.0", "ux_m": "-3e-20"}
    assert _caption(row, 0) == "equilibrium: tilt 0.00 deg, monitored ux 0.00 mm"
    assert _caption({"time_s": "1.0", "ux_m": "-0.0042"}, 0) == "t = 1.000 s, monitored ux -4.20 mm"


def test_a_shake_frame_before_the_table_started_or_before_the_frame_before_is_refused(tmp_path):
    """Found by a hunt: time_s = -5 in the middle of a shake series was drawn."""
    from drydem.errors import DrydemError
    from drydem.report.animation import _caption, _check_increasing

    with pytest.raises(ValueError, match=r"time_s '-5': must be a finite number >= 0"):
        _caption({"time_s": "-5", "ux_m": "0"}, 0)
    rows = [{"frame": "0", "time_s": "0.0"}, {"frame": "1", "time_s": "0.2"}, {"frame": "2", "time_s": "0.1"}]
    with pytest.raises(DrydemError, match=r"frames.csv: line 4: time_s 0.1 is before the frame before's, 0.2 \(line 3\)"):
        _check_increasing(tmp_path / "frames.csv", rows)


@pytest.mark.parametrize("interrupted_at_deg", [10.0, 15.0])
def test_a_resumed_tilt_keeps_its_thinned_vtk_series_whole_and_refuses_to_leave_it_partial(wall, tmp_path, monkeypatch,
                                                                                         interrupted_at_deg):
    """Found by a hunt: a run begun with --vtk --save-every 3, interrupted and resumed, kept
    frames at other tilts than the uninterrupted run (counting on from the frames written, not
    from the checkpoint's equilibria); a run resumed without --vtk left its series stopped at
    the interruption, which `drydem animate` then rendered as the collapse; one resumed with
    --vtk where none was begun started its series at the checkpoint. The last two are refused,
    as is another --save-every; the first gives the uninterrupted run's frames."""
    from drydem.io.results import PushoverWriter

    model_file = tmp_path / "wall.toml"
    save_model(wall, model_file)
    tilt = ["tilt", str(model_file), "--increment", "5", "--fixed", "--save-every", "2"]
    whole = CliRunner().invoke(main, [*tilt, "--vtk", "--out", str(tmp_path / "whole")])
    assert whole.exit_code == 0, whole.output
    write_row = PushoverWriter.__call__

    def interrupting(writer, record):
        write_row(writer, record)
        if record.tilt_deg >= interrupted_at_deg:
            raise KeyboardInterrupt

    out = tmp_path / "run"
    monkeypatch.setattr(PushoverWriter, "__call__", interrupting)
    assert CliRunner().invoke(main, [*tilt, "--vtk", "--out", str(out)]).exit_code == 130
    monkeypatch.undo()
    without = CliRunner().invoke(main, [*tilt[:-2], "--out", str(out), "--resume"])
    assert without.exit_code == 1 and "holds the VTK series of the run being resumed; resume with --vtk" in without.output
    other = CliRunner().invoke(main, [*tilt[:-1], "3", "--vtk", "--out", str(out), "--resume"])
    assert other.exit_code == 1 and "the VTK series was begun with --save-every 2" in other.output
    settings = out / "vtk" / "series.json"
    kept = settings.read_text()
    settings.write_text('{"every_other": 2}')  # the reason in plain words, not KeyError('every')
    foreign = CliRunner().invoke(main, [*tilt, "--vtk", "--out", str(out), "--resume"])
    assert foreign.exit_code == 1 and "series.json: not the settings of a drydem tilt --vtk series (no 'every')" in foreign.output
    settings.write_text(kept)
    resumed = CliRunner().invoke(main, [*tilt, "--vtk", "--out", str(out), "--resume"])
    assert resumed.exit_code == 0, resumed.output
    assert [(r["frame"], r["kind"], r["tilt_deg"]) for r in frames(out / "vtk")] == \
        [(r["frame"], r["kind"], r["tilt_deg"]) for r in frames(tmp_path / "whole" / "vtk")]


def test_a_frames_csv_number_not_as_drydem_writes_it_or_a_changing_direction_is_refused(wall, tmp_path):
    """Found by a hunt: float() read time_s 0_5 as 5 s; ux_m 1e300 was captioned; a series whose
    load direction changed from x to y was drawn from both sides."""
    from drydem.errors import DrydemError
    from drydem.report.animation import _caption, series_frames

    with pytest.raises(ValueError, match=r"time_s '0_5': not a plain decimal number, as drydem writes it"):
        _caption({"time_s": "0_5", "ux_m": "0"}, 0)
    with pytest.raises(ValueError, match=r"ux_m '1e300': must be a finite number in \[-2e\+06, 2e\+06\]"):
        _caption({"kind": "equilibrium", "tilt_deg": "1.0", "ux_m": "1e300"}, 0)
    folder = tmp_path / "vtk"
    VtkSeries(folder, wall)  # an empty series' folder
    for k in range(2):
        write_vtu(wall, folder / f"blocks_{k:04d}.vtu")
    (folder / "frames.csv").write_text("frame,kind,tilt_deg,ux_m,load_direction\n0,equilibrium,0.0,0,x\n1,equilibrium,1.0,0,y\n")
    with pytest.raises(DrydemError, match="frames.csv: line 3: load_direction y, where line 2 has x: drydem writes one load"):
        series_frames(folder)
