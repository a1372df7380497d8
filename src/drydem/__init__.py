"""drydem: discrete element analysis of dry-joint masonry.

Rigid convex polyhedral blocks, zero-thickness joints with normal and shear stiffness
and Mohr-Coulomb friction, explicit dynamic relaxation with local damping.

Layers, each importing only those before it (tests/test_layers.py): the foundation
(``errors``, ``files``, ``compiled_cache``); the data model (``drydem.model``); the engine
(``drydem.engine``); the masonry domain (``drydem.masonry``); the analyses
(``drydem.analysis``); input and output files (``drydem.io``); parametric studies
(``drydem.parametric``); reports and figures (``drydem.report``); the command line (``drydem.cli``).

The API below is imported at its first use (PEP 562's module ``__getattr__``): ``import drydem``
imports neither numba nor scipy, and the command line starts without them (tests/test_start.py).
"""

import importlib

from drydem.errors import DivergenceError, DrydemError, GeometryError, ModelError

__version__ = "0.1.0"

#: the API imported at its first use: name -> the module that defines it
LAZY = {
    "EquilibriumResult": "drydem.engine.simulation", "Simulation": "drydem.engine.simulation",
    "Block": "drydem.model.assembly", "Model": "drydem.model.assembly", "build_model": "drydem.model.assembly",
    "ConvexPolyhedron": "drydem.model.geometry", "box": "drydem.model.geometry", "convex_hull": "drydem.model.geometry",
    "G": "drydem.model.parameters", "ContactSettings": "drydem.model.parameters", "JointMaterial": "drydem.model.parameters",
    "SolverSettings": "drydem.model.parameters", "Supports": "drydem.model.parameters", "State": "drydem.model.state",
}

__all__ = ["DivergenceError", "DrydemError", "GeometryError", "ModelError", *LAZY]


def lazy_attribute(package: str, lazy: dict[str, str], name: str):
    """``package``'s attribute ``name``: imported from the module ``lazy`` names for it (the
    module ``__getattr__`` of drydem and of its packages that import their API lazily)."""
    if name not in lazy:
        raise AttributeError(f"module {package!r} has no attribute {name!r}")
    return getattr(importlib.import_module(lazy[name]), name)


def __getattr__(name: str):
    return lazy_attribute(__name__, LAZY, name)


def __dir__() -> list[str]:
    return sorted({*globals(), *LAZY})
