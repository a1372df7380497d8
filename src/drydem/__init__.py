"""drydem: discrete element analysis of dry-joint masonry.

Rigid convex polyhedral blocks, zero-thickness joints with normal and shear stiffness
and Mohr-Coulomb friction, explicit dynamic relaxation with local damping.
"""

from drydem import compiled_cache

compiled_cache.check()  # first: no compiled function may be loaded from a stale cache

from drydem.errors import DivergenceError, DrydemError, GeometryError, ModelError
from drydem.geometry import ConvexPolyhedron, box, convex_hull
from drydem.model import Block, Model, build_model
from drydem.parameters import ContactSettings, JointMaterial, SolverSettings, Supports
from drydem.solve import G, EquilibriumResult, Simulation
from drydem.state import State

__version__ = "0.1.0"

__all__ = [
    "Block", "ConvexPolyhedron", "ContactSettings", "DivergenceError", "DrydemError", "EquilibriumResult", "G",
    "GeometryError", "JointMaterial", "Model", "ModelError", "Simulation", "SolverSettings", "State", "Supports",
    "box", "build_model", "convex_hull",
]
