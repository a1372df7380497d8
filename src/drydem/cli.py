"""The ``drydem`` command line."""

from __future__ import annotations

import time
from dataclasses import replace
from datetime import datetime
from pathlib import Path

import click
import numpy as np

from drydem import __version__, examples
from drydem.errors import DrydemError
from drydem.io.model_file import load_model
from drydem.model import Model
from drydem.parameters import CRITERIA
from drydem.solve import Simulation

#: the tilting analysis' checkpoint in its results folder
CHECKPOINT = "checkpoint.npz"


@click.group()
@click.version_option(__version__, prog_name="drydem")
def main() -> None:
    """drydem: discrete element analysis of dry-joint masonry."""


@main.command()
@click.argument("target")
@click.option("--settle", is_flag=True, help="Also cycle to equilibrium under vertical gravity and report the settlement.")
def check(target: str, settle: bool) -> None:
    """Validate TARGET (a model file or a shipped example) and print its blocks, contacts and timestep."""
    try:
        path = examples.resolve(target)
        model = load_model(path)
        sim = Simulation(model)
    except DrydemError as exc:
        raise click.ClickException(str(exc)) from None
    c = sim.contacts
    movable = model.block_movable
    click.echo(f"model           {path}")
    click.echo(f"blocks          {model.n_blocks} ({int(movable.sum())} movable, {int((~movable).sum())} fixed)")
    click.echo(f"mass            {model.total_mass:.6g} kg (movable blocks)")
    density = model.contact_density
    click.echo(f"contacts        {len(c.pairs)} face contacts, {c.count} sub-contacts ({density.along} points per length, {density.across} across y)")
    click.echo(f"contact area    {c.area.sum():.6g} m2, tolerance {model.contact_tolerance:.3g} m")
    click.echo(f"joint           kn {model.joint.kn:.3g} Pa/m, ks {model.joint.ks:.3g} Pa/m, friction {model.joint.friction:g}")
    mass_note = " (mass scaled)" if model.solver.mass_scaling else ""
    click.echo(f"timestep        {sim.timestep:.4g} s{mass_note}")
    if settle:
        _settle(sim)


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


@main.command()
@click.argument("target")
@click.option("--kn", type=float, help="Normal joint stiffness, Pa/m (overrides the model file).")
@click.option("--ks", type=float, help="Shear joint stiffness, Pa/m.")
@click.option("--friction", type=float, help="Coulomb friction coefficient.")
@click.option("--points", type=int, help="Sub-contact points per length.")
@click.option("--density", type=float, help="Density of every block, kg/m3.")
@click.option("--increment", type=float, default=0.1, show_default=True, help="Tilt step, deg.")
@click.option("--adaptive", is_flag=True, help="Coarse steps, then bisection down to the increment.")
@click.option("--stop-displacement", type=float, default=0.10, show_default=True, help="Monitored horizontal displacement that ends the run, m.")
@click.option("--criterion", type=click.Choice(CRITERIA), help="Equilibrium criterion (default: the model file's).")
@click.option("--loading", type=click.Choice(["tilt", "multiplier"]), default="tilt", show_default=True, help="Tilt the gravity or add lambda g horizontally.")
@click.option("--monitor", help="Block whose centroid is monitored (default: the top block nearest the middle).")
@click.option("--max-angle", type=float, default=80.0, show_default=True, help="Largest tilt tried, deg.")
@click.option("--out", type=click.Path(file_okay=False, path_type=Path), help="Results folder (default: results/TARGET-TIME).")
@click.option("--resume", is_flag=True, help="Go on from the checkpoint in --out (same TARGET and options).")
def tilt(target, kn, ks, friction, points, density, increment, adaptive, stop_displacement, criterion, loading, monitor, max_angle, out, resume) -> None:
    """Tilting-table analysis of TARGET (a model file or a shipped example): collapse angle,
    pushover curve, Eurocode 8 drift-limit angles, plots."""
    from tqdm import tqdm

    from drydem.analysis.tilt import TiltSettings, tilt_analysis
    from drydem.io.results import PushoverWriter, write_summary
    from drydem.report.plots import mechanism_figure, pushover_figure

    try:
        path = examples.resolve(target)
        model = _with_overrides(load_model(path), kn=kn, ks=ks, friction=friction, points=points, density=density, criterion=criterion)
        settings = TiltSettings(
            increment_deg=increment, adaptive=adaptive, stop_displacement_m=stop_displacement, loading=loading,
            monitor=monitor, max_angle_deg=max_angle,
        )
        if monitor is not None:
            model.block_index(monitor)
    except DrydemError as exc:
        raise click.ClickException(str(exc)) from None
    if resume and (out is None or not (out / CHECKPOINT).is_file()):
        raise click.ClickException(f"--resume needs --out DIR holding a {CHECKPOINT} from an earlier run")
    out = out or Path("results") / f"{path.stem}-{datetime.now():%Y%m%d-%H%M%S}"
    out.mkdir(parents=True, exist_ok=True)
    click.echo(f"{path}: {model.n_blocks} blocks, kn {model.joint.kn:.3g} Pa/m, ks {model.joint.ks:.3g} Pa/m, "
               f"mu {model.joint.friction:g}, {model.contacts.points_per_length} points per length -> {out}")
    with tqdm(desc="tilting", unit=" cycles", unit_scale=True, leave=False) as bar:

        def progress(theta, cycles, ux):
            bar.update(cycles - bar.n)
            bar.set_postfix_str(f"{theta:.2f} deg, ux {ux * 1e3:.2f} mm")

        try:
            result = tilt_analysis(
                model, settings, on_record=PushoverWriter(out, append=resume), on_progress=progress, checkpoint=out / CHECKPOINT, resume=resume
            )
        except DrydemError as exc:
            raise click.ClickException(str(exc)) from None
        except KeyboardInterrupt:
            click.echo(f"\ninterrupted; what was found is in {out}. Go on with the same command plus --out {out} --resume", err=True)
            raise SystemExit(130) from None
    write_summary(out, result, model)
    pushover_figure(result, out / "pushover.png", title=path.stem)
    collapse = result.collapse_angle_deg
    lost_by_then = frozenset(name for name, theta in result.lost_blocks if collapse is not None and theta <= collapse)
    states = [
        ("last equilibrium" if collapse is not None else "under gravity", result.collapse_state or result.final_state, lost_by_then),
        (f"past collapse ({result.ended_by})", result.final_state, frozenset(name for name, _ in result.lost_blocks)),
    ]
    mechanism_figure(model, states, out / "mechanism.png", monitored=result.monitored_block)
    if not result.stable_under_gravity:
        click.echo("the model cannot stand under its own weight (state saved in the plots)")
    elif result.collapse_angle_deg is None:
        click.echo(f"no collapse up to {max_angle} deg")
    else:
        click.echo(f"collapse angle  {result.collapse_angle_deg:.2f} deg (load multiplier {result.load_multiplier:.4f}; ended by {result.ended_by})")
    dls = result.drift_limit_angles_deg
    click.echo("drift limits    " + ", ".join(f"{float(k):.2%}: " + ("not reached" if v is None else f"{v:.2f} deg") for k, v in dls.items()))
    if result.lost_blocks:
        first = min(theta for _, theta in result.lost_blocks)
        click.echo(f"lost blocks     {len(result.lost_blocks)} fell out of the model, the first at {first:.2f} deg (listed in summary.json)")
    click.echo(f"cycles          {result.cycles} in {result.runtime_s:.1f} s; results in {out}")


def _with_overrides(model: Model, *, kn, ks, friction, points, density, criterion) -> Model:
    """The model with the command-line options that were given."""
    joint = {k: v for k, v in {"kn": kn, "ks": ks, "friction": friction}.items() if v is not None}
    changes = {}
    if joint:
        changes["joint"] = replace(model.joint, **joint)
    if points is not None:
        changes["contacts"] = replace(model.contacts, points_per_length=points)
    if criterion is not None:
        changes["solver"] = replace(model.solver, criterion=criterion)
    return model.replace(density=density, **changes) if changes or density is not None else model
