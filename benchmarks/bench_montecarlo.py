"""A Monte Carlo of a competition wall: wall time of the run and per sample.

Issue 17's goal: 100 samples of WD3 at the paper's 0.1 deg protocol (adaptive, kn = 3e7 Pa/m,
the wall file's) in <= 5 minutes on 2 cores. Each sample is drydem montecarlo's: the wall with
its brick heights drawn (sd 0.1 mm, about 2 % of the 5.5 mm brick: the scatter of real bricks)
and a tilting analysis, on one worker process per core reused across samples, no figures per
sample. The time per sample is the wall time over the samples times the workers (the core-
seconds each costs, worker start included), beside the mean of the samples' own analysis times.

Run: python benchmarks/bench_montecarlo.py [--wall WD3] [--samples 100] [--workers 2] [--height-sd 0.1] [--increment 0.1] [--fixed]
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

from drydem.parametric.montecarlo import MonteCarloSettings, monte_carlo
from drydem.analysis.tilt import TiltSettings
from drydem.io.target import load_target
from drydem.masonry.imperfections import Imperfections
from drydem.parametric.workers import open_workers

GOAL_S = 300.0


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--wall", default="WD3", help="a built-in wall or a wall file")
    parser.add_argument("--samples", type=int, default=100)
    parser.add_argument("--workers", type=int, default=2, help="local processes")
    parser.add_argument("--height-sd", type=float, default=0.1, help="brick height standard deviation, mm")
    parser.add_argument("--increment", type=float, default=0.1, help="tilt step, deg")
    parser.add_argument("--fixed", action="store_true", help="fixed steps instead of the adaptive protocol")
    args = parser.parse_args()
    wall = load_target(args.wall).wall
    settings = MonteCarloSettings(samples=args.samples, seed=0, imperfections=Imperfections(height_sd_mm=args.height_sd),
                                  tilt=TiltSettings(increment_deg=args.increment, adaptive=not args.fixed))
    with tempfile.TemporaryDirectory() as folder:
        start = time.perf_counter()
        with open_workers(args.workers) as pool:
            outcome = monte_carlo(wall, settings, Path(folder), pool.executor, target={"name": args.wall}, in_flight=pool.slots)
        elapsed = time.perf_counter() - start
    summary = outcome.summary
    analysis_s = [s["runtime_s"] for s in summary["samples"]]
    collapse, dls = summary["collapse_angle_deg"], summary["dls_angle_deg"]
    print(f"{args.wall}: {args.samples} samples, height sd {args.height_sd} mm, {'fixed' if args.fixed else 'adaptive'} "
          f"{args.increment} deg, {args.workers} workers")
    print(f"wall time        {elapsed:.1f} s (goal {GOAL_S:.0f} s for 100 samples on 2 cores)")
    print(f"per sample       {elapsed * args.workers / args.samples:.2f} core-s (wall time x workers / samples); analysis "
          f"{sum(analysis_s) / len(analysis_s):.2f} s mean, {max(analysis_s):.2f} s max")
    print(f"collapse angle   mean {collapse['mean']:.2f} deg, std {collapse['std']:.2f} deg, p05 {collapse['p05']:.2f} deg "
          f"({collapse['count']} samples)")
    if dls["count"]:
        print(f"DLS angle        mean {dls['mean']:.2f} deg, std {dls['std'] or 0.0:.2f} deg, p05 {dls['p05']:.2f} deg ({dls['count']} samples)")


if __name__ == "__main__":
    main()
