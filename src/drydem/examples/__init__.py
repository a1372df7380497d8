"""Model files shipped with drydem, usable by name wherever a model file is expected."""

from __future__ import annotations

from pathlib import Path

from drydem.errors import ModelError

DIRECTORY = Path(__file__).parent


def names() -> list[str]:
    return sorted(p.stem for p in DIRECTORY.glob("*.toml"))


def resolve(target: str) -> Path:
    """``target`` as a model file path: an existing file, or the name of a shipped example."""
    path = Path(target)
    if path.is_file():
        return path
    shipped = DIRECTORY / f"{target}.toml"
    if shipped.is_file():
        return shipped
    raise ModelError(f"{target}: no such model file, and not a shipped example ({', '.join(names())})")
