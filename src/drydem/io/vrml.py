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
``shape{k}``; repeated names get ``-2``, ``-3``... (a note says so).

Limits, checked while parsing, before any block is built: nodes nest at most :data:`MAX_DEPTH`
deep, and the scene expands to at most :data:`MAX_BLOCKS` shapes and :data:`MAX_POINTS`
vertices, a ``USE`` counting as a copy of the node it names (nested DEF/USE doubles a scene at
each level: a 1 kB file could otherwise expand to millions of blocks).
"""

from __future__ import annotations

import math
import re
import itertools
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from drydem.errors import ModelError
from drydem.files import PLAIN_INTEGER, PLAIN_NUMBER, read_text
from drydem.io.mesh import check_reader_arguments, closed_convex_block
from drydem.model.assembly import MAX_BLOCKS, Block
from drydem.model.parameters import shown

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
#: the most levels of nodes (a top-level node is 1 deep), a USE counting the levels it copies in:
#: exports nest a few (Transform, Group, Shape, geometry), and the reader recurses once a level
MAX_DEPTH = 200
#: the most vertices a scene may expand to (USE copies counted): 50 a block at MAX_BLOCKS blocks
MAX_POINTS = 50 * MAX_BLOCKS
#: what a VRML file must be, for messages
EXPECTED = "drydem reads VRML 2.0 / VRML97 files (the header '#VRML V2.0 utf8', UTF-8 text)"
_TOKEN = re.compile(r'\s+|,|#[^\n]*|"(?:[^"\\]|\\.)*"|[{}\[\]]|[^\s,{}\[\]"#]+')


@dataclass
class Node:
    """A parsed VRML node: its type, DEF name, fields (name -> list of values) and line; and,
    once parsed, what it expands to (USE copies counted): its shapes, its vertices and its
    height in levels of nodes (1: no child node)."""

    type: str
    name: str | None
    line: int
    fields: dict[str, list] = field(default_factory=dict)
    shapes: int = 0
    points: int = 0
    height: int = 1


def read_vrml(path: str | Path, *, unit_m: float = 1.0) -> tuple[list[Block], list[str]]:
    """The blocks of a VRML file, coordinates times ``unit_m`` (m: drydem.io.mesh.UNIT), and notes
    on the names given to shapes that share one (:func:`_labels`), as drydem.io.mesh.read_mesh
    gives its own; ModelError naming the file and line."""
    check_reader_arguments("read_vrml", path, unit_m)
    path = Path(path)
    text = read_text(path, EXPECTED)
    if not text.startswith("#VRML V2.0"):
        raise ModelError(f"{path}, line 1: not a VRML 2.0 / VRML97 file (the header must be '#VRML V2.0 utf8')")
    nodes = _Parser(text, str(path)).nodes()
    shapes: list[tuple[str | None, np.ndarray, list[list[int]], int]] = []
    with np.errstate(over="ignore", invalid="ignore"):  # a transform past the float range: the block refuses inf
        for node in nodes:
            _collect(node, np.eye(4), None, shapes, str(path))
    if not shapes:
        raise ModelError(f"{path}: no Shape with an IndexedFaceSet or Box")
    labels, notes = _labels([name or f"shape{k}" for k, (name, *_) in enumerate(shapes)], path)
    blocks = [closed_convex_block(points * unit_m, faces, name=label, where=f"{path}, line {line}: Shape {label!r}")
              for label, (_, points, faces, line) in zip(labels, shapes)]
    return blocks, notes


def _labels(names: list[str], path: Path) -> tuple[list[str], list[str]]:
    """Block names for shapes named ``names`` (in file order): each name once, a repeated one
    NAME-2, NAME-3, ... (skipping any name the file gives), and a note for each repeated name
    saying what its blocks are called (a USE copy, or a DEF name given twice)."""
    given, labels, shared = set(names), [], {}
    for name in names:
        label = name if name not in shared else next(f"{name}-{n}" for n in itertools.count(2) if f"{name}-{n}" not in given | set(labels))
        labels.append(label)
        shared.setdefault(name, []).append(label)
    notes = [f"{path}: {len(named)} shapes share the name {name!r} (a USE copy, or a DEF given twice): they are the blocks "
             f"{', '.join(map(repr, named))} in file order" for name, named in shared.items() if len(named) > 1]
    return labels, notes


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
        if not (size > 0).all():
            raise ModelError(f"{where}: Box.size = {size.tolist()}: each side must be a number above 0")
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
    return points, _faces(_indices(node, "coordIndex", source), len(points), where)


def _faces(coord_index: list[int | float], count: int, where: str) -> list[list[int]]:
    """The faces of an IndexedFaceSet's coordIndex: each entry a whole number, a point's index
    (0 to ``count`` - 1) or -1 ending a face (the last face may end without it)."""
    faces, face = [], []
    for value in [*coord_index, -1]:
        if isinstance(value, float) and not value.is_integer():
            raise ModelError(f"{where}: coordIndex {value!r} is not a whole number (a point's index from 0, or -1 ending a face)")
        i = int(value)
        if i == -1:
            if face:
                faces.append(face)
            face = []
        elif not 0 <= i < count:
            raise ModelError(f"{where}: coordIndex {shown(value)} is out of range (there are {count} points)")
        else:
            face.append(i)
    return faces


def _transform_matrix(node: Node, source: str) -> np.ndarray:
    """P' = T C R SR S SR^-1 C^-1 P, the Transform's 4 x 4 matrix (ISO/IEC 14772-1, 6.52)."""
    t = _numbers(node, "translation", [0, 0, 0], 3, source)
    c = _numbers(node, "center", [0, 0, 0], 3, source)
    r = _axis_angle(node, "rotation", source)
    sr = _axis_angle(node, "scaleOrientation", source)
    s = np.diag(_numbers(node, "scale", [1, 1, 1], 3, source))
    linear = r @ sr @ s @ sr.T
    matrix = np.eye(4)
    matrix[:3, :3] = linear
    matrix[:3, 3] = np.asarray(t) + np.asarray(c) - linear @ np.asarray(c)
    return matrix


def _axis_angle(node: Node, name: str, source: str) -> np.ndarray:
    """The rotation matrix of the field ``name`` (x y z angle, an SFRotation): its axis is not
    zero, unless its angle is 0 (no rotation); the axis may be of any length."""
    values = _numbers(node, name, [0, 0, 1, 0], 4, source)
    axis, angle = np.asarray(values[:3], float), values[3]
    scale = np.abs(axis).max()  # a unit axis at any size: 1e200 squared is past the float range
    if scale == 0 and angle != 0:
        raise ModelError(f"{source}, line {node.line}: {node.type}.{name} = {values}: the axis (the first three numbers) "
                         "is zero, so it names no direction to turn by the angle; give an axis, or the angle 0")
    if scale == 0:
        return np.eye(3)
    axis = axis / scale
    return Rotation.from_rotvec(axis / np.linalg.norm(axis) * angle).as_matrix()


def _field(node: Node, name: str, default, count: int | None, source: str) -> list[int | float]:
    """The field ``name`` of ``node`` (``default`` if it is missing; None: it must be there):
    numbers as read (int or float), ``count`` of them if given."""
    values = node.fields.get(name)
    if values is None:
        if default is None:
            raise ModelError(f"{source}, line {node.line}: {node.type} needs the field {name!r}")
        return list(default)
    if not all(map(_is_value_number, values)) or (count is not None and len(values) != count):
        expected = f"{count} numbers" if count else "numbers"
        written = " ".join("TRUE" if v is True else "FALSE" if v is False else str(v) for v in values)  # as in the file
        raise ModelError(f"{source}, line {node.line}: {node.type}.{name} must be {expected}, got {shown(written)}")
    return values


def _numbers(node: Node, name: str, default, count: int | None, source: str) -> list[float]:
    """The field ``name`` of ``node`` as :func:`_field` reads it, as floats, each finite (VRML
    has no nan or inf; a number past 1.8e308 reads as inf)."""
    values = [_float(v) for v in _field(node, name, default, count, source)]
    _check_finite(node, name, values, source)
    return values


def _indices(node: Node, name: str, source: str) -> list[int | float]:
    """The field ``name`` of ``node``, which must be there, as :func:`_field` reads it: a whole
    number as written (an int, shown whole in messages), any other finite."""
    values = _field(node, name, None, None, source)
    _check_finite(node, name, [v for v in values if isinstance(v, float)], source)
    return values


def _check_finite(node: Node, name: str, values: list[float], source: str) -> None:
    """The rule on a field's numbers: each finite."""
    infinite = [v for v in values if not math.isfinite(v)]
    if infinite:
        raise ModelError(f"{source}, line {node.line}: {node.type}.{name} holds {infinite[0]!r}: each number must be "
                         "finite (no nan, inf, or a number past 1.8e308)")


def _float(value: int | float) -> float:
    """A number read as a float: an int past the float range is inf, as the float of its digits is."""
    try:
        return float(value)
    except OverflowError:
        return math.inf if value > 0 else -math.inf


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
        self.depth = 0  # levels of nodes open around the token at self.at

    def nodes(self) -> list[Node]:
        """The top-level nodes, which together expand to at most MAX_BLOCKS shapes and MAX_POINTS vertices."""
        found, shapes, points = [], 0, 0
        while self.at < len(self.tokens):
            node = self._node()
            found.append(node)
            shapes, points = shapes + node.shapes, points + node.points
            self._check_expansion(shapes, points, node.line)
        return found

    def _check_expansion(self, shapes: int, points: int, line: int) -> None:
        """The rule on USE copies: the scene up to ``line`` expands to at most MAX_BLOCKS shapes and MAX_POINTS vertices."""
        for count, limit, what in ((shapes, MAX_BLOCKS, "shapes"), (points, MAX_POINTS, "vertices")):
            if count > limit:
                raise ModelError(f"{self.source}, line {line}: up to this node, the scene expands to more than {limit:,} {what} "
                                 f"(each USE copies the node it names): drydem reads at most {limit:,}")

    def _tally(self, node: Node) -> None:
        """What ``node`` expands to, from its child nodes' (parsed already, a USE's included), within the limits."""
        children = [value for values in node.fields.values() for value in values if isinstance(value, Node)]
        node.shapes = (node.type == "Shape") + sum(child.shapes for child in children)
        own_points = {"Box": 8, "Coordinate": len(node.fields.get("point", [])) // 3}.get(node.type, 0)
        node.points = own_points + sum(child.points for child in children)
        node.height = 1 + max((child.height for child in children), default=0)
        self._check_expansion(node.shapes, node.points, node.line)

    def _check_depth(self, levels: int, what: str, line: int) -> None:
        """The rule on nesting: a node at most MAX_DEPTH levels deep, ``levels`` open here (a USE's copies counted)."""
        if levels > MAX_DEPTH:
            raise ModelError(f"{self.source}, line {line}: {what} nests nodes {levels} levels deep: drydem reads "
                             f"at most {MAX_DEPTH} (a USE counts the levels of the node it copies)")

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
            self._check_depth(self.depth + self.defined[name].height, f"USE {name}", line)
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
        self._check_depth(self.depth + 1, token, line)
        self.depth += 1
        self._expect("{")
        while self._peek()[0] != "}":
            field_name, field_line = self._next()
            if field_name in UNSUPPORTED:
                raise ModelError(f"{self.source}, line {field_line}: {field_name} is not supported by drydem's VRML reader")
            node.fields[field_name] = self._value()
        self._next()
        self.depth -= 1
        self._tally(node)
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
        while self.at < len(self.tokens) and _is_number(self._peek()[0]) and values and _is_value_number(values[0]):
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
            return [_number(token)]
        if token in ("TRUE", "FALSE"):
            return [token == "TRUE"]
        if token.startswith('"') or token == "NULL":
            return [token.strip('"')]
        raise ModelError(f"{self.source}, line {line}: unexpected {token!r} in a field value")


def _number(token: str) -> int | float:
    """A number token's value: an int where it is written as a whole number (an index, kept as
    written; past Python's limit on an integer's digits, a float), else a float."""
    if PLAIN_INTEGER.fullmatch(token):
        try:
            return int(token)
        except ValueError:
            pass
    return float(token)


def _is_value_number(value) -> bool:
    """Whether a parsed field value is a number (TRUE and FALSE are booleans, not numbers)."""
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _is_number(token: str) -> bool:
    """Whether ``token`` is a number as VRML writes one (:data:`~drydem.files.PLAIN_NUMBER`)."""
    return PLAIN_NUMBER.fullmatch(token) is not None
