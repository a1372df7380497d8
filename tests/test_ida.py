"""Incremental dynamic analysis: shake grids in a study (every motion at every scale), checked
whole at load time, swept and resumed like the other analyses, and reported as IDA curves and a
table of collapse intensities (the dynamic counterpart of the tilting angle)."""

import json
import math
from dataclasses import asdict

import numpy as np
import pytest
from click.testing import CliRunner

from drydem.analysis.shake import read_motion
from drydem.cli import main
from drydem.errors import ModelError
from drydem.parametric.records import RecordError, SUMMARY_KEYS, load_records, read_record, record_path, write_record
from drydem.parametric.study import RunSpec, ground_motion, load_study
from drydem.parametric.sweep import pending, sweep
from drydem.parametric.workers import local_executor
from drydem.report.ida import collapse_table, ida_curves
from drydem.report.study import build_report

#: one block 20 mm wide (x) and 80 mm tall on a fixed base: it uplifts at g tan(alpha) = 9.81 x 0.25 = 2.45 m/s2;
#: under a 2 Hz one-sine pulse it stands at 2 m/s2 (peak rotation ~1e-3 rad) and overturns at 3 and 4 m/s2
BLOCK = """
[material]
density = 2000.0
[joint]
kn = 1e9
ks = 1e9
friction = 0.8
[contacts]
points_per_length = 2
[supports]
fix_y = true
[[block]]
name = "base"
fixed = true
box = { min = [-0.1, -0.01, -0.01], max = [0.12, 0.01, 0.0] }
[[block]]
name = "block"
box = { min = [0.0, -0.01, 0.0], max = [0.02, 0.01, 0.08] }
"""
#: a half sine of 1 m/s2 over 0.2 s, which does not end at rest (final velocity 0.4 / pi m/s): its baseline correction changes it
RECORD = "time_s,acc_x_m_s2\n" + "".join(f"{0.01 * k:.2f},{math.sin(math.pi * k / 20):.6f}\n" for k in range(21))
SCALES = [1.0, 2.0, 3.0, 4.0]
STUDY = """
[study]
name = "ida"
[defaults]
increment_deg = 2.0
[[grid]]
name = "ida"
analysis = "shake"
targets = ["block.toml"]
motions = ["pulse:one-sine:2"]
scales = [1.0, 2.0, 3.0, 4.0]
duration_s = 2.0
kn = [1e8]
"""
#: the study with a record file, a second pulse and a tilt grid: loaded, not run
MIXED = STUDY.replace('motions = ["pulse:one-sine:2"]', 'motions = ["pulse:one-sine:2", "records/wave.csv", "pulse:one-sine:2.0"]') + """
[[grid]]
name = "tilt"
targets = ["block.toml"]
protocol = ["fixed"]
"""


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    path = tmp_path_factory.mktemp("ida")
    (path / "block.toml").write_text(BLOCK)
    (path / "brick.toml").write_text(BLOCK.replace("max = [0.02, 0.01, 0.08]", "max = [0.02, 0.01, 0.0044]"))  # squat: b / h = 0.01 / 0.0022
    (path / "records").mkdir()
    (path / "records" / "wave.csv").write_text(RECORD)
    (path / "ida.toml").write_text(STUDY)
    (path / "mixed.toml").write_text(MIXED)
    return path


@pytest.fixture(scope="module")
def swept(folder):
    """The study swept once on two local processes: (its runs, the results folder, the outcome)."""
    runs = load_study(folder / "ida.toml").runs
    results = folder / "results"
    with local_executor(2) as executor:
        outcome = sweep(runs, results, executor)
    return runs, results, outcome


# --- the study -----------------------------------------------------------------------------


def test_a_shake_grid_makes_one_run_per_target_motion_scale_and_override(folder):
    study = load_study(folder / "mixed.toml")
    shake = [s for s in study.runs if s.analysis == "shake"]
    assert len(study.runs) == 1 * 2 * 4 + 1  # "pulse:one-sine:2" and "pulse:one-sine:2.0" are one motion
    assert {(s.motion, s.scale) for s in shake} == {(m, k) for m in ("pulse:one-sine:2.0", str(folder / "records" / "wave.csv")) for k in SCALES}
    assert all(s.protocol == "time-history" and s.increment_deg is None and s.duration_s == 2.0 and s.restitution is None
               and s.contact_damping_ratio is None  # ShakeSettings' default
               and s.kn == s.ks == 1e8 and s.target == str(folder / "block.toml") for s in shake)
    assert len({s.id for s in study.runs}) == len(study.runs)
    ids = {s.id.rsplit("-", 1)[0] for s in shake}
    assert "shake-block-one-sine-2Hz-x3-kn1e+08-ks1e+08" in ids and "shake-block-wave.csv-x0.5-kn1e+08-ks1e+08" not in ids
    assert "shake-block-wave.csv-x2-kn1e+08-ks1e+08" in ids


def test_a_pulse_is_scaled_to_its_amplitude_and_a_record_is_baseline_corrected_first(folder):
    spec = next(s for s in load_study(folder / "mixed.toml").runs if s.motion == str(folder / "records" / "wave.csv") and s.scale == 3.0)
    raw = read_motion(folder / "records" / "wave.csv")
    corrected = raw.baseline_corrected()
    assert abs(raw.velocity_m_s()[-1, 0]) > 0.05 and abs(corrected.velocity_m_s()[-1, 0]) < 1e-12
    settings = spec.shake_settings()
    np.testing.assert_allclose(settings.motion.acceleration_m_s2, 3.0 * corrected.acceleration_m_s2, rtol=1e-14)
    assert settings.duration_s == 2.0 and settings.restitution is None and settings.contact_damping_ratio is None
    pulse = RunSpec(**(asdict(spec) | {"motion": "pulse:one-sine:2.0", "scale": 2.5}))
    assert pulse.shake_settings().motion.pga_m_s2 == pytest.approx(2.5, rel=1e-12)  # amplitude 1 m/s2 x 2.5
    assert ground_motion("pulse:one-sine:2.0").pga_m_s2 == pytest.approx(1.0, rel=1e-12)


def test_tilt_and_limit_runs_keep_their_ids():
    """The shake fields are left out of the hash when None: the records of earlier sweeps stay theirs."""
    assert RunSpec(analysis="tilt", target="WD1", protocol="fixed", kn=3e7, ks=3e7).id == "tilt-WD1-kn3e+07-ks3e+07-fixed-029e66c8fe"
    assert RunSpec(analysis="limit", target="WD2", protocol="associative").id == "limit-WD2-associative-414439886a"
    assert RunSpec(analysis="tilt", target="/x/pier.toml", protocol="adaptive", kn=1e9, ks=1e8, friction=0.7, points=2,
                   increment_deg=0.5).id == "tilt-pier-kn1e+09-ks1e+08-adaptive-04e08cb9ad"


GRID = "[[grid]] #0 ('ida')"


@pytest.mark.parametrize("change, message", [
    (("scales = [1.0, 2.0, 3.0, 4.0]", "scales = [1.0, true]"), "scales [True]: each must be a finite number > 0"),
    (("scales = [1.0, 2.0, 3.0, 4.0]", "scales = [nan, 2.0]"), "scales [nan]: each must be a finite number > 0"),
    (("scales = [1.0, 2.0, 3.0, 4.0]", "scales = [0.0, -1.0, inf]"), "scales [0.0, -1.0, inf]: each must be a finite number > 0"),
    (("scales = [1.0, 2.0, 3.0, 4.0]", 'scales = ["2"]'), "scales ['2']: each must be a finite number > 0"),
    (("scales = [1.0, 2.0, 3.0, 4.0]", "scales = []"), "scales = []: needs at least one value"),
    (("scales = [1.0, 2.0, 3.0, 4.0]\n", ""), "scales = []: needs at least one value (a shake grid needs targets, motions and scales)"),
    (('"pulse:one-sine:2"', '"records/missing.csv"'), "motions: {folder}/records/missing.csv: no such file"),
    (('"pulse:one-sine:2"', '"records"'), "motions: {folder}/records: is a folder"),
    (('"pulse:one-sine:2"', '"block.toml"'), "motions: {folder}/block.toml: unknown motion file type '.toml'"),
    (('"pulse:one-sine:2"', '"records/bad.csv"'), "motions: {folder}/records/bad.csv: line 3: acc_x_m_s2: 'x' is not a number"),
    # the block is in-plane (fix_y): a record along y alone would move nothing
    (('"pulse:one-sine:2"', '"records/y.csv"'),
     "y.csv, baseline-corrected: its y component shakes the model along y (peak 0.5 m/s2), but its blocks are held in y"),
    (('"pulse:one-sine:2"', '"pulse:square:2"'), "motions: 'pulse:square:2.0': pulse kind = 'square': must be one of"),
    (('"pulse:one-sine:2"', '"pulse:one-sine:fast"'), "the frequency 'fast' is not a plain decimal number"),
    # found by a hunt: float() took 1_0 (10 Hz) and a full-width 4; int() raised on a superscript 2 and on 5,000 digits
    (('"pulse:one-sine:2"', '"pulse:one-sine:1_0"'), "the frequency '1_0' is not a plain decimal number"),
    (('"pulse:one-sine:2"', '"pulse:one-sine:\uff14"'), "the frequency '\uff14' is not a plain decimal number"),
    (('"pulse:one-sine:2"', '"pulse:sine:4:\u00b2"'), "the cycles '\u00b2' are not a whole number of at most 6 digits (0-9)"),
    (('"pulse:one-sine:2"', '"pulse:sine:4:' + "9" * 5000 + '"'), "are not a whole number of at most 6 digits (0-9)"),
    (('"pulse:one-sine:2"', '"pulse:one-sine:0"'), "motions: 'pulse:one-sine:0.0': pulse frequency_hz = 0.0: must be a number in (0, inf) Hz"),
    (('"pulse:one-sine:2"', '"pulse:one-sine"'), "motions: 'pulse:one-sine': a pulse is pulse:KIND:FREQUENCY_HZ"),
    (('"pulse:one-sine:2"', '"pulse:one-sine:2:3"'), "pulse cycles = 3: a one-sine pulse has no cycles to repeat"),
    (('["pulse:one-sine:2"]', '[2.0]'), "motions [2.0]: each must be a file (CSV or .AT2) or a pulse"),
    (("duration_s = 2.0", "duration_s = -1.0"), "shake setting duration_s = -1.0: must be a number in (0, 1e+06] s"),
    (("duration_s = 2.0", 'restitution = 1.5'), "restitution (or 'housner') = 1.5: must be a number in (0, 1]"),
    (("duration_s = 2.0", 'restitution = "hausner"'), "restitution (or 'housner') = 'hausner'"),
    (("duration_s = 2.0", "restitution = 0.9\ncontact_damping_ratio = 0.3"), "restitution and contact_damping_ratio both set"),
    (("duration_s = 2.0", "contact_damping_ratio = -0.3"), "contact_damping_ratio = -0.3: must be a number in [0, 10]"),
    (("duration_s = 2.0", 'monitor = "nobody"'), "monitor = 'nobody': {folder}/block.toml: no block named 'nobody'"),
    (("duration_s = 2.0", 'monitor = "base"'), "the monitored block 'base' is fixed"),
    (('targets = ["block.toml"]', 'targets = ["brick.toml"]\nrestitution = "housner"'),
     "restitution = 'housner': the monitored block 'block' is too squat to rock: alpha = atan(b / h) = 77.6 deg"),
    (("kn = [1e8]", "kn = [-1.0]"), "kn = -1.0: must be a number in [1e+04, 1e+15] Pa/m"),
    (("duration_s = 2.0", "increment_deg = 1.0"), "unknown key(s) ['increment_deg'] in the grid (a shake analysis)"),
    (("duration_s = 2.0", 'protocol = ["fixed"]'), "unknown key(s) ['protocol'] in the grid (a shake analysis)"),
    (('analysis = "shake"', 'analysis = "tilt"'), "unknown key(s) ['duration_s', 'motions', 'scales'] in the grid (a tilt analysis)"),
    (('analysis = "shake"', 'analysis = "quake"'), "analysis = 'quake': must be one of ['tilt', 'limit', 'shake']"),
])
def test_a_bad_shake_grid_is_refused_naming_the_grid_and_key(folder, change, message):
    (folder / "records" / "bad.csv").write_text("time_s,acc_x_m_s2\n0,0\n0.1,x\n")
    (folder / "records" / "y.csv").write_text("time_s,acc_x_m_s2,acc_y_m_s2\n0,0,0\n0.1,0,1\n0.2,0,0\n")
    study = folder / "bad.toml"
    study.write_text(STUDY.replace(*change))
    with pytest.raises(ModelError) as caught:
        load_study(study)
    text, message = str(caught.value), message.format(folder=folder)
    assert text.startswith(str(study)), text
    assert any(line.strip().startswith(f"{study}: {GRID}: ") and message in line for line in text.splitlines()), text


def test_every_problem_of_a_shake_study_is_named_at_once(folder):
    study = folder / "bad.toml"
    study.write_text(STUDY.replace('"pulse:one-sine:2"', '"records/missing.csv", "pulse:one-sine:-2"')
                     .replace("duration_s = 2.0", "duration_s = 0.0"))
    with pytest.raises(ModelError) as caught:
        load_study(study)
    text = str(caught.value)
    assert "problems, nothing run" in text
    for fragment in (f"{GRID}: motions: {folder}/records/missing.csv: no such file", f"{GRID}: motions: 'pulse:one-sine:-2.0'",
                     f"{GRID}: shake setting duration_s = 0.0"):
        assert fragment in text, text


def test_a_shake_study_prints_the_notes_on_its_motions_once_as_drydem_shake_does(folder, tmp_path):
    # a record starting late is shifted to 0, and a y component on a model held in y moves
    # nothing: drydem shake says both; a sweep ran them silently
    (folder / "records" / "late_xy.csv").write_text("time_s,acc_x_m_s2,acc_y_m_s2\n0.5,0,0\n0.525,2,0.5\n0.55,0,0\n")
    study = folder / "noted.toml"
    study.write_text(STUDY.replace('"pulse:one-sine:2"', '"records/late_xy.csv"').replace("duration_s = 2.0", "duration_s = 0.02"))
    notes = load_study(study).notes
    assert len(notes) == 3, notes
    assert "late_xy.csv: the record starts at t = 0.5 s; it was shifted by" in notes[0]
    assert "late_xy.csv: the baseline correction shifts the x acceleration by up to" in notes[1]  # one triangle, one way
    assert "late_xy.csv, baseline-corrected, before its scales: its y component (peak 0.25 m/s2)" in notes[2]
    assert "moves nothing: the blocks are held in y" in notes[2]
    result = CliRunner().invoke(main, ["sweep", str(study), "--out", str(tmp_path / "out"), "--workers", "1"])
    assert result.exit_code == 0, result.output
    assert [line for line in result.output.splitlines() if line.startswith("note: ")] == [f"note: {note}" for note in notes]


def test_shake_settings_may_come_from_the_defaults_and_a_grid_s_own_replace_them(folder):
    study = folder / "defaults.toml"
    study.write_text(STUDY.replace("increment_deg = 2.0", "increment_deg = 2.0\nduration_s = 1.5\nrestitution = 0.8")
                     .replace("duration_s = 2.0", "contact_damping_ratio = 0.2"))
    runs = load_study(study).runs
    assert {(s.duration_s, s.restitution, s.contact_damping_ratio) for s in runs} == {(1.5, None, 0.2)}


# --- the sweep -----------------------------------------------------------------------------


def test_a_sweep_records_every_run_with_its_response(swept):
    runs, results, outcome = swept
    assert (outcome.finished, outcome.failed, outcome.skipped) == (len(SCALES), 0, 0)
    records = {r["id"]: r for r in load_records(results).valid}
    assert set(records) == {s.id for s in runs} and not load_records(results).corrupt
    for spec in runs:
        record = records[spec.id]
        assert record["status"] == "ok" and record["pushover"] == [] and RunSpec(**record["spec"]) == spec
        summary = record["summary"]
        assert SUMMARY_KEYS["shake"] <= set(summary)
        assert {"overturned", "max_rotation_rad", "max_displacement_m", "residual_displacement_m", "pga_m_s2", "scale", "motion",
                "cycles", "runtime_s"} <= set(summary)
        assert summary["scale"] == spec.scale and summary["motion"] == spec.motion == "pulse:one-sine:2.0"
        assert summary["pga_m_s2"] == pytest.approx(spec.scale, rel=1e-12) and summary["motion_pga_m_s2"] == pytest.approx(1.0)
        assert summary["cycles"] > 0 and summary["runtime_s"] > 0 and summary["model"]["joint"]["kn"] == 1e8
    overturned = {records[s.id]["summary"]["scale"]: records[s.id]["summary"]["overturned"] for s in runs}
    assert overturned == {1.0: False, 2.0: False, 3.0: True, 4.0: True}  # uplift at g tan(alpha) = 2.45 m/s2
    standing = [records[s.id]["summary"] for s in runs if s.scale <= 2.0]
    assert all(s["max_rotation_rad"] < 0.01 and s["ended_by"] == "duration" for s in standing)


def test_a_resumed_sweep_runs_nothing_new(swept):
    runs, results, _ = swept
    written = {s.id: record_path(results, s.id).stat().st_mtime_ns for s in runs}
    assert pending(runs, results).todo == []
    with local_executor(1) as executor:
        outcome = sweep(runs, results, executor)
    assert (outcome.finished, outcome.skipped) == (0, len(runs))
    assert {s.id: record_path(results, s.id).stat().st_mtime_ns for s in runs} == written


def test_drydem_sweep_and_report_take_a_shake_study(folder, swept):
    _, results, _ = swept
    result = CliRunner().invoke(main, ["sweep", str(folder / "ida.toml"), "--out", str(results)])
    assert result.exit_code == 0, result.output
    assert f"0 runs done (0 failed), {len(SCALES)} skipped" in result.output
    result = CliRunner().invoke(main, ["report", str(results), "--out", str(folder / "cli-report")])
    assert result.exit_code == 0 and "ida_rotation.png" in (folder / "cli-report" / "report.md").read_text()


def test_a_shake_record_without_its_response_is_corrupt(swept):
    runs, results, _ = swept
    good = json.loads(record_path(results, runs[0].id).read_text())
    for summary, message in (({k: v for k, v in good["summary"].items() if k != "overturned"}, "summary must hold"),
                             (good["summary"] | {"overturned": "no"}, "summary overturned = 'no': must be true or false"),
                             (good["summary"] | {"max_rotation_rad": None}, "max_rotation_rad = None: must be a number"),
                             # found by a hunt: out of range, they were drawn and tabled
                             (good["summary"] | {"pga_m_s2": math.inf}, r"pga_m_s2 = inf: must be a number in \[0, inf\) m/s2"),
                             (good["summary"] | {"max_rotation_rad": -1.0}, "max_rotation_rad = -1.0: must be a number in"),
                             (good["summary"] | {"max_rotation_rad": 1e308}, "max_rotation_rad = 1e\\+308: must be a number in"),
                             (good["summary"] | {"cycles": -3}, "cycles = -3: must be a whole number >= 0")):
        path = write_record(results.parent / "corrupt", good | {"summary": summary})
        with pytest.raises(RecordError, match=message):
            read_record(path)


# --- the report ----------------------------------------------------------------------------


def test_the_report_has_the_ida_figure_and_the_collapse_scale_of_the_records(swept, folder):
    _, results, _ = swept
    text = build_report(results, folder / "report").markdown.read_text()
    records = [r for r in load_records(results).valid if r["spec"]["analysis"] == "shake"]
    smallest = min(r["spec"]["scale"] for r in records if r["summary"]["overturned"])
    assert smallest == 3.0
    assert "## IDA: collapse intensity per target and record" in text
    assert f"| block | one-sine 2 Hz | 1 | 1, 2, 3, 4 | {smallest:g} | 3 | 0.306 | - |" in text
    assert "(figures/ida_rotation.png)" in text and "IDA: peak rotation of the monitored block" in text
    assert "a larger scale may survive" in text.lower() and "safe region" in text
    assert (folder / "report" / "figures" / "ida_rotation.png").stat().st_size > 5_000
    html = (folder / "report" / "report.html").read_text()
    # the IDA's table and figure alone: a study without a run of the paper's walls has none of its tables and figures
    assert html.count("<table>") == 1 and html.count("<img") == 1 and "No run of the paper's walls" in text


def made_up(scale: float, overturned: bool, *, motion="pulse:one-sine:2.0", kn=1e9, target="WD1") -> dict:
    spec = RunSpec(analysis="shake", target=target, protocol="time-history", kn=kn, ks=kn, increment_deg=None, motion=motion,
                   scale=scale, restitution="housner")
    summary = {"overturned": overturned, "max_rotation_rad": 1.4 if overturned else 0.01 * scale, "max_displacement_m": 0.0,
               "residual_displacement_m": 0.0, "pga_m_s2": 2.0 * scale, "motion_pga_m_s2": 2.0, "scale": scale, "motion": motion,
               "cycles": 100, "runtime_s": 1.0}
    return {"id": spec.id, "spec": asdict(spec), "status": "ok", "error": None, "summary": summary, "pushover": []}


def test_the_collapse_scale_is_the_smallest_that_overturned_and_larger_survivals_are_said(tmp_path):
    """A rocking block may survive above its minimum overturning intensity: the collapse is the
    smallest overturning scale, the survivals above it are listed, nothing is bisected."""
    records = [made_up(s, fell) for s, fell in ((0.5, False), (1.0, True), (1.5, False), (2.0, True))]
    records += [made_up(s, False, motion="/r/a.AT2") for s in (1.0, 2.0)]
    records += [made_up(s, s > 1.0, kn=1e8) for s in (1.0, 2.0)]
    curves = ida_curves(records + [made_up(3.0, True) | {"status": "failed"}])
    header, rows = collapse_table(curves)
    assert header[:3] == ["target", "record", "parameters"] and header[-1] == "larger scales survived"
    assert rows == [
        ["WD1", "a.AT2", "kn 1e+09, ks 1e+09", "2", "1, 2", "none up to 2", "none up to 4", "none up to 0.408", "-"],
        ["WD1", "one-sine 2 Hz", "kn 1e+08, ks 1e+08", "2", "1, 2", "2", "4", "0.408", "-"],
        ["WD1", "one-sine 2 Hz", "kn 1e+09, ks 1e+09", "2", "0.5, 1, 1.5, 2", "1", "2", "0.204", "1.5"],
    ]
    for record in records:
        write_record(tmp_path, record)
    text = build_report(tmp_path).markdown.read_text()
    assert "| WD1 | one-sine 2 Hz | kn 1e+09, ks 1e+09 | 2 | 0.5, 1, 1.5, 2 | 1 | 2 | 0.204 | 1.5 |" in text


def test_a_report_without_shake_runs_has_no_ida_section(tmp_path):
    from test_report import limit_record

    write_record(tmp_path, limit_record("WD2", "associative"))
    text = build_report(tmp_path).markdown.read_text()
    assert "IDA" not in text and not (tmp_path / "report" / "figures" / "ida_rotation.png").exists()
