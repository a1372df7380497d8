"""Calibration of the joint stiffness (the seed paper's post-diction, Section 4.4, automated):
the kn (ks = kn, or a fixed ratio) that minimises the mean absolute relative error between
computed and experimental collapse angles over a set of walls.

The search is over log10 kn: a coarse log-spaced grid, then golden-section refinement around
its best point (Kiefer 1953), every evaluation memoised so that finished runs are reused. The
error against kn need not be unimodal over the whole range (the grid is there for that); inside
the bracket it is assumed to be.

:func:`calibrate_stiffness` is ``drydem calibrate``: a :class:`StiffnessSearch` (its settings all
checked before anything runs) evaluated by sweeping each kn's tilting runs into a results folder,
whose records it reuses. Its objective, for one kn, is :func:`calibration_error` of those runs'
records: a wall that cannot stand under its own weight counts as 0 deg (:func:`wall_angle`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from concurrent.futures import Executor
from dataclasses import dataclass
from pathlib import Path
from types import SimpleNamespace

from drydem.errors import DrydemError, ModelError
from drydem.model.parameters import JOINT_STIFFNESS, JointMaterial, Range, field_problems, refuse
from drydem.parametric.records import RecordError, read_record, record_path
from drydem.parametric.study import RunSpec, joint_law_text
from drydem.parametric.sweep import SweepOutcome, sweep

GOLDEN = (math.sqrt(5) - 1) / 2
#: ks / kn: any positive ratio (the stiffnesses it gives are checked against JOINT_STIFFNESS)
KS_RATIO = Range(0.0, None, low_open=True)
#: the ends of the kn searched (Pa/m), each a joint stiffness (and kn_min < kn_max)
BOUND_RULES = {"kn_min": JOINT_STIFFNESS, "kn_max": JOINT_STIFFNESS}
#: the rule of each setting of :func:`calibrate`'s search: a grid has at least its two ends, and
#: 1000 points (evaluations) is far more than a curve needs; the tolerance is in log10 kn, where
#: 1 (a factor of 10) would end the refinement at once
SEARCH_RULES = {"grid": Range(2, 1000, integer=True), "tolerance": Range(0.0, 1.0, low_open=True, high_open=True),
                "max_evaluations": Range(1, None, integer=True)}


class CalibrationError(DrydemError):
    """A calibration that cannot go on: its runs failed, or another process is computing them."""


@dataclass(frozen=True)
class Calibration:
    """best_kn (Pa/m) and its error; curve: every (kn, error) evaluated, sorted by kn."""

    best_kn: float
    best_error: float
    curve: list[tuple[float, float]]


def calibrate(error: Callable[[float], float], kn_min: float, kn_max: float, *, grid: int = 5,
              tolerance: float = 0.01, max_evaluations: int = 30) -> Calibration:
    """Minimise ``error(kn)`` over [kn_min, kn_max] (Pa/m) to within ``tolerance`` in log10 kn;
    ModelError naming every setting out of its range (:data:`BOUND_RULES`, :data:`SEARCH_RULES`)."""
    def name(field: str) -> str:
        return f"calibrate {field}"

    search = SimpleNamespace(kn_min=kn_min, kn_max=kn_max, grid=grid, tolerance=tolerance, max_evaluations=max_evaluations)
    refuse(_bound_problems(search, name) + field_problems(search, SEARCH_RULES, name))
    seen: dict[float, float] = {}

    def f(log_kn: float) -> float:
        key = round(log_kn, 9)
        if key not in seen:
            seen[key] = float(error(10.0**key))
        return seen[key]

    lo, hi = math.log10(kn_min), math.log10(kn_max)
    points = [lo + (hi - lo) * k / (grid - 1) for k in range(grid)]
    best = min(points, key=f)
    k = points.index(best)
    a, b = points[max(k - 1, 0)], points[min(k + 1, grid - 1)]
    c, d = b - GOLDEN * (b - a), a + GOLDEN * (b - a)
    while b - a > tolerance and len(seen) < max_evaluations:
        if f(c) <= f(d):
            b, d = d, c
            c = b - GOLDEN * (b - a)
        else:
            a, c = c, d
            d = a + GOLDEN * (b - a)
    log_best = min(seen, key=seen.get)
    curve = sorted((10.0**x, e) for x, e in seen.items())
    return Calibration(10.0**log_best, seen[log_best], curve)


def _bound_problems(search, name: Callable[[str], str]) -> list[str]:
    """Why ``search``'s kn_min and kn_max (each named by ``name(field)``) are not the ends of a
    range of joint stiffnesses: out of :data:`BOUND_RULES`, or not kn_min < kn_max."""
    found = field_problems(search, BOUND_RULES, name)
    if not found and not search.kn_min < search.kn_max:
        found.append(f"{name('kn_min')} = {search.kn_min!r}, {name('kn_max')} = {search.kn_max!r}: need {name('kn_min')} < {name('kn_max')}")
    return found


def mean_absolute_relative_error(computed: dict[str, float], experiment: dict[str, float]) -> float:
    """Mean of |computed - experiment| / experiment over the walls in ``computed`` (paper Table 3)."""
    return sum(abs(computed[d] - experiment[d]) / experiment[d] for d in computed) / len(computed)


def experimental_angles() -> dict[str, float]:
    """The experimental collapse angles (deg) of the seed paper's walls (its Table 1)."""
    from drydem.masonry.published import savalle2022

    return savalle2022()["table1_experiment"]["collapse_angle_deg"]


def wall_angle(summary: dict) -> float | None:
    """The collapse angle a tilting run's ``summary`` gives the objective (deg): a wall that
    cannot stand under its own weight has no capacity, 0 deg (the paper's WD4, 6, 7 at kn = 1e7),
    rather than no value, which would leave it out of the mean and flatter that kn. None when the
    run found no angle to compare: no equilibrium under gravity within max_cycles (no verdict on
    stability), or no collapse up to the largest tilt tried."""
    if summary.get("stable_under_gravity") is False:
        return 0.0
    return summary["collapse_angle_deg"]


def calibration_error(records: Mapping[str, dict], experiment: Mapping[str, float] | None = None) -> float:
    """The objective that :func:`calibrate_stiffness` minimises, for one kn: the mean absolute
    relative error (:func:`mean_absolute_relative_error`) of the walls' collapse angles against
    ``experiment`` (deg; default :func:`experimental_angles`), from ``records``, each wall's
    tilting run record at that kn (:func:`drydem.parametric.records.read_record`). A wall that
    cannot stand under its own weight counts as 0 deg (:func:`wall_angle`). CalibrationError
    naming every wall whose run failed or found no angle to compare (no verdict)."""
    experiment = experimental_angles() if experiment is None else experiment
    unusable = [f"{d}: {r['error']}" for d, r in records.items() if r["status"] == "failed"]
    angles = {d: wall_angle(r["summary"]) for d, r in records.items() if r["status"] != "failed"}
    unusable += [f"{d}: {records[d]['summary']['ended_by']}" for d, angle in angles.items() if angle is None]
    if unusable:
        raise CalibrationError("runs without a collapse angle:\n  " + "\n  ".join(unusable))
    return mean_absolute_relative_error(angles, experiment)


@dataclass(frozen=True)
class StiffnessSearch:
    """What ``drydem calibrate`` fits: the kn (Pa/m) in [kn_min, kn_max] that best reproduces the
    experimental collapse angles of ``designs``, with ks = ks_ratio x kn, from adaptive tilting
    runs down to steps of ``increment`` deg (the field names are the command's options).

    ``joint_law``: a stress-dependent law (``[joint]`` keys: model and its parameters, e.g.
    ``{"model": "power", "kn_exponent": 1.0, "stress_ref": 1000.0}``) whose kn and ks are then
    the ones fitted: the law's shape given, its level calibrated; None: the walls' own joints."""

    designs: tuple[str, ...]
    kn_min: float = 1e7
    kn_max: float = 1e9
    ks_ratio: float = 1.0
    increment: float = 0.1
    joint_law: dict | None = None

    def problems(self, name: Callable[[str], str] = str) -> list[str]:
        """Every invalid setting and the rule it breaks, each named by ``name(field)``: walls with
        an experimental angle; kn_min and kn_max joint stiffnesses with kn_min < kn_max; ks =
        ks_ratio x kn a joint stiffness at both ends; the increment a tilt step (TiltSettings')."""
        from drydem.analysis.tilt import SETTING_RANGES

        found = []
        known = experimental_angles()
        unknown = [d for d in self.designs if d not in known]
        if not self.designs or unknown:
            what = f"no experimental collapse angle for {unknown}" if unknown else "needs at least one wall"
            found.append(f"{name('designs')} {','.join(self.designs)!r}: {what}; known: {', '.join(sorted(known))}")
        bounds = _bound_problems(self, name)
        found += bounds + field_problems(self, {"ks_ratio": KS_RATIO, "increment": SETTING_RANGES["increment_deg"]}, name)
        ks = (self.ks_ratio * self.kn_min, self.ks_ratio * self.kn_max)
        if not bounds and self.ks_ratio in KS_RATIO and not all(k in JOINT_STIFFNESS for k in ks):
            found.append(f"{name('ks_ratio')} = {self.ks_ratio!r}: ks = ratio x kn, {ks[0]:.3g} to {ks[1]:.3g} Pa/m, {JOINT_STIFFNESS}")
        elif not bounds and self.joint_law:
            found += _law_problems(self.joint_law, (self.kn_min, self.kn_max), self.ks_ratio)
        return found

    def runs(self, kn: float) -> list[RunSpec]:
        """The runs that evaluate ``kn``, one per design."""
        return [RunSpec(analysis="tilt", target=d, protocol="adaptive", kn=kn, ks=self.ks_ratio * kn, increment_deg=self.increment,
                        joint_law=joint_law_text(self.joint_law)) for d in self.designs]


def _law_problems(law: dict, kn_range: tuple[float, float], ks_ratio: float) -> list[str]:
    """Why the joint ``law`` cannot take the kn at either end of ``kn_range`` (ks = ks_ratio x kn)."""
    found = []
    for kn in kn_range:
        try:
            JointMaterial(kn=kn, ks=ks_ratio * kn, **law)
        except (ModelError, TypeError) as exc:
            found.append(f"joint law {law} at kn = {kn:.4g} Pa/m: {exc}")
    return sorted(set(found), key=found.index)


def calibrate_stiffness(search: StiffnessSearch, results: Path, executor: Executor, *, in_flight: int | None = None,
                        on_evaluation: Callable[[float, float, SweepOutcome], None] | None = None) -> Calibration:
    """:func:`calibrate` ``search`` on ``executor``: each kn's runs swept into ``results``
    (reusing those recorded, running again the corrupt ones), the objective
    :func:`calibration_error` against the experiments. ``on_evaluation(kn, error, outcome)``
    after each kn. ModelError for invalid settings (all named), CalibrationError when a kn's
    runs failed or are being computed by another process."""
    refuse(search.problems())
    experiment = experimental_angles()

    def error(kn: float) -> float:
        specs = search.runs(kn)
        outcome = sweep(specs, results, executor, in_flight=in_flight)
        if outcome.elsewhere:
            raise CalibrationError(f"kn = {kn:.4g}: {outcome.elsewhere} of its runs are being computed by another drydem process "
                                   f"on {results} (their claims: {Path(results) / 'runs'}/*.lock); run calibrate again when it has finished")
        records, unreadable = {}, []
        for design, spec in zip(search.designs, specs):
            try:
                records[design] = read_record(record_path(results, spec.id))
            except RecordError as exc:
                unreadable.append(str(exc))
        if unreadable:
            raise CalibrationError(f"kn = {kn:.4g}: run records that cannot be read:\n  " + "\n  ".join(unreadable))
        try:
            value = calibration_error(records, experiment)
        except CalibrationError as exc:
            raise CalibrationError(f"kn = {kn:.4g}: {exc}") from None
        if on_evaluation is not None:
            on_evaluation(kn, value, outcome)
        return value

    return calibrate(error, search.kn_min, search.kn_max)
