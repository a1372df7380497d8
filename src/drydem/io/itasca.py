"""Itasca 3DEC command files (``.dat``, ``.3ddat``): a model as the commands that build it in 3DEC 7 or 9.

:func:`write_3dec` writes, after a comment header (drydem version, the model's source, SI units):

* ``model new`` and ``model large-strain on`` (blocks rotate and slide by finite amounts);
* each block as ``block create group 'NAME' slot 'drydem' polyhedron face x,y,z x,y,z ... face ...``:
  its faces' vertices, clockwise seen from outside the block as 3DEC asks (drydem stores them
  counter-clockwise, so each face is written reversed), one face per line joined by the
  continuation ``...``, coordinates to full double precision; the block's drydem name is its
  group in the slot ``drydem``;
* the supports: every block in one group of the slot ``support`` per set of degrees of freedom
  that drydem holds (``fixed``: all six, the base; ``held-y-rx-rz``: the in-plane walls'
  movable blocks; ``free``: none), then ``block fix velocity-y range group ... slot 'support'``,
  one degree of freedom (``velocity-x`` ... ``rotation-z``, 3DEC's velocities and angular
  velocities about the world axes) per line, or ``block fix`` without a keyword for all six.
  A fixed velocity keeps its value, zero at the start as in drydem. Every restraint of
  :class:`drydem.model.parameters.Supports` (and the rx, rz that an in-plane model adds) is a
  3DEC velocity, so nothing is left out;
* ``block property density`` (the most common density for all blocks, then each other block's);
* the joints: ``block contact generate-subcontacts``, ``block contact jmodel assign mohr`` and
  ``block contact property stiffness-normal kn stiffness-shear ks friction phi cohesion c
  tension t``, with phi = atan(mu) in degrees (3DEC takes a friction angle, drydem a Coulomb
  coefficient); the same values as the material table's default
  (``block contact material-table default property ...``), which 3DEC gives the contacts that
  form while the blocks move (it has no default stiffness, the manual says, so one must be given);
* ``block mechanical damping local alpha`` (drydem's local damping is 3DEC's) and
  ``model gravity 0 0 -9.81``.

Comments at the end say what 3DEC does its own way and is not written: drydem's sub-contact
grid and contact tolerance (3DEC triangulates the faces; ``block face triangulate`` refines
them), the convergence criterion and the analysis (tilting, shaking). A stress-dependent joint
law has no counterpart in 3DEC's Mohr-Coulomb joint, and a block name that 3DEC cannot keep as a
group name (empty, or with a quote, ``=`` or a line break) cannot be written: both are refused
(ModelError) before anything is written.

Sources, the Itasca manuals (docs.itascacg.com, 3DEC 7.0 ``3dec700`` and 9.0 ``itasca900``):
3DEC > Modeling > Problem solving > "Creating Single Blocks" (``block create polyhedron``,
faces clockwise from outside, convex, ``model new``),
``3dec/docproject/source/modeling/problemsolving/singleblocks.html``; the block command
reference ``3dec/block/doc/manual/block_manual/block_commands/block/cmd_block.create.html``
(``group s1 slot s2``, the continuation ``...`` anywhere but inside a vertex), ``cmd_block.group``,
``cmd_block.fix`` (keywords velocity-x/-y/-z, rotation-x/-y/-z; blocks whose centroid is in
the range), ``cmd_block.property`` (density), ``cmd_block.mechanical`` (damping local), and
``block_commands/block.contact/cmd_block.contact.generate-subcontacts``, ``.jmodel``,
``.property``, ``.material-table``; the Mohr-Coulomb joint model's property table
(``3dec/docproject/source/theory/mohrcoulomb/mohrcoulomb.html``: stiffness-normal,
stiffness-shear Pa/m, friction deg, cohesion, tension Pa); the common model commands
``common/kernel/doc/manual/model/commands/cmd_model.new``, ``cmd_model.large-strain``,
``cmd_model.gravity``; the range element ``group s slot s2``. The command and keyword lists
were read through itasca-mcp 0.10.6's extraction of the 3DEC 7.0 and 9.0 command reference,
and the statement forms checked against compas-3dec 0.2.0 (``block create group ... poly face
...``, ``block contact material-table default property ...``), which drives 3DEC itself.
"""

from __future__ import annotations

import math
from collections import Counter
from pathlib import Path

import numpy as np

from drydem import __version__
from drydem.errors import ModelError
from drydem.files import write_text
from drydem.model.assembly import Model
from drydem.model.parameters import FILE_PATH, G, InstanceOf, SolverSettings, check_arguments

#: the group slots that hold each block's drydem name and its support group
NAME_SLOT, SUPPORT_SLOT = "drydem", "support"
#: 3DEC's block fix keyword of each drydem degree of freedom (x, y, z, rx, ry, rz)
FIX_KEYWORDS = ("velocity-x", "velocity-y", "velocity-z", "rotation-x", "rotation-y", "rotation-z")
DOF_NAMES = ("x", "y", "z", "rx", "ry", "rz")
#: characters a 3DEC group name cannot hold: its quote, the slot=group separator, line breaks
NOT_IN_NAMES = ("'", "=", "\n", "\r")


def write_3dec(model: Model, path: str | Path) -> None:
    """Write ``model`` to ``path`` as a 3DEC command file (see the module docstring); ModelError
    for an argument that is not what it must be (found by a hunt: a bare TypeError for a path of
    None) or a model 3DEC cannot take."""
    check_arguments("write_3dec", {"model": InstanceOf(Model), "path": FILE_PATH}, model=model, path=path)
    write_text(path, threedec_commands(model))


def threedec_commands(model: Model) -> str:
    """The 3DEC command file of ``model``, as text; ModelError if it is no Model or 3DEC cannot take it."""
    check_arguments("threedec_commands", {"model": InstanceOf(Model)}, model=model)
    _check_exportable(model)
    sections = (_header(model), _blocks(model), _supports(model), _densities(model), _joints(model), _solver(model),
                _not_written(model))
    return "\n".join(line for section in sections for line in section) + "\n"


def _check_exportable(model: Model) -> None:
    """ModelError for a stress-dependent joint law or a block name 3DEC cannot keep."""
    if model.joint.stress_dependent:
        raise ModelError(f"{model.source}: [joint] model = {model.joint.model!r}: 3DEC's Mohr-Coulomb joint (jmodel mohr) "
                         "has constant stiffness; export a model with the constant law")
    for name in model.block_name:
        if not name.strip() or any(c in name for c in NOT_IN_NAMES):
            raise ModelError(f"{model.source}: block {name!r}: a 3DEC group name cannot keep this name (empty, or with a quote, "
                             "'=' or a line break); rename the block")


def _header(model: Model) -> list[str]:
    fixed = int((~model.block_movable).sum())
    return [f"; drydem {__version__}: Itasca 3DEC command file (3DEC 7 and 9 syntax), written by drydem export",
            f"; model: {model.source}",
            "; units SI: m, kg, s; density kg/m3; joint stiffness Pa/m; cohesion, tension Pa; angles deg",
            f"; {model.n_blocks} rigid blocks ({fixed} fixed); z up, gravity along -z",
            "model new",
            "model large-strain on"]


def _blocks(model: Model) -> list[str]:
    lines = [f"; blocks: faces' vertices clockwise seen from outside; each block's drydem name is its group in slot '{NAME_SLOT}'"]
    for name, shape in zip(model.block_name, model.block_shape):
        faces = [" ".join(_vector(v) for v in shape.vertices[face[::-1]]) for face in shape.faces]
        lines.append(f"block create group '{name}' slot '{NAME_SLOT}' polyhedron ...")
        lines += [f"  face {face} ..." for face in faces[:-1]] + [f"  face {faces[-1]}"]
    return lines


def _supports(model: Model) -> list[str]:
    """One support group per set of held degrees of freedom: the most common for every block,
    then each other block's; then block fix per group and degree of freedom."""
    groups = [_support_group(row) for row in model.block_fixed]
    common = Counter(groups).most_common(1)[0][0]
    lines = [f"; supports: blocks grouped in slot '{SUPPORT_SLOT}' by the degrees of freedom drydem holds; "
             "a fixed velocity stays zero",
             f"block group '{common}' slot '{SUPPORT_SLOT}'"]
    lines += [f"block group '{group}' slot '{SUPPORT_SLOT}' {_block_range(name)}"
              for name, group in zip(model.block_name, groups) if group != common]
    for group, row in dict(zip(groups, model.block_fixed)).items():
        where = f"range group '{group}' slot '{SUPPORT_SLOT}'"
        lines += [f"block fix {where}"] if row.all() else [f"block fix {FIX_KEYWORDS[k]} {where}" for k in np.flatnonzero(row)]
    if model.in_plane:
        lines.append("; rotation-x and rotation-z are held because the model is in plane (drydem.model.assembly.Model.in_plane)")
    return lines


def _support_group(row: np.ndarray) -> str:
    """``fixed`` (all six degrees of freedom held), ``free`` (none), else ``held-`` and the held ones."""
    if row.all():
        return "fixed"
    return "held-" + "-".join(DOF_NAMES[k] for k in np.flatnonzero(row)) if row.any() else "free"


def _densities(model: Model) -> list[str]:
    common = Counter(model.block_density.tolist()).most_common(1)[0][0]
    lines = [f"block property density {_number(common)}"]
    return lines + [f"block property density {_number(rho)} {_block_range(name)}"
                    for name, rho in zip(model.block_name, model.block_density.tolist()) if rho != common]


def _joints(model: Model) -> list[str]:
    joint = model.joint
    phi_deg = math.degrees(math.atan(joint.friction))
    values = (f"stiffness-normal {_number(joint.kn)} stiffness-shear {_number(joint.ks)} friction {_number(phi_deg)} "
              f"cohesion {_number(joint.cohesion)} tension {_number(joint.tension)}")
    return [f"; joints: Mohr-Coulomb (jmodel mohr), friction angle atan({joint.friction:g}) = {phi_deg:.6g} deg",
            "block contact generate-subcontacts",
            "block contact jmodel assign mohr",
            f"block contact property {values}",
            f"block contact material-table default property {values}"]


def _solver(model: Model) -> list[str]:
    return [f"block mechanical damping local {_number(model.solver.damping)}",
            f"model gravity 0 0 {_number(-G)}"]


def _not_written(model: Model) -> list[str]:
    density = model.contact_density
    return [f"; not written, 3DEC does it its own way: drydem's sub-contact grid ({density.along} points per length, "
            f"{density.across} across y) and contact tolerance ({model.contact_tolerance:.4g} m): 3DEC triangulates the faces "
            "(block face triangulate refines them);",
            f"; the convergence criterion ({_criterion(model.solver)}) and the analysis (drydem tilt, drydem shake): "
            f"settle under gravity with e.g. model solve ratio-local {_number(model.solver.ratio)} (3DEC's ratio is its own measure)"]


def _criterion(solver: SolverSettings) -> str:
    """drydem's equilibrium criterion in words, with its value."""
    if solver.criterion == "velocity":
        return f"velocity: the largest block point speed below {_number(solver.max_velocity)} m/s"
    return f"ratio: the largest unbalanced force over the mean block weight below {_number(solver.ratio)}"


def _block_range(name: str) -> str:
    return f"range group '{name}' slot '{NAME_SLOT}'"


def _vector(point) -> str:
    return ",".join(_number(x) for x in point)


def _number(value: float) -> str:
    """Shortest text that reads back as the same double (Python's repr)."""
    return repr(float(value))
