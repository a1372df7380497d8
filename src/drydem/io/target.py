"""What the commands analyse: a built-in wall, a wall file, a model file or an imported mesh."""

from __future__ import annotations

import os
from dataclasses import dataclass, replace
from pathlib import Path

from drydem.masonry import designs
from drydem.errors import ModelError
from drydem.model.parameters import TEXT, check_arguments, shown
from drydem.files import read_toml
from drydem.io.mesh import UNIT
from drydem.io.model_file import model_from_dict
from drydem.model.assembly import Model, base_under, build_model
from drydem.masonry.building import BUILDINGS, builtin_building
from drydem.masonry.walls import Wall, is_wall_file, wall_from_dict

#: file suffixes read as geometry to import, each closed convex shape a block
MESH_SUFFIXES = {".wrl": "VRML", ".vrml": "VRML", ".obj": "OBJ", ".stl": "STL", ".json": "compas JSON"}


@dataclass(frozen=True)
class Target:
    """A resolved target: its name (for titles and folders), file, model and, for walls, the
    wall; notes: what an imported file could not say and was assumed (the commands print them)."""

    name: str
    path: Path
    model: Model
    wall: Wall | None = None
    notes: tuple[str, ...] = ()
    builtin: bool = False

    @property
    def recorded(self) -> str:
        """The target as a result's summary records it, as a sweep's run does (RunSpec.target): a
        built-in's name, a file's absolute path (so that a report tells the user's from the paper's)."""
        return self.name if self.builtin else str(self.path.resolve())


def load_target(target: str, *, unit_m: float = 1.0) -> Target:
    """Resolve ``target``: the name of a built-in wall or building (``drydem designs``;
    :data:`drydem.masonry.building.BUILDINGS`), a wall file or a
    model file (.toml), or geometry to import (.wrl, .obj, .stl, compas .json; coordinates times ``unit_m``
    give metres). Imported blocks stand on a fixed base block (drydem.model.assembly.base_under) and
    get the default material and options. ModelError says what was tried (or names the argument
    that is not what it must be: ``target`` a text, ``unit_m`` drydem.io.mesh.UNIT)."""
    if isinstance(target, os.PathLike):
        target = os.fspath(target)
    check_arguments("load_target", {"unit_m": UNIT}, unit_m=unit_m)
    if not isinstance(target, str):
        check_arguments("load_target", {"target": TEXT}, target=target)
    if not target.strip():
        raise ModelError(f"{target!r}: an empty TARGET; give a built-in wall ({', '.join(designs.names())}), "
                         f"building ({', '.join(BUILDINGS)}) or a file")
    path = Path(target)
    try:
        if path.is_file():
            return _file_target(path, unit_m)
        found = "a folder, not a file" if path.is_dir() else "not a regular file" if os.path.lexists(path) else "no such file"
    except OSError as exc:  # a name the system refuses (too long, ...)
        found = exc.strerror or str(exc)
    if target in BUILDINGS:
        return Target(target, Path(target), builtin_building(target), builtin=True)
    builtin = designs.find(target)
    if builtin is None:
        named = target if target.isprintable() else shown(target)  # a NUL or an escape of a study's target, as written
        raise ModelError(f"{named}: {found}, and not a built-in wall ({', '.join(designs.names())}) "
                         f"or building ({', '.join(BUILDINGS)})")
    return replace(_file_target(builtin, unit_m), builtin=True)


def _file_target(path: Path, unit_m: float) -> Target:
    """The target in the file ``path`` (:func:`load_target`)."""
    suffix = path.suffix.lower()
    if suffix in MESH_SUFFIXES:
        model, notes = imported_model(path, unit_m=unit_m)
        return Target(path.stem, path, model, notes=tuple(notes))
    if suffix != ".toml":
        known = ", ".join([".toml", *MESH_SUFFIXES])
        raise ModelError(f"{path}: unknown file type {path.suffix!r}; drydem reads {known}")
    data, text = read_toml(path)
    if is_wall_file(data):
        wall = wall_from_dict(data, source=str(path), text=text, default_name=path.stem)
        return Target(wall.name, path, wall.model(), wall)
    return Target(path.stem, path, model_from_dict(data, source=str(path)))


def imported_model(path: Path, *, unit_m: float = 1.0) -> tuple[Model, list[str]]:
    """The blocks of a VRML, OBJ, STL or compas JSON file, density 1800 kg/m3 (or a compas_dem
    block's material's), the default joint and options, no supports (``drydem export`` writes it
    as a model file to edit), and notes on what was assumed. Blocks the file marks fixed
    (drydem.io.mesh, drydem.io.compas_json) are the supports; a file
    with none gets a fixed base block under its blocks (drydem.model.assembly.base_under), and a note."""
    from drydem.io.compas_json import read_compas
    from drydem.io.mesh import read_mesh
    from drydem.io.vrml import read_vrml

    kind = MESH_SUFFIXES[path.suffix.lower()]
    if kind == "VRML":
        blocks, notes = read_vrml(path, unit_m=unit_m)
    elif kind == "compas JSON":
        blocks, notes = read_compas(path, unit_m=unit_m)
    else:
        blocks, notes = read_mesh(path, unit_m=unit_m)
    if not any(b.fixed for b in blocks):
        blocks = [base_under(blocks), *blocks]
        notes.append(f"{path}: no block is marked fixed: the blocks stand on an added fixed block {blocks[0].name!r}")
    return build_model(blocks, density=1800.0, source=str(path)), notes
