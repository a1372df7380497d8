"""Calibration of the joint stiffness (the seed paper's post-diction, Section 4.4, automated):
the kn (ks = kn, or a fixed ratio) that minimises the mean absolute relative error between
computed and experimental collapse angles over a set of walls.

The search is over log10 kn: a coarse log-spaced grid, then golden-section refinement around
its best point (Kiefer 1953), every evaluation memoised so that finished runs are reused. The
error against kn need not be unimodal over the whole range (the grid is there for that); inside
the bracket it is assumed to be.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

GOLDEN = (math.sqrt(5) - 1) / 2


@dataclass(frozen=True)
class Calibration:
    """best_kn (Pa/m) and its error; curve: every (kn, error) evaluated, sorted by kn."""

    best_kn: float
    best_error: float
    curve: list[tuple[float, float]]


def calibrate(error: Callable[[float], float], kn_min: float, kn_max: float, *, grid: int = 5,
              tolerance: float = 0.01, max_evaluations: int = 30) -> Calibration:
    """Minimise ``error(kn)`` over [kn_min, kn_max] (Pa/m) to within ``tolerance`` in log10 kn."""
    if not 0 < kn_min < kn_max:
        raise ValueError(f"need 0 < kn_min < kn_max, got {kn_min}, {kn_max}")
    seen: dict[float, float] = {}

    def f(log_kn: float) -> float:
        key = round(log_kn, 9)
        if key not in seen:
            seen[key] = float(error(10.0**key))
        return seen[key]

    lo, hi = math.log10(kn_min), math.log10(kn_max)
    points = [lo + (hi - lo) * k / (grid - 1) for k in range(grid)]
    best = min(points, key=f)
    k = points.index(best)
    a, b = points[max(k - 1, 0)], points[min(k + 1, grid - 1)]
    c, d = b - GOLDEN * (b - a), a + GOLDEN * (b - a)
    while b - a > tolerance and len(seen) < max_evaluations:
        if f(c) <= f(d):
            b, d = d, c
            c = b - GOLDEN * (b - a)
        else:
            a, c = c, d
            d = a + GOLDEN * (b - a)
    log_best = min(seen, key=seen.get)
    curve = sorted((10.0**x, e) for x, e in seen.items())
    return Calibration(10.0**log_best, seen[log_best], curve)


def mean_absolute_relative_error(computed: dict[str, float], experiment: dict[str, float]) -> float:
    """Mean of |computed - experiment| / experiment over the walls in ``computed`` (paper Table 3)."""
    return sum(abs(computed[d] - experiment[d]) / experiment[d] for d in computed) / len(computed)
