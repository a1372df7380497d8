"""The engine: contacts (broad phase, narrow phase, tracking), the compiled explicit cycles (3D
and planar), inertia and timestep, and the :class:`Simulation` that cycles a model to equilibrium.

Public API: :class:`Simulation` (its ``state``, ``contacts``, ``blocks``, ``timestep``,
``run_cycles``), :class:`ContactTracker`, :class:`~drydem.engine.loop.LoopSettings`.
"""

from drydem.engine.loop import LoopSettings
from drydem.engine.simulation import ENGINES, EquilibriumResult, Simulation, Snapshot, StepStats
from drydem.engine.tracker import ContactTracker

__all__ = ["ENGINES", "ContactTracker", "EquilibriumResult", "LoopSettings", "Simulation", "Snapshot", "StepStats"]
