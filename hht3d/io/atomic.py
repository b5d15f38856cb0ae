"""Atomic writes, the temporary files they leave behind, and checking output locations before a run.

A file is written as ``.NAME.PID-XXXXXXXX.part`` beside its target and renamed
over it only once complete (``NAME`` is cut so that the temporary name fits
in 255 bytes; ``PID`` is the writing process).  A run that is killed leaves
such files; :func:`remove_stale_parts` removes those of processes that no
longer run, and those of the current process and its workers at a stop.

The temporary file is made with ``O_EXCL``/``O_NOFOLLOW`` in the folder
opened once (``dir_fd`` where the platform has it, so that the rename goes
into that folder); just before the rename, the temporary file must still
resolve into that folder, and a writer confined to an output folder
(:func:`hht3d.io.manifest.recording`) checks it is still inside it
(:func:`check_inside`): a subfolder swapped for a symlink after the checks
is refused, not followed.
"""

from __future__ import annotations

import contextlib
import os
import re
import tempfile
import threading
import uuid
from collections.abc import Callable, Collection, Iterable, Iterator
from pathlib import Path

import psutil

from ..errors import OutputError, one_line
from .formats import NAME_MAX, short

__all__ = [
    "atomic_path",
    "before_rename",
    "check_inside",
    "check_output_paths",
    "confined",
    "remove_stale_parts",
    "stop_writes",
    "wait_for_writes",
    "writes_end_with",
    "PART",
]

#: A temporary file of :func:`atomic_path`: ``.NAME.PID-XXXXXXXX.part``.
PART = re.compile(r"^\..*\.(\d+)-[a-z0-9_]{8}\.part$")
_SUFFIX_BYTES = len(".part") + 1 + 8
#: Set when the process is stopping: no new temporary file is made, none is renamed.
_STOPPING = threading.Event()
#: The number of :func:`atomic_path` blocks open in this process (other threads may be writing at a stop).
_OPEN = 0
_OPEN_CHANGED = threading.Condition()
_NOFOLLOW = getattr(os, "O_NOFOLLOW", 0)
#: Whether files can be made and renamed relative to an open folder (POSIX; not Windows).
_DIR_FD = {os.open, os.rename, os.unlink} <= os.supports_dir_fd  # os.replace takes dir_fd where os.rename does
#: In a worker process, the run's process whose end stops every write (:func:`writes_end_with`).
_PARENT: int | None = None


def stop_writes() -> None:
    """Make every later :func:`atomic_path` in this process fail at once, and every open one remove its
    temporary file instead of renaming it (the process is stopping)."""
    _STOPPING.set()


def writes_end_with(parent: int) -> None:
    """In a worker process: make every later :func:`atomic_path` fail, and every open one remove its
    temporary file, once process ``parent`` (the run's) has ended, so that nothing the worker
    finishes afterwards is renamed into place or recorded as done in a manifest
    (:func:`hht3d.execution.workers.end_with_parent` ends the worker itself)."""
    global _PARENT
    _PARENT = parent


def _refusal(path: Path) -> OutputError | None:
    """Why ``path`` may not be written now: the run is stopping, or this worker's run has ended."""
    if _STOPPING.is_set():
        return OutputError(f"{short(path)}: not written: the run is stopping")
    if _PARENT is not None and (os.getppid() != _PARENT or not _alive(_PARENT)):
        return OutputError(f"{short(path)}: not written: the run's process {_PARENT} has ended")
    return None


def wait_for_writes(timeout: float) -> bool:
    """Wait up to ``timeout`` seconds for the :func:`atomic_path` blocks open in other threads to end
    (after :func:`stop_writes` each removes its temporary file); whether none is left open."""
    with _OPEN_CHANGED:
        return _OPEN_CHANGED.wait_for(lambda: _OPEN == 0, timeout)


def _opened(change: int) -> None:
    global _OPEN
    with _OPEN_CHANGED:
        _OPEN += change
        _OPEN_CHANGED.notify_all()


def _prefix(name: str) -> str:
    """``.NAME.PID-``, ``NAME`` cut (at a character boundary) so that the whole temporary name fits."""
    pid = f".{os.getpid()}-"
    room = NAME_MAX - 1 - len(pid) - _SUFFIX_BYTES
    cut = os.fsencode(name)[:room].decode("utf-8", "ignore") if len(os.fsencode(name)) > room else name
    return f".{cut}{pid}"


@contextlib.contextmanager
def atomic_path(path: Path | str) -> Iterator[Path]:
    """Yield a temporary path beside ``path``; rename it to ``path`` on success.

    On any exception the temporary file is removed and ``path`` is untouched.

    Parameters
    ----------
    path : Path or str
        The file to write.

    Yields
    ------
    Path
        The temporary path to write to, in the ``with`` block.

    Raises
    ------
    OutputError
        The folder cannot be made, or writing failed (no permission, full
        disk, a folder in the way), or the folder was swapped since the
        temporary file was made there, or the run is stopping or has ended
        (:func:`stop_writes`, :func:`writes_end_with`); names ``path`` and the reason.

    Examples
    --------
    >>> import tempfile
    >>> from pathlib import Path
    >>> from hht3d.io import atomic_path
    >>> path = Path(tempfile.mkdtemp()) / "out" / "table.csv"
    >>> with atomic_path(path) as tmp:
    ...     _ = tmp.write_text("a,b")
    >>> path.read_text(), sorted(p.name for p in path.parent.iterdir())
    ('a,b', ['table.csv'])
    """
    path = Path(path)
    if (refusal := _refusal(path)) is not None:
        raise refusal
    folder = None
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        folder = os.open(path.parent, os.O_RDONLY | getattr(os, "O_DIRECTORY", 0)) if _DIR_FD else None
        made_in = os.fstat(folder) if folder is not None else os.stat(path.parent)
        name = _create(path, folder)
    except OSError as exc:
        if folder is not None:
            os.close(folder)
        raise _cannot_write(path, exc) from None
    tmp = path.parent / name
    _opened(+1)
    try:
        yield tmp
        if (refusal := _refusal(path)) is not None:  # a stop began, or the run ended, while this thread wrote
            raise refusal
        if not os.path.samestat(os.stat(tmp.parent), made_in):
            raise OutputError(
                f"{short(path)}: not written: its folder {short(path.parent)} was replaced while the "
                "file was written (by a link?); nothing was renamed: check the output folder"
            )
        _record(tmp, path)
        _at(os.replace, folder, name, path.name, tmp, path)
    except BaseException as exc:
        for remove in ((lambda: _at(os.unlink, folder, name, None, tmp, None)), (lambda: os.unlink(tmp))):
            with contextlib.suppress(OSError):  # the second: the writer followed a swapped folder
                remove()
        if isinstance(exc, OSError):
            raise _cannot_write(path, exc) from None
        raise
    finally:
        _opened(-1)
        if folder is not None:
            os.close(folder)


def _create(path: Path, folder: int | None) -> str:
    """Make a new empty temporary file for ``path`` (``O_EXCL``, no link followed) and return its name."""
    flags = os.O_WRONLY | os.O_CREAT | os.O_EXCL | _NOFOLLOW | getattr(os, "O_CLOEXEC", 0)
    for _ in range(100):
        name = f"{_prefix(path.name)}{uuid.uuid4().hex[:8]}.part"
        try:
            fd = (
                os.open(name, flags, 0o666, dir_fd=folder)
                if folder is not None
                else os.open(path.parent / name, flags, 0o666)
            )
        except FileExistsError:
            continue
        os.close(fd)
        return name
    raise FileExistsError(f"no free temporary name beside {path.name}")


def _at(
    operation: Callable[..., None], folder: int | None, name: str, target: str | None, tmp: Path, path: Path | None
) -> None:
    """``operation`` (os.replace or os.unlink) on the temporary file, relative to the open ``folder`` if any."""
    if folder is None:
        operation(tmp, *([path] if path is not None else []))
    elif target is None:
        operation(name, dir_fd=folder)
    else:
        operation(name, target, src_dir_fd=folder, dst_dir_fd=folder)


def confined(path: Path | str, folder: Path | str) -> Path | None:
    """``path`` resolved (symlinks followed) if it lies inside ``folder`` resolved, else ``None``.

    Parameters
    ----------
    path : Path or str
        The path to check.
    folder : Path or str
        The folder it should lie in.

    Returns
    -------
    Path or None
        The resolved path, or ``None`` outside ``folder``.

    Examples
    --------
    >>> from hht3d.io import confined
    >>> confined("out/../elsewhere/x.ply", "out") is None
    True
    >>> confined("out/sub/x.ply", "out").name
    'x.ply'
    """
    resolved, root = Path(os.path.realpath(path)), Path(os.path.realpath(folder))
    return resolved if resolved == root or root in resolved.parents else None


def check_inside(tmp: Path, path: Path | str, folder: Path | str) -> None:
    """Refuse, just before its rename, a temporary file of ``path`` that no longer lies inside ``folder``
    (a subfolder swapped for a link after the output locations were checked).

    Raises
    ------
    OutputError
    """
    if confined(tmp, folder) is None:
        raise OutputError(
            f"{short(path)}: not written: its folder now resolves to "
            f"{short(os.path.realpath(Path(tmp).parent))}, outside the output folder {short(folder)} "
            "(swapped for a link after the check?); nothing outside was replaced"
        )


#: What this thread calls with ``(tmp, path)`` just before each rename of :func:`atomic_path`.
_BEFORE_RENAME = threading.local()


@contextlib.contextmanager
def before_rename(hook: Callable[[Path, Path | str], None] | None) -> Iterator[None]:
    """Call ``hook(tmp, path)`` in this thread before each rename of :func:`atomic_path`, once the
    temporary file is complete (``None``: nothing); the manifest records writes this way
    (:func:`hht3d.io.manifest.recording`)."""
    previous, _BEFORE_RENAME.hook = getattr(_BEFORE_RENAME, "hook", None), hook
    try:
        yield
    finally:
        _BEFORE_RENAME.hook = previous


def _record(tmp: Path, path: Path | str) -> None:
    hook = getattr(_BEFORE_RENAME, "hook", None)
    if hook is not None:
        hook(tmp, path)


def _alive(pid: int) -> bool:
    """Whether process ``pid`` exists (``psutil``: on Windows ``os.kill(pid, 0)`` would end it)."""
    return psutil.pid_exists(pid)


def remove_stale_parts(folders: Iterable[Path | str], own: Collection[int] = ()) -> list[Path]:
    """Remove the temporary files of :func:`atomic_path` in ``folders`` (not below) whose writing
    process has ended, or is one of ``own`` (pids of this run stopping); return what was removed.

    Parameters
    ----------
    folders : iterable of Path or str
        The folders to clean (missing ones are skipped).
    own : collection of int, optional
        Process ids whose parts are removed even while they run (default none).

    Returns
    -------
    list of Path
        The files removed.

    Examples
    --------
    >>> import tempfile
    >>> from hht3d.io import remove_stale_parts
    >>> remove_stale_parts([tempfile.mkdtemp(), "no/such/folder"])  # nothing left behind
    []
    """
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
    return OutputError(
        f"{short(path)}: cannot write ({exc.strerror or one_line(exc)}); free space, fix the "
        "permissions or choose another output folder"
    )


def check_output_paths(paths: Iterable[Path | str]) -> None:
    """Check, creating nothing, that files can be written at ``paths`` (their folders may not exist yet).

    For each path: it must not be a folder; the nearest existing folder
    above it must be a folder (not a file such as ``/dev/full``) in which a
    probe (a temporary folder, made and removed at once) succeeds, which
    catches read-only and pseudo file systems (``/proc``) and missing
    permissions before anything is computed.

    Parameters
    ----------
    paths : iterable of Path or str
        The files to be written.

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
            raise OutputError(
                f"{short(path)}: cannot write ({exc.strerror or one_line(exc)}); choose another output path"
            ) from None


def _check_output_path(path: Path, probed: set) -> None:
    """:func:`check_output_paths` of one path; ``probed`` holds the folders already found writable."""
    if path.is_dir():
        raise OutputError(
            f"{short(path)}: cannot write: a folder of that name is in the way; remove it or change the output path"
        )
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
        raise OutputError(
            f"{short(path)}: cannot write: creating anything in {existing} fails "
            f"({exc.strerror or one_line(exc)}); choose another output folder"
        ) from None
    probed.add(existing)
