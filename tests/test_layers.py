"""The package's layers: each module imports only from its own layer and those below it, and
nothing in src/ imports the tests' oracles (issue 15).

data model -> engine -> masonry -> analyses -> io -> parametric studies -> reports -> cli, on a
foundation (errors, files, compiled_cache) that everything may use. Every import counts, those
inside functions too: a lazy import upwards is still a dependency upwards.
"""

import ast
import pathlib

import pytest

import drydem

PACKAGE = pathlib.Path(drydem.__file__).parent
#: the layers from the bottom; a module belongs to the first whose prefix it has
LAYERS = [
    ("drydem.errors", "drydem.files", "drydem.compiled_cache"),
    ("drydem.model",),
    ("drydem.engine",),
    ("drydem.masonry",),
    ("drydem.analysis",),
    ("drydem.io",),
    ("drydem.parametric",),
    ("drydem.report",),
    ("drydem.cli",),
]


def layer(module: str) -> int | None:
    """The layer of a drydem module (None: the package itself, which re-exports the API)."""
    for level, prefixes in enumerate(LAYERS):
        if any(module == p or module.startswith(p + ".") for p in prefixes):
            return level
    return None


def module_name(path: pathlib.Path) -> str:
    parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def imports(path: pathlib.Path) -> list[tuple[int, str]]:
    """(line, module) of every import in a source file, function-level ones included; ``from
    package import name`` counts as ``package.name`` when that is a module."""
    found = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            found += [(node.lineno, alias.name) for alias in node.names]
        elif isinstance(node, ast.ImportFrom) and node.module:
            for alias in node.names:
                candidate = f"{node.module}.{alias.name}"
                is_module = any(PACKAGE.parent.joinpath(*candidate.split(".")).with_suffix(s).exists() for s in (".py", ""))
                found.append((node.lineno, candidate if is_module else node.module))
    return found


SOURCES = sorted(PACKAGE.rglob("*.py"))


def test_every_module_has_a_layer():
    assert [module_name(p) for p in SOURCES if layer(module_name(p)) is None] == ["drydem"]


@pytest.mark.parametrize("path", SOURCES, ids=lambda p: module_name(p))
def test_imports_go_down_the_layers_and_never_to_an_oracle(path):
    importer = module_name(path)
    upward = []
    for line, module in imports(path):
        if module.split(".")[0] == "oracles":
            upward.append(f"line {line}: {module} (a test oracle)")
        elif module.startswith("drydem") and importer != "drydem":
            level, own = layer(module), layer(importer)
            if level is not None and level > own:
                upward.append(f"line {line}: {module} (layer {LAYERS[level][0]} above {LAYERS[own][0]})")
    assert not upward, f"{importer} imports upwards: {upward}"


def test_the_check_sees_an_upward_import(tmp_path):
    # the rule itself: a model module importing the engine, lazily, is caught
    source = tmp_path / "bad.py"
    source.write_text("def f():\n    from drydem.engine.simulation import Simulation\n")
    level = layer("drydem.model.assembly")
    assert [layer(m) > level for _, m in imports(source)] == [True]
