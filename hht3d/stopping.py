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

import _thread
import contextlib
import multiprocessing
import os
import signal
import sys
import threading
import time
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
    _take_swallowed()
    raise Stopped(signum)


#: The signal of a stop that Python swallowed, until it is raised again (:func:`_unraisable_hook`).
_swallowed: list[int] = []
_swallowed_lock = threading.Lock()
#: Seconds after which a swallowed stop is raised again in the main thread.
RAISE_AGAIN_AFTER = 0.01


def _take_swallowed() -> int | None:
    with _swallowed_lock:
        return _swallowed.pop() if _swallowed else None


def _raise_again() -> None:
    """Trip the swallowed stop's signal in the main thread (from a thread: the hook has returned by then)."""
    time.sleep(RAISE_AGAIN_AFTER)
    with _swallowed_lock:
        if _swallowed:
            _thread.interrupt_main(signal.Signals(_swallowed[-1]))


def _unraisable_hook(previous: Any) -> Any:
    """A ``sys.unraisablehook`` that raises a :class:`Stopped` again when Python swallowed it.

    A signal's handler runs wherever the main thread is; in a ``__del__`` method or a weakref
    callback Python ignores its exception, and the run went on to exit 0, its stop lost.  The hook
    records the stop, re-arms the handlers and has a thread trip the signal once the hook has
    returned, so the stop surfaces in the code that runs next (or at the end of
    :func:`stop_on_signals`); other unraisable exceptions go to ``previous``."""

    def hook(unraisable: Any) -> None:
        stop = unraisable.exc_value
        if not isinstance(stop, Stopped) or threading.current_thread() is not threading.main_thread():
            previous(unraisable)
            return
        with _swallowed_lock:
            _swallowed[:] = [stop.signum]
        while True:
            try:
                for sig in SIGNALS:
                    signal.signal(sig, _raise)
                threading.Thread(target=_raise_again, name="hht3d-stop", daemon=True).start()
                return
            except Stopped as again:  # the thread tripped it before this hook returned: once more
                with _swallowed_lock:
                    _swallowed[:] = [again.signum]

    return hook


@contextlib.contextmanager
def stop_on_signals() -> Iterator[None]:
    """Raise :class:`Stopped` in the main thread on the first SIGTERM or SIGINT; handlers restored after.

    A stop raised where Python swallows exceptions (a ``__del__``, a weakref callback) is raised
    again in the code that follows, at the latest when the block ends (:func:`_unraisable_hook`).
    Outside the main thread (where Python cannot set handlers) it changes nothing.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = {sig: signal.signal(sig, _raise) for sig in SIGNALS}
    previous_hook = sys.unraisablehook
    sys.unraisablehook = _unraisable_hook(previous_hook)
    try:
        yield
    finally:
        swallowed = _take_swallowed()
        sys.unraisablehook = previous_hook
        for sig, handler in previous.items():
            signal.signal(sig, handler)
        if swallowed is not None:
            raise Stopped(swallowed)


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
