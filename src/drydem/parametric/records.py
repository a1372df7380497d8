"""A run's record on disk: ``RESULTS/runs/ID.json``, written atomically as soon as the run
finishes, holds the parameters, the status ("ok" or "failed" with the error), the summary and
the pushover curve (empty for limit and shake runs). A record is checked when it is read: one
that is not JSON, lacks a key, or whose parameters do not give its id is corrupt
(:class:`RecordError`), and a sweep runs it again.

The folder of a ``drydem tilt`` or ``drydem limit`` run (``--out``, by default
``results/TARGET-TIME``) reads as a record too (:func:`run_folder_record`): so that a report
holds the runs made one by one beside a sweep's.
"""

from __future__ import annotations

import csv
import json
import os
from dataclasses import asdict, dataclass
from pathlib import Path

from drydem.errors import DrydemError
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
#: the numbers of a shake run's summary (m, rad, m/s2, s; NaN and infinities allowed, as recorded)
SHAKE_NUMBERS = ("max_rotation_rad", "max_displacement_m", "residual_displacement_m", "pga_m_s2", "scale", "runtime_s")
#: the columns of a pushover curve: tilt (deg), ux, uz (m), drift, cycles
CURVE_COLUMNS = 5


def read_record(path: str | Path) -> dict:
    """The record in ``path``, checked: a JSON object whose id is the file's name and the id of
    its parameters, with the keys of its status (RECORD_KEYS, SUMMARY_KEYS). RecordError naming
    the file and what is wrong otherwise (a sweep killed while writing one without the atomic
    write, a disk full, a hand edit)."""
    path = Path(path)
    record = _read_json(path, "record")
    problem = _record_problem(record, path.name.removesuffix(".json"))
    if problem is not None:
        raise RecordError(f"{path}: {problem}")
    return record


def _read_json(path: Path, what: str):
    """The JSON in ``path``, a run's ``what`` (record, summary); RecordError naming the file if it
    cannot be read or is not JSON (a run killed while writing it without the atomic write, a hand edit)."""
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except OSError as exc:
        raise RecordError(f"{path}: cannot read the {what} ({exc.strerror})") from None
    except ValueError as exc:  # not JSON, or not UTF-8
        raise RecordError(f"{path}: not a JSON {what}, empty or cut short? ({exc})") from None


def _record_problem(record, run_id: str) -> str | None:
    """What is wrong with ``record`` as the record of run ``run_id``, or None."""
    if not isinstance(record, dict):
        return f"a record is a JSON object, not {type(record).__name__}"
    status = record.get("status")
    if status not in RECORD_KEYS:
        return f"status = {status!r}: must be one of {list(RECORD_KEYS)}"
    missing = sorted(RECORD_KEYS[status] - set(record))
    if missing:
        return f"a {status!r} record without {missing}"
    if record["id"] != run_id:
        return f"its id {record['id']!r} is not its file's name"
    try:
        spec = RunSpec(**record["spec"])
        spec_id = spec.id
    except (TypeError, ValueError) as exc:
        return f"spec is not the parameters of a run ({exc})"
    if spec_id != run_id:
        return f"its parameters are those of run {spec_id!r}, not of {run_id!r}"
    if spec.analysis not in ANALYSES:
        return f"spec analysis = {spec.analysis!r}: must be one of {list(ANALYSES)}"
    if status == "failed":
        return None if isinstance(record["error"], str) else "error must be the run's error message"
    return _result_problem(spec, record["summary"], record["pushover"])


def _result_problem(spec: RunSpec, summary, curve) -> str | None:
    """What is wrong with the ``summary`` and pushover ``curve`` of a finished run of ``spec``, or None."""
    if not isinstance(summary, dict) or not SUMMARY_KEYS[spec.analysis] <= set(summary):
        return f"summary must hold {sorted(SUMMARY_KEYS[spec.analysis])}"
    if spec.analysis == "shake":
        problem = _shake_problem(spec, summary)
        if problem is not None:
            return problem
    elif not (summary["collapse_angle_deg"] is None or _numeric(summary["collapse_angle_deg"])):
        return f"summary collapse_angle_deg = {summary['collapse_angle_deg']!r}: must be a number (deg) or null"
    if spec.analysis == "tilt" and not isinstance(summary["drift_limit_angles_deg"], dict):
        return "summary drift_limit_angles_deg must map drift limits to angles"
    if not isinstance(curve, list) or not all(isinstance(row, list) and len(row) == CURVE_COLUMNS and all(map(_numeric, row)) for row in curve):
        return f"pushover must be a list of rows of {CURVE_COLUMNS} numbers (tilt, ux, uz, drift, cycles)"
    return None


def _shake_problem(spec: RunSpec, summary: dict) -> str | None:
    """What is wrong with a shake run's spec and summary (the report reads them), or None."""
    if not isinstance(spec.motion, str) or not (_numeric(spec.scale) and spec.scale > 0):
        return f"spec motion = {spec.motion!r}, scale = {spec.scale!r}: a shake run has a motion (a string) and a scale (> 0)"
    if not isinstance(summary["overturned"], bool):
        return f"summary overturned = {summary['overturned']!r}: must be true or false"
    bad = [key for key in SHAKE_NUMBERS if not _numeric(summary[key])]
    if bad:
        return f"summary {', '.join(f'{key} = {summary[key]!r}' for key in bad)}: must be numbers"
    if not (isinstance(summary["cycles"], int) and not isinstance(summary["cycles"], bool)):
        return f"summary cycles = {summary['cycles']!r}: must be a whole number"
    if not isinstance(summary["motion"], str):
        return f"summary motion = {summary['motion']!r}: must be the run's motion (a string)"
    return None


def _numeric(value) -> bool:
    """An int or float (not a boolean); NaN and infinities are numbers a run may record."""
    return isinstance(value, (int, float)) and not isinstance(value, bool)


@dataclass(frozen=True)
class Records:
    """The records of a results folder: ``valid`` ones, and the ``corrupt`` ones' errors (each
    naming its file), left out."""

    valid: list[dict]
    corrupt: list[RecordError]


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
    summary = _read_json(path, "summary")
    keys = set(summary) if isinstance(summary, dict) else set()
    analysis = next((a for a in ("tilt", "limit") if SUMMARY_KEYS[a] | {"analysis", "model"} <= keys), None)
    if analysis is None:
        return None
    settings, model = summary["analysis"], summary["model"]
    joint, contacts = (model.get(table) if isinstance(model, dict) else None for table in ("joint", "contacts"))
    target = summary.get("target") or (model.get("source") if isinstance(model, dict) else None)
    if not (isinstance(settings, dict) and isinstance(joint, dict) and isinstance(contacts, dict) and isinstance(target, str)):
        raise RecordError(f"{path}: not a drydem {analysis} summary: it needs its target and its analysis, "
                          "model joint and contacts tables")
    if not all(_numeric(joint.get(key)) for key in ("kn", "ks", "friction")):
        raise RecordError(f"{path}: model joint kn, ks and friction must be numbers (Pa/m, Pa/m, -), not "
                          f"{joint.get('kn')!r}, {joint.get('ks')!r}, {joint.get('friction')!r}")
    law = {k: v for k, v in joint.items() if k not in NOT_LAW_KEYS and v is not None}
    spec = RunSpec(analysis=analysis, target=target, protocol=_protocol(analysis, summary), kn=joint["kn"], ks=joint["ks"],
                   friction=joint["friction"], points=contacts.get("points_per_length"),
                   increment_deg=settings.get("increment_deg") if analysis == "tilt" else None,
                   joint_law=joint_law_text(law) if law.get("model", "constant") != "constant" else None)
    curve = _pushover_csv(Path(folder) / PUSHOVER_FILE) if analysis == "tilt" else []
    problem = _result_problem(spec, summary, curve)
    if problem is not None:
        raise RecordError(f"{path}: {problem}")
    return {"id": Path(folder).resolve().name, "spec": asdict(spec), "status": "ok", "error": None, "summary": summary,
            "pushover": curve}


def _protocol(analysis: str, summary: dict) -> str:
    """A run folder's protocol (:data:`~drydem.parametric.study.ANALYSES`): a tilt's adaptive or fixed, a limit analysis' method."""
    return ("adaptive" if summary["analysis"].get("adaptive") else "fixed") if analysis == "tilt" else str(summary["method"])




def _pushover_csv(path: Path) -> list[list[float]]:
    """A tilt's pushover.csv as a record's curve (:data:`CURVE_FROM_CSV`); RecordError naming the file."""
    try:
        with path.open(newline="", encoding="utf-8") as file:
            rows = list(csv.reader(file))[1:]
        return [[float(row[k]) for k in CURVE_FROM_CSV] for row in rows]
    except OSError as exc:
        raise RecordError(f"{path}: cannot read the run's pushover curve ({exc.strerror})") from None
    except (ValueError, IndexError):
        raise RecordError(f"{path}: not a pushover curve (rows of numbers: tilt_deg, load_multiplier, ux_m, uz_m, drift, "
                          "cycles)") from None


def run_folders(results: Path) -> list[Path]:
    """The folders where a command's run may be: ``results`` and its sub-folders, in name order."""
    results = Path(results)
    return [results, *sorted(p for p in results.iterdir() if p.is_dir())]


def load_run_folders(results: Path) -> Records:
    """The records of the ``drydem tilt`` and ``drydem limit`` run folders among ``results`` and
    its sub-folders (:func:`run_folders`, :func:`run_folder_record`)."""
    valid, corrupt = [], []
    for folder in run_folders(results):
        try:
            record = run_folder_record(folder)
        except RecordError as exc:
            corrupt.append(exc)
            continue
        if record is not None:
            valid.append(record)
    return Records(valid, corrupt)
