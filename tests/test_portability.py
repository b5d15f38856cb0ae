"""Nothing POSIX-only is needed: hht3d's own code imports and runs a dataset without ``fcntl``,
``resource`` or ``signal.SIGTERM``.

A fresh interpreter blocks those before importing hht3d, the way Windows lacks them.  The
output folder's lock (:func:`hht3d.io.lock.folder_lock`) then takes its Windows branch,
given a ``msvcrt`` whose ``locking`` is a process-local lock (a real one would make the standard
library believe it runs on Windows).  A two-file local dataset runs, taking that lock to record
its outputs.
"""

from __future__ import annotations

import json
import subprocess
import sys
import textwrap

import pytest

from helpers.models import shipped_model_path

PRELUDE = textwrap.dedent("""
    import errno, os, signal, sys, threading, types

    # The dependencies first: each picks its own platform's backend (psutil's Linux one needs
    # resource, distributed's locket fcntl; on Windows they take their Windows ones).
    # What is checked is hht3d's own code.
    import dask, distributed, fsspec, matplotlib, numpy, open3d, plotly, plyfile, psutil, robust_laplacian
    import scipy.sparse.linalg, yaml

    sys.modules["fcntl"] = None      # import fcntl -> ImportError, as on Windows
    sys.modules["resource"] = None
    del signal.SIGTERM

    calls = []
    held = {}

    def locking(fd, mode, nbytes):   # msvcrt.locking of one byte, within this process
        key = os.fstat(fd).st_ino
        calls.append(mode)
        if mode == LK_NBLCK:
            if not held.setdefault(key, threading.Lock()).acquire(blocking=False):
                raise OSError(errno.EACCES, "locked by another")
        elif mode == LK_UNLCK:
            held[key].release()
        else:
            raise OSError(errno.EINVAL, "unexpected mode")

    LK_UNLCK, LK_NBLCK = 0, 2
""")

RUN = textwrap.dedent("""
    import importlib, json, pkgutil
    import hht3d

    for module in pkgutil.walk_packages(hht3d.__path__, "hht3d."):  # every module imports
        if module.name != "hht3d.__main__":  # the CLI's entry point: it would run
            importlib.import_module(module.name)
    from hht3d.dataset import run_dataset
    from hht3d.io import lock as folder_locks

    folder_locks.msvcrt = types.SimpleNamespace(locking=locking, LK_NBLCK=LK_NBLCK, LK_UNLCK=LK_UNLCK)
    rows = run_dataset(sys.argv[1:3], sys.argv[3], scheduler="synchronous", progress=False,
                       max_imfs=2)
    print(json.dumps({"status": [r.status for r in rows], "fcntl": folder_locks.fcntl is None,
                      "locks": calls.count(LK_NBLCK), "unlocks": calls.count(LK_UNLCK),
                      "posix": [m for m in ("fcntl", "resource") if sys.modules.get(m) is not None]}))
""")


@pytest.mark.slow
def test_imports_and_runs_a_dataset_without_posix_only_modules(tmp_path):
    inputs = [str(shipped_model_path(name)) for name in ("spot.ply", "sphere_oct4098.ply")]
    done = subprocess.run(
        [sys.executable, "-c", PRELUDE + RUN, *inputs, str(tmp_path / "out")],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert done.returncode == 0, done.stderr[-3000:]
    report = json.loads(done.stdout.strip().splitlines()[-1])
    assert report["status"] == ["ok", "ok"]
    assert report["fcntl"] and report["posix"] == []
    assert report["locks"] >= 2 and report["locks"] == report["unlocks"]
    assert sorted(p.name for p in (tmp_path / "out").glob("*_hht.*")) == [
        "sphere_oct4098_hht.npz",
        "sphere_oct4098_hht.ply",
        "spot_hht.npz",
        "spot_hht.ply",
    ]


def test_the_lock_fails_clearly_where_no_lock_exists(tmp_path, monkeypatch):
    """A platform with neither ``fcntl`` nor ``msvcrt`` gets one line, not an AttributeError."""
    from hht3d.errors import OutputError
    from hht3d.io import lock as folder_locks

    monkeypatch.setattr(folder_locks, "fcntl", None)
    monkeypatch.setattr(folder_locks, "msvcrt", None)
    with pytest.raises(OutputError, match="neither fcntl nor msvcrt"):
        with folder_locks.folder_lock(tmp_path / "out"):
            pass
