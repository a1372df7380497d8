"""One tilting analysis as it cycles (:class:`TiltRun`): a step cycled to equilibrium or to a
collapse, the predictor that starts each step, the blocks that fall out; and when a coarse
adaptive trial is abandoned (:func:`trial_limit`)."""

from __future__ import annotations

from collections.abc import Callable
from functools import partial

import numpy as np

from drydem.analysis.support import dropped_out, lost_drops
from drydem.analysis.tilt.settings import (
    EQUILIBRIUM, FELL, GAVE_UP, MAX_CYCLES, MONITOR_FELL, MONITOR_TOPPLED, STOP_DISPLACEMENT, TOPPLED_RAD, Frame, Record,
    TiltSettings, check_loading, monitor_index, wall_height,
)
from drydem.engine.contacts import SubContacts
from drydem.engine.inertia import contact_stiffness, stiffness_bound
from drydem.engine.joints import kernel_joint
from drydem.engine.simulation import Simulation, Snapshot
from drydem.model.assembly import Model
from drydem.model.parameters import G
from drydem.model.rotation import rotation_vectors, turns_from_drawn
from drydem.model.state import State

#: what :meth:`TiltRun.restore` goes back to: the simulation and the blocks lost by then
Saved = tuple[Snapshot, list[tuple[str, float]]]


class Trace:
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


class TiltRun:
    """One analysis as it cycles. Keeps the model, the settings and ``on_progress``; the
    Simulation (``sim``); the monitored block (``monitor``) and the wall height (``height``,
    the drift's denominator); the blocks taken out of the analysis (``lost``: name and tilt)
    and the drop past which a block is out (``lost_drop``, m); and for the predictor, the last
    three equilibria (``equilibria``), the trends between them (``trends``) and the joints'
    ``elastic_closure`` (m, :func:`elastic_closure`)."""

    def __init__(self, model: Model, settings: TiltSettings, on_progress: Callable[[float, int, float], None] | None):
        self.model, self.settings, self.on_progress = model, settings, on_progress
        check_loading(model, settings)
        self.sim = Simulation(model)
        self.monitor = monitor_index(model, settings.monitor, settings.tilt_axis)
        self.height = wall_height(model)
        self.lost: list[tuple[str, float]] = []
        self.lost_drop = lost_drops(model, settings.lost_drop_heights)
        #: the last three equilibria, (tilt in deg, State), oldest first, and the trends
        #: (displacement m/deg, rotation rad/deg, largest point motion m/deg) between them
        self.equilibria: list[tuple[float, State]] = []
        self.trends: list[tuple[np.ndarray, np.ndarray, float]] = []
        self.elastic_closure = elastic_closure(model, self.sim.contacts)

    def remember(self, theta_deg: float, state: State | None = None) -> None:
        """``state`` (default: the current one) is an equilibrium at ``theta_deg``."""
        state = self.sim.state.copy() if state is None else state
        if self.equilibria:
            self.trends = [*self.trends[-1:], self._trend(*self.equilibria[-1], theta_deg, state)]
        self.equilibria = [*self.equilibria[-2:], (theta_deg, state)]

    def predict(self, theta_deg: float) -> None:
        """Move the blocks (at the last equilibrium) along the trend of the last two equilibria,
        extrapolated linearly in the tilt to ``theta_deg``, if that trend is elastic; capped
        (:mod:`drydem.analysis.tilt`)."""
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
        """The monitored block's displacement from where it was drawn, m: along the load
        direction (x, or y when tilting about x; :attr:`TiltSettings.load_direction`) and z."""
        moved = self.sim.state.position[self.monitor] - self.model.block_centroid[self.monitor]
        return float(moved[self.settings.load_direction]), float(moved[2])

    def save(self) -> Saved:
        """What :meth:`restore` goes back to: the simulation's snapshot and the blocks lost so far."""
        return self.sim.snapshot(), list(self.lost)

    def restore(self, saved: Saved) -> None:
        """Go back to ``saved`` (:meth:`save`), the count of cycles run included."""
        snapshot, lost = saved
        self.sim.restore(snapshot)
        self.lost = list(lost)

    def equilibrate(self, theta_deg: float, *, vertical: bool = False, chunk_cycles: int | None = None,
                    trace: Trace | None = None, give_up: Callable[[], bool] | None = None) -> tuple[str, int]:
        """Cycle at ``theta_deg`` until equilibrium, the stop displacement, the fall or toppling
        of the monitored block, ``give_up()`` or max cycles; returns how it ended (EQUILIBRIUM,
        STOP_DISPLACEMENT, MONITOR_FELL, MONITOR_TOPPLED, GAVE_UP, MAX_CYCLES, or FELL under
        vertical gravity) and the cycles run. Progress is reported and a frame added to
        ``trace`` every ``chunk_cycles`` (default the settings').

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
        max_cycles = self.model.solver.max_cycles
        stop = partial(self._stop, give_up)
        done = 0
        while True:
            chunk = min(chunk_cycles or self.settings.chunk_cycles, max_cycles - done)
            result = self.sim.cycle_to_equilibrium(gravity=gravity, max_cycles=chunk, stop=stop)
            done += result.cycles
            ended = self._chunk_ended(theta_deg, result.converged, vertical, trace, give_up)
            if ended is not None:
                return ended, done
            if done >= max_cycles:
                return MAX_CYCLES, done

    def _stop(self, give_up: Callable[[], bool] | None) -> bool:
        """Whether to stop cycling the chunk early: a block fell out, the monitored one
        included, the monitored block toppled, its point moved the stop displacement, or ``give_up()``."""
        dropped = self._dropped()
        return (
            self._fallen(dropped).size > 0
            or bool(dropped[self.monitor])
            or self.toppled()
            or abs(self.displacement()[0]) >= self.settings.stop_displacement_m
            or (give_up is not None and give_up())
        )

    def _chunk_ended(self, theta_deg: float, converged: bool, vertical: bool, trace: Trace | None,
                     give_up: Callable[[], bool] | None) -> str | None:
        """After a chunk of :meth:`equilibrate`: take out the blocks that fell, report progress,
        add to ``trace``; how the call ended, or None if it goes on."""
        dropped = self._dropped()
        lost = self._fallen(dropped)
        if lost.size:
            self.lost += [(self.model.block_name[b], theta_deg) for b in lost]
            if vertical:
                return FELL
            self.sim.remove_blocks(lost)
        ux, _ = self.displacement()
        if self.on_progress is not None:
            self.on_progress(theta_deg, self.sim.cycles, ux)
        if trace is not None:
            trace.add(lambda: self.frame("past collapse", theta_deg))
        if dropped[self.monitor]:
            if vertical:
                self.lost.append((self.model.block_name[self.monitor], theta_deg))
            return FELL if vertical else MONITOR_FELL
        if give_up is not None and not converged and give_up():
            return GAVE_UP
        if self.toppled():
            return FELL if vertical else MONITOR_TOPPLED
        if abs(ux) >= self.settings.stop_displacement_m:  # at rest there or not: it went on to the maximum angle, or
            return FELL if vertical else STOP_DISPLACEMENT  # stood in stage 1 and "collapsed" at the first step
        return EQUILIBRIUM if converged else None

    def toppled(self) -> bool:
        """Whether the monitored block has turned more than :data:`TOPPLED_RAD` from where it
        was drawn (:func:`~drydem.model.rotation.turns_from_drawn`)."""
        return bool(turns_from_drawn(self.sim.state.quaternion[self.monitor:self.monitor + 1])[0] > TOPPLED_RAD)

    def _dropped(self) -> np.ndarray:
        """(nb,) bool: the block, still in the analysis, has a rigid-body drop beyond its
        lost-drop: its centroid is lower than where it was drawn by more than that plus the
        settlement the joints' elastic closure explains (:func:`drydem.analysis.support.dropped_out`)."""
        return dropped_out(self.model, self.sim.state, self.sim.contacts, self.sim.active, self.lost_drop)

    def _fallen(self, dropped: np.ndarray) -> np.ndarray:
        """Blocks still in the analysis (but the monitored one) that ``dropped`` out of the model."""
        fallen = np.flatnonzero(dropped & self.sim.active & self.model.block_movable)
        return fallen[fallen != self.monitor]

    def frame(self, kind: str, theta_deg: float) -> Frame:
        """The current state as a :class:`Frame` of ``kind`` at ``theta_deg``."""
        return Frame(kind, theta_deg, self.displacement()[0], self.sim.state.copy(), self.sim.contacts.copy(), self.sim.active.copy())

    def record(self, theta_deg: float, cycles: int, settled_ux_m: float | None) -> Record:
        """The current state as the :class:`Record` of an equilibrium at ``theta_deg``, its drift
        measured from ``settled_ux_m`` (m), the monitored displacement at the equilibrium under
        the model's own weight (None: this is that equilibrium, of drift 0)."""
        ux, uz = self.displacement()
        drift = (ux - (ux if settled_ux_m is None else settled_ux_m)) / self.height
        return Record(tilt_deg=theta_deg, ux_m=ux, uz_m=uz, drift=drift, cycles=cycles)


def elastic_closure(model: Model, contacts: SubContacts) -> float:
    """Median over the sprung free blocks of m g / sum(k A), m, with the contacts of the model as
    drawn: how far a block's own weight closes its joints (the predictor's scale)."""
    bound = stiffness_bound(kernel_joint(model.joint), contacts, G * float(model.block_mass[model.block_movable].sum()))
    k_t, _ = contact_stiffness(contacts, bound.stiffness, model.n_blocks)
    sprung = model.block_movable & (k_t > 0)
    return float(np.median(model.block_mass[sprung] * G / k_t[sprung])) if sprung.any() else 0.0


def trial_limit(run: TiltRun, records: list[Record], step: float, settings: TiltSettings) -> Callable[[], bool]:
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
