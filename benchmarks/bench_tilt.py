"""Full tilting analyses of a competition wall: wall time, cycles and collapse angles.

Issue 3's goals (one core): kn = 3e7 Pa/m <= 3 s fixed and <= 0.5 s adaptive; kn = 1e9 Pa/m
<= 20 s fixed and <= 4 s adaptive, for a 30 %-void competition wall with 4 points per length:
here the built-in WD3 (a reconstruction, 30.1 % voids), kn = ks. Cycles count every cycle run,
those of abandoned adaptive trials included.

Run: python benchmarks/bench_tilt.py [--wall WD3] [--kn 3e7 1e9] [--increment 0.1] [--protocol fixed adaptive]
"""

from __future__ import annotations

import argparse
import time

from drydem.analysis.tilt import TiltSettings, tilt_analysis
from drydem.io.target import load_target
from drydem.model.parameters import JointMaterial

GOALS_S = {(3e7, False): 3.0, (3e7, True): 0.5, (1e9, False): 20.0, (1e9, True): 4.0}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--wall", default="WD3", help="a built-in wall or a wall/model file")
    parser.add_argument("--kn", type=float, nargs="+", default=[3e7, 1e9], help="joint stiffnesses kn = ks, Pa/m")
    parser.add_argument("--increment", type=float, default=0.1, help="tilt step, deg")
    parser.add_argument("--protocol", nargs="+", choices=["fixed", "adaptive"], default=["fixed", "adaptive"])
    args = parser.parse_args()
    wall = load_target(args.wall).model
    tilt_analysis(wall, TiltSettings(increment_deg=30.0, max_angle_deg=30.0))  # compile / load the cache
    print(f"{'kn (Pa/m)':>10} {'protocol':>9} {'collapse (deg)':>15} {'DLS (deg)':>10} {'cycles':>9} {'time (s)':>9} {'goal (s)':>9}")
    for kn in args.kn:
        for protocol in args.protocol:
            adaptive = protocol == "adaptive"
            model = wall.replace(joint=JointMaterial(kn=kn, ks=kn, friction=wall.joint.friction))
            start = time.perf_counter()
            result = tilt_analysis(model, TiltSettings(increment_deg=args.increment, adaptive=adaptive))
            elapsed = time.perf_counter() - start
            dls = result.drift_limit_angles_deg[0.01]
            goal = GOALS_S.get((kn, adaptive))
            print(
                f"{kn:10.3g} {protocol:>9} {result.collapse_angle_deg!s:>15} {'-' if dls is None else f'{dls:.2f}':>10} "
                f"{result.cycles:9d} {elapsed:9.1f} {'-' if goal is None else f'{goal:.1f}':>9}",
                flush=True,
            )


if __name__ == "__main__":
    main()
