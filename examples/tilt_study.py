"""A tilting-table study of a small dry-joint wall, from Python, end to end.

1. a wall built from its brick layout (the README's demo wall: an opening under a lintel,
   running and honeycomb bond),
2. tilted to collapse (adaptive steps down to 0.1 deg): its collapse angle and Eurocode 8
   drift-limit angles (the tilt at which the top's drift reaches 0.5 %, 0.75 % and 1 %),
3. its pushover curve as a pandas DataFrame, saved as CSV,
4. its limit analysis (rigid blocks, associative friction: an upper bound of the capacity),
5. a small sweep of the joint stiffness kn = ks (1e7, 3e7, 1e8 Pa/m),
6. a figure of the pushover curve and of the collapse angle against kn.

A collapse angle is found to the tilt step, and round-off can move it by more (``drydem
calibrate`` measures by how much): read the sweep's differences of a few tenths of a degree as
noise, not as the effect of kn.

Writes tilt_study/pushover.csv, tilt_study/sweep.csv and tilt_study/tilt_study.png in the working
folder. Run it with ``python examples/tilt_study.py`` (pandas needed: ``pip install -e ".[data]"``):
about 7 s on one core (2026-11-25) once drydem's kernels are compiled (the first run compiles them).
"""

from pathlib import Path

import matplotlib.pyplot as plt
import pandas as pd

from drydem.analysis.limit import LimitSettings, limit_analysis
from drydem.analysis.tilt import TiltSettings, tilt_analysis
from drydem.masonry.walls import wall_from_dict

WALL = {
    "wall": {"name": "demo", "title": "a two-brick opening under a lintel"},
    "brick": {"length_m": 0.025, "height_m": 0.0055, "width_m": 0.012},
    "joint": {"kn": 3e7, "ks": 3e7, "friction": 0.5},
    "supports": {"fix_y": True},
    "layout": {"courses": "5B\nb4Bb\nBLB\nBb__bB\nbB__Bb\n5B\nB,B.B,B\nbB.B.Bb\n5B\n"},
}
SETTINGS = TiltSettings(increment_deg=0.1, adaptive=True)  # the paper's step, adaptive
OUT = Path("tilt_study")


def main() -> None:
    OUT.mkdir(exist_ok=True)
    model = wall_from_dict(WALL, source="demo wall").model()
    print(f"{model.n_blocks} blocks")

    result = tilt_analysis(model, SETTINGS)
    print(f"collapse angle  {result.collapse_angle_deg} deg ({result.ended_by})")
    for drift, angle in result.drift_limit_angles_deg.items():  # keyed by the drift: 0.005, 0.0075, 0.01
        print(f"drift {drift:.2%}     " + ("not reached before the collapse" if angle is None else f"reached at {angle:.1f} deg"))
    curve = result.to_dataframe()  # tilt_deg, load_multiplier, ux_m, uz_m, drift, cycles
    curve.to_csv(OUT / "pushover.csv", index=False)

    limit = limit_analysis(model, LimitSettings())
    print(f"limit analysis  {limit.collapse_angle_deg:.1f} deg (upper bound, associative)")

    runs = {3e7: result} | {kn: tilt_analysis(model.overridden(kn=kn, ks=kn), SETTINGS) for kn in (1e7, 1e8)}
    sweep = pd.DataFrame([{"kn_Pa_m": kn, "collapse_angle_deg": run.collapse_angle_deg,
                           "drift_0.5%_angle_deg": run.drift_limit_angles_deg[0.005]} for kn, run in sorted(runs.items())])
    sweep.to_csv(OUT / "sweep.csv", index=False)
    print(sweep.to_string(index=False))

    figure, (left, right) = plt.subplots(1, 2, figsize=(9, 3.5))
    left.plot(curve["drift"] * 100, curve["tilt_deg"], marker=".")
    left.axhline(limit.collapse_angle_deg, color="grey", linestyle="--", label="limit analysis")
    for k, drift in enumerate(result.drift_limit_angles_deg):
        left.axvline(drift * 100, color="tab:red", linewidth=0.8, label=None if k else "drift limits (EC8)")
    left.set(xlabel="drift of the top (%)", ylabel="tilt (deg)", title="pushover, kn = 3e7 Pa/m", xlim=(0.0, 2.0))
    left.legend()
    right.semilogx(sweep["kn_Pa_m"], sweep["collapse_angle_deg"], marker="o")
    right.set(xlabel="kn = ks (Pa/m)", ylabel="collapse angle (deg)", title="stiffness sweep")
    figure.tight_layout()
    figure.savefig(OUT / "tilt_study.png", dpi=100)
    print(f"wrote {OUT / 'pushover.csv'}, {OUT / 'sweep.csv'}, {OUT / 'tilt_study.png'}")


if __name__ == "__main__":
    main()
