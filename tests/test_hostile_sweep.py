"""Studies, sweeps, reports and calibration off the happy path (issue 14): every bad input and
fault gets a clear answer (the file or option and the rule, a non-zero exit, no traceback), and
nothing is lost: corrupt records are run again, a killed sweep leaves no worker behind and goes
on with what is missing, two sweeps on one folder compute each run once."""

from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import sys
import textwrap
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import asdict
from pathlib import Path

import pytest
from click.testing import CliRunner

from drydem.parametric import study as study_module
from drydem.parametric import sweep as sweep_module
from drydem.parametric.calibrate import StiffnessSearch, calibrate_stiffness
from drydem.parametric.limits import MAX_RUNS
from drydem.parametric.records import load_records, read_record, record_path, write_record
from drydem.parametric.study import RunSpec, load_study
from drydem.parametric.sweep import SweepError, claim, lock_path, pending, release, sweep
from drydem.cli import main
from processes import DRYDEM
from drydem.errors import ModelError
from test_sweep import STUDY, WALL_FILE, WALLS

LINUX = pytest.mark.skipif(not Path("/proc/self/stat").is_file(), reason="finds processes in /proc")
#: a wall whose tilting runs take about a second each: long enough to be killed in flight
SLOW_WALL = "BBBB\nbBBBb\n" * 6
SLOW_STUDY = """
[study]
name = "slow"
[[grid]]
targets = ["wall.toml"]
kn = [1e7, 1.5e7, 2e7, 3e7, 5e7, 7e7, 1e8, 1.5e8, 2e8, 3e8, 5e8, 1e9]
protocol = ["fixed"]
increment_deg = 2.0
"""


@pytest.fixture
def folder(tmp_path):
    """The small study of test_sweep (8 runs of a fraction of a second) and its walls."""
    for name, courses in WALLS.items():
        (tmp_path / name).write_text(WALL_FILE.format(courses=courses))
    (tmp_path / "wall.toml").write_text(WALL_FILE.format(courses=SLOW_WALL))
    (tmp_path / "small.toml").write_text(STUDY)
    (tmp_path / "slow.toml").write_text(SLOW_STUDY)
    return tmp_path


def invoke(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


def refused(result, *fragments):
    """The command stopped with a message holding every fragment, and no traceback."""
    assert result.exit_code != 0, result.output
    assert isinstance(result.exception, SystemExit), result.exception
    assert "Traceback" not in result.output
    for fragment in fragments:
        assert fragment in result.output, (fragment, result.output)


# --- studies: every run checked before the first starts --------------------------------------


BAD_STUDY = """
[study]
name = "bad"
[defaults]
increment_deg = 95.0
[[grid]]
name = "stiffness"
targets = ["pier.toml", "nowhere.toml"]
kn = [true, -1.0, 1e7, "1e8"]
friction = [0]
points = [0, 2.5]
protocol = ["fixed"]
[[grid]]
name = "limit"
analysis = ["limit"]
targets = ["pier.toml"]
[[grid]]
name = "empty"
targets = ["pier.toml"]
kn = []
[[grid]]
name = "numbers"
targets = [1]
"""


def test_a_study_with_bad_values_names_every_one_and_runs_nothing(folder):
    study = folder / "bad.toml"
    study.write_text(BAD_STUDY)
    result = invoke("sweep", study, "--out", folder / "results")
    grid = f"{study}: [[grid]] #0 ('stiffness')"
    refused(result, "problems, nothing run",
            f"{grid}: kn = True: must be a number in",  # a boolean is not 1.0
            f"{grid}: kn = -1.0: must be a number in [1e+04, 1e+15] Pa/m",
            f"{grid}: kn = '1e8': must be a number",
            f"{grid}: friction = 0: must be a number in (0, 10]",
            f"{grid}: points = 0: must be an integer in [1, 32]",
            f"{grid}: points = 2.5: must be an integer",
            f"{grid}: tilt setting increment_deg = 95.0: must be a number in [0.001, 90) deg",
            f"{grid}: targets: {folder / 'nowhere.toml'}: no such file, and not a built-in wall",
            f"{study}: [[grid]] #1 ('limit'): analysis = ['limit']: must be one of ['tilt', 'limit', 'shake']",
            f"{study}: [[grid]] #2 ('empty'): kn = []: needs at least one value",
            f"{study}: [[grid]] #3 ('numbers'): targets [1]: each must be a built-in wall's name or a file")
    assert f"{study}: [defaults] increment_deg = 95.0: must be a number in [0.001, 90) deg" in result.output
    assert result.output.count("kn = True") == 1  # its ks (ks = kn) is not named again
    assert "[joint]" not in result.output  # the grid's keys, as the study writes them
    assert not (folder / "results").exists()


def test_defaults_no_grid_takes_are_checked_too(folder):
    """Found by a hunt: [defaults] values no grid took (shake settings in a study of tilting
    grids) were accepted without a word, whatever they were."""
    study = folder / "defaults.toml"
    study.write_text(BAD_STUDY.split("[[grid]]")[0].replace("increment_deg = 95.0", 'restitution = "nonsense"\nduration_s = -5\n'
                                                                                   "contact_damping_ratio = true\npoints = [4, 0]")
                     + '[[grid]]\nname = "limit"\nanalysis = "limit"\ntargets = ["pier.toml"]\n')
    refused(invoke("sweep", study, "--out", folder / "results"), "problems, nothing run",
            f"{study}: [defaults] restitution = 'nonsense': must be a number in (0, 1]",
            f"{study}: [defaults] duration_s = -5: must be a number in (0, 1e+06] s",
            f"{study}: [defaults] contact_damping_ratio = True: must be a number",
            f"{study}: [defaults] points = 0: must be an integer in [1, 32]")
    assert not (folder / "results").exists()


@pytest.mark.parametrize("change, message", [
    (('increment_deg = 5.0', 'increment_deg = 0'), "tilt setting increment_deg = 0: must be a number in [0.001, 90) deg"),
    (('increment_deg = 5.0', 'increment_deg = true'), "tilt setting increment_deg = True: must be a number"),
    (('kn = [1e7, 1e8, 1e9]', 'kn = [1e7, 1e8, 1e9]\nks = []'), "ks = []: needs at least one value"),
    (('kn = [1e7, 1e8, 1e9]', 'kn = [1e7, 1e8, 1e9]\npoints = [1, true]'), "points = True: must be an integer"),
    (('[[grid]]\nname = "limit"', '[[grid]]\nname = "limit"\nfriction = -0.5'), "friction = -0.5: must be a number in (0, 10]"),
])
def test_a_bad_value_anywhere_is_an_error_naming_the_file_and_rule(folder, change, message):
    study = folder / "small.toml"
    study.write_text(STUDY.replace(*change))
    with pytest.raises(ModelError) as caught:
        load_study(study)
    assert message in str(caught.value) and str(caught.value).startswith(str(study))


def test_a_study_path_that_is_a_folder_is_said_to_be_one(folder):
    (folder / "g2.toml").mkdir()  # it was "no such study file", though the path exists
    refused(invoke("sweep", folder / "g2.toml"), f"{folder / 'g2.toml'}: is a folder, not a study file")


@pytest.mark.parametrize("name", ['"../../x"', '"{folder}/elsewhere"', '""', '" "', '"."', '".."', '"a\\\\b"', "5"],
                         ids=["parent path", "absolute path", "empty", "blank", "dot", "dot dot", "backslash", "integer"])
def test_a_study_name_that_is_not_a_plain_file_name_is_refused_before_any_folder_is_made(folder, name, monkeypatch):
    study = folder / "small.toml"
    study.write_text(STUDY.replace('name = "small"', f"name = {name.format(folder=folder)}"))
    (folder / "a" / "b").mkdir(parents=True)
    monkeypatch.chdir(folder / "a" / "b")  # results/../../x would be folder/a/x
    refused(invoke("sweep", study, "--workers", 1), f"{study}: [study] name = ", "(it names a results folder)")
    assert sorted(str(p.relative_to(folder)) for p in folder.rglob("*") if p.is_dir()) == ["a", "a/b"]


def test_a_study_description_that_is_not_text_is_refused(folder):
    study = folder / "small.toml"
    study.write_text(STUDY.replace('name = "small"', 'name = "small"\ndescription = 3'))
    with pytest.raises(ModelError, match=r"\[study\] description = 3: must be a string"):
        load_study(study)


def test_a_grid_of_more_runs_than_a_study_makes_is_refused_at_once_naming_its_sizes(folder):
    ks = ", ".join(f"{1e7 * (1 + k / 100):g}" for k in range(400))
    friction = ", ".join(f"{0.3 + k / 1000:g}" for k in range(400))
    study = folder / "small.toml"
    study.write_text(STUDY.replace("kn = [1e7, 1e8, 1e9]", f"kn = [1e7, 1e8, 1e9]\nks = [{ks}]\nfriction = [{friction}]"))
    start = time.perf_counter()
    with pytest.raises(ModelError) as caught:
        load_study(study)
    assert time.perf_counter() - start < 5.0  # refused before its 960000 runs are laid out and checked
    assert (f"{study}: [[grid]] #0 ('stiffness'): 960000 runs (1 protocol x 2 targets x 3 kn x 400 ks x 400 friction x 1 points): "
            f"a study makes at most {MAX_RUNS} runs") in str(caught.value)


def test_grids_that_together_make_more_runs_than_a_study_makes_are_refused_naming_each_count(folder, monkeypatch):
    monkeypatch.setattr(study_module, "MAX_RUNS", 7)  # the small study makes 8 runs: 6 tilt, 2 limit
    with pytest.raises(ModelError) as caught:
        load_study(folder / "small.toml")
    assert (f"{folder / 'small.toml'}: 8 runs (grids #0 'stiffness' 6, #1 'limit' 2; a run several grids share counted once): "
            "a study makes at most 7 runs") in str(caught.value)
    monkeypatch.setattr(study_module, "MAX_RUNS", 8)
    assert len(load_study(folder / "small.toml").runs) == 8


def test_a_grid_that_is_not_a_table_is_named(folder):
    study = folder / "small.toml"
    study.write_text('grid = [1]\n[study]\nname = "numbers"\n')
    with pytest.raises(ModelError, match=r"\[\[grid\]\] #0 \('\?'\): the grid must be a table"):
        load_study(study)


# --- records: corrupt ones are named, run again, left out of reports -------------------------


def ok_record(spec: RunSpec, angle: float = 20.0) -> dict:
    """A record as run_one writes it, of a made-up tilting run."""
    summary = {"collapse_angle_deg": angle, "drift_limit_angles_deg": {"0.01": angle / 2}, "wall_height_m": 0.1}
    return {"id": spec.id, "spec": asdict(spec), "status": "ok", "error": None, "summary": summary,
            "pushover": [[0.0, 0.0, 0.0, 0.0, 10]], "runtime_s": 0.0}


SPEC = RunSpec(analysis="tilt", target="WD1", protocol="fixed", kn=3e7, ks=3e7)
OTHER = RunSpec(analysis="tilt", target="WD1", protocol="fixed", kn=1e8, ks=1e8)
CORRUPTIONS = {
    "empty": (lambda text: "", "not a JSON record"),
    "truncated": (lambda text: text[: len(text) // 2], "not a JSON record, empty or cut short?"),
    "not utf-8": (lambda text: "\udcff", "not a JSON record"),
    "a list": (lambda text: "[1, 2]", "a record is a JSON object, not list"),
    "no status": (lambda text: json.dumps({k: v for k, v in json.loads(text).items() if k != "status"}), "status = None: must be one of"),
    "no summary": (lambda text: json.dumps({k: v for k, v in json.loads(text).items() if k != "summary"}), "a 'ok' record without ['summary']"),
    "summary lacks keys": (lambda text: json.dumps(json.loads(text) | {"summary": {}}), "summary must hold"),
    "bad curve": (lambda text: json.dumps(json.loads(text) | {"pushover": [[1, 2]]}), "pushover must be a list of rows of 5 numbers"),
    "a NaN in the curve": (lambda text: json.dumps(json.loads(text) | {"pushover": [[1, float("nan"), 0, 0, 10]]}),
                           "pushover row 0 (1, nan, 0, 0, 10): the numbers must be finite"),
    "another run's": (lambda text: json.dumps(json.loads(text) | {"spec": asdict(OTHER)}), f"are those of run '{OTHER.id}'"),
    "bad spec": (lambda text: json.dumps(json.loads(text) | {"spec": {"kn": 1}}), "spec is not the parameters of a run"),
}


@pytest.mark.parametrize("corruption", CORRUPTIONS)
def test_a_corrupt_record_is_named_and_to_be_run_again(tmp_path, corruption):
    corrupt, message = CORRUPTIONS[corruption]
    path = write_record(tmp_path, ok_record(SPEC))
    path.write_text(corrupt(path.read_text()), errors="surrogateescape")
    with pytest.raises(sweep_module.RecordError, match=re.escape(message)) as caught:
        read_record(path)
    assert str(caught.value).startswith(str(path))
    todo = pending([SPEC], tmp_path)
    assert todo.todo == [SPEC] and todo.recorded == 0 and [str(e) for e in todo.corrupt] == [str(caught.value)]
    records = load_records(tmp_path)
    assert records.valid == [] and [str(e) for e in records.corrupt] == [str(caught.value)]


def test_a_records_folder_or_record_path_taken_by_something_else_is_refused_before_any_run(folder):
    """Found by a hunt: OUT/runs as a file was a NotADirectoryError traceback, and a folder where
    a run's record goes was read as a corrupt record, the run computed, then an IsADirectoryError
    traceback when its record could not replace the folder (the run lost)."""
    out = folder / "results"
    out.mkdir()
    (out / "runs").write_text("mine")
    for command in (["sweep", folder / "small.toml", "--out", out], ["calibrate", out, "--designs", "WD3"]):
        refused(invoke(*command), "runs: exists and is not a folder, where a sweep writes its records")
    assert (out / "runs").read_text() == "mine"
    (out / "runs").unlink()
    assert invoke("sweep", folder / "small.toml", "--out", out, "--workers", "2").exit_code == 0
    first = sorted((out / "runs").glob("*.json"))[0]
    first.unlink()
    first.mkdir()
    result = invoke("sweep", folder / "small.toml", "--out", out, "--workers", "2")
    refused(result, f"{first}: is not a file but where the record of run {first.stem} goes; move it away")
    assert "runs done" not in result.output and first.is_dir() and not list((out / "runs").glob("*.tmp"))


def test_a_sweep_that_left_runs_to_another_sweep_does_not_say_the_study_is_complete(folder):
    """Found by a hunt: it exited 0, though the other sweep, killed meanwhile, never recorded them."""
    out = folder / "results"
    assert invoke("sweep", folder / "small.toml", "--out", out, "--workers", "2").exit_code == 0
    first = sorted((out / "runs").glob("*.json"))[0]
    first.unlink()
    held = claim(out, first.stem)  # another sweep's (a lock is per open file)
    try:
        result = invoke("sweep", folder / "small.toml", "--out", out, "--workers", "2")
    finally:
        release(out, first.stem, held)
    refused(result, f"the study is not complete: 1 runs left to another sweep working on {out}")
    assert "0 runs done (0 failed)" in result.output and not first.exists()


def test_more_workers_than_four_a_core_are_refused_naming_the_bound(folder):
    from drydem.parametric.workers import cores

    # found by a hunt: --workers 1000000 started a local process per run
    too_many = 4 * cores() + 1
    refused(invoke("sweep", folder / "small.toml", "--out", folder / "out", "--workers", too_many),
            f"{too_many}: at most {too_many - 1} local processes (4 per core; this process may run on {cores()} cores)")
    assert not (folder / "out").exists()


def test_a_value_listed_twice_and_grids_of_one_name_are_noted(folder):
    """Found by a hunt: kn = [3e7, 3e7] made one run, and two grids named alike ran, without a word."""
    (folder / "twice.toml").write_text('[study]\nname = "t"\n[[grid]]\nname = "g"\ntargets = ["pier.toml"]\nkn = [3e7, 3e7]\n'
                                        '[[grid]]\nname = "g"\ntargets = ["pier.toml"]\nkn = [1e8]\n')
    study = load_study(folder / "twice.toml")
    assert len(study.runs) == 2
    assert study.notes[:2] == (f"{folder / 'twice.toml'}: [[grid]] #0 ('g'): 1 of its 2 runs are the same as another of its runs "
                               "(a value listed twice?): each is run once",
                               f"{folder / 'twice.toml'}: [[grid]] #1 ('g'): another grid before it has the name 'g'")


def test_a_study_file_that_is_a_pipe_is_called_so_not_missing(folder):
    os.mkfifo(folder / "pipe.toml")  # found by a hunt: "no such study file", where `check` says what it is
    refused(invoke("sweep", folder / "pipe.toml", "--out", folder / "out"), "pipe.toml: not a regular file (a pipe or a device?)")


def test_a_restarted_sweep_runs_the_corrupt_records_again_and_says_which(folder):
    out = folder / "results"
    assert invoke("sweep", folder / "small.toml", "--out", out, "--workers", "2").exit_code == 0
    runs = sorted((out / "runs").glob("*.json"))
    runs[0].write_text("")
    runs[1].write_text(runs[1].read_text()[:100])
    runs[2].write_text(json.dumps(json.loads(runs[3].read_text()) | {"id": runs[2].stem}))  # another run's parameters
    kept = {p: p.stat().st_mtime_ns for p in runs[3:]}
    result = invoke("sweep", folder / "small.toml", "--out", out, "--workers", "2")
    assert result.exit_code == 0, result.output
    assert "8 runs, 5 already recorded" in result.output and "3 runs done (0 failed), 5 skipped" in result.output
    for path in runs[:3]:
        assert f"corrupt record, run again: {path}: " in result.stderr
        read_record(path)  # valid now
    assert {p: p.stat().st_mtime_ns for p in runs[3:]} == kept


def test_a_report_leaves_out_corrupt_records_and_names_them(folder):
    write_record(folder, ok_record(SPEC))
    broken = write_record(folder, ok_record(OTHER))
    broken.write_text('{"id": ')
    result = invoke("report", folder)
    assert result.exit_code == 0, result.output
    assert f"corrupt record left out: {broken}: not a JSON record" in result.stderr
    text = (folder / "report" / "report.md").read_text()
    assert "1 runs recorded (0 failed)" in text and "1 corrupt records left out" in text and str(broken) in text


def test_a_report_of_a_folder_without_runs_says_it_has_nothing_to_report(tmp_path):
    refused(invoke("report", tmp_path), f"{tmp_path}: nothing to report: no runs/ folder")
    # found by a hunt: a shake run's folder was said to have no summary.json, which it has
    (tmp_path / "summary.json").write_text(json.dumps({"overturned": False, "max_rotation_rad": 0.0}))
    refused(invoke("report", tmp_path), f"{tmp_path / 'summary.json'} is of another analysis (a `drydem shake` run's folder is its own report")


# --- claims: one run, one sweep -------------------------------------------------------------


def made_up_run(spec: RunSpec) -> dict:
    """Stands for run_one (in threads): a record at once, the angle growing with log kn."""
    import math

    return ok_record(spec, angle=10.0 + 2.0 * math.log10(spec.kn / 1e7))


def test_a_run_claimed_by_another_sweep_is_left_to_it_and_a_dead_claim_is_taken_over(tmp_path, monkeypatch):
    monkeypatch.setattr(sweep_module, "run_one", made_up_run)
    (tmp_path / "runs").mkdir()
    held = claim(tmp_path, SPEC.id)  # another sweep (a lock is per open file, so one in this process is another's)
    lock_path(tmp_path, OTHER.id).write_text("claimed by a sweep killed since")  # a file without its lock
    left = []
    with ThreadPoolExecutor(2) as executor:
        outcome = sweep([SPEC, OTHER], tmp_path, executor, on_other=left.append)
        assert (outcome.finished, outcome.elsewhere, outcome.skipped) == (1, 1, 0) and left == [SPEC]
        assert record_path(tmp_path, OTHER.id).is_file() and not record_path(tmp_path, SPEC.id).exists()
        assert not lock_path(tmp_path, OTHER.id).exists()
        # the other sweep records it, then ends its claim: nothing left to do here
        write_record(tmp_path, made_up_run(SPEC))
        release(tmp_path, SPEC.id, held)
        outcome = sweep([SPEC, OTHER], tmp_path, executor)
    assert (outcome.finished, outcome.elsewhere, outcome.skipped) == (0, 0, 2)
    assert not list((tmp_path / "runs").glob("*.lock"))


def test_a_run_another_sweep_recorded_as_failed_meanwhile_counts_as_failed_not_done(tmp_path, monkeypatch):
    """Found by a review: it counted as done, so the study was called complete (exit 0)."""
    monkeypatch.setattr(sweep_module, "run_one", made_up_run)
    (tmp_path / "runs").mkdir()
    held = claim(tmp_path, SPEC.id)

    def the_other_sweep_fails_it(spec):
        write_record(tmp_path, {"id": spec.id, "spec": asdict(spec), "status": "failed", "error": "ModelError: made up"})
        release(tmp_path, spec.id, held)

    with ThreadPoolExecutor(2) as executor:
        outcome = sweep([SPEC, OTHER], tmp_path, executor, on_other=the_other_sweep_fails_it)
    assert (outcome.finished, outcome.skipped, outcome.failed_before, outcome.elsewhere) == (1, 1, 1, 0)


def test_a_run_recorded_by_another_sweep_after_this_one_looked_is_not_run_again(tmp_path, monkeypatch):
    monkeypatch.setattr(sweep_module, "run_one", made_up_run)

    def recorded_meanwhile(runs, results, **kw):
        plan = real_pending(runs, results, **kw)
        write_record(results, made_up_run(SPEC))  # by another sweep, between the look and the claim
        return plan

    real_pending = sweep_module.pending
    monkeypatch.setattr(sweep_module, "pending", recorded_meanwhile)
    with ThreadPoolExecutor(1) as executor:
        outcome = sweep([SPEC, OTHER], tmp_path, executor)
    assert (outcome.finished, outcome.skipped) == (1, 1)


def test_a_run_the_executor_loses_stops_the_sweep_with_its_id(tmp_path, monkeypatch):
    def killed(spec):
        raise RuntimeError("worker killed")

    monkeypatch.setattr(sweep_module, "run_one", killed)
    with ThreadPoolExecutor(1) as executor, pytest.raises(SweepError, match=re.escape(f"run {SPEC.id} was lost by the executor (RuntimeError: worker killed)")):
        sweep([SPEC], tmp_path, executor)
    assert not list((tmp_path / "runs").glob("*.lock"))


# --- killed sweeps, concurrent sweeps (real processes) ----------------------------------------


def _stat(pid: int) -> list[str] | None:
    """The fields of /proc/PID/stat after the command name (state, ppid, ...), None if gone."""
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    except (FileNotFoundError, ProcessLookupError):
        return None


def alive(pid: int) -> bool:
    fields = _stat(pid)
    return fields is not None and fields[0] not in ("Z", "X")  # a zombie has ended


def descendants(pid: int) -> list[int]:
    children: dict[int, list[int]] = {}
    for entry in os.listdir("/proc"):
        if entry.isdigit() and (fields := _stat(int(entry))) is not None:
            children.setdefault(int(fields[1]), []).append(int(entry))
    found, todo = [], [pid]
    while todo:
        below = children.get(todo.pop(), [])
        found += below
        todo += below
    return found


def eventually(condition, timeout_s: float = 120.0) -> bool:
    """Whether ``condition()`` becomes true within a generous time (no timing is asserted)."""
    end = time.monotonic() + timeout_s
    while not condition():
        if time.monotonic() > end:
            return False
        time.sleep(0.05)
    return True


@LINUX
@pytest.mark.parametrize("initializer", ["_exit_with_parent", "_watch_parent"])
def test_a_worker_ends_with_its_killed_parent(tmp_path, initializer):
    script = tmp_path / "parent.py"
    script.write_text(textwrap.dedent(f"""
        import multiprocessing, os, time
        from concurrent.futures import ProcessPoolExecutor
        from drydem.parametric import workers

        if __name__ == "__main__":
            pool = ProcessPoolExecutor(1, mp_context=multiprocessing.get_context("spawn"),
                                       initializer=workers.{initializer}, initargs=(os.getpid(),))
            print(pool.submit(os.getpid).result(), flush=True)
            pool.submit(time.sleep, 600)
            time.sleep(600)
    """))
    parent = subprocess.Popen([sys.executable, str(script)], stdout=subprocess.PIPE, text=True)
    worker = int(parent.stdout.readline())
    assert alive(worker)
    parent.kill()
    parent.wait()
    assert eventually(lambda: not alive(worker)), f"worker {worker} outlived its parent"


def drydem_sweep(study: Path, out: Path, workers: int, log: Path) -> subprocess.Popen:
    """``drydem sweep`` in a process of its own, its output to ``log`` (a file, not a pipe, that
    a worker left behind would hold open)."""
    with open(log, "w") as file:
        return subprocess.Popen([*DRYDEM, "sweep", str(study), "--out", str(out), "--workers", str(workers)], stdout=file, stderr=subprocess.STDOUT)


@LINUX
def test_a_sweep_killed_outright_leaves_no_process_and_goes_on_with_what_is_missing(folder):
    out = folder / "results"
    killed = drydem_sweep(folder / "slow.toml", out, 2, folder / "killed.log")
    assert eventually(lambda: any((out / "runs").glob("*.json")) or killed.poll() is not None)
    processes = descendants(killed.pid)  # the workers and multiprocessing's resource tracker
    os.kill(killed.pid, signal.SIGKILL)
    killed.wait()
    try:
        assert processes and eventually(lambda: not any(alive(p) for p in processes)), [p for p in processes if alive(p)]
    finally:  # a failure leaves nothing running
        for pid in filter(alive, processes):
            os.kill(pid, signal.SIGKILL)
    recorded = {p: p.stat().st_mtime_ns for p in (out / "runs").glob("*.json")}
    assert 0 < len(recorded) < 12, "the sweep was to be killed with runs left"
    result = invoke("sweep", folder / "slow.toml", "--out", out, "--workers", "2")
    assert result.exit_code == 0, result.output
    assert f"12 runs, {len(recorded)} already recorded" in result.output
    assert f"{12 - len(recorded)} runs done (0 failed), {len(recorded)} skipped" in result.output
    assert {p: p.stat().st_mtime_ns for p in recorded} == recorded
    assert len(load_records(out).valid) == 12 and not list((out / "runs").glob("*.lock"))


@LINUX  # flock claims
def test_two_sweeps_on_one_folder_compute_each_run_once(folder):
    out = folder / "results"
    logs = [folder / f"sweep{k}.log" for k in range(2)]
    sweeps = [drydem_sweep(folder / "slow.toml", out, 1, log) for log in logs]
    try:
        for s in sweeps:
            s.wait(timeout=600)
    finally:
        for s in sweeps:
            s.kill()
    outputs = [log.read_text() for log in logs]
    # the last to end finds every run recorded; the first may end while the other still runs
    # some it left to it, and then says the study is not complete yet
    codes = [s.returncode for s in sweeps]
    assert 0 in codes and all(code == 0 or "left to another sweep" in text for code, text in zip(codes, outputs)), outputs
    done = [int(re.search(r"(\d+) runs done \(0 failed\)", text).group(1)) for text in outputs]
    assert sum(done) == 12, outputs  # each run computed by one of them
    assert len(load_records(out).valid) == 12 and not list((out / "runs").glob("*.lock"))


# --- the scheduler: fail fast, say where ------------------------------------------------------


def test_an_unreachable_scheduler_fails_fast_naming_it(folder):
    start = time.monotonic()
    result = subprocess.run([*DRYDEM, "sweep", str(folder / "small.toml"), "--out", str(folder / "results"),
                             "--scheduler", "tcp://127.0.0.1:1"], capture_output=True, text=True, timeout=300)
    # 5 s to connect, the rest is starting Python; bounded loosely (a shared machine is slow)
    assert result.returncode == 1 and time.monotonic() - start < 60
    assert "cannot reach the Dask scheduler at tcp://127.0.0.1:1" in result.stderr and "check that it is running" in result.stderr
    assert "Traceback" not in result.stdout + result.stderr
    assert not list((folder / "results").glob("runs/*.json"))


@pytest.mark.parametrize("address", ["nonsense", "foo://host:1", "", "tcp://host", "tls://127.0.0.1:1", "ucx://127.0.0.1:1",
                                     "inproc://x:1"])
def test_a_scheduler_address_that_is_not_one_is_named(folder, address):
    refused(invoke("sweep", folder / "small.toml", "--out", folder / "results", "--scheduler", address),
            f"scheduler {address!r} is not a scheduler address", "expected tcp://HOST:PORT")


# --- calibration ------------------------------------------------------------------------------


@pytest.mark.parametrize("options, message", [
    (["--kn-min", "1e9", "--kn-max", "1e7"], "--kn-min = 1000000000.0, --kn-max = 10000000.0: need --kn-min < --kn-max"),
    (["--kn-min", "1e8", "--kn-max", "1e8"], "need --kn-min < --kn-max"),
    (["--kn-min", "-1e7"], "--kn-min = -10000000.0: must be a number in [1e+04, 1e+15] Pa/m"),
    (["--kn-max", "0"], "--kn-max = 0.0: must be a number in [1e+04, 1e+15] Pa/m"),
    (["--ks-ratio", "0"], "--ks-ratio = 0.0: must be a number in (0, inf)"),
    (["--ks-ratio", "-2"], "--ks-ratio = -2.0: must be a number in (0, inf)"),
    (["--ks-ratio", "1e9"], "--ks-ratio = 1000000000.0: ks = ratio x kn, 1e+16 to 1e+18 Pa/m, must be a number in [1e+04, 1e+15]"),
    (["--increment", "0"], "--increment = 0.0: must be a number in [0.001, 90) deg"),
    (["--increment", "90"], "--increment = 90.0: must be a number in [0.001, 90) deg"),
    (["--designs", "WD1,WD9"], "--designs 'WD1,WD9': no experimental collapse angle for WD9; known: WD1, WD2"),
    (["--designs", " , "], "--designs ',': an empty name (two commas in a row, or one at an end)"),
    (["--designs", ""], "--designs '': needs at least one wall"),
    (["--designs", "WD1,,WD2"], "--designs 'WD1,,WD2': an empty name (two commas in a row, or one at an end)"),
    (["--designs", "WD1,WD2,"], "--designs 'WD1,WD2,': an empty name"),
    (["--designs", "WD1,WD2,WD1"], "--designs 'WD1,WD2,WD1': WD1 given more than once; give each wall once"),
])
def test_calibrate_options_are_checked_before_anything_runs(tmp_path, options, message):
    refused(invoke("calibrate", tmp_path / "results", *options), message)
    assert not (tmp_path / "results").exists()


def test_calibrate_names_every_bad_option_at_once(tmp_path):
    refused(invoke("calibrate", tmp_path / "results", "--kn-min", "-1", "--ks-ratio", "0", "--increment", "100"),
            "--kn-min = -1.0", "--ks-ratio = 0.0", "--increment = 100.0")


def test_calibration_runs_corrupt_records_again_and_says_so(tmp_path, monkeypatch):
    monkeypatch.setattr(sweep_module, "run_one", made_up_run)
    search = StiffnessSearch(("WD1", "WD6"), kn_min=1e7, kn_max=1e9)
    first = search.runs(1e7)[0]
    write_record(tmp_path, made_up_run(first)).write_text("{")
    said = []
    with ThreadPoolExecutor(2) as executor:
        result = calibrate_stiffness(search, tmp_path, executor, on_evaluation=lambda kn, error, outcome: said.append(outcome.corrupt))
    assert said[0] and str(record_path(tmp_path, first.id)) in said[0][0] and not any(said[1:])
    assert read_record(record_path(tmp_path, first.id))["status"] == "ok"
    assert 1e7 <= result.best_kn <= 1e9


def test_calibration_stops_on_failed_runs_naming_them(tmp_path, monkeypatch):
    def failing(spec):
        return {"id": spec.id, "spec": asdict(spec), "status": "failed", "error": "ModelError: made up"}

    monkeypatch.setattr(sweep_module, "run_one", failing)
    with ThreadPoolExecutor(1) as executor, pytest.raises(sweep_module.DrydemError, match="runs without a collapse angle:\n  WD1: ModelError: made up"):
        calibrate_stiffness(StiffnessSearch(("WD1",)), tmp_path, executor)
