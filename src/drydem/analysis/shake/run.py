"""One time history on a shaking table: :func:`shake_analysis`.

Before anything is cycled, a motion only along axes in which every block is held ([supports]
fix_x, fix_y or fix_z: an in-plane wall is held in y) is refused (:func:`check_held_axes`):
that motion would move nothing, and the response reported would be no response to it (a
component along such an axis beside others moves nothing either: a note says so).

Stage 1: the model settles under vertical gravity with the static solver (local damping,
cycled to equilibrium), as the tilting analysis does; a model that cannot stand (a block fell
out while it settled, by the tilting analysis's rule,
:func:`drydem.analysis.support.dropped_out`: a floating block), or reaches no equilibrium
within ``max_cycles``, is not shaken (DrydemError saying which).

Then the timestep of stage 2 is known: a motion it cannot follow (a pulse whose period, or a
record whose duration, spans fewer than STEPS_PER_PERIOD timesteps,
:meth:`~drydem.analysis.shake.motion.GroundMotion.resolution_problem`) is refused there.

Stage 2: the time history. Local damping is off; the contacts get their dashpots (the ratio
given or calibrated to the target restitution, :mod:`drydem.analysis.shake.restitution`) and
Rayleigh damping if asked (:mod:`drydem.engine.damping`). The table's acceleration a_g(t)
enters as the inertial body force -m a_g of the table's frame at every cycle
(:func:`drydem.engine.loop.cycle_loop`): for a rigid table, translating without turning,
this is the same as moving the fixed blocks, and gives the response relative to the table
directly. Mass scaling is off (it would change the dynamics). Each cycle takes the motion's
mean over its velocity step (:meth:`~drydem.analysis.shake.motion.GroundMotion.per_cycle`), so
the table's velocity is exact at every half step; a change of the timestep at a re-detection
ends the chunk, so each cycle's time is exact.

Rows of the history are written every ``output_interval_s`` and at the end; falls are looked
for at each row, so a fall's time is known to within one output interval.

A block has fallen when it turned more than ``fall_rotation_deg`` from its orientation at rest
(overturned), or when its centroid dropped more than ``lost_drop_heights`` of its own heights
below where it rested (it fell out of the model; it is then taken out of the analysis, as in
the tilting analysis). The analysis stops when the monitored block has fallen.
"""

from __future__ import annotations

import math
import time
from dataclasses import replace
from collections.abc import Callable

import numpy as np

from drydem.analysis.shake.motion import DIRECTIONS, STEPS_PER_PERIOD, GroundMotion
from drydem.analysis.shake.restitution import RockingBlock, calibrated_damping_ratio, housner_restitution
from drydem.analysis.shake.settings import DURATION, HOUSNER, MONITOR_FELL, History, ShakeFrame, ShakeResult, ShakeSettings
from drydem.analysis.support import dropped_out, lost_drops, too_soft_joints
from drydem.analysis.tilt.settings import monitor_index
from drydem.engine.damping import Damping
from drydem.engine.simulation import Simulation
from drydem.errors import DrydemError, ModelError
from drydem.model.assembly import Model
from drydem.model.parameters import CALLBACK, InstanceOf, check_arguments
from drydem.model.rotation import rotation_vectors, turn_angles

#: cycles at most whose table accelerations are made at once (2.4 MB): an output interval of
#: 1,000 s (the most allowed) at a microsecond timestep would have asked for an array of 24 GB
GROUND_CHUNK_CYCLES = 100_000


def shake_analysis(
    model: Model, settings: ShakeSettings, *, on_progress: Callable[[float, int, float], None] | None = None,
    on_frame: Callable[[ShakeFrame], None] | None = None, on_note: Callable[[str], None] | None = None,
) -> ShakeResult:
    """The time history of ``model`` under ``settings.motion`` (module docstring).

    ``on_progress(time_s, cycles, rotation_rad)`` and ``on_frame(frame)`` are called at every
    output interval; ``on_note(text)`` before the shaking if the viscous damping shortens the
    timestep more than SLOW_DAMPING_FACTOR-fold (:func:`slow_damping_note`) and if a record is
    sampled finer than the timestep (:meth:`GroundMotion.aliasing_note`). Every argument
    is checked first: ModelError naming each one that is not what it must be (a model,
    settings, None or a function)."""
    check_arguments("shake_analysis", {"model": InstanceOf(Model), "settings": InstanceOf(ShakeSettings), "on_progress": CALLBACK,
                                       "on_frame": CALLBACK, "on_note": CALLBACK},
                    model=model, settings=settings, on_progress=on_progress, on_frame=on_frame, on_note=on_note)
    start = time.perf_counter()
    if model.solver.mass_scaling:
        model = model.replace(solver=replace(model.solver, mass_scaling=False))
    monitor = monitor_index(model, settings.monitor)
    check_held_axes(model, settings.motion)
    check_dashpots(model, settings)
    sim = Simulation(model)
    settle(sim, settings.lost_drop_heights)
    ratio, restitution = damping_ratio(model, monitor, settings)
    undamped_s = sim.timestep
    sim.use_damping(Damping(0.0, ratio, settings.rayleigh_stiffness_s, settings.rayleigh_mass_per_s))
    note = slow_damping_note(undamped_s, sim.timestep, ratio, settings)
    if note is not None and on_note is not None:
        on_note(note)
    unresolved = settings.motion.resolution_problem(sim.timestep)
    if unresolved is not None:
        raise ModelError(f"{model.source}: {unresolved}")
    note = settings.motion.aliasing_note(sim.timestep)
    if note is not None and on_note is not None:
        on_note(note)
    if settings.analysed_s < STEPS_PER_PERIOD * sim.timestep:  # 1e-300 s ran no cycle and reported "no block fell"
        raise ModelError(f"{model.source}: duration_s = {settings.analysed_s:g} s (--duration) spans fewer than {STEPS_PER_PERIOD} "
                         f"timesteps of {sim.timestep:.3g} s (the model's at the start of the shaking): the table would hardly move; "
                         f"give at least {STEPS_PER_PERIOD * sim.timestep:.3g} s")
    if settings.output_interval_s < sim.timestep:  # a row per cycle at most: the history would not be at the interval recorded
        raise ModelError(f"{model.source}: output_interval_s = {settings.output_interval_s:g} s (--output-interval) is shorter than "
                         f"the timestep, {sim.timestep:.3g} s (the model's at the start of the shaking): the history has a row at "
                         f"most every cycle; give at least {sim.timestep:.3g} s")
    shaking = Shaking(sim, monitor, settings)
    shaking.run(on_progress, on_frame)
    return shaking.result(ratio, restitution, time.perf_counter() - start)


#: the shortening of the timestep by the viscous damping past which :func:`shake_analysis` says so
SLOW_DAMPING_FACTOR = 10.0


def slow_damping_note(undamped_s: float, damped_s: float, contact_ratio: float, settings: ShakeSettings) -> str | None:
    """What the viscous damping costs, if it shortens the timestep (from ``undamped_s`` to
    ``damped_s``, s) more than :data:`SLOW_DAMPING_FACTOR`-fold: the cycles the analysed time
    then takes, and the coefficients that did it (the damping ratio at the highest frequency,
    :func:`drydem.engine.damping.timestep_factor`, grows as beta / dt: a Rayleigh stiffness term
    meant for the structure's modes overdamps the joints' stiff one); None otherwise."""
    if damped_s * SLOW_DAMPING_FACTOR >= undamped_s:
        return None
    return (f"the viscous damping shortens the timestep {undamped_s / damped_s:.3g}-fold, to {damped_s:.3g} s: "
            f"{settings.analysed_s / damped_s:.3g} cycles for {settings.analysed_s:g} s (contact_damping_ratio {contact_ratio:.3g}, "
            f"rayleigh_stiffness_s {settings.rayleigh_stiffness_s:g} s, rayleigh_mass_per_s {settings.rayleigh_mass_per_s:g} 1/s; "
            "a stiffness term beta damps the joints' highest frequency at a ratio of about beta / the undamped timestep)")


def check_held_axes(model: Model, motion: GroundMotion, given_by: Callable[[str], str] | None = None) -> list[str]:
    """The components of ``motion`` along an axis in which every block is held ([supports]
    fix_x, fix_y, fix_z), as notes: the table frame's inertial force along it is taken by the
    supports (it acts at each block's centroid, so it turns nothing either), so they move
    nothing (a 3-component record on an in-plane wall: its x and z components are analysed).
    ModelError if every component of ``motion`` is such, and the motion would move nothing,
    silently: as the tilting analysis refuses to load an in-plane model out of its plane
    (:func:`drydem.analysis.tilt.check_loading`). ``given_by(axis)`` names what gave that
    component (a command's option; default: the motion's component)."""
    axes = list(zip(DIRECTIONS, model.supports.mask[:3], motion.peaks_m_s2))
    held = [(axis, peak) for axis, fixed, peak in axes if fixed and peak > 0.0]
    free = [axis for axis, fixed, peak in axes if not fixed and peak > 0.0]
    given = (lambda axis: f"{motion.name}: its {axis} component") if given_by is None else given_by
    if held and not free:
        axis, peak = held[0]
        others = " or ".join(other for other, fixed in zip(DIRECTIONS, model.supports.mask[:3]) if not fixed)
        instead = f"shake it along {others}, or" if others else "or"
        raise ModelError(f"{model.source}: {given(axis)} shakes the model along {axis} (peak {peak:.4g} m/s2), but its blocks are "
                         f"held in {axis} ([supports] fix_{axis} = true): the motion would move nothing; {instead} give it "
                         f"blocks free in {axis} ([supports] fix_{axis} = false)")
    return [f"{given(axis)} (peak {peak:.4g} m/s2) moves nothing: the blocks are held in {axis} ([supports] fix_{axis} = true); "
            f"the motion along {' and '.join(free)} is analysed" for axis, peak in held]


def settle(sim: Simulation, lost_drop_heights: float) -> None:
    """Stage 1: cycle to equilibrium under gravity; DrydemError if a block fell out of the model
    meanwhile (dropped more than ``lost_drop_heights`` of its height,
    :func:`~drydem.analysis.support.dropped_out`: as the tilting analysis's stage 1 says the
    model cannot stand; a block drawn floating, or resting on nothing that holds it) or if there
    is no equilibrium within max_cycles. The shaking starts from rest under gravity: from
    anything else, the response would not be the motion's."""
    model = sim.model
    lost_drop = lost_drops(model, lost_drop_heights)

    def fallen() -> np.ndarray:
        return np.flatnonzero(dropped_out(model, sim.state, sim.contacts, sim.active, lost_drop) & model.block_movable)

    settled = sim.cycle_to_equilibrium(stop=lambda: fallen().size > 0)
    fell = fallen()
    if fell.size:
        names = ", ".join(repr(model.block_name[b]) for b in fell[:10]) + (f" and {fell.size - 10} more" if fell.size > 10 else "")
        soft = too_soft_joints(model, fell)
        raise DrydemError(f"{model.source}: the model cannot stand under its own weight: {names} fell while it settled under "
                          f"gravity (dropped more than {lost_drop_heights:g} of its heights below where it is drawn, beyond its joints' "
                          f"elastic settlement; {soft + '; ' if soft else ''}drydem check names the blocks that touch nothing): the "
                          "shaking starts from rest, so it was not run")
    if not settled.converged:
        raise DrydemError(f"{model.source}: no equilibrium under gravity within {settled.cycles} cycles: the shaking starts "
                          "from rest, so it was not run (raise [solver] max_cycles)")


def check_dashpots(model: Model, settings: ShakeSettings) -> None:
    """ModelError if ``settings`` give contact dashpots (a damping ratio other than 0, the
    default's 0.5 included, or one calibrated to a restitution; Rayleigh's stiffness term) to a
    model whose joints are stress-dependent, which takes none yet (the engine refuses them:
    :class:`~drydem.engine.simulation.Simulation`), saying how to run it (found by a hunt:
    the engine's message, after the settling, named neither the default nor the options)."""
    if not model.joint.stress_dependent:
        return
    ratio = settings.damping_ratio
    if ratio == 0 and settings.rayleigh_stiffness_s == 0:
        return
    given = ("calibrated to the restitution (--restitution)" if ratio is None else
             f"{ratio:g}" + (" (the default)" if settings.contact_damping_ratio is None else " (--damping-ratio)"))
    raise ModelError(f"{model.source}: its joints follow the {model.joint.model} law, whose stiffness follows the stress, and "
                     f"contact dashpots are sized for a constant kn: the contacts' damping ratio is {given}"
                     + (f" and Rayleigh's stiffness term {settings.rayleigh_stiffness_s:g} s" if settings.rayleigh_stiffness_s else "")
                     + "; give --damping-ratio 0 (contact_damping_ratio = 0) and no --rayleigh-stiffness (Rayleigh's mass term, "
                     "--rayleigh-mass, may damp the motion)")


def damping_ratio(model: Model, monitor: int, settings: ShakeSettings) -> tuple[float, float | None]:
    """The contacts' damping ratio zeta and the restitution it was calibrated to (None when zeta is set)."""
    if settings.damping_ratio is not None:
        return float(settings.damping_ratio) + 0.0, None  # + 0.0: a given -0.0 is reported as 0
    direction = settings.motion.main_direction
    target = housner_target(model, monitor, direction) if settings.restitution == HOUSNER else settings.restitution
    return calibrated_damping_ratio(model, monitor, target, direction), target


def housner_target(model: Model, monitor: int, direction: int) -> float:
    """Housner's restitution of the monitored block rocking along ``direction`` (0: x, 1: y:
    the motion's :attr:`~drydem.analysis.shake.motion.GroundMotion.main_direction`); DrydemError
    if the block is too squat to rock (r = 1 - 1.5 sin^2(alpha) <= 0: alpha >= 54.7 deg), with
    what to give instead."""
    alpha = RockingBlock.of(model, monitor, direction).alpha_rad
    target = housner_restitution(alpha)
    if target <= 0.0:
        raise DrydemError(
            f"{model.source}: the monitored block {model.block_name[monitor]!r} is too squat for Housner's restitution: alpha = "
            f"atan(b / h) = {math.degrees(alpha):.1f} deg gives 1 - 1.5 sin^2(alpha) = {target:.2f} (it rocks only below "
            "54.7 deg); set the contact damping directly with --damping-ratio Z (contact_damping_ratio), or monitor a slender block"
        )
    return target


class Shaking:
    """Stage 2 as it runs: the Simulation at rest under gravity, the monitored block, the rest
    state the response is measured from, the motion's main direction (the rotation across it is
    recorded), the history's rows and the blocks fallen so far."""

    def __init__(self, sim: Simulation, monitor: int, settings: ShakeSettings):
        self.sim, self.monitor, self.settings = sim, monitor, settings
        self.rest = sim.state.copy()
        self.start_cycles = sim.cycles
        self.timestep = sim.timestep
        self.lost_drop = lost_drops(sim.model, settings.lost_drop_heights)
        self.fall_rotation = np.radians(settings.fall_rotation_deg)
        self.fallen: list[tuple[str, float, str]] = []
        self.ended_by = DURATION
        self.start_s = sim.time_s
        self.direction = settings.motion.main_direction  # once: it takes the record's peaks
        self.rows: list[tuple[float, np.ndarray, np.ndarray, float, float]] = []
        self._record()

    def run(self, on_progress, on_frame) -> None:
        """Cycle to the analysed time, one output interval at a time; the end is always a row."""
        settings, sim = self.settings, self.sim
        self._report(on_progress, on_frame)
        end = settings.analysed_s
        next_output = settings.output_interval_s
        while self.time_s < end - 0.5 * sim.timestep:
            dt = sim.timestep
            cycles = min(max(1, int(round((min(next_output, end) - self.time_s) / dt))), GROUND_CHUNK_CYCLES)
            ground = settings.motion.per_cycle(dt, cycles, self.time_s, first_step_s=sim.velocity_step_s)
            sim.cycle(cycles, ground_acceleration=ground, stop=lambda: sim.timestep != dt)
            if self.time_s < min(next_output, end) - 0.5 * dt:
                continue
            next_output += settings.output_interval_s
            self._record()
            self._report(on_progress, on_frame)
            if self._falls():
                self.ended_by = MONITOR_FELL
                return

    @property
    def time_s(self) -> float:
        """Model time since the shaking started, s."""
        return self.sim.time_s - self.start_s

    def _report(self, on_progress, on_frame) -> None:
        """Hand the last row to ``on_progress`` and ``on_frame``."""
        sim = self.sim
        time_s, ground, moved, across, _ = self.rows[-1]
        if on_progress is not None:
            on_progress(self.time_s, sim.cycles - self.start_cycles, across)
        if on_frame is not None:
            on_frame(ShakeFrame(time_s, ground, moved, across, sim.state.copy(), sim.contacts.copy(), sim.active.copy()))

    def _record(self) -> None:
        """A row of the history: time, the table's acceleration then, the monitored block's
        displacement, its rotation across the motion (:class:`History` ``rotation_rad``) and the
        whole angle it turned from rest, about any axis."""
        b = self.monitor
        moved = self.sim.state.position[b] - self.rest.position[b]
        turned = rotation_vectors(self.rest.quaternion[b:b + 1], self.sim.state.quaternion[b:b + 1])[0]
        across = turned[1] if self.direction == 0 else -turned[0]
        ground = self.settings.motion.acceleration_at(self.time_s)
        self.rows.append((self.time_s, ground, moved, float(across), float(np.linalg.norm(turned))))

    def _falls(self) -> bool:
        """Note the blocks that fell since the last look, take out those that dropped out of the
        model; whether the monitored block fell."""
        sim, model = self.sim, self.sim.model
        named = {name for name, _, _ in self.fallen}
        turned = turn_angles(self.rest.quaternion, sim.state.quaternion) > self.fall_rotation
        dropped = self.rest.position[:, 2] - sim.state.position[:, 2] > self.lost_drop
        candidates = model.block_movable & sim.active
        for rule, hit in ((f"turned more than {self.settings.fall_rotation_deg:g} deg", turned), ("dropped out of the model", dropped)):
            self.fallen += [(model.block_name[b], self.time_s, rule) for b in np.flatnonzero(hit & candidates) if model.block_name[b] not in named]
            named |= {model.block_name[b] for b in np.flatnonzero(hit & candidates)}
        out = np.flatnonzero(dropped & candidates)
        if self.monitor in out or turned[self.monitor]:
            return True
        if out.size:
            sim.remove_blocks(out)
        return False

    def result(self, ratio: float, restitution: float | None, runtime_s: float) -> ShakeResult:
        """The :class:`ShakeResult` of the history run."""
        times, ground, moved, turn, angle = (np.array(column) for column in zip(*self.rows))
        history = History(times, ground, moved[:, 0], moved[:, 1], moved[:, 2], turn, ("y", "-x")[self.direction])
        horizontal = np.hypot(history.ux_m, history.uy_m)
        return ShakeResult(
            settings=self.settings, monitored_block=self.sim.model.block_name[self.monitor], overturned=bool(self.fallen),
            fallen_blocks=list(self.fallen), max_rotation_rad=float(angle.max()), max_displacement_m=float(horizontal.max()),
            residual_displacement_m=float(horizontal[-1]), duration_s=float(self.time_s), cycles=self.sim.cycles - self.start_cycles,
            runtime_s=runtime_s, contact_damping_ratio=ratio, restitution=restitution, timestep_s=self.timestep,
            ended_by=self.ended_by, history=history, final_state=self.sim.state.copy(),
        )
