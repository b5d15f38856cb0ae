"""The lock of an output folder, ``FOLDER/.hht3d.lock``, shared by concurrent runs and threads.

It is the operating system's exclusive lock (``flock`` on POSIX, ``msvcrt.locking`` on
Windows), so a process that dies holding it releases it.  The lock file holds its holder's
pid, host and run id; a run finding it held says who holds it and gives up after
:data:`LOCK_TIMEOUT` seconds (``HHT3D_LOCK_TIMEOUT``).  A lock file that is a link or not a
regular file is refused, never followed.
"""

from __future__ import annotations

import contextlib
import errno
import json
import os
import socket
import stat
import threading
import time
from collections.abc import Iterator
from pathlib import Path

try:  # POSIX
    import fcntl
except ImportError:  # Windows
    fcntl = None  # type: ignore[assignment]  # the module or None, by platform
try:  # Windows
    import msvcrt
except ImportError:  # POSIX
    msvcrt = None  # type: ignore[assignment]  # the module or None, by platform

from ..errors import OutputError, one_line
from ..logs import get_logger

__all__ = ["LOCK", "LOCK_TIMEOUT", "folder_lock", "lock_timeout"]

LOCK = ".hht3d.lock"
_NOFOLLOW = getattr(os, "O_NOFOLLOW", 0)
#: Seconds a run waits for another process's lock on an output folder before giving up
#: (the environment variable ``HHT3D_LOCK_TIMEOUT`` overrides it).
LOCK_TIMEOUT = 600.0
_POLL = 0.2
#: Windows locks a byte range that readers cannot read: one past the holder's line.
_LOCKED_BYTE = 4096
_LOG = get_logger("hht3d.io")
_HELD = threading.local()


@contextlib.contextmanager
def folder_lock(folder: Path | str, run: str | None = None) -> Iterator[None]:
    """An exclusive lock on ``folder`` (made if missing) between processes, threads and runs;
    taken again by the thread holding it, it is a no-op.

    The lock file ``FOLDER/.hht3d.lock`` holds the pid, host and run id of its
    holder.  A run that finds it held logs once who holds it, then waits up
    to :func:`lock_timeout` seconds.  The lock file must be a regular file:
    a symbolic link (to a file outside) is not followed, created or locked.

    Raises
    ------
    OutputError
        The lock file is a link or not a regular file, or another process held it for the whole timeout.
    """
    folder = Path(folder)
    held = _HELD.__dict__.setdefault("folders", set())
    key = os.path.realpath(folder)
    if key in held:
        yield
        return
    fd = _open_lock(folder)
    try:
        _acquire(fd, folder)
        held.add(key)
        try:
            _write_holder(fd, run)
            yield
        finally:
            held.discard(key)
            _unlock(fd)
    finally:
        os.close(fd)


def lock_timeout() -> float:
    """:data:`LOCK_TIMEOUT`, or the seconds in the environment variable ``HHT3D_LOCK_TIMEOUT``.

    Raises
    ------
    OutputError
        ``HHT3D_LOCK_TIMEOUT`` is not a number of seconds.
    """
    text = os.environ.get("HHT3D_LOCK_TIMEOUT")
    if text is None:
        return LOCK_TIMEOUT
    try:
        seconds = float(text)
    except ValueError:
        seconds = -1.0
    if not seconds >= 0:
        raise OutputError(f"HHT3D_LOCK_TIMEOUT={text!r}: not a number of seconds; set it to e.g. 600")
    return seconds


def _open_lock(folder: Path) -> int:
    """The lock file of ``folder``, opened (made if missing) without following a link."""
    path = folder / LOCK
    flags = os.O_RDWR | os.O_CREAT | _NOFOLLOW | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_BINARY", 0)
    try:
        folder.mkdir(parents=True, exist_ok=True)
        if not _NOFOLLOW and os.path.islink(path):
            raise OSError(errno.ELOOP, "a symbolic link")
        fd = os.open(path, flags, 0o666)
    except OSError as exc:
        if exc.errno in (errno.ELOOP, errno.EISDIR):
            raise _not_regular(path) from None
        raise OutputError(f"{folder}: cannot lock the output folder ({exc.strerror or one_line(exc)})") from None
    if not stat.S_ISREG(os.fstat(fd).st_mode):
        os.close(fd)
        raise _not_regular(path)
    return fd


def _not_regular(path: Path) -> OutputError:
    return OutputError(
        f"{path}: the output folder's lock file is a link or not a regular file; hht3d locks only a "
        "regular file it made: remove it and run again"
    )


def _acquire(fd: int, folder: Path) -> None:
    """Take the lock of the open lock file ``fd``, waiting at most :func:`lock_timeout` seconds."""
    if _try_lock(fd):
        return
    timeout = lock_timeout()
    _LOG.info(f"{folder}: waiting for {_holder(fd)}, which holds the output folder's lock (at most {timeout:g} s)")
    deadline = time.monotonic() + timeout
    while not _try_lock(fd):
        if time.monotonic() >= deadline:
            raise OutputError(
                f"{folder}: {_holder(fd)} still holds the output folder's lock after {timeout:g} s; "
                "wait for that run to end (or stop it), choose another output folder, or set "
                "HHT3D_LOCK_TIMEOUT to wait longer"
            )
        time.sleep(_POLL)


def _try_lock(fd: int) -> bool:
    """Try to take the operating system's exclusive lock on ``fd`` at once: ``flock`` on POSIX,
    ``msvcrt.locking`` of one byte on Windows.  Either is released when the holding process ends,
    however it ends."""
    if fcntl is not None:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            return False
        return True
    if msvcrt is None:
        raise OutputError("this platform has neither fcntl nor msvcrt: output folders cannot be locked")
    os.lseek(fd, _LOCKED_BYTE, os.SEEK_SET)
    try:
        msvcrt.locking(fd, msvcrt.LK_NBLCK, 1)
    except OSError as exc:
        if exc.errno not in (errno.EACCES, errno.EDEADLOCK):
            raise
        return False
    return True


def _unlock(fd: int) -> None:
    if fcntl is not None:
        fcntl.flock(fd, fcntl.LOCK_UN)
        return
    os.lseek(fd, _LOCKED_BYTE, os.SEEK_SET)
    msvcrt.locking(fd, msvcrt.LK_UNLCK, 1)


def _write_holder(fd: int, run: str | None) -> None:
    """Write who holds the lock (pid, host, run id) at the start of the lock file."""
    line = json.dumps({"pid": os.getpid(), "host": socket.gethostname(), "run": run}).encode()[: _LOCKED_BYTE - 1]
    os.ftruncate(fd, 0)
    os.lseek(fd, 0, os.SEEK_SET)
    os.write(fd, line + b"\n")


def _holder(fd: int) -> str:
    """Who holds the lock, as its lock file says: ``"pid 12 on host h (run R)"``."""
    try:
        os.lseek(fd, 0, os.SEEK_SET)
        data = json.loads(os.read(fd, _LOCKED_BYTE))
        who = f"pid {int(data['pid'])} on {str(data['host'])[:100]}"
        return who + (f" (run {str(data['run'])[:100]})" if data.get("run") else "")
    except (OSError, ValueError, TypeError, KeyError):
        return "another process"
