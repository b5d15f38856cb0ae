"""Writing to object storage: atomic uploads, conditional updates, and the check of a bucket before a run.

* :func:`atomic_location` / :func:`write_via`: a writer writes a temporary
  local file, which is then uploaded.  On object stores (S3, GCS, Azure) one
  upload is atomic: an object appears under its name only once complete, so a
  killed run leaves no partial object under a final name.  Elsewhere the
  upload goes to a temporary name and is moved over the final one.
* :func:`update_object`: read, change and write one object, conditionally
  where the store supports it (S3), so that two runs merging one summary or
  manifest keep each other's entries.
* :func:`check_outputs`: before computing, the bucket exists and a probe
  object can be written and removed in each output folder.

Locations, back-ends and reading are :mod:`hht3d.io.storage`'s.
"""

from __future__ import annotations

import contextlib
import uuid
from collections.abc import Callable, Iterable, Iterator
from pathlib import Path, PurePosixPath
from typing import Any

from ..errors import HHT3DError, OutputError
from ..redaction import redact
from .atomic import atomic_path, check_output_paths
from .storage import _access_error, _protocol, file_name, filesystem, is_url, local_path, temporary_folder

__all__ = ["atomic_location", "write_via", "update_object", "check_outputs"]

#: Protocols on which one upload is atomic (an object is visible only once complete).
_ATOMIC_UPLOAD = {"s3", "s3a", "gs", "gcs", "az", "abfs", "abfss", "memory"}
#: Protocols whose back-end writes conditionally (s3fs: ``If-None-Match: *``, ``If-Match`` an ETag).
_CONDITIONAL = {"s3", "s3a"}
#: Tries of :func:`update_object` when other writers keep coming first.
_UPDATE_TRIES = 20


@contextlib.contextmanager
def atomic_location(location: Path | str, storage_options: dict | None = None) -> Iterator[Path]:
    """Like :func:`hht3d.io.atomic.atomic_path`, for a path or URL: yield a temporary local path.

    For a URL, the file is uploaded once the block succeeds; on an exception
    nothing is uploaded and the temporary file is removed.

    Raises
    ------
    OutputError
        The upload failed (names the URL and the reason).
    """
    location = local_path(location)
    if not is_url(location):
        with atomic_path(location) as tmp:
            yield tmp
        return
    fs, path = filesystem(location, storage_options)
    with temporary_folder() as folder:
        local = Path(folder) / file_name(location)
        yield local
        _upload(fs, str(local), path, location)


def _upload(fs: Any, local: str, path: str, location: str) -> None:
    """Put ``local`` at ``path``, so that no object appears under ``path`` before it is complete."""
    try:
        if _protocol(location) in _ATOMIC_UPLOAD:
            fs.put_file(local, path)
        else:
            partial = f"{PurePosixPath(path).parent}/.{PurePosixPath(path).name}.{uuid.uuid4().hex}.part"
            fs.makedirs(str(PurePosixPath(path).parent), exist_ok=True)
            fs.put_file(local, partial)
            try:
                fs.mv(partial, path)
            finally:
                with contextlib.suppress(OSError):
                    if fs.exists(partial):
                        fs.rm_file(partial)
    except Exception as exc:  # the back-ends raise many types (network, client errors)
        raise OutputError(
            f"{redact(location)}: cannot write ({_access_error(exc)}); check the bucket and "
            "the credentials, or choose another output folder"
        ) from None
    finally:
        fs.invalidate_cache(str(PurePosixPath(path).parent))


def write_via(write: Callable[..., Any], *args: Any, storage_options: dict | None = None, **options: Any) -> Any:
    """``write(*args, **options)`` whose last positional argument is a path or URL; returns it.

    A URL is written by ``write`` to a temporary local file, then uploaded
    (:func:`atomic_location`).
    """
    *values, location = args
    location = local_path(location)
    if not is_url(location):
        return write(*values, location, **options)
    with atomic_location(location, storage_options) as local:
        write(*values, local, **options)
    return location


def update_object(url: str, update: Callable[[Any], Any], storage_options: dict | None = None) -> None:
    """Replace the object at ``url`` by ``update(its bytes, or None if missing)``, other writers' changes kept.

    On S3 the write is conditional (``If-Match`` the ETag read, ``If-None-Match``
    when there was none): when another writer came first, its bytes are read
    and ``update`` applied again.  Other stores have no conditional write
    here: the last writer wins.

    Raises
    ------
    OutputError
    """
    fs, path = filesystem(url, storage_options)
    conditional = _protocol(url) in _CONDITIONAL
    for _ in range(_UPDATE_TRIES):
        fs.invalidate_cache(str(PurePosixPath(path).parent))
        try:
            try:
                etag, old = fs.info(path).get("ETag"), fs.cat_file(path)
            except FileNotFoundError:
                etag, old = None, None
            data = update(old)
            if not conditional:
                with atomic_location(url, storage_options) as tmp:
                    tmp.write_bytes(data)
                return
            fs.pipe_file(path, data, **({"IfMatch": etag} if etag else {"mode": "create"}))
            return
        except Exception as exc:  # the back-ends raise many types (network, client errors)
            if not (conditional and _came_first(exc)):
                raise OutputError(
                    f"{redact(url)}: cannot write ({_access_error(exc)}); check the bucket and the "
                    "credentials, or choose another output folder"
                ) from None
    raise OutputError(f"{redact(url)}: cannot write: other runs kept changing it ({_UPDATE_TRIES} tries); run again")


def _came_first(exc: Exception) -> bool:
    """Whether a conditional write failed because another writer changed the object (HTTP 412)."""
    return isinstance(exc, FileExistsError) or "pre-condition" in str(exc).lower() or "412" in str(exc)


def check_outputs(locations: Iterable[Path | str], storage_options: dict | None = None) -> None:
    """:func:`hht3d.io.atomic.check_output_paths` for paths and URLs, creating nothing that stays.

    For URLs: the bucket (or container) exists and a probe object can be
    written and removed in each output folder.

    Raises
    ------
    OutputError
        One line naming the location and what to change.
    """
    locations = list(map(local_path, locations))
    check_output_paths([p for p in locations if not is_url(p)])
    folders = dict.fromkeys(str(p).rsplit("/", 1)[0] for p in locations if is_url(p))
    for folder in folders:
        _check_remote_folder(folder, storage_options)


def _check_remote_folder(folder: str, storage_options: dict | None) -> None:
    fs, path = filesystem(folder + "/", storage_options)
    bucket = path.strip("/").split("/", 1)[0]
    protocol = _protocol(folder)
    try:
        if protocol in _ATOMIC_UPLOAD - {"memory"} and not fs.exists(bucket):
            raise OutputError(
                f"{redact(folder)}: cannot write: the bucket {bucket!r} does not exist (or these "
                "credentials cannot see it); create it or choose another output folder"
            )
        probe = f"{path.rstrip('/')}/.hht3d-probe-{uuid.uuid4().hex}"
        fs.pipe_file(probe, b"")
        fs.rm_file(probe)
    except HHT3DError:
        raise
    except Exception as exc:  # the back-ends raise many types (network, client errors)
        raise OutputError(
            f"{redact(folder)}: cannot write ({_access_error(exc)}); choose another output "
            "folder or fix the permissions"
        ) from None
