"""The brick-layout text format: a wall drawn one course per line, top course first.

The wall lies in the x-z plane (x along the wall, z up, y through its width). Each course
is a row of tokens, each as long as it says along the wall::

    B     a full brick (stretcher)
    b     a half brick
    H     a header brick (turned 90 deg: its width along the wall, its length across it) in a
          half-brick slot, centred, leaving a gap of (length/2 - width)/2 on each side
    L     the lintel: lintel_length_m long (default 3 brick lengths)
    .     a void half a brick long
    _     a void a brick long
    ,     a void a quarter of a brick long: an offset, e.g. for honeycomb bond, where the
          bricks of a course bear on the ends of two bricks below

A number before a token repeats it (``7B`` = ``BBBBBBB``); spaces are ignored, ``#`` starts
a comment. The bond and its offsets are written out: a running-bond course starts with a
half brick. Every course must have the length of the first one. A 2-brick wall of three
courses, the middle one with half bricks at its ends and a brick-long void between them::

    BB            # top course
    b_b
    BB            # bottom course, on the base block

Internally a course is a row of quarter-brick *cells*.
Blocks are named ``c{course}b{k}``: course 0 at the bottom, k counting the course's blocks
from x = 0. The wall's bottom is at z = 0, its left end at x = 0.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np

from drydem.errors import ModelError
from drydem.geometry import box
from drydem.model import Block, base_under

#: token -> (kind, cells); the lintel's cells depend on the brick size (None here)
TOKENS: dict[str, tuple[str, int | None]] = {
    "B": ("brick", 4),
    "b": ("half", 2),
    "H": ("header", 2),
    "L": ("lintel", None),
    ".": ("void", 2),
    "_": ("void", 4),
    ",": ("void", 1),
}
_TOKEN = re.compile(r"(\d*)(\S)")


@dataclass(frozen=True, kw_only=True)
class BrickSize:
    """A brick's length (along the wall), height and width (across it), m; the lintel's length, m
    (default three brick lengths, the competition brief's special lintel)."""

    length_m: float
    height_m: float
    width_m: float
    lintel_length_m: float | None = None

    def __post_init__(self):
        for name in ("length_m", "height_m", "width_m", "lintel_length_m"):
            value = getattr(self, name)
            if value is not None and not (isinstance(value, (int, float)) and value > 0):
                raise ModelError(f"[brick] {name} = {value!r}: must be a positive number (m)")
        if self.lintel_length_m is None:
            object.__setattr__(self, "lintel_length_m", 3 * self.length_m)
        cells = self.lintel_length_m / self.cell_m
        if abs(cells - round(cells)) > 1e-9 or round(cells) < 1:
            raise ModelError(f"[brick] lintel_length_m = {self.lintel_length_m}: must be a whole number of quarter bricks ({self.cell_m} m)")

    @property
    def cell_m(self) -> float:
        """The layout's unit: a quarter of a brick length, m."""
        return 0.25 * self.length_m

    @property
    def lintel_cells(self) -> int:
        return round(self.lintel_length_m / self.cell_m)


@dataclass(frozen=True)
class Unit:
    """One token of a course: ``kind`` (brick, half, header, lintel or void) over cells
    [start, start + cells) of ``course`` (0 at the bottom)."""

    kind: str
    course: int
    start: int
    cells: int

    @property
    def is_void(self) -> bool:
        return self.kind == "void"


@dataclass(frozen=True)
class Layout:
    """A parsed layout: every course's units, bottom course first."""

    courses: tuple[tuple[Unit, ...], ...]
    cells_per_course: int

    @property
    def units(self) -> list[Unit]:
        return [u for course in self.courses for u in course]

    @property
    def solid_units(self) -> list[Unit]:
        """The units that become blocks, in block order (course by course, left to right)."""
        return [u for u in self.units if not u.is_void]

    @property
    def void_ratio(self) -> float:
        """Void cells over all cells: the share of the wall's face left open by design."""
        voids = sum(u.cells for u in self.units if u.is_void)
        return voids / (self.cells_per_course * len(self.courses))

    def count(self, kind: str) -> int:
        return sum(u.kind == kind for u in self.units)

    def block_names(self) -> list[str]:
        names = []
        for course in self.courses:
            solid = [u for u in course if not u.is_void]
            names += [f"c{u.course}b{k}" for k, u in enumerate(solid)]
        return names

    def unsupported(self) -> list[str]:
        """Names of the blocks above the first course with a void under every one of their cells:
        nothing holds them up (drawing mistakes, such as a brick straight over an opening)."""
        solid = np.zeros((len(self.courses), self.cells_per_course), dtype=bool)
        for u in self.solid_units:
            solid[u.course, u.start:u.start + u.cells] = True
        return [name for name, u in zip(self.block_names(), self.solid_units)
                if u.course > 0 and not solid[u.course - 1, u.start:u.start + u.cells].any()]

    def kinds(self) -> list[str]:
        """Each block's kind, in the order of :meth:`blocks`: "base", then the units' kinds."""
        return ["base", *(u.kind for u in self.solid_units)]

    def void_outlines(self, brick: BrickSize) -> list[np.ndarray]:
        """The voids as rectangles in the wall's plane: (4, 2) x-z corners each, m."""
        outlines = []
        for u in self.units:
            if u.is_void:
                (x0, _, z0), (x1, _, z1) = unit_box(u, brick)
                outlines.append(np.array([[x0, z0], [x1, z0], [x1, z1], [x0, z1]]))
        return outlines

    def blocks(self, brick: BrickSize) -> list[Block]:
        """A fixed block "base" under the wall (drydem.model.base_under), then one block per
        solid unit, named as :meth:`block_names` says."""
        bricks = [Block(name=name, shape=box(*unit_box(u, brick), name=f"block {name!r}"))
                  for name, u in zip(self.block_names(), self.solid_units)]
        return [base_under(bricks), *bricks]


def unit_box(unit: Unit, brick: BrickSize) -> tuple[list[float], list[float]]:
    """The corners (min, max) of a solid unit's block, m."""
    x0, x1 = unit.start * brick.cell_m, (unit.start + unit.cells) * brick.cell_m
    depth = brick.width_m
    if unit.kind == "header":
        middle, depth = 0.5 * (x0 + x1), brick.length_m
        x0, x1 = middle - 0.5 * brick.width_m, middle + 0.5 * brick.width_m
    z0 = unit.course * brick.height_m
    return [x0, -0.5 * depth, z0], [x1, 0.5 * depth, z0 + brick.height_m]


def parse_layout(text: str, brick: BrickSize, *, source: str = "<layout>", first_line: int = 1) -> Layout:
    """Read a layout (module docstring); errors name ``source`` and the line, counting the
    text's first line as ``first_line``."""
    rows: list[tuple[int, list[tuple[str, int]]]] = []
    for number, line in enumerate(text.splitlines(), start=first_line):
        body = line.split("#", 1)[0].replace(" ", "").replace("\t", "")
        if body:
            rows.append((number, _tokens(body, brick, source, number)))
    if not rows:
        raise ModelError(f"{source}: the layout has no courses")
    first_number, first = rows[0]
    width = sum(cells for _, cells in first)
    courses = []
    for course, (number, tokens) in enumerate(reversed(rows)):
        length = sum(cells for _, cells in tokens)
        if length != width:
            raise ModelError(
                f"{source}, line {number}: the course is {length / 4:g} bricks long ({length * brick.cell_m:.4g} m); "
                f"the wall is {width / 4:g} ({width * brick.cell_m:.4g} m), set by the top course on line {first_number}"
            )
        start, units = 0, []
        for kind, cells in tokens:
            units.append(Unit(kind, course, start, cells))
            start += cells
        courses.append(tuple(units))
    return Layout(tuple(courses), width)


def _tokens(body: str, brick: BrickSize, source: str, number: int) -> list[tuple[str, int]]:
    tokens = []
    for match in _TOKEN.finditer(body):
        count, symbol = match.groups()
        if symbol not in TOKENS:
            known = ", ".join(f"{s!r} ({kind})" for s, (kind, _) in TOKENS.items())
            raise ModelError(f"{source}, line {number}: unknown token {symbol!r} in {body!r}; known: {known}")
        kind, cells = TOKENS[symbol]
        repeat = int(count) if count else 1
        if repeat < 1:
            raise ModelError(f"{source}, line {number}: repeat count {count} before {symbol!r} must be at least 1")
        tokens += [(kind, brick.lintel_cells if cells is None else cells)] * repeat
    return tokens
