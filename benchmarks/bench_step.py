"""Cost of one explicit cycle: the numba kernels (3D and planar) against the NumPy reference.

The wall: the seed paper's bricks (25 x 5.5 x 12 mm), 8 per course, 27 courses, running bond,
33 % voids, 4 points per length in both directions of every face (the 3D grid)
(tests/wall_fixtures.py), settled under gravity and then tilted 10 deg so that every
joint carries shear. Every engine runs the same cycles from the same state, on one core, in
this process. Goals (issue 2): <= 15 ns per sub-contact-step for the 3D numba kernel, >= 15x
faster than the vectorised NumPy reference. The wall is in-plane, so drydem cycles it with the
planar kernel (drydem.engine.cycle_planar) and one point across the width (its default there): timed on
the same 3D grid and on that default, against the 3D kernel on the grid.

Run: python benchmarks/bench_step.py [--cycles N]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

import drydem as dd
from drydem.engine import cycle3d, cycle_planar, loop
from drydem.engine.damping import Damping
from drydem.engine.joints import kernel_joint
from drydem.engine.simulation import AT_REST
from drydem.engine.threads import using_threads

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))  # the oracles and the wall live with the tests
from oracles import cycle as reference  # noqa: E402
from wall_fixtures import benchmark_wall  # noqa: E402


def time_engine(run_cycles, sim, cycles: int, gravity) -> float:
    """Seconds per cycle of ``run_cycles`` from a copy of the simulation's state (best of 3)."""
    best = np.inf
    for _ in range(3):
        state = sim.state.copy()
        contacts = sim.contacts.copy()
        start = time.perf_counter()
        settings = loop.LoopSettings(gravity, sim.timestep, Damping(0.8), cycles, loop.RATIO, -1.0, 1.0, 1.0, np.inf, AT_REST, sim.closure_limit, sim.timestep)
        unlimited = sim.neighbours._replace(limit=np.full(len(sim.neighbours.pairs), np.inf))
        n, code, _, _ = run_cycles(state, sim.blocks, contacts, kernel_joint(sim.model.joint), settings, state.copy(), unlimited)
        best = min(best, (time.perf_counter() - start) / n)
        assert code == loop.RUNNING and n == cycles
    return best


def tilted_wall(points_across: int | None) -> dd.Simulation:
    """The benchmark wall settled, then at equilibrium at 10 deg."""
    sim = dd.Simulation(benchmark_wall(kn=3e7, points_per_length=4, points_across=points_across))
    sim.cycle_to_equilibrium()
    sim.cycle_to_equilibrium(gravity=GRAVITY)
    return sim


GRAVITY = dd.G * np.array([np.sin(np.radians(10.0)), 0.0, -np.cos(np.radians(10.0))])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cycles", type=int, default=20_000, help="numba cycles per timing (the reference runs 1/100 of them)")
    args = parser.parse_args()

    grid, default = tilted_wall(4), tilted_wall(None)
    timings = {}
    # one core, as drydem runs a wall this small (threads_for): numba's parallel loops would
    # otherwise wake a second thread at every one of them (~3x the cycle of 1,363 sub-contacts)
    with using_threads(1):
        for name, run_cycles, sim, cycles in [
            ("numba 3D, 4 across", cycle3d.run_cycles, grid, args.cycles),
            ("reference, 4 across", reference.run_cycles, grid, max(10, args.cycles // 100)),
            ("planar, 4 across", cycle_planar.run_cycles, grid, args.cycles),
            ("planar, 1 across", cycle_planar.run_cycles, default, args.cycles),
        ]:
            time_engine(run_cycles, sim, 10, GRAVITY)  # compile / load the cache
            timings[name] = (time_engine(run_cycles, sim, cycles, GRAVITY), sim.contacts.count)
    print(f"wall: {grid.model.n_blocks} blocks, {len(grid.contacts.pairs)} contacts, dt = {grid.timestep:.3g} s (3D grid)")
    fast = timings["numba 3D, 4 across"][0]
    for name, (seconds, ns) in timings.items():
        goal = "  (goal <= 15)" if name.startswith("numba") else ""
        print(f"{name:20s} {seconds * 1e6:9.2f} us/cycle  {ns:5d} sub-contacts  {seconds / ns * 1e9:7.2f} ns per sub-contact-step{goal}"
              f"  {fast / seconds:6.2f} x the 3D kernel")
    print(f"speed-up of numba 3D over the reference {timings['reference, 4 across'][0] / fast:9.1f} x  (goal >= 15)")


if __name__ == "__main__":
    main()
