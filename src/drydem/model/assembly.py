"""The Model: blocks, supports and materials, frozen once built.

Build one with :func:`build_model` from :class:`Block` descriptions (the model file
loader, :mod:`drydem.io.model_file`, does exactly that). Everything that changes during
a run lives in :class:`drydem.model.state.State` and the engine's contacts (:mod:`drydem.engine`).
"""

from __future__ import annotations

import dataclasses
import hashlib
import inspect
import itertools
from collections import Counter
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from functools import cached_property
from typing import ClassVar

import numpy as np

from drydem.errors import ModelError
from drydem.model.boxes import bounds, pair_chunks
from drydem.model.geometry import PARALLEL_SINE, ConvexPolyhedron, FlatGeometry, box, frozen_array
from drydem.model.parameters import (
    DENSITY, FLAG, NAME, TEXT, ContactDensity, ContactSettings, InstanceOf, JointMaterial, SolverSettings, Supports, check_arguments,
    check_fields, is_integer, shown,
)
from drydem.model.rotation import matrices

#: default contact tolerance as a fraction of the thinnest movable block (m/m)
TOLERANCE_FRACTION = 0.05
#: largest contact tolerance as a fraction of the thinnest movable block: beyond half of it,
#: faces on the far side of a block would count as touching its neighbours
MAX_TOLERANCE_FRACTION = 0.5
#: initial overlaps deeper than this fraction of the contact tolerance are errors
OVERLAP_FRACTION = 0.01
#: the most blocks a model may have: twice the largest DEM masonry models (~10^5 blocks)
MAX_BLOCKS = 200_000
#: an in-plane model's faces are parallel or normal to y, and its blocks' mid-planes coincide,
#: to this fraction of the block size (|n_y|; mid-plane offsets)
IN_PLANE_TOLERANCE = 1e-6


@dataclass(frozen=True, kw_only=True)
class Block:
    """One block as described by the user.

    name : unique label used in messages and outputs. shape : its geometry in the model's
    frame (m). density : kg/m3, None for the model's. fixed : all six degrees of freedom fixed.
    """

    name: str
    shape: ConvexPolyhedron
    density: float | None = None
    fixed: bool = False

    def __post_init__(self):
        check_fields(self, BLOCK_RULES, f"block {shown(self.name)}", optional=("density",))


#: the rule of each field of :class:`Block` (a model file's [[block]] is held to the same): a name
#: that messages can show, a polyhedron (drydem.box, drydem.convex_hull), the density in its range
#: (None: the model's), fixed a switch ("no" is not False)
BLOCK_RULES = {"name": NAME, "shape": InstanceOf(ConvexPolyhedron), "density": DENSITY, "fixed": FLAG}


def base_under(blocks: list[Block], *, overhang_m: float = 0.05, depth_m: float = 0.01) -> Block:
    """A fixed block on which ``blocks`` stand: its top at their lowest point, ``overhang_m``
    beyond them at each end along x (the tilt direction), as wide as they are in y, ``depth_m``
    deep or BASE_DEPTH_FRACTION of its length if that is more; named "base", or "base-2",
    "base-3", ... if one of ``blocks`` has that name."""
    lo = np.min([b.shape.vertices.min(0) for b in blocks], axis=0)
    hi = np.max([b.shape.vertices.max(0) for b in blocks], axis=0)
    taken = {b.name for b in blocks}
    name = next(n for n in itertools.chain(["base"], (f"base-{k}" for k in itertools.count(2))) if n not in taken)
    depth_m = max(depth_m, BASE_DEPTH_FRACTION * (hi[0] - lo[0] + 2.0 * overhang_m))
    shape = box([lo[0] - overhang_m, lo[1], lo[2] - depth_m], [hi[0] + overhang_m, hi[1], lo[2]], name=name)
    return Block(name=name, shape=shape, fixed=True)


#: the least depth of :func:`base_under`'s base, as a fraction of its length: a 1 cm slab under a
#: 1 km wall of 2000 half-metre bricks was refused as a degenerate (flat) block; the paper's walls
#: keep their 1 cm
BASE_DEPTH_FRACTION = 1e-3


@dataclass(frozen=True, kw_only=True, eq=False)
class Model:
    """Frozen description of a block assembly (nb blocks); its arrays are read-only.

    block_name : names. block_shape : geometry as given (this is the body frame: a block's
    body coordinates are its model-file coordinates minus its centroid). block_density : (nb,)
    kg/m3, as given. block_mass : (nb,) kg.
    block_inertia : (nb, 3, 3) kg m2 about the centroid. block_fixed : (nb, 6) bool, fixed
    degrees of freedom (x, y, z, rx, ry, rz). block_radius : (nb,) m, centroid-to-vertex
    maximum. contact_tolerance : m, resolved from ``contacts.tolerance``. source : where the
    model came from (file name), for messages.
    in_plane : the paper's walls: every movable block is held in y and every block is a prism
    across y (faces parallel or normal to y) symmetric about one plane y = y0. Forces then stay
    in the x-z plane and the blocks only move in it (x, z, rotation about y): rx and rz are held
    too (symmetry keeps them at zero anyway), and :mod:`drydem.engine.cycle_planar` cycles such a model with
    3 degrees of freedom per block.
    """

    block_name: tuple[str, ...]
    block_shape: tuple[ConvexPolyhedron, ...] = field(repr=False)
    block_density: np.ndarray = field(repr=False)
    block_mass: np.ndarray = field(repr=False)
    block_inertia: np.ndarray = field(repr=False)
    block_fixed: np.ndarray = field(repr=False)
    block_radius: np.ndarray = field(repr=False)
    joint: JointMaterial
    contacts: ContactSettings
    supports: Supports
    solver: SolverSettings
    contact_tolerance: float
    in_plane: bool
    source: str = "<python>"
    #: how a Model is made (its fields are derived from the blocks)
    MADE_BY: ClassVar[str] = "drydem.build_model(blocks, density=...), or drydem.io.model_file.load_model(path)"

    def __post_init__(self):
        # frozen means its arrays too: a block mass of -5 set through model.block_mass[1] ran
        for name in ("block_density", "block_mass", "block_inertia", "block_fixed", "block_radius"):
            object.__setattr__(self, name, frozen_array(getattr(self, name)))

    @property
    def n_blocks(self) -> int:
        return len(self.block_name)

    @cached_property
    def block_centroid(self) -> np.ndarray:
        """(nb, 3) centroids in the model file, m (computed once; read-only: the tilt measures
        displacements from it, and a Simulation starts there). The other cached arrays below are
        the engine's, handed to the compiled kernels, which are built for writable arrays."""
        return frozen_array(np.array([s.centroid for s in self.block_shape]))

    @cached_property
    def blocks_digest(self) -> str:
        """SHA-1 (hex) of the blocks' vertices, densities and fixities, in order (computed once):
        what a saved state must have been cycled on to be restored into this model."""
        found = hashlib.sha1()
        for shape in self.block_shape:
            found.update(np.ascontiguousarray(shape.vertices).tobytes())
        found.update(self.block_density.tobytes() + self.block_fixed.tobytes())
        return found.hexdigest()

    @cached_property
    def block_movable(self) -> np.ndarray:
        """(nb,) bool: the block has at least one free degree of freedom (computed once)."""
        return ~self.block_fixed.all(axis=1)

    @cached_property
    def geometry(self) -> FlatGeometry:
        """The blocks' body geometry flattened for the compiled contact detection (computed once)."""
        return FlatGeometry.of(self.block_shape)

    @cached_property
    def block_inertia_inverse(self) -> np.ndarray:
        """(nb, 3, 3) inverse inertia tensors, 1/(kg m2)."""
        return np.linalg.inv(self.block_inertia)

    @cached_property
    def block_inertia_whitening(self) -> np.ndarray:
        """(nb, 3, 3) W = L^-1 with I = L L^T (Cholesky): W K W^T has the eigenvalues of I^-1 K."""
        return np.linalg.inv(np.linalg.cholesky(self.block_inertia))

    @property
    def contact_density(self) -> ContactDensity:
        """Sub-contact density resolved from ``contacts`` and ``supports`` (see ContactSettings)."""
        along = self.contacts.points_per_length
        across = self.contacts.points_across
        if across is None:
            across = 1 if self.in_plane else min(2, along) if self.supports.fix_y else along
        return ContactDensity(along=along, across=across)

    @property
    def total_mass(self) -> float:
        """Mass of the movable blocks, kg."""
        return float(self.block_mass[self.block_movable].sum())

    def block_index(self, name: str) -> int:
        try:
            return self.block_name.index(name)
        except ValueError:
            raise ModelError(f"{self.source}: no block named {name!r}") from None

    def block_indices(self, blocks, where: str) -> np.ndarray:
        """(k,) int64 the indices of ``blocks``: a block's name or index (0 to nb - 1; not
        negative, which would count from the end), or a list or array of them; ModelError
        naming ``where`` and the first entry that is neither (a boolean is no index)."""
        if isinstance(blocks, np.ndarray):
            blocks = blocks.tolist()  # NumPy's integers and texts as Python's
        if isinstance(blocks, str) or is_integer(blocks):
            blocks = [blocks]
        elif not isinstance(blocks, (list, tuple)):
            raise ModelError(f"{self.source}: {where} = {shown(blocks)}: must be a block name or index, or a list of them")
        return np.array([self.block_number(entry, where) for entry in blocks], dtype=np.int64)

    def block_number(self, block, where: str) -> int:
        """The index of ``block``, a block's name or index (0 to nb - 1); ModelError naming
        ``where`` and ``block`` if it is neither."""
        if isinstance(block, str):
            return self.block_index(block)
        if is_integer(block) and 0 <= block < self.n_blocks:
            return int(block)
        raise ModelError(f"{self.source}: {where}: {shown(block)} is no block: must be a block name or an index in "
                         f"[0, {self.n_blocks - 1}]")

    def world_vertices(self, block: int, position: np.ndarray, quaternion: np.ndarray) -> np.ndarray:
        """The vertices of ``block`` at centroid ``position`` (3,) m and orientation
        ``quaternion`` (4,) (body -> world, drydem.model.state): x = R(q) (v - c0) + position."""
        shape = self.block_shape[block]
        return (shape.vertices - shape.centroid) @ matrices(quaternion[None])[0].T + position

    def parameter_changes(self, *, kn: float | None = None, ks: float | None = None, friction: float | None = None,
                          points: int | None = None, criterion: str | None = None, joint_law: Mapping | None = None) -> dict:
        """The tables that the given values (None: unchanged) change, for :meth:`replace`: joint
        kn, ks (Pa/m) and friction, its law (``joint_law``: model and the law's keys,
        :meth:`~drydem.model.parameters.JointMaterial.changed`), contacts points_per_length,
        solver criterion. Building them checks each value (ModelError naming it and its range)
        without building a model."""
        if not (joint_law is None or isinstance(joint_law, Mapping)):
            raise ModelError(f"{self.source}: joint_law = {shown(joint_law)}: must be a mapping of [joint] keys, e.g. "
                             "{'model': 'power', 'kn_exponent': 0.5, 'stress_ref': 1e4, 'kn_min': 1e6}")
        joint = {k: v for k, v in (("kn", kn), ("ks", ks), ("friction", friction)) if v is not None} | dict(joint_law or {})
        changes = {"joint": self.joint.changed(**joint)} if joint else {}
        if points is not None:
            changes["contacts"] = dataclasses.replace(self.contacts, points_per_length=points)
        if criterion is not None:
            changes["solver"] = dataclasses.replace(self.solver, criterion=criterion)
        return changes

    def overridden(self, *, density: float | None = None, **values) -> Model:
        """The model with the given values changed (those of :meth:`parameter_changes`, and one
        ``density`` in kg/m3 for every block); itself if none is given. ModelError naming a key
        that is none of those, and the allowed ones."""
        _refuse_unknown(f"{self.source}: Model.overridden", values, ["density", *inspect.signature(self.parameter_changes).parameters])
        changes = self.parameter_changes(**values)
        return self.replace(density=density, **changes) if changes or density is not None else self

    def replace(self, *, density: float | None = None, **changes) -> Model:
        """A copy with some parameters changed: joint, contacts, supports, solver, or one
        ``density`` (kg/m3) for every block."""
        _refuse_unknown(f"{self.source}: Model.replace", changes, ["density", "joint", "contacts", "supports", "solver"])
        blocks = [
            Block(name=n, shape=s, fixed=bool(f.all()), density=None if density is not None else float(rho))
            for n, s, f, rho in zip(self.block_name, self.block_shape, self.block_fixed, self.block_density)
        ]
        params = dict(joint=self.joint, contacts=self.contacts, supports=self.supports, solver=self.solver) | changes
        common = density if density is not None else float(self.block_density.max())
        return build_model(blocks, density=common, source=self.source, **params)


def _refuse_unknown(where: str, given: Mapping, allowed: list[str]) -> None:
    """ModelError naming ``where``, the keys of ``given`` not ``allowed``, and the allowed ones."""
    unknown = sorted(set(given) - set(allowed))
    if unknown:
        raise ModelError(f"{where}: unknown key(s) {unknown}; allowed: {allowed}")


def build_model(
    blocks: list[Block],
    *,
    density: float,
    joint: JointMaterial = JointMaterial(),
    contacts: ContactSettings = ContactSettings(),
    supports: Supports = Supports(),
    solver: SolverSettings = SolverSettings(),
    source: str = "<python>",
) -> Model:
    """Validate the blocks and freeze them into a :class:`Model`.

    ``blocks`` is any iterable of :class:`Block` (a generator is read once). Raises ModelError
    for an argument of the wrong kind (naming it and the kind it must be), more than
    :data:`MAX_BLOCKS` blocks, duplicate names, a
    density out of :data:`drydem.model.parameters.DENSITY`, no movable block, a contact tolerance
    above half the thinnest movable block, or two blocks overlapping deeper than 1 % of the
    contact tolerance (naming both and the depth).
    """
    blocks = _checked_arguments(blocks, joint=joint, contacts=contacts, supports=supports, solver=solver, source=source)
    DENSITY.check(density, f"{source}: [material] density")
    duplicates = sorted(name for name, count in Counter(b.name for b in blocks).items() if count > 1)
    if duplicates:
        raise ModelError(f"{source}: duplicate block names {duplicates}")
    if all(b.fixed for b in blocks):
        raise ModelError(f"{source}: every block is fixed; nothing can move")
    per_block = np.array([density if b.density is None else b.density for b in blocks], dtype=float)
    return _assemble(blocks, per_block, joint=joint, contacts=contacts, supports=supports, solver=solver, source=source)


#: the kind of each argument of :func:`build_model` but the blocks and the density
ARGUMENT_RULES = {"joint": InstanceOf(JointMaterial), "contacts": InstanceOf(ContactSettings), "supports": InstanceOf(Supports),
                  "solver": InstanceOf(SolverSettings), "source": TEXT}


def _checked_arguments(blocks, **arguments) -> list[Block]:
    """``blocks`` as a list, after ModelError naming every argument of :func:`build_model` of the
    wrong kind (:data:`ARGUMENT_RULES`) and every entry of ``blocks`` that is no Block (a
    polyhedron needs its name: Block(name=..., shape=...)), or saying there are no blocks; each
    Block and settings object is checked again, as it was made (its ``__post_init__``)."""
    source = arguments["source"] if isinstance(arguments["source"], str) else "<python>"
    check_arguments(f"{source}: build_model", ARGUMENT_RULES, **arguments)
    if isinstance(blocks, (str, Mapping)) or not isinstance(blocks, Iterable):
        raise ModelError(f"{source}: build_model blocks = {shown(blocks)}: must be a list of Block")
    blocks = list(blocks)
    wrong = [i for i, b in enumerate(blocks) if not isinstance(b, Block)]
    if wrong:
        more = f" (and {len(wrong) - 1} more entries)" if len(wrong) > 1 else ""
        raise ModelError(f"{source}: build_model blocks[{wrong[0]}] = {shown(blocks[wrong[0]])}: must be a Block "
                         f"(Block(name=..., shape=...)){more}")
    if not blocks:
        raise ModelError(f"{source}: the model has no blocks")
    if len(blocks) > MAX_BLOCKS:
        raise ModelError(f"{source}: {len(blocks):,} blocks: a model has at most {MAX_BLOCKS:,}")
    for checked in (*blocks, *(arguments[name] for name in ("joint", "contacts", "supports", "solver"))):
        checked.__post_init__()  # again: a frozen dataclass still changes through object.__setattr__, and the kernels trust
        # its values (points_per_length set to 0 after the check corrupted the heap)
    return blocks


def _assemble(blocks, density, *, joint, contacts, supports, solver, source) -> Model:
    shapes = tuple(b.shape for b in blocks)
    fixed = np.array([[True] * 6 if b.fixed else list(supports.mask) for b in blocks], dtype=bool)
    in_plane = _in_plane(shapes, fixed)
    if in_plane:
        fixed[:, [3, 5]] = True
    if fixed.all():
        raise ModelError(f"{source}: every degree of freedom of every block is held ([supports] fix_x ... fix_rz = true, "
                         "or every block fixed); nothing can move")
    thinnest = min(_thickness(s) for s, f in zip(shapes, fixed) if not f.all())
    tolerance = TOLERANCE_FRACTION * thinnest if contacts.tolerance is None else contacts.tolerance
    if tolerance > MAX_TOLERANCE_FRACTION * thinnest:
        raise ModelError(
            f"{source}: [contacts] tolerance = {tolerance!r} m: must be at most {MAX_TOLERANCE_FRACTION:g} of the thinnest "
            f"movable block ({thinnest:.4g} m), i.e. <= {MAX_TOLERANCE_FRACTION * thinnest:.4g} m (default {TOLERANCE_FRACTION:g} of it)"
        )
    model = Model(
        block_name=tuple(b.name for b in blocks),
        block_shape=shapes,
        block_density=density,
        block_mass=density * np.array([s.volume for s in shapes]),
        block_inertia=np.array([s.inertia_tensor(rho) for s, rho in zip(shapes, density)]),
        block_fixed=fixed,
        block_radius=np.array([np.linalg.norm(s.vertices - s.centroid, axis=1).max() for s in shapes]),
        joint=joint,
        contacts=contacts,
        supports=supports,
        solver=solver,
        contact_tolerance=float(tolerance),
        in_plane=in_plane,
        source=source,
    )
    _check_overlaps(model)
    return model


def _in_plane(shapes: tuple[ConvexPolyhedron, ...], fixed: np.ndarray) -> bool:
    """Whether the model is in-plane (see :class:`Model`): movable blocks held in y, every block
    a y-prism, all with one mid-plane (to IN_PLANE_TOLERANCE of the smallest block)."""
    if not fixed[~fixed.all(axis=1), 1].all():
        return False
    for s in shapes:
        ny = np.abs(s.face_normals[:, 1])
        if not np.all((ny < IN_PLANE_TOLERANCE) | (ny > 1.0 - IN_PLANE_TOLERANCE)):
            return False
    mid = [0.5 * (s.vertices[:, 1].min() + s.vertices[:, 1].max()) for s in shapes]
    return bool(np.ptp(mid) <= IN_PLANE_TOLERANCE * min(s.size for s in shapes))


def _thickness(shape: ConvexPolyhedron) -> float:
    """Smallest width of a convex polyhedron across its face normals, m."""
    heights = shape.vertices @ shape.face_normals.T
    return float((heights.max(0) - heights.min(0)).min())


def _check_overlaps(model: Model) -> None:
    """ModelError naming a pair of blocks that overlap by more than OVERLAP_FRACTION of the
    contact tolerance at the start (their penetration depth,
    :func:`~drydem.model.geometry.penetration_depth`, worked out by :func:`penetration_depths`):
    the candidate pairs are found and checked about OVERLAP_PAIRS at a time (:func:`pair_chunks`,
    blocks in the order of their lower x), and the first overlap of the first chunk holding one
    (in the order of the blocks' numbers) is named: 3,000 coincident cubes took 20 s to be
    refused, and 30,000 would have held 7 GB of candidate pairs."""
    limit = OVERLAP_FRACTION * model.contact_tolerance
    shapes = list(model.block_shape)
    for pairs in pair_chunks(*bounds(shapes), model.block_movable, 0.0, OVERLAP_PAIRS):
        depth = penetration_depths(shapes, pairs)
        over = np.flatnonzero(depth > limit)
        if over.size:
            i, j = (int(b) for b in pairs[over[0]])
            raise ModelError(
                f"{model.source}: blocks {model.block_name[i]!r} and {model.block_name[j]!r} overlap by "
                f"{depth[over[0]]:.3g} m at the start (allowed: {limit:.3g} m, 1 % of the contact tolerance)"
            )


#: candidate pairs :func:`_check_overlaps` takes at a time
OVERLAP_PAIRS = 1 << 14


#: pairs of :func:`penetration_depths` are taken this many (pair, vertex, face or edge axis) entries at a time
DEPTH_CHUNK = 1 << 21


def penetration_depths(shapes: list[ConvexPolyhedron], pairs: np.ndarray) -> np.ndarray:
    """(P,) :func:`~drydem.model.geometry.penetration_depth` of each pair (i, j) of ``pairs``
    (P, 2) of ``shapes``, m, vectorised: each block's vertices, face planes and edge directions
    padded to the most any block has (repeating one of its own, which changes no minimum or
    maximum), then the separations along both blocks' faces and their edges' cross products, in
    chunks; the reference face chosen with the same tie rule (:func:`~drydem.model.geometry.best_separation`)."""
    pairs = np.asarray(pairs, dtype=np.int64).reshape(-1, 2)
    if not len(pairs):
        return np.zeros(0)
    used = np.unique(pairs)
    at = np.full(len(shapes), -1, dtype=np.int64)
    at[used] = np.arange(len(used))
    vertices = _padded([shapes[b].vertices for b in used])
    normals = _padded([shapes[b].face_normals for b in used])
    edges = _padded([shapes[b].edge_directions for b in used])
    offsets = _padded([np.einsum("fi,fi->f", s.face_normals, s.vertices[[f[0] for f in s.faces]]) for s in (shapes[b] for b in used)])
    size = np.array([shapes[b].size for b in used])
    depth = np.empty(len(pairs))
    step = max(1, DEPTH_CHUNK // (vertices.shape[1] * max(normals.shape[1], edges.shape[1] ** 2)))
    for start in range(0, len(pairs), step):
        a, b = at[pairs[start:start + step, 0]], at[pairs[start:start + step, 1]]
        sa = (vertices[b] @ normals[a].transpose(0, 2, 1)).min(axis=1) - offsets[a]
        sb = (vertices[a] @ normals[b].transpose(0, 2, 1)).min(axis=1) - offsets[b]
        fa, fb = sa.max(axis=1), sb.max(axis=1)
        tie = 1e-9 * np.minimum(size[a], size[b])
        faces = np.where(fa >= fb - tie, fa, fb)
        depth[start:start + step] = -np.maximum(faces, _edge_separations(vertices[a], vertices[b], edges[a], edges[b]))
    return depth


def _padded(rows: list[np.ndarray]) -> np.ndarray:
    """(n, most, ...) the arrays ``rows`` stacked, each padded to the longest by repeating its last row."""
    most = max(len(r) for r in rows)
    return np.stack([np.concatenate([r, np.repeat(r[-1:], most - len(r), axis=0)]) for r in rows])


def _edge_separations(va: np.ndarray, vb: np.ndarray, ea: np.ndarray, eb: np.ndarray) -> np.ndarray:
    """(P,) :func:`~drydem.model.geometry.edge_separation` of P pairs: vertices (P, nv, 3), edge
    directions (P, ne, 3); a's edges taken a few at a time, so that at most about DEPTH_CHUNK
    projections are held at once however many edges the blocks have."""
    per_edge = va.shape[0] * va.shape[1] * eb.shape[1]
    step = max(1, DEPTH_CHUNK // per_edge)
    best = np.full(len(va), -np.inf)
    for start in range(0, ea.shape[1], step):
        axes = np.cross(ea[:, start:start + step, None], eb[:, None]).reshape(len(ea), -1, 3)
        length = np.linalg.norm(axes, axis=2)
        parallel = length <= PARALLEL_SINE
        axes = axes / np.where(parallel, 1.0, length)[..., None]
        pa, pb = va @ axes.transpose(0, 2, 1), vb @ axes.transpose(0, 2, 1)
        gaps = np.maximum(pb.min(axis=1) - pa.max(axis=1), pa.min(axis=1) - pb.max(axis=1))
        best = np.maximum(best, np.where(parallel, -np.inf, gaps).max(axis=1))
    return best
