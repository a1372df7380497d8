"""The ``drydem`` command line: the click group :func:`main` (:mod:`drydem.cli.common`) and its
commands, one module per kind of work, each thin over the Python API: :mod:`~drydem.cli.models`
(check, show, export, designs), :mod:`~drydem.cli.tilting` (tilt, animate),
:mod:`~drydem.cli.shaking` (shake), :mod:`~drydem.cli.limits` (limit), :mod:`~drydem.cli.studies`
(sweep, report, calibrate) and :mod:`~drydem.cli.montecarlo` (montecarlo)."""

import atexit
import gc

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
    tests and scripts call in a process that goes on, leaves the collector alone."""
    atexit.register(gc.freeze)
    main()
