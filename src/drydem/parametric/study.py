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

A study is checked whole when it is loaded: every target is loaded and every run's overrides
applied to it (the parameter classes check the values), so that a bad value anywhere stops the
study before its first run, with every problem named, rather than hours later as a failed run.

Every run has an id made of its parameters (and a hash of them): the name of its record
(:mod:`drydem.parametric.records`).
"""

from __future__ import annotations

import hashlib
import itertools
import json
from dataclasses import asdict, dataclass, replace
from pathlib import Path

from drydem.errors import DrydemError, ModelError
from drydem.files import read_toml
from drydem.model.assembly import Model
from drydem.model.tables import no_unknown

ANALYSES = {"tilt": ("fixed", "adaptive"), "limit": ("associative", "non-associative")}
DEFAULT_PROTOCOL = {"tilt": "adaptive", "limit": "associative"}
GRID_KEYS = {"name", "analysis", "targets", "kn", "ks", "friction", "points", "protocol", "increment_deg"}
DEFAULT_KEYS = {"friction", "points", "increment_deg"}
#: the RunSpec fields that override the target's parameters
OVERRIDES = ("kn", "ks", "friction", "points")


@dataclass(frozen=True)
class RunSpec:
    """One run of a study. kn, ks (Pa/m), friction and points override the target's when given.
    Grids that share a run (same parameters) share its record."""

    analysis: str
    target: str
    protocol: str
    kn: float | None = None
    ks: float | None = None
    friction: float | None = None
    points: int | None = None
    increment_deg: float = 0.1

    @property
    def id(self) -> str:
        """Readable and unique: analysis, target, stiffnesses, protocol and a hash of everything."""
        digest = hashlib.sha1(json.dumps(asdict(self), sort_keys=True).encode()).hexdigest()[:10]
        stiffness = "" if self.kn is None else f"-kn{self.kn:.3g}-ks{self.ks:.3g}"
        return f"{self.analysis}-{Path(self.target).stem}{stiffness}-{self.protocol}-{digest}"

    @property
    def overrides(self) -> dict:
        """The values this run changes in its target's model (None: the target's), as keywords of
        :meth:`drydem.model.assembly.Model.overridden` and ``parameter_changes``."""
        return {key: getattr(self, key) for key in OVERRIDES}

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


@dataclass(frozen=True)
class Study:
    name: str
    description: str
    runs: list[RunSpec]
    source: str


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
    runs: list[RunSpec] = []
    problems: list[str] = []
    models: dict[str, object] = {}  # target -> its model, or the message saying why it cannot be loaded
    for k, grid in enumerate(grids):
        name = grid.get("name", "?") if isinstance(grid, dict) else "?"
        where = f"{source}: [[grid]] #{k} ({name!r})"
        try:
            no_unknown(grid, GRID_KEYS, where, "the grid")
            runs += _grid_runs(defaults | grid, path.parent, where, models, problems)
        except ModelError as exc:
            problems.append(str(exc))
    if problems:
        unique = list(dict.fromkeys(problems))
        raise ModelError(unique[0] if len(unique) == 1 else f"{source}: {len(unique)} problems, nothing run:\n  " + "\n  ".join(unique))
    return Study(str(meta.get("name", path.stem)), str(meta.get("description", "")), list(dict.fromkeys(runs)), source)


def _grid_runs(grid: dict, folder: Path, where: str, models: dict, problems: list[str]) -> list[RunSpec]:
    """The runs of one grid, each checked on its target; a problem found is appended to
    ``problems`` (ModelError when the grid cannot even be expanded)."""
    analysis = grid.get("analysis", "tilt")
    if not isinstance(analysis, str) or analysis not in ANALYSES:
        raise ModelError(f"{where}: analysis = {analysis!r}: must be one of {list(ANALYSES)}")
    values = {key: _list(grid.get(key, default)) for key, default in
              (("protocol", DEFAULT_PROTOCOL[analysis]), ("targets", []), ("kn", None), ("friction", None), ("points", None))}
    empty = [key for key, found in values.items() if not found]
    if empty:
        raise ModelError(f"{where}: {', '.join(empty)} = []: needs at least one value"
                         + (" (targets: built-in walls or files)" if "targets" in empty else ""))
    bad = [p for p in values["protocol"] if p not in ANALYSES[analysis]]
    if bad:
        raise ModelError(f"{where}: protocol {bad} is not one of {list(ANALYSES[analysis])} for a {analysis} analysis")
    names = [t for t in values["targets"] if not isinstance(t, str)]
    if names:
        raise ModelError(f"{where}: targets {names}: each must be a built-in wall's name or a file (a string)")
    targets = [t if not (folder / t).is_file() else str(folder / t) for t in values["targets"]]
    ks_values = grid.get("ks", "kn")
    if isinstance(ks_values, list) and not ks_values:
        raise ModelError(f"{where}: ks = []: needs at least one value, or \"kn\" (ks = kn)")
    runs = []
    for target, protocol, kn, friction, points in itertools.product(targets, values["protocol"], values["kn"], values["friction"], values["points"]):
        for ks in ([kn] if ks_values == "kn" else _list(ks_values)):
            runs.append(RunSpec(analysis=analysis, target=target, protocol=protocol, kn=kn, ks=ks, friction=friction, points=points,
                                increment_deg=grid.get("increment_deg", 0.1)))
    found = len(problems)
    for spec in runs:
        if spec.target not in models:
            models[spec.target] = _load_model(spec.target)
        model = models[spec.target]
        problems += [f"{where}: {problem}" for problem in ([model] if isinstance(model, str) else _problems(model, spec))]
    return [] if len(problems) > found else [_normalised(spec) for spec in runs]


def _load_model(target: str):
    """The model of ``target``, or the message saying why it cannot be loaded."""
    from drydem.io.target import load_target

    try:
        return load_target(target).model
    except DrydemError as exc:
        return f"targets: {exc}"


def _problems(model, spec: RunSpec) -> list[str]:
    """Why ``spec`` cannot run on ``model``: its overrides applied to the model and its tilt
    step, as the run itself builds them (the rules are the parameter classes', written once),
    each override alone so that one bad value does not hide another."""
    checks = [lambda key=key: model.parameter_changes(**{key: getattr(spec, key)}) for key in OVERRIDES]
    found = []
    for check in [*checks, spec.tilt_settings]:  # a limit run's increment is unused, but is part of its id
        try:
            check()
        except ModelError as exc:
            found.append(str(exc))
    return found


def _normalised(spec: RunSpec) -> RunSpec:
    """``spec`` with its checked numbers as floats (1e7 and 10000000 are one run)."""
    def number(value):
        return None if value is None else float(value)

    return replace(spec, kn=number(spec.kn), ks=number(spec.ks), friction=number(spec.friction), increment_deg=float(spec.increment_deg))


def _list(value) -> list:
    return value if isinstance(value, list) else [value]
