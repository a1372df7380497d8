"""Wall files shipped with drydem, usable by name wherever a model is expected: the seven
competition walls WD1-WD7 of the seed paper (reconstructions, not the original drawings) and
``perforated_wall``, the example of the tests and benchmarks."""

from __future__ import annotations

from pathlib import Path

DIRECTORY = Path(__file__).parent


def names() -> list[str]:
    """The built-in walls: WD1..WD7 first, then the examples."""
    return sorted((p.stem for p in DIRECTORY.glob("*.toml")), key=lambda n: (not n.startswith("WD"), n))


def find(name: str) -> Path | None:
    """The wall file of a built-in wall (case-insensitive name), or None."""
    for known in names():
        if known.lower() == name.lower():
            return DIRECTORY / f"{known}.toml"
    return None
