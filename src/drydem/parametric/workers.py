"""Where a sweep's runs go: local processes (:func:`local_executor`, whose workers die with the
sweep), or a Dask cluster's (:func:`connect`), both opened by :func:`open_workers`."""

from __future__ import annotations

import os
import sys
import threading
import time
from collections.abc import Iterator
from concurrent.futures import Executor
from contextlib import contextmanager
from dataclasses import dataclass

from drydem.parametric.sweep import SweepError

#: how long a Dask scheduler has to answer before the sweep gives up on it, s: a scheduler that
#: is up answers a connection in milliseconds, so a longer wait only delays saying it is not
SCHEDULER_TIMEOUT_S = 5.0


#: local worker processes at most per core this process may run on: more only queue for the
#: cores, each a Python process with its own kernels (--workers 1000000 started one per run)
WORKERS_PER_CORE = 4


def cores() -> int:
    """The cores this process may run on: its CPU affinity (taskset, a container's cpuset), where
    the system tells it, else all of the machine's."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


def most_workers() -> int:
    """The most local worker processes a run may ask for (:data:`WORKERS_PER_CORE` per core)."""
    return WORKERS_PER_CORE * cores()


@dataclass(frozen=True)
class Workers:
    """Where runs go: an ``executor``, a description of it (``where``), and the runs it computes
    at once (``slots``; None for a Dask cluster, which may grow)."""

    executor: Executor
    where: str
    slots: int | None


@contextmanager
def open_workers(workers: int | None = None, scheduler: str | None = None) -> Iterator[Workers]:
    """``workers`` local processes (:func:`local_executor`; default: one per core, :func:`cores`), or the cluster
    of the Dask scheduler at ``scheduler`` (:func:`connect`). On an exception (an interrupt)
    the queued runs are cancelled rather than waited for."""
    if scheduler is not None:
        client = connect(scheduler)
        pool = Workers(client.get_executor(), f"Dask scheduler {scheduler}", None)
    else:
        workers = workers or cores()
        client, pool = None, Workers(local_executor(workers), f"{workers} local processes", workers)
    try:
        yield pool
    except BaseException:
        if client is None:
            pool.executor.shutdown(wait=False, cancel_futures=True)
        raise
    else:
        pool.executor.shutdown()
    finally:
        if client is not None:
            client.close()


def connect(address: str, *, timeout_s: float = SCHEDULER_TIMEOUT_S):
    """A Dask client of the scheduler at ``address``; SweepError naming the address and what to
    check when it is not an address (:func:`check_scheduler_address` before any client is made;
    whatever Dask still refuses as it makes one, the same) or does not answer within
    ``timeout_s`` (Dask's own default waits 30 s and then raises a bare OSError)."""
    from distributed import Client

    check_scheduler_address(address)
    try:
        return Client(address, timeout=timeout_s)
    except (ValueError, TypeError) as exc:
        raise _not_an_address(address, exc) from None
    except OSError as exc:
        raise SweepError(f"cannot reach the Dask scheduler at {address} ({exc}): check that it is running "
                         "(`dask scheduler` prints its address), that the host and port are right, and that no firewall "
                         "blocks the port") from None


def check_scheduler_address(address: str) -> None:
    """SweepError unless ``address`` is a network address Dask can connect to: a known scheme
    (tcp:// when none is given) that reaches another process (not inproc://), whose connector this
    installation has (ucx:// needs UCX) and, for tls:// and wss://, a TLS configuration; and a
    HOST:PORT. Checked before any ``Client`` is made: one that fails half-made leaves its event
    loop and state behind in this process, and a later one failed there with a bare
    AssertionError from inside distributed (tls:// then ucx:// then inproc://, in one test
    process)."""
    from distributed.comm.addressing import parse_address, parse_host_port
    from distributed.comm.registry import get_backend
    from distributed.security import Security

    try:
        scheme, location = parse_address(address)
        if scheme == "inproc":
            raise ValueError("inproc:// is a scheduler inside one process")
        get_backend(scheme).get_connector()
        if scheme in ("tls", "wss") and Security().get_connection_args("client")["ssl_context"] is None:
            raise ValueError(f"{scheme}:// needs a TLS configuration (Dask's distributed.comm.tls settings)")
        parse_host_port(location)
    except (ValueError, TypeError) as exc:
        raise _not_an_address(address, exc) from None


def _not_an_address(address: str, reason: Exception) -> SweepError:
    """The SweepError of an address Dask cannot use, with its ``reason``."""
    return SweepError(f"scheduler {address!r} is not a scheduler address ({reason}): expected tcp://HOST:PORT, "
                      "the address `dask scheduler` prints (port 8786 by default)")


def local_executor(workers: int) -> Executor:
    """``workers`` local processes, spawned (fresh interpreters, no forked state), that end when
    this process ends however it ends, each running its kernels on one thread (:func:`_start_worker`)."""
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor

    return ProcessPoolExecutor(max_workers=workers, mp_context=multiprocessing.get_context("spawn"),
                               initializer=_start_worker, initargs=(os.getpid(),))


def _start_worker(parent: int) -> None:
    """Worker initializer: :func:`_exit_with_parent`, and one kernel thread
    (:func:`drydem.engine.threads.set_threads`): the processes already share the cores out, and
    each on every core would oversubscribe them (the results are the same for any count)."""
    from drydem.engine.threads import set_threads

    _exit_with_parent(parent)
    set_threads(1)


#: prctl's option that asks for a signal when the parent ends (linux/prctl.h)
PR_SET_PDEATHSIG = 1


def _exit_with_parent(parent: int) -> None:
    """Worker initializer: end this worker when ``parent`` (the sweep) ends. Without it a sweep
    killed outright (kill -9, the out-of-memory killer) leaves its workers computing on, then
    waiting forever (each holds both ends of the pool's queue, so none sees it close).

    On Linux the kernel sends the worker SIGKILL when its parent ends (prctl PR_SET_PDEATHSIG):
    at once, even in the middle of a numba kernel, which holds the GIL for as long as it runs,
    and with nothing to run in the worker; the parent is checked after setting it, in case it
    ended before. The signal follows the parent *thread* that started the worker: the pool
    starts its workers in the thread that submits, which for :func:`sweep` is the thread that
    waits for them. Elsewhere, :func:`_watch_parent`."""
    if sys.platform.startswith("linux"):
        import ctypes
        import signal

        if ctypes.CDLL(None, use_errno=True).prctl(PR_SET_PDEATHSIG, signal.SIGKILL) == 0:
            if os.getppid() != parent:
                os._exit(1)
            return
    _watch_parent(parent)


def _watch_parent(parent: int) -> None:
    """Worker initializer: a daemon thread ends this worker when its parent pid is no longer
    ``parent`` (it was re-parented: its parent ended), checking every second (portable, but it
    needs the GIL, so it waits for a numba kernel that runs to return)."""
    def watch():
        while os.getppid() == parent:
            time.sleep(1.0)
        os._exit(1)

    threading.Thread(target=watch, name="exit-with-parent", daemon=True).start()
