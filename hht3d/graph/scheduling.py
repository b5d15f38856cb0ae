"""Running hht3d task graphs on a Dask scheduler, with progress reporting.

Graph construction (:mod:`hht3d.graph.stages`) and execution are separate: any
graph runs unchanged on

* ``"synchronous"``: one thread, for debugging (pdb works inside tasks);
* ``"threads"``: a local thread pool;
* ``"processes"``: a local process pool (BLAS limited to one thread per
  process so the pool does not oversubscribe the cores);
* ``"distributed"``: a ``dask.distributed`` cluster, either a
  ``LocalCluster`` started on demand with ``workers`` single-threaded worker
  processes, or an existing scheduler given by ``address``
  (``"tcp://host:8786"``).

Progress goes to stderr: a bar on a terminal; in a log file or pipe, one
plain line at most every :data:`PROGRESS_INTERVAL` seconds.
"""
from __future__ import annotations

import contextlib
import logging
import os
import signal
import sys
import time

import dask
from dask.callbacks import Callback

from ..errors import InputError, one_line
from .cluster import ClusterLost, gather_bounded

__all__ = ["SCHEDULERS", "MAX_WORKERS", "PROGRESS_INTERVAL", "ProgressLines", "compute", "open_client",
           "worker_count", "ClusterLost"]

SCHEDULERS = ("synchronous", "threads", "processes", "distributed")
#: The most workers a run may ask for: threads, processes or local-cluster workers.
MAX_WORKERS = 256
#: Seconds between progress lines when stderr is not a terminal.
PROGRESS_INTERVAL = 10.0

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


def _limit_blas_threads() -> None:
    """Process-pool initializer: runs before numpy is imported in a spawned worker.

    Workers also ignore SIGINT: Ctrl-C reaches the whole process group, and
    the main process stops them (:mod:`hht3d.stopping`), without a traceback
    from each.
    """
    os.environ.update(SINGLE_THREAD_ENV)
    signal.signal(signal.SIGINT, signal.SIG_IGN)


@contextlib.contextmanager
def open_client(workers: int | None = None, address: str | None = None, *, log=sys.stderr):
    """A ``distributed.Client``: to ``address`` if given, else to a new ``LocalCluster``.

    The local cluster has ``workers`` single-threaded worker processes
    (default: one per core); both are closed on exit.  The dashboard link is
    written to ``log``.
    """
    from distributed import Client, LocalCluster

    if address:
        try:
            client = Client(address, timeout="10s")
        except (OSError, TimeoutError, ValueError, TypeError) as exc:
            raise InputError(f"cannot reach the Dask scheduler at {address!r}: {one_line(exc)}") from None
        cluster = None
    else:
        with _sigint_ignored_by_children():
            # Only critical logs: a worker stopped mid-heartbeat (SIGTERM, Ctrl-C) logs an ERROR with a
            # traceback; task errors reach the client and the summary rows anyway.
            cluster = LocalCluster(n_workers=workers or os.cpu_count(), threads_per_worker=1,
                                   processes=True, dashboard_address=":0", silence_logs=logging.CRITICAL)
        client = Client(cluster)
    try:
        if log is not None:
            print(f"hht3d: Dask dashboard at {client.dashboard_link}", file=log)
        yield client
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


@contextlib.contextmanager
def _sigint_ignored_by_children():
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


def compute(*graphs, scheduler: str = "threads", workers: int | None = None, address: str | None = None,
            progress: bool = True, client=None):
    """Compute Dask objects and return their values (a tuple, like ``dask.compute``).

    Parameters
    ----------
    graphs
        ``dask.delayed`` objects or collections of them.
    scheduler : {"synchronous", "threads", "processes", "distributed"}
    workers : int, optional
        Threads, processes or local-cluster workers; default one per core.
    address : str, optional
        Scheduler address of an existing cluster (implies ``"distributed"``).
    progress : bool
        Show progress on stderr (a bar, or plain lines when it is not a terminal).
    client : distributed.Client, optional
        Reuse a client instead of opening one.
    """
    if address or client is not None:
        scheduler = "distributed"
    if scheduler not in SCHEDULERS:
        raise InputError(f"unknown scheduler {scheduler!r}; choose one of {SCHEDULERS}")
    if workers is not None and not 1 <= workers <= MAX_WORKERS:
        raise InputError(f"workers must be in [1, {MAX_WORKERS}], got {workers}")
    if scheduler == "distributed":
        if client is not None:
            return _compute_distributed(client, graphs, progress)
        with open_client(workers, address) as opened:
            return _compute_distributed(opened, graphs, progress, address or "a local cluster")
    options = {"scheduler": scheduler}
    if scheduler == "threads" and workers:
        options["num_workers"] = workers
    bar = _local_progress() if progress else contextlib.nullcontext()
    with bar, (_process_pool(workers) if scheduler == "processes" else contextlib.nullcontext()) as pool:
        return dask.compute(*graphs, **options, **({"pool": pool} if pool is not None else {}))


@contextlib.contextmanager
def _process_pool(workers: int | None):
    """A pool of ``workers`` processes (default one per core) with BLAS limited to one thread, all
    started at once with SIGINT ignored (so that Ctrl-C, sent to the whole process group, reaches the
    main process only, even while a worker is still starting)."""
    from concurrent.futures import ProcessPoolExecutor
    import multiprocessing

    count = workers or os.cpu_count() or 1
    context = multiprocessing.get_context(dask.config.get("multiprocessing.context", "spawn"))
    with _sigint_ignored_by_children():
        pool = ProcessPoolExecutor(count, mp_context=context, initializer=_limit_blas_threads)
        for _ in range(count):  # each submission finding no idle worker starts one
            pool.submit(os.getpid)
    try:
        yield pool
    finally:
        pool.shutdown(wait=False, cancel_futures=True)


def _is_terminal(stream) -> bool:
    try:
        return stream.isatty()
    except (AttributeError, ValueError):  # no isatty, or closed
        return False


def _local_progress():
    """A redrawn bar on a terminal; rate-limited plain lines otherwise."""
    if _is_terminal(sys.stderr):
        from dask.diagnostics import ProgressBar

        return ProgressBar(minimum=1.0, out=sys.stderr)
    return ProgressLines(sys.stderr)


class ProgressLines(Callback):
    """Progress of a local scheduler as plain lines, ``hht3d: 40% of 125 tasks done, 12 s``.

    At most one line per ``interval`` seconds (default
    :data:`PROGRESS_INTERVAL`), and a last one when the run took longer than
    that: a log of a long run gets a few lines, not a redrawn bar's thousands
    of updates.
    """

    def __init__(self, out, interval: float | None = None):
        super().__init__()
        self.out, self.interval = out, PROGRESS_INTERVAL if interval is None else interval
        self.start = self.last = time.monotonic()

    def _start_state(self, dsk, state):
        self.start = self.last = time.monotonic()

    def _posttask(self, key, result, dsk, state, worker_id):
        now = time.monotonic()
        if now - self.last >= self.interval:
            self.last = now
            self._line(state, now)

    def _finish(self, dsk, state, errored):
        now = time.monotonic()
        if now - self.start >= self.interval and not errored:
            self._line(state, now)

    def _line(self, state, now: float) -> None:
        done = len(state["finished"])
        total = done + sum(len(state[k]) for k in ("ready", "waiting", "running"))
        print(f"hht3d: {100 * done // max(total, 1)}% of {total} tasks done, {now - self.start:.0f} s",
              file=self.out, flush=True)


def _compute_distributed(client, graphs, progress: bool, where: str = "the given client"):
    from distributed import progress as show_progress

    futures = client.compute(list(graphs))
    if progress and _is_terminal(sys.stderr):
        show_progress(futures, notebook=False)
        print(file=sys.stderr)
    return tuple(gather_bounded(client, futures, where))
