"""Videos of a tilting analysis from its VTK series (drydem.io.vtk.VtkSeries), as the paper's
supplementary videos: the blocks coloured by displacement magnitude (a wall in its plane, a deep
3D model such as a building in 3D: drydem.report.plots.one_deep), the tilt angle
and the monitored displacement on every frame, the states past collapse at the end; and of a
shaking-table analysis from its series (drydem.io.vtk.ShakeSeries): the model time and the
monitored displacement on every frame. The captions follow the columns of ``frames.csv``; a 3D
model is seen from the side its load pushes towards (the series' ``load_direction``, x in a
series written before it was recorded), as in ``mechanism.png``.

Frames are drawn by the renderers of ``mechanism.png`` (drydem.report.plots.draw_displacements,
draw_faces_3d), so pictures and videos agree. MP4 through imageio-ffmpeg (the ffmpeg binary
ships in that package); GIF (Pillow) when MP4 cannot be written or is not asked for. The video file is
checked before any frame is drawn (an existing one is kept unless it is to be replaced), and written
whole or not at all (drydem.files). A series is read whole before any drawing: a file that is not one
drydem writes (not a regular file, not text, a row of an unknown kind or load direction, a truncated
frame, a non-finite number, no block left in the analysis, a frame of another model: another block
count, a column drydem does not write, a frame number listed twice or out of order) is named, with
its line. Frame files on disk that ``frames.csv`` does not list are left out,
with a note: not refused, since a run stopped between a frame and its index, or resumed and ended
sooner, leaves some.
"""

from __future__ import annotations

import math
import os
import re
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from drydem.errors import DrydemError, OutputTakenError, plain_reason
from drydem.files import PLAIN_NUMBER, regular_file, replaceable, replaced_atomically
from drydem.io.vtk import FRAME_KINDS, LOAD_AXES, frame_number, frames_csv_rows
from drydem.model.geometry import MAX_COORDINATE_M
from drydem.model.parameters import shown
from drydem.report.plots import draw_displacements, draw_faces_3d, frame_3d, new_figure, one_deep, plain_text, xz_outline

#: frame size: 1280 x 720 pixels (a multiple of 16, as H.264 wants)
FIGURE_IN, DPI = (8.0, 4.5), 160
#: the video formats written, by suffix
VIDEO_SUFFIXES = (".mp4", ".gif")
#: the frame rates a video may have, frames per second: from 10 s a frame to the fastest a GIF can
#: show (it counts a frame's delay in hundredths of a second)
FPS_RANGE = (0.1, 100.0)
#: the fields of a frame's blocks_NNNN.vtu that a video reads (cell data)
FRAME_FIELDS = ("active", "displacement_magnitude", "fixed")


@dataclass(frozen=True)
class VideoFrame:
    """One frame: the blocks still in the analysis (each the world vertices of its faces, m),
    their displacement magnitudes (mm), the caption, which of the blocks may move (not fixed),
    the load's direction (0: x, 1: y) and how many blocks the frame's file holds, in the analysis
    or not (every frame of a series holds its model's blocks)."""

    blocks: list[list[np.ndarray]]
    magnitude_mm: np.ndarray
    caption: str
    moving: np.ndarray
    load_direction: int = 0
    n_blocks: int = 0


#: what a frame's file must be, said when it is not
VTU_EXPECTED = "a frame of drydem tilt or shake --vtk is a blocks_NNNN.vtu file that frames.csv lists"
#: a frame's file on disk, listed in frames.csv or not
FRAME_FILE = re.compile(r"blocks_\d{4,}\.vtu")
#: the columns of ``frames.csv`` that drydem writes (drydem.io.vtk.VtkSeries, ShakeSeries): a
#: tilting series' and, with ``time_s``, a shaking-table series'; the last, ``load_direction``,
#: is missing from a series written before it was recorded
FRAMES_COLUMNS = {"tilt": ("frame", "kind", "tilt_deg", "ux_m", "load_direction"),
                  "shake": ("frame", "time_s", "ux_m", "load_direction")}


def series_frames(folder: Path, *, note: Callable[[str], None] | None = None) -> list[VideoFrame]:
    """The frames of the VTK series in ``folder``: those ``frames.csv`` lists, each from its
    ``blocks_NNNN.vtu``. A DrydemError names the file (and the line of ``frames.csv``) that is not
    one drydem writes (each read only once it is a regular file: drydem.files.regular_file), and a
    frame whose block count differs from the first frame's (a file of another model). Frame files
    on disk that ``frames.csv`` does not list are left out, said to ``note`` (one line): a run
    stopped between a frame and its index, or resumed and ended sooner, leaves them."""
    folder = Path(folder)
    index = folder / "frames.csv"
    if not os.path.lexists(index):
        raise DrydemError(f"{folder}: no frames.csv: not a VTK series of drydem tilt or shake --vtk")
    rows = frames_csv_rows(index)
    if not rows:
        raise DrydemError(f"{index}: no frames")
    _check_columns(index, [name for name in rows[0] if name is not None])
    listed = [_listed_frame(index, line, row) for line, row in enumerate(rows, start=2)]
    _check_increasing(index, rows)
    _check_one_direction(index, listed)
    unlisted = _unlisted(folder, listed)
    if unlisted and note is not None:
        note(f"{folder}: {len(unlisted)} frames on disk are not listed in frames.csv ({', '.join(unlisted[:3])}"
             f"{', ...' if len(unlisted) > 3 else ''}): left out of the video")
    return _same_model([_read_frame(file, caption, load_direction) for file, caption, load_direction in listed], listed)


def _unlisted(folder: Path, listed: list[tuple[Path, str, int]]) -> list[str]:
    """The names of the frame files (:data:`FRAME_FILE`) in ``folder`` that are not ``listed``, sorted."""
    on_disk = {path.name for path in folder.glob("blocks_*.vtu") if FRAME_FILE.fullmatch(path.name)}
    return sorted(on_disk - {file.name for file, _, _ in listed})


def _check_columns(index: Path, header: list[str]) -> None:
    """A DrydemError naming ``frames.csv`` (line 1) if its ``header`` has a column that drydem
    does not write or lacks one it does (:data:`FRAMES_COLUMNS`; ``load_direction`` may be
    missing): a table of something else, or edited."""
    kind = "shake" if "time_s" in header else "tilt"
    unknown = [name for name in header if name not in FRAMES_COLUMNS[kind]]
    missing = [name for name in FRAMES_COLUMNS[kind][:-1] if name not in header]
    for problem, names in (("unknown columns", unknown), ("missing columns", missing)):
        if names:
            raise DrydemError(f"{index}: line 1: {problem} {', '.join(shown(name) for name in names)}; drydem writes the columns "
                              f"{', '.join(FRAMES_COLUMNS['tilt'])} (tilt --vtk) or {', '.join(FRAMES_COLUMNS['shake'])} "
                              "(shake --vtk), load_direction missing in a series written before it was recorded")


def _check_increasing(index: Path, rows: list[dict]) -> None:
    """A DrydemError naming the line of ``frames.csv`` whose frame number is not after the one
    before (each checked by :func:`~drydem.io.vtk.frame_number`): drydem numbers a series' frames 0, 1, 2, ...,
    so a frame listed twice or out of order is not a series it wrote."""
    for line, (before, row) in enumerate(zip(rows, rows[1:]), start=3):
        if int(row["frame"]) <= int(before["frame"]):
            raise DrydemError(f"{index}: line {line}: frame {row['frame']} is not after frame {before['frame']} (line {line - 1}): "
                              "frame numbers must increase strictly, as drydem numbers a series' frames (0, 1, 2, ...)")
        if row.get("time_s") is not None and _finite(row, "time_s", 0.0) < _finite(before, "time_s", 0.0):
            raise DrydemError(f"{index}: line {line}: time_s {row['time_s']} is before the frame before's, {before['time_s']} "
                              f"(line {line - 1}): a shaking table's frames follow its model time")


def _check_one_direction(index: Path, listed: list[tuple[Path, str, int]]) -> None:
    """A DrydemError naming ``frames.csv`` if its rows' load direction changes: drydem writes one
    per series (found by a hunt: x, then y, was drawn seen from both sides)."""
    directions = [load_direction for _, _, load_direction in listed]
    other = next((k for k, direction in enumerate(directions) if direction != directions[0]), None)
    if other is not None:
        raise DrydemError(f"{index}: line {other + 2}: load_direction {LOAD_AXES[directions[other]]}, where line 2 has "
                          f"{LOAD_AXES[directions[0]]}: drydem writes one load direction per series")


def _listed_frame(index: Path, line: int, row: dict) -> tuple[Path, str, int]:
    """A row of ``frames.csv`` (at ``line``): its frame's file, caption and load direction; a
    DrydemError naming the file and line if the row is not one drydem writes (as many values
    as the header has columns, a frame number of :func:`~drydem.io.vtk.frame_number`)."""
    try:
        if None in row or None in row.values():  # csv.DictReader: values past the header, or too few
            values = sum(value is not None for name, value in row.items() if name is not None) + len(row.get(None, []))
            raise ValueError(f"{values} values; the header has {len(row) - (None in row)} columns")
        frame = frame_number(row["frame"])
        load_direction = _load_direction(row)
        return index.parent / f"blocks_{frame:04d}.vtu", _caption(row, load_direction), load_direction
    except (KeyError, TypeError, ValueError) as exc:
        raise DrydemError(f"{index}: line {line}: not a frame of drydem tilt or shake --vtk ({plain_reason(exc)})") from None


def _same_model(frames: list[VideoFrame], listed: list[tuple[Path, str, int]]) -> list[VideoFrame]:
    """``frames`` if each holds as many blocks as the first; else a DrydemError naming the first
    frame's file (of ``listed``) that does not: a file of another model."""
    for frame, (file, _, _) in zip(frames, listed):
        if frame.n_blocks != frames[0].n_blocks:
            raise DrydemError(f"{file}: {frame.n_blocks} blocks, but the series' first frame {listed[0][0].name} has "
                              f"{frames[0].n_blocks}: every frame of a series holds the same model's blocks (a file of another model?)")
    return frames


def _read_mesh(file: Path):
    """The meshio mesh in ``file`` once it is a regular file, and its fields of :data:`FRAME_FIELDS`;
    a DrydemError naming it if it is not a readable VTU file (meshio's reader called directly:
    meshio.read prints its reason and exits on a file it cannot parse) or lacks a field."""
    from meshio.vtu import read as read_vtu

    regular_file(file, VTU_EXPECTED)
    try:
        mesh = read_vtu(str(file))
    except Exception as exc:  # ReadError (often without a reason), an XML ParseError, a zlib or base64 error, ...
        raise DrydemError(f"{file}: not a readable VTU file (truncated, or not a frame drydem writes)"
                          + (f": {exc}" if str(exc) else "")) from None
    try:
        return mesh, {name: np.concatenate(mesh.cell_data[name]) for name in FRAME_FIELDS}
    except (KeyError, TypeError, ValueError) as exc:  # a foreign file lacks the fields
        raise DrydemError(f"{file}: cannot read the frame: {plain_reason(exc)}") from None


def _read_frame(file: Path, caption: str, load_direction: int) -> VideoFrame:
    """The frame in ``file`` (a ``blocks_NNNN.vtu``, :func:`_read_mesh`): its blocks still in the
    analysis (``active``). A DrydemError naming the file if a point or a displacement magnitude is
    not a finite number (a magnitude also >= 0), or if no block is left in the analysis (nothing
    to draw)."""
    mesh, fields = _read_mesh(file)
    _check_frame(file, mesh, fields)
    magnitude = fields["displacement_magnitude"] * 1e3
    active, fixed = fields["active"].astype(bool), fields["fixed"].astype(bool)
    if not active.any():
        raise DrydemError(f"{file}: no block in the analysis (active = 0 for every block): nothing to draw")
    try:
        cells = [cell for block in mesh.cells for cell in block.data]
        blocks = [[mesh.points[face] for face in faces] for faces, on in zip(cells, active, strict=True) if on]
    except (IndexError, ValueError) as exc:  # a face naming a point the file lacks; fields and cells of other lengths
        raise DrydemError(f"{file}: cannot read the frame: {plain_reason(exc)}") from None
    return VideoFrame(blocks, magnitude[active], caption, ~fixed[active], load_direction, len(cells))


#: m: how far from the origin a frame's point may be, ten times a model's vertices
#: (:data:`~drydem.model.geometry.MAX_COORDINATE_M`), for blocks that moved (1e300 failed in Qhull)
FRAME_REACH_M = 10.0 * MAX_COORDINATE_M


def _check_frame(file: Path, mesh, fields: dict[str, np.ndarray]) -> None:
    """A DrydemError naming ``file`` unless its ``mesh`` is of polyhedra (one a block), its points
    finite numbers within :data:`FRAME_REACH_M` and its ``fields`` (:data:`FRAME_FIELDS`) one
    value a block: active and fixed 0 or 1, the displacement magnitude a finite number >= 0.
    Checked before drawing, which failed on such files in matplotlib or Qhull (a traceback)."""
    not_ours = "not a frame drydem writes"
    kinds = sorted({block.type for block in mesh.cells if not block.type.startswith("polyhedron")})
    if kinds or not mesh.cells:
        raise DrydemError(f"{file}: cells {', '.join(kinds) or '(none)'}: {not_ours} (one polyhedron a block)")
    if not np.isfinite(mesh.points).all() or np.abs(mesh.points).max(initial=0.0) > FRAME_REACH_M:
        raise DrydemError(f"{file}: points: not all finite numbers within {FRAME_REACH_M:g} m of the origin: {not_ours}")
    blocks = sum(len(block.data) for block in mesh.cells)
    for name, values in fields.items():
        if values.shape != (blocks,):
            raise DrydemError(f"{file}: {name}: shape {values.shape}, not one value a block ({blocks} blocks): {not_ours}")
    for name in ("active", "fixed"):
        if not np.isin(fields[name], (0, 1)).all():
            raise DrydemError(f"{file}: {name}: values other than 0 and 1: {not_ours}")
    if not (np.isfinite(fields["displacement_magnitude"]) & (fields["displacement_magnitude"] >= 0.0)).all():
        raise DrydemError(f"{file}: displacement_magnitude: not all finite numbers >= 0: {not_ours}")


def _load_direction(row: dict) -> int:
    """The load's direction in a row of ``frames.csv``: 0 (x) or 1 (y); x where the series
    does not say (written before it was recorded); a ValueError for anything else."""
    axis = row.get("load_direction") or "x"
    if axis not in LOAD_AXES:
        raise ValueError(f"load_direction {axis!r}: must be one of {', '.join(LOAD_AXES)}")
    return LOAD_AXES.index(axis)


def _caption(row: dict, load_direction: int) -> str:
    """A frame's caption from its row of ``frames.csv``: a shaking-table frame (a ``time_s``
    column) gives the model time and the monitored ux, a tilting one its kind, tilt and the
    monitored displacement along the load (``ux_m``: along y when tilting about x); a
    ValueError for a kind not of :data:`drydem.io.vtk.FRAME_KINDS`."""
    if row.get("time_s") is not None:
        return f"t = {_finite(row, 'time_s', 0.0):.3f} s, monitored ux {_millimetres(_displacement(row))} mm"
    if row["kind"] not in FRAME_KINDS:
        raise ValueError(f"kind {row['kind']!r}: must be one of {', '.join(map(repr, FRAME_KINDS))}")
    along = f"monitored u{LOAD_AXES[load_direction]} {_millimetres(_displacement(row))} mm"
    return f"{row['kind']}: tilt {_finite(row, 'tilt_deg', 0.0, 90.0):.2f} deg, {along}"


def _millimetres(metres: float) -> str:
    """``metres`` in mm to 0.01 mm, a round-off below it shown as 0.00, not -0.00."""
    return f"{round(metres * 1e3, 2) + 0.0:.2f}"


def _displacement(row: dict) -> float:
    """The monitored displacement (``ux_m``) of a row of ``frames.csv``, m: within the reach of a
    model's coordinates (:data:`~drydem.model.geometry.MAX_COORDINATE_M`; found by a hunt: 1e300
    was drawn)."""
    return _finite(row, "ux_m", -2.0 * MAX_COORDINATE_M, 2.0 * MAX_COORDINATE_M)


def _finite(row: dict, column: str, low: float = -math.inf, high: float = math.inf) -> float:
    """The number in ``column`` of a row of ``frames.csv``; a ValueError naming the column if it
    is not a plain decimal (as drydem writes it: float() also takes 0_5, read as 5, found by a
    hunt) or not a finite number (NaN, inf) in [``low``, ``high``] (a tilt in [0, 90] deg, a
    model time none or more: a tilt of 1e300 deg was drawn as a caption)."""
    if not PLAIN_NUMBER.fullmatch(row[column].strip()):
        raise ValueError(f"{column} {row[column]!r}: not a plain decimal number, as drydem writes it")
    value = float(row[column])
    if not (math.isfinite(value) and low <= value <= high):
        bounds = "" if (low, high) == (-math.inf, math.inf) else f" in [{low:g}, {high:g}]" if high < math.inf else f" >= {low:g}"
        raise ValueError(f"{column} {row[column]!r}: must be a finite number{bounds}")
    return value


def check_fps(fps: float) -> float:
    """``fps`` if it is a finite frame rate within :data:`FPS_RANGE`; else a DrydemError saying
    the range (NaN fails every comparison, so it is refused too)."""
    low, high = FPS_RANGE
    if not (math.isfinite(fps) and low <= fps <= high):
        raise DrydemError(f"{fps!r} frames per second: must be a finite number from {low:g} to {high:g}")
    return fps


def video_path(path: Path, *, overwrite: bool = False) -> Path:
    """``path`` if a video can be written there: a suffix of :data:`VIDEO_SUFFIXES`, and nothing
    there yet, or a regular file and ``overwrite`` (drydem.files.replaceable); else a DrydemError
    naming it and the rule."""
    path = Path(path)
    if path.suffix.lower() not in VIDEO_SUFFIXES:
        raise DrydemError(f"{path}: cannot write {path.suffix or 'a file without suffix'!r} videos; "
                          f"the suffix must be {' or '.join(VIDEO_SUFFIXES)}")
    return replaceable(path, overwrite, other="another --out")


def render_video(folder: Path, path: Path, *, fps: float = 8.0, overwrite: bool = False,
                 note: Callable[[str], None] | None = None) -> Path:
    """Render the VTK series in ``folder`` to ``path`` (.mp4 or .gif) at ``fps`` frames per second
    (:func:`check_fps`); an .mp4 that ffmpeg cannot write falls back to a .gif beside it. An
    existing video (the .gif of the fall-back too) is replaced only if ``overwrite``, else refused
    (:func:`video_path`; ``path`` before any frame is drawn). Frames on disk that the series does
    not list are said to ``note`` (:func:`series_frames`). Returns the file written."""
    import imageio.v2 as imageio
    from matplotlib.colors import LogNorm

    check_fps(fps)
    path = video_path(path, overwrite=overwrite)
    frames = series_frames(folder, note=note)
    largest = max(float(f.magnitude_mm.max(initial=0.0)) for f in frames) or 1.0
    norm = LogNorm(largest * 1e-3, largest)  # equilibria (mm) and collapse (dm) on one scale
    points = np.vstack([face for frame in frames for block in frame.blocks for face in block])
    low, high = points.min(axis=0), points.max(axis=0)
    margin = 0.05 * (high - low).max()
    flat = one_deep([np.vstack(block) for block, moving in zip(frames[0].blocks, frames[0].moving) if moving])
    images = [_image(frame, norm, low - margin, high + margin, flat=flat) for frame in frames]
    if path.suffix.lower() == ".mp4":
        try:
            with replaced_atomically(path, replace=overwrite) as partial, imageio.get_writer(partial, fps=fps, codec="libx264", macro_block_size=16) as writer:
                for image in images:
                    writer.append_data(image)
            return path
        except OutputTakenError:  # another process's video: no fall-back
            raise
        except (ImportError, RuntimeError, DrydemError):  # no ffmpeg, or it failed (an OSError): fall back to a GIF
            path = video_path(path.with_suffix(".gif"), overwrite=overwrite)
    with replaced_atomically(path, replace=overwrite) as partial:
        imageio.mimsave(partial, images, duration=1000.0 / fps, loop=0)  # Pillow's duration: ms a frame
    return path


def _image(frame: VideoFrame, norm, low: np.ndarray, high: np.ndarray, *, flat: bool) -> np.ndarray:
    """The frame's pixels (RGB): the blocks ``flat`` in the x-z plane or in 3D, in the box
    ``low``-``high`` (m) of the whole video."""
    fig = new_figure(figsize=FIGURE_IN, dpi=DPI, layout="constrained")
    values = np.clip(frame.magnitude_mm, norm.vmin, None)
    if flat:
        ax = fig.subplots()
        draw_displacements(fig, ax, [xz_outline(np.vstack(block)) for block in frame.blocks], values, title=frame.caption, norm=norm)
        ax.set(xlim=(low[0], high[0]), ylim=(low[2], high[2]))
    else:
        ax = fig.subplots(subplot_kw={"projection": "3d"})
        owner = np.repeat(np.arange(len(frame.blocks)), [len(block) for block in frame.blocks])
        draw_faces_3d(fig, ax, [face for block in frame.blocks for face in block], owner, values, title=frame.caption, norm=norm,
                      load_direction=frame.load_direction)
        frame_3d(ax, low, high, title=frame.caption, load_direction=frame.load_direction)
    plain_text(fig)
    fig.canvas.draw()
    return np.asarray(fig.canvas.buffer_rgba())[:, :, :3].copy()
