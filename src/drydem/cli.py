"""The ``drydem`` command line."""

from __future__ import annotations

import functools
import itertools
import signal
import time
from contextlib import contextmanager
from dataclasses import dataclass, fields
from datetime import datetime
from pathlib import Path

import click
import numpy as np

from drydem import __version__
from drydem.masonry import designs
from drydem.errors import DrydemError
from drydem.io.target import Target, load_target
from drydem.model.assembly import Model
from drydem.model.parameters import CRITERIA, JOINT_MODELS
from drydem.masonry.imperfections import Imperfections
from drydem.engine.simulation import Simulation

#: the tilting analysis' checkpoint in its results folder, and the file it is written to first
CHECKPOINT = "checkpoint.npz"
CHECKPOINT_PARTIAL = ".checkpoint.partial.npz"


#: length units of imported geometry (VRML, OBJ, STL), in metres
UNITS = {"m": 1.0, "cm": 0.01, "mm": 0.001}

unit_option = click.option("--unit", type=click.Choice(list(UNITS)), default="m", show_default=True,
                           help="Length unit of imported geometry (.wrl, .obj, .stl).")


workers_option = click.option("--workers", type=click.IntRange(min=1), help="Local processes (default: all cores).")
scheduler_option = click.option("--scheduler", help="Address of a Dask distributed scheduler to run on instead (tcp://host:8786).")
#: the options of a joint law: option name -> ([joint] key, the option)
JOINT_LAW_OPTIONS = {
    "joint_model": ("model", click.option("--joint-model", type=click.Choice(JOINT_MODELS),
                                          help="Joint law ([joint] model): constant, or kn and ks a power of the normal stress sigma or "
                                               "affine in it (overrides the model file's law; the law's keys below)")),
    "kn_exponent": ("kn_exponent", click.option("--kn-exponent", type=float, help="power: kn (sigma / stress_ref)^kn_exponent.")),
    "ks_exponent": ("ks_exponent", click.option("--ks-exponent", type=float, help="power: ks (sigma / stress_ref)^ks_exponent "
                                                                                       "(default: kn_exponent).")),
    "stress_ref": ("stress_ref", click.option("--stress-ref", type=float, help="power: the stress at which kn and ks hold, Pa.")),
    "kn_per_stress": ("kn_per_stress", click.option("--kn-per-stress", type=float, help="affine: kn + kn_per_stress sigma, 1/m.")),
    "ks_per_stress": ("ks_per_stress", click.option("--ks-per-stress", type=float, help="affine: ks + ks_per_stress sigma, 1/m "
                                                                                             "(default: kn_per_stress).")),
    "joint_kn_min": ("kn_min", click.option("--joint-kn-min", type=float, help="The law's smallest stiffness, Pa/m ([joint] kn_min).")),
    "joint_kn_max": ("kn_max", click.option("--joint-kn-max", type=float, help="The law's largest stiffness, Pa/m ([joint] kn_max).")),
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


def _target(target: str, unit: str = "m") -> Target:
    """Load TARGET or exit with its error; print to stderr what an imported file could not say."""
    try:
        found = load_target(target, unit_m=UNITS[unit])
    except DrydemError as exc:
        raise click.ClickException(str(exc)) from None
    for note in found.notes:
        click.echo(f"note: {note}", err=True)
    return found


@click.group()
@click.version_option(__version__, prog_name="drydem")
def main() -> None:
    """drydem: discrete element analysis of dry-joint masonry."""


@main.command()
@click.argument("target")
@click.option("--settle", is_flag=True, help="Also cycle to equilibrium under vertical gravity and report the settlement.")
@click.option("--strict", is_flag=True, help="Fail if a wall breaks the competition brief.")
@unit_option
def check(target: str, settle: bool, strict: bool, unit: str) -> None:
    """Validate TARGET (a built-in wall, a wall or model file, or a .wrl/.obj/.stl) and print
    its blocks, contacts and timestep."""
    from drydem.masonry.brief import brief_violations
    from drydem.analysis.support import unsupported

    found = _target(target, unit)
    model = found.model
    try:
        sim = Simulation(model)
    except DrydemError as exc:
        raise click.ClickException(str(exc)) from None
    c = sim.contacts
    movable = model.block_movable
    click.echo(f"model           {found.path}")
    if found.wall is not None:
        violations = brief_violations(found.wall)
        click.echo(f"wall            {found.wall.name} {found.wall.title}: {found.wall.layout.void_ratio:.1%} voids, "
                   + ("meets the competition brief" if not violations else "breaks the brief: " + "; ".join(violations)))
        _fail_if_strict(strict, violations, found)
    click.echo(f"blocks          {model.n_blocks} ({int(movable.sum())} movable, {int((~movable).sum())} fixed)")
    click.echo(f"mass            {model.total_mass:.6g} kg (movable blocks)")
    density = model.contact_density
    click.echo(f"contacts        {len(c.pairs)} face contacts, {c.count} sub-contacts ({density.along} points per length, {density.across} across y)")
    click.echo(f"contact area    {c.area.sum():.6g} m2, tolerance {model.contact_tolerance:.3g} m")
    click.echo(f"joint           {model.joint.stiffness_text}, friction {model.joint.friction:g}")
    mass_note = " (mass scaled)" if model.solver.mass_scaling else ""
    click.echo(f"timestep        {sim.timestep:.4g} s{mass_note}")
    floating = [model.block_name[b] for b in unsupported(model, c)]
    if floating:
        click.echo(f"unsupported     {len(floating)} movable blocks touch nothing and will fall under gravity: "
                   + ", ".join(repr(name) for name in floating[:10]) + (", ..." if len(floating) > 10 else ""), err=True)
    if settle:
        _settle(sim)


def _fail_if_strict(strict: bool, violations: list[str], found: Target) -> None:
    if strict and violations:
        raise click.ClickException(f"{found.path}: breaks the competition brief ({len(violations)} violations)")


def _settle(sim: Simulation) -> None:
    from tqdm import tqdm

    model = sim.model
    start = time.perf_counter()
    with tqdm(desc="settling under gravity", unit=" cycles", leave=False) as bar:

        def progress(cycles, stats):
            bar.update(cycles - bar.n)
            bar.set_postfix(ratio=f"{stats.ratio:.2e}", speed=f"{stats.max_speed:.2e} m/s")

        result = sim.cycle_to_equilibrium(progress=progress)
    elapsed = time.perf_counter() - start
    drop = model.block_centroid[:, 2] - sim.state.position[:, 2]
    status = "converged" if result.converged else "NOT converged"
    click.echo(f"equilibrium     {status} after {result.cycles} cycles ({result.criterion} {result.ratio:.2e}), {elapsed:.2f} s")
    top = int(np.argmax(model.block_centroid[:, 2]))
    click.echo(f"settlement      {drop.max() * 1e3:.4g} mm max, top block {model.block_name[top]!r} {drop[top] * 1e3:.4g} mm")
    if not result.converged:
        raise SystemExit(1)


@dataclass(frozen=True)
class TiltOptions:
    """The model and protocol options of ``drydem tilt``, bundled by :func:`tilt_options`
    (``drydem montecarlo`` takes them too: each of its samples is a tilting analysis)."""

    kn: float | None
    ks: float | None
    friction: float | None
    points: int | None
    density: float | None
    criterion: str | None
    joint_law: dict | None
    increment: float
    adaptive: bool
    predictor: bool
    stop_displacement: float
    loading: str
    monitor: str | None
    max_angle: float

    def model_overrides(self) -> dict:
        """The keywords of :meth:`Model.overridden` these options give (None: the model's)."""
        return dict(kn=self.kn, ks=self.ks, friction=self.friction, points=self.points, density=self.density, criterion=self.criterion,
                    joint_law=self.joint_law)

    def settings(self):
        """The TiltSettings these options give (DrydemError for a value out of its range)."""
        from drydem.analysis.tilt import TiltSettings

        return TiltSettings(increment_deg=self.increment, adaptive=self.adaptive, predictor=self.predictor,
                            stop_displacement_m=self.stop_displacement, loading=self.loading, monitor=self.monitor,
                            max_angle_deg=self.max_angle)


def tilt_options(*, adaptive: bool):
    """The options of :class:`TiltOptions`, handed to the command as one ``tilt`` argument;
    ``adaptive``: the protocol by default (--adaptive or --fixed)."""
    protocol = "adaptive" if adaptive else "fixed"
    options = [
        click.option("--kn", type=float, help="Normal joint stiffness, Pa/m (overrides the model file)."),
        click.option("--ks", type=float, help="Shear joint stiffness, Pa/m."),
        click.option("--friction", type=float, help="Coulomb friction coefficient."),
        click.option("--points", type=int, help="Sub-contact points per length."),
        click.option("--density", type=float, help="Density of every block, kg/m3."),
        click.option("--increment", type=float, default=0.1, show_default=True, help="Tilt step, deg."),
        click.option("--adaptive/--fixed", default=adaptive,
                     help=f"Coarse steps, then bisection down to the increment; or every step one increment (default: {protocol})."),
        click.option("--predictor/--no-predictor", default=True, show_default=True,
                     help="Start each step from the last two equilibria extrapolated (fewer cycles)."),
        click.option("--stop-displacement", type=float, default=0.10, show_default=True,
                     help="Monitored horizontal displacement that ends the run, m."),
        click.option("--criterion", type=click.Choice(CRITERIA), help="Equilibrium criterion (default: the model file's)."),
        click.option("--loading", type=click.Choice(["tilt", "multiplier"]), default="tilt", show_default=True,
                     help="Tilt the gravity or add lambda g horizontally."),
        click.option("--monitor", help="Block whose centroid is monitored (default: the top block nearest the middle)."),
        click.option("--max-angle", type=float, default=80.0, show_default=True, help="Largest tilt tried, deg."),
    ]
    names = [f.name for f in fields(TiltOptions)]

    def decorate(command):
        @functools.wraps(command)
        def bundled(**values):
            return command(tilt=TiltOptions(**{name: values.pop(name) for name in names}), **values)

        bundled = joint_law_options(bundled)
        for option in reversed(options):
            bundled = option(bundled)
        return bundled

    return decorate


@main.command()
@click.argument("target")
@tilt_options(adaptive=False)
@click.option("--out", type=click.Path(path_type=Path), help="Results folder (default: results/TARGET-TIME).")
@click.option("--resume", is_flag=True, help="Go on from the checkpoint in --out (same TARGET and options).")
@click.option("--overwrite", is_flag=True, help="Replace the results of an earlier run in --out (they are kept otherwise).")
@click.option("--vtk", is_flag=True, help="Write a VTK time series for ParaView (OUT/vtk: blocks and sub-contacts).")
@click.option("--save-every", type=click.IntRange(min=1), default=1, show_default=True,
              help="With --vtk: keep every N-th equilibrium state (the states past collapse are all kept).")
@click.option("--video", is_flag=True, help="Also render OUT/collapse.mp4 (GIF if ffmpeg is missing); implies --vtk.")
@unit_option
def tilt(target, tilt: TiltOptions, out, resume, overwrite, vtk, save_every, video, unit) -> None:
    """Tilting-table analysis of TARGET (a built-in wall, a wall or model file, or a
    .wrl/.obj/.stl): collapse angle, pushover curve, Eurocode 8 drift-limit angles, plots.
    Exits 1 when equilibrium could not be reached within max_cycles (no verdict), 130 or 143
    when interrupted (the last equilibrium is kept for --resume)."""
    from tqdm import tqdm

    from drydem.analysis.tilt import NO_EQUILIBRIUM, NO_EQUILIBRIUM_UNDER_GRAVITY, monitor_index, tilt_analysis
    from drydem.engine.checkpoint import load_checkpoint
    from drydem.io.results import PushoverWriter
    from drydem.io.vtk import VtkSeries

    found = _target(target, unit)
    try:
        model = found.model.overridden(**tilt.model_overrides())
        settings = tilt.settings()
        monitor_index(model, tilt.monitor)
        if resume and overwrite:
            raise DrydemError("--resume goes on from the run in --out and --overwrite deletes it: give one of them")
        if resume and (out is None or not (out / CHECKPOINT).is_file()):
            raise DrydemError(f"--resume needs --out DIR holding a {CHECKPOINT} from an earlier run" + (f" ({out} has none)" if out else ""))
        folder = _results_folder(out, found.name, resume=resume, overwrite=overwrite)
        if resume:
            _, saved = load_checkpoint(folder / CHECKPOINT)
    except DrydemError as exc:
        raise click.ClickException(str(exc)) from None
    click.echo(f"{found.name} ({found.path}): {model.n_blocks} blocks, {model.joint.stiffness_text}, "
               f"mu {model.joint.friction:g}, {model.contacts.points_per_length} points per length -> {folder}")
    if resume:
        click.echo(f"resuming from {folder / CHECKPOINT}: last equilibrium at {float(saved['theta_deg']):g} deg "
                   f"({len(saved['records'])} equilibrium states)")
    if model.solver.damping == 0:
        click.echo("warning: [solver] damping = 0: dynamic relaxation has nothing to dissipate energy with and may never "
                   "reach equilibrium", err=True)
    go_on = "the same command plus --resume" if out is not None else f"the same command plus --out {folder} --resume"
    with _signals_interrupt() as received, tqdm(desc="tilting", unit=" cycles", unit_scale=True, leave=False) as bar:

        def progress(theta, cycles, ux):
            bar.update(cycles - bar.n)
            bar.set_postfix_str(f"{theta:.2f} deg, ux {ux * 1e3:.2f} mm")

        try:
            series = VtkSeries(folder / "vtk", model, every=save_every, resume=resume) if vtk or video else None
            result = tilt_analysis(
                model, settings, on_record=PushoverWriter(folder), on_progress=progress, on_frame=series,
                checkpoint=folder / CHECKPOINT, resume=resume,
            )
        except DrydemError as exc:
            raise click.ClickException(str(exc)) from None
        except OSError as exc:
            raise click.ClickException(f"{exc.filename or folder}: cannot write results ({exc.strerror or exc})") from None
        except KeyboardInterrupt:
            saved = f"the last equilibrium is saved in {folder / CHECKPOINT}" if (folder / CHECKPOINT).is_file() else "no equilibrium was reached yet"
            click.echo(f"\ninterrupted ({received.name}); {saved}. Go on with {go_on}", err=True)
            raise SystemExit(128 + received.number) from None
    _tilt_outputs(found, model, result, folder, series)
    if video:
        _render(series.folder, folder / "collapse.mp4", fps=8.0)
    if result.ended_by in (NO_EQUILIBRIUM_UNDER_GRAVITY, NO_EQUILIBRIUM):
        raise SystemExit(1)


#: what ``drydem shake`` writes in its results folder
SHAKE_OUTPUTS = ("summary.json", "history.csv", "history.png", "vtk", "shake.mp4", "shake.gif")
#: what ``drydem montecarlo`` writes in its results folder besides summary.json
MONTECARLO_OUTPUTS = ("samples", "histogram.png")
#: what ``drydem tilt``, ``drydem limit``, ``drydem shake`` and ``drydem montecarlo`` write in
#: their results folders (deleted first by --overwrite, whichever of them wrote them)
RUN_OUTPUTS = ("summary.json", "pushover.csv", "pushover.png", "mechanism.png", CHECKPOINT, CHECKPOINT_PARTIAL, "vtk",
               "collapse.mp4", "collapse.gif") + tuple(name for name in SHAKE_OUTPUTS if name not in ("summary.json", "vtk")) \
    + MONTECARLO_OUTPUTS


def _results_folder(out: Path | None, name: str, *, resume: bool | None = False, overwrite: bool = False) -> Path:
    """``out`` made ready for a run (drydem.io.results.prepare_folder; ``resume`` None for a
    command that cannot resume), or by default a new results/NAME-TIME folder (numbered -2,
    -3, ... if two runs start in the same second)."""
    from drydem.io.results import prepare_folder

    if out is None:
        stem = f"{name}-{datetime.now():%Y%m%d-%H%M%S}"
        out = Path("results") / stem
        for k in itertools.count(2):
            if not out.exists():
                break
            out = Path("results") / f"{stem}-{k}"
    return prepare_folder(out, RUN_OUTPUTS, resume=resume, overwrite=overwrite)


class _Received:
    """The signal that interrupted a command: its name and number (SIGINT until told otherwise)."""

    name, number = "SIGINT", int(signal.SIGINT)


@contextmanager
def _signals_interrupt():
    """SIGTERM (a kill, a scheduler's time limit) interrupts like Ctrl-C: KeyboardInterrupt,
    so that the command says what it saved and how to go on. Yields what was received."""
    received = _Received()

    def interrupt(number, frame):
        received.name, received.number = signal.Signals(number).name, number
        raise KeyboardInterrupt

    previous = signal.signal(signal.SIGTERM, interrupt)
    try:
        yield received
    finally:
        signal.signal(signal.SIGTERM, previous)


def _tilt_outputs(found: Target, model: Model, result, folder: Path, series) -> None:
    """Write summary.json and the figures of a tilting analysis and print what it found."""
    from drydem.io.results import tilt_summary, write_summary
    from drydem.report.plots import mechanism_figure, pushover_figure

    write_summary(folder, tilt_summary(result, model))
    pushover_figure(result, folder / "pushover.png", title=found.name)
    last = result.last_equilibrium_deg
    lost_by_then = frozenset(name for name, theta in result.lost_blocks if last is not None and theta <= last)
    states = [
        ("last equilibrium" if last is not None else "under gravity", result.collapse_state or result.final_state, lost_by_then),
        (f"past collapse ({result.ended_by})", result.final_state, frozenset(name for name, _ in result.lost_blocks)),
    ]
    mechanism_figure(model, states, folder / "mechanism.png", monitored=result.monitored_block)
    for line in _tilt_verdict(result, model):
        click.echo(line)
    dls = result.drift_limit_angles_deg
    click.echo("drift limits    " + ", ".join(f"{float(k):.2%}: " + ("not reached" if v is None else f"{v:.2f} deg") for k, v in dls.items()))
    if result.lost_blocks and result.stable_under_gravity:
        first = min(theta for _, theta in result.lost_blocks)
        click.echo(f"lost blocks     {len(result.lost_blocks)} fell out of the model, the first at {first:.2f} deg (listed in summary.json)")
    click.echo(f"cycles          {result.cycles} in {result.runtime_s:.1f} s; results in {folder}")
    if series is not None:
        click.echo(f"vtk             {len(series.rows)} states in {series.folder} (open blocks.pvd and contacts.pvd in ParaView)")


def _tilt_verdict(result, model: Model) -> list[str]:
    """What the analysis found, in words that claim no more than it showed."""
    from drydem.analysis.tilt import MAXIMUM_ANGLE, NO_EQUILIBRIUM, NO_EQUILIBRIUM_UNDER_GRAVITY

    fell = ", ".join(repr(name) for name, _ in result.lost_blocks[:5]) + (", ..." if len(result.lost_blocks) > 5 else "")
    if result.stable_under_gravity is False:
        what = f"{fell} fell" if fell else (f"the monitored block {result.monitored_block!r} moved "
                                           f"{result.settings.stop_displacement_m:g} m (the stop displacement)")
        return [f"the model cannot stand under its own weight: {what} (state in mechanism.png)"]
    if result.ended_by == NO_EQUILIBRIUM_UNDER_GRAVITY:
        return [f"no equilibrium under gravity within [solver] max_cycles = {model.solver.max_cycles}: no verdict on whether it "
                "stands; raise max_cycles (or check damping) and run again"]
    if result.ended_by == MAXIMUM_ANGLE:
        return [f"no collapse up to {result.settings.max_angle_deg} deg"]
    if result.ended_by == NO_EQUILIBRIUM:
        return [f"last equilibrium {result.last_equilibrium_deg:.2f} deg; the next step reached no equilibrium within [solver] "
                f"max_cycles = {model.solver.max_cycles} and did not collapse either: no collapse angle "
                "(raise max_cycles to decide)"]
    return [f"collapse angle  {result.collapse_angle_deg:.2f} deg (load multiplier {result.load_multiplier:.4f}; ended by {result.ended_by})"]


#: the pulses of ``drydem shake --pulse`` (drydem.analysis.shake.PULSES, not imported here to keep
#: the command line quick to start; a test holds them equal)
PULSE_KINDS = ("one-sine", "sine", "ricker")
#: the frame rate of the ``drydem shake --video`` (one frame per kept output interval)
SHAKE_FPS = 25.0
#: the ``drydem shake`` options of the settings of drydem.analysis.shake.ShakeSettings they set
SHAKE_OPTIONS = {"duration_s": "--duration", "output_interval_s": "--output-interval", "contact_damping_ratio": "--damping-ratio",
                 "rayleigh_mass_per_s": "--rayleigh-mass", "rayleigh_stiffness_s": "--rayleigh-stiffness"}
#: the ``drydem shake`` options of the arguments of drydem.analysis.shake.pulse they set
PULSE_OPTIONS = {"amplitude_m_s2": "--amplitude", "frequency_hz": "--frequency", "cycles": "--cycles", "direction": "--direction"}


class _Restitution(click.ParamType):
    """``--restitution``: a number, or the word housner."""

    name = "R|housner"

    def convert(self, value, param, ctx):
        if not isinstance(value, str):
            return value
        if value.strip().lower() == "housner":
            return "housner"
        try:
            return float(value)
        except ValueError:
            self.fail(f"{value!r} is neither a number nor 'housner'", param, ctx)


@main.command()
@click.argument("target")
@click.option("--motion", type=click.Path(path_type=Path),
              help="Ground motion record: a CSV file with the header time_s,acc_x_m_s2[,acc_y_m_s2,acc_z_m_s2] (s, m/s2), or a "
                   "PEER NGA .AT2 file (in g).")
@click.option("--direction", type=click.Choice(["x", "y", "z"]), help="Direction of an .AT2 record or of a --pulse (default x); a CSV "
                                                                       "file names its directions in its header.")
@click.option("--scale", type=float, default=1.0, show_default=True, help="Multiplies the motion.")
@click.option("--baseline/--no-baseline", default=None,
              help="Baseline-correct the --motion record (the default): a linear baseline subtracted from the acceleration brings "
                   "the table to rest (zero velocity and displacement) at the record's end. Pulses are analytic and never corrected.")
@click.option("--pulse", type=click.Choice(PULSE_KINDS), help="An analytic pulse instead of a record (with --amplitude and --frequency).")
@click.option("--amplitude", type=float, help="Peak acceleration of the --pulse, m/s2 (negative: the other way).")
@click.option("--frequency", type=float, help="Frequency of the --pulse, Hz (ricker: its peak frequency).")
@click.option("--cycles", type=int, help="Periods of a --pulse sine (default 1).")
@click.option("--duration", type=float, help="Analysed time, s (default: the motion's duration; beyond it the table is no longer accelerated).")
@click.option("--output-interval", type=float, default=0.005, show_default=True,
              help="A row of history.csv (and a VTK state) every this many seconds of model time.")
@click.option("--restitution", type=_Restitution(), metavar="R|housner",
              help="Target coefficient of restitution of the monitored block's rocking impacts, in (0, 1], or 'housner' "
                   "(1 - 1.5 sin^2 alpha): the contact damping ratio is calibrated to it by free rocking of that block.")
@click.option("--damping-ratio", type=float,
              help="Contact damping ratio (of critical), set directly instead of --restitution (default: 0.5 if neither is given).")
@click.option("--rayleigh-mass", type=float, default=0.0, show_default=True, help="Rayleigh damping, mass term alpha, 1/s.")
@click.option("--rayleigh-stiffness", type=float, default=0.0, show_default=True, help="Rayleigh damping, stiffness term beta, s.")
@click.option("--kn", type=float, help="Normal joint stiffness, Pa/m (overrides the model file).")
@click.option("--ks", type=float, help="Shear joint stiffness, Pa/m.")
@click.option("--friction", type=float, help="Coulomb friction coefficient.")
@click.option("--points", type=int, help="Sub-contact points per length.")
@click.option("--density", type=float, help="Density of every block, kg/m3.")
@joint_law_options
@click.option("--monitor", help="Block whose response is recorded (default: the top block nearest the middle).")
@click.option("--out", type=click.Path(path_type=Path), help="Results folder (default: results/TARGET-TIME).")
@click.option("--overwrite", is_flag=True, help="Replace the results of an earlier run in --out (they are kept otherwise).")
@click.option("--vtk", is_flag=True, help="Write a VTK time series for ParaView (OUT/vtk: blocks and sub-contacts, in model time).")
@click.option("--save-every", type=click.IntRange(min=1), default=1, show_default=True,
              help="With --vtk: keep the state of every N-th output interval.")
@click.option("--video", is_flag=True, help="Also render OUT/shake.mp4 (GIF if ffmpeg is missing), a frame per kept state at "
                                             f"{SHAKE_FPS:g} frames per second (--save-every thins them); implies --vtk.")
@unit_option
def shake(target, motion, direction, scale, baseline, pulse, amplitude, frequency, cycles, duration, output_interval, restitution,
          damping_ratio, rayleigh_mass, rayleigh_stiffness, kn, ks, friction, points, density, joint_law, monitor, out, overwrite, vtk,
          save_every, video, unit) -> None:
    """Shaking-table analysis of TARGET (a built-in wall, a wall or model file, or a
    .wrl/.obj/.stl): the time history of the model under a ground motion, a --motion record or
    a --pulse (give one), from rest under gravity. Writes history.csv (the monitored block's
    response, row by row as the run goes), history.png and summary.json (whether and when blocks
    fell, peak and residual response, PGA, damping). Exits 130 or 143 when interrupted (the
    history so far is kept)."""
    from tqdm import tqdm

    from drydem.analysis.shake import HOUSNER, ShakeSettings, shake_analysis
    from drydem.analysis.shake.run import housner_target
    from drydem.analysis.tilt import monitor_index
    from drydem.io.results import HistoryWriter
    from drydem.io.vtk import ShakeSeries

    try:
        _shake_motion_options(motion, pulse, amplitude, frequency, cycles, baseline)
    except DrydemError as exc:
        raise click.ClickException(str(exc)) from None
    found = _target(target, unit)
    try:
        ground, corrected = _shake_motion(motion, direction, scale, baseline, pulse, amplitude, frequency, cycles)
        model = found.model.overridden(kn=kn, ks=ks, friction=friction, points=points, density=density, joint_law=joint_law)
        values = dict(duration_s=duration, output_interval_s=output_interval, restitution=restitution, contact_damping_ratio=damping_ratio,
                      rayleigh_mass_per_s=rayleigh_mass, rayleigh_stiffness_s=rayleigh_stiffness, monitor=monitor)
        _check_shake_options(values)
        settings = ShakeSettings(motion=ground, **values)
        monitored = monitor_index(model, monitor)
        if settings.restitution == HOUSNER:
            housner_target(model, monitored)  # refused before the run: a squat block does not rock
        folder = _results_folder(out, found.name, resume=None, overwrite=overwrite)
    except DrydemError as exc:
        raise click.ClickException(str(exc)) from None
    click.echo(f"{found.name} ({found.path}): {model.n_blocks} blocks, {model.joint.stiffness_text}, "
               f"mu {model.joint.friction:g}, {model.contacts.points_per_length} points per length; {ground.name}, "
               f"PGA {ground.pga_m_s2:.4g} m/s2, {settings.analysed_s:g} s -> {folder}")
    try:
        live = _LiveHistory(HistoryWriter(folder), ShakeSeries(folder / "vtk", model, every=save_every) if vtk or video else None)
    except OSError as exc:
        raise click.ClickException(f"{exc.filename or folder}: cannot write results ({exc.strerror or exc})") from None
    total = settings.analysed_s
    bar_format = "{l_bar}{bar}| {n:.3f}/{total:.3f} s [{elapsed}<{remaining}{postfix}]"
    with _signals_interrupt() as received, tqdm(total=total, desc="shaking", unit=" s", bar_format=bar_format, leave=False) as bar:

        def progress(time_s, cycles, rotation_rad):
            bar.update(min(time_s, total) - bar.n)
            bar.set_postfix_str(f"rotation {rotation_rad:.3g} rad")

        try:
            result = shake_analysis(model, settings, on_progress=progress, on_frame=live)
        except DrydemError as exc:
            raise click.ClickException(str(exc)) from None
        except OSError as exc:
            raise click.ClickException(f"{exc.filename or folder}: cannot write results ({exc.strerror or exc})") from None
        except KeyboardInterrupt:
            click.echo(f"\ninterrupted ({received.name}) at {live.time_s:.3f} s of {total:g} s; the history so far is in "
                       f"{live.writer.path} ({live.writer.rows} rows), "
                       "no summary.json", err=True)
            raise SystemExit(128 + received.number) from None
    try:
        _shake_outputs(found, model, result, folder, live.series, scale=scale, baseline_corrected=corrected)
    except DrydemError as exc:
        raise click.ClickException(str(exc)) from None
    except OSError as exc:
        raise click.ClickException(f"{exc.filename or folder}: cannot write results ({exc.strerror or exc})") from None
    if video:
        _render(live.series.folder, folder / "shake.mp4", fps=SHAKE_FPS)


def _shake_motion_options(motion, pulse, amplitude, frequency, cycles, baseline) -> None:
    """DrydemError unless the options give the ground motion one way: --motion FILE, or --pulse
    KIND with --amplitude and --frequency (and the options of that way only)."""
    if motion is not None and pulse is not None:
        raise DrydemError("give one ground motion: --motion FILE (a record) or --pulse KIND, not both")
    if motion is None and pulse is None:
        raise DrydemError("no ground motion: give --motion FILE (a CSV or PEER .AT2 record) or --pulse "
                          f"{'|'.join(PULSE_KINDS)} with --amplitude A (m/s2) and --frequency F (Hz)")
    if pulse is None:
        given = [name for name, value in (("--amplitude", amplitude), ("--frequency", frequency), ("--cycles", cycles)) if value is not None]
        if given:
            raise DrydemError(f"{', '.join(given)} appl{'ies' if len(given) == 1 else 'y'} to a --pulse only; a --motion record "
                              "is changed by --scale")
        return
    missing = [name for name, value in (("--amplitude A (m/s2)", amplitude), ("--frequency F (Hz)", frequency)) if value is None]
    if missing:
        raise DrydemError(f"--pulse {pulse} needs {' and '.join(missing)}")
    if baseline:
        raise DrydemError("--baseline corrects a --motion record; a pulse is analytic and is not corrected")


def _shake_motion(motion, direction, scale, baseline, pulse, amplitude, frequency, cycles):
    """The ground motion the options give, and whether it was baseline-corrected; a DrydemError
    naming the file or the option at fault."""
    from types import SimpleNamespace

    from drydem.analysis.shake.motion import PULSE_RULES, pulse as make_pulse, read_motion
    from drydem.model.parameters import Range, field_problems, refuse

    refuse([problem for problem in [Range(None, None).problem(scale, "--scale")] if problem])
    if pulse is not None:
        values = dict(amplitude_m_s2=amplitude, frequency_hz=frequency, cycles=1 if cycles is None else cycles,
                      direction=direction or "x")
        refuse(field_problems(SimpleNamespace(**values), {field: PULSE_RULES[field] for field in values}, PULSE_OPTIONS.get))
        if pulse != "sine" and values["cycles"] != 1:
            raise DrydemError(f"--cycles {cycles}: a {pulse} pulse is one period; --pulse sine repeats it")
        ground, corrected = make_pulse(pulse, **values), False
    else:
        ground = read_motion(motion, direction)
        corrected = baseline is not False
        if corrected:
            ground = ground.baseline_corrected()
    return (ground if scale == 1.0 else ground.scaled(scale)), corrected


def _check_shake_options(values: dict) -> None:
    """A DrydemError naming every option of ``values`` (ShakeSettings' fields) out of its range."""
    from types import SimpleNamespace

    from drydem.analysis.shake.settings import HOUSNER, RESTITUTION, SETTING_RULES
    from drydem.model.parameters import field_problems, refuse

    rules = {field: SETTING_RULES[field] for field in SHAKE_OPTIONS}
    problems = field_problems(SimpleNamespace(**values), rules, SHAKE_OPTIONS.get, optional=("duration_s", "contact_damping_ratio"))
    restitution = values["restitution"]
    if restitution is not None and restitution != HOUSNER:
        problems += [problem for problem in [RESTITUTION.problem(restitution, "--restitution")] if problem]
    refuse(problems)
    if restitution is not None and values["contact_damping_ratio"] is not None:
        raise DrydemError("--damping-ratio and --restitution both given: the damping ratio is calibrated to the restitution; give one")


class _LiveHistory:
    """The rows of history.csv as the analysis gives its frames (``shake_analysis(...,
    on_frame=live)``), and the frames to the VTK series if there is one."""

    def __init__(self, writer, series):
        self.writer, self.series = writer, series
        self.time_s = 0.0

    def __call__(self, frame) -> None:
        self.writer.row(frame.time_s, frame.ground_acceleration_m_s2, frame.displacement_m, frame.rotation_rad)
        self.time_s = frame.time_s
        if self.series is not None:
            self.series(frame)


def _shake_outputs(found: Target, model: Model, result, folder: Path, series, *, scale: float, baseline_corrected: bool) -> None:
    """Write history.csv whole, summary.json and history.png of a shaking-table analysis and
    print what it found."""
    import math

    from drydem.analysis.shake import HOUSNER, MONITOR_FELL
    from drydem.io.results import fall_rule, shake_summary, write_history_csv, write_summary
    from drydem.report.plots import history_figure

    write_history_csv(folder, result.history)
    write_summary(folder, shake_summary(result, model, scale=scale, baseline_corrected=baseline_corrected))
    history_figure(result.history, folder / "history.png", title=f"{found.name}: {result.settings.motion.name}",
                   monitored=result.monitored_block, fallen=result.fallen_blocks)
    settings, motion = result.settings, result.settings.motion
    if result.fallen_blocks:
        fell = "; ".join(f"{name!r} at {time_s:.3f} s ({rule})" for name, time_s, rule in result.fallen_blocks[:5])
        more = f"; {len(result.fallen_blocks) - 5} more in summary.json" if len(result.fallen_blocks) > 5 else ""
        count = len(result.fallen_blocks)
        click.echo(f"overturned      yes: {count} block{'s' if count > 1 else ''} fell: {fell}{more}")
    else:
        click.echo(f"overturned      no: no block fell ({fall_rule(settings)})")
    if result.ended_by == MONITOR_FELL:
        click.echo(f"stopped         at {result.duration_s:.3f} s of {settings.analysed_s:g} s: the monitored block "
                   f"{result.monitored_block!r} fell")
    click.echo(f"rotation        max {result.max_rotation_rad:.4g} rad ({math.degrees(result.max_rotation_rad):.3g} deg), "
               f"monitored block {result.monitored_block!r}")
    click.echo(f"displacement    max {result.max_displacement_m * 1e3:.4g} mm, residual {result.residual_displacement_m * 1e3:.4g} mm "
               "(horizontal, relative to the table)")
    click.echo(f"ground motion   PGA {motion.pga_m_s2:.4g} m/s2 ({motion.pga_g:.3g} g): {motion.name}, {motion.duration_s:g} s")
    if result.restitution is None:
        given = "given" if settings.contact_damping_ratio is not None else "the default"
        damping = f"contact damping ratio {result.contact_damping_ratio:.4g} ({given})"
    else:
        housner = ", Housner's" if settings.restitution == HOUSNER else ""
        damping = f"contact damping ratio {result.contact_damping_ratio:.4g}, calibrated to the restitution {result.restitution:.4g}{housner}"
    if settings.rayleigh_mass_per_s or settings.rayleigh_stiffness_s:
        damping += f"; Rayleigh alpha {settings.rayleigh_mass_per_s:g} 1/s, beta {settings.rayleigh_stiffness_s:g} s"
    click.echo(f"damping         {damping}")
    click.echo(f"cycles          {result.cycles} (timestep {result.timestep_s:.3g} s) in {result.runtime_s:.1f} s; results in {folder}")
    if series is not None:
        click.echo(f"vtk             {len(series.rows)} states in {series.folder} (open blocks.pvd and contacts.pvd in ParaView)")


@main.command()
@click.argument("target")
@click.option("--non-associative", is_flag=True, help="Friction without dilatancy (iterative LP of Gilbert et al. 2006).")
@click.option("--friction", type=float, help="Coulomb friction coefficient (overrides the model file).")
@click.option("--out", type=click.Path(path_type=Path), help="Results folder (default: results/TARGET-limit-TIME).")
@click.option("--overwrite", is_flag=True, help="Replace the results of an earlier run in --out (they are kept otherwise).")
@unit_option
def limit(target, non_associative, friction, out, overwrite, unit) -> None:
    """Limit analysis of TARGET: the largest horizontal load multiplier (tilt angle atan(lambda))
    that rigid blocks can carry, with its collapse mechanism. Each stage is printed to stderr
    as it starts, with the time so far (the LP of a large wall takes minutes)."""
    from drydem.analysis.limit import LimitSettings, limit_analysis
    from drydem.analysis.tilt import wall_height
    from drydem.io.results import limit_summary, write_summary
    from drydem.report.plots import mechanism_figure

    found = _target(target, unit)
    settings = LimitSettings(non_associative=non_associative)
    try:  # before the analysis, which can take minutes
        model = found.model.overridden(friction=friction)
        out = _results_folder(out, f"{found.name}-limit", resume=None, overwrite=overwrite)
    except DrydemError as exc:
        raise click.ClickException(str(exc)) from None
    start = time.perf_counter()

    def progress(stage: str) -> None:
        click.echo(f"[{time.perf_counter() - start:7.1f} s] {stage}", err=True)

    try:
        result = limit_analysis(model, settings, on_progress=progress)
    except DrydemError as exc:
        raise click.ClickException(str(exc)) from None
    runtime = time.perf_counter() - start
    write_summary(out, limit_summary(result, settings, model, runtime))
    label = "LA-NA" if non_associative else "LA-A"
    moved = result.mechanism_state(model, 0.1 * wall_height(model))
    mechanism_figure(model, [(f"{label} mechanism (scaled)", moved, frozenset())], out / "mechanism.png")
    click.echo(f"{found.name}: {label} load multiplier {result.load_multiplier:.4f}, collapse angle {result.collapse_angle_deg:.2f} deg")
    if non_associative:
        state = "converged" if result.converged else "NOT converged (last iterate reported)"
        click.echo(f"iterations      {result.iterations} ({state}): lambda {result.history[0]:.4f} (LA-A) -> {result.history[-1]:.4f}")
    click.echo(f"solver          {result.status}; {runtime:.1f} s; results in {out}")


@main.command()
@click.argument("result_dir", type=click.Path(exists=True, file_okay=False, path_type=Path))
@click.option("--out", "-o", type=click.Path(dir_okay=False, path_type=Path), help="Video file, .mp4 or .gif (default: RESULT_DIR/collapse.mp4).")
@click.option("--fps", type=click.FloatRange(min=0.1), default=8.0, show_default=True, help="Frames per second.")
def animate(result_dir: Path, out: Path | None, fps: float) -> None:
    """Render the VTK series of a `drydem tilt --vtk` run (RESULT_DIR or RESULT_DIR/vtk) to a video."""
    folder = result_dir / "vtk" if (result_dir / "vtk").is_dir() else result_dir
    _render(folder, out or result_dir / "collapse.mp4", fps=fps)


def _render(folder: Path, path: Path, *, fps: float) -> None:
    from drydem.report.animation import render_video

    try:
        written = render_video(folder, path, fps=fps)
    except DrydemError as exc:
        raise click.ClickException(str(exc)) from None
    click.echo(f"video           {written}")


@main.command()
@click.argument("study_file")
@click.option("--out", type=click.Path(path_type=Path), help="Results folder (default: results/STUDY-NAME).")
@workers_option
@scheduler_option
@click.option("--retry-failed", is_flag=True, help="Run again the runs recorded as failed.")
def sweep(study_file: str, out: Path | None, workers: int | None, scheduler: str | None, retry_failed: bool) -> None:
    """Run a parametric study (STUDY_FILE, TOML, or a shipped study: savalle2022): every run a
    tilting, limit or shaking-table analysis, each recorded in OUT/runs as it finishes; run again to go on
    where it stopped (corrupt records are run again). The whole study is checked before the
    first run; two sweeps on one OUT share its runs."""
    from tqdm import tqdm

    from drydem.masonry import studies
    from drydem.files import writable_folder
    from drydem.parametric.study import load_study
    from drydem.parametric.sweep import pending
    from drydem.parametric.sweep import sweep as run_sweep
    from drydem.parametric.workers import open_workers

    path = Path(study_file) if Path(study_file).is_file() else studies.find(study_file)
    if path is None:
        raise click.ClickException(f"{study_file}: no such study file, and not a shipped study (savalle2022)")
    try:
        study = load_study(path)
    except DrydemError as exc:
        raise click.ClickException(str(exc)) from None
    try:
        out = writable_folder(out or Path("results") / study.name)
    except DrydemError as exc:
        raise click.ClickException(str(exc)) from None
    plan = pending(study.runs, out, retry_failed=retry_failed)
    click.echo(f"{study.name}: {len(study.runs)} runs, {plan.recorded} already recorded in {out}")
    for corrupt in plan.corrupt:
        click.echo(f"corrupt record, run again: {corrupt}", err=True)
    failures = []
    try:  # a DrydemError: a scheduler that does not answer, or runs the executor lost
        with open_workers(workers, scheduler) as pool, _signals_interrupt() as received, \
                tqdm(total=len(plan.todo), desc="runs", unit=" run") as bar:
            bar.write(f"running {len(plan.todo)} on {pool.where}")

            def done(record):
                bar.update(1)
                if record["status"] == "failed":
                    failures.append(f"{record['id']}: {record['error']}")
                    bar.set_postfix(failed=len(failures))

            try:
                outcome = run_sweep(study.runs, out, pool.executor, retry_failed=retry_failed, in_flight=pool.slots, on_done=done,
                                    on_other=lambda spec: bar.update(1))
            except KeyboardInterrupt:
                click.echo(f"\ninterrupted ({received.name}); the finished runs are recorded in {out}; the same command goes on", err=True)
                raise SystemExit(128 + received.number) from None
    except DrydemError as exc:
        raise click.ClickException(str(exc)) from None
    for failure in failures:
        click.echo(f"failed: {failure}", err=True)
    click.echo(f"{outcome.finished} runs done ({outcome.failed} failed), {outcome.skipped} skipped; records in {out / 'runs'}")
    if outcome.elsewhere:
        click.echo(f"{outcome.elsewhere} runs left to another sweep working on {out} (it holds their claims, runs/*.lock); "
                   "run this command again once it has finished to check that every run is recorded")


@main.command()
@click.argument("results_dir", type=click.Path(exists=True, file_okay=False, path_type=Path))
@click.option("--out", type=click.Path(file_okay=False, path_type=Path), help="Report folder (default: RESULTS_DIR/report).")
def report(results_dir: Path, out: Path | None) -> None:
    """Write the report of a study (Markdown, HTML, PNG figures in the style of the paper);
    corrupt records are left out and named."""
    from drydem.report.study import build_report

    try:
        written = build_report(results_dir, out)
    except DrydemError as exc:
        raise click.ClickException(str(exc)) from None
    except OSError as exc:
        raise click.ClickException(f"{exc.filename}: cannot write the report ({exc.strerror})") from None
    for corrupt in written.corrupt:
        click.echo(f"corrupt record left out: {corrupt}", err=True)
    click.echo(f"report          {written.markdown} and {written.html}")


@main.command()
@click.argument("results_dir", type=click.Path(path_type=Path))
@click.option("--designs", default="WD1,WD2,WD3,WD4,WD5,WD6,WD7", show_default=True, help="Walls to fit, comma-separated.")
@click.option("--kn-min", type=float, default=1e7, show_default=True, help="Smallest kn searched, Pa/m.")
@click.option("--kn-max", type=float, default=1e9, show_default=True, help="Largest kn searched, Pa/m.")
@click.option("--ks-ratio", type=float, default=1.0, show_default=True, help="ks = ratio x kn.")
@click.option("--increment", type=float, default=0.1, show_default=True, help="Tilt step of the (adaptive) runs, deg.")
@joint_law_options
@workers_option
@scheduler_option
def calibrate(results_dir, designs, kn_min, kn_max, ks_ratio, increment, joint_law, workers, scheduler) -> None:
    """Find the kn that best reproduces the experimental collapse angles (paper Table 1) of
    DESIGNS, reusing and adding runs in RESULTS_DIR (the paper's post-diction, Section 4.4);
    every option is checked before anything runs. With a stress-dependent joint law
    (--joint-model and its keys), the law's shape is kept and its kn (ks = ratio x kn) fitted."""
    from drydem.parametric.calibrate import StiffnessSearch, calibrate_stiffness
    from drydem.files import writable_folder
    from drydem.parametric.workers import open_workers

    search = StiffnessSearch(tuple(d.strip() for d in designs.split(",") if d.strip()), kn_min, kn_max, ks_ratio, increment, joint_law)
    problems = search.problems(name=lambda field: "--" + field.replace("_", "-"))
    if problems:
        raise click.ClickException("\n".join(problems))
    try:
        writable_folder(results_dir)
    except DrydemError as exc:
        raise click.ClickException(str(exc)) from None
    law = f" of the joint law {joint_law}" if joint_law else ""
    click.echo(f"calibrating kn{law} over [{kn_min:.3g}, {kn_max:.3g}] Pa/m on {', '.join(search.designs)} (runs kept in {results_dir})")

    def evaluated(kn, error, outcome):
        for corrupt in outcome.corrupt:
            click.echo(f"corrupt record, run again: {corrupt}", err=True)
        click.echo(f"  kn {kn:10.4g} Pa/m   mean absolute error {error:.2%}")

    try:  # a DrydemError: a scheduler that does not answer, or a kn's runs without an angle
        with open_workers(workers, scheduler) as pool, _signals_interrupt() as received:
            click.echo(f"running on {pool.where}")
            try:
                result = calibrate_stiffness(search, results_dir, pool.executor, in_flight=pool.slots, on_evaluation=evaluated)
            except KeyboardInterrupt:
                click.echo(f"\ninterrupted ({received.name}); the finished runs are recorded in {results_dir}; the same command reuses them",
                           err=True)
                raise SystemExit(128 + received.number) from None
    except DrydemError as exc:
        raise click.ClickException(str(exc)) from None
    click.echo(f"best kn         {result.best_kn:.4g} Pa/m (ks = {ks_ratio:g} kn): mean absolute error {result.best_error:.2%}")


@main.command(name="designs")
def list_designs() -> None:
    """List the built-in walls: WD1-WD7 (reconstructions of the seed paper's competition walls)
    and the examples, with their void ratio, block count and the competition-brief check."""
    from drydem.masonry.brief import brief_violations

    click.echo(f"{'name':<16} {'title':<28} {'voids':>6} {'blocks':>6}  brief")
    for name in designs.names():
        wall = _target(name).wall
        violations = brief_violations(wall)
        verdict = "ok" if not violations else "breaks it: " + "; ".join(violations)
        click.echo(f"{name:<16} {wall.title[:28]:<28} {wall.layout.void_ratio:>6.1%} {len(wall.layout.solid_units):>6}  {verdict}")
    click.echo("WD1-WD7 are reconstructions that obey the brief, not the original drawings (drydem show NAME draws one).")


def _amplitude_mm(ctx, param, value):
    """An imperfection amplitude, mm: not given (None), or a finite number >= 0."""
    if value is not None and not (np.isfinite(value) and value >= 0.0):
        raise click.BadParameter(f"{value!r}: must be a finite number >= 0 (mm)")
    return value


def _factor(ctx, param, value):
    """A drawing factor: a finite number > 0."""
    if not (np.isfinite(value) and value > 0.0):
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
        click.option("--seed", type=click.IntRange(min=0), default=0, show_default=True, help="Seed of the imperfections' random draws."),
        click.option("--height-sd", type=float, metavar="MM", callback=_amplitude_mm,
                     help="Imperfect bricks: standard deviation of each brick's height, mm."),
        click.option("--height-distribution", type=click.Choice(["normal", "uniform"]), default="normal", show_default=True,
                     help="Distribution of the heights (uniform: the same standard deviation)."),
        click.option("--flatness-sd", type=float, metavar="MM", callback=_amplitude_mm,
                     help="Imperfect bricks: each bed face tilted along the wall, its edges this standard deviation off its mid-line, mm."),
        click.option("--misalignment-sd", type=float, metavar="MM", callback=_amplitude_mm,
                     help="Imperfect bricks: standard deviation of each brick's placement along the wall, mm."),
    ]
    for option in reversed(options):
        command = option(command)
    return command


def imperfections_from_options(height_sd: float | None, height_distribution: str, flatness_sd: float | None,
                               misalignment_sd: float | None) -> Imperfections | None:
    """The imperfections the options of :func:`imperfection_options` ask for (an amplitude not
    given is zero); None where no amplitude is given: the perfect wall."""
    amplitudes = {"height_sd_mm": height_sd, "flatness_sd_mm": flatness_sd, "misalignment_sd_mm": misalignment_sd}
    if all(value is None for value in amplitudes.values()):
        return None
    try:
        return Imperfections(height_distribution=height_distribution,
                             **{name: 0.0 if value is None else value for name, value in amplitudes.items()})
    except DrydemError as exc:
        raise click.ClickException(str(exc)) from None


def _imperfect_drawing(found: Target, imperfections: Imperfections, seed: int, factor: float) -> tuple[Model, str]:
    """The wall of ``found`` with imperfect bricks, deviations ``factor`` times larger
    (drydem.masonry.imperfections.exaggerated_model), and a line saying so for the title."""
    from drydem.masonry.imperfections import exaggerated_model

    if found.wall is None:
        raise click.ClickException(f"{found.path}: imperfect bricks (--height-sd, --flatness-sd, --misalignment-sd) need a brick "
                                   "layout: a wall file or a built-in wall, not a model file or a mesh")
    try:
        imperfections.check_for(found.wall.brick, found.wall.source, name=IMPERFECTION_OPTIONS.__getitem__)
        model, used = exaggerated_model(found.wall, imperfections, seed, factor)
    except DrydemError as exc:
        raise click.ClickException(str(exc)) from None
    capped = "" if used == factor else f" (not x{factor:g}: bricks keep half their height)"
    return model, f"imperfect bricks, seed {seed}, deviations x{used:.3g}{capped}\n{imperfections}"


@main.command()
@click.argument("target")
@click.option("--out", "-o", type=click.Path(dir_okay=False, path_type=Path), help="PNG file (default: TARGET.png here).")
@click.option("--strict", is_flag=True, help="Fail if a wall breaks the competition brief.")
@unit_option
@imperfection_options
@click.option("--exaggerate", type=float, default=1.0, show_default=True, metavar="FACTOR", callback=_factor,
              help="Draw the imperfections' deviations FACTOR times larger (the same draws), so that a 0.1 mm scatter shows.")
def show(target: str, out: Path | None, strict: bool, unit: str, seed: int, height_sd: float | None, height_distribution: str,
         flatness_sd: float | None, misalignment_sd: float | None, exaggerate: float) -> None:
    """Draw TARGET as built (bricks, half bricks, headers, lintel, voids, the monitored block) to
    a PNG (or another format matplotlib writes, by the suffix), written whole or not at all.
    With --height-sd, --flatness-sd or --misalignment-sd, draw a wall's bricks imperfect, drawn
    from --seed (drydem.masonry.imperfections), their deviations --exaggerate times larger."""
    from drydem.analysis.tilt import monitored_block
    from drydem.masonry.brief import brief_violations
    from drydem.files import replaced_atomically, writable
    from drydem.report.plots import figure_path, layout_figure

    imperfections = imperfections_from_options(height_sd, height_distribution, flatness_sd, misalignment_sd)
    found = _target(target, unit)
    model, wall = found.model, found.wall
    title = found.name if wall is None else f"{wall.name} {wall.title}: {wall.layout.void_ratio:.1%} voids"
    voids = wall.layout.void_outlines(wall.brick) if wall is not None else []
    if imperfections is not None:
        model, note = _imperfect_drawing(found, imperfections, seed, exaggerate)
        title, voids = f"{title}\n{note}", []  # the voids' outlines are the perfect wall's
    monitored = model.block_name[monitored_block(model)]
    out = out or Path(f"{found.name}.png")
    kinds = wall.layout.kinds() if wall is not None else None
    try:
        with replaced_atomically(writable(figure_path(out))) as partial:
            layout_figure(model, partial, kinds=kinds, voids=voids, monitored=monitored, title=title)
    except DrydemError as exc:
        raise click.ClickException(str(exc)) from None
    click.echo(f"{found.name}: {model.n_blocks} blocks, monitored block {monitored} -> {out}")
    if wall is not None:
        violations = brief_violations(wall)
        for violation in violations:
            click.echo(f"brief: {violation}", err=True)
        _fail_if_strict(strict, violations, found)


@main.command()
@click.argument("target")
@click.argument("output", type=click.Path(dir_okay=False, path_type=Path))
@unit_option
def export(target: str, output: Path, unit: str) -> None:
    """Write TARGET's blocks to OUTPUT: a model file (.toml), ParaView (.vtu) or a mesh (.obj,
    .stl: block names, shapes and fixed blocks; not the material, joint, contacts, supports or
    solver, which only a .toml keeps). OUTPUT is written whole or not at all."""
    from drydem.io.mesh import write_mesh
    from drydem.io.model_file import save_model
    from drydem.files import replaced_atomically, writable
    from drydem.io.vtk import write_vtu

    writers = {".toml": save_model, ".vtu": write_vtu, ".obj": write_mesh, ".stl": write_mesh}
    writer = writers.get(output.suffix.lower())
    if writer is None:
        raise click.ClickException(f"{output}: unknown output type {output.suffix!r}; drydem writes {', '.join(writers)}")
    try:
        writable(output)
        found = _target(target, unit)
        with replaced_atomically(output) as partial:
            writer(found.model, partial)
    except DrydemError as exc:
        raise click.ClickException(str(exc)) from None
    click.echo(f"{found.name}: {found.model.n_blocks} blocks -> {output}")
    if writer is write_mesh:
        click.echo(f"note: {output} keeps the block names, shapes and fixed blocks, not the material, joint, contacts, "
                   "supports or solver settings (export to .toml for those)", err=True)


@main.command()
@click.argument("target")
@click.option("--samples", type=click.IntRange(min=1), default=100, show_default=True,
              help="Imperfect walls analysed; sample k's seed depends on --seed and k only, so more samples extend a run.")
@imperfection_options
@tilt_options(adaptive=True)
@click.option("--out", type=click.Path(path_type=Path), help="Results folder (default: results/TARGET-montecarlo-TIME).")
@click.option("--resume", is_flag=True, help="Go on with the run in --out (same TARGET and options; --samples may grow): the samples "
                                              "recorded there are kept, the missing and corrupt ones run.")
@click.option("--overwrite", is_flag=True, help="Replace the results of an earlier run in --out (they are kept otherwise).")
@workers_option
@scheduler_option
def montecarlo(target, samples, seed, height_sd, height_distribution, flatness_sd, misalignment_sd, tilt: TiltOptions, out, resume,
               overwrite, workers, scheduler) -> None:
    """Monte Carlo tilting analyses of TARGET (a built-in wall or a wall file: imperfections are
    drawn on its bricks): SAMPLES walls, each with its own imperfections drawn from its own
    seed, each a tilting analysis (drydem tilt's options; adaptive by default). Writes
    OUT/samples/NNNN (each sample's summary.json with its seed and imperfections, and
    pushover.csv) as they finish, OUT/summary.json (every sample's collapse and DLS angles, and
    their mean, std, CoV, 5th percentile) after each, and OUT/histogram.png at the end. Per
    sample there are no figures, VTK series or videos (drydem tilt TARGET gives them for a
    wall; no --vtk, --video, --unit). Exits 1 when no sample found a collapse angle, 130 or 143
    when interrupted (--resume goes on)."""
    from tqdm import tqdm

    from drydem.parametric.montecarlo import MonteCarloSettings, check_resumable, experiment, monte_carlo, pending_samples, sample_model
    from drydem.analysis.tilt import monitor_index
    from drydem.parametric.workers import open_workers

    imperfections = imperfections_from_options(height_sd, height_distribution, flatness_sd, misalignment_sd)
    if imperfections is None or imperfections.is_zero:
        raise click.ClickException("no imperfections: every sample would be the perfect wall; give --height-sd, --flatness-sd or "
                                   "--misalignment-sd (mm, > 0)")
    found = _target(target)
    if found.wall is None:
        raise click.ClickException(f"{target}: a model file has no brick layout, and imperfections are drawn on a wall's bricks: "
                                   "give a built-in wall (drydem designs) or a wall file")
    try:
        imperfections.check_for(found.wall.brick, found.wall.source, name=IMPERFECTION_OPTIONS.__getitem__)
        settings = MonteCarloSettings(samples=samples, seed=seed, imperfections=imperfections, tilt=tilt.settings(),
                                      model_overrides=tilt.model_overrides())
        monitor_index(sample_model(found.wall, settings, 0), tilt.monitor)  # the options checked on one sample, before any run
        if resume and overwrite:
            raise DrydemError("--resume goes on with the run in --out and --overwrite deletes it: give one of them")
        if resume and (out is None or not (out / "summary.json").is_file()):
            raise DrydemError("--resume needs --out DIR holding the summary.json of an earlier drydem montecarlo"
                              + (f" ({out} has none)" if out else ""))
        folder = _results_folder(out, f"{found.name}-montecarlo", resume=resume, overwrite=overwrite)
        if resume:
            check_resumable(folder, settings, found.wall)
    except DrydemError as exc:
        raise click.ClickException(str(exc)) from None
    measured = experiment(found.name) if designs.find(target) is not None else None
    about = {"name": found.name, "path": str(found.path), "experiment": measured}
    protocol = f"{'adaptive' if tilt.adaptive else 'fixed'} {tilt.increment:g} deg"
    plan = pending_samples(folder, settings)
    click.echo(f"{found.name} ({found.path}): {samples} samples ({imperfections}), seed {settings.seed}, {protocol}; "
               f"{len(plan.recorded)} already recorded in {folder}")
    for corrupt in plan.corrupt:
        click.echo(f"corrupt sample, run again: {corrupt}", err=True)
    try:
        with open_workers(workers, scheduler) as pool, _signals_interrupt() as received, \
                tqdm(total=len(plan.todo), desc="samples", unit=" sample") as bar:
            bar.write(f"running on {pool.where}")

            def done(entry):
                bar.update(1)
                angle = entry["collapse_angle_deg"]
                bar.set_postfix_str(f"sample {entry['index']}: " + (f"{angle:.2f} deg" if angle is not None else entry["ended_by"] or "failed"))

            try:
                outcome = monte_carlo(found.wall, settings, folder, pool.executor, target=about, in_flight=pool.slots, on_sample=done)
            except KeyboardInterrupt:
                click.echo(f"\ninterrupted ({received.name}); the finished samples are recorded in {folder}; go on with the same "
                           f"command plus {'' if out is not None else f'--out {folder} '}--resume", err=True)
                raise SystemExit(128 + received.number) from None
    except DrydemError as exc:
        raise click.ClickException(str(exc)) from None
    _montecarlo_outputs(found.name, outcome.summary, folder, measured)
    click.echo(f"{outcome.finished} samples run, {outcome.skipped} recorded before; results in {folder}")
    if outcome.summary["collapse_angle_deg"]["count"] == 0:
        raise SystemExit(1)


def _montecarlo_outputs(name: str, summary: dict, folder: Path, measured: dict | None) -> None:
    """Draw histogram.png of a Monte Carlo run and print its statistics."""
    from drydem.report.plots import histogram_figure

    collapse, dls = summary["collapse_angle_deg"], summary["dls_angle_deg"]
    angles = [s["collapse_angle_deg"] for s in summary["samples"] if s["collapse_angle_deg"] is not None]
    band = None if measured is None else (measured["mean_deg"], measured["cov"])
    histogram_figure(angles, folder / "histogram.png", title=f"{name}: {len(angles)} imperfect walls", mean_deg=collapse["mean"],
                     p05_deg=collapse["p05"], experiment=band)
    for sample in summary["samples"]:
        if sample["status"] == "failed":
            click.echo(f"failed: sample {sample['index']} (seed {sample['seed']}): {sample['error']}", err=True)
    excluded = summary["excluded"]["collapse_angle_deg"]
    left_out = f"; left out: {', '.join(f'{n} {outcome}' for outcome, n in excluded.items())}" if excluded else ""
    click.echo(f"collapse angle  {_statistics_line(collapse)}{left_out}")
    click.echo(f"DLS angle       {_statistics_line(dls)} (drift 1 %)")
    if measured is not None:
        click.echo(f"experiment      {measured['mean_deg']:.1f} deg, CoV {measured['cov']:.1%} (Savalle et al. 2022, Table 1)")


def _statistics_line(stats: dict) -> str:
    """A statistic of drydem.parametric.montecarlo.statistics in words."""
    if stats["count"] == 0:
        return "no sample found one"
    spread = "" if stats["std"] is None else f", std {stats['std']:.2f} deg" + ("" if stats["cov"] is None else f" (CoV {stats['cov']:.1%})")
    return f"mean {stats['mean']:.2f} deg{spread}, 5th percentile {stats['p05']:.2f} deg, over {stats['count']} samples"
