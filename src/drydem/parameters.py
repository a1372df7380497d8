"""Parameters as frozen, keyword-only dataclasses with units, validated when created.

Each class maps one-to-one to a table of the model file (``[joint]``,
``[contacts]``, ``[supports]``, ``[solver]``); field names are the TOML keys.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields

from drydem.errors import ModelError


def _require(ok: bool, owner: str, name: str, value, rule: str) -> None:
    if not ok:
        raise ModelError(f"[{owner}] {name} = {value!r}: {rule}")


def _positive(owner: str, name: str, value: float) -> None:
    _require(isinstance(value, (int, float)) and math.isfinite(value) and value > 0, owner, name, value, "must be a positive number")


def _non_negative(owner: str, name: str, value: float) -> None:
    _require(isinstance(value, (int, float)) and math.isfinite(value) and value >= 0, owner, name, value, "must be a number >= 0")


@dataclass(frozen=True, kw_only=True)
class JointMaterial:
    """Dry joint: linear springs per unit area plus Mohr-Coulomb slip.

    kn, ks : normal and shear stiffness, Pa/m (stress per unit relative displacement).
    friction : Coulomb coefficient mu (tan of the friction angle), > 0.
    cohesion : c, Pa. tension : tensile strength, Pa. Both drop to zero for a
        sub-contact once it fails in shear or tension (3DEC's rule).
    """

    kn: float = 3e7
    ks: float = 3e7
    friction: float = 0.5
    cohesion: float = 0.0
    tension: float = 0.0

    def __post_init__(self):
        _positive("joint", "kn", self.kn)
        _positive("joint", "ks", self.ks)
        _positive("joint", "friction", self.friction)
        _non_negative("joint", "cohesion", self.cohesion)
        _non_negative("joint", "tension", self.tension)


@dataclass(frozen=True, kw_only=True)
class ContactSettings:
    """Contact detection and sub-contact density.

    points_per_length : sub-contacts along each in-plane direction of a full face,
        ends included (2 = corners only, 3DEC's vertex sub-contacts; 1 = one point at
        the centroid of the contact polygon).
    points_across : sub-contacts across the wall, along y; ``None`` = 1 for in-plane models
        (:attr:`drydem.model.Model.in_plane`: the contact forces are uniform across the width,
        so one point on the mid-plane with the whole width's area is exact), 2 for other
        models with every block fixed in y, else points_per_length.
    tolerance : m, gap below which faces are in contact; ``None`` = 5 % of the
        thinnest free block. Contacts are re-detected whenever neighbouring blocks have
        moved half of it relative to each other.
    """

    points_per_length: int = 4
    points_across: int | None = None
    tolerance: float | None = None

    def __post_init__(self):
        _require(
            isinstance(self.points_per_length, int) and not isinstance(self.points_per_length, bool) and self.points_per_length >= 1,
            "contacts", "points_per_length", self.points_per_length, "must be an integer >= 1",
        )
        _require(
            self.points_across is None or (isinstance(self.points_across, int) and not isinstance(self.points_across, bool) and self.points_across >= 1),
            "contacts", "points_across", self.points_across, "must be an integer >= 1",
        )
        if self.tolerance is not None:
            _positive("contacts", "tolerance", self.tolerance)


@dataclass(frozen=True, kw_only=True)
class Supports:
    """Degrees of freedom fixed for every block (world axes); x, y, z translations, rx, ry, rz rotations."""

    fix_x: bool = False
    fix_y: bool = False
    fix_z: bool = False
    fix_rx: bool = False
    fix_ry: bool = False
    fix_rz: bool = False

    def __post_init__(self):
        for f in fields(self):
            value = getattr(self, f.name)
            _require(isinstance(value, bool), "supports", f.name, value, "must be true or false")

    @property
    def mask(self) -> tuple[bool, ...]:
        """Fixed flags in the order x, y, z, rx, ry, rz."""
        return (self.fix_x, self.fix_y, self.fix_z, self.fix_rx, self.fix_ry, self.fix_rz)


CRITERIA = ("ratio", "velocity")


@dataclass(frozen=True, kw_only=True)
class SolverSettings:
    """Explicit dynamic relaxation.

    damping : local damping coefficient alpha (paper Eq. 4), 0 <= alpha < 1.
    timestep_safety : fraction of the critical timestep used, 0 < f <= 1.
    mass_scaling : scale each block's inertia to its contact stiffness (statics only; it can
        blow up in collapse flows, where fictitious masses differ a lot between neighbours).
    criterion : "ratio" (max unbalanced force / mean weight < ``ratio``) or
        "velocity" (max block point speed < ``max_velocity``, m/s; the paper's 1e-13).
    max_cycles : cycles allowed for one equilibrium before it is reported as not converged.
    """

    damping: float = 0.8
    timestep_safety: float = 0.8
    mass_scaling: bool = False
    criterion: str = "ratio"
    ratio: float = 1e-5
    max_velocity: float = 1e-13
    max_cycles: int = 2_000_000

    def __post_init__(self):
        _require(isinstance(self.damping, (int, float)) and 0 <= self.damping < 1, "solver", "damping", self.damping, "must be in [0, 1)")
        _require(
            isinstance(self.timestep_safety, (int, float)) and 0 < self.timestep_safety <= 1,
            "solver", "timestep_safety", self.timestep_safety, "must be in (0, 1]",
        )
        _require(isinstance(self.mass_scaling, bool), "solver", "mass_scaling", self.mass_scaling, "must be true or false")
        _require(self.criterion in CRITERIA, "solver", "criterion", self.criterion, f"must be one of {CRITERIA}")
        _positive("solver", "ratio", self.ratio)
        _positive("solver", "max_velocity", self.max_velocity)
        _require(
            isinstance(self.max_cycles, int) and not isinstance(self.max_cycles, bool) and self.max_cycles > 0,
            "solver", "max_cycles", self.max_cycles, "must be a positive integer",
        )
