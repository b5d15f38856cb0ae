"""Storage options kept out of the task graph: the tasks carry an opaque token, the options travel apart.

``storage_options`` given from Python may hold credentials (a secret key, a
session token).  Put in a task they would be pickled with the graph, sent to
the scheduler and shown by any dump of it.  :func:`seal` instead keeps them
in this process's registry and returns a :class:`Sealed` reference, which
pickles as its token alone: 32 hex digits of an HMAC of the options under a
key drawn for this process, so equal options give one token (and one graph
key) in a run, and nothing about them can be read back from it.  The task
that reads or writes a URL resolves the token where it runs
(:func:`unsealed`):

* ``synchronous`` and ``threads``: in this process's memory;
* ``processes``: each pool worker receives the registry when it starts (its
  initializer's arguments, sent down the worker's pipe, not in a task);
* ``distributed``: a worker plugin installs it on every worker, also on those
  that join later (:mod:`hht3d.execution.sharing`); the scheduler holds the
  plugin only as serialized bytes to hand to new workers.

A worker that has not received the token fails with a line saying how to share the options.
"""

from __future__ import annotations

import copy
import hashlib
import hmac
import json
import os
import secrets
import threading

from ..errors import InputError
from ..redaction import remember_secrets

__all__ = ["Sealed", "seal", "unsealed", "registered", "install"]

_KEY = secrets.token_bytes(32)
_REGISTRY: dict[str, dict] = {}
_LOCK = threading.Lock()


class Sealed:
    """A reference to storage options held out of the graph (:func:`seal`); only ``token`` is pickled."""

    __slots__ = ("token",)

    def __init__(self, token: str):
        self.token = token

    def __reduce__(self) -> tuple:
        return (Sealed, (self.token,))

    def __dask_tokenize__(self) -> tuple:
        return ("hht3d-sealed-storage-options", self.token)

    def __eq__(self, other: object) -> bool:
        return isinstance(other, Sealed) and other.token == self.token

    def __hash__(self) -> int:
        return hash(self.token)

    def __repr__(self) -> str:
        return f"<storage options {self.token[:8]}, kept out of the task graph>"


def seal(options: dict | Sealed | None) -> Sealed | None:
    """A :class:`Sealed` reference to ``options``, kept in this process's registry (``None`` for none).

    Their credentials are also remembered for redaction (:func:`hht3d.redaction.remember_secrets`).
    """
    if isinstance(options, Sealed):
        return options
    if not options:
        return None
    text = json.dumps(options, sort_keys=True, default=repr).encode()
    token = hmac.new(_KEY, text, hashlib.sha256).hexdigest()[:32]
    remember_secrets(options)
    with _LOCK:
        _REGISTRY.setdefault(token, copy.deepcopy(options))
    return Sealed(token)


def unsealed(options: dict | Sealed | None) -> dict | None:
    """The storage options ``options`` stands for, where a task runs (plain options pass unchanged).

    Raises
    ------
    InputError
        The token was never shared with this process (a graph computed by another client than
        :func:`hht3d.execution.compute`).
    """
    if not isinstance(options, Sealed):
        return options
    with _LOCK:
        found = _REGISTRY.get(options.token)
    if found is None:
        raise InputError(
            f"the storage options of this task are not on this worker (process {os.getpid()}): they are "
            "kept out of the task graph and sent to the workers hht3d.execution.compute runs on; with "
            "a client of your own, call hht3d.execution.share_storage_options(client) first"
        )
    return found


def registered() -> dict[str, dict]:
    """Every token of this process and its options, to install in a worker (:func:`install`)."""
    with _LOCK:
        return dict(_REGISTRY)


def install(entries: dict[str, dict] | None) -> None:
    """Add ``entries`` (from :func:`registered` in the run's process) to this worker's registry."""
    for options in (entries or {}).values():
        remember_secrets(options)
    with _LOCK:
        _REGISTRY.update(entries or {})
