"""Blocks from surface meshes (OBJ, STL via meshio) and blocks to them.

Each connected, closed surface of the mesh becomes a block: its vertices must be the corners
of a convex polyhedron (drydem.geometry.convex_hull names the one that is not), and every
edge must be shared by exactly two faces (an open mesh names its free edge).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from drydem.errors import ModelError
from drydem.geometry import convex_hull
from drydem.model import Block, Model

#: vertices closer than this fraction of the mesh's size are one vertex
MERGE_FRACTION = 1e-9


def read_mesh(path: str | Path, *, unit_m: float = 1.0) -> list[Block]:
    """The blocks of an OBJ or STL file (one per connected closed surface, named
    ``part{k}`` in file order), coordinates times ``unit_m``."""
    import meshio

    path = Path(path)
    try:
        mesh = meshio.read(path)
    except Exception as exc:  # meshio raises many types (ReadError, ValueError, ...) for bad files
        raise ModelError(f"{path}: cannot read the mesh: {exc}") from None
    faces = [list(face) for cells in mesh.cells if cells.type in ("triangle", "quad", "polygon") for face in cells.data]
    if not faces:
        raise ModelError(f"{path}: no faces (triangles or polygons) in the mesh")
    points, faces = _merged(np.asarray(mesh.points, dtype=float) * unit_m, faces)
    return [closed_convex_block(points, part, name=f"part{k}", where=f"{path}: part {k}")
            for k, part in enumerate(_surfaces(len(points), faces))]


def write_mesh(model: Model, path: str | Path) -> None:
    """Every block's faces as triangles, in one OBJ or STL file (by the suffix)."""
    import meshio

    points, triangles = [], []
    for shape in model.block_shape:
        offset = sum(len(p) for p in points)
        points.append(shape.vertices)
        triangles += [[offset + f[0], offset + f[i], offset + f[i + 1]] for f in shape.faces for i in range(1, len(f) - 1)]
    meshio.write(path, meshio.Mesh(np.vstack(points), [("triangle", np.array(triangles))]))


def closed_convex_block(points: np.ndarray, faces: list[list[int]], *, name: str, where: str) -> Block:
    """The block bounded by ``faces`` (vertex indices into ``points``, m): the surface must be
    closed (each edge in two faces) and its vertices in convex position. Errors say ``where``."""
    edges: dict[tuple[int, int], int] = {}
    for face in faces:
        for a, b in zip(face, face[1:] + face[:1]):
            key = (min(a, b), max(a, b))
            edges[key] = edges.get(key, 0) + 1
    bad = [(edge, n) for edge, n in edges.items() if n != 2]
    if bad:
        (a, b), n = bad[0]
        raise ModelError(f"{where}: the surface is not closed: the edge {points[a].tolist()} - {points[b].tolist()} "
                         f"belongs to {n} face(s), not 2 ({len(bad)} such edges)")
    used = sorted({i for face in faces for i in face})
    return Block(name=name, shape=convex_hull(points[used], name=where))


def _merged(points: np.ndarray, faces: list[list[int]]) -> tuple[np.ndarray, list[list[int]]]:
    """Coincident vertices made one (STL repeats every vertex in each triangle)."""
    size = float(np.ptp(points, axis=0).max()) or 1.0
    keys = np.round(points / (MERGE_FRACTION * size)).astype(np.int64)
    _, first, inverse = np.unique(keys, axis=0, return_index=True, return_inverse=True)
    inverse = inverse.ravel()
    return points[first], [[int(inverse[i]) for i in face] for face in faces]


def _surfaces(n_points: int, faces: list[list[int]]) -> list[list[list[int]]]:
    """The faces grouped by connected surface (faces sharing vertices), in order of first face."""
    rows = [face[0] for face in faces for _ in face]
    cols = [i for face in faces for i in face]
    graph = coo_matrix((np.ones(len(rows)), (rows, cols)), shape=(n_points, n_points))
    _, label = connected_components(graph, directed=False)
    groups: dict[int, list[list[int]]] = {}
    for face in faces:
        groups.setdefault(int(label[face[0]]), []).append(face)
    return list(groups.values())
