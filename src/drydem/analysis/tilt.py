"""Tilting-table analysis and pushover by a load multiplier (Savalle et al. 2022, Section 3).

Stage 1: vertical gravity in one step, cycled to equilibrium. Stage 2: the tilt theta
grows by ``increment_deg`` and gravity becomes

    tilt:        g (sin theta, 0, -cos theta)        (paper Eq. 5)
    multiplier:  g (lambda, 0, -1), lambda = tan theta   (classic pushover, the same statics
                 direction; theta = atan(lambda) is its tilt equivalent)

cycling to equilibrium at each step, until the monitored point has moved
``stop_displacement_m`` horizontally, the monitored block has fallen out of the model (below,
a part of the wall that collapses onto the rubble of another may come to rest within the
stop displacement), or equilibrium cannot be reached within the solver's ``max_cycles``.
The collapse angle is the largest tilt at which the model was in equilibrium.

Predictor: each step starts from the trend of the last two equilibria, extrapolated to the new
tilt and applied as one cycle's rigid motion (:meth:`~drydem.engine.simulation.Simulation.move`; the joints
follow it as in any cycle), so that dynamic relaxation only has the step's non-linearity left to
remove: about half the cycles on the competition walls. Only an elastic trend is extrapolated:
a slip or a local failure is not recovered when the load grows (friction keeps what it is
given), so extrapolating one would ratchet it on. The step after one whose motion per degree
grew more than ``predictor_growth`` times over the step before starts without a prediction,
and every move of a block point is capped at ``predictor_cap_closures`` elastic closures: the
median over the blocks of m g / sum(k A), what a block's own weight closes its joints by (the
contacts as drawn). The cap thus follows the joint stiffness: a soft wall moves far and
elastically at every step, a stiff one little, but as much as a soft one once it slips. The default, 150, is
about one contact tolerance at kn = 3e7 Pa/m on the competition walls and 1/30 of one at 1e9
(a cap of one tolerance there extrapolated a slip of WD1 into a local failure at 22.4 deg,
against 26.3 without the predictor).

Adaptive protocol: steps of ``increment_deg * 2**refinements``; a step that fails is undone
(the last equilibrium is restored, shear history included) and halved, down to
``increment_deg``; so the collapse angle is found to within one increment, as with fixed steps.
A coarse step is judged failed early, once its motion is clearly not elastic (``_trial_limit``):
only steps of one increment are followed to the stop criteria.

Blocks that fall out of the model (a rigid-body drop of more than ``lost_drop_heights`` of
their own heights: the centroid's drop below where it was drawn, less the settlement the
joints' elastic closure explains, :mod:`drydem.analysis.support`; e.g. a brick sliding out of a course)
are taken out of the analysis and reported, so that a local failure does not hide the global
collapse. A tall or soft wall's elastic settlement is not a fall.

Stage 1 ends in one of three ways: equilibrium; a fall (a block falls or the monitored point
moves ``stop_displacement_m``: the model cannot stand under its own weight, and the blocks that
fell are named); or no equilibrium within the solver's ``max_cycles``, which is no verdict on
stability (``stable_under_gravity`` is then None) and is reported as such.
"""

from __future__ import annotations

import hashlib
import json
import math
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

from drydem.analysis.drift import drift_limit_angles
from drydem.errors import ModelError
from drydem.engine.checkpoint import load_checkpoint, save_checkpoint
from drydem.model.assembly import Model
from drydem.engine.inertia import contact_stiffness
from drydem.model.parameters import G, Range
from drydem.engine.contacts import SubContacts
from drydem.model.rotation import matrices, rotation_vectors
from drydem.engine.simulation import Simulation
from drydem.model.state import State
from drydem.analysis.support import elastic_settlement, load_paths

LOADINGS = ("tilt", "multiplier")
#: how a call of :meth:`_Run.equilibrate` ended
EQUILIBRIUM, FELL, MONITOR_FELL, STOP_DISPLACEMENT, GAVE_UP, MAX_CYCLES = (
    "equilibrium", "fell", "monitored block fell", "stop displacement", "gave up", "max cycles",
)
#: why an analysis ended (TiltResult.ended_by): a collapse (MONITOR_FELL, STOP_DISPLACEMENT),
#: or one of these, none of which is a collapse
UNSTABLE_UNDER_GRAVITY = "unstable under gravity"
NO_EQUILIBRIUM_UNDER_GRAVITY = "no equilibrium under gravity within max_cycles"
NO_EQUILIBRIUM = "no equilibrium within max_cycles"
MAXIMUM_ANGLE = "maximum angle"
#: states past collapse are sampled this many times per chunk_cycles (drydem tilt --vtk)
FRAME_SAMPLING = 10


#: the allowed values of TiltSettings' numbers (a tilt of 90 deg or more is no tilting table)
SETTING_RANGES = {
    "increment_deg": Range(0.0, 90.0, low_open=True, high_open=True, unit="deg"),
    "refinements": Range(0, 12, integer=True),
    "stop_displacement_m": Range(0.0, 100.0, low_open=True, unit="m"),
    "max_angle_deg": Range(0.0, 90.0, low_open=True, high_open=True, unit="deg"),
    "lost_drop_heights": Range(0.0, None, low_open=True),
    "chunk_cycles": Range(1, None, integer=True),
    "trial_growth": Range(1.0, None, low_open=True),
    "trial_floor_m": Range(0.0, None, low_open=True, unit="m"),
    "predictor_growth": Range(1.0, None),
    "predictor_cap_closures": Range(0.0, None, low_open=True),
}


@dataclass(frozen=True, kw_only=True)
class TiltSettings:
    """Protocol parameters (CLI options of ``drydem tilt``).

    increment_deg : tilt step, deg (paper: 0.1). adaptive : coarse steps and bisection.
    refinements : adaptive steps start at increment_deg * 2**refinements. stop_displacement_m :
    horizontal displacement of the monitored point that ends the analysis, m (paper: 0.10).
    loading : "tilt" or "multiplier". monitor : block name (default: the block whose top is
    highest, nearest the middle of the wall). max_angle_deg : the analysis ends there, deg.
    lost_drop_heights : a block whose centroid dropped more than this many times its own
    height is taken out. chunk_cycles : cycles between checks of the monitored point.
    trial_growth, trial_floor_m : a coarse adaptive trial is abandoned as failed once the
    monitored point has moved more than trial_growth times the displacement the last two
    equilibria predict for it, and at least trial_floor_m (m), or once a block has fallen out.
    predictor : start each step from the last two equilibria extrapolated (module docstring),
    unless the last step moved predictor_growth times more per degree than the one before; the
    move capped at predictor_cap_closures elastic closures of the joints (module docstring).
    """

    increment_deg: float = 0.1
    adaptive: bool = False
    refinements: int = 4
    stop_displacement_m: float = 0.10
    loading: str = "tilt"
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
        for name, allowed in SETTING_RANGES.items():
            allowed.check(getattr(self, name), f"tilt setting {name}")
        if self.loading not in LOADINGS:
            raise ModelError(f"tilt setting loading = {self.loading!r}: must be one of {LOADINGS}")
        if self.monitor is not None and not isinstance(self.monitor, str):
            raise ModelError(f"tilt setting monitor = {self.monitor!r}: must be a block name")
        if self.increment_deg > self.max_angle_deg:
            raise ModelError(
                f"tilt setting increment_deg = {self.increment_deg!r} exceeds max_angle_deg = {self.max_angle_deg!r}: "
                "no step would be taken"
            )

    def gravity(self, theta_deg: float) -> np.ndarray:
        """Gravity vector (m/s2) at tilt (or tilt-equivalent) ``theta_deg``."""
        t = math.radians(theta_deg)
        if self.loading == "tilt":
            return G * np.array([math.sin(t), 0.0, -math.cos(t)])
        return G * np.array([math.tan(t), 0.0, -1.0])


@dataclass(frozen=True)
class Record:
    """One equilibrium state of the pushover curve: tilt (deg), monitored displacement (m),
    drift (ux / wall height) and the cycles this step took."""

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
    (deg), the monitored horizontal displacement (m), the blocks' State, their sub-contacts and
    which blocks are still in the analysis (``active``, (nb,) bool)."""

    kind: str
    tilt_deg: float
    ux_m: float
    state: State = field(repr=False)
    contacts: SubContacts = field(repr=False)
    active: np.ndarray = field(repr=False)


class _Trace:
    """The frames of the step being cycled, one per chunk, at most ``limit``: past that, every
    other frame is dropped and only every other chunk kept, so a long flow stays evenly sampled."""

    def __init__(self, limit: int = 240):
        self.frames: list[Frame] = []
        self.limit, self.stride, self.seen = limit, 1, 0

    def add(self, make: Callable[[], Frame]) -> None:
        self.seen += 1
        if self.seen % self.stride:
            return
        self.frames.append(make())
        if len(self.frames) > self.limit:
            self.frames, self.stride = self.frames[1::2], 2 * self.stride


@dataclass
class TiltResult:
    """Outcome of :func:`tilt_analysis`. States are block positions/orientations (State);
    ``cycles`` counts every cycle run, those of abandoned adaptive trials included.
    ``stable_under_gravity``: True (stage 1 reached equilibrium), False (a block fell under its
    own weight: named in ``lost_blocks`` at 0 deg, or the monitored point moved the stop
    displacement), None (no equilibrium within max_cycles: not known). ``ended_by``: why the
    analysis stopped. ``last_equilibrium_deg``: the largest tilt in equilibrium;
    ``collapse_angle_deg`` is that tilt only when the next step collapsed (the monitored block
    fell or moved the stop displacement), else None (no collapse up to the maximum angle, or no
    equilibrium within max_cycles, which is no verdict)."""

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
    def drift_limit_angles_deg(self) -> dict[str, float | None]:
        return drift_limit_angles([r.tilt_deg for r in self.records], [r.drift for r in self.records])


def monitored_block(model: Model) -> int:
    """The movable block whose top is highest; ties go to the one nearest the middle of the wall."""
    movable = np.flatnonzero(model.block_movable)
    tops = np.array([model.block_shape[b].vertices[:, 2].max() for b in movable])
    highest = movable[tops >= tops.max() - 1e-9 * model.contact_tolerance]
    middle = np.mean([model.block_shape[b].centroid[0] for b in movable])
    return int(highest[np.argmin(np.abs(model.block_centroid[highest, 0] - middle))])


def monitor_index(model: Model, name: str | None) -> int:
    """The block to monitor: ``name``'s (ModelError if there is none or it is fixed: a fixed
    block never moves), or by default :func:`monitored_block`."""
    if name is None:
        return monitored_block(model)
    block = model.block_index(name)
    if not model.block_movable[block]:
        raise ModelError(f"{model.source}: the monitored block {name!r} is fixed (it cannot move); monitor a movable block")
    return block


def wall_height(model: Model) -> float:
    """Height of the movable blocks above their lowest point, m (the drift's denominator)."""
    z = np.concatenate([model.block_shape[b].vertices[:, 2] for b in np.flatnonzero(model.block_movable)])
    return float(z.max() - z.min())


class _Run:
    """Bookkeeping of one analysis: the simulation, the monitored point, the lost blocks."""

    def __init__(self, model: Model, settings: TiltSettings, on_progress):
        self.model, self.settings, self.on_progress = model, settings, on_progress
        self.sim = Simulation(model)
        self.monitor = monitor_index(model, settings.monitor)
        self.height = wall_height(model)
        self.lost: list[tuple[str, float]] = []
        heights = np.array([np.ptp(shape.vertices[:, 2]) for shape in model.block_shape])
        self.lost_drop = settings.lost_drop_heights * heights
        #: the last three equilibria, (tilt in deg, State), oldest first, and the trends
        #: (displacement m/deg, rotation rad/deg, largest point motion m/deg) between them
        self.equilibria: list[tuple[float, State]] = []
        self.trends: list[tuple[np.ndarray, np.ndarray, float]] = []
        self.elastic_closure = _elastic_closure(model, self.sim.contacts)

    def remember(self, theta_deg: float, state: State | None = None) -> None:
        """``state`` (default: the current one) is an equilibrium at ``theta_deg``."""
        state = self.sim.state.copy() if state is None else state
        if self.equilibria:
            self.trends = [*self.trends[-1:], self._trend(*self.equilibria[-1], theta_deg, state)]
        self.equilibria = [*self.equilibria[-2:], (theta_deg, state)]

    def predict(self, theta_deg: float) -> None:
        """Move the blocks (at the last equilibrium) along the trend of the last two equilibria,
        extrapolated linearly in the tilt to ``theta_deg``, if that trend is elastic; capped
        (module docstring)."""
        if not self.settings.predictor or not self.trends:
            return
        displacement, rotation, motion = self.trends[-1]
        if len(self.trends) == 2 and motion > self.settings.predictor_growth * self.trends[-2][2]:
            return
        scale = theta_deg - self.equilibria[-1][0]
        cap = self.settings.predictor_cap_closures * self.elastic_closure
        scale = min(scale, cap / motion) if motion * scale > cap else scale
        self.sim.move(scale * displacement, scale * rotation, gravity=self.settings.gravity(theta_deg))

    def _trend(self, theta_0: float, before: State, theta_1: float, after: State) -> tuple[np.ndarray, np.ndarray, float]:
        """Displacements (nb, 3) m/deg and rotation vectors (nb, 3) rad/deg from equilibrium
        ``before`` to ``after``, and the largest motion of a block point, m/deg."""
        displacement = (after.position - before.position) / (theta_1 - theta_0)
        rotation = rotation_vectors(before.quaternion, after.quaternion) / (theta_1 - theta_0)
        motion = float((np.linalg.norm(displacement, axis=1) + np.linalg.norm(rotation, axis=1) * self.model.block_radius).max())
        return displacement, rotation, motion

    def displacement(self) -> tuple[float, float]:
        moved = self.sim.state.position[self.monitor] - self.model.block_centroid[self.monitor]
        return float(moved[0]), float(moved[2])

    def equilibrate(self, theta_deg: float, *, vertical: bool = False, chunk_cycles: int | None = None,
                    trace: _Trace | None = None, give_up: Callable[[], bool] | None = None) -> tuple[str, int]:
        """Cycle at ``theta_deg`` until equilibrium, the stop displacement, the fall of the
        monitored block, ``give_up()`` or max cycles; returns how it ended (EQUILIBRIUM,
        STOP_DISPLACEMENT, MONITOR_FELL, GAVE_UP, MAX_CYCLES, or FELL under vertical gravity) and
        the cycles run. Progress is reported and a frame added to ``trace`` every
        ``chunk_cycles`` (default the settings').

        Blocks that fall out are taken out and the cycling goes on, except under vertical
        gravity (stage 1): a model that loses a block under its own weight cannot stand (the
        blocks are added to ``lost`` and FELL returned).
        Falls, the stop displacement and ``give_up()`` are also looked at whenever the
        simulation re-detects contacts, so that a falling block (which needs new contacts every
        few cycles) is taken out, and a collapse recognised, as soon as it happens.
        Stage 2 steps start with the predictor (:meth:`predict`), from the last equilibrium.
        """
        gravity = np.array([0.0, 0.0, -G]) if vertical else self.settings.gravity(theta_deg)
        if not vertical:
            self.predict(theta_deg)
        solver = self.model.solver
        done = 0

        def stop() -> bool:
            dropped = self._dropped()
            return (
                self._fallen(dropped).size > 0
                or bool(dropped[self.monitor])
                or abs(self.displacement()[0]) >= self.settings.stop_displacement_m
                or (give_up is not None and give_up())
            )

        while True:
            chunk = min(chunk_cycles or self.settings.chunk_cycles, solver.max_cycles - done)
            result = self.sim.cycle_to_equilibrium(gravity=gravity, max_cycles=chunk, stop=stop)
            done += result.cycles
            dropped = self._dropped()
            lost = self._fallen(dropped)
            if lost.size:
                self.lost += [(self.model.block_name[b], theta_deg) for b in lost]
                if vertical:
                    return FELL, done
                self.sim.remove_blocks(lost)
            ux, _ = self.displacement()
            if self.on_progress is not None:
                self.on_progress(theta_deg, self.sim.cycles, ux)
            if trace is not None:
                trace.add(lambda: self.frame("past collapse", theta_deg))
            if dropped[self.monitor]:
                if vertical:
                    self.lost.append((self.model.block_name[self.monitor], theta_deg))
                return (FELL if vertical else MONITOR_FELL), done
            if give_up is not None and not result.converged and give_up():
                return GAVE_UP, done
            if result.converged:
                return EQUILIBRIUM, done
            if abs(ux) >= self.settings.stop_displacement_m:
                return (FELL if vertical else STOP_DISPLACEMENT), done
            if done >= solver.max_cycles:
                return MAX_CYCLES, done

    def _dropped(self) -> np.ndarray:
        """(nb,) bool: the block, still in the analysis, has a rigid-body drop beyond its
        lost-drop: its centroid is lower than where it was drawn by more than that plus the
        settlement the joints' elastic closure explains (:mod:`drydem.analysis.support`; looked for only
        when some such block has dropped that far at all)."""
        position = self.sim.state.position
        drop = self.model.block_centroid[:, 2] - position[:, 2]
        if not np.any((drop > self.lost_drop) & self.sim.active):
            return np.zeros(self.model.n_blocks, dtype=bool)
        paths = load_paths(self.sim.contacts, position, matrices(self.sim.state.quaternion))
        return (drop - elastic_settlement(*paths, position[:, 2]) > self.lost_drop) & self.sim.active

    def _fallen(self, dropped: np.ndarray) -> np.ndarray:
        """Blocks still in the analysis (but the monitored one) that ``dropped`` out of the model."""
        fallen = np.flatnonzero(dropped & self.sim.active & self.model.block_movable)
        return fallen[fallen != self.monitor]

    def frame(self, kind: str, theta_deg: float) -> Frame:
        return Frame(kind, theta_deg, self.displacement()[0], self.sim.state.copy(), self.sim.contacts.copy(), self.sim.active.copy())

    def record(self, theta_deg: float, cycles: int) -> Record:
        ux, uz = self.displacement()
        return Record(tilt_deg=theta_deg, ux_m=ux, uz_m=uz, drift=ux / self.height, cycles=cycles)


def tilt_analysis(
    model: Model,
    settings: TiltSettings = TiltSettings(),
    *,
    on_record: Callable[[Record], None] | None = None,
    on_progress: Callable[[float, int, float], None] | None = None,
    on_frame: Callable[[Frame], None] | None = None,
    checkpoint: Path | None = None,
    resume: bool = False,
) -> TiltResult:
    """Run the tilting-table (or multiplier) protocol on ``model`` (see module docstring).

    ``on_record(record)`` is called at every equilibrium state as it is found (to write results
    as the run goes); ``on_progress(theta_deg, cycles_so_far, ux_m)`` every few thousand cycles;
    ``on_frame(frame)`` (a :class:`Frame`) at every equilibrium state and, at the end, for the
    states past collapse: the last step is replayed from the last equilibrium, sampled every
    ``chunk_cycles / FRAME_SAMPLING`` cycles (the result is that of the analysis itself; the
    replay only shows it, and costs nothing unless ``on_frame`` is given).
    With ``checkpoint`` (a path), the run is saved there at every equilibrium state; with
    ``resume`` too, it goes on from that file instead of starting over (ModelError naming the
    settings that differ if it is of another model or protocol), and ``on_record`` is first
    called for the equilibria the checkpoint holds.
    """
    start = time.perf_counter()
    run = _Run(model, settings, on_progress)
    keep_snapshots = settings.adaptive or on_frame is not None
    records: list[Record] = []

    def accept(theta: float, step: float, cycles: int) -> None:
        # the checkpoint last: an interrupt before it is saved redoes this step on --resume,
        # which hands the callbacks this equilibrium again rather than never
        records.append(run.record(theta, cycles))
        run.remember(theta)
        if on_record is not None:
            on_record(records[-1])
        if on_frame is not None:
            on_frame(run.frame("equilibrium", theta))
        if checkpoint is not None:
            save_checkpoint(checkpoint, run.sim.snapshot(), _progress(records, run, theta, step) | {"fingerprint": json.dumps(fingerprint)})

    step = settings.increment_deg * (2**settings.refinements if settings.adaptive else 1)
    fingerprint = _fingerprint(model, settings)
    if resume:
        theta, step = _resume(run, checkpoint, fingerprint, records)
        for record in records if on_record is not None else []:
            on_record(record)
        stable = True
    else:
        initial = run.sim.snapshot() if on_frame is not None else None
        outcome, cycles = run.equilibrate(0.0, vertical=True)
        theta, stable = 0.0, {EQUILIBRIUM: True, MAX_CYCLES: None}.get(outcome, False)
        if stable:
            accept(0.0, step, cycles)
    if not stable:
        ended_by = UNSTABLE_UNDER_GRAVITY if stable is False else NO_EQUILIBRIUM_UNDER_GRAVITY
        last_good, lost_at_good = initial, []
    else:
        last_good, lost_at_good = run.sim.snapshot(), list(run.lost)
        ended_by = MAXIMUM_ANGLE
        while theta + step <= settings.max_angle_deg + 1e-9:
            coarse = settings.adaptive and step > settings.increment_deg * (1 + 1e-9)
            outcome, cycles = run.equilibrate(theta + step, give_up=_trial_limit(run, records, step, settings) if coarse else None)
            if outcome == EQUILIBRIUM:
                theta = round(theta + step, 9)
                accept(theta, step, cycles)
                if keep_snapshots:
                    last_good, lost_at_good = run.sim.snapshot(), list(run.lost)
                continue
            if coarse:
                cycles_run = run.sim.cycles
                run.sim.restore(last_good)
                run.sim.cycles = cycles_run  # the abandoned trial's cycles count: they were run
                run.lost = list(lost_at_good)
                step /= 2
                continue
            ended_by = {MAX_CYCLES: NO_EQUILIBRIUM}.get(outcome, outcome)
            break
    result = TiltResult(
        settings=settings,
        monitored_block=model.block_name[run.monitor],
        wall_height_m=run.height,
        stable_under_gravity=stable,
        last_equilibrium_deg=theta if stable else None,
        collapse_angle_deg=theta if ended_by in (MONITOR_FELL, STOP_DISPLACEMENT) else None,
        records=records,
        lost_blocks=run.lost,
        cycles=run.sim.cycles,
        runtime_s=time.perf_counter() - start,
        collapse_state=run.equilibria[-1][1] if run.equilibria else None,
        final_state=run.sim.state.copy(),
        ended_by=ended_by,
    )
    if on_frame is not None and ended_by not in (MAXIMUM_ANGLE, NO_EQUILIBRIUM_UNDER_GRAVITY):
        run.sim.restore(last_good)
        run.lost = list(lost_at_good)
        trace = _Trace()
        run.equilibrate(0.0 if not stable else theta + step, vertical=not stable,
                        chunk_cycles=max(1, settings.chunk_cycles // FRAME_SAMPLING), trace=trace)
        for frame in trace.frames:
            on_frame(frame)
    return result


def _resume(run: _Run, checkpoint: Path, fingerprint: dict[str, str], records: list[Record]) -> tuple[float, float]:
    """Restore ``run`` and ``records`` from ``checkpoint``; returns the tilt (deg) of its last
    equilibrium and the step (deg) to take next. ModelError if it is of another model or protocol."""
    snapshot, saved = load_checkpoint(checkpoint)
    _check_fingerprint(checkpoint, saved, fingerprint)
    run.sim.restore(snapshot)
    records += [Record(*row[:4], int(row[4])) for row in saved["records"].tolist()]
    run.lost = list(zip(saved["lost_blocks"].tolist(), saved["lost_tilt_deg"].tolist()))
    rest = np.zeros((run.model.n_blocks, 3))
    for th, x, q in zip(saved["previous_theta_deg"], saved["previous_position"], saved["previous_quaternion"]):
        run.remember(float(th), State(x, q, rest.copy(), rest.copy()))
    theta = float(saved["theta_deg"])
    run.remember(theta)
    return theta, float(saved["step_deg"])


def _elastic_closure(model: Model, contacts: SubContacts) -> float:
    """Median over the sprung free blocks of m g / sum(k A), m, with the contacts of the model as
    drawn: how far a block's own weight closes its joints (the predictor's scale)."""
    k_t, _ = contact_stiffness(contacts, model.joint.kn, model.joint.ks, model.n_blocks)
    sprung = model.block_movable & (k_t > 0)
    return float(np.median(model.block_mass[sprung] * G / k_t[sprung])) if sprung.any() else 0.0


def _trial_limit(run: _Run, records: list[Record], step: float, settings: TiltSettings) -> Callable[[], bool]:
    """When to abandon a coarse adaptive trial as failed (it is then halved, as any failure):
    a block fell out during it, or the monitored point has moved more than ``trial_growth``
    times what the last two equilibria predict for this step (at least ``trial_floor_m``).
    A collapse needs only to be recognised here, not followed to the stop displacement; an
    equilibrium wrongly abandoned costs a bisection, not a wrong answer, since the steps of one
    increment are judged by the full criteria."""
    lost_before = len(run.lost)
    ux0 = run.displacement()[0]
    if len(records) >= 2 and records[-1].tilt_deg > records[-2].tilt_deg:
        slope = abs(records[-1].ux_m - records[-2].ux_m) / (records[-1].tilt_deg - records[-2].tilt_deg)
    else:
        slope = 0.0
    limit = max(settings.trial_growth * slope * step, settings.trial_floor_m)
    return lambda: len(run.lost) > lost_before or abs(run.displacement()[0] - ux0) > limit


def _fingerprint(model: Model, settings: TiltSettings) -> dict[str, str]:
    """What a checkpoint must match to be resumed, by name: the model's source, blocks (a hash
    of their geometry, densities and fixities), every parameter of its tables and every tilt
    setting (values as repr strings)."""
    blocks = hashlib.sha1()
    for shape in model.block_shape:
        blocks.update(np.ascontiguousarray(shape.vertices).tobytes())
    blocks.update(model.block_density.tobytes() + model.block_fixed.tobytes())
    items = {"model": model.source, "blocks": f"{model.n_blocks} blocks, geometry {blocks.hexdigest()[:12]}"}
    for table in ("joint", "contacts", "supports", "solver"):
        items |= {f"[{table}] {k}": v for k, v in asdict(getattr(model, table)).items()}
    items |= {f"tilt setting {k}": v for k, v in asdict(settings).items()}
    return {k: repr(v) for k, v in items.items()}


def _check_fingerprint(checkpoint: Path, saved: dict, fingerprint: dict[str, str]) -> None:
    """ModelError naming every setting in which ``checkpoint`` differs from this run."""
    try:
        before = json.loads(str(saved["fingerprint"]))
    except (KeyError, ValueError):
        before = None
    if not isinstance(before, dict):
        raise ModelError(f"{checkpoint}: written by another version of drydem (no settings to compare); start again without --resume")
    differ = [f"{k}: {before.get(k, 'absent')} in the checkpoint, {v} now" for k, v in fingerprint.items() if before.get(k) != v]
    if differ:
        raise ModelError(f"{checkpoint}: the checkpoint is of another model or protocol ({'; '.join(differ)}); not resuming")


def _progress(records: list[Record], run: _Run, theta: float, step: float) -> dict:
    """The protocol's position, for a checkpoint (with the equilibria before the last one, for
    the predictor)."""
    nb = run.model.n_blocks
    previous = run.equilibria[:-1]
    return {
        "previous_theta_deg": np.array([th for th, _ in previous], dtype=float),
        "previous_position": np.array([s.position for _, s in previous]).reshape(-1, nb, 3),
        "previous_quaternion": np.array([s.quaternion for _, s in previous]).reshape(-1, nb, 4),
        "records": np.array([[r.tilt_deg, r.ux_m, r.uz_m, r.drift, r.cycles] for r in records]),
        "lost_blocks": np.array([name for name, _ in run.lost], dtype=str),
        "lost_tilt_deg": np.array([t for _, t in run.lost], dtype=float),
        "theta_deg": theta,
        "step_deg": step,
    }
