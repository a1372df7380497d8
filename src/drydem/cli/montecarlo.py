"""``drydem montecarlo``: tilting analyses of imperfect copies of a wall."""

from __future__ import annotations

import sys
from pathlib import Path

import click

from drydem.masonry import designs
from drydem.errors import DrydemError
from drydem.cli.common import (
    IMPERFECTION_OPTIONS, PlainIntRange, imperfection_options, imperfections_from_options, main, out_path, resolve_target, results_folder,
    failure_message, scheduler_option, signals_interrupt, workers_option, writing_results,
)
from drydem.cli.tilting import TiltOptions, tilt_options
from drydem.parametric.limits import MAX_SAMPLES, SAMPLES, SAMPLES_REASON


def _samples(ctx, param, value: int) -> int:
    """--samples within :data:`drydem.parametric.limits.SAMPLES` (at most MAX_SAMPLES, whose
    reason the message gives); click has refused a value under 1 or not a whole number."""
    if value not in SAMPLES:
        raise click.BadParameter(f"{value}: {SAMPLES} ({SAMPLES_REASON}); for more, start another run with another --seed and --out")
    return value


@main.command()
@click.argument("target")
@click.option("--samples", type=PlainIntRange(min=1), default=100, show_default=True, callback=_samples,
              help=f"Imperfect walls analysed, at most {MAX_SAMPLES} ({SAMPLES_REASON}); sample k's seed depends on --seed and k "
                   "only, so more samples extend a run.")
@imperfection_options
@tilt_options(adaptive=True)
@click.option("--out", type=click.Path(), callback=out_path, help="Results folder (default: results/TARGET-montecarlo-TIME).")
@click.option("--resume", is_flag=True, help="Go on with the run in --out (same TARGET and options; --samples may grow, never below "
                                              "the samples it holds, which would leave some out of its summary): the samples "
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
    their mean, std, CoV, 5th percentile) as they finish, and OUT/histogram.png at the end. Per
    sample there are no figures, VTK series or videos (drydem tilt TARGET gives them for a
    wall; no --vtk, --video, --unit). Exits 1 when no sample found a collapse angle, 130 or 143
    when interrupted (--resume goes on)."""
    from tqdm import tqdm

    from drydem.parametric.montecarlo import SAMPLES_FOLDER, MonteCarloSettings, check_resumable, experiment, monte_carlo, sample_model
    from drydem.analysis.tilt import check_loading, check_stop_displacement, monitor_index
    from drydem.parametric.workers import open_workers

    imperfections = imperfections_from_options(height_sd, height_distribution, flatness_sd, misalignment_sd)
    if imperfections is None or imperfections.is_zero:
        raise click.ClickException("no imperfections: every sample would be the perfect wall; give --height-sd, --flatness-sd or "
                                   "--misalignment-sd (mm, > 0)")
    found = resolve_target(target)
    if found.wall is None:
        raise click.ClickException(f"{target}: not a wall (a model file, a building or imported geometry has no brick layout), "
                                   "and imperfections are drawn on a wall's bricks: give a built-in wall (drydem designs) or a wall file")
    try:
        imperfections.check_for(found.wall.brick, found.wall.source, name=IMPERFECTION_OPTIONS.__getitem__)
        settings = MonteCarloSettings(samples=samples, seed=seed, imperfections=imperfections, tilt=tilt.settings(),
                                      model_overrides=tilt.model_overrides())
        first = sample_model(found.wall, settings, 0)  # the options checked on one sample, before any run
        check_loading(first, settings.tilt)  # found by a hunt: each sample failed on it, after the run had started
        monitor_index(first, tilt.monitor, settings.tilt.tilt_axis)
        check_stop_displacement(first, settings.tilt)
        if resume and overwrite:
            raise DrydemError("--resume goes on with the run in --out and --overwrite deletes it: give one of them")
        if resume and (out is None or not (out / "summary.json").is_file()):
            raise DrydemError("--resume needs --out DIR holding the summary.json of an earlier drydem montecarlo"
                              + (f" ({out} has none)" if out else ""))
        folder = results_folder(out, f"{found.name}-montecarlo", resume=resume, overwrite=overwrite)
        if resume:
            check_resumable(folder, settings, found.wall)
    except DrydemError as exc:
        raise click.ClickException(str(exc)) from None
    measured = experiment(found.name) if designs.find(target) is not None else None
    about = {"name": found.name, "path": str(found.path), "experiment": measured}
    protocol = f"{'adaptive' if tilt.adaptive else 'fixed'} {tilt.increment:g} deg"
    click.echo(f"{found.name} ({found.path}): {samples} samples ({imperfections}), seed {settings.seed}, {protocol}; in {folder}")
    go_on = f"the same command plus {'' if out is not None else f'--out {folder} '}--resume"
    kept = f"the finished samples are recorded in {folder}; go on with {go_on}"
    try:
        with open_workers(workers, scheduler) as pool, signals_interrupt() as received, \
                tqdm(total=samples, desc="samples", unit=" sample") as bar:

            def planned(plan):  # read once the folder is held (monte_carlo)
                bar.write(f"{len(plan.recorded)} already recorded; running {len(plan.todo)} on {pool.where}")
                for corrupt in plan.corrupt:
                    bar.write(f"corrupt sample, run again: {corrupt}", file=sys.stderr)
                bar.reset(total=len(plan.todo))

            def done(entry):
                bar.update(1)
                angle = entry["collapse_angle_deg"]
                bar.set_postfix_str(f"sample {entry['index']}: " + (f"{angle:.2f} deg" if angle is not None else entry["ended_by"] or "failed"))

            try:
                outcome = monte_carlo(found.wall, settings, folder, pool.executor, target=about, in_flight=pool.slots, on_sample=done,
                                      on_plan=planned)
            except OSError as exc:  # a full disk
                raise click.ClickException(f"{failure_message(exc, folder)}; {kept}") from None
            except KeyboardInterrupt:
                click.echo(f"\ninterrupted ({received.name}); {kept}", err=True)
                raise SystemExit(128 + received.number) from None
    except DrydemError as exc:
        raise click.ClickException(str(exc)) from None
    with writing_results(folder):
        _montecarlo_outputs(found.name, outcome.summary, folder, measured)
    click.echo(f"{outcome.finished} samples run, {outcome.skipped} recorded before; results in {folder}")
    failed = sum(sample["status"] == "failed" for sample in outcome.summary["samples"])
    if failed:
        raise click.ClickException(f"{failed} of {samples} samples failed (each named above, its error in its summary.json under "
                                   f"{folder / SAMPLES_FOLDER}), left out of the statistics; --resume runs a sample again "
                                   "whose folder is removed")
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
