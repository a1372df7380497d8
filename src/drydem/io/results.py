"""Result files of an analysis, written as the run goes (a crash keeps what was written).

``pushover.csv``: one row per equilibrium state, appended and flushed as each is found.
``history.csv`` (a shaking-table analysis): one row per output interval of the monitored
block's response, appended and flushed as each comes (:class:`HistoryWriter`), then written
whole from the analysis' :class:`~drydem.analysis.shake.History` at the end
(:func:`write_history_csv`).
``summary.json``: collapse angle, load multiplier, model and analysis parameters, run time,
drydem version (a tilting analysis adds drift-limit angles, cycles, lost blocks; a limit
analysis its method and solver status; a shaking-table analysis its own: :func:`shake_summary`);
written at the end.
"""

from __future__ import annotations

import csv
import json
import os
import re
import shutil
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from dataclasses import asdict, fields
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from drydem import __version__
from drydem.errors import DrydemError
from drydem.files import WRITING, held, locked_by_another, regular_file, replaceable, replaced_atomically, writable_folder, write_text

if TYPE_CHECKING:  # annotations only: importing the limit analysis takes scipy.optimize, a third of a second
    from drydem.analysis.limit import LimitResult, LimitSettings
    from drydem.analysis.shake import History, ShakeResult, ShakeSettings
    from drydem.analysis.tilt import Record, TiltResult
    from drydem.model.assembly import Model

PUSHOVER_COLUMNS = ("tilt_deg", "load_multiplier", "ux_m", "uz_m", "drift", "cycles")
#: the columns of history.csv: the first five are the public interface, the others come after
HISTORY_COLUMNS = ("time_s", "ground_acc_x_m_s2", "ux_m", "uz_m", "rotation_rad", "ground_acc_y_m_s2", "ground_acc_z_m_s2", "uy_m")


class PushoverWriter:
    """Writes ``pushover.csv`` in ``folder`` anew and appends equilibrium states to it as they
    are found (a resumed analysis first hands it those of its checkpoint, so the file always
    matches the checkpoint, whatever a kill left in it). A DrydemError if a link, a pipe or a
    device is there (drydem.files.replaceable): a link would be written through, a pipe waited on."""

    def __init__(self, folder: Path):
        self.path = replaceable(folder / "pushover.csv", True, option="--resume")
        self.rows = 0
        with self.path.open("w", newline="") as f:
            csv.writer(f).writerow(PUSHOVER_COLUMNS)

    def __call__(self, record: Record) -> None:
        with self.path.open("a", newline="") as f:
            csv.writer(f).writerow(
                [f"{record.tilt_deg:.6f}", f"{record.load_multiplier:.8g}", f"{record.ux_m:.8g}", f"{record.uz_m:.8g}",
                 f"{record.drift:.8g}", record.cycles]
            )
        self.rows += 1


def _history_cells(time_s: float, ground: Sequence[float | None], displacement: Sequence[float | None],
                   rotation_rad: float | None) -> list[str]:
    """A row of history.csv in the order of HISTORY_COLUMNS; a value not known (None) is an empty cell."""

    def cell(value, digits=8):
        return "" if value is None else f"{float(value):.{digits}g}"

    (gx, gy, gz), (ux, uy, uz) = ground, displacement
    return [cell(time_s, 10), cell(gx), cell(ux), cell(uz), cell(rotation_rad), cell(gy), cell(gz), cell(uy)]


class HistoryWriter:
    """Writes ``history.csv`` in ``folder`` anew (its header) and appends a row, flushed, at each
    call of :meth:`row`, so that an interrupted run keeps the rows it reached."""

    def __init__(self, folder: Path):
        self.path = folder / "history.csv"
        self.rows = 0
        with self.path.open("w", newline="") as f:
            csv.writer(f).writerow(HISTORY_COLUMNS)

    def row(self, time_s: float, ground_acceleration_m_s2: Sequence[float | None], displacement_m: Sequence[float | None],
            rotation_rad: float | None) -> None:
        """One row: time (s), the table's acceleration (x, y, z; m/s2), the monitored block's
        displacement relative to the table (x, y, z; m) and its rotation about y (rad); None
        for a value not known (an empty cell)."""
        with self.path.open("a", newline="") as f:
            csv.writer(f).writerow(_history_cells(time_s, ground_acceleration_m_s2, displacement_m, rotation_rad))
        self.rows += 1


def write_history_csv(folder: Path, history: History) -> Path:
    """``history`` as ``folder/history.csv`` (HISTORY_COLUMNS, one row per output interval),
    written whole or not at all: it replaces the rows :class:`HistoryWriter` wrote as the run went."""
    path = folder / "history.csv"
    with replaced_atomically(path) as partial, partial.open("w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(HISTORY_COLUMNS)
        for k, time_s in enumerate(history.time_s):
            moved = (history.ux_m[k], history.uy_m[k], history.uz_m[k])
            writer.writerow(_history_cells(time_s, history.ground_acceleration_m_s2[k], moved, history.rotation_rad[k]))
    return path


def fall_rule(settings: ShakeSettings) -> str:
    """When a block has fallen in a shaking-table analysis, in words."""
    return (f"a block has fallen when it turned more than {settings.fall_rotation_deg:g} deg from its orientation at rest, "
            f"or its centroid dropped more than {settings.lost_drop_heights:g} of its heights below where it rested")


def shake_settings_summary(settings: ShakeSettings) -> dict:
    """The settings of a shaking-table analysis as plain JSON: the motion by its name (its
    samples are in history.csv and its description in the summary's ``motion``)."""
    plain = {f.name: getattr(settings, f.name) for f in fields(settings) if f.name != "motion"}
    return {"motion": settings.motion.name, **plain, "analysed_s": settings.analysed_s}


def shake_summary(result: ShakeResult, model: Model, *, scale: float = 1.0, baseline_corrected: bool = False) -> dict:
    """The content of a shaking-table analysis' ``summary.json``. ``scale`` and
    ``baseline_corrected`` say how the caller made the analysed motion from its source (a
    record or pulse multiplied by ``scale``, then baseline-corrected or not); the peaks and the
    PGA are those of the motion analysed."""
    motion = result.settings.motion
    fallen = [{"block": name, "time_s": time_s, "rule": rule} for name, time_s, rule in result.fallen_blocks]
    return {
        "overturned": result.overturned,
        "overturn_rule": fall_rule(result.settings),
        "fallen_blocks": fallen,
        "first_fall_s": min((f["time_s"] for f in fallen), default=None),
        "monitored_block": result.monitored_block,
        "max_rotation_rad": result.max_rotation_rad,
        "max_rotation_deg": float(np.degrees(result.max_rotation_rad)),
        "max_displacement_m": result.max_displacement_m,
        "residual_displacement_m": result.residual_displacement_m,
        "duration_s": result.duration_s,
        "ended_by": result.ended_by,
        "cycles": result.cycles,
        "runtime_s": round(result.runtime_s, 3),
        "timestep_s": result.timestep_s,
        "pga_m_s2": motion.pga_m_s2,
        "pga_g": motion.pga_g,
        "motion": {
            "name": motion.name,
            "duration_s": motion.duration_s,
            "samples": int(motion.time_s.size),
            "scale": scale,
            "baseline_corrected": baseline_corrected,
            "peaks_m_s2": list(motion.peaks_m_s2),
        },
        "contact_damping_ratio": result.contact_damping_ratio,
        "restitution": result.restitution,
        "history_rows": int(result.history.time_s.size),
        "analysis": shake_settings_summary(result.settings),
        "model": model_summary(model),
        "drydem_version": __version__,
    }


def tilt_summary(result: TiltResult, model: Model) -> dict:
    """The content of a tilting analysis' ``summary.json``."""
    return {
        "collapse_angle_deg": result.collapse_angle_deg,
        "load_multiplier": result.load_multiplier,
        "last_equilibrium_deg": result.last_equilibrium_deg,
        "stable_under_gravity": result.stable_under_gravity,
        "ended_by": result.ended_by,
        "drift_limit_angles_deg": {repr(limit): angle for limit, angle in result.drift_limit_angles_deg.items()},
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


#: the file a run holds its results folder by while it writes there (drydem.files.held): a
#: second run given the same folder is refused, not mixed in (deleted when the run ends)
FOLDER_LOCK = ".drydem.lock"
#: the file a Monte Carlo run (drydem.parametric.montecarlo, from Python too) holds its folder by
MONTECARLO_LOCK = ".montecarlo.lock"


def is_lock(name: str) -> bool:
    """Whether the file ``name`` is one of drydem's locks, which a run killed by the system (kill
    -9) may leave in its folder: no result (:data:`FOLDER_LOCK`, :data:`MONTECARLO_LOCK`, and
    the lock beside a file being written, drydem.files.partial_name with drydem.files.WRITING)."""
    return name in (FOLDER_LOCK, MONTECARLO_LOCK) or (name.startswith(".") and f".{WRITING}" in name)


def being_written(folder: Path) -> bool:
    """Whether a drydem run holds ``folder`` (its :data:`FOLDER_LOCK`, or the
    :data:`MONTECARLO_LOCK` a Monte Carlo run started from Python holds alone), through another
    open file than this process's own (drydem.files.locked_by_another)."""
    return any(locked_by_another(Path(folder) / lock) for lock in (FOLDER_LOCK, MONTECARLO_LOCK))


def writer_of(folder: Path) -> Path | None:
    """The folder, ``folder`` itself or one it lies in (symbolic links followed), that another
    drydem run is writing in (:func:`being_written`), or None: a run's folder holds folders of
    its own (a Monte Carlo run's samples/, a tilt's vtk/) that another run must not write in."""
    real = Path(os.path.realpath(folder))  # not Path.resolve, which raises RuntimeError on a loop of links
    return next((above for above in (real, *real.parents) if being_written(above)), None)


def refuse_if_written(folder: Path, advice: str) -> None:
    """A DrydemError if another drydem run is writing in ``folder`` or a folder it lies in
    (:func:`writer_of`): "FOLDER: another drydem run is writing there[ (in WRITER)]; ADVICE"."""
    writer = writer_of(folder)
    if writer is not None:
        inside = "" if writer == Path(os.path.realpath(folder)) else f" (in {writer})"
        raise DrydemError(f"{folder}: another drydem run is writing there{inside}; {advice}")


#: what a run is told to do when another holds its results folder
RUN_BUSY_ADVICE = "wait for it to end, or give another --out"


@contextmanager
def prepared_folder(folder: Path, outputs: tuple[str, ...], *, resume: bool | None = False, overwrite: bool = False) -> Iterator[Path]:
    """``folder``, ready for a run's ``outputs`` (file and folder names) and held by this process
    for the block (:data:`FOLDER_LOCK`): a DrydemError if another drydem process holds it or a
    folder it lies in (:func:`refuse_if_written`).

    Nothing is lost: a folder that already holds files is refused (DrydemError naming them)
    unless the run goes on from it (``resume``; None for a run that cannot, so the message does
    not offer it) or ``overwrite`` is asked, which deletes the
    earlier run's ``outputs`` first, so no stale file (an old video, VTK frames) is left beside
    the new results; other files are kept. Only a drydem run's outputs are deleted
    (:func:`drydem_run_folder`): files of those names that no drydem run wrote there (a user's
    samples/ or vtk/, a motion record called history.csv, a model file inside them: found by a
    hunt, each deleted) are refused, with ``overwrite`` too, and so are files in a run's output
    folders that no run writes there (:func:`_not_written_by_a_run`). The run marks the folder as its
    own (:data:`RUN_MARK`) for the block, and leaves the mark if it wrote anything. A path that
    is not a folder, or cannot be made or written in, is refused with the reason
    (:func:`drydem.files.writable_folder`).
    """
    refuse_if_written(folder, RUN_BUSY_ADVICE)  # before writable_folder makes it inside another run's
    folder = writable_folder(folder)
    busy = f"{folder}: another drydem run is writing there; {RUN_BUSY_ADVICE}"
    with held(folder / FOLDER_LOCK, busy):  # taken for this run: being_written only looked
        present = _present(folder)
        ours = [name for name in present if name in outputs]
        _check_outputs(folder, present, ours, resume=resume, overwrite=overwrite)
        for name in ours if overwrite and not resume else ():
            path = folder / name
            shutil.rmtree(path) if path.is_dir() and not path.is_symlink() else path.unlink()
        # replaced, not written through: a link there was followed to its target (found by a hunt)
        write_text(folder / RUN_MARK, f"a results folder of drydem {__version__}: drydem tilt, limit, shake or montecarlo\n")
        try:
            yield folder
        finally:
            if not _present(folder):  # a run refused before its first result leaves the folder as it found it
                (folder / RUN_MARK).unlink(missing_ok=True)


#: the file by which a results folder is a drydem run's (:func:`prepared_folder`)
RUN_MARK = ".drydem-run"


def _present(folder: Path) -> list[str]:
    """The names in ``folder`` but drydem's locks and its :data:`RUN_MARK`, sorted."""
    return sorted(p.name for p in folder.iterdir() if not is_lock(p.name) and p.name != RUN_MARK)


def _check_outputs(folder: Path, present: list[str], ours: list[str], *, resume: bool | None, overwrite: bool) -> None:
    """The rule of :func:`prepared_folder` on what ``folder`` holds (``present``, of which
    ``ours`` are named as a run's outputs): DrydemError if the run would replace or mix with
    them unasked, or if ``overwrite`` would delete files no drydem run wrote there (a run that
    goes on, ``resume``, is checked by what it reads: a checkpoint's digest and fingerprint)."""
    if ours and not resume and not drydem_run_folder(folder):
        raise DrydemError(f"{folder}: holds {', '.join(ours)}, named as a run's results but not written there by a drydem run "
                          f"(no {RUN_MARK} nor drydem summary.json): drydem deletes no file it did not write; move them away, "
                          "or give another --out")
    foreign = [path for name in ours for path in _not_written_by_a_run(folder, name)] if overwrite and not resume else []
    if foreign:
        raise DrydemError(f"{folder}: --overwrite would delete {', '.join(foreign[:5])}{', ...' if len(foreign) > 5 else ''}, "
                          "which no drydem run writes there: drydem deletes no file it did not write; move them away, "
                          "or give another --out")
    if present and not (resume or overwrite):
        go_on = "" if resume is None else ", --resume to go on with it (a run of this command)"
        others = f"{', '.join(present[:5])}{', ...' if len(present) > 5 else ''}"
        raise DrydemError(f"{folder}: already holds another run ({', '.join(ours)}); pass --overwrite to replace it{go_on}, "
                          "or another --out" if ours else
                          f"{folder}: already holds other files ({others}); pass --overwrite to write the run beside them "
                          "(they are kept), or another --out")


#: the files a run writes in its output folders (paths inside them, "/" between folders; a
#: name drydem is writing, .NAME.partial.SUFFIX or its lock, taken for NAME.SUFFIX): the VTK
#: series (drydem.io.vtk) and the Monte Carlo samples (drydem.parametric.montecarlo)
OUTPUT_FOLDER_FILES = {"vtk": re.compile(r"(blocks|contacts)(_\d+\.vtu|\.pvd)|frames\.csv|series\.json"),
                       "samples": re.compile(r"\d+/(summary\.json|pushover\.csv)")}
#: drydem's tag on a name being written (drydem.files.partial_name): .STEM.TAG.SUFFIX or .STEM.TAG
BEING_WRITTEN = re.compile(rf"\.(.+)\.(partial|{WRITING})(\.[^.]*)?")


def _not_written_by_a_run(folder: Path, name: str) -> list[str]:
    """The files inside output folder ``name`` of ``folder`` (none if it is a file) that no run
    writes there (:data:`OUTPUT_FOLDER_FILES`), as NAME/PATH (found by a hunt: --overwrite
    deleted a file a user had put in an earlier run's vtk/)."""
    written = OUTPUT_FOLDER_FILES.get(name)
    top = folder / name
    if not top.is_dir() or top.is_symlink():
        return []
    found = []
    for root, _, files in os.walk(top):
        for file in files:
            parts = Path(root, file).relative_to(top).parts
            inside = "/".join(BEING_WRITTEN.sub(r"\1\3", part) if BEING_WRITTEN.fullmatch(part) else part for part in parts)
            if written is None or not written.fullmatch(inside):
                found.append(f"{name}/{'/'.join(parts)}")
    return sorted(found)


def drydem_run_folder(folder: Path) -> bool:
    """Whether ``folder`` holds a drydem run's results: its :data:`RUN_MARK`, or a summary.json
    of drydem (its drydem_version: a finished run of a drydem before the mark)."""
    mark = folder / RUN_MARK
    if mark.is_file() and not mark.is_symlink():
        return True
    try:
        summary = json.loads(regular_file(folder / "summary.json", "").read_text(encoding="utf-8"))
    except (DrydemError, OSError, ValueError, RecursionError):
        return False
    return isinstance(summary, dict) and "drydem_version" in summary


def records_folder(folder: Path, command: str = "sweep") -> Path:
    """``folder`` made ready for the records of a sweep (or of ``command``, named in the advice;
    :func:`drydem.files.writable_folder`; sweeps
    may share one), unless it is a single run's, in which the records would be mixed: one being
    written (:func:`refuse_if_written`: it or a folder it lies in) or one written (its summary.json).
    DrydemError naming it otherwise."""
    advice = "give a sweep its own --out" if command == "sweep" else f"give {command} a sweep's folder, or a new one"
    refuse_if_written(folder, advice)
    folder = writable_folder(folder)
    if (folder / "summary.json").is_file():
        raise DrydemError(f"{folder}: holds a drydem run (summary.json), not a sweep's records; {advice}")
    return folder


def write_summary(folder: Path, content: dict) -> Path:
    """``content`` as ``folder/summary.json``."""
    path = folder / "summary.json"
    with replaced_atomically(path) as partial:
        partial.write_text(json.dumps(content, indent=2) + "\n")
    return path
