"""A reader of 3DEC command files, the tests' oracle of :mod:`drydem.io.itasca`: written from the
3DEC manual's command forms (the table in tests/test_itasca_export.py), sharing no code with the
writer, and strict: a statement it does not know is an error, not skipped.

What it understands, as 3DEC would apply it in file order:

* ``;`` starts a comment line; a line ending in ``...`` goes on on the next one;
* ``block create group 'N' slot 'S' polyhedron face x,y,z x,y,z ... face ...``: a block, its faces;
* ``block group 'G' slot 'S' [range group 'N' slot 'S2']``: G in slot S for every block, or for
  those whose group in slot S2 is N (a slot holds one group);
* ``block fix [velocity-x ... rotation-z] range ...``: the degree(s) of freedom of the blocks in
  the range held (no keyword: all six);
* ``block property density f [range ...]``; ``block contact jmodel assign m``;
  ``block contact property k v ...`` and ``block contact material-table default property k v ...``;
  ``block mechanical damping local f``; ``model gravity gx gy gz``; ``model new``,
  ``model large-strain on``, ``block contact generate-subcontacts`` (no state to keep).
"""

from __future__ import annotations

import shlex
from dataclasses import dataclass, field

import numpy as np

#: block fix keywords, in drydem's order of degrees of freedom (x, y, z, rx, ry, rz)
FIX = ("velocity-x", "velocity-y", "velocity-z", "rotation-x", "rotation-y", "rotation-z")
CONTINUATION = "..."


@dataclass
class Deck:
    """What a command file builds: blocks by name (each a list of (k, 3) face polygons as written),
    their groups by slot, held degrees of freedom (6 bools) and density, the joint model and
    properties, the material table's default properties, damping and gravity."""

    faces: dict[str, list[np.ndarray]] = field(default_factory=dict)
    groups: dict[str, dict[str, str]] = field(default_factory=dict)
    held: dict[str, list[bool]] = field(default_factory=dict)
    density: dict[str, float] = field(default_factory=dict)
    jmodel: str | None = None
    contact: dict[str, float] = field(default_factory=dict)
    default_contact: dict[str, float] = field(default_factory=dict)
    damping: float | None = None
    gravity: tuple[float, ...] | None = None


def statements(text: str) -> list[tuple[int, str]]:
    """(first line number, command) of each statement: comments and blank lines dropped, lines
    ending in ``...`` joined to the next."""
    found, pending, start = [], [], 0
    for number, line in enumerate(text.splitlines(), start=1):
        stripped = line.strip()
        if not pending and (not stripped or stripped.startswith(";")):
            continue
        start = start if pending else number
        if stripped.endswith(CONTINUATION):
            pending.append(stripped[:-len(CONTINUATION)].strip())
            continue
        found.append((start, " ".join(pending + [stripped])))
        pending = []
    if pending:
        raise ValueError(f"line {start}: the file ends inside a continued statement")
    return found


def read_deck(text: str) -> Deck:
    """Apply the statements of a 3DEC command file in order (ValueError naming the line of one it
    does not know)."""
    deck = Deck()
    for number, command in statements(text):
        words = shlex.split(command)
        try:
            _apply(deck, words)
        except (ValueError, IndexError, KeyError) as exc:
            raise ValueError(f"line {number}: cannot read {command[:80]!r}: {exc}") from None
    return deck


def _apply(deck: Deck, words: list[str]) -> None:
    if words[:2] == ["block", "create"]:
        _create(deck, words[2:])
    elif words[:2] == ["block", "group"]:
        group, slot, rest = words[2], _slot(words[3:]), words[5:]
        for name in _selected(deck, rest):
            deck.groups[name][slot] = group
    elif words[:2] == ["block", "fix"]:
        dofs = range(6) if words[2] == "range" else [FIX.index(words[2])]
        for name in _selected(deck, words[2:] if words[2] == "range" else words[3:]):
            for k in dofs:
                deck.held[name][k] = True
    elif words[:3] == ["block", "property", "density"]:
        for name in _selected(deck, words[4:]):
            deck.density[name] = float(words[3])
    elif words[:4] == ["block", "contact", "jmodel", "assign"] and len(words) == 5:
        deck.jmodel = words[4]
    elif words[:3] == ["block", "contact", "property"]:
        deck.contact = _pairs(words[3:])
    elif words[:5] == ["block", "contact", "material-table", "default", "property"]:
        deck.default_contact = _pairs(words[5:])
    elif words[:4] == ["block", "mechanical", "damping", "local"] and len(words) == 5:
        deck.damping = float(words[4])
    elif words[:2] == ["model", "gravity"] and len(words) == 5:
        deck.gravity = tuple(float(w) for w in words[2:])
    elif words not in (["model", "new"], ["model", "large-strain", "on"], ["block", "contact", "generate-subcontacts"]):
        _unknown(words)


def _create(deck: Deck, words: list[str]) -> None:
    """``group 'N' slot 'S' polyhedron face v v v ... face ...``."""
    if words[0] != "group" or words[4] != "polyhedron" or words[5] != "face":
        _unknown(words)
    name, slot = words[1], _slot(words[2:])
    if name in deck.faces:
        raise ValueError(f"a second block named {name!r}")
    faces, current = [], None
    for word in words[5:]:
        if word == "face":
            current = []
            faces.append(current)
        else:
            current.append([float(x) for x in word.split(",", 2)])
    deck.faces[name] = [np.array(face) for face in faces]
    deck.groups[name] = {slot: name}
    deck.held[name] = [False] * 6


def _slot(words: list[str]) -> str:
    if words[0] != "slot":
        raise ValueError(f"expected slot, found {words[0]!r}")
    return words[1]


def _selected(deck: Deck, words: list[str]) -> list[str]:
    """The blocks of ``range group 'N' slot 'S'``, or every block when ``words`` is empty."""
    if not words:
        return list(deck.faces)
    if words[:2] != ["range", "group"] or len(words) != 5:
        _unknown(words)
    group, slot = words[2], _slot(words[3:])
    return [name for name, slots in deck.groups.items() if slots.get(slot) == group]


def _pairs(words: list[str]) -> dict[str, float]:
    if len(words) % 2:
        raise ValueError("keywords and values do not pair up")
    return {key: float(value) for key, value in zip(words[::2], words[1::2])}


def _unknown(words: list[str]):
    raise ValueError(f"not a statement this reader knows: {' '.join(words)[:80]!r}")


def signed_volume(faces: list[np.ndarray]) -> float:
    """Volume enclosed by the faces, m3, by the divergence theorem over each face's fan of
    triangles: sum det(a, b, c) / 6; positive when the faces run counter-clockwise seen from
    outside, negative when clockwise (3DEC's order)."""
    total = 0.0
    for face in faces:
        for b, c in zip(face[1:-1], face[2:]):
            total += float(np.linalg.det(np.array([face[0], b, c]))) / 6.0
    return total
