"""Every script in examples/ runs: in a fresh working folder, it exits with 0 and every file its
last line says it wrote (``wrote PATH, PATH, ...``, the examples' convention) is there and not
empty."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

EXAMPLES = sorted((Path(__file__).resolve().parents[1] / "examples").glob("*.py"))


def test_there_are_examples():
    assert EXAMPLES  # a glob that found nothing would pass the test below


@pytest.mark.slow
@pytest.mark.parametrize("script", EXAMPLES, ids=lambda path: path.name)
def test_an_example_runs_and_writes_what_it_says(script, tmp_path):
    # one thread each: the kernels' threads would spin against the other tests on a shared machine
    environment = os.environ | {"NUMBA_NUM_THREADS": "1", "MPLBACKEND": "Agg"}
    run = subprocess.run([sys.executable, str(script)], cwd=tmp_path, env=environment, capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr[-3000:]
    last = run.stdout.strip().splitlines()[-1]
    assert last.startswith("wrote "), f"{script.name}: its last line should name what it wrote: {last!r}"
    written = [tmp_path / name for name in last.removeprefix("wrote ").split(", ")]
    assert all(path.is_file() and path.stat().st_size > 0 for path in written), [str(p) for p in written if not p.is_file()]
