"""Clean stops: SIGTERM and SIGINT end a run with one line, its workers ended, its temporary files removed.

:func:`stop_on_signals` turns the first SIGTERM or SIGINT into
:class:`Stopped` in the main thread (later ones are ignored while the run
stops).  :func:`clean_stop` then refuses new temporary files
(:func:`hht3d.io.atomic.stop_writes`), ends the worker processes this process
started (a process pool, a local Dask cluster), releases the locks of URL
output folders, and removes the temporary files of this process and of
ended ones in the output folders.  Outputs are
written atomically and recorded in the folder's manifest before their
rename, so the run is resumable with ``--resume``.  The CLI exits with
128 + the signal number (143 for SIGTERM, 130 for SIGINT).
"""

from __future__ import annotations

import contextlib
import multiprocessing
import os
import signal
import threading
from collections.abc import Iterable, Iterator
from pathlib import Path
from typing import Any

__all__ = ["SIGNALS", "Stopped", "stop_on_signals", "clean_stop"]

#: The signals that stop a run: SIGTERM where the platform has it (POSIX, and Windows'
#: ``signal.raise_signal``), and SIGINT.
SIGNALS = tuple(getattr(signal, name) for name in ("SIGTERM", "SIGINT") if hasattr(signal, name))
#: Seconds a worker process is given to end after SIGTERM before it is killed.
WORKER_GRACE = 3.0
#: Seconds the writes open in other threads are given to end (and remove their temporary files).
WRITE_GRACE = 10.0


class Stopped(BaseException):
    """The run was stopped by a signal (a ``BaseException``, like ``KeyboardInterrupt``)."""

    def __init__(self, signum: int):
        super().__init__(signal.Signals(signum).name)
        self.signum = signum

    @property
    def exit_code(self) -> int:
        return 128 + self.signum


def _raise(signum: int, frame: Any) -> None:
    for sig in SIGNALS:  # one stop at a time: a second Ctrl-C does not interrupt the cleanup
        signal.signal(sig, signal.SIG_IGN)
    raise Stopped(signum)


@contextlib.contextmanager
def stop_on_signals() -> Iterator[None]:
    """Raise :class:`Stopped` in the main thread on the first SIGTERM or SIGINT; handlers restored after.

    Outside the main thread (where Python cannot set handlers) it changes nothing.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = {sig: signal.signal(sig, _raise) for sig in SIGNALS}
    try:
        yield
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)


def clean_stop(folders: Iterable[Path | str]) -> list:
    """End this process's worker processes, release its URL folders' locks, remove the temporary files
    left in ``folders``, and the temporary folders of downloads and uploads of this process and of its
    ended workers (their ``with`` blocks never finish: the stop ends with ``os._exit``).  Writes open in
    other threads (the threads scheduler) are waited for, up to :data:`WRITE_GRACE` seconds: each
    removes its temporary file instead of renaming it.  (The I/O it needs is imported here: this module loads before
    numpy, so that the command line catches a signal from its first moment, :mod:`hht3d.__main__`.)"""
    import psutil

    from .io import remove_stale_parts
    from .io.atomic import stop_writes, wait_for_writes
    from .io.storage import remove_temporary_folders
    from .io.url_lock import release_all

    stop_writes()
    wait_for_writes(WRITE_GRACE)  # a thread writing a figure would otherwise make its file after the removal
    release_all()  # the locks of URL output folders: the next run need not wait for their expiry
    pids = {os.getpid(), *(p.pid for p in psutil.Process().children(recursive=True))}
    children = multiprocessing.active_children()
    for child in children:
        with contextlib.suppress(Exception):
            child.terminate()
    for child in children:
        child.join(WORKER_GRACE)
        if child.is_alive():
            child.kill()
            child.join(WORKER_GRACE)
    return remove_stale_parts(folders, own={os.getpid()}) + remove_temporary_folders(pids)
