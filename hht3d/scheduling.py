"""Running hht3d task graphs on a Dask scheduler, with progress reporting.

Graph construction (:mod:`hht3d.graph`) and execution are separate: any
graph runs unchanged on

* ``"synchronous"``: one thread, for debugging (pdb works inside tasks);
* ``"threads"``: a local thread pool;
* ``"processes"``: a local process pool (BLAS limited to one thread per
  process so the pool does not oversubscribe the cores);
* ``"distributed"``: a ``dask.distributed`` cluster, either a
  ``LocalCluster`` started on demand with ``workers`` single-threaded worker
  processes, or an existing scheduler given by ``address``
  (``"tcp://host:8786"``).
"""
from __future__ import annotations

import contextlib
import os
import sys

import dask

from .errors import InputError

__all__ = ["SCHEDULERS", "compute", "open_client", "worker_count"]

SCHEDULERS = ("synchronous", "threads", "processes", "distributed")

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
    """Process-pool initializer: runs before numpy is imported in a spawned worker."""
    os.environ.update(SINGLE_THREAD_ENV)


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
        except (OSError, TimeoutError) as exc:
            raise InputError(f"cannot reach the Dask scheduler at {address!r}: {exc}") from None
        cluster = None
    else:
        cluster = LocalCluster(n_workers=workers or os.cpu_count(), threads_per_worker=1,
                               processes=True, dashboard_address=":0", silence_logs=40)
        client = Client(cluster)
    try:
        if log is not None:
            print(f"hht3d: Dask dashboard at {client.dashboard_link}", file=log)
        yield client
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


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
        Show a progress bar on stderr.
    client : distributed.Client, optional
        Reuse a client instead of opening one.
    """
    if address or client is not None:
        scheduler = "distributed"
    if scheduler not in SCHEDULERS:
        raise InputError(f"unknown scheduler {scheduler!r}; choose one of {SCHEDULERS}")
    if workers is not None and workers < 1:
        raise InputError(f"workers must be >= 1, got {workers}")
    if scheduler == "distributed":
        if client is not None:
            return _compute_distributed(client, graphs, progress)
        with open_client(workers, address) as opened:
            return _compute_distributed(opened, graphs, progress)
    options = {"scheduler": scheduler}
    if scheduler != "synchronous" and workers:
        options["num_workers"] = workers
    if scheduler == "processes":
        options["initializer"] = _limit_blas_threads
    bar = _local_progress() if progress else contextlib.nullcontext()
    with bar:
        return dask.compute(*graphs, **options)


def _local_progress():
    from dask.diagnostics import ProgressBar

    return ProgressBar(minimum=1.0, out=sys.stderr)


def _compute_distributed(client, graphs, progress: bool):
    from distributed import progress as show_progress

    futures = client.compute(list(graphs))
    if progress:
        show_progress(futures, notebook=False)
        print(file=sys.stderr)
    return tuple(client.gather(futures))
