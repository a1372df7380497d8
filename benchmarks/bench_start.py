"""Start-up times: ``drydem --help``, ``import drydem`` and a one-block tilt end to end.

Issue 19's goals: ``drydem --help`` <= 0.3 s; a one-block tilt (a brick on a fixed base, the
model file of tests/test_model_file.py, every output written) <= 1 s with the kernels in numba's
cache. Each time is the median of --runs fresh processes, after one run not counted (it writes
Python's bytecode and, if the kernels are not cached yet, compiles them: it says so), with
Python's bytecode cache on as in an installed package (PYTHONDONTWRITEBYTECODE removed); the
bare interpreter's start (``python -c pass``) is printed for scale, and the tilt with
``--threads 1`` too: the two must be alike, a one-block model taking one thread whatever the
setting (drydem.engine.threads.threads_for; before it, with the other core busy, the default
2 threads took 54-72 s, numba's parallel loops waiting for a core at every cycle).

The floor under the tilt, printed too: ``import numba``, then the first call of any cached
kernel, a one-block box sweep (numba builds its target context then: it imports
numba.np.arraymath, whose BLAS check imports scipy.linalg, whatever the kernel), and the import
of matplotlib's Figure and Agg canvas (the figures). Measured 2026-11-25 (2 cores, idle):
python + numpy ~0.1 s, import numba 0.30 s, numba's first call 0.36-0.40 s (0.25 s of it
scipy.linalg), matplotlib 0.34-0.44 s, drawing and writing the two figures 0.45 s: the first
two alone are ~0.8 s of the 1 s goal before drydem reads its model, which is why the one-block
tilt stays at ~2 s.

Run: python benchmarks/bench_start.py [--runs 5]
"""

from __future__ import annotations

import argparse
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

#: the command line of ``drydem`` in this interpreter
DRYDEM = [sys.executable, "-c", "from drydem.cli import console; console()"]
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))  # the model lives with the tests
from test_model_file import GOOD as ONE_BLOCK  # noqa: E402  a brick on a fixed base: it slides at atan 0.5 = 26.6 deg
#: the goals, s (None: printed for scale)
GOALS_S = {"python -c pass": None, "python -c 'import drydem'": None, "drydem --help": 0.3, "drydem tilt one_block.toml": 1.0,
           "  the same, --threads 1": 1.0, "floor: import numba": None, "  + first cached call": None, "  matplotlib Figure, Agg": None}
#: the first call of a cached kernel (drydem.model.boxes' sort and sweep of one box): numba's target context built
FIRST_CALL = ("import numpy as np; from drydem.model.boxes import overlapping_pairs; "
              "overlapping_pairs(np.zeros((1, 3)), np.ones((1, 3)), np.ones(1, bool), 0.0)")


def seconds(command: list[str], env: dict[str, str]) -> float:
    """Wall time of ``command`` run to its end, s (it must succeed)."""
    start = time.perf_counter()
    subprocess.run(command, check=True, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return time.perf_counter() - start


def median_s(command_for_run, runs: int, env: dict[str, str]) -> float:
    """Median wall time of ``runs`` runs of ``command_for_run(k)``, after a first run not counted."""
    first = subprocess.run(command_for_run(0), check=True, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    said = [line for line in first.stderr.replace("\r", "\n").splitlines() if line.startswith("compiled in ")]
    if said:
        print(f"  (the first, uncounted run compiled the kernels: {said[-1]})", flush=True)
    return statistics.median(seconds(command_for_run(k), env) for k in range(1, runs + 1))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=5, help="runs timed per command")
    args = parser.parse_args()
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    folder = Path(tempfile.mkdtemp(prefix="bench_start-"))
    try:
        model = folder / "one_block.toml"
        model.write_text(ONE_BLOCK)
        commands = {
            "python -c pass": lambda k: [sys.executable, "-c", "pass"],
            "python -c 'import drydem'": lambda k: [sys.executable, "-c", "import drydem"],
            "drydem --help": lambda k: [*DRYDEM, "--help"],
            "drydem tilt one_block.toml": lambda k: [*DRYDEM, "tilt", str(model), "--out", str(folder / f"run-{k}")],
            "  the same, --threads 1": lambda k: [*DRYDEM, "tilt", str(model), "--threads", "1", "--out", str(folder / f"one-{k}")],
            "floor: import numba": lambda k: [sys.executable, "-c", "import numba"],
            "  + first cached call": lambda k: [sys.executable, "-c", FIRST_CALL],
            "  matplotlib Figure, Agg": lambda k: [sys.executable, "-c", "import matplotlib.figure, matplotlib.backends.backend_agg"],
        }
        print(f"{'command':<28} {'median (s)':>10} {'goal (s)':>9} {'/ goal':>7}   ({args.runs} runs, {os.cpu_count()} cores)")
        for name, command in commands.items():
            measured = median_s(command, args.runs, env)
            goal = GOALS_S[name]
            ratio = "-" if goal is None else f"{measured / goal:.2f}"
            print(f"{name:<28} {measured:10.3f} {'-' if goal is None else f'{goal:.1f}':>9} {ratio:>7}", flush=True)
    finally:
        shutil.rmtree(folder, ignore_errors=True)


if __name__ == "__main__":
    main()
