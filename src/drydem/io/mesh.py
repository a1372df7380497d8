"""Blocks from surface meshes (OBJ, STL) and blocks to them.

A block is a closed surface: every edge shared by exactly two faces (an open mesh names its
free edge), no vertex inside the hull of the others (drydem.model.geometry.convex_hull names it),
and enclosing its convex hull's volume (this catches reflex vertices that lie on a hull
face, such as an L-shaped prism's).

Names and fixed blocks, so that a round trip keeps them (:func:`write_mesh` writes them so):

* OBJ: each object (``o NAME``; in a file without objects, each group ``g NAME``) is a block
  of that name; a block is fixed when its faces use the material ``fixed`` (``usemtl fixed``:
  Blender, Rhino and MeshLab keep object names and materials).
* ASCII STL: each solid (``solid NAME`` ... ``endsolid``) is a block of that name; a solid
  named ``NAME [fixed]`` is the fixed block NAME.
* Binary STL, and faces the file does not name: the file cannot say, so the blocks are the
  runs of faces that close a surface, in file order (mesh writers write each solid's faces one
  after another), named ``part0``, ``part1``, ...; :func:`read_mesh` returns a note saying so.

The readers are drydem's own, not meshio's: meshio's OBJ reader drops objects, groups and
materials, and its ASCII STL reader drops solid names and skips lines unchecked; both formats
are a handful of statements. Every error names the file and the line (or binary triangle).
"""

from __future__ import annotations

import codecs
import math
import re
from dataclasses import dataclass, field
from itertools import chain, count
from pathlib import Path

import numpy as np

from drydem.errors import ModelError
from drydem.files import PLAIN_INTEGER, PLAIN_NUMBER, regular_file, write_text
from drydem.model.geometry import convex_hull, far_vertex_problem
from drydem.model.assembly import Block, Model
from drydem.model.parameters import FILE_PATH, NAME, InstanceOf, Range, check_arguments, shown

#: vertices closer than this fraction of the mesh's size are one vertex
MERGE_FRACTION = 1e-9
#: a surface enclosing less than (1 - this) of its convex hull's volume is not convex
CONVEX_VOLUME_TOLERANCE = 1e-6
#: the OBJ material of fixed blocks, and the one written for the others
FIXED_MATERIAL, MOVABLE_MATERIAL = "fixed", "block"
#: the end of an STL solid's name that marks it fixed
FIXED_SOLID = " [fixed]"
#: binary STL: an 80-byte header, the triangle count, then 50 bytes per triangle
STL_TRIANGLE = np.dtype([("normal", "<f4", 3), ("vertices", "<f4", (3, 3)), ("attribute", "<u2")])
#: the size of a file's coordinate unit, m (``unit_m`` of the readers: 0.001 for millimetres): a
#: finite number > 0 (0 would collapse the blocks, a negative one mirror the model, nan and a
#: boolean are no size)
UNIT = Range(0.0, None, low_open=True, unit="m")
#: the suffixes :func:`write_mesh` writes, and the format of each
WRITTEN_SUFFIXES = {".obj": "OBJ", ".stl": "ASCII STL"}


@dataclass
class _Solid:
    """Faces read as one named block, or as blocks to tell apart (name None: the file gives
    none): the faces (indices into the file's points), where each is in the file (line or
    triangle) and whether each is marked fixed; what the file calls it (object, group, solid)
    and the lines that give its name."""

    name: str | None
    kind: str = "solid"
    named: list[int] = field(default_factory=list)
    faces: list[list[int]] = field(default_factory=list)
    origins: list[str] = field(default_factory=list)
    fixed: list[bool] = field(default_factory=list)

    def add(self, face: list[int], origin: str, fixed: bool) -> None:
        self.faces.append(face)
        self.origins.append(origin)
        self.fixed.append(fixed)


class _Names:
    """The names a generator gives, by position, each made once and kept (a run's name is asked
    for twice: for an error while its faces are read, and for its block)."""

    def __init__(self, names):
        self._names, self._made = names, []

    def __getitem__(self, k: int) -> str:
        while len(self._made) <= k:
            self._made.append(next(self._names))
        return self._made[k]


def _free(names, taken: frozenset[str]):
    """``names`` but those in ``taken`` (the names the file gives its solids: an object 'A' of
    two blocks beside an object 'A-2' gave two blocks 'A-2')."""
    return (name for name in names if name not in taken)


def check_reader_arguments(where: str, path, unit_m) -> None:
    """ModelError naming ``WHERE`` (a reader) and its argument that is not what it must be: ``path``
    a file path, ``unit_m`` (:data:`UNIT`) a number > 0: each reader checks them where it starts."""
    check_arguments(where, {"path": FILE_PATH, "unit_m": UNIT}, path=path, unit_m=unit_m)


def read_mesh(path: str | Path, *, unit_m: float = 1.0) -> tuple[list[Block], list[str]]:
    """The blocks of an OBJ or STL file (coordinates times ``unit_m``, m: :data:`UNIT`) and notes
    on what the file does not say (block names). See the module docstring for names and fixed blocks."""
    check_reader_arguments("read_mesh", path, unit_m)
    path = Path(path)
    try:
        data = regular_file(path, "an OBJ or STL file").read_bytes()  # a pipe would be waited on forever
    except OSError as exc:
        raise ModelError(f"{path}: cannot read: {exc.strerror or exc}") from None
    reader = _read_obj if path.suffix.lower() == ".obj" else _read_stl
    points, solids, notes = reader(path, data)
    if not any(s.faces for s in solids):
        raise ModelError(f"{path}: no faces: the file holds no block")
    points = np.asarray(points, dtype=float) * unit_m
    far = far_vertex_problem(points)  # before merging: a vertex at 1e11 m made the merge radius swallow whole blocks
    if far is not None:
        raise ModelError(f"{path}: {far}")
    points, merged = _merged(points, [face for s in solids for face in s.faces])
    blocks, start, unnamed, renamed = [], 0, 0, []
    taken = frozenset(s.name for s in solids if s.name is not None)
    parts = _Names(_free((f"part{n}" for n in count()), taken))  # the unnamed runs of the whole file
    for solid in solids:
        faces, start = merged[start:start + len(solid.faces)], start + len(solid.faces)
        # a solid's runs: its name, then NAME-2, NAME-3, ...; unnamed ones the next parts
        names, first = (parts, unnamed) if solid.name is None else \
            (_Names(chain([solid.name], _free((f"{solid.name}-{n}" for n in count(2)), taken))), 0)
        runs = _closed_runs(faces, solid.origins, lambda k, names=names, first=first: f"{path}: {names[first + k]!r}")
        for k, (a, b) in enumerate(runs):
            name, fixed = names[first + k], solid.fixed[a:b]
            if name not in NAME:  # found by a hunt: a NUL in an object's name was refused naming neither file nor line
                raise ModelError(f"{path}: line {solid.named[0]}: {solid.kind} name {shown(name)}: {NAME}")
            where = f"{path}: {name!r}"
            if any(fixed) and not all(fixed):
                raise ModelError(f"{where}: {sum(fixed)} of its {b - a} faces are marked fixed (from {solid.origins[a + fixed.index(True)]}), "
                                 f"the others not; a fixed block has all its faces in the material {FIXED_MATERIAL!r}")
            block = closed_convex_block(points, faces[a:b], name=name, where=where)  # its faces wound one way, as VRML's and compas'
            blocks.append(Block(name=name, shape=block.shape, fixed=all(fixed)))
        unnamed += len(runs) if solid.name is None else 0
        renamed += _renamed(path, solid, [names[first + k] for k in range(len(runs))])
    if unnamed:
        what = "a binary STL names no block" if _is_binary_stl(path, data) else "some faces are in no named object or solid"
        skip = ", skipping the names of the file's objects" if any(re.fullmatch(r"part\d+", name) for name in taken) else ""
        notes.append(f"{path}: {what}: {unnamed} block(s) are named part0, part1, ... in file order{skip}")
    return blocks, notes + renamed


def _renamed(path: Path, solid: _Solid, names: list[str]) -> list[str]:
    """A note on a named solid whose faces close several surfaces, so several blocks (NAME,
    NAME-2, ...): where the file gives the name (more than once: an OBJ adds each statement's
    faces to one object of that name) and what the blocks are named."""
    if solid.name is None or len(names) < 2:
        return []
    lines = _first_few(list(map(str, solid.named)))
    given = (f"is named on lines {lines} (the name occurs {len(solid.named)} times in the file)" if len(solid.named) > 1
             else f"(line {lines})")
    return [f"{path}: the {solid.kind} {solid.name!r} {given}: its faces close {len(names)} surfaces, "
            f"read as {len(names)} blocks named {_first_few(list(map(repr, names)))}"]


def _first_few(items: list[str], shown_items: int = 5) -> str:
    """The first ``shown_items`` of ``items`` joined, and how many more (a note on 5,000 cubes in
    one group listed every line and name: 113 kB)."""
    more = len(items) - shown_items
    return ", ".join(items[:shown_items]) + (f", ... ({more} more)" if more > 0 else "")


def write_mesh(model: Model, path: str | Path) -> None:
    """Every block as a named solid in one OBJ (its faces as polygons) or ASCII STL file (as
    triangles), by the suffix; fixed blocks marked as the module docstring says. Coordinates
    are written to full double precision, so the blocks read back as they were. ModelError for
    another suffix (:data:`WRITTEN_SUFFIXES`) or an argument that is not what it must be."""
    check_arguments("write_mesh", {"model": InstanceOf(Model), "path": FILE_PATH}, model=model, path=path)
    path = Path(path)
    if path.suffix.lower() not in WRITTEN_SUFFIXES:
        raise ModelError(f"write_mesh path = {shown(str(path))}: the suffix {path.suffix!r} is no mesh format written here; "
                         f"give one of {', '.join(WRITTEN_SUFFIXES)} ({', '.join(WRITTEN_SUFFIXES.values())})")
    fixed = model.block_fixed.all(axis=1)
    for name in model.block_name:
        if name != name.strip() or len(name.splitlines()) != 1 or name.endswith(FIXED_SOLID):
            raise ModelError(f"{model.source}: block {name!r}: a mesh file cannot keep this name (empty, surrounding "
                             f"blanks, a line break, or ending in {FIXED_SOLID.strip()!r}); rename the block")
    writer = _obj_text if path.suffix.lower() == ".obj" else _stl_text
    text = writer(model, fixed)
    write_text(path, text)


def closed_convex_block(points: np.ndarray, faces: list[list[int]], *, name: str, where: str) -> Block:
    """The block bounded by ``faces`` (vertex indices into ``points``, m): the surface must be
    closed (each edge in two faces), its faces wound consistently (all counter-clockwise or all
    clockwise seen from outside: each edge run one way by one face and the other way by the
    other, without which its enclosed volume means nothing) and its vertices in convex position.
    Errors say ``where``."""
    runs: dict[tuple[int, int], int] = {}
    for face in faces:
        for a, b in zip(face, face[1:] + face[:1]):
            runs[(a, b)] = runs.get((a, b), 0) + 1
    edges: dict[tuple[int, int], int] = {}
    for (a, b), n in runs.items():
        edges[(min(a, b), max(a, b))] = edges.get((min(a, b), max(a, b)), 0) + n
    bad = [(edge, n) for edge, n in edges.items() if n != 2]
    if bad:
        (a, b), n = bad[0]
        raise ModelError(f"{where}: the surface is not closed: the edge {points[a].tolist()} - {points[b].tolist()} "
                         f"belongs to {n} face(s), not 2 ({len(bad)} such edges)")
    same_way = [edge for edge, n in runs.items() if n > 1]
    if same_way:
        a, b = same_way[0]
        raise ModelError(f"{where}: the faces do not wind consistently: the edge {points[a].tolist()} - {points[b].tolist()} "
                         f"runs the same way in both its faces ({len(same_way)} such edges; turn the faces that wind the other way)")
    return Block(name=name, shape=_convex_shape(points, faces, where=where))


def _convex_shape(points: np.ndarray, faces: list[list[int]], *, where: str):
    """The convex polyhedron of a closed surface, which must enclose its hull's volume."""
    used = sorted({i for face in faces for i in face})
    shape = convex_hull(points[used], name=where)
    enclosed = enclosed_volume(points, faces)
    if enclosed < (1 - CONVEX_VOLUME_TOLERANCE) * shape.volume:
        raise ModelError(f"{where}: the surface is not convex: it encloses {enclosed:.6g} m3, its convex hull "
                         f"{shape.volume:.6g} m3 (split it into convex blocks)")
    return shape


def enclosed_volume(points: np.ndarray, faces: list[list[int]]) -> float:
    """Volume enclosed by a closed surface, m3: sum over face fans of det(a, b, c) / 6 (divergence
    theorem), made positive (the faces may wind either way, consistently)."""
    total = 0.0
    for face in faces:
        a = points[face[0]]
        for b, c in zip(face[1:-1], face[2:]):
            total += float(np.dot(a, np.cross(points[b], points[c])))
    return abs(total) / 6.0


#: the OBJ statements that do not shape blocks (normals, texture coordinates, smoothing, lines,
#: free-form geometry, display attributes: Wavefront's OBJ specification); any other is noted
OBJ_OTHER_STATEMENTS = frozenset(
    "vt vn vp s l p mtllib usemap maplib cstype deg bmat step curv curv2 surf parm trim hole scrv sp end con mg lod bevel "
    "c_interp d_interp trace_obj shadow_obj ctech stech call csh".split())
#: the numbers an OBJ vertex may give after x y z: none, w, or a colour r g b
OBJ_VERTEX_EXTRAS = (0, 1, 3)


def _read_obj(path: Path, data: bytes) -> tuple[list[list[float]], list[_Solid], list[str]]:
    """Vertices, solids and notes of an OBJ file: ``v``, ``f`` (``i``, ``i/t``, ``i/t/n``,
    ``i//n``; negative indices count back from the last vertex), ``o``, ``g``, ``usemtl``; the
    statements of :data:`OBJ_OTHER_STATEMENTS` do not shape blocks; any other is not OBJ (a
    typo: ``V 1 1 1``), skipped and named in a note (found by a hunt: skipped without a word)."""
    points: list[list[float]] = []
    unknown: dict[str, int] = {}  # a statement that is not OBJ, and the first line it is on
    faces = []  # (line, object, group, material, vertex indices)
    obj = group = material = None
    stated: dict[str, dict[str, list[int]]] = {"o": {}, "g": {}}  # the lines naming each object and group
    for number, line in enumerate(_text(path, data).splitlines(), start=1):
        words = line.split()
        if not words or words[0].startswith("#"):
            continue
        key, rest = words[0], line.strip()[len(words[0]):].strip() or None
        if key == "v":
            points.append(_coordinates(words[1:], f"{path}: line {number}: vertex {len(points) + 1}", extras=OBJ_VERTEX_EXTRAS))
        elif key == "f":
            faces.append((number, obj, group, material, _face(words[1:], len(points), f"{path}: line {number}")))
        elif key == "o":
            obj = rest
        elif key == "g":
            group = rest
        elif key == "usemtl":
            material = rest
        elif key not in OBJ_OTHER_STATEMENTS:
            unknown.setdefault(key, number)
        if key in stated and rest is not None:
            stated[key].setdefault(rest, []).append(number)
    for number, *_, face in faces:
        if max(face) >= len(points):
            raise ModelError(f"{path}: line {number}: the face refers to vertex {shown(max(face) + 1)}; the file has {len(points)}")
    by_object = any(obj is not None for _, obj, *_ in faces)
    kind, statement = ("object", "o") if by_object else ("group", "g")
    solids: dict[str | None, _Solid] = {}  # a name seen again adds faces to its solid, as OBJ groups do
    for number, obj, group, material, face in faces:
        name = obj if by_object else group
        solid = solids.setdefault(name, _Solid(name, kind, stated[statement].get(name, [])))
        solid.add(face, f"line {number}", (material or "").lower() == FIXED_MATERIAL)
    notes = [f"{path}: not OBJ statements, skipped: " + _first_few([f"{shown(key)} (line {line})" for key, line in unknown.items()])]
    return points, list(solids.values()), notes if unknown else []


def _face(words: list[str], count: int, where: str) -> list[int]:
    """0-based vertex indices of an OBJ face (its vertex references, ``count`` vertices read so far)."""
    if len(words) < 3:
        raise ModelError(f"{where}: a face needs at least 3 vertices, this one has {len(words)}")
    indices = []
    for word in words:
        index = _vertex_reference(word, where)
        if index == 0 or index < -count:
            raise ModelError(f"{where}: the face refers to vertex {shown(index)}, which does not exist "
                             f"({count} vertices so far; numbers start at 1, negative ones count back)")
        indices.append(index - 1 if index > 0 else count + index)
    return indices


def _vertex_reference(word: str, where: str) -> int:
    """The vertex number of a face's vertex reference ``v``, ``v/vt``, ``v/vt/vn`` or ``v//vn``:
    whole numbers, the texture and normal ones (not used) left out or empty."""
    parts = word.split("/")
    if not PLAIN_INTEGER.fullmatch(parts[0]):
        raise ModelError(f"{where}: {shown(word)} is not a vertex number")
    if len(parts) > 3:
        raise ModelError(f"{where}: {shown(word)}: a face's vertex is v, v/vt, v/vt/vn or v//vn, not {len(parts)} numbers")
    for what, part in zip(("texture", "normal"), parts[1:]):
        if part and not PLAIN_INTEGER.fullmatch(part):
            raise ModelError(f"{where}: {shown(word)}: the {what} index {shown(part)} is not a whole number "
                             "(a face's vertex is v, v/vt, v/vt/vn or v//vn; vt and vn may be left out)")
    try:
        return int(parts[0])
    except ValueError:  # past Python's limit on the digits of an integer
        raise ModelError(f"{where}: {shown(word)} is not a vertex number ({len(parts[0]):,} digits)") from None


def _read_stl(path: Path, data: bytes) -> tuple[list[list[float]], list[_Solid], list[str]]:
    """Vertices and solids of a binary or ASCII STL file, told apart by the size: a binary file
    is 84 + 50 n bytes for the n triangles its header counts (some start with "solid" too)."""
    if _is_binary_stl(path, data):
        triangles = np.frombuffer(data, dtype=STL_TRIANGLE, offset=84)["vertices"].astype(float)
        bad = np.flatnonzero(~np.isfinite(triangles).all(axis=(1, 2)))
        if len(bad):
            raise ModelError(f"{path}: binary triangle {bad[0]}: a vertex is not a finite number ({len(bad)} such triangles)")
        solid = _Solid(None, faces=np.arange(3 * len(triangles)).reshape(-1, 3).tolist(),
                       origins=[f"triangle {k}" for k in range(len(triangles))], fixed=[False] * len(triangles))
        return triangles.reshape(-1, 3).tolist(), [solid], []
    if not data.removeprefix(codecs.BOM_UTF8).lstrip().startswith(b"solid"):
        if len(data) < 84:
            raise ModelError(f"{path}: not an STL file: it does not start with 'solid' (ASCII), and its {len(data)} bytes are "
                             "too few for a binary STL (an 80-byte header and a 4-byte triangle count, then 50 bytes a triangle)")
        count = int.from_bytes(data[80:84], "little")
        raise ModelError(f"{path}: not an STL file: it does not start with 'solid' (ASCII), and its {len(data)} bytes are not "
                         f"84 + 50 x {count} (binary, {count} triangles by its header)")
    return *_read_ascii_stl(path, _text(path, data)), []


def _is_binary_stl(path: Path, data: bytes) -> bool:
    return path.suffix.lower() == ".stl" and len(data) >= 84 and len(data) == 84 + 50 * int.from_bytes(data[80:84], "little")


def _read_ascii_stl(path: Path, text: str) -> tuple[list[list[float]], list[_Solid]]:
    """``solid NAME``, then facets (``facet normal``, ``outer loop``, three ``vertex x y z``,
    ``endloop``, ``endfacet``), ``endsolid`` (``endsolid NAME``: the name of the solid it
    closes); one or more solids. The normals are not used (drydem orients faces itself), but
    must be three finite numbers, as the vertices; each statement is checked in its place."""
    points: list[list[float]] = []
    solids: list[_Solid] = []
    solid = facet = None
    number = 0
    for number, line in enumerate(text.splitlines(), start=1):
        words = line.split()
        if not words:
            continue
        where, key = f"{path}: line {number}", words[0].lower()
        expected = {"solid": solid is None, "facet": solid is not None and facet is None, "outer": facet is not None,
                    "vertex": facet is not None, "endloop": facet is not None, "endfacet": facet is not None,
                    "endsolid": solid is not None and facet is None}
        if key not in expected:
            raise ModelError(f"{where}: {words[0]!r} is not an ASCII STL statement")
        if not expected[key]:
            place = "inside a facet" if facet is not None else "inside a solid" if solid is not None else "outside any solid"
            raise ModelError(f"{where}: {words[0]!r} is out of place ({place})")
        if key == "solid":
            name = line.strip()[len(words[0]):].strip() or None
            fixed = name is not None and name.endswith(FIXED_SOLID)
            solid = _Solid(name[: -len(FIXED_SOLID)] if fixed else name, "solid", [number])
            solids.append(solid)
        elif key in ("outer", "endloop", "endfacet") and words[1:] != (["loop"] if key == "outer" else []):
            statement = "outer loop" if key == "outer" else key
            raise ModelError(f"{where}: {shown(line.strip())}: the statement is {statement}, alone on its line")
        if key == "facet":  # its normal is not used, but read: a NaN there is a damaged file
            if len(words) < 2 or words[1].lower() != "normal":
                raise ModelError(f"{where}: {shown(line.strip())}: a facet begins 'facet normal nx ny nz'")
            _coordinates(words[2:], where, "a facet normal")
            facet, start = [], number
        elif key == "vertex":
            if len(facet) == 3:
                raise ModelError(f"{where}: a fourth vertex in the facet of line {start}: an STL facet is a triangle, 3 vertices")
            facet.append(len(points))
            points.append(_coordinates(words[1:], f"{where}: vertex"))
        elif key == "endfacet":
            if len(facet) != 3:
                raise ModelError(f"{where}: the facet has {len(facet)} vertices; it needs 3 (an STL facet is a triangle)")
            solid.add(facet, f"line {start}", fixed)
            facet = None
        elif key == "endsolid":
            _check_endsolid(line.strip()[len(words[0]):].strip(), name, solid.named[0], where)
            solid = None
    if solid is not None:
        inside = "a nameless solid" if solid.name is None else f"the solid {solid.name!r}"
        raise ModelError(f"{path}: line {number}: the file ends inside {inside} (no endsolid): is it cut short?")
    return points, solids


def _check_endsolid(closing: str, opened: str | None, line: int, where: str) -> None:
    """The rule on ``endsolid NAME``: the name, when given, is the one of the solid it closes
    (``opened``, given on ``line``; a file cut inside the line, or solids mixed up, differ), its
    spacing aside; after a nameless ``solid``, any name is taken."""
    if closing and opened and closing.split() != opened.split():  # spacing aside; a nameless solid takes any
        raise ModelError(f"{where}: endsolid names {shown(closing)}, but it closes the solid {shown(opened or '')} of line "
                         f"{line}: the name after endsolid, when given, must be the solid's (is the file cut short?)")


def _coordinates(words: list[str], where: str, what: str = "a vertex", extras: tuple[int, ...] = (0,)) -> list[float]:
    """x, y, z: three finite numbers, then as many more as one of ``extras`` allows (an OBJ
    vertex's w or colour, which are not used; found by a hunt: ``v 1 1 1 abc`` and STL's
    ``vertex 1 2 3 7 junk`` were read), each a :data:`~drydem.files.PLAIN_NUMBER` (float() also
    takes 1_0 for 10); ``what`` they are, in the message."""
    if not all(PLAIN_NUMBER.fullmatch(w) for w in words):
        raise ModelError(f"{where}: {shown(' '.join(words))}: the coordinates must be numbers")
    numbers = [float(w) for w in words]
    if len(numbers) < 3 or not all(map(math.isfinite, numbers)):
        raise ModelError(f"{where}: {shown(' '.join(words))}: {what} needs three finite numbers x y z")
    if len(numbers) - 3 not in extras:
        forms = [{0: "x y z", 1: "x y z w", 3: "x y z r g b"}[n] for n in extras]
        raise ModelError(f"{where}: {shown(' '.join(words))}: {len(numbers)} numbers; {what} is "
                         f"{', '.join(forms[:-1]) + ' or ' if len(forms) > 1 else ''}{forms[-1]}")
    return numbers[:3]


def _text(path: Path, data: bytes) -> str:
    """``data`` as UTF-8 text, a byte order mark at its start dropped (found by a hunt: it was
    read as part of the first statement, whose name or vertex was lost)."""
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise ModelError(f"{path}: not a text file (byte {exc.start} is not UTF-8)") from None


def _obj_text(model: Model, fixed: np.ndarray) -> str:
    lines = [f"# {model.n_blocks} blocks of {model.source}, written by drydem: one object per block; "
             f"fixed blocks use the material {FIXED_MATERIAL!r}"]
    offset = 1
    for name, shape, is_fixed in zip(model.block_name, model.block_shape, fixed):
        lines += [f"o {name}", f"usemtl {FIXED_MATERIAL if is_fixed else MOVABLE_MATERIAL}"]
        lines += [f"v {x!r} {y!r} {z!r}" for x, y, z in shape.vertices.tolist()]
        lines += ["f " + " ".join(str(offset + i) for i in face) for face in shape.faces]
        offset += len(shape.vertices)
    return "\n".join(lines) + "\n"


def _stl_text(model: Model, fixed: np.ndarray) -> str:
    lines = []
    for name, shape, is_fixed in zip(model.block_name, model.block_shape, fixed):
        solid = name + FIXED_SOLID if is_fixed else name
        lines.append(f"solid {solid}")
        for face, (nx, ny, nz) in zip(shape.faces, shape.face_normals.tolist()):
            for i in range(1, len(face) - 1):
                lines += [f"facet normal {nx!r} {ny!r} {nz!r}", "outer loop"]
                lines += [f"vertex {x!r} {y!r} {z!r}" for x, y, z in shape.vertices[[face[0], face[i], face[i + 1]]].tolist()]
                lines += ["endloop", "endfacet"]
        lines.append(f"endsolid {solid}")
    return "\n".join(lines) + "\n"


def _merged(points: np.ndarray, faces: list[list[int]]) -> tuple[np.ndarray, list[list[int]]]:
    """Coincident vertices made one (STL repeats every vertex in each triangle)."""
    size = float(np.ptp(points, axis=0).max()) or 1.0
    keys = np.round(points / (MERGE_FRACTION * size)).astype(np.int64)
    _, first, inverse = np.unique(keys, axis=0, return_index=True, return_inverse=True)
    inverse = inverse.ravel()
    return points[first], [[int(inverse[i]) for i in face] for face in faces]


def _closed_runs(faces: list[list[int]], origins: list[str], where) -> list[tuple[int, int]]:
    """The faces split into runs that each close a surface, in file order.

    Touching blocks share vertices and edges, so the surfaces cannot be told apart by
    connectivity; but mesh writers (Rhino, CAD exports, :func:`write_mesh`) write each solid's
    faces one after another. A run ends as soon as each of its edges is in exactly two faces.
    Returns each run as (first, end) face positions. ``where(k)`` names the k-th run in
    errors; ``origins`` says where each face is in the file.
    """
    runs, start, edges, unpaired = [], 0, {}, 0
    for end, face in enumerate(faces, start=1):
        for a, b in zip(face, face[1:] + face[:1]):
            key = (min(a, b), max(a, b))
            count = edges.get(key, 0) + 1
            edges[key] = count
            unpaired += {1: 1, 2: -1, 3: 1}.get(count, 0)  # edges in other than two faces
        if unpaired == 0:
            runs.append((start, end))
            start, edges = end, {}
    if start < len(faces):
        raise ModelError(f"{where(len(runs))} (from {origins[start]}) is not a closed surface: "
                         f"{unpaired} edge(s) are not in exactly two faces")
    return runs
