"""Small models shared by the tests."""

from __future__ import annotations

import textwrap

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import drydem as dd

#: the seed paper's brick (Savalle et al. 2022, Section 2): length x width x height, m
BRICK = (0.025, 0.012, 0.0055)


def turned(vertices, turn_deg: float) -> np.ndarray:
    """Vertices turned by ``turn_deg`` about the world z axis."""
    return np.asarray(vertices) @ Rotation.from_euler("z", turn_deg, degrees=True).as_matrix().T


def box_vertices(lower, upper) -> np.ndarray:
    lo, hi = np.asarray(lower, float), np.asarray(upper, float)
    return np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])


def stack_model(
    heights,
    *,
    size_xy=(BRICK[0], BRICK[1]),
    joint=dd.JointMaterial(kn=1e8, ks=1e8, friction=0.5),
    points: int = 4,
    turn_deg: float = 0.0,
    solver=dd.SolverSettings(),
    supports=dd.Supports(),
    density: float = 1800.0,
    lift: float = 0.0,
) -> dd.Model:
    """A fixed base and blocks of footprint ``size_xy`` stacked with heights ``heights`` (m),
    the first ``lift`` m above the base; everything turned ``turn_deg`` about z."""
    bx, by = size_xy
    blocks = [dd.Block(name="base", shape=dd.convex_hull(turned(box_vertices([-2 * bx, -2 * by, -0.01], [3 * bx, 3 * by, 0.0]), turn_deg)), fixed=True)]
    z = lift
    for k, h in enumerate(heights):
        shape = dd.convex_hull(turned(box_vertices([0.0, 0.0, z], [bx, by, z + h]), turn_deg))
        blocks.append(dd.Block(name=f"block{k}", shape=shape))
        z += h
    return dd.build_model(
        blocks, density=density, joint=joint, contacts=dd.ContactSettings(points_per_length=points),
        supports=supports, solver=solver,
    )


def prism_model(sides: int, radius: float, height: float, *, points: int = 4, kn: float = 1e10, turn_rad: float = 0.0,
                slab_end_x: float | None = None) -> dd.Model:
    """A regular prism of ``sides`` sides (circumradius ``radius``, a vertex along +x, the
    tilting table's downhill direction, unless turned ``turn_rad`` about its axis) standing on a
    fixed slab (ending at x = ``slab_end_x`` if given, under the prism); stiff joints (kn = ks, Pa/m),
    mu = 1, so that it topples, at tan = radius / (height / 2), rather than slides (round columns, drums)."""
    angle = turn_rad + 2 * np.pi * np.arange(sides) / sides
    ring = radius * np.stack([np.cos(angle), np.sin(angle)], axis=1)
    prism = dd.convex_hull(np.concatenate([np.c_[ring, np.zeros(sides)], np.c_[ring, np.full(sides, height)]]))
    slab = dd.box([-2 * radius, -2 * radius, -0.01], [2 * radius if slab_end_x is None else slab_end_x, 2 * radius, 0.0])
    return dd.build_model(
        [dd.Block(name="slab", shape=slab, fixed=True), dd.Block(name="prism", shape=prism)], density=1800.0,
        joint=dd.JointMaterial(kn=kn, ks=kn, friction=1.0), contacts=dd.ContactSettings(points_per_length=points),
    )


def tilted_gravity(theta_deg: float, turn_deg: float = 0.0) -> np.ndarray:
    """The tilting table's gravity g (sin theta, 0, -cos theta) (paper Eq. 5), turned about z."""
    t = np.radians(theta_deg)
    return turned(dd.G * np.array([np.sin(t), 0.0, -np.cos(t)]), turn_deg)


def layout_blocks(courses: str) -> list[dd.Block]:
    """The blocks of a brick layout (drydem.masonry.layout; top course first) of the paper's bricks, on a fixed base."""
    from drydem.masonry.brief import PAPER_BRICK
    from drydem.masonry.layout import parse_layout

    return parse_layout(textwrap.dedent(courses), PAPER_BRICK).blocks(PAPER_BRICK)


@pytest.fixture(scope="session")
def benchmark_wall() -> dd.Model:
    """The built-in perforated_wall: 8 x 27 bricks, running bond, 33 % voids, in-plane (fixed in y), kn = ks = 3e7."""
    from wall_fixtures import benchmark_wall

    return benchmark_wall(kn=3e7)
