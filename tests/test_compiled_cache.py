"""numba's cache of the compiled engine follows every source it is compiled from (drydem.compiled_cache)."""

import ast
import os
import pathlib
import shutil
import subprocess
import sys

import pytest

import drydem
from drydem import compiled_cache

#: a brick on a fixed slab, in-plane (drydem.engine.cycle_planar's kernel), on a table tilted 10 deg for 300
#: cycles: it sticks (friction 0.5 > tan 10 deg) and shears the joint elastically; prints its
#: displacement, m
SHEARED_BRICK = """
import numpy as np
import drydem as dd
from drydem.engine import cycle_planar

blocks = [dd.Block(name="slab", shape=dd.box([-0.1, 0.0, -0.02], [0.1, 0.012, 0.0]), fixed=True),
          dd.Block(name="brick", shape=dd.box([0.0, 0.0, 0.0], [0.025, 0.012, 0.0055]))]
model = dd.build_model(blocks, density=1800.0, supports=dd.Supports(fix_y=True))
sim = dd.Simulation(model)
assert sim.run_cycles is cycle_planar.run_cycles
theta = np.radians(10.0)
sim.cycle(300, gravity=dd.G * np.array([np.sin(theta), 0.0, -np.cos(theta)]))
print(sim.state.position[1, 0] - model.block_centroid[1, 0])
"""


def sheared_brick(package_parent, *, compiled):
    """SHEARED_BRICK's displacement, m, with drydem imported from ``package_parent`` and the
    kernels compiled (from numba's cache where it has them) or run as Python (NUMBA_DISABLE_JIT)."""
    env = {k: v for k, v in os.environ.items() if k not in ("NUMBA_CACHE_DIR", "NUMBA_DISABLE_JIT")}
    env |= {"PYTHONPATH": str(package_parent)} | ({} if compiled else {"NUMBA_DISABLE_JIT": "1"})
    run = subprocess.run([sys.executable, "-c", SHEARED_BRICK], capture_output=True, text=True, env=env, timeout=600)
    assert run.returncode == 0, run.stderr[-3000:]
    return float(run.stdout)


@pytest.mark.slow
def test_editing_the_joint_law_reaches_the_cached_planar_kernel(tmp_path):
    # halve ks in a copy's joints.py: numba alone would load cycle_planar.run_cycles from its cache
    # (cycle_planar.py did not change) with the old shear_law inlined, and part from the same code
    # run as Python
    shutil.copytree(pathlib.Path(drydem.__file__).parent, tmp_path / "drydem")  # with its caches: the first run loads them
    before = sheared_brick(tmp_path, compiled=True)
    joints = tmp_path / "drydem" / "engine" / "joints.py"
    law = joints.read_text()
    assert law.count("    return joint.ks * area") == 1  # the shear stiffness of a joint of constant stiffness
    joints.write_text(law.replace("    return joint.ks * area", "    return 0.5 * joint.ks * area"))
    after = sheared_brick(tmp_path, compiled=True)
    assert after == pytest.approx(sheared_brick(tmp_path, compiled=False), rel=1e-9)
    assert after > 1.5 * before > 0.0  # a softer joint: the brick slid further


def test_compiled_modules_are_keyed_on_what_they_import():
    # the inlined joint law, damping, loop and rotations; the SubContacts type and the narrow
    # phase's model-layer types
    planar = compiled_cache.dependencies("drydem.engine.cycle_planar")
    assert {"drydem.engine.joints", "drydem.engine.damping", "drydem.engine.loop", "drydem.model.rotation", "drydem.model.parameters"} <= planar
    narrow = compiled_cache.dependencies("drydem.engine.narrow_phase")
    assert {"drydem.engine.contacts", "drydem.model.geometry", "drydem.model.rotation"} <= narrow
    assert "drydem.engine.narrow_phase" not in planar


def test_every_compiled_module_checks_its_cache_folder_last():
    # compiled_cache.check(__name__) as the last statement: none of the module's functions can be
    # called (and loaded from the cache) before it, and no module is left unchecked
    for name in compiled_cache.compiled_modules():
        last = ast.parse(compiled_cache.module_file(name).read_text(encoding="utf-8")).body[-1]
        assert ast.unparse(last) == "compiled_cache.check(__name__)", name


def test_the_cache_check_is_not_a_source_of_the_kernels():
    # every compiled module imports compiled_cache to call check: editing it must not throw away
    # every cached kernel
    assert "drydem.compiled_cache" not in compiled_cache.dependencies("drydem.engine.cycle3d")


def test_cache_folders_are_where_numba_writes(tmp_path):
    # every module with cached functions has its folder found (numba's private cache attribute
    # still there), in __pycache__ beside the sources or, with NUMBA_CACHE_DIR, under it, and
    # the stamp is written there when a compiled module of the folder is imported
    names = [n for n in compiled_cache.compiled_modules() if compiled_cache.cache_folder(n) is not None]
    assert {
        "drydem.engine.joints", "drydem.engine.damping", "drydem.engine.loop", "drydem.engine.cycle3d", "drydem.engine.inertia",
        "drydem.engine.narrow_phase", "drydem.engine.broad_phase", "drydem.engine.cycle_planar", "drydem.engine.refresh",
        "drydem.model.rotation", "drydem.model.boxes", "drydem.analysis.support",
    } <= set(names)
    if not os.environ.get("NUMBA_CACHE_DIR"):
        assert compiled_cache.cache_folder("drydem.engine.narrow_phase") == compiled_cache.module_file("drydem.engine.narrow_phase").parent / "__pycache__"
    script = "from drydem import compiled_cache as c; print(c.cache_folder('drydem.engine.narrow_phase'))"
    env = os.environ | {"NUMBA_CACHE_DIR": str(tmp_path)}
    run = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, env=env, timeout=600)
    assert run.returncode == 0, run.stderr[-3000:]
    folder = pathlib.Path(run.stdout.strip())
    assert folder.parent == tmp_path and (folder / compiled_cache.STAMP).is_file()
