"""The protocol of :mod:`drydem.analysis.tilt`, stage by stage: stage 1 under vertical gravity
(:func:`stand_under_gravity`) or a resume from a checkpoint (:meth:`TiltProtocol.resume`),
stage 2's steps with the adaptive bisection (:func:`step_up`), the result
(:func:`tilt_result`) and the replay past collapse for the frames (:func:`replay_collapse`);
:func:`tilt_analysis` runs them in turn. :class:`TiltProtocol` is where the protocol stands
and what it does with each equilibrium."""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from drydem.analysis.tilt import checkpointing
from drydem.analysis.tilt.run import Saved, TiltRun, Trace, trial_limit
from drydem.analysis.tilt.settings import (
    DIVERGED, EQUILIBRIUM, MAX_CYCLES, MAXIMUM_ANGLE, MONITOR_FELL, MONITOR_TOPPLED, NO_EQUILIBRIUM, NO_EQUILIBRIUM_UNDER_GRAVITY,
    STOP_DISPLACEMENT, UNSTABLE_UNDER_GRAVITY, Frame, Record, TiltResult, TiltSettings,
)
from drydem.errors import DivergenceError
from drydem.model.assembly import Model
from drydem.model.parameters import CALLBACK, FILE_PATH, FLAG, InstanceOf, Range, argument_problems, refuse

#: states past collapse are sampled this many times per chunk_cycles (drydem tilt --vtk)
FRAME_SAMPLING = 10
#: s of run between two checkpoints: an equilibrium is saved if the last save is this old (the
#: first always). Saving every step took a quarter of a one-block tilt's 4 s; a kill now costs
#: at most this much work again
CHECKPOINT_EVERY_S = 5.0


#: s between two checkpoints: 0 saves at every equilibrium
CHECKPOINT_EVERY = Range(0.0, None, unit="s")
#: the rule of each argument of :func:`tilt_analysis` (``checkpoint`` may also be None)
ARGUMENT_RULES = {"model": InstanceOf(Model), "settings": InstanceOf(TiltSettings), "on_record": CALLBACK,
                  "on_progress": CALLBACK, "on_frame": CALLBACK, "checkpoint": FILE_PATH,
                  "checkpoint_every_s": CHECKPOINT_EVERY, "resume": FLAG}


@dataclass
class TiltProtocol:
    """Where the protocol stands and what it does with each equilibrium it finds.

    ``theta``: the tilt of the last equilibrium (deg); ``step``: the step to take next (deg);
    ``records``: the equilibria found. Each equilibrium is handed to ``on_record`` and
    ``on_frame`` as it is found, saved to ``checkpoint`` (with ``fingerprint``,
    :mod:`~drydem.analysis.tilt.checkpointing`) when the last save is ``checkpoint_every_s``
    old (time.monotonic() of the last: ``saved_at``) and, where it may be gone back to
    (adaptive steps, or frames to replay), kept as ``last_good`` (:meth:`TiltRun.save`).
    ``started_at``: time.perf_counter() when the analysis started; ``runtime_before_s``: the
    runtime a resumed checkpoint had reached (:meth:`runtime_s`)."""

    run: TiltRun
    step: float
    fingerprint: dict[str, str]
    on_record: Callable[[Record], None] | None = None
    on_frame: Callable[[Frame], None] | None = None
    checkpoint: Path | None = None
    checkpoint_every_s: float = CHECKPOINT_EVERY_S
    saved_at: float = -math.inf
    started_at: float = field(default_factory=time.perf_counter)
    runtime_before_s: float = 0.0
    theta: float = 0.0
    records: list[Record] = field(default_factory=list)
    last_good: Saved | None = None

    def accept(self, theta: float, cycles: int) -> None:
        """The run is in equilibrium at ``theta`` (deg), found in ``cycles``."""
        # the checkpoint after the callbacks: an interrupt before it is saved redoes this step
        # on --resume, which hands the callbacks this equilibrium again rather than never
        self.theta = theta
        self.records.append(self.run.record(theta, cycles, self.records[0].ux_m if self.records else None))
        self.run.remember(theta)
        if self.on_record is not None:
            self.on_record(self.records[-1])
        if self.on_frame is not None:
            self.on_frame(self.run.frame("equilibrium", theta))
        if self.checkpoint is not None and time.monotonic() - self.saved_at >= self.checkpoint_every_s:
            checkpointing.save(self.checkpoint, self.run, self.records, theta, self.step, self.fingerprint, self.runtime_s())
            self.saved_at = time.monotonic()
        self.keep()

    def runtime_s(self) -> float:
        """s of analysis: this call's so far, plus what a resumed checkpoint had reached (found by a
        hunt: a resumed run reported only its own part; the time between that checkpoint and the
        interruption is redone, and counted once)."""
        return self.runtime_before_s + time.perf_counter() - self.started_at

    def keep(self) -> None:
        """Keep the run's state as ``last_good`` if it may be gone back to."""
        if self.run.settings.adaptive or self.on_frame is not None:
            self.last_good = self.run.save()

    def undo_trial(self) -> None:
        """A coarse trial failed: back to the last equilibrium, with half the step. The
        abandoned trial's cycles still count: they were run."""
        cycles_run = self.run.sim.cycles
        self.run.restore(self.last_good)
        self.run.sim.cycles = cycles_run
        self.step /= 2

    def resume(self) -> None:
        """Go on from ``checkpoint`` (:func:`~drydem.analysis.tilt.checkpointing.resume`),
        handing ``on_record`` the equilibria it holds."""
        self.theta, self.step, self.runtime_before_s = checkpointing.resume(self.run, self.checkpoint, self.fingerprint, self.records)
        if self.on_record is not None:
            for record in self.records:
                self.on_record(record)
        self.keep()


def stand_under_gravity(protocol: TiltProtocol) -> bool | None:
    """Stage 1: vertical gravity in one step, cycled to equilibrium (accepted at 0 deg). Returns
    whether the model stands under its own weight: True, False (a block fell or the monitored
    point moved the stop displacement) or None (no equilibrium within max_cycles: not known)."""
    protocol.keep()  # a model that cannot stand is replayed from as drawn
    outcome, cycles = protocol.run.equilibrate(0.0, vertical=True)
    stable = {EQUILIBRIUM: True, MAX_CYCLES: None}.get(outcome, False)
    if stable:
        protocol.accept(0.0, cycles)
    return stable


def step_up(protocol: TiltProtocol) -> str:
    """Stage 2: tilt by ``protocol.step`` and cycle to equilibrium, step after step, up to the
    maximum angle; a failed coarse adaptive trial (given up early by
    :func:`~drydem.analysis.tilt.run.trial_limit`, or diverged) is undone and halved, and so is a coarse
    step that would pass the maximum angle (the angles below it are tried in increments, as
    anywhere else). Returns why it ended (TiltResult.ended_by)."""
    run, settings = protocol.run, protocol.run.settings
    while True:
        coarse = settings.adaptive and protocol.step > settings.increment_deg * (1 + 1e-9)
        if protocol.theta + protocol.step > settings.max_angle_deg + 1e-9:
            if not coarse:
                return MAXIMUM_ANGLE
            protocol.step /= 2
            continue
        give_up = trial_limit(run, protocol.records, protocol.step, settings) if coarse else None
        try:
            outcome, cycles = run.equilibrate(protocol.theta + protocol.step, give_up=give_up)
        except DivergenceError:
            outcome = DIVERGED
        if outcome == EQUILIBRIUM:
            protocol.accept(round(protocol.theta + protocol.step, 9), cycles)
        elif coarse:
            protocol.undo_trial()
        else:
            return {MAX_CYCLES: NO_EQUILIBRIUM}.get(outcome, outcome)


def tilt_result(protocol: TiltProtocol, stable: bool | None, ended_by: str, runtime_s: float) -> TiltResult:
    """The :class:`TiltResult` of the protocol as it ended."""
    run = protocol.run
    return TiltResult(
        settings=run.settings,
        monitored_block=run.model.block_name[run.monitor],
        wall_height_m=run.height,
        stable_under_gravity=stable,
        last_equilibrium_deg=protocol.theta if stable else None,
        collapse_angle_deg=protocol.theta if ended_by in (MONITOR_FELL, MONITOR_TOPPLED, STOP_DISPLACEMENT) else None,
        records=protocol.records,
        # a diverged step's falls are no more a result than its state
        lost_blocks=[lost for lost in run.lost if lost[1] <= protocol.theta + 1e-9] if ended_by == DIVERGED else run.lost,
        cycles=run.sim.cycles,
        runtime_s=runtime_s,
        collapse_state=run.equilibria[-1][1] if run.equilibria else None,
        final_state=run.equilibria[-1][1].copy() if ended_by == DIVERGED else run.sim.state.copy(),
        ended_by=ended_by,
    )


def replay_collapse(run: TiltRun, saved: Saved, theta_deg: float, *, vertical: bool = False) -> list[Frame]:
    """The frames past collapse: the step to ``theta_deg`` (stage 1 with ``vertical``) cycled
    again from ``saved``, the last equilibrium (or the model as drawn), a frame every
    ``chunk_cycles / FRAME_SAMPLING`` cycles (:class:`~drydem.analysis.tilt.run.Trace`); the
    frames up to a divergence, should the replay diverge (the result is the analysis's)."""
    run.restore(saved)
    trace = Trace()
    try:
        run.equilibrate(theta_deg, vertical=vertical, chunk_cycles=max(1, run.settings.chunk_cycles // FRAME_SAMPLING), trace=trace)
    except DivergenceError:
        pass
    return trace.frames


def tilt_analysis(
    model: Model,
    settings: TiltSettings = TiltSettings(),
    *,
    on_record: Callable[[Record], None] | None = None,
    on_progress: Callable[[float, int, float], None] | None = None,
    on_frame: Callable[[Frame], None] | None = None,
    checkpoint: str | Path | None = None,
    checkpoint_every_s: float = CHECKPOINT_EVERY_S,
    resume: bool = False,
) -> TiltResult:
    """Run the tilting-table (or multiplier) protocol on ``model`` (see :mod:`drydem.analysis.tilt`).

    ``on_record(record)`` is called at every equilibrium state as it is found (to write results
    as the run goes); ``on_progress(theta_deg, cycles_so_far, ux_m)`` every few thousand cycles;
    ``on_frame(frame)`` (a :class:`Frame`) at every equilibrium state and, at the end, for the
    states past collapse: the last step is replayed from the last equilibrium, sampled every
    ``chunk_cycles / FRAME_SAMPLING`` cycles (the result is that of the analysis itself; the
    replay only shows it, and costs nothing unless ``on_frame`` is given).
    With ``checkpoint`` (a path), the run is saved there at an equilibrium state at least every
    ``checkpoint_every_s`` s of run (the first at once; 0: at every one); with
    ``resume`` too, it goes on from that file instead of starting over (ModelError naming the
    settings that differ if it is of another model or protocol), and ``on_record`` is first
    called for the equilibria the checkpoint holds.
    Every argument is checked before the work (:data:`ARGUMENT_RULES`): ModelError naming each
    one that breaks its rule (a callback that is no function, a checkpoint that is no path, a
    resume without a checkpoint).
    """
    problems = argument_problems("tilt_analysis", ARGUMENT_RULES, optional=("checkpoint",), model=model, settings=settings,
                                 on_record=on_record, on_progress=on_progress, on_frame=on_frame, checkpoint=checkpoint,
                                 checkpoint_every_s=checkpoint_every_s, resume=resume)
    if resume in FLAG and resume and checkpoint is None:
        problems.append("tilt_analysis resume = True needs a checkpoint (the file to go on from)")
    refuse(problems)
    checkpoint = None if checkpoint is None else Path(checkpoint)
    start = time.perf_counter()
    run = TiltRun(model, settings, on_progress)
    fingerprint = checkpointing.fingerprint(model, settings)
    protocol = TiltProtocol(run, settings.first_step(), fingerprint, on_record, on_frame, checkpoint, checkpoint_every_s,
                            started_at=start)
    if resume:
        protocol.resume()
        stable = True
    else:
        stable = stand_under_gravity(protocol)
    if stable:
        ended_by = step_up(protocol)
    else:
        ended_by = UNSTABLE_UNDER_GRAVITY if stable is False else NO_EQUILIBRIUM_UNDER_GRAVITY
    result = tilt_result(protocol, stable, ended_by, protocol.runtime_s())
    if on_frame is not None and ended_by not in (MAXIMUM_ANGLE, NO_EQUILIBRIUM_UNDER_GRAVITY, DIVERGED):
        theta = protocol.theta + protocol.step if stable else 0.0
        for frame in replay_collapse(run, protocol.last_good, theta, vertical=not stable):
            on_frame(frame)
    return result
