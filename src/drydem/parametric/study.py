"""A parametric study: its file, checked whole when it is loaded, and the runs it makes.

A study file is TOML; each ``[[grid]]`` is a cartesian product, the study is their union::

    [study]
    name = "savalle2022"
    description = "..."
    [defaults]                  # optional, for every grid
    friction = 0.5
    points = 4                  # sub-contacts per length
    increment_deg = 0.1
    [[grid]]
    name = "stiffness"          # a label (a run several grids share is run once)
    analysis = "tilt"           # or "limit"
    targets = ["WD1", "WD2"]    # built-in walls, or files relative to the study file
    kn = [1e7, 3e7, 1e9]        # Pa/m
    ks = "kn"                   # ks = kn (default), or a list of values
    protocol = ["adaptive"]     # tilt: fixed, adaptive; limit: associative, non-associative
    [[grid]]
    name = "ida"                # incremental dynamic analysis: every motion at every scale
    analysis = "shake"
    targets = ["WD1"]
    motions = ["records/a.csv", "records/b.AT2", "pulse:one-sine:2.0"]
    scales = [0.5, 1.0, 1.5]    # factors on each motion (> 0)
    duration_s = 3.0            # optional: analysed time, s (default: each motion's)
    restitution = "housner"     # optional: Housner's, or a number in (0, 1], the contacts'
    # contact_damping_ratio = 0.3  # damping calibrated to it; or their damping ratio set
    #                           # directly; neither: ShakeSettings' default
    # monitor = "block"         # optional: the block whose response is recorded
    kn = [1e9]                  # optional overrides, as for tilt (ks, friction, points too)

A shake grid's motions are files relative to the study file (CSV or PEER .AT2, along x,
:func:`drydem.analysis.shake.read_motion`), baseline-corrected before they are scaled, or
analytic pulses ``pulse:KIND:FREQUENCY_HZ`` (``pulse:sine:FREQUENCY_HZ:CYCLES``) of amplitude
1 m/s2, so that the scale is the amplitude (:func:`drydem.analysis.shake.pulse`, not
corrected). Its runs are the product of targets, motions, scales and overrides (no protocol,
no increment). ``[defaults]`` may also give duration_s, restitution or contact_damping_ratio
(a grid's own restitution or ratio replaces the default of the other).

``[study]``'s name names the default results folder (results/NAME): a plain file name, neither
a path nor "." or "..". A study makes at most :data:`~drydem.parametric.limits.MAX_RUNS` runs,
all grids together (that module says why); a grid larger than that is refused before it is
expanded.

A study is checked whole when it is loaded: every target is loaded and every run's overrides
applied to it (the parameter classes check the values), and every shake run's motion read and its
settings built, so that a bad value anywhere stops the study before its first run, with every
problem named, rather than hours later as a failed run.

Every run has an id made of its parameters (and a hash of them): the name of its record
(:mod:`drydem.parametric.records`).
"""

from __future__ import annotations

import hashlib
import itertools
import json
import math
import re
from dataclasses import asdict, dataclass, replace
from pathlib import Path

from drydem.errors import DrydemError, ModelError
from drydem.files import PLAIN_NUMBER, plain_name_problem, read_toml
from drydem.model.assembly import Model
from drydem.model.parameters import JOINT_RULES, POINTS, is_number
from drydem.model.tables import no_unknown
from drydem.parametric.limits import MAX_RUNS

#: the analyses of a study and their protocols (a shake run has one: the time history)
ANALYSES = {"tilt": ("fixed", "adaptive"), "limit": ("associative", "non-associative"), "shake": ("time-history",)}
DEFAULT_PROTOCOL = {"tilt": "adaptive", "limit": "associative", "shake": "time-history"}
#: the keys of a grid, by analysis
COMMON_KEYS = {"name", "analysis", "targets", "kn", "ks", "friction", "points"}
SHAKE_KEYS = {"motions", "scales", "duration_s", "restitution", "contact_damping_ratio", "monitor"}
GRID_KEYS = {"tilt": COMMON_KEYS | {"protocol", "increment_deg"}, "limit": COMMON_KEYS | {"protocol", "increment_deg"},
             "shake": COMMON_KEYS | SHAKE_KEYS}
DEFAULT_KEYS = {"friction", "points", "increment_deg", "duration_s", "restitution", "contact_damping_ratio"}
#: the most characters of a target's or motion's name a run id shows (the hash tells runs apart):
#: the id names the run's record and lock files, and a 240-character target name made them past
#: the 255 bytes a file name may have (an OSError traceback)
ID_PART_CHARACTERS = 60
#: the RunSpec fields that override the target's parameters
OVERRIDES = ("kn", "ks", "friction", "points")
#: the rule of each of the OVERRIDES, checked under the grid's own key (its message names that key)
OVERRIDE_RULES = {"kn": JOINT_RULES["kn"], "ks": JOINT_RULES["ks"], "friction": JOINT_RULES["friction"], "points": POINTS}
#: the RunSpec fields of shake runs only: None in the others, and then left out of the id's
#: hash, so that the ids (the record names) of tilt and limit runs are those they always had
SHAKE_FIELDS = ("motion", "scale", "duration_s", "restitution", "contact_damping_ratio", "monitor")
#: the RunSpec fields left out of the id's hash when None: the shake fields and the joint law
OPTIONAL_FIELDS = (*SHAKE_FIELDS, "joint_law")
#: a motion that is an analytic pulse: ``pulse:KIND:FREQUENCY_HZ[:CYCLES]``, amplitude 1 m/s2
PULSE_PREFIX = "pulse:"
#: m/s2: the amplitude of a study's pulse, so that a run's scale is its pulse's amplitude
PULSE_AMPLITUDE_M_S2 = 1.0


def joint_law_text(law: dict | None) -> str | None:
    """A joint law (``[joint]`` keys: model and the law's parameters) as :attr:`RunSpec.joint_law`:
    JSON with sorted keys, so that one law has one text (and one run id)."""
    return None if not law else json.dumps(law, sort_keys=True)


@dataclass(frozen=True)
class RunSpec:
    """One run of a study. kn, ks (Pa/m), friction and points override the target's when given.
    Grids that share a run (same parameters) share its record.

    ``joint_law``: the joint's law, as a JSON object of ``[joint]`` keys (``model`` and the
    law's parameters, :func:`joint_law_text`), replacing the target's; None: the target's.

    A shake run (analysis "shake", protocol "time-history", increment_deg None) also has its
    ``motion`` (a motion file's path or a pulse, module docstring), the ``scale`` on it, and
    the settings of :class:`~drydem.analysis.shake.ShakeSettings` it changes (``duration_s``,
    ``restitution``, ``contact_damping_ratio``, ``monitor``; None: the default)."""

    analysis: str
    target: str
    protocol: str
    kn: float | None = None
    ks: float | None = None
    friction: float | None = None
    points: int | None = None
    increment_deg: float | None = 0.1
    motion: str | None = None
    scale: float | None = None
    duration_s: float | None = None
    restitution: float | str | None = None
    contact_damping_ratio: float | None = None
    monitor: str | None = None
    joint_law: str | None = None

    @property
    def id(self) -> str:
        """Readable and unique: analysis, target, (motion and scale,) (the joint law's model,)
        stiffnesses, protocol and a hash of everything (the fields of :data:`OPTIONAL_FIELDS` left out when None)."""
        fields = {key: value for key, value in asdict(self).items() if not (key in OPTIONAL_FIELDS and value is None)}
        digest = hashlib.sha1(json.dumps(fields, sort_keys=True).encode()).hexdigest()[:10]
        law = "" if self.joint_law is None else f"-{json.loads(self.joint_law).get('model', 'law')}"
        stiffness = law + ("" if self.kn is None else f"-kn{self.kn:.3g}-ks{self.ks:.3g}")
        target = Path(self.target).stem[:ID_PART_CHARACTERS]
        if self.analysis == "shake":
            scale = "" if self.scale is None else f"-x{self.scale:.4g}"
            motion = motion_label(str(self.motion), compact=True)[:ID_PART_CHARACTERS]
            return f"{self.analysis}-{target}-{motion}{scale}{stiffness}-{digest}"
        return f"{self.analysis}-{target}{stiffness}-{self.protocol}-{digest}"

    @property
    def overrides(self) -> dict:
        """The values this run changes in its target's model (None: the target's), as keywords of
        :meth:`drydem.model.assembly.Model.overridden` and ``parameter_changes``."""
        law = None if self.joint_law is None else json.loads(self.joint_law)
        return {key: getattr(self, key) for key in OVERRIDES} | {"joint_law": law}

    def model(self) -> Model:
        """The model this run analyses: its target's (:func:`drydem.io.target.load_target`) with
        :attr:`overrides` applied; ModelError for a target that cannot be loaded or a value out
        of its range."""
        from drydem.io.target import load_target

        return load_target(self.target).model.overridden(**self.overrides)

    def tilt_settings(self):
        """The tilting settings of this run (TiltSettings checks the increment)."""
        from drydem.analysis.tilt import TiltSettings

        return TiltSettings(increment_deg=self.increment_deg, adaptive=self.protocol == "adaptive")

    def shake_settings(self, motion=None):
        """The shaking settings of this run: its motion (:func:`ground_motion`, or ``motion``,
        that motion already read) times its scale, and its settings (ShakeSettings checks them);
        ModelError for a motion that cannot be read or a value out of its range."""
        from drydem.analysis.shake import ShakeSettings

        motion = ground_motion(self.motion) if motion is None else motion
        return ShakeSettings(motion=motion.scaled(self.scale), duration_s=self.duration_s, restitution=self.restitution,
                             contact_damping_ratio=self.contact_damping_ratio, monitor=self.monitor)


def ground_motion(motion: str):
    """The motion of a shake run before it is scaled: the pulse ``pulse:KIND:FREQUENCY_HZ[:CYCLES]``
    of amplitude 1 m/s2, or the record in the file ``motion`` baseline-corrected
    (:meth:`~drydem.analysis.shake.GroundMotion.baseline_corrected`); ModelError naming the
    motion and the problem."""
    from drydem.analysis.shake import pulse, read_motion

    if not isinstance(motion, str):
        raise ModelError(f"{motion!r}: a motion is a file's path or a pulse {PULSE_PREFIX}KIND:FREQUENCY_HZ (a string)")
    if not motion.startswith(PULSE_PREFIX):
        return read_motion(motion).baseline_corrected()
    kind, frequency_hz, cycles = _pulse_parts(motion)
    try:
        return pulse(kind, amplitude_m_s2=PULSE_AMPLITUDE_M_S2, frequency_hz=frequency_hz, cycles=cycles)
    except ModelError as exc:
        raise ModelError(f"{motion!r}: {exc}") from None


def _pulse_parts(motion: str) -> tuple[str, float, int]:
    """KIND, FREQUENCY_HZ and CYCLES (default 1) of ``pulse:KIND:FREQUENCY_HZ[:CYCLES]``, as
    numbers where they are; ModelError naming the motion if it has not that form (the values
    themselves are checked by :func:`~drydem.analysis.shake.pulse`)."""
    parts = motion.split(":")[1:]
    form = f"{motion!r}: a pulse is {PULSE_PREFIX}KIND:FREQUENCY_HZ or {PULSE_PREFIX}sine:FREQUENCY_HZ:CYCLES"
    if len(parts) not in (2, 3):
        raise ModelError(form)
    kind, frequency, cycles = parts[0], parts[1].strip(), parts[2].strip() if len(parts) == 3 else "1"
    # plain decimals only, as every number drydem reads (found by a hunt: float() took 1_0 and a
    # full-width 4, int() raised on a superscript 2 and on 5,000 digits)
    if not PLAIN_NUMBER.fullmatch(frequency):
        raise ModelError(f"{form}; the frequency {frequency!r} is not a plain decimal number")
    if not (re.fullmatch("[0-9]{1,6}", cycles)):
        raise ModelError(f"{form}; the cycles {cycles!r} are not a whole number of at most 6 digits (0-9)")
    return kind, float(frequency), int(cycles)


def motion_label(motion: str, *, compact: bool = False) -> str:
    """A short name of a run's motion: the file's name, or ``one-sine 2 Hz`` (``sine 2 Hz, 3
    cycles``) for a pulse; ``compact``: fit for a file name (``one-sine-2Hz``, ``sine-2Hz-3cycles``;
    characters other than letters, digits and ``._-+`` as ``-``)."""
    label = Path(motion).name
    if motion.startswith(PULSE_PREFIX):
        try:
            kind, frequency_hz, cycles = _pulse_parts(motion)
        except ModelError:
            label = motion
        else:
            several = cycles != 1
            label = (f"{kind}-{frequency_hz:g}Hz" + (f"-{cycles}cycles" if several else "") if compact
                     else f"{kind} {frequency_hz:g} Hz" + (f", {cycles} cycles" if several else ""))
    return "".join(c if c.isalnum() or c in "._-+" else "-" for c in label) if compact else label


@dataclass(frozen=True)
class Study:
    """A checked study file: its runs, and notes: on runs a grid makes twice (a value listed
    twice) and grids of one name, and those on its motions that drydem shake prints for one run
    (a record shifted to start at 0, a component along an axis the supports hold: :func:`_motion_notes`)."""

    name: str
    description: str
    runs: list[RunSpec]
    source: str
    notes: tuple[str, ...] = ()


def load_study(path: str | Path) -> Study:
    """Read a study file and check every run it makes (module docstring); one ModelError that
    names, for every problem, the file, the grid and the key with its rule."""
    path = Path(path)
    data, _ = read_toml(path)
    source = str(path)
    no_unknown(data, {"study", "defaults", "grid"}, source, "top level")
    meta, defaults = data.get("study", {}), data.get("defaults", {})
    no_unknown(meta, {"name", "description"}, source, "[study]")
    no_unknown(defaults, DEFAULT_KEYS, source, "[defaults]")
    grids = data.get("grid")
    if not isinstance(grids, list) or not grids:
        raise ModelError(f"{source}: no [[grid]] entries")
    name, description = meta.get("name", path.stem), meta.get("description", "")
    problems = _texts_problems(name, description, source) + _defaults_problems(defaults, source)
    runs, notes = _runs(grids, defaults, path, problems)
    if problems:
        unique = list(dict.fromkeys(problems))
        raise ModelError(unique[0] if len(unique) == 1 else f"{source}: {len(unique)} problems, nothing run:\n  " + "\n  ".join(unique))
    return Study(name, description, runs, source, notes)


def _texts_problems(name, description, source: str) -> list[str]:
    """Why ``[study]``'s name or description cannot be used: the name names the default results
    folder, results/NAME, so it must be one plain file name (:func:`drydem.files.plain_name_problem`:
    "../x" or an absolute path would write elsewhere); the description is text."""
    problems = [] if isinstance(description, str) else [f"{source}: [study] description = {description!r}: must be a string"]
    problem = plain_name_problem(name)
    return problems + ([] if problem is None else [f"{source}: [study] name = {name!r}: {problem}"])


def _defaults_problems(defaults: dict, source: str) -> list[str]:
    """Why ``[defaults]``' values cannot be used, each by the rule the runs taking it check,
    whether or not a grid takes it (found by a hunt: ``restitution = "nonsense"`` or
    ``duration_s = -5``, which no grid took, were accepted without a word). A list is checked
    value by value, as a grid's."""
    from drydem.analysis.shake.settings import HOUSNER, RESTITUTION
    from drydem.analysis.shake.settings import SETTING_RULES as SHAKE_RULES
    from drydem.analysis.tilt.settings import SETTING_RANGES as TILT_RULES

    rules = {"friction": JOINT_RULES["friction"], "points": POINTS, "increment_deg": TILT_RULES["increment_deg"],
             "duration_s": SHAKE_RULES["duration_s"], "contact_damping_ratio": SHAKE_RULES["contact_damping_ratio"],
             "restitution": RESTITUTION}
    found = [rules[key].problem(value, f"{source}: [defaults] {key}") for key, values in defaults.items() if key in rules
             for value in _list(values) if not (key == "restitution" and value == HOUSNER)]
    return [problem for problem in found if problem is not None]


def _runs(grids: list, defaults: dict, path: Path, problems: list[str]) -> tuple[list[RunSpec], tuple[str, ...]]:
    """The runs of every grid, each once, each checked on its target, and the notes on runs a
    grid lists twice, grids of one name and their motions (:func:`_motion_notes`); a problem
    found is appended to ``problems``. Once the runs
    exceed :data:`MAX_RUNS` the grids after are not expanded: the study is refused, naming each
    grid's count."""
    source = str(path)
    runs: dict[RunSpec, None] = {}
    counts: list[str] = []
    twice: list[str] = []  # notes: runs a grid makes more than once, grids of one name
    models: dict[str, object] = {}  # target -> its model, or the message saying why it cannot be loaded
    motions: dict[str, object] = {}  # motion -> its unscaled GroundMotion, or the message saying why it cannot be read
    for k, grid in enumerate(grids):
        name = grid.get("name", "?") if isinstance(grid, dict) else "?"
        where = f"{source}: [[grid]] #{k} ({name!r})"
        try:
            analysis = grid.get("analysis", "tilt") if isinstance(grid, dict) else None
            keys = GRID_KEYS.get(analysis, set()) if isinstance(analysis, str) else set()
            no_unknown(grid, keys or set().union(*GRID_KEYS.values()), where, f"the grid (a {analysis} analysis)" if keys else "the grid")
            found = _grid_runs(_with_defaults(defaults, grid), path.parent, where, models, problems, motions)
        except ModelError as exc:
            problems.append(str(exc))
            continue
        if len(set(found)) < len(found):
            twice.append(f"{where}: {len(found) - len(set(found))} of its {len(found)} runs are the same as another of its runs (a value "
                         "listed twice?): each is run once")
        if name != "?" and any(isinstance(g, dict) and g.get("name") == name for g in grids[:k]):
            twice.append(f"{where}: another grid before it has the name {name!r}")
        runs |= dict.fromkeys(found)
        counts.append(f"#{k} {name!r} {len(found)}")
        if len(runs) > MAX_RUNS:
            problems.append(f"{source}: {'at least ' if k + 1 < len(grids) else ''}{len(runs)} runs (grids {', '.join(counts)}; a run "
                            f"several grids share counted once): {_too_many()}")
            break
    return list(runs), () if problems else tuple(twice) + _motion_notes(runs, models, motions)


def _motion_notes(runs, models: dict, motions: dict) -> tuple[str, ...]:
    """Each once, the notes drydem shake prints for the shaking runs of ``runs`` (their
    targets' models and unscaled motions read in ``models`` and ``motions``): what reading a
    motion changed (its ``notes``) and the components of a motion along an axis its target's
    supports hold (:func:`~drydem.analysis.shake.run.check_held_axes`)."""
    from drydem.analysis.shake.run import check_held_axes

    notes: dict[str, None] = {}
    for target, motion in dict.fromkeys((spec.target, spec.motion) for spec in runs if spec.motion is not None):
        unscaled = motions[motion]
        notes |= dict.fromkeys(unscaled.notes)
        notes |= dict.fromkeys(check_held_axes(models[target], unscaled, lambda axis: f"{unscaled.name}, before its scales: its {axis} component"))
    return tuple(notes)


def _too_many() -> str:
    """Why a study is refused when it makes more than MAX_RUNS runs, and what to do."""
    return (f"a study makes at most {MAX_RUNS} runs (each a record to keep and to report; drydem.parametric.limits says why); "
            "give fewer values, or split it into several study files, which may share one --out")


def _refuse_too_many(where: str, sizes: dict[str, int]) -> None:
    """ModelError if a grid of ``sizes`` (the number of values of each of its keys) makes more
    than :data:`MAX_RUNS` runs, naming each size: checked before the grid is expanded, so that a
    grid of millions is refused at once rather than laid out and checked run by run."""
    count = math.prod(sizes.values())
    if count > MAX_RUNS:
        raise ModelError(f"{where}: {count} runs ({' x '.join(f'{n} {key}' for key, n in sizes.items())}): {_too_many()}")


def _sizes(values: dict[str, list], grid: dict) -> dict[str, int]:
    """How many values each key of ``grid`` has (``values``: its lists), ks after kn: one for
    ks = "kn" (the default), the ks of each kn."""
    ks_values = grid.get("ks", "kn")
    sizes = {key: len(found) for key, found in values.items() if key not in ("friction", "points")}
    ks = 1 if ks_values == "kn" else len(_list(ks_values))
    return sizes | {"ks": ks, "friction": len(values["friction"]), "points": len(values["points"])}


def _with_defaults(defaults: dict, grid: dict) -> dict:
    """``grid`` over ``defaults``; a grid's own restitution or contact damping ratio replaces
    the default of either (they are exclusive)."""
    exclusive = {"restitution", "contact_damping_ratio"}
    if exclusive & set(grid):
        defaults = {key: value for key, value in defaults.items() if key not in exclusive}
    return defaults | grid


def _grid_runs(grid: dict, folder: Path, where: str, models: dict, problems: list[str], motions: dict) -> list[RunSpec]:
    """The runs of one grid, each checked on its target; a problem found is appended to
    ``problems`` (ModelError when the grid cannot even be expanded)."""
    analysis = grid.get("analysis", "tilt")
    if not isinstance(analysis, str) or analysis not in ANALYSES:
        raise ModelError(f"{where}: analysis = {analysis!r}: must be one of {list(ANALYSES)}")
    if analysis == "shake":
        return _shake_runs(grid, folder, where, models, problems, motions)
    values = {key: _list(grid.get(key, default)) for key, default in
              (("protocol", DEFAULT_PROTOCOL[analysis]), ("targets", []), ("kn", None), ("friction", None), ("points", None))}
    empty = [key for key, found in values.items() if not found]
    if empty:
        raise ModelError(f"{where}: {', '.join(empty)} = []: needs at least one value"
                         + (" (targets: built-in walls or files)" if "targets" in empty else ""))
    bad = [p for p in values["protocol"] if p not in ANALYSES[analysis]]
    if bad:
        raise ModelError(f"{where}: protocol {bad} is not one of {list(ANALYSES[analysis])} for a {analysis} analysis")
    _refuse_too_many(where, _sizes(values, grid))
    targets = _targets(values["targets"], folder, where)
    runs = [RunSpec(analysis=analysis, target=target, protocol=protocol, kn=kn, ks=ks, friction=friction, points=points,
                    increment_deg=grid.get("increment_deg", 0.1))
            for target, protocol, (kn, ks, friction, points) in itertools.product(targets, values["protocol"], _overrides(grid, values, where))]
    return _checked(runs, where, models, problems, {})


def _targets(targets: list, folder: Path, where: str) -> list[str]:
    """The grid's targets: files relative to the study's folder, or the names of built-in walls
    and buildings; any other name is a file there too, which the run then finds missing (it was
    looked for in the current folder, so that a study run from elsewhere analysed another file)."""
    from drydem.masonry import designs
    from drydem.masonry.building import BUILDINGS

    names = [t for t in targets if not isinstance(t, str)]
    if names:
        raise ModelError(f"{where}: targets {names}: each must be a built-in wall's name or a file (a string)")
    built_in = set(designs.names()) | set(BUILDINGS)
    return [t if t in built_in and not (folder / t).is_file() else str(folder / t) for t in targets]


def _overrides(grid: dict, values: dict, where: str) -> list[tuple]:
    """Every (kn, ks, friction, points) of the grid."""
    ks_values = grid.get("ks", "kn")
    if isinstance(ks_values, list) and not ks_values:
        raise ModelError(f"{where}: ks = []: needs at least one value, or \"kn\" (ks = kn)")
    return [(kn, ks, friction, points) for kn, friction, points in itertools.product(values["kn"], values["friction"], values["points"])
            for ks in ([kn] if ks_values == "kn" else _list(ks_values))]


def _shake_runs(grid: dict, folder: Path, where: str, models: dict, problems: list[str], motions: dict) -> list[RunSpec]:
    """The runs of a shake grid: every target, motion, scale and override (module docstring)."""
    values = {key: _list(grid.get(key, [] if key in ("targets", "motions", "scales") else None))
              for key in ("targets", "motions", "scales", "kn", "friction", "points")}
    empty = [key for key, found in values.items() if not found]
    if empty:
        raise ModelError(f"{where}: {', '.join(empty)} = []: needs at least one value"
                         + (" (a shake grid needs targets, motions and scales)" if set(empty) & {"targets", "motions", "scales"} else ""))
    bad = [scale for scale in values["scales"] if not (is_number(scale) and scale > 0)]
    if bad:
        raise ModelError(f"{where}: scales {bad}: each must be a finite number > 0 (a factor on every motion)")
    _refuse_too_many(where, _sizes(values, grid))
    targets = _targets(values["targets"], folder, where)
    named = [m for m in values["motions"] if not isinstance(m, str)]
    if named:
        raise ModelError(f"{where}: motions {named}: each must be a file (CSV or .AT2) or a pulse {PULSE_PREFIX}KIND:FREQUENCY_HZ (a string)")
    found = [_motion(m, folder) for m in values["motions"]]
    shake = {key: grid.get(key) for key in ("duration_s", "restitution", "contact_damping_ratio", "monitor")}
    runs = [RunSpec(analysis="shake", target=target, protocol=DEFAULT_PROTOCOL["shake"], kn=kn, ks=ks, friction=friction, points=points,
                    increment_deg=None, motion=motion, scale=scale, **shake)
            for target, motion, scale, (kn, ks, friction, points) in itertools.product(targets, found, values["scales"], _overrides(grid, values, where))]
    return _checked(runs, where, models, problems, motions)


def _motion(motion: str, folder: Path) -> str:
    """A grid's motion as a run has it: a pulse as written (its numbers normalised, so that 2
    and 2.0 are one run), or a file by its path from the study's folder."""
    if motion.startswith(PULSE_PREFIX):
        try:
            kind, frequency_hz, cycles = _pulse_parts(motion)
        except ModelError:
            return motion
        return f"{PULSE_PREFIX}{kind}:{frequency_hz!r}" + (f":{cycles}" if cycles != 1 else "")
    return str(folder / motion)


def _checked(runs: list[RunSpec], where: str, models: dict, problems: list[str], motions: dict) -> list[RunSpec]:
    """``runs``, normalised, if each can run on its target (and its motion); otherwise []
    with the problems appended to ``problems``."""
    found = len(problems)
    for spec in runs:
        if spec.target not in models:
            models[spec.target] = _load_model(spec.target)
        model = models[spec.target]
        if spec.motion is not None and spec.motion not in motions:
            motions[spec.motion] = _read_motion(spec.motion)
        motion = motions.get(spec.motion)
        found_here = [model, *([motion] if isinstance(motion, str) else [])] if isinstance(model, str) else _problems(model, spec, motion)
        problems += [f"{where}: {problem}" for problem in found_here]
    return [] if len(problems) > found else [_normalised(spec) for spec in runs]


def _read_motion(motion: str):
    """The unscaled motion ``motion`` (:func:`ground_motion`), or the message saying why it cannot be read."""
    try:
        return ground_motion(motion)
    except DrydemError as exc:
        return f"motions: {exc}"


def _load_model(target: str):
    """The model of ``target``, or the message saying why it cannot be loaded."""
    from drydem.io.target import load_target

    try:
        return load_target(target).model
    except DrydemError as exc:
        return f"targets: {exc}"


def _problems(model, spec: RunSpec, motion=None) -> list[str]:
    """Why ``spec`` cannot run on ``model``: its overrides applied to the model and its tilt
    step, or its shaking settings on ``motion`` (its motion read, or the message saying why it
    cannot be), as the run itself builds them (the rules are the parameter classes', written
    once), each override alone so that one bad value does not hide another."""
    checks = [lambda key=key: _override(model, spec, key) for key in OVERRIDES if not (key == "ks" and spec.ks is spec.kn)]
    if spec.analysis == "tilt":  # and its stop displacement, the default's, against the wall's height
        from drydem.analysis.tilt import TiltSettings, check_stop_displacement

        checks += [spec.tilt_settings, lambda: check_stop_displacement(model, TiltSettings())]
    elif spec.analysis != "shake":
        checks.append(spec.tilt_settings)  # a limit run's increment is unused, but is part of its id
    else:
        from drydem.analysis.shake.run import check_held_axes

        if isinstance(motion, str):  # the settings are checked all the same, on a stand-in motion
            checks.append(lambda message=motion: _raise(message))
            motion = ground_motion(f"{PULSE_PREFIX}one-sine:1.0")
        else:  # a motion moving the model along held axes only would move nothing (the run refuses it)
            checks.append(lambda: check_held_axes(model, motion))
        checks += [lambda: spec.shake_settings(motion), lambda: _monitored(model, spec)]
    found = []
    for check in checks:
        try:
            check()
        except ModelError as exc:
            found.append(str(exc))
    return found


def _override(model, spec: RunSpec, key: str) -> None:
    """ModelError naming the grid's ``key`` (not the model table's) unless the run's value of it
    obeys its rule (:data:`OVERRIDE_RULES`) and fits ``model`` (its joint law, ...). A ks that is
    the run's kn (ks = "kn", the default) is not checked again: one mistake, one message."""
    value = getattr(spec, key)
    if value is not None:
        OVERRIDE_RULES[key].check(value, key)
    model.parameter_changes(**{key: value})


def _raise(message: str):
    raise ModelError(message)


def _monitored(model, spec: RunSpec) -> None:
    """ModelError unless the run's monitor (None: the default block) names a movable block of
    ``model`` that can rock if its restitution is Housner's (r = 1 - 1.5 sin^2 alpha > 0)."""
    import math

    from drydem.analysis.shake import HOUSNER, housner_restitution
    from drydem.analysis.shake.restitution import slenderness
    from drydem.analysis.tilt.settings import monitor_index

    monitor = spec.monitor
    if not (monitor is None or isinstance(monitor, str)):
        return  # ShakeSettings refuses it
    try:
        block = monitor_index(model, monitor)
    except ModelError as exc:
        raise ModelError(f"monitor = {monitor!r}: {exc}") from None
    if spec.restitution == HOUSNER:
        alpha = math.atan2(*slenderness(model.block_shape[block]))
        if housner_restitution(alpha) <= 0.0:
            raise ModelError(f"restitution = {HOUSNER!r}: the monitored block {model.block_name[block]!r} is too squat to rock: "
                             f"alpha = atan(b / h) = {math.degrees(alpha):.1f} deg gives 1 - 1.5 sin^2(alpha) = "
                             f"{housner_restitution(alpha):.2f} <= 0; give contact_damping_ratio, or monitor a slender block")


def _normalised(spec: RunSpec) -> RunSpec:
    """``spec`` with its checked numbers as floats (1e7 and 10000000 are one run)."""
    def number(value):
        return None if value is None else float(value)

    restitution = spec.restitution if isinstance(spec.restitution, str) else number(spec.restitution)
    return replace(spec, kn=number(spec.kn), ks=number(spec.ks), friction=number(spec.friction), increment_deg=number(spec.increment_deg),
                   scale=number(spec.scale), duration_s=number(spec.duration_s), restitution=restitution,
                   contact_damping_ratio=number(spec.contact_damping_ratio))


def _list(value) -> list:
    return value if isinstance(value, list) else [value]
