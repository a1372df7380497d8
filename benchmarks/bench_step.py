"""Cost of one explicit cycle per sub-contact: numba kernels against the NumPy reference.

The wall: the seed paper's bricks (25 x 5.5 x 12 mm), 8 per course, 27 courses, running bond,
33 % voids, 4 points per length in both directions of every face (the 3D grid; in-plane runs
use 2 across the width by default, half the sub-contacts) (drydem.walls.benchmark_wall),
settled under gravity and then tilted 10 deg so that every joint carries shear. Both engines run the same cycles from the same
state, on one core, in this process. Goals (issue 2): <= 15 ns per sub-contact-step for the
numba engine, >= 15x faster than the vectorised NumPy reference.

Run: python benchmarks/bench_step.py [--cycles N]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

import drydem as dd
from drydem import kernels, reference
from drydem.joints import JointArrays
from drydem.walls import benchmark_wall


def time_engine(run_cycles, sim, cycles: int, gravity) -> float:
    """Seconds per cycle of ``run_cycles`` from a copy of the simulation's state (best of 3)."""
    best = np.inf
    for _ in range(3):
        state = sim.state.copy()
        contacts = sim.contacts.copy()
        start = time.perf_counter()
        n, code, _, _ = run_cycles(
            state, sim._blocks, contacts, JointArrays.of(sim.model.joint), gravity, sim.timestep, 0.8, cycles,
            kernels.RATIO, -1.0, 1.0, 1.0, state.copy(), sim.neighbours._replace(limit=np.full(len(sim.neighbours.pairs), np.inf)), np.inf,
        )
        best = min(best, (time.perf_counter() - start) / n)
        assert code == kernels.RUNNING and n == cycles
    return best


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cycles", type=int, default=20_000, help="numba cycles per timing (the reference runs 1/100 of them)")
    args = parser.parse_args()

    model = benchmark_wall(kn=3e7, points_per_length=4, points_across=4)
    sim = dd.Simulation(model)
    sim.cycle_to_equilibrium()
    theta = np.radians(10.0)
    gravity = dd.G * np.array([np.sin(theta), 0.0, -np.cos(theta)])
    sim.cycle_to_equilibrium(gravity=gravity)
    ns = sim.contacts.count

    time_engine(kernels.run_cycles, sim, 10, gravity)  # compile / load the cache
    fast = time_engine(kernels.run_cycles, sim, args.cycles, gravity)
    slow = time_engine(reference.run_cycles, sim, max(10, args.cycles // 100), gravity)
    print(f"wall: {model.n_blocks} blocks, {len(sim.contacts.pairs)} contacts, {ns} sub-contacts, dt = {sim.timestep:.3g} s")
    print(f"numba      {fast * 1e6:9.2f} us/cycle  {fast / ns * 1e9:7.2f} ns per sub-contact-step  (goal <= 15)")
    print(f"reference  {slow * 1e6:9.2f} us/cycle  {slow / ns * 1e9:7.2f} ns per sub-contact-step")
    print(f"speed-up   {slow / fast:9.1f} x  (goal >= 15)")


if __name__ == "__main__":
    main()
