"""Blocks from compas JSON files (compas meshes, compas_dem block models) and blocks to them.

compas (https://compas.dev, ``compas.json_dump``; compas/data/encoders.py) writes each object
as ``{"dtype": "package.module/Class", "data": {...}, "name": ..., "guid": ...}``, a subclass
listing its parents' dtypes under ``"inheritance"``. drydem parses these files itself, without
compas, and reads:

* a compas Mesh (dtype ``compas.datastructures/Mesh``; compas/datastructures/mesh/mesh.py,
  ``Mesh.__data__``): ``data["vertex"]`` maps each vertex key (an integer, as a string) to its
  attributes ``x``, ``y``, ``z`` (one that is missing takes ``data["default_vertex_attributes"]``'s
  value); ``data["face"]`` maps each face key to its vertex keys, counter-clockwise seen from
  outside; ``data["attributes"]`` holds the mesh's own attributes. The block is named after the
  mesh (its ``"name"``) and is fixed when ``attributes["is_support"]`` is true, the key with
  which compas_dem's vault templates mark supports (compas_dem/models/blockmodel.py,
  ``BlockModel.from_barrelvault``);
* a list of meshes, or an object mapping block names to meshes;
* a compas_dem block model (dtype ``compas_dem.models/BlockModel``, or any model whose
  ``inheritance`` names ``compas_model.models/Model``; compas_model/models/model.py,
  ``Model.__data__``): ``data["elements"]`` maps guids to elements, each a block
  (compas_dem/elements/block.py, ``Block.__data__``): ``"geometry"`` a Mesh in the element's
  frame, ``"transformation"`` null or a compas Transformation (``{"matrix": 4 x 4}``),
  ``"is_support"`` (the block is fixed), ``"name"``, ``"material"`` null or the guid of one of
  ``data["materials"]``, whose ``"density"`` (kg/m3), if it has one, is the block's.
  ``data["tree"]`` nests the elements: an element's geometry goes to the model by its own
  transformation, then its parents', then the model's ``data["transformation"]``
  (compas_model/elements/element.py, ``Element.compute_modeltransformation``; a 4 x 4 matrix
  acts on homogeneous points, as compas.geometry.transform_points, and must be affine, its last
  row 0 0 0 1). ``data["graph"]["node"]`` gives each element its graph node, the block index of compas_dem's ``BlockModel.add_support``;
  the blocks are read in that order. The contacts on the graph's edges are not read (drydem
  finds its own); modifiers (cuts of one element by another) are refused; features are not
  read, as compas_dem's ``Block.compute_elementgeometry`` does not apply them.

Names that several blocks share (compas names every mesh made from a box ``Box`` and every
compas_dem block ``Block``) get their position appended (``Block-3``: the graph node or the
index in the list), and a note says so. Each block must be a closed convex surface
(drydem.io.mesh.closed_convex_block); errors name the file and the mesh or element.

:func:`write_compas` writes a JSON list of compas Meshes, one per block in model order: named
after the block, ``attributes["is_support"]`` its fixed flag, vertex keys 0, 1, ... in the
block's vertex order, faces as drydem orients them (counter-clockwise seen from outside, as
compas expects), no guid (compas makes one on loading; the same model gives the same file).
``compas.json_load`` returns the list of Meshes; in compas_dem, each goes to a BlockModel by
``add_support_from_mesh`` or ``add_block_from_mesh`` after its ``attributes["is_support"]``.
"""

from __future__ import annotations

import json
import math
import sys
from dataclasses import dataclass, replace
from functools import partial
from pathlib import Path

import numpy as np

from drydem.errors import ModelError
from drydem.files import PLAIN_INTEGER, read_text, write_text
from drydem.io.mesh import check_reader_arguments, closed_convex_block
from drydem.model.assembly import Block, Model
from drydem.model.parameters import DENSITY, FILE_PATH, InstanceOf, check_arguments, shown

MESH_DTYPE = "compas.datastructures/Mesh"
MODEL_DTYPE = "compas_model.models/Model"
#: compas_dem's block model, read as a model even where its "inheritance" is left out
BLOCK_MODEL_DTYPE = "compas_dem.models/BlockModel"
#: compas's transformations (compas/geometry/transformations), each ``{"matrix": 4 x 4}``
TRANSFORMATION_DTYPES = tuple(f"compas.geometry/{kind}" for kind in
                              ("Transformation", "Translation", "Rotation", "Scale", "Reflection", "Projection", "Shear"))
#: the mesh attribute (and compas_dem element key) that marks a fixed block
SUPPORT_KEY = "is_support"
#: the most digits of a JSON integer: Python's own limit on reading one (int() of a longer digit
#: string is refused, as it takes time quadratic in its length); no number drydem reads is that long
MAX_INTEGER_DIGITS = sys.int_info.default_max_str_digits
#: what drydem reads, for messages
READS = "a compas Mesh, a list or object of Meshes, or a compas_dem BlockModel (as compas.json_dump writes them)"


@dataclass(frozen=True)
class _Part:
    """A mesh to make a block of: its name in the file, its position (list index or graph
    node, appended to a shared name), the mesh's JSON, the 4 x 4 matrix placing it, whether it
    is fixed, its density (kg/m3, None: the model's) and where it is, for messages."""

    name: str
    index: int
    mesh: dict
    matrix: np.ndarray
    fixed: bool
    density: float | None
    where: str


def read_compas(path: str | Path, *, unit_m: float = 1.0) -> tuple[list[Block], list[str]]:
    """The blocks of a compas JSON file (coordinates times ``unit_m``, m: drydem.io.mesh.UNIT) and
    notes on what was assumed (names made unique). See the module docstring for the formats."""
    check_reader_arguments("read_compas", path, unit_m)
    path = Path(path)
    text = read_text(path, f"drydem reads {READS}")
    try:
        data = json.loads(text, parse_int=partial(_integer, source=str(path)), object_pairs_hook=partial(_unique, source=str(path)))
    except json.JSONDecodeError as exc:
        raise ModelError(f"{path}: not JSON: {exc.msg} at line {exc.lineno}, column {exc.colno}; drydem reads {READS}") from None
    except RecursionError:
        raise ModelError(f"{path}: its JSON is nested too deeply to read; drydem reads {READS}") from None
    with np.errstate(over="ignore", invalid="ignore"):  # a matrix past the float range: the block refuses inf
        parts = _parts(data, str(path))
    if not parts:
        raise ModelError(f"{path}: no mesh: the file holds no block")
    counts: dict[str, int] = {}
    for part in parts:
        counts[part.name] = counts.get(part.name, 0) + 1
    with np.errstate(over="ignore", invalid="ignore"):
        blocks = [_block(part, part.name if counts[part.name] == 1 else f"{part.name}-{part.index}", unit_m) for part in parts]
    shared = [name for name, n in counts.items() if n > 1]
    notes = [f"{path}: {sum(counts[n] for n in shared)} blocks share the names {', '.join(map(repr, shared))}: "
             f"each is named NAME-N after its position in the file (graph node or list index)"] if shared else []
    return blocks, notes + [note for part in parts if (note := _unused_vertices(part)) is not None]


def _unused_vertices(part: _Part) -> str | None:
    """A note naming the vertices of a part's mesh that no face uses (legal in compas, say after
    faces were deleted; the block is its faces' surface, so they are left out), None if none."""
    data = part.mesh["data"]
    used = {str(key) for face in data["face"].values() for key in face}
    unused = [key for key in data["vertex"] if key not in used]
    if not unused:
        return None
    shown_keys = ", ".join(unused[:5]) + (f" and {len(unused) - 5} more" if len(unused) > 5 else "")
    return f"{part.where}: vertices {shown_keys} are used by no face: left out of the block"


def _integer(digits: str, source: str) -> int:
    """A JSON integer of at most MAX_INTEGER_DIGITS digits."""
    if len(digits.lstrip("-")) > MAX_INTEGER_DIGITS:
        raise ModelError(f"{source}: an integer of {len(digits.lstrip('-')):,} digits ({digits[:12]}...): more than the "
                         f"{MAX_INTEGER_DIGITS:,} digits an integer may have; drydem reads {READS}")
    return int(digits)


def _unique(pairs: list[tuple[str, object]], source: str) -> dict:
    """A JSON object whose keys are each given once (json.loads keeps a repeated key's last
    value: a block or a vertex dropped without a word)."""
    data = dict(pairs)
    if len(data) < len(pairs):
        seen: set[str] = set()
        key = next(key for key, _ in pairs if key in seen or seen.add(key))
        raise ModelError(f"{source}: the key {shown(key)} occurs more than once in one JSON object: each key of an object must be "
                         f"given once (the second would replace the first); drydem reads {READS}")
    return data


def write_compas(model: Model, path: str | Path) -> None:
    """Every block as a compas Mesh in a JSON list (see the module docstring), coordinates to
    full double precision so that the blocks read back as they were."""
    check_arguments("write_compas", {"model": InstanceOf(Model), "path": FILE_PATH}, model=model, path=path)
    fixed = model.block_fixed.all(axis=1)
    meshes = [_mesh_json(name, shape, bool(is_fixed))
              for name, shape, is_fixed in zip(model.block_name, model.block_shape, fixed)]
    write_text(path, json.dumps(meshes, indent=1) + "\n")


def _mesh_json(name: str, shape, fixed: bool) -> dict:
    """A block's shape as compas's Mesh.__data__ lays it out."""
    vertices = {str(i): dict(zip("xyz", xyz)) for i, xyz in enumerate(shape.vertices.tolist())}
    faces = {str(f): [int(i) for i in face] for f, face in enumerate(shape.faces)}
    data = {"attributes": {SUPPORT_KEY: fixed}, "default_vertex_attributes": {"x": 0.0, "y": 0.0, "z": 0.0},
            "default_edge_attributes": {}, "default_face_attributes": {}, "vertex": vertices, "face": faces,
            "facedata": {f: {} for f in faces}, "edgedata": {}, "max_vertex": len(vertices) - 1, "max_face": len(faces) - 1}
    return {"dtype": MESH_DTYPE, "data": data, "name": name}


#: the JSON name of each kind of value Python's json makes
JSON_KINDS = {type(None): "null", bool: "true or false", int: "number", float: "number", str: "string", list: "array", dict: "object"}


def _parts(data, source: str) -> list[_Part]:
    """The meshes of the file's top-level value, by its kind."""
    if isinstance(data, list):
        return [_mesh_part(item, _name(item, f"{source}: mesh {k}"), k, f"{source}: mesh {k}") for k, item in enumerate(data)]
    if not isinstance(data, dict):
        raise ModelError(f"{source}: the file holds a JSON {JSON_KINDS.get(type(data), type(data).__name__)}; drydem reads {READS}")
    if "dtype" not in data:
        blank = [key for key in data if not key.strip()]
        if blank:  # found by a hunt: the key "" was taken, the block called "Mesh"
            raise ModelError(f"{source}: the key {blank[0]!r} is blank: the keys of an object of meshes are their blocks' names")
        return [_mesh_part(item, key, k, f"{source}: mesh") for k, (key, item) in enumerate(data.items())]
    if _is(data, MODEL_DTYPE) or data.get("dtype") == BLOCK_MODEL_DTYPE:
        return _model_parts(data, source)
    if not _is(data, MESH_DTYPE):
        raise ModelError(f"{source}: the file holds a {data['dtype']!r}, not a {MESH_DTYPE!r} or a {MODEL_DTYPE!r}; "
                         f"drydem reads {READS}")
    return [_mesh_part(data, _name(data, source), 0, f"{source}: mesh")]


def _is(data: dict, dtype: str) -> bool:
    """Whether a compas object is of ``dtype`` or inherits from it (its "inheritance" list)."""
    inheritance = data.get("inheritance") or []
    return data.get("dtype") == dtype or (isinstance(inheritance, list) and dtype in inheritance)


def _name(data, where: str) -> str | None:
    name = data.get("name") if isinstance(data, dict) else None
    if name is not None and not isinstance(name, str):
        raise ModelError(f"{where}: the name must be a string, not {name!r}")
    if name is not None and not name.strip():  # a block's name must be a text (the model said so, without the file)
        raise ModelError(f"{where}: the name {name!r} is blank; give the mesh a name, or none (it is then called \"Mesh\")")
    return name


def _mesh_part(data, name: str | None, index: int, where: str) -> _Part:
    """A mesh of a list or an object, or the file's only one, in model coordinates; one without
    a name is called "Mesh", as compas calls it."""
    where = where if name is None else f"{where} {name!r}"
    mesh = _mesh(data, where)
    attributes = _optional_object(mesh["data"].get("attributes"), f"{where}: attributes")
    fixed = _flag(attributes.get(SUPPORT_KEY, False), f"{where}: {SUPPORT_KEY}")
    return _Part(name or "Mesh", index, mesh, np.eye(4), fixed, None, where)


def _mesh(data, where: str) -> dict:
    """``data``, checked to be a compas Mesh with a data object."""
    if not isinstance(data, dict) or "dtype" not in data:
        raise ModelError(f"{where}: not a compas object (no 'dtype'); drydem reads {READS}")
    if not _is(data, MESH_DTYPE):
        raise ModelError(f"{where}: a {data['dtype']!r}, not a {MESH_DTYPE!r}; drydem reads {READS}")
    _object(data.get("data"), f"{where}: data")
    return data


def _model_parts(data: dict, source: str) -> list[_Part]:
    """The blocks of a compas_dem BlockModel, in graph-node order, placed in model coordinates."""
    body = _object(data.get("data"), f"{source}: data")
    elements = _object(body.get("elements"), f"{source}: elements")
    materials = _optional_object(body.get("materials"), f"{source}: materials")
    graph = _object(body.get("graph"), f"{source}: graph")
    model_matrix = _matrix(body.get("transformation"), f"{source}: the model's transformation")
    parents = _parents(_object(body.get("tree"), f"{source}: tree"), elements, source)
    for edge, attributes in _edges(graph, source):
        if _object(attributes, f"{source}: graph edge {edge}").get("modifiers"):
            raise ModelError(f"{source}: graph edge {edge} has modifiers (cuts of one element by another); "
                             "drydem reads blocks as their meshes are: apply the modifiers in compas first")
    nodes = _object(graph.get("node"), f"{source}: graph nodes")
    parts, node_of = [], {}
    for node, attributes in sorted(nodes.items(), key=lambda item: _key(item[0], f"{source}: graph node")):
        guid = _object(attributes, f"{source}: graph node {node}").get("element")
        if not isinstance(guid, str) or guid not in elements:
            raise ModelError(f"{source}: graph node {node}: its element {guid!r} is not in the model's elements")
        if guid in node_of:
            raise ModelError(f"{source}: graph nodes {node_of[guid]} and {node} both hold the element {guid}: "
                             "each element is one block, on one graph node")
        node_of[guid] = node
        where = f"{source}: element {guid} (graph node {node})"
        element = _element(elements, guid, source)
        matrix = model_matrix
        for above in [*reversed(parents.get(guid, [])), guid]:  # the root's first: model T ... parent T element T
            transformation = _element(elements, above, source).get("transformation")
            matrix = matrix @ _matrix(transformation, f"{source}: element {above}: transformation")
        name = _name(element, where) or "Block"
        parts.append(_Part(name, int(node), _mesh(element.get("geometry"), f"{where}: geometry"), matrix,
                           _flag(element.get(SUPPORT_KEY, False), f"{where}: {SUPPORT_KEY}"),
                           _density(element.get("material"), materials, where), f"{where}: {name!r}"))
    _refuse_off_the_graph(elements, nodes, parents, source)
    return parts


def _refuse_off_the_graph(elements: dict, nodes: dict, parents: dict[str, list[str]], source: str) -> None:
    """ModelError naming the model's elements that are on no graph node and no ancestor in the
    tree of one that is: drydem reads the blocks from the graph's nodes, and would leave them
    out without a word (found by a hunt: an element on the tree but not the graph was dropped)."""
    on_graph = {attributes.get("element") for attributes in nodes.values() if isinstance(attributes, dict)
                and isinstance(attributes.get("element"), str)}
    grouping = {above for guid in on_graph for above in parents.get(guid, [])}
    off = sorted(guid for guid in elements if guid not in on_graph and guid not in grouping)
    if off:
        more = f" (and {len(off) - 5} more)" if len(off) > 5 else ""
        raise ModelError(f"{source}: element(s) {', '.join(map(repr, off[:5]))}{more} are on no graph node: drydem reads the "
                         "blocks from the graph's nodes, each element one block on one node (compas_model's add_element puts it there)")


def _element(elements: dict, guid: str, source: str) -> dict:
    """The data of the element ``guid``."""
    return _object(_object(elements[guid], f"{source}: element {guid}").get("data"), f"{source}: element {guid}: data")


def _edges(graph: dict, source: str) -> list[tuple[str, object]]:
    """Each edge of a compas Graph's adjacency ``edge`` (u -> v -> attributes), as (u-v, attributes)."""
    edges = _optional_object(graph.get("edge"), f"{source}: graph edges")
    return [(f"{u}-{v}", attributes)
            for u, nbrs in edges.items() for v, attributes in _object(nbrs, f"{source}: graph edge {u}").items()]


def _parents(tree: dict, elements: dict, source: str) -> dict[str, list[str]]:
    """Each element's ancestors in the model's tree (compas_model ElementNode children), nearest
    first; an element is on one tree node (it has one parent, and is not its own ancestor)."""
    parents: dict[str, list[str]] = {}

    def walk(node, above: list[str]) -> None:
        for child in _optional_list(_object(node, f"{source}: tree node").get("children"), f"{source}: tree children"):
            guid = _object(child, f"{source}: tree node").get("element")
            if guid is not None and (not isinstance(guid, str) or guid not in elements):
                raise ModelError(f"{source}: the tree names the element {guid!r}, which is not in the model's elements")
            if guid in parents:
                under = "under itself" if guid in above else "twice"
                raise ModelError(f"{source}: the tree holds the element {guid} {under}: each element is on one tree node")
            if guid is not None:
                parents[guid] = above
            walk(child, above if guid is None else [guid, *above])

    walk(_optional_object(tree.get("root"), f"{source}: tree root"), [])
    return parents


def _block(part: _Part, name: str, unit_m: float) -> Block:
    """The closed convex block of a part's mesh, placed by its matrix, times ``unit_m``."""
    data, where = part.mesh["data"], part.where
    defaults = _optional_object(data.get("default_vertex_attributes"), f"{where}: default_vertex_attributes")
    vertices = _object(data.get("vertex"), f"{where}: vertex")
    index = {key: k for k, key in enumerate(vertices)}
    points = np.array([[_number(_object(attributes, f"{where}: vertex {key}").get(axis, defaults.get(axis)),
                                f"{where}: vertex {key}: {axis}") for axis in "xyz"]
                       for key, attributes in vertices.items()], dtype=float).reshape(-1, 3)
    faces = []
    for key, face in _object(data.get("face"), f"{where}: face").items():
        face = _list(face, f"{where}: face {key}")
        if len(face) < 3:
            raise ModelError(f"{where}: face {key} has {len(face)} vertices; a face needs at least 3")
        _check_face_keys(face, f"{where}: face {key}")
        missing = [v for v in face if str(v) not in index]
        if missing:
            raise ModelError(f"{where}: face {key} refers to vertex {shown(missing[0])}, which the mesh does not have")
        faces.append([index[str(v)] for v in face])
    placed = points @ part.matrix[:3, :3].T + part.matrix[:3, 3]
    block = closed_convex_block(placed * unit_m, faces, name=name, where=where)
    return replace(block, fixed=part.fixed, density=part.density)


def _check_face_keys(face: list, where: str) -> None:
    """The rule on a face's vertices: JSON integers, the vertices' keys (as compas writes them;
    not strings, booleans or floats, which only look like them)."""
    wrong = [v for v in face if not isinstance(v, int) or isinstance(v, bool)]
    if wrong:
        raise ModelError(f"{where}: its vertex {json.dumps(wrong[0])[:40]} is not an integer: a face lists its vertices' "
                         "keys as JSON integers")


def _matrix(value, where: str) -> np.ndarray:
    """The 4 x 4 matrix of a compas Transformation (identity for null): four rows of four finite
    numbers, the last 0 0 0 1 (an affine map, as a block's placement is; a projection's is not)."""
    if value is None:
        return np.eye(4)
    value = _object(value, where)
    if value.get("dtype") not in TRANSFORMATION_DTYPES:
        raise ModelError(f"{where}: a {value.get('dtype')!r}, not a compas transformation ({', '.join(TRANSFORMATION_DTYPES)})")
    rows = [_list(row, f"{where}: matrix") for row in _list(_object(value.get("data"), f"{where}: data").get("matrix"), f"{where}: matrix")]
    if len(rows) != 4 or any(len(row) != 4 for row in rows):
        raise ModelError(f"{where}: the matrix must be 4 x 4, not rows of {', '.join(str(len(row)) for row in rows) or 'nothing'}")
    matrix = np.array([[_number(x, f"{where}: matrix") for x in row] for row in rows], dtype=float)
    if not np.array_equal(matrix[3], [0.0, 0.0, 0.0, 1.0]):
        raise ModelError(f"{where}: the matrix's last row is {matrix[3].tolist()}, not [0, 0, 0, 1]: a block is placed by an "
                         "affine transformation (a projection is not one)")
    return matrix


def _density(material, materials: dict, where: str) -> float | None:
    """The density (kg/m3) of an element's material, None if it has none (the model's default);
    in a block's range (drydem.model.parameters.DENSITY)."""
    if material is None:
        return None
    if not isinstance(material, str) or material not in materials:
        raise ModelError(f"{where}: its material {material!r} is not in the model's materials")
    density = _object(_object(materials[material], f"{where}: material").get("data"), f"{where}: material data").get("density")
    if density is None:
        return None
    density = _number(density, f"{where}: material density")
    DENSITY.check(density, f"{where}: material {material}: density")
    return density


def _key(key: str, where: str) -> int:
    """A compas Graph's node key, a whole number written in ASCII digits (int() also takes 1_0 and " 2 ")."""
    if not PLAIN_INTEGER.fullmatch(key):
        raise ModelError(f"{where} {key!r}: a key must be an integer")
    return int(key)


def _number(value, where: str) -> float:
    """A finite JSON number (a boolean is not one, nor an integer too large for a float)."""
    finite = (isinstance(value, float) and math.isfinite(value)) or (
        isinstance(value, int) and not isinstance(value, bool) and abs(value) < 1e300)
    if not finite:
        raise ModelError(f"{where}: {json.dumps(value)[:40]} is not a finite number")
    return float(value)


def _flag(value, where: str) -> bool:
    if not isinstance(value, bool):
        raise ModelError(f"{where}: {json.dumps(value)[:40]} is not true or false")
    return value


def _object(value, where: str) -> dict:
    if not isinstance(value, dict):
        raise ModelError(f"{where}: must be a JSON object, not {json.dumps(value)[:40]}")
    return value


def _optional_object(value, where: str) -> dict:
    """A JSON object that compas may leave out or write as null (then empty); anything else,
    [] or 0 or "" included, is refused as :func:`_object` refuses it."""
    return {} if value is None else _object(value, where)


def _optional_list(value, where: str) -> list:
    """A JSON list that compas may leave out or write as null (then empty), as :func:`_optional_object`."""
    return [] if value is None else _list(value, where)


def _list(value, where: str) -> list:
    if not isinstance(value, list):
        raise ModelError(f"{where}: must be a JSON list, not {json.dumps(value)[:40]}")
    return value
