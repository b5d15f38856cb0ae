"""Sending a run's sealed storage options to its workers, apart from the task graph (:mod:`hht3d.io.sealed`).

A task carries only the token of its storage options.  Local pool workers get
the registry in their initializer (:func:`hht3d.execution.workers.limit_blas_threads`);
a ``dask.distributed`` cluster gets it from :func:`share_storage_options`, a
worker plugin installed on every worker now and on those that join later.
"""

from __future__ import annotations

from typing import Any

from distributed.diagnostics.plugin import WorkerPlugin

from ..io.sealed import install, registered

__all__ = ["StorageOptionsPlugin", "share_storage_options", "PLUGIN_NAME"]

#: The name of the plugin on the cluster: a later run's registry replaces an earlier one's.
PLUGIN_NAME = "hht3d-storage-options"


class StorageOptionsPlugin(WorkerPlugin):
    """Installs sealed storage options (``entries``, from :func:`hht3d.io.sealed.registered`) on a worker."""

    def __init__(self, entries: dict[str, dict]):
        self.entries = entries

    def setup(self, worker: Any) -> None:
        install(self.entries)


def share_storage_options(client: Any) -> None:
    """Install this process's sealed storage options on the workers of ``client`` (nothing when there
    are none), before a graph whose tasks carry their tokens is computed there."""
    entries = registered()
    if entries:
        client.register_plugin(StorageOptionsPlugin(entries), name=PLUGIN_NAME)
