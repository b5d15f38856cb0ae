"""Open3D with its log and the native output of C/C++ code (Qhull's too) kept off the terminal.

At the bottom of the package (standard library only), so that geometry and
io can both use it without importing each other.
"""

from __future__ import annotations

import contextlib
import os
import sys
import tempfile
import threading
from collections.abc import Iterator
from typing import Any

__all__ = ["captured_native_output", "quiet_open3d"]

#: Serialises the redirection of the process's stdout/stderr (see :func:`captured_native_output`).
_NATIVE_OUTPUT = threading.Lock()


@contextlib.contextmanager
def captured_native_output() -> Iterator[None]:
    """Send what C and C++ code writes to file descriptors 1 and 2 to a temporary file, then drop it.

    Qhull (inside Open3D) prints warnings and 25-line error reports there,
    below Python's ``sys.stdout``/``sys.stderr``; its errors also reach
    Python as exceptions, which are reported instead.  The redirection is
    process-wide, so it is serialised by a lock and kept to the native call
    it wraps.
    """
    with _NATIVE_OUTPUT, tempfile.TemporaryFile() as sink:
        for stream in (sys.stdout, sys.stderr):
            with contextlib.suppress(Exception):
                stream.flush()
        try:
            saved = [os.dup(1), os.dup(2)]
        except OSError:  # no standard descriptors (a daemon): nothing can leak
            yield
            return
        try:
            os.dup2(sink.fileno(), 1)
            os.dup2(sink.fileno(), 2)
            yield
        finally:
            _flush_c_streams()
            for fd, copy in zip((1, 2), saved):
                os.dup2(copy, fd)
                os.close(copy)


def _flush_c_streams() -> None:
    """``fflush(NULL)``: write out C stdio buffers before the descriptors are restored."""
    import ctypes

    with contextlib.suppress(Exception):
        ctypes.CDLL(None).fflush(None)


@contextlib.contextmanager
def quiet_open3d() -> Iterator[Any]:
    """Open3D with its log at error level and its native output (Qhull's too) captured."""
    import open3d as o3d

    with o3d.utility.VerbosityContextManager(o3d.utility.VerbosityLevel.Error), captured_native_output():
        yield o3d
