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
"""
from __future__ import annotations

import contextlib
import errno
import hashlib
import json
import os
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
from .atomic import atomic_path, before_rename

__all__ = ["MANIFEST", "LOCK", "new_run_id", "folder_lock", "entries", "is_recorded", "record", "Recorded",
           "recording", "recorded_names", "check_overwrites"]

MANIFEST = ".hht3d-manifest.json"
LOCK = ".hht3d.lock"


def new_run_id() -> str:
    """A run id: UTC time and a random suffix."""
    return f"{time.strftime('%Y%m%dT%H%M%SZ', time.gmtime())}-{uuid.uuid4().hex[:8]}"


_HELD = threading.local()


@contextlib.contextmanager
def folder_lock(folder):
    """An exclusive lock on ``folder`` (made if missing) between processes, threads and runs;
    taken again by the thread holding it, it is a no-op."""
    folder = Path(folder)
    held = _HELD.__dict__.setdefault("folders", set())
    key = os.path.realpath(folder)
    if key in held:
        yield
        return
    try:
        folder.mkdir(parents=True, exist_ok=True)
        handle = open(folder / LOCK, "a+b")
    except OSError as exc:
        raise OutputError(f"{folder}: cannot lock the output folder ({exc.strerror or one_line(exc)})") from None
    with handle, _exclusive(handle):
        held.add(key)
        try:
            yield
        finally:
            held.discard(key)


@contextlib.contextmanager
def _exclusive(handle):
    """Hold the operating system's exclusive lock on the open file ``handle``, waiting until it is
    free: ``flock`` on POSIX, ``msvcrt.locking`` of its first byte on Windows.  Either is released
    when the holding process ends, however it ends."""
    if fcntl is not None:
        fcntl.flock(handle, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(handle, fcntl.LOCK_UN)
        return
    if msvcrt is None:
        raise OutputError("this platform has neither fcntl nor msvcrt: output folders cannot be locked")
    handle.seek(0)
    while True:
        try:
            msvcrt.locking(handle.fileno(), msvcrt.LK_LOCK, 1)  # tries for 10 s, then raises EDEADLOCK
            break
        except OSError as exc:
            if exc.errno != errno.EDEADLOCK:
                raise
    try:
        yield
    finally:
        handle.seek(0)
        msvcrt.locking(handle.fileno(), msvcrt.LK_UNLCK, 1)


def _key(path, folder) -> str:
    return os.path.relpath(os.path.realpath(path), os.path.realpath(folder))


def entries(folder) -> dict:
    """The manifest's entries by relative path (empty without a readable manifest)."""
    try:
        data = json.loads((Path(folder) / MANIFEST).read_text(encoding="utf-8"))
        return dict(data.get("files", {}))
    except (OSError, ValueError, AttributeError):
        return {}


def _digest(path) -> tuple[int, str]:
    sha = hashlib.sha256()
    size = 0
    with open(path, "rb") as handle:
        while block := handle.read(1 << 20):
            sha.update(block)
            size += len(block)
    return size, sha.hexdigest()


def is_recorded(path, folder, known: dict | None = None) -> bool:
    """Whether ``path`` is a complete file that hht3d wrote: recorded, same size and checksum, not empty."""
    entry = (entries(folder) if known is None else known).get(_key(path, folder))
    try:
        if not entry or entry.get("size", 0) <= 0 or os.path.getsize(path) != entry["size"]:
            return False
        return _digest(path) == (entry["size"], entry.get("sha256"))
    except OSError:
        return False


def record(paths, folder, run: str, *, named=None) -> None:
    """Add complete files to the manifest of ``folder`` (under its lock; the manifest is written atomically).

    ``named`` gives the names to record them under (default ``paths``): a
    temporary file is recorded under its final name just before it is renamed.
    """
    found = {_key(n, folder): _digest(p) for p, n in zip(paths, named or paths)}
    with before_rename(None), folder_lock(folder):  # the manifest itself is not recorded
        files = entries(folder)
        stamp = time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())
        files.update({key: {"size": size, "sha256": sha, "run": run, "written": stamp}
                      for key, (size, sha) in found.items()})
        with atomic_path(Path(folder) / MANIFEST) as tmp:
            tmp.write_text(json.dumps({"version": 1, "files": files}, indent=1), encoding="utf-8")


def recording(folder, run: str):
    """Record the atomic writes of this thread in the manifest of ``folder`` (see :class:`Recorded`)."""
    return before_rename(lambda tmp, path: record([tmp], folder, run, named=[path]))


class Recorded:
    """A writer whose atomic writes are recorded in the manifest of ``folder`` (a picklable task function).

    Each file is recorded, under its final name, by :func:`hht3d.io.atomic.atomic_path` just before the
    rename that completes it, so that a run stopped at any point never leaves a complete output the
    manifest does not know.
    """

    def __init__(self, write, folder, run: str):
        self.write, self.folder, self.run = write, str(folder), run
        self.__name__ = getattr(write, "__name__", "write")
        self.__module__, self.__qualname__ = write.__module__, write.__qualname__

    def __dask_tokenize__(self):
        return (self.write.__module__, self.write.__qualname__, self.folder, self.run)

    def __call__(self, *args, **kwargs):
        with recording(self.folder, self.run):
            return self.write(*args, **kwargs)


def recorded_names(folder) -> set[str]:
    """Names of the files directly in ``folder`` that a manifest of it or of a folder above records."""
    real = Path(os.path.realpath(folder))
    names = set()
    for above in [real, *real.parents]:
        if (above / MANIFEST).is_file():
            inside = os.path.relpath(real, above)
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
    for path in paths:
        if os.path.lexists(path) and not is_recorded(path, folder, known):
            raise OutputError(f"{path}: exists and hht3d did not write it (or it changed since: not as recorded "
                              f"in {Path(folder) / MANIFEST}); it is kept: move it away, change the output path, "
                              "or pass --overwrite")
