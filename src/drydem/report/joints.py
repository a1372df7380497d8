"""Stress-dependent joints in the report of a study: the tilting runs with a joint law
(:attr:`drydem.parametric.study.RunSpec.joint_law`, written by ``drydem calibrate
--joint-model ...``), grouped into evaluations (one law at one kn, ks, over the walls), the
calibrated law among them, and its collapse angles beside the experiments and the constant
kn = ks = 3e7 of the seed paper's Table 3.

The objective is the calibration's own (:func:`drydem.parametric.calibrate.calibration_error`),
so that the law the report calls calibrated is the one ``drydem calibrate`` found.
"""

from __future__ import annotations

import json
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from pathlib import Path

from drydem.errors import ModelError
from drydem.model.parameters import JointMaterial
from drydem.parametric.calibrate import (CalibrationError, calibration_error, experimental_angles, mean_absolute_relative_error,
                                         wall_angle)


def wall_of(record: dict) -> str:
    """The wall a run analyses: its target's name (a built-in design or a file's stem)."""
    return Path(record["spec"]["target"]).stem


def joint_law(record: dict) -> str | None:
    """The run's joint law (JSON text), None for the target's joints; records written before
    the laws have no such key."""
    return record["spec"].get("joint_law")


def relative_error_percent(angle: float | None, experiment: float) -> float | None:
    """100 (angle - experiment) / experiment, None without an angle."""
    return None if angle is None else 100 * (angle - experiment) / experiment


@dataclass(frozen=True)
class LawEvaluation:
    """One evaluation of a joint law: its ``law`` (RunSpec.joint_law), ``kn`` and ``ks`` (Pa/m),
    and its adaptive tilting runs by wall, ok or failed."""

    law: str
    kn: float
    ks: float
    runs: Mapping[str, dict]

    def error(self, experiment: Mapping[str, float]) -> float | None:
        """The calibration's objective (:func:`calibration_error`: the mean absolute relative
        error of the collapse angles, a wall that cannot stand at 0 deg) over the walls of
        ``experiment``; None unless the evaluation is complete: every one of those walls run,
        no run failed, each with a verdict."""
        if any(r["status"] != "ok" for r in self.runs.values()) or not set(experiment) <= set(self.runs):
            return None
        try:
            return calibration_error({d: self.runs[d] for d in experiment}, experiment)
        except CalibrationError:  # a wall without a verdict
            return None

    def angle(self, design: str) -> float | None:
        """The wall's collapse angle as the objective counts it (:func:`wall_angle`), None if not run."""
        run = self.runs.get(design)
        return None if run is None or run["status"] != "ok" else wall_angle(run["summary"])


def law_evaluations(records: Iterable[dict]) -> list[LawEvaluation]:
    """The adaptive tilting runs with a joint law among ``records`` (ok and failed), grouped by
    (joint_law, kn, ks); the finest increment where a wall was run twice."""
    groups: dict[tuple, dict[str, dict]] = {}
    runs = [r for r in records if joint_law(r) is not None and r["spec"]["analysis"] == "tilt" and r["spec"]["protocol"] == "adaptive"]
    for r in sorted(runs, key=lambda r: -(r["spec"]["increment_deg"] or 0.0)):
        groups.setdefault((joint_law(r), r["spec"]["kn"], r["spec"]["ks"]), {})[wall_of(r)] = r
    return [LawEvaluation(law, kn, ks, walls) for (law, kn, ks), walls in groups.items()]


def calibrated(evaluations: Iterable[LawEvaluation], experiment: Mapping[str, float]) -> LawEvaluation | None:
    """The complete evaluation (:meth:`LawEvaluation.error`) with the smallest error, None if none is."""
    scored = [(e.error(experiment), e) for e in evaluations]
    scored = [(error, e) for error, e in scored if error is not None]
    return min(scored, key=lambda pair: pair[0])[1] if scored else None


def law_words(law: str, kn: float, ks: float) -> str:
    """The joint law in words (:attr:`JointMaterial.stiffness_text`: kn and ks, the law and its
    clamps), or as recorded for a law this drydem does not read."""
    try:
        return JointMaterial(kn=kn, ks=ks, **json.loads(law)).stiffness_text
    except (ValueError, TypeError, ModelError):
        return f"joint law {law} at kn = {kn:.3g}, ks = {ks:.3g} Pa/m"


def _angle_cell(angles: Mapping[str, float | None], design: str, experiment: float) -> str:
    """The wall's angle in ``angles`` and its relative error against the experiment; "not run"
    for a wall not in ``angles``, "no verdict" for one whose run found no angle (None)."""
    if design not in angles:
        return "not run"
    angle = angles[design]
    return "no verdict" if angle is None else f"{angle:.1f} ({relative_error_percent(angle, experiment):+.1f} %)"


def law_table(best: LawEvaluation, constant: Mapping[str, float | None],
              experiment: Mapping[str, float] | None = None) -> tuple[list[str], list[list[str]]]:
    """The header and rows of the law table: per wall, the experimental collapse angle (Savalle
    et al. 2022, Table 1, :func:`experimental_angles`), the angle at constant kn = ks = 3e7
    (``constant``, by wall: the walls run, None for no verdict) and the calibrated law's
    (``best``), each with its relative error; last, the mean absolute relative error of both
    (the constant one over the walls with an angle, said when not all)."""
    experiment = experimental_angles() if experiment is None else experiment
    law = {d: best.angle(d) for d in experiment}
    rows = [[d, f"{experiment[d]:.1f}", _angle_cell(constant, d, experiment[d]), _angle_cell(law, d, experiment[d])]
            for d in sorted(experiment)]
    ran = {d: constant[d] for d in experiment if constant.get(d) is not None}
    if not ran:
        mean = "no verdict" if constant else "not run"
    else:
        mean = f"{100 * mean_absolute_relative_error(ran, experiment):.1f} %"
        mean += "" if len(ran) == len(experiment) else f" ({len(ran)} of {len(experiment)} walls)"
    rows.append(["mean absolute relative error", "", mean, f"{100 * best.error(experiment):.1f} %"])
    return ["wall", "experiment (deg)", "constant kn = ks = 3e7 (deg, error)", "calibrated law (deg, error)"], rows


def law_caption(evaluations: list[LawEvaluation], best: LawEvaluation | None, experiment: Mapping[str, float]) -> str:
    """What the law table shows: the calibrated law in words, and how many law evaluations the
    folder holds (and how many of them are complete)."""
    complete = sum(e.error(experiment) is not None for e in evaluations)
    laws = len({e.law for e in evaluations})
    count = (f"{len(evaluations)} law evaluations (one law at one kn, ks, adaptive tilting runs) in the folder, of {laws} "
             f"law{'s' if laws != 1 else ''}; {complete} complete (all of {', '.join(sorted(experiment))} run, none failed, each "
             f"with a verdict)")
    if best is None:
        return f"{count}: no calibrated law yet."
    return (f"Calibrated law: {law_words(best.law, best.kn, best.ks)}; the complete evaluation with the smallest mean absolute "
            f"relative error of the collapse angles (`drydem calibrate`'s objective; a wall that cannot stand counts as 0 deg). "
            f"{count}.")
