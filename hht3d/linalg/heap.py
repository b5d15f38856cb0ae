"""Freed memory handed back to the operating system where the C library keeps it (glibc).

glibc serves allocations below its mmap threshold (at most 32 MB) from heaps that it does not
shrink when they are freed in the middle.  When the HHT lets a 10M-point cloud's coarsening
hierarchy go (1.7 GB of levels, mostly smaller arrays), 917 MB of it stayed resident, and the
monogenic stage's arrays, which are larger and mapped anew, came on top of it: ``malloc_trim``
returns those pages.  Elsewhere (macOS, Windows, musl) there is nothing to call and nothing
is done.
"""

from __future__ import annotations

import ctypes
import functools
import sys
from typing import Any

__all__ = ["release_free_heap"]


@functools.lru_cache(maxsize=1)
def _malloc_trim() -> Any:
    """glibc's ``malloc_trim`` from the process's own symbols, or ``None``."""
    if not sys.platform.startswith("linux"):
        return None
    try:
        trim = ctypes.CDLL(None).malloc_trim
    except (OSError, AttributeError):  # no loadable C library, or one without it (musl)
        return None
    trim.argtypes, trim.restype = [ctypes.c_size_t], ctypes.c_int
    return trim


def release_free_heap() -> bool:
    """Return the C heap's free pages to the operating system; whether the C library could (glibc)."""
    trim = _malloc_trim()
    if trim is None:
        return False
    trim(0)
    return True
