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
half brick. Every course must have the length of the first one, and a wall has at least one
brick. A 2-brick wall of three courses, the middle one with half bricks at its ends and a
brick-long void between them::

    BB            # top course
    b_b
    BB            # bottom course, on the base block

Internally a course is a row of quarter-brick *cells*.
Blocks are named ``c{course}b{k}``: course 0 at the bottom, k counting the course's blocks
from x = 0. The wall's bottom is at z = 0, its left end at x = 0.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

import numpy as np

from drydem.errors import ModelError
from drydem.model.geometry import box
from drydem.model.assembly import Block, base_under
from drydem.model.parameters import Range

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
#: a token and its repeat count (ASCII digits only: ``int`` would read other scripts' digits)
_TOKEN = re.compile(r"([0-9]*)(\S)")

#: the largest wall face, in brick faces (wall length in bricks x courses, voids included): 10^5,
#: about the size of the largest DEM masonry models (~10^5 blocks), whose every cycle would take
#: milliseconds here (~60 ns per block). Layouts are checked against it before any course is
#: expanded, so that a mistyped repeat count (``1000000B``) is an error, not a hang.
MAX_FACE_BRICKS = 100_000

#: a brick's (or the lintel's) dimensions, m: from model-scale bricks of a tenth of a millimetre
#: to 20 m, about the largest stones ever laid (Baalbek); beyond, the blocks are numbers Qhull
#: cannot hull (1e-300 m) or millimetres written as metres
BRICK_SIZE = Range(1e-4, 20.0, unit="m")


@dataclass(frozen=True, kw_only=True)
class BrickSize:
    """A brick's length (along the wall), height and width (across it), m; the lintel's length, m
    (default three brick lengths, the competition brief's special lintel)."""

    length_m: float
    height_m: float
    width_m: float
    lintel_length_m: float | None = None

    def __post_init__(self):
        """Each dimension in :data:`BRICK_SIZE`; the lintel a whole number of quarter bricks
        (the layout's cells) and at least a brick long: the shortest opening is half a brick,
        and a lintel bears on a quarter brick at least on each side of it."""
        for name in ("length_m", "height_m", "width_m", "lintel_length_m"):
            value = getattr(self, name)
            if value is not None:
                BRICK_SIZE.check(value, f"[brick] {name}")
        if self.lintel_length_m is None:
            object.__setattr__(self, "lintel_length_m", 3 * self.length_m)
        cells = self.lintel_length_m / self.cell_m
        if abs(cells - round(cells)) > 1e-9:
            raise ModelError(f"[brick] lintel_length_m = {self.lintel_length_m}: must be a whole number of quarter bricks ({self.cell_m} m)")
        if round(cells) < 4:
            raise ModelError(f"[brick] lintel_length_m = {self.lintel_length_m}: must be at least a brick long "
                             f"({self.length_m} m), to span a half-brick opening with a quarter brick of bearing on each side")

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
        """A fixed block "base" under the wall (drydem.model.assembly.base_under), then one block per
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
    text's first line as ``first_line``. The courses are read as runs (a token and its repeat
    count) and checked, against :data:`MAX_FACE_BRICKS` and each other, before any is expanded."""
    rows: list[tuple[int, list[tuple[str, int, int]]]] = []
    room = 4 * MAX_FACE_BRICKS  # cells left under the limit
    for number, line in enumerate(text.splitlines(), start=first_line):
        body = line.split("#", 1)[0].replace(" ", "").replace("\t", "")
        if body:
            runs, room = _runs(body, brick, f"{source}, line {number}", room)
            rows.append((number, runs))
    if not rows:
        raise ModelError(f"{source}: the layout has no courses")
    first_number, first = rows[0]
    if all(kind == "void" for _, runs in rows for kind, _, _ in runs):
        last_number = rows[-1][0]
        lines = f"line {first_number}" if last_number == first_number else f"lines {first_number}-{last_number}"
        raise ModelError(f"{source}, {lines}: the layout has only voids; a wall needs at least one brick")
    bottom_number, bottom = rows[-1]
    if all(kind == "void" for kind, _, _ in bottom):
        raise ModelError(f"{source}, line {bottom_number}: the bottom course is all voids: the base is drawn under the bottom "
                         "course, so the wall would stand on it one course lower than drawn; remove the course")
    width = sum(cells * repeat for _, cells, repeat in first)
    courses = []
    for course, (number, runs) in enumerate(reversed(rows)):
        length = sum(cells * repeat for _, cells, repeat in runs)
        if length != width:
            raise ModelError(
                f"{source}, line {number}: the course is {length / 4:g} bricks long ({length * brick.cell_m:.4g} m); "
                f"the wall is {width / 4:g} ({width * brick.cell_m:.4g} m), set by the top course on line {first_number}"
            )
        start, units = 0, []
        for kind, cells, repeat in runs:
            for _ in range(repeat):
                units.append(Unit(kind, course, start, cells))
                start += cells
        courses.append(tuple(units))
    return Layout(tuple(courses), width)


def _runs(body: str, brick: BrickSize, where: str, room: int) -> tuple[list[tuple[str, int, int]], int]:
    """A course's tokens as runs (kind, cells, repeat count), and the cells the wall may still
    have after it; ``where`` names the line in errors, ``room`` is the number of cells the wall
    may still have under :data:`MAX_FACE_BRICKS` before it."""
    runs = []
    for match in _TOKEN.finditer(body):
        count, symbol = match.groups()
        if symbol not in TOKENS:
            known = ", ".join(f"{s!r} ({kind})" for s, (kind, _) in TOKENS.items())
            raise ModelError(f"{where}: unknown token {symbol!r} in {_shown(body)}; known: {known}")
        kind, cells = TOKENS[symbol]
        cells = brick.lintel_cells if cells is None else cells
        repeat = _repeat(count)
        if repeat < 1:
            raise ModelError(f"{where}: repeat count {count} before {symbol!r} must be at least 1")
        room -= repeat * cells
        if room < 0:
            raise ModelError(
                f"{where}: {_shown(match.group(0))} takes the wall past {MAX_FACE_BRICKS:,} bricks of face (its "
                f"length in bricks times its courses, voids included), the most drydem takes (the largest DEM "
                f"masonry models have about 10^5 blocks)"
            )
        runs.append((kind, cells, repeat))
    return runs, room


def _repeat(count: str) -> int | float:
    """A token's repeat count, 1 if it has none. A count of more than 9 digits is past
    :data:`MAX_FACE_BRICKS` whatever the token: it is read as infinite (``int`` refuses numbers
    of more than 4,300 digits)."""
    if not count:
        return 1
    digits = count.lstrip("0")
    return int(digits or "0") if len(digits) <= 9 else math.inf


def _shown(text: str, limit: int = 40) -> str:
    """``text`` quoted for an error message, cut short if longer than ``limit`` characters."""
    return repr(text) if len(text) <= limit else f"{text[:limit]!r}... ({len(text):,} characters)"
