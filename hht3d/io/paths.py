"""Where files may be read and written: output confinement, file-name checks, input expansion.

* :func:`confined` (from :mod:`hht3d.io.atomic`, which checks it again
  just before each rename) is the one test of "inside this folder", after
  symlinks; a URL-aware layer can call it with its own resolution.
* :func:`check_name` refuses, before anything is computed, a name the file
  system would refuse at the write: a control character (NUL included), a
  component over :data:`NAME_MAX` bytes, a path over :data:`PATH_MAX` bytes.
* :func:`resolve_inputs` expands files, folders and globs: an existing file
  is taken literally (``scan[1].ply``), a file reached twice through a
  symlink loop is listed once, and files that hht3d wrote (recorded in a
  manifest, :mod:`hht3d.io.manifest`) are never taken as inputs.
"""

from __future__ import annotations

import glob
import os
from collections.abc import Collection, Iterable
from pathlib import Path
from typing import Any

from ..errors import InputError, OutputError, one_line, shown
from .atomic import confined
from .formats import (
    MESH_EXTENSIONS,
    NAME_MAX,
    PATH_MAX,
    POINT_CLOUD_EXTENSIONS,
    check_extension,
    check_regular_file,
    short,
)
from .manifest import recorded_names

__all__ = ["NAME_MAX", "PATH_MAX", "confined", "check_output_location", "check_name", "resolve_inputs", "short"]


def check_output_location(path: Path | str, folder: Path | str, where: str) -> None:
    """Refuse an output that resolves outside ``folder`` (``where`` names the step or output).

    Parameters
    ----------
    path : Path or str
        The output path.
    folder : Path or str
        The output folder.
    where : str
        The step or output the error names.

    Raises
    ------
    OutputError
        Naming ``where``, the resolved path and the folder.

    Examples
    --------
    >>> from hht3d.io import check_output_location
    >>> check_output_location("out/x.ply", "out", "outputs.files")  # inside: nothing happens
    >>> check_output_location("../x.ply", "out", "outputs.files")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    hht3d.errors.OutputError: outputs.files: ../x.ply resolves to ..., outside the output folder out; ...
    """
    if confined(path, folder) is None:
        raise OutputError(
            f"{where}: {short(path)} resolves to {short(os.path.realpath(path))}, outside the "
            f"output folder {short(folder)}; write inside it (or set outputs.allow_outside: true)"
        )


def check_name(path: Path | str, where: str) -> None:
    """Refuse a path that no file system takes: control characters, a component or the whole too long.

    Parameters
    ----------
    path : Path or str
        The output path.
    where : str
        The step or output the error names.

    Raises
    ------
    OutputError

    Examples
    --------
    >>> from hht3d.io import check_name
    >>> check_name("out/x" + chr(9) + "y.ply", "outputs.files")  # a tab  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    hht3d.errors.OutputError: outputs.files: the file name ... holds a control character; use printable characters
    """
    text = os.fspath(path)
    if any(ord(ch) < 32 or ord(ch) == 127 for ch in text):
        raise OutputError(f"{where}: the file name {shown(text)} holds a control character; use printable characters")
    encoded = os.fsencode(text)
    if len(encoded) > PATH_MAX:
        raise OutputError(f"{where}: the path {short(text)} is {len(encoded)} bytes long; the limit is {PATH_MAX}")
    for part in Path(text).parts:
        size = len(os.fsencode(part))
        if size > NAME_MAX:
            raise OutputError(
                f"{where}: the file name {short(part)} is {size} bytes long; the limit is "
                f"{NAME_MAX}; shorten the path pattern or the name"
            )


def resolve_inputs(spec: Any) -> list[Path]:
    """Expand an input spec into files: a file, a folder (its mesh/point files),
    a glob pattern, or a list of these.  Order is sorted and duplicates dropped.

    Folders and globs yield only the files with a mesh or point-cloud
    extension, never one that a manifest in its folder records as written
    by hht3d; a file named explicitly must have a usable extension.  An
    existing file is taken as named even when its name holds ``*?[``; a
    file found again through a symlink loop is listed once (by its
    shortest path).

    Parameters
    ----------
    spec : str, Path or list
        A file, a folder, a glob pattern, or a list of these.

    Returns
    -------
    list of Path
        The input files, sorted, without duplicates.

    Raises
    ------
    InputError
        A named file is missing or has an unknown extension, or a folder/glob
        matches no usable file.

    Examples
    --------
    >>> from hht3d import data_path
    >>> from hht3d.io import resolve_inputs
    >>> [p.name for p in resolve_inputs(data_path("spot.ply").parent)]  # the mesh files of a folder
    ['sphere_oct4098.ply', 'spot.ply']
    """
    specs = [spec] if isinstance(spec, (str, Path)) else list(spec)
    found: list[Path] = []
    usable = set(MESH_EXTENSIONS + POINT_CLOUD_EXTENSIONS)
    for item in specs:
        text = str(item)
        try:
            matches = _input_files(text, usable)
        except OSError as exc:
            raise InputError(f"{short(text)}: cannot read ({exc.strerror or one_line(exc)})") from None
        if not matches:
            raise InputError(
                f"{text}: matches no mesh or point-cloud file ({', '.join(sorted(usable))}), or only files hht3d wrote"
            )
        found.extend(matches)
    return _once(found)


def _input_files(text: str, usable: Collection[str]) -> list[Path]:
    """The usable files of one input spec: the named file, a folder's, or a glob's."""
    path = Path(text)
    if path.is_dir():
        return _not_outputs(p for p in path.iterdir() if p.suffix.lower() in usable and p.is_file())
    if os.path.lexists(path):
        check_regular_file(path)
        check_extension(path)
        return [path]
    if any(ch in text for ch in "*?["):
        return _not_outputs(
            p for p in map(Path, glob.iglob(text, recursive=True)) if p.suffix.lower() in usable and p.is_file()
        )
    raise InputError(f"{text}: no such file or folder")


def _not_outputs(paths: Iterable[Path]) -> list[Path]:
    """``paths`` without those recorded by a manifest of their folder, sorted, each file once."""
    names: dict[Path, set] = {}
    kept = []
    for path in paths:
        folder = path.parent
        if folder not in names:
            names[folder] = recorded_names(folder)
        if path.name not in names[folder]:
            kept.append(path)
    return _once(sorted(kept))


def _once(paths: Iterable[Path]) -> list[Path]:
    """Each file once: of the paths reaching one real file, the shortest, in the first one's place."""
    chosen: dict[str, Path] = {}
    for path in paths:
        real = os.path.realpath(path)
        best = chosen.get(real)
        if best is None or len(path.parts) < len(best.parts):
            chosen[real] = path
    return list(chosen.values())
