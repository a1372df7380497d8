"""The report against hostile summaries: every field it reads is checked when a record is loaded
(types, finiteness, physical ranges), so that a bad record is named as corrupt, with its file,
field and rule, and left out, and the report is still written for the good ones; never a
traceback, never nonsense in a table."""

import csv
import json
import math

import pytest
from click.testing import CliRunner

from drydem.cli import main
from drydem.io.results import PUSHOVER_COLUMNS
from drydem.parametric.limits import MAX_SAMPLES
from drydem.parametric.study import RunSpec

#: the rows of the good runs in the report's tables of the user's runs
GOOD_TILT_ROW = "| pier.toml | kn 1e+08 Pa/m, ks 1e+08 Pa/m | 0.5 | 4 | fixed | 1 | 24.0 | 20.0 |"
GOOD_LIMIT_ROW = "| pier.toml | 0.5 | associative | 24.4 | 0.4545 |"
GOOD_MONTECARLO_ROW = "| WD1 | good | 3 | 18.00 | 1.00 | 5.0 | 17.00 |"


def tilt_summary() -> dict:
    """A ``drydem tilt`` summary of a pier (what the report reads of it)."""
    return {"target": "pier.toml", "collapse_angle_deg": 24.0, "load_multiplier": 0.4452, "last_equilibrium_deg": 24.0,
            "stable_under_gravity": True, "ended_by": "stop displacement", "drift_limit_angles_deg": {"0.005": 10.0, "0.01": 20.0},
            "wall_height_m": 0.055, "analysis": {"increment_deg": 1.0, "adaptive": False},
            "model": {"joint": {"kn": 1e8, "ks": 1e8, "friction": 0.5, "model": "constant"}, "contacts": {"points_per_length": 4}}}


def limit_summary() -> dict:
    """A ``drydem limit`` summary of the pier."""
    return {"target": "pier.toml", "collapse_angle_deg": 24.44, "load_multiplier": 0.4545, "method": "associative", "analysis": {},
            "model": {"joint": {"kn": 1e8, "ks": 1e8, "friction": 0.5, "model": "constant"}, "contacts": {"points_per_length": 4}}}


def changed(summary: dict, path: tuple, value) -> dict:
    """``summary`` with the field at ``path`` (keys, outermost first) set to ``value``."""
    table = summary
    for key in path[:-1]:
        table = table[key]
    table[path[-1]] = value
    return summary


def run_folder(results, name: str, summary: dict):
    """A run's folder ``results/name``: its summary.json (``summary`` as JSON text, or the text
    itself) and a tilt's pushover.csv; the summary's path."""
    folder = results / name
    folder.mkdir(parents=True)
    path = folder / "summary.json"
    path.write_text(summary if isinstance(summary, str) else json.dumps(summary))
    with (folder / "pushover.csv").open("w", newline="") as file:
        csv.writer(file).writerows([PUSHOVER_COLUMNS, *([t, 0.01 * t, 1e-4 * t, 0.0, 1e-4 * t / 0.055, 100] for t in range(25))])
    return path


def report(results) -> tuple[str, str]:
    """``drydem report results``: its stderr and the report's text (it must succeed, no traceback)."""
    result = CliRunner().invoke(main, ["report", str(results)])
    assert result.exit_code == 0 and result.exception is None, result.output
    assert "Traceback" not in result.stderr
    return result.stderr, (results / "report" / "report.md").read_text()


def assert_left_out(results, bad, message: str, good_row: str) -> str:
    """The report of ``results`` names ``bad`` as corrupt with ``message`` and holds the good run's ``good_row``."""
    stderr, text = report(results)
    assert f"corrupt record left out: {bad}: {message}" in stderr
    assert "1 runs recorded (0 failed)" in text and "1 corrupt records left out" in text and f"- `{bad}: {message}" in text
    assert good_row in text
    return text


BAD_TILT_FIELDS = {
    "string DLS angle": (("drift_limit_angles_deg", "0.01"), "abc", "summary drift_limit_angles_deg 0.01 = 'abc': must be a number in [0, 90] deg"),
    "list DLS angle": (("drift_limit_angles_deg", "0.01"), [1], "summary drift_limit_angles_deg 0.01 = [1]: must be a number in [0, 90] deg"),
    "string increment": (("analysis", "increment_deg"), "tiny", "summary analysis increment_deg = 'tiny': must be a number in (0, 90) deg"),
    "string adaptive": (("analysis", "adaptive"), "yes", "summary analysis adaptive = 'yes': must be true or false"),
    "string points": (("model", "contacts", "points_per_length"), "many",
                      "summary model contacts points_per_length = 'many': must be an integer in [1, 32]"),
    "boolean kn": (("model", "joint", "kn"), True, "summary model joint kn = True: must be a number in [1e+04, 1e+15] Pa/m"),
    "list joint law": (("model", "joint", "model"), ["power"], "summary model joint model = ['power']: must be one of"),
    "string lower bound": (("last_equilibrium_deg",), "x", "summary last_equilibrium_deg = 'x': must be a number in [0, 90] deg"),
    "string height": (("wall_height_m",), "tall", "summary wall_height_m = 'tall': must be a number in (0, 1e+04] m"),
    "negative height": (("wall_height_m",), -5, "summary wall_height_m = -5: must be a number in (0, 1e+04] m"),
    "overflowing angle": (("collapse_angle_deg",), 1e308, "summary collapse_angle_deg = 1e+308: must be a number in [0, 90] deg"),
    "string angle": (("collapse_angle_deg",), "26", "summary collapse_angle_deg = '26': must be a number in [0, 90] deg"),
    "string stability": (("stable_under_gravity",), "no", "summary stable_under_gravity = 'no': must be true or false"),
    # found by a hunt: these were taken, an ending the report's cells are drawn by
    "number ending": (("ended_by",), 5, "summary ended_by = 5: must be one of ('monitored block fell', 'monitored block toppled', "),
    "unknown ending": (("ended_by",), "fell over", "summary ended_by = 'fell over': must be one of"),
    "negative cycles": (("cycles",), -1, "summary cycles = -1: must be an integer in [0, inf)"),
    "fractional cycles": (("cycles",), 2.5, "summary cycles = 2.5: must be an integer in [0, inf)"),
    # found by a hunt: a Monte Carlo sample's angle edited to 42 beside its last equilibrium at 17 was averaged in
    "collapse past the last equilibrium": (("collapse_angle_deg",), 30.0, "summary collapse_angle_deg = 30: not the last "
                                                                           "equilibrium's tilt, 24 deg"),
}


@pytest.mark.parametrize("field", BAD_TILT_FIELDS)
def test_a_tilt_summary_with_a_bad_field_is_named_corrupt_and_left_out(tmp_path, field):
    path, value, message = BAD_TILT_FIELDS[field]
    run_folder(tmp_path, "good", tilt_summary())
    summary = changed(tilt_summary(), path, value)
    if field == "string lower bound":  # the field the report reads of a run without equilibrium
        summary |= {"ended_by": "no equilibrium within max_cycles", "collapse_angle_deg": None}
    bad = run_folder(tmp_path, "bad", summary)
    text = assert_left_out(tmp_path, bad, message, GOOD_TILT_ROW)
    assert "tilting runs: 1;" in text


@pytest.mark.parametrize("field, value, message", [
    ("method", 5, "summary method = 5: must be one of ('associative', 'non-associative')"),
    ("method", {"a": 1}, "summary method = {'a': 1}: must be one of ('associative', 'non-associative')"),
    ("load_multiplier", "x", "summary load_multiplier = 'x': must be a number in [0, inf)"),
    ("collapse_angle_deg", -3.0, "summary collapse_angle_deg = -3.0: must be a number in [0, 90] deg"),
], ids=["integer method", "table method", "string multiplier", "negative angle"])
def test_a_limit_summary_with_an_unknown_method_or_a_bad_number_is_named_corrupt_and_left_out(tmp_path, field, value, message):
    run_folder(tmp_path, "good", limit_summary())
    bad = run_folder(tmp_path, "bad", limit_summary() | {field: value})
    text = assert_left_out(tmp_path, bad, message, GOOD_LIMIT_ROW)
    assert "limit analyses: 1;" in text


def test_a_run_that_stood_to_its_maximum_angle_shows_as_no_collapse_up_to_it():
    # it showed as '-', which the legend explained only for the DLS column
    from drydem.report.study import angle_text

    stood = tilt_summary() | {"collapse_angle_deg": None, "last_equilibrium_deg": 10.0, "ended_by": "maximum angle"}
    assert angle_text(stood) == "none up to 10.0" and angle_text(tilt_summary()) == "24.0"


def test_a_link_to_a_run_folder_is_the_same_run_not_a_second(tmp_path):
    run_folder(tmp_path, "good", tilt_summary())
    (tmp_path / "link").symlink_to(tmp_path / "good")
    _, text = report(tmp_path)
    assert text.count(GOOD_TILT_ROW) == 1 and "tilting runs: 1;" in text


def test_a_pushover_csv_with_a_field_past_the_csv_limit_is_named_corrupt():
    # a 200,000-character field was a csv.Error traceback from drydem report
    import pathlib
    import tempfile

    from drydem.parametric.records import RecordError, _pushover_csv

    path = pathlib.Path(tempfile.mkdtemp()) / "pushover.csv"
    path.write_text(",".join(PUSHOVER_COLUMNS) + "\n" + '"' + "1" * 200_000 + '"\n')
    with pytest.raises(RecordError, match="pushover.csv: not a pushover curve"):
        _pushover_csv(path)


@pytest.mark.parametrize("content, message", [
    ("", "not a pushover curve"),
    (f"{','.join(PUSHOVER_COLUMNS)}\n0,0,nan,0,0,1\n", "pushover row 0 (0, nan, 0, 0, 1): the numbers must be finite"),
    (f"{','.join(PUSHOVER_COLUMNS)}\n1e300,0,0,0,0,1\n", "pushover row 0 (1e+300, 0, 0, 0, 1): the numbers must be finite, the tilt an angle in [0, 90] deg"),
    # found by a hunt: fractional cycles and rows in reverse order were drawn
    (f"{','.join(PUSHOVER_COLUMNS)}\n0,0,0,0,0,3.5\n", "pushover row 0 (0, 0, 0, 0, 3.5): the numbers must be finite, the tilt "
     "an angle in [0, 90] deg and the cycles a whole number"),
    (f"{','.join(PUSHOVER_COLUMNS)}\n1,0,0,0,0,1\n0,0,0,0,0,1\n", "pushover row 1: tilt 0 deg, not above the row before's 1: the tilts must increase"),
])
def test_a_pushover_csv_empty_or_with_a_nan_or_an_absurd_tilt_or_out_of_order_is_named_corrupt(tmp_path, content, message):
    """Found by a hunt: such a curve was counted and drawn as a run's, with no note."""
    run_folder(tmp_path, "good", tilt_summary())
    bad = run_folder(tmp_path, "bad", tilt_summary())
    (bad.parent / "pushover.csv").write_text(content)
    stderr, text = report(tmp_path)
    # the file named is the curve's (a hunt found its rows blamed on summary.json)
    assert f"corrupt record left out: {bad.parent / 'pushover.csv'}: " in stderr and message in stderr
    assert "1 runs recorded (0 failed)" in text and GOOD_TILT_ROW in text


def test_a_pushover_row_at_or_past_the_stop_displacement_is_named_corrupt(tmp_path):
    """A tilt ends where the monitored block reaches its stop displacement, at rest there or not
    (drydem.analysis.tilt.run), so no equilibrium row of pushover.csv is there (ux 1e-4 t m here)."""
    run_folder(tmp_path, "good", changed(tilt_summary(), ("analysis", "stop_displacement_m"), 0.1))
    bad = run_folder(tmp_path, "past", changed(tilt_summary(), ("analysis", "stop_displacement_m"), 0.001))
    stderr, text = report(tmp_path)
    assert (f"corrupt record left out: {bad.parent / 'pushover.csv'}: pushover row 10: ux 0.001 m, at or past the run's stop "
            "displacement 0.001 m, where it ended: no equilibrium is recorded there") in stderr
    assert "1 runs recorded (0 failed)" in text and GOOD_TILT_ROW in text


def test_a_pushover_csv_cut_short_of_the_summary_s_equilibria_is_named_corrupt(tmp_path):
    """Found by a hunt: a pushover.csv cut to 49 of its 201 rows was drawn up to 4.8 deg beside
    tables saying 20.0 deg. The summary records one row per equilibrium state (25 here)."""
    run_folder(tmp_path, "good", tilt_summary() | {"equilibrium_states": 25})
    bad = run_folder(tmp_path, "cut", tilt_summary() | {"equilibrium_states": 201})
    stderr, text = report(tmp_path)
    assert (f"corrupt record left out: {bad.parent / 'pushover.csv'}: 25 rows, where summary.json records 201 equilibrium states "
            "(one row each): cut short or edited by hand?") in stderr
    assert "1 runs recorded (0 failed)" in text and GOOD_TILT_ROW in text


def test_a_pushover_csv_ending_before_the_summary_s_last_equilibrium_is_named_corrupt(tmp_path):
    """The curve's rows are the equilibria, so its last is the last equilibrium (24 deg here)."""
    run_folder(tmp_path, "good", tilt_summary())
    bad = run_folder(tmp_path, "edited", tilt_summary() | {"last_equilibrium_deg": 30.0, "collapse_angle_deg": 30.0})
    stderr, text = report(tmp_path)
    assert (f"corrupt record left out: {bad.parent / 'pushover.csv'}: its last row is at 24 deg, where summary.json records the "
            "last equilibrium at 30 deg: cut short or edited by hand?") in stderr
    assert "1 runs recorded (0 failed)" in text and GOOD_TILT_ROW in text


def test_a_run_made_with_a_step_below_today_s_least_is_still_a_result():
    # the least tilt step became 0.001 deg; a run recorded before with 1e-4 deg is no corrupt record
    from drydem.parametric.records import collapse_problem

    assert collapse_problem("tilt", changed(tilt_summary(), ("analysis", "increment_deg"), 1e-4)) is None


def test_a_limit_analysis_with_cohesion_may_find_any_multiplier_and_is_reported(tmp_path):
    """Cohesion 1e8 Pa on light blocks gives lambda ~ 1e8 (collapse angle ~90 deg): a result, no corrupt record."""
    run_folder(tmp_path, "strong", limit_summary() | {"load_multiplier": 1.02e8, "collapse_angle_deg": 89.9999994})
    stderr, text = report(tmp_path)
    assert "corrupt" not in stderr + text and "| associative | 90.0 | 1.02e+08 |" in text  # 4 significant digits, not 102000000.0000


def sweep_record(spec: dict, run_id: str | None = None, **summary) -> dict:
    """A sweep's record of a made-up tilting run of ``spec`` (RunSpec's fields), named ``run_id``
    (default: the spec's id), its summary changed by ``summary``."""
    return {"id": run_id or RunSpec(**spec).id, "spec": spec, "status": "ok", "error": None, "pushover": [[0.0, 0.0, 0.0, 0.0, 10]],
            "summary": {"collapse_angle_deg": 20.0, "drift_limit_angles_deg": {"0.01": 10.0}, "wall_height_m": 0.1} | summary}


PIER = {"analysis": "tilt", "target": "pier.toml", "protocol": "fixed"}


@pytest.mark.parametrize("record, message", [
    ({"status": ["ok"], "id": "x"}, "status = ['ok']: must be one of ['ok', 'failed']"),
    (sweep_record(PIER | {"points": "many"}), "spec points = 'many': must be an integer in [1, 32]"),
    (sweep_record(PIER | {"protocol": ["fixed"]}), "spec protocol = ['fixed']: must be the name of a protocol (a string)"),
    (sweep_record(PIER | {"joint_law": "[1]"}, "x"), "spec is not the parameters of a run ('list' object has no attribute 'get')"),
    (sweep_record(PIER, wall_height_m=-5), "summary wall_height_m = -5: must be a number in (0, 1e+04] m"),
    ({"id": RunSpec(**PIER, friction="rough").id, "spec": PIER | {"friction": "rough"}, "status": "failed", "error": "ModelError: made up"},
     "spec friction = 'rough': must be a number or null"),
], ids=["list status", "string points", "list protocol", "list joint law", "negative height", "failed with a string friction"])
def test_a_sweep_record_with_a_bad_field_is_named_corrupt_and_left_out(tmp_path, record, message):
    run_folder(tmp_path, "good", tilt_summary())
    bad = tmp_path / "runs" / f"{record['id']}.json"
    bad.parent.mkdir()
    bad.write_text(json.dumps(record))
    assert_left_out(tmp_path, bad, message, GOOD_TILT_ROW)


def test_a_failed_run_whose_parameters_failed_it_is_no_corrupt_record(tmp_path):
    """Its parameters out of their ranges are why it failed: named with its error, not run again."""
    spec = RunSpec(**PIER, kn=-1.0, ks=-1.0)
    failed = {"id": spec.id, "spec": spec.__dict__, "status": "failed", "error": "ModelError: [joint] kn = -1.0: must be a number in"}
    (tmp_path / "runs").mkdir()
    (tmp_path / "runs" / f"{spec.id}.json").write_text(json.dumps(failed))
    stderr, text = report(tmp_path)
    assert "corrupt" not in stderr + text and "1 failed" in text
    assert f"- `{spec.id}`: ModelError: [joint] kn = -1.0: must be a number in" in text


DEEP = "[" * 200_000 + "]" * 200_000


def test_json_nested_too_deep_is_named_corrupt_not_a_recursion_error(tmp_path):
    run_folder(tmp_path, "good", tilt_summary())
    bad_summary = run_folder(tmp_path, "deep", DEEP)
    bad_record = tmp_path / "runs" / "x.json"
    bad_record.parent.mkdir()
    bad_record.write_text(DEEP)
    stderr, text = report(tmp_path)
    assert f"corrupt record left out: {bad_summary}: not a summary: JSON nested deeper than" in stderr
    assert f"corrupt record left out: {bad_record}: not a record: JSON nested deeper than" in stderr
    assert "1 runs recorded (0 failed)" in text and "2 corrupt records left out" in text and GOOD_TILT_ROW in text


def montecarlo_summary(results, name: str, **statistics):
    """A ``drydem montecarlo`` summary of WD1 in results/montecarlo/NAME (its statistics changed by ``statistics``); its path."""
    path = results / "montecarlo" / name / "summary.json"
    path.parent.mkdir(parents=True)
    stats = {"count": 3, "mean": 18.0, "std": 1.0, "cov": 0.05, "p05": 17.0} | statistics
    path.write_text(json.dumps({"target": {"name": "WD1"}, "collapse_angle_deg": stats, "settings": {"imperfections": {}}}))
    return path


@pytest.mark.parametrize("statistics, message", [
    ({"count": 10**400}, "collapse_angle_deg count = 1000"),
    ({"count": "3"}, f"collapse_angle_deg count = '3': must be an integer in [0, {MAX_SAMPLES:.4g}]"),
    ({"count": -1}, f"collapse_angle_deg count = -1: must be an integer in [0, {MAX_SAMPLES:.4g}]"),
    ({"mean": 1e308}, "collapse_angle_deg mean = 1e+308: must be a number in [0, 90] deg"),
    ({"cov": float("nan")}, f"collapse_angle_deg cov = nan: must be a number in [0, {math.sqrt(MAX_SAMPLES):.4g}]"),
], ids=["huge count", "string count", "negative count", "overflowing mean", "NaN CoV"])
def test_a_montecarlo_summary_with_a_bad_statistic_is_named_and_left_out(tmp_path, statistics, message):
    montecarlo_summary(tmp_path, "good")
    bad = montecarlo_summary(tmp_path, "bad", **statistics)
    _, text = report(tmp_path)
    assert f"1 Monte Carlo summaries cannot be read, left out:\n\n- `{bad}: {message}" in text
    assert GOOD_MONTECARLO_ROW in text and "| bad |" not in text


def test_a_montecarlo_summary_without_some_statistics_shows_them_as_none(tmp_path):
    """A run of one sample has no std, CoV or p05 (null); a summary may leave them out as well."""
    path = montecarlo_summary(tmp_path, "one")
    path.write_text(json.dumps(json.loads(path.read_text()) | {"collapse_angle_deg": {"count": 1, "mean": 18.0}}))
    stderr, text = report(tmp_path)
    assert "cannot be read" not in text and "Traceback" not in stderr and "| WD1 | one | 1 | 18.00 | - | - | - |" in text


def test_a_montecarlo_summary_nested_too_deep_or_with_bad_imperfections_is_named_and_left_out(tmp_path):
    montecarlo_summary(tmp_path, "good")
    deep = tmp_path / "montecarlo" / "deep" / "summary.json"
    deep.parent.mkdir()
    deep.write_text(DEEP)
    odd = montecarlo_summary(tmp_path, "odd")
    odd.write_text(json.dumps(json.loads(odd.read_text()) | {"settings": {"imperfections": {"height_sd_mm": -1}}}))
    _, text = report(tmp_path)
    assert "2 Monte Carlo summaries cannot be read, left out:" in text
    assert f"- `{deep}: not a Monte Carlo summary: JSON nested deeper than" in text
    assert f"- `{odd}: settings imperfections: imperfections height_sd_mm = -1: must be a number in" in text
    assert GOOD_MONTECARLO_ROW in text


@pytest.mark.parametrize("name", ["report.md", "report.html"])
def test_a_report_file_drydem_did_not_write_is_kept_unless_overwrite(tmp_path, name):
    # drydem's own earlier report is made again from the records; a file of its name that it
    # did not write (it does not begin as drydem's does) was silently replaced
    run_folder(tmp_path, "good", limit_summary())
    report(tmp_path)
    report(tmp_path)  # its own report, replaced without asking
    mine = tmp_path / "report" / name
    mine.write_text("my notes\n")
    refused = CliRunner().invoke(main, ["report", str(tmp_path)])
    assert refused.exit_code == 1 and f"{mine}: exists; pass --overwrite to replace it, or another --out" in refused.output
    assert mine.read_text() == "my notes\n"
    replaced = CliRunner().invoke(main, ["report", str(tmp_path), "--overwrite"])
    assert replaced.exit_code == 0, replaced.output
    assert mine.read_text() != "my notes\n"


def test_a_figures_folder_of_no_drydem_report_is_kept_unless_overwrite(tmp_path):
    """Found by a hunt: report.md and report.html were kept, but a file of a figure's name in
    OUT/figures was silently replaced."""
    run_folder(tmp_path, "good", limit_summary())
    figures = tmp_path / "report" / "figures"
    figures.mkdir(parents=True)
    (figures / "mine.png").write_bytes(b"my picture")
    refused = CliRunner().invoke(main, ["report", str(tmp_path)])
    assert refused.exit_code == 1 and f"{figures}: holds files of no drydem report (mine.png); pass --overwrite" in refused.output
    assert sorted(p.name for p in figures.iterdir()) == ["mine.png"] and not (tmp_path / "report" / "report.md").exists()
    assert CliRunner().invoke(main, ["report", str(tmp_path), "--overwrite"]).exit_code == 0
    assert (figures / "mine.png").read_bytes() == b"my picture"  # another name: kept beside the report's figures
    assert CliRunner().invoke(main, ["report", str(tmp_path)]).exit_code == 0  # its own report now: made again


@pytest.mark.parametrize("text, kind", [("[1, 2]", "list"), ("null", "null"), ('"a string"', "str")])
def test_a_summary_that_is_not_a_json_object_is_named_corrupt(tmp_path, text, kind):
    # it was taken for another analysis' summary and skipped: with no other run, "nothing to report"
    run_folder(tmp_path, "good", limit_summary())
    bad = run_folder(tmp_path, "bad", text)
    assert_left_out(tmp_path, bad, f"not a drydem summary: its JSON is {kind}, not an object", GOOD_LIMIT_ROW)


def test_a_report_of_corrupt_records_only_is_written_and_exits_non_zero(tmp_path):
    # it exited 0 with "0 runs recorded": a script took it for a report
    bad = run_folder(tmp_path, "bad", limit_summary() | {"load_multiplier": "abc"})
    result = CliRunner().invoke(main, ["report", str(tmp_path)])
    assert result.exit_code == 1 and "Traceback" not in result.output
    assert f"corrupt record left out: {bad}" in result.output
    assert f"every record of {tmp_path} is corrupt (1, named above and in the report): the report holds no run" in result.output
    assert "0 runs recorded" in (tmp_path / "report" / "report.md").read_text()


def test_a_summary_naming_a_key_twice_is_named_corrupt(tmp_path):
    """Found by a hunt: Python's json keeps the last of two equal keys, so a collapse angle
    appended to a summary replaced the run's in the tables."""
    run_folder(tmp_path, "good", tilt_summary())
    bad = run_folder(tmp_path, "bad", json.dumps(tilt_summary())[:-1] + ', "collapse_angle_deg": 3.0}')
    stderr, text = report(tmp_path)
    assert f"corrupt record left out: {bad}: not a summary drydem wrote: the key 'collapse_angle_deg' is given twice" in stderr
    assert "1 runs recorded (0 failed)" in text and GOOD_TILT_ROW in text


@pytest.mark.parametrize("change, message", [
    ({"analysis": {"increment_deg": 1.0, "adaptive": False, "tilt_axis": "z"}}, "summary analysis tilt_axis = 'z': must be one of"),
    ({"analysis": {"increment_deg": 1.0, "adaptive": False, "loading": "gravity"}}, "summary analysis loading = 'gravity': must be one of"),
    ({"drift_limit_angles_deg": {"0.005": 10.0, "0.01": 89.0}},
     "summary drift_limit_angles_deg 0.01 = 89: above the last equilibrium, 24 deg (a drift limit is reached at an equilibrium)"),
], ids=["tilt-axis", "loading", "drift-limit"])
def test_a_summary_whose_settings_or_drift_limits_drydem_cannot_have_written_is_named_corrupt(tmp_path, change, message):
    """Found by a hunt: a tilt_axis "z", a loading "gravity" and a drift limit reached at 89 deg
    beside a collapse at 24 were tabled."""
    run_folder(tmp_path, "good", tilt_summary())
    bad = run_folder(tmp_path, "bad", tilt_summary() | change)
    stderr, text = report(tmp_path)
    assert f"corrupt record left out: {bad}: " in stderr and message in stderr
    assert "1 runs recorded (0 failed)" in text and GOOD_TILT_ROW in text
