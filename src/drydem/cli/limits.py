"""``drydem limit``: limit analysis."""

from __future__ import annotations

import sys
import threading
import time

import click

from drydem.errors import DrydemError
from drydem.cli.common import (
    joint_option, main, out_path, resolve_target, results_folder, threads_option, unit_option, writing_results,
)


@main.command()
@click.argument("target")
@click.option("--non-associative", is_flag=True, help="Friction without dilatancy (the iterative scheme of Gilbert et al. 2006).")
@joint_option("friction", "--friction", "Coulomb friction coefficient (overrides the model file).")
@click.option("--tilt-axis", type=click.Choice(["y", "x"]), default="y", show_default=True,
              help="Axis the table tilts about: y, the live load along x (in the plane of a wall along x); "
                   "x, the live load along y (out of that plane; not for in-plane models, held in y).")
@click.option("--out", type=click.Path(), callback=out_path, help="Results folder (default: results/TARGET-limit-TIME).")
@click.option("--overwrite", is_flag=True, help="Replace the results of an earlier run in --out (they are kept otherwise).")
@unit_option
@threads_option
def limit(target, non_associative, friction, tilt_axis, out, overwrite, unit) -> None:
    """Limit analysis of TARGET: the largest horizontal load multiplier (tilt angle atan(lambda))
    that rigid blocks can carry, with its collapse mechanism. Each stage is printed to stderr
    as it starts, with the time so far: finding the contacts, assembling the problem (its
    size), solving it (in-plane models: a linear program, HiGHS; 3D: a second-order cone
    program, Clarabel), and each non-associative iteration with its lambda so far."""
    from drydem.analysis.limit import LimitSettings, limit_analysis
    from drydem.model.parameters import LOAD_DIRECTION
    from drydem.io.results import limit_summary, write_summary
    from drydem.report.plots import limit_mechanism_figure
    from tqdm import tqdm

    found = resolve_target(target, unit)
    try:  # before the analysis, which can take minutes
        settings = LimitSettings(non_associative=non_associative, tilt_axis=tilt_axis)
        model = found.model.overridden(friction=friction)
        out = results_folder(out, f"{found.name}-limit", resume=None, overwrite=overwrite)
    except DrydemError as exc:
        raise click.ClickException(str(exc)) from None
    start = time.perf_counter()
    # a line per stage (kept), and under it a bar with the stage and the time it has taken so far,
    # redrawn every second by a thread: HiGHS lets Python run while it solves (minutes on large models)
    with tqdm(bar_format="{desc} ({elapsed})", desc="starting", leave=False) as bar:

        def progress(stage: str) -> None:
            bar.write(f"[{time.perf_counter() - start:7.1f} s] {stage}", file=sys.stderr)
            bar.set_description_str(stage.split(" (")[0], refresh=False)
            bar.reset()

        stop = threading.Event()
        ticker = threading.Thread(target=_refresh_every_second, args=(bar, stop), daemon=True)
        ticker.start()
        try:
            result = limit_analysis(model, settings, on_progress=progress)
        except DrydemError as exc:
            raise click.ClickException(str(exc)) from None
        finally:
            stop.set()
            ticker.join()
    runtime = time.perf_counter() - start
    label = "LA-NA" if non_associative else "LA-A"
    with writing_results(out, unfinished=f"; {out} holds no finished run (no summary.json)"):
        limit_mechanism_figure(model, result, out / "mechanism.png", title=f"{label} mechanism (shape exaggerated)",
                               load_direction=LOAD_DIRECTION[tilt_axis])
        write_summary(out, {"target": found.recorded} | limit_summary(result, settings, model, runtime))  # last, as a tilt's
    click.echo(f"{found.name}: {label} load multiplier (along {'xy'[tilt_axis == 'x']}) {result.load_multiplier:.4f}, collapse angle {result.collapse_angle_deg:.2f} deg")
    if non_associative:
        state = "converged" if result.converged else "NOT converged (last iterate reported)"
        click.echo(f"iterations      {result.iterations} ({state}): lambda {result.history[0]:.4f} (LA-A) -> {result.history[-1]:.4f}")
    click.echo(f"solver          {result.status}; {runtime:.1f} s; results in {out}")


def _refresh_every_second(bar, stop: threading.Event) -> None:
    """Redraw ``bar`` (its elapsed time) every second until ``stop`` is set."""
    while not stop.wait(1.0):
        bar.refresh()
