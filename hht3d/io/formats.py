"""Which files can be read (extensions, the regular-file check done before opening one), and the
length limits of file names."""

from __future__ import annotations

import os
import re
import stat
from pathlib import Path

from ..errors import MAX_SHOWN, InputError, one_line
from ..errors import shown as shown_value

__all__ = [
    "MESH_EXTENSIONS",
    "MESHIO_EXTENSIONS",
    "POINT_CLOUD_EXTENSIONS",
    "PLY_RESERVED",
    "check_extension",
    "check_regular_file",
    "checked_name",
    "usable_name",
    "NAME_MAX",
    "PATH_MAX",
    "short",
]

#: Suffixes read through meshio (:mod:`hht3d.io.mesh_files`), of its formats that need no other package.
MESHIO_EXTENSIONS = (".vtu", ".vtk", ".msh", ".mesh", ".inp", ".bdf", ".nas", ".su2", ".avs", ".ugrid", ".mdpa")
MESH_EXTENSIONS = (".ply", ".obj", ".off", ".stl", ".glb", ".gltf", *MESHIO_EXTENSIONS)
POINT_CLOUD_EXTENSIONS = (".ply", ".pcd", ".xyz", ".xyzn", ".pts", ".las", ".laz", ".e57")
#: PLY vertex properties with a fixed meaning (position, normal, colour).
PLY_RESERVED = {"x", "y", "z", "nx", "ny", "nz", "red", "green", "blue", "alpha"}
#: Attribute names hht3d writes as PLY properties.
_NAME = re.compile(r"^[A-Za-z_][A-Za-z0-9_.\-]*$")

#: The longest file name (one path component) and whole path, in bytes, on Linux file systems.
NAME_MAX = 255
PATH_MAX = 4096


def short(path: Path | str) -> str:
    """A path for a message, cut if absurdly long."""
    return one_line(path, MAX_SHOWN)


_KINDS = {
    stat.S_IFIFO: "a FIFO (named pipe)",
    stat.S_IFCHR: "a character device",
    stat.S_IFBLK: "a block device",
    stat.S_IFSOCK: "a socket",
    stat.S_IFDIR: "a folder",
}


def check_extension(path: Path) -> None:
    """Raise :class:`InputError` unless ``path`` has a mesh or point-cloud extension."""
    if path.suffix.lower() not in MESH_EXTENSIONS + POINT_CLOUD_EXTENSIONS:
        raise InputError(
            f"{path}: unknown extension {path.suffix.lower() or '(none)'!r}; meshes: "
            f"{', '.join(MESH_EXTENSIONS)}; point clouds: {', '.join(POINT_CLOUD_EXTENSIONS)}"
        )


def check_regular_file(path: Path, what: str = "a mesh or point-cloud file") -> None:
    """Raise :class:`InputError` unless ``path`` is (or links to) a regular file: missing, a folder,
    a FIFO, a device (``/dev/urandom``) or a socket are each named as such.

    Parameters
    ----------
    path : Path
        The file to check.
    what : str, optional
        What the error says the file should be (default ``"a mesh or point-cloud file"``).

    Examples
    --------
    >>> import tempfile
    >>> from pathlib import Path
    >>> from hht3d.io import check_regular_file
    >>> check_regular_file(Path(tempfile.mkdtemp()))  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    hht3d.errors.InputError: ...: is a folder, not a mesh or point-cloud file; give one file (...)
    """
    shown = one_line(path, MAX_SHOWN)
    try:
        mode = os.stat(path).st_mode
    except FileNotFoundError:
        dangling = os.path.islink(path)
        raise InputError(
            f"{shown}: {'a symbolic link to a missing file' if dangling else 'no such file'}; check the path"
        ) from None
    except OSError as exc:
        raise InputError(f"{shown}: cannot read ({exc.strerror or one_line(exc)})") from None
    except ValueError:  # an embedded NUL, which no file system takes
        raise InputError(
            f"{shown_value(os.fspath(path))}: the path holds a NUL character; give the file's real name"
        ) from None
    if stat.S_ISDIR(mode):
        raise InputError(f"{shown}: is a folder, not {what}; give one file (pipeline inputs take folders)")
    if not stat.S_ISREG(mode):
        kind = _KINDS.get(stat.S_IFMT(mode), "not a regular file")
        raise InputError(f"{shown}: is {kind}, not a regular file; give {what}")


def checked_name(key: object) -> str:
    """``key`` if it is usable as a written PLY property, else an :class:`InputError`."""
    if not _NAME.match(str(key)) or key in PLY_RESERVED:
        raise InputError(
            f"attribute name {key!r} is not usable as a PLY property "
            "(letters, digits, '_', '.', '-'; not x/y/z/nx/ny/nz/red/green/blue/alpha)"
        )
    return str(key)


def usable_name(key: str) -> str:
    """A property name read from a file made writable: other characters become ``_``, and a name
    not starting with a letter or ``_`` gets a leading ``_`` (PLY allows ``0bad``; hht3d writes ``_0bad``)."""
    name = re.sub(r"[^A-Za-z0-9_.\-]", "_", key)
    return name if _NAME.match(name) else f"_{name}"
