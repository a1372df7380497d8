"""``drydem limit``: limit analysis."""

from __future__ import annotations

import sys
import threading
import time
from collections.abc import Callable
from typing import TYPE_CHECKING

import click

from drydem.errors import DrydemError
from drydem.cli.common import (
    joint_option, main, out_path, resolve_target, results_folder, signals_interrupt, threads_option, unit_option, writing_results,
)

if TYPE_CHECKING:
    from drydem.analysis.limit import LimitResult


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
    program, Clarabel), and each non-associative iteration with its lambda so far. Exits 1
    when the non-associative iteration does not converge (no verdict; the results are written)."""
    from drydem.analysis.limit import LimitSettings, limit_analysis
    from drydem.model.parameters import LOAD_DIRECTION
    from drydem.io.results import limit_summary, write_summary
    from drydem.report.plots import limit_mechanism_figure

    found = resolve_target(target, unit)
    try:  # before the analysis, which can take minutes
        settings = LimitSettings(non_associative=non_associative, tilt_axis=tilt_axis)
        model = found.model.overridden(friction=friction)
        out = results_folder(out, f"{found.name}-limit", resume=None, overwrite=overwrite)
    except DrydemError as exc:
        raise click.ClickException(str(exc)) from None
    start = time.perf_counter()
    result = _solve_interruptibly(lambda progress: limit_analysis(model, settings, on_progress=progress), start)
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
    if not result.converged:  # no verdict, as a tilt without equilibrium (found by a hunt: exit 0)
        raise click.ClickException(f"the non-associative iteration did not converge within {settings.max_iterations} iterations: "
                                   f"its last multiplier, {result.load_multiplier:.4g}, is no result (summary.json has converged "
                                   "false); compare with LA-A and the DEM tilt")


def _solve_interruptibly(solve: Callable[[Callable[[str], None]], LimitResult], start: float) -> LimitResult:
    """``solve(progress)`` in a thread of its own, while this one redraws a bar under the line
    each stage prints (stderr), with the stage's time so far, every second (HiGHS and Clarabel
    let Python run while they solve, minutes on large models) and takes Ctrl-C and SIGTERM: a
    solver in compiled code sees neither (found by a hunt: Ctrl-C waited until HiGHS had
    finished, 37 s on a 60 x 60 wall, and SIGTERM ended the command without a word).
    Interrupted, the command ends at once (130 or 143):
    a limit analysis has no partial result to keep, and the solver's thread, a daemon, ends
    with the process."""
    from tqdm import tqdm

    outcome: dict = {}
    with signals_interrupt() as received, tqdm(bar_format="{desc} ({elapsed})", desc="starting", leave=False) as bar:

        def progress(stage: str) -> None:
            bar.write(f"[{time.perf_counter() - start:7.1f} s] {stage}", file=sys.stderr)
            bar.set_description_str(stage.split(" (")[0], refresh=False)
            bar.reset()

        def run() -> None:
            try:
                outcome["result"] = solve(progress)
            except BaseException as exc:  # handed to the waiting thread, which raises it
                outcome["error"] = exc

        solver = threading.Thread(target=run, name="drydem-limit", daemon=True)
        solver.start()
        try:
            while solver.is_alive():
                solver.join(1.0)
                bar.refresh()
        except KeyboardInterrupt:
            click.echo(f"\ninterrupted ({received.name}) while {bar.desc or 'starting'}; a limit analysis keeps no partial "
                       "result: nothing is written", err=True)
            raise SystemExit(128 + received.number) from None
    if isinstance(outcome.get("error"), DrydemError):
        raise click.ClickException(str(outcome["error"])) from None
    if "error" in outcome:
        raise outcome["error"]
    return outcome["result"]
