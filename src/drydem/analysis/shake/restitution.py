"""Rocking impacts: Housner's coefficient of restitution, and the contacts' damping ratio that
gives a target one.

A rigid block of width 2b and height 2h rocking on a rigid base (Housner 1963, "The behavior
of inverted pendulum structures during earthquakes", BSSA 53(2)) loses energy at each impact;
the coefficient of restitution r is the ratio of its angular velocities after and before.
Conservation of angular momentum about the new pivot gives, for a rectangular block,

    r_housner = 1 - 1.5 sin^2(alpha),   alpha = atan(b / h).

Between impacts the energy is kept, so successive peaks theta_n obey

    cos(alpha - theta_n+1) - cos(alpha) = r^2 (cos(alpha - theta_n) - cos(alpha)),

which is how a DEM model's restitution is measured here: the monitored block alone, on a
fixed base under it, with the model's joints, released from rest turned by
RELEASE_FRACTION alpha about its corner, cycled without local damping to its first peak after
the impact. The DEM impact is not instantaneous (the joints are springs), so r follows from the
contact dashpots' ratio zeta (:mod:`drydem.engine.damping`), and zeta is found by a root
search on r(zeta) (Brent's method), as Vlachakis, Giouvanidis, Mehrotra & Lourenco 2021 (J. Eng.
Mech. 147(11), 04021089) calibrate the damping of 3DEC's rocking blocks to a target
restitution by free-rocking analyses.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

from drydem.engine.damping import Damping
from drydem.engine.simulation import Simulation
from drydem.errors import DrydemError
from drydem.model.assembly import Block, Model, build_model
from drydem.model.geometry import ConvexPolyhedron, box
from drydem.model.parameters import G, Supports
from drydem.model.rotation import rotation_vectors
from drydem.model.state import State

#: the calibration releases the block turned by this fraction of its slenderness alpha
RELEASE_FRACTION = 0.5
#: the damping ratios among which a target restitution is looked for (from lightly damped up)
RATIO_GRID = (0.02, 0.05, 0.1, 0.2, 0.4, 0.8, 1.6)
#: the calibrated ratio's tolerance (absolute)
RATIO_TOLERANCE = 1e-4
#: cycles per look at the block while it rocks
CHUNK_CYCLES = 10
#: a turn to the other side after the impact is a peak only beyond this fraction of the release turn
PEAK_FLOOR = 0.05


def housner_restitution(alpha_rad: float) -> float:
    """r = 1 - 1.5 sin^2(alpha) (Housner 1963), the rigid rectangular block's angular-velocity ratio at impact."""
    return 1.0 - 1.5 * math.sin(alpha_rad) ** 2


def slenderness(shape: ConvexPolyhedron, direction: int = 0) -> tuple[float, float]:
    """(b, h), m: the half width along ``direction`` (0: x, 1: y) and half height of a block's
    bounding box as drawn; alpha = atan(b / h). A block shaken along y rocks about x, across its
    width along y (found by a hunt: its width along x was taken whatever the motion)."""
    extent = np.ptp(shape.vertices, axis=0)
    return float(extent[direction] / 2.0), float(extent[2] / 2.0)


@dataclass(frozen=True)
class RockingBlock:
    """One block alone on a fixed base under it (``model``: blocks "base" and "block"), in the
    x-z plane, with another model's joints and contacts; (b, h) its half sizes (m)."""

    model: Model
    half_width_m: float
    half_height_m: float

    @property
    def alpha_rad(self) -> float:
        return math.atan2(self.half_width_m, self.half_height_m)

    @classmethod
    def of(cls, model: Model, block: int, direction: int = 0) -> RockingBlock:
        """The block ``block`` of ``model``, set on the ground, with the model's joints and
        density, rocking along ``direction`` (0: x, the default; 1: y, about x: the block is
        turned a quarter about z so that its width along y lies along x, where it rocks here)."""
        shape = model.block_shape[block]
        lowest = shape.vertices.min(axis=0)
        turn = np.eye(3) if direction == 0 else np.array([[0.0, 1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
        standing = shape.transformed(turn, -turn @ np.array([shape.centroid[0], shape.centroid[1], lowest[2]]))
        b, h = slenderness(standing)
        depth = np.ptp(standing.vertices[:, 1])
        base = box([-4.0 * b, -depth, -0.5 * h], [4.0 * b, depth, 0.0], name="base")
        density = float(model.block_mass[block] / shape.volume)
        rocking = build_model(
            [Block(name="base", shape=base, fixed=True), Block(name="block", shape=standing)], density=density,
            joint=model.joint, contacts=model.contacts, supports=Supports(fix_y=True), source=f"{model.source}: rocking block",
        )
        return cls(rocking, b, h)

    def released(self, theta_rad: float) -> State:
        """At rest, turned by ``theta_rad`` (> 0: top toward +x) about its bottom corner on that side."""
        corner = np.array([math.copysign(self.half_width_m, theta_rad), 0.0, 0.0])
        c, s = math.cos(theta_rad), math.sin(theta_rad)
        turn = np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])
        state = State.at_rest(self.model.block_centroid)
        state.position[1] = corner + turn @ (self.model.block_centroid[1] - corner)
        state.quaternion[1] = (math.cos(theta_rad / 2.0), 0.0, math.sin(theta_rad / 2.0), 0.0)
        return state

    def first_peak_after_impact(self, theta0_rad: float, damping: Damping, *, max_seconds: float = 10.0) -> float:
        """|theta| (rad) at the first peak after the first impact, released from rest at
        ``theta0_rad``: the largest turn to the other side, once the block is clearly coming
        back from it (turned less than half of it) or back on the first side. Only turns beyond
        PEAK_FLOOR theta0 count, so that the chatter of the corners at impact is no peak."""
        sim = Simulation(self.model, state=self.released(theta0_rad), damping=damping)
        gravity = np.array([0.0, 0.0, -G])
        floor = PEAK_FLOOR * abs(theta0_rad)
        side = math.copysign(1.0, theta0_rad)
        upright = State.at_rest(self.model.block_centroid[1:]).quaternion
        crossed, peak = False, 0.0
        while sim.time_s < max_seconds:
            sim.cycle(CHUNK_CYCLES, gravity=gravity)
            theta = float(rotation_vectors(upright, sim.state.quaternion[1:])[0, 1]) * side
            crossed = crossed or theta < 0.0
            if crossed:
                peak = max(peak, -theta)
                if (peak > floor and -theta < 0.5 * peak) or theta > floor:
                    return peak
        raise DrydemError(f"{self.model.source}: released at {theta0_rad:.3g} rad, no impact and rebound within {max_seconds:g} s")

    def restitution(self, contact_damping_ratio: float) -> float:
        """The DEM r for the contacts' damping ratio zeta, from the peaks before and after the
        first impact (module docstring)."""
        alpha = self.alpha_rad
        theta0 = RELEASE_FRACTION * alpha
        theta1 = self.first_peak_after_impact(theta0, Damping(0.0, contact_ratio=contact_damping_ratio))
        energy_ratio = (math.cos(alpha - theta1) - math.cos(alpha)) / (math.cos(alpha - theta0) - math.cos(alpha))
        return math.sqrt(max(energy_ratio, 0.0))


def calibrated_damping_ratio(model: Model, block: int, restitution: float, direction: int = 0) -> float:
    """zeta for which the block ``block`` of ``model``, rocking alone on its joints along
    ``direction`` (0: x, 1: y; :meth:`RockingBlock.of`), has the
    coefficient of restitution ``restitution`` (module docstring): the first interval of
    RATIO_GRID over which r(zeta) crosses it, refined by Brent's method. r(zeta) is not
    monotonic (heavily damped corners stick and lose less), nor is it at the undamped end
    (stiff undamped corners chatter). DrydemError if no ratio of the grid gives the
    restitution: the dashpots cannot make an impact lose more than a rigid block's impact
    does (about Housner's r).
    """
    rocking = RockingBlock.of(model, block, direction)
    ratios = np.array(RATIO_GRID)
    excess = np.array([rocking.restitution(ratio) for ratio in ratios]) - restitution
    crossing = _falls_through(excess)
    if crossing.size == 0:
        raise DrydemError(f"{model.source}: block {model.block_name[block]!r} rocking alone on its joints has a restitution "
                          f"{_between(excess + restitution)} for contact damping ratios {RATIO_GRID[0]:g} to {RATIO_GRID[-1]:g} "
                          f"with {model.contacts.points_per_length} points per length: {restitution:.3g} cannot be reached. "
                          f"{_with_corner_points(model, block, restitution, direction)}Or give the contact damping ratio directly "
                          "(drydem shake --damping-ratio, ShakeSettings.contact_damping_ratio)")
    low, high = ratios[crossing[0]], ratios[crossing[0] + 1]
    return float(brentq(lambda ratio: rocking.restitution(ratio) - restitution, low, high, xtol=RATIO_TOLERANCE))


def _falls_through(excess: np.ndarray) -> np.ndarray:
    """The intervals of RATIO_GRID over which r(zeta) - target falls through zero."""
    return np.flatnonzero((excess[:-1] >= 0.0) & (excess[1:] <= 0.0))


def _between(restitutions: np.ndarray) -> str:
    return f"between {restitutions.min():.3f} and {restitutions.max():.3f}"


def _with_corner_points(model: Model, block: int, restitution: float, direction: int) -> str:
    """What 2 points per length (sub-contacts at the corners, as Housner's rigid block pivots
    and lands) would reach, for a model with more: sub-contacts spread over the bed take the
    impact gradually and lose less of it (the 0.2 x 0.8 m block, Housner's r 0.912: 0.909 to
    0.963 with 2 points, 0.947 to 0.982 with 4). Empty for a model with 2."""
    if model.contacts.points_per_length == 2:
        return ""
    corners = RockingBlock.of(model.overridden(points=2), block, direction)
    reached = np.array([corners.restitution(ratio) for ratio in RATIO_GRID])
    verdict = "which reaches it" if _falls_through(reached - restitution).size else "which does not reach it either"
    return (f"Sub-contacts spread over the bed lose less at impact: with 2 points per length (--points 2: at the corners, "
            f"as Housner's block pivots) it is {_between(reached)}, {verdict}. ")
