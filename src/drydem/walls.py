"""Brick walls on a fixed base: running bond with rectangular openings.

The wall lies in the x-z plane (x along the wall, z up, y through its width). Each
course is split into half-brick cells; even courses start with a full brick, odd
courses with a half brick (running bond). An opening removes the cells of a
rectangle of courses x half-brick columns; a brick cut by an opening keeps its
remaining part. Dry bricks cannot span an opening (without mortar they slide down
between their neighbours), so by default the course above an opening gets a lintel:
one block bearing one half brick on each side.
"""

from __future__ import annotations

from dataclasses import dataclass

from drydem.geometry import box
from drydem.model import Block, Model, build_model
from drydem.parameters import ContactSettings, JointMaterial, Supports

#: the seed paper's brick: length, height, width (m) and density (kg/m3), Savalle et al. 2022, Section 2
PAPER_BRICK_M = (0.025, 0.0055, 0.012)
PAPER_DENSITY = 1800.0


@dataclass(frozen=True, kw_only=True)
class Opening:
    """Void over courses [course_start, course_stop) and half-brick columns [half_start, half_stop)."""

    course_start: int
    course_stop: int
    half_start: int
    half_stop: int
    lintel: bool = True

    def covers(self, course: int, half: int) -> bool:
        return self.course_start <= course < self.course_stop and self.half_start <= half < self.half_stop

    def lintel_cells(self, course: int) -> range:
        """Half-brick cells of this opening's lintel in ``course`` (empty if none there)."""
        if not self.lintel or course != self.course_stop:
            return range(0)
        return range(self.half_start - 1, self.half_stop + 1)


#: the benchmark wall: the paper's 8 x 27 brick wall with four 50 x 49.5 mm openings under 75 mm lintels (33 % voids)
BENCHMARK_OPENINGS = (
    Opening(course_start=3, course_stop=12, half_start=2, half_stop=6),
    Opening(course_start=3, course_stop=12, half_start=10, half_stop=14),
    Opening(course_start=15, course_stop=24, half_start=2, half_stop=6),
    Opening(course_start=15, course_stop=24, half_start=10, half_stop=14),
)


def running_bond_wall(
    *,
    courses: int,
    bricks_per_course: int,
    openings: tuple[Opening, ...] = (),
    brick_m: tuple[float, float, float] = PAPER_BRICK_M,
    base_overhang_m: float = 0.05,
    base_depth_m: float = 0.01,
) -> list[Block]:
    """A fixed base block ("base") and the wall's bricks ("c{course}b{index}"), bottom at z = 0."""
    length, height, width = brick_m
    half = 0.5 * length
    cells = 2 * bricks_per_course
    blocks = [
        Block(
            name="base",
            shape=box([-base_overhang_m, -0.5 * width, -base_depth_m], [cells * half + base_overhang_m, 0.5 * width, 0.0], name="base"),
            fixed=True,
        )
    ]
    for course in range(courses):
        z0 = course * height
        owner = _course_owners(cells, course, openings)
        for k, unit in enumerate(_runs(owner)):
            x0, x1 = unit[0] * half, (unit[-1] + 1) * half
            name = f"c{course}b{k}"
            blocks.append(Block(name=name, shape=box([x0, -0.5 * width, z0], [x1, 0.5 * width, z0 + height], name=name)))
    return blocks


def _course_owners(cells: int, course: int, openings: tuple[Opening, ...]) -> list[int]:
    """For each half-brick cell of a course, the id of the unit that fills it (-1: void).

    Units are the bond's bricks (pairs of cells, half bricks at both ends of odd courses),
    overridden by lintels, then by openings.
    """
    odd = course % 2 == 1
    owner = [(h + 1) // 2 if odd else h // 2 for h in range(cells)]
    for k, opening in enumerate(openings):
        for h in opening.lintel_cells(course):
            owner[h] = cells + k
    for h in range(cells):
        if any(o.covers(course, h) for o in openings):
            owner[h] = -1
    return owner


def _runs(owner: list[int]) -> list[list[int]]:
    """Contiguous cells of the same unit: each becomes one block."""
    runs: list[list[int]] = []
    for h, unit in enumerate(owner):
        if unit < 0:
            continue
        if runs and owner[runs[-1][-1]] == unit and runs[-1][-1] == h - 1:
            runs[-1].append(h)
        else:
            runs.append([h])
    return runs


def benchmark_wall(*, kn: float = 3e7, points_per_length: int = 4, points_across: int | None = None) -> Model:
    """The benchmark wall (8 bricks x 27 courses, running bond, 33 % voids, four lintels) as an
    in-plane model (every block fixed in y, paper Section 3), kn = ks, mu = 0.5, on a fixed base.

    This is the shipped example ``perforated_wall`` and the wall of ``benchmarks/``; it is not
    one of the paper's competition walls. ``points_across`` as in ContactSettings (default 2).
    """
    return build_model(
        running_bond_wall(courses=27, bricks_per_course=8, openings=BENCHMARK_OPENINGS),
        density=PAPER_DENSITY,
        joint=JointMaterial(kn=kn, ks=kn, friction=0.5),
        contacts=ContactSettings(points_per_length=points_per_length, points_across=points_across),
        supports=Supports(fix_y=True),
    )
