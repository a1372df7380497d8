"""Blocks from VRML 2.0 / VRML97 files (``.wrl``), as Rhino exports them and as 3DEC's
``block generate from-vrml`` reads them: every ``Shape`` whose geometry is an
``IndexedFaceSet`` becomes one block, placed by its enclosing ``Transform`` nodes.

Read by a small parser of the VRML97 grammar (ISO/IEC 14772-1:1997, clause 5) rather than a
library: the packages on PyPI are unmaintained (PyVRML97, last release 2019) or GPL-licensed
compiled converters that merge shapes into one mesh (vrmlxpy), losing the blocks.

Supported: ``Transform`` (translation, rotation, scale, scaleOrientation, center), ``Group``,
``Anchor``, ``Collision`` (their ``children``), ``Shape`` with ``IndexedFaceSet`` (``coord
Coordinate { point }``, ``coordIndex``) or ``Box`` (``size``), ``DEF``/``USE``. Appearance,
lights, viewpoints and other nodes that carry no geometry are skipped. ``PROTO``, ``ROUTE``,
``Inline`` and other geometry nodes are errors naming their line.

A block is named after the DEF name of its Shape, else of its nearest named ancestor, else
``shape{k}``; repeated names get ``-2``, ``-3``...
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from drydem.errors import ModelError
from drydem.io.mesh import closed_convex_block
from drydem.model.assembly import Block

GROUPING = {"Transform", "Group", "Anchor", "Collision"}
#: nodes that carry no geometry: skipped wherever they are
SKIPPED = {
    "Appearance", "Material", "ImageTexture", "PixelTexture", "MovieTexture", "TextureTransform", "Background", "Fog",
    "NavigationInfo", "Viewpoint", "WorldInfo", "DirectionalLight", "PointLight", "SpotLight", "Sound", "AudioClip",
    "Script", "TimeSensor", "ProximitySensor", "TouchSensor", "VisibilitySensor", "Normal", "Color", "TextureCoordinate",
    "PositionInterpolator", "OrientationInterpolator", "ColorInterpolator", "ScalarInterpolator",
}
GEOMETRY = {"IndexedFaceSet", "Box"}
UNSUPPORTED = {"PROTO", "EXTERNPROTO", "ROUTE", "Inline", "Switch", "LOD", "Billboard"}
_TOKEN = re.compile(r'\s+|,|#[^\n]*|"(?:[^"\\]|\\.)*"|[{}\[\]]|[^\s,{}\[\]"#]+')


@dataclass
class Node:
    """A parsed VRML node: its type, DEF name, fields (name -> list of values) and line."""

    type: str
    name: str | None
    line: int
    fields: dict[str, list] = field(default_factory=dict)


def read_vrml(path: str | Path, *, unit_m: float = 1.0) -> list[Block]:
    """The blocks of a VRML file, coordinates times ``unit_m``; ModelError naming the file and line."""
    path = Path(path)
    try:
        text = path.read_text(errors="replace")
    except OSError as exc:
        raise ModelError(f"{path}: cannot read the file ({exc.strerror})") from None
    if not text.startswith("#VRML V2.0"):
        raise ModelError(f"{path}, line 1: not a VRML 2.0 / VRML97 file (the header must be '#VRML V2.0 utf8')")
    nodes = _Parser(text, str(path)).nodes()
    shapes: list[tuple[str | None, np.ndarray, list[list[int]], int]] = []
    for node in nodes:
        _collect(node, np.eye(4), None, shapes, str(path))
    if not shapes:
        raise ModelError(f"{path}: no Shape with an IndexedFaceSet or Box")
    blocks, taken = [], {}
    for k, (name, points, faces, line) in enumerate(shapes):
        base = name or f"shape{k}"
        taken[base] = taken.get(base, 0) + 1
        label = base if taken[base] == 1 else f"{base}-{taken[base]}"
        blocks.append(closed_convex_block(points * unit_m, faces, name=label, where=f"{path}, line {line}: Shape {label!r}"))
    return blocks


def _collect(node: Node, to_world: np.ndarray, name: str | None, out: list, source: str) -> None:
    """Walk the scene graph, appending (name, world points, faces, line) for every Shape."""
    name = node.name or name
    if node.type in SKIPPED:
        return
    if node.type in GROUPING:
        matrix = to_world @ _transform_matrix(node, source) if node.type == "Transform" else to_world
        for child in node.fields.get("children", []):
            if isinstance(child, Node):
                _collect(child, matrix, name, out, source)
        return
    if node.type != "Shape":
        raise ModelError(f"{source}, line {node.line}: unsupported node {node.type!r} here (drydem reads "
                         f"{', '.join(sorted(GROUPING))} and Shape)")
    geometry = [g for g in node.fields.get("geometry", []) if isinstance(g, Node)]
    if not geometry:
        raise ModelError(f"{source}, line {node.line}: Shape without geometry")
    points, faces = _geometry(geometry[0], source)
    world = points @ to_world[:3, :3].T + to_world[:3, 3]
    out.append((name, world, faces, node.line))


def _geometry(node: Node, source: str) -> tuple[np.ndarray, list[list[int]]]:
    where = f"{source}, line {node.line}"
    if node.type == "Box":
        size = np.asarray(_numbers(node, "size", [2.0, 2.0, 2.0], 3, source))
        corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], float) * 0.5 * size
        faces = [[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3]]
        return corners, faces
    if node.type != "IndexedFaceSet":
        raise ModelError(f"{where}: unsupported geometry node {node.type!r} (drydem reads {', '.join(sorted(GEOMETRY))})")
    coord = [c for c in node.fields.get("coord", []) if isinstance(c, Node)]
    if not coord or coord[0].type != "Coordinate":
        raise ModelError(f"{where}: IndexedFaceSet needs coord Coordinate {{ point [...] }}")
    values = _numbers(coord[0], "point", None, None, source)
    if len(values) % 3:
        raise ModelError(f"{source}, line {coord[0].line}: {len(values)} numbers in point, not a multiple of 3")
    points = np.asarray(values, float).reshape(-1, 3)
    index = [int(i) for i in _numbers(node, "coordIndex", None, None, source)]
    faces, face = [], []
    for i in [*index, -1]:
        if i == -1:
            if face:
                faces.append(face)
            face = []
        elif not 0 <= i < len(points):
            raise ModelError(f"{where}: coordIndex {i} is out of range (there are {len(points)} points)")
        else:
            face.append(i)
    return points, faces


def _transform_matrix(node: Node, source: str) -> np.ndarray:
    """P' = T C R SR S SR^-1 C^-1 P, the Transform's 4 x 4 matrix (ISO/IEC 14772-1, 6.52)."""
    t = _numbers(node, "translation", [0, 0, 0], 3, source)
    c = _numbers(node, "center", [0, 0, 0], 3, source)
    r = _axis_angle(_numbers(node, "rotation", [0, 0, 1, 0], 4, source))
    sr = _axis_angle(_numbers(node, "scaleOrientation", [0, 0, 1, 0], 4, source))
    s = np.diag(_numbers(node, "scale", [1, 1, 1], 3, source))
    linear = r @ sr @ s @ sr.T
    matrix = np.eye(4)
    matrix[:3, :3] = linear
    matrix[:3, 3] = np.asarray(t) + np.asarray(c) - linear @ np.asarray(c)
    return matrix


def _axis_angle(values: list[float]) -> np.ndarray:
    axis, angle = np.asarray(values[:3], float), values[3]
    norm = np.linalg.norm(axis)
    return np.eye(3) if norm == 0 else Rotation.from_rotvec(axis / norm * angle).as_matrix()


def _numbers(node: Node, name: str, default, count: int | None, source: str) -> list[float]:
    values = node.fields.get(name)
    if values is None:
        if default is None:
            raise ModelError(f"{source}, line {node.line}: {node.type} needs the field {name!r}")
        return list(default)
    if not all(isinstance(v, float) for v in values) or (count is not None and len(values) != count):
        expected = f"{count} numbers" if count else "numbers"
        raise ModelError(f"{source}, line {node.line}: {node.type}.{name} must be {expected}, got {values!r}")
    return values


class _Parser:
    """Recursive descent over the token stream: nodes, fields, values (ISO/IEC 14772-1, A.2)."""

    def __init__(self, text: str, source: str):
        self.source = source
        self.tokens: list[tuple[str, int]] = []
        line = 1
        for match in _TOKEN.finditer(text):
            token = match.group()
            if token.strip() and token != "," and not token.startswith("#"):
                self.tokens.append((token, line))
            line += token.count("\n")
        self.at = 0
        self.defined: dict[str, Node] = {}

    def nodes(self) -> list[Node]:
        found = []
        while self.at < len(self.tokens):
            found.append(self._node())
        return found

    def _peek(self) -> tuple[str, int]:
        if self.at >= len(self.tokens):
            line = self.tokens[-1][1] if self.tokens else 1
            raise ModelError(f"{self.source}, line {line}: unexpected end of file (a '}}' or ']' is missing)")
        return self.tokens[self.at]

    def _next(self) -> tuple[str, int]:
        token = self._peek()
        self.at += 1
        return token

    def _expect(self, wanted: str) -> None:
        token, line = self._next()
        if token != wanted:
            raise ModelError(f"{self.source}, line {line}: expected {wanted!r}, found {token!r}")

    def _node(self) -> Node:
        token, line = self._next()
        if token == "USE":
            name, line = self._next()
            if name not in self.defined:
                raise ModelError(f"{self.source}, line {line}: USE {name}: no node was DEFined with that name before")
            return self.defined[name]
        name = None
        if token == "DEF":
            name, _ = self._next()
            token, line = self._next()
        if token in UNSUPPORTED:
            raise ModelError(f"{self.source}, line {line}: {token} is not supported by drydem's VRML reader")
        if not re.fullmatch(r"[A-Za-z_][\w-]*", token):
            raise ModelError(f"{self.source}, line {line}: expected a node type, found {token!r}")
        node = Node(token, name, line)
        self._expect("{")
        while self._peek()[0] != "}":
            field_name, field_line = self._next()
            if field_name in UNSUPPORTED:
                raise ModelError(f"{self.source}, line {field_line}: {field_name} is not supported by drydem's VRML reader")
            node.fields[field_name] = self._value()
        self._next()
        if name:
            self.defined[name] = node
        return node

    def _value(self) -> list:
        """A field value as a flat list of numbers, strings, booleans or nodes."""
        token, line = self._peek()
        if token == "[":
            self._next()
            values = []
            while self._peek()[0] != "]":
                values += self._single()
            self._next()
            return values
        if self._starts_node():
            return [self._node()]
        values = self._single()
        while self.at < len(self.tokens) and _is_number(self._peek()[0]) and values and isinstance(values[0], float):
            values += self._single()
        return values

    def _starts_node(self) -> bool:
        token = self._peek()[0]
        following = self.tokens[self.at + 1][0] if self.at + 1 < len(self.tokens) else ""
        return token in ("DEF", "USE") or following == "{"

    def _single(self) -> list:
        if self._starts_node():
            return [self._node()]
        token, line = self._next()
        if _is_number(token):
            return [float(token)]
        if token in ("TRUE", "FALSE"):
            return [token == "TRUE"]
        if token.startswith('"') or token == "NULL":
            return [token.strip('"')]
        raise ModelError(f"{self.source}, line {line}: unexpected {token!r} in a field value")


def _is_number(token: str) -> bool:
    try:
        float(token)
    except ValueError:
        return False
    return True
