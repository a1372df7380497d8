"""The engine: contacts (broad phase, narrow phase, tracking), the compiled explicit cycles (3D
and planar), inertia and timestep, and the :class:`Simulation` that cycles a model to equilibrium.

Public API: :class:`Simulation` (its ``state``, ``contacts``, ``blocks``, ``timestep``,
``run_cycles``), :class:`ContactTracker`, :class:`~drydem.engine.loop.LoopSettings`, imported at
their first use (drydem.lazy_attribute): ``drydem.engine.threads`` alone loads no kernel.
"""

from drydem import lazy_attribute

#: the API imported at its first use: name -> the module that defines it
LAZY = {
    "LoopSettings": "drydem.engine.loop", "ContactTracker": "drydem.engine.tracker",
    **{name: "drydem.engine.simulation" for name in ("ENGINES", "EquilibriumResult", "Simulation", "Snapshot", "StepStats")},
}

__all__ = list(LAZY)


def __getattr__(name: str):
    return lazy_attribute(__name__, LAZY, name)
