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

Every run has an id made of its parameters (and a hash of them), and its record, written
atomically to ``RESULTS/runs/ID.json`` as soon as it finishes, holds the parameters, the
status ("ok" or "failed" with the error), the summary and the pushover curve. A sweep started
again skips the runs already recorded, so a killed sweep loses only the runs in flight. Runs
go to any ``concurrent.futures`` executor: local processes, or a Dask cluster's.
"""

from __future__ import annotations

import hashlib
import itertools
import json
import os
import time
import traceback
from collections.abc import Callable, Iterable
from concurrent.futures import Executor, as_completed
from dataclasses import asdict, dataclass
from pathlib import Path

from drydem.errors import ModelError
from drydem.io.model_file import _no_unknown, read_toml

ANALYSES = {"tilt": ("fixed", "adaptive"), "limit": ("associative", "non-associative")}
DEFAULT_PROTOCOL = {"tilt": "adaptive", "limit": "associative"}
GRID_KEYS = {"name", "analysis", "targets", "kn", "ks", "friction", "points", "protocol", "increment_deg"}
DEFAULT_KEYS = {"friction", "points", "increment_deg"}


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


@dataclass(frozen=True)
class Study:
    name: str
    description: str
    runs: list[RunSpec]
    source: str


def load_study(path: str | Path) -> Study:
    """Read a study file; ModelError naming the file, the grid and the key."""
    path = Path(path)
    data, _ = read_toml(path)
    source = str(path)
    _no_unknown(data, {"study", "defaults", "grid"}, source, "top level")
    meta, defaults = data.get("study", {}), data.get("defaults", {})
    _no_unknown(meta, {"name", "description"}, source, "[study]")
    _no_unknown(defaults, DEFAULT_KEYS, source, "[defaults]")
    grids = data.get("grid")
    if not isinstance(grids, list) or not grids:
        raise ModelError(f"{source}: no [[grid]] entries")
    runs: list[RunSpec] = []
    for k, grid in enumerate(grids):
        runs += _grid_runs(defaults | grid, path.parent, f"{source}: [[grid]] #{k} ({grid.get('name', '?')!r})")
    unique = list(dict.fromkeys(runs))
    return Study(str(meta.get("name", path.stem)), str(meta.get("description", "")), unique, source)


def _grid_runs(grid: dict, folder: Path, where: str) -> list[RunSpec]:
    _no_unknown(grid, GRID_KEYS, where, "the grid")
    analysis = grid.get("analysis", "tilt")
    if analysis not in ANALYSES:
        raise ModelError(f"{where}: analysis = {analysis!r}: must be one of {list(ANALYSES)}")
    protocols = _list(grid.get("protocol", DEFAULT_PROTOCOL[analysis]))
    bad = [p for p in protocols if p not in ANALYSES[analysis]]
    if bad:
        raise ModelError(f"{where}: protocol {bad} is not one of {list(ANALYSES[analysis])} for a {analysis} analysis")
    targets = _list(grid.get("targets"))
    if not targets:
        raise ModelError(f"{where}: needs targets = [...] (built-in walls or files)")
    targets = [t if not (folder / t).is_file() else str(folder / t) for t in targets]
    kns = _list(grid.get("kn", [None]))
    ks_values = grid.get("ks", "kn")
    runs = []
    for target, protocol, kn, friction, points in itertools.product(
        targets, protocols, kns, _list(grid.get("friction", [None])), _list(grid.get("points", [None]))
    ):
        for ks in ([kn] if ks_values == "kn" else _list(ks_values)):
            runs.append(RunSpec(
                analysis=analysis, target=target, protocol=protocol,
                kn=None if kn is None else float(kn), ks=None if ks is None else float(ks),
                friction=None if friction is None else float(friction), points=points,
                increment_deg=float(grid.get("increment_deg", 0.1)),
            ))
    return runs


def _list(value) -> list:
    return value if isinstance(value, list) else [value]


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
    from dataclasses import replace

    from drydem.io.results import limit_summary, tilt_summary
    from drydem.io.target import load_target

    model = load_target(spec.target).model
    joint = {k: v for k, v in (("kn", spec.kn), ("ks", spec.ks), ("friction", spec.friction)) if v is not None}
    changes = {"joint": replace(model.joint, **joint)} if joint else {}
    if spec.points is not None:
        changes["contacts"] = replace(model.contacts, points_per_length=spec.points)
    model = model.replace(**changes) if changes else model
    if spec.analysis == "limit":
        from drydem.analysis.limit import LimitSettings, limit_analysis

        settings = LimitSettings(non_associative=spec.protocol == "non-associative")
        start = time.perf_counter()
        result = limit_analysis(model, settings)
        return {"summary": limit_summary(result, settings, model, time.perf_counter() - start), "pushover": []}
    from drydem.analysis.tilt import TiltSettings, tilt_analysis

    result = tilt_analysis(model, TiltSettings(increment_deg=spec.increment_deg, adaptive=spec.protocol == "adaptive"))
    curve = [[r.tilt_deg, r.ux_m, r.uz_m, r.drift, r.cycles] for r in result.records]
    return {"summary": tilt_summary(result, model), "pushover": curve}


def record_path(results: Path, run_id: str) -> Path:
    return Path(results) / "runs" / f"{run_id}.json"


def write_record(results: Path, record: dict) -> Path:
    """Write a run's record atomically (a temporary file renamed over the final one)."""
    path = record_path(results, record["id"])
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(json.dumps(record, indent=1) + "\n")
    os.replace(tmp, path)
    return path


def load_records(results: Path) -> list[dict]:
    """Every record in ``results/runs`` (in name order)."""
    return [json.loads(p.read_text()) for p in sorted((Path(results) / "runs").glob("*.json"))]


@dataclass(frozen=True)
class SweepOutcome:
    """How a sweep went: runs finished now, skipped (recorded before), failed (now)."""

    finished: int
    skipped: int
    failed: int


def pending(runs: Iterable[RunSpec], results: Path, *, retry_failed: bool = False) -> list[RunSpec]:
    """The runs without a record (or with a failed one, when ``retry_failed``)."""
    todo = []
    for spec in runs:
        path = record_path(results, spec.id)
        if not path.is_file() or (retry_failed and json.loads(path.read_text())["status"] == "failed"):
            todo.append(spec)
    return todo


def sweep(runs: list[RunSpec], results: Path, executor: Executor, *, retry_failed: bool = False,
          on_done: Callable[[dict], None] | None = None) -> SweepOutcome:
    """Run what is not recorded yet on ``executor``, writing each record as it comes in."""
    todo = pending(runs, results, retry_failed=retry_failed)
    futures = [executor.submit(run_one, spec) for spec in todo]
    failed = 0
    for future in as_completed(futures):
        record = future.result()
        write_record(results, record)
        failed += record["status"] == "failed"
        if on_done is not None:
            on_done(record)
    return SweepOutcome(finished=len(todo), skipped=len(runs) - len(todo), failed=failed)
