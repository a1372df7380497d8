"""Cycling a model: contact (re-)detection, timestep, equilibrium by dynamic relaxation.

A :class:`Simulation` holds a frozen :class:`~drydem.model.Model`, the mutable
:class:`~drydem.state.State` and the current :class:`~drydem.contacts.SubContacts`.
Contacts are re-detected whenever two neighbouring blocks may have moved half the
contact tolerance relative to each other (separated ones: their separation) since their
pair was last looked at, or any block may have
moved far enough for a block outside its neighbour list to reach it (bounds on every
point's displacement, so no new touch is missed: :func:`drydem.kernels.detection_slack`);
each detection recomputes the timestep (or, with mass scaling, the fictitious masses at
the first timestep).

Equilibrium (3DEC's ``solve``): cycle until

* ``ratio``: max over free blocks of the unbalanced force (or moment / block radius)
  divided by the mean weight of the free blocks is below ``SolverSettings.ratio``, or
* ``velocity``: the fastest block point (|v| + |omega| r) is slower than
  ``SolverSettings.max_velocity`` (the paper's 1e-13 m/s).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from drydem import contacts, kernels, narrow, planar, reference, refresh
from drydem.errors import DivergenceError, ModelError
from drydem.joints import JointArrays
from drydem.model import Model
from drydem.motion import BlockArrays, contact_stiffness, critical_timestep, scaled_inertia
from drydem.parameters import SolverSettings
from drydem.rotation import matrices, rotate_by_vector
from drydem.state import State

#: "numba": compiled, the planar kernel for in-plane models (drydem.planar), else the 3D one;
#: "numba-3d": the compiled 3D kernel for every model; "reference": the NumPy 3D oracle
ENGINES = ("numba", "numba-3d", "reference")
#: standard gravity, m/s2
G = 9.81
#: neighbour-list margin in contact tolerances: blocks whose bounding boxes are this close are
#: watched for relative motion; any block moving (margin - tolerance) / 2 re-detects everything
NEIGHBOUR_MARGIN = 10.0
#: cycles run in one call of the kernel loop between progress reports
CHUNK = 5_000
#: 1/kg: blocks this heavy keep their velocities through a cycle's forces (Simulation.move)
IMMOVABLE_INVERSE_MASS = 1e-300


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
    neighbour list, the blocks still in the analysis, cycles run."""

    state: State
    contacts: contacts.SubContacts
    neighbours: contacts.NeighbourList
    broad_state: State
    active: np.ndarray
    cycles: int
    scaled_timestep: float | None


class Simulation:
    """A model being cycled. ``engine`` is one of ENGINES ("numba", the default, is the fastest).

    ``timestep`` (s) overrides the automatic one; it must not exceed the critical timestep.
    """

    def __init__(self, model: Model, *, state: State | None = None, engine: str = "numba", timestep: float | None = None):
        if engine not in ENGINES:
            raise ValueError(f"engine must be one of {sorted(ENGINES)}, not {engine!r}")
        self.model = model
        self.state = state.copy() if state is not None else State.at_rest(model.block_centroid)
        self.engine = engine
        if engine == "reference":
            self._run_cycles = reference.run_cycles
        else:
            self._run_cycles = planar.run_cycles if engine == "numba" and model.in_plane else kernels.run_cycles
        self.contacts = contacts.SubContacts.empty()
        self.neighbours = contacts.NeighbourList.empty()
        self.active = np.ones(model.n_blocks, dtype=bool)
        self._blocks: BlockArrays | None = None
        self.cycles = 0
        self.detections = 0
        self._fixed_timestep = timestep
        self._scaled_timestep: float | None = None
        self.detect_contacts()

    # -- contacts and inertia -------------------------------------------------------------
    def detect_contacts(self) -> None:
        """Re-detect every contact at the current state (shear stress carried over)."""
        self._detect(everything=True)

    def _detect(self, *, everything: bool) -> None:
        """Refresh the contacts (:func:`drydem.kernels.detection_slack` said so, or ``everything``).

        Neighbour pairs that moved less than half their limit relative to each other since their
        snapshot keep their sub-contacts and shear history untouched; the others go
        through the narrow phase again, inheriting shear stress from their old sub-contacts
        (:func:`drydem.refresh.merge`). The broad phase runs again only when some block
        has moved far from where the last one saw it.
        """
        m, s = self.model, self.state
        nb, tol = m.n_blocks, m.contact_tolerance
        rot = matrices(s.quaternion)
        old_list, old = self.neighbours, self.contacts
        motion = np.empty(len(old_list.pairs))
        kernels.pair_motions(s, old_list, m.block_radius, motion)
        if everything or self._moved_far():
            lower, upper = narrow.bounding_boxes(m.geometry, s.position, rot)
            pairs = contacts.broad_phase(lower, upper, m.block_movable, 0.5 * NEIGHBOUR_MARGIN * tol)
            pairs = pairs[self.active[pairs].all(axis=1)]
            self._broad_state = s.copy()
        else:
            pairs = old_list.pairs
        where, kept, keep_contact = refresh.match_pairs(old_list.pairs, old_list.limit, motion, pairs, old.pairs, nb, everything=everything)
        stale = pairs[~kept]
        fresh, separation = contacts.narrow_phase_compiled(m.geometry, stale, s.position, rot, tolerance=tol, density=m.contact_density)
        self.contacts = refresh.merge(old, keep_contact, fresh, s.position, rot)
        snapshot_position, snapshot_quaternion = s.position[pairs], s.quaternion[pairs]
        snapshot_position[kept] = old_list.position[where[kept]]
        snapshot_quaternion[kept] = old_list.quaternion[where[kept]]
        limit = np.empty(len(pairs))
        limit[kept] = old_list.limit[where[kept]]
        limit[~kept] = np.maximum(0.5 * tol, separation - 0.5 * tol)
        self.neighbours = contacts.NeighbourList(pairs, snapshot_position, snapshot_quaternion, limit)
        self.detections += 1
        self._update_inertia()

    def _moved_far(self) -> bool:
        """Some block point moved (margin - tolerance) / 2 since the last broad phase."""
        return kernels.detection_slack(
            self.state, self._broad_state, contacts.NeighbourList.empty(), self.model.block_radius, self._absolute_limit,
            np.empty(self.model.n_blocks),
        ) <= 0.0

    @property
    def _absolute_limit(self) -> float:
        return 0.5 * (NEIGHBOUR_MARGIN - 1.0) * self.model.contact_tolerance

    def _update_inertia(self) -> None:
        m, solver = self.model, self.model.solver
        k_t, k_r = contact_stiffness(self.contacts, m.joint.kn, m.joint.ks, m.n_blocks)
        critical = critical_timestep(m.block_mass, m.block_inertia_whitening, m.block_movable & self.active, k_t, k_r)
        if self._fixed_timestep is not None:
            if self._fixed_timestep > critical:
                raise ModelError(
                    f"{m.source}: timestep {self._fixed_timestep:.3g} s exceeds the critical timestep "
                    f"{critical:.3g} s (kn = {m.joint.kn:.3g} Pa/m); the run would blow up"
                )
            dt = self._fixed_timestep
        else:
            dt = solver.timestep_safety * critical if np.isfinite(critical) else self._free_flight_timestep()
        mass, inertia = m.block_mass, m.block_inertia
        if solver.mass_scaling:
            if self._scaled_timestep is None:
                self._scaled_timestep = dt
            dt = self._scaled_timestep
            mass, inertia = scaled_inertia(mass, inertia, k_t, k_r, dt, solver.timestep_safety)
            self._keep_kinetic_energy(mass, inertia)
        self.timestep = float(dt)
        movable = m.block_movable & self.active
        self._blocks = BlockArrays(
            mass=m.block_mass,
            inv_mass=np.where(movable, 1.0 / mass, 0.0),
            inertia_body=inertia,
            inv_inertia_body=np.linalg.inv(inertia) if solver.mass_scaling else m.block_inertia_inverse,
            free=(~m.block_fixed & movable[:, None]).astype(float),
            radius=m.block_radius,
            origin=m.block_centroid,
        )

    def _keep_kinetic_energy(self, mass: np.ndarray, inertia: np.ndarray) -> None:
        """Rescale velocities when fictitious masses change, so that each block keeps its kinetic
        energy (a change of fictitious inertia must not create or destroy energy)."""
        if self._blocks is None:
            return
        old = self._blocks
        old_mass = np.divide(1.0, old.inv_mass, out=np.zeros_like(old.inv_mass), where=old.inv_mass > 0)
        self.state.velocity[:] *= np.sqrt(np.divide(old_mass, mass, out=np.ones_like(mass), where=mass > 0))[:, None]
        rot = matrices(self.state.quaternion)
        omega_body = np.einsum("nji,nj->ni", rot, self.state.angular_velocity)
        before = np.einsum("ni,nij,nj->n", omega_body, old.inertia_body, omega_body)
        after = np.einsum("ni,nij,nj->n", omega_body, inertia, omega_body)
        self.state.angular_velocity[:] *= np.sqrt(np.divide(before, after, out=np.ones_like(after), where=after > 0))[:, None]

    def _free_flight_timestep(self) -> float:
        """Timestep with no springs: a tenth of the time to fall through the contact tolerance."""
        return 0.1 * float(np.sqrt(2.0 * self.model.contact_tolerance / G))

    def remove_blocks(self, blocks) -> None:
        """Take blocks out of the analysis (e.g. bricks that fell out of the wall): they stop
        moving, lose their contacts and no longer count for equilibrium."""
        self.active[np.asarray(blocks, dtype=np.int64)] = False
        keep = self.active[self.contacts.pairs].all(axis=1)
        self.contacts = contacts.subset(self.contacts, keep)
        self.neighbours = contacts.NeighbourList(*(a[self.active[self.neighbours.pairs].all(axis=1)] for a in self.neighbours))
        self.state.velocity[~self.active] = 0.0
        self.state.angular_velocity[~self.active] = 0.0
        self._update_inertia()

    def snapshot(self) -> Snapshot:
        """Everything needed to resume cycling from now (see :meth:`restore`)."""
        return Snapshot(
            state=self.state.copy(), contacts=self.contacts.copy(), neighbours=self.neighbours.copy(),
            broad_state=self._broad_state.copy(), active=self.active.copy(), cycles=self.cycles, scaled_timestep=self._scaled_timestep,
        )

    def restore(self, snapshot: Snapshot) -> None:
        """Go back to a :meth:`snapshot` (its arrays are copied, so it can be restored again)."""
        self.state = snapshot.state.copy()
        self.contacts = snapshot.contacts.copy()
        self.neighbours = snapshot.neighbours.copy()
        self._broad_state = snapshot.broad_state.copy()
        self.active = snapshot.active.copy()
        self.cycles = snapshot.cycles
        self._scaled_timestep = snapshot.scaled_timestep
        self._update_inertia()

    # -- cycling --------------------------------------------------------------------------
    def move(self, displacement: np.ndarray, rotation: np.ndarray, *, gravity=(0.0, 0.0, -G)) -> None:
        """Move every free block by ``displacement`` (nb, 3) m and the rotation vector ``rotation``
        (nb, 3) rad (world frame) within one cycle, and leave it at rest there.

        The joints follow as in any cycle: the shear springs take the tangential relative
        displacement (Mohr-Coulomb capping them), the normal ones the gaps. The move is a cycle
        with the velocities displacement / dt and rotation / dt in which the blocks are too
        heavy (IMMOVABLE_INVERSE_MASS) for the joint forces to change them. A predictor for the
        next load step (:mod:`drydem.analysis.tilt`): dynamic relaxation then starts near the new
        equilibrium. Fixed degrees of freedom do not move, whatever is asked of them.
        """
        blocks = self._blocks
        self.state.velocity[:] = np.asarray(displacement, dtype=float) * blocks.free[:, :3] / self.timestep
        self.state.angular_velocity[:] = np.asarray(rotation, dtype=float) * blocks.free[:, 3:] / self.timestep
        heavy = blocks._replace(
            inv_mass=np.where(blocks.inv_mass > 0, IMMOVABLE_INVERSE_MASS, 0.0), inv_inertia_body=np.zeros_like(blocks.inv_inertia_body)
        )
        # its kinetic energy is not the dynamics', so not a divergence (a NaN still is)
        self._run(gravity, 1, criterion=kernels.RATIO, limit=-1.0, criterion_name="none", travel_slack=np.inf, blocks=heavy)
        self.state.velocity[:] = 0.0
        self.state.angular_velocity[:] = 0.0

    def cycle(self, n: int, *, gravity=(0.0, 0.0, -G)) -> EquilibriumResult:
        """Run exactly ``n`` cycles (re-detecting contacts as needed), no equilibrium test."""
        return self._run(gravity, n, criterion=kernels.RATIO, limit=-1.0, criterion_name="none")

    def cycle_to_equilibrium(
        self, *, gravity=(0.0, 0.0, -G), solver: SolverSettings | None = None, progress: Callable[[int, StepStats], None] | None = None,
        stop: Callable[[], bool] | None = None,
    ) -> EquilibriumResult:
        """Cycle until at rest (see module docstring); non-convergence is returned, not hidden.

        ``progress(cycles, stats)`` is called every few thousand cycles. ``stop()`` is asked
        whenever the compiled loop hands back (at every re-detection, so every few cycles
        while blocks move fast, and at least every CHUNK cycles): True ends the call there,
        unconverged. Raises DivergenceError if the integration blows up.
        """
        solver = solver or self.model.solver
        criterion, limit = (kernels.RATIO, solver.ratio) if solver.criterion == "ratio" else (kernels.VELOCITY, solver.max_velocity)
        return self._run(
            gravity, solver.max_cycles, criterion=criterion, limit=limit, criterion_name=solver.criterion, progress=progress, stop=stop
        )

    def _run(
        self, gravity, max_cycles: int, *, criterion: int, limit: float, criterion_name: str, progress=None,
        travel_slack: float | None = None, blocks: BlockArrays | None = None, stop: Callable[[], bool] | None = None,
    ) -> EquilibriumResult:
        m = self.model
        g = np.asarray(gravity, dtype=float)
        if g.shape != (3,) or not np.all(np.isfinite(g)):
            raise ModelError(f"gravity must be a finite [gx, gy, gz] in m/s2, got {gravity!r}")
        moving = m.block_movable & self.active
        weight = float(np.linalg.norm(g)) * float(m.block_mass[moving].sum()) / max(int(moving.sum()), 1)
        if criterion_name == "ratio" and weight == 0.0:
            raise ModelError("the 'ratio' criterion needs gravity (it divides by the mean weight); use 'velocity'")
        joint = JointArrays.of(m.joint)
        if travel_slack is None:
            travel_slack = m.total_mass * m.contact_tolerance
        done, detections = 0, 0
        code, stats = kernels.RUNNING, StepStats(np.inf, np.inf)
        while done < max_cycles:
            loop = kernels.LoopSettings(
                g, self.timestep, m.solver.damping, min(CHUNK, max_cycles - done), criterion, limit, max(weight, 1e-300),
                travel_slack, self._absolute_limit,
            )
            n, code, ratio, speed = self._run_cycles(self.state, blocks or self._blocks, self.contacts, joint, loop, self._broad_state, self.neighbours)
            stats = StepStats(ratio, speed)
            done += n
            self.cycles += n
            if progress is not None:
                progress(done, stats)
            if code == kernels.DIVERGED:
                raise DivergenceError(
                    f"{m.source}: the integration diverged after {self.cycles} cycles (more kinetic energy than gravity "
                    f"can have supplied; timestep {self.timestep:.3g} s): "
                    "reduce the timestep (solver.timestep_safety) or check the stiffness and masses"
                )
            if code == kernels.CONVERGED:
                break
            if code == kernels.REDETECT:
                self._detect(everything=False)
                detections += 1
            if stop is not None and stop():
                break
        return EquilibriumResult(code == kernels.CONVERGED, done, criterion_name, float(stats.ratio), float(stats.max_speed), detections)

    # -- diagnostics ----------------------------------------------------------------------
    def energy(self, *, gravity=(0.0, 0.0, -G)) -> dict[str, float]:
        """Kinetic, gravitational and elastic (joint spring) energy, J, all at the half step.

        The velocities are those of t - dt/2 in leapfrog terms, so the positions are rewound
        by half a step (x - v dt/2, rotations by -omega dt/2) before the potentials are
        evaluated. Kinetic: sum 1/2 m v^2 + 1/2 omega . I_w omega (true masses);
        gravitational: -sum m g . (x - x_model_file); elastic: sum 1/2 kn A u_n^2 over closed
        sub-contacts plus 1/2 |F_s|^2 / (ks A) (no-tension joints).
        """
        m, s, c = self.model, self.state, self.contacts
        half = -0.5 * self.timestep
        position = s.position + half * s.velocity
        quaternion = s.quaternion.copy()
        for q, w in zip(quaternion, s.angular_velocity):
            rotate_by_vector(q, *(half * w))
        rot = matrices(quaternion)
        inertia_world = np.einsum("nij,njk,nlk->nil", rot, m.block_inertia, rot)
        kinetic = 0.5 * (m.block_mass * np.einsum("ni,ni->n", s.velocity, s.velocity)).sum()
        kinetic += 0.5 * np.einsum("ni,nij,nj->", s.angular_velocity, inertia_world, s.angular_velocity)
        gravitational = -float((m.block_mass * ((position - m.block_centroid) @ np.asarray(gravity, float))).sum())
        _, gap, _ = contacts.world_points(c, position, rot)
        closure = np.maximum(-gap, 0.0)
        elastic = 0.5 * (m.joint.kn * c.area * closure**2).sum()
        elastic += 0.5 * (np.einsum("ni,ni->n", c.shear_force, c.shear_force) / (m.joint.ks * c.area)).sum()
        return {"kinetic": float(kinetic), "gravitational": gravitational, "elastic": float(elastic)}

    def reactions(self, block: int) -> np.ndarray:
        """Total contact force (N, world frame) that the other blocks exert on ``block``."""
        c = self.contacts
        _, _, normal = contacts.world_points(c, self.state.position, matrices(self.state.quaternion))
        f = c.normal_force[:, None] * normal + c.shear_force
        return f[c.block_inc == block].sum(0) - f[c.block_ref == block].sum(0)
