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

The objective is noisy: a collapse angle is found to the tilt step only, so the error is a
staircase in kn, and round-off may send a run through its soft contacts along another path,
so the error may jump between kn that physics cannot tell apart; the search may end on any kn
whose error is within that noise of the least. :attr:`StiffnessCalibration.noise` gives the
larger of the two, where it matters, at the best kn: the step one tilt step on one wall makes,
and the spread of the error over the kn within 2 % of the best (:data:`NEIGHBOURHOOD`), where
the error's smooth part is flat: the search's last evaluations, which cost nothing, and two
probes, the best kn's walls run again at kn x (1 -+ 0.1 %) (:data:`NOISE_STEP`, two more kn
where the search took up to 30), so that there are always three. No model of the error curve
is needed, as a fit through the scatter farther out would need one to part the curve's slope
from its noise. Measured on the seven walls (2026-11-25, adaptive, 0.1 deg): 1.4 points of the
mean absolute relative error over the six kn within 2 % of the best (4.28e7 Pa/m), WD1's angle
19.5 deg there and 21.2 deg at 0.7 % more kn, though the two probes alone moved no angle; one
tilt step on one wall is 0.18 points.

The calibration, :class:`StiffnessCalibration`, is written to a file (``drydem calibrate``:
``RESULTS/calibration.json``, :func:`calibration_content`) after each kn, whole or not at
all, and finished at the end; an interrupted calibration goes on from its runs, and a finished
one, or one with other settings, is not replaced unless asked (:func:`check_calibration_file`).
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable, Mapping, Sequence
from concurrent.futures import Executor
from dataclasses import asdict, dataclass
from pathlib import Path
from types import SimpleNamespace

from drydem import __version__
from drydem.errors import DrydemError, ModelError
from drydem.files import replaced_atomically, writable
from drydem.io.results import records_folder
from drydem.model.parameters import JOINT_STIFFNESS, JointMaterial, Range, field_problems, refuse
from drydem.parametric.records import RecordError, read_json, read_record, record_path
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


def calibration_angles(records: Mapping[str, dict]) -> dict[str, float]:
    """Each wall's collapse angle (deg) as the objective counts it (:func:`wall_angle`: 0 deg
    for a wall that cannot stand under its own weight), from ``records``, each wall's tilting
    run record (:func:`drydem.parametric.records.read_record`). CalibrationError naming every
    wall whose run failed or found no angle to compare (no verdict)."""
    unusable = [f"{d}: {r['error']}" for d, r in records.items() if r["status"] == "failed"]
    angles = {d: wall_angle(r["summary"]) for d, r in records.items() if r["status"] != "failed"}
    unusable += [f"{d}: {records[d]['summary']['ended_by']}" for d, angle in angles.items() if angle is None]
    if unusable:
        raise CalibrationError("runs without a collapse angle:\n  " + "\n  ".join(unusable))
    return angles


def calibration_error(records: Mapping[str, dict], experiment: Mapping[str, float] | None = None) -> float:
    """The objective that :func:`calibrate_stiffness` minimises, for one kn: the mean absolute
    relative error (:func:`mean_absolute_relative_error`) of the walls' collapse angles
    (:func:`calibration_angles` of ``records``, each wall's tilting run record at that kn)
    against ``experiment`` (deg; default :func:`experimental_angles`)."""
    experiment = experimental_angles() if experiment is None else experiment
    return mean_absolute_relative_error(calibration_angles(records), experiment)


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

        found = _design_problems(self.designs, name)
        bounds = _bound_problems(self, name)
        found += bounds + field_problems(self, {"ks_ratio": KS_RATIO, "increment": SETTING_RANGES["increment_deg"]}, name)
        ks = (self.ks_ratio * self.kn_min, self.ks_ratio * self.kn_max)
        if not bounds and self.ks_ratio in KS_RATIO and not all(k in JOINT_STIFFNESS for k in ks):
            found.append(f"{name('ks_ratio')} = {self.ks_ratio!r}: ks = ratio x kn, {ks[0]:.3g} to {ks[1]:.3g} Pa/m, {JOINT_STIFFNESS}")
        elif not bounds and self.joint_law:
            found += _law_problems(self.joint_law, (self.kn_min, self.kn_max), self.ks_ratio)
        return found

    def settings(self) -> dict:
        """The search as JSON values, and the noise probes' step: the calibration file's
        ``settings`` (a calibration goes on from an unfinished file only with the same)."""
        return json.loads(json.dumps(asdict(self) | {"noise_step": NOISE_STEP}))

    def runs(self, kn: float) -> list[RunSpec]:
        """The runs that evaluate ``kn``, one per design."""
        return [RunSpec(analysis="tilt", target=d, protocol="adaptive", kn=kn, ks=self.ks_ratio * kn, increment_deg=self.increment,
                        joint_law=joint_law_text(self.joint_law)) for d in self.designs]


def _design_problems(designs: tuple[str, ...], name: Callable[[str], str]) -> list[str]:
    """Why ``designs`` cannot be fitted: none, an empty name (two commas in a row, or one at an
    end), a wall without an experimental angle, or one given twice (its error would count twice
    in the mean that is minimised)."""
    known = experimental_angles()
    given, listed = f"{name('designs')} {','.join(designs)!r}", f"known: {', '.join(sorted(known))}"
    if not designs or "" in designs:
        what = "an empty name (two commas in a row, or one at an end)" if designs else "needs at least one wall"
        return [f"{given}: {what}; {listed}"]
    unknown = [d for d in designs if d not in known]
    twice = list(dict.fromkeys(d for d in designs if designs.count(d) > 1))
    found = [f"{given}: no experimental collapse angle for {', '.join(unknown)}; {listed}"] if unknown else []
    return found + ([f"{given}: {', '.join(twice)} given more than once; give each wall once (its error would count twice in "
                     "the mean)"] if twice else [])


def _law_problems(law: dict, kn_range: tuple[float, float], ks_ratio: float) -> list[str]:
    """Why the joint ``law`` cannot take the kn at either end of ``kn_range`` (ks = ks_ratio x kn),
    each reason once: with the kn it holds at, unless it holds at both (a key the law lacks)."""
    found: dict[str, list[float]] = {}
    for kn in kn_range:
        try:
            JointMaterial(kn=kn, ks=ks_ratio * kn, **law)
        except (ModelError, TypeError) as exc:
            found.setdefault(str(exc), []).append(kn)
    words = ", ".join(f"{key} = {value}" for key, value in law.items())  # found by a hunt: shown as a dict
    return [f"joint law {words}{'' if len(kns) == len(kn_range) else f' at kn = {kns[0]:.4g} Pa/m'}: {reason}"
            for reason, kns in found.items()]


@dataclass(frozen=True)
class Evaluation:
    """One kn evaluated: kn and ks (Pa/m), the objective ``error`` (:func:`calibration_error`, a
    fraction), and by wall its collapse angle as the objective counts it (``angles_deg``) and its
    run's id (``runs``: the record ``RESULTS/runs/ID.json``)."""

    kn: float
    ks: float
    error: float
    angles_deg: dict[str, float]
    runs: dict[str, str]


@dataclass(frozen=True)
class StiffnessCalibration:
    """What :func:`calibrate_stiffness` found for ``search``: its ``evaluations`` (sorted by
    kn), the ``best`` of them, and the ``probes`` of the objective's noise (:attr:`noise`),
    which take no part in the search."""

    search: StiffnessSearch
    evaluations: tuple[Evaluation, ...]
    best: Evaluation
    probes: tuple[Evaluation, ...]

    @property
    def best_kn(self) -> float:
        return self.best.kn

    @property
    def best_error(self) -> float:
        return self.best.error

    @property
    def noise(self) -> dict:
        """How noisy the objective is at the best kn, in its units (a fraction): ``error``, the
        larger of two measures, differences of the error below which are not meaningful.

        ``spread``: the range (max - min) of the objective over ``kn``: the evaluations within
        a factor NEIGHBOURHOOD of the best kn (the search's last ones, free) and the probes, its
        walls run again at kn x (1 -+ NOISE_STEP) (:func:`probe_stiffnesses`, two more kn that
        make the measure whatever the search's last steps were). Over so small a change of kn
        the error's smooth part moves by far less than the tilt step's (at its minimum it is
        flat to first order), so what moves is the solution's own noise: round-off taking
        another path through a soft contact. A range of a few values: an order of magnitude,
        not a bound. ``angles_deg``: that range of each wall's collapse angle (deg; it holds the
        wall's own trend over those kn too, a step or two), ``largest_deg`` the largest, of ``wall``.

        ``step``: the objective's change when one wall's angle moves by one tilt step (the
        increment: an adaptive run finds the collapse angle to it), increment / (walls x
        experimental angle), for the wall where it is largest (``step_wall``): the objective is a
        staircase of such steps, whatever the round-off."""
        near = [e for e in self.evaluations if max(e.kn / self.best.kn, self.best.kn / e.kn) <= NEIGHBOURHOOD]
        group = sorted({e.kn: e for e in (*near, *self.probes)}.values(), key=lambda e: e.kn)
        angles = {d: max(e.angles_deg[d] for e in group) - min(e.angles_deg[d] for e in group) for d in self.search.designs}
        wall = max(angles, key=angles.get)
        experiment = experimental_angles()
        steps = {d: self.search.increment / (len(self.search.designs) * experiment[d]) for d in self.search.designs}
        step_wall = max(steps, key=steps.get)
        spread = max(e.error for e in group) - min(e.error for e in group)
        return {"error": max(spread, steps[step_wall]), "spread": spread, "step": steps[step_wall], "step_wall": step_wall,
                "angles_deg": angles, "largest_deg": angles[wall], "wall": wall, "kn": [e.kn for e in group], "how": NOISE_METHOD}

    def to_dataframe(self):
        """The evaluations and then the probes as a pandas DataFrame (:func:`drydem.analysis.dataframes.data_frame`), one
        row each: ``kn_Pa_m``, ``ks_Pa_m``, ``error`` (the objective, a fraction), ``probe`` (True for a noise
        probe), and each wall's ``angle_WALL_deg``; ``attrs``: ``best_kn_Pa_m``, ``best_error``, ``noise``, ``settings``."""
        from drydem.analysis.dataframes import data_frame

        rows = [(e, False) for e in self.evaluations] + [(e, True) for e in self.probes]
        columns = {"kn_Pa_m": [e.kn for e, _ in rows], "ks_Pa_m": [e.ks for e, _ in rows], "error": [e.error for e, _ in rows],
                   "probe": [probe for _, probe in rows]}
        columns |= {f"angle_{d}_deg": [e.angles_deg[d] for e, _ in rows] for d in self.search.designs}
        return data_frame(columns, {"best_kn_Pa_m": self.best_kn, "best_error": self.best_error, "noise": self.noise,
                                    "settings": self.search.settings()})


#: the relative change of kn at which :attr:`StiffnessCalibration.noise` probes the objective:
#: log10(1.001) = 4.3e-4 in log10 kn, a twentieth of the search's tolerance (0.01)
NOISE_STEP = 1e-3
#: the evaluations :attr:`StiffnessCalibration.noise` counts besides its probes: those within
#: this factor of the best kn (2 %: about the search's tolerance, 0.01 in log10 kn = 2.3 %)
NEIGHBOURHOOD = 1.02
#: how :attr:`StiffnessCalibration.noise` is measured, in words (written with it)
NOISE_METHOD = (f"the larger of the objective's range (max - min) over the kn evaluated within {NEIGHBOURHOOD - 1:.0%} of the best "
                f"and two probes (kn x (1 -+ {NOISE_STEP:g}); at a bound of the range, both inside it), and its step when one "
                "wall's collapse angle moves by one tilt step (increment / (walls x experimental angle)), the largest over the walls")
#: the calibration's file in its results folder (``drydem calibrate``'s default ``--out``)
CALIBRATION_FILE = "calibration.json"


def probe_stiffnesses(kn: float, kn_min: float, kn_max: float) -> tuple[float, float]:
    """The kn (Pa/m) of the noise probes of ``kn``: kn x (1 - NOISE_STEP) and kn x (1 +
    NOISE_STEP), or at a bound of [kn_min, kn_max] the two inside it (kn x (1 + 1 and 2 x
    NOISE_STEP), or minus), so that every run is one of the range searched."""
    inside = [pair for pair in ((-1, 1), (1, 2), (-1, -2))
              if kn_min <= kn * (1 + min(pair) * NOISE_STEP) and kn * (1 + max(pair) * NOISE_STEP) <= kn_max]
    low, high = (inside or [(-1, 1)])[0]
    return kn * (1 + low * NOISE_STEP), kn * (1 + high * NOISE_STEP)


def calibration_content(search: StiffnessSearch, evaluations: Sequence[Evaluation], result: StiffnessCalibration | None = None) -> dict:
    """What the calibration file holds: ``finished`` (False until the ``result`` is given: a
    calibration of the same ``settings`` goes on from it), the ``settings``
    (:meth:`StiffnessSearch.settings`), the ``best`` evaluation and the ``noise``
    (:attr:`StiffnessCalibration.noise`; both None until finished), the ``evaluations`` (kn, ks
    in Pa/m, error a fraction, angles in deg, run ids), the noise ``probes``."""
    return {"finished": result is not None, "settings": search.settings(),
            "best": None if result is None else asdict(result.best), "noise": None if result is None else result.noise,
            "evaluations": [asdict(e) for e in evaluations], "probes": [] if result is None else [asdict(e) for e in result.probes],
            "drydem_version": __version__}


def check_calibration_file(path: Path, search: StiffnessSearch, *, overwrite: bool = False) -> None:
    """DrydemError unless a calibration of ``search`` may write ``path``: there is no such file,
    or it is an unfinished calibration with the same settings (it goes on: its runs are in the
    results folder, and its evaluations are made again from them), or ``overwrite`` is asked.
    Nothing is lost otherwise."""
    if overwrite or not Path(path).exists():
        return
    try:
        recorded = read_json(Path(path), "calibration")
        finished, settings, evaluations = recorded["finished"], recorded["settings"], recorded["evaluations"]
    except (RecordError, TypeError, KeyError):
        finished = settings = evaluations = None
    if not (isinstance(finished, bool) and isinstance(settings, dict) and isinstance(evaluations, list)
            and all(isinstance(e, dict) for e in evaluations)):  # found by a hunt: "evaluations": "lots" was taken
        raise DrydemError(f"{path}: exists and is not a drydem calibration; pass --overwrite to replace it, or another --out")
    if finished or settings != search.settings():
        differ = sorted(key for key in settings.keys() | search.settings().keys() if settings.get(key) != search.settings().get(key))
        what = "a finished calibration" if finished and not differ else f"a calibration with other settings ({', '.join(differ)})"
        raise DrydemError(f"{path}: already holds {what}; pass --overwrite to replace it, or another --out")


def write_calibration(path: Path, content: dict) -> Path:
    """``content`` (:func:`calibration_content`) as JSON in ``path``, whole or not at all."""
    with replaced_atomically(path) as partial:
        partial.write_text(json.dumps(content, indent=1) + "\n", encoding="utf-8")
    return path


def calibrate_stiffness(search: StiffnessSearch, results: Path, executor: Executor, *, out: Path | None = None, overwrite: bool = False,
                        in_flight: int | None = None,
                        on_evaluation: Callable[[float, float, SweepOutcome], None] | None = None) -> StiffnessCalibration:
    """:func:`calibrate` ``search`` on ``executor``: each kn's runs swept into ``results``
    (reusing those recorded, running again the corrupt ones), the objective
    :func:`calibration_error` against the experiments; then the noise probes
    (:attr:`StiffnessCalibration.noise`). With ``out``, the calibration is written there
    (:func:`calibration_content`) after each kn and at the end, once :func:`check_calibration_file`
    allows it. ``on_evaluation(kn, error, outcome)`` after each kn, probes included. ModelError
    for invalid settings (all named), CalibrationError when a kn's runs failed or are being
    computed by another process, DrydemError for an ``out`` that cannot or may not be written."""
    refuse(search.problems())
    experiment = experimental_angles()
    records_folder(results, "calibrate")
    if out is not None:
        check_calibration_file(writable(out), search, overwrite=overwrite)
    found: dict[float, Evaluation] = {}

    def evaluate(kn: float) -> Evaluation:
        evaluation, outcome = evaluated(search, kn, results, executor, experiment, in_flight=in_flight)
        if on_evaluation is not None:
            on_evaluation(kn, evaluation.error, outcome)
        return evaluation

    def searched() -> tuple[Evaluation, ...]:
        return tuple(sorted(found.values(), key=lambda e: e.kn))

    def error(kn: float) -> float:
        found[kn] = evaluate(kn)
        if out is not None:
            write_calibration(out, calibration_content(search, searched()))
        return found[kn].error

    best = found[calibrate(error, search.kn_min, search.kn_max).best_kn]
    probes = tuple(evaluate(kn) for kn in probe_stiffnesses(best.kn, search.kn_min, search.kn_max))
    result = StiffnessCalibration(search, searched(), best, probes)
    if out is not None:
        write_calibration(out, calibration_content(search, result.evaluations, result))
    return result


def evaluated(search: StiffnessSearch, kn: float, results: Path, executor: Executor, experiment: Mapping[str, float], *,
              in_flight: int | None = None) -> tuple[Evaluation, SweepOutcome]:
    """The objective at ``kn``: its walls' runs swept into ``results`` on ``executor`` (those
    recorded reused), their collapse angles against ``experiment`` (deg); and the sweep's
    outcome. CalibrationError when runs are being computed by another process, cannot be read
    or found no angle."""
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
        angles = calibration_angles(records)
    except CalibrationError as exc:
        raise CalibrationError(f"kn = {kn:.4g}: {exc}") from None
    evaluation = Evaluation(kn, search.ks_ratio * kn, mean_absolute_relative_error(angles, experiment), angles,
                            {d: spec.id for d, spec in zip(search.designs, specs)})
    return evaluation, outcome
