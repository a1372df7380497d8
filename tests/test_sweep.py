"""Parametric studies: local and Dask runs agree, a killed sweep resumes, failures are recorded."""

import json
from dataclasses import asdict

import pytest

from drydem.parametric.records import load_records, record_path
from drydem.parametric.study import RunSpec, load_study
from drydem.parametric.sweep import pending, sweep
from drydem.parametric.workers import local_executor
from drydem.errors import ModelError

#: two small walls (tilting in a second or two) as wall files beside the study
WALLS = {
    "stack.toml": "BB\nbBb\nBB\nbBb\n",
    "pier.toml": "B\n" * 10,  # rocks at atan(25 / 55) = 24.4 deg when rigid
}
WALL_FILE = '''[brick]
length_m = 0.025
height_m = 0.0055
width_m = 0.012
[supports]
fix_y = true
[layout]
courses = """
{courses}"""
'''
STUDY = """
[study]
name = "small"
[defaults]
increment_deg = 5.0
[[grid]]
name = "stiffness"
targets = ["stack.toml", "pier.toml"]
kn = [1e7, 1e8, 1e9]
protocol = ["fixed"]
[[grid]]
name = "limit"
analysis = "limit"
targets = ["stack.toml", "pier.toml"]
"""


@pytest.fixture
def study_file(tmp_path):
    for name, courses in WALLS.items():
        (tmp_path / name).write_text(WALL_FILE.format(courses=courses))
    path = tmp_path / "small.toml"
    path.write_text(STUDY)
    return path


def local(workers=2):
    return local_executor(workers)


def outcomes(results):
    return {r["id"]: (r["status"], r["summary"]["collapse_angle_deg"], r["pushover"]) for r in load_records(results).valid}


def test_a_study_expands_its_grids_and_shares_repeated_runs(study_file):
    study = load_study(study_file)
    assert study.name == "small" and len(study.runs) == 2 * 3 + 2
    assert len({spec.id for spec in study.runs}) == len(study.runs)
    tilt = [s for s in study.runs if s.analysis == "tilt"]
    assert all(s.ks == s.kn and s.protocol == "fixed" and s.increment_deg == 5.0 for s in tilt)
    twice = study_file.with_name("twice.toml")
    twice.write_text(STUDY + STUDY[STUDY.index("[[grid]]"):].replace('"stiffness"', '"again"'))
    assert load_study(twice).runs == study.runs


@pytest.mark.slow
def test_local_processes_and_a_dask_cluster_give_the_same_records(study_file, tmp_path):
    from distributed import Client, LocalCluster

    runs = load_study(study_file).runs
    with local() as executor:
        outcome = sweep(runs, tmp_path / "local", executor)
    assert (outcome.finished, outcome.skipped, outcome.failed) == (len(runs), 0, 0)
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster, Client(cluster) as client:
        sweep(runs, tmp_path / "dask", client.get_executor())
    assert outcomes(tmp_path / "local") == outcomes(tmp_path / "dask")
    # softer joints, lower collapse angle (paper Fig. 6): on the pier, 1e7 < 1e9
    pier = {r["spec"]["kn"]: r["summary"]["collapse_angle_deg"] for r in load_records(tmp_path / "local").valid
            if r["spec"]["analysis"] == "tilt" and "pier" in r["spec"]["target"]}
    assert pier[1e7] < pier[1e9]


def test_a_sweep_started_again_skips_what_is_recorded(study_file, tmp_path):
    runs = load_study(study_file).runs
    results = tmp_path / "results"
    with local(1) as executor:
        sweep(runs[:3], results, executor)  # as if killed after three runs
        written = {spec.id: record_path(results, spec.id).stat().st_mtime_ns for spec in runs[:3]}
        assert len(pending(runs, results).todo) == len(runs) - 3
        outcome = sweep(runs, results, executor)
    assert (outcome.finished, outcome.skipped) == (len(runs) - 3, 3)
    assert {spec_id: record_path(results, spec_id).stat().st_mtime_ns for spec_id in written} == written
    assert len(load_records(results).valid) == len(runs)
    assert not list((results / "runs").glob("*.tmp"))


def test_a_failing_run_is_recorded_and_the_sweep_goes_on(study_file, tmp_path):
    good = load_study(study_file).runs[0]
    bad = RunSpec(analysis="tilt", target=str(tmp_path / "missing.toml"), protocol="fixed")
    negative = RunSpec(analysis="tilt", target=good.target, protocol="fixed", kn=-1.0, ks=-1.0)
    with local(1) as executor:
        outcome = sweep([bad, good, negative], tmp_path / "results", executor)
    assert (outcome.finished, outcome.failed) == (3, 2)
    records = {r["id"]: r for r in load_records(tmp_path / "results").valid}
    assert "missing.toml: no such file" in records[bad.id]["error"]
    assert "kn = -1.0: must be a number in" in records[negative.id]["error"]
    assert records[good.id]["status"] == "ok"
    # retried on request only
    assert [s.id for s in pending([bad, good], tmp_path / "results").todo] == []
    assert pending([bad, good], tmp_path / "results").failed == 1
    assert [s.id for s in pending([bad, good], tmp_path / "results", retry_failed=True).todo] == [bad.id]


@pytest.mark.parametrize("change, message", [
    (('protocol = ["fixed"]', 'protocol = ["fast"]'), r"protocol \['fast'\] is not one of \['fixed', 'adaptive'\]"),
    (('kn = [1e7', 'kk = [1e7'), r"unknown key\(s\) \['kk'\] in the grid"),
    (('analysis = "limit"', 'analysis = "modal"'), r"analysis = 'modal': must be one of"),
])
def test_bad_study_files_name_the_grid_and_key(study_file, change, message):
    study_file.write_text(STUDY.replace(*change))
    with pytest.raises(ModelError, match=message) as caught:
        load_study(study_file)
    assert str(caught.value).startswith(str(study_file))


def test_a_target_file_is_looked_for_beside_the_study_not_in_the_current_folder(study_file, tmp_path, monkeypatch):
    # a study in sub/ naming stack.toml, which only the current folder held, analysed that file
    sub = tmp_path / "sub"
    sub.mkdir()
    (sub / "small.toml").write_text(STUDY)
    monkeypatch.chdir(tmp_path)
    with pytest.raises(ModelError, match=f"{sub / 'stack.toml'}: no such file"):
        load_study(sub / "small.toml")
    assert {spec.target for spec in load_study(study_file).runs} == {str(tmp_path / name) for name in WALLS}


def test_a_run_id_keeps_a_file_name_within_255_bytes_whatever_the_target_s_name():
    # a 240-character target name made record and lock file names past 255 bytes: an OSError traceback
    long = RunSpec(analysis="tilt", target="w" * 240 + ".toml", protocol="fixed", kn=None, ks=None, friction=None, points=None,
                   increment_deg=5.0)
    other = RunSpec(analysis="tilt", target="w" * 239 + "x.toml", protocol="fixed", kn=None, ks=None, friction=None, points=None,
                    increment_deg=5.0)
    assert len((long.id + ".lock").encode()) < 255 and long.id != other.id
    short = RunSpec(analysis="tilt", target="WD1", protocol="fixed", kn=None, ks=None, friction=None, points=None, increment_deg=5.0)
    assert short.id.startswith("tilt-WD1-fixed-")  # a short name's id is as it was: records made before are found


def test_a_record_holds_parameters_summary_and_curve(study_file, tmp_path):
    spec = load_study(study_file).runs[0]
    with local(1) as executor:
        sweep([spec], tmp_path, executor)
    record = json.loads(record_path(tmp_path, spec.id).read_text())
    assert record["spec"]["kn"] == spec.kn and record["status"] == "ok" and record["error"] is None
    assert record["summary"]["collapse_angle_deg"] == record["pushover"][-1][0]
    assert {"drift_limit_angles_deg", "model", "cycles"} <= set(record["summary"])


def test_drydem_sweep_then_again_then_report(study_file, tmp_path):
    from click.testing import CliRunner

    from drydem.cli import main

    out = tmp_path / "results"
    result = CliRunner().invoke(main, ["sweep", str(study_file), "--out", str(out), "--workers", "2"])
    assert result.exit_code == 0, result.output
    assert "small: 8 runs, 0 already recorded" in result.output and "8 runs done (0 failed), 0 skipped" in result.output
    result = CliRunner().invoke(main, ["sweep", str(study_file), "--out", str(out)])
    assert "8 already recorded" in result.output and "0 runs done (0 failed), 8 skipped" in result.output
    result = CliRunner().invoke(main, ["report", str(out)])
    assert result.exit_code == 0 and (out / "report" / "report.html").is_file()
    result = CliRunner().invoke(main, ["sweep", "nosuchstudy"])
    assert result.exit_code == 1 and "not a shipped study (savalle2022)" in result.output


def test_a_run_analyses_its_target_with_its_overrides_as_the_cli_does():
    from drydem.io.target import load_target

    spec = RunSpec(analysis="tilt", target="WD1", protocol="fixed", kn=1e8, ks=5e7, friction=0.7, points=2)
    assert spec.overrides == {"kn": 1e8, "ks": 5e7, "friction": 0.7, "points": 2, "joint_law": None}
    model = spec.model()
    assert (model.joint.kn, model.joint.ks, model.joint.friction, model.contacts.points_per_length) == (1e8, 5e7, 0.7, 2)
    assert model.joint == load_target("WD1").model.overridden(**spec.overrides).joint
    plain = RunSpec(analysis="tilt", target="WD1", protocol="fixed")
    assert plain.model().joint == load_target("WD1").model.joint
    with pytest.raises(ModelError, match=r"\[joint\] friction = -1.0: must be a number in \(0, 10\]"):
        RunSpec(analysis="tilt", target="WD1", protocol="fixed", friction=-1.0).model()


def test_drydem_sweep_exits_1_while_a_run_of_the_study_is_recorded_as_failed(study_file, tmp_path):
    """A script tells a complete study from its exit status: a failed run (recorded now, or
    before and not retried) makes the sweep exit 1 naming the count and --retry-failed."""
    from click.testing import CliRunner

    from drydem.cli import main
    from drydem.parametric.records import write_record

    study_file.write_text(STUDY[:STUDY.index("[[grid]]")] + STUDY[STUDY.index('[[grid]]\nname = "limit"'):])
    runs = load_study(study_file).runs
    out = tmp_path / "results"
    write_record(out, {"id": runs[0].id, "spec": asdict(runs[0]), "status": "failed", "error": "ModelError: made up"})
    result = CliRunner().invoke(main, ["sweep", str(study_file), "--out", str(out), "--workers", "1"])
    assert result.exit_code == 1, result.output
    assert "1 runs done (0 failed), 1 skipped" in result.output
    assert "the study is not complete: 0 runs failed now and 1 recorded as failed before" in result.output
    assert "--retry-failed" in result.output
    result = CliRunner().invoke(main, ["sweep", str(study_file), "--out", str(out), "--workers", "1", "--retry-failed"])
    assert result.exit_code == 0, result.output
    assert "1 runs done (0 failed), 1 skipped" in result.output
    assert {r["status"] for r in load_records(out).valid} == {"ok"}


def test_a_study_tilting_a_wall_too_tall_for_the_stop_displacement_is_refused_before_any_run(study_file):
    # as drydem tilt refuses it: 0.10 m is 0.25 % of a 40 m wall, and reaching it is no collapse
    (study_file.parent / "stack.toml").write_text(WALL_FILE.format(courses="b1Bb\n2B\n").replace("0.025", "20").replace(
        "0.0055", "20").replace("0.012", "20"))
    with pytest.raises(ModelError, match=r"stop_displacement_m = 0.1 m \(--stop-displacement\) is a drift of 0.25% of the wall's 40 m "
                                         r"height") as caught:
        load_study(study_file)
    assert str(caught.value).startswith(str(study_file))


def test_a_run_recorded_on_a_target_file_that_changed_since_is_neither_taken_as_done_nor_replaced_unasked(study_file, tmp_path):
    """Found by a hunt: a sweep run again after its target file was edited (or on another file
    of the same path) said "1 skipped" and kept the old file's result. A record keeps the
    SHA-256 of each file its run read; a run recorded on other content is left as it is, and the
    sweep exits 1 naming the file and --retry-changed, which runs it again on the file as it is."""
    from click.testing import CliRunner

    from drydem.cli import main

    study_file.write_text(STUDY[:STUDY.index("[[grid]]")] + STUDY[STUDY.index('[[grid]]\nname = "limit"'):])
    out = tmp_path / "results"
    first = CliRunner().invoke(main, ["sweep", str(study_file), "--out", str(out), "--workers", "1"])
    assert first.exit_code == 0, first.output
    pier = study_file.parent / "pier.toml"
    before = {r["spec"]["target"]: r for r in load_records(out).valid}
    assert set(before[str(pier)]["inputs"]) == {str(pier)}
    pier.write_text(WALL_FILE.format(courses="B\n" * 5))  # half as tall: it rocks later
    again = CliRunner().invoke(main, ["sweep", str(study_file), "--out", str(out), "--workers", "1"])
    assert again.exit_code == 1, again.output
    assert "0 runs done (0 failed), 2 skipped" in again.output
    assert f"1 runs are recorded on files whose content has changed since, or that are gone ({pier})" in again.output
    assert "--retry-changed" in again.output
    assert {r["spec"]["target"]: r for r in load_records(out).valid} == before  # nothing replaced unasked
    retried = CliRunner().invoke(main, ["sweep", str(study_file), "--out", str(out), "--workers", "1", "--retry-changed"])
    assert retried.exit_code == 0, retried.output
    assert "1 runs done (0 failed), 1 skipped" in retried.output
    after = {r["spec"]["target"]: r for r in load_records(out).valid}
    assert after[str(pier)]["summary"]["collapse_angle_deg"] != before[str(pier)]["summary"]["collapse_angle_deg"]
    assert after[str(pier)]["inputs"] != before[str(pier)]["inputs"]
