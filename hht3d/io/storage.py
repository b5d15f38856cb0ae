"""Files where users keep them: fsspec URLs (``s3://``, ``gs://``, ``az://``, ``https://``, ``memory://``).

Every place hht3d reads or writes takes either a local path or a URL with
``storage_options`` (passed to :func:`fsspec.core.url_to_fs`; credentials come
from the back-end's usual places: environment, config files, instance roles).
This module holds the URL locations, back-ends, listing and reading; local
paths go to :mod:`hht3d.io.read` unchanged, and writing is
:mod:`hht3d.io.uploads`'s.

* Locations: ``file://`` is the local path it names (:func:`local_path`);
  names and folders of URLs never include a query string.
* Reading: a URL is downloaded to a temporary local file (Open3D reads only
  from paths), read, and the file is removed.  Messages name the URL.
* Secrets in ``storage_options`` are remembered for :func:`hht3d.redaction.redact`.

The back-ends are extras: ``pip install 'hht3d[s3]'`` (s3fs), ``[gcs]``
(gcsfs), ``[azure]`` (adlfs); a missing one is named with its pip command.
"""

from __future__ import annotations

import contextlib
import os
import posixpath
import shutil
import tempfile
from collections.abc import Callable, Collection, Iterator
from pathlib import Path, PurePosixPath
from typing import Any, TypeGuard
from urllib.parse import urlsplit

from ..errors import HHT3DError, InputError, one_line
from ..redaction import redact, remember_secrets
from .formats import MESH_EXTENSIONS, POINT_CLOUD_EXTENSIONS
from .paths import resolve_inputs

__all__ = [
    "EXTRAS",
    "is_url",
    "local_path",
    "under",
    "options_for",
    "filesystem",
    "input_size",
    "file_name",
    "stem",
    "parent_name",
    "join",
    "resolve_locations",
    "local_copy",
    "load_url",
    "TEMPORARY_PREFIX",
    "temporary_folder",
    "remove_temporary_folders",
]

#: The hht3d extra that installs each protocol's back-end.
EXTRAS = {
    "s3": "s3",
    "s3a": "s3",
    "gs": "gcs",
    "gcs": "gcs",
    "az": "azure",
    "abfs": "azure",
    "abfss": "azure",
    "adl": "azure",
}
_GLOB = "*?["


def is_url(location: Path | str) -> TypeGuard[str]:
    """Whether ``location`` is an fsspec URL (``protocol://...``) rather than a local path; a ``file://``
    URL is the local path it names (:func:`local_path`), with every local rule."""
    return isinstance(location, str) and "://" in location and not _is_file_url(location)


def _is_file_url(location: Path | str) -> TypeGuard[str]:
    """``file://`` or ``local://``: fsspec's names for the local file system."""
    return isinstance(location, str) and location.split("://", 1)[0].lower() in ("file", "local")


def local_path(location: Path | str) -> Path | str:
    """``location`` as hht3d takes it wherever a location enters: a ``file://`` (or ``local://``) URL as
    the local :class:`~pathlib.Path` it names, anything else unchanged.

    Raises
    ------
    InputError
        A ``file://`` URL naming another host.
    """
    if not _is_file_url(location):
        return location
    from urllib.request import url2pathname

    parts = urlsplit(location)
    if parts.netloc not in ("", "localhost"):
        raise InputError(
            f"{location}: a file:// URL names a local path, not one on host {parts.netloc!r}; write file:///path"
        )
    return Path(url2pathname(parts.path))


def _protocol(url: str) -> str:
    return url.split("::")[-1].split("://", 1)[0].lower()


def options_for(url: str, storage_options: dict | None) -> dict:
    """The ``storage_options`` of ``url``'s back-end.

    ``storage_options`` is either one set of options for every URL of a run, or a mapping keyed
    by protocol, e.g. ``{"s3": {"client_kwargs": {...}}, "https": {}}``, for runs that mix stores
    (one set of S3 options given to an ``https://`` input fails inside its HTTP client).
    """
    import fsspec

    options = storage_options or {}
    protocols = set(fsspec.available_protocols())
    if options and all(key in protocols and isinstance(value, dict) for key, value in options.items()):
        return options.get(_protocol(url), {})
    return options


def filesystem(url: str, storage_options: dict | None = None) -> tuple[Any, str]:
    """``(fs, path)`` of a URL; a missing back-end names the pip command that installs it.

    ``storage_options``: as for :func:`options_for`.

    Raises
    ------
    InputError
        Unknown protocol, missing back-end or bad ``storage_options``.
    """
    import fsspec.core

    remember_secrets(storage_options)
    protocol = _protocol(url)
    try:
        return fsspec.core.url_to_fs(url, **options_for(url, storage_options))
    except ImportError:
        extra = EXTRAS.get(protocol)
        how = f"pip install 'hht3d[{extra}]'" if extra else "install the fsspec back-end for it"
        raise InputError(
            f"{redact(url)}: reading and writing {protocol}:// needs a back-end that is not installed; {how}"
        ) from None
    except (ValueError, TypeError) as exc:
        raise InputError(
            f"{redact(url)}: cannot open {protocol}:// ({one_line(exc)}); check the URL and storage_options"
        ) from None


def input_size(location: Path | str, storage_options: dict | None = None) -> int:
    """Bytes of an input file or object, 0 when it cannot be read (its load then says why)."""
    try:
        if is_url(location):
            fs, path = filesystem(location, storage_options)
            return int(fs.size(path) or 0)
        return Path(location).stat().st_size
    except Exception:  # missing, unreadable, or a back-end's own error types: the load reports it
        return 0


def _key(url: str) -> str:
    """The path part of a URL (no query string)."""
    return urlsplit(url.split("::")[-1]).path


def file_name(location: Path | str) -> str:
    """File name of a path or URL (a URL's query string left out)."""
    return PurePosixPath(_key(location)).name if is_url(location) else Path(location).name


def stem(location: Path | str) -> str:
    """File name without its suffix."""
    return PurePosixPath(file_name(location)).stem


def parent_name(location: Path | str) -> str:
    """Name of the folder holding a path or URL (a bucket's name for a top-level object)."""
    if not is_url(location):
        return Path(location).parent.name
    url = urlsplit(location.split("::")[-1])
    parent = PurePosixPath(url.path).parent.name
    return parent or url.netloc


def join(folder: Path | str, file_name: str) -> Path | str:
    """``folder / file_name``: a Path for a local folder, a URL string for a URL (its key normalised:
    no ``.`` or ``..`` left in it, which a tool syncing the bucket would follow)."""
    folder = local_path(folder)
    if is_url(folder):
        return _normalised(f"{folder.rstrip('/')}/{file_name}")
    return Path(folder) / file_name


def _normalised(url: str) -> str:
    """``url`` with ``.``, ``..`` and repeated slashes of its path resolved lexically."""
    head, _, rest = url.partition("://")
    return f"{head}://{posixpath.normpath(rest) if rest.strip('/') else rest}"


def under(url: str, folder: str) -> str | None:
    """The key of the URL ``url`` relative to the URL ``folder``, both normalised lexically; ``None`` if
    ``url`` does not lie under ``folder``."""
    root, found = _normalised(folder).rstrip("/") + "/", _normalised(url)
    return found[len(root) :] if found.startswith(root) and len(found) > len(root) else None


def _access_error(exc: Exception) -> str:
    if isinstance(exc, TypeError):  # an option of another back-end, e.g. S3's endpoint_url given to https
        return (
            f"storage_options do not fit this back-end: {one_line(exc)}; for runs that mix stores, key "
            "them by protocol, e.g. {s3: {client_kwargs: ...}, https: {}}"
        )
    if isinstance(exc, PermissionError):
        return "access denied; check the credentials (environment, config files or instance role)"
    if isinstance(exc, FileNotFoundError):
        return "no such object or bucket"
    return one_line(f"{type(exc).__name__}: {exc}")


def resolve_locations(spec: Any, storage_options: dict | None = None) -> list:
    """:func:`hht3d.io.paths.resolve_inputs` for paths and URLs: files, folders, globs, lists.

    URLs come back as URLs (``s3://bucket/scans/a.ply``), local files as Paths.

    Raises
    ------
    InputError
        A named object is missing, a folder or glob matches no usable file, or
        the store cannot be listed.
    """
    specs = [spec] if isinstance(spec, (str, Path)) else list(spec)
    found: list[Path | str] = []
    for item in map(local_path, specs):
        found.extend(_remote_inputs(item, storage_options) if is_url(item) else resolve_inputs(item))
    return list(dict.fromkeys(found))


def _remote_inputs(url: str, storage_options: dict | None) -> list[str]:
    fs, path = filesystem(url, storage_options)
    usable = set(MESH_EXTENSIONS + POINT_CLOUD_EXTENSIONS)
    try:
        fs.invalidate_cache()
        if any(ch in _key(url) for ch in _GLOB):  # not in a query string (signed URLs)
            paths = [p for p in fs.glob(path) if fs.isfile(p)]
        elif fs.isdir(path):
            paths = [p for p, info in fs.find(path, maxdepth=1, detail=True).items() if info["type"] == "file"]
        elif fs.isfile(path):
            suffix = PurePosixPath(_key(url)).suffix.lower()  # a signed URL's query is no part of its name
            if suffix not in usable:
                raise InputError(
                    redact(f"{url}: unknown extension {suffix or '(none)'!r}; use one of {', '.join(sorted(usable))}")
                )
            return [url]
        else:
            raise InputError(f"{redact(url)}: no such object or folder; check the URL")
    except HHT3DError:
        raise
    except Exception as exc:  # the back-ends raise many types (network, client errors)
        raise InputError(f"{redact(url)}: cannot list ({_access_error(exc)})") from None
    matches = sorted(_as_written(url, fs, p) for p in paths if PurePosixPath(p).suffix.lower() in usable)
    if not matches:
        raise InputError(f"{redact(url)}: matches no mesh or point-cloud file ({', '.join(sorted(usable))})")
    return matches


def _as_written(url: str, fs: Any, path: str) -> str:
    """A listed object's URL with the protocol the user wrote (``az://``, not the back-end's ``abfs://``)."""
    full = fs.unstrip_protocol(path)
    written = url.split("::")[-1].split("://", 1)[0]
    return f"{written}://{full.split('://', 1)[1]}"


#: Prefix of the temporary folders of downloads and uploads; the process id follows it.
TEMPORARY_PREFIX = "hht3d-"


def temporary_folder() -> tempfile.TemporaryDirectory[str]:
    """A temporary folder named after this process, so that a stop can find it after its owner
    (a thread or worker process ended without running its cleanup, :func:`remove_temporary_folders`)."""
    return tempfile.TemporaryDirectory(prefix=f"{TEMPORARY_PREFIX}{os.getpid()}-")


def remove_temporary_folders(pids: Collection[int]) -> list[Path]:
    """Remove the temporary folders of :func:`temporary_folder` made by the processes ``pids``."""
    removed = []
    for pid in pids:
        for folder in Path(tempfile.gettempdir()).glob(f"{TEMPORARY_PREFIX}{pid}-*"):
            shutil.rmtree(folder, ignore_errors=True)
            removed.append(folder)
    return removed


@contextlib.contextmanager
def local_copy(location: Path | str, storage_options: dict | None = None, *, head: int | None = None) -> Iterator[Path]:
    """A local path holding ``location``'s bytes (the first ``head`` only if given); removed afterwards.

    A local path is yielded as it is.

    Raises
    ------
    InputError
        The object cannot be read (missing, access denied, network).
    """
    location = local_path(location)
    if not is_url(location):
        yield Path(location)
        return
    fs, path = filesystem(location, storage_options)
    with temporary_folder() as folder:
        local = Path(folder) / (file_name(location) or "object")
        try:
            if head is None:
                fs.get_file(path, str(local))
            else:
                local.write_bytes(fs.cat_file(path, start=0, end=head))
        except Exception as exc:  # the back-ends raise many types (network, client errors)
            raise InputError(f"{redact(location)}: cannot read ({_access_error(exc)})") from None
        yield local


def load_url(load: Callable[..., Any], url: str, storage_options: dict | None = None, **options: Any) -> Any:
    """``load`` (:func:`hht3d.io.read.load`) of a URL through a temporary local copy; messages name the URL."""
    with local_copy(url, storage_options) as local:
        try:
            return load(local, **{**options, "name": options.get("name") or stem(url)})
        except InputError as exc:
            raise InputError(str(exc).replace(str(local), redact(url))) from None
