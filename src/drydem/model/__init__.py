"""The data model: what the user describes, frozen once built (blocks, their geometry and
materials, supports, solver settings) and the blocks' time-varying state.

Nothing here imports the engine or anything above it (tests/test_layers.py). The API below is
imported at its first use (drydem.lazy_attribute): ``drydem.model.parameters`` alone imports
neither numba nor scipy.
"""

from drydem import lazy_attribute

#: the API imported at its first use: name -> the module that defines it
LAZY = {name: "drydem.model.assembly" for name in ("Block", "Model", "base_under", "build_model")}

__all__ = list(LAZY)


def __getattr__(name: str):
    return lazy_attribute(__name__, LAZY, name)
