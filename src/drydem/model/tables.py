"""The parameter tables of model and wall files (``[material]``, ``[joint]``, ``[contacts]``,
``[supports]``, ``[solver]``) into the data model's parameters; unknown keys are errors."""

from __future__ import annotations

from contextlib import contextmanager
from dataclasses import fields

from drydem.errors import DrydemError, ModelError
from drydem.model.parameters import ContactSettings, JointMaterial, SolverSettings, Supports

#: the parameter tables and the classes they fill (field names are the TOML keys)
SECTIONS = {"joint": JointMaterial, "contacts": ContactSettings, "supports": Supports, "solver": SolverSettings}


def parameters_from_dict(data: dict, source: str) -> dict:
    """The keyword arguments of :func:`build_model` other than the blocks, from the tables
    ``[material]`` (density, kg/m3, default 1800), ``[joint]``, ``[contacts]``, ``[supports]``
    and ``[solver]``; each table optional, unknown keys errors."""
    params = {name: _section(data.get(name, {}), cls, name, source) for name, cls in SECTIONS.items()}
    material = data.get("material", {})
    no_unknown(material, {"density"}, source, "[material]")
    params["density"] = material.get("density", 1800.0)
    return params


@contextmanager
def errors_naming(source: str):
    """Re-raise a DrydemError with ``source`` in front of its message, if not there yet."""
    try:
        yield
    except DrydemError as exc:
        message = str(exc)
        raise type(exc)(message if message.startswith(source) else f"{source}: {message}") from None


def no_unknown(table: dict, allowed: set[str], source: str, where: str) -> None:
    """ModelError naming ``source`` and ``where`` unless ``table`` is a table whose keys are all ``allowed``."""
    if not isinstance(table, dict):
        raise ModelError(f"{source}: {where} must be a table")
    unknown = sorted(set(table) - allowed)
    if unknown:
        raise ModelError(f"{source}: unknown key(s) {unknown} in {where}; allowed: {sorted(allowed)}")


def _section(table: dict, cls, name: str, source: str):
    """The parameters ``cls`` of the table ``[name]``; ModelError naming the file for an unknown key or a bad value."""
    no_unknown(table, {f.name for f in fields(cls)}, source, f"[{name}]")
    try:
        return cls(**table)
    except TypeError as exc:
        raise ModelError(f"{source}: [{name}]: {exc}") from None
