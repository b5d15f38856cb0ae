"""What each worker of a local scheduler is set up with: its BLAS threads, SIGINT, its parent, and how many there are.

Process-pool workers run their BLAS, OpenMP and MKL with one thread each
(:data:`SINGLE_THREAD_ENV`), so that the pool does not oversubscribe the
cores, and ignore SIGINT: Ctrl-C reaches the whole process group, and the
main process stops them (:mod:`hht3d.stopping`).  They end with their parent
(:func:`end_with_parent`).
"""

from __future__ import annotations

import ast
import contextlib
import os
import signal
import sys
import threading
import time
from collections.abc import Iterator
from types import FrameType

import dask
import psutil

from ..io.atomic import writes_end_with
from ..io.sealed import install
from ..linalg.threads import SINGLE_THREAD_ENV

__all__ = [
    "SINGLE_THREAD_ENV",
    "worker_count",
    "limit_blas_threads",
    "end_with_parent",
    "parent_alive",
    "PARENT_CHECK",
    "sigint_ignored_by_children",
    "check_main_guard",
]


def worker_count() -> int:
    """Workers of the scheduler a graph built now will most likely run on.

    The workers of the current ``dask.distributed`` client if there is one,
    else dask's configured ``num_workers``, else one per core (the default of
    :func:`compute` for every scheduler).

    Returns
    -------
    int
        The workers of the default distributed client, else Dask's ``num_workers`` or the cores; at least 1.

    Examples
    --------
    >>> import dask
    >>> from hht3d.execution import worker_count
    >>> with dask.config.set(num_workers=3):  # no distributed client here
    ...     worker_count()
    3
    """
    try:
        from distributed import default_client

        return max(1, len(default_client().scheduler_info()["workers"]))
    except (ImportError, ValueError):  # no distributed, or no client
        return int(dask.config.get("num_workers", None) or os.cpu_count() or 1)


def limit_blas_threads(parent: int | None = None, storage_options: dict[str, dict] | None = None) -> None:
    """Process-pool initializer: runs before numpy is imported in a spawned worker.

    Workers also ignore SIGINT: Ctrl-C reaches the whole process group, and
    the main process stops them (:mod:`hht3d.stopping`), without a traceback
    from each.  They end with their parent (:func:`end_with_parent`), even
    when it is killed and cannot stop them.  ``storage_options`` are the run's
    sealed options (:func:`hht3d.io.sealed.registered`), whose tokens its tasks carry.
    """
    install(storage_options)
    os.environ.update(SINGLE_THREAD_ENV)
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    end_with_parent(parent)


#: ``prctl`` option that sends a signal to this process when its parent ends (Linux).
_PR_SET_PDEATHSIG = 1
#: Seconds between a worker's checks that its parent still runs, where the kernel cannot end it.
PARENT_CHECK = 0.5


def end_with_parent(parent: int | None) -> None:
    """End this worker when its parent process ``parent`` ends, so that a parent killed with
    SIGKILL leaves no worker computing and recording results.

    On Linux the kernel does it (``PR_SET_PDEATHSIG``).  Elsewhere, or where ``prctl`` is refused,
    a daemon thread checks every :data:`PARENT_CHECK` seconds, between tasks and within long ones,
    that the parent still runs (:func:`parent_alive`), and ends the worker when it does not.  In
    either case no write finished after the parent ended is renamed into place or recorded in a
    manifest (:func:`hht3d.io.atomic.writes_end_with`): that check is made at the write, so it
    holds in the moments before the kernel or the thread acts.  A parent already gone ends the
    worker at once.
    """
    if parent is None:
        return
    writes_end_with(parent)
    if not _kernel_ends_worker():
        threading.Thread(target=_watch_parent, args=(parent,), name="hht3d-parent", daemon=True).start()
    if not parent_alive(parent):  # the parent ended before either took effect
        os._exit(1)


def _kernel_ends_worker() -> bool:
    """Ask the kernel to SIGKILL this process when its parent ends; whether it will (Linux only)."""
    import ctypes

    if not sys.platform.startswith("linux"):
        return False
    libc = ctypes.CDLL(None, use_errno=True)
    return bool(libc.prctl(_PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0) == 0)


def parent_alive(parent: int) -> bool:
    """Whether ``parent`` is still this process's parent and runs: on POSIX an orphan is adopted
    (its ``getppid`` changes); Windows keeps the former id, so the process itself is looked up."""
    return os.getppid() == parent and psutil.pid_exists(parent)


def _watch_parent(parent: int) -> None:
    """End this worker process as soon as ``parent`` has ended (a daemon thread of
    :func:`end_with_parent`; ``os._exit``: the task running has nothing left to report to)."""
    while parent_alive(parent):
        time.sleep(PARENT_CHECK)
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
