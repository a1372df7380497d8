"""Commands on a model itself: ``check``, ``show``, ``export`` and ``designs``."""

from __future__ import annotations

import os
import time
from pathlib import Path
from typing import TYPE_CHECKING

import click

from drydem.masonry import designs
from drydem.errors import DrydemError
from drydem.cli.common import (
    _factor, IMPERFECTION_OPTIONS, PLAIN_FLOAT, imperfection_options, imperfections_from_options, main, more_cycles_advice, out_path,
    resolve_target, unit_option,
)

if TYPE_CHECKING:
    from drydem.engine.simulation import Simulation
    from drydem.io.target import Target
    from drydem.masonry.imperfections import Imperfections
    from drydem.model.assembly import Model


@main.command()
@click.argument("target")
@click.option("--settle", is_flag=True, help="Also cycle to equilibrium under vertical gravity and report the settlement.")
@click.option("--strict", is_flag=True, help="Fail if a wall breaks the competition brief (a wall only).")
@unit_option
def check(target: str, settle: bool, strict: bool, unit: str) -> None:
    """Validate TARGET (a built-in wall, a wall or model file, or a .wrl/.obj/.stl/.json) and print
    its blocks, contacts and timestep; warn (stderr) of movable blocks that touch nothing and of
    a model with no fixed block, which fall under gravity."""
    from drydem.masonry.brief import brief_violations
    from drydem.analysis.support import unsupported
    from drydem.engine.narrow_phase import kind_counts
    from drydem.engine.simulation import Simulation
    from drydem.model.rotation import matrices

    found = resolve_target(target, unit)
    _strict_needs_a_wall(strict, found)
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
    kinds = kind_counts(model.geometry, c.pairs, sim.state.position, matrices(sim.state.quaternion), tolerance=model.contact_tolerance,
                        density=density)
    of_kinds = ", ".join(f"{count} {name}" for name, count in kinds.items() if count)
    click.echo(f"contacts        {len(c.pairs)}{f' ({of_kinds})' if of_kinds else ''}, {c.count} sub-contacts "
               f"({density.along} points per length, {density.across} across y)")
    click.echo(f"contact area    {c.area.sum():.6g} m2, tolerance {model.contact_tolerance:.3g} m")
    click.echo(f"joint           {model.joint.stiffness_text}, friction {model.joint.friction:g}")
    mass_note = " (mass scaled)" if model.solver.mass_scaling else ""
    click.echo(f"timestep        {sim.timestep:.4g} s{mass_note}")
    floating = [model.block_name[b] for b in unsupported(model, c)]
    if floating:
        click.echo(f"unsupported     {len(floating)} movable blocks touch nothing and will fall under gravity: "
                   + ", ".join(repr(name) for name in floating[:10]) + (", ..." if len(floating) > 10 else ""), err=True)
    if not model.block_fixed[:, 2].any():  # as a floating block above, a warning: tilt says the model cannot stand
        click.echo("unsupported     no fixed block (none marked fixed nor held vertically by [supports]): nothing holds the model up "
                   "under gravity (tilt: cannot stand; limit: unstable); mark a support block fixed = true", err=True)
    spread = _mass_spread(model)
    if spread is not None and model.solver.criterion == "ratio":
        click.echo(spread, err=True)
    if settle:
        _settle(sim)


#: the ratio of the heaviest movable block's mass to the lightest's beyond which ``drydem check``
#: warns that the ratio criterion may call a moving model at rest (README, "Equilibrium")
MASS_SPREAD_WARNING = 1e6


def _mass_spread(model) -> str | None:
    """A warning if the movable blocks' masses span more than :data:`MASS_SPREAD_WARNING`: the
    ratio criterion divides by the mean weight, which the heaviest set, while the timestep
    follows the lightest, so a heavy block's oscillation spans many cycles and passes its
    equilibrium at speed (a 10 m block under a 1e-6 m one was called at rest at 0.11 m/s)."""
    mass = model.block_mass[model.block_movable]
    if mass.size < 2 or mass.max() <= MASS_SPREAD_WARNING * mass.min():
        return None
    return (f"warning         the movable blocks' masses span {mass.max() / mass.min():.1e} ({mass.min():.3g} to {mass.max():.3g} kg): "
            "the ratio criterion divides by the mean weight, which the heaviest set, while the timestep follows the lightest, "
            "so a heavy block may pass its equilibrium at speed and be called at rest; use [solver] criterion = \"velocity\"")


def _strict_needs_a_wall(strict: bool, found: Target) -> None:
    """--strict checks a wall against the competition brief: a usage error for a TARGET that is
    not a wall (a model file, a building, a mesh), for which it would be silently ignored."""
    if strict and found.wall is None:
        raise click.UsageError(f"--strict checks a wall against the competition brief; {found.path} is not a wall "
                               "(a built-in wall or a wall file) but a model, building or mesh")


def _fail_if_strict(strict: bool, violations: list[str], found: Target) -> None:
    """Exit 1 if ``strict`` and the wall of ``found`` breaks the brief (``violations``)."""
    if strict and violations:
        plural = "s" if len(violations) != 1 else ""
        raise click.ClickException(f"{found.path}: breaks the competition brief ({len(violations)} violation{plural})")


def _settle(sim: Simulation) -> None:
    """Cycle ``sim`` to equilibrium under gravity and print it; stopped, unconverged, as soon as a
    block falls out of the model (the tilt's rule, drydem.analysis.support.dropped_out: two of
    its heights below where it was drawn), which otherwise fell on for up to max_cycles."""
    import numpy as np
    from tqdm import tqdm

    from drydem.analysis.support import LARGE_CLOSURE_FRACTION, dropped_out, largest_closure, lost_drops, moved_rigidly, too_soft_joints
    from drydem.analysis.tilt import TiltSettings

    model = sim.model
    lost_drop = lost_drops(model, TiltSettings().lost_drop_heights)
    fallen: list[int] = []

    def fell() -> bool:
        fallen[:] = np.flatnonzero(dropped_out(model, sim.state, sim.contacts, sim.active, lost_drop)).tolist()
        return bool(fallen)

    start = time.perf_counter()
    with tqdm(desc="settling under gravity", unit=" cycles", leave=False) as bar:

        def progress(cycles, stats):
            bar.update(cycles - bar.n)
            bar.set_postfix(ratio=f"{stats.ratio:.2e}", speed=f"{stats.max_speed:.2e} m/s")

        result = sim.cycle_to_equilibrium(progress=progress, stop=fell)
    elapsed = time.perf_counter() - start
    drop = model.block_centroid[:, 2] - sim.state.position[:, 2]
    status = "converged" if result.converged else "stopped, a block fell" if fallen else "NOT converged"
    click.echo(f"equilibrium     {status} after {result.cycles} cycles ({result.criterion} {result.ratio:.2e}), {elapsed:.2f} s")
    if fallen:  # the verdict and reasons of tilt's stage 1 (found by a hunt: said to be no convergence)
        soft = too_soft_joints(model, fallen)
        click.echo(f"fell out        {len(fallen)} blocks dropped more than two of their heights: "
                   + ", ".join(repr(model.block_name[b]) for b in fallen[:10]) + (", ..." if len(fallen) > 10 else "")
                   + ": the model cannot stand under its own weight" + (f"; {soft}" if soft else ""), err=True)
    elif not result.converged:
        click.echo(f"no equilibrium  within [solver] max_cycles = {model.solver.max_cycles}: no verdict on whether it stands; "
                   + more_cycles_advice(model, "raise max_cycles (or check damping) and run again"), err=True)
    top = int(np.argmax(model.block_centroid[:, 2]))
    click.echo(f"settlement      {drop.max() * 1e3:.4g} mm max, top block {model.block_name[top]!r} {drop[top] * 1e3:.4g} mm")
    moved, turn, move = moved_rigidly(model, sim.state)
    if moved >= 0 and not fallen:
        click.echo(f"note: block {model.block_name[moved]!r} turned {np.degrees(turn):.1f} deg and moved {move * 1e3:.4g} mm sideways "
                   "under its own weight: more than joints give, so it toppled or slid; the model does not stand as drawn, "
                   "and the equilibrium reached is another", err=True)
    fraction, block = largest_closure(model, sim.contacts)
    if fraction > LARGE_CLOSURE_FRACTION:
        click.echo(f"note: a joint of {model.block_name[block]!r} closes by {fraction:.0%} of the block's thickness: beyond the small "
                   "closures a zero-thickness joint stands for, so this settlement is the springs', not the masonry's; stiffen "
                   "[joint] kn", err=True)
    if not result.converged:
        raise SystemExit(1)

@main.command(name="designs")
def list_designs() -> None:
    """List the built-in walls: WD1-WD7 (reconstructions of the seed paper's competition walls)
    and the examples, with their void ratio, bricks (the model has one block more, the fixed
    base) and the competition-brief check; and the built-in 3D buildings (building-small,
    building-large) with their blocks, the fixed base among them."""
    from drydem.masonry.brief import brief_violations

    click.echo(f"{'name':<16} {'title':<28} {'voids':>6} {'bricks':>6}  brief")
    for name in designs.names():
        wall = resolve_target(name).wall
        violations = brief_violations(wall)
        verdict = "ok" if not violations else "breaks it: " + "; ".join(violations)
        click.echo(f"{name:<16} {wall.title[:28]:<28} {wall.layout.void_ratio:>6.1%} {len(wall.layout.solid_units):>6}  {verdict}")
    from drydem.masonry.building import BUILDINGS

    click.echo(f"\n{'name':<16} {'3D building':<28} {'plan':>13} {'blocks':>6}")
    for name, building in BUILDINGS.items():
        spec = building.spec
        title = f"{spec.storeys} storeys, {spec.windows_per_wall} windows a wall"
        plan = f"{spec.length_m:g} x {spec.width_m:g} m"
        click.echo(f"{name:<16} {title:<28} {plan:>13} {spec.block_count:>6}")
    click.echo("\nA wall's model has its bricks and a fixed base; a building's blocks include its fixed base.")
    click.echo("The buildings (drydem.masonry.building) are 3D: --tilt-axis x loads their long walls out of plane.")
    click.echo("WD1-WD7 are reconstructions that obey the brief, not the original drawings (drydem show NAME draws one).")

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
@click.option("--out", "-o", type=click.Path(dir_okay=False), callback=out_path, help="PNG file (default: TARGET.png here).")
@click.option("--overwrite", is_flag=True, help="Replace the file if it exists (else an existing file is kept and the command fails).")
@click.option("--strict", is_flag=True, help="Fail if a wall breaks the competition brief (a wall only).")
@unit_option
@imperfection_options
@click.option("--exaggerate", type=PLAIN_FLOAT, default=1.0, show_default=True, metavar="FACTOR", callback=_factor,
              help="Draw the imperfections' deviations FACTOR times larger (the same draws), so that a 0.1 mm scatter shows.")
def show(target: str, out: Path | None, overwrite: bool, strict: bool, unit: str, seed: int, height_sd: float | None, height_distribution: str,
         flatness_sd: float | None, misalignment_sd: float | None, exaggerate: float) -> None:
    """Draw TARGET as built (bricks, half bricks, headers, lintel, voids, the monitored block) to
    a PNG (or another format matplotlib writes, by the suffix), written whole or not at all; an
    existing file is replaced only with --overwrite (checked before drawing). With --height-sd,
    --flatness-sd or --misalignment-sd, draw a wall's bricks imperfect, drawn from --seed
    (drydem.masonry.imperfections), their deviations --exaggerate times larger."""
    from drydem.analysis.tilt import monitored_block
    from drydem.masonry.brief import brief_violations
    from drydem.files import replaced_atomically
    from drydem.report.plots import layout_figure

    imperfections = imperfections_from_options(height_sd, height_distribution, flatness_sd, misalignment_sd)
    if imperfections is None and exaggerate != 1.0:
        raise click.UsageError("--exaggerate scales the imperfections' deviations: give --height-sd, --flatness-sd or "
                               "--misalignment-sd too (a perfect wall has none to draw larger)")
    found = resolve_target(target, unit)
    _strict_needs_a_wall(strict, found)
    out = _figure_out(out or Path(f"{found.name}.png"), overwrite)
    model, wall = found.model, found.wall
    title = found.name if wall is None else f"{wall.name} {wall.title}: {wall.layout.void_ratio:.1%} voids"
    voids = wall.layout.void_outlines(wall.brick) if wall is not None else []
    if imperfections is not None:
        model, note = _imperfect_drawing(found, imperfections, seed, exaggerate)
        title, voids = f"{title}\n{note}", []  # the voids' outlines are the perfect wall's
    monitored = model.block_name[monitored_block(model)]
    kinds = wall.layout.kinds() if wall is not None else None
    try:
        with replaced_atomically(out, replace=overwrite) as partial:
            layout_figure(model, partial, kinds=kinds, voids=voids, monitored=monitored, title=title)
    except DrydemError as exc:
        raise click.ClickException(str(exc)) from None
    click.echo(f"{found.name}: {model.n_blocks} blocks, monitored block {monitored} -> {out}")
    if wall is not None:
        violations = brief_violations(wall)
        for violation in violations:
            click.echo(f"brief: {violation}", err=True)
        _fail_if_strict(strict, violations, found)


def _figure_out(out: Path, overwrite: bool) -> Path:
    """``out`` if a figure can be drawn there: a format matplotlib writes (its suffix), and nothing
    there yet, or a regular file and ``overwrite`` (drydem.files.replaceable); else exit naming it."""
    from drydem.files import replaceable
    from drydem.report.plots import figure_path

    try:
        return replaceable(figure_path(out), overwrite, other="another --out")
    except DrydemError as exc:
        raise click.ClickException(str(exc)) from None


def _file_name(ctx, param, value: str) -> Path:
    """OUTPUT as a path, or a usage error if it is empty or blank (Path("") is "."), or if it ends
    with a separator or in ``.`` or ``..``: it then names a folder (``out.json/``, ``out.json/.``),
    which Path would silently read as the file ``out.json``."""
    if not value.strip():
        raise click.BadParameter(f"{value!r}: an empty path; give a file name")
    if value.endswith(("/", os.sep)) or os.path.basename(value) in (".", ".."):
        raise click.BadParameter(f"{value!r} names a folder (it ends with a separator, . or ..); give a file name")
    return Path(value)


@main.command()
@click.argument("target")
@click.argument("output", type=click.Path(dir_okay=False), callback=_file_name)
@click.option("--overwrite", is_flag=True, help="Replace OUTPUT if it exists (else an existing file is kept and the command fails).")
@unit_option
def export(target: str, output: Path, overwrite: bool, unit: str) -> None:
    """Write TARGET's blocks to OUTPUT: a model file (.toml), ParaView (.vtu), an Itasca 3DEC command
    file (.dat, .3ddat: blocks, supports, joint, density, gravity) or a mesh (.obj,
    .stl, or .json, a list of compas Meshes: block names, shapes and fixed blocks; not the
    material, joint, contacts, supports or solver, which a .toml keeps). OUTPUT is written
    whole or not at all, and an existing one is replaced only with --overwrite."""
    from drydem.io.compas_json import write_compas
    from drydem.io.itasca import write_3dec
    from drydem.io.mesh import write_mesh
    from drydem.io.model_file import save_model
    from drydem.files import replaceable, replaced_atomically
    from drydem.io.vtk import write_vtu

    writers = {".toml": save_model, ".vtu": write_vtu, ".obj": write_mesh, ".stl": write_mesh, ".json": write_compas,
               ".dat": write_3dec, ".3ddat": write_3dec}
    writer = writers.get(output.suffix.lower())
    if writer is None:
        raise click.ClickException(f"{output}: unknown output type {output.suffix!r}; drydem writes {', '.join(writers)}")
    try:
        replaceable(output, overwrite, other="another OUTPUT")
        found = resolve_target(target, unit)
        with replaced_atomically(output, replace=overwrite) as partial:
            writer(found.model, partial)
    except DrydemError as exc:
        raise click.ClickException(str(exc)) from None
    click.echo(f"{found.name}: {found.model.n_blocks} blocks -> {output}")
    if writer in (write_mesh, write_compas):
        click.echo(f"note: {output} keeps the block names, shapes and fixed blocks, not the material, joint, contacts, "
                   "supports or solver settings (export to .toml for those)", err=True)
