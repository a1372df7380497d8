"""The data model: what the user describes, frozen once built (blocks, their geometry and
materials, supports, solver settings) and the blocks' time-varying state.

Nothing here imports the engine or anything above it (tests/test_layers.py).
"""

from drydem.model.assembly import Block, Model, base_under, build_model

__all__ = ["Block", "Model", "base_under", "build_model"]
