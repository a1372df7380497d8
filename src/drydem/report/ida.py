"""Incremental dynamic analysis (IDA) in the report of a study: its shake runs (``analysis =
"shake"``, :mod:`drydem.parametric.study`) as one curve per target and motion (and per other
parameters where they vary), peak response against intensity, and each curve's collapse: the
dynamic counterpart of the tilting analysis' collapse angle.

A curve's intensity is the PGA of each scaled motion (scale x the motion's PGA); its response
is the monitored block's largest |rotation| over the run (rad). Its collapse scale is the
smallest scale at which the run overturned (a block fell). A rocking block may survive a
larger one (the "safe region" above the minimum overturning acceleration: Zhang & Makris 2001,
"Rocking response of free-standing blocks under cycloidal pulses", J. Eng. Mech. 127(5)), so
the collapse scale is a minimum over the scales run, not the bound of a bisection, and the
scales above it that survived are said.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from drydem.model.parameters import G
from drydem.parametric.study import motion_label

#: the RunSpec fields that tell a shake run's curve apart, beside its target and motion
VARIANT = ("kn", "ks", "friction", "points", "duration_s", "restitution", "contact_damping_ratio", "monitor")

FIGURE_CAPTION = (
    "IDA: peak rotation of the monitored block (max |rotation| about y over the run, rad, log scale) against the PGA of "
    "the scaled motion (m/s2; g on the top axis), one curve per target and record; crosses: runs that overturned (a block "
    "fell); ringed: the collapse scale, the smallest scale at which the run overturned. A larger scale may survive (the "
    "'safe region' above the minimum overturning intensity of a rocking block): the curves join every scale run, they "
    "do not bisect between the last survival and the first collapse")
TABLE_TITLE = "IDA: collapse intensity per target and record (the dynamic counterpart of the collapse angle)"
TABLE_NOTE = (
    "Collapse: the smallest scale run at which the target overturned (a block fell), and its PGA = scale x the record's "
    "PGA (file records baseline-corrected; pulses of 1 m/s2, so that the scale is the amplitude). \"none up to X\": no "
    "run overturned, X the largest scale (PGA) run. A larger scale may survive (last column): the collapse scale is a "
    "minimum over the scales run, not a bisected threshold.")


@dataclass(frozen=True)
class IdaCurve:
    """The ok shake runs of one target and motion (and one set of the :data:`VARIANT` fields:
    ``variant``, (name, value) pairs), by increasing scale: ``scales``, the PGA of each scaled
    motion (m/s2), the peak rotation (rad) and whether it overturned; ``motion_pga_m_s2``: the
    motion's PGA before its scale."""

    target: str
    motion: str
    variant: tuple[tuple[str, object], ...]
    scales: tuple[float, ...]
    pga_m_s2: tuple[float, ...]
    max_rotation_rad: tuple[float, ...]
    overturned: tuple[bool, ...]
    motion_pga_m_s2: float

    @property
    def collapse(self) -> int | None:
        """The index of the smallest scale at which the run overturned, None if none did."""
        return next((k for k, fell in enumerate(self.overturned) if fell), None)

    @property
    def survived_above(self) -> list[float]:
        """The scales above the collapse scale whose runs did not overturn (the safe region)."""
        first = self.collapse
        return [] if first is None else [s for s, fell in zip(self.scales[first + 1:], self.overturned[first + 1:]) if not fell]

    def label(self, varying: set[str]) -> str:
        """The target and record, and the ``varying`` fields of the variant."""
        extra = [f"{name} {_value(value)}" for name, value in self.variant if name in varying]
        return ", ".join([Path(self.target).stem, motion_label(self.motion), *extra])


def ida_curves(records: list[dict]) -> list[IdaCurve]:
    """The IDA curves of the ok shake records among ``records`` (sorted by target, motion and variant)."""
    groups: dict[tuple, list[dict]] = {}
    for record in records:
        spec = record["spec"]
        if record["status"] == "ok" and spec["analysis"] == "shake":
            key = (spec["target"], spec["motion"], tuple((name, spec.get(name)) for name in VARIANT))
            groups.setdefault(key, []).append(record)
    curves = []
    for (target, motion, variant), runs in sorted(groups.items(), key=lambda item: (item[0][0], item[0][1], repr(item[0][2]))):
        runs.sort(key=lambda r: r["spec"]["scale"])
        summaries = [r["summary"] for r in runs]
        scales = tuple(float(r["spec"]["scale"]) for r in runs)
        pga = tuple(float(s["pga_m_s2"]) for s in summaries)
        base = summaries[0].get("motion_pga_m_s2", pga[0] / scales[0])
        curves.append(IdaCurve(target, motion, variant, scales, pga, tuple(float(s["max_rotation_rad"]) for s in summaries),
                               tuple(bool(s["overturned"]) for s in summaries), float(base)))
    return curves


def varying(curves: list[IdaCurve]) -> set[str]:
    """The VARIANT fields whose values differ among ``curves`` (said in their labels)."""
    values: dict[str, set[str]] = {}
    for curve in curves:
        for name, value in curve.variant:
            values.setdefault(name, set()).add(repr(value))
    return {name for name, found in values.items() if len(found) > 1}


def draw_ida(ax, curves: list[IdaCurve]) -> bool:
    """The IDA curves on ``ax`` (FIGURE_CAPTION); whether there was one to draw."""
    differ = varying(curves)
    positive = all(r > 0 for curve in curves for r in curve.max_rotation_rad)
    for curve in curves:
        pga, rotation = np.array(curve.pga_m_s2), np.array(curve.max_rotation_rad)
        line, = ax.plot(pga, rotation, "o-", markersize=3, label=curve.label(differ))
        fell = np.array(curve.overturned)
        if fell.any():
            ax.plot(pga[fell], rotation[fell], "x", color=line.get_color(), markersize=8)
            first = curve.collapse
            ax.plot(pga[first], rotation[first], "o", markersize=13, markerfacecolor="none", color=line.get_color())
    ax.set(xlabel="PGA (m/s2)", ylabel="max rotation (rad)", yscale="log" if curves and positive else "linear")
    if curves:
        top = ax.secondary_xaxis("top", functions=(lambda a: a / G, lambda g: g * G))
        top.set_xlabel("PGA (g)")
    ax.grid(alpha=0.3)
    if ax.get_legend_handles_labels()[0]:
        ax.legend(fontsize="x-small")
    return bool(curves)


def collapse_table(curves: list[IdaCurve]) -> tuple[list[str], list[list[str]]]:
    """The header and rows of the collapse table (TABLE_TITLE, TABLE_NOTE): per curve, the
    record's PGA, the scales run, the collapse scale and PGA (m/s2, g) or "none up to", and the
    larger scales that survived."""
    differ = varying(curves)
    header = ["target", "record", *(["parameters"] if differ else []), "record PGA (m/s2)", "scales run", "collapse scale",
              "collapse PGA (m/s2)", "collapse PGA (g)", "larger scales survived"]
    rows = []
    for curve in curves:
        first = curve.collapse
        if first is None:
            cells = [f"none up to {curve.scales[-1]:g}", f"none up to {curve.pga_m_s2[-1]:.3g}", f"none up to {curve.pga_m_s2[-1] / G:.3g}"]
        else:
            cells = [f"{curve.scales[first]:g}", f"{curve.pga_m_s2[first]:.3g}", f"{curve.pga_m_s2[first] / G:.3g}"]
        extra = [", ".join(f"{name} {_value(value)}" for name, value in curve.variant if name in differ)] if differ else []
        rows.append([Path(curve.target).stem, motion_label(curve.motion), *extra, f"{curve.motion_pga_m_s2:.3g}",
                     ", ".join(f"{s:g}" for s in curve.scales), *cells, ", ".join(f"{s:g}" for s in curve.survived_above) or "-"])
    return header, rows


def _value(value) -> str:
    if isinstance(value, float) and math.isfinite(value):
        return f"{value:g}"
    return "default" if value is None else str(value)
