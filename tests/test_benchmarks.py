"""Every benchmark still runs: each script on its smallest case, as a user would start it.

The benchmarks measure the performance goals on demand and are timed nowhere here (machines
are shared and noisy); this only checks that they run to their table without an error, since
nothing else imports them (bench_tilt.py read the drift limits by a key the results no longer
had, a KeyError found only when the numbers were wanted).
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

BENCHMARKS = Path(__file__).resolve().parents[1] / "benchmarks"


@pytest.mark.slow
@pytest.mark.parametrize("script, arguments, printed", [
    ("bench_tilt.py", ["--kn", "3e7", "--increment", "5", "--protocol", "fixed"], "collapse (deg)"),
    ("bench_limit.py", ["--cases", "wall20"], "wall20"),
    ("bench_montecarlo.py", ["--samples", "2", "--workers", "1", "--increment", "2"], "collapse angle"),
    ("bench_shake.py", ["--kn", "3e7", "--duration", "0.5"], "model s/s"),
    ("bench_step.py", ["--cycles", "20"], "speed-up of numba 3D over the reference"),
    ("bench_threads.py", ["--cycles", "5", "--repeats", "1"], "parallel efficiency on 2 threads"),
    ("bench_scale.py", ["--cases", "building-small"], "building-small: 1936 blocks"),
    ("bench_start.py", ["--runs", "1"], "drydem --help"),
])
def test_the_benchmark_runs_to_its_table(tmp_path, script, arguments, printed):
    done = subprocess.run([sys.executable, str(BENCHMARKS / script), *arguments], capture_output=True, text=True,
                          timeout=600, cwd=tmp_path)
    assert done.returncode == 0, (done.stdout + done.stderr)[-3000:]
    assert printed in done.stdout and "Traceback" not in done.stderr
