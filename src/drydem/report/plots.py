"""Figures of a tilting analysis: pushover curve (paper Figs 9-11) and mechanism (Figs 7-8);
of a limit analysis: its mechanism (:func:`limit_mechanism_figure`); of a shaking-table
analysis: the response history (:func:`history_figure`); of a Monte Carlo run: the histogram
of its angles (:func:`histogram_figure`). The pushover and the mechanisms are also given as
Figures, unwritten (``*_drawing``), to look at or check their artists; each file is written whole
or not at all (:func:`saved`).

matplotlib is imported inside the functions, so the engine does not load it. Figures are
:class:`matplotlib.figure.Figure` objects made by :func:`new_figure`, outside pyplot: drawing
one neither selects nor changes matplotlib's backend (a notebook's stays as it is), and no
figure is left open in pyplot's list.
"""

from __future__ import annotations

from collections import Counter
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from drydem.analysis.drift import EC8_DRIFT_LIMITS, EC8_DRIFT_MEANINGS
from drydem.analysis.tilt import TiltResult, wall_height
from drydem.errors import DrydemError
from drydem.files import replaced_atomically
from drydem.model.assembly import Model
from drydem.model.state import State

if TYPE_CHECKING:  # annotations only: the limit analysis imports scipy.optimize
    from drydem.analysis.limit import LimitResult
    from drydem.analysis.shake import History


def new_figure(**options):
    """A matplotlib Figure (``options``: figsize, dpi, layout, ...) drawn on an Agg canvas of
    its own, not pyplot's: ``fig.savefig`` writes it, ``fig.canvas.buffer_rgba()`` gives its
    pixels once drawn, and the global backend is left alone."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(**options)
    FigureCanvasAgg(fig)
    return fig


#: matplotlib's formats that need a LaTeX installation (xelatex), which drydem does not require
NEEDS_LATEX = ("pgf",)


def figure_path(path: str | Path) -> Path:
    """``path`` if matplotlib writes the format its suffix names (.png, .pdf, .svg, ...), else
    a DrydemError listing them: checked before drawing, as matplotlib would fail only at the end."""
    from matplotlib.backend_bases import FigureCanvasBase

    path = Path(path)
    formats = [f for f in FigureCanvasBase.get_supported_filetypes() if f not in NEEDS_LATEX]
    if path.suffix[1:].lower() not in formats:
        raise DrydemError(f"{path}: cannot draw a figure in the format {path.suffix or '(no suffix)'!r}; "
                          f"the suffix must be one of {', '.join('.' + f for f in formats)}")
    return path


def saved(fig, path: Path) -> Path:
    """Write ``fig`` to ``path`` at 150 dpi, whole or not at all (:func:`~drydem.files.replaced_atomically`),
    its texts as written (:func:`plain_text`)."""
    plain_text(fig)
    with replaced_atomically(path) as partial:
        fig.savefig(partial, dpi=150, bbox_inches="tight", pad_inches=0.1)
    return path


def plain_text(fig) -> None:
    """Every text of ``fig`` drawn as it is written, before the figure is first drawn: no
    mathtext (a $ in a file or block name is no formula: found by a hunt, a model file named
    ``a$^$.toml`` made every figure raise matplotlib's ParseSyntaxException), and a file name's
    bytes that are not UTF-8 (Python's surrogate escapes, which FreeType refuses: a TypeError)
    shown as "?". A text still empty is a tick label its axis' formatter writes when the figure is
    drawn: numbers, in mathtext by design (a log axis' 10^8), so it is left to be parsed (found by
    a hunt: the report's kn axes read $\\mathdefault{10^{8}}$)."""
    from matplotlib.text import Text

    for text in fig.findobj(Text):
        written = text.get_text()
        if not written:
            continue
        text.set_parse_math(False)
        shown_text = written.encode("utf-8", "replace").decode("utf-8")
        if shown_text != written:
            text.set_text(shown_text)


def pushover_figure(result: TiltResult, path: Path, *, title: str = "") -> Path:
    """:func:`pushover_drawing` written to ``path``."""
    return saved(pushover_drawing(result, title=title), path)


#: colour and line style of each of the EC8 drift limits on a pushover curve
DRIFT_STYLES = {0.005: ("tab:purple", ":"), 0.0075: ("tab:brown", "-."), 0.01: ("tab:green", "--")}


def pushover_drawing(result: TiltResult, *, title: str = ""):
    """The pushover curve, a Figure: tilt angle against the monitored horizontal displacement
    since the tilt began (from the first record's, as the drift:
    :class:`~drydem.analysis.tilt.Record`), mm; the EN 1998-1 4.4.3.2 drift limits (lines at
    limit x wall height) named by the buildings they are for
    (:data:`~drydem.analysis.drift.EC8_DRIFT_MEANINGS`), each with the angle at which the curve
    first reaches it, marked on the curve, or "not reached"; the
    blocks lost on the way (:func:`draw_lost_blocks`), so that a plateau where bricks fell is
    not read as ductility; the collapse angle."""
    fig = new_figure(figsize=(7.2, 6.4), layout="constrained")
    ax = fig.subplots()
    ux_mm = (np.array([r.ux_m for r in result.records]) - result.records[0].ux_m) * 1e3 if result.records else np.zeros(0)
    tilt = np.array([r.tilt_deg for r in result.records])
    ax.plot(ux_mm, tilt, "-", marker="." if len(tilt) < 60 else None, color="tab:blue", label="equilibrium states")
    angles = result.drift_limit_angles_deg
    for limit in EC8_DRIFT_LIMITS:
        colour, style = DRIFT_STYLES[limit]
        x_mm, at = limit * result.wall_height_m * 1e3, angles[limit]
        reached = "not reached" if at is None else f"reached at {at:.2f} deg"
        ax.axvline(x_mm, color=colour, linestyle=style, linewidth=1.2,
                   label=f"drift {limit * 100:g} %, {EC8_DRIFT_MEANINGS[limit]}: {reached}")
        if at is not None:
            ax.plot(x_mm, at, "o", color=colour, markersize=5)
            ax.annotate(f"{limit * 100:g} %: {at:.2f} deg", (x_mm, at), xytext=(7, -2), textcoords="offset points",
                        fontsize="small", color=colour, va="top", bbox=dict(facecolor="white", edgecolor="none", pad=0.5))
    draw_lost_blocks(ax, result.lost_blocks, ux_mm, tilt)
    if result.collapse_angle_deg is not None:
        ax.axhline(result.collapse_angle_deg, color="tab:red", linewidth=1, label=f"collapse {result.collapse_angle_deg:.2f} deg")
    ylabel = "tilt angle (deg)" if result.settings.loading == "tilt" else "atan(load multiplier) (deg)"
    along = "" if result.settings.load_direction == 0 else " along y"
    ax.set(xlabel=f"horizontal displacement of {result.monitored_block}{along} since 0 deg (mm)", ylabel=ylabel, title=title)
    ax.set_xlim(left=min(0.0, ux_mm.min(initial=0.0)))
    ax.set_ylim(bottom=0.0)
    ax.grid(alpha=0.3)
    fig.legend(loc="outside lower center", fontsize="small", title="Eurocode 8 damage limitation (EN 1998-1 4.4.3.2) and failures",
               title_fontsize="small")
    return fig


def draw_lost_blocks(ax, lost_blocks: list[tuple[str, float]], ux_mm: np.ndarray, tilt_deg: np.ndarray, *, listed: int = 3) -> None:
    """Mark on a pushover curve (``ux_mm``, ``tilt_deg`` increasing) each tilt at which blocks
    were lost (``lost_blocks``: name, tilt in deg): an orange triangle at that tilt on the
    curve's first state at or past it (beside the curve's end if past its last state, e.g. in
    the collapse), labelled "N blocks lost at X deg", and the jump to that state drawn over in
    orange: a local failure, not ductility. Past the first ``listed`` tilts, the rest share one label."""
    events = sorted(Counter(t for _, t in lost_blocks).items())
    rest = sum(n for _, n in events[listed:])
    jumps = []  # x, y of each jump, then nan: one line
    for k, (tilt, n) in enumerate(events):
        i = int(np.searchsorted(tilt_deg, tilt - 1e-9))
        if 0 < i < len(tilt_deg):
            jumps += [(ux_mm[i - 1], tilt_deg[i - 1]), (ux_mm[i], tilt_deg[i]), (np.nan, np.nan)]
        x_mm = ux_mm[min(i, len(ux_mm) - 1)] if len(ux_mm) else 0.0
        when = " (past the last equilibrium)" if i == len(tilt_deg) else ""
        label = (f"{n} block{'s' * (n > 1)} lost at {tilt:.2f} deg{when}" if k < listed else
                 f"{rest} more blocks lost at {events[listed][0]:.2f} to {events[-1][0]:.2f} deg" if k == listed else None)
        ax.plot(x_mm, tilt, "v", color="tab:orange", markeredgecolor="k", markersize=8, label=label, gid="lost blocks", zorder=3)
    if jumps:
        ax.plot(*np.transpose(jumps), color="tab:orange", linewidth=2.5, label="jump where blocks fell: a local failure, not ductility")


def history_figure(history: History, path: Path, *, title: str = "", monitored: str = "",
                   fallen: list[tuple[str, float, str]] = ()) -> Path:
    """The time history of a shaking-table analysis in three panels on one time axis: the
    table's acceleration (m/s2; each component that is not zero throughout), the monitored
    block's displacement relative to the table (ux, uz and a uy that is not zero, mm) and its
    rotation across the motion (rad, about ``history.rotation_about``). The first fall among
    ``fallen`` (block, time in s, rule) is marked on every panel."""
    fig = new_figure(figsize=(7.2, 6.4), layout="constrained")
    ground_ax, moved_ax, turn_ax = fig.subplots(3, 1, sharex=True)
    t = history.time_s
    ground = history.ground_acceleration_m_s2
    shown = [k for k in range(3) if np.any(ground[:, k])] or [0]
    for k in shown:
        ground_ax.plot(t, ground[:, k], color=("tab:gray", "tab:olive", "tab:brown")[k], label=f"a_{'xyz'[k]}")
    ground_ax.set(ylabel="table acceleration (m/s2)", title=title)
    moved_ax.plot(t, history.ux_m * 1e3, color="tab:blue", label="ux")
    if np.any(history.uy_m):
        moved_ax.plot(t, history.uy_m * 1e3, color="tab:green", label="uy")
    moved_ax.plot(t, history.uz_m * 1e3, color="tab:orange", label="uz")
    who = f" of {monitored}" if monitored else ""
    moved_ax.set(ylabel=f"displacement{who}\nrelative to the table (mm)")
    turn_ax.plot(t, history.rotation_rad, color="tab:purple", label=f"rotation about {history.rotation_about}")
    turn_ax.set(xlabel="time (s)", ylabel=f"rotation{who} (rad)")
    span = max(t[-1] - t[0], 1e-9)
    right = t[0] + span
    if len(fallen):
        first = min(time_s for _, time_s, _ in fallen)
        names = [name for name, time_s, _ in fallen if time_s == first]
        label = f"{', '.join(names[:3])}{', ...' if len(names) > 3 else ''} fell at {first:.3f} s"
        for ax in (ground_ax, moved_ax, turn_ax):
            ax.axvline(first, color="tab:red", linestyle="--", linewidth=1.2, label=label if ax is ground_ax else None)
        right = max(right, first + 0.03 * span)  # a fall at the end stays in sight
    for ax in (ground_ax, moved_ax, turn_ax):
        ax.axhline(0.0, color="0.6", linewidth=0.6)
        ax.grid(alpha=0.3)
        ax.legend(loc="upper right", fontsize="small")
    turn_ax.set_xlim(t[0], right)
    return saved(fig, path)


def xz_outline(points: np.ndarray) -> np.ndarray:
    """A block's outline in the wall's plane (x, z): the hull of its projected vertices, m."""
    from scipy.spatial import ConvexHull

    xz = np.asarray(points)[:, [0, 2]]
    return xz[ConvexHull(xz).vertices]


def block_outlines(model: Model, state: State, blocks: np.ndarray) -> list[np.ndarray]:
    """Outlines of ``blocks`` in the wall's plane (x, z) at ``state``, m."""
    return [xz_outline(model.world_vertices(b, state.position[b], state.quaternion[b])) for b in blocks]


def draw_displacements(fig, ax, outlines: list[np.ndarray], magnitude_mm: np.ndarray, *, title: str, norm=None,
                       colorbar: bool = True):
    """The renderer of mechanisms and videos: block outlines coloured by displacement magnitude
    (mm, on ``norm``, default 0 to the largest), a colour bar unless ``colorbar`` is False (a
    figure of several panels draws one for all), equal axes. Returns the coloured collection."""
    from matplotlib.collections import PolyCollection
    from matplotlib.colors import Normalize

    norm = norm or Normalize(0.0, float(magnitude_mm.max(initial=0.0)) or 1.0)
    polys = PolyCollection(outlines, array=magnitude_mm, cmap="viridis", norm=norm, edgecolors="k", linewidths=0.3)
    ax.add_collection(polys)
    if colorbar:
        fig.colorbar(polys, ax=ax, label="displacement (mm)", shrink=0.8)
    ax.autoscale_view()
    ax.set_aspect("equal")
    ax.set(title=title, xlabel="x (m)", ylabel="z (m)")
    return polys


#: how blocks lost (fallen out of the model) are drawn: faded, dashed, where they were taken out
LOST_STYLE = dict(facecolors="0.75", edgecolors="0.3", linewidths=0.6, linestyles="--", alpha=0.35,
                  label="lost: fell out of the model (drawn where taken out)")


def is_wall_like(model: Model) -> bool:
    """Whether the model is a wall drawn in the x-z plane, shown by its projection on that plane:
    its movable blocks span in y no more than the deepest of them (no block lies behind
    another). A building or any other deep 3D model is drawn in 3D instead
    (:func:`draw_blocks_3d`)."""
    movable = np.flatnonzero(model.block_movable)
    return one_deep([model.block_shape[b].vertices for b in movable])


def one_deep(blocks: list[np.ndarray]) -> bool:
    """Whether ``blocks`` (each its vertices, m) span in y no more than the deepest of them: a
    wall, drawn by its projection on the x-z plane (:func:`is_wall_like`; none: True)."""
    if not blocks:
        return True
    lo = np.array([b[:, 1].min() for b in blocks])
    hi = np.array([b[:, 1].max() for b in blocks])
    return bool(hi.max() - lo.min() <= (hi - lo).max() * (1 + 1e-6) + 1e-12)


#: the camera's azimuth (deg, matplotlib's) of a 3D mechanism by the load direction (x, y): on the
#: side the load pushes towards, a little off its axis, so that what it pushes out is in front
VIEW_AZIMUTH = {0: -25.0, 1: 65.0}


def block_faces(model: Model, state: State, blocks) -> tuple[list[np.ndarray], np.ndarray]:
    """The faces of ``blocks`` at ``state`` (each its world vertices, m) and, for each face, the
    position in ``blocks`` of its block."""
    faces, owner = [], []
    for k, b in enumerate(blocks):
        world = model.world_vertices(b, state.position[b], state.quaternion[b])
        faces += [world[f] for f in model.block_shape[b].faces]
        owner += [k] * len(model.block_shape[b].faces)
    return faces, np.array(owner, dtype=int)


def draw_blocks_3d(fig, ax, model: Model, state: State, blocks: np.ndarray, values: np.ndarray, *, title: str,
                   norm=None, colours=None, marker: tuple[np.ndarray, str] | None = None, load_direction: int = 0,
                   label: str = "displacement (mm)", lost: np.ndarray = (), colorbar: bool = True):
    """A 3D model in perspective on ``ax`` (a 3D axes): the faces of ``blocks`` at ``state``
    coloured by ``values`` (one per block, on ``norm``, with a colour bar ``label`` unless
    ``colorbar`` is False) or by ``colours`` (one per block), the ``lost`` blocks faded
    (:data:`LOST_STYLE`), an optional ``marker`` (x-y-z point, label: for the caller's legend),
    true proportions, seen from the side the load (``load_direction`` 0: x, 1: y) pushes
    towards. Returns the collection of ``blocks``' faces."""
    faces, owner = block_faces(model, state, blocks)
    polys = draw_faces_3d(fig, ax, faces, owner, values, title=title, norm=norm, colours=colours, load_direction=load_direction,
                          label=label, lost=block_faces(model, state, lost)[0], colorbar=colorbar)
    if marker is not None:
        ax.plot(*[[c] for c in marker[0]], "r+", markersize=12, markeredgewidth=2, label=marker[1], zorder=10)
    return polys


def draw_faces_3d(fig, ax, faces: list[np.ndarray], owner: np.ndarray, values, *, title: str, norm=None, colours=None,
                  load_direction: int = 0, label: str = "displacement (mm)", lost: list[np.ndarray] = (), colorbar: bool = True):
    """The renderer of 3D mechanisms and videos (:func:`draw_blocks_3d`): ``faces`` (each its
    world vertices, m) of blocks numbered ``owner`` (one per face), coloured by their block's
    value or colour, the ``lost`` faces faded; true proportions over what is drawn, seen from
    the side the load pushes towards. Returns the collection of ``faces``."""
    from matplotlib.colors import Normalize
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    polys = Poly3DCollection(faces, edgecolors="k", linewidths=0.15)
    if colours is None:
        norm = norm or Normalize(0.0, float(np.max(values, initial=0.0)) or 1.0)
        polys.set_array(np.asarray(values)[owner])
        polys.set_cmap("viridis")
        polys.set_norm(norm)
        if colorbar:
            fig.colorbar(polys, ax=ax, label=label, shrink=0.6, pad=0.14)
    else:
        polys.set_facecolor([colours[k] for k in owner])
    ax.add_collection3d(polys)
    lost = list(lost)
    if lost:
        ax.add_collection3d(Poly3DCollection(lost, **LOST_STYLE))
    points = np.concatenate(list(faces) + lost) if len(faces) + len(lost) else np.zeros((1, 3))
    frame_3d(ax, points.min(0), points.max(0), title=title, load_direction=load_direction)
    return polys


def frame_3d(ax, lo: np.ndarray, hi: np.ndarray, *, title: str, load_direction: int = 0) -> None:
    """A 3D axes showing the box ``lo``-``hi`` (m) in true proportions, seen from the side the
    load (``load_direction`` 0: x, 1: y) pushes towards (:data:`VIEW_AZIMUTH`)."""
    ax.set(xlim=(lo[0], hi[0]), ylim=(lo[1], hi[1]), zlim=(lo[2], hi[2]), xlabel="x (m)", ylabel="y (m)", zlabel="z (m)", title=title)
    ax.set_box_aspect(np.maximum(hi - lo, 1e-3 * (hi - lo).max()))
    ax.view_init(elev=22.0, azim=VIEW_AZIMUTH.get(load_direction, -60.0))


def mechanism_figure(model: Model, states: list[tuple[str, State, frozenset[str]]], path: Path, *, monitored: str | None = None,
                     load_direction: int = 0) -> Path:
    """:func:`mechanism_drawing` written to ``path``."""
    return saved(mechanism_drawing(model, states, monitored=monitored, load_direction=load_direction), path)


def mechanism_drawing(model: Model, states: list[tuple[str, State, frozenset[str]]], *, monitored: str | None = None,
                      load_direction: int = 0):
    """The model at each of ``states`` (label, State, names of the blocks lost by then), a
    Figure (:func:`panels_drawing`): blocks coloured by the magnitude of their displacement from
    the model file, every panel on one logarithmic scale, so that millimetres at equilibrium and
    decimetres past collapse both show (a thousandth of the largest and less share its darkest
    colour)."""
    from matplotlib.colors import LogNorm

    magnitudes = [np.linalg.norm(state.position - model.block_centroid, axis=1) * 1e3 for _, state, _ in states]
    lost = [np.isin(model.block_name, list(names)) for _, _, names in states]
    largest = max(float(m[~gone].max(initial=0.0)) for m, gone in zip(magnitudes, lost)) or 1.0
    norm = LogNorm(largest * 1e-3, largest)
    panels = [(label, state, np.clip(m, norm.vmin, None), gone) for (label, state, _), m, gone in zip(states, magnitudes, lost)]
    return panels_drawing(model, panels, norm=norm, label="displacement (mm, log scale)",
                          monitored=monitored, load_direction=load_direction)


#: how far a limit-analysis mechanism is drawn: its fastest point moved this share of the wall height
MECHANISM_DRAWN_HEIGHTS = 0.1


def limit_mechanism_figure(model: Model, result: LimitResult, path: Path, *, title: str, load_direction: int = 0) -> Path:
    """:func:`limit_mechanism_drawing` written to ``path``."""
    return saved(limit_mechanism_drawing(model, result, title=title, load_direction=load_direction), path)


def limit_mechanism_drawing(model: Model, result: LimitResult, *, title: str, load_direction: int = 0):
    """The collapse mechanism of a limit analysis, a Figure (:func:`panels_drawing`): the blocks
    moved along it until its fastest point has moved :data:`MECHANISM_DRAWN_HEIGHTS` of the wall
    height (the shape exaggerated), coloured by their centroid's virtual displacement divided by
    the largest: a mechanism has a shape, not a magnitude."""
    from matplotlib.colors import Normalize

    speed = np.linalg.norm(result.velocity, axis=1)
    state = result.mechanism_state(model, MECHANISM_DRAWN_HEIGHTS * wall_height(model))
    panels = [(title, state, speed / (speed.max(initial=0.0) or 1.0), np.zeros(model.n_blocks, dtype=bool))]
    return panels_drawing(model, panels, norm=Normalize(0.0, 1.0), label="virtual displacement (normalised: largest 1)",
                          load_direction=load_direction)


def panels_drawing(model: Model, panels: list[tuple[str, State, np.ndarray, np.ndarray]], *, norm, label: str,
                   monitored: str | None = None, load_direction: int = 0):
    """The model at each of ``panels`` (title, State, a value per block on ``norm``, lost: (nb,)
    bool) side by side, a Figure: a wall in its plane (x-z), a deep 3D model such as a building
    in 3D (:func:`is_wall_like`) seen from the side the load (``load_direction`` 0: x, 1: y)
    pushes towards. Blocks in the model are coloured by their value, one colour bar ``label``
    for all panels; lost blocks are faded (:data:`LOST_STYLE`); the ``monitored`` block is
    outlined in red (marked + in 3D). The legend is under the panels, on no block."""
    from matplotlib.collections import PolyCollection
    from matplotlib.patches import Polygon

    flat = is_wall_like(model)
    fig = new_figure(figsize=(5.2 * len(panels) + 1.2, 4.0) if flat else (6.4 * len(panels) + 1.2, 6.2), layout="constrained")
    axes = fig.subplots(1, len(panels), squeeze=False, sharex=flat, sharey=flat, subplot_kw=None if flat else {"projection": "3d"})[0]
    for ax, (title, state, values, lost) in zip(axes, panels):
        kept, gone = np.flatnonzero(~lost), np.flatnonzero(lost)
        if not flat:
            marker = None if monitored is None else (state.position[model.block_index(monitored)], f"monitored: {monitored}")
            polys = draw_blocks_3d(fig, ax, model, state, kept, values[kept], title=title, norm=norm, lost=gone, marker=marker,
                                   load_direction=load_direction, colorbar=False)
            continue
        polys = draw_displacements(fig, ax, block_outlines(model, state, kept), values[kept], title=title, norm=norm, colorbar=False)
        if gone.size:
            ax.add_collection(PolyCollection(block_outlines(model, state, gone), **LOST_STYLE))
        if monitored is not None:
            outline = block_outlines(model, state, [model.block_index(monitored)])[0]
            ax.add_patch(Polygon(outline, fill=False, edgecolor="red", linewidth=1.8, zorder=3, label=f"monitored: {monitored}"))
        ax.autoscale_view()
    bar = fig.colorbar(polys, ax=list(axes), label=label, shrink=0.8)
    bar.ax.yaxis.set_major_formatter("{x:g}")  # 0.1, 1, 10 rather than powers of ten
    legend = {text: handle for ax in axes for handle, text in zip(*ax.get_legend_handles_labels())}
    if legend:
        fig.legend(legend.values(), legend.keys(), loc="outside lower center", ncols=len(legend), fontsize="small")
    return fig


#: colours of the layout drawing, by unit kind (drydem.masonry.layout)
KIND_COLOURS = {"brick": "#c8703c", "half": "#e0a070", "header": "#8c4a2a", "lintel": "#3c6ec8", "void": "white", "base": "0.6"}


def layout_figure(model: Model, path: Path, *, kinds: list[str] | None = None, voids: list[np.ndarray] = (),
                  monitored: str | None = None, title: str = "") -> Path:
    """The model in its plane as built: blocks coloured by ``kinds`` (one per block: brick,
    half, header, lintel, base; default brick, base for fixed blocks), ``voids`` (x-z outlines,
    m) hatched, the ``monitored`` block ringed. A deep 3D model (:func:`is_wall_like`: a
    building) is drawn in 3D, the voids left out."""
    from matplotlib.collections import PolyCollection
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    fixed = model.block_fixed.all(axis=1)
    kinds = kinds or ["base" if f else "brick" for f in fixed]
    if not is_wall_like(model):
        fig = new_figure(figsize=(8.0, 6.4), layout="constrained")
        ax = fig.subplots(subplot_kw={"projection": "3d"})
        marker = None if monitored is None else (model.block_centroid[model.block_index(monitored)], f"monitored: {monitored}")
        draw_blocks_3d(fig, ax, model, State.at_rest(model.block_centroid), np.arange(model.n_blocks), np.zeros(model.n_blocks),
                       colours=[KIND_COLOURS[k] for k in kinds], title=title, marker=marker)
        if marker is not None:
            fig.legend(loc="outside lower center", fontsize="small")
        return saved(fig, path)
    outlines = block_outlines(model, State.at_rest(model.block_centroid), np.arange(model.n_blocks))
    fig = new_figure(figsize=(8.0, 4.4), layout="constrained")
    ax = fig.subplots()
    ax.add_collection(PolyCollection(outlines, facecolors=[KIND_COLOURS[k] for k in kinds], edgecolors="k", linewidths=0.4))
    if len(voids):
        ax.add_collection(PolyCollection(voids, facecolors="white", edgecolors="0.5", hatch="////", linewidths=0.3))
    legend = [Patch(facecolor=KIND_COLOURS[k], edgecolor="k", label=k) for k in dict.fromkeys(kinds)]
    if len(voids):
        legend.append(Patch(facecolor="white", edgecolor="0.5", hatch="////", label="void"))
    if monitored is not None:
        b = model.block_index(monitored)
        ax.plot(*model.block_centroid[b, [0, 2]], "o", markersize=9, markerfacecolor="none", markeredgecolor="red", markeredgewidth=2)
        legend.append(Line2D([], [], marker="o", linestyle="", markerfacecolor="none", markeredgecolor="red", label=f"monitored: {monitored}"))
    ax.autoscale_view()
    ax.set_aspect("equal")
    ax.set(title=title, xlabel="x (m)", ylabel="z (m)")
    ax.legend(handles=legend, loc="upper left", bbox_to_anchor=(1.0, 1.0), fontsize="small")
    return saved(fig, path)


#: the most bars a histogram of angles on a lattice is drawn with, one per step (more: numpy's "auto")
MAX_LATTICE_BARS = 60


def histogram_bins(angles: np.ndarray):
    """The bins of a histogram of ``angles``: one bar per step, centred on it, where the distinct
    angles lie on a lattice of their smallest spacing (tilts' collapse angles are multiples of
    the increment: with numpy's "auto" bins their edges fell on the values, each drawn in the
    bar above it but the last, drawn in the bar below; found by a hunt), at most
    :data:`MAX_LATTICE_BARS`; else numpy's "auto" (one bar for a single value)."""
    values = np.unique(angles)
    if values.size < 2:
        return 1
    step = float(np.diff(values).min())
    steps = (values - values[0]) / step
    if np.abs(steps - np.round(steps)).max() > 1e-6 or steps[-1] >= MAX_LATTICE_BARS:
        return "auto"
    return values[0] + step * (np.arange(round(steps[-1]) + 2) - 0.5)


def histogram_figure(angles_deg, path: Path, *, title: str = "", mean_deg: float | None = None, p05_deg: float | None = None,
                     experiment: tuple[float, float] | None = None, xlabel: str = "collapse angle (deg)") -> Path:
    """Histogram of the samples' ``angles_deg`` (a Monte Carlo run), with their mean and 5th
    percentile marked, and an ``experiment`` (mean in deg, coefficient of variation as a
    fraction) drawn as its mean and the band mean (1 +- cov). The legend is drawn only when
    something is labelled (no sample angle and nothing marked: none, and no warning of
    matplotlib's)."""
    angles = np.asarray(angles_deg, dtype=float)
    fig = new_figure(figsize=(6.4, 4.4), layout="constrained")
    ax = fig.subplots()
    if angles.size:
        ax.hist(angles, bins=histogram_bins(angles), color="tab:blue", alpha=0.75, edgecolor="white",
                label=f"{angles.size} samples")
    if experiment is not None:
        mean, cov = experiment
        ax.axvspan(mean * (1.0 - cov), mean * (1.0 + cov), color="tab:green", alpha=0.15, zorder=0,
                   label=f"experiment CoV {cov:.1%}")
        ax.axvline(mean, color="tab:green", linewidth=1.5, label=f"experiment {mean:.1f} deg")
    if mean_deg is not None:
        ax.axvline(mean_deg, color="tab:red", linewidth=1.5, label=f"mean {mean_deg:.2f} deg")
    if p05_deg is not None:
        ax.axvline(p05_deg, color="tab:red", linestyle="--", linewidth=1.2, label=f"5th percentile {p05_deg:.2f} deg")
    ax.set(xlabel=xlabel, ylabel="samples", title=title)
    ax.grid(alpha=0.3)
    if ax.get_legend_handles_labels()[1]:
        ax.legend(loc="best", fontsize="small")
    return saved(fig, path)
