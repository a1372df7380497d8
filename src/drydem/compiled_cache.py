"""numba's cache of drydem's compiled functions, keyed on every source they are compiled from.

numba checks a cached function against its own file only (a hash of it, and the function's
bytecode), but compiled code also takes functions inlined from other modules
(:func:`drydem.engine.joints.shear_law` in :func:`drydem.engine.cycle_planar.run_cycles`), constants frozen from
them (:data:`oracles.polygon.SLIVER_FRACTION` in :mod:`drydem.engine.narrow_phase`) and their types
(:class:`drydem.engine.contacts.SubContacts`). Edit one of those in an editable install and numba goes
on loading the old machine code.

:func:`check` runs when drydem is imported, before any compiled function is loaded (numba
loads one at its first call). It hashes each compiled module's source together with those of
the drydem modules it imports at module level, directly or through others (the only places its
compiled code can take anything from), and compares the hashes with the stamp kept in the
cache folder. The cache files of a module whose hash changed are deleted (numba compiles it
again and writes them anew), and the stamp is rewritten.

The cache folder is the one numba picked for the module (numba.core.caching: NUMBA_CACHE_DIR
where set, else the ``__pycache__`` beside the source where writable, as in an editable install,
else numba's user-wide cache folder, as for a read-only site-packages), read off the module's
compiled functions. A stamp or a cache file that cannot be written or removed is left as it is
(numba then cannot write there either): a file error never stops drydem from importing.
"""

from __future__ import annotations

import ast
import functools
import hashlib
import importlib
import json
import os
import re
from pathlib import Path

#: the drydem package's folder
PACKAGE = Path(__file__).resolve().parent
#: the stamp's file name in a cache folder: JSON {"package": hash of all the package's sources,
#: "modules": {compiled module: hash of its sources}}
STAMP = "drydem-sources.json"


def check() -> dict[str, list[Path]]:
    """Delete the cache files of the compiled modules whose sources changed since the stamp
    (module docstring); returns the files deleted, by module.

    The stamp also holds a hash of all the package's sources: while it holds, nothing changed,
    and the modules' imports are not parsed again (the slow part, a tenth of a second)."""
    folders: dict[Path, list[str]] = {}
    for name in compiled_modules():
        folder = cache_folder(name)
        if folder is not None:
            folders.setdefault(folder, []).append(name)
    package = _digest(_module_name(path) for path in PACKAGE.rglob("*.py"))
    hashes = None
    deleted: dict[str, list[Path]] = {}
    for folder, names in folders.items():
        stamp = _read_stamp(folder / STAMP)
        if stamp.get("package") == package:
            continue
        hashes = hashes or source_hashes([n for modules in folders.values() for n in modules])
        known = stamp.get("modules", {})
        for name in names:
            if known.get(name) != hashes[name]:
                deleted[name] = _delete_cache_files(folder, module_file(name).stem)
        _write_stamp(folder / STAMP, {"package": package, "modules": {**known, **{n: hashes[n] for n in names}}})
    return deleted


def compiled_modules() -> list[str]:
    """drydem's modules that may have functions cached by numba: their source has cache=True
    (a module that only mentions it has no cache folder, :func:`cache_folder`)."""
    return [
        _module_name(path) for path in sorted(PACKAGE.rglob("*.py")) if re.search(r"\bcache\s*=\s*True", path.read_text(encoding="utf-8"))
    ]


def source_hashes(names: list[str]) -> dict[str, str]:
    """For each module of ``names``, a hash of its source and those of the drydem modules it
    imports at module level, directly or not."""
    return {name: _digest(dependencies(name)) for name in names}


def dependencies(name: str) -> set[str]:
    """The drydem module ``name`` and every drydem module it imports at module level, directly
    or through others."""
    found, todo = set(), [name]
    while todo:
        module = todo.pop()
        if module not in found:
            found.add(module)
            todo.extend(_imports(module))
    return found


def module_file(name: str) -> Path:
    """The source file of the drydem module ``name`` (dotted)."""
    path = PACKAGE.parent.joinpath(*name.split("."))
    return path / "__init__.py" if path.is_dir() else path.with_suffix(".py")


def cache_folder(name: str) -> Path | None:
    """The folder where numba caches the compiled functions of module ``name``, None if it
    caches none of them (NUMBA_DISABLE_JIT, for instance)."""
    module = importlib.import_module(name)
    for value in vars(module).values():
        py_func = getattr(value, "py_func", None)
        path = getattr(getattr(value, "_cache", None), "cache_path", None)
        if py_func is not None and py_func.__module__ == name and path:
            return Path(path)
    return None


def _digest(names) -> str:
    """SHA-256 of the sources of the drydem modules ``names``, each with its name, in name order."""
    digest = hashlib.sha256()
    for name in sorted(names):
        digest.update(name.encode() + b"\0" + module_file(name).read_bytes() + b"\0")
    return digest.hexdigest()


def _module_name(path: Path) -> str:
    parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _imports(name: str) -> set[str]:
    """The drydem modules that module ``name`` imports outside functions (at import time)."""
    path = module_file(name)
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    found = set()
    for node in _module_level(_tree(path)):
        if isinstance(node, ast.Import):
            found.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                base = ".".join(package.split(".")[: len(package.split(".")) - node.level + 1] + ([base] if base else []))
            for alias in node.names:
                submodule = f"{base}.{alias.name}"
                found.add(submodule if _is_module(submodule) else base)
    return {m for m in found if _is_module(m)}


def _module_level(tree: ast.Module):
    """The statements of ``tree`` run at import: all but those in function bodies."""
    todo = list(tree.body)
    while todo:
        node = todo.pop()
        yield node
        if not isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            todo.extend(c for c in ast.iter_child_nodes(node) if isinstance(c, (ast.stmt, ast.excepthandler, ast.match_case)))


def _tree(path: Path) -> ast.Module:
    stat = path.stat()
    return _parse(path, stat.st_mtime_ns, stat.st_size)


@functools.lru_cache(maxsize=None)
def _parse(path: Path, mtime_ns: int, size: int) -> ast.Module:
    """``path`` parsed, once per version of the file (its modification time and size in the key)."""
    return ast.parse(path.read_text(encoding="utf-8"))


def _is_module(name: str) -> bool:
    return name.split(".")[0] == PACKAGE.name and module_file(name).is_file()


def _read_stamp(path: Path) -> dict[str, str]:
    try:
        stamp = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return {}
    return stamp if isinstance(stamp, dict) else {}


def _write_stamp(path: Path, stamp: dict[str, str]) -> None:
    """Written whole or not at all (a temporary file renamed), as numba writes its index."""
    temporary = path.with_name(f"{path.name}.{os.getpid()}.tmp")
    try:
        temporary.write_text(json.dumps(stamp, indent=0, sort_keys=True), encoding="utf-8")
        os.replace(temporary, path)
    except OSError:
        temporary.unlink(missing_ok=True)


def _delete_cache_files(folder: Path, stem: str) -> list[Path]:
    """numba's index (.nbi) and data (.nbc) files of the functions of the module file ``stem``.py
    in ``folder`` (named stem.function-line.pyXY...)."""
    deleted = []
    for path in [*folder.glob(f"{stem}.*.nbi"), *folder.glob(f"{stem}.*.nbc")]:
        try:
            path.unlink()
        except OSError:
            continue
        deleted.append(path)
    return deleted
