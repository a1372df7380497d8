"""Cycling a model: explicit dynamic relaxation to equilibrium, with contact tracking.

A :class:`Simulation` holds a frozen :class:`~drydem.model.assembly.Model`, the mutable
:class:`~drydem.model.state.State`, a :class:`~drydem.engine.tracker.ContactTracker` (the
contacts, re-detected as the blocks move) and the blocks' constants for the compiled cycle
(:func:`drydem.engine.inertia.timestep_and_blocks`: each detection recomputes the timestep or,
with mass scaling, the fictitious masses at the first timestep).

Equilibrium (3DEC's ``solve``): cycle until

* ``ratio``: max over free blocks of the unbalanced force (or moment / block radius)
  divided by the mean weight of the free blocks is below ``SolverSettings.ratio``, or
* ``velocity``: the fastest block point (|v| + |omega| r) is slower than
  ``SolverSettings.max_velocity`` (the paper's 1e-13 m/s).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from drydem.engine import diagnostics, loop
from drydem.engine.contacts import NeighbourList, SubContacts, closing_motion, snapshot_problem
from drydem.engine.damping import VISCOUS_RULES, Damping
from drydem.engine.inertia import BlockConstants, keep_kinetic_energy, point_speed_m_s, timestep_and_blocks
from drydem.engine.joints import kernel_joint
from drydem.engine.threads import threads_for, using_threads
from drydem.engine.tracker import ContactTracker
from drydem.errors import DivergenceError, ModelError
from drydem.model.assembly import Model
from drydem.model.geometry import MAX_COORDINATE_M, given, real_array
from drydem.model.parameters import (
    CALLBACK, DAMPING, MAX_ACCELERATION_M_S2, MAX_CYCLES, G, InstanceOf, Range, check_arguments, check_fields, shown,
)
from drydem.model.rotation import matrices
from drydem.model.state import QUATERNION_TOLERANCE, STATE_BOUNDS, State, block_array, checked_state

#: "numba": compiled, the planar cycle for in-plane models (drydem.engine.cycle_planar), else the
#: 3D one; "numba-3d": the compiled 3D cycle for every model
ENGINES = ("numba", "numba-3d")
#: a timestep given to a Simulation, s: above 0, and not below a picosecond, which is 50 times
#: below the critical timestep of any model drydem accepts (the stiffest joint, 1e15 Pa/m, under
#: the lightest micrometre block, 1 kg/m3: ~5e-11 s); one above the critical timestep is refused
#: as it is worked out (drydem.engine.inertia.timestep_and_blocks)
TIMESTEP = Range(1e-12, None, unit="s")
#: cycles run by one call of Simulation.cycle: none or more, at most an equilibrium's most
CYCLE_COUNT = Range(0, MAX_CYCLES.high, integer=True)
#: cycles run in one call of the kernel loop between progress reports
CHUNK = 5_000
#: cycles at most in one call of the kernel loop on a shaking table: the divergence test allows
#: for the table's work up to the call's end (Simulation._energy_slack_j), so a call is kept short
#: that the allowance does not run far ahead of the cycles it is tested at
TABLE_CHUNK = 256
#: 1/kg: blocks this heavy keep their velocities through a cycle's forces (Simulation.move)
IMMOVABLE_INVERSE_MASS = 1e-300
#: the ground acceleration of a table at rest (LoopSettings.ground_acceleration)
AT_REST = np.zeros((0, 3))
#: the rule of the scalars of a Snapshot given to Simulation.restore (it may come from a file):
#: cycles run and model time, none or more; the timestep kept by mass scaling (None: none yet),
#: above 0; the divergence test's farthest travel, none or more (each finite)
SNAPSHOT_RULES = {"cycles": Range(0, None, integer=True), "time_s": Range(0.0, None, unit="s"),
                  "scaled_timestep": Range(0.0, None, low_open=True, unit="s"), "farthest_travel_kg_m": Range(0.0, None, unit="kg m"),
                  "timestep": Range(0.0, None, low_open=True, unit="s"), "velocity_step_s": Range(0.0, None, low_open=True, unit="s")}


class StepStats(NamedTuple):
    """What the last cycle measured: unbalanced-force ratio and maximum block point speed (m/s)."""

    ratio: float
    max_speed: float


@dataclass(frozen=True)
class EquilibriumResult:
    """Outcome of :meth:`Simulation.cycle_to_equilibrium`.

    converged : the criterion was met. cycles : cycles run. criterion : "ratio" or "velocity".
    ratio : unbalanced-force ratio at the last cycle. max_speed : m/s, fastest block point at
    the last cycle. detections : contact detections during the call.
    """

    converged: bool
    cycles: int
    criterion: str
    ratio: float
    max_speed: float
    detections: int


@dataclass(frozen=True)
class Snapshot:
    """A saved point of a :class:`Simulation`: state, contacts with their shear history,
    neighbour list, the state at the last broad phase, the blocks still in the analysis, cycles
    run, model time (s), the timestep kept by mass scaling (s), the digest of the blocks it was
    cycled on (:attr:`drydem.model.assembly.Model.blocks_digest`: it restores into their model
    only), the farthest travel so far (kg m, the divergence test's: :meth:`Simulation._travel_kg_m`),
    and the timestep and the next cycle's velocity step (s, :attr:`Simulation.velocity_step_s`;
    None in a checkpoint of an earlier drydem: the timestep then)."""

    state: State
    contacts: SubContacts
    neighbours: NeighbourList
    broad_state: State
    active: np.ndarray
    cycles: int
    time_s: float
    scaled_timestep: float | None
    blocks_digest: str
    farthest_travel_kg_m: float = 0.0
    timestep: float | None = None
    velocity_step_s: float | None = None


class Simulation:
    """A model being cycled, from ``state`` (default: at rest as drawn).

    ``engine`` is one of ENGINES ("numba", the default, is the fastest) or a function with the
    signature of :func:`drydem.engine.cycle3d.run_cycles` (the tests pass the NumPy oracle).
    ``timestep`` (s) overrides the automatic one: a number in :data:`TIMESTEP`, not above the
    critical timestep. ``state`` is checked and copied (:func:`~drydem.model.state.checked_state`:
    float64 arrays of the model's blocks, unit quaternions; an in-plane model cycled by the
    planar kernel turns about y only). Each argument of the wrong kind or value is a ModelError
    naming it.
    ``damping`` (:class:`~drydem.engine.damping.Damping`; default: the model's local damping
    alone, for statics) is what the cycles dissipate energy with; viscous damping shortens the
    timestep (:func:`drydem.engine.damping.timestep_factor`).

    Public arrays: ``state``; ``contacts``, ``neighbours`` and ``active`` (the blocks still in the
    analysis) of the ``tracker``; ``blocks``, the constants the cycle runs with
    (:class:`~drydem.engine.inertia.BlockConstants`); ``timestep`` (s); ``closure_limit`` (ns,) m,
    the sub-contact closures up to which the timestep holds for a stress-dependent joint
    (:func:`~drydem.engine.inertia.stiffness_bound`); ``run_cycles``, the
    cycle function; ``cycles`` run so far and the model time they span, ``time_s`` (the sum of
    their timesteps, s).
    """

    def __init__(self, model: Model, *, state: State | None = None, engine: str | Callable = "numba", timestep: float | None = None,
                 damping: Damping | None = None):
        InstanceOf(Model).check(model, "Simulation model")
        if timestep is not None:
            TIMESTEP.check(timestep, f"{model.source}: Simulation timestep")
        self.model = model
        self.damping = Damping(model.solver.damping) if damping is None else _checked(damping, model)
        self.run_cycles = _cycle_function(model, engine)
        self._planar = _planar(model, engine)
        self.state = State.at_rest(model.block_centroid) if state is None else state
        self.tracker = ContactTracker(model, self.state)
        #: (nb, 3) m: the centroids the cycling started from, the divergence test's origin: a block
        #: released above its base has fallen that far when it lands (:func:`drydem.engine.loop.cycle_loop`)
        self._origin = self.state.position.copy()
        #: kg m: the largest sum m |x - x_origin| over the moving blocks at the end of a call of the
        #: kernel loop, part of the divergence test's allowance (:meth:`_energy_slack_j`)
        self._farthest_travel_kg_m = 0.0
        #: m/s2: the largest g_max of the calls so far, with which the allowance bounds the work done (:meth:`_energy_slack_j`)
        self._largest_g_m_s2 = 0.0
        self.blocks: BlockConstants | None = None
        self.cycles = 0
        self.time_s = 0.0
        #: m/s: the sum over the cycles run with a ground acceleration of |a_g| dt (:meth:`_energy_slack_j`)
        self.table_impulse_m_s = 0.0
        self._fixed_timestep = None if timestep is None else float(timestep)
        self._scaled_timestep: float | None = None
        self._update_inertia()
        #: J: the kinetic and elastic energy of a ``state`` given to start from, part of the
        #: divergence test's allowance (:meth:`_energy_slack_j`): a block given a speed, or
        #: released overlapping another, may turn it into motion without gravity's help. Zero
        #: for the model as drawn: at rest, its overlaps within build_model's 1 % of the contact
        #: tolerance, which the settling allowance covers (no energy pass at every start)
        energy = {"kinetic": 0.0, "elastic": 0.0} if state is None else self.energy(gravity=np.zeros(3))
        self._start_energy_j = energy["kinetic"] + energy["elastic"]

    @property
    def contacts(self) -> SubContacts:
        return self.tracker.contacts

    @property
    def neighbours(self) -> NeighbourList:
        return self.tracker.neighbours

    @property
    def active(self) -> np.ndarray:
        return self.tracker.active

    @property
    def detections(self) -> int:
        return self.tracker.detections

    def detect_contacts(self) -> None:
        """Re-detect every contact at the current state (shear stress carried over)."""
        self.tracker.detect(self.state, everything=True)
        self._update_inertia()

    def _update_inertia(self) -> None:
        """The timestep, block constants and closure limit for the current contacts and their
        stresses; with mass scaling, the velocities keep each block's kinetic energy through the
        change of fictitious masses. When the timestep changes from dt_old to dt (contacts made
        or lost, a stress-dependent joint stiffening), the next cycle's velocities step by
        (dt_old + dt) / 2 (:class:`~drydem.engine.loop.LoopSettings` ``first_velocity_dt``),
        the variable-step leapfrog: the plain step dt would add or remove an impulse of
        force * (dt - dt_old) / 2 at every change: an undamped cube bouncing clear of its base
        lost 6 % of its height a bounce that way, a hexagonal prism rocking on its corners 20 % of
        its drop energy in 1 s (with the mean step: 0.04 % of the height over 11 bounces, 1.8 %)."""
        old = self.timestep if self.blocks is not None else None
        dt, blocks, self.closure_limit = timestep_and_blocks(
            self.model, self.tracker.contacts, self.tracker.active, fixed_timestep=self._fixed_timestep, scaled_timestep=self._scaled_timestep,
            damping=self.damping, origin=self._origin, closing=self._closing(),
            point_speed_m_s=point_speed_m_s(self.state, self.model.block_radius) + self._flight_reach_m_s(),
        )
        if self.model.solver.mass_scaling:
            self._scaled_timestep = dt
            if self.blocks is not None:
                keep_kinetic_energy(self.state, self.blocks, blocks)
        self.timestep, self.blocks = dt, blocks
        self._first_velocity_dt = dt if old is None else 0.5 * (old + dt)

    def _flight_reach_m_s(self) -> float:
        """m/s, what a flying block may gain before the next re-detection, which comes before it
        has moved the tracker's absolute limit d: sqrt(2 g d) (free fall under g = G)."""
        return float(np.sqrt(2.0 * G * self.tracker.absolute_limit))

    def _closing(self) -> tuple[np.ndarray, np.ndarray, float] | None:
        """For a stress-dependent joint, each sub-contact's closure (m) and closing speed (m/s)
        (:func:`drydem.engine.contacts.closing_motion`) and the timestep they were reached with:
        a joint closing fast (an impact) is counted at the stiffness it is about to reach, and
        the timestep resolves its stiffening (:func:`drydem.engine.inertia.stiffness_bound`).
        None for a constant joint or before the first timestep."""
        if not self.model.joint.stress_dependent or self.blocks is None:
            return None
        return (*closing_motion(self.tracker.contacts, self.state, matrices(self.state.quaternion)), self.timestep)

    @property
    def state(self) -> State:
        """The blocks' :class:`~drydem.model.state.State`, which the cycles change in place. One
        assigned is checked and copied (:meth:`fit_state`; found by a hunt: a text assigned was a
        numba TypingError); one changed in place is checked again as each :meth:`cycle` and
        :meth:`cycle_to_equilibrium` starts (a zero quaternion had cycled "to equilibrium")."""
        return self._state

    @state.setter
    def state(self, state: State) -> None:
        self._state = self.fit_state(state)

    def _recheck_state(self, where: str) -> None:
        """ModelError (:meth:`fit_state`'s, naming ``where``) if the state, changed in place since
        it was checked, is no longer one the cycles can run: a value past
        :data:`~drydem.model.state.STATE_BOUNDS` or not finite, a quaternion off unit norm (or, for
        the planar cycle, turned about another axis than y). Looked at on the live arrays, without
        fit_state's copy (found by a review: the copy made the restitution's cycle(10) loop 25 %
        slower); their shapes and dtype cannot change in place."""
        s = self._state
        norm_off = np.abs(np.linalg.norm(s.quaternion, axis=1) - 1.0)
        fine = all(np.abs(getattr(s, name)).max(initial=0.0) <= bound for name, bound in STATE_BOUNDS.items())  # NaN: False
        fine = fine and bool((norm_off <= QUATERNION_TOLERANCE).all())
        if fine and self._planar:
            fine = np.abs(s.quaternion[:, [1, 3]]).max(initial=0.0) <= QUATERNION_TOLERANCE
        if not fine:
            self.fit_state(s, where)

    def fit_state(self, state: State, where: str | None = None) -> State:
        """A checked copy of ``state`` (:func:`~drydem.model.state.checked_state`); for the planar
        kernel, which reads a quaternion as a turn about y (:mod:`drydem.engine.cycle_planar`),
        ModelError for a block turned about another axis. Messages start with ``where``
        (default: the model's source and "Simulation")."""
        where = f"{self.model.source}: Simulation" if where is None else where
        state = checked_state(state, self.model.n_blocks, where)
        if not self._planar:
            return state
        tilted = np.flatnonzero(np.abs(state.quaternion[:, [1, 3]]).max(axis=1) > QUATERNION_TOLERANCE)
        if tilted.size:
            raise ModelError(f"{where} state.quaternion[{tilted[0]}] = {state.quaternion[tilted[0]].tolist()}: the blocks of an in-plane "
                             "model turn about y only, (w, 0, y, 0), in its planar cycle (engine='numba-3d' turns them any way)")
        return state

    def use_damping(self, damping: Damping) -> None:
        """Cycle on with ``damping`` (the timestep follows: dashpots shorten it)."""
        self.damping = _checked(damping, self.model)
        self._update_inertia()

    def remove_blocks(self, blocks) -> None:
        """Take ``blocks`` out of the analysis (e.g. bricks that fell out of the wall): they stop
        moving, lose their contacts and no longer count for equilibrium. ``blocks``: a block's
        name or index, or a list or array of them (:meth:`~drydem.model.assembly.Model.block_indices`)."""
        self.tracker.remove(self.model.block_indices(blocks, "remove_blocks"))
        self.state.velocity[~self.active] = 0.0
        self.state.angular_velocity[~self.active] = 0.0
        self._update_inertia()

    def snapshot(self) -> Snapshot:
        """Everything needed to resume cycling from now (see :meth:`restore`)."""
        t = self.tracker
        return Snapshot(
            state=self.state.copy(), contacts=t.contacts.copy(), neighbours=t.neighbours.copy(), broad_state=t.broad_state.copy(),
            active=t.active.copy(), cycles=self.cycles, time_s=self.time_s, scaled_timestep=self._scaled_timestep,
            blocks_digest=self.model.blocks_digest, farthest_travel_kg_m=self._farthest_travel_kg_m,
            timestep=self.timestep, velocity_step_s=self._first_velocity_dt,
        )

    def restore(self, snapshot: Snapshot) -> None:
        """Go back to a :meth:`snapshot` (its arrays are copied, so it can be restored again;
        its state is checked as :class:`Simulation`'s: a snapshot may come from a file,
        :mod:`drydem.engine.checkpoint`)."""
        InstanceOf(Snapshot).check(snapshot, f"{self.model.source}: Simulation.restore snapshot")
        where = f"{self.model.source}: Simulation.restore: snapshot"
        check_fields(snapshot, SNAPSHOT_RULES, where, optional=("scaled_timestep", "timestep", "velocity_step_s"))
        if snapshot.blocks_digest != self.model.blocks_digest:
            raise ModelError(f"{where} of other blocks (vertices, densities or fixities: digest {str(snapshot.blocks_digest)[:12]!r}, "
                             f"this model's {self.model.blocks_digest[:12]!r}): a snapshot restores into the model it was taken of")
        problem = snapshot_problem(snapshot.contacts, snapshot.neighbours, snapshot.active, self.model.n_blocks)
        if problem is not None:
            raise ModelError(f"{where} {problem}")
        # every part checked before any is taken: a refused snapshot leaves the simulation as it was
        state, broad_state = self.fit_state(snapshot.state), self.fit_state(snapshot.broad_state, f"{where} broad")
        self._state = state
        t = self.tracker
        t.contacts, t.neighbours = snapshot.contacts.copy(), snapshot.neighbours.copy()
        t.broad_state, t.active = broad_state, snapshot.active.copy()
        self.cycles, self.time_s = int(snapshot.cycles), float(snapshot.time_s)
        self._farthest_travel_kg_m = float(snapshot.farthest_travel_kg_m)
        self._scaled_timestep = None if snapshot.scaled_timestep is None else float(snapshot.scaled_timestep)
        self._update_inertia()
        self._first_velocity_dt = _restored_velocity_step(snapshot, self.timestep)

    # -- cycling --------------------------------------------------------------------------
    def move(self, displacement: np.ndarray, rotation: np.ndarray, *, gravity=(0.0, 0.0, -G)) -> None:
        """Move every free block by ``displacement`` (nb, 3) m and the rotation vector ``rotation``
        (nb, 3) rad (world frame) within one cycle, and leave it at rest there.

        The joints follow as in any cycle: the shear springs take the tangential relative
        displacement (Mohr-Coulomb capping them), the normal ones the gaps. The move is a cycle
        with the velocities displacement / dt and rotation / dt in which the blocks are too
        heavy (IMMOVABLE_INVERSE_MASS) for the joint forces to change them. A predictor for the
        next load step (:mod:`drydem.analysis.tilt`): dynamic relaxation then starts near the new
        equilibrium. Fixed degrees of freedom do not move, whatever is asked of them. ModelError
        for a displacement component beyond MAX_COORDINATE_M or a rotation beyond half a turn.
        """
        shape = (self.model.n_blocks, 3)
        where = f"{self.model.source}: move"
        displacement = block_array(displacement, shape, f"{where} displacement")
        rotation = block_array(rotation, shape, f"{where} rotation")
        reach = {"displacement": (np.abs(displacement).max(axis=1), MAX_COORDINATE_M, "m"),
                 "rotation": (np.linalg.norm(rotation, axis=1), np.pi, "rad (half a turn)")}
        for name, (size, bound, unit) in reach.items():  # a brick moved 100 km without a word; 1e300 m was called a divergence
            far = np.flatnonzero(size > bound)
            if far.size:
                raise ModelError(f"{where} {name} of block {self.model.block_name[far[0]]!r}: {size[far[0]]:.3g} {unit.split()[0]}, "
                                 f"beyond {bound:.4g} {unit}, the most a move may be")
        gravity = self._gravity(gravity, "move")
        blocks = self.blocks
        self.state.velocity[:] = displacement * blocks.free[:, :3] / self.timestep
        self.state.angular_velocity[:] = rotation * blocks.free[:, 3:] / self.timestep
        heavy = blocks._replace(
            inv_mass=np.where(blocks.inv_mass > 0, IMMOVABLE_INVERSE_MASS, 0.0), inv_inertia_body=np.zeros_like(blocks.inv_inertia_body)
        )
        # its kinetic energy is not the dynamics', so not a divergence (a NaN still is)
        self._run(gravity, 1, criterion=loop.RATIO, limit=-1.0, criterion_name="none", energy_slack_j=np.inf, blocks=heavy)
        self.state.velocity[:] = 0.0
        self.state.angular_velocity[:] = 0.0

    @property
    def velocity_step_s(self) -> float:
        """s, the velocity step of the next cycle: (dt_old + dt) / 2 right after the timestep
        changed from dt_old (:meth:`_update_inertia`), else the timestep."""
        return self._first_velocity_dt

    def cycle(self, n: int, *, gravity=(0.0, 0.0, -G), ground_acceleration: np.ndarray | None = None,
              stop: Callable[[], bool] | None = None) -> EquilibriumResult:
        """Run ``n`` cycles (re-detecting contacts as needed), no equilibrium test; ``stop()``
        as in :meth:`cycle_to_equilibrium`.

        ``ground_acceleration`` (n, 3) m/s2: the table's acceleration at each of the cycles; the
        blocks then move in the frame of the table (:func:`drydem.engine.loop.cycle_loop`), so
        their positions and velocities are relative to it, each component at most
        :data:`~drydem.model.parameters.MAX_ACCELERATION_M_S2` in magnitude. ModelError for ``n`` not in
        :data:`CYCLE_COUNT`, and for each other argument of the wrong kind (``gravity``:
        :meth:`_gravity`; ``stop``: None or a function)."""
        where = f"{self.model.source}: cycle"
        self._recheck_state(where)
        CYCLE_COUNT.check(n, f"{where} n")
        n = int(n)  # a NumPy integer (np.uint64) does not mix with Python's ints in the slices below
        gravity = self._gravity(gravity, "cycle")
        CALLBACK.check(stop, f"{where} stop")
        if ground_acceleration is not None:
            ground_acceleration = _ground(ground_acceleration, n, f"{where} ground_acceleration")
        return self._run(gravity, n, criterion=loop.RATIO, limit=-1.0, criterion_name="none", ground=ground_acceleration, stop=stop)

    def cycle_to_equilibrium(
        self, *, gravity=(0.0, 0.0, -G), max_cycles: int | None = None, progress: Callable[[int, StepStats], None] | None = None,
        stop: Callable[[], bool] | None = None,
    ) -> EquilibriumResult:
        """Cycle until at rest by the model's criterion (see module docstring), at most
        ``max_cycles`` (default the solver's); non-convergence is returned, not hidden.

        ``progress(cycles, stats)`` is called every few thousand cycles. ``stop()`` is asked
        whenever the compiled loop hands back (at every re-detection, so every few cycles
        while blocks move fast, and at least every CHUNK cycles): True ends the call there,
        unconverged. Raises DivergenceError if the integration blows up; ModelError for an
        argument of the wrong kind (``gravity``: :meth:`_gravity`; ``progress`` and ``stop``:
        None or a function) and when no movable block is left in the analysis.
        """
        solver = self.model.solver
        where = f"{self.model.source}: cycle_to_equilibrium"
        self._recheck_state(where)
        if max_cycles is None:
            max_cycles = solver.max_cycles
        MAX_CYCLES.check(max_cycles, f"{where} max_cycles")
        max_cycles = int(max_cycles)  # a NumPy integer (np.uint64) does not mix with Python's ints in _run
        gravity = self._gravity(gravity, "cycle_to_equilibrium")
        check_arguments(where, {"progress": CALLBACK, "stop": CALLBACK}, progress=progress, stop=stop)
        if not (self.model.block_movable & self.active).any():
            raise ModelError(f"{where}: no movable block is left in the analysis (every block is fixed or taken out by "
                             "remove_blocks): there is nothing to cycle to equilibrium")
        criterion, limit = (loop.RATIO, solver.ratio) if solver.criterion == "ratio" else (loop.VELOCITY, solver.max_velocity)
        return self._run(
            gravity, max_cycles, criterion=criterion, limit=limit, criterion_name=solver.criterion, progress=progress, stop=stop
        )

    def _gravity(self, gravity, method: str) -> np.ndarray:
        """``gravity`` (m/s2) as a float64 (3,) array; ModelError naming ``method`` and gravity
        unless it is three finite real numbers (an array, a list or a tuple: no texts, booleans,
        complex numbers or masked values) of magnitude at most :data:`~drydem.model.parameters.MAX_ACCELERATION_M_S2`."""
        where = f"{self.model.source}: {method} gravity"
        g = real_array(gravity)
        if g is None or g.shape != (3,):
            raise ModelError(f"{where} = {given(gravity)}: must be [gx, gy, gz], three real numbers in m/s2 "
                             "(not texts, booleans, complex numbers or masked values)")
        if not np.isfinite(g).all():
            raise ModelError(f"{where} = {shown(g.tolist())}: must be three finite numbers in m/s2")
        magnitude = math.hypot(*g)  # scaled: np.linalg.norm of 1e300 overflowed to inf, with a RuntimeWarning
        if magnitude > MAX_ACCELERATION_M_S2:
            raise ModelError(f"{where} = {shown(g.tolist())}: its magnitude {magnitude:.9g} m/s2 must be at most "
                             f"{MAX_ACCELERATION_M_S2:g} m/s2 (about 100 g, past any earthquake record or shaking table)")
        return g

    def _run(
        self, gravity: np.ndarray, max_cycles: int, *, criterion: int, limit: float, criterion_name: str, progress=None,
        energy_slack_j: float | None = None, blocks: BlockConstants | None = None, stop: Callable[[], bool] | None = None,
        ground: np.ndarray | None = None,
    ) -> EquilibriumResult:
        m = self.model
        g = gravity  # checked by the caller (_gravity)
        moving = m.block_movable & self.active
        moving_mass = float(m.block_mass[moving].sum())
        weight = float(np.linalg.norm(g)) * moving_mass / max(int(moving.sum()), 1)
        if criterion_name == "ratio" and weight == 0.0:
            raise ModelError(f"{m.source}: the 'ratio' criterion needs gravity (it divides by the mean weight); use 'velocity'")
        joint = kernel_joint(m.joint)
        done, detections = 0, 0
        code, stats = loop.RUNNING, StepStats(np.inf, np.inf)
        while done < max_cycles:
            chunk = min(CHUNK if ground is None else TABLE_CHUNK, max_cycles - done)
            table = AT_REST if ground is None else ground[done:done + chunk]
            slack = self._energy_slack_j(g, table, moving_mass) if energy_slack_j is None else energy_slack_j
            settings = loop.LoopSettings(
                g, self.timestep, self.damping, chunk, criterion, limit, max(weight, 1e-300), slack, self.tracker.absolute_limit,
                table, self.closure_limit, self._first_velocity_dt,
            )
            tracker = self.tracker
            with using_threads(threads_for(tracker.contacts.count)):
                n, code, ratio, speed = self.run_cycles(self.state, blocks or self.blocks, tracker.contacts, joint, settings,
                                                        tracker.broad_state, tracker.neighbours)
            stats = StepStats(ratio, speed)
            self._farthest_travel_kg_m = max(self._farthest_travel_kg_m, self._travel_kg_m(moving))
            self._first_velocity_dt = self.timestep
            self.table_impulse_m_s += float(np.linalg.norm(table[:n], axis=1).sum()) * self.timestep
            done += n
            self.cycles += n
            self.time_s += n * self.timestep
            if progress is not None:
                progress(done, stats)
            if code == loop.DIVERGED:
                supplied = "gravity" if ground is None else "gravity and the table's motion"
                raise DivergenceError(
                    f"{m.source}: the integration diverged after {self.cycles} cycles (more kinetic energy than {supplied} "
                    f"can have supplied; timestep {self.timestep:.3g} s): "
                    "reduce the timestep (solver.timestep_safety) or check the stiffness and masses"
                )
            if code == loop.CONVERGED:
                break
            if code == loop.REDETECT:
                with using_threads(threads_for(self.tracker.contacts.count)):
                    self.tracker.detect(self.state)
                detections += 1
            if code in (loop.REDETECT, loop.STIFFENED):
                self._update_inertia()
            if stop is not None and stop():
                break
        return EquilibriumResult(code == loop.CONVERGED, done, criterion_name, float(stats.ratio), float(stats.max_speed), detections)

    def _travel_kg_m(self, moving: np.ndarray) -> float:
        """kg m: sum m |x - x_origin| over the ``moving`` blocks (nb,) bool. The divergence test
        (:func:`drydem.engine.loop.cycle_loop`) bounds the kinetic energy by the work gravity can
        have done, |g| sum m |x - x_origin|; the test also allows the farthest travel so far, as
        the bound on that work over the past does (:meth:`_energy_slack_j`): without it, a block
        bouncing back up to where it was released, with the few per cent of energy an impact of a
        few cycles gains, has travelled about nothing and was called diverged."""
        m = self.model
        return float(m.block_mass[moving] @ np.linalg.norm(self.state.position[moving] - self._origin[moving], axis=1))

    def _energy_slack_j(self, gravity: np.ndarray, table: np.ndarray, moving_mass: float) -> float:
        """J: what the divergence test (:func:`drydem.engine.loop.cycle_loop`) allows beyond
        DIVERGENCE_FACTOR g_max sum m |x - x0| in a call cycling ``table`` (the table's
        acceleration at each cycle, m/s2; none: (0, 3)), before the same factor: the energy the
        cycling started with (:attr:`_start_energy_j`), g_max times the total mass times the
        contact tolerance (the settling at the start) and times the farthest travel so far
        (:meth:`_travel_kg_m`), and the work of the table.

        The test bounds the kinetic energy by the work of the body forces, g_max sum m |x - x0|:
        true of gravity, which is conservative, but not of the table frame's inertial force
        -m a_g(t), which changes with time: a block that the table threw up (it dropped faster
        than g) lands where it started, with travel 0, and speed. Its work is bounded otherwise.
        With U the energy in the table's frame (kinetic, elastic and gravity's potential),
        dU/dt = -a_g . sum m v - dissipation <= |a_g| sqrt(2 M K) (Cauchy-Schwarz, M the moving
        mass, K the kinetic energy), and K <= U + G*, G* = |g| max over the past of
        sum m |x - x0|; so (Bihari's inequality) sqrt(K) <= sqrt(U0 + G*) + sqrt(M / 2) V with
        V = integral of |a_g| dt, and K <= 2 (U0 + G*) + M V^2. The table's part is M V^2 / 2,
        V summed to the call's end (:attr:`table_impulse_m_s` before it; a call is at most
        TABLE_CHUNK cycles), so the allowance of its work, 10 M V^2 / 2, is 5 times the bound. A
        blow-up grows exponentially and soon passes it (and a NaN is caught at every cycle). The
        work done so far is bounded with the largest g_max of any call (this one and those before:
        the joints keep what an earlier gravity compressed them with; turned off after settling,
        it was released as kinetic energy that this call's g_max, 0, called a divergence)."""
        magnitude = np.linalg.norm(table, axis=1)
        g_max = float(np.linalg.norm(gravity)) + float(magnitude.max(initial=0.0))  # the loop's g_max for this call
        self._largest_g_m_s2 = max(self._largest_g_m_s2, g_max)
        speed = self.table_impulse_m_s + float(magnitude.sum()) * self.timestep
        settling = self.model.total_mass * self.model.contact_tolerance
        return self._start_energy_j + self._largest_g_m_s2 * (settling + self._farthest_travel_kg_m) + 0.5 * moving_mass * speed**2

    # -- diagnostics ----------------------------------------------------------------------
    def energy(self, *, gravity=(0.0, 0.0, -G)) -> dict[str, float]:
        """Kinetic, gravitational and elastic energy, J (:func:`drydem.engine.diagnostics.energies`);
        ``gravity`` as :meth:`cycle` takes it (:meth:`_gravity`). The positions are rewound by
        half their last step, dt_old = 2 velocity_step_s - dt right after a change of timestep."""
        last_step = 2.0 * self._first_velocity_dt - self.timestep
        return diagnostics.energies(self.model, self.state, self.contacts, last_step, self._gravity(gravity, "energy"))

    def reactions(self, block: int) -> np.ndarray:
        """Total contact force (N, world frame) that the other blocks exert on ``block`` (its
        index or name)."""
        return diagnostics.reactions(self.state, self.contacts, self.model.block_number(block, "reactions block"))


def _restored_velocity_step(snapshot: Snapshot, timestep: float) -> float:
    """s, the first velocity step after restoring ``snapshot`` with ``timestep``: its velocities
    were last stepped for dt_v = 2 velocity_step_s - dt_snapshot (dt_snapshot but right after a
    change of timestep), so the variable step is (dt_v + timestep) / 2; ``timestep`` itself for
    a snapshot that does not say (an earlier drydem's checkpoint)."""
    if snapshot.timestep is None or snapshot.velocity_step_s is None:
        return timestep
    return float(snapshot.velocity_step_s) + 0.5 * (timestep - float(snapshot.timestep))


def _checked(damping: Damping, model: Model) -> Damping:
    """``damping`` as floats, or a ModelError naming each coefficient out of its range, or
    refusing dashpots on a stress-dependent joint."""
    if not isinstance(damping, Damping):
        raise ModelError(f"{model.source}: damping must be a drydem.engine.damping.Damping, got {damping!r}")
    check_fields(damping, {"local": DAMPING, **VISCOUS_RULES}, f"{model.source}: damping")
    if model.joint.stress_dependent and (damping.contact_ratio > 0 or damping.stiffness_proportional > 0):
        raise ModelError(f"{model.source}: contact dashpots (a damping ratio or Rayleigh's stiffness term) with a stress-dependent "
                         f"joint ({model.joint.model} law): the dashpots are sized for a constant kn, and neither their damping ratio "
                         "nor the timestep's bound for them would hold as kn follows the stress; not supported yet")
    return Damping(*(float(value) for value in damping))


def _ground(acceleration, n: int, where: str) -> np.ndarray:
    """The table's ``acceleration`` (m/s2) at each of ``n`` cycles as a float64 (n, 3) array
    (:func:`~drydem.model.state.block_array`: finite real numbers, no texts, booleans or
    complex numbers); ModelError naming ``where`` otherwise, or for a component beyond
    :data:`~drydem.model.parameters.MAX_ACCELERATION_M_S2` (a ground motion's bound)."""
    array = block_array(acceleration, (n, 3), f"{where} (m/s2)")
    peak = np.abs(array)
    if peak.size and peak.max() > MAX_ACCELERATION_M_S2:
        i, k = np.unravel_index(int(np.argmax(peak)), peak.shape)
        raise ModelError(f"{where}[{i}, {k}] = {array[i, k]:g} m/s2: each component must be at most {MAX_ACCELERATION_M_S2:g} m/s2 "
                         "in magnitude (about 100 g, past any earthquake record or shaking table)")
    return array


def _planar(model: Model, engine: str | Callable) -> bool:
    """Whether ``engine`` cycles ``model`` with the planar kernel (:mod:`drydem.engine.cycle_planar`)."""
    return engine == "numba" and model.in_plane


def _cycle_function(model: Model, engine: str | Callable) -> Callable:
    """The run_cycles function of ``engine`` for ``model`` (see :class:`Simulation`)."""
    if callable(engine):
        return engine
    if engine not in ENGINES:
        raise ModelError(f"engine = {engine!r}: must be one of {list(ENGINES)} or a run_cycles function")
    if _planar(model, engine):  # imported here: a run loads only the kernels of its own cycle
        from drydem.engine import cycle_planar

        return cycle_planar.run_cycles
    from drydem.engine import cycle3d

    return cycle3d.run_cycles
