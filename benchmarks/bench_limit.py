"""Limit analysis at scale (issue 18): the time of each stage for a 60 x 60 brick in-plane wall
(3,631 blocks) and the 3D buildings SMALL (1,936 blocks) and LARGE (19,853 blocks).

Stages: contact detection (ContactTracker at the corners), assembly (equilibrium matrix and the
LP's columns, or the cones'), the solve (HiGHS: scipy.optimize.linprog; 3D, Clarabel on the exact
Coulomb cones: timed around the call) and the mechanism (velocities from the duals). Goal: LARGE
in <= 60 s on 2 cores.

Run: python benchmarks/bench_limit.py [--cases wall60 small large] [--method highs-ipm] [--non-associative] [--pyramid]
"""

from __future__ import annotations

import argparse
import time

import drydem as dd
from drydem.analysis import limit as la
from drydem.analysis.limit import LimitSettings, limit_analysis
from drydem.masonry import building
from drydem.masonry.brief import PAPER_BRICK
from drydem.masonry.layout import parse_layout


def brick_wall(bricks: int, courses: int, mu: float = 0.6) -> dd.Model:
    """In-plane running bond of the paper's bricks, ``bricks`` long and ``courses`` high (60 x 60: 3,631 blocks)."""
    text = "".join(f"{bricks}B\n" if c % 2 else f"b{bricks - 1}Bb\n" for c in range(courses))
    return dd.build_model(parse_layout(text, PAPER_BRICK).blocks(PAPER_BRICK), density=1800.0,
                          joint=dd.JointMaterial(kn=1e10, ks=1e10, friction=mu), supports=dd.Supports(fix_y=True))


CASES = {
    "wall60": lambda: brick_wall(60, 60),
    "wall20": lambda: brick_wall(20, 20),
    "small": lambda: building.building_model(building.SMALL),
    "large": lambda: building.building_model(building.LARGE),
}


class Clock:
    """Seconds per stage: the progress callback marks contact detection and assembly; the
    solver and the mechanism are timed around their calls."""

    def __init__(self):
        self.seconds: dict[str, float] = {}
        self.mark, self.stage = time.perf_counter(), None

    def switch(self, stage: str | None) -> None:
        now = time.perf_counter()
        if self.stage is not None:
            self.seconds[self.stage] = self.seconds.get(self.stage, 0.0) + now - self.mark
        self.mark, self.stage = now, stage

    def progress(self, line: str) -> None:
        print(f"    {line}", flush=True)
        self.switch("contacts" if line.startswith("finding") else "assembly")

    def wrap(self, function, stage: str):
        def timed(*args, **kwargs):
            previous = self.stage
            self.switch(stage)
            try:
                return function(*args, **kwargs)
            finally:
                self.switch(previous if stage == "solve" else None)
        return timed


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", nargs="+", choices=list(CASES), default=["wall60", "small", "large"])
    parser.add_argument("--method", default=la.METHOD, choices=list(la.SOLVER_NAMES), help="scipy.optimize.linprog's HiGHS method")
    parser.add_argument("--non-associative", action="store_true")
    parser.add_argument("--tilt-axis", choices=list(la.TILT_AXES), default="y")
    parser.add_argument("--pyramid", action="store_true", help="3D: the 16-sided pyramid's LP by HiGHS, not the exact cone by Clarabel")
    args = parser.parse_args()
    la.METHOD = args.method
    la.EXACT_CONE = not args.pyramid
    solve, cone, mechanism = la.linprog, la._clarabel, la._mechanism
    print(f"{'case':>8} {'blocks':>7} {'lambda':>12} {'contacts':>9} {'assembly':>9} {'solve':>9} {'mechanism':>10} {'total':>9}  (s)")
    for case in args.cases:
        start = time.perf_counter()
        model = CASES[case]()
        print(f"  {case}: {model.n_blocks} blocks built in {time.perf_counter() - start:.1f} s", flush=True)
        clock = Clock()
        la.linprog, la._clarabel, la._mechanism = clock.wrap(solve, "solve"), clock.wrap(cone, "solve"), clock.wrap(mechanism, "mechanism")
        try:
            start = time.perf_counter()
            result = limit_analysis(model, LimitSettings(non_associative=args.non_associative, tilt_axis=args.tilt_axis),
                                    on_progress=clock.progress)
            total = time.perf_counter() - start
        finally:
            la.linprog, la._clarabel, la._mechanism = solve, cone, mechanism
        s = clock.seconds
        print(f"{case:>8} {model.n_blocks:7d} {result.load_multiplier:12.8f} {s.get('contacts', 0):9.2f} {s.get('assembly', 0):9.2f} "
              f"{s.get('solve', 0):9.2f} {s.get('mechanism', 0):10.2f} {total:9.2f}", flush=True)


if __name__ == "__main__":
    main()
