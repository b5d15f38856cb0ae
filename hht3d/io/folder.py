"""An output folder of a run: the one place where a local folder and an fsspec URL differ.

* **A local folder** gets every safety rule: outputs confined to it (checked
  by :func:`check_locations`), no file that hht3d did not write replaced
  unless ``overwrite`` (:func:`hht3d.io.manifest.check_overwrites`), stale
  temporary files of killed runs removed, every complete write recorded in
  ``.hht3d-manifest.json`` with its size and checksum under the run id
  (:class:`hht3d.io.manifest.Recorded`), and ``resume`` trusting only what
  the manifest records.
* **A URL folder** (``s3://bucket/out``, :mod:`hht3d.io.storage`) has no
  manifest and no lock: a probe object checks that it can be written, each
  file is written locally by the worker and uploaded atomically, and
  ``resume`` skips an input whose outputs all exist.
"""
from __future__ import annotations

import os
from pathlib import Path

from ..errors import OutputError
from . import storage
from .atomic import check_output_paths, remove_stale_parts
from .manifest import Recorded, check_overwrites, entries, is_recorded, new_run_id
from .paths import check_name, check_output_location

__all__ = ["OutputFolder", "Uploaded", "check_locations"]


class Uploaded:
    """A writer whose last positional argument is a URL: written locally, then uploaded
    (:func:`hht3d.io.storage.write_via`; a picklable task function)."""

    def __init__(self, write, storage_options: dict | None):
        self.write, self.storage_options = write, storage_options or None
        self.__name__ = getattr(write, "__name__", "write")
        self.__module__, self.__qualname__ = write.__module__, write.__qualname__

    def __dask_tokenize__(self):
        return (self.write.__module__, self.write.__qualname__, repr(sorted((self.storage_options or {}).items())))

    def __call__(self, *args, **kwargs):
        return storage.write_via(self.write, *args, storage_options=self.storage_options, **kwargs)


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

    def __init__(self, location, *, storage_options: dict | None = None, run: str | None = None,
                 allow_outside: bool = False):
        self.location, self.storage_options = storage.local_path(location), storage_options or None
        self.is_url, self.allow_outside = storage.is_url(self.location), allow_outside
        self.run = run or new_run_id()
        self._known: dict | None = None

    def prepare(self, paths, *, overwrite: bool = False) -> None:
        """Before a run: the outputs can be written; locally, none replaces a file hht3d did not write
        (unless ``overwrite``) and temporary files that killed runs left in their folders are removed.

        Raises
        ------
        OutputError
        """
        paths = list(paths)
        if self.is_url:
            storage.check_outputs(paths, self.storage_options)
            return
        check_output_paths(paths)
        self.check_overwrites(paths, overwrite=overwrite)
        remove_stale_parts(self.part_folders(paths))

    def finish(self, paths) -> None:
        """After a run: remove the temporary files that workers killed mid-write left (a nanny
        restarts such a worker and its task runs again elsewhere); a URL folder has none here."""
        remove_stale_parts(self.part_folders(paths))

    def check_overwrites(self, paths, *, overwrite: bool = False) -> None:
        """Locally, refuse to replace a file hht3d did not write (:func:`hht3d.io.manifest.check_overwrites`);
        a URL folder keeps no manifest and checks nothing here.

        Raises
        ------
        OutputError
        """
        if not self.is_url:
            check_overwrites(paths, self.location, overwrite)

    def part_folders(self, paths) -> set:
        """The local folders where writes of ``paths`` leave temporary files (none for a URL folder,
        whose temporary files are in the system's temporary folder)."""
        return set() if self.is_url else {Path(self.location), *(Path(p).parent for p in paths)}

    def done(self, paths) -> bool:
        """Whether an input with these outputs is finished (``resume``): locally, every output is
        recorded complete in the manifest (same size and checksum); for a URL, every output exists."""
        if self.is_url:
            return all(storage.exists(p, self.storage_options) for p in paths)
        if self._known is None:
            self._known = entries(self.location)
        return all(is_recorded(p, self.location, self._known) for p in paths)

    def writer(self, write):
        """``write`` as a task function writing into this folder: recorded locally, uploaded to a URL."""
        if self.is_url:
            return Uploaded(write, self.storage_options)
        return Recorded(write, self.location, self.run, allow_outside=self.allow_outside)


def check_locations(items: dict, folder, *, allow_outside: bool = False,
                    where=lambda source, path: str(path)) -> None:
    """Refuse, before anything is computed, outputs that no file system takes, that resolve outside a
    local ``folder`` (unless ``allow_outside``), or that are one of the inputs.

    ``items`` maps each input to its output paths; ``where(source, path)``
    names an output in messages.  A URL output's key is normalised
    (:func:`hht3d.io.storage.join`) and must stay under its folder's prefix.

    Raises
    ------
    OutputError
    """
    def real(location):
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
                raise OutputError(f"{where(source, path)}: {path} is the input {clash}; an input is never an "
                                  "output: change the output path or folder")


def _check_inside(path, folder, where: str) -> None:
    """Refuse an output outside ``folder``: locally after links, for a URL by its normalised key."""
    if not storage.is_url(path):
        check_output_location(path, folder, where)
    elif not storage.inside(path, folder):
        raise OutputError(f"{where}: {path} leaves the output folder {folder}; write inside it (or set "
                          "outputs.allow_outside: true)")
