"""The model to VTK unstructured grids (``.vtu``, via meshio) for ParaView.

Every block is one polyhedron cell (VTK_POLYHEDRON: its faces as vertex loops), in model
order, with cell fields ``block_id`` (index into the model's blocks), ``fixed`` (1 for a
block with all six degrees of freedom fixed), ``mass`` (kg), ``displacement`` (m, of the
centroid from the model file) and ``displacement_magnitude`` (m).
"""

from __future__ import annotations

from itertools import groupby
from pathlib import Path

import numpy as np

from drydem.model import Model
from drydem.state import State


def write_vtu(model: Model, path: str | Path, state: State | None = None) -> Path:
    """Write the blocks at ``state`` (default: as in the model file) to ``path`` (.vtu)."""
    import meshio

    state = state or State.at_rest(model.block_centroid)
    points, cells, offset = [], [], 0
    for b, shape in enumerate(model.block_shape):
        points.append(model.world_vertices(b, state.position[b], state.quaternion[b]))
        cells.append((f"polyhedron{len(shape.vertices)}", [np.asarray(face) + offset for face in shape.faces]))
        offset += len(shape.vertices)
    blocks = [(kind, [faces for _, faces in run]) for kind, run in groupby(cells, key=lambda cell: cell[0])]
    displacement = state.position - model.block_centroid
    fields = {
        "block_id": np.arange(model.n_blocks),
        "fixed": model.block_fixed.all(axis=1).astype(np.int8),
        "mass": model.block_mass,
        "displacement": displacement,
        "displacement_magnitude": np.linalg.norm(displacement, axis=1),
    }
    sizes = np.cumsum([0] + [len(faces) for _, faces in blocks])
    cell_data = {name: [values[a:b] for a, b in zip(sizes[:-1], sizes[1:])] for name, values in fields.items()}
    meshio.write(Path(path), meshio.Mesh(np.vstack(points), blocks, cell_data=cell_data), file_format="vtu")
    return Path(path)
