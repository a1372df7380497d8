"""Files that are not what drydem expects, and output paths that would lose a file or mean
another: a pipe where a frame or frames.csv should be (read, it would never end), a series
mixed with another model's frames or cut short, a truncated frame, an empty or dangling --out,
show's --overwrite and --strict, and a model with nothing fixed to stand on."""

import os
import signal
import stat
from contextlib import contextmanager
from pathlib import Path

import pytest
from click.testing import CliRunner

import drydem as dd
from drydem.cli import main
from drydem.errors import DrydemError
from drydem.files import WRITING, held, lock_exclusively, locked_by_another, partial_name, replaced_atomically, unlock
from drydem.io.model_file import save_model
from drydem.io.vtk import write_vtu
from conftest import layout_blocks

HEADER = "frame,kind,tilt_deg,ux_m,load_direction"

#: two paper bricks stacked, neither fixed: nothing holds them up
FLOATING = """[joint]
kn = 3e7
ks = 3e7
friction = 0.5
[supports]
fix_y = true
[[block]]
name = "b1"
box = { min = [0, -0.006, 0], max = [0.025, 0.006, 0.0055] }
[[block]]
name = "b2"
box = { min = [0, -0.006, 0.0055], max = [0.025, 0.006, 0.011] }
"""


def wall_model(courses: str = "BB\n") -> dd.Model:
    return dd.build_model(layout_blocks(courses), density=1800.0, supports=dd.Supports(fix_y=True))


@pytest.fixture(scope="module")
def wall() -> dd.Model:
    return wall_model()


def saved(model: dd.Model, path):
    """``path``, where ``model`` is saved as a model file."""
    save_model(model, path)
    return path


def series(folder, model, count=3, rows=None):
    """``folder`` holding a tilting series of ``count`` frames of ``model`` at rest, listed by
    ``rows`` of frames.csv (default: each frame an equilibrium, 1 deg apart)."""
    folder.mkdir()
    for k in range(count):
        write_vtu(model, folder / f"blocks_{k:04d}.vtu")
    rows = [f"{k},equilibrium,{k:.6f},0,x" for k in range(count)] if rows is None else rows
    (folder / "frames.csv").write_text("\n".join([HEADER, *rows]) + "\n")
    return folder


@contextmanager
def within(seconds: int = 60):
    """Fail rather than hang if the block runs longer than ``seconds`` (a pipe opened for reading
    waits for a writer forever)."""
    def expired(number, frame):
        raise TimeoutError(f"still running after {seconds} s: waiting on a pipe?")

    previous = signal.signal(signal.SIGALRM, expired)
    signal.alarm(seconds)
    try:
        yield
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, previous)


def invoke(*args):
    with within():
        return CliRunner().invoke(main, [str(a) for a in args])


def refused(result, *messages, code=1):
    """Exit ``code`` through click (no traceback), each of ``messages`` said."""
    assert result.exit_code == code and isinstance(result.exception, SystemExit), result.output
    assert "Traceback" not in result.output
    for message in messages:
        assert message in result.output, result.output
    return result


def test_animate_refuses_a_frame_file_that_is_a_pipe_without_waiting_on_it(wall, tmp_path):
    folder = series(tmp_path / "vtk", wall)
    (folder / "blocks_0001.vtu").unlink()
    os.mkfifo(folder / "blocks_0001.vtu")
    refused(invoke("animate", folder, "--out", tmp_path / "v.gif"),
            f"{folder / 'blocks_0001.vtu'}: not a regular file (a pipe, a socket or a device): drydem reads files only")
    assert not (tmp_path / "v.gif").exists()


def test_animate_refuses_a_frames_csv_that_is_a_pipe_without_waiting_on_it(wall, tmp_path):
    folder = series(tmp_path / "vtk", wall)
    (folder / "frames.csv").unlink()
    os.mkfifo(folder / "frames.csv")
    refused(invoke("animate", folder, "--out", tmp_path / "v.gif"), f"{folder / 'frames.csv'}: not a regular file")


def test_a_resumed_series_refuses_a_frames_csv_that_is_a_pipe(wall, tmp_path):
    from drydem.io.vtk import VtkSeries

    (tmp_path / "vtk").mkdir()
    os.mkfifo(tmp_path / "vtk" / "frames.csv")
    with within(), pytest.raises(DrydemError, match="frames.csv: not a regular file"):
        VtkSeries(tmp_path / "vtk", wall, resumed_tilts_deg=[0.0])
    assert stat.S_ISFIFO(os.lstat(tmp_path / "vtk" / "frames.csv").st_mode)


def test_a_resumed_run_refuses_a_pushover_csv_that_is_a_pipe(tmp_path):
    from drydem.io.results import PushoverWriter

    os.mkfifo(tmp_path / "pushover.csv")
    with within(), pytest.raises(DrydemError, match=r"pushover.csv: exists and is not a regular file \(a link, a pipe or a device\): "
                                                    r"--resume replaces files only"):
        PushoverWriter(tmp_path)


@pytest.mark.parametrize("make, reason", [
    (os.mkfifo, "not a regular file (a pipe, a socket or a device): drydem reads files only"),
    (os.mkdir, "is a folder, not a file"),
    (lambda path: None, "cannot read the file (No such file or directory)"),
    (lambda path: path.symlink_to(path.with_name("gone")), "cannot read the file ({path} is a link to the missing {tmp}/gone)"),
], ids=["pipe", "folder", "missing", "dangling-link"])
def test_read_text_reads_only_a_regular_file(tmp_path, make, reason):
    from drydem.files import read_text

    path = tmp_path / "frames.csv"
    make(path)
    with within(), pytest.raises(DrydemError) as refusal:
        read_text(path, "CSV text")
    assert str(refusal.value) == f"{path}: {reason.format(path=path, tmp=tmp_path)}; CSV text"


def test_animate_refuses_a_frame_of_another_model(wall, tmp_path):
    folder = series(tmp_path / "vtk", wall)
    write_vtu(wall_model("BB\nBB\n"), folder / "blocks_0002.vtu")
    refused(invoke("animate", folder, "--out", tmp_path / "v.gif"),
            f"{folder / 'blocks_0002.vtu'}: 5 blocks, but the series' first frame blocks_0000.vtu has 3")
    assert not (tmp_path / "v.gif").exists()


@pytest.mark.parametrize("row, message", [
    ("1,bogus,1.000000,0,x", "kind 'bogus': must be one of 'equilibrium', 'past collapse'"),
    ("1,equilibrium,1.000000,0,z", "load_direction 'z': must be one of x, y"),
    ("-1,equilibrium,1.000000,0,x", "frame -1: must be an integer >= 0"),
    ("3.0,equilibrium,1.000000,0,x", "frame '3.0': must be written in the digits 0-9, as drydem writes it"),  # found by a hunt: in int()'s words
], ids=["kind", "load-direction", "frame-number", "decimal-frame"])
def test_animate_refuses_a_row_of_frames_csv_not_as_drydem_writes_it(wall, tmp_path, row, message):
    folder = series(tmp_path / "vtk", wall, count=2, rows=["0,equilibrium,0.000000,0,x", row])
    refused(invoke("animate", folder, "--out", tmp_path / "v.gif"),
            f"{folder / 'frames.csv'}: line 3: not a frame of drydem tilt or shake --vtk ({message})")


def test_animate_refuses_a_shaking_row_loaded_along_z(wall, tmp_path):
    folder = tmp_path / "vtk"
    folder.mkdir()
    write_vtu(wall, folder / "blocks_0000.vtu")
    (folder / "frames.csv").write_text("frame,time_s,ux_m,load_direction\n0,0,0,z\n")
    refused(invoke("animate", folder, "--out", tmp_path / "v.gif"), "line 2: not a frame", "load_direction 'z': must be one of x, y")


def test_animate_names_a_shake_runs_video_as_shake_video_does(wall, tmp_path):
    """Found by a hunt: a shake run was animated to RESULT_DIR/collapse.mp4, beside the
    shake.mp4 that ``shake --video`` writes."""
    folder = tmp_path / "run" / "vtk"
    folder.mkdir(parents=True)
    for k in range(2):
        write_vtu(wall, folder / f"blocks_{k:04d}.vtu")
    (folder / "frames.csv").write_text("frame,time_s,ux_m,load_direction\n0,0,0,x\n1,0.04,0.001,x\n")
    result = invoke("animate", tmp_path / "run")
    assert result.exit_code == 0, result.output
    assert not list((tmp_path / "run").glob("collapse.*")) and list((tmp_path / "run").glob("shake.*"))
    # given the run's vtk/ itself, the video goes beside it, as --video writes it (not into vtk/,
    # where --overwrite of the run would find a file no run writes there)
    for video in (tmp_path / "run").glob("shake.*"):
        video.unlink()
    result = invoke("animate", folder)
    assert result.exit_code == 0, result.output
    assert not list(folder.glob("shake.*")) and list((tmp_path / "run").glob("shake.*"))


def test_animate_notes_the_frames_on_disk_that_frames_csv_does_not_list(wall, tmp_path):
    """A frames.csv cut short is drawn as it stands, with a note naming the frames left out (a
    run stopped between a frame and its index, or resumed and ending sooner, leaves such files)."""
    import imageio.v2 as imageio

    folder = series(tmp_path / "vtk", wall, count=6, rows=["0,equilibrium,0.000000,0,x", "1,equilibrium,1.000000,0,x"])
    result = invoke("animate", folder, "--out", tmp_path / "v.gif")
    assert result.exit_code == 0, result.output
    assert (f"note: {folder}: 4 frames on disk are not listed in frames.csv (blocks_0002.vtu, blocks_0003.vtu, "
            "blocks_0004.vtu, ...): left out of the video") in result.stderr
    assert len(imageio.mimread(tmp_path / "v.gif")) == 2


def test_animate_names_a_truncated_frame_and_prints_nothing_else(wall, tmp_path):
    folder = series(tmp_path / "vtk", wall)
    whole = (folder / "blocks_0001.vtu").read_bytes()
    (folder / "blocks_0001.vtu").write_bytes(whole[:300])
    result = refused(invoke("animate", folder, "--out", tmp_path / "v.gif"),
                     f"{folder / 'blocks_0001.vtu'}: not a readable VTU file (truncated, or not a frame drydem writes)")
    assert result.stdout == ""  # meshio.read would print its reason, an empty line, to stdout


def test_show_keeps_an_existing_file_unless_told_to_overwrite_it(wall, tmp_path, monkeypatch):
    from drydem.report import plots

    target = saved(wall, tmp_path / "wall.toml")
    drawn, draw = [], plots.layout_figure
    monkeypatch.setattr(plots, "layout_figure", lambda *args, **kwargs: drawn.append(1) or draw(*args, **kwargs))
    out = tmp_path / "wall.png"
    out.write_bytes(b"an earlier figure")
    refused(invoke("show", target, "-o", out), f"{out}: exists; pass --overwrite to replace it, or another --out")
    assert out.read_bytes() == b"an earlier figure" and not drawn  # refused before drawing
    assert invoke("show", target, "-o", out, "--overwrite").exit_code == 0
    assert out.read_bytes().startswith(b"\x89PNG") and len(drawn) == 1
    pipe = tmp_path / "pipe.png"
    os.mkfifo(pipe)
    refused(invoke("show", target, "-o", pipe), f"{pipe}: exists; pass --overwrite")
    refused(invoke("show", target, "-o", pipe, "--overwrite"),
            f"{pipe}: exists and is not a regular file (a link, a pipe or a device): --overwrite replaces files only")
    assert stat.S_ISFIFO(os.lstat(pipe).st_mode) and len(drawn) == 1


@pytest.mark.parametrize("command", ["show", "check"])
def test_strict_is_refused_for_a_target_that_is_not_a_wall(wall, tmp_path, monkeypatch, command):
    """--strict checks a wall against the competition brief: on a model file it would be ignored."""
    monkeypatch.chdir(tmp_path)
    target = saved(wall, tmp_path / "wall.toml")
    refused(invoke(command, target, "--strict"), f"--strict checks a wall against the competition brief; {target} is not a wall", code=2)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["wall.toml"]
    assert invoke(command, "WD2", "--strict", *(["-o", tmp_path / "wd2.png"] if command == "show" else [])).exit_code == 0


def commands_with_out() -> list[str]:
    return sorted(name for name, command in main.commands.items() if any(p.name == "out" for p in command.params))


def test_the_commands_with_an_out_option_are_those_expected():
    assert commands_with_out() == ["animate", "calibrate", "limit", "montecarlo", "report", "shake", "show", "sweep", "tilt"]


@pytest.mark.parametrize("command", commands_with_out())
@pytest.mark.parametrize("blank", ["", " "])
def test_an_empty_out_is_refused_not_read_as_the_current_folder(tmp_path, monkeypatch, command, blank):
    monkeypatch.chdir(tmp_path)
    refused(invoke(command, "--out", blank), "Invalid value for '--out'", f"{blank!r}: an empty path; give a file or folder name", code=2)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("blank", ["", " "])
def test_an_empty_calibrate_results_dir_is_refused_not_read_as_the_current_folder(tmp_path, monkeypatch, blank):
    monkeypatch.chdir(tmp_path)  # found by a hunt: `drydem calibrate ""` began writing its runs here
    refused(invoke("calibrate", blank, "--designs", "WD3"), "Invalid value for 'RESULTS_DIR'", f"{blank!r}: an empty path", code=2)
    assert list(tmp_path.iterdir()) == []


def test_an_empty_motion_is_refused_not_read_as_the_current_folder(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # found by a hunt: ".: is a folder, not a motion file"
    refused(invoke("shake", "WD3", "--motion", ""), "Invalid value for '--motion': '': an empty path", code=2)


def test_a_model_file_with_a_byte_order_mark_reads(tmp_path):
    path = tmp_path / "bom.toml"  # found by a hunt: as Windows editors write it, refused as "Invalid statement"
    path.write_bytes(b"\xef\xbb\xbf" + b'[[block]]\nname = "b"\nbox = { min = [0, 0, 0], max = [0.2, 0.1, 0.05] }\n')
    result = invoke("check", path)
    assert result.exit_code == 0 and "blocks          1 (1 movable, 0 fixed)" in result.output, result.output


def test_an_empty_export_output_is_refused(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    refused(invoke("export", "WD1", ""), "Invalid value for 'OUTPUT': '': an empty path; give a file name", code=2)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("command, out, message", [
    ("limit", "gone", "{tmp}/gone: cannot write results there ({tmp}/gone is a link to the missing {tmp}/nowhere)"),
    ("tilt", "gone/run", "{tmp}/gone/run: cannot write results there ({tmp}/gone is a link to the missing {tmp}/nowhere)"),
    ("show", "gone/wall.png", "{tmp}/gone/wall.png: the folder {tmp}/gone does not exist ({tmp}/gone is a link to the missing {tmp}/nowhere)"),
])
def test_an_out_through_a_link_to_a_missing_folder_says_so(wall, tmp_path, command, out, message):
    target = saved(wall, tmp_path / "wall.toml")
    (tmp_path / "gone").symlink_to(tmp_path / "nowhere")
    refused(invoke(command, target, "--out", tmp_path / out), message.format(tmp=tmp_path))
    assert not (tmp_path / "nowhere").exists()


def test_check_warns_of_a_model_with_no_fixed_block(wall, tmp_path):
    path = tmp_path / "floating.toml"
    path.write_text(FLOATING)
    result = invoke("check", path)
    assert result.exit_code == 0, result.output
    assert "unsupported     no fixed block" in result.stderr and "nothing holds the model up" in result.stderr
    result = invoke("check", saved(wall, tmp_path / "wall.toml"))
    assert result.exit_code == 0 and "no fixed block" not in result.output


def test_report_and_a_resumed_montecarlo_name_a_record_that_is_a_pipe_without_waiting_on_it(tmp_path):
    """A sweep's record and a Monte Carlo summary that are pipes: named (not regular files), never
    opened; a folder whose summary.json is a pipe is no run folder (skipped, not waited on)."""
    from drydem.parametric.montecarlo import MonteCarloError, MonteCarloSettings, check_resumable
    from drydem.analysis.tilt import TiltSettings
    from drydem.masonry.imperfections import Imperfections
    from drydem.io.target import load_target

    (tmp_path / "runs").mkdir()
    os.mkfifo(tmp_path / "runs" / "x.json")
    (tmp_path / "run").mkdir()
    os.mkfifo(tmp_path / "run" / "summary.json")
    with within():
        result = CliRunner().invoke(main, ["report", str(tmp_path)])
    assert result.exit_code == 1 and "the report holds no run" in result.output, result.output  # its only record is corrupt
    assert f"{tmp_path / 'runs' / 'x.json'}: not a regular file (a pipe, a socket or a device)" in result.output
    (tmp_path / "mc").mkdir()
    os.mkfifo(tmp_path / "mc" / "summary.json")
    wall = load_target("WD1").wall
    with within(), pytest.raises(MonteCarloError, match="not the summary of a drydem montecarlo run"):
        check_resumable(tmp_path / "mc", MonteCarloSettings(samples=2, seed=0, imperfections=Imperfections(height_sd_mm=0.1),
                                                            tilt=TiltSettings()), wall)


def test_a_runs_pushover_csv_or_a_mesh_that_is_a_pipe_is_named_without_waiting_on_it(tmp_path):
    """Found by a hunt: drydem report waited forever on a tilt folder whose pushover.csv was a
    pipe (its summary.json was checked, not the curve), and read_mesh on a pipe named .obj."""
    from drydem.io.mesh import read_mesh

    run = tmp_path / "results" / "run"
    run.mkdir(parents=True)
    with within():
        assert CliRunner().invoke(main, ["tilt", "WD3", "--increment", "45", "--max-angle", "45", "--out", str(run),
                                         "--overwrite"]).exit_code == 0
    (run / "pushover.csv").unlink()
    os.mkfifo(run / "pushover.csv")
    with within():
        result = CliRunner().invoke(main, ["report", str(tmp_path / "results")])
    assert result.exit_code == 1 and "the report holds no run" in result.output, result.output
    assert f"{run / 'pushover.csv'}: not a regular file (a pipe, a socket or a device)" in result.output
    os.mkfifo(tmp_path / "pipe.obj")
    with within(), pytest.raises(dd.ModelError, match="pipe.obj: not a regular file"):
        read_mesh(tmp_path / "pipe.obj")


def test_a_toml_file_nested_thousands_deep_is_refused_naming_it(tmp_path):
    """Found by a hunt: tomllib parses nested arrays recursively; 3,000 levels ended in a
    RecursionError's traceback."""
    path = tmp_path / "deep.toml"
    path.write_text("[material]\ndensity = " + "[" * 3000 + "]" * 3000 + "\n")
    result = CliRunner().invoke(main, ["check", str(path)])
    assert result.exit_code == 1 and "Traceback" not in result.output
    assert f"{path}: nested deeper than Python's recursion limit" in result.output


def test_a_link_left_at_the_partial_name_is_not_written_through(tmp_path, monkeypatch):
    # drydem writes OUTPUT as .STEM.partial.SUFFIX, then renames it: a link planted there made
    # the export write the model into the link's target and left OUTPUT a link to it
    monkeypatch.chdir(tmp_path)
    (tmp_path / "important.txt").write_text("keep me")
    os.symlink("important.txt", tmp_path / ".y.partial.obj")
    result = invoke("export", "WD1", "y.obj")
    assert result.exit_code == 0, result.output
    assert (tmp_path / "important.txt").read_text() == "keep me"
    assert not (tmp_path / "y.obj").is_symlink() and (tmp_path / "y.obj").read_text().startswith("#")
    assert not os.path.lexists(tmp_path / ".y.partial.obj")


def test_two_processes_writing_one_output_do_not_share_its_partial_file(tmp_path):
    """Two `export`s to one file at once both wrote .STEM.partial.SUFFIX, each deleting the
    other's, and one failed naming that temporary file (found by a hunt)."""
    path = tmp_path / "x.vtu"
    lock = partial_name(path, WRITING)
    held = lock_exclusively(lock)  # the other process, writing x.vtu
    try:
        with pytest.raises(DrydemError, match="x.vtu: another drydem process is writing it"):
            with replaced_atomically(path) as partial:
                partial.write_text("mine")
    finally:
        unlock(lock, held)
    assert not path.exists() and not lock.exists()


def test_a_file_written_by_another_process_meanwhile_is_kept_unless_replacing_was_asked(tmp_path):
    """`export` and `show` look for an existing OUTPUT before their work; two started together
    both found none, and the last to finish replaced the other's without --overwrite."""
    path = tmp_path / "x.txt"
    with pytest.raises(DrydemError, match="x.txt: was written by another process while drydem wrote it, and is kept; pass --overwrite"):
        with replaced_atomically(path, replace=False) as partial:
            partial.write_text("mine")
            path.write_text("theirs")
    assert path.read_text() == "theirs" and sorted(p.name for p in tmp_path.iterdir()) == ["x.txt"]
    with replaced_atomically(path) as partial:
        partial.write_text("mine")
    assert path.read_text() == "mine"


def test_a_lock_file_that_cannot_be_deleted_leaves_the_error_of_the_run(tmp_path, monkeypatch):
    """A results folder made read-only mid-run: the checkpoint's error was followed by a
    PermissionError traceback from deleting the folder's lock (found by a hunt)."""
    original = Path.unlink

    def refused_for_locks(self, missing_ok=False):
        if self.name.endswith(".lock"):
            raise PermissionError(13, "Permission denied", str(self))
        return original(self, missing_ok=missing_ok)

    monkeypatch.setattr(Path, "unlink", refused_for_locks)
    with pytest.raises(DrydemError, match="the run's own error"):
        with held(tmp_path / "run.lock", "busy"):
            raise DrydemError("the run's own error")
    monkeypatch.setattr(Path, "unlink", original)
    with held(tmp_path / "run.lock", "busy"):  # the file left is taken over
        pass
    assert not (tmp_path / "run.lock").exists()


def test_a_link_or_a_pipe_at_a_lock_name_is_refused_not_written_through_or_waited_on(tmp_path):
    """Found by a review: a link planted at .drydem.lock had drydem empty its target and write
    "held by ..." into it; a pipe there was a traceback, or a wait without end."""
    (tmp_path / "victim.txt").write_text("precious")
    os.symlink(tmp_path / "victim.txt", tmp_path / "link.lock")
    os.mkfifo(tmp_path / "pipe.lock")
    with pytest.raises(DrydemError, match="link.lock: cannot make the lock file \\(a link; a lock file is a regular file: remove it\\)"):
        lock_exclusively(tmp_path / "link.lock")
    with pytest.raises(DrydemError, match="pipe.lock: is not a regular file \\(a pipe or a device\\); a lock file is: remove it"):
        lock_exclusively(tmp_path / "pipe.lock")
    assert (tmp_path / "victim.txt").read_text() == "precious"
    assert not locked_by_another(tmp_path / "pipe.lock") and not locked_by_another(tmp_path / "link.lock")


@pytest.mark.parametrize("command", [["tilt", "WD1"], ["limit", "WD1"], ["sweep", "study.toml"]])
def test_an_out_name_longer_than_the_system_takes_is_named_not_a_traceback(tmp_path, monkeypatch, command):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "study.toml").write_text('[study]\nname = "s"\n[[grid]]\ntargets = ["WD1"]\n')
    result = invoke(*command, "--out", "d" * 256)
    assert result.exit_code == 1 and "Traceback" not in result.output, result.output
    assert "File name too long" in result.output and not list(tmp_path.glob("d*"))


def test_an_output_name_of_250_characters_is_written(tmp_path, monkeypatch):
    # the partial name adds 9 characters: past the system's 255 it was an OSError traceback
    monkeypatch.chdir(tmp_path)
    name = "b" * 246 + ".obj"
    result = invoke("export", "WD1", name)
    assert result.exit_code == 0, result.output
    assert (tmp_path / name).is_file() and [p.name for p in tmp_path.iterdir()] == [name]


def test_a_model_file_whose_name_is_a_formula_is_tilted_drawn_and_exported(wall, tmp_path):
    """Found by a hunt: matplotlib read "a$^$" in a figure's title as a formula (a
    ParseSyntaxException traceback in tilt, show, shake, montecarlo and report)."""
    model = saved(wall, tmp_path / "a$^$.toml")
    tilted = invoke("tilt", model, "--increment", "10", "--fixed", "--out", tmp_path / "run")
    assert tilted.exit_code == 0, tilted.output
    assert (tmp_path / "run" / "pushover.png").is_file() and (tmp_path / "run" / "mechanism.png").is_file()
    assert invoke("show", model, "-o", tmp_path / "wall.png").exit_code == 0


def test_a_model_file_whose_name_is_not_utf_8_is_drawn_exported_and_named(wall, tmp_path):
    """Found by a hunt: a file name whose bytes are not UTF-8 (a surrogate escape in Python) in a
    figure's title made FreeType raise a TypeError, in an OBJ or 3DEC file's comment a
    UnicodeEncodeError, and on a terminal whose error handler is strict any message naming it.
    It is drawn and written as "?", and given back to the terminal as it was."""
    import subprocess
    import sys

    from drydem.io.itasca import write_3dec
    from drydem.io.mesh import write_mesh
    from drydem.io.target import load_target
    from drydem.report.plots import layout_figure

    path = saved(wall, tmp_path / os.fsdecode(b"\xfe.toml"))
    model = load_target(str(path)).model
    layout_figure(model, tmp_path / "wall.png", title=f"{path.name}: as built")
    for write, name in ((write_mesh, "out.obj"), (write_3dec, "out.dat")):
        write(model, tmp_path / name)
        assert "?.toml" in (tmp_path / name).read_text(encoding="utf-8")  # UTF-8 throughout
    strict = dict(os.environ, PYTHONIOENCODING="utf-8:strict")
    checked = subprocess.run([sys.executable, "-c", "from drydem.cli import console; console()", "check", os.fsencode(path)],
                             capture_output=True, env=strict, timeout=300)
    assert checked.returncode == 0, checked.stderr[-800:]
    assert os.fsencode(path) in checked.stdout
