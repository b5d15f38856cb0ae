"""Atomic writes, the temporary files they leave behind, and checking output locations before a run.

A file is written as ``.NAME.PID-XXXXXXXX.part`` beside its target and renamed
over it only once complete (``NAME`` is cut so that the temporary name fits
in 255 bytes; ``PID`` is the writing process).  A run that is killed leaves
such files; :func:`remove_stale_parts` removes those of processes that no
longer run, and those of the current process and its workers at a stop.
"""
from __future__ import annotations

import contextlib
import os
import re
import tempfile
import threading
from pathlib import Path

import psutil

from ..errors import OutputError, one_line
from .formats import NAME_MAX, short

__all__ = ["atomic_path", "before_rename", "check_output_paths", "remove_stale_parts", "stop_writes", "PART"]

#: A temporary file of :func:`atomic_path`: ``.NAME.PID-XXXXXXXX.part``.
PART = re.compile(r"^\..*\.(\d+)-[a-z0-9_]{8}\.part$")
_SUFFIX_BYTES = len(".part") + 1 + 8
#: Set when the process is stopping: no new temporary file is made.
_STOPPING = threading.Event()


def stop_writes() -> None:
    """Make every later :func:`atomic_path` in this process fail at once (the process is stopping)."""
    _STOPPING.set()


def _prefix(name: str) -> str:
    """``.NAME.PID-``, ``NAME`` cut (at a character boundary) so that the whole temporary name fits."""
    pid = f".{os.getpid()}-"
    room = NAME_MAX - 1 - len(pid) - _SUFFIX_BYTES
    cut = os.fsencode(name)[:room].decode("utf-8", "ignore") if len(os.fsencode(name)) > room else name
    return f".{cut}{pid}"


@contextlib.contextmanager
def atomic_path(path):
    """Yield a temporary path beside ``path``; rename it to ``path`` on success.

    On any exception the temporary file is removed and ``path`` is untouched.

    Raises
    ------
    OutputError
        The folder cannot be made, or writing failed (no permission, full
        disk, a folder in the way); names ``path`` and the reason.
    """
    path = Path(path)
    if _STOPPING.is_set():
        raise OutputError(f"{short(path)}: not written: the run is stopping")
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=_prefix(path.name), suffix=".part", dir=path.parent)
    except OSError as exc:
        raise _cannot_write(path, exc) from None
    os.close(fd)
    try:
        yield Path(tmp)
        os.chmod(tmp, 0o666 & ~_umask())  # mkstemp creates 0600; match an ordinary write
        _record(tmp, path)
        os.replace(tmp, path)
    except BaseException as exc:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)
        if isinstance(exc, OSError):
            raise _cannot_write(path, exc) from None
        raise


#: What this thread calls with ``(tmp, path)`` just before each rename of :func:`atomic_path`.
_BEFORE_RENAME = threading.local()


@contextlib.contextmanager
def before_rename(hook):
    """Call ``hook(tmp, path)`` in this thread before each rename of :func:`atomic_path`, once the
    temporary file is complete (``None``: nothing); the manifest records writes this way
    (:func:`hht3d.io.manifest.recording`)."""
    previous, _BEFORE_RENAME.hook = getattr(_BEFORE_RENAME, "hook", None), hook
    try:
        yield
    finally:
        _BEFORE_RENAME.hook = previous


def _record(tmp, path) -> None:
    hook = getattr(_BEFORE_RENAME, "hook", None)
    if hook is not None:
        hook(tmp, path)


def _alive(pid: int) -> bool:
    """Whether process ``pid`` exists (``psutil``: on Windows ``os.kill(pid, 0)`` would end it)."""
    return psutil.pid_exists(pid)


def remove_stale_parts(folders, own=()) -> list[Path]:
    """Remove the temporary files of :func:`atomic_path` in ``folders`` (not below) whose writing
    process has ended, or is one of ``own`` (pids of this run stopping); return what was removed."""
    removed = []
    for folder in {Path(f) for f in folders}:
        try:
            names = [entry.name for entry in os.scandir(folder) if entry.is_file(follow_symlinks=False)]
        except OSError:  # not made yet, or not a folder
            continue
        for name in names:
            match = PART.match(name)
            if match and (int(match.group(1)) in own or not _alive(int(match.group(1)))):
                with contextlib.suppress(OSError):
                    os.unlink(folder / name)
                    removed.append(folder / name)
    return removed


def _cannot_write(path: Path, exc: OSError) -> OutputError:
    return OutputError(f"{short(path)}: cannot write ({exc.strerror or one_line(exc)}); free space, fix the "
                       "permissions or choose another output folder")


def check_output_paths(paths) -> None:
    """Check, creating nothing, that files can be written at ``paths`` (their folders may not exist yet).

    For each path: it must not be a folder; the nearest existing folder
    above it must be a folder (not a file such as ``/dev/full``) in which a
    probe (a temporary folder, made and removed at once) succeeds, which
    catches read-only and pseudo file systems (``/proc``) and missing
    permissions before anything is computed.

    Raises
    ------
    OutputError
        Naming the path, the folder at fault and the reason.
    """
    probed: set[Path] = set()
    for path in map(Path, paths):
        try:
            _check_output_path(path, probed)
        except OSError as exc:
            raise OutputError(f"{short(path)}: cannot write ({exc.strerror or one_line(exc)}); choose another "
                              "output path") from None


def _check_output_path(path: Path, probed: set) -> None:
    """:func:`check_output_paths` of one path; ``probed`` holds the folders already found writable."""
    if path.is_dir():
        raise OutputError(f"{short(path)}: cannot write: a folder of that name is in the way; remove it or change "
                          "the output path")
    existing = path.parent
    while not os.path.lexists(existing) and existing != existing.parent:
        existing = existing.parent
    if existing in probed:
        return
    if not existing.is_dir():
        raise OutputError(f"{short(path)}: cannot write: {existing} is not a folder; choose another output folder")
    try:
        os.rmdir(tempfile.mkdtemp(prefix=".hht3d-probe-", dir=existing))
    except OSError as exc:
        raise OutputError(f"{short(path)}: cannot write: creating anything in {existing} fails "
                          f"({exc.strerror or one_line(exc)}); choose another output folder") from None
    probed.add(existing)


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask
