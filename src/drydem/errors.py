"""Exceptions raised by drydem; each message names the file, block or parameter at fault."""


class DrydemError(Exception):
    """Base class of every error drydem raises on purpose."""


class GeometryError(DrydemError):
    """A block's vertices do not describe a convex, non-degenerate polyhedron."""


class ModelError(DrydemError):
    """A model (file or Python) is invalid: unknown key, bad value, overlapping blocks."""


class DivergenceError(DrydemError):
    """The explicit integration blew up (timestep too large or the model is unstable numerically)."""


class OutputTakenError(DrydemError):
    """An output file is being written by another process, or was written by one while drydem
    wrote its own (which then keeps the other's)."""
