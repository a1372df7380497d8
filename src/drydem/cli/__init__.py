"""The ``drydem`` command line: the click group :func:`main` (:mod:`drydem.cli.common`) and its
commands, one module per kind of work, each thin over the Python API: :mod:`~drydem.cli.models`
(check, show, export, designs), :mod:`~drydem.cli.tilting` (tilt, animate),
:mod:`~drydem.cli.shaking` (shake), :mod:`~drydem.cli.limits` (limit), :mod:`~drydem.cli.studies`
(sweep, report, calibrate) and :mod:`~drydem.cli.montecarlo` (montecarlo)."""

import atexit
import gc
import sys

import click

from drydem.cli import limits, models, montecarlo, shaking, studies, tilting
from drydem.cli.common import main
from drydem.cli.shaking import PULSE_KINDS

#: the modules whose import registers their commands on :func:`main`
COMMAND_MODULES = (models, tilting, shaking, limits, studies, montecarlo)

__all__ = ["COMMAND_MODULES", "PULSE_KINDS", "console", "main"]


def console() -> None:
    """The ``drydem`` program (pyproject.toml's script): :func:`main`, with every object the
    garbage collector tracks frozen as the interpreter shuts down (:func:`gc.freeze` as an
    atexit hook), so that its last collections skip the ~10^5 objects numba's import and
    kernels leave: they would free nothing the end of the process does not, and took 0.1-0.4 s
    of a one-block tilt's 2.5-3.5 s (measured 2026-11-26, benchmarks/bench_start.py). Files are
    closed by the code that writes them, never by a collection. :func:`main` itself, which
    tests and scripts call in a process that goes on, leaves the collector alone.

    A Ctrl-C that no command has taken over yet (while Python imports, or a model is read)
    exits 130 as one a command takes does, not click's "Aborted!" and 1; so does one that
    reached a compiled kernel being loaded, which numba turns into a SystemError (found by a
    hunt: a traceback).

    A file name's bytes that are not UTF-8 (Python's surrogate escapes) are written to the
    terminal as they were, whatever the locale's error handler (found by a hunt: strict, it
    made the first message naming such a file a UnicodeEncodeError traceback)."""
    atexit.register(gc.freeze)
    for stream in (sys.stdout, sys.stderr):
        if hasattr(stream, "reconfigure"):  # a TextIOWrapper (not one a caller put there)
            stream.reconfigure(errors="surrogateescape")
    try:
        main(standalone_mode=False)
    except click.ClickException as exc:  # what click's standalone mode does with them
        exc.show()
        sys.exit(exc.exit_code)
    except click.exceptions.Abort:
        _interrupted()
    except SystemError as exc:
        if not _caused_by_interrupt(exc):
            raise
        _interrupted()


def _interrupted() -> None:
    """End the process as interrupted by the signal received (SIGINT unless a command's
    :func:`~drydem.cli.common.signals_interrupt` saw another: found by a hunt, a SIGTERM that
    reached numba loading a kernel was called SIGINT)."""
    from drydem.cli.common import LAST_RECEIVED

    click.echo(f"\ninterrupted ({LAST_RECEIVED.name})", err=True)
    sys.exit(128 + LAST_RECEIVED.number)


def _caused_by_interrupt(exc: BaseException | None) -> bool:
    """Whether a KeyboardInterrupt is in ``exc``'s chain of causes and contexts."""
    seen = set()
    while exc is not None and id(exc) not in seen:
        if isinstance(exc, KeyboardInterrupt):
            return True
        seen.add(id(exc))
        exc = exc.__cause__ or exc.__context__
    return False
