"""Hostile inputs and faults of model files and `drydem tilt`: each gets a non-zero exit and a
message naming the file, block or parameter and the rule (ranges say the allowed range), never
a traceback or a silent acceptance; and no result is lost. (Walls and layouts:
test_walls.py / test_layout.py; sweeps: test_hostile_sweep.py; geometry files and other
outputs: test_hostile_io.py.)"""

import json
import os
import re
import shutil
import zipfile
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

import drydem as dd
from drydem.analysis.tilt import TiltSettings, tilt_analysis
from drydem.cli import main
from drydem.engine.checkpoint import DIGEST, digest
from drydem.errors import DrydemError
from drydem.files import WRITING, lock_exclusively, partial_name, replaced_atomically, unlock
from drydem.io.results import FOLDER_LOCK, RUN_MARK

#: a brick on a base: the cheapest model that tilts (slides at atan 0.5 = 26.6 deg)
BRICK_ON_BASE = """\
[joint]
kn = 1e8
ks = 1e8
friction = 0.5
[solver]
ratio = 1e-5
[[block]]
name = "base"
fixed = true
box = { min = [-0.05, 0.0, -0.01], max = [0.1, 0.012, 0.0] }
[[block]]
name = "brick"
box = { min = [0.0, 0.0, 0.0], max = [0.025, 0.012, 0.0055] }
"""


@pytest.fixture(autouse=True)
def in_tmp_path(tmp_path, monkeypatch):
    """Default results folders (results/NAME-TIME) go under the test's folder."""
    monkeypatch.chdir(tmp_path)


def run(*args):
    """`drydem ARGS` in-process; the result, after checking it did not end in a traceback."""
    result = CliRunner().invoke(main, [str(a) for a in args])
    assert result.exception is None or isinstance(result.exception, SystemExit), result.exception
    return result


def model_file(tmp_path, text=BRICK_ON_BASE, name="brick.toml"):
    path = tmp_path / name
    path.write_text(text)
    return path


def refused(result, *fragments):
    """Non-zero exit, no traceback, and every fragment in the message."""
    assert result.exit_code not in (0, None), result.output
    assert "Traceback" not in result.output
    for fragment in fragments:
        assert fragment in result.output, result.output
    return True


@pytest.mark.parametrize(
    "change, fragments",
    [
        (("kn = 1e8", "kn = true"), ["[joint] kn = True: must be a number in [1e+04, 1e+15] Pa/m"]),
        (("friction = 0.5", "friction = false"), ["[joint] friction = False: must be a number in (0, 10]"]),
        (("ratio = 1e-5", "ratio = 1e300"), ["[solver] ratio = 1e+300: must be a number in [1e-12, 0.01]"]),
        (("ratio = 1e-5", "damping = 1.0"), ["[solver] damping = 1.0: must be a number in [0, 1)"]),
        (("ratio = 1e-5", "max_cycles = 2.5"), ["[solver] max_cycles = 2.5: must be an integer in [1, 1e+10]"]),
        (("[solver]", "[contacts]\ntolerance = 1.0\n[solver]"), ["[contacts] tolerance = 1.0 m: must be at most 0.5 of the thinnest movable block"]),
        (("[solver]", "[contacts]\npoints_per_length = 100\n[solver]"), ["[contacts] points_per_length = 100: must be an integer in [1, 32]"]),
        (("[joint]", "[material]\ndensity = true\n[joint]"), ["[material] density = True: must be a number in [1, 2.5e+04] kg/m3"]),
        (("min = [0.0, 0.0, 0.0]", "min = [true, 0.0, 0.0]"), ["[[block]] #1 ('brick') box min = [True, 0.0, 0.0]: must be [x, y, z]"]),
        (('name = "brick"', 'name = "brick"\ndensity = 1e9'), ["[[block]] #1 ('brick') density = 1000000000.0: must be a number in [1, 2.5e+04]"]),
    ],
)
def test_absurd_or_boolean_values_are_refused_with_the_allowed_range(tmp_path, change, fragments):
    text = BRICK_ON_BASE.replace(*change)
    assert text != BRICK_ON_BASE
    assert refused(run("check", model_file(tmp_path, text)), "brick.toml", *fragments)


def test_a_binary_file_is_not_taken_for_toml(tmp_path):
    path = tmp_path / "garbage.toml"
    path.write_bytes(np.random.default_rng(1).integers(0, 256, 400, dtype=np.uint8).tobytes())
    assert refused(run("check", path), "garbage.toml: not a text file")


def test_a_results_folder_holding_a_run_is_never_replaced_silently(tmp_path):
    path, out = model_file(tmp_path), tmp_path / "run"
    assert run("tilt", path, "--out", out, "--increment", "2").exit_code == 0
    first = (out / "summary.json").read_text()
    (out / "vtk").mkdir()
    (out / "collapse.mp4").write_bytes(b"old video")
    assert refused(run("tilt", path, "--out", out, "--increment", "2"), "already holds another run", "--overwrite",
                   "--resume to go on with it (a run of this command)")  # not "from its checkpoint": montecarlo resumes its samples
    assert (out / "summary.json").read_text() == first
    # --overwrite replaces it and leaves nothing stale of the old run beside the new results
    assert run("tilt", path, "--out", out, "--increment", "2", "--overwrite").exit_code == 0
    assert not (out / "vtk").exists() and not (out / "collapse.mp4").exists() and (out / "summary.json").is_file()
    assert refused(run("tilt", path, "--out", out, "--resume", "--overwrite"), "give one of them")


def test_overwrite_deletes_no_file_of_a_run_s_name_that_no_drydem_run_wrote(tmp_path):
    """Found by a hunt: --overwrite deleted a user's samples/ and vtk/ (a folder with no drydem
    run in it), the model file the run read from inside them, and a motion record named
    history.csv that shake then replaced by its output. Only a folder a drydem run marked
    (RUN_MARK), or a finished run's summary.json, has outputs to delete."""
    path, out = model_file(tmp_path), tmp_path / "project"
    (out / "samples").mkdir(parents=True)
    (out / "vtk").mkdir()
    (out / "samples" / "heights.csv").write_text("lab data")
    model = out / "samples" / "brick.toml"
    model.write_text(path.read_text())
    for options in ([], ["--overwrite"]):
        assert refused(run("tilt", model, "--out", out, "--increment", "2", *options),
                       "project: holds samples, vtk, named as a run's results but not written there by a drydem run")
    assert (out / "samples" / "heights.csv").read_text() == "lab data" and model.is_file() and not (out / RUN_MARK).exists()
    assert run("tilt", path, "--out", out / "run", "--increment", "2").exit_code == 0  # a run's own folder: marked
    assert (out / "run" / RUN_MARK).is_file()
    (out / "run" / "vtk").mkdir()
    assert run("tilt", path, "--out", out / "run", "--increment", "2", "--overwrite").exit_code == 0
    assert not (out / "run" / "vtk").exists() and (out / "run" / "summary.json").is_file()
    # a run refused once its folder was made, before any result (the shaking's start): no mark left
    assert refused(run("shake", path, "--pulse", "one-sine", "--amplitude", "1", "--frequency", "5", "--damping-ratio", "0.1",
                       "--duration", "1e-9", "--out", tmp_path / "instant"), "spans fewer than 20 timesteps")
    assert list((tmp_path / "instant").iterdir()) == []


def test_a_run_mark_that_is_a_link_is_replaced_not_written_through_and_a_folder_is_refused(tmp_path):
    """Found by a hunt: the mark (RUN_MARK) was written through a link, replacing its target's
    text, and a folder of its name ended in IsADirectoryError's traceback."""
    path, victim = model_file(tmp_path), tmp_path / "precious.txt"
    victim.write_text("precious")
    (tmp_path / "linked").mkdir()
    (tmp_path / "linked" / RUN_MARK).symlink_to(victim)
    assert run("tilt", path, "--out", tmp_path / "linked", "--increment", "2").exit_code == 0
    assert victim.read_text() == "precious" and not (tmp_path / "linked" / RUN_MARK).is_symlink()
    (tmp_path / "folder" / RUN_MARK).mkdir(parents=True)
    assert refused(run("tilt", path, "--out", tmp_path / "folder", "--increment", "2"), f"{RUN_MARK}: is a folder")


def test_overwrite_deletes_no_file_a_user_put_in_a_run_s_output_folder(tmp_path):
    """Found by a hunt: --overwrite deleted the whole vtk/ of a run's folder, with a file a user
    had put there after the run. It deletes the VTK series a run writes, and refuses, deleting
    nothing, while vtk/ holds anything else."""
    path, out = model_file(tmp_path), tmp_path / "run"
    assert run("tilt", path, "--out", out, "--increment", "2", "--vtk").exit_code == 0
    series = sorted(p.name for p in (out / "vtk").iterdir())
    assert "blocks.pvd" in series and "blocks_0000.vtu" in series
    (out / "vtk" / "mine.vtu").write_text("my own")
    (out / "vtk" / "notes").mkdir()
    (out / "vtk" / "notes" / "a.txt").write_text("mine")
    assert refused(run("tilt", path, "--out", out, "--increment", "2", "--overwrite"),
                   "--overwrite would delete vtk/mine.vtu, vtk/notes/a.txt, which no drydem run writes there")
    assert sorted(p.name for p in (out / "vtk").iterdir()) == sorted(series + ["mine.vtu", "notes"])
    shutil.rmtree(out / "vtk" / "notes"), (out / "vtk" / "mine.vtu").unlink()
    assert run("tilt", path, "--out", out, "--increment", "2", "--overwrite").exit_code == 0
    assert not (out / "vtk").exists() and (out / "summary.json").is_file()


@pytest.mark.parametrize("failure, code, said", [
    (OSError(28, "No space left on device", "mechanism.png"), 1, "mechanism.png: cannot write results (No space left on device)"),
    (KeyboardInterrupt(), 130, "interrupted (SIGINT) while writing the results"),
])
def test_a_tilt_stopped_while_writing_its_results_is_no_finished_run_and_resume_writes_them(tmp_path, monkeypatch, failure, code, said):
    """Found by a hunt: summary.json was written first, so a full disk or a Ctrl-C while the
    figures were drawn left a folder without mechanism.png that --resume called finished (and a
    traceback, or "Aborted!" and exit 1). summary.json is now written last."""
    from drydem.report import plots

    path, out = model_file(tmp_path), tmp_path / "run"
    draw = plots.mechanism_figure
    monkeypatch.setattr(plots, "mechanism_figure", lambda *args, **kwargs: (_ for _ in ()).throw(failure))
    result = run("tilt", path, "--out", out, "--increment", "2")
    assert result.exit_code == code and said in result.output and "holds no finished run (no summary.json)" in result.output
    assert not (out / "summary.json").exists() and not (out / "mechanism.png").exists()
    monkeypatch.setattr(plots, "mechanism_figure", draw)
    resumed = run("tilt", path, "--out", out, "--increment", "2", "--resume")
    assert resumed.exit_code == 0 and "nothing to resume" not in resumed.output, resumed.output
    assert (out / "summary.json").is_file() and (out / "mechanism.png").is_file()
    fresh = run("tilt", path, "--out", tmp_path / "fresh", "--increment", "2")
    assert json.loads((out / "summary.json").read_text())["collapse_angle_deg"] == json.loads(
        (tmp_path / "fresh" / "summary.json").read_text())["collapse_angle_deg"] and fresh.exit_code == 0


@pytest.mark.parametrize("command, figure", [
    (("limit",), "limit_mechanism_figure"),
    (("shake", "--pulse", "one-sine", "--amplitude", "1", "--frequency", "5", "--duration", "0.05"), "history_figure"),
])
def test_a_limit_or_shake_that_cannot_write_its_figure_says_so_without_a_traceback(tmp_path, monkeypatch, command, figure):
    """A full disk while drawing the figures: a traceback for limit (shake said it); now both
    name the file and say the folder holds no summary.json, which is written last."""
    from drydem.report import plots

    failure = OSError(28, "No space left on device", f"{figure}.png")
    monkeypatch.setattr(plots, figure, lambda *args, **kwargs: (_ for _ in ()).throw(failure))
    out = tmp_path / "run"
    assert refused(run(command[0], model_file(tmp_path), *command[1:], "--out", out),
                   f"{figure}.png: cannot write results (No space left on device)", "no summary.json")
    assert not (out / "summary.json").exists()


def test_a_tilt_whose_first_checkpoint_cannot_be_written_leaves_no_run_to_resume(tmp_path, monkeypatch):
    """Found by a hunt (an --out path too long for the checkpoint's lock): the run failed after
    its first pushover row, which then made the same command refuse, offering --resume with no
    checkpoint to go on from."""
    from drydem.analysis.tilt import checkpointing

    def full(*args, **kwargs):
        raise OSError(36, "File name too long", "checkpoint.npz")

    path, out = model_file(tmp_path), tmp_path / "run"
    monkeypatch.setattr(checkpointing, "save", full)
    assert refused(run("tilt", path, "--out", out, "--increment", "2"), "checkpoint.npz: cannot write results (File name too long)")
    assert list(out.iterdir()) == []
    monkeypatch.undo()
    assert run("tilt", path, "--out", out, "--increment", "2").exit_code == 0


def test_a_results_folder_another_run_is_writing_in_is_refused_and_left_alone(tmp_path):
    """Two runs given one --out, both started before either wrote, used to both pass the
    "already holds a run" check and replace each other's files (last one wins)."""
    path, out = model_file(tmp_path), tmp_path / "run"
    out.mkdir()
    (out / "checkpoint.npz").write_bytes(b"the other run's")
    (out / RUN_MARK).write_text("a drydem run's folder")
    lock = out / FOLDER_LOCK
    held = lock_exclusively(lock)  # another run (a lock is per open file, so one in this process is another's)
    try:
        for options in ([], ["--overwrite"], ["--resume"]):
            assert refused(run("tilt", path, "--out", out, "--increment", "2", *options), "run: another drydem run is writing there")
        assert refused(run("limit", path, "--out", out), "another drydem run is writing there")
        assert sorted(p.name for p in out.iterdir()) == [RUN_MARK, FOLDER_LOCK, "checkpoint.npz"]
        assert (out / "checkpoint.npz").read_bytes() == b"the other run's"
    finally:
        unlock(lock, held)
    # the holder gone, the folder is free; a run leaves no lock behind
    assert run("tilt", path, "--out", out, "--increment", "2", "--overwrite").exit_code == 0
    assert (out / "summary.json").is_file() and not lock.exists()


def test_no_run_writes_inside_a_folder_another_run_is_writing_in(tmp_path):
    """Found in the fifth session: a run held only its own folder, so `tilt --out mc/samples/x`
    during a Monte Carlo run in mc wrote among its samples; now a folder inside a held one (or a
    link to it) is refused as the held one is, and nothing is made there."""
    path, mc = model_file(tmp_path), tmp_path / "mc"
    (mc / "samples").mkdir(parents=True)
    (tmp_path / "link").symlink_to(mc / "samples")
    (tmp_path / "study.toml").write_text('[study]\nname = "s"\n[[grid]]\ntargets = ["brick.toml"]\n')
    held = lock_exclusively(mc / ".montecarlo.lock")
    try:
        for out in (mc / "samples" / "x", tmp_path / "link" / "y", mc / "samples"):
            assert refused(run("tilt", path, "--out", out, "--increment", "2"), f"another drydem run is writing there (in {mc.resolve()})")
        assert refused(run("limit", path, "--out", mc / "samples" / "x"), f"(in {mc.resolve()}); wait for it to end, or give another --out")
        assert refused(run("sweep", tmp_path / "study.toml", "--out", mc / "samples" / "s"), "give a sweep its own --out")
        assert sorted(p.name for p in (mc / "samples").iterdir()) == []
    finally:
        unlock(mc / ".montecarlo.lock", held)
    assert run("tilt", path, "--out", mc / "samples" / "x", "--increment", "2").exit_code == 0
    (tmp_path / "loop").symlink_to(tmp_path / "loop")  # the folders above a link that leads nowhere: no RuntimeError
    assert refused(run("tilt", path, "--out", tmp_path / "loop" / "x"), "loop/x: cannot write results there")


def test_a_file_written_where_no_file_can_be_made_is_named_before_its_lock(tmp_path):
    """Found by a hunt: ``drydem export WD3 /proc/model.dat`` named only /proc/.model.writing.dat."""
    target = tmp_path / "missing" / "model.dat"
    with pytest.raises(DrydemError, match=f"^{re.escape(str(target))}: cannot write: .*writing.dat: cannot make the lock file"):
        with replaced_atomically(target):
            pass


def test_a_lock_is_refused_by_name_where_its_file_cannot_be_made_and_taken_again_once_released(tmp_path):
    with pytest.raises(DrydemError, match="missing/x.lock: cannot make the lock file \\(No such file or directory\\)"):
        lock_exclusively(tmp_path / "missing" / "x.lock")
    first = lock_exclusively(tmp_path / "x.lock")
    assert lock_exclusively(tmp_path / "x.lock") is None and "held by" in (tmp_path / "x.lock").read_text()
    unlock(tmp_path / "x.lock", first)
    assert not (tmp_path / "x.lock").exists()
    again = lock_exclusively(tmp_path / "x.lock")
    assert again is not None
    unlock(tmp_path / "x.lock", again)


def test_a_folder_a_run_is_writing_in_is_neither_animated_nor_swept_into(tmp_path):
    """Found by a hunt: `animate` rendered a run still being written (which then replaced the
    video), and a sweep wrote its records beside a running tilt's files, or a finished one's."""
    path, out = model_file(tmp_path), tmp_path / "run"
    (tmp_path / "study.toml").write_text('[study]\nname = "s"\n[[grid]]\ntargets = ["brick.toml"]\n')
    (out / "vtk").mkdir(parents=True)
    (out / RUN_MARK).write_text("a drydem run's folder")
    held = lock_exclusively(out / FOLDER_LOCK)
    try:
        assert refused(run("animate", out), "run: another drydem run is writing there; animate it once the run has ended")
        assert refused(run("animate", out / "vtk"), f"vtk: another drydem run is writing there (in {out.resolve()}); animate it")
        assert refused(run("sweep", tmp_path / "study.toml", "--out", out), "run: another drydem run is writing there; give a sweep its own --out")
    finally:
        unlock(out / FOLDER_LOCK, held)
    montecarlo = lock_exclusively(out / ".montecarlo.lock")  # a Monte Carlo run started from Python holds only its own lock
    try:
        assert refused(run("tilt", path, "--out", out, "--increment", "2", "--overwrite"), "run: another drydem run is writing there")
    finally:
        unlock(out / ".montecarlo.lock", montecarlo)
    assert run("tilt", path, "--out", out, "--increment", "2", "--overwrite").exit_code == 0
    assert refused(run("sweep", tmp_path / "study.toml", "--out", out), "run: holds a drydem run (summary.json), not a sweep's records")
    assert refused(run("calibrate", out, "--designs", "WD3"), "not a sweep's records; give calibrate a sweep's folder, or a new one")
    assert not (out / "runs").exists()


def test_a_lock_left_by_a_killed_run_is_no_file_of_the_folder(tmp_path):
    """kill -9 leaves a Monte Carlo run's lock file, or the lock beside a file being written
    (the system drops the lock, not the file): the folder then counted as holding "other files
    (.montecarlo.lock)"."""
    path, out = model_file(tmp_path), tmp_path / "run"
    out.mkdir()
    stale = [".montecarlo.lock", partial_name(out / "checkpoint.npz", WRITING).name]
    for name in stale:
        (out / name).write_text("held by a run killed outright")
    assert run("tilt", path, "--out", out, "--increment", "2").exit_code == 0
    for finished in out.iterdir():  # the run's outputs gone, the user's notes and the old locks left
        if finished.name not in stale:
            finished.unlink()
    (out / "notes.txt").write_text("mine")
    assert refused(run("tilt", path, "--out", out, "--increment", "2"),
                   "run: already holds other files (notes.txt); pass --overwrite to write the run beside them (they are kept)")


def test_default_results_folders_are_never_shared(tmp_path, monkeypatch):
    """Two runs started in the same second both take results/NAME-TIME: the folder was looked
    for, then made (exist_ok), so a run that found it free could end up writing into the
    folder another run made in between. Each run now makes its own exclusively (-2, -3, ...)."""
    import drydem.cli.common as common

    class Frozen(common.datetime):
        @classmethod
        def now(cls, tz=None):
            return cls(2026, 1, 2, 3, 4, 5)

    original, raced = Path.mkdir, []

    def another_run_makes_it_first(self, *args, **kwargs):
        if self.name == "brick-20260102-030405" and not raced:
            raced.append(self)
            original(self, parents=True)
        return original(self, *args, **kwargs)

    monkeypatch.setattr(common, "datetime", Frozen)
    monkeypatch.setattr(Path, "mkdir", another_run_makes_it_first)
    assert run("tilt", model_file(tmp_path), "--increment", "2").exit_code == 0
    results = tmp_path / "results"
    assert sorted(p.name for p in results.iterdir()) == ["brick-20260102-030405", "brick-20260102-030405-2"]
    assert not any((results / "brick-20260102-030405").iterdir())  # the other run's folder is left to it
    assert (results / "brick-20260102-030405-2" / "summary.json").is_file()
    monkeypatch.setattr(Path, "mkdir", original)
    results.rename(tmp_path / "moved")
    results.symlink_to(tmp_path / "nowhere")  # a link to nothing: said, not looped on
    assert refused(run("tilt", model_file(tmp_path), "--increment", "2"), "results is a link to the missing")


def test_a_results_folder_that_cannot_be_one_is_refused(tmp_path):
    path, not_a_folder = model_file(tmp_path), tmp_path / "file"
    not_a_folder.write_text("x")
    assert refused(run("tilt", path, "--out", os.devnull), f"{os.devnull}: exists and is not a folder")
    assert refused(run("tilt", path, "--out", not_a_folder / "run"), "file/run: cannot write results there")


@pytest.mark.parametrize("content", [b"", b"PK\x03\x04 truncated", bytes(range(256)) * 4])
def test_an_unreadable_checkpoint_is_named(tmp_path, content):
    out = tmp_path / "run"
    out.mkdir()
    (out / "checkpoint.npz").write_bytes(content)
    # found by a hunt: the advice was "without --resume", which a run's folder refuses without --overwrite
    assert refused(run("tilt", model_file(tmp_path), "--out", out, "--resume"), "checkpoint.npz: not a readable drydem checkpoint",
                   "(on the command line: --overwrite instead of --resume)")


def _pair_to_a_missing_block(arrays):
    arrays["contacts.pairs"][0, 1] = 10**9


def _remembered_equilibrium_turned_about_x(arrays):
    quaternion = arrays["state.quaternion"].copy()
    quaternion[1] = [0.6, 0.8, 0.0, 0.0]
    arrays |= {"progress.previous_theta_deg": np.array([1.0]), "progress.previous_position": arrays["state.position"][None],
               "progress.previous_quaternion": quaternion[None]}


def _negative_step(arrays):
    arrays["progress.step_deg"] = np.asarray(-1.0)  # it tilted on to -27 deg and called that a collapse


def _unknown_lost_block(arrays):
    arrays |= {"progress.lost_blocks": np.array(["nosuch"]), "progress.lost_tilt_deg": np.array([1.0])}


def _records_out_of_order(arrays):
    # found by a hunt: reversed records resumed, and every drift limit was said reached at 12.30 deg
    arrays["progress.records"] = np.concatenate([arrays["progress.records"]] * 2)


def _records_cut(arrays):
    # found by a review: a ValueError's traceback (a reshape) where --vtk went on from their tilts
    arrays["progress.records"] = arrays["progress.records"].ravel()[:-1]


@pytest.mark.parametrize("spoil, message", [
    # block 10**9 in the checkpoint's contacts: the compiled cycle read out of bounds and the
    # interpreter died of a segmentation fault on --resume
    (_pair_to_a_missing_block, "snapshot contacts.pairs: block numbers 0 to 1000000000, not within 0 to 1"),
    (_negative_step, "its next step of -1.0 deg: must be in (0, 0.1] deg (the first step)"),
    (_unknown_lost_block, "its lost blocks ['nosuch']: not blocks of the model"),
    (_records_out_of_order, "its records: must be rows of finite numbers (tilt, ux, uz, drift, cycles), the tilts increasing"),
    (_records_cut, "numbers): must be rows of five numbers (tilt, ux, uz, drift, cycles)"),
    # a remembered equilibrium (the predictor's) turned about x: the in-plane model's planar
    # cycle reads a quaternion as a turn about y, and would have gone on from a wrong state
    (_remembered_equilibrium_turned_about_x,
     "previous equilibrium state.quaternion[1] = [0.6, 0.8, 0.0, 0.0]: the blocks of an in-plane model turn about y only"),
])
def test_a_checkpoint_that_does_not_fit_the_model_is_named_not_a_crash(tmp_path, spoil, message):
    out, path = tmp_path / "run", model_file(tmp_path, BRICK_ON_BASE + "[supports]\nfix_y = true\n")  # in-plane: the planar cycle
    assert run("tilt", path, "--out", out).exit_code == 0
    (out / "summary.json").unlink()  # an unfinished run, as after a kill
    with np.load(out / "checkpoint.npz") as data:
        arrays = {key: data[key] for key in data.files}
    spoil(arrays)
    np.savez(out / "checkpoint.npz", **arrays)  # its digest no longer fits: refused as changed
    assert refused(run("tilt", path, "--out", out, "--resume"), "checkpoint.npz: not a readable drydem checkpoint (ValueError: its "
                   "arrays have changed since it was written (SHA-256 ")
    del arrays[DIGEST]  # as a faulty writer would, its digest made again: its structure is checked
    np.savez(out / "checkpoint.npz", **arrays, **{DIGEST: np.asarray(digest(arrays))})
    assert refused(run("tilt", path, "--out", out, "--resume"), "checkpoint.npz: not a readable drydem checkpoint (", message)


def test_a_checkpoint_without_its_digest_or_claiming_terabytes_is_named_not_a_traceback(tmp_path):
    """A file of an earlier drydem (no digest) is not trusted; an array header claiming 2 TiB
    was a MemoryError traceback."""
    out, path = tmp_path / "run", model_file(tmp_path)
    assert run("tilt", path, "--out", out).exit_code == 0
    (out / "summary.json").unlink()
    with np.load(out / "checkpoint.npz") as data:
        arrays = {key: data[key] for key in data.files if key != DIGEST}
    np.savez(out / "checkpoint.npz", **arrays)
    assert refused(run("tilt", path, "--out", out, "--resume"), "no SHA-256 digest of its arrays: written by an earlier drydem")
    with zipfile.ZipFile(out / "checkpoint.npz") as archive:
        members = {name: archive.read(name) for name in archive.namelist()}
    member = members["state.position.npy"]  # magic, version, header length (2 bytes), header padded with spaces, data
    length = int.from_bytes(member[8:10], "little")
    header = member[10:10 + length].replace(b"(2, 3)", b"(100000000000, 3)")
    header = header.rstrip(b" \n")[:length - 1].ljust(length - 1) + b"\n"
    members["state.position.npy"] = member[:10] + header + member[10 + length:]
    with zipfile.ZipFile(out / "checkpoint.npz", "w") as archive:
        for name, content in members.items():
            archive.writestr(name, content)
    assert refused(run("tilt", path, "--out", out, "--resume"), "checkpoint.npz: not a readable drydem checkpoint (")


def test_a_checkpoint_resumes_whichever_path_names_the_same_model_file(tmp_path, monkeypatch):
    """brick.toml from its folder and the absolute path are one model: resumed, not 'another model'."""
    from drydem.io.target import load_target

    monkeypatch.chdir(tmp_path)
    model_file(tmp_path)
    checkpoint = tmp_path / "checkpoint.npz"
    tilt_analysis(load_target("brick.toml").model, TiltSettings(increment_deg=5.0), checkpoint=checkpoint)
    result = tilt_analysis(load_target(str(tmp_path / "brick.toml")).model, TiltSettings(increment_deg=5.0), checkpoint=checkpoint,
                           resume=True)
    assert result.collapse_angle_deg is not None


def test_resuming_with_other_settings_names_each_of_them(tmp_path):
    from drydem.io.target import load_target

    model = load_target(str(model_file(tmp_path))).model
    checkpoint = tmp_path / "checkpoint.npz"
    tilt_analysis(model, TiltSettings(increment_deg=5.0), checkpoint=checkpoint)
    stiffer = model.replace(joint=dd.JointMaterial(kn=2e8, ks=1e8, friction=0.5))
    with pytest.raises(dd.ModelError, match=r"\[joint\] kn: 100000000.0 in the checkpoint, 200000000.0 now; "
                                            r"tilt setting increment_deg: 5.0 in the checkpoint, 2.0 now"):
        tilt_analysis(stiffer, TiltSettings(increment_deg=2.0), checkpoint=checkpoint, resume=True)


def test_tilt_options_out_of_range_are_named(tmp_path):
    path = model_file(tmp_path)
    assert refused(run("tilt", path, "--monitor", "base"), "monitored block 'base' is fixed")
    assert refused(run("tilt", path, "--monitor", "nothing"), "no block named 'nothing'")
    assert refused(run("tilt", path, "--increment", "10", "--max-angle", "5"), "increment_deg = 10.0 exceeds max_angle_deg = 5.0")
    assert not (tmp_path / "results").exists()


@pytest.mark.parametrize("option, value, message", [
    ("--increment", "0", "0.0: must be a number in [0.001, 90) deg (tilt setting increment_deg)"),
    ("--increment", "1e-12", "1e-12: must be a number in [0.001, 90) deg (tilt setting increment_deg)"),
    ("--max-angle", "90", "90.0: must be a number in (0, 90) deg (tilt setting max_angle_deg)"),
    ("--stop-displacement", "-1", "-1.0: must be a number in [1e-09, 100] m (tilt setting stop_displacement_m)"),
    ("--stop-displacement", "1e-300", "1e-300: must be a number in [1e-09, 100] m (tilt setting stop_displacement_m)"),
    ("--kn", "0", "0.0: must be a number in [1e+04, 1e+15] Pa/m ([joint] kn)"),
    ("--ks", "nan", "nan: must be a number in [1e+04, 1e+15] Pa/m ([joint] ks)"),
    ("--friction", "inf", "inf: must be a number in (0, 10] ([joint] friction)"),
    ("--points", "33", "33: must be an integer in [1, 32] ([contacts] points_per_length)"),
    ("--density", "0.5", "0.5: must be a number in [1, 2.5e+04] kg/m3 (the density of every block)"),
    ("--kn-exponent", "4", "4.0: must be a number in [0, 3] ([joint] kn_exponent)"),
    ("--joint-kn-min", "1", "1.0: must be a number in [1e+04, 1e+15] Pa/m ([joint] kn_min)"),
])
def test_a_tilt_option_out_of_its_range_is_refused_as_itself_with_what_it_sets(tmp_path, option, value, message):
    """The message names the option the user typed (not only the model key it sets), the value
    and the rule: a usage error (exit 2), before the target is read and the folder made."""
    result = run("tilt", model_file(tmp_path), option, value, "--out", tmp_path / "never")
    assert result.exit_code == 2 and refused(result, f"Invalid value for '{option}': {message}")
    assert not (tmp_path / "never").exists()


@pytest.mark.parametrize("command, option, value, kind", [
    ("tilt", "--kn", "3_0e7", "float"),  # Python's float() reads 3_0e7 as 3e8
    ("tilt", "--increment", "0x10", "float"),
    ("tilt", "--threads", "1_0", "integer"),
    ("tilt", "--points", "\u0664", "integer"),  # an Arabic-Indic four, which int() takes
    ("shake", "--amplitude", "0_5", "float"),  # found by a hunt: ran a pulse of 5 m/s2
    ("montecarlo", "--samples", "1_0", "integer"),
    ("animate", "--fps", "1_0", "float"),
])
def test_a_number_option_takes_plain_digits_only(tmp_path, command, option, value, kind):
    result = run(command, model_file(tmp_path), option, value, "--out", tmp_path / "never")
    assert result.exit_code == 2 and refused(result, f"Invalid value for '{option}': {value!r} is not a valid {kind} (ASCII digits")
    assert not (tmp_path / "never").exists()


def test_a_limit_analysis_stops_at_once_when_interrupted_while_the_solver_runs(tmp_path, monkeypatch):
    """Found by a hunt: HiGHS, in compiled code, kept Ctrl-C waiting until it had solved
    (minutes on large models), and SIGTERM ended the command without a word. The solver now
    runs in a thread of its own; here one that would take a minute, interrupted by SIGTERM
    after 0.5 s, ends the command at once (exit 143), and its folder is left empty."""
    import signal
    import threading
    import time

    from drydem.analysis import limit as limit_module

    def slow(model, settings, on_progress=None):
        on_progress("solving a problem that takes a minute")
        # sent from here, once the command's handler is in place (SIGTERM's default would end pytest)
        threading.Timer(0.5, os.kill, (os.getpid(), signal.SIGTERM)).start()
        time.sleep(60.0)

    monkeypatch.setattr(limit_module, "limit_analysis", slow)
    out = tmp_path / "run"
    start = time.perf_counter()
    result = run("limit", model_file(tmp_path), "--out", out)
    assert time.perf_counter() - start < 10.0
    assert result.exit_code == 143 and "interrupted (SIGTERM) while solving a problem that takes a minute; a limit analysis " \
        "keeps no partial result: nothing is written" in result.output, result.output
    assert list(out.iterdir()) == []


def test_limit_names_its_friction_option_out_of_range(tmp_path):
    result = run("limit", model_file(tmp_path), "--friction", "0", "--out", tmp_path / "never")
    assert result.exit_code == 2 and refused(result, "Invalid value for '--friction': 0.0: must be a number in (0, 10] ([joint] friction)")


def test_no_equilibrium_under_gravity_exits_non_zero_without_a_verdict(tmp_path):
    text = BRICK_ON_BASE.replace("ratio = 1e-5", "damping = 0.0\nmax_cycles = 3000")
    result = run("tilt", model_file(tmp_path, text), "--out", tmp_path / "run")
    assert refused(result, "damping = 0", "no equilibrium under gravity within [solver] max_cycles = 3000: no verdict")
    assert "cannot stand" not in result.output and (tmp_path / "run" / "summary.json").is_file()


def test_a_tilt_whose_step_diverges_exits_non_zero_without_a_verdict_and_keeps_its_results(tmp_path, monkeypatch):
    from test_tilt import diverging_past

    diverging_past(monkeypatch, 2.5)
    result = run("tilt", model_file(tmp_path), "--increment", "1", "--out", tmp_path / "run")
    assert refused(result, "last equilibrium 2.00 deg; the integration of the next step diverged", "no collapse angle",
                   "reduce [solver] timestep_safety = 0.8")
    summary = json.loads((tmp_path / "run" / "summary.json").read_text())
    assert summary["ended_by"] == "integration diverged" and summary["collapse_angle_deg"] is None
    assert (tmp_path / "run" / "pushover.csv").read_text().count("\n") == 4  # the header and 0, 1, 2 deg


def test_check_names_a_block_that_touches_nothing(tmp_path):
    text = BRICK_ON_BASE + '[[block]]\nname = "floater"\nbox = { min = [0.0, 0.0, 0.5], max = [0.025, 0.012, 0.5055] }\n'
    result = run("check", model_file(tmp_path, text))
    assert result.exit_code == 0 and "unsupported     1 movable blocks touch nothing and will fall under gravity: 'floater'" in result.output


def test_a_limit_analysis_never_replaces_an_earlier_one_silently(tmp_path):
    path, out = model_file(tmp_path), tmp_path / "limit"
    assert run("limit", path, "--out", out).exit_code == 0
    first = (out / "summary.json").read_text()
    result = run("limit", path, "--out", out, "--friction", "0.8")
    assert refused(result, "already holds another run (mechanism.png, summary.json); pass --overwrite to replace it, or another --out")
    assert (out / "summary.json").read_text() == first
    assert run("limit", path, "--out", out, "--friction", "0.8", "--overwrite").exit_code == 0
    assert (out / "summary.json").read_text() != first


@pytest.mark.parametrize("command", [["sweep", "savalle2022", "--out"], ["calibrate"]])
def test_a_study_folder_that_cannot_be_one_is_refused(tmp_path, command):
    not_a_folder = tmp_path / "file"
    not_a_folder.write_text("x")
    assert refused(run(*command, os.devnull), f"{os.devnull}: exists and is not a folder")
    assert refused(run(*command, not_a_folder / "results"), "file/results: cannot write results there")


@pytest.mark.parametrize("make, message", [
    (lambda: dd.JointMaterial(kn=True), "[joint] kn = True: must be a number in [1e+04, 1e+15] Pa/m"),
    (lambda: dd.JointMaterial(friction=1), None),  # an int is a number
    (lambda: dd.ContactSettings(points_per_length=True), "[contacts] points_per_length = True: must be an integer in [1, 32]"),
    (lambda: dd.ContactSettings(tolerance=False), "[contacts] tolerance = False: must be a number in [1e-09, inf) m"),
    (lambda: dd.ContactSettings(tolerance=1e-300), "[contacts] tolerance = 1e-300: must be a number in [1e-09, inf) m"),
    (lambda: dd.SolverSettings(max_cycles=True), "[solver] max_cycles = True: must be an integer in [1, 1e+10]"),
    (lambda: dd.SolverSettings(mass_scaling=1), "[solver] mass_scaling = 1: must be true or false"),
    (lambda: dd.SolverSettings(criterion="speed"), "[solver] criterion = 'speed': must be one of ('ratio', 'velocity')"),
    (lambda: dd.Supports(fix_y="yes"), "[supports] fix_y = 'yes': must be true or false"),
    (lambda: TiltSettings(increment_deg=True), "tilt setting increment_deg = True: must be a number in [0.001, 90) deg"),
])
def test_python_settings_refuse_booleans_as_numbers_with_one_error_type(make, message):
    if message is None:
        make()
        return
    with pytest.raises(dd.ModelError) as refused:
        make()
    assert str(refused.value) == message


@pytest.mark.parametrize("field, value, rule", [
    ("lost_drop_heights", 1e300, "must be a number in (0, 1000]"),
    ("chunk_cycles", 10**300, "must be an integer in [1, 1e+10]"),
    ("trial_growth", 1e300, "must be a number in (1, 1e+06]"),
    ("trial_floor_m", 1e300, "must be a number in (0, 100] m"),
    ("predictor_growth", 1e300, "must be a number in [1, 1e+06]"),
    ("predictor_cap_closures", float("inf"), "must be a number in (0, 1e+06]"),
])
def test_a_tilt_setting_that_would_switch_its_rule_off_is_refused(field, value, rule):
    """A huge factor or count is no setting of the rule it names but its silent removal (a trial
    never abandoned, a falling block never taken out)."""
    with pytest.raises(dd.ModelError, match=re.escape(rule)) as info:
        TiltSettings(**{field: value})
    assert str(info.value).startswith(f"tilt setting {field} = ")


def test_a_shake_setting_keeping_falling_blocks_forever_is_refused():
    from drydem.analysis.shake import ShakeSettings, pulse

    motion = pulse("one-sine", amplitude_m_s2=1.0, frequency_hz=2.0)
    with pytest.raises(dd.ModelError, match=re.escape("shake setting lost_drop_heights = 1e+300: must be a number in (0, 1000]")):
        ShakeSettings(motion=motion, lost_drop_heights=1e300)


def test_every_bad_field_of_a_parameter_table_is_named_at_once():
    with pytest.raises(dd.ModelError) as refused:
        dd.JointMaterial(kn=0.0, friction=-1.0)
    assert str(refused.value) == ("[joint] kn = 0.0: must be a number in [1e+04, 1e+15] Pa/m; "
                                  "[joint] friction = -1.0: must be a number in (0, 10]")


def test_a_400_digit_integer_or_a_long_text_is_refused_and_shown_elided(tmp_path):
    """JSON and TOML hold integers beyond a float's range (1.8e308): no number here, and no
    OverflowError; a message shows such a value, or a long text, cut in the middle with its length."""
    with pytest.raises(dd.ModelError) as info:
        dd.JointMaterial(kn=10**400, friction="x" * 10_000)
    assert str(info.value) == ("[joint] kn = 100000000000000000...000000000000000000 (401 characters): must be a number in "
                               "[1e+04, 1e+15] Pa/m; [joint] friction = 'xxxxxxxxxxxxxxxxx...xxxxxxxxxxxxxxxxx' (10002 characters): "
                               "must be a number in (0, 10]")
    path = model_file(tmp_path)
    path.write_text(path.read_text().replace("kn = 1e8", "kn = " + "9" * 400))
    result = CliRunner().invoke(main, ["check", str(path)])
    assert refused(result, "[joint] kn = 999999999999999999...999999999999999999 (400 characters): must be a number")


@pytest.mark.parametrize("every", [0, 1.5, True])
def test_a_vtk_series_keeps_every_positive_integer_th_state_only(tmp_path, every):
    from drydem.io.model_file import load_model
    from drydem.io.vtk import VtkSeries

    model = load_model(model_file(tmp_path))
    with pytest.raises(dd.ModelError, match=rf"VtkSeries every = {every!r}: must be an integer in \[1, inf\)"):
        VtkSeries(tmp_path / "vtk", model, every=every)


@pytest.mark.parametrize("command", ["tilt", "montecarlo"])
def test_a_stop_displacement_below_the_dls_drift_of_the_wall_is_refused(tmp_path, command):
    """Found by a hunt: a wall of 20 m bricks (40 m high) "collapsed" at 17 deg having moved the
    default 0.10 m, a drift of 0.25 %, and stood to 26 deg given 5 m. A stop displacement below
    1 % of the height (the DLS drift) would end the run before the drift limits it reports."""
    wall = tmp_path / "big.toml"
    wall.write_text('[brick]\nlength_m = 20\nheight_m = 20\nwidth_m = 20\n[supports]\nfix_y = true\n[layout]\ncourses = """\nb1Bb\n2B\n"""\n')
    extra = ["--height-sd", "1"] if command == "montecarlo" else []
    assert refused(run(command, wall, *extra, "--out", tmp_path / "run"),
                   "stop_displacement_m = 0.1 m (--stop-displacement) is a drift of 0.25% of the wall's 40 m height, below the 1% "
                   "of the damage limitation state: the analysis would end there and call it a collapse; give at least 0.4 m")
    assert not (tmp_path / "run").exists()


FAR_STIFF_BRICK = """[material]
density = 2000.0
[joint]
kn = 1e15
ks = 1e15
friction = 0.8
[solver]
max_cycles = 20000
[supports]
fix_y = true
[[block]]
name = "base"
fixed = true
box = { min = [-0.05, -0.006, 9.99], max = [0.05, 0.006, 10.0] }
[[block]]
name = "brick"
box = { min = [-0.0125, -0.006, 10.0], max = [0.0125, 0.006, 10.0055] }
"""


def test_a_model_round_off_keeps_from_equilibrium_is_not_told_to_raise_max_cycles(tmp_path):
    """Found by a hunt: a brick 10 m up on kn = 1e15 Pa/m keeps an unbalanced-force ratio of
    about 1 % (positions known to 1.8e-15 m, times kn A = 3e11 N/m, over its 0.032 N weight)
    however long it cycles, and was told to raise max_cycles; WD3's floor is 1e-8."""
    from drydem.analysis.support import roundoff_ratio
    from drydem.io.target import load_target

    path = model_file(tmp_path, FAR_STIFF_BRICK, "far.toml")
    assert 0.005 < roundoff_ratio(load_target(str(path)).model) < 0.05
    assert roundoff_ratio(load_target("WD3").model.overridden(kn=1e10, ks=1e10)) < 1e-7
    result = run("tilt", path, "--out", tmp_path / "run")
    assert result.exit_code == 1 and "no equilibrium under gravity within [solver] max_cycles = 20000" in result.output
    assert "round-off keeps the unbalanced-force ratio at about 0.016" in result.output and "raise max_cycles" not in result.output
