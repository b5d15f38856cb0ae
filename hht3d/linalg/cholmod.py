"""CHOLMOD through ``cvxopt`` (extra ``fast``; GPL, hence not a core dependency)."""

from __future__ import annotations

import threading
from typing import Any

import numpy as np
import scipy.sparse as sp

from ..errors import NumericalError
from .factor import Factor, Latest, UpperTriangle

__all__ = ["CholmodPattern", "CHOLMOD_LOCK"]

#: cvxopt keeps CHOLMOD's workspace in one process-wide ``cholmod_common``: one thread at a
#: time (held by :class:`~hht3d.linalg.symbolic.SymbolicFactorization`, the registry's ``lock``).
CHOLMOD_LOCK = threading.RLock()


class CholmodPattern:
    """CHOLMOD (cvxopt) supernodal Cholesky with the ordering and symbolic analysis done once.

    One cvxopt sparse matrix holds the lower triangle in CSC order; each
    factorization overwrites its values and refactorizes numerically in
    place, so (as with PARDISO) only the latest factor is valid.
    """

    def __init__(self, pattern: sp.csr_matrix, module: Any) -> None:
        self.n = pattern.shape[0]
        self._cvxopt, self._cholmod = module, module.cholmod
        self._lower = UpperTriangle(pattern)  # CSR upper == CSC lower
        # CSC lower: column = CSR row, row = CSR column; values 1 so that none is dropped
        self._matrix = module.spmatrix(
            1.0, self._lower.indices.astype(np.int64), self._lower.rows.astype(np.int64), (self.n, self.n)
        )
        if len(self._matrix.V) != len(self._lower.rows):  # pragma: no cover - cvxopt invariant
            raise NumericalError("cvxopt changed the sparsity pattern of the matrix")
        try:
            self._factor = self._cholmod.symbolic(self._matrix, uplo="L")
        except (ValueError, MemoryError) as exc:
            raise NumericalError(f"CHOLMOD symbolic analysis failed: {exc}") from exc
        self._latest = Latest("CHOLMOD")

    def factorize(self, a: sp.csr_matrix) -> Factor:
        values = self._cvxopt.matrix(self._lower.data(a))
        self._matrix.V = values
        try:
            self._cholmod.numeric(self._matrix, self._factor)
        except ArithmeticError as exc:
            raise NumericalError(
                f"CHOLMOD: the matrix is not positive definite (pivot {exc.args[0]} of the permuted matrix)"
            ) from exc
        except (ValueError, MemoryError) as exc:
            raise NumericalError(f"CHOLMOD factorization failed: {exc}") from exc
        token = self._latest.claim()

        def solve(b: np.ndarray) -> np.ndarray:
            self._latest.check(token)
            x = self._cvxopt.matrix(b)
            self._cholmod.solve(self._factor, x)
            return np.array(x).reshape(b.shape)

        return Factor(solve, self.n)
