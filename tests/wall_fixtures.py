"""The wall of the tests and ``benchmarks/``."""

from __future__ import annotations

from dataclasses import replace

import drydem as dd
from drydem.masonry import designs
from drydem.masonry.walls import load_wall


def benchmark_wall(*, kn: float = 3e7, points_per_length: int = 4, points_across: int | None = None) -> dd.Model:
    """The built-in ``perforated_wall`` (8 bricks x 27 courses, running bond, 33 % voids, four
    lintels; in-plane, mu = 0.5) with kn = ks = ``kn`` and the given contact density; not one of
    the paper's competition walls."""
    wall = load_wall(designs.find("perforated_wall"))
    return replace(
        wall, joint=dd.JointMaterial(kn=kn, ks=kn, friction=wall.joint.friction),
        contacts=dd.ContactSettings(points_per_length=points_per_length, points_across=points_across),
    ).model()
