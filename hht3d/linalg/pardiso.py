"""MKL PARDISO through ``pypardiso`` (extra ``fast``, x86-64 only)."""

from __future__ import annotations

import ctypes
import functools
import importlib.metadata
import os
import threading
import weakref
from typing import Any

import numpy as np
import scipy.sparse as sp

from ..errors import NumericalError
from .factor import Factor, Latest, UpperTriangle

__all__ = ["PardisoPattern", "PARDISO_LOCK", "listed_mkl_runtime"]

#: MKL PARDISO is entered by one thread at a time, whatever the handle: held by
#: :class:`~hht3d.linalg.symbolic.SymbolicFactorization` (the registry's ``lock``) and by the
#: finalizer that frees a handle, which the garbage collector may run in any thread.
PARDISO_LOCK = threading.RLock()


def listed_mkl_runtime() -> str | None:
    """The path of MKL's runtime library (``mkl_rt``) as the ``mkl`` wheel's file list names it, or ``None``
    (no ``mkl`` distribution, or none of its ``mkl_rt`` files loads).

    pypardiso finds it by globbing every file under ``sys.prefix/lib``: 1.6 s on this machine's environment
    (247,784 directory entries), in every process that creates a solver.  The file list takes 5 ms.
    """
    try:
        files = importlib.metadata.distribution("mkl").files or []
    except importlib.metadata.PackageNotFoundError:
        return None
    for path in sorted((str(f.locate()) for f in files if "mkl_rt" in f.name), key=len):
        try:
            ctypes.CDLL(path)
        except OSError:
            continue
        return path
    return None


@functools.lru_cache(maxsize=1)
def _locate_mkl(pypardiso: Any) -> None:
    """Find MKL's runtime once per process and tell pypardiso where it is: from the ``mkl`` wheel's file
    list (:func:`listed_mkl_runtime`), else by pypardiso's own search of the installation tree.

    pypardiso otherwise searches the tree every time a solver is created.
    """
    if "PYPARDISO_MKL_RT" not in os.environ:
        os.environ["PYPARDISO_MKL_RT"] = listed_mkl_runtime() or pypardiso.PyPardisoSolver().libmkl._name


class PardisoPattern:
    """MKL PARDISO in SPD mode with the symbolic phase run once.

    ``solver`` is the ``pypardiso.PyPardisoSolver`` (its ``iparm`` reports
    memory and fill); every phase goes through :meth:`run`, which calls MKL
    with the pattern's 1-based index arrays made once (pypardiso would
    convert them on every call: two index-sized copies per solve).
    """

    def __init__(self, pattern: sp.csr_matrix, module: Any) -> None:
        self.n = pattern.shape[0]
        self._upper = UpperTriangle(pattern)
        self._error = module.pardiso_wrapper.PyPardisoError
        _locate_mkl(module)
        self.solver = module.PyPardisoSolver(mtype=2)  # MKL's SPD defaults
        weakref.finalize(self, _free, self.solver)
        self._latest = Latest("PARDISO")
        self._indptr = (self._upper.indptr + 1).astype(np.int32)
        self._indices = (self._upper.indices + 1).astype(np.int32)
        self.run(11, self._upper.data(pattern), np.zeros((self.n, 1), order="F"))
        # keep the defaults MKL filled in, minus iterative refinement: SPD
        # solves are accurate to ~1e-13 without it and 5x faster on many columns
        self.solver.iparm[0] = 1
        self.solver.iparm[7] = 0

    def run(self, phase: int, upper: np.ndarray, b: np.ndarray) -> np.ndarray:
        """PARDISO ``phase`` (11 analysis, 22 numeric factorization, 33 solve) on the upper-triangle
        values ``upper``, with the right-hand sides ``b`` (n, k) in Fortran order."""
        s, int_p = self.solver, ctypes.POINTER(ctypes.c_int32)
        x, error = np.zeros_like(b), ctypes.c_int32(0)
        s._mkl_pardiso(
            s.pt.ctypes.data_as(ctypes.POINTER(s._pt_type[0])),
            _int32(1),
            _int32(1),
            _int32(s.mtype),
            _int32(phase),
            _int32(self.n),
            upper.ctypes.data_as(ctypes.POINTER(ctypes.c_double)),
            self._indptr.ctypes.data_as(int_p),
            self._indices.ctypes.data_as(int_p),
            s.perm.ctypes.data_as(int_p),
            _int32(b.shape[1]),
            s.iparm.ctypes.data_as(int_p),
            _int32(s.msglvl),
            b.ctypes.data_as(ctypes.POINTER(ctypes.c_double)),
            x.ctypes.data_as(ctypes.POINTER(ctypes.c_double)),
            ctypes.byref(error),
        )
        if error.value != 0:
            raise NumericalError(f"PARDISO phase {phase} failed: {self._error(error.value)}")
        return x

    def factorize(self, a: sp.csr_matrix) -> Factor:
        upper = self._upper.data(a)
        self.run(22, upper, np.zeros((self.n, 1), order="F"))
        token = self._latest.claim()

        def solve(b: np.ndarray) -> np.ndarray:
            self._latest.check(token)
            columns = np.asfortranarray(b.reshape(self.n, -1), dtype=np.float64)
            return np.ascontiguousarray(self.run(33, upper, columns)).reshape(b.shape)

        return Factor(solve, self.n)


def _free(solver: Any) -> None:
    """Release all of MKL's memory for ``solver``'s handle (PARDISO phase -1)."""
    with PARDISO_LOCK:
        solver.free_memory(True)


def _int32(value: int) -> Any:
    return ctypes.byref(ctypes.c_int32(value))
