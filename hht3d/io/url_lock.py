"""The lock of a URL output folder, ``FOLDER/.hht3d.lock``: one run at a time where the store writes conditionally.

On S3 the lock is an object created with ``If-None-Match: *``, so that of two
runs only one creates it.  It holds its holder's host, pid, run id, start
time and expiry, as JSON; a heartbeat thread rewrites it (``If-Match`` its
ETag) every :data:`HEARTBEAT` seconds, moving the expiry :data:`EXPIRY`
seconds ahead.  A run finding it held says who holds it, waits up to
``HHT3D_LOCK_TIMEOUT`` seconds (:func:`hht3d.io.lock.lock_timeout`) and
fails with one line naming the holder; a lock whose expiry has passed (its
holder was killed) is taken over, with a warning.  The lock is removed at
the end of the run, and by a clean stop (:func:`release_all`).

Stores without conditional writes here (``memory://``, ``gs://``, ``az://``,
...) and S3 servers that ignore them (checked at each run: a second
exclusive create of the lock just made must be refused) get no lock: a
warning at run start says that the last of two runs writing at once wins.
"""

from __future__ import annotations

import contextlib
import json
import os
import socket
import threading
import time
from collections.abc import Iterator
from datetime import datetime, timezone
from typing import Any

from ..errors import OutputError
from ..logs import get_logger
from ..redaction import redact
from .lock import LOCK, lock_timeout
from .storage import _access_error, _protocol, filesystem
from .uploads import _CONDITIONAL, _came_first

__all__ = ["HEARTBEAT", "EXPIRY", "url_lock", "release_all"]

#: Seconds between two heartbeats of a held lock.
HEARTBEAT = 30.0
#: Seconds after its last heartbeat that a lock is stale, and taken over by the next run.
EXPIRY = 120.0
_POLL = 0.5
#: Seconds a release waits for a heartbeat under way.
_JOIN = 10.0
#: Seconds a stop keeps removing a lock it was taking, for writes in flight that land late.
_LATE_WRITES = 2.0
_LOG = get_logger("hht3d.io")
_HELD: dict[str, _Held] = {}
#: Locks being taken (``url`` -> ``fs, path, record``): a stop removes them if they are on the store.
_PENDING: dict[str, tuple] = {}
_GUARD = threading.RLock()  # reentrant: a stop handler may run while this thread holds it


class _Held:
    """A lock this process holds (``fs`` is None where the store gives no lock), and its heartbeat."""

    def __init__(self, url: str, fs: Any, path: str, record: dict, etag: str | None):
        self.url, self.fs, self.path, self.record, self.etag = url, fs, path, record, etag
        self.thread_id, self._stop = threading.get_ident(), threading.Event()
        self._beat = threading.Thread(target=self._heartbeat, name="hht3d-lock-heartbeat", daemon=True)
        if fs is not None:
            self._beat.start()

    def _heartbeat(self) -> None:
        while not self._stop.wait(HEARTBEAT):
            self.record["expires"] = _stamp(time.time() + EXPIRY)
            try:
                self.etag = _put(self.fs, self.path, self.record, IfMatch=self.etag)
            except Exception as exc:  # the back-ends raise many types (network, client errors)
                if _came_first(exc):
                    _LOG.warning(f"{redact(self.url)}: another run took over this run's output folder lock")
                    return
                _LOG.debug(f"{redact(self.url)}: lock heartbeat failed ({_access_error(exc)}); retrying")

    def release(self) -> None:
        """Stop the heartbeat and remove the lock object if it is still this run's."""
        self._stop.set()
        if self.fs is None:
            return
        self._beat.join(_JOIN)
        _remove_if_ours(self.url, self.fs, self.path, self.record)


def _remove_if_ours(url: str, fs: Any, path: str, record: dict) -> None:
    """Remove the lock object at ``path`` if it is the one ``record`` describes (this run's)."""
    try:
        found = _read(fs, path)[0]
        if found and found.get("run") == record["run"]:
            fs.rm_file(path)
    except Exception as exc:  # the back-ends raise many types (network, client errors)
        _LOG.warning(
            f"{redact(url)}/{LOCK}: cannot remove this run's lock ({_access_error(exc)}); "
            f"the next run takes it over {EXPIRY:g} s after its last heartbeat"
        )


@contextlib.contextmanager
def url_lock(folder: str, storage_options: dict | None = None, run: str | None = None) -> Iterator[None]:
    """Hold the lock of the URL output folder ``folder`` (see the module); taken again by the thread
    holding it, it is a no-op.

    Raises
    ------
    OutputError
        Another run held the lock for the whole timeout (names it), or the lock cannot be written.
    """
    url = folder.rstrip("/")
    with _GUARD:
        mine = url in _HELD and _HELD[url].thread_id == threading.get_ident()
    if mine:
        yield
        return
    held = _acquire(url, storage_options, run)
    with _GUARD:
        _HELD[url] = held
    try:
        yield
    finally:
        held.release()  # still in _HELD meanwhile: a stop that cuts the release short has release_all redo it
        with _GUARD:
            _HELD.pop(url, None)


def release_all() -> None:
    """Release every lock this process holds or is taking (a clean stop, :func:`hht3d.stopping.clean_stop`).

    A lock being taken may already be on the store while its creation is checked: a stop in that
    window removes it too, if it is this run's."""
    with _GUARD:
        held, pending = list(_HELD.values()), list(_PENDING.items())
        _HELD.clear()
        _PENDING.clear()
    for lock in held:
        lock.release()
    for url, (fs, path, record) in pending:
        if all(lock.url != url for lock in held):
            _remove_late(url, fs, path, record)


def _remove_late(url: str, fs: Any, path: str, record: dict) -> None:
    """Remove a lock being taken, and again if a write that was in flight (the creation or its
    check, sent by the store's event loop) lands after that, for :data:`_LATE_WRITES` seconds."""
    until = time.monotonic() + _LATE_WRITES
    while True:
        _remove_if_ours(url, fs, path, record)
        if time.monotonic() >= until:
            return
        time.sleep(_POLL / 5)


def _acquire(url: str, storage_options: dict | None, run: str | None) -> _Held:
    fs, path = filesystem(f"{url}/{LOCK}", storage_options)
    if _protocol(url) not in _CONDITIONAL:
        return _unlocked(url, "this store has no conditional writes here")
    record = {"host": socket.gethostname(), "pid": os.getpid(), "run": run, "started": _stamp(time.time())}
    with _GUARD:
        _PENDING[url] = (fs, path, record)
    try:
        held = _create(url, fs, path, record)
    except Exception:  # not a stop: a stop leaves it pending, for release_all to remove if it landed
        with _GUARD:
            _PENDING.pop(url, None)
        raise
    with _GUARD:  # held and no longer pending at once: a stop finds it one way or the other
        _HELD[url] = held
        _PENDING.pop(url, None)
    return held


def _create(url: str, fs: Any, path: str, record: dict) -> _Held:
    """Write the lock ``record``, waiting for (or taking over from) another run's."""
    deadline = None
    while True:
        record["expires"] = _stamp(time.time() + EXPIRY)
        try:
            etag = _put(fs, path, record, mode="create")
        except Exception as exc:  # the back-ends raise many types (network, client errors)
            if not _came_first(exc):
                raise _cannot(url, exc) from None
        else:
            return _checked(url, fs, path, record, etag)
        holder, etag = _read(fs, path)
        if not holder and etag is None:  # released meanwhile
            continue
        if _expired(holder):
            with contextlib.suppress(Exception):  # when another run took it over first, wait for that one
                etag = _put(fs, path, record, IfMatch=etag)
                _LOG.warning(
                    f"{redact(url)}: took over the output folder's lock of {_who(holder)}, whose last "
                    f"heartbeat is over {EXPIRY:g} s old (its run was killed or lost)"
                )
                return _Held(url, fs, path, record, etag)
        if deadline is None:
            timeout = lock_timeout()
            _LOG.info(
                f"{redact(url)}: waiting for {_who(holder)}, which holds the output folder's lock "
                f"(at most {timeout:g} s)"
            )
            deadline = time.monotonic() + timeout
        if time.monotonic() >= deadline:
            raise OutputError(
                redact(
                    f"{url}: {_who(holder)} still holds the output folder's lock after {timeout:g} s; wait "
                    "for that run to end (or stop it), choose another output folder, or set "
                    "HHT3D_LOCK_TIMEOUT to wait longer"
                )
            )
        time.sleep(_POLL)


def _checked(url: str, fs: Any, path: str, record: dict, etag: str | None) -> _Held:
    """The lock just created, once the store has refused to create it a second time (else no lock)."""
    try:
        _put(fs, path, record, mode="create")
    except Exception as exc:  # the back-ends raise many types (network, client errors)
        if _came_first(exc):
            return _Held(url, fs, path, record, etag)
        raise _cannot(url, exc) from None
    with contextlib.suppress(Exception):
        fs.rm_file(path)
    return _unlocked(url, "this store ignores conditional writes (If-None-Match: *)")


def _unlocked(url: str, why: str) -> _Held:
    _LOG.warning(
        f"{redact(url)}: the output folder is not locked, as {why}: if two runs write into it at "
        "once, the last writer wins (see Safety in the user guide)"
    )
    return _Held(url, None, "", {}, None)


def _put(fs: Any, path: str, record: dict, **conditions: Any) -> str | None:
    """Write the lock ``record`` at ``path`` under ``conditions``; its new ETag."""
    answer = fs.pipe_file(path, json.dumps(record).encode(), **conditions)
    return answer.get("ETag") if isinstance(answer, dict) else None


def _read(fs: Any, path: str) -> tuple[dict, str | None]:
    """The lock's record and ETag (ETag first: a record changed since then fails an ``If-Match`` of it);
    ``({}, None)`` if it is missing, an empty record if it is not a lock hht3d wrote."""
    fs.invalidate_cache(path.rsplit("/", 1)[0])
    try:
        etag, data = fs.info(path).get("ETag"), fs.cat_file(path)
    except FileNotFoundError:
        return {}, None
    try:
        record = json.loads(data)
    except ValueError:
        record = None
    return (record if isinstance(record, dict) else {}), etag


def _expired(record: dict) -> bool:
    """Whether the lock's expiry has passed (a lock without a readable expiry never expires)."""
    try:
        return datetime.fromisoformat(str(record["expires"])).timestamp() < time.time()
    except (KeyError, ValueError):
        return False


def _who(record: dict) -> str:
    """Who holds the lock: ``"pid 12 on h (run R, started 2026-01-02T03:04:05+00:00)"``."""
    try:
        who = f"pid {int(record['pid'])} on {str(record['host'])[:100]}"
    except (KeyError, TypeError, ValueError):
        return "another run"
    details = [f"run {str(record['run'])[:100]}"] if record.get("run") else []
    details += [f"started {str(record['started'])[:40]}"] if record.get("started") else []
    return who + (f" ({', '.join(details)})" if details else "")


def _stamp(seconds: float) -> str:
    return datetime.fromtimestamp(seconds, timezone.utc).isoformat(timespec="seconds")


def _cannot(url: str, exc: Exception) -> OutputError:
    return OutputError(
        f"{redact(url)}: cannot lock the output folder ({_access_error(exc)}); check the bucket and the "
        "credentials, or choose another output folder"
    )
