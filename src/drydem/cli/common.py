"""What the commands share: the ``drydem`` group, target loading, results folders, interruption,
and the options of several commands (units, workers, joint laws, imperfections).

The command modules import at module level only what their options need, the rest in the
commands: ``drydem --help`` imports neither numba, scipy, numpy nor matplotlib (tests/test_start.py)."""

from __future__ import annotations

import functools
import itertools
import math
import os
import re
import shutil
import signal
from collections.abc import Callable
from contextlib import contextmanager
from datetime import datetime
from pathlib import Path
from typing import TYPE_CHECKING

import click

from drydem import __version__
from drydem.errors import DrydemError
from drydem.files import PLAIN_INTEGER, PLAIN_NUMBER
from drydem.model.parameters import DENSITY, JOINT_MODELS, JOINT_RULES, POINTS, Rule

if TYPE_CHECKING:
    from drydem.io.target import Target
    from drydem.model.assembly import Model
    from drydem.masonry.imperfections import Imperfections


class _Plain:
    """A number option as the files drydem reads write a number (drydem.files.PLAIN_NUMBER):
    click's float and int are Python's, which also take 1_0 for 10 (``--amplitude 0_5`` ran a
    pulse of 5 m/s2) and other scripts' digits; then click's own conversion and range."""

    pattern: re.Pattern
    kind: str
    written: str

    def convert(self, value, param, ctx):
        if isinstance(value, str) and not self.pattern.fullmatch(value.strip()):
            self.fail(f"{value!r} is not a valid {self.kind} ({self.written}; not 1_0 nor 0x10)", param, ctx)
        return super().convert(value, param, ctx)


class PlainFloat(_Plain, click.types.FloatParamType):
    pattern, kind, written = PLAIN_NUMBER, "float", "ASCII digits, an optional sign, point and exponent"


class PlainInt(_Plain, click.types.IntParamType):
    pattern, kind, written = PLAIN_INTEGER, "integer", "ASCII digits and an optional sign"


class PlainIntRange(_Plain, click.IntRange):
    pattern, kind, written = PlainInt.pattern, PlainInt.kind, PlainInt.written


PLAIN_FLOAT, PLAIN_INT = PlainFloat(), PlainInt()


#: the tilting analysis' checkpoint in its results folder, and the file it is written to first
CHECKPOINT = "checkpoint.npz"
CHECKPOINT_PARTIAL = ".checkpoint.partial.npz"


#: length units of imported geometry (VRML, OBJ, STL), in metres
UNITS = {"m": 1.0, "cm": 0.01, "mm": 0.001}

unit_option = click.option("--unit", type=click.Choice(list(UNITS)), default="m", show_default=True,
                           help="Length unit of imported geometry (.wrl, .obj, .stl, compas .json).")


def _workers(ctx, param, value):
    """--workers: None (one per core) or at most drydem.parametric.workers.most_workers(), else a
    usage error naming the bound."""
    if value is not None:
        from drydem.parametric.workers import WORKERS_PER_CORE, cores, most_workers

        if value > most_workers():
            raise click.BadParameter(f"{value}: at most {most_workers()} local processes ({WORKERS_PER_CORE} per core; this process "
                                     f"may run on {cores()} cores): more would only queue for them")
    return value


workers_option = click.option("--workers", type=PlainIntRange(min=1), callback=_workers,
                              help="Local processes, at most 4 per core (default: one per core this process may run on).")
scheduler_option = click.option("--scheduler", help="Address of a Dask distributed scheduler to run on instead (tcp://host:8786).")


def _threads(ctx, param, value):
    """--threads: set as soon as it is read (drydem.engine.threads.set_threads; None: all cores),
    or a usage error naming the allowed range."""
    from drydem.engine.threads import set_threads

    try:
        set_threads(value)
    except DrydemError as exc:
        raise click.BadParameter(str(exc)) from None
    return value


#: the compiled kernels' threads (drydem.engine.threads): set by the option itself, so a command
#: takes no argument for it; the results are the same for every count, only the speed changes
threads_option = click.option("--threads", type=PLAIN_INT, callback=_threads, expose_value=False,
                              help="Most threads for the compiled kernels (default: all cores; a small model takes fewer).")


def ruled(rule: Rule | Callable[[], Rule], sets: str):
    """An option's callback: its value if ``rule`` (drydem.model.parameters; or a function
    giving it, for a rule whose module imports NumPy, which ``drydem --help`` does not) allows
    it, else a usage error naming the option (click does), the rule and ``sets``, what the
    value sets in the model or analysis: ``--kn -1`` is refused as itself, before the target
    is read. None (not given) passes."""
    def check(ctx, param, value):
        allowed = rule if isinstance(rule, Rule) else rule()
        if value is not None and value not in allowed:
            raise click.BadParameter(f"{value!r}: {allowed} ({sets})")
        return value
    return check


def joint_option(key: str, flag: str, help: str):
    """An option setting the [joint] table's ``key``, checked by its rule (JOINT_RULES)."""
    return click.option(flag, type=PLAIN_FLOAT, callback=ruled(JOINT_RULES[key], f"[joint] {key}"), help=help)


#: the options that override a model's parameters (``drydem tilt``, ``montecarlo``, ``shake``):
#: the keyword of drydem.model.assembly.Model.overridden -> the option
MODEL_OPTIONS = {
    "kn": joint_option("kn", "--kn", "Normal joint stiffness, Pa/m (overrides the model file)."),
    "ks": joint_option("ks", "--ks", "Shear joint stiffness, Pa/m."),
    "friction": joint_option("friction", "--friction", "Coulomb friction coefficient."),
    "points": click.option("--points", type=PLAIN_INT, callback=ruled(POINTS, "[contacts] points_per_length"),
                           help="Sub-contact points per length."),
    "density": click.option("--density", type=PLAIN_FLOAT, callback=ruled(DENSITY, "the density of every block"),
                            help="Density of every block, kg/m3."),
}


def model_options(command):
    """The options of :data:`MODEL_OPTIONS` (each its own argument of ``command``, by its keyword)."""
    for option in reversed(MODEL_OPTIONS.values()):
        command = option(command)
    return command


#: the options of a joint law: option name -> ([joint] key, the option)
JOINT_LAW_OPTIONS = {
    "joint_model": ("model", click.option("--joint-model", type=click.Choice(JOINT_MODELS),
                                          help="Joint law ([joint] model): constant, or kn and ks a power of the normal stress sigma or "
                                               "affine in it (overrides the model file's law; the law's keys below)")),
    "kn_exponent": ("kn_exponent", joint_option("kn_exponent", "--kn-exponent", "power: kn (sigma / stress_ref)^kn_exponent.")),
    "ks_exponent": ("ks_exponent", joint_option("ks_exponent", "--ks-exponent", "power: ks (sigma / stress_ref)^ks_exponent "
                                                                                  "(default: kn_exponent).")),
    "stress_ref": ("stress_ref", joint_option("stress_ref", "--stress-ref", "power: the stress at which kn and ks hold, Pa.")),
    "kn_per_stress": ("kn_per_stress", joint_option("kn_per_stress", "--kn-per-stress", "affine: kn + kn_per_stress sigma, 1/m.")),
    "ks_per_stress": ("ks_per_stress", joint_option("ks_per_stress", "--ks-per-stress", "affine: ks + ks_per_stress sigma, 1/m "
                                                                                        "(default: kn_per_stress).")),
    "joint_kn_min": ("kn_min", joint_option("kn_min", "--joint-kn-min", "The law's smallest stiffness, Pa/m ([joint] kn_min).")),
    "joint_kn_max": ("kn_max", joint_option("kn_max", "--joint-kn-max", "The law's largest stiffness, Pa/m ([joint] kn_max).")),
}


def joint_law_options(command):
    """The options of :data:`JOINT_LAW_OPTIONS`, handed to ``command`` as one ``joint_law``
    argument: the ``[joint]`` keys given (None when none is)."""
    @functools.wraps(command)
    def bundled(**values):
        law = {key: values.pop(name) for name, (key, _) in JOINT_LAW_OPTIONS.items()}
        return command(joint_law={key: value for key, value in law.items() if value is not None} or None, **values)

    for _, option in reversed(JOINT_LAW_OPTIONS.values()):
        bundled = option(bundled)
    return bundled


def out_path(ctx, param, value: str | None) -> Path | None:
    """--out of every command, calibrate's RESULTS_DIR and shake's --motion: None where not given, else its Path;
    a usage error for an empty or blank one, which the system would read as the current folder
    (Path("") is "."; found by a hunt: `drydem calibrate ""` began writing its runs here)."""
    if value is None:
        return None
    if not value.strip():
        raise click.BadParameter(f"{value!r}: an empty path; give a file or folder name (an empty one would mean the current folder)")
    return Path(value)


def given(option: str) -> bool:
    """Whether the current command's parameter ``option`` (its Python name) was given on the
    command line, not left at its default (an option that applies only with another one is
    refused without it rather than silently ignored)."""
    from click.core import ParameterSource

    return click.get_current_context().get_parameter_source(option) == ParameterSource.COMMANDLINE


def check_save_every(save_every: int, series: bool) -> None:
    """DrydemError if --save-every was given without a VTK series to thin (``series``: --vtk or
    --video): it would be ignored (found by a hunt: drydem shake took it silently)."""
    if given("save_every") and not series:
        raise DrydemError(f"--save-every {save_every} thins the VTK series: it needs --vtk or --video")


def resolve_target(target: str, unit: str = "m") -> Target:
    """Load TARGET or exit with its error; print to stderr what an imported file could not say."""
    from drydem.io.target import MESH_SUFFIXES, load_target

    if unit != "m" and Path(target).suffix.lower() not in MESH_SUFFIXES:
        raise click.ClickException(f"{target}: --unit {unit} applies to imported geometry ({', '.join(MESH_SUFFIXES)}); "
                                   "a built-in, a wall file and a model file are in metres")
    try:
        found = load_target(target, unit_m=UNITS[unit])
    except DrydemError as exc:
        raise click.ClickException(str(exc)) from None
    for note in found.notes:
        click.echo(f"note: {note}", err=True)
    return found


@click.group()
@click.version_option(__version__, prog_name="drydem")
@click.pass_context
def main(ctx: click.Context) -> None:
    """drydem: discrete element analysis of dry-joint masonry."""
    from drydem.compiled_cache import compile_notice

    ctx.with_resource(compile_notice())  # a first run says it compiles the kernels, and for how long

#: what ``drydem shake`` writes in its results folder
SHAKE_OUTPUTS = ("summary.json", "history.csv", "history.png", "vtk", "shake.mp4", "shake.gif")
#: what ``drydem montecarlo`` writes in its results folder besides summary.json
MONTECARLO_OUTPUTS = ("samples", "histogram.png")
#: what ``drydem tilt``, ``drydem limit``, ``drydem shake`` and ``drydem montecarlo`` write in
#: their results folders (deleted first by --overwrite, whichever of them wrote them)
RUN_OUTPUTS = ("summary.json", "pushover.csv", "pushover.png", "mechanism.png", CHECKPOINT, CHECKPOINT_PARTIAL, "vtk",
               "collapse.mp4", "collapse.gif") + tuple(name for name in SHAKE_OUTPUTS if name not in ("summary.json", "vtk")) \
    + MONTECARLO_OUTPUTS


def results_folder(out: Path | None, name: str, *, resume: bool | None = False, overwrite: bool = False) -> Path:
    """``out`` made ready for a run and held until the command ends
    (drydem.io.results.prepared_folder; ``resume`` None for a command that cannot resume), or by
    default a new results/NAME-TIME folder (numbered -2, -3, ... if two runs start in the same
    second: each is made exclusively, so two runs never share one)."""
    from drydem.io.results import prepared_folder

    if out is None:
        stem = f"{name}-{datetime.now():%Y%m%d-%H%M%S}"
        for k in itertools.count(1):
            out = Path("results") / (stem if k == 1 else f"{stem}-{k}")
            try:
                out.mkdir(parents=True)
                break
            except OSError:  # taken (next number), or a reason prepared_folder says ("results" is a file, ...)
                if not os.path.lexists(out):
                    break
    return click.get_current_context().with_resource(prepared_folder(out, RUN_OUTPUTS, resume=resume, overwrite=overwrite))


def discard_unstarted(table: Path, series) -> None:
    """Remove what a run refused before its first result (a tilt: before its first checkpoint,
    from which alone it could go on) wrote: ``table`` (pushover.csv or history.csv) and the
    folder of ``series`` (a VTK series with no state;
    None: none). The run's folder held neither before (:func:`results_folder`); left there, they
    made the same --out refuse the corrected command without --overwrite."""
    table.unlink(missing_ok=True)
    if series is not None and not series.rows:
        shutil.rmtree(series.folder, ignore_errors=True)


def failure_message(exc: DrydemError | OSError, folder: Path) -> str:
    """What went wrong while a run wrote its results, for the user: a DrydemError's own message,
    or the file an OSError (a full disk, a folder made read-only) names, else ``folder``, and why
    it could not be written."""
    return str(exc) if isinstance(exc, DrydemError) else f"{exc.filename or folder}: cannot write results ({exc.strerror or exc})"


@contextmanager
def writing_results(folder: Path, *, unfinished: str = ""):
    """Within it, a DrydemError or an OSError ends the command with :func:`failure_message`
    (then ``unfinished``: what the folder holds now and how to go on), without a traceback."""
    try:
        yield
    except (DrydemError, OSError) as exc:
        raise click.ClickException(failure_message(exc, folder) + unfinished) from None


class _Received:
    """The signal that interrupted a command: its name and number (SIGINT until told otherwise)."""

    name, number = "SIGINT", int(signal.SIGINT)


#: the signal that interrupted the last command run in this process: for
#: :func:`drydem.cli.console`, which names it where an interruption escaped the command
LAST_RECEIVED = _Received()


@contextmanager
def signals_interrupt():
    """SIGTERM (a kill, a scheduler's time limit) interrupts like Ctrl-C: KeyboardInterrupt,
    so that the command says what it saved and how to go on. Yields what was received (also
    kept in :data:`LAST_RECEIVED`)."""
    received = LAST_RECEIVED
    received.name, received.number = "SIGINT", int(signal.SIGINT)

    def interrupt(number, frame):
        received.name, received.number = signal.Signals(number).name, number
        raise KeyboardInterrupt

    previous = signal.signal(signal.SIGTERM, interrupt)
    try:
        yield received
    finally:
        signal.signal(signal.SIGTERM, previous)

def _amplitude_mm(ctx, param, value):
    """An imperfection amplitude, mm: not given (None), or a finite number >= 0."""
    if value is not None and not (math.isfinite(value) and value >= 0.0):
        raise click.BadParameter(f"{value!r}: must be a finite number >= 0 (mm)")
    return value


def _factor(ctx, param, value):
    """A drawing factor: a finite number > 0."""
    if not (math.isfinite(value) and value > 0.0):
        raise click.BadParameter(f"{value!r}: must be a finite number > 0")
    return value


#: the option of each amplitude of drydem.masonry.imperfections.Imperfections
IMPERFECTION_OPTIONS = {"height_sd_mm": "--height-sd", "flatness_sd_mm": "--flatness-sd", "misalignment_sd_mm": "--misalignment-sd"}


def imperfection_options(command):
    """Add the imperfect-brick options (drydem.masonry.imperfections) to ``command``: --seed,
    --height-sd, --height-distribution, --flatness-sd and --misalignment-sd, passed as ``seed``,
    ``height_sd``, ``height_distribution``, ``flatness_sd`` and ``misalignment_sd``; the amplitudes
    are None where not given (:func:`imperfections_from_options` reads them)."""
    options = [
        click.option("--seed", type=PlainIntRange(min=0), default=0, show_default=True, help="Seed of the imperfections' random draws."),
        click.option("--height-sd", type=PLAIN_FLOAT, metavar="MM", callback=_amplitude_mm,
                     help="Imperfect bricks: standard deviation of each brick's height, mm."),
        click.option("--height-distribution", type=click.Choice(["normal", "uniform"]), default="normal", show_default=True,
                     help="Distribution of the heights (uniform: the same standard deviation)."),
        click.option("--flatness-sd", type=PLAIN_FLOAT, metavar="MM", callback=_amplitude_mm,
                     help="Imperfect bricks: each bed face tilted along the wall, its edges this standard deviation off its mid-line, mm."),
        click.option("--misalignment-sd", type=PLAIN_FLOAT, metavar="MM", callback=_amplitude_mm,
                     help="Imperfect bricks: standard deviation of each brick's placement along the wall, mm."),
    ]
    for option in reversed(options):
        command = option(command)
    return command


def imperfections_from_options(height_sd: float | None, height_distribution: str, flatness_sd: float | None,
                               misalignment_sd: float | None) -> Imperfections | None:
    """The imperfections the options of :func:`imperfection_options` ask for (an amplitude not
    given is zero); None where no amplitude is given: the perfect wall."""
    from drydem.masonry.imperfections import Imperfections

    amplitudes = {"height_sd_mm": height_sd, "flatness_sd_mm": flatness_sd, "misalignment_sd_mm": misalignment_sd}
    if all(value is None for value in amplitudes.values()):
        return None
    try:
        return Imperfections(height_distribution=height_distribution,
                             **{name: 0.0 if value is None else value for name, value in amplitudes.items()})
    except DrydemError as exc:
        raise click.ClickException(str(exc)) from None


def more_cycles_advice(model: Model, advice: str) -> str:
    """``advice`` (more cycles), unless round-off keeps the unbalanced-force ratio above the
    criterion (:func:`drydem.analysis.support.roundoff_ratio`), where no number of cycles helps."""
    from drydem.analysis.support import roundoff_ratio

    floor = roundoff_ratio(model)
    if model.solver.criterion != "ratio" or floor < model.solver.ratio:
        return advice
    return (f"round-off keeps the unbalanced-force ratio at about {floor:.2g} (kn times a block's largest face times the spacing of "
            f"doubles at the farthest coordinate, over the mean block weight) against [solver] ratio = {model.solver.ratio:g}: "
            "more cycles cannot reach it; bring the model near the origin, soften [joint] kn or raise ratio")
