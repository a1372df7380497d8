"""Wall files: a brick layout (drydem.masonry.layout) with its bricks, material and analysis options.

A wall file is TOML::

    [wall]
    name = "WD3"                      # default: the file's stem
    title = "Lyon"                    # the team or a short description
    description = "..."               # free text; say here if the wall is a reconstruction
    [brick]
    length_m = 0.025                  # along the wall
    height_m = 0.0055
    width_m = 0.012                   # across the wall
    lintel_length_m = 0.075           # optional, default 3 brick lengths
    [layout]
    courses = \"\"\"
    bBBBBBBBb                         # top course first (drydem.masonry.layout)
    ...
    \"\"\"

plus the model file's optional tables ``[material]``, ``[joint]``, ``[contacts]``,
``[supports]`` and ``[solver]`` (drydem.io.model_file). The blocks stand on a fixed base block.
A TOML file with any of ``[wall]``, ``[brick]`` or ``[layout]`` is a wall file.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

from drydem.errors import ModelError
from drydem.files import plain_name_problem, read_toml
from drydem.model.tables import SECTIONS, errors_naming, no_unknown, parameters_from_dict
from drydem.masonry.layout import BrickSize, Layout, parse_layout
from drydem.model.assembly import Model, build_model
from drydem.model.parameters import ContactSettings, JointMaterial, SolverSettings, Supports

WALL_KEYS = {"name", "title", "description"}
LAYOUT_KEYS = {"courses"}
#: the tables only a wall file has: any of them makes a TOML file a wall file
WALL_TABLES = {"wall", "brick", "layout"}
#: what a wall file's layout looks like, for the messages
COURSES_FORM = 'courses = """...""", one course per line, top course first'


@dataclass(frozen=True)
class Wall:
    """A wall file, read: what it says of itself, its bricks and layout, and the model options."""

    name: str
    title: str
    description: str
    brick: BrickSize
    layout: Layout
    density: float
    joint: JointMaterial
    contacts: ContactSettings
    supports: Supports
    solver: SolverSettings
    source: str

    def model(self) -> Model:
        """The wall's blocks on their fixed base, with the file's material and options."""
        with errors_naming(self.source):
            return build_model(
                self.layout.blocks(self.brick), density=self.density, joint=self.joint, contacts=self.contacts,
                supports=self.supports, solver=self.solver, source=self.source,
            )


def is_wall_file(data: dict) -> bool:
    """Whether parsed TOML is a wall file rather than a model file: it has one of
    :data:`WALL_TABLES` (so that a wall file missing its ``[layout]`` is told so, not read as a
    model file with unknown tables)."""
    return not WALL_TABLES.isdisjoint(data)


def load_wall(path: str | Path) -> Wall:
    """Read a wall file; ModelError naming the file, the table or the layout's line."""
    path = Path(path)
    data, text = read_toml(path)
    return wall_from_dict(data, source=str(path), text=text, default_name=path.stem)


def wall_from_dict(data: dict, *, source: str, text: str = "", default_name: str = "wall") -> Wall:
    """A wall from parsed TOML (it must have a ``[layout]``); ``text``, the file's text, lets
    layout errors give file line numbers."""
    no_unknown(data, {*WALL_TABLES, "material", *SECTIONS}, source, "top level")
    if "layout" not in data:
        raise ModelError(f"{source}: a wall file needs a [layout] table with {COURSES_FORM} (drydem.masonry.layout)")
    meta, brick_table, layout_table = (data.get(key, {}) for key in ("wall", "brick", "layout"))
    no_unknown(meta, WALL_KEYS, source, "[wall]")
    no_unknown(layout_table, LAYOUT_KEYS, source, "[layout]")
    no_unknown(brick_table, {"length_m", "height_m", "width_m", "lintel_length_m"}, source, "[brick]")
    with errors_naming(source):
        name, title, description = _texts(meta, default_name)
        missing = sorted({"length_m", "height_m", "width_m"} - set(brick_table))
        if missing:
            raise ModelError(f"[brick] needs {', '.join(missing)}")
        brick = BrickSize(**brick_table)
        courses = layout_table.get("courses")
        if not isinstance(courses, str):
            raise ModelError(f"[layout] needs {COURSES_FORM}")
        first_line = _courses_line(text, courses)
        where = source if first_line is not None else f"{source}: [layout] courses"
        layout = parse_layout(courses, brick, source=where, first_line=first_line or 1)
        params = parameters_from_dict(data, source)
    return Wall(name=name, title=title, description=description, brick=brick, layout=layout, source=source, **params)


def _texts(meta: dict, default_name: str) -> tuple[str, str, str]:
    """``[wall]``'s name (default ``default_name``), title and description, each a string; the
    name also names the results folder, so it must be a plain file name (:func:`drydem.files.plain_name_problem`)."""
    values = {"name": default_name, "title": "", "description": ""} | meta
    for key, value in values.items():
        if not isinstance(value, str):
            raise ModelError(f"[wall] {key} = {value!r}: must be a string")
    name = values["name"]
    problem = plain_name_problem(name)
    if problem is not None:
        raise ModelError(f"[wall] name = {name!r}: {problem}")
    return name, values["title"], values["description"]


def _courses_line(text: str, courses: str) -> int | None:
    """The line of the file ``text`` on which the string ``courses`` starts: after the line of
    its ``courses =`` key for a multi-line string (TOML drops the newline after the quotes).
    None where the file does not hold it as written (no text, a string with escapes such as
    ``\\n``, a quoted or dotted key)."""
    for match in re.finditer(r"^[ \t]*courses[ \t]*=[ \t]*(\"\"\"|'''|\"|')\n?", text, re.MULTILINE):
        if text.startswith(courses, match.end()):
            return text.count("\n", 0, match.end()) + 1
    return None
