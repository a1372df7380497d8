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


def plain_reason(exc: Exception) -> str:
    """What ``exc`` says went wrong, as plain text for a message: its own words, a missing key
    as "no 'name'", never Python's repr (a hunt found ValueError("...") in animate's messages)."""
    if isinstance(exc, KeyError) and exc.args:
        return f"no {exc.args[0]!r}"
    return str(exc) or type(exc).__name__
