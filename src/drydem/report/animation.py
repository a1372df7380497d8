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
drydem writes (not text, a non-finite number, no block left in the analysis) is named, with its line.
"""

from __future__ import annotations

import csv
import io
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from drydem.errors import DrydemError
from drydem.files import read_text, replaceable, replaced_atomically
from drydem.io.vtk import LOAD_AXES
from drydem.report.plots import draw_displacements, draw_faces_3d, frame_3d, new_figure, one_deep, xz_outline

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
    and the load's direction (0: x, 1: y)."""

    blocks: list[list[np.ndarray]]
    magnitude_mm: np.ndarray
    caption: str
    moving: np.ndarray
    load_direction: int = 0


def series_frames(folder: Path) -> list[VideoFrame]:
    """The frames of the VTK series in ``folder`` (``frames.csv`` and ``blocks_NNNN.vtu``); a
    DrydemError naming the file (and the line of ``frames.csv``) that is not one drydem writes."""
    folder = Path(folder)
    index = folder / "frames.csv"
    if not index.is_file():
        raise DrydemError(f"{folder}: no frames.csv: not a VTK series of drydem tilt or shake --vtk")
    rows = _index_rows(index)
    if not rows:
        raise DrydemError(f"{index}: no frames")
    frames = []
    for line, row in enumerate(rows, start=2):
        try:
            file = folder / f"blocks_{int(row['frame']):04d}.vtu"
            load_direction = _load_direction(row)
            caption = _caption(row, load_direction)
        except (KeyError, TypeError, ValueError) as exc:
            raise DrydemError(f"{index}: line {line}: not a frame of drydem tilt or shake --vtk ({exc!r})") from None
        frames.append(_read_frame(file, caption, load_direction))
    return frames


def _index_rows(index: Path) -> list[dict]:
    """The rows of ``frames.csv``; a DrydemError naming it if it is not CSV text (with the line)."""
    reader = csv.DictReader(io.StringIO(read_text(index, "frames.csv of drydem tilt or shake --vtk is CSV text"), newline=""))
    try:
        return list(reader)
    except csv.Error as exc:
        raise DrydemError(f"{index}: line {reader.line_num}: not CSV ({exc})") from None


def _read_frame(file: Path, caption: str, load_direction: int) -> VideoFrame:
    """The frame in ``file`` (a ``blocks_NNNN.vtu``): its blocks still in the analysis (``active``).
    A DrydemError naming the file if it cannot be read or lacks a field of :data:`FRAME_FIELDS`,
    if a point or a displacement magnitude is not a finite number (a magnitude also >= 0), or if no
    block is left in the analysis (nothing to draw)."""
    import meshio

    try:
        mesh = meshio.read(file)
        fields = {name: np.concatenate(mesh.cell_data[name]) for name in FRAME_FIELDS}
    except Exception as exc:  # meshio raises many types (ReadError, ...); a foreign file lacks the fields (KeyError)
        raise DrydemError(f"{file}: cannot read the frame: {exc!r}") from None
    if not np.isfinite(mesh.points).all():
        raise DrydemError(f"{file}: points: not all finite numbers (NaN or inf): not a frame drydem writes")
    magnitude = fields["displacement_magnitude"] * 1e3
    if not (np.isfinite(magnitude) & (magnitude >= 0.0)).all():
        raise DrydemError(f"{file}: displacement_magnitude: not all finite numbers >= 0: not a frame drydem writes")
    active, fixed = fields["active"].astype(bool), fields["fixed"].astype(bool)
    if not active.any():
        raise DrydemError(f"{file}: no block in the analysis (active = 0 for every block): nothing to draw")
    try:
        cells = [cell for block in mesh.cells for cell in block.data]
        blocks = [[mesh.points[face] for face in faces] for faces, on in zip(cells, active, strict=True) if on]
    except (IndexError, ValueError) as exc:  # a face naming a point the file lacks; fields and cells of other lengths
        raise DrydemError(f"{file}: cannot read the frame: {exc!r}") from None
    return VideoFrame(blocks, magnitude[active], caption, ~fixed[active], load_direction)


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
    monitored displacement along the load (``ux_m``: along y when tilting about x)."""
    if row.get("time_s") is not None:
        return f"t = {_finite(row, 'time_s'):.3f} s, monitored ux {_finite(row, 'ux_m') * 1e3:.2f} mm"
    along = f"monitored u{LOAD_AXES[load_direction]} {_finite(row, 'ux_m') * 1e3:.2f} mm"
    return f"{row['kind']}: tilt {_finite(row, 'tilt_deg'):.2f} deg, {along}"


def _finite(row: dict, column: str) -> float:
    """The number in ``column`` of a row of ``frames.csv``; a ValueError naming the column if it
    is not a finite number (NaN, inf)."""
    value = float(row[column])
    if not math.isfinite(value):
        raise ValueError(f"{column} {row[column]!r}: must be a finite number")
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


def render_video(folder: Path, path: Path, *, fps: float = 8.0, overwrite: bool = False) -> Path:
    """Render the VTK series in ``folder`` to ``path`` (.mp4 or .gif) at ``fps`` frames per second
    (:func:`check_fps`); an .mp4 that ffmpeg cannot write falls back to a .gif beside it. An
    existing video (the .gif of the fall-back too) is replaced only if ``overwrite``, else refused
    (:func:`video_path`; ``path`` before any frame is drawn). Returns the file written."""
    import imageio.v2 as imageio
    from matplotlib.colors import LogNorm

    check_fps(fps)
    path = video_path(path, overwrite=overwrite)
    frames = series_frames(folder)
    largest = max(float(f.magnitude_mm.max(initial=0.0)) for f in frames) or 1.0
    norm = LogNorm(largest * 1e-3, largest)  # equilibria (mm) and collapse (dm) on one scale
    points = np.vstack([face for frame in frames for block in frame.blocks for face in block])
    low, high = points.min(axis=0), points.max(axis=0)
    margin = 0.05 * (high - low).max()
    flat = one_deep([np.vstack(block) for block, moving in zip(frames[0].blocks, frames[0].moving) if moving])
    images = [_image(frame, norm, low - margin, high + margin, flat=flat) for frame in frames]
    if path.suffix.lower() == ".mp4":
        try:
            with replaced_atomically(path) as partial, imageio.get_writer(partial, fps=fps, codec="libx264", macro_block_size=16) as writer:
                for image in images:
                    writer.append_data(image)
            return path
        except (ImportError, RuntimeError, DrydemError):  # no ffmpeg, or it failed (an OSError): fall back to a GIF
            path = video_path(path.with_suffix(".gif"), overwrite=overwrite)
    with replaced_atomically(path) as partial:
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
    fig.canvas.draw()
    return np.asarray(fig.canvas.buffer_rgba())[:, :, :3].copy()
