"""How many threads hht3d's own numerical kernels may use.

The cores this process may run on, or ``OMP_NUM_THREADS`` where it is set: Dask's worker
processes set it to 1 (:mod:`hht3d.execution.workers`), so that the workers of one machine
do not oversubscribe its cores.  NumPy and SciPy's sparse products release the GIL, so
threads of one process run them in parallel.
"""

from __future__ import annotations

import os

__all__ = ["usable_cores", "SINGLE_THREAD_ENV"]

#: Environment that keeps a process's BLAS/OpenMP/MKL to one thread (Dask worker processes, block processes).
SINGLE_THREAD_ENV = {"OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1"}


def usable_cores() -> int:
    """``OMP_NUM_THREADS`` where set to a positive integer, else the cores this process may run on."""
    budget = os.environ.get("OMP_NUM_THREADS", "")
    if budget.isdigit() and int(budget) > 0:
        return int(budget)
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1
