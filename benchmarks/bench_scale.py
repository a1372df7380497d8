"""Analyses at scale (issue 18's goals, 2 cores): the 60 x 60 brick in-plane wall's adaptive tilt
at kn = 3e7 Pa/m in <= 2 minutes, and the ~20,000-block building's gravity settlement in <= 2
minutes. Prints wall time, cycles, cycle rate and the outcome of each, measured in one run.

Run: python benchmarks/bench_scale.py [--threads N] [--cases wall60 building-large building-small] [--give-up-min 15]
"""

from __future__ import annotations

import argparse
import time

from drydem.analysis.tilt import TiltSettings, tilt_analysis
from drydem.engine.simulation import Simulation
from drydem.masonry.building import builtin_building
from drydem.masonry.walls import wall_from_dict

GOAL_S = 120.0
#: the settlement is given up (and said so) after this many cycles
MAX_SETTLEMENT_CYCLES = 100_000


def wall_60x60():
    """A 60-course running-bond wall of 60 bricks per course (half bricks at the ends of every
    other course): 3,630 bricks on a fixed base, the WD bricks (25 x 5.5 x 12 mm), kn = ks = 3e7."""
    courses = "\n".join("B" * 60 if row % 2 == 0 else "b" + "B" * 59 + "b" for row in range(60))
    data = {
        "wall": {"name": "wall60"}, "brick": {"length_m": 0.025, "height_m": 0.0055, "width_m": 0.012},
        "material": {"density": 1800.0}, "joint": {"kn": 3e7, "ks": 3e7, "friction": 0.5},
        "contacts": {"points_per_length": 4}, "supports": {"fix_y": True}, "layout": {"courses": courses},
    }
    return wall_from_dict(data, source="wall60").model()


class GaveUp(Exception):
    """The tilt ran past --give-up-min: what it had reached is reported instead of its end."""


def tilt_wall(give_up_s: float) -> str:
    """The 60 x 60 wall's adaptive tilt, its tilt printed every 30 s; given up after ``give_up_s``."""
    model = wall_60x60()
    start = time.perf_counter()
    reached = {"theta": 0.0, "cycles": 0, "printed": start}

    def progress(theta, cycles, ux) -> None:
        now = time.perf_counter()
        reached.update(theta=theta, cycles=cycles)
        if now - reached["printed"] >= 30.0:
            reached["printed"] = now
            print(f"  {now - start:.0f} s: tilt {theta:.2f} deg, {cycles} cycles, ux {ux * 1e3:.3f} mm", flush=True)
        if now - start > give_up_s:
            raise GaveUp

    try:
        result = tilt_analysis(model, TiltSettings(increment_deg=0.1, adaptive=True), on_progress=progress)
    except GaveUp:
        elapsed = time.perf_counter() - start
        return (f"wall60: {model.n_blocks} blocks, adaptive tilt GIVEN UP after {elapsed:.0f} s at tilt {reached['theta']:.2f} deg, "
                f"{reached['cycles']} cycles ({reached['cycles'] / elapsed:.0f} cycles/s), goal {GOAL_S:.0f} s")
    elapsed = time.perf_counter() - start
    return (f"wall60: {model.n_blocks} blocks, adaptive tilt: collapse {result.collapse_angle_deg} deg, ended by {result.ended_by}, "
            f"{result.cycles} cycles in {elapsed:.1f} s ({result.cycles / elapsed:.0f} cycles/s), goal {GOAL_S:.0f} s")


def settle_building(name: str) -> str:
    start = time.perf_counter()
    model = builtin_building(name)
    built = time.perf_counter() - start
    start = time.perf_counter()
    simulation = Simulation(model)
    outcome = simulation.cycle_to_equilibrium(max_cycles=MAX_SETTLEMENT_CYCLES, progress=_report(start))
    elapsed = time.perf_counter() - start
    return (f"{name}: {model.n_blocks} blocks built in {built:.1f} s, {simulation.contacts.count} sub-contacts; settlement: "
            f"converged {outcome.converged} after {outcome.cycles} cycles in {elapsed:.1f} s "
            f"({outcome.cycles / elapsed:.0f} cycles/s, {elapsed / max(outcome.cycles, 1) / max(simulation.contacts.count, 1) * 1e9:.1f} ns "
            f"per sub-contact-cycle), goal {GOAL_S:.0f} s")


def _report(start: float):
    """A progress callback printing cycles, unbalanced-force ratio and time so far."""
    def report(cycles, stats) -> None:
        print(f"  {cycles} cycles, ratio {stats.ratio:.2e}, {time.perf_counter() - start:.0f} s", flush=True)
    return report


CASES = ("building-small", "building-large", "wall60")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", nargs="+", choices=CASES, default=list(CASES))
    parser.add_argument("--threads", type=int, default=None, help="threads of the compiled kernels (default: all cores)")
    parser.add_argument("--give-up-min", type=float, default=15.0, help="wall60: stop the tilt after this many minutes and say where it was")
    args = parser.parse_args()
    from drydem.engine.threads import set_threads

    set_threads(args.threads)
    for case in args.cases:
        print(tilt_wall(args.give_up_min * 60.0) if case == "wall60" else settle_building(case), flush=True)


if __name__ == "__main__":
    main()
