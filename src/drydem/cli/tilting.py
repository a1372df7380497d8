"""``drydem tilt`` (its options, shared with ``montecarlo``) and ``drydem animate``."""

from __future__ import annotations

import functools
from collections.abc import Callable
from dataclasses import dataclass, fields
from pathlib import Path
from typing import TYPE_CHECKING

import click

from drydem.errors import DrydemError, ModelError
from drydem.model.parameters import CRITERIA
from drydem.cli.common import (
    CHECKPOINT, MODEL_OPTIONS, PLAIN_FLOAT, PlainIntRange, check_save_every, discard_unstarted, joint_law_options, main,
    more_cycles_advice, out_path, resolve_target, failure_message, results_folder, ruled, signals_interrupt, threads_option, unit_option,
    writing_results,
)

if TYPE_CHECKING:
    from drydem.io.target import Target
    from drydem.model.assembly import Model


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
    tilt_axis: str
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
                            stop_displacement_m=self.stop_displacement, loading=self.loading, tilt_axis=self.tilt_axis,
                            monitor=self.monitor, max_angle_deg=self.max_angle)


def tilt_setting(field: str):
    """The callback of the option setting TiltSettings' ``field``: its rule checked
    (drydem.analysis.tilt.settings.SETTING_RANGES, imported when the option is read)."""
    def rule():
        from drydem.analysis.tilt.settings import SETTING_RANGES

        return SETTING_RANGES[field]

    return ruled(rule, f"tilt setting {field}")


def tilt_options(*, adaptive: bool):
    """The options of :class:`TiltOptions`, handed to the command as one ``tilt`` argument;
    ``adaptive``: the protocol by default (--adaptive or --fixed)."""
    protocol = "adaptive" if adaptive else "fixed"
    options = [
        *MODEL_OPTIONS.values(),
        click.option("--increment", type=PLAIN_FLOAT, default=0.1, show_default=True, callback=tilt_setting("increment_deg"),
                     help="Tilt step, deg."),
        click.option("--adaptive/--fixed", default=adaptive,
                     help=f"Coarse steps, then bisection down to the increment; or every step one increment (default: {protocol})."),
        click.option("--predictor/--no-predictor", default=True, show_default=True,
                     help="Start each step from the last two equilibria extrapolated (fewer cycles)."),
        click.option("--stop-displacement", type=PLAIN_FLOAT, default=0.10, show_default=True, callback=tilt_setting("stop_displacement_m"),
                     help="Monitored horizontal displacement that ends the run, m."),
        click.option("--criterion", type=click.Choice(CRITERIA), help="Equilibrium criterion (default: the model file's)."),
        click.option("--loading", type=click.Choice(["tilt", "multiplier"]), default="tilt", show_default=True,
                     help="Tilt the gravity or add lambda g horizontally."),
        click.option("--tilt-axis", type=click.Choice(["y", "x"]), default="y", show_default=True,
                     help="Horizontal axis the table turns about: y loads along x (in the plane of a wall drawn in x-z); "
                          "x loads along y, out of the plane of the walls along x (3D models; a building's long walls)."),
        click.option("--monitor", help="Block whose centroid is monitored (default: the top block nearest the middle in x; "
                                       "with --tilt-axis x, on the leeward wall)."),
        click.option("--max-angle", type=PLAIN_FLOAT, default=80.0, show_default=True, callback=tilt_setting("max_angle_deg"),
                     help="Largest tilt tried, deg."),
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
@click.option("--out", type=click.Path(), callback=out_path, help="Results folder (default: results/TARGET-TIME).")
@click.option("--resume", is_flag=True, help="Go on from the checkpoint in --out (same TARGET and options).")
@click.option("--overwrite", is_flag=True, help="Replace the results of an earlier run in --out (they are kept otherwise).")
@click.option("--vtk", is_flag=True, help="Write a VTK time series for ParaView (OUT/vtk: blocks and sub-contacts).")
@click.option("--save-every", type=PlainIntRange(min=1), default=1, show_default=True,
              help="With --vtk: keep every N-th equilibrium state (the states past collapse are all kept).")
@click.option("--video", is_flag=True, help="Also render OUT/collapse.mp4 (GIF if ffmpeg is missing); implies --vtk.")
@unit_option
@threads_option
def tilt(target, tilt: TiltOptions, out, resume, overwrite, vtk, save_every, video, unit) -> None:
    """Tilting-table analysis of TARGET (a built-in wall, a wall or model file, or a
    .wrl/.obj/.stl/.json): collapse angle, pushover curve, Eurocode 8 drift-limit angles, plots.
    Exits 1 when equilibrium could not be reached within max_cycles or a step diverged (no
    verdict), 130 or 143 when interrupted (the last equilibrium is kept for --resume)."""
    from drydem.analysis.tilt import DIVERGED, NO_EQUILIBRIUM, NO_EQUILIBRIUM_UNDER_GRAVITY

    found = resolve_target(target, unit)
    try:
        model, settings, folder, saved = _tilt_plan(found, tilt, out, resume, overwrite, vtk or video, save_every)
    except DrydemError as exc:
        raise click.ClickException(str(exc)) from None
    if resume and (folder / "summary.json").is_file():
        _check_finished(folder)
        if (vtk or video) and not (folder / "vtk").is_dir():
            raise click.ClickException(f"{folder} holds a finished run without a VTK series: --vtk and --video need it run again "
                                       "(--overwrite instead of --resume)")
        click.echo(f"{folder} holds a finished run of these options (summary.json): nothing to resume, its results are kept "
                   "(--overwrite runs it again" + ("; drydem animate renders its VTK series" if video else "") + ")")
        return
    _announce_tilt(found, model, settings, folder, saved)
    go_on = "the same command plus --resume" if out is not None else f"the same command plus --out {folder} --resume"
    result, series = _run_tilt(found, model, settings, folder, saved=saved, series=vtk or video, save_every=save_every, go_on=go_on)
    if video:
        _render(series.folder, folder / "collapse.mp4", fps=8.0)
    if result.ended_by in (NO_EQUILIBRIUM_UNDER_GRAVITY, NO_EQUILIBRIUM, DIVERGED):
        raise SystemExit(1)


def _tilt_plan(found: Target, tilt: TiltOptions, out: Path | None, resume: bool, overwrite: bool, series: bool, save_every: int):
    """The model, settings and results folder of a tilt, and the checkpoint's saved state when
    resuming (else None); DrydemError for options that contradict each other or the folder."""
    from drydem.analysis.tilt import check_loading, check_stop_displacement, monitor_index
    from drydem.analysis.tilt.checkpointing import check_fingerprint, fingerprint, saved_records
    from drydem.engine.checkpoint import load_checkpoint, unreadable

    model = found.model.overridden(**tilt.model_overrides())
    settings = tilt.settings()
    check_loading(model, settings)
    check_stop_displacement(model, settings)
    monitor_index(model, tilt.monitor, settings.tilt_axis)
    if resume and overwrite:
        raise DrydemError("--resume goes on from the run in --out and --overwrite deletes it: give one of them")
    check_save_every(save_every, series)
    if resume and (out is None or not (out / CHECKPOINT).is_file()):
        raise DrydemError(f"--resume needs --out DIR holding a {CHECKPOINT} from an earlier run" + (f" ({out} has none)" if out else ""))
    folder = results_folder(out, found.name, resume=resume, overwrite=overwrite)
    saved = None
    if resume:
        _, saved = load_checkpoint(folder / CHECKPOINT)
        check_fingerprint(folder / CHECKPOINT, saved, fingerprint(model, settings))
        try:  # before the VTK series goes on from their tilts (found by a review: a ValueError's traceback)
            saved_records(saved)
        except ModelError as exc:
            raise unreadable(folder / CHECKPOINT, exc) from None
        if not (folder / "summary.json").is_file():  # a finished run resumes nothing (the command says so)
            _check_resumed_series(folder, saved, series)
    return model, settings, folder, saved


def _check_resumed_series(folder: Path, saved: dict, series: bool) -> None:
    """DrydemError unless a resumed run's VTK series would be whole: one begun (OUT/vtk) goes on
    only with --vtk or --video, and one asked for where none was begun would miss the
    equilibria before the checkpoint (found by a hunt: either way the series was partial, and
    rendered as the collapse without a word)."""
    begun = (folder / "vtk" / "frames.csv").is_file()
    if begun and not series:
        raise DrydemError(f"{folder / 'vtk'}: holds the VTK series of the run being resumed; resume with --vtk (or --video) and "
                          "the same --save-every so that it goes on, or move that folder away to go on without it")
    if series and not begun:
        raise DrydemError(f"{folder}: the run being resumed has no VTK series, and one begun now would miss its "
                          f"{len(saved['records'])} equilibrium states up to {float(saved['theta_deg']):g} deg; resume without "
                          "--vtk and --video, or run it again from the start with --overwrite")


def _announce_tilt(found: Target, model: Model, settings, folder: Path, saved: dict | None) -> None:
    """Say what is tilted, how, where the results go and, resuming, from where."""
    click.echo(f"{found.name} ({found.path}): {model.n_blocks} blocks, {model.joint.stiffness_text}, "
               f"mu {model.joint.friction:g}, {model.contacts.points_per_length} points per length -> {folder}")
    if settings.tilt_axis != "y":
        click.echo(f"tilting about {settings.tilt_axis}: the lateral load acts along {'xy'[settings.load_direction]}")
    if saved is not None:
        click.echo(f"resuming from {folder / CHECKPOINT}: last equilibrium at {float(saved['theta_deg']):g} deg "
                   f"({len(saved['records'])} equilibrium states)")
    if model.solver.damping == 0:
        click.echo("warning: [solver] damping = 0: dynamic relaxation has nothing to dissipate energy with and may never "
                   "reach equilibrium", err=True)


def _run_tilt(found: Target, model: Model, settings, folder: Path, *, saved: dict | None, series: bool, save_every: int, go_on: str):
    """Tilt with a progress bar, writing pushover rows, checkpoints (and VTK frames if
    ``series``) as it goes, then its results (:func:`_tilt_outputs`), going on from the
    checkpoint's ``saved`` content when resuming; the result and the VTK series (None without
    one). An interruption or a failure to write ends the command, saying what was kept and
    ``go_on``."""
    from tqdm import tqdm

    from drydem.analysis.tilt import CHECKPOINT_EVERY_S, tilt_analysis
    from drydem.analysis.tilt.checkpointing import saved_records
    from drydem.io.results import PushoverWriter
    from drydem.io.vtk import VtkSeries

    with signals_interrupt() as received:
        with tqdm(desc="tilting", unit=" cycles", unit_scale=True, leave=False) as bar:

            def progress(theta, cycles, ux):
                bar.update(cycles - bar.n)
                bar.set_postfix_str(f"{theta:.2f} deg, u{'xy'[settings.load_direction]} {ux * 1e3:.2f} mm")

            # before the first cycle count: minutes on 10^4-10^5 blocks (found by a hunt: a bar that looked hung)
            bar.set_postfix_str("finding the contacts, then settling under gravity")
            frames = writer = None
            resume = saved is not None
            try:
                frames = (VtkSeries(folder / "vtk", model, every=save_every, resumed_tilts_deg=saved_records(saved)[:, 0] if resume else None,
                                    load_direction=settings.load_direction) if series else None)
                writer = PushoverWriter(folder)
                result = tilt_analysis(model, settings, on_record=writer, on_progress=progress, on_frame=frames,
                                       checkpoint=folder / CHECKPOINT, resume=resume)
            except (DrydemError, OSError) as exc:
                if writer is not None and not resume and not (folder / CHECKPOINT).is_file():
                    # nothing to go on from: rows without a checkpoint (its first save failed)
                    # made the same command refuse, offering a --resume that could not resume
                    discard_unstarted(writer.path, frames)
                raise click.ClickException(failure_message(exc, folder)) from None
            except KeyboardInterrupt:
                kept = (f"the run is saved in {folder / CHECKPOINT} (up to {CHECKPOINT_EVERY_S:g} s before)"
                        if (folder / CHECKPOINT).is_file() else "no equilibrium was reached yet")
                click.echo(f"\ninterrupted ({received.name}); {kept}. Go on with {go_on}", err=True)
                raise SystemExit(128 + received.number) from None
        _written(lambda: _tilt_outputs(found, model, result, folder, frames), folder, received, go_on)
    return result, frames


def _written(write: Callable[[], None], folder: Path, received, go_on: str) -> None:
    """``write()`` the results of a finished analysis; a failure to write them (a full disk) or
    an interruption is said without a traceback: summary.json is written last, so the folder
    then holds no finished run and ``go_on`` (--resume, from the checkpoint) writes them all."""
    unfinished = f"{folder} holds no finished run (no summary.json); {go_on} writes the results again"
    try:
        with writing_results(folder, unfinished=f"; {unfinished}"):
            write()
    except KeyboardInterrupt:
        click.echo(f"\ninterrupted ({received.name}) while writing the results; {unfinished}", err=True)
        raise SystemExit(128 + received.number) from None


def _tilt_outputs(found: Target, model: Model, result, folder: Path, series) -> None:
    """Write the figures and, last (a finished run's mark: :func:`_written`), summary.json of a
    tilting analysis, and print what it found."""
    from drydem.analysis.tilt import DIVERGED
    from drydem.io.results import tilt_summary, write_summary
    from drydem.report.plots import mechanism_figure, pushover_figure

    pushover_figure(result, folder / "pushover.png", title=found.name)
    last = result.last_equilibrium_deg
    lost_by_then = frozenset(name for name, theta in result.lost_blocks if last is not None and theta <= last)
    states = [
        (f"last equilibrium ({last:.2f} deg)" if last is not None else "under gravity", result.collapse_state or result.final_state,
         lost_by_then),
    ]
    if result.ended_by != DIVERGED:  # a diverged step's state is nothing to show
        states.append((f"past collapse ({result.ended_by})", result.final_state, frozenset(name for name, _ in result.lost_blocks)))
    mechanism_figure(model, states, folder / "mechanism.png", monitored=result.monitored_block,
                     load_direction=result.settings.load_direction)
    write_summary(folder, {"target": found.recorded} | tilt_summary(result, model))
    for line in _tilt_verdict(result, model):
        click.echo(line)
    dls = result.drift_limit_angles_deg
    click.echo("drift limits    " + ", ".join(f"{k:.2%}: " + ("not reached" if v is None else f"{v:.2f} deg") for k, v in dls.items()))
    if result.lost_blocks and result.stable_under_gravity:
        first = min(theta for _, theta in result.lost_blocks)
        click.echo(f"lost blocks     {len(result.lost_blocks)} fell out of the model, the first at {first:.2f} deg (listed in summary.json)")
    click.echo(f"cycles          {result.cycles} in {result.runtime_s:.1f} s; results in {folder}")
    if series is not None:
        click.echo(f"vtk             {len(series.rows)} states in {series.folder} (open blocks.pvd and contacts.pvd in ParaView)")


def _tilt_verdict(result, model: Model) -> list[str]:
    """What the analysis found, in words that claim no more than it showed."""
    from drydem.analysis.support import too_soft_joints
    from drydem.analysis.tilt import DIVERGED, MAXIMUM_ANGLE, NO_EQUILIBRIUM, NO_EQUILIBRIUM_UNDER_GRAVITY

    fell = ", ".join(repr(name) for name, _ in result.lost_blocks[:5]) + (", ..." if len(result.lost_blocks) > 5 else "")
    if result.stable_under_gravity is False:
        what = f"{fell} fell" if fell else (f"the monitored block {result.monitored_block!r} moved "
                                           f"{result.settings.stop_displacement_m:g} m (the stop displacement)")
        soft = too_soft_joints(model, [model.block_index(name) for name, _ in result.lost_blocks] or [model.block_index(result.monitored_block)])
        return [f"the model cannot stand under its own weight: {what} (state in mechanism.png)" + (f"; {soft}" if soft else "")]
    if result.ended_by == NO_EQUILIBRIUM_UNDER_GRAVITY:
        return [f"no equilibrium under gravity within [solver] max_cycles = {model.solver.max_cycles}: no verdict on whether it "
                f"stands; {more_cycles_advice(model, 'raise max_cycles (or check damping) and run again')}"]
    if result.ended_by == MAXIMUM_ANGLE:
        return [f"no collapse up to {result.last_equilibrium_deg:.2f} deg (the last step within max_angle_deg = "
                f"{result.settings.max_angle_deg:g})"]
    if result.ended_by == NO_EQUILIBRIUM:
        return [f"last equilibrium {result.last_equilibrium_deg:.2f} deg; the next step reached no equilibrium within [solver] "
                f"max_cycles = {model.solver.max_cycles} and did not collapse either: no collapse angle "
                f"({more_cycles_advice(model, 'raise max_cycles to decide')})"]
    if result.ended_by == DIVERGED:
        return [f"last equilibrium {result.last_equilibrium_deg:.2f} deg; the integration of the next step diverged (more "
                f"kinetic energy than gravity can have supplied): no collapse angle; reduce [solver] timestep_safety = "
                f"{model.solver.timestep_safety:g} or check the joint stiffness and block masses, and run again"]
    return [f"collapse angle  {result.collapse_angle_deg:.2f} deg (load multiplier {result.load_multiplier:.4f}; ended by {result.ended_by})"]


def _fps(ctx, param, value):
    """--fps: a frame rate within drydem.report.animation.FPS_RANGE, or a usage error naming it."""
    from drydem.report.animation import check_fps

    try:
        return check_fps(value)
    except DrydemError as exc:
        raise click.BadParameter(str(exc)) from None


@main.command()
@click.argument("result_dir", type=click.Path(exists=True, file_okay=False, path_type=Path))
@click.option("--out", "-o", type=click.Path(dir_okay=False), callback=out_path, help="Video file, .mp4 or .gif (default: RESULT_DIR/collapse.mp4, or shake.mp4 for a shake run; beside a run's vtk/ given itself).")
@click.option("--fps", type=PLAIN_FLOAT, default=8.0, show_default=True, callback=_fps,
              help="Frames per second, 0.1 to 100 (10 s a frame to the fastest a GIF can show: it counts in hundredths of a second).")
@click.option("--overwrite", is_flag=True, help="Replace the video if it exists (else an existing file is kept and the command fails).")
def animate(result_dir: Path, out: Path | None, fps: float, overwrite: bool) -> None:
    """Render the VTK series of a `drydem tilt --vtk` run (RESULT_DIR or RESULT_DIR/vtk) to a video.
    An existing video is replaced only with --overwrite (checked before any frame is drawn)."""
    from drydem.io.results import refuse_if_written

    try:  # RESULT_DIR, or RESULT_DIR/vtk, of a run still going
        refuse_if_written(result_dir, "animate it once the run has ended (a run with --video renders its own video)")
    except DrydemError as exc:
        raise click.ClickException(str(exc)) from None
    folder = result_dir / "vtk" if (result_dir / "vtk").is_dir() else result_dir
    # a run's vtk/ given itself: its video beside it, as --video writes it (found by a review: a
    # video in vtk/ is no file of a run's there, and --overwrite of the run refused the folder)
    run_dir = result_dir.parent if folder == result_dir and result_dir.name == "vtk" else result_dir
    _render(folder, out or _default_video(run_dir, folder), fps=fps, overwrite=overwrite)


def _check_finished(folder: Path) -> None:
    """ClickException if the finished run in ``folder`` is damaged: its summary.json or
    pushover.csv unreadable or not what the run wrote
    (:func:`~drydem.parametric.records.run_folder_record`; found by a hunt: a --resume said a
    run whose pushover.csv was cut short was finished and kept)."""
    from drydem.parametric.records import RecordError, run_folder_record

    try:
        run_folder_record(folder)
    except RecordError as exc:
        raise click.ClickException(f"{exc}; the finished run in {folder} is damaged: --overwrite runs it again") from None


def _default_video(result_dir: Path, series: Path) -> Path:
    """RESULT_DIR/shake.mp4 for a shaking-table series (its frames.csv has a time_s column), as
    shake --video names it, else RESULT_DIR/collapse.mp4, as tilt --video (found by a hunt: a
    shake run was animated to collapse.mp4). A series that cannot be read is given a tilt's
    name: rendering it then says why."""
    from drydem.files import read_text

    try:
        header = read_text(series / "frames.csv", "frames.csv is CSV text").partition("\n")[0]
    except DrydemError:
        header = ""
    return result_dir / ("shake.mp4" if "time_s" in header.strip().split(",") else "collapse.mp4")


def _render(folder: Path, path: Path, *, fps: float, overwrite: bool = True) -> None:
    """Render the series in ``folder`` to ``path`` (drydem.report.animation.render_video) and say
    where, with a note on stderr of frames on disk the series does not list; exit with the message
    of a DrydemError. ``overwrite`` by default: tilt --video and shake --video render into the
    results folder they own (new, resumed, or emptied by --overwrite); animate passes its --overwrite."""
    from drydem.report.animation import render_video

    try:
        written = render_video(folder, path, fps=fps, overwrite=overwrite, note=lambda line: click.echo(f"note: {line}", err=True))
    except DrydemError as exc:
        raise click.ClickException(str(exc)) from None
    click.echo(f"video           {written}")
