"""The model file: a TOML description of blocks, joints, contacts, supports and solver.

Example (units SI; every table but ``[[block]]`` optional)::

    [material]
    density = 1800.0            # kg/m3 (a block may override it)
    [joint]
    kn = 3e7                    # Pa/m
    ks = 3e7                    # Pa/m
    friction = 0.5              # Coulomb coefficient
    cohesion = 0.0              # Pa
    tension = 0.0               # Pa
    [contacts]
    points_per_length = 4
    tolerance = 2.5e-4          # m (default: 5 % of the thinnest block)
    [supports]
    fix_y = true                # every block's y translation fixed (also fix_x, fix_z, fix_rx, ...)
    [solver]
    damping = 0.8               # local damping alpha
    criterion = "ratio"         # or "velocity"
    [[block]]
    name = "base"
    fixed = true
    box = { min = [-0.05, -0.006, -0.01], max = [0.25, 0.006, 0.0] }
    [[block]]
    name = "brick"
    vertices = [[0, -0.006, 0], [0.025, -0.006, 0], ...]   # convex hull of these points

Unknown tables or keys are errors (a misspelt ``frction`` must not silently fall back
to the default); so are wrong types. Messages name the file, table, block and key.
"""

from __future__ import annotations

import json
from dataclasses import asdict
from pathlib import Path
from types import SimpleNamespace

import numpy as np

from drydem.errors import ModelError
from drydem.files import read_toml, writable, write_text
from drydem.model.geometry import ConvexPolyhedron, box, convex_hull, face_interior_points
from drydem.model.assembly import BLOCK_RULES, Block, Model, build_model
from drydem.model.parameters import FILE_PATH, TEXT, InstanceOf, check_arguments, field_problems, is_number, refuse, shown
from drydem.model.tables import SECTIONS, errors_naming, no_unknown, parameters_from_dict

BLOCK_KEYS = {"name", "fixed", "density", "box", "vertices"}


def load_model(path: str | Path) -> Model:
    """Read and validate a model file; raises ModelError naming the file and the culprit
    (and ``path`` itself if it is no path)."""
    check_arguments("load_model", {"path": FILE_PATH}, path=path)
    path = Path(path)
    data, _ = read_toml(path)
    return model_from_dict(data, source=str(path))


def model_from_dict(data: dict, *, source: str = "<dict>") -> Model:
    """Build a model from the parsed TOML structure (see module docstring); ModelError for a
    ``source`` that is no text (messages begin with it)."""
    check_arguments("model_from_dict", {"source": TEXT}, source=source)
    no_unknown(data, {"material", "block", *SECTIONS}, source, "top level")
    with errors_naming(source):
        params = parameters_from_dict(data, source)
        blocks = data.get("block")
        if not isinstance(blocks, list) or not blocks:
            raise ModelError(f"{source}: no [[block]] entries")
        return build_model([_block(b, i, source) for i, b in enumerate(blocks)], source=source, **params)


def _block(entry: dict, index: int, source: str) -> Block:
    name = entry.get("name", f"block{index}") if isinstance(entry, dict) else f"block{index}"
    where = f"[[block]] #{index} ({shown(name)})"
    no_unknown(entry, BLOCK_KEYS, source, where)
    fields = SimpleNamespace(name=name, fixed=entry.get("fixed", False), density=entry.get("density"))
    refuse(field_problems(fields, {key: BLOCK_RULES[key] for key in vars(fields)}, lambda key: f"{source}: {where} {key}",
                          optional=("density",)))  # Block's rules, said before its geometry is built, naming the file
    if ("box" in entry) == ("vertices" in entry):
        raise ModelError(f"{source}: {where} needs exactly one of 'box' or 'vertices'")
    if "box" in entry:
        spec = entry["box"]
        no_unknown(spec, {"min", "max"}, source, f"{where} box")
        if "min" not in spec or "max" not in spec:
            raise ModelError(f"{source}: {where} box needs 'min' and 'max'")
        shape = box(_point(spec["min"], f"{source}: {where} box min"), _point(spec["max"], f"{source}: {where} box max"),
                    name=f"block {name!r}")
    else:
        vertices = entry["vertices"]
        if not isinstance(vertices, list):
            raise ModelError(f"{source}: {where} vertices = {vertices!r}: must be a list of [x, y, z] points (m)")
        points = [_point(v, f"{source}: {where} vertex {k}") for k, v in enumerate(vertices)]
        shape = convex_hull(points, name=f"block {name!r}")
        _refuse_face_interior_points(points, shape, f"{source}: {where}")
    return Block(name=name, shape=shape, density=fields.density, fixed=fields.fixed)


def _refuse_face_interior_points(points: list, shape: ConvexPolyhedron, where: str) -> None:
    """ModelError if a listed vertex lies inside a face of the hull (neither a corner nor on an
    edge): the hull would drop it, and such a point is most often the re-entrant corner of a
    non-convex shape, as an L's inner corner, which the hull would silently fill in (else a
    needless point on a flat face)."""
    inner = face_interior_points(np.asarray(points), shape)
    if inner.size:
        k = int(inner[0])
        raise ModelError(f"{where} vertex {k} {points[k]} lies inside a face of the convex hull of the vertices, not at a corner, "
                         "and the hull would drop it: a re-entrant corner makes a non-convex shape (split it into convex "
                         "blocks); a point on a flat face, remove it")


def _point(value, where: str) -> list[float]:
    """``value`` as an [x, y, z] point in metres, or ModelError naming ``where`` (a boolean is
    not a coordinate, though Python counts True as 1)."""
    if not (isinstance(value, list) and len(value) == 3 and all(is_number(c) for c in value)):
        raise ModelError(f"{where} = {value!r}: must be [x, y, z], three finite numbers (m)")
    return value


def model_to_dict(model: Model) -> dict:
    """The model as the TOML structure :func:`model_from_dict` reads.

    Axis-aligned boxes are written as ``box = {min, max}``, other blocks as their hull vertices.
    """
    density = model.block_density
    common = float(np.median(density))
    data: dict = {"material": {"density": common}}
    for name in SECTIONS:
        data[name] = {k: v for k, v in asdict(getattr(model, name)).items() if v is not None}
    blocks = []
    for name, shape, fixed, rho in zip(model.block_name, model.block_shape, model.block_fixed, density):
        entry: dict = {"name": name}
        if fixed.all():
            entry["fixed"] = True
        if not np.isclose(rho, common, rtol=1e-12):
            entry["density"] = float(rho)
        lo, hi = shape.vertices.min(0), shape.vertices.max(0)
        if np.isclose(shape.volume, np.prod(hi - lo), rtol=1e-12):
            entry["box"] = {"min": lo.tolist(), "max": hi.tolist()}
        else:
            entry["vertices"] = shape.vertices.tolist()
        blocks.append(entry)
    data["block"] = blocks
    return data


def save_model(model: Model, path: str | Path, *, header: str = "") -> None:
    """Write ``model`` as a model file that :func:`load_model` reads back to the same model;
    ``header`` lines go first, as TOML comments.

    Written by hand rather than with a TOML library: the schema has only scalars and numeric
    arrays, and this keeps one line per block (tomli-w splits every array over many lines).
    ModelError naming an argument that is not what it must be (a path not ending in .toml); DrydemError
    naming ``path`` if it cannot be written (a folder, in a folder that does not exist, no permission).
    """
    check_arguments("save_model", {"model": InstanceOf(Model), "path": FILE_PATH, "header": InstanceOf(str)},
                    model=model, path=path, header=header)
    path = writable(path)
    if path.suffix.lower() != ".toml":  # TOML written into x.obj was taken silently
        raise ModelError(f"save_model path = {str(path)!r}: a model file is TOML, its name ends in .toml "
                         "(drydem.io.mesh.write_mesh writes .obj and .stl, drydem export every format)")
    data = model_to_dict(model)
    lines = [f"# {line}" for line in header.splitlines()]
    for table in ("material", *SECTIONS):
        lines += ["", f"[{table}]"] + [f"{k} = {_toml(v)}" for k, v in data[table].items()]
    for entry in data["block"]:
        lines += ["", "[[block]]"] + [f"{k} = {_toml(v)}" for k, v in entry.items()]
    write_text(path, "\n".join(lines).lstrip("\n") + "\n")


def _toml(value) -> str:
    """An inline TOML value: bool, int, float, str, list or dict of those."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (int, float)):
        return repr(value)
    if isinstance(value, str):  # JSON's ASCII escapes write a character past U+FFFF as two surrogates, which TOML refuses
        return json.dumps(value, ensure_ascii=False).replace("\x7f", "\\u007f")  # TOML escapes DEL too, JSON does not
    if isinstance(value, dict):
        return "{ " + ", ".join(f"{k} = {_toml(v)}" for k, v in value.items()) + " }"
    return "[" + ", ".join(_toml(v) for v in value) + "]"
