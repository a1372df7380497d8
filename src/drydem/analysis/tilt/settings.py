"""What the tilting analysis is given and gives back: its settings (:class:`TiltSettings`,
checked against :data:`SETTING_RANGES`), the outcome names, the states it reports
(:class:`Record`, :class:`Frame`, :class:`TiltResult`), and the block it monitors and the wall
height its drift is measured against."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from drydem.analysis.dataframes import data_frame
from drydem.analysis.drift import DLS_DRIFT, drift_limit_angles
from drydem.engine.contacts import SubContacts
from drydem.errors import ModelError
from drydem.model.assembly import Model
from drydem.model.parameters import (FLAG, LOST_DROP_HEIGHTS, MAX_ACCELERATION_M_S2, SOLVER_RULES, G, LOAD_DIRECTION, TILT_AXES, OneOf,
                                     Range, check_fields)
from drydem.model.state import State

LOADINGS = ("tilt", "multiplier")
#: how a call of :meth:`~drydem.analysis.tilt.run.TiltRun.equilibrate` ended
EQUILIBRIUM, FELL, MONITOR_FELL, MONITOR_TOPPLED, STOP_DISPLACEMENT, GAVE_UP, MAX_CYCLES = (
    "equilibrium", "fell", "monitored block fell", "monitored block toppled", "stop displacement", "gave up", "max cycles",
)
#: the turn from where it was drawn, rad, past which the monitored block has toppled (it lies on
#: another face or rocks on an edge: a collapse, however little it moved; found by a hunt: a
#: 5.5 x 25 mm brick on its end toppled at 9.7 deg, moved 16 mm, lay on its side and was given
#: the collapse angle of its sliding, 26.5 deg, the default stop displacement being 0.10 m)
TOPPLED_RAD = math.radians(45.0)
#: why an analysis ended (TiltResult.ended_by): a collapse (MONITOR_FELL, MONITOR_TOPPLED,
#: STOP_DISPLACEMENT), or one of these, none of which is a collapse
UNSTABLE_UNDER_GRAVITY = "unstable under gravity"
NO_EQUILIBRIUM_UNDER_GRAVITY = "no equilibrium under gravity within max_cycles"
NO_EQUILIBRIUM = "no equilibrium within max_cycles"
MAXIMUM_ANGLE = "maximum angle"
#: a step after the last equilibrium blew up (:class:`~drydem.errors.DivergenceError`): no
#: verdict, like NO_EQUILIBRIUM (found by a hunt: an octagonal prism overhanging its slab's edge
#: at kn = 1e12 Pa/m diverged in the step it toppled in; the tilt stopped with the error, and the
#: equilibria it had found were not reported. That divergence's cause, an edge-face contact taken
#: for crossed edges, is fixed: :func:`drydem.engine.narrow_phase._edge_along_face`)
DIVERGED = "integration diverged"
#: every TiltResult.ended_by: the three collapses, then the endings that are none
ENDINGS = (MONITOR_FELL, MONITOR_TOPPLED, STOP_DISPLACEMENT, UNSTABLE_UNDER_GRAVITY, NO_EQUILIBRIUM_UNDER_GRAVITY, NO_EQUILIBRIUM,
           MAXIMUM_ANGLE, DIVERGED)


#: the allowed values of TiltSettings' numbers (a tilt of 90 deg or more is no tilting table)
SETTING_RANGES = {
    # a thousandth of a degree is 90,000 steps to 90 deg; at 1e-12 the predictor's extrapolation
    # divided by a difference of tilts lost to round-off
    "increment_deg": Range(1e-3, 90.0, high_open=True, unit="deg"),
    "refinements": Range(0, 12, integer=True),
    # a nanometre: the joints' elastic shear at the first step can exceed it, and a stop
    # displacement below it (1e-300 m) measures nothing but round-off
    "stop_displacement_m": Range(1e-9, 100.0, unit="m"),
    "max_angle_deg": Range(0.0, 90.0, low_open=True, high_open=True, unit="deg"),
    "lost_drop_heights": LOST_DROP_HEIGHTS,
    "chunk_cycles": SOLVER_RULES["max_cycles"],  # a check of the monitored point at most as far apart as one equilibrium's cycles may be
    # the factors of the adaptive trials and the predictor: past 1e6 each rule is off in all but
    # name, which a setting must not hide (a trial is abandoned, a predicted move capped, never)
    "trial_growth": Range(1.0, 1e6, low_open=True),
    "trial_floor_m": Range(0.0, 100.0, low_open=True, unit="m"),  # as stop_displacement_m
    "predictor_growth": Range(1.0, 1e6),
    "predictor_cap_closures": Range(0.0, 1e6, low_open=True),
}


#: deg: the largest tilt-equivalent of the load multiplier protocol, where its gravity
#: g (tan theta, -1), of magnitude g / cos theta, reaches the largest acceleration a Simulation takes
STEEPEST_MULTIPLIER_DEG = math.degrees(math.acos(G / MAX_ACCELERATION_M_S2))
#: the rule of every field of TiltSettings but the monitored block's name
SETTING_RULES = SETTING_RANGES | {"adaptive": FLAG, "loading": OneOf(LOADINGS), "predictor": FLAG, "tilt_axis": OneOf(TILT_AXES)}


@dataclass(frozen=True, kw_only=True)
class TiltSettings:
    """Protocol parameters (CLI options of ``drydem tilt``).

    increment_deg : tilt step, deg (paper: 0.1). adaptive : coarse steps and bisection.
    refinements : adaptive steps start at increment_deg * 2**refinements. stop_displacement_m :
    horizontal displacement of the monitored point that ends the analysis, m (paper: 0.10).
    loading : "tilt" or "multiplier". tilt_axis : the horizontal axis the table turns about,
    "y" (default: the lateral load acts along +x, in the plane of a wall drawn in x-z) or "x"
    (the lateral load acts along +y: out of the plane of such a wall, and of a building's walls
    running along x); the multiplier's load lambda g acts along the same direction, and the
    monitored displacement, the drift and the stop displacement are measured along it. An
    in-plane model (held in y) cannot be tilted about x (:func:`check_loading`).
    monitor : block name (default: :func:`monitored_block`). max_angle_deg : the analysis ends there, deg.
    lost_drop_heights : a block whose centroid dropped more than this many times its own
    height is taken out. chunk_cycles : cycles between checks of the monitored point.
    trial_growth, trial_floor_m : a coarse adaptive trial is abandoned as failed once the
    monitored point has moved more than trial_growth times the displacement the last two
    equilibria predict for it, and at least trial_floor_m (m), or once a block has fallen out.
    predictor : start each step from the last two equilibria extrapolated
    (:mod:`drydem.analysis.tilt`), unless the last step moved predictor_growth times more per
    degree than the one before; the move capped at predictor_cap_closures elastic closures of
    the joints (:mod:`drydem.analysis.tilt`).
    """

    increment_deg: float = 0.1
    adaptive: bool = False
    refinements: int = 4
    stop_displacement_m: float = 0.10
    loading: str = "tilt"
    tilt_axis: str = "y"
    monitor: str | None = None
    max_angle_deg: float = 80.0
    lost_drop_heights: float = 2.0
    chunk_cycles: int = 2000
    trial_growth: float = 4.0
    trial_floor_m: float = 5e-4
    predictor: bool = True
    predictor_growth: float = 2.0
    predictor_cap_closures: float = 150.0

    def __post_init__(self):
        check_fields(self, SETTING_RULES, "tilt setting")
        if self.monitor is not None and not (isinstance(self.monitor, str) and self.monitor.strip()):  # "" named no block
            raise ModelError(f"tilt setting monitor = {self.monitor!r}: must be a block name")
        if self.increment_deg > self.max_angle_deg:
            raise ModelError(
                f"tilt setting increment_deg = {self.increment_deg!r} exceeds max_angle_deg = {self.max_angle_deg!r}: "
                "no step would be taken"
            )
        if self.loading == "multiplier" and self.max_angle_deg > STEEPEST_MULTIPLIER_DEG:
            raise ModelError(f"tilt setting max_angle_deg = {self.max_angle_deg!r}: with loading = 'multiplier' at most "
                             f"{STEEPEST_MULTIPLIER_DEG:.6f} deg, where the gravity g (tan theta, -1), of magnitude g / cos theta, "
                             f"reaches {MAX_ACCELERATION_M_S2:g} m/s2 (drydem.model.parameters.MAX_ACCELERATION_M_S2)")

    @property
    def load_direction(self) -> int:
        """The horizontal axis the lateral load acts along: 0 (x, tilting about y) or 1 (y,
        tilting about x)."""
        return LOAD_DIRECTION[self.tilt_axis]

    def gravity(self, theta_deg: float) -> np.ndarray:
        """Gravity vector (m/s2) at tilt (or tilt-equivalent) ``theta_deg``: g (sin, -cos) or
        g (tan, -1) in the plane of the load direction (:attr:`load_direction`) and z."""
        t = math.radians(theta_deg)
        lateral, vertical = (math.sin(t), -math.cos(t)) if self.loading == "tilt" else (math.tan(t), -1.0)
        g = np.array([0.0, 0.0, G * vertical])
        g[self.load_direction] = G * lateral
        return g

    def first_step(self) -> float:
        """The first stage 2 step, deg: one increment, or 2**refinements of them if adaptive."""
        return self.increment_deg * (2**self.refinements if self.adaptive else 1)


@dataclass(frozen=True)
class Record:
    """One equilibrium state of the pushover curve: tilt (deg), the monitored block's
    displacement from where it was drawn along the load direction (``ux_m``: along x, or along y
    when tilting about x) and vertically (``uz_m``), m, the drift and the cycles this step took.

    The drift is the displacement the tilt caused over the wall's height, (ux - ux_0) / height,
    ux_0 that of the first record, the equilibrium under the model's own weight (0 deg): as a
    tilting table's transducers are zeroed once the wall stands, and 3DEC's displacements reset
    after the initial equilibrium (found by a hunt: an imperfect pier that settled 0.66 mm
    sideways under its own weight reached every drift limit at 0 deg)."""

    tilt_deg: float
    ux_m: float
    uz_m: float
    drift: float
    cycles: int

    @property
    def load_multiplier(self) -> float:
        return math.tan(math.radians(self.tilt_deg))


@dataclass(frozen=True)
class Frame:
    """A state of the analysis to show: ``kind`` "equilibrium" or "past collapse", the tilt
    (deg), the monitored displacement along the load direction (m), the blocks' State, their sub-contacts and
    which blocks are still in the analysis (``active``, (nb,) bool)."""

    kind: str
    tilt_deg: float
    ux_m: float
    state: State = field(repr=False)
    contacts: SubContacts = field(repr=False)
    active: np.ndarray = field(repr=False)


@dataclass
class TiltResult:
    """Outcome of :func:`~drydem.analysis.tilt.tilt_analysis`. States are block
    positions/orientations (State); ``cycles`` counts every cycle run, those of abandoned
    adaptive trials included.
    ``stable_under_gravity``: True (stage 1 reached equilibrium), False (a block fell under its
    own weight: named in ``lost_blocks`` at 0 deg, or the monitored point moved the stop
    displacement), None (no equilibrium within max_cycles: not known). ``ended_by``: why the
    analysis stopped. ``last_equilibrium_deg``: the largest tilt in equilibrium;
    ``collapse_angle_deg`` is that tilt only when the next step collapsed (the monitored block
    fell or moved the stop displacement), else None (no collapse up to the maximum angle, or no
    equilibrium within max_cycles, or a step that diverged, which are no verdict).
    ``final_state``: where the cycling ended (the last equilibrium's state after a step that diverged)."""

    settings: TiltSettings
    monitored_block: str
    wall_height_m: float
    stable_under_gravity: bool | None
    last_equilibrium_deg: float | None
    collapse_angle_deg: float | None
    records: list[Record]
    lost_blocks: list[tuple[str, float]]
    cycles: int
    runtime_s: float
    collapse_state: State | None = field(repr=False)
    final_state: State = field(repr=False)
    ended_by: str

    @property
    def load_multiplier(self) -> float | None:
        return None if self.collapse_angle_deg is None else math.tan(math.radians(self.collapse_angle_deg))

    @property
    def drift_limit_angles_deg(self) -> dict[float, float | None]:
        return drift_limit_angles([r.tilt_deg for r in self.records], [r.drift for r in self.records])

    def to_dataframe(self):
        """The pushover curve as a pandas DataFrame (:func:`drydem.analysis.dataframes.data_frame`), one row per equilibrium
        state (:class:`Record`) in the columns of ``pushover.csv``: ``tilt_deg``,
        ``load_multiplier``, ``ux_m``, ``uz_m`` (the monitored block's displacement along the
        load direction and vertically, m), ``drift``, ``cycles``; ``attrs``: the outcome
        (``collapse_angle_deg``, ``load_multiplier``, ``last_equilibrium_deg``,
        ``stable_under_gravity``, ``ended_by``, ``drift_limit_angles_deg``, ``lost_blocks`` as
        (block, tilt_deg) pairs, ``monitored_block``, ``wall_height_m``, ``cycles``, ``runtime_s``)."""
        columns = {"tilt_deg": [r.tilt_deg for r in self.records], "load_multiplier": [r.load_multiplier for r in self.records]}
        columns |= {name: [getattr(r, name) for r in self.records] for name in ("ux_m", "uz_m", "drift", "cycles")}
        outcome = ("collapse_angle_deg", "load_multiplier", "last_equilibrium_deg", "stable_under_gravity", "ended_by",
                   "drift_limit_angles_deg", "lost_blocks", "monitored_block", "wall_height_m", "cycles", "runtime_s")
        return data_frame(columns, {name: getattr(self, name) for name in outcome})


def monitored_block(model: Model, tilt_axis: str = "y") -> int:
    """The top block nearest the middle of the wall in x (the mean x of the movable blocks'
    centroids; the walls are drawn along x). The top blocks are the movable ones whose top is
    above the centroid of the highest: the top course of a wall, whose tops differ by the
    imperfections of its bricks (a fraction of a millimetre; the highest alone would be the
    tallest brick, anywhere along the course) while the course below ends half a brick lower.
    With ``tilt_axis`` "x" (the load along y), remaining ties go to the block farthest along +y:
    of a building, the top middle block of the leeward wall running along x (wall 2), which the
    load pushes out of its plane and away from the building."""
    movable = np.flatnonzero(model.block_movable)
    tops = np.array([model.block_shape[b].vertices[:, 2].max() for b in movable])
    highest = movable[tops > model.block_centroid[movable[np.argmax(tops)], 2]]
    middle = np.mean([model.block_shape[b].centroid[0] for b in movable])
    off = np.abs(model.block_centroid[highest, 0] - middle)
    if tilt_axis == "x":
        nearest = highest[off <= off.min() + 1e-9 * model.contact_tolerance]
        return int(nearest[np.argmax(model.block_centroid[nearest, 1])])
    return int(highest[np.argmin(off)])


def check_loading(model: Model, settings: TiltSettings) -> None:
    """ModelError if ``settings`` load ``model`` where it cannot move: an in-plane model (held
    in y, :attr:`~drydem.model.assembly.Model.in_plane`) tilted about x."""
    if settings.tilt_axis == "x" and model.in_plane:
        raise ModelError(f"{model.source}: tilt_axis = 'x' loads the model along y, out of its plane, but it is an in-plane "
                         "model (its blocks are held in y); tilt it about y, or give it blocks free in y ([supports])")


def check_stop_displacement(model: Model, settings: TiltSettings) -> None:
    """ModelError if the stop displacement is a drift below :data:`~drydem.analysis.drift.DLS_DRIFT`
    (1 %) of the wall's height (:func:`wall_height`): the analysis would end there, before the
    drift limits it reports, and call it a collapse (found by a hunt: a wall of 20 m bricks
    "collapsed" at 17 deg having moved the default 0.10 m, a drift of 0.25 %, and stood to 26
    deg given 5 m). The commands check it; :func:`tilt_analysis` does not, so that the rule's
    own tests can stop a brick at a micrometre."""
    height = wall_height(model)
    if settings.stop_displacement_m < DLS_DRIFT * height:
        raise ModelError(f"{model.source}: stop_displacement_m = {settings.stop_displacement_m:g} m (--stop-displacement) is a drift "
                         f"of {settings.stop_displacement_m / height:.2%} of the wall's {height:.4g} m height, below the "
                         f"{DLS_DRIFT:.0%} of the damage limitation state: the analysis would end there and call it a collapse; "
                         f"give at least {DLS_DRIFT * height:.4g} m (the default 0.10 m is two thirds of the paper's 0.15 m walls)")


def monitor_index(model: Model, name: str | None, tilt_axis: str = "y") -> int:
    """The block to monitor: ``name``'s (ModelError if there is none or it is fixed: a fixed
    block never moves), or by default :func:`monitored_block` for ``tilt_axis``."""
    if name is None:
        return monitored_block(model, tilt_axis)
    block = model.block_index(name)
    if not model.block_movable[block]:
        raise ModelError(f"{model.source}: the monitored block {name!r} is fixed (it cannot move); monitor a movable block")
    return block


def wall_height(model: Model) -> float:
    """Height of the movable blocks above their lowest point, m (the drift's denominator)."""
    z = np.concatenate([model.block_shape[b].vertices[:, 2] for b in np.flatnonzero(model.block_movable)])
    return float(z.max() - z.min())
