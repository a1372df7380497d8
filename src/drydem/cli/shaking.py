"""``drydem shake``: the shaking-table analysis."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import TYPE_CHECKING

import click

from drydem.errors import DrydemError
from drydem.cli.common import (
    PLAIN_FLOAT, PLAIN_INT, PlainIntRange, check_save_every, discard_unstarted, failure_message, joint_law_options, main,
    model_options, out_path, resolve_target, results_folder, signals_interrupt, threads_option, unit_option, writing_results,
)
from drydem.cli.tilting import _render

if TYPE_CHECKING:
    from drydem.io.target import Target
    from drydem.model.assembly import Model


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
@click.option("--motion", type=click.Path(), callback=out_path,
              help="Ground motion record: a CSV file with the header time_s,acc_x_m_s2[,acc_y_m_s2,acc_z_m_s2] (s, m/s2), or a "
                   "PEER NGA .AT2 file (in g).")
@click.option("--direction", type=click.Choice(["x", "y", "z"]), help="Direction of an .AT2 record or of a --pulse (default x); a CSV "
                                                                       "file names its directions in its header.")
@click.option("--scale", type=PLAIN_FLOAT, default=1.0, show_default=True, help="Multiplies the motion (not 0; negative: the other way).")
@click.option("--baseline/--no-baseline", default=None,
              help="Baseline-correct the --motion record (the default): a linear baseline subtracted from the acceleration brings "
                   "the table to rest (zero velocity and displacement) at the record's end. Pulses are analytic and never corrected.")
@click.option("--pulse", type=click.Choice(PULSE_KINDS), help="An analytic pulse instead of a record (with --amplitude and --frequency).")
@click.option("--amplitude", type=PLAIN_FLOAT, help="Peak acceleration of the --pulse, m/s2 (not 0; negative: the other way).")
@click.option("--frequency", type=PLAIN_FLOAT, help="Frequency of the --pulse, Hz (ricker: its peak frequency).")
@click.option("--cycles", type=PLAIN_INT, help="Periods of a --pulse sine (default 1).")
@click.option("--duration", type=PLAIN_FLOAT, help="Analysed time, s (default: the motion's duration; beyond it the table is no longer accelerated).")
@click.option("--output-interval", type=PLAIN_FLOAT, default=0.005, show_default=True,
              help="A row of history.csv (and a VTK state) every this many seconds of model time.")
@click.option("--restitution", type=_Restitution(), metavar="R|housner",
              help="Target coefficient of restitution of the monitored block's rocking impacts, in (0, 1], or 'housner' "
                   "(1 - 1.5 sin^2 alpha): the contact damping ratio is calibrated to it by free rocking of that block.")
@click.option("--damping-ratio", type=PLAIN_FLOAT,
              help="Contact damping ratio (of critical), set directly instead of --restitution (default: 0.5 if neither is given).")
@click.option("--rayleigh-mass", type=PLAIN_FLOAT, default=0.0, show_default=True, help="Rayleigh damping, mass term alpha, 1/s.")
@click.option("--rayleigh-stiffness", type=PLAIN_FLOAT, default=0.0, show_default=True, help="Rayleigh damping, stiffness term beta, s.")
@model_options
@joint_law_options
@click.option("--monitor", help="Block whose response is recorded (default: the top block nearest the middle).")
@click.option("--out", type=click.Path(), callback=out_path, help="Results folder (default: results/TARGET-TIME).")
@click.option("--overwrite", is_flag=True, help="Replace the results of an earlier run in --out (they are kept otherwise).")
@click.option("--vtk", is_flag=True, help="Write a VTK time series for ParaView (OUT/vtk: blocks and sub-contacts, in model time).")
@click.option("--save-every", type=PlainIntRange(min=1), default=1, show_default=True,
              help="With --vtk: keep the state of every N-th output interval.")
@click.option("--video", is_flag=True, help="Also render OUT/shake.mp4 (GIF if ffmpeg is missing), a frame per kept state at "
                                             f"{SHAKE_FPS:g} frames per second (--save-every thins them); implies --vtk.")
@unit_option
@threads_option
def shake(target, motion, direction, scale, baseline, pulse, amplitude, frequency, cycles, duration, output_interval, restitution,
          damping_ratio, rayleigh_mass, rayleigh_stiffness, kn, ks, friction, points, density, joint_law, monitor, out, overwrite, vtk,
          save_every, video, unit) -> None:
    """Shaking-table analysis of TARGET (a built-in wall, a wall or model file, or a
    .wrl/.obj/.stl/.json): the time history of the model under a ground motion, a --motion record or
    a --pulse (give one), from rest under gravity. Writes history.csv (the monitored block's
    response, row by row as the run goes), history.png and summary.json (whether and when blocks
    fell, peak and residual response, PGA, damping). Exits 130 or 143 when interrupted (the
    history so far is kept)."""
    from drydem.analysis.shake import HOUSNER, ShakeSettings
    from drydem.analysis.shake.run import check_dashpots, check_held_axes, housner_target
    from drydem.analysis.tilt import monitor_index
    from drydem.io.results import HistoryWriter
    from drydem.io.vtk import ShakeSeries

    try:
        _shake_motion_options(motion, pulse, amplitude, frequency, cycles, baseline)
        check_save_every(save_every, vtk or video)
    except DrydemError as exc:
        raise click.ClickException(str(exc)) from None
    found = resolve_target(target, unit)
    try:
        ground, corrected = _shake_motion(motion, direction, scale, baseline, pulse, amplitude, frequency, cycles)
        model = found.model.overridden(kn=kn, ks=ks, friction=friction, points=points, density=density, joint_law=joint_law)
        values = dict(duration_s=duration, output_interval_s=output_interval, restitution=restitution, contact_damping_ratio=damping_ratio,
                      rayleigh_mass_per_s=rayleigh_mass, rayleigh_stiffness_s=rayleigh_stiffness, monitor=monitor)
        _check_shake_options(values)
        settings = ShakeSettings(motion=ground, **values)
        held_notes = check_held_axes(model, ground, _component_option(motion, direction))
        check_dashpots(model, settings)
        monitored = monitor_index(model, monitor)
        if settings.restitution == HOUSNER:
            housner_target(model, monitored, ground.main_direction)  # refused before the run: a squat block does not rock
        folder = results_folder(out, found.name, resume=None, overwrite=overwrite)
    except DrydemError as exc:
        raise click.ClickException(str(exc)) from None
    for note in (*ground.notes, *held_notes):
        click.echo(f"note: {note}", err=True)
    click.echo(f"{found.name} ({found.path}): {model.n_blocks} blocks, {model.joint.stiffness_text}, "
               f"mu {model.joint.friction:g}, {model.contacts.points_per_length} points per length; {ground.name}, "
               f"PGA {ground.pga_m_s2:.4g} m/s2, {settings.analysed_s:g} s -> {folder}")
    with writing_results(folder):
        series = ShakeSeries(folder / "vtk", model, every=save_every, load_direction=ground.main_direction) if vtk or video else None
        live = _LiveHistory(HistoryWriter(folder), series)
    result = _run_shake(model, settings, folder, live)
    with writing_results(folder, unfinished=f"; {folder} holds the history but no summary.json"):
        _shake_outputs(found, model, result, folder, live.series, scale=scale, baseline_corrected=corrected)
    if video:
        _render(live.series.folder, folder / "shake.mp4", fps=SHAKE_FPS)


def _run_shake(model: Model, settings, folder: Path, live: _LiveHistory):
    """Shake with a progress bar, ``live`` writing the history (and VTK frames) as it goes; the
    result. An error or an interruption ends the command, saying what the folder keeps."""
    from tqdm import tqdm

    from drydem.analysis.shake import shake_analysis

    total = settings.analysed_s
    bar_format = "{l_bar}{bar}| {n:.3f}/{total:.3f} s [{elapsed}<{remaining}{postfix}]"
    with signals_interrupt() as received, tqdm(total=total, desc="shaking", unit=" s", bar_format=bar_format, leave=False) as bar:

        def progress(time_s, cycles, rotation_rad):
            bar.update(min(time_s, total) - bar.n)
            bar.set_postfix_str(f"rotation {rotation_rad:.3g} rad")

        try:
            return shake_analysis(model, settings, on_progress=progress, on_frame=live,
                                  on_note=lambda note: bar.write(f"note: {note}", file=sys.stderr))
        except (DrydemError, OSError) as exc:
            if isinstance(exc, DrydemError) and not live.writer.rows:
                discard_unstarted(live.writer.path, live.series)
            raise click.ClickException(failure_message(exc, folder)) from None
        except KeyboardInterrupt:
            click.echo(f"\ninterrupted ({received.name}) at {live.time_s:.3f} s of {total:g} s; the history so far is in "
                       f"{live.writer.path} ({live.writer.rows} rows), no summary.json", err=True)
            raise SystemExit(128 + received.number) from None


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
    if baseline is not None:  # found by a hunt: --no-baseline with a pulse was taken and ignored
        raise DrydemError(f"--{'' if baseline else 'no-'}baseline says whether a --motion record is baseline-corrected; a pulse "
                          "is analytic and never corrected")


def _shake_motion(motion, direction, scale, baseline, pulse, amplitude, frequency, cycles):
    """The ground motion the options give, and whether it was baseline-corrected; a DrydemError
    naming the file or the option at fault."""
    from types import SimpleNamespace

    from drydem.analysis.shake.motion import MIN_PEAK_M_S2, NONZERO, PULSE_RULES, pulse as make_pulse, read_motion
    from drydem.model.parameters import field_problems, refuse

    refuse([problem for problem in [NONZERO.problem(scale, "--scale")] if problem])
    if pulse is not None:
        values = dict(amplitude_m_s2=amplitude, frequency_hz=frequency, cycles=1 if cycles is None else cycles,
                      direction=direction or "x")
        rules = {field: PULSE_RULES[field] for field in values} | {"amplitude_m_s2": NONZERO}
        refuse(field_problems(SimpleNamespace(**values), rules, PULSE_OPTIONS.get))
        if pulse != "sine" and values["cycles"] != 1:
            raise DrydemError(f"--cycles {cycles}: a {pulse} pulse is one period; --pulse sine repeats it")
        ground, corrected = make_pulse(pulse, **values), False
    else:
        ground = read_motion(motion, direction)
        corrected = baseline is not False
        if corrected:
            ground = ground.baseline_corrected()
    ground = ground if scale == 1.0 else ground.scaled(scale)
    peak = max(ground.peaks_m_s2)
    if peak < MIN_PEAK_M_S2:  # found by a hunt: --amplitude 5e-324 ran, "PGA 4.941e-324 m/s2"
        raise DrydemError(f"{ground.label}: its peak acceleration, {peak:.3g} m/s2, is below {MIN_PEAK_M_S2:g} m/s2 (1e-10 g, "
                          "far below any accelerometer's resolution): a table at rest, no motion; check --amplitude and --scale")
    return ground, corrected


def _component_option(motion, direction):
    """What gave a motion's component along an axis, for messages: ``--direction AXIS`` for a
    pulse or an .AT2 record, the column of a CSV record (``FILE: its column acc_y_m_s2``)."""
    if motion is not None and motion.suffix.lower() == ".csv":
        return lambda axis: f"{motion}: its column acc_{axis}_m_s2"
    return lambda axis: f"--direction {axis}" if direction is not None else f"--direction {axis} (the default)"


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
    history_figure(result.history, folder / "history.png", title=f"{found.name}: {result.settings.motion.name}",
                   monitored=result.monitored_block, fallen=result.fallen_blocks)
    # last, as a tilt's: a folder with summary.json holds a finished run, its figure included
    write_summary(folder, shake_summary(result, model, scale=scale, baseline_corrected=baseline_corrected))
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
