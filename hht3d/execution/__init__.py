"""Running task graphs: the schedulers, their workers, progress and lost clusters.

* :mod:`~hht3d.execution.schedulers` — :func:`compute` on ``synchronous``, ``threads``,
  ``processes`` or ``distributed``, and :func:`open_client`;
* :mod:`~hht3d.execution.workers` — how many workers, their BLAS threads and SIGINT;
* :mod:`~hht3d.execution.progress` — progress bars and plain progress lines;
* :mod:`~hht3d.execution.cluster` — gathering results from a cluster that may lose its workers;
* :mod:`~hht3d.execution.sharing` — a run's sealed storage options sent to a cluster's workers.
"""

from typing import Any

from .cluster import ClusterLost
from .progress import PROGRESS_INTERVAL, ProgressLines
from .schedulers import MAX_WORKERS, SCHEDULERS, ExecutionOptions, compute, open_client
from .workers import worker_count


def share_storage_options(client: Any) -> None:
    """Install this process's sealed storage options on ``client``'s workers
    (:func:`hht3d.execution.sharing.share_storage_options`; imports ``distributed``).

    Parameters
    ----------
    client : distributed.Client
        The client whose workers receive the options.
    """
    from .sharing import share_storage_options as share

    share(client)


__all__ = [
    "SCHEDULERS",
    "MAX_WORKERS",
    "compute",
    "open_client",
    "worker_count",
    "PROGRESS_INTERVAL",
    "ProgressLines",
    "ExecutionOptions",
    "ClusterLost",
    "share_storage_options",
]
