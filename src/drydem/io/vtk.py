"""VTK output for ParaView (unstructured grids ``.vtu`` via meshio, ``.pvd`` series index).

Blocks: one polyhedron cell (VTK_POLYHEDRON) per block, in model order, with cell fields
``block_id`` (index into the model's blocks), ``fixed`` (1: all six degrees of freedom fixed),
``active`` (0: taken out of the analysis), ``mass`` (kg), ``displacement`` (m, of the centroid
from the model file) and its ``displacement_magnitude``, ``rotation`` (rotation vector from the
model file, rad), ``velocity`` (m/s) and ``angular_velocity`` (rad/s).

Sub-contacts: one vertex cell per sub-contact at its incident material point, with point
fields ``normal_force`` (N, compression positive), ``shear_force`` (N, on the incident block)
and its magnitude, ``slip`` (0 open, 1 stuck, 2 sliding: the shear force at the Coulomb limit
c A + mu N), ``gap`` (m, negative when closed) and the two blocks.

Series: :class:`VtkSeries` (a tilting analysis' frames, indexed by frame number and tilt) and
:class:`ShakeSeries` (a shaking-table analysis', indexed by model time).
"""

from __future__ import annotations

import csv
import io
import json
import os
from itertools import groupby
from pathlib import Path
from xml.sax.saxutils import quoteattr

import numpy as np

from drydem.engine.contacts import SubContacts, world_points
from drydem.errors import DrydemError, ModelError, plain_reason
from drydem.files import read_text, replaced_atomically, writable
from drydem.model.assembly import Model
from drydem.model.geometry import described, real_array
from drydem.model.parameters import FILE_PATH, InstanceOf, Range, check_arguments, shown
from drydem.model.rotation import matrices
from drydem.model.state import State, checked_state

OPEN, STUCK, SLIDING = 0, 1, 2


def write_vtu(model: Model, path: str | Path, state: State | None = None, active: np.ndarray | None = None) -> Path:
    """Write the blocks at ``state`` (default: as in the model file) to ``path`` (ending in .vtu);
    ``active`` (default: all) says, block by block, which are still in the analysis. ModelError
    naming an argument that is not what it must be: ``state`` a State of the model's blocks
    (:func:`~drydem.model.state.checked_state`), ``active`` one boolean per block."""
    import meshio
    from scipy.spatial.transform import Rotation

    check_arguments("write_vtu", {"model": InstanceOf(Model), "path": FILE_PATH}, model=model, path=path)
    if Path(path).suffix.lower() != ".vtu":  # found by a hunt: VTU's XML was written to x.txt, which ParaView does not open as VTU
        raise ModelError(f"write_vtu path = {shown(str(path))}: the suffix {Path(path).suffix!r} is no VTU file's; give a path ending in .vtu")
    state = State.at_rest(model.block_centroid) if state is None else checked_state(state, model.n_blocks, "write_vtu")
    active = np.ones(model.n_blocks, dtype=bool) if active is None else _flags(active, model.n_blocks, "write_vtu active")
    points, cells, offset = [], [], 0
    for b, shape in enumerate(model.block_shape):
        points.append(model.world_vertices(b, state.position[b], state.quaternion[b]))
        cells.append((f"polyhedron{len(shape.vertices)}", [np.asarray(face) + offset for face in shape.faces]))
        offset += len(shape.vertices)
    blocks = [(kind, [faces for _, faces in run]) for kind, run in groupby(cells, key=lambda cell: cell[0])]
    displacement = state.position - model.block_centroid
    rotation = Rotation.from_quat(np.roll(state.quaternion, -1, axis=1)).as_rotvec()  # (x, y, z, w) order
    fields = {
        "block_id": np.arange(model.n_blocks),
        "fixed": model.block_fixed.all(axis=1).astype(np.int8),
        "active": active.astype(np.int8),
        "mass": model.block_mass,
        "displacement": displacement,
        "displacement_magnitude": np.linalg.norm(displacement, axis=1),
        "rotation": rotation,
        "velocity": state.velocity,
        "angular_velocity": state.angular_velocity,
    }
    sizes = np.cumsum([0] + [len(faces) for _, faces in blocks])
    cell_data = {name: [values[a:b] for a, b in zip(sizes[:-1], sizes[1:])] for name, values in fields.items()}
    with replaced_atomically(writable(path)) as partial:
        meshio.write(partial, meshio.Mesh(np.vstack(points), blocks, cell_data=cell_data), file_format="vtu")
    return Path(path)


def _flags(value, count: int, where: str) -> np.ndarray:
    """``value`` as a (count,) boolean array; ModelError naming ``where`` unless it is one (an
    array or a list of True and False: 0 and 1 are numbers, not flags)."""
    try:
        array = np.asarray(value)
    except (TypeError, ValueError):  # ragged lists
        array = None
    if array is None or array.dtype != np.bool_ or array.shape != (count,):
        raise ModelError(f"{where} must be a ({count},) array of booleans, one per block (True: in the analysis), got {described(value)}")
    return array


def write_contacts_vtu(model: Model, path: str | Path, state: State, sub: SubContacts) -> Path:
    """Write the sub-contacts at ``state`` to ``path`` (.vtu): points with their forces and slip state."""
    import meshio

    point, gap, _ = world_points(sub, state.position, matrices(state.quaternion))
    shear = np.linalg.norm(sub.shear_force, axis=1)
    joint = model.joint
    limit = joint.cohesion * sub.area * sub.intact + joint.friction * sub.normal_force
    slip = np.where(sub.normal_force <= 0.0, OPEN, np.where(shear >= limit * (1 - 1e-6), SLIDING, STUCK))
    data = {
        "normal_force": sub.normal_force, "shear_force": sub.shear_force, "shear_force_magnitude": shear,
        "slip": slip.astype(np.int8), "gap": gap, "block_ref": sub.block_ref, "block_inc": sub.block_inc,
    }
    cells = [("vertex", np.arange(sub.count)[:, None])] if sub.count else []
    meshio.write(Path(path), meshio.Mesh(point.reshape(-1, 3), cells, point_data=data), file_format="vtu")
    return Path(path)


#: the kinds of a tilting series' frames in its ``frames.csv`` (drydem.analysis.tilt.Frame)
FRAME_KINDS = ("equilibrium", "past collapse")
#: the load's directions in a series' ``frames.csv``, by index (0: x, 1: y)
LOAD_AXES = ("x", "y")
LOAD_DIRECTION = Range(0, len(LOAD_AXES) - 1, integer=True)
#: keep every N-th equilibrium frame (``drydem tilt --save-every``)
SAVE_EVERY = Range(1, None, integer=True)


class VtkSeries:
    """Frames of a tilting analysis (drydem.analysis.tilt.Frame) as two VTK time series in
    ``folder``: ``blocks_NNNN.vtu`` and ``contacts_NNNN.vtu``, indexed by ``blocks.pvd`` and
    ``contacts.pvd`` (time = frame number), ``frames.csv`` (frame, kind, tilt, monitored
    displacement along the load, the load's direction ``load_direction``: 0, "x", or 1, "y",
    which a video is seen from) and ``series.json`` (``{"every": N}``). Each frame is written as
    it comes, and the indexes rewritten atomically, so a crash keeps what was written.
    Equilibrium frames are kept every ``every``-th, and the last before the states past collapse,
    which are all kept. Use an instance as ``tilt_analysis(..., on_frame=series)``.

    ``resumed_tilts_deg``: None for a new series; for the series of a run resumed from a
    checkpoint, the tilts of the n equilibrium states it holds (the first column of
    ``saved["records"]`` of :func:`~drydem.engine.checkpoint.load_checkpoint`): the frames of
    those are kept, the frames after them (written before the interruption, given again by the
    resumed analysis) dropped, and the count of equilibria goes on from n, so that the frames
    kept are those of an uninterrupted run (found by a hunt: counting on from the frames written
    shifted every later frame of a --save-every 3 series). The series must have been begun with
    the same ``every`` (its series.json), and its frames kept must be those equilibria's, each
    file there (:func:`_check_resumed_frames`): DrydemError otherwise. A ``folder`` that is a
    link is refused: the frames would be written into its target."""

    def __init__(self, folder: Path, model: Model, *, every: int = 1, resumed_tilts_deg=None, load_direction: int = 0):
        SAVE_EVERY.check(every, "VtkSeries every")
        LOAD_DIRECTION.check(load_direction, "VtkSeries load_direction")
        tilts = None if resumed_tilts_deg is None else _resumed_tilts(resumed_tilts_deg)
        self.folder, self.model, self.every, self.load_axis = Path(folder), model, every, LOAD_AXES[load_direction]
        if self.folder.is_symlink():  # found by a hunt: a resumed run wrote its frames into another run's series
            raise DrydemError(f"{self.folder}: is a link; a run writes its VTK series in a folder of its own")
        self.folder.mkdir(parents=True, exist_ok=True)
        self.rows: list[tuple[int, str, float, float]] = []
        self.equilibria = 0
        self._skipped = None  # the last equilibrium frame, when ``every`` left it out
        if tilts is not None:
            _check_series_every(self.folder, every)
            self.rows = _equilibrium_rows(self.folder / "frames.csv")[:-(-len(tilts) // every)]
            _check_resumed_frames(self.folder, self.rows, tilts[::every])
            self.equilibria = len(tilts)
        _write_series_settings(self.folder, every)

    def __call__(self, frame) -> None:
        if frame.kind == "equilibrium":
            self.equilibria += 1
            self._skipped = frame if (self.equilibria - 1) % self.every else None
            if self._skipped is not None:
                return
        elif self._skipped is not None:  # the last equilibrium, kept whatever ``every`` (found by a hunt: it was dropped)
            skipped, self._skipped = self._skipped, None
            self._write(skipped)
        self._write(frame)

    def _write(self, frame) -> None:
        k = len(self.rows)
        _write_frame(self.model, self.folder, k, frame)
        self.rows.append((k, frame.kind, frame.tilt_deg, frame.ux_m))
        _write_indexes(self.folder, len(self.rows), ("frame", "kind", "tilt_deg", "ux_m", "load_direction"),
                       [(i, kind, f"{tilt:.6f}", f"{ux:.8g}", self.load_axis) for i, kind, tilt, ux in self.rows])


def _resumed_tilts(tilts_deg) -> np.ndarray:
    """``tilts_deg`` as a 1-D float array; ModelError naming VtkSeries resumed_tilts_deg unless
    it is one of finite numbers."""
    tilts = real_array(tilts_deg)
    if tilts is None or tilts.ndim != 1 or not np.isfinite(tilts).all():
        raise ModelError(f"VtkSeries resumed_tilts_deg = {shown(tilts_deg)}: must be the tilts (deg) of the equilibria "
                         "the resumed run's checkpoint holds, a list of finite numbers")
    return tilts


#: deg: how far a kept frame's tilt may be from its equilibrium's: frames.csv writes 6 decimals
FRAME_TILT_TOLERANCE_DEG = 1e-6


def _check_resumed_frames(folder: Path, rows: list, tilts_deg: np.ndarray) -> None:
    """DrydemError naming ``folder`` unless its kept equilibrium ``rows`` (frames.csv) are one per
    tilt of ``tilts_deg`` (the checkpoint's equilibria, every ``every``-th), at those tilts, each
    with its blocks and contacts files (found by a hunt: another run's series copied in, a
    frames.csv cut short and a frame's file deleted were each spliced into the resumed series)."""
    tilts = np.array([row[2] for row in rows])
    problem = None
    if len(rows) < len(tilts_deg):
        problem = f"it lists {len(rows)} of the {len(tilts_deg)} equilibrium frames the run's checkpoint has reached"
    elif len(tilts) and np.abs(tilts - tilts_deg).max() > FRAME_TILT_TOLERANCE_DEG:
        k = int(np.argmax(np.abs(tilts - tilts_deg)))
        problem = f"its frame {k} is at {tilts[k]:g} deg where the run's equilibrium is at {tilts_deg[k]:g} deg"
    else:
        missing = [name for k in range(len(rows)) for name in (f"blocks_{k:04d}.vtu", f"contacts_{k:04d}.vtu")
                   if not (folder / name).is_file()]
        problem = f"{missing[0]}, which frames.csv lists, is missing" if missing else None
    if problem is not None:
        raise DrydemError(f"{folder}: its VTK series is not this run's ({problem}): pass --overwrite to run again from the "
                          "start, or give another --out")
#: a tilting series' settings file in its folder: ``{"every": N}``
SERIES_SETTINGS = "series.json"


def _write_series_settings(folder: Path, every: int) -> None:
    """``folder``/series.json: the series' ``every`` (:class:`VtkSeries`)."""
    with replaced_atomically(folder / SERIES_SETTINGS) as partial:
        partial.write_text(json.dumps({"every": every}) + "\n")


def _check_series_every(folder: Path, every: int) -> None:
    """DrydemError naming ``folder``'s series.json if the series there was begun keeping every
    other number of equilibrium frames than ``every`` (resumed with another --save-every, its
    frames would be unevenly spaced). A series without the file (none begun, or one of a drydem
    before it) is taken as it is."""
    path = folder / SERIES_SETTINGS
    if not os.path.lexists(path):
        return
    try:
        begun = json.loads(read_text(path, "series.json of drydem tilt --vtk is JSON text"))["every"]
    except (ValueError, TypeError, KeyError) as exc:
        raise DrydemError(f"{path}: not the settings of a drydem tilt --vtk series ({plain_reason(exc)})") from None
    if begun != every:
        raise DrydemError(f"{path}: the VTK series was begun with --save-every {begun}; resumed with --save-every {every} its "
                          f"frames would be unevenly spaced: resume with --save-every {begun}")


class ShakeSeries:
    """Frames of a shaking-table analysis (drydem.analysis.shake.ShakeFrame) as the same two
    VTK time series as :class:`VtkSeries` in ``folder`` (``blocks_NNNN.vtu`` and
    ``contacts_NNNN.vtu``, indexed by ``blocks.pvd`` and ``contacts.pvd``, here with the model
    time in seconds as each DataSet's time, so that ParaView plays them in time), and
    ``frames.csv`` (frame, time_s, monitored ux_m, and the table's main horizontal direction
    ``load_direction``, 0: "x" or 1: "y", which a video is seen from). Every ``every``-th frame
    is kept, each written as it comes, the indexes rewritten atomically. Use an instance as
    ``shake_analysis(..., on_frame=series)``."""

    def __init__(self, folder: Path, model: Model, *, every: int = 1, load_direction: int = 0):
        SAVE_EVERY.check(every, "ShakeSeries every")
        LOAD_DIRECTION.check(load_direction, "ShakeSeries load_direction")
        self.folder, self.model, self.every, self.load_axis = Path(folder), model, every, LOAD_AXES[load_direction]
        self.folder.mkdir(parents=True, exist_ok=True)
        self.rows: list[tuple[int, float, float]] = []
        self.frames = 0

    def __call__(self, frame) -> None:
        self.frames += 1
        if (self.frames - 1) % self.every:
            return
        k = len(self.rows)
        _write_frame(self.model, self.folder, k, frame)
        self.rows.append((k, frame.time_s, frame.ux_m))
        _write_indexes(self.folder, len(self.rows), ("frame", "time_s", "ux_m", "load_direction"),
                       [(i, f"{t:.9g}", f"{ux:.8g}", self.load_axis) for i, t, ux in self.rows], times=[t for _, t, _ in self.rows])


def _write_frame(model: Model, folder: Path, k: int, frame) -> None:
    """Frame ``k``'s blocks and sub-contacts (any frame with ``state``, ``active`` and ``contacts``)."""
    write_vtu(model, folder / f"blocks_{k:04d}.vtu", frame.state, frame.active)
    write_contacts_vtu(model, folder / f"contacts_{k:04d}.vtu", frame.state, frame.contacts)


def _write_indexes(folder: Path, count: int, header: tuple[str, ...], rows: list[tuple], *, times: list[float] | None = None) -> None:
    """Rewrite, each atomically, the two ``.pvd`` indexes of the first ``count`` frames (times:
    the frame numbers unless ``times`` is given) and ``frames.csv`` (``header`` and ``rows``)."""
    for series in ("blocks", "contacts"):
        with replaced_atomically(folder / f"{series}.pvd") as partial:
            partial.write_text(_pvd([f"{series}_{i:04d}.vtu" for i in range(count)], times))
    with replaced_atomically(folder / "frames.csv") as partial, partial.open("w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(header)
        writer.writerows(rows)


def frames_csv_rows(index: Path) -> list[dict]:
    """The rows of a series' ``frames.csv`` (each a dict by column); a DrydemError naming it if it
    is not a regular file (drydem.files.read_text: a pipe there is not waited on) or not CSV text
    (with the line), or a column is named twice (a row would hold only the last one's value)."""
    reader = csv.DictReader(io.StringIO(read_text(index, "frames.csv of drydem tilt or shake --vtk is CSV text"), newline=""))
    try:
        header = reader.fieldnames or []
        twice = list(dict.fromkeys(name for name in header if header.count(name) > 1))
        if twice:
            raise DrydemError(f"{index}: line 1: columns named twice: {', '.join(shown(name) for name in twice)}; drydem writes each once")
        return list(reader)
    except csv.Error as exc:
        raise DrydemError(f"{index}: line {reader.line_num}: not CSV ({exc})") from None


#: the largest frame number: 9 digits, more frames than any series holds (each is a file)
MAX_FRAME = 999_999_999


def frame_number(text: str) -> int:
    """The frame number ``text`` of a row of ``frames.csv``: digits 0-9 (int() also takes +1, 1_0
    and digits of other scripts), at most :data:`MAX_FRAME`; a ValueError saying the rule (found
    by a hunt: 3.0 was refused in int()'s words)."""
    digits = text.removeprefix("-")
    if not (digits.isascii() and digits.isdigit()):
        raise ValueError(f"frame {shown(text)}: must be written in the digits 0-9, as drydem writes it")
    if digits != text:
        raise ValueError(f"frame {shown(text) if len(text) > 12 else text}: must be an integer >= 0")
    if len(text.lstrip("0")) > len(str(MAX_FRAME)) or int(text) > MAX_FRAME:  # int() refuses more than 4,300 digits
        raise ValueError(f"frame {shown(text)}: must be at most {MAX_FRAME} (more frames than any series holds)")
    return int(text)


def _equilibrium_rows(index: Path) -> list[tuple[int, str, float, float]]:
    """The equilibrium frames listed in a series' ``frames.csv`` (none if it is missing);
    DrydemError naming the file and line if it is not one drydem wrote (:func:`frames_csv_rows`)."""
    if not os.path.lexists(index):
        return []
    rows = []
    for line, row in enumerate(frames_csv_rows(index), start=2):
        try:
            frame = (frame_number(row["frame"]), row["kind"], float(row["tilt_deg"]), float(row["ux_m"]))
        except (KeyError, TypeError, ValueError) as exc:
            raise DrydemError(f"{index}: line {line}: not a frame of drydem tilt --vtk ({plain_reason(exc)})") from None
        if frame[1] == "equilibrium" and frame[0] == len(rows):
            rows.append(frame)
    return rows


def _pvd(files: list[str], times: list[float] | None = None) -> str:
    """A ParaView collection: one DataSet per file, time = its position (or its ``times`` entry)."""
    stamps = [str(t) for t in range(len(files))] if times is None else [f"{t:.9g}" for t in times]
    entries = "\n".join(f'    <DataSet timestep="{t}" part="0" file={quoteattr(name)}/>' for t, name in zip(stamps, files))
    return f'<?xml version="1.0"?>\n<VTKFile type="Collection" version="0.1">\n  <Collection>\n{entries}\n  </Collection>\n</VTKFile>\n'
