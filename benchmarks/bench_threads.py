"""The 3D kernel on numba's threads: cost per sub-contact, its flatness with the model's size, and
parallel efficiency.

Models: 3D buildings (drydem.masonry.building; not held in y, so the 3D kernel, 4 x 4 points a
face) from two courses on a 0.5 m square plan (~1.3e3 sub-contacts) and two courses of the small
building's plan (~4e3) up to the small building itself (~7.5e4), and with --large the large one (~7e5). Each settles for a few hundred cycles under
gravity tilted 10 deg (every joint loaded, some shear), then the kernel's ``run_cycles`` runs a
fixed number of cycles from copies of that state, without re-detection (as benchmarks/bench_step.py).
Every number comes from this one run and process; each timing is the best of ``--repeats`` (the
spread, max / min, says how noisy the machine was).

Goals (issue 18): <= 15 ns per sub-contact-cycle on one thread; flat within 20 % from 1e3 to
1e5 sub-contacts; parallel efficiency t1 / (n t_n) >= 80 % on 2 cores.

Run: python benchmarks/bench_threads.py [--cycles N] [--repeats R] [--large]
"""

from __future__ import annotations

import argparse
import dataclasses
import time

import numpy as np

import drydem as dd
from drydem.engine import cycle3d, loop
from drydem.engine.damping import Damping
from drydem.engine.joints import kernel_joint
from drydem.engine.simulation import AT_REST
from drydem.engine.threads import available, using_threads
from drydem.masonry.building import LARGE, SMALL, building_model

GRAVITY = dd.G * np.array([np.sin(np.radians(10.0)), 0.0, -np.cos(np.radians(10.0))])
#: the small building's plan with fewer courses and no openings, and the small building: ~1e3 to ~1e5 sub-contacts
PLAIN = dict(storeys=1, windows_per_wall=0, sill_courses=0, window_height_courses=1, door_height_courses=0)
SIZES = {"0.5 m plan, 2 courses": dataclasses.replace(SMALL, length_m=0.5, width_m=0.5, storey_height_courses=2, **PLAIN)}
SIZES |= {f"{k} courses": dataclasses.replace(SMALL, storey_height_courses=k, **PLAIN) for k in (2, 6, 16)}
SIZES["SMALL (40 courses)"] = SMALL


def settled(spec, cycles: int = 300) -> dd.Simulation:
    sim = dd.Simulation(building_model(spec), engine="numba-3d")
    sim.cycle(cycles, gravity=GRAVITY)
    return sim


def timings(sim: dd.Simulation, cycles: int, repeats: int) -> np.ndarray:
    """Seconds per cycle of ``repeats`` runs of ``cycles`` cycles from copies of the state."""
    joint = kernel_joint(sim.model.joint)
    unlimited = sim.neighbours._replace(limit=np.full(len(sim.neighbours.pairs), np.inf))
    out = []
    for _ in range(repeats):
        state, contacts = sim.state.copy(), sim.contacts.copy()
        settings = loop.LoopSettings(GRAVITY, sim.timestep, Damping(0.8), cycles, loop.RATIO, -1.0, 1.0, np.inf, np.inf, AT_REST,
                                     sim.closure_limit, sim.timestep)
        start = time.perf_counter()
        n, code, _, _ = cycle3d.run_cycles(state, sim.blocks, contacts, joint, settings, state.copy(), unlimited)
        out.append((time.perf_counter() - start) / n)
        assert code == loop.RUNNING and n == cycles, code
    return np.array(out)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cycles", type=int, default=2_000_000, help="sub-contact-cycles per timing, in all (spread over the cycles)")
    parser.add_argument("--repeats", type=int, default=5, help="timings of each case (the best counts)")
    parser.add_argument("--large", action="store_true", help="also the large building (~7e5 sub-contacts; slow to build)")
    args = parser.parse_args()
    sizes = dict(SIZES, **({"LARGE": LARGE} if args.large else {}))
    threads = list(range(1, available() + 1))
    print(f"numba threads available: {available()}; {args.repeats} timings per case, best (and max / min)")
    rows = {}
    for name, spec in sizes.items():
        sim = settled(spec)
        ns = sim.contacts.count
        cycles = max(20, args.cycles // ns)
        with using_threads(1):
            timings(sim, 5, 1)  # compile or load from the cache
        per_thread = {}
        for n in threads:
            with using_threads(n):
                per_thread[n] = timings(sim, cycles, args.repeats)
        rows[name] = (sim.model.n_blocks, len(sim.contacts.pairs), ns, cycles, per_thread)
        best = {n: t.min() for n, t in per_thread.items()}
        line = "  ".join(f"{n} thr {best[n] / ns * 1e9:6.2f} ns (x{t.max() / t.min():4.2f}) eff {best[1] / (n * best[n]):4.0%}"
                         for n, t in per_thread.items())
        print(f"{name:22s} {sim.model.n_blocks:6d} blocks {len(sim.contacts.pairs):7d} contacts {ns:8d} sub-contacts "
              f"{cycles:6d} cycles | {line}", flush=True)
    one = {name: row[4][1].min() / row[2] * 1e9 for name, row in rows.items()}
    print(f"one thread: {min(one.values()):.2f} to {max(one.values()):.2f} ns per sub-contact-cycle (goal <= 15); "
          f"flatness max / min {max(one.values()) / min(one.values()):.3f} (goal <= 1.20)")
    for n in threads[1:]:
        eff = {name: row[4][1].min() / (n * row[4][n].min()) for name, row in rows.items()}
        print(f"parallel efficiency on {n} threads: " + ", ".join(f"{name} {e:.0%}" for name, e in eff.items()) + " (goal >= 80 % on 2)")


if __name__ == "__main__":
    main()
