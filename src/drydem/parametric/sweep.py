"""Parametric studies: a study file, its runs (tilting or limit analyses), one record per run.

A study file is TOML; each ``[[grid]]`` is a cartesian product, the study is their union::

    [study]
    name = "savalle2022"
    description = "..."
    [defaults]                  # optional, for every grid
    friction = 0.5
    points = 4                  # sub-contacts per length
    increment_deg = 0.1
    [[grid]]
    name = "stiffness"          # a label (a run several grids share is run once)
    analysis = "tilt"           # or "limit"
    targets = ["WD1", "WD2"]    # built-in walls, or files relative to the study file
    kn = [1e7, 3e7, 1e9]        # Pa/m
    ks = "kn"                   # ks = kn (default), or a list of values
    protocol = ["adaptive"]     # tilt: fixed, adaptive; limit: associative, non-associative

A study is checked whole when it is loaded: every target is loaded and every run's overrides
applied to it (the parameter classes check the values), so that a bad value anywhere stops the
study before its first run, with every problem named, rather than hours later as a failed run.

Every run has an id made of its parameters (and a hash of them), and its record, written
atomically to ``RESULTS/runs/ID.json`` as soon as it finishes, holds the parameters, the
status ("ok" or "failed" with the error), the summary and the pushover curve. A sweep started
again skips the runs validly recorded and reruns the missing and the corrupt ones (a record
that is not JSON, lacks a key, or whose parameters do not give its id), so a killed sweep loses
only the runs in flight. Runs go to any ``concurrent.futures`` executor: local processes
(:func:`local_executor`, whose workers die with the sweep), or a Dask cluster's.

Two sweeps may work on one results folder: a run is computed by the sweep that claims it, an
exclusive ``flock`` on ``RESULTS/runs/ID.lock`` held from submission until its record is
written (see :func:`_claim`); the other sweep leaves it and says so.
"""

from __future__ import annotations

import fcntl
import hashlib
import itertools
import json
import os
import socket
import sys
import threading
import time
import traceback
from collections.abc import Callable, Iterable, Iterator
from concurrent.futures import FIRST_COMPLETED, Executor, Future, wait
from contextlib import contextmanager
from dataclasses import asdict, dataclass, replace
from pathlib import Path

from drydem.errors import DrydemError, ModelError
from drydem.files import read_toml
from drydem.model.assembly import Model
from drydem.model.tables import no_unknown

ANALYSES = {"tilt": ("fixed", "adaptive"), "limit": ("associative", "non-associative")}
DEFAULT_PROTOCOL = {"tilt": "adaptive", "limit": "associative"}
GRID_KEYS = {"name", "analysis", "targets", "kn", "ks", "friction", "points", "protocol", "increment_deg"}
DEFAULT_KEYS = {"friction", "points", "increment_deg"}
#: the RunSpec fields that override the target's parameters
OVERRIDES = ("kn", "ks", "friction", "points")
#: how long a Dask scheduler has to answer before the sweep gives up on it, s: a scheduler that
#: is up answers a connection in milliseconds, so a longer wait only delays saying it is not
SCHEDULER_TIMEOUT_S = 5.0


class RecordError(DrydemError):
    """A run record that cannot be used (unreadable, not JSON, incomplete, or not its run's);
    the message names the file and what is wrong."""


class SweepError(DrydemError):
    """The executor lost runs (a worker killed, a cluster gone): not a run's failure."""


@dataclass(frozen=True)
class RunSpec:
    """One run of a study. kn, ks (Pa/m), friction and points override the target's when given.
    Grids that share a run (same parameters) share its record."""

    analysis: str
    target: str
    protocol: str
    kn: float | None = None
    ks: float | None = None
    friction: float | None = None
    points: int | None = None
    increment_deg: float = 0.1

    @property
    def id(self) -> str:
        """Readable and unique: analysis, target, stiffnesses, protocol and a hash of everything."""
        digest = hashlib.sha1(json.dumps(asdict(self), sort_keys=True).encode()).hexdigest()[:10]
        stiffness = "" if self.kn is None else f"-kn{self.kn:.3g}-ks{self.ks:.3g}"
        return f"{self.analysis}-{Path(self.target).stem}{stiffness}-{self.protocol}-{digest}"

    @property
    def overrides(self) -> dict:
        """The values this run changes in its target's model (None: the target's), as keywords of
        :meth:`drydem.model.assembly.Model.overridden` and ``parameter_changes``."""
        return {key: getattr(self, key) for key in OVERRIDES}

    def model(self) -> Model:
        """The model this run analyses: its target's (:func:`drydem.io.target.load_target`) with
        :attr:`overrides` applied; ModelError for a target that cannot be loaded or a value out
        of its range."""
        from drydem.io.target import load_target

        return load_target(self.target).model.overridden(**self.overrides)


@dataclass(frozen=True)
class Study:
    name: str
    description: str
    runs: list[RunSpec]
    source: str


def load_study(path: str | Path) -> Study:
    """Read a study file and check every run it makes (module docstring); one ModelError that
    names, for every problem, the file, the grid and the key with its rule."""
    path = Path(path)
    data, _ = read_toml(path)
    source = str(path)
    no_unknown(data, {"study", "defaults", "grid"}, source, "top level")
    meta, defaults = data.get("study", {}), data.get("defaults", {})
    no_unknown(meta, {"name", "description"}, source, "[study]")
    no_unknown(defaults, DEFAULT_KEYS, source, "[defaults]")
    grids = data.get("grid")
    if not isinstance(grids, list) or not grids:
        raise ModelError(f"{source}: no [[grid]] entries")
    runs: list[RunSpec] = []
    problems: list[str] = []
    models: dict[str, object] = {}  # target -> its model, or the message saying why it cannot be loaded
    for k, grid in enumerate(grids):
        name = grid.get("name", "?") if isinstance(grid, dict) else "?"
        where = f"{source}: [[grid]] #{k} ({name!r})"
        try:
            no_unknown(grid, GRID_KEYS, where, "the grid")
            runs += _grid_runs(defaults | grid, path.parent, where, models, problems)
        except ModelError as exc:
            problems.append(str(exc))
    if problems:
        unique = list(dict.fromkeys(problems))
        raise ModelError(unique[0] if len(unique) == 1 else f"{source}: {len(unique)} problems, nothing run:\n  " + "\n  ".join(unique))
    return Study(str(meta.get("name", path.stem)), str(meta.get("description", "")), list(dict.fromkeys(runs)), source)


def _grid_runs(grid: dict, folder: Path, where: str, models: dict, problems: list[str]) -> list[RunSpec]:
    """The runs of one grid, each checked on its target; a problem found is appended to
    ``problems`` (ModelError when the grid cannot even be expanded)."""
    analysis = grid.get("analysis", "tilt")
    if not isinstance(analysis, str) or analysis not in ANALYSES:
        raise ModelError(f"{where}: analysis = {analysis!r}: must be one of {list(ANALYSES)}")
    values = {key: _list(grid.get(key, default)) for key, default in
              (("protocol", DEFAULT_PROTOCOL[analysis]), ("targets", []), ("kn", None), ("friction", None), ("points", None))}
    empty = [key for key, found in values.items() if not found]
    if empty:
        raise ModelError(f"{where}: {', '.join(empty)} = []: needs at least one value"
                         + (" (targets: built-in walls or files)" if "targets" in empty else ""))
    bad = [p for p in values["protocol"] if p not in ANALYSES[analysis]]
    if bad:
        raise ModelError(f"{where}: protocol {bad} is not one of {list(ANALYSES[analysis])} for a {analysis} analysis")
    names = [t for t in values["targets"] if not isinstance(t, str)]
    if names:
        raise ModelError(f"{where}: targets {names}: each must be a built-in wall's name or a file (a string)")
    targets = [t if not (folder / t).is_file() else str(folder / t) for t in values["targets"]]
    ks_values = grid.get("ks", "kn")
    if isinstance(ks_values, list) and not ks_values:
        raise ModelError(f"{where}: ks = []: needs at least one value, or \"kn\" (ks = kn)")
    runs = []
    for target, protocol, kn, friction, points in itertools.product(targets, values["protocol"], values["kn"], values["friction"], values["points"]):
        for ks in ([kn] if ks_values == "kn" else _list(ks_values)):
            runs.append(RunSpec(analysis=analysis, target=target, protocol=protocol, kn=kn, ks=ks, friction=friction, points=points,
                                increment_deg=grid.get("increment_deg", 0.1)))
    found = len(problems)
    for spec in runs:
        if spec.target not in models:
            models[spec.target] = _load_model(spec.target)
        model = models[spec.target]
        problems += [f"{where}: {problem}" for problem in ([model] if isinstance(model, str) else _problems(model, spec))]
    return [] if len(problems) > found else [_normalised(spec) for spec in runs]


def _load_model(target: str):
    """The model of ``target``, or the message saying why it cannot be loaded."""
    from drydem.io.target import load_target

    try:
        return load_target(target).model
    except DrydemError as exc:
        return f"targets: {exc}"


def _problems(model, spec: RunSpec) -> list[str]:
    """Why ``spec`` cannot run on ``model``: its overrides applied to the model and its tilt
    step, as the run itself builds them (the rules are the parameter classes', written once),
    each override alone so that one bad value does not hide another."""
    bare = replace(spec, **dict.fromkeys(OVERRIDES))
    checks = [lambda key=key: _overrides(model, replace(bare, **{key: getattr(spec, key)})) for key in OVERRIDES]
    found = []
    for check in [*checks, lambda: _tilt_settings(spec)]:  # a limit run's increment is unused, but is part of its id
        try:
            check()
        except ModelError as exc:
            found.append(str(exc))
    return found


def _normalised(spec: RunSpec) -> RunSpec:
    """``spec`` with its checked numbers as floats (1e7 and 10000000 are one run)."""
    def number(value):
        return None if value is None else float(value)

    return replace(spec, kn=number(spec.kn), ks=number(spec.ks), friction=number(spec.friction), increment_deg=float(spec.increment_deg))


def _list(value) -> list:
    return value if isinstance(value, list) else [value]


def _overrides(model, spec: RunSpec) -> dict:
    """``model``'s tables that ``spec`` changes (kn, ks, friction, points), for Model.replace;
    ModelError (from JointMaterial, ContactSettings) for a value out of its range."""
    return model.parameter_changes(**spec.overrides)


def _tilt_settings(spec: RunSpec):
    """The tilting settings of ``spec`` (TiltSettings checks the increment)."""
    from drydem.analysis.tilt import TiltSettings

    return TiltSettings(increment_deg=spec.increment_deg, adaptive=spec.protocol == "adaptive")


def run_one(spec: RunSpec) -> dict:
    """Run ``spec`` and return its record; a failure is recorded, never raised."""
    start = time.perf_counter()
    record = {"id": spec.id, "spec": asdict(spec)}
    try:
        record |= {"status": "ok", "error": None} | _analyse(spec)
    except Exception as exc:  # a failing run must not stop the sweep: its error is the record
        record |= {"status": "failed", "error": f"{type(exc).__name__}: {exc}", "traceback": traceback.format_exc(limit=5)}
    return record | {"runtime_s": round(time.perf_counter() - start, 3)}


def _analyse(spec: RunSpec) -> dict:
    from drydem.io.results import limit_summary, tilt_summary

    model = spec.model()
    if spec.analysis == "limit":
        from drydem.analysis.limit import LimitSettings, limit_analysis

        settings = LimitSettings(non_associative=spec.protocol == "non-associative")
        start = time.perf_counter()
        result = limit_analysis(model, settings)
        return {"summary": limit_summary(result, settings, model, time.perf_counter() - start), "pushover": []}
    from drydem.analysis.tilt import tilt_analysis

    result = tilt_analysis(model, _tilt_settings(spec))
    curve = [[r.tilt_deg, r.ux_m, r.uz_m, r.drift, r.cycles] for r in result.records]
    return {"summary": tilt_summary(result, model), "pushover": curve}


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
SUMMARY_KEYS = {"tilt": {"collapse_angle_deg", "drift_limit_angles_deg", "wall_height_m"}, "limit": {"collapse_angle_deg", "method"}}
#: the columns of a pushover curve: tilt (deg), ux, uz (m), drift, cycles
CURVE_COLUMNS = 5


def read_record(path: str | Path) -> dict:
    """The record in ``path``, checked: a JSON object whose id is the file's name and the id of
    its parameters, with the keys of its status (RECORD_KEYS, SUMMARY_KEYS). RecordError naming
    the file and what is wrong otherwise (a sweep killed while writing one without the atomic
    write, a disk full, a hand edit)."""
    path = Path(path)
    try:
        record = json.loads(path.read_text(encoding="utf-8"))
    except OSError as exc:
        raise RecordError(f"{path}: cannot read the record ({exc.strerror})") from None
    except ValueError as exc:  # not JSON, or not UTF-8
        raise RecordError(f"{path}: not a JSON record, empty or cut short? ({exc})") from None
    problem = _record_problem(record, path.name.removesuffix(".json"))
    if problem is not None:
        raise RecordError(f"{path}: {problem}")
    return record


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
    summary, curve = record["summary"], record["pushover"]
    if not isinstance(summary, dict) or not SUMMARY_KEYS[spec.analysis] <= set(summary):
        return f"summary must hold {sorted(SUMMARY_KEYS[spec.analysis])}"
    if not (summary["collapse_angle_deg"] is None or _numeric(summary["collapse_angle_deg"])):
        return f"summary collapse_angle_deg = {summary['collapse_angle_deg']!r}: must be a number (deg) or null"
    if spec.analysis == "tilt" and not isinstance(summary["drift_limit_angles_deg"], dict):
        return "summary drift_limit_angles_deg must map drift limits to angles"
    if not isinstance(curve, list) or not all(isinstance(row, list) and len(row) == CURVE_COLUMNS and all(map(_numeric, row)) for row in curve):
        return f"pushover must be a list of rows of {CURVE_COLUMNS} numbers (tilt, ux, uz, drift, cycles)"
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


@dataclass(frozen=True)
class Pending:
    """What a sweep has to run: ``todo`` (no record, a corrupt one, or a failed one when retried),
    how many runs are ``recorded``, the ``corrupt`` records' errors, and for each run to do the
    identity of its record file when looked at (:func:`_identity`), to tell after claiming it
    whether another sweep recorded it meanwhile."""

    todo: list[RunSpec]
    recorded: int
    corrupt: list[RecordError]
    seen: dict[str, tuple[int, int] | None]


def pending(runs: Iterable[RunSpec], results: Path, *, retry_failed: bool = False) -> Pending:
    """The runs to do (see :class:`Pending`)."""
    runs = list(runs)
    todo, corrupt, seen = [], [], {}
    for spec in runs:
        path = record_path(results, spec.id)
        identity = _identity(path)
        try:
            needed = identity is None or (read_record(path)["status"] == "failed" and retry_failed)
        except RecordError as exc:
            corrupt.append(exc)
            needed = True
        if needed:
            todo.append(spec)
            seen[spec.id] = identity
    return Pending(todo, len(runs) - len(todo), corrupt, seen)


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


def _claim(results: Path, run_id: str) -> int | None:
    """Claim run ``run_id`` for this process: the descriptor of ``RESULTS/runs/ID.lock`` locked
    exclusively (flock), held until :func:`_release`; None if another process holds it.

    A lock rather than a file created exclusively (O_EXCL): the kernel drops it when its process
    ends, however it ends (kill -9, a crash), so there is no stale claim to detect and take
    over by guessing from process ids and hosts, and no window in which two sweeps both take a
    stale one over. (On NFS, Linux maps flock to the lock manager's locks, across hosts.) The
    file only tells a person who holds it: host, pid, time. Its holder deletes it before
    unlocking it, so a process that opened it before that and locks it after finds it is no
    longer the file at that path, and tries again on the new one."""
    path = lock_path(results, run_id)
    while True:
        fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            os.close(fd)
            return None
        except OSError as exc:
            os.close(fd)
            raise SweepError(f"{path}: cannot lock the run's claim ({exc.strerror}): does this file system support locks?") from None
        try:
            current = os.stat(path).st_ino == os.fstat(fd).st_ino
        except FileNotFoundError:
            current = False
        if current:
            os.ftruncate(fd, 0)
            os.write(fd, f"claimed by {socket.gethostname()} pid {os.getpid()} at {time.strftime('%Y-%m-%d %H:%M:%S')}\n".encode())
            return fd
        os.close(fd)


def _release(results: Path, run_id: str, fd: int) -> None:
    """End a claim: delete its file, then unlock it (closing it)."""
    lock_path(results, run_id).unlink(missing_ok=True)
    os.close(fd)


@dataclass(frozen=True)
class SweepOutcome:
    """How a sweep went: runs ``finished`` now (``failed`` of them failed), ``skipped`` (validly
    recorded, before the sweep or by another sweep since), ``elsewhere`` (being computed by
    another sweep on the same folder, left to it), ``corrupt`` (the errors of the records found
    corrupt, each naming its file: run again, unless left to another sweep)."""

    finished: int
    skipped: int
    failed: int
    elsewhere: int = 0
    corrupt: tuple[str, ...] = ()


def sweep(runs: Iterable[RunSpec], results: Path, executor: Executor, *, retry_failed: bool = False, in_flight: int | None = None,
          on_done: Callable[[dict], None] | None = None, on_other: Callable[[RunSpec], None] | None = None) -> SweepOutcome:
    """Run on ``executor`` what is not validly recorded yet (:func:`pending`), claiming each run
    (:func:`_claim`) just before submitting it and writing its record as it comes in.

    At most ``in_flight`` runs are claimed at a time (default: all); the executor's worker count
    lets a second sweep on the same folder share the runs left rather than find them all
    claimed. A run another sweep has claimed is left to it; one it recorded since
    :func:`pending` looked is not run again. ``on_done(record)`` is called for every run
    finished here, ``on_other(spec)`` for every run left to or done by another sweep.
    SweepError if the executor loses a run (a worker killed): the runs finished are recorded."""
    results = Path(results)
    runs = list(runs)
    plan = pending(runs, results, retry_failed=retry_failed)
    (results / "runs").mkdir(parents=True, exist_ok=True)
    queue = iter(plan.todo)
    window = in_flight or max(len(plan.todo), 1)
    claims: dict[Future, tuple[RunSpec, int]] = {}
    finished = failed = skipped = elsewhere = 0
    try:
        while True:
            while len(claims) < window and (spec := next(queue, None)) is not None:
                fd = _claim(results, spec.id)
                if fd is not None and _identity(record_path(results, spec.id)) == plan.seen[spec.id]:
                    claims[_submit(executor, spec, fd, results)] = (spec, fd)
                    continue
                if fd is None:
                    elsewhere += 1
                else:  # recorded by another sweep since pending() looked
                    _release(results, spec.id, fd)
                    skipped += 1
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
                    _release(results, spec.id, fd)
                finished += 1
                failed += record["status"] == "failed"
                if on_done is not None:
                    on_done(record)
    finally:
        for spec, fd in claims.values():
            _release(results, spec.id, fd)
    return SweepOutcome(finished=finished, skipped=plan.recorded + skipped, failed=failed, elsewhere=elsewhere,
                        corrupt=tuple(str(exc) for exc in plan.corrupt))


def _submit(executor: Executor, spec: RunSpec, fd: int, results: Path) -> Future:
    """``run_one(spec)`` submitted; SweepError (the claim released) if the executor refuses it."""
    try:
        return executor.submit(run_one, spec)
    except Exception as exc:
        _release(results, spec.id, fd)
        raise SweepError(f"the executor refused run {spec.id} ({type(exc).__name__}: {exc}); the runs finished are recorded") from exc


def _result(future: Future, spec: RunSpec) -> dict:
    """The record a run returned; SweepError if the executor lost it (run_one never raises)."""
    try:
        return future.result()
    except Exception as exc:
        raise SweepError(f"run {spec.id} was lost by the executor ({type(exc).__name__}: {exc}); "
                         "the runs finished are recorded: run the sweep again to go on") from exc


@dataclass(frozen=True)
class Workers:
    """Where runs go: an ``executor``, a description of it (``where``), and the runs it computes
    at once (``slots``; None for a Dask cluster, which may grow)."""

    executor: Executor
    where: str
    slots: int | None


@contextmanager
def open_workers(workers: int | None = None, scheduler: str | None = None) -> Iterator[Workers]:
    """``workers`` local processes (:func:`local_executor`; default: all cores), or the cluster
    of the Dask scheduler at ``scheduler`` (:func:`connect`). On an exception (an interrupt)
    the queued runs are cancelled rather than waited for."""
    if scheduler is not None:
        client = connect(scheduler)
        pool = Workers(client.get_executor(), f"Dask scheduler {scheduler}", None)
    else:
        workers = workers or os.cpu_count() or 1
        client, pool = None, Workers(local_executor(workers), f"{workers} local processes", workers)
    try:
        yield pool
    except BaseException:
        if client is None:
            pool.executor.shutdown(wait=False, cancel_futures=True)
        raise
    else:
        pool.executor.shutdown()
    finally:
        if client is not None:
            client.close()


def connect(address: str, *, timeout_s: float = SCHEDULER_TIMEOUT_S):
    """A Dask client of the scheduler at ``address``; SweepError naming the address and what to
    check when it is not an address or does not answer within ``timeout_s`` (Dask's own default
    waits 30 s and then raises a bare OSError)."""
    from distributed import Client

    try:
        return Client(address, timeout=timeout_s)
    except (ValueError, TypeError) as exc:
        raise SweepError(f"scheduler {address!r} is not a scheduler address ({exc}): expected tcp://HOST:PORT, "
                         "the address `dask scheduler` prints (port 8786 by default)") from None
    except OSError as exc:
        raise SweepError(f"cannot reach the Dask scheduler at {address} ({exc}): check that it is running "
                         "(`dask scheduler` prints its address), that the host and port are right, and that no firewall "
                         "blocks the port") from None


def local_executor(workers: int) -> Executor:
    """``workers`` local processes, spawned (fresh interpreters, no forked state), that end when
    this process ends however it ends (:func:`_exit_with_parent`)."""
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor

    return ProcessPoolExecutor(max_workers=workers, mp_context=multiprocessing.get_context("spawn"),
                               initializer=_exit_with_parent, initargs=(os.getpid(),))


#: prctl's option that asks for a signal when the parent ends (linux/prctl.h)
PR_SET_PDEATHSIG = 1


def _exit_with_parent(parent: int) -> None:
    """Worker initializer: end this worker when ``parent`` (the sweep) ends. Without it a sweep
    killed outright (kill -9, the out-of-memory killer) leaves its workers computing on, then
    waiting forever (each holds both ends of the pool's queue, so none sees it close).

    On Linux the kernel sends the worker SIGKILL when its parent ends (prctl PR_SET_PDEATHSIG):
    at once, even in the middle of a numba kernel, which holds the GIL for as long as it runs,
    and with nothing to run in the worker; the parent is checked after setting it, in case it
    ended before. The signal follows the parent *thread* that started the worker: the pool
    starts its workers in the thread that submits, which for :func:`sweep` is the thread that
    waits for them. Elsewhere, :func:`_watch_parent`."""
    if sys.platform.startswith("linux"):
        import ctypes
        import signal

        if ctypes.CDLL(None, use_errno=True).prctl(PR_SET_PDEATHSIG, signal.SIGKILL) == 0:
            if os.getppid() != parent:
                os._exit(1)
            return
    _watch_parent(parent)


def _watch_parent(parent: int) -> None:
    """Worker initializer: a daemon thread ends this worker when its parent pid is no longer
    ``parent`` (it was re-parented: its parent ended), checking every second (portable, but it
    needs the GIL, so it waits for a numba kernel that runs to return)."""
    def watch():
        while os.getppid() == parent:
            time.sleep(1.0)
        os._exit(1)

    threading.Thread(target=watch, name="exit-with-parent", daemon=True).start()
