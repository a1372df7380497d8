"""Result files of an analysis, written as the run goes (a crash keeps what was written).

``pushover.csv``: one row per equilibrium state, appended and flushed as each is found.
``summary.json``: collapse angle, load multiplier, model and analysis parameters, run time,
drydem version (a tilting analysis adds drift-limit angles, cycles, lost blocks; a limit
analysis its method and solver status); written at the end.
"""

from __future__ import annotations

import csv
import json
import shutil
from dataclasses import asdict
from pathlib import Path

from drydem import __version__
from drydem.errors import DrydemError
from drydem.files import replaced_atomically, writable_folder
from drydem.analysis.limit import LimitResult, LimitSettings
from drydem.analysis.tilt import Record, TiltResult
from drydem.model.assembly import Model

PUSHOVER_COLUMNS = ("tilt_deg", "load_multiplier", "ux_m", "uz_m", "drift", "cycles")


class PushoverWriter:
    """Writes ``pushover.csv`` in ``folder`` anew and appends equilibrium states to it as they
    are found (a resumed analysis first hands it those of its checkpoint, so the file always
    matches the checkpoint, whatever a kill left in it)."""

    def __init__(self, folder: Path):
        self.path = folder / "pushover.csv"
        with self.path.open("w", newline="") as f:
            csv.writer(f).writerow(PUSHOVER_COLUMNS)

    def __call__(self, record: Record) -> None:
        with self.path.open("a", newline="") as f:
            csv.writer(f).writerow(
                [f"{record.tilt_deg:.6f}", f"{record.load_multiplier:.8g}", f"{record.ux_m:.8g}", f"{record.uz_m:.8g}",
                 f"{record.drift:.8g}", record.cycles]
            )


def tilt_summary(result: TiltResult, model: Model) -> dict:
    """The content of a tilting analysis' ``summary.json``."""
    return {
        "collapse_angle_deg": result.collapse_angle_deg,
        "load_multiplier": result.load_multiplier,
        "last_equilibrium_deg": result.last_equilibrium_deg,
        "stable_under_gravity": result.stable_under_gravity,
        "ended_by": result.ended_by,
        "drift_limit_angles_deg": result.drift_limit_angles_deg,
        "monitored_block": result.monitored_block,
        "wall_height_m": result.wall_height_m,
        "lost_blocks": [{"block": name, "tilt_deg": tilt} for name, tilt in result.lost_blocks],
        "equilibrium_states": len(result.records),
        "cycles": result.cycles,
        "runtime_s": round(result.runtime_s, 3),
        "analysis": asdict(result.settings),
        "model": model_summary(model),
        "drydem_version": __version__,
    }


def limit_summary(result: LimitResult, settings: LimitSettings, model: Model, runtime_s: float) -> dict:
    """The content of a limit analysis' ``summary.json``."""
    return {
        "collapse_angle_deg": result.collapse_angle_deg,
        "load_multiplier": result.load_multiplier,
        "method": result.method,
        "solver_status": result.status,
        "iterations": result.iterations,
        "converged": result.converged,
        "load_multiplier_history": result.history,
        "runtime_s": round(runtime_s, 3),
        "analysis": asdict(settings),
        "model": model_summary(model),
        "drydem_version": __version__,
    }


def model_summary(model: Model) -> dict:
    """What a result says of its model: source, size, mass and parameters."""
    return {
        "source": model.source,
        "blocks": model.n_blocks,
        "movable_blocks": int(model.block_movable.sum()),
        "mass_kg": model.total_mass,
        "joint": asdict(model.joint),
        "contacts": asdict(model.contacts) | {"tolerance_m": model.contact_tolerance},
        "supports": asdict(model.supports),
        "solver": asdict(model.solver),
    }


def prepare_folder(folder: Path, outputs: tuple[str, ...], *, resume: bool | None = False, overwrite: bool = False) -> Path:
    """Make ``folder`` ready for a run's ``outputs`` (file and folder names) and return it.

    Nothing is lost: a folder that already holds files is refused (DrydemError naming them)
    unless the run goes on from it (``resume``; None for a run that cannot, so the message does
    not offer it) or ``overwrite`` is asked, which deletes the
    earlier run's ``outputs`` first, so no stale file (an old video, VTK frames) is left beside
    the new results; other files are kept. A path that is not a folder, or cannot be made or
    written in, is refused with the reason (:func:`drydem.files.writable_folder`).
    """
    present = sorted(p.name for p in writable_folder(folder).iterdir())
    if present and not resume:
        ours = [name for name in present if name in outputs]
        if not overwrite:
            what = f"another run ({', '.join(ours)})" if ours else f"other files ({', '.join(present[:5])}{', ...' if len(present) > 5 else ''})"
            go_on = "" if resume is None else ", --resume to go on from its checkpoint"
            raise DrydemError(f"{folder}: already holds {what}; pass --overwrite to replace it{go_on}, or another --out")
        for name in ours:
            path = folder / name
            shutil.rmtree(path) if path.is_dir() and not path.is_symlink() else path.unlink()
    return folder


def write_summary(folder: Path, content: dict) -> Path:
    """``content`` as ``folder/summary.json``."""
    path = folder / "summary.json"
    with replaced_atomically(path) as partial:
        partial.write_text(json.dumps(content, indent=2) + "\n")
    return path
