"""MKL PARDISO through ``pypardiso`` (extra ``fast``, x86-64 only)."""
from __future__ import annotations

import functools
import os
import weakref

import numpy as np
import scipy.sparse as sp

from ..errors import NumericalError
from .factor import Factor, Latest, UpperTriangle

__all__ = ["PardisoPattern"]


@functools.lru_cache(maxsize=1)
def _locate_mkl(pypardiso) -> None:
    """Find MKL's runtime once per process and tell pypardiso where it is.

    pypardiso otherwise searches the whole installation tree for ``mkl_rt``
    every time a solver is created (0.3-0.7 s each).
    """
    if "PYPARDISO_MKL_RT" not in os.environ:
        os.environ["PYPARDISO_MKL_RT"] = pypardiso.PyPardisoSolver().libmkl._name


class PardisoPattern:
    """MKL PARDISO in SPD mode with the symbolic phase run once.

    ``solver`` is the ``pypardiso.PyPardisoSolver`` (its ``iparm`` reports
    memory and fill); every phase goes through :meth:`run`.
    """

    def __init__(self, pattern: sp.csr_matrix, module):
        self.n = pattern.shape[0]
        self._upper = UpperTriangle(pattern)
        self._error = module.pardiso_wrapper.PyPardisoError
        _locate_mkl(module)
        self.solver = module.PyPardisoSolver(mtype=2)  # MKL's SPD defaults
        weakref.finalize(self, self.solver.free_memory, True)
        self._latest = Latest("PARDISO")
        self.run(11, self._upper.csr(pattern), np.zeros((self.n, 1)))
        # keep the defaults MKL filled in, minus iterative refinement: SPD
        # solves are accurate to ~1e-13 without it and 5x faster on many columns
        self.solver.iparm[0] = 1
        self.solver.iparm[7] = 0

    def run(self, phase: int, upper: sp.csr_matrix, b: np.ndarray) -> np.ndarray:
        """PARDISO ``phase`` (11 analysis, 22 numeric factorization, 33 solve) on ``upper``."""
        self.solver.set_phase(phase)
        try:
            return self.solver._call_pardiso(upper, b)
        except self._error as exc:
            raise NumericalError(f"PARDISO phase {phase} failed: {exc}") from exc

    def factorize(self, a: sp.csr_matrix) -> Factor:
        upper = self._upper.csr(a)
        self.run(22, upper, np.zeros((self.n, 1)))
        token = self._latest.claim()

        def solve(b: np.ndarray) -> np.ndarray:
            self._latest.check(token)
            return self.run(33, upper, np.asfortranarray(b))

        return Factor(solve, self.n)
