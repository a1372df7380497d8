"""Figures of a tilting analysis: pushover curve (paper Figs 9-11) and mechanism (Figs 7-8).

matplotlib is imported inside the functions (Agg backend), so the engine does not load it.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from drydem.analysis.drift import EC8_DRIFT_LIMITS
from drydem.analysis.tilt import TiltResult
from drydem.model import Model
from drydem.rotation import matrices
from drydem.state import State


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def pushover_figure(result: TiltResult, path: Path, *, title: str = "") -> Path:
    """Tilt angle against the monitored horizontal displacement, with the EC8 drift limits."""
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(6.4, 4.4), layout="constrained")
    ux_mm = np.array([r.ux_m for r in result.records]) * 1e3
    tilt = [r.tilt_deg for r in result.records]
    ax.plot(ux_mm, tilt, "-", marker="." if len(tilt) < 60 else None, color="tab:blue", label="equilibrium states")
    for limit, style in zip(EC8_DRIFT_LIMITS, (":", "-.", "--")):
        ax.axvline(limit * result.wall_height_m * 1e3, color="0.4", linestyle=style, linewidth=1, label=f"drift {limit:.2%}")
    if result.collapse_angle_deg is not None:
        ax.axhline(result.collapse_angle_deg, color="tab:red", linewidth=1, label=f"collapse {result.collapse_angle_deg:.2f} deg")
    ylabel = "tilt angle (deg)" if result.settings.loading == "tilt" else "atan(load multiplier) (deg)"
    ax.set(xlabel=f"horizontal displacement of {result.monitored_block} (mm)", ylabel=ylabel, title=title)
    ax.set_xlim(left=min(0.0, ux_mm.min(initial=0.0)))
    ax.set_ylim(bottom=0.0)
    ax.grid(alpha=0.3)
    ax.legend(loc="lower right", fontsize="small")
    fig.savefig(path, dpi=150)
    plt.close(fig)
    return path


def block_outlines(model: Model, state: State, blocks: np.ndarray) -> list[np.ndarray]:
    """Outlines of ``blocks`` in the wall's plane (x, z), m: the hull of the projected vertices."""
    from scipy.spatial import ConvexHull

    rot = matrices(state.quaternion)
    outlines = []
    for b in blocks:
        shape = model.block_shape[b]
        world = (shape.vertices - shape.centroid) @ rot[b].T + state.position[b]
        xz = world[:, [0, 2]]
        outlines.append(xz[ConvexHull(xz).vertices])
    return outlines


def mechanism_figure(model: Model, states: list[tuple[str, State, frozenset[str]]], path: Path, *, monitored: str | None = None) -> Path:
    """The model in its plane at each of ``states`` (label, State, names of blocks to leave out,
    e.g. those fallen away by then), blocks coloured by the magnitude of their displacement from
    the model file, each panel on its own scale (millimetres at equilibrium, decimetres past collapse)."""
    plt = _pyplot()
    from matplotlib.collections import PolyCollection

    shown = [np.array([b for b, name in enumerate(model.block_name) if name not in hidden]) for _, _, hidden in states]
    magnitudes = [np.linalg.norm(s.position[b] - model.block_centroid[b], axis=1) * 1e3 for (_, s, _), b in zip(states, shown)]
    fig, axes = plt.subplots(1, len(states), figsize=(5.6 * len(states), 4.2), layout="constrained", squeeze=False)
    for ax, (label, state, _), blocks, magnitude in zip(axes[0], states, shown, magnitudes):
        outlines = block_outlines(model, state, blocks)
        polys = PolyCollection(outlines, array=magnitude, cmap="viridis", clim=(0.0, float(magnitude.max(initial=0.0)) or 1.0),
                               edgecolors="k", linewidths=0.3)
        ax.add_collection(polys)
        fig.colorbar(polys, ax=ax, label="displacement (mm)", shrink=0.8)
        if monitored is not None:
            b = model.block_index(monitored)
            ax.plot(*state.position[b, [0, 2]], "r+", markersize=10, label=f"monitored: {monitored}")
            ax.legend(loc="upper right", fontsize="small")
        ax.autoscale_view()
        ax.set_aspect("equal")
        ax.set(title=label, xlabel="x (m)", ylabel="z (m)")
    fig.savefig(path, dpi=150)
    plt.close(fig)
    return path
