"""A run's record on disk: ``RESULTS/runs/ID.json``, written atomically as soon as the run
finishes, holds the parameters, the status ("ok" or "failed" with the error), the summary and
the pushover curve (empty for limit and shake runs). A record is checked when it is read: one
that is not JSON, lacks a key, whose parameters do not give its id, or whose fields that the
report reads break their rules (types, finiteness, physical ranges: :data:`SUMMARY_RULES`,
:data:`SPEC_RULES`) is corrupt (:class:`RecordError`), and a sweep runs it again.

The folder of a ``drydem tilt`` or ``drydem limit`` run (``--out``, by default
``results/TARGET-TIME``) reads as a record too (:func:`run_folder_record`): so that a report
holds the runs made one by one beside a sweep's.
"""

from __future__ import annotations

import csv
import json
import math
import os
import sys
from collections.abc import Collection, Mapping
from dataclasses import asdict, dataclass, field
from pathlib import Path
from types import SimpleNamespace

from drydem.analysis.drift import drift_limit_angles, drifts
from drydem.analysis.tilt.settings import ENDINGS, LOADINGS, TILT_AXES
from drydem.errors import DrydemError, ModelError
from drydem.files import regular_file
from drydem.model.parameters import FLAG, FRICTION, JOINT_RULES, JOINT_STIFFNESS, POINTS, OneOf, Range, Rule, field_problems
from drydem.parametric.study import ANALYSES, RunSpec, joint_law_text


class RecordError(DrydemError):
    """A run record that cannot be used (unreadable, not JSON, incomplete, or not its run's);
    the message names the file and what is wrong."""


def record_path(results: Path, run_id: str) -> Path:
    return Path(results) / "runs" / f"{run_id}.json"


def write_record(results: Path, record: dict) -> Path:
    """Write a run's record atomically: a temporary file, flushed to the disk, renamed over the
    final one, so that a crash (or a power cut) leaves the old record or the new, not a part."""
    path = record_path(results, record["id"])
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f"{path.name}.{os.getpid()}.tmp")
    with open(tmp, "w", encoding="utf-8") as file:
        file.write(json.dumps(record, indent=1) + "\n")
        file.flush()
        os.fsync(file.fileno())
    os.replace(tmp, path)
    return path


#: the keys of a record, by status, and of its summary, by analysis: what the report and the
#: calibration read (a record without them is corrupt)
RECORD_KEYS = {"ok": {"id", "spec", "status", "summary", "pushover"}, "failed": {"id", "spec", "status", "error"}}
SUMMARY_KEYS = {"tilt": {"collapse_angle_deg", "drift_limit_angles_deg", "wall_height_m"}, "limit": {"collapse_angle_deg", "method"},
                "shake": {"overturned", "max_rotation_rad", "max_displacement_m", "residual_displacement_m", "pga_m_s2", "scale",
                          "motion", "cycles", "runtime_s"}}
#: the numbers of a shake run's summary (m, rad, m/s2, s), and the motion's PGA before its scale
#: (optional), as a run records them:
#: finite, a rotation an angle turned (at most pi), the scale > 0, the rest >= 0 (found by a
#: hunt: a PGA of Infinity made the IDA table say "none up to inf", a rotation of 1e308
#: overflowed in the figure, NaN and -1 were drawn)
SHAKE_RULES = {"max_rotation_rad": Range(0.0, math.pi, unit="rad"), "max_displacement_m": Range(0.0, None, unit="m"),
               "residual_displacement_m": Range(0.0, None, unit="m"), "pga_m_s2": Range(0.0, None, unit="m/s2"),
               "scale": Range(0.0, None, low_open=True), "runtime_s": Range(0.0, None, unit="s"),
               "motion_pga_m_s2": Range(0.0, None, unit="m/s2")}
#: the columns of a pushover curve: tilt (deg), ux, uz (m), drift, cycles
CURVE_COLUMNS = 5
#: a tilting run's angles and a limit analysis' (atan of its multiplier), deg: a tilting table
#: turns below 90 deg (TiltSettings' max_angle_deg), and no angle is negative
ANGLE = Range(0.0, 90.0, unit="deg")
#: the lateral load multiplier at collapse, tan of the collapse angle: a number >= 0, with no
#: bound above (a limit analysis with cohesion or tension finds any multiplier: 1e8 for
#: cohesion 1e8 Pa on light blocks)
LOAD_MULTIPLIER = Range(0.0, None)
#: the height a wall's drift is measured against, m: > 0, and 1e4 m is above any structure (the tallest, 828 m)
HEIGHT = Range(0.0, 1e4, low_open=True, unit="m")
#: the rules of the fields of a tilt or limit summary the report reads (:mod:`drydem.report.study`);
#: each may be null or absent (no value) but those of :data:`SUMMARY_NOT_NULL`
SUMMARY_RULES = {"tilt": {"collapse_angle_deg": ANGLE, "last_equilibrium_deg": ANGLE, "load_multiplier": LOAD_MULTIPLIER,
                          "stable_under_gravity": FLAG, "wall_height_m": HEIGHT, "ended_by": OneOf(ENDINGS),
                          "cycles": Range(0, None, integer=True)},
                 "limit": {"collapse_angle_deg": ANGLE, "load_multiplier": LOAD_MULTIPLIER, "method": OneOf(ANALYSES["limit"])}}
SUMMARY_NOT_NULL = ("wall_height_m", "method")
#: deg: a recorded run's tilt step, in (0, 90): runs made before the least step of
#: drydem.analysis.tilt.settings.SETTING_RANGES (0.001 deg) are results still
RECORDED_INCREMENT = Range(0.0, 90.0, low_open=True, high_open=True, unit="deg")
#: the rules of a tilt summary's settings (``analysis``) that a run folder's record takes
TILT_SETTING_RULES = {"increment_deg": RECORDED_INCREMENT, "adaptive": FLAG, "tilt_axis": OneOf(TILT_AXES), "loading": OneOf(LOADINGS)}
#: the rules of the tables of a summary's model (:func:`drydem.io.results.model_summary`) the
#: report reads: the joint's (kn, ks and friction never null; its law's fields where given) and
#: the contacts' points per length (null: not recorded)
MODEL_RULES = {"joint": JOINT_RULES, "contacts": {"points_per_length": POINTS}}
MODEL_NOT_NULL = ("kn", "ks", "friction")
#: the rules of a finished run's parameters (:class:`RunSpec`; each null: the target's own), those
#: its model obeyed (every analysis) and its tilting settings (a tilting run's increment alone)
SPEC_RULES = {"kn": JOINT_STIFFNESS, "ks": JOINT_STIFFNESS, "friction": FRICTION, "points": POINTS,
              "increment_deg": RECORDED_INCREMENT}


def read_record(path: str | Path) -> dict:
    """The record in ``path``, checked: a JSON object whose id is the file's name and the id of
    its parameters, with the keys of its status (RECORD_KEYS, SUMMARY_KEYS). RecordError naming
    the file and what is wrong otherwise (a sweep killed while writing one without the atomic
    write, a disk full, a hand edit)."""
    path = Path(path)
    record = read_json(path, "record")
    problem = _record_problem(record, path.name.removesuffix(".json"))
    if problem is not None:
        raise RecordError(f"{path}: {problem}")
    return record


def read_json(path: Path, what: str):
    """The JSON in ``path``, a run's ``what`` (record, summary); RecordError naming the file if it
    cannot be read, is not JSON (a run killed while writing it without the atomic write, a hand
    edit) or is nested deeper than Python's recursion limit (no file drydem writes is)."""
    try:
        text = regular_file(path, f"a drydem {what}").read_text(encoding="utf-8")  # a pipe would hang
        return json.loads(text, object_pairs_hook=_unique_keys)
    except _RepeatedKey as exc:
        raise RecordError(f"{path}: not a {what} drydem wrote: {exc}") from None
    except ModelError as exc:
        raise RecordError(str(exc)) from None
    except OSError as exc:
        raise RecordError(f"{path}: cannot read the {what} ({exc.strerror})") from None
    except ValueError as exc:  # not JSON, or not UTF-8
        raise RecordError(f"{path}: not a JSON {what}, empty or cut short? ({exc})") from None
    except RecursionError:
        raise RecordError(f"{path}: not a {what}: JSON nested deeper than {sys.getrecursionlimit()} levels") from None


class _RepeatedKey(ValueError):
    """A JSON object names a key twice (Python's json keeps the last: found by a hunt, a
    collapse angle appended to a summary replaced the run's)."""


def _unique_keys(pairs: list[tuple[str, object]]) -> dict:
    """The JSON object of ``pairs``; _RepeatedKey if a key is given twice."""
    table = {}
    for key, value in pairs:
        if key in table:
            raise _RepeatedKey(f"the key {key!r} is given twice")
        table[key] = value
    return table


def table_problems(table: Mapping, rules: Mapping[str, Rule], where: str, *, optional: Collection[str] = ()) -> list[str]:
    """``WHERE FIELD = VALUE: must be ...`` for every field of the JSON object ``table`` named in
    ``rules`` that breaks its rule (:func:`~drydem.model.parameters.field_problems`); a field in
    ``optional`` may also be null or absent."""
    values = SimpleNamespace(**{field: table.get(field) for field in rules})
    return field_problems(values, rules, lambda field: f"{where} {field}", optional=optional)


def _record_problem(record, run_id: str) -> str | None:
    """What is wrong with ``record`` as the record of run ``run_id``, or None."""
    if not isinstance(record, dict):
        return f"a record is a JSON object, not {type(record).__name__}"
    status = record.get("status")
    if status not in OneOf(tuple(RECORD_KEYS)):
        return f"status = {status!r}: must be one of {list(RECORD_KEYS)}"
    missing = sorted(RECORD_KEYS[status] - set(record))
    if missing:
        return f"a {status!r} record without {missing}"
    if record["id"] != run_id:
        return f"its id {record['id']!r} is not its file's name"
    inputs = record.get("inputs", {})
    if not (isinstance(inputs, dict) and all(isinstance(k, str) and isinstance(v, str) for k, v in inputs.items())):
        return "inputs must be a table of the files the run read, each with the SHA-256 of its content (a text)"
    try:
        spec = RunSpec(**record["spec"])
        spec_id = spec.id
    except (TypeError, ValueError, AttributeError) as exc:  # AttributeError: a joint law that is not a JSON object
        return f"spec is not the parameters of a run ({exc})"
    if spec_id != run_id:
        return f"its parameters are those of run {spec_id!r}, not of {run_id!r}"
    problem = _spec_problem(spec, status)
    if problem is not None:
        return problem
    if status == "failed":
        return None if isinstance(record["error"], str) else "error must be the run's error message"
    return _result_problem(spec, record["summary"], record["pushover"])


def _spec_problem(spec: RunSpec, status: str) -> str | None:
    """What is wrong with a run's parameters, or None: its analysis one of :data:`ANALYSES`, its
    protocol a name; a finished run's within :data:`SPEC_RULES` (those it ran with), a failed
    run's numbers or null (they may be those that failed it: run again, they would fail again)."""
    if spec.analysis not in OneOf(tuple(ANALYSES)):
        return f"spec analysis = {spec.analysis!r}: must be one of {list(ANALYSES)}"
    if not isinstance(spec.protocol, str):
        return f"spec protocol = {spec.protocol!r}: must be the name of a protocol (a string)"
    ranged = {} if status == "failed" else {k: v for k, v in SPEC_RULES.items() if k != "increment_deg" or spec.analysis == "tilt"}
    problems = field_problems(spec, ranged, lambda field: f"spec {field}", optional=ranged)
    numbers = [key for key in SPEC_RULES if key not in ranged and not (getattr(spec, key) is None or _numeric(getattr(spec, key)))]
    problems += [f"spec {key} = {getattr(spec, key)!r}: must be a number or null" for key in numbers]
    return "; ".join(problems) or None


def _result_problem(spec: RunSpec, summary, curve) -> str | None:
    """What is wrong with the ``summary`` and pushover ``curve`` of a finished run of ``spec``, or None."""
    if not isinstance(summary, dict) or not SUMMARY_KEYS[spec.analysis] <= set(summary):
        return f"summary must hold {sorted(SUMMARY_KEYS[spec.analysis])}"
    problem = _shake_problem(spec, summary) if spec.analysis == "shake" else collapse_problem(spec.analysis, summary)
    if problem is not None:
        return problem
    return _curve_problem(curve)


#: deg: how far a summary's drift-limit angle may lie from the one its pushover curve gives (the
#: curve's rows in pushover.csv keep 8 digits; a drift measured from as drawn moved WD1's by 0.46 deg)
DRIFT_ANGLE_SLACK_DEG = 1e-3


def drift_problem(summary: dict, curve: list) -> str | None:
    """What is wrong with a tilt summary's drift-limit angles, or None: each must be the angle its
    pushover ``curve`` (rows tilt, ux, ...) gives, within :data:`DRIFT_ANGLE_SLACK_DEG`, the drift
    measured from the curve's first row, the equilibrium under the wall's own weight
    (:class:`drydem.analysis.tilt.Record`; found by a review: a Monte Carlo run resumed on samples
    of a drydem that measured it from as drawn mixed the two in its statistics). A summary
    without a height, or a limit that is no number, is left to the other checks."""
    angles, height = summary.get("drift_limit_angles_deg"), summary.get("wall_height_m")
    if not curve or not isinstance(angles, dict) or not (_numeric(height) and height > 0):
        return None
    try:
        limits = [float(limit) for limit in angles]
        found = drift_limit_angles([row[0] for row in curve], drifts([row[1] for row in curve], height), tuple(limits))
    except (ValueError, ModelError):
        return None
    for (limit, given), expected in zip(angles.items(), (found[value] for value in limits)):
        if (given is None) != (expected is None) or (expected is not None and abs(given - expected) > DRIFT_ANGLE_SLACK_DEG):
            shown = "not reached" if expected is None else f"{expected:.4f} deg"
            return (f"summary drift_limit_angles_deg {limit} = {given}: its pushover curve gives {shown}, the drift measured "
                    "from the equilibrium at 0 deg (written by a drydem that measured it from as drawn, or edited): run it again")
    return None


def _curve_problem(curve) -> str | None:
    """What is wrong with a finished run's pushover ``curve``, or None: rows of
    :data:`CURVE_COLUMNS` finite numbers, the tilt an :data:`ANGLE` and the cycles none or more (a
    NaN was drawn and tabled as a run's)."""
    if not isinstance(curve, list) or not all(isinstance(row, list) and len(row) == CURVE_COLUMNS and all(map(_numeric, row)) for row in curve):
        return f"pushover must be a list of rows of {CURVE_COLUMNS} numbers (tilt, ux, uz, drift, cycles)"
    for k, (tilt, ux, uz, drift, cycles) in enumerate(curve):
        if not all(map(math.isfinite, (tilt, ux, uz, drift, cycles))) or tilt not in ANGLE or cycles < 0 or cycles % 1:
            row = ", ".join(f"{value:g}" for value in (tilt, ux, uz, drift, cycles))
            return (f"pushover row {k} ({row}): the numbers must be finite, the tilt an angle in [0, 90] "
                    "deg and the cycles a whole number, none or more")
        if k and tilt <= curve[k - 1][0]:  # found by a hunt: rows in reverse order were drawn
            return f"pushover row {k}: tilt {tilt:g} deg, not above the row before's {curve[k - 1][0]:g}: the tilts must increase"
    return None


def _shake_problem(spec: RunSpec, summary: dict) -> str | None:
    """What is wrong with a shake run's spec and summary (the report reads them), or None."""
    if not isinstance(spec.motion, str) or not (_numeric(spec.scale) and spec.scale > 0):
        return f"spec motion = {spec.motion!r}, scale = {spec.scale!r}: a shake run has a motion (a string) and a scale (> 0)"
    if not isinstance(summary["overturned"], bool):
        return f"summary overturned = {summary['overturned']!r}: must be true or false"
    problems = table_problems(summary, SHAKE_RULES, "summary", optional=("motion_pga_m_s2",))
    if problems:
        return "; ".join(problems)
    if not (isinstance(summary["cycles"], int) and not isinstance(summary["cycles"], bool) and summary["cycles"] >= 0):
        return f"summary cycles = {summary['cycles']!r}: must be a whole number >= 0"
    if not isinstance(summary["motion"], str):
        return f"summary motion = {summary['motion']!r}: must be the run's motion (a string)"
    return None


def collapse_problem(analysis: str, summary: dict) -> str | None:
    """What is wrong with what the report reads of a tilt or limit ``summary``, or None: its fields
    within :data:`SUMMARY_RULES` (angles in [0, 90] deg, a height > 0, a known method, ...), a
    tilt's drift limit angles and settings (:func:`_tilt_problems`) and its model's (:func:`_model_problems`)."""
    optional = set(SUMMARY_RULES[analysis]) - set(SUMMARY_NOT_NULL)
    problems = table_problems(summary, SUMMARY_RULES[analysis], "summary", optional=optional)
    problems += (_tilt_problems(summary) if analysis == "tilt" else []) + _model_problems(summary.get("model"))
    return "; ".join(problems) or None


def _tilt_problems(summary: dict) -> list[str]:
    """The problems of a tilt summary beyond :data:`SUMMARY_RULES`: each drift limit's angle in
    [0, 90] deg or null (never reached), and at most the last equilibrium's (a limit is reached at
    an equilibrium; found by a hunt: one at 89 deg beside a collapse at 25 was tabled); the
    settings within :data:`TILT_SETTING_RULES` (a tilt_axis "z" was taken); a collapse angle that
    is not the last equilibrium's tilt."""
    drift = summary["drift_limit_angles_deg"]
    if not isinstance(drift, dict):
        return ["summary drift_limit_angles_deg must map drift limits to angles"]
    problems = table_problems(drift, dict.fromkeys(drift, ANGLE), "summary drift_limit_angles_deg", optional=drift)
    last, collapse = summary.get("last_equilibrium_deg"), summary.get("collapse_angle_deg")
    if not problems and _numeric(last):
        problems = [f"summary drift_limit_angles_deg {limit} = {angle:g}: above the last equilibrium, {last:g} deg (a drift limit is "
                    "reached at an equilibrium)" for limit, angle in drift.items() if angle is not None and angle > last + 1e-9]
    if not problems and _numeric(last) and _numeric(collapse) and abs(collapse - last) > 1e-9:  # found by a hunt: 42 beside 17 was averaged
        problems = [f"summary collapse_angle_deg = {collapse:g}: not the last equilibrium's tilt, {last:g} deg (a tilt that collapses "
                    "does so in the step after its last equilibrium, and is given that equilibrium's tilt)"]
    settings = summary.get("analysis", {})
    if not isinstance(settings, dict):
        return [*problems, "summary analysis must be the tilting settings (a table)"]
    return problems + table_problems(settings, TILT_SETTING_RULES, "summary analysis", optional=TILT_SETTING_RULES)


def _model_problems(model) -> list[str]:
    """The problems of the model a summary records (none without one): its joint and contacts
    tables, where given, within :data:`MODEL_RULES` (the joint's kn, ks and friction never null)."""
    if model is None:
        return []
    if not (isinstance(model, dict) and all(isinstance(model.get(table, {}), dict) for table in MODEL_RULES)):
        return ["summary model must be a table, and its joint and contacts tables"]
    return [problem for table, rules in MODEL_RULES.items() if table in model
            for problem in table_problems(model[table], rules, f"summary model {table}", optional=set(rules) - set(MODEL_NOT_NULL))]


def _numeric(value) -> bool:
    """An int or float (not a boolean); NaN and infinities are numbers a run may record."""
    return isinstance(value, (int, float)) and not isinstance(value, bool)


@dataclass(frozen=True)
class Records:
    """The records of a results folder: ``valid`` ones, and the ``corrupt`` ones' errors (each
    naming its file), left out; and the run folders of other analyses (``other``: a shake's, a
    Monte Carlo run's), which hold no record."""

    valid: list[dict]
    corrupt: list[RecordError]
    other: list[Path] = field(default_factory=list)


def load_records(results: Path) -> Records:
    """Every record in ``results/runs`` (in name order), checked by :func:`read_record`."""
    valid, corrupt = [], []
    for path in sorted((Path(results) / "runs").glob("*.json")):
        try:
            valid.append(read_record(path))
        except RecordError as exc:
            corrupt.append(exc)
    return Records(valid, corrupt)


#: a run folder's files: the summary (written when the run ends) and a tilt's pushover curve
#: (:data:`drydem.io.results.PUSHOVER_COLUMNS`: tilt_deg, load_multiplier, ux_m, uz_m, drift, cycles)
SUMMARY_FILE, PUSHOVER_FILE = "summary.json", "pushover.csv"
#: the pushover.csv columns a record's curve keeps (:data:`CURVE_COLUMNS`: tilt, ux, uz, drift, cycles)
CURVE_FROM_CSV = (0, 2, 3, 4, 5)
#: the keys of a summary's joint table that are not a joint law's (:attr:`RunSpec.joint_law`)
NOT_LAW_KEYS = {"kn", "ks", "friction", "cohesion", "tension"}


def run_folder_record(folder: Path) -> dict | None:
    """The folder of a ``drydem tilt`` or ``drydem limit`` run as an ok record: id the folder's
    name; spec its target (the summary's, else its model's source), protocol, and the joint and
    contact settings its model records (kn, ks, friction, points, joint law); its summary; a
    tilt's curve from pushover.csv. None for a folder without summary.json (no run, or one not
    finished) or of another analysis (a shake or Monte Carlo run's). RecordError naming the file
    that cannot be read or is not what the run writes."""
    path = Path(folder) / SUMMARY_FILE
    if not path.is_file():
        return None
    summary = read_json(path, "summary")
    if not isinstance(summary, dict):
        raise RecordError(f"{path}: not a drydem summary: its JSON is {type(summary).__name__ if summary is not None else 'null'}, "
                          "not an object")
    keys = set(summary)
    analysis = next((a for a in ("tilt", "limit") if SUMMARY_KEYS[a] | {"analysis", "model"} <= keys), None)
    if analysis is None:
        return None
    settings, model = summary["analysis"], summary["model"]
    joint, contacts = (model.get(table) if isinstance(model, dict) else None for table in ("joint", "contacts"))
    target = summary.get("target") or (model.get("source") if isinstance(model, dict) else None)
    if not (isinstance(settings, dict) and isinstance(joint, dict) and isinstance(contacts, dict) and isinstance(target, str)):
        raise RecordError(f"{path}: not a drydem {analysis} summary: it needs its target and its analysis, "
                          "model joint and contacts tables")
    law = {k: v for k, v in joint.items() if k not in NOT_LAW_KEYS and v is not None}
    spec = RunSpec(analysis=analysis, target=target, protocol=_protocol(analysis, summary), kn=joint.get("kn"), ks=joint.get("ks"),
                   friction=joint.get("friction"), points=contacts.get("points_per_length"),
                   increment_deg=settings.get("increment_deg") if analysis == "tilt" else None,
                   joint_law=joint_law_text(law) if law.get("model", "constant") != "constant" else None)
    curve = read_pushover(folder, summary) if analysis == "tilt" else []
    problem = _result_problem(spec, summary, curve)
    if problem is not None:
        raise RecordError(f"{path}: {problem}")
    return {"id": Path(folder).resolve().name, "spec": asdict(spec), "status": "ok", "error": None, "summary": summary,
            "pushover": curve}


def read_pushover(folder: str | Path, summary: dict) -> list[list[float]]:
    """The pushover curve of the tilt run in ``folder`` whose summary.json holds ``summary`` (its
    rows: :data:`CURVE_FROM_CSV`); RecordError naming pushover.csv if it cannot be read, or its
    rows are not a finished run's (:func:`_curve_problem`) or not those its summary records
    (:func:`_rows_problem`): a row of the curve is pushover.csv's fault, not summary.json's."""
    path = Path(folder) / PUSHOVER_FILE
    curve = _pushover_csv(path)
    problem = _curve_problem(curve) or _rows_problem(summary, curve)
    if problem is not None:
        raise RecordError(f"{path}: {problem}")
    return curve


def _rows_problem(summary: dict, curve: list) -> str | None:
    """A tilt's pushover.csv without one row per equilibrium state its summary records, or None
    (found by a hunt: a pushover.csv cut to 49 of its 201 rows was drawn beside the tables of
    the whole run), whose last row is not at the last equilibrium's tilt, or with a row at or past the stop displacement (summary analysis
    stop_displacement_m). What a summary does not record (a drydem before it) is not checked."""
    states = summary.get("equilibrium_states")
    if isinstance(states, int) and not isinstance(states, bool) and states != len(curve):
        return (f"{len(curve)} rows, where summary.json records {states} equilibrium states (one row each): cut short or "
                "edited by hand?")
    last = summary.get("last_equilibrium_deg")
    if curve and _numeric(last) and abs(curve[-1][0] - last) > DRIFT_ANGLE_SLACK_DEG:
        return (f"its last row is at {curve[-1][0]:g} deg, where summary.json records the last equilibrium at {last:g} deg: "
                "cut short or edited by hand?")
    analysis = summary.get("analysis")  # a dict in a summary drydem wrote (found by a review: a text was an AttributeError)
    stop = analysis.get("stop_displacement_m") if isinstance(analysis, dict) else None
    past = [k for k, row in enumerate(curve) if _numeric(stop) and abs(row[1]) >= stop]
    if past:  # the run ends at the stop displacement, equilibrium or not (drydem.analysis.tilt.run)
        return (f"pushover row {past[0]}: ux {curve[past[0]][1]:g} m, at or past the run's stop displacement {stop:g} m, where "
                "it ended: no equilibrium is recorded there")
    return None


def _protocol(analysis: str, summary: dict) -> str:
    """A run folder's protocol (:data:`~drydem.parametric.study.ANALYSES`): a tilt's adaptive or fixed, a limit analysis' method."""
    return ("adaptive" if summary["analysis"].get("adaptive") else "fixed") if analysis == "tilt" else str(summary["method"])


def _pushover_csv(path: Path) -> list[list[float]]:
    """A tilt's pushover.csv as a record's curve (:data:`CURVE_FROM_CSV`); RecordError naming the
    file (a pipe, which would be waited on forever, too)."""
    try:
        with regular_file(path, "a drydem pushover.csv").open(newline="", encoding="utf-8") as file:
            rows = list(csv.reader(file))
        if not rows:  # a run writes the header as it starts
            raise ValueError("no header")
        return [[float(row[k]) for k in CURVE_FROM_CSV] for row in rows[1:]]
    except ModelError as exc:
        raise RecordError(str(exc)) from None
    except OSError as exc:
        raise RecordError(f"{path}: cannot read the run's pushover curve ({exc.strerror})") from None
    except (ValueError, IndexError, csv.Error):  # csv.Error: a field past the csv module's limit (131,072 characters)
        raise RecordError(f"{path}: not a pushover curve (rows of numbers: tilt_deg, load_multiplier, ux_m, uz_m, drift, "
                          "cycles)") from None


def run_folders(results: Path) -> list[Path]:
    """The folders where a command's run may be: ``results`` and its sub-folders, in name order,
    each once (a link to another of them is the same run, not a second one)."""
    results = Path(results)
    found: dict[Path, Path] = {}
    for folder in [results, *sorted(p for p in results.iterdir() if p.is_dir())]:
        found.setdefault(folder.resolve(), folder)
    return list(found.values())


def load_run_folders(results: Path) -> Records:
    """The records of the ``drydem tilt`` and ``drydem limit`` run folders among ``results`` and
    its sub-folders (:func:`run_folders`, :func:`run_folder_record`), and the folders of the
    runs of other analyses (``other``)."""
    valid, corrupt, other = [], [], []
    for folder in run_folders(results):
        try:
            record = run_folder_record(folder)
        except RecordError as exc:
            corrupt.append(exc)
            continue
        if record is not None:
            valid.append(record)
        elif (folder / SUMMARY_FILE).is_file():
            other.append(folder)
    return Records(valid, corrupt, other)
