"""A masonry building in 3D: four single-leaf dry-joint walls round a rectangle, with
bonded corners, windows, a door and lintels, on a fixed base slab.

Axes: x and y horizontal, z up; units SI. The plan is the rectangle [0, length_m] x
[0, width_m] (outer faces). The walls are numbered counter-clockwise from the south:

    0  south, along x, y in [0, t]             1  east, along y, x in [length_m - t, length_m]
    2  north, along x, y in [width_m - t, width_m]   3  west, along y, x in [0, t]

with t = brick_width_m = brick_length_m / 2 (a stretcher-bond leaf one brick wide). Positions
along a wall are counted in *cells* of a quarter brick from its outer end at x = 0 (walls 0, 2)
or y = 0 (walls 1, 3); a wall of length N cells.

Rules (each one a short function below):

* **Corners** (:func:`course_span`): on even courses the walls along x (0, 2) run through the
  corners, cells [0, N], and the walls along y butt against them, cells [2, N - 2]; on odd
  courses the other way round. Each corner square t x t is thus taken by the two walls in
  turn: the returns are bonded.
* **Bond** (:func:`bond`): a course is laid from its start in whole bricks (4 cells); with the
  through and the butting courses starting half a brick apart, this is running bond, and at
  each corner the through brick laps the butting course by half a brick. A wall a whole number
  of bricks long needs no closer; one with an extra half brick ends each course with two
  three-quarter closers (3 + 3 cells), which lap the course below by a quarter brick.
* **Openings** (:func:`opening_starts`): ``windows_per_wall`` windows ``window_width_bricks``
  wide on every wall and storey, on the whole-brick grid, separated and flanked by piers of
  equal whole bricks (the spare bricks go to the end piers), each pier at least
  :data:`MIN_PIER_BRICKS`; the window's void spans ``window_height_courses`` courses from
  ``sill_courses`` above the storey's first course. With ``door_height_courses`` > 0 the middle
  window of the south wall's ground storey is a door instead (sill 0, that height).
* **Lintels** (:func:`lintel_span`): over each opening, in the course above it, one block
  spanning the opening plus :data:`BEARING_CELLS` (half a brick) on each side. Jambs on the
  whole-brick grid and lintel ends on the half-brick grid cut the bricks of the courses into
  halves, never less: every block is at least half a brick long.

There are no floors: the storeys only set where the openings are. Blocks are named
``s{storey}w{wall}c{course}b{k}`` (course counted within the storey from 0, k counting the
course's bricks along the wall) and ``s{storey}w{wall}c{course}l{k}`` for the lintel of
opening k; the fixed base slab, first, is ``base``.

Two built-in buildings are TARGETs of every command (:data:`BUILDINGS`): ``building-small``
(:data:`SMALL`, 1,936 blocks) and ``building-large`` (:data:`LARGE`, 19,853 blocks), e.g.
``drydem tilt building-small --tilt-axis x`` (tilting about x loads the long walls, 0 and 2,
out of their plane) or ``drydem export building-small building.toml`` (a model file to edit).
A building of any other size is built from Python with a :class:`BuildingSpec`::

    from drydem.masonry.building import BuildingSpec, building_model
    from drydem.io.model_file import save_model

    spec = BuildingSpec(length_m=1.0, width_m=0.8, storeys=1, storey_height_courses=12,
                        brick_length_m=0.1, brick_height_m=0.05, windows_per_wall=1,
                        window_width_bricks=2, window_height_courses=5, sill_courses=4)
    house = building_model(spec, density=1800.0)     # a Model: tilt_analysis(house, ...)
    save_model(house, "house.toml")                  # drydem tilt house.toml --tilt-axis x
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from drydem.errors import ModelError
from drydem.masonry.layout import BRICK_SIZE, BrickSize
from drydem.model.assembly import MAX_BLOCKS, Block, Model, build_model
from drydem.model.geometry import box
from drydem.model.parameters import (DENSITY, G, ContactSettings, InstanceOf, JointMaterial, Range, SolverSettings, check_arguments,
                                     check_fields, refuse)

#: the narrowest pier, in bricks: room for a lintel's bearing and a bonded brick beside it
MIN_PIER_BRICKS = 2
#: a lintel's bearing on each side of its opening, cells (half a brick)
BEARING_CELLS = 2
#: plan lengths, m: at most 1 km (any building); the least is set by the openings and piers
PLAN_LENGTH = Range(0.0, 1000.0, low_open=True, unit="m")
#: counts of storeys, courses and openings, and sizes in bricks and courses
STOREYS = Range(1, 100, integer=True)
COURSES = Range(1, 10_000, integer=True)
COUNT = Range(0, 1000, integer=True)
#: a brick's length and height, m (the layout format's range)
RULES = {"length_m": PLAN_LENGTH, "width_m": PLAN_LENGTH, "storeys": STOREYS, "storey_height_courses": COURSES,
         "brick_length_m": BRICK_SIZE, "brick_height_m": BRICK_SIZE, "windows_per_wall": COUNT,
         "window_width_bricks": Range(1, 1000, integer=True), "window_height_courses": Range(1, 10_000, integer=True),
         "sill_courses": Range(0, 10_000, integer=True), "door_height_courses": Range(0, 10_000, integer=True)}
#: relative round-off allowed when checking that a plan length is a whole number of half bricks
ROUND_OFF = 1e-9


@dataclass(frozen=True, kw_only=True)
class BuildingSpec:
    """A building (module docstring for the rules): outer plan ``length_m`` (x) by ``width_m``
    (y), each a whole number of half bricks; ``storeys`` of ``storey_height_courses`` courses;
    bricks ``brick_length_m`` x ``brick_height_m`` (width: half the length, the wall's
    thickness); the openings. Checked when created: ModelError naming each field and rule."""

    length_m: float
    width_m: float
    storeys: int
    storey_height_courses: int
    brick_length_m: float
    brick_height_m: float
    windows_per_wall: int = 1
    window_width_bricks: int = 2
    window_height_courses: int = 4
    sill_courses: int = 3
    door_height_courses: int = 0

    def __post_init__(self):
        check_fields(self, RULES, "[building]")
        refuse(_plan_problems(self) + _opening_problems(self))
        bricks = self.courses * (self.wall_cells(0) + self.wall_cells(1)) // 2
        if bricks > MAX_BLOCKS:
            raise ModelError(f"[building]: the walls hold {bricks:,} bricks (courses x perimeter in bricks); "
                             f"must be at most {MAX_BLOCKS:,} blocks")

    @property
    def brick_width_m(self) -> float:
        """The wall's thickness, m: half a brick length."""
        return 0.5 * self.brick_length_m

    @property
    def brick(self) -> BrickSize:
        """The brick (:class:`~drydem.masonry.layout.BrickSize`): its cell, a quarter brick, is
        the unit of positions along a wall, as in a layout."""
        return BrickSize(length_m=self.brick_length_m, height_m=self.brick_height_m, width_m=self.brick_width_m)

    @property
    def courses(self) -> int:
        return self.storeys * self.storey_height_courses

    @property
    def block_count(self) -> int:
        """The blocks of :func:`building_model`, the base slab included (counted from the
        courses' pieces, no geometry built)."""
        pieces = (course_pieces(self, wall, storey, course) for storey in range(self.storeys) for wall in range(4)
                  for course in range(self.storey_height_courses))
        return 1 + sum(len(bricks) + len(lintels) for bricks, lintels in pieces)

    def wall_cells(self, wall: int) -> int:
        """The outer length of ``wall`` in cells (walls 0, 2 along x; 1, 3 along y)."""
        return round((self.width_m if wall % 2 else self.length_m) / self.brick.cell_m)

    def wall_volume_m3(self) -> float:
        """The walls' volume in closed form, m3: plan ring times height, minus the openings."""
        t, h = self.brick_width_m, self.brick_height_m
        ring = self.length_m * self.width_m - (self.length_m - 2 * t) * (self.width_m - 2 * t)
        window = self.window_width_bricks * self.brick_length_m * t * h
        voids = 4 * self.storeys * self.windows_per_wall * self.window_height_courses
        if self.door_height_courses:
            voids += self.door_height_courses - self.window_height_courses
        return ring * self.courses * h - voids * window


def _plan_problems(spec: BuildingSpec) -> list[str]:
    """Each plan length a whole number of half bricks, at least :data:`MIN_PIER_BRICKS` x 2 bricks."""
    problems = []
    half = 0.5 * spec.brick_length_m
    for name in ("length_m", "width_m"):
        value = getattr(spec, name)
        halves = value / half
        if abs(halves - round(halves)) > ROUND_OFF * max(1.0, halves):
            problems.append(f"[building] {name} = {value!r}: must be a whole number of half bricks ({half:g} m)")
        elif round(halves) < 4 * MIN_PIER_BRICKS:
            problems.append(f"[building] {name} = {value!r}: must be at least {2 * MIN_PIER_BRICKS} bricks "
                            f"({2 * MIN_PIER_BRICKS * spec.brick_length_m:g} m)")
    return problems


def _opening_problems(spec: BuildingSpec) -> list[str]:
    """Openings and their lintels inside a storey, and piers of at least MIN_PIER_BRICKS on each wall."""
    problems = []
    if spec.sill_courses + spec.window_height_courses + 1 > spec.storey_height_courses:
        problems.append(f"[building] sill_courses + window_height_courses + 1 (the lintel) = "
                        f"{spec.sill_courses + spec.window_height_courses + 1}: must be at most storey_height_courses "
                        f"({spec.storey_height_courses})")
    if spec.door_height_courses and spec.door_height_courses + 1 > spec.storey_height_courses:
        problems.append(f"[building] door_height_courses + 1 (the lintel) = {spec.door_height_courses + 1}: "
                        f"must be at most storey_height_courses ({spec.storey_height_courses})")
    if spec.door_height_courses and not spec.windows_per_wall:
        problems.append("[building] door_height_courses: a door takes a window's place; windows_per_wall must be at least 1")
    for wall, name in ((0, "length_m"), (1, "width_m")):
        n, w = spec.windows_per_wall, spec.window_width_bricks
        solid = spec.wall_cells(wall) // 4 - n * w
        if n and solid < (n + 1) * MIN_PIER_BRICKS:
            problems.append(f"[building] windows_per_wall = {n}, window_width_bricks = {w}: the openings do not fit in "
                            f"{name} = {getattr(spec, name)!r} (each of the {n + 1} piers must be at least {MIN_PIER_BRICKS} bricks)")
    return problems


def course_span(spec: BuildingSpec, wall: int, course: int) -> tuple[int, int]:
    """Cells [start, end) of ``wall`` in ``course`` (counted from the bottom): the whole length
    where the wall runs through the corners (walls along x on even courses, along y on odd
    ones), else between the two other walls."""
    n = spec.wall_cells(wall)
    return (0, n) if wall % 2 == course % 2 else (2, n - 2)


def bond(start: int, end: int) -> list[tuple[int, int]]:
    """Running bond over cells [start, end) (an even number of cells): whole bricks from the
    start; a half-brick surplus is taken by two three-quarter closers at the end, and a course
    of one half brick is one half brick."""
    bricks, rest = divmod(end - start, 4)
    lengths = [4] * bricks if rest == 0 else [2] if bricks == 0 else [4] * (bricks - 1) + [3, 3]
    edges = np.cumsum([start, *lengths]).tolist()
    return list(zip(edges[:-1], edges[1:]))


def opening_starts(spec: BuildingSpec, wall: int) -> list[int]:
    """The first cell of each window of ``wall``: on the whole-brick grid, equal piers between
    the windows, the spare whole bricks split between the end piers (the first one gets the
    smaller half)."""
    n, w = spec.windows_per_wall, spec.window_width_bricks
    if not n:
        return []
    solid = spec.wall_cells(wall) // 4 - n * w
    pier = solid // (n + 1)
    first = (solid - (n - 1) * pier) // 2
    return [4 * (first + k * (w + pier)) for k in range(n)]


def openings(spec: BuildingSpec, wall: int, storey: int) -> list[tuple[int, int, int, int]]:
    """The openings of ``wall`` in ``storey``: (first cell, end cell, first course, end course),
    courses counted within the storey; the door, if any, in the middle of wall 0's ground storey."""
    found = []
    starts = opening_starts(spec, wall)
    for k, start in enumerate(starts):
        door = spec.door_height_courses and wall == 0 and storey == 0 and k == len(starts) // 2
        low, height = (0, spec.door_height_courses) if door else (spec.sill_courses, spec.window_height_courses)
        found.append((start, start + 4 * spec.window_width_bricks, low, low + height))
    return found


def lintel_span(opening: tuple[int, int, int, int]) -> tuple[int, int, int]:
    """The lintel of an opening: (first cell, end cell, course within the storey)."""
    start, end, _, top = opening
    return start - BEARING_CELLS, end + BEARING_CELLS, top


def course_pieces(spec: BuildingSpec, wall: int, storey: int, course: int) -> tuple[list[tuple[int, int]], list[tuple[int, int, int]]]:
    """The bricks (first cell, end cell) of ``wall`` in a course of ``storey`` (counted within
    it), the bond cut by the openings and lintels of that course; and the course's lintels
    (first cell, end cell, opening index)."""
    holes, lintels = [], []
    for k, opening in enumerate(openings(spec, wall, storey)):
        start, end, low, top = opening
        if low <= course < top:
            holes.append((start, end))
        lintel = lintel_span(opening)
        if lintel[2] == course:
            holes.append(lintel[:2])
            lintels.append((lintel[0], lintel[1], k))
    bricks = bond(*course_span(spec, wall, storey * spec.storey_height_courses + course))
    return _cut(bricks, holes), lintels


def _cut(pieces: list[tuple[int, int]], holes: list[tuple[int, int]]) -> list[tuple[int, int]]:
    """``pieces`` less the cells of ``holes`` (disjoint intervals), in order."""
    for h0, h1 in holes:
        pieces = [part for a, b in pieces for part in ((a, min(b, h0)), (max(a, h1), b)) if part[1] > part[0]]
    return pieces


def piece_box(spec: BuildingSpec, wall: int, course: int, cells: tuple[int, int]) -> tuple[np.ndarray, np.ndarray]:
    """The corners (min, max), m, of the block over ``cells`` of ``wall`` in ``course`` (from the bottom)."""
    t, q = spec.brick_width_m, spec.brick.cell_m
    along = (cells[0] * q, cells[1] * q)
    across = (0.0, t) if wall in (0, 3) else ((spec.width_m - t, spec.width_m) if wall == 2 else (spec.length_m - t, spec.length_m))
    x, y = (along, across) if wall % 2 == 0 else (across, along)
    z = (course * spec.brick_height_m, (course + 1) * spec.brick_height_m)
    return np.array([x[0], y[0], z[0]]), np.array([x[1], y[1], z[1]])


def _block(name: str, lo: np.ndarray, hi: np.ndarray) -> Block:
    """A box block between its corners (m)."""
    return Block(name=name, shape=box(lo, hi, name=f"block {name!r}"))


def base_slab(spec: BuildingSpec) -> Block:
    """The fixed base: a brick high, overhanging the plan by a brick on every side, its top at z = 0."""
    over, h = spec.brick_length_m, spec.brick_height_m
    shape = box([-over, -over, -h], [spec.length_m + over, spec.width_m + over, 0.0], name="base")
    return Block(name="base", shape=shape, fixed=True)


def building_blocks(spec: BuildingSpec) -> list[Block]:
    """The fixed base slab, then the walls' blocks storey by storey, wall by wall, course by
    course, along the wall (names in the module docstring)."""
    check_arguments("building_blocks", {"spec": InstanceOf(BuildingSpec)}, spec=spec)
    blocks = [base_slab(spec)]
    for storey in range(spec.storeys):
        for wall in range(4):
            for course in range(spec.storey_height_courses):
                level = storey * spec.storey_height_courses + course
                bricks, lintels = course_pieces(spec, wall, storey, course)
                prefix = f"s{storey}w{wall}c{course}"
                blocks += [_block(f"{prefix}b{k}", *piece_box(spec, wall, level, cells)) for k, cells in enumerate(bricks)]
                blocks += [_block(f"{prefix}l{k}", *piece_box(spec, wall, level, (a, b))) for a, b, k in lintels]
    return blocks


#: the buildings' default joint: kn = ks = 1e9 Pa/m, the default friction. The walls' default
#: (kn = 3e7, for the 0.15 m competition walls) is too soft for storeys of single-leaf wall: under
#: its own weight, building-small's ground-storey pier between the north windows buckles out of
#: its plane (rotational stiffness of a joint kn t^3 b / 12 against the storey above) and a
#: brick falls out in stage 1; at 1e9 it stands, and tilted about x collapses at 3.4 deg
BUILDING_JOINT = JointMaterial(kn=1e9, ks=1e9)


def building_model(spec: BuildingSpec, *, density: float = 1800.0, joint: JointMaterial = BUILDING_JOINT,
                   contacts: ContactSettings | None = None, solver: SolverSettings | None = None,
                   source: str = "<building>") -> Model:
    """The building as a 3D :class:`Model`: no supports (only the base slab is fixed); density
    kg/m3; the joint :data:`BUILDING_JOINT` by default; contacts and solver default to their defaults; ``source`` names it in messages (and
    in a tilting checkpoint's fingerprint). Save it as a model file with
    :func:`drydem.io.model_file.save_model`. ModelError naming each argument that is not what it
    must be (:data:`ARGUMENT_RULES`; contacts and solver may be None, for their defaults)."""
    check_arguments("building_model", ARGUMENT_RULES, optional=("contacts", "solver"), spec=spec, joint=joint, contacts=contacts,
                    solver=solver)
    return build_model(building_blocks(spec), density=density, joint=joint,
                       contacts=ContactSettings() if contacts is None else contacts,
                       solver=SolverSettings() if solver is None else solver, source=source)


#: the rule of each argument of :func:`building_model`
ARGUMENT_RULES = {"spec": InstanceOf(BuildingSpec), "joint": InstanceOf(JointMaterial), "contacts": InstanceOf(ContactSettings),
                  "solver": InstanceOf(SolverSettings)}


#: ~2,000 blocks (1,936): a two-storey model-scale house, 1.5 m x 1.25 m in plan (15 x 12.5 bricks of
#: 100 x 50 x 50 mm: the short walls end with three-quarter closers), 1 m per storey, two windows
#: a wall and storey and a door
SMALL = BuildingSpec(length_m=1.5, width_m=1.25, storeys=2, storey_height_courses=20, brick_length_m=0.1,
                     brick_height_m=0.05, windows_per_wall=2, window_width_bricks=2, window_height_courses=8,
                     sill_courses=6, door_height_courses=14)
#: ~20,000 blocks (19,853): a three-storey full-scale house, 14.4 m x 9.72 m in plan (60 x 40.5
#: bricks of 240 x 120 x 80 mm), 3.2 m per storey, four windows a wall and storey and a door
LARGE = BuildingSpec(length_m=14.4, width_m=9.72, storeys=3, storey_height_courses=40, brick_length_m=0.24,
                     brick_height_m=0.08, windows_per_wall=4, window_width_bricks=5, window_height_courses=18,
                     sill_courses=11, door_height_courses=28)

#: building-large's joints: kn = ks = 5e10 Pa/m, E = kn h = 4 GPa over its 80 mm courses (a brick
#: masonry's modulus) and 2.4 times :func:`buckling_joint_stiffness` of its 9.6 m leaf. At
#: BUILDING_JOINT's 1e9 the leaf is 20 times too soft: its settlement never converged, the
#: walls bulging out of plane from the round-off up (issue 18)
FULL_SCALE_JOINT = JointMaterial(kn=5e10, ks=5e10)


def buckling_joint_stiffness(height_m: float, course_m: float, thickness_m: float, density: float = 1800.0) -> float:
    """The joint stiffness kn, Pa/m, below which a free-standing dry leaf ``height_m`` tall
    buckles under its own weight: Greenhill's (1881) height L_cr = 1.986 (EI / q)^(1/3)
    (Timoshenko & Gere, Theory of Elastic Stability, 2nd ed., 2.13) with the stack's bending
    stiffness per breadth EI = kn h t^3 / 12 (each joint's rotational stiffness kn t^3 / 12
    smeared over a course h) and its weight q = rho g t, solved for kn:
    kn = 12 rho g L^3 / (1.986^3 h t^2). Returns and piers braced by cross walls stand at less
    (building-small stands at 0.6 times its full height's value). ModelError naming an argument
    that is no length in :data:`PLAN_LENGTH` or no density in DENSITY (found by a hunt: True,
    -1 and NaN gave numbers, a text a TypeError)."""
    check_arguments("buckling_joint_stiffness", {"height_m": PLAN_LENGTH, "course_m": PLAN_LENGTH, "thickness_m": PLAN_LENGTH,
                                                 "density": DENSITY},
                    height_m=height_m, course_m=course_m, thickness_m=thickness_m, density=density)
    return 12.0 * density * G * height_m**3 / (1.986**3 * course_m * thickness_m**2)


@dataclass(frozen=True)
class BuiltinBuilding:
    """A built-in building: its geometry and its joints' default material."""

    spec: BuildingSpec
    joint: JointMaterial


#: the built-in buildings, by their TARGET name (``drydem designs`` lists them)
BUILDINGS = {"building-small": BuiltinBuilding(SMALL, BUILDING_JOINT), "building-large": BuiltinBuilding(LARGE, FULL_SCALE_JOINT)}


def builtin_building(name: str) -> Model | None:
    """The model of the built-in building ``name`` (:data:`BUILDINGS`: its geometry and joint,
    the other defaults of :func:`building_model`, its source the name), or None if there is
    none of that name."""
    building = BUILDINGS.get(name)
    return None if building is None else building_model(building.spec, joint=building.joint, source=name)
