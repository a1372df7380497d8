"""The competition brief the seed paper's walls obey, and a checker for wall layouts.

The brief of the 10th International Masonry Conference student competition (Milan, 2018), as
Savalle, Lourenço & Milani (2022), Section 2, and the organisers report it: bricks
25 x 5.5 x 12 mm; a wall 8 bricks long and 27 courses high (0.200 x 0.1485 m); voids at least
30 % of the wall's face; the left and right edges and the top course unperforated; one special
lintel 3 bricks long; any bond, half bricks allowed.
"""

from __future__ import annotations

from dataclasses import dataclass

from drydem.masonry.layout import BrickSize
from drydem.masonry.walls import Wall

#: the seed paper's brick, Section 2
PAPER_BRICK = BrickSize(length_m=0.025, height_m=0.0055, width_m=0.012)
PAPER_DENSITY = 1800.0  # kg/m3, Section 2


@dataclass(frozen=True, kw_only=True)
class Brief:
    """What a competition wall must satisfy."""

    brick: BrickSize = PAPER_BRICK
    length_bricks: int = 8
    courses: int = 27
    min_void_ratio: float = 0.30
    lintels: int = 1


COMPETITION = Brief()


def brief_violations(wall: Wall, brief: Brief = COMPETITION) -> list[str]:
    """Every way in which ``wall`` breaks ``brief``, in words (empty: it complies)."""
    layout, found = wall.layout, []
    if not _same_brick(wall.brick, brief.brick):
        b = brief.brick
        found.append(f"bricks are not {b.length_m * 1e3:g} x {b.height_m * 1e3:g} x {b.width_m * 1e3:g} mm with a "
                     f"{b.lintel_length_m * 1e3:g} mm lintel")
    if layout.cells_per_course != 4 * brief.length_bricks:
        found.append(f"the wall is {layout.cells_per_course / 4:g} bricks long, not {brief.length_bricks}")
    if len(layout.courses) != brief.courses:
        found.append(f"the wall has {len(layout.courses)} courses, not {brief.courses}")
    if layout.void_ratio < brief.min_void_ratio:
        found.append(f"voids are {layout.void_ratio:.1%} of the face, less than {brief.min_void_ratio:.0%}")
    for course in layout.courses:
        if course[0].is_void or course[-1].is_void:
            found.append(f"course {course[0].course} (from the bottom) has a void at the wall's edge")
    if any(u.is_void for u in layout.courses[-1]):
        found.append("the top course has a void")
    if layout.count("lintel") != brief.lintels:
        found.append(f"{layout.count('lintel')} lintels, not {brief.lintels}")
    floating = layout.unsupported()
    if floating:
        found.append(f"nothing under block(s) {', '.join(floating)}: the wall cannot be built")
    return found


def _same_brick(a: BrickSize, b: BrickSize) -> bool:
    """Equal dimensions to 1e-9 m (a lintel of 3 x 0.025 m is 0.07500000000000001 m)."""
    names = ("length_m", "height_m", "width_m", "lintel_length_m")
    return all(abs(getattr(a, n) - getattr(b, n)) < 1e-9 for n in names)
