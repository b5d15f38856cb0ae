"""An output folder of a run: the one place where a local folder and an fsspec URL differ.

* **A local folder** gets every safety rule: outputs confined to it (checked
  by :func:`check_locations`), no file that hht3d did not write replaced
  unless ``overwrite`` (:func:`hht3d.io.manifest.check_overwrites`), stale
  temporary files of killed runs removed, every complete write recorded in
  ``.hht3d-manifest.json`` with its size and checksum under the run id
  (:class:`hht3d.io.manifest.Recorded`), and ``resume`` trusting only what
  the manifest records.
* **A URL folder** (``s3://bucket/out``, :mod:`hht3d.io.storage`) gets the
  rules the store allows: output keys normalised and confined under the
  folder's prefix (:func:`check_locations`), a probe object checking before
  the run that it can be written, each file written locally by the worker
  and uploaded atomically, and a manifest object of the same shape written
  after the outputs (:meth:`OutputFolder.finish`), so that ``resume`` trusts
  only outputs of the recorded size and checksum.  A run holds the folder's
  lock object where the store writes conditionally (S3,
  :mod:`hht3d.io.url_lock`), and the manifest is updated conditionally
  (:func:`hht3d.io.uploads.update_object`); elsewhere the last writer wins.
  No rule keeps hht3d from replacing an object it did not write.
"""

from __future__ import annotations

import contextlib
import json
import os
from collections.abc import Callable, Iterable, Iterator
from pathlib import Path, PurePosixPath
from typing import Any, cast

from ..errors import OutputError
from . import storage, uploads
from .atomic import check_output_paths, remove_stale_parts
from .manifest import (
    MANIFEST,
    Recorded,
    check_overwrites,
    digest,
    entries,
    is_recorded,
    new_run_id,
    updated,
    valid_entries,
)
from .paths import check_name, check_output_location
from .sealed import Sealed, seal, unsealed
from .url_lock import url_lock

__all__ = ["OutputFolder", "Uploaded", "check_locations"]


class Uploaded:
    """A writer whose last positional argument is a URL: written locally, then uploaded
    (:func:`hht3d.io.uploads.write_via`; a picklable task function).  Its storage options are
    sealed (:mod:`hht3d.io.sealed`): the task carries their token, resolved where it runs."""

    def __init__(self, write: Callable[..., Any], storage_options: dict | Sealed | None):
        self.write, self.storage_options = write, seal(storage_options)
        self.__name__ = getattr(write, "__name__", "write")
        self.__module__, self.__qualname__ = write.__module__, write.__qualname__

    def __dask_tokenize__(self) -> tuple:
        return (self.write.__module__, self.write.__qualname__, self.storage_options)

    def __call__(self, *args: Any, **kwargs: Any) -> Any:
        return uploads.write_via(self.write, *args, storage_options=unsealed(self.storage_options), **kwargs)


class OutputFolder:
    """Where a run writes: a local folder or a URL, with the rules of each (see the module).

    Parameters
    ----------
    location : path or URL
    storage_options : dict, optional
        For a URL: options of its fsspec back-end.
    run : str, optional
        The run id recorded in a local folder's manifest (default: a new one).
    allow_outside : bool
        Outputs may lie outside a local folder (``outputs.allow_outside``); otherwise each write is
        checked again, just before its rename, to resolve inside it.
    """

    def __init__(
        self,
        location: Path | str,
        *,
        storage_options: dict | None = None,
        run: str | None = None,
        allow_outside: bool = False,
    ):
        self.location, self.storage_options = storage.local_path(location), storage_options or None
        self.is_url, self.allow_outside = storage.is_url(self.location), allow_outside
        self.run = run or new_run_id()
        self._known: dict | None = None

    @contextlib.contextmanager
    def lock(self) -> Iterator[None]:
        """Hold a URL folder's lock for a run (:func:`hht3d.io.url_lock.url_lock`); a local folder is
        locked by each write of its manifest and summary instead (:mod:`hht3d.io.lock`).

        Raises
        ------
        OutputError
            Another run held the lock for the whole timeout (names it).
        """
        if not self.is_url:
            yield
            return
        with url_lock(self._url, self.storage_options, self.run):
            yield

    def prepare(self, paths: Iterable[Path | str], *, overwrite: bool = False) -> None:
        """Before a run: the outputs can be written; locally, none replaces a file hht3d did not write
        (unless ``overwrite``) and temporary files that killed runs left in their folders are removed.

        Raises
        ------
        OutputError
        """
        paths = list(paths)
        if self.is_url:
            uploads.check_outputs(paths, self.storage_options)
            return
        check_output_paths(paths)
        self.check_overwrites(paths, overwrite=overwrite)
        remove_stale_parts(self.part_folders(paths))

    def finish(self, paths: Iterable[Path | str], written: Iterable[Path | str] = ()) -> None:
        """After a run: remove the temporary files that workers killed mid-write left (a nanny
        restarts such a worker and its task runs again elsewhere); a URL folder has none here, and
        records the ``written`` outputs in its manifest object (:meth:`record`)."""
        remove_stale_parts(self.part_folders(paths))
        if self.is_url:
            self.record(cast(Iterable[str], written))  # a URL folder's outputs are URLs

    def record(self, urls: Iterable[str]) -> None:
        """Add the objects ``urls`` of a URL folder, as they are now, to its manifest object (written last,
        merged with other runs' entries; :func:`hht3d.io.uploads.update_object`)."""
        found = {}
        for url in urls:
            key, sums = storage.under(url, self._url), _digest_of(url, self.storage_options)
            if key is not None and sums is not None:
                found[key] = sums
        if found:
            uploads.update_object(
                cast(str, storage.join(self._url, MANIFEST)),
                lambda old: updated(self._parsed(old), found, self.run).encode(),
                self.storage_options,
            )

    def recorded(self, url: str) -> bool:
        """Whether a URL folder's manifest object records ``url`` as it is now (same size and SHA-256)."""
        if self._known is None:
            fs, path = storage.filesystem(cast(str, storage.join(self._url, MANIFEST)), self.storage_options)
            try:
                fs.invalidate_cache()
                self._known = self._parsed(fs.cat_file(path))
            except Exception:  # the back-ends raise many types: no manifest counts as empty
                self._known = {}
        entry: Any = self._known.get(storage.under(url, self._url))
        return bool(entry) and _digest_of(url, self.storage_options, entry["size"]) == (entry["size"], entry["sha256"])

    @property
    def _url(self) -> str:
        """The location of a URL folder (for the type checker)."""
        return cast(str, self.location)

    @staticmethod
    def _parsed(data: bytes | None) -> dict:
        """The valid entries of a manifest's bytes (:func:`hht3d.io.manifest.valid_entries`)."""
        try:
            return valid_entries(json.loads(data)) if data else {}
        except ValueError:
            return {}

    def check_overwrites(self, paths: Iterable[Path | str], *, overwrite: bool = False) -> None:
        """Locally, refuse to replace a file hht3d did not write (:func:`hht3d.io.manifest.check_overwrites`);
        a URL folder checks nothing here (no rule protects an object hht3d did not write).

        Raises
        ------
        OutputError
        """
        if not self.is_url:
            check_overwrites(paths, self.location, overwrite)

    def part_folders(self, paths: Iterable[Path | str]) -> set:
        """The local folders where writes of ``paths`` leave temporary files (none for a URL folder,
        whose temporary files are in the system's temporary folder)."""
        return set() if self.is_url else {Path(self.location), *(Path(p).parent for p in paths)}

    def done(self, paths: Iterable[Path | str]) -> bool:
        """Whether an input with these outputs is finished (``resume``): locally, every output is
        recorded complete in the manifest (same size and checksum); for a URL, likewise in its manifest
        object (:meth:`recorded`)."""
        if self.is_url:
            return all(self.recorded(cast(str, p)) for p in paths)
        if self._known is None:
            self._known = entries(self.location)
        return all(is_recorded(p, self.location, self._known) for p in paths)

    def writer(self, write: Callable[..., Any]) -> Callable[..., Any]:
        """``write`` as a task function writing into this folder: recorded locally, uploaded to a URL."""
        if self.is_url:
            return Uploaded(write, self.storage_options)
        return Recorded(write, self.location, self.run, allow_outside=self.allow_outside)


def _digest_of(url: str, storage_options: dict | None, size: int | None = None) -> tuple[int, str] | None:
    """Size and SHA-256 of the object at ``url`` (read afresh; ``None`` if it is missing, unreadable or,
    when ``size`` is given, of another size, which is checked before anything is read)."""
    fs, path = storage.filesystem(url, storage_options)
    fs.invalidate_cache(str(PurePosixPath(path).parent))
    try:
        if size is not None and fs.info(path)["size"] != size:
            return None
        with fs.open(path, "rb") as handle:
            return digest(handle)
    except Exception:  # the back-ends raise many types: unreadable counts as absent, the item is redone
        return None


def check_locations(
    items: dict,
    folder: Path | str,
    *,
    allow_outside: bool = False,
    where: Callable[[Any, Any], str] = lambda source, path: str(path),
) -> None:
    """Refuse, before anything is computed, outputs that no file system takes, that resolve outside a
    local ``folder`` (unless ``allow_outside``), or that are one of the inputs.

    ``items`` maps each input to its output paths; ``where(source, path)``
    names an output in messages.  A URL output's key is normalised
    (:func:`hht3d.io.storage.join`) and must stay under its folder's prefix.

    Raises
    ------
    OutputError
    """

    def real(location: Path | str) -> str:
        return str(location) if storage.is_url(location) else os.path.realpath(location)

    folder = storage.local_path(folder)
    inputs = {real(source): source for source in items}
    for source, paths in items.items():
        for path in paths:
            check_name(path, where(source, path))
            if not allow_outside:
                _check_inside(path, folder, where(source, path))
            clash = inputs.get(real(path))
            if clash is not None:
                raise OutputError(
                    f"{where(source, path)}: {path} is the input {clash}; an input is never an "
                    "output: change the output path or folder"
                )


def _check_inside(path: Path | str, folder: Path | str, where: str) -> None:
    """Refuse an output outside ``folder``: locally after links, for a URL by its normalised key."""
    if not storage.is_url(path):
        check_output_location(path, folder, where)
    elif storage.under(path, cast(str, folder)) is None:  # a URL folder's outputs are URLs
        raise OutputError(
            f"{where}: {path} leaves the output folder {folder}; write inside it (or set outputs.allow_outside: true)"
        )
