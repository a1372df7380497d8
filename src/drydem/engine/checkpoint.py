"""Checkpoints of a running analysis: everything needed to go on after a crash or a kill.

One ``.npz`` file holds a :class:`drydem.engine.simulation.Snapshot` (block state, contacts with their
shear history, neighbour list, blocks still in the analysis) and the analysis' own progress
(arrays and scalars by name). It is written to a temporary file and renamed
(:func:`drydem.files.replaced_atomically`), so a kill while writing leaves the previous
checkpoint intact; Ctrl-C or SIGTERM while it is written waits for it (:func:`drydem.files.uninterrupted`).
The file holds the SHA-256 digest of its arrays (:data:`DIGEST`): a file spoiled or edited since
it was written, or written by a drydem before the digest, is refused, not resumed into wrong
numbers; the analysis that resumes one checks its structure against the model too.
"""

from __future__ import annotations

import hashlib
import zipfile
from collections.abc import Mapping
from pathlib import Path

import numpy as np

from drydem.engine.contacts import NeighbourList, SubContacts
from drydem.engine.simulation import Snapshot
from drydem.errors import DrydemError, ModelError
from drydem.files import regular_file, replaced_atomically, uninterrupted
from drydem.model.state import State

_PARTS = {"state": State, "contacts": SubContacts, "neighbours": NeighbourList, "broad_state": State}
#: the Snapshot's timestep and velocity step, s (NaN for None): absent from an earlier drydem's checkpoint
OPTIONAL_STEPS = ("timestep", "velocity_step_s")


def save_checkpoint(path: Path, snapshot: Snapshot, progress: dict) -> None:
    """Write ``snapshot`` and ``progress`` (name -> array or scalar) to ``path`` atomically, at
    that very name whatever its suffix (``.npz`` or another, or none)."""
    arrays = {f"{part}.{name}": value for part in _PARTS for name, value in getattr(snapshot, part)._asdict().items()}
    arrays |= {"active": snapshot.active, "cycles": snapshot.cycles, "time_s": snapshot.time_s,
               "scaled_timestep": np.nan if snapshot.scaled_timestep is None else snapshot.scaled_timestep,
               "farthest_travel_kg_m": snapshot.farthest_travel_kg_m, "blocks_digest": snapshot.blocks_digest}
    arrays |= {name: np.nan if getattr(snapshot, name) is None else getattr(snapshot, name) for name in OPTIONAL_STEPS}
    arrays = {name: np.asarray(value) for name, value in arrays.items()}
    arrays |= {f"progress.{name}": np.asarray(value) for name, value in progress.items()}
    arrays[DIGEST] = np.asarray(digest(arrays))
    with uninterrupted(), replaced_atomically(path) as partial, open(partial, "wb") as file:
        # to an open file: np.savez appends ".npz" to a file name without that suffix, and the
        # file would then not be at the partial name that replaces ``path`` (ck.json, ck)
        np.savez(file, **arrays)


#: the name of the array holding the SHA-256 digest of a checkpoint's other arrays (:func:`digest`)
DIGEST = "sha256"


def digest(arrays: Mapping[str, np.ndarray]) -> str:
    """The SHA-256 digest (hex) of ``arrays`` (name -> array): each one's name, dtype, shape and
    bytes, in the order of their names."""
    found = hashlib.sha256()
    for name in sorted(arrays):
        array = np.ascontiguousarray(arrays[name])
        found.update(f"{name}|{array.dtype.str}|{array.shape}|".encode())
        found.update(array.tobytes())
    return found.hexdigest()


def _check_digest(data) -> None:
    """ValueError unless the checkpoint ``data`` (an open NpzFile) holds the digest of its other
    arrays (:func:`digest`)."""
    if DIGEST not in data.files:
        raise ValueError("it holds no SHA-256 digest of its arrays: written by an earlier drydem, or not by drydem")
    held = str(data[DIGEST])
    found = digest({key: data[key] for key in data.files if key != DIGEST})
    if found != held:
        raise ValueError(f"its arrays have changed since it was written (SHA-256 {found[:12]}..., written {held[:12]}...)")


def load_checkpoint(path: Path) -> tuple[Snapshot, dict]:
    """The snapshot and progress saved by :func:`save_checkpoint`; DrydemError naming the file
    if it is missing, empty, truncated, not a drydem checkpoint, or no regular file (a pipe would
    be waited on forever)."""
    try:
        with np.load(regular_file(path, "a checkpoint is the checkpoint.npz a run writes")) as data:
            _check_digest(data)
            parts = {part: cls(**{name: data[f"{part}.{name}"] for name in cls._fields}) for part, cls in _PARTS.items()}
            scaled, time_s, farthest = (float(data[key]) for key in ("scaled_timestep", "time_s", "farthest_travel_kg_m"))
            if not 0.0 <= farthest < np.inf:
                raise ValueError(f"farthest_travel_kg_m = {farthest}: must be a finite number >= 0")
            steps = {name: float(data[name]) for name in OPTIONAL_STEPS if name in data.files}
            snapshot = Snapshot(**parts, active=data["active"], cycles=int(data["cycles"]), time_s=time_s,
                                scaled_timestep=None if np.isnan(scaled) else scaled, blocks_digest=str(data["blocks_digest"]),
                                farthest_travel_kg_m=farthest, **{name: None if np.isnan(step) else step for name, step in steps.items()})
            progress = {key.removeprefix("progress."): data[key] for key in data.files if key.startswith("progress.")}
    except (OSError, ValueError, KeyError, EOFError, MemoryError, zipfile.BadZipFile, ModelError) as exc:
        # np.load raises each of these for a missing, empty, truncated or foreign file (MemoryError:
        # an array's header claiming terabytes)
        raise unreadable(path, exc) from None
    return snapshot, progress


def unreadable(path: Path, reason: Exception) -> DrydemError:
    """The error for a checkpoint at ``path`` that cannot be read or resumed, saying why (``reason``) and what to do."""
    return DrydemError(f"{path}: not a readable drydem checkpoint ({type(reason).__name__}: {reason}); "
                       "start the analysis again from the beginning (on the command line: --overwrite instead of --resume)")
