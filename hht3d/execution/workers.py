"""What each worker of a local scheduler is set up with: its BLAS threads, SIGINT, and how many there are.

Process-pool workers run their BLAS, OpenMP and MKL with one thread each
(:data:`SINGLE_THREAD_ENV`), so that the pool does not oversubscribe the
cores, and ignore SIGINT: Ctrl-C reaches the whole process group, and the
main process stops them (:mod:`hht3d.stopping`).
"""
from __future__ import annotations

import contextlib
import os
import signal

import dask

__all__ = ["SINGLE_THREAD_ENV", "worker_count", "limit_blas_threads", "end_with_parent", "sigint_ignored_by_children"]

#: Environment that keeps each worker process's BLAS/OpenMP/MKL to one thread.
SINGLE_THREAD_ENV = {"OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1"}


def worker_count() -> int:
    """Workers of the scheduler a graph built now will most likely run on.

    The workers of the current ``dask.distributed`` client if there is one,
    else dask's configured ``num_workers``, else one per core (the default of
    :func:`compute` for every scheduler).
    """
    try:
        from distributed import default_client

        return max(1, len(default_client().scheduler_info()["workers"]))
    except (ImportError, ValueError):  # no distributed, or no client
        return int(dask.config.get("num_workers", None) or os.cpu_count() or 1)


def limit_blas_threads(parent: int | None = None) -> None:
    """Process-pool initializer: runs before numpy is imported in a spawned worker.

    Workers also ignore SIGINT: Ctrl-C reaches the whole process group, and
    the main process stops them (:mod:`hht3d.stopping`), without a traceback
    from each.  They end with their parent (:func:`end_with_parent`), even
    when it is killed and cannot stop them.
    """
    os.environ.update(SINGLE_THREAD_ENV)
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    end_with_parent(parent)


#: ``prctl`` option that sends a signal to this process when its parent ends (Linux).
_PR_SET_PDEATHSIG = 1


def end_with_parent(parent: int | None) -> None:
    """Have the kernel end this worker when its parent process ``parent`` ends (Linux's
    ``PR_SET_PDEATHSIG``), so that a parent killed with SIGKILL leaves no worker computing and
    recording results; a parent already gone ends the worker at once.  Elsewhere nothing is set:
    there a killed parent's pool workers end when they next find their call queue closed."""
    import ctypes
    import sys

    if not sys.platform.startswith("linux") or parent is None:
        return
    libc = ctypes.CDLL(None, use_errno=True)
    if libc.prctl(_PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0) != 0:
        return  # not permitted here: the pool's own shutdown remains
    if os.getppid() != parent:  # the parent ended before the request took effect
        os._exit(1)


@contextlib.contextmanager
def sigint_ignored_by_children():
    """Worker processes started inside ignore SIGINT (an ignored signal stays ignored in a new
    interpreter), so Ctrl-C reaches the main process only, which stops them (:mod:`hht3d.stopping`).

    Multiprocessing's resource tracker is started first with its output dropped: after a stop it
    would otherwise report, on the terminal, the semaphores of the ended workers that it removes.
    """
    import threading
    from multiprocessing import resource_tracker

    from ..open3d_quiet import captured_native_output

    with captured_native_output():
        resource_tracker.ensure_running()
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)
