"""Dynamic time histories of a competition wall: model seconds per wall second, cycles.

Issue 16's goal (one core): 10 s of motion on WD3 at kn = 1e9 Pa/m in <= 5 s. The motion is a
synthetic accelerogram of earthquake-like content, the same in every run (seeded): a sum of
sines from 0.5 to 10 Hz with random phases and a Kanai-Tajimi-like spectrum (ground
frequency 2.5 Hz, damping 0.6), under a trapezoidal envelope (1 s rise, 5 s strong motion,
4 s decay), baseline-corrected and scaled to a PGA of 0.2 g. Each run settles the wall under
gravity first (timed apart); the dynamic stage is what the goal is about. The contacts'
damping ratio is given (0.2), so no restitution is calibrated.

Run: python benchmarks/bench_shake.py [--wall WD3] [--kn 3e7 1e9] [--duration 10] [--pga-g 0.2]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from drydem.analysis.shake import GroundMotion, ShakeSettings, shake_analysis
from drydem.analysis.shake.run import settle
from drydem.engine.simulation import Simulation
from drydem.io.target import load_target
from drydem.model.parameters import G, JointMaterial

GOAL_S = {1e9: 5.0}


def synthetic_record(duration_s: float, pga_g: float, *, seed: int = 16, dt_s: float = 0.005) -> GroundMotion:
    """The benchmark's accelerogram (module docstring), m/s2 along x."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, duration_s + dt_s / 2, dt_s)
    frequencies = np.linspace(0.5, 10.0, 200)
    ratio = frequencies / 2.5
    spectrum = (1 + 4 * 0.36 * ratio**2) / ((1 - ratio**2) ** 2 + 4 * 0.36 * ratio**2)
    phases = rng.uniform(0.0, 2 * np.pi, frequencies.size)
    signal = (np.sqrt(spectrum)[:, None] * np.sin(2 * np.pi * frequencies[:, None] * t + phases[:, None])).sum(axis=0)
    envelope = np.clip(np.minimum(t / 1.0, (duration_s - t) / 4.0), 0.0, 1.0)
    acceleration = np.zeros((t.size, 3))
    acceleration[:, 0] = signal * envelope
    motion = GroundMotion(t, acceleration, "synthetic").baseline_corrected()
    return motion.scaled(pga_g * G / motion.pga_m_s2)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--wall", default="WD3", help="a built-in wall or a wall/model file")
    parser.add_argument("--kn", type=float, nargs="+", default=[3e7, 1e9], help="joint stiffnesses kn = ks, Pa/m")
    parser.add_argument("--duration", type=float, default=10.0, help="record length, s")
    parser.add_argument("--pga-g", type=float, default=0.2, help="peak ground acceleration, g")
    args = parser.parse_args()
    wall = load_target(args.wall).model
    motion = synthetic_record(args.duration, args.pga_g)
    shake_analysis(wall, ShakeSettings(motion=motion, duration_s=0.01, contact_damping_ratio=0.2))  # compile / load the cache
    print(f"{'kn (Pa/m)':>10} {'cycles':>9} {'dt (s)':>9} {'settle (s)':>10} {'shake (s)':>9} {'model s/s':>9} {'goal (s)':>9} "
          f"{'max rot (rad)':>13} {'overturned':>10}")
    for kn in args.kn:
        model = wall.replace(joint=JointMaterial(kn=kn, ks=kn, friction=wall.joint.friction))
        settings = ShakeSettings(motion=motion, contact_damping_ratio=0.2)
        start = time.perf_counter()
        settle(Simulation(model), settings.lost_drop_heights)  # the analysis' first stage alone, timed apart
        settled = time.perf_counter() - start
        start = time.perf_counter()
        result = shake_analysis(model, settings)
        shake = time.perf_counter() - start - settled
        goal = GOAL_S.get(kn)
        print(
            f"{kn:10.3g} {result.cycles:9d} {result.timestep_s:9.3g} {settled:10.2f} {shake:9.2f} {result.duration_s / shake:9.2f} "
            f"{'-' if goal is None else f'{goal:.1f}':>9} {result.max_rotation_rad:13.3g} {result.overturned!s:>10}",
            flush=True,
        )


if __name__ == "__main__":
    main()
