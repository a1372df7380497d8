"""numba's cache of drydem's compiled functions, keyed on every source they are compiled from.

numba checks a cached function against its own file only (a hash of it, and the function's
bytecode), but compiled code also takes functions inlined from other modules
(:func:`drydem.engine.joints.shear_law` in :func:`drydem.engine.cycle_planar.run_cycles`), constants frozen from
them (:data:`oracles.polygon.SLIVER_FRACTION` in :mod:`drydem.engine.narrow_phase`) and their types
(:class:`drydem.engine.contacts.SubContacts`). Edit one of those in an editable install and numba goes
on loading the old machine code.

:func:`check` runs at the end of every module with cached compiled functions (its last
statement, ``compiled_cache.check(__name__)``, tests/test_compiled_cache.py), before any of them
can be called (numba loads one from its cache at its first call), and once per cache folder and
process. It hashes the sources of each compiled module of that folder together with those of
the drydem modules it imports at module level, directly or through others (the only places its
compiled code can take anything from), and compares the hashes with the stamp kept in the
cache folder. The cache files of a module whose hash changed are deleted (numba compiles it
again and writes them anew), and the stamp is rewritten. Importing drydem checks nothing and
imports no numba.

The cache folder is the one numba picked for the module (numba.core.caching: NUMBA_CACHE_DIR
where set, else the ``__pycache__`` beside the source where writable, as in an editable install,
else numba's user-wide cache folder, as for a read-only site-packages), read off the module's
compiled functions. A stamp or a cache file that cannot be written or removed is left as it is
(numba then cannot write there either): a file error never stops drydem from importing.

Compiling all the kernels takes most of a minute (58 s for the first ``drydem tilt WD3`` in the
README), once: :func:`compile_notice` says so while numba compiles a cached function (a cache
miss: numba's event "numba:compile", which a load from the cache does not raise), and nothing
when every kernel comes from the cache.
"""

from __future__ import annotations

import ast
import functools
import hashlib
import importlib
import json
import os
import re
import sys
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

#: the drydem package's folder
PACKAGE = Path(__file__).resolve().parent
#: the stamp's file name in a cache folder: JSON {"package": hash of all the package's sources,
#: "modules": {compiled module: hash of its sources}}
STAMP = "drydem-sources.json"
#: the cache folders checked in this process (:func:`check`)
_CHECKED: set[Path] = set()
#: the compile announced before one was timed on this machine, s: about what all the kernels of
#: a tilt took on 2026-11-23/25 (41-58 s, README), a few less for those of one analysis
FIRST_COMPILE_S = 50.0
#: the file in a cache folder keeping how long the last compile took: JSON {"seconds": s}
COMPILE_TIME = "drydem-compile-time.json"
#: s without a compile after which compiling is over (a run compiles its kernels at their first
#: calls, a few hundredths of a second apart but for a model built or a figure drawn between)
QUIET_S = 1.0
#: s between two updates of the seconds spent compiling
TICK_S = 0.5
#: the notices waiting for numba's import to listen to its compiles (:func:`_listen`)
_NOTICES: list[CompileNotice] = []


def check(name: str) -> list[Path]:
    """Delete the cache files of the compiled modules of ``name``'s cache folder whose sources
    changed since the stamp (module docstring), once per folder and process; returns the files
    deleted. The last statement of every module with cached functions (``name`` its own).

    The compiled modules of a folder are those beside ``name``'s source (numba's folder follows
    the source's: numba.core.caching's locators); a module whose folder is another is checked at
    its own import. The stamp also holds a hash of all the package's sources: while it holds,
    nothing changed, and the modules' imports are not parsed again (the slow part, a tenth of a
    second)."""
    folder = cache_folder(name)
    _listen()
    if folder is None or folder in _CHECKED:
        return []
    _CHECKED.add(folder)
    names = [n for n in compiled_modules() if module_file(n).parent == module_file(name).parent]
    package = _digest(_sources())
    stamp = _read_json(folder / STAMP)
    if stamp.get("package") == package:
        return []
    hashes = source_hashes(names)
    known = stamp.get("modules", {})
    deleted = [path for n in names if known.get(n) != hashes[n] for path in _delete_cache_files(folder, module_file(n).stem)]
    _write_json(folder / STAMP, {"package": package, "modules": {**known, **hashes}})
    return deleted


@contextmanager
def compile_notice(file=None) -> Iterator[CompileNotice]:
    """While in it, numba compiling drydem's kernels is said on ``file`` (default: stderr), as
    :class:`CompileNotice` words it; nothing is said when they all come from the cache. Imports
    no numba: the notice listens from the import of the first compiled module (:func:`check`)."""
    notice = CompileNotice(file or sys.stderr)
    _NOTICES.append(notice)
    if "numba" in sys.modules:
        _listen()
    try:
        yield notice
    finally:
        _NOTICES.remove(notice)
        if notice.listener is not None:
            from numba.core import event

            event.unregister("numba:compile", notice.listener)
        notice.close()


class CompileNotice:
    """Numba's compiles of cached functions, said on ``file``: "compiling the kernels once (about
    N s)" at the first (N: the last compile's time kept in the cache folder, :data:`COMPILE_TIME`,
    else :data:`FIRST_COMPILE_S`), the seconds spent compiling on a "compiling the kernels" bar
    (tqdm) while they go on, and "compiled in N s" once none has run for :data:`QUIET_S` (a run
    compiles each kernel at its first call, a few at a time). Compiles nested in another (its
    callees) count within it."""

    def __init__(self, file):
        self.file = file
        self.listener = None  # numba's listener, once registered (:func:`_listen`)
        self.estimate_s = None  # what the first compile announced; None before it
        self.folder = None  # the cache folder of the first compiled function: where its time is kept
        self.compiled_s = 0.0  # seconds of the compiles that ended
        self.depth = 0  # compiles in progress, nested
        self.began = self.ended = 0.0  # time.monotonic() the outermost compile began, the last ended
        self.bar = None
        self.lock = threading.Lock()
        self.stop = threading.Event()
        self.ticker = None

    def start(self, folder: Path) -> None:
        """A compile began (a cached function's, in cache ``folder``)."""
        from tqdm import tqdm

        with self.lock:
            self.depth += 1
            if self.depth > 1:
                return
            self.began = time.monotonic()
            if self.estimate_s is None:
                self.folder, self.estimate_s = folder, _last_compile_s(folder)
                tqdm.write(f"compiling the kernels once (about {self.estimate_s:.0f} s)", file=self.file)
            if self.ticker is None:
                self.ticker = threading.Thread(target=self._tick, name="drydem-compile-notice", daemon=True)
                self.ticker.start()

    def end(self) -> None:
        """A compile ended."""
        with self.lock:
            self.depth -= 1
            if self.depth == 0:
                self.ended = time.monotonic()
                self.compiled_s += self.ended - self.began

    def close(self) -> None:
        """Say how long compiling took, if a compile began and that is not said yet."""
        self.stop.set()
        ticker = self.ticker  # set to None by the ticker itself once compiling is over
        if ticker is not None:
            ticker.join()
        with self.lock:
            self._finish()

    def _tick(self) -> None:
        """Show the seconds spent compiling every :data:`TICK_S` until compiling is over."""
        while not self.stop.wait(TICK_S):
            with self.lock:
                now = time.monotonic()
                if self.depth == 0 and now - self.ended >= QUIET_S:
                    self._finish()
                    return
                self._show(self.compiled_s + (now - self.began if self.depth else 0.0))

    def _show(self, elapsed_s: float) -> None:
        from tqdm import tqdm

        if self.bar is None:
            self.bar = tqdm(desc=f"compiling the kernels (about {self.estimate_s:.0f} s)", bar_format="{desc}: {n:.0f} s",
                            file=self.file, leave=False)
        self.bar.n = elapsed_s
        self.bar.refresh()

    def _finish(self) -> None:
        """Compiling is over (the lock held): the bar closed, its time said and kept."""
        if self.ticker is None:
            return
        from tqdm import tqdm

        if self.bar is not None:
            self.bar.close()
            self.bar = None
        self.ticker = None
        tqdm.write(f"compiled in {self.compiled_s:.0f} s", file=self.file)
        _write_json(self.folder / COMPILE_TIME, {"seconds": self.compiled_s})


def _last_compile_s(folder: Path) -> float:
    """The seconds the last compile took, kept in ``folder`` (:data:`COMPILE_TIME`), else
    :data:`FIRST_COMPILE_S`."""
    seconds = _read_json(folder / COMPILE_TIME).get("seconds")
    return float(seconds) if isinstance(seconds, (int, float)) and 0.0 < seconds < 1e5 else FIRST_COMPILE_S


def _listen() -> None:
    """Register the notices waiting for numba's compile events (numba is imported)."""
    if not _NOTICES:
        return
    from numba.core import event

    for notice in _NOTICES:
        if notice.listener is None:
            notice.listener = _listener_type()(notice)
            event.register("numba:compile", notice.listener)


@functools.cache
def _listener_type() -> type:
    """numba's listener of compile events (its base class imported with numba), passing those of
    cached functions (a cache folder: numba's Dispatcher.stats) on to a :class:`CompileNotice`."""
    from numba.core import event

    def cache_folder_of(compiled) -> Path | None:
        path = getattr(getattr(compiled.data.get("dispatcher"), "stats", None), "cache_path", None)
        return Path(path) if path else None

    class Listener(event.Listener):
        def __init__(self, notice: CompileNotice):
            self.notice = notice

        def on_start(self, compiled) -> None:
            folder = cache_folder_of(compiled)
            if folder is not None:
                self.notice.start(folder)

        def on_end(self, compiled) -> None:
            if cache_folder_of(compiled) is not None:
                self.notice.end()

    return Listener


@functools.cache
def compiled_modules() -> tuple[str, ...]:
    """drydem's modules with functions cached by numba: a line of their source starts with a
    numba decorator that sets ``cache`` True (under NUMBA_DISABLE_JIT, none has a cache folder,
    :func:`cache_folder`)."""
    decorator = re.compile(rb"^@numba\.\w+\([^)]*\bcache\s*=\s*True", re.MULTILINE)
    return tuple(name for name, source in sorted(_sources().items()) if decorator.search(source))


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
    module = sys.modules.get(name) or importlib.import_module(name)  # at the end of its own import: in sys.modules
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
        digest.update(name.encode() + b"\0" + _sources()[name] + b"\0")
    return digest.hexdigest()


@functools.cache
def _sources() -> dict[str, bytes]:
    """The source of every module of the package, by name, read once per process (a file open
    costs a tenth of a millisecond, and each cache folder's check reads them all)."""
    return {_module_name(path): path.read_bytes() for path in PACKAGE.rglob("*.py")}


def _module_name(path: Path) -> str:
    parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _imports(name: str) -> set[str]:
    """The drydem modules that module ``name`` imports outside functions (at import time), but
    this one (each compiled module imports it to call :func:`check`)."""
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
    return {m for m in found if _is_module(m) and m != __name__}  # this module: nothing compiled takes code from it


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


def _read_json(path: Path) -> dict:
    """The JSON object in ``path``; empty where it is missing or not one."""
    try:
        found = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return {}
    return found if isinstance(found, dict) else {}


def _write_json(path: Path, found: dict) -> None:
    """Written whole or not at all (a temporary file renamed), as numba writes its index."""
    temporary = path.with_name(f"{path.name}.{os.getpid()}.tmp")
    try:
        temporary.write_text(json.dumps(found, indent=0, sort_keys=True), encoding="utf-8")
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
