"""Running a study's runs (:mod:`drydem.parametric.study`), each recorded as it finishes
(:mod:`drydem.parametric.records`), on any ``concurrent.futures`` executor: local processes or a
Dask cluster's (:mod:`drydem.parametric.workers`).

A sweep started again skips the runs validly recorded and reruns the missing and the corrupt
ones, so a killed sweep loses only the runs in flight.

Two sweeps may work on one results folder: a run is computed by the sweep that claims it, an
exclusive ``flock`` on ``RESULTS/runs/ID.lock`` held from submission until its record is
written (see :func:`claim`); the other sweep leaves it and says so.
"""

from __future__ import annotations

import hashlib
import os
import time
import traceback
from collections.abc import Callable, Iterable
from concurrent.futures import FIRST_COMPLETED, Executor, Future, wait
from dataclasses import asdict, dataclass, field
from pathlib import Path

from drydem.errors import DrydemError
from drydem.files import lock_exclusively, unlock
from drydem.model.parameters import FILE_PATH, check_arguments
from drydem.parametric.records import RecordError, load_records, read_record, record_path, write_record
from drydem.parametric.study import PULSE_PREFIX, RunSpec, ground_motion


class SweepError(DrydemError):
    """The executor lost runs (a worker killed, a cluster gone): not a run's failure."""


def run_one(spec: RunSpec) -> dict:
    """Run ``spec`` and return its record, with the digests of the files it reads
    (:func:`input_digests`, ``inputs``); a failure is recorded, never raised."""
    start = time.perf_counter()
    record = {"id": spec.id, "spec": asdict(spec), "inputs": input_digests(spec)}
    try:
        record |= {"status": "ok", "error": None} | _analyse(spec)
    except Exception as exc:  # a failing run must not stop the sweep: its error is the record
        record |= {"status": "failed", "error": f"{type(exc).__name__}: {exc}", "traceback": traceback.format_exc(limit=5)}
    return record | {"runtime_s": round(time.perf_counter() - start, 3)}


def _analyse(spec: RunSpec) -> dict:
    from drydem.io.results import limit_summary, tilt_summary

    model = spec.model()
    if spec.analysis == "shake":
        from drydem.analysis.shake import shake_analysis

        motion = ground_motion(spec.motion)
        settings = spec.shake_settings(motion)
        return {"summary": shake_summary(shake_analysis(model, settings), spec, motion, model), "pushover": []}
    if spec.analysis == "limit":
        from drydem.analysis.limit import LimitSettings, limit_analysis

        settings = LimitSettings(non_associative=spec.protocol == "non-associative")
        start = time.perf_counter()
        result = limit_analysis(model, settings)
        return {"summary": limit_summary(result, settings, model, time.perf_counter() - start), "pushover": []}
    from drydem.analysis.tilt import tilt_analysis

    result = tilt_analysis(model, spec.tilt_settings())
    curve = [[r.tilt_deg, r.ux_m, r.uz_m, r.drift, r.cycles] for r in result.records]
    return {"summary": tilt_summary(result, model), "pushover": curve}


def input_digests(spec: RunSpec, known: dict[str, str | None] | None = None) -> dict[str, str]:
    """{path: SHA-256 of its content} of the files a run reads: its target unless a built-in
    wall, its motion unless a pulse; a file that cannot be read is left out (the run fails on
    it). ``known``: digests already taken, by path, to reuse and add to."""
    known = {} if known is None else known
    for path in (spec.target, spec.motion):
        if path is not None and path not in known and not path.startswith(PULSE_PREFIX):
            try:
                known[path] = hashlib.sha256(Path(path).read_bytes()).hexdigest() if Path(path).is_file() else None
            except OSError:
                known[path] = None
    return {path: known[path] for path in (spec.target, spec.motion) if known.get(path) is not None}


def changed_inputs(record: dict, spec: RunSpec, known: dict[str, str | None]) -> list[str]:
    """The files among those a record was run on (its ``inputs``) whose content is not what it
    was then, or that are gone: its result is not of the files as they are. None known for a
    record of a drydem before the digests (no ``inputs``): [] (found by a hunt: a sweep run
    again after its target file was edited, or on another file of the same path, took the old
    record as done)."""
    now = input_digests(spec, known)
    return [path for path, digest in (record.get("inputs") or {}).items() if now.get(path) != digest]


def shake_summary(result, spec: RunSpec, motion, model) -> dict:
    """The summary of a shake run's record: ``drydem shake``'s
    (:func:`drydem.io.results.shake_summary`), with the motion as the study gives it
    (``spec.motion``, which the report's IDA groups by: :mod:`drydem.report.ida`), the analysed
    motion's name and the PGA of ``motion``, the motion before its scale; records.SUMMARY_KEYS
    are checked."""
    from drydem.io.results import shake_summary as command_summary

    corrected = not spec.motion.startswith(PULSE_PREFIX)
    return command_summary(result, model, scale=spec.scale, baseline_corrected=corrected) | {
        "motion": spec.motion,
        "motion_name": result.settings.motion.name,
        "motion_pga_m_s2": motion.pga_m_s2,
        "scale": spec.scale,
        "baseline_corrected": corrected,
    }


@dataclass
class Pending:
    """What a sweep has to run: ``todo`` (no record, a corrupt one, or a failed one or one run on
    input files that changed since when retried), how many runs are ``recorded`` (``failed`` of
    them recorded as failed and not retried; ``changed``: {id: the files changed since} of those
    run on files that changed, not retried: :func:`changed_inputs`), the ``corrupt`` records'
    errors, and for each run to do the identity of its record file when looked at
    (:func:`_identity`), to tell after claiming it whether another sweep recorded it meanwhile."""

    todo: list[RunSpec] = field(default_factory=list)
    recorded: int = 0
    failed: int = 0
    corrupt: list[RecordError] = field(default_factory=list)
    seen: dict[str, tuple[int, int] | None] = field(default_factory=dict)
    changed: dict[str, list[str]] = field(default_factory=dict)


def pending(runs: Iterable[RunSpec], results: Path, *, retry_failed: bool = False, retry_changed: bool = False) -> Pending:
    """The runs to do (see :class:`Pending`). SweepError naming the path, before any run, if
    RESULTS/runs is there but no folder, or a run's record path is taken by something else than
    a file (a folder: a record could not be put in its place once the run is done)."""
    runs = list(runs)
    folder = Path(results) / "runs"
    if folder.exists() and not folder.is_dir():
        raise SweepError(f"{folder}: exists and is not a folder, where a sweep writes its records; move it away or give another --out")
    plan, known = Pending(), {}
    for spec in runs:
        path = record_path(results, spec.id)
        identity = _identity(path)
        if identity is not None and not path.is_file():
            raise SweepError(f"{path}: is not a file but where the record of run {spec.id} goes; move it away")
        if identity is None or _to_run_again(plan, spec, path, known, retry_failed, retry_changed):
            plan.todo.append(spec)
            plan.seen[spec.id] = identity
    plan.recorded = len(runs) - len(plan.todo)
    return plan


def _to_run_again(plan: Pending, spec: RunSpec, path: Path, known: dict, retry_failed: bool, retry_changed: bool) -> bool:
    """Whether the run recorded in ``path`` is to be run again: its record is corrupt (noted in
    ``plan``), failed and ``retry_failed``, or run on files changed since and ``retry_changed``;
    a failed or changed one not retried is counted in ``plan``."""
    try:
        record = read_record(path)
    except RecordError as exc:
        plan.corrupt.append(exc)
        return True
    was_failed, changed = record["status"] == "failed", changed_inputs(record, spec, known)
    again = (was_failed and retry_failed) or (bool(changed) and retry_changed)
    plan.failed += was_failed and not again
    if changed and not again:
        plan.changed[spec.id] = changed
    return again


def _identity(path: Path) -> tuple[int, int] | None:
    """The file's inode and modification time, None if there is none: a record written again is
    a new file (write_record renames a new one over it), so this changes with every write."""
    try:
        stat = os.stat(path)
    except FileNotFoundError:
        return None
    return stat.st_ino, stat.st_mtime_ns


def lock_path(results: Path, run_id: str) -> Path:
    return Path(results) / "runs" / f"{run_id}.lock"


def claim(results: Path, run_id: str) -> int | None:
    """Claim run ``run_id`` for this process: the descriptor of ``RESULTS/runs/ID.lock`` locked
    exclusively, held until :func:`release`; None if another process holds it
    (:func:`drydem.files.lock_exclusively`: the kernel drops the lock when its process ends,
    however it ends, so there is no stale claim)."""
    return lock_exclusively(lock_path(results, run_id))


def release(results: Path, run_id: str, fd: int) -> None:
    """End a claim: delete its file, then unlock it (closing it)."""
    unlock(lock_path(results, run_id), fd)


@dataclass(frozen=True)
class SweepOutcome:
    """How a sweep went: runs ``finished`` now (``failed`` of them failed), ``skipped`` (validly
    recorded, before the sweep or by another sweep since; ``failed_before`` of them recorded as
    failed, before the sweep and not retried or by another sweep since; ``changed_before``: {id:
    files} of them run on input files that changed since, not retried), ``elsewhere`` (left to
    another sweep on the same folder, which had not recorded them when this one ended),
    ``corrupt`` (the errors of the records found corrupt, each naming its file: run again,
    unless left to another sweep)."""

    finished: int
    skipped: int
    failed: int
    failed_before: int = 0
    elsewhere: int = 0
    corrupt: tuple[str, ...] = ()
    changed_before: dict[str, list[str]] = field(default_factory=dict)


def sweep(runs: Iterable[RunSpec], results: Path, executor: Executor, *, retry_failed: bool = False, retry_changed: bool = False,
          in_flight: int | None = None,
          on_done: Callable[[dict], None] | None = None, on_other: Callable[[RunSpec], None] | None = None) -> SweepOutcome:
    """Run on ``executor`` what is not validly recorded yet (:func:`pending`), claiming each run
    (:func:`claim`) just before submitting it and writing its record as it comes in.

    At most ``in_flight`` runs are claimed at a time (default: all); the executor's worker count
    lets a second sweep on the same folder share the runs left rather than find them all
    claimed. A run another sweep has claimed is left to it; one it recorded since
    :func:`pending` looked is not run again. ``on_done(record)`` is called for every run
    finished here, ``on_other(spec)`` for every run left to or done by another sweep.
    SweepError if the executor loses a run (a worker killed): the runs finished are recorded."""
    results = Path(results)
    runs = list(runs)
    plan = pending(runs, results, retry_failed=retry_failed, retry_changed=retry_changed)
    (results / "runs").mkdir(parents=True, exist_ok=True)
    queue = iter(plan.todo)
    window = in_flight or max(len(plan.todo), 1)
    claims: dict[Future, tuple[RunSpec, int]] = {}
    finished = failed = 0
    left: list[RunSpec] = []  # claimed by another sweep
    others: list[RunSpec] = []  # recorded by another sweep since pending() looked
    try:
        while True:
            while len(claims) < window and (spec := next(queue, None)) is not None:
                fd = claim(results, spec.id)
                if fd is not None and _identity(record_path(results, spec.id)) == plan.seen[spec.id]:
                    claims[_submit(executor, spec, fd, results)] = (spec, fd)
                    continue
                if fd is None:
                    left.append(spec)
                else:
                    release(results, spec.id, fd)
                    others.append(spec)
                if on_other is not None:
                    on_other(spec)
            if not claims:
                break
            done, _ = wait(claims, return_when=FIRST_COMPLETED)
            for future in done:
                spec, fd = claims.pop(future)
                try:
                    record = _result(future, spec)
                    write_record(results, record)
                finally:
                    release(results, spec.id, fd)
                finished += 1
                failed += record["status"] == "failed"
                if on_done is not None:
                    on_done(record)
    finally:
        for spec, fd in claims.values():
            release(results, spec.id, fd)
    # the runs left to another sweep that it has recorded by now count as its records say (found
    # by a hunt: each of two sweeps sharing a study said it was not complete; by a review: one
    # the other recorded as failed counted as done)
    recorded = [*others, *(spec for spec in left if _identity(record_path(results, spec.id)) != plan.seen[spec.id])]
    statuses = [_recorded_status(results, spec) for spec in recorded]
    done, failed_there = statuses.count("ok"), statuses.count("failed")
    return SweepOutcome(finished=finished, skipped=plan.recorded + done + failed_there, failed=failed,
                        failed_before=plan.failed + failed_there,
                        elsewhere=len(left) + len(others) - done - failed_there, corrupt=tuple(str(exc) for exc in plan.corrupt),
                        changed_before=plan.changed)


def _recorded_status(results: Path, spec: RunSpec) -> str | None:
    """The status, "ok" or "failed", of the record another sweep wrote for ``spec``; None if it
    cannot be read (the run is then not taken as done)."""
    try:
        return read_record(record_path(results, spec.id))["status"]
    except RecordError:
        return None


def records_dataframe(results: Path):
    """The run records of a results folder (:func:`drydem.parametric.records.load_records`) as a
    pandas DataFrame (:func:`drydem.analysis.dataframes.data_frame`), one row per valid
    record in name order: ``id``, ``status``, ``error``, ``runtime_s``, the run's parameters
    (:class:`~drydem.parametric.study.RunSpec`'s fields, kn and ks as ``kn_Pa_m`` and
    ``ks_Pa_m``), then every number, text or flag of its summary under the summary's own name
    (``collapse_angle_deg``, ``ended_by``, ``max_rotation_rad``, ...; a column holds None or
    NaN where a run's analysis has no such value) and a tilting run's drift-limit angles as
    ``drift_LIMIT_angle_deg``; ``attrs``: ``corrupt``, the corrupt records' errors, left out.
    ModelError if ``results`` is no path; DrydemError if it is no folder with a runs/ folder
    (found by a hunt: a tilt run's folder gave an empty table, and a file "no such folder")."""
    from drydem.analysis.dataframes import data_frame

    check_arguments("records_dataframe", {"results": FILE_PATH}, results=results)
    results = Path(results)
    expected = "a sweep's results folder, its --out, holds runs/ID.json"
    if not results.is_dir():
        raise DrydemError(f"{results}: {'not a folder' if results.exists() else 'no such results folder'} ({expected})")
    if not (results / "runs").is_dir():
        raise DrydemError(f"{results}: no runs/ folder, so no sweep's results ({expected})")
    loaded = load_records(results)
    units = {"kn": "kn_Pa_m", "ks": "ks_Pa_m"}
    rows = []
    for record in loaded.valid:
        row = {"id": record["id"], "status": record["status"], "error": record.get("error"), "runtime_s": record.get("runtime_s")}
        row |= {units.get(key, key): value for key, value in record["spec"].items()}
        summary = record.get("summary", {})
        row |= {key: value for key, value in summary.items() if key not in row and isinstance(value, (int, float, str, type(None)))}
        row |= {f"drift_{limit}_angle_deg": angle for limit, angle in summary.get("drift_limit_angles_deg", {}).items()}
        rows.append(row)
    names = list(dict.fromkeys(name for row in rows for name in row))
    return data_frame({name: [row.get(name) for row in rows] for name in names}, {"corrupt": [str(exc) for exc in loaded.corrupt]})


def _submit(executor: Executor, spec: RunSpec, fd: int, results: Path) -> Future:
    """``run_one(spec)`` submitted; SweepError (the claim released) if the executor refuses it."""
    try:
        return executor.submit(run_one, spec)
    except Exception as exc:
        release(results, spec.id, fd)
        raise SweepError(f"the executor refused run {spec.id} ({type(exc).__name__}: {exc}); the runs finished are recorded") from exc


def _result(future: Future, spec: RunSpec) -> dict:
    """The record a run returned; SweepError if the executor lost it (run_one never raises)."""
    try:
        return future.result()
    except Exception as exc:
        raise SweepError(f"run {spec.id} was lost by the executor ({type(exc).__name__}: {exc}); "
                         "the runs finished are recorded: run the sweep again to go on") from exc
