"""Freed heap handed back to the operating system (hht3d.linalg.heap): the kernel's resident size is
the oracle on Linux; elsewhere, and without glibc, nothing is called and nothing fails."""

import ctypes
import sys

import numpy as np
import pytest

from hht3d.linalg import heap


def _resident_mb() -> float:
    with open("/proc/self/status") as status:
        return int(status.read().split("VmRSS:")[1].split()[0]) / 1024


@pytest.fixture
def fresh():
    heap._malloc_trim.cache_clear()
    yield heap
    heap._malloc_trim.cache_clear()


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="glibc's malloc_trim and /proc")
def test_freed_small_arrays_leave_the_resident_set(fresh):
    """160 MB of 8 KB arrays, 7 of 8 freed: glibc keeps the pages (every 8th array pins the heap) until
    they are released; then at least 100 of the 140 MB freed leave the resident set."""
    arrays = [np.ones(1024) for _ in range(20_000)]
    kept = arrays[::8]
    del arrays
    before = _resident_mb()
    assert fresh.release_free_heap()
    assert before - _resident_mb() > 100, (before, _resident_mb())
    assert len(kept) == 2500


@pytest.mark.parametrize(
    "missing",
    [
        lambda mp: mp.setattr(sys, "platform", "win32"),
        lambda mp: mp.setattr(ctypes, "CDLL", lambda *a, **k: (_ for _ in ()).throw(OSError("no C library"))),
        lambda mp: mp.setattr(ctypes, "CDLL", lambda *a, **k: object()),  # a C library without malloc_trim (musl)
    ],
    ids=["windows", "no-libc", "no-symbol"],
)
def test_without_glibc_nothing_is_called(fresh, monkeypatch, missing):
    missing(monkeypatch)
    assert fresh.release_free_heap() is False
