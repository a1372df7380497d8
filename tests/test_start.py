"""Starting fast (issue 19): the command line and ``import drydem`` import no numerical library
they do not use, and a first run says that it compiles the kernels, a warm cache nothing.
Structural checks, not timings: benchmarks/bench_start.py measures the times."""

import json
import os
import subprocess
import sys
import textwrap

import pytest

import drydem
from drydem import compiled_cache

#: what starting takes longest to import (python -X importtime): none is needed to read options
HEAVY = ("numba", "numpy", "scipy", "scipy.spatial", "matplotlib", "dask", "meshio", "tqdm", "drydem.engine.simulation",
         "drydem.model.assembly")


def imported_after(code: str) -> list[str]:
    """The modules of :data:`HEAVY` imported after running ``code`` in a fresh interpreter."""
    script = f"{code}\nimport sys\nprint('imported:', *(m for m in {HEAVY!r} if m in sys.modules))"
    run = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stderr[-3000:]
    last = run.stdout.splitlines()[-1].split()
    assert last[0] == "imported:", run.stdout[-3000:]
    return last[1:]


@pytest.mark.parametrize("code", [
    "import drydem",
    "import drydem.cli",
    "from drydem.cli import main\nmain(['--help'], standalone_mode=False)",
    "from drydem.cli import main\nmain(['tilt', '--help'], standalone_mode=False)",
], ids=["import drydem", "import drydem.cli", "drydem --help", "drydem tilt --help"])
def test_starting_imports_no_numerical_library(code):
    assert imported_after(code) == []


def test_the_api_is_imported_at_its_first_use():
    from drydem.engine.simulation import Simulation
    from drydem.model.assembly import build_model

    assert drydem.Simulation is Simulation and drydem.build_model is build_model
    assert set(drydem.__all__) <= set(dir(drydem))
    with pytest.raises(AttributeError, match="module 'drydem' has no attribute 'Simulator'"):
        drydem.Simulator  # noqa: B018 (the attribute access is the test)


#: a module with one cached compiled function, and a script compiling it (or loading it from
#: numba's cache) under compiled_cache.compile_notice
KERNEL = "import numba\n\n@numba.njit(cache=True)\ndef add_one(x):\n    return x + 1\n"
RUN_KERNEL = textwrap.dedent("""
    import numba
    from drydem.compiled_cache import compile_notice

    with compile_notice():
        import kernel
        assert kernel.add_one(1) == 2
""")


def run_kernel(tmp_path) -> str:
    """The standard error of RUN_KERNEL with the kernel's cache in tmp_path/cache."""
    (tmp_path / "kernel.py").write_text(KERNEL)
    env = os.environ | {"NUMBA_CACHE_DIR": str(tmp_path / "cache"), "PYTHONPATH": str(tmp_path)}
    run = subprocess.run([sys.executable, "-c", RUN_KERNEL], capture_output=True, text=True, timeout=300, env=env)
    assert run.returncode == 0, run.stderr[-3000:]
    return run.stderr


def test_a_compile_is_announced_and_timed_and_a_warm_cache_says_nothing(tmp_path):
    cold = run_kernel(tmp_path)
    assert f"compiling the kernels once (about {compiled_cache.FIRST_COMPILE_S:.0f} s)" in cold and "compiled in " in cold
    assert run_kernel(tmp_path) == ""  # loaded from numba's cache: not a word
    # the next compile announces the time the last one took, kept beside the cache files
    [index] = (tmp_path / "cache").rglob("kernel.add_one-*.nbi")
    kept = json.loads((index.parent / compiled_cache.COMPILE_TIME).read_text())["seconds"]
    assert 0.0 < kept < 300.0
    (index.parent / compiled_cache.COMPILE_TIME).write_text(json.dumps({"seconds": 12.0}))
    index.unlink()
    assert "compiling the kernels once (about 12 s)" in run_kernel(tmp_path)


@pytest.mark.parametrize("kept", [None, "not json", '{"seconds": -1}', '{"seconds": "ten"}', '[12]'])
def test_a_missing_or_broken_compile_time_announces_the_documented_estimate(tmp_path, kept):
    if kept is not None:
        (tmp_path / compiled_cache.COMPILE_TIME).write_text(kept)
    assert compiled_cache._last_compile_s(tmp_path) == compiled_cache.FIRST_COMPILE_S
