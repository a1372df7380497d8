"""Study files shipped with drydem (``drydem sweep NAME``): ``savalle2022``, the seed paper's study."""

from __future__ import annotations

from pathlib import Path

DIRECTORY = Path(__file__).parent


def find(name: str) -> Path | None:
    """The shipped study file called ``name``, or None."""
    path = DIRECTORY / f"{name}.toml"
    return path if path.is_file() else None
