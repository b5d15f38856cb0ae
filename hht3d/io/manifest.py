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
replaced by the next record.  Records are made under the folder's lock
(:mod:`hht3d.io.lock`).
"""

from __future__ import annotations

import hashlib
import json
import os
import posixpath
import re
import stat
import time
import uuid
from collections.abc import Callable, Iterable, Sequence
from pathlib import Path
from typing import Any, BinaryIO

from ..errors import OutputError
from .atomic import atomic_path, before_rename, check_inside, confined
from .lock import folder_lock

__all__ = [
    "MANIFEST",
    "new_run_id",
    "valid_entries",
    "entries",
    "digest",
    "is_recorded",
    "record",
    "updated",
    "Recorded",
    "recording",
    "recorded_names",
    "check_overwrites",
]

MANIFEST = ".hht3d-manifest.json"
_SHA256 = re.compile(r"[0-9a-f]{64}")


def new_run_id() -> str:
    """A run id: UTC time and a random suffix.

    Returns
    -------
    str
        ``YYYYmmddTHHMMSSZ-xxxxxxxx``.

    Examples
    --------
    >>> from hht3d.io import new_run_id
    >>> run = new_run_id()
    >>> len(run), run[8], run[15:17]
    (25, 'T', 'Z-')
    """
    return f"{time.strftime('%Y%m%dT%H%M%SZ', time.gmtime())}-{uuid.uuid4().hex[:8]}"


def _key(path: Path | str, folder: Path | str) -> str | None:
    """``path`` relative to ``folder`` after links (POSIX separators), or ``None`` if it lies outside."""
    real = confined(path, folder)
    return None if real is None else Path(os.path.relpath(real, os.path.realpath(folder))).as_posix()


def _entry_key(key: object) -> str | None:
    """A manifest key normalised lexically, or ``None`` if it is not a relative path staying in its folder."""
    if not isinstance(key, str) or not key or "\0" in key or "\\" in key or key.startswith("/") or ":" in key[:2]:
        return None
    norm = posixpath.normpath(key)
    return None if norm in (".", "..") or norm.startswith("../") else norm


def _well_formed(entry: Any) -> bool:
    return (
        isinstance(entry, dict)
        and type(entry.get("size")) is int
        and entry["size"] > 0
        and isinstance(entry.get("sha256"), str)
        and _SHA256.fullmatch(entry["sha256"]) is not None
    )


def valid_entries(data: Any, inside: Callable[[str], bool] = lambda key: True) -> dict:
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


def entries(folder: Path | str) -> dict:
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


def digest(handle: BinaryIO) -> tuple[int, str]:
    """Size and SHA-256 of what an open binary file holds, read to its end."""
    sha = hashlib.sha256()
    size = 0
    while block := handle.read(1 << 20):
        sha.update(block)
        size += len(block)
    return size, sha.hexdigest()


def _digest(path: Path | str) -> tuple[int, str]:
    with open(path, "rb") as handle:
        return digest(handle)


def is_recorded(path: Path | str, folder: Path | str, known: dict | None = None) -> bool:
    """Whether ``path`` is a complete file that hht3d wrote: recorded inside ``folder``, same size and checksum.

    Parameters
    ----------
    path : Path or str
        The file to look up.
    folder : Path or str
        The folder whose manifest is read.
    known : dict, optional
        The manifest's entries, already read (default: read them).

    Returns
    -------
    bool
        Whether the file is as recorded.

    Examples
    --------
    >>> import tempfile
    >>> from pathlib import Path
    >>> from hht3d.io import is_recorded, new_run_id, record
    >>> folder = Path(tempfile.mkdtemp())
    >>> (folder / "x.npz").write_bytes(b"result")
    6
    >>> record([folder / "x.npz"], folder, new_run_id())
    >>> (folder / "x.npz").write_bytes(b"edited")  # changed since: no longer as recorded
    6
    >>> is_recorded(folder / "x.npz", folder)
    False
    """
    entry = (entries(folder) if known is None else known).get(_key(path, folder))
    try:
        if not entry or os.path.getsize(path) != entry["size"]:
            return False
        return _digest(path) == (entry["size"], entry["sha256"])
    except OSError:
        return False


def record(
    paths: Iterable[Path | str], folder: Path | str, run: str, *, named: Sequence[Path | str] | None = None
) -> None:
    """Add complete files to the manifest of ``folder`` (under its lock; the manifest is written atomically).

    ``named`` gives the names to record them under (default ``paths``): a
    temporary file is recorded under its final name just before it is
    renamed.  A file outside ``folder`` (``allow_outside``) is not recorded.
    Invalid entries of the manifest (:func:`valid_entries`) are dropped.

    Parameters
    ----------
    paths : iterable of Path or str
        The complete files to record.
    folder : Path or str
        The folder whose manifest records them.
    run : str
        The run id they are recorded under.
    named : sequence of Path or str, optional
        The names to record them under, one per path (default ``paths``).

    Examples
    --------
    >>> import tempfile
    >>> from pathlib import Path
    >>> from hht3d.io import is_recorded, new_run_id, record
    >>> folder = Path(tempfile.mkdtemp())
    >>> (folder / "x.npz").write_bytes(b"result")
    6
    >>> record([folder / "x.npz"], folder, new_run_id())
    >>> is_recorded(folder / "x.npz", folder)
    True
    """
    found = {_key(n, folder): _digest(p) for p, n in zip(paths, named or paths)}
    found.pop(None, None)
    with before_rename(None), folder_lock(folder, run):  # the manifest itself is not recorded
        with atomic_path(Path(folder) / MANIFEST) as tmp:
            tmp.write_text(updated(entries(folder), found, run), encoding="utf-8")


def updated(files: dict, found: dict, run: str) -> str:
    """The text of a manifest of ``files`` and, written now by the run ``run``, ``found`` (key: (size, SHA-256))."""
    stamp = time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())
    files = {
        **files,
        **{key: {"size": size, "sha256": sha, "run": run, "written": stamp} for key, (size, sha) in found.items()},
    }
    return json.dumps({"version": 1, "files": files}, indent=1)


def recording(folder: Path | str, run: str, *, confine: bool = True) -> Any:
    """Record the atomic writes of this thread in the manifest of ``folder`` (see :class:`Recorded`); with
    ``confine``, refuse at its rename a file that no longer resolves inside ``folder``
    (:func:`hht3d.io.atomic.check_inside`)."""

    def hook(tmp: Path, path: Path | str) -> None:
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

    def __init__(self, write: Callable[..., Any], folder: Path | str, run: str, *, allow_outside: bool = False):
        self.write, self.folder, self.run, self.allow_outside = write, str(folder), run, allow_outside
        self.__name__ = getattr(write, "__name__", "write")
        self.__module__, self.__qualname__ = write.__module__, write.__qualname__

    def __dask_tokenize__(self) -> tuple:
        return (self.write.__module__, self.write.__qualname__, self.folder, self.run, self.allow_outside)

    def __call__(self, *args: Any, **kwargs: Any) -> Any:
        with recording(self.folder, self.run, confine=not self.allow_outside):
            return self.write(*args, **kwargs)


def recorded_names(folder: Path | str) -> set[str]:
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


def check_overwrites(paths: Iterable[Path | str], folder: Path | str, overwrite: bool) -> None:
    """Refuse to replace an existing file that hht3d did not write (unless ``overwrite``).

    Parameters
    ----------
    paths : iterable of Path or str
        The files to be written.
    folder : Path or str
        The output folder, whose manifest records what hht3d wrote.
    overwrite : bool
        Replace any existing file (the check is skipped).

    Raises
    ------
    OutputError
        Naming the first such file.

    Examples
    --------
    >>> import tempfile
    >>> from pathlib import Path
    >>> from hht3d.io import check_overwrites
    >>> folder = Path(tempfile.mkdtemp())
    >>> (folder / "notes.txt").write_text("mine")
    4
    >>> check_overwrites([folder / "notes.txt"], folder, overwrite=True)  # allowed
    >>> check_overwrites([folder / "notes.txt"], folder, overwrite=False)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    hht3d.errors.OutputError: .../notes.txt: exists and hht3d did not write it ...
    """
    if overwrite:
        return
    known = entries(folder)
    for path in paths:  # by its real path too: "sub/../x" exists even where "sub" does not
        if (os.path.lexists(path) or os.path.lexists(os.path.realpath(path))) and not is_recorded(path, folder, known):
            raise OutputError(
                f"{path}: exists and hht3d did not write it (or it changed since: not as recorded "
                f"in {Path(folder) / MANIFEST}); it is kept: move it away, change the output path, "
                "or pass --overwrite"
            )
