"""How many threads the compiled kernels run on.

The cycles (:mod:`drydem.engine.cycle3d`) run their loops over blocks and contacts on numba's
threads, as many as the model's size is worth (:func:`threads_for`) up to all the cores by default (``numba.config.NUMBA_NUM_THREADS``, itself set by the
environment variable NUMBA_NUM_THREADS). Every thread count gives the same numbers, bit for bit:
each contact writes its own sums and each block adds its contacts' in contact order, so a
result does not depend on the machine's cores or on this setting, only its speed does.

numba's setting belongs to the Python thread that makes it (each thread starts with all the
cores): :func:`set_threads` and :func:`using_threads` act on the calling thread's kernels.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager

import numba

from drydem.model.parameters import Range


def available() -> int:
    """The most threads the kernels may run on: numba's thread pool (NUMBA_NUM_THREADS, by
    default the machine's cores)."""
    return int(numba.config.NUMBA_NUM_THREADS)


#: the sub-contacts each thread of a cycle takes: a model with fewer runs on fewer threads (one
#: below twice this). Waking a thread costs about what a cycle of a thousand sub-contacts does
#: (benchmarks/bench_threads.py, 2 idle cores: 2 threads ran 1.3e3 sub-contacts at 75 %
#: efficiency, 3.9e3 to 7.4e4 at 69-100 %; the 60 x 60 wall's 3.6e4 at 86 %, 306 against 528 us
#: a cycle), and a thread waits for a core: with one of the 2 cores busy elsewhere, a one-block
#: tilt took 54-72 s on 2 threads and 2.3 s on one (2026-11-25). So the paper's walls (~1e3)
#: keep one thread, and from 1e4 a model takes two (the 60 x 60 wall had one at 20,000 a thread)
SUBCONTACTS_PER_THREAD = 5_000


def threads_for(subcontacts: int) -> int:
    """The threads a cycle of ``subcontacts`` sub-contacts runs on: one per
    :data:`SUBCONTACTS_PER_THREAD`, at least one and at most :func:`get_threads` (the setting,
    ``--threads``). Any count gives the same numbers (module docstring): only the speed."""
    return max(1, min(get_threads(), subcontacts // SUBCONTACTS_PER_THREAD))


def thread_rule() -> Range:
    """What a thread count must be: an integer from 1 to :func:`available`."""
    return Range(1, available(), integer=True)


def get_threads() -> int:
    """The threads the calling Python thread's kernels run on."""
    return int(numba.get_num_threads())


def set_threads(n: int | None) -> int:
    """Run the compiled kernels on ``n`` threads (None: all of :func:`available`); returns the
    count before. A ModelError (a :class:`~drydem.errors.DrydemError`) says ``threads = VALUE:
    must be an integer in [1, N]`` for a boolean, a non-integer or a count out of range."""
    count = available() if n is None else n
    thread_rule().check(count, "threads")
    previous = get_threads()
    numba.set_num_threads(count)
    return previous


@contextmanager
def using_threads(n: int | None) -> Iterator[int]:
    """Run the kernels on ``n`` threads (None: all) within the ``with`` block, as before after it;
    yields the count in force."""
    previous = set_threads(n)
    try:
        yield get_threads()
    finally:
        numba.set_num_threads(previous)
