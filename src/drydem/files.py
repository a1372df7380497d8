"""Files: read a TOML input with a message naming it; refuse an output path that cannot be written
before any work, and write each file whole or not at all; the numbers text files hold."""

from __future__ import annotations

import errno
import fcntl
import os
import re
import signal
import socket
import stat
import sys
import tempfile
import threading
import time
import tomllib
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from drydem.errors import DrydemError, ModelError, OutputTakenError

#: a number as the text files drydem reads write one (motion records, OBJ, STL, VRML): ASCII
#: digits with an optional sign, point and exponent (Python's float() also takes 1_0 for 10, and
#: the digits of other scripts); nan and inf match, for the readers to refuse as not finite
PLAIN_NUMBER = re.compile(r"[+-]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?|[+-]?(?:nan|inf|infinity)", re.IGNORECASE)
#: a whole number as those files write one (int() also takes 1_0, and other scripts' digits)
PLAIN_INTEGER = re.compile(r"[+-]?[0-9]+")


def plain_name_problem(name) -> str | None:
    """Why ``name``, read from an input file, cannot name one file or folder inside a results
    folder (``must be ...``), None if it can: a string, not blank, without a path separator (/ or
    \\) or a NUL, and neither "." nor "..". So RESULTS/NAME stays inside RESULTS: "../x" or an
    absolute path would write elsewhere, "." and ".." are RESULTS itself and its parent."""
    if not isinstance(name, str):
        return "must be a string (it names a results folder)"
    if not name.strip() or name in (".", "..") or any(c in name for c in "/\\\0"):
        return "must be a non-empty name without / or \\, and not . or .. (it names a results folder)"
    return None


def writable(path: str | Path) -> Path:
    """``path`` if a file can be created there; else a DrydemError naming it and the reason (its
    folder is missing or not a folder or not writable, the path is a folder, or the system
    refuses the name, e.g. too long). Commands call it before their work, so that a long
    analysis does not end on a path it cannot write."""
    path = Path(path)
    folder = path.parent
    try:
        if path.is_dir():
            raise DrydemError(f"{path}: is a folder; give a file name")
        if not folder.exists():
            link = _missing_link(folder)
            raise DrydemError(f"{path}: the folder {folder} does not exist" + (f" ({link})" if link else ""))
        if not folder.is_dir():
            raise DrydemError(f"{path}: {folder} is not a folder")
    except OSError as exc:
        raise DrydemError(f"{path}: {exc.strerror or exc}") from None
    if not os.access(folder, os.W_OK | os.X_OK):
        raise DrydemError(f"{path}: no permission to write in {folder}")
    return path


def replaceable(path: str | Path, overwrite: bool, *, option: str = "--overwrite", other: str = "another file name") -> Path:
    """``path`` once :func:`writable`, if nothing is there, or a regular file and ``overwrite``:
    drydem replaces no result unless asked. Else a DrydemError: "exists; pass OPTION to replace
    it, or OTHER" for anything there (a file, a link, even a broken one, a pipe), and under
    ``overwrite`` "is not a regular file" for a link, pipe or device (os.replace would put a
    file in its place, not write through it)."""
    path = writable(path)
    if not os.path.lexists(path):
        return path
    if not overwrite:
        raise DrydemError(f"{path}: exists; pass {option} to replace it, or {other}")
    if path.is_symlink() or not path.is_file():
        raise DrydemError(f"{path}: exists and is not a regular file (a link, a pipe or a device): {option} replaces files only")
    return path


def writable_folder(folder: str | Path) -> Path:
    """``folder``, made (with its parents) if missing, once a file could be created in it; else a
    DrydemError naming it and the reason (it is a file or a device, a parent is a file, no
    permission, no space). Commands call it before their work, as :func:`writable`."""
    folder = Path(folder)
    try:
        if folder.exists() and not folder.is_dir():
            raise DrydemError(f"{folder}: exists and is not a folder; give a folder")
        folder.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryFile(dir=folder):
            pass
    except OSError as exc:
        raise DrydemError(f"{folder}: cannot write results there ({_missing_link(folder) or exc.strerror or exc})") from None
    return folder


def _missing_link(path: Path) -> str | None:
    """"LINK is a link to the missing TARGET" where ``path`` or a folder above it is a link to
    nothing (a dangling symbolic link, of which the system only says "File exists" or "No such
    file or directory"), else None."""
    try:
        for part in (path, *path.parents):
            if part.is_symlink() and not part.exists():
                return f"{part} is a link to the missing {os.readlink(part)}"
    except OSError:  # a name the system refuses (too long): its own reason is said instead
        pass
    return None


def write_text(path: str | Path, text: str) -> Path:
    """``text`` written to ``path`` in UTF-8 (as drydem's readers read it, whatever the locale),
    once :func:`writable` says it can be, and whole or not at all (:func:`replaced_atomically`:
    a DrydemError naming ``path`` and the reason if the system refuses). A file name's bytes
    that are not UTF-8 (Python's surrogate escapes, in a comment naming the model's source) are
    written as "?" (found by a hunt: a UnicodeEncodeError traceback)."""
    path = writable(path)
    with replaced_atomically(path) as partial:
        partial.write_text(text, encoding="utf-8", errors="replace")
    return path


#: the tag of the lock beside a file being written (:func:`replaced_atomically`, :func:`partial_name`)
WRITING = "writing"


@contextmanager
def replaced_atomically(path: str | Path, *, replace: bool = True):
    """Yield a temporary file name beside ``path`` (:func:`partial_name`; same suffix: writers
    that go by it still work) to write to. When the block ends normally the file replaces
    ``path`` in one step (os.replace); when it raises, the file is removed. So ``path`` is never
    half-written: it is the old file or the whole new one. An OSError is re-raised as a
    DrydemError naming ``path`` and the reason. Whatever a killed run left at the temporary
    name is removed first, a link included: a writer would write through it to its target.

    Two processes writing ``path`` at once would write the one temporary file: the second is
    refused (OutputTakenError), ``path`` held by a lock beside it (:func:`held`, the name
    ``.STEM.writing.SUFFIX``: :data:`WRITING`). With ``replace`` False (a command that replaces
    no file unless asked, which looked before its work) the file is put in place only if
    nothing is there by then (:func:`_put_in_place`)."""
    path = Path(path)
    temporary = partial_name(path)
    busy = f"{path}: another drydem process is writing it; wait for it to end, or give another name"
    with held(partial_name(path, WRITING), busy, OutputTakenError, guarding=path):
        try:
            if temporary.is_symlink() or temporary.is_file():
                temporary.unlink()
            yield temporary
            _put_in_place(temporary, path, replace)
        except OSError as exc:
            raise DrydemError(f"{path}: cannot write: {exc.strerror or exc}") from None
        finally:
            if temporary.is_file() and not temporary.is_symlink():
                temporary.unlink()


def _put_in_place(temporary: Path, path: Path, replace: bool) -> None:
    """``temporary`` renamed to ``path``; with ``replace`` False only if nothing is at ``path``
    (a hard link made, which fails if the name is taken, in one step), else an OutputTakenError: the
    file another process wrote there meanwhile is kept. A file system without hard links (FAT)
    is looked at, then renamed to."""
    if replace:
        os.replace(temporary, path)
        return
    kept = OutputTakenError(f"{path}: was written by another process while drydem wrote it, and is kept; pass --overwrite to "
                            "replace it, or give another name")
    try:
        os.link(temporary, path)
    except FileExistsError:
        raise kept from None
    except OSError:
        if os.path.lexists(path):
            raise kept from None
        os.replace(temporary, path)


def lock_exclusively(path: Path) -> int | None:
    """The descriptor of ``path`` locked exclusively (flock) for this process, created if
    missing, held until :func:`unlock`; None if another open file of it holds the lock.
    DrydemError naming ``path`` if it is not a regular file (:func:`_lock_file`) or the file
    system refuses the lock.

    A lock rather than a file created exclusively (O_EXCL): the kernel drops it when its process
    ends, however it ends (kill -9, a crash), so there is no stale lock to detect and take over
    by guessing from process ids and hosts, and no window in which two processes both take a
    stale one over. The file only tells a person who holds it: host, pid, time. Its holder
    deletes it before unlocking it (:func:`unlock`), so a process that opened it before that and
    locks it after finds it is no longer the file at that path, and tries again on the new one.
    On a local file system a lock belongs to an open file, so a second lock of ``path`` in the
    same process is refused too; on NFS, where Linux emulates flock with the lock manager's
    per-process locks (across hosts), it is not."""
    while True:
        fd = _lock_file(path)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            os.close(fd)
            return None
        except OSError as exc:
            os.close(fd)
            raise DrydemError(f"{path}: cannot lock it ({exc.strerror}): does this file system support locks?") from None
        try:
            if os.lstat(path).st_ino == os.fstat(fd).st_ino:
                os.ftruncate(fd, 0)
                os.write(fd, f"held by {socket.gethostname()} pid {os.getpid()} since {time.strftime('%Y-%m-%d %H:%M:%S')}\n".encode())
                return fd
        except FileNotFoundError:
            pass
        except OSError as exc:
            os.close(fd)
            raise DrydemError(f"{path}: cannot write the lock file ({exc.strerror})") from None
        os.close(fd)


def _lock_file(path: Path) -> int:
    """A descriptor of the regular file ``path``, made if missing, never opened through a link
    (a planted link would have drydem empty and write its target) nor waited on (a pipe);
    DrydemError naming ``path`` otherwise."""
    try:
        fd = os.open(path, os.O_RDWR | os.O_CREAT | os.O_NOFOLLOW | os.O_NONBLOCK, 0o644)
    except OSError as exc:
        reason = "a link; a lock file is a regular file: remove it" if exc.errno == errno.ELOOP else exc.strerror
        raise DrydemError(f"{path}: cannot make the lock file ({reason})") from None
    if not stat.S_ISREG(os.fstat(fd).st_mode):
        os.close(fd)
        raise DrydemError(f"{path}: is not a regular file (a pipe or a device); a lock file is: remove it")
    return fd


def unlock(path: Path, fd: int) -> None:
    """End a lock of :func:`lock_exclusively`: delete its file, then unlock it (closing it). A
    file that cannot be deleted (its folder made read-only meanwhile) is left: the lock goes
    with the descriptor, and the next holder takes the file over."""
    try:
        Path(path).unlink(missing_ok=True)
    except OSError:
        pass
    os.close(fd)


def locked_by_another(path: Path) -> bool:
    """Whether the lock ``path`` (:func:`lock_exclusively`) is held through another open file
    (another process, or this one through another descriptor), looked at without making or
    changing anything: False if there is no such regular file or it cannot be read."""
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NOFOLLOW | os.O_NONBLOCK)
    except OSError:
        return False
    try:
        if not stat.S_ISREG(os.fstat(fd).st_mode):
            return False
        fcntl.flock(fd, fcntl.LOCK_SH | fcntl.LOCK_NB)
        return False
    except BlockingIOError:
        return True
    except OSError:
        return False
    finally:
        os.close(fd)


@contextmanager
def held(path: Path, busy: str, error: type[DrydemError] = DrydemError, *, guarding: Path | None = None) -> Iterator[None]:
    """``path`` locked (:func:`lock_exclusively`) for the block; ``error(busy)`` if another
    process holds it. A lock that cannot be made names the file it is ``guarding`` first, if
    given (found by a hunt: an export into a folder where no file can be made named only the lock)."""
    try:
        fd = lock_exclusively(path)
    except DrydemError as exc:
        if guarding is None:
            raise
        raise DrydemError(f"{guarding}: cannot write: {exc}") from None
    if fd is None:
        raise error(busy)
    try:
        yield
    finally:
        unlock(path, fd)


#: bytes: the longest file name most file systems take (ext4, APFS, NTFS: 255)
MAX_NAME_BYTES = 255


def partial_name(path: Path, tag: str = "partial") -> Path:
    """``.STEM.TAG.SUFFIX`` beside ``path``: the names drydem reserves for a file being written
    (:func:`replaced_atomically`: TAG partial, and :data:`WRITING` for its lock), its stem cut so that
    the name stays within MAX_NAME_BYTES (a legal 250-character name would otherwise give one
    the system refuses)."""
    stem = path.stem
    while stem and len(os.fsencode(f".{stem}.{tag}{path.suffix}")) > MAX_NAME_BYTES:
        stem = stem[:-1]
    return path.with_name(f".{stem}.{tag}{path.suffix}")


@contextmanager
def uninterrupted():
    """Hold SIGINT and SIGTERM until the block ends, then deliver them to the handlers in force
    before it. A writer that a KeyboardInterrupt stops half-way may fail on its own cleanup and
    mask the interrupt with another error (numpy's savez: "Can't close the ZIP file while there
    is an open writing handle"): what is written is written, then the interrupt comes. Python
    runs signal handlers in the main thread only: elsewhere this holds nothing."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    held: list[int] = []
    previous = {number: signal.signal(number, lambda received, frame: held.append(received))
                for number in (signal.SIGINT, signal.SIGTERM)}
    try:
        yield
    finally:
        for number, handler in previous.items():
            signal.signal(number, signal.SIG_DFL if handler is None else handler)
        for number in held:
            signal.raise_signal(number)


def regular_file(path: Path, expected: str) -> Path:
    """``path`` if it is a regular file (or a link to one), checked before it is opened; else a
    ModelError naming it, what it is instead, and what was ``expected`` of it: missing, a folder,
    or a pipe, socket or device (reading a pipe waits for a writer forever, /dev/zero never ends)."""
    try:
        mode = Path(path).stat().st_mode
    except OSError as exc:
        raise ModelError(f"{path}: cannot read the file ({_missing_link(Path(path)) or exc.strerror or exc}); {expected}") from None
    if stat.S_ISDIR(mode):
        raise ModelError(f"{path}: is a folder, not a file; {expected}")
    if not stat.S_ISREG(mode):
        raise ModelError(f"{path}: not a regular file (a pipe, a socket or a device): drydem reads files only; {expected}")
    return path


def read_text(path: Path, expected: str, *, encoding: str = "utf-8") -> str:
    """The text of ``path`` (UTF-8 unless ``encoding`` says otherwise) once it is a regular file
    (:func:`regular_file`), a UTF-8 byte order mark at its start dropped (as Windows editors write
    it; found by a hunt: a TOML file and a frames.csv with one were refused); ModelError naming the
    file if it cannot be read, or if it is not text, then saying what was ``expected`` of it."""
    try:
        return regular_file(path, expected).read_text(encoding="utf-8-sig" if encoding == "utf-8" else encoding)
    except OSError as exc:
        raise ModelError(f"{path}: cannot read the file ({exc.strerror or exc})") from None
    except UnicodeDecodeError as exc:
        raise ModelError(f"{path}: not a text file (byte {exc.start} is not {encoding.upper()}); {expected}") from None


def read_toml(path: Path) -> tuple[dict, str]:
    """A TOML file's tables and its text (for line numbers); ModelError naming the file if it
    cannot be read or parsed."""
    if path.is_dir():
        raise ModelError(f"{path}: is a directory, not a TOML file")
    text = read_text(path, "a model, wall or study file is TOML text")
    try:
        return tomllib.loads(text), text
    except tomllib.TOMLDecodeError as exc:
        raise ModelError(f"{path}: not valid TOML: {exc}") from None
    except RecursionError:  # arrays or inline tables nested thousands deep: tomllib parses them recursively
        raise ModelError(f"{path}: nested deeper than Python's recursion limit ({sys.getrecursionlimit():,}); no table of a model, "
                         "wall or study file is nested more than a few levels") from None
    except ValueError:  # an integer of more digits than Python converts (4,300), raised by int() inside tomllib
        raise ModelError(f"{path}: an integer of more than {sys.get_int_max_str_digits():,} digits, which Python does not read; "
                         "no number of a model needs that many") from None
