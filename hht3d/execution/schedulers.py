"""Running hht3d task graphs on a Dask scheduler.

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

Progress goes to stderr (:mod:`hht3d.execution.progress`); local workers are
set up by :mod:`hht3d.execution.workers`.
"""

from __future__ import annotations

import contextlib
import logging
import os
import sys
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from typing import Any

import dask

from ..decomposition.options import EnsembleOptions
from ..errors import InputError, one_line
from ..io.sealed import registered
from ..logs import get_logger, quieted, showing
from ..records import Record, option
from .cluster import gather_bounded
from .progress import in_notebook, is_terminal, local_progress
from .workers import check_main_guard, limit_blas_threads, sigint_ignored_by_children

__all__ = ["SCHEDULERS", "MAX_WORKERS", "ExecutionOptions", "compute", "open_client"]

SCHEDULERS = ("synchronous", "threads", "processes", "distributed")
#: The most workers a run may ask for: threads, processes or local-cluster workers.
MAX_WORKERS = 256


@dataclass(frozen=True)
class ExecutionOptions(Record):
    """The ``execution`` block: where and how the graph runs (:func:`compute`),
    and the default seed of randomised steps.  Its settings are also the checks of the CLI's
    ``--scheduler`` and ``--workers``."""

    label = "execution"

    scheduler: str = option("threads", "Dask scheduler", choices=SCHEDULERS)
    workers: int | None = option(
        None,
        "threads, processes or cluster workers (default: one per core)",
        kind="int",
        minimum=1,
        maximum=MAX_WORKERS,
    )
    address: str | None = option(None, "address of a running dask.distributed scheduler", kind="str")
    progress: bool = option(True, "progress bar on stderr")
    seed: int = option(0, "default seed of randomised steps", like=EnsembleOptions.specs()["seed"])


_LOG = get_logger("hht3d.execution")


@contextlib.contextmanager
def open_client(workers: int | None = None, address: str | None = None, *, announce: bool = True) -> Iterator[Any]:
    """A ``distributed.Client``: to ``address`` if given, else to a new ``LocalCluster``.

    The local cluster has ``workers`` single-threaded worker processes
    (default: one per core); both are closed on exit.  With ``announce``, the
    dashboard link is logged (``hht3d.execution``, :mod:`hht3d.logs`).

    Parameters
    ----------
    workers : int, optional
        Worker processes of the local cluster (default: one per core).
    address : str, optional
        The address of a running Dask scheduler; when given, no local cluster is made.
    announce : bool, optional
        Log the dashboard link (default ``True``).

    Yields
    ------
    distributed.Client
        The client, closed (with its local cluster) when the ``with`` block ends.
    """
    from distributed import Client, LocalCluster

    if address:
        try:
            client = Client(address, timeout="10s")
        except (OSError, TimeoutError, ValueError, TypeError) as exc:
            raise InputError(f"cannot reach the Dask scheduler at {address!r}: {one_line(exc)}") from None
        cluster = None
    else:
        with sigint_ignored_by_children():
            # Only critical logs: a worker stopped mid-heartbeat (SIGTERM, Ctrl-C) logs an ERROR with a
            # traceback; task errors reach the client and the summary rows anyway.
            cluster = LocalCluster(
                n_workers=workers or os.cpu_count(),
                threads_per_worker=1,
                processes=True,
                dashboard_address=":0",
                silence_logs=logging.CRITICAL,
            )
        client = Client(cluster)
    try:
        if announce:
            _LOG.info("Dask dashboard at %s", client.dashboard_link)
        yield client
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


def compute(
    *graphs: Any,
    scheduler: str = "threads",
    workers: int | None = None,
    address: str | None = None,
    progress: bool = True,
    client: Any = None,
) -> tuple:
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
        Show progress: in a notebook its widget (distributed) or a redrawn bar, on a terminal a bar on
        stderr, otherwise plain lines through the ``hht3d.progress`` logger (shown unless the
        application configured logging).
    client : distributed.Client, optional
        Reuse a client instead of opening one.

    Returns
    -------
    tuple
        The value of each graph, in order.

    Examples
    --------
    >>> import dask
    >>> from hht3d.execution import compute
    >>> compute(dask.delayed(sum)([1, 2]), dask.delayed(max)(3, 4), scheduler="synchronous", progress=False)
    (3, 4)
    """
    if address or client is not None:
        scheduler = "distributed"
    if scheduler not in SCHEDULERS:
        raise InputError(f"unknown scheduler {scheduler!r}; choose one of {SCHEDULERS}")
    ExecutionOptions.check("workers", workers)
    if scheduler == "processes" or (scheduler == "distributed" and not address and client is None):
        check_main_guard(f"{scheduler} scheduler")
    with showing() if progress else contextlib.nullcontext():
        if scheduler == "distributed":
            # the client's reconnect attempts: a lost cluster is reported as ClusterLost instead
            with quieted("distributed.client"):
                if client is not None:
                    return _compute_distributed(client, graphs, progress)
                with open_client(workers, address) as opened:
                    return _compute_distributed(opened, graphs, progress, address or "a local cluster")
        options: dict[str, Any] = {"scheduler": scheduler}
        if scheduler == "threads" and workers:
            options["num_workers"] = workers
        bar = local_progress() if progress else contextlib.nullcontext()
        pool: Any = _process_pool(workers) if scheduler == "processes" else contextlib.nullcontext()
        with bar, pool as pool:
            return dask.compute(*graphs, **options, **({"pool": pool} if pool is not None else {}))


@contextlib.contextmanager
def _process_pool(workers: int | None) -> Iterator[Any]:
    """A pool of ``workers`` processes (default one per core) with BLAS limited to one thread and the
    run's sealed storage options (:mod:`hht3d.io.sealed`: the tasks carry their tokens), all
    started at once with SIGINT ignored (so that Ctrl-C, sent to the whole process group, reaches the
    main process only, even while a worker is still starting)."""
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor

    count = workers or os.cpu_count() or 1
    context = multiprocessing.get_context(dask.config.get("multiprocessing.context", "spawn"))
    with sigint_ignored_by_children():
        pool = ProcessPoolExecutor(
            count, mp_context=context, initializer=limit_blas_threads, initargs=(os.getpid(), registered())
        )
        for _ in range(count):  # each submission finding no idle worker starts one
            pool.submit(os.getpid)
    try:
        yield pool
    finally:
        pool.shutdown(wait=False, cancel_futures=True)


def _compute_distributed(client: Any, graphs: Sequence[Any], progress: bool, where: str = "the given client") -> tuple:
    from distributed import progress as show_progress

    from .sharing import share_storage_options

    share_storage_options(client)  # the tasks carry only their tokens (hht3d.io.sealed)
    futures = client.compute(list(graphs))
    if progress and in_notebook():  # the notebook's widget, shown now, updates itself while the results are gathered
        from IPython.display import display

        display(show_progress(futures, notebook=True))
    elif progress and is_terminal(sys.stderr):
        show_progress(futures, notebook=False)
        print(file=sys.stderr)
    return tuple(gather_bounded(client, futures, where))
