"""Checkpoints of a tilting analysis: what it saves at every equilibrium (:func:`save`), what a
checkpoint must match to be resumed (:func:`fingerprint`, :func:`check_fingerprint`), and the
resume itself (:func:`resume`)."""

from __future__ import annotations

import ast
import json
import math
import os
from dataclasses import asdict
from pathlib import Path

import numpy as np

from drydem.analysis.drift import drifts
from drydem.analysis.tilt.run import TiltRun
from drydem.analysis.tilt.settings import Record, TiltSettings
from drydem.engine.checkpoint import load_checkpoint, save_checkpoint, unreadable
from drydem.errors import ModelError
from drydem.model.assembly import Model
from drydem.model.state import State


def fingerprint(model: Model, settings: TiltSettings) -> dict[str, str]:
    """What a checkpoint must match to be resumed, by name: the model's source, blocks (a hash
    of their geometry, densities and fixities), every parameter of its tables and every tilt
    setting (values as repr strings)."""
    items = {"model": model.source, "blocks": f"{model.n_blocks} blocks, geometry {model.blocks_digest[:12]}"}
    for table in ("joint", "contacts", "supports", "solver"):
        items |= {f"[{table}] {k}": v for k, v in asdict(getattr(model, table)).items()}
    items |= {f"tilt setting {k}": v for k, v in asdict(settings).items()}
    return {k: repr(v) for k, v in items.items()}


def check_fingerprint(checkpoint: Path, saved: dict, fingerprint: dict[str, str]) -> None:
    """ModelError naming every setting in which ``checkpoint`` differs from this run."""
    try:
        before = json.loads(str(saved["fingerprint"]))
    except (KeyError, ValueError):
        before = None
    if not isinstance(before, dict):
        raise ModelError(f"{checkpoint}: written by another version of drydem (no settings to compare); start again from the "
                         "beginning (--overwrite instead of --resume)")
    differ = [f"{k}: {before.get(k, 'absent')} in the checkpoint, {v} now" for k, v in fingerprint.items()
              if before.get(k) != v and not (k == "model" and _same_file(before.get(k), v))]
    if differ:
        raise ModelError(f"{checkpoint}: the checkpoint is of another model or protocol ({'; '.join(differ)}); not resuming")


def _same_file(before: str | None, now: str) -> bool:
    """Whether two models' sources (their fingerprints' repr strings) name the same file by two
    paths (``brick.toml`` and ``/home/me/brick.toml``): the model's blocks and parameters are
    compared anyway, so the path it was read by is no reason to refuse a resume."""
    try:
        return before is not None and os.path.samefile(ast.literal_eval(before), ast.literal_eval(now))
    except (OSError, ValueError, SyntaxError, TypeError):
        return False


def saved_records(saved: dict) -> np.ndarray:
    """A checkpoint's equilibrium records (:func:`progress`) as rows (tilt deg, ux m, uz m, drift,
    cycles); ModelError unless they are numbers, five a row."""
    records = np.asarray(saved["records"])
    if records.dtype.kind not in "iuf" or records.size % 5:
        raise ModelError(f"its records ({records.dtype}, {records.size} numbers): must be rows of five numbers "
                         "(tilt, ux, uz, drift, cycles)")
    return records.astype(float).reshape(-1, 5)


def progress(records: list[Record], run: TiltRun, theta: float, step: float) -> dict:
    """The protocol's position, for a checkpoint (with the equilibria before the last one, for
    the predictor)."""
    nb = run.model.n_blocks
    previous = run.equilibria[:-1]
    return {
        "previous_theta_deg": np.array([th for th, _ in previous], dtype=float),
        "previous_position": np.array([s.position for _, s in previous]).reshape(-1, nb, 3),
        "previous_quaternion": np.array([s.quaternion for _, s in previous]).reshape(-1, nb, 4),
        "records": np.array([[r.tilt_deg, r.ux_m, r.uz_m, r.drift, r.cycles] for r in records]),
        "lost_blocks": np.array([name for name, _ in run.lost], dtype=str),
        "lost_tilt_deg": np.array([t for _, t in run.lost], dtype=float),
        "theta_deg": theta,
        "step_deg": step,
    }


def save(checkpoint: Path, run: TiltRun, records: list[Record], theta: float, step: float, fingerprint: dict[str, str],
         runtime_s: float) -> None:
    """Save ``run`` at its equilibrium at ``theta`` (deg), with ``records``, the ``step`` (deg)
    to take next, the run's ``fingerprint`` and its ``runtime_s`` so far, to ``checkpoint``."""
    saved = progress(records, run, theta, step) | {"fingerprint": json.dumps(fingerprint), "runtime_s": runtime_s}
    save_checkpoint(checkpoint, run.sim.snapshot(), saved)


def resume(run: TiltRun, checkpoint: Path, fingerprint: dict[str, str], records: list[Record]) -> tuple[float, float, float]:
    """Restore ``run`` and ``records`` from ``checkpoint``; returns the tilt (deg) of its last
    equilibrium, the step (deg) to take next and the runtime (s) the run had reached (0 for a
    checkpoint of a drydem before it kept it). ModelError if it is of another model or
    protocol; DrydemError naming the file if what it holds does not fit the model (a file
    edited or spoiled: its contacts are checked before the compiled kernels index by them)."""
    snapshot, saved = load_checkpoint(checkpoint)
    check_fingerprint(checkpoint, saved, fingerprint)
    try:
        return _restored(run, snapshot, saved, records)
    except (ModelError, ValueError, TypeError, IndexError, KeyError) as exc:
        raise unreadable(checkpoint, exc) from None


def _restored(run: TiltRun, snapshot, saved: dict, records: list[Record]) -> tuple[float, float, float]:
    """:func:`resume` once the file is read and its fingerprint matches."""
    theta, step, settings = float(saved["theta_deg"]), float(saved["step_deg"]), run.settings
    runtime_s = float(saved["runtime_s"]) if "runtime_s" in saved else 0.0
    if not (math.isfinite(runtime_s) and runtime_s >= 0.0):
        raise ModelError(f"its runtime {runtime_s!r} s: must be a finite number >= 0")
    if not 0.0 <= theta <= settings.max_angle_deg + 1e-9:  # the protocol's own slack at the maximum angle
        raise ModelError(f"its last equilibrium at {theta!r} deg: must be in [0, {settings.max_angle_deg:g}] deg (max_angle_deg)")
    if not 0.0 < step <= settings.first_step() * (1 + 1e-9):  # an adaptive run's first step may pass 90 deg
        raise ModelError(f"its next step of {step!r} deg: must be in (0, {settings.first_step():g}] deg (the first step)")
    lost = list(zip(saved["lost_blocks"].tolist(), saved["lost_tilt_deg"].tolist()))
    unknown = sorted({name for name, _ in lost} - set(run.model.block_name))
    if unknown:
        raise ModelError(f"its lost blocks {unknown}: not blocks of the model")
    run.sim.restore(snapshot)
    rows = saved_records(saved)
    if not np.isfinite(rows).all() or (np.diff(rows[:, 0]) <= 0).any() or (rows[:, 4] < 0).any() or (rows[:, 4] % 1).any() \
            or (rows.size and abs(rows[-1, 0] - theta) > 1e-9):  # found by a hunt: reversed records resumed to wrong drift angles
        raise ModelError("its records: must be rows of finite numbers (tilt, ux, uz, drift, cycles), the tilts increasing to its last "
                         "equilibrium's, the cycles whole, none or more")
    rows[:, 3] = drifts(rows[:, 1], run.height)  # as Record defines it (a checkpoint before it measured it from as drawn)
    records += [Record(tilt, ux, uz, drift, int(cycles)) for tilt, ux, uz, drift, cycles in rows.tolist()]
    run.lost = lost
    rest = np.zeros((run.model.n_blocks, 3))
    for th, x, q in zip(saved["previous_theta_deg"], saved["previous_position"], saved["previous_quaternion"]):
        run.remember(float(th), run.sim.fit_state(State(x, q, rest.copy(), rest.copy()), "previous equilibrium"))
    run.remember(theta)
    return theta, step, runtime_s
