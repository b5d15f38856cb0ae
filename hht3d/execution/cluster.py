"""Waiting for a ``dask.distributed`` computation with bounds: a lost cluster is reported, not waited for.

A worker that dies is replaced by the scheduler and its tasks rerun, at
most ``distributed.scheduler.allowed-failures`` times per task (Dask's
default 3) before the task counts as killing its workers.  What cannot
recover is reported as :class:`ClusterLost`, in one line, within a bounded
time:

* the scheduler is gone (the client lost its connection);
* the cluster has had no workers for ``hht3d.no-workers-timeout`` seconds
  (Dask configuration; default :data:`NO_WORKERS_TIMEOUT`, environment
  ``DASK_HHT3D__NO_WORKERS_TIMEOUT``);
* a task killed its worker more often than allowed.
"""

from __future__ import annotations

import asyncio
import time
from concurrent.futures import CancelledError
from typing import Any

import dask

from ..errors import HHT3DError, one_line

__all__ = ["ClusterLost", "NO_WORKERS_TIMEOUT", "gather_bounded"]

#: Seconds a run waits for a cluster that has no workers before giving up.
NO_WORKERS_TIMEOUT = 60.0
#: Seconds between checks of the cluster while waiting.
POLL = 1.0


class ClusterLost(HHT3DError):
    """The Dask cluster a run was computing on is gone (its scheduler, or every worker)."""


def gather_bounded(client: Any, futures: Any, where: str) -> list:
    """``client.gather(futures)``, checking the cluster every :data:`POLL` seconds.

    Raises
    ------
    ClusterLost
        Naming ``where`` (the scheduler) and what was lost.
    """
    from distributed import wait
    from distributed.scheduler import KilledWorker

    patience = float(dask.config.get("hht3d.no-workers-timeout", NO_WORKERS_TIMEOUT))
    alone_since = None
    while True:
        try:
            wait(futures, timeout=POLL)
            return client.gather(futures)
        except (TimeoutError, asyncio.TimeoutError):
            pass
        except CancelledError:
            raise ClusterLost(f"lost the connection to the Dask scheduler at {where}") from None
        except KilledWorker as exc:
            raise ClusterLost(
                f"a task ended its Dask worker at {where} too often "
                f"(distributed.scheduler.allowed-failures): {one_line(exc)}"
            ) from None
        if client.status != "running" or any(f.status == "cancelled" for f in futures):
            raise ClusterLost(f"lost the connection to the Dask scheduler at {where}")
        if client.scheduler_info().get("workers"):
            alone_since = None
        elif alone_since is None:
            alone_since = time.monotonic()
        elif time.monotonic() - alone_since > patience:
            raise ClusterLost(
                f"the Dask cluster at {where} has had no workers for {patience:.0f} s (hht3d.no-workers-timeout)"
            )
