"""The ``drydem`` command line."""

from __future__ import annotations

import time

import click
import numpy as np

from drydem import __version__, examples
from drydem.errors import DrydemError
from drydem.io.model_file import load_model
from drydem.solve import Simulation


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
    click.echo(f"contacts        {len(c.pairs)} face contacts, {c.count} sub-contacts ({model.contacts.points_per_length} points per length)")
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
