"""What each worker of a local scheduler is set up with: its BLAS threads, SIGINT, and how many there are.

Process-pool workers run their BLAS, OpenMP and MKL with one thread each
(:data:`SINGLE_THREAD_ENV`), so that the pool does not oversubscribe the
cores, and ignore SIGINT: Ctrl-C reaches the whole process group, and the
main process stops them (:mod:`hht3d.stopping`).
"""

from __future__ import annotations

import ast
import contextlib
import os
import signal
import sys
from collections.abc import Iterator
from types import FrameType

import dask

__all__ = [
    "SINGLE_THREAD_ENV",
    "worker_count",
    "limit_blas_threads",
    "end_with_parent",
    "sigint_ignored_by_children",
    "check_main_guard",
]

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

    if not sys.platform.startswith("linux") or parent is None:
        return
    libc = ctypes.CDLL(None, use_errno=True)
    if libc.prctl(_PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0) != 0:
        return  # not permitted here: the pool's own shutdown remains
    if os.getppid() != parent:  # the parent ended before the request took effect
        os._exit(1)


@contextlib.contextmanager
def sigint_ignored_by_children() -> Iterator[None]:
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


def check_main_guard(what: str) -> None:
    """Refuse to start worker processes from the top level of a script outside ``if __name__ ==
    "__main__":``.

    Worker processes are spawned: each imports the main script again, so an unguarded call would
    run again in every worker (Dask's ``LocalCluster`` and ``multiprocessing`` then stall, and the
    run hangs without a word).  ``what`` names the scheduler in the message.

    Raises
    ------
    InputError
        Naming the script, the line and the fix.
    """
    from ..errors import InputError

    main = sys.modules.get("__main__")
    path = getattr(main, "__file__", None)
    spec = getattr(getattr(main, "__spec__", None), "name", "") or ""
    if spec == "__main__" or spec.endswith(".__main__"):  # python -m PACKAGE: spawned workers skip it
        return
    frame: FrameType | None = sys._getframe(1)
    while frame is not None and not (
        frame.f_globals is getattr(main, "__dict__", None) and frame.f_code.co_name == "<module>"
    ):
        frame = frame.f_back
    if frame is None or path is None:  # not called from a script's top level (a function, a notebook, -c)
        return
    try:
        tree = ast.parse(open(path, encoding="utf-8").read())
    except (OSError, SyntaxError, ValueError):
        return
    line = frame.f_lineno
    guarded = any(
        isinstance(node, ast.If)
        and _is_main_test(node.test)
        and node.body[0].lineno <= line <= (node.body[-1].end_lineno or line)
        for node in ast.walk(tree)
    )
    if not guarded:
        raise InputError(
            f"{path}:{line}: the {what} starts worker processes, and each imports this script "
            'again: put the call under `if __name__ == "__main__":`'
        )


def _is_main_test(test: ast.expr) -> bool:
    """Whether ``test`` is ``__name__ == "__main__"`` (either way round)."""
    if not (isinstance(test, ast.Compare) and len(test.ops) == 1 and isinstance(test.ops[0], ast.Eq)):
        return False
    sides = [test.left, *test.comparators]
    names = {s.id for s in sides if isinstance(s, ast.Name)}
    values = {s.value for s in sides if isinstance(s, ast.Constant)}
    return names == {"__name__"} and values == {"__main__"}
