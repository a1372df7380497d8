"""Imperfect bricks: a wall's blocks with random heights, tilted bed faces and placement errors.

Real bricks are not the layout's perfect boxes: their heights scatter, their bed faces are
neither flat nor parallel, and the mason lays them a little off. On a dry joint of stiffness
kn = 3e7 Pa/m the wall's own weight closes the joints by about 0.1 mm, so deviations of that
size decide which bricks bear and which hang. This module draws such a wall, reproducibly from a
seed, by changing the blocks' geometry (not a stiffness):

* **height**: brick i is ``h + dh_i`` high, ``dh_i = height_sd * z_i``; ``z_i`` standard normal,
  or uniform on [-sqrt(3), sqrt(3)] (the same standard deviation) for ``"uniform"``.
* **flatness** (out-of-flatness modelled as out-of-parallelism): each bed face, bottom and top,
  is a plane tilted along the wall, its right edge ``flatness_sd * z`` above its mid-line and its
  left edge as much below (``z`` standard normal; so each corner's deviation has standard
  deviation ``flatness_sd``). The brick then bears on a line or a point instead of its whole
  face: the reduced effective contact area comes from the geometry. The tilt is along x only:
  the walls are analysed in-plane (fix_y), and a tilt across y would make every block a
  non-prism and the model 3D (drydem.model.assembly) for a direction the analysis holds fixed.
  Tilts leave a brick's volume unchanged (they turn about the face's mid-line).
* **misalignment**: brick i is laid ``misalignment_sd * z_i`` to the right of its place along the
  wall (z standard normal), course by course from left to right, never left of the end of the
  brick laid before it in its course (a mason butts bricks; gaps open, bricks never interpenetrate).

Courses are built on the bricks below, so that no two blocks overlap whatever the draws: each
brick is lowered onto (or lifted to) the highest top beneath its footprint (of every brick laid
before it, and the base at z = 0), tops and bottoms being planes whose difference is linear
along x, so the highest point is at an end of the overlap of the two footprints. Levels are
tracked as *deviations* from the layout's nominal z (drydem.masonry.layout.unit_box), so that zero
amplitudes give the layout's floats exactly: the perfect wall, bit for bit, base block included.
(A brick the layout leaves with nothing under it, :meth:`Layout.unsupported`, falls onto what lies
beneath, as it would under gravity; the built-in walls have none.)

**Draws.** ``numpy.random.SeedSequence(seed).spawn(3)`` gives three independent streams, one per
kind, each a ``numpy.random.default_rng``: heights ``standard_normal(n)`` (or ``uniform(-sqrt(3),
sqrt(3), n)``), flatness ``standard_normal((n, 2))`` (bottom and top face of each brick), misalignment
``standard_normal(n)``; n is the number of bricks, in the layout's block order. The unit draws are
then multiplied by the amplitudes, so one seed gives the same draws whatever the amplitudes:
switching one kind on or off leaves the others alone, and :meth:`Imperfections.scaled` scales
the same wall's deviations (up to the placement rules, which are not linear).
"""

from __future__ import annotations

import dataclasses
import math
import sys
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from drydem.errors import ModelError
from drydem.masonry.layout import BrickSize, unit_box
from drydem.masonry.walls import Wall
from drydem.model.assembly import Block, Model, base_under, build_model
from drydem.model.geometry import box, convex_hull
from drydem.model.parameters import InstanceOf, OneOf, Range, check_arguments, check_fields, is_number, refuse
from drydem.model.tables import errors_naming

#: amplitudes are given in millimetres; geometry is in metres
MM = 1e-3
#: an amplitude, mm: a finite number, zero for none
AMPLITUDE = Range(0.0, None, unit="mm")
#: the rule of each field of :class:`Imperfections`
RULES = {"height_sd_mm": AMPLITUDE, "height_distribution": OneOf(("normal", "uniform")),
         "flatness_sd_mm": AMPLITUDE, "misalignment_sd_mm": AMPLITUDE}
#: the largest height and flatness amplitudes, as fractions of the brick height: real bricks
#: scatter by 1-2 %; at these bounds a brick end thinner than :data:`MIN_THICKNESS_FRACTION` of
#: the nominal height is a 7-sigma draw (thickness sd sqrt(0.1^2 + 2 * 0.05^2) = 0.12 h)
HEIGHT_SD_FRACTION = 0.10
FLATNESS_SD_FRACTION = 0.05
#: the largest misalignment, in bricks: a quarter brick is the layout's cell, the bearing of a
#: honeycomb bond; beyond it the layout no longer says which brick stands on which
MISALIGNMENT_SD_FRACTION = 0.25
#: no drawn brick may be thinner than this fraction of its nominal height anywhere
MIN_THICKNESS_FRACTION = 0.1
#: :func:`exaggerated_model` keeps every drawn brick at least this fraction of its nominal height
DRAWN_THICKNESS_FRACTION = 0.5


@dataclass(frozen=True, kw_only=True)
class Imperfections:
    """The amplitudes of a wall's imperfections (module docstring), mm; all zero: the perfect wall.

    height_sd_mm: standard deviation of each brick's height. height_distribution: "normal" or
    "uniform" (same standard deviation: half-width sqrt(3) height_sd_mm). flatness_sd_mm:
    standard deviation of each bed-face edge about the face's mid-line (a random tilt along the
    wall). misalignment_sd_mm: standard deviation of each brick's placement along the wall.
    Checked here against :data:`RULES`, and against the brick by :meth:`check_for`.
    """

    height_sd_mm: float = 0.0
    height_distribution: str = "normal"
    flatness_sd_mm: float = 0.0
    misalignment_sd_mm: float = 0.0

    def __post_init__(self):
        check_fields(self, RULES, "imperfections")

    @property
    def is_zero(self) -> bool:
        """Whether every amplitude is zero: the wall is the perfect one."""
        return self.height_sd_mm == 0 and self.flatness_sd_mm == 0 and self.misalignment_sd_mm == 0

    def scaled(self, factor: float) -> Imperfections:
        """Every amplitude times ``factor`` (>= 0, and small enough that every amplitude stays a
        finite number): with the same seed, the same draws scaled. ModelError naming the factor."""
        largest = max(self.height_sd_mm, self.flatness_sd_mm, self.misalignment_sd_mm)
        limit = Range(0.0, sys.float_info.max / largest if largest > 0 else None)
        problem = limit.problem(factor, "Imperfections.scaled factor")
        if problem is not None:
            raise ModelError(problem + (f" (beyond it the largest amplitude, {largest:g} mm, times the factor is no finite number)"
                                        if largest > 0 and is_number(factor) and factor > 0 else ""))
        return dataclasses.replace(self, height_sd_mm=factor * self.height_sd_mm, flatness_sd_mm=factor * self.flatness_sd_mm,
                                   misalignment_sd_mm=factor * self.misalignment_sd_mm)

    def check_for(self, brick: BrickSize, where: str, name: Callable[[str], str] = "imperfections {}".format) -> None:
        """ModelError naming ``where`` (the wall), each amplitude too large for ``brick`` (by
        ``name(field)``: a command names its option), its value and the rule: heights and flatness
        at most :data:`HEIGHT_SD_FRACTION` and :data:`FLATNESS_SD_FRACTION` of the brick height,
        misalignment :data:`MISALIGNMENT_SD_FRACTION` of its length."""
        limits = {"height_sd_mm": (HEIGHT_SD_FRACTION, brick.height_m, "height"),
                  "flatness_sd_mm": (FLATNESS_SD_FRACTION, brick.height_m, "height"),
                  "misalignment_sd_mm": (MISALIGNMENT_SD_FRACTION, brick.length_m, "length")}
        problems = []
        for field, (fraction, size_m, dimension) in limits.items():
            value = getattr(self, field)
            if value > fraction * size_m / MM:
                problems.append(f"{where}: {name(field)} = {value!r}: must be at most {fraction * size_m / MM:.4g} mm, "
                                f"{fraction:.0%} of the brick {dimension} ({size_m / MM:.4g} mm)")
        refuse(problems)

    def __str__(self) -> str:
        return (f"height sd {self.height_sd_mm:g} mm {self.height_distribution}, flatness sd {self.flatness_sd_mm:g} mm, "
                f"misalignment sd {self.misalignment_sd_mm:g} mm")


@dataclass(frozen=True)
class Placement:
    """Where each brick (n, the layout's block order) was laid, m: its footprint along the wall
    ``x_start``..``x_end``; ``lift`` of its bottom's mid-line above the nominal level; its height
    deviation ``height``; the slopes (dz/dx) of its ``bottom_slope`` and ``top_slope`` faces.
    The bottom lies at nominal bottom + lift + bottom_slope (x - mid), the top at nominal top +
    lift + height + top_slope (x - mid), mid the footprint's middle."""

    x_start: np.ndarray
    x_end: np.ndarray
    lift: np.ndarray
    height: np.ndarray
    bottom_slope: np.ndarray
    top_slope: np.ndarray

    @property
    def mid(self) -> np.ndarray:
        return 0.5 * (self.x_start + self.x_end)

    def thickness_deviation(self) -> np.ndarray:
        """(n, 2) each brick's thickness minus the nominal height at its left and right ends, m."""
        ends = np.stack([self.x_start, self.x_end], axis=1) - self.mid[:, None]
        return self.height[:, None] + (self.top_slope - self.bottom_slope)[:, None] * ends


def imperfect_blocks(wall: Wall, imperfections: Imperfections, seed: int) -> list[Block]:
    """The wall's blocks drawn with ``imperfections`` from ``seed`` (module docstring): the fixed
    base first, then the bricks, named and ordered as :meth:`Layout.blocks`. ModelError naming
    the wall for an amplitude too large for its brick, or a bad seed, or an argument of the wrong
    kind (:data:`ARGUMENT_RULES`)."""
    check_arguments("imperfect_blocks", ARGUMENT_RULES, wall=wall, imperfections=imperfections)
    with errors_naming(wall.source):
        imperfections.check_for(wall.brick, wall.source)
        return _blocks(wall, placement(wall, imperfections, seed), seed)


def imperfect_model(wall: Wall, imperfections: Imperfections, seed: int) -> Model:
    """:meth:`Wall.model` with the blocks of :func:`imperfect_blocks`."""
    check_arguments("imperfect_model", ARGUMENT_RULES, wall=wall, imperfections=imperfections)
    return _model(wall, imperfect_blocks(wall, imperfections, seed))


def exaggerated_model(wall: Wall, imperfections: Imperfections, seed: int, factor: float) -> tuple[Model, float]:
    """For drawing: the wall of :func:`imperfect_model` with every deviation ``factor`` times
    larger (the same draws, :meth:`Imperfections.scaled`), and the factor used. ``imperfections``
    is checked against the brick as given; the factor is lowered, where it has to be, so that
    every brick keeps at least :data:`DRAWN_THICKNESS_FRACTION` of its height (thickness is linear
    in the factor): a picture, not a model to analyse."""
    check_arguments("exaggerated_model", ARGUMENT_RULES, wall=wall, imperfections=imperfections)
    with errors_naming(wall.source):
        imperfections.check_for(wall.brick, wall.source)
        Range(0.0, None, low_open=True).check(factor, "exaggeration factor")
        thinnest = float(placement(wall, imperfections, seed).thickness_deviation().min(initial=0.0))
        if thinnest < 0.0:
            factor = min(factor, (1.0 - DRAWN_THICKNESS_FRACTION) * wall.brick.height_m / -thinnest)
        drawn = imperfections.scaled(factor)
        blocks = _blocks(wall, placement(wall, drawn, seed), seed)
    return _model(wall, blocks), factor


#: the kind of each argument of :func:`imperfect_model`, :func:`imperfect_blocks` and
#: :func:`exaggerated_model`: a wall as drydem.masonry.walls.load_wall reads it (not its Model,
#: whose blocks have lost their layout) and its amplitudes
ARGUMENT_RULES = {"wall": InstanceOf(Wall), "imperfections": InstanceOf(Imperfections)}


def standard_draws(n: int, distribution: str, seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The unit draws of ``n`` bricks from ``seed`` (module docstring): heights (n,), flatness
    (n, 2) (bottom, top face), misalignment (n,), each of unit variance."""
    if not isinstance(seed, (int, np.integer)) or isinstance(seed, bool) or seed < 0:
        raise ModelError(f"seed = {seed!r}: must be a non-negative integer")
    heights, flatness, misalignment = (np.random.default_rng(s) for s in np.random.SeedSequence(seed).spawn(3))
    if distribution == "uniform":
        height = heights.uniform(-math.sqrt(3.0), math.sqrt(3.0), n)
    else:
        height = heights.standard_normal(n)
    return height, flatness.standard_normal((n, 2)), misalignment.standard_normal(n)


def placement(wall: Wall, imperfections: Imperfections, seed: int) -> Placement:
    """Where every brick of ``wall`` goes (:class:`Placement`): misaligned left to right in each
    course, then laid course by course on the highest top beneath it (module docstring)."""
    units = wall.layout.solid_units
    height, flatness, shift = standard_draws(len(units), imperfections.height_distribution, seed)
    boxes = [unit_box(u, wall.brick) for u in units]
    x_start, x_end = _laid_along(units, boxes, imperfections.misalignment_sd_mm * MM * shift)
    length = np.array([hi[0] - lo[0] for lo, hi in boxes])
    edge = imperfections.flatness_sd_mm * MM * flatness
    laid = Placement(x_start=x_start, x_end=x_end, lift=np.zeros(len(units)), height=imperfections.height_sd_mm * MM * height,
                     bottom_slope=2.0 * edge[:, 0] / length, top_slope=2.0 * edge[:, 1] / length)
    return dataclasses.replace(laid, lift=_lifts(laid, np.array([u.course for u in units]), wall.brick.height_m))


def _laid_along(units, boxes, shift: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each brick's footprint along the wall, m: its nominal one moved by ``shift``, but never
    starting left of the end of the brick laid before it in its course."""
    x_start, x_end = np.empty(len(units)), np.empty(len(units))
    previous_end, course = -math.inf, None
    for i, (unit, (lo, hi)) in enumerate(zip(units, boxes)):
        if unit.course != course:
            previous_end, course = -math.inf, unit.course
        x_start[i] = max(lo[0] + shift[i], previous_end)
        x_end[i] = hi[0] + (x_start[i] - lo[0])  # nominal + the move: exact when there is none
        previous_end = x_end[i]
    return x_start, x_end


def _lifts(laid: Placement, course: np.ndarray, brick_height_m: float) -> np.ndarray:
    """Each brick's lift (:class:`Placement`): the least that puts its bottom on or above every
    top beneath it, course by course. Only the *surface* is searched: the bricks not yet covered
    end to end by a later course (a covered brick's top lies under the brick that covers it). The
    base's top, z = 0, is a surface under everything."""
    lift = laid.lift.copy()
    mid = laid.mid
    surface = np.zeros(0, dtype=int)
    for c in range(course.max() + 1):
        now = np.flatnonzero(course == c)
        # base: its top is the nominal bottom of course 0, c h below this course's
        base = [-c * brick_height_m - laid.bottom_slope[now] * (x - mid[now]) for x in (laid.x_start[now], laid.x_end[now])]
        need = np.maximum(*base)
        if surface.size:
            low = np.maximum(laid.x_start[now, None], laid.x_start[None, surface])
            high = np.minimum(laid.x_end[now, None], laid.x_end[None, surface])
            # a top's deviation from this course's nominal bottom, minus the bottom's slope term
            top = lift[surface] + laid.height[surface] + (course[surface] + 1 - c) * brick_height_m
            gaps = [top + laid.top_slope[surface] * (x - mid[surface]) - laid.bottom_slope[now, None] * (x - mid[now, None])
                    for x in (low, high)]
            need = np.maximum(need, np.where(low < high, np.maximum(*gaps), -np.inf).max(axis=1))
        lift[now] = need
        covered = np.array([_covered(laid.x_start[j], laid.x_end[j], laid.x_start[now], laid.x_end[now]) for j in surface], dtype=bool)
        surface = np.concatenate([surface[~covered], now])
    return lift


def _covered(start: float, end: float, starts: np.ndarray, ends: np.ndarray) -> bool:
    """Whether [start, end] lies within the union of the disjoint intervals [starts, ends]."""
    overlap = np.clip(np.minimum(ends, end) - np.maximum(starts, start), 0.0, None)
    return bool(overlap.sum() >= end - start)


def _blocks(wall: Wall, laid: Placement, seed: int) -> list[Block]:
    """The base and the bricks as placed: each brick the convex hull of its eight corners, or,
    where its bed faces are level, a box (drydem.model.geometry.box: a brick placed as drawn is
    the layout's box, bit for bit). ModelError for a brick thinner than :data:`MIN_THICKNESS_FRACTION` of its height."""
    h = wall.brick.height_m
    thickness = h + laid.thickness_deviation()
    names = wall.layout.block_names()
    thin = np.flatnonzero(thickness.min(axis=1) < MIN_THICKNESS_FRACTION * h)
    if thin.size:
        i = int(thin[0])
        raise ModelError(f"seed {seed}: brick {names[i]!r} is drawn {thickness[i].min() / MM:.4g} mm thick at an end, less than "
                         f"{MIN_THICKNESS_FRACTION:.0%} of the brick height ({h / MM:.4g} mm): the amplitudes are too large for it")
    mid = laid.mid
    bricks = []
    for i, (name, unit) in enumerate(zip(names, wall.layout.solid_units)):
        lo, hi = unit_box(unit, wall.brick)
        ends = (laid.x_start[i], laid.x_end[i])
        bottom = [lo[2] + (laid.lift[i] + laid.bottom_slope[i] * (x - mid[i])) for x in ends]
        top = [hi[2] + (laid.lift[i] + laid.height[i] + laid.top_slope[i] * (x - mid[i])) for x in ends]
        where = f"block {name!r}"
        if bottom[0] == bottom[1] and top[0] == top[1]:  # level faces: a box
            shape = box([ends[0], lo[1], bottom[0]], [ends[1], hi[1], top[0]], name=where)
        else:
            shape = convex_hull(np.array([[x, y, z] for k, x in enumerate(ends) for y in (lo[1], hi[1]) for z in (bottom[k], top[k])]),
                                name=where)
        bricks.append(Block(name=name, shape=shape))
    return [base_under(bricks), *bricks]


def _model(wall: Wall, blocks: list[Block]) -> Model:
    """The model of ``blocks`` with the wall's material and options, as :meth:`Wall.model`."""
    with errors_naming(wall.source):
        return build_model(blocks, density=wall.density, joint=wall.joint, contacts=wall.contacts,
                           supports=wall.supports, solver=wall.solver, source=wall.source)
