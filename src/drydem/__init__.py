"""drydem: discrete element analysis of dry-joint masonry.

Rigid convex polyhedral blocks, zero-thickness joints with normal and shear stiffness
and Mohr-Coulomb friction, explicit dynamic relaxation with local damping.

Layers, each importing only those before it (tests/test_layers.py): the foundation
(``errors``, ``files``, ``compiled_cache``); the data model (``drydem.model``); the engine
(``drydem.engine``); the masonry domain (``drydem.masonry``); the analyses
(``drydem.analysis``); input and output files (``drydem.io``); parametric studies
(``drydem.parametric``); reports and figures (``drydem.report``); the command line (``drydem.cli``).
"""

from drydem import compiled_cache

compiled_cache.check()  # first: no compiled function may be loaded from a stale cache

from drydem.engine import EquilibriumResult, Simulation
from drydem.errors import DivergenceError, DrydemError, GeometryError, ModelError
from drydem.model import Block, Model, build_model
from drydem.model.geometry import ConvexPolyhedron, box, convex_hull
from drydem.model.parameters import G, ContactSettings, JointMaterial, SolverSettings, Supports
from drydem.model.state import State

__version__ = "0.1.0"

__all__ = [
    "Block", "ConvexPolyhedron", "ContactSettings", "DivergenceError", "DrydemError", "EquilibriumResult", "G",
    "GeometryError", "JointMaterial", "Model", "ModelError", "Simulation", "SolverSettings", "State", "Supports",
    "box", "build_model", "convex_hull",
]
