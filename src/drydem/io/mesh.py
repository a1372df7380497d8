"""Blocks from surface meshes (OBJ, STL via meshio) and blocks to them.

Each closed surface of the mesh (its faces one after another in the file) becomes a block: every edge must be shared by
exactly two faces (an open mesh names its free edge), no vertex may lie inside the hull of the
others (drydem.geometry.convex_hull names it), and the surface must enclose its convex hull's
volume (this catches reflex vertices that lie on a hull face, such as an L-shaped prism's).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from drydem.errors import ModelError
from drydem.geometry import convex_hull
from drydem.model import Block, Model

#: vertices closer than this fraction of the mesh's size are one vertex
MERGE_FRACTION = 1e-9
#: a surface enclosing less than (1 - this) of its convex hull's volume is not convex
CONVEX_VOLUME_TOLERANCE = 1e-6


def read_mesh(path: str | Path, *, unit_m: float = 1.0) -> list[Block]:
    """The blocks of an OBJ or STL file (one per closed surface, its faces written one after
    another, named ``part{k}`` in file order), coordinates times ``unit_m``."""
    import meshio

    path = Path(path)
    try:
        with np.errstate(over="ignore"):  # meshio's binary-STL sniffing overflows a uint32 on ASCII files
            mesh = meshio.read(path)
    except Exception as exc:  # meshio raises many types (ReadError, ValueError, ...) for bad files
        raise ModelError(f"{path}: cannot read the mesh: {exc}") from None
    faces = [list(face) for cells in mesh.cells if cells.type in ("triangle", "quad", "polygon") for face in cells.data]
    if not faces:
        raise ModelError(f"{path}: no faces (triangles or polygons) in the mesh")
    points, faces = _merged(np.asarray(mesh.points, dtype=float) * unit_m, faces)
    return [closed_convex_block(points, part, name=f"part{k}", where=f"{path}: part {k}")
            for k, part in enumerate(_closed_runs(faces, path))]


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
    shape = convex_hull(points[used], name=where)
    enclosed = enclosed_volume(points, faces)
    if enclosed < (1 - CONVEX_VOLUME_TOLERANCE) * shape.volume:
        raise ModelError(f"{where}: the surface is not convex: it encloses {enclosed:.6g} m3, its convex hull "
                         f"{shape.volume:.6g} m3 (split it into convex blocks)")
    return Block(name=name, shape=shape)


def enclosed_volume(points: np.ndarray, faces: list[list[int]]) -> float:
    """Volume enclosed by a closed surface, m3: sum over face fans of det(a, b, c) / 6 (divergence
    theorem), made positive (the faces may wind either way, consistently)."""
    total = 0.0
    for face in faces:
        a = points[face[0]]
        for b, c in zip(face[1:-1], face[2:]):
            total += float(np.dot(a, np.cross(points[b], points[c])))
    return abs(total) / 6.0


def _merged(points: np.ndarray, faces: list[list[int]]) -> tuple[np.ndarray, list[list[int]]]:
    """Coincident vertices made one (STL repeats every vertex in each triangle)."""
    size = float(np.ptp(points, axis=0).max()) or 1.0
    keys = np.round(points / (MERGE_FRACTION * size)).astype(np.int64)
    _, first, inverse = np.unique(keys, axis=0, return_index=True, return_inverse=True)
    inverse = inverse.ravel()
    return points[first], [[int(inverse[i]) for i in face] for face in faces]


def _closed_runs(faces: list[list[int]], source: Path) -> list[list[list[int]]]:
    """The faces split into runs that each close a surface, in file order.

    Touching blocks share vertices and edges, so the surfaces cannot be told apart by
    connectivity; but mesh writers (Rhino, CAD exports, :func:`write_mesh`) write each solid's
    faces one after another. A run ends as soon as each of its edges is in exactly two faces.
    """
    runs, run, edges, unpaired = [], [], {}, 0
    for face in faces:
        run.append(face)
        for a, b in zip(face, face[1:] + face[:1]):
            key = (min(a, b), max(a, b))
            count = edges.get(key, 0) + 1
            edges[key] = count
            unpaired += {1: 1, 2: -1, 3: 1}.get(count, 0)  # edges in other than two faces
        if unpaired == 0:
            runs.append(run)
            run, edges = [], {}
    if run:
        raise ModelError(f"{source}: part {len(runs)} (from face {len(faces) - len(run)}) is not a closed surface: "
                         f"{unpaired} edge(s) are not in exactly two faces")
    return runs
