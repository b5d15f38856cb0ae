"""The manifest of an output folder: which files hht3d wrote there, complete, with size and checksum.

``FOLDER/.hht3d-manifest.json`` maps each file written (its path relative to
the folder) to its size in bytes, SHA-256, the run that wrote it and when.
An entry is added once the file is complete (after its atomic rename), under
an exclusive lock on ``FOLDER/.hht3d.lock`` shared by concurrent runs.  It is
what makes a folder safe to reuse:

* a file hht3d did not write is never replaced unless asked
  (:func:`check_overwrites`, the CLI's ``--overwrite``);
* ``--resume`` trusts an output only if the manifest records it and its size
  and checksum still match (:func:`is_recorded`; a 0-byte file never is);
* files the manifest records are never taken as inputs
  (:func:`recorded_names`, used by :func:`hht3d.io.paths.resolve_inputs`).

The manifest is untrusted input (anyone may plant one): an entry counts only
if it is well formed and its path stays inside the folder, lexically and
after links (:func:`valid_entries`, :func:`entries`); a manifest that is not
valid JSON of that shape, or not a regular file, counts as empty and is
replaced by the next record.  The lock file holds its holder's pid, host and
run id; a run finding it held says who holds it and gives up after
:data:`LOCK_TIMEOUT` seconds (``HHT3D_LOCK_TIMEOUT``).
"""
from __future__ import annotations

import contextlib
import errno
import hashlib
import json
import os
import posixpath
import re
import socket
import stat
import threading
import time
import uuid
from pathlib import Path

try:  # POSIX
    import fcntl
except ImportError:  # Windows
    fcntl = None
try:  # Windows
    import msvcrt
except ImportError:  # POSIX
    msvcrt = None

from ..errors import OutputError, one_line
from ..logs import get_logger
from .atomic import atomic_path, before_rename, check_inside, confined

__all__ = ["MANIFEST", "LOCK", "LOCK_TIMEOUT", "new_run_id", "folder_lock", "lock_timeout", "valid_entries",
           "entries", "digest", "is_recorded", "record", "updated", "Recorded", "recording", "recorded_names",
           "check_overwrites"]

MANIFEST = ".hht3d-manifest.json"
LOCK = ".hht3d.lock"
_NOFOLLOW = getattr(os, "O_NOFOLLOW", 0)
_SHA256 = re.compile(r"[0-9a-f]{64}")


def new_run_id() -> str:
    """A run id: UTC time and a random suffix."""
    return f"{time.strftime('%Y%m%dT%H%M%SZ', time.gmtime())}-{uuid.uuid4().hex[:8]}"


#: Seconds a run waits for another process's lock on an output folder before giving up
#: (the environment variable ``HHT3D_LOCK_TIMEOUT`` overrides it).
LOCK_TIMEOUT = 600.0
_POLL = 0.2
#: Windows locks a byte range that readers cannot read: one past the holder's line.
_LOCKED_BYTE = 4096
_LOG = get_logger("hht3d.io")
_HELD = threading.local()


@contextlib.contextmanager
def folder_lock(folder, run: str | None = None):
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
    return OutputError(f"{path}: the output folder's lock file is a link or not a regular file; hht3d locks only a "
                       "regular file it made: remove it and run again")


def _acquire(fd: int, folder: Path) -> None:
    """Take the lock of the open lock file ``fd``, waiting at most :func:`lock_timeout` seconds."""
    if _try_lock(fd):
        return
    timeout = lock_timeout()
    _LOG.info(f"{folder}: waiting for {_holder(fd)}, which holds the output folder's lock (at most {timeout:g} s)")
    deadline = time.monotonic() + timeout
    while not _try_lock(fd):
        if time.monotonic() >= deadline:
            raise OutputError(f"{folder}: {_holder(fd)} still holds the output folder's lock after {timeout:g} s; "
                              "wait for that run to end (or stop it), choose another output folder, or set "
                              "HHT3D_LOCK_TIMEOUT to wait longer")
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
    line = json.dumps({"pid": os.getpid(), "host": socket.gethostname(), "run": run}).encode()[:_LOCKED_BYTE - 1]
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


def _key(path, folder) -> str | None:
    """``path`` relative to ``folder`` after links (POSIX separators), or ``None`` if it lies outside."""
    real = confined(path, folder)
    return None if real is None else Path(os.path.relpath(real, os.path.realpath(folder))).as_posix()


def _entry_key(key) -> str | None:
    """A manifest key normalised lexically, or ``None`` if it is not a relative path staying in its folder."""
    if not isinstance(key, str) or not key or "\0" in key or "\\" in key or key.startswith("/") or ":" in key[:2]:
        return None
    norm = posixpath.normpath(key)
    return None if norm in (".", "..") or norm.startswith("../") else norm


def _well_formed(entry) -> bool:
    return (isinstance(entry, dict) and type(entry.get("size")) is int and entry["size"] > 0
            and isinstance(entry.get("sha256"), str) and _SHA256.fullmatch(entry["sha256"]) is not None)


def valid_entries(data, inside=lambda key: True) -> dict:
    """The entries of a parsed manifest that are well formed (a positive integer size, a SHA-256) and whose
    key is a relative path staying in the folder, lexically and by ``inside(key)``; the rest are ignored,
    as is a manifest that is not a mapping with ``files``: nothing they name counts as written by hht3d."""
    files = data.get("files") if isinstance(data, dict) else None
    if not isinstance(files, dict):
        return {}
    found = {}
    for key, entry in files.items():
        norm = _entry_key(key)
        if norm is not None and _well_formed(entry) and inside(norm):
            found[norm] = entry
    return found


def entries(folder) -> dict:
    """The manifest's valid entries by relative path (:func:`valid_entries`; empty without a readable manifest
    that is a regular file), keeping only those that resolve inside ``folder`` after links."""
    path = Path(folder) / MANIFEST
    try:
        if not stat.S_ISREG(os.lstat(path).st_mode):  # a link or a FIFO is no manifest hht3d wrote
            return {}
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return {}
    return valid_entries(data, lambda key: confined(Path(folder) / key, folder) is not None)


def digest(handle) -> tuple[int, str]:
    """Size and SHA-256 of what an open binary file holds, read to its end."""
    sha = hashlib.sha256()
    size = 0
    while block := handle.read(1 << 20):
        sha.update(block)
        size += len(block)
    return size, sha.hexdigest()


def _digest(path) -> tuple[int, str]:
    with open(path, "rb") as handle:
        return digest(handle)


def is_recorded(path, folder, known: dict | None = None) -> bool:
    """Whether ``path`` is a complete file that hht3d wrote: recorded inside ``folder``, same size and checksum."""
    entry = (entries(folder) if known is None else known).get(_key(path, folder))
    try:
        if not entry or os.path.getsize(path) != entry["size"]:
            return False
        return _digest(path) == (entry["size"], entry["sha256"])
    except OSError:
        return False


def record(paths, folder, run: str, *, named=None) -> None:
    """Add complete files to the manifest of ``folder`` (under its lock; the manifest is written atomically).

    ``named`` gives the names to record them under (default ``paths``): a
    temporary file is recorded under its final name just before it is
    renamed.  A file outside ``folder`` (``allow_outside``) is not recorded.
    Invalid entries of the manifest (:func:`valid_entries`) are dropped.
    """
    found = {_key(n, folder): _digest(p) for p, n in zip(paths, named or paths)}
    found.pop(None, None)
    with before_rename(None), folder_lock(folder, run):  # the manifest itself is not recorded
        with atomic_path(Path(folder) / MANIFEST) as tmp:
            tmp.write_text(updated(entries(folder), found, run), encoding="utf-8")


def updated(files: dict, found: dict, run: str) -> str:
    """The text of a manifest of ``files`` and, written now by the run ``run``, ``found`` (key: (size, SHA-256))."""
    stamp = time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())
    files = {**files, **{key: {"size": size, "sha256": sha, "run": run, "written": stamp}
                         for key, (size, sha) in found.items()}}
    return json.dumps({"version": 1, "files": files}, indent=1)


def recording(folder, run: str, *, confine: bool = True):
    """Record the atomic writes of this thread in the manifest of ``folder`` (see :class:`Recorded`); with
    ``confine``, refuse at its rename a file that no longer resolves inside ``folder``
    (:func:`hht3d.io.atomic.check_inside`)."""
    def hook(tmp, path):
        if confine:
            check_inside(tmp, path, folder)
        record([tmp], folder, run, named=[path])
    return before_rename(hook)


class Recorded:
    """A writer whose atomic writes are recorded in the manifest of ``folder`` (a picklable task function).

    Each file is recorded, under its final name, by :func:`hht3d.io.atomic.atomic_path` just before the
    rename that completes it, so that a run stopped at any point never leaves a complete output the
    manifest does not know.  Unless ``allow_outside``, a file whose folder no longer resolves inside
    ``folder`` at that point is refused (:func:`recording`).
    """

    def __init__(self, write, folder, run: str, *, allow_outside: bool = False):
        self.write, self.folder, self.run, self.allow_outside = write, str(folder), run, allow_outside
        self.__name__ = getattr(write, "__name__", "write")
        self.__module__, self.__qualname__ = write.__module__, write.__qualname__

    def __dask_tokenize__(self):
        return (self.write.__module__, self.write.__qualname__, self.folder, self.run, self.allow_outside)

    def __call__(self, *args, **kwargs):
        with recording(self.folder, self.run, confine=not self.allow_outside):
            return self.write(*args, **kwargs)


def recorded_names(folder) -> set[str]:
    """Names of the files directly in ``folder`` that a manifest of it or of a folder above records."""
    real = Path(os.path.realpath(folder))
    names = set()
    for above in [real, *real.parents]:
        if (above / MANIFEST).is_file():
            inside = Path(os.path.relpath(real, above)).as_posix()
            for key in entries(above):
                parent, _, name = key.rpartition("/")
                if (parent or ".") == inside:
                    names.add(name)
    return names


def check_overwrites(paths, folder, overwrite: bool) -> None:
    """Refuse to replace an existing file that hht3d did not write (unless ``overwrite``).

    Raises
    ------
    OutputError
        Naming the first such file.
    """
    if overwrite:
        return
    known = entries(folder)
    for path in paths:  # by its real path too: "sub/../x" exists even where "sub" does not
        if (os.path.lexists(path) or os.path.lexists(os.path.realpath(path))) and not is_recorded(path, folder, known):
            raise OutputError(f"{path}: exists and hht3d did not write it (or it changed since: not as recorded "
                              f"in {Path(folder) / MANIFEST}); it is kept: move it away, change the output path, "
                              "or pass --overwrite")
