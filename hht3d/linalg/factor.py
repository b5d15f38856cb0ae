"""What every backend shares: the :class:`Factor` it returns and the fixed-pattern bookkeeping."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import scipy.sparse as sp

from ..errors import InputError, NumericalError

__all__ = ["Factor", "Pattern", "UpperTriangle", "Latest", "entries_on_pattern"]


class Factor:
    """A numeric factorization of one SPD matrix; ``solve`` takes (n,) or (n, k)."""

    def __init__(self, solve: Callable[[np.ndarray], np.ndarray], n: int) -> None:
        self._solve = solve
        self.n = n

    def solve(self, b: np.ndarray) -> np.ndarray:
        b = np.asarray(b, dtype=np.float64)
        if b.shape[0] != self.n:
            raise InputError(f"right-hand side has {b.shape[0]} rows, the matrix has {self.n}")
        x = self._solve(b)
        if not np.all(np.isfinite(x)):
            raise NumericalError("sparse solve produced non-finite values (singular matrix?)")
        return x


class Pattern:
    """The analysed sparsity pattern: every matrix factorized must have exactly it."""

    def __init__(self, pattern: sp.csr_matrix):
        self.n = pattern.shape[0]
        self._indptr, self._indices = pattern.indptr.copy(), pattern.indices.copy()

    def check(self, a: sp.csr_matrix) -> sp.csr_matrix:
        if not (np.array_equal(a.indptr, self._indptr) and np.array_equal(a.indices, self._indices)):
            raise InputError("matrix sparsity pattern differs from the analysed one")
        return a


class UpperTriangle(Pattern):
    """The upper triangle of matrices on one analysed pattern, by a fixed index map.

    For a symmetric matrix the CSR upper triangle is also the CSC lower
    triangle: the same three arrays.
    """

    def __init__(self, pattern: sp.csr_matrix):
        super().__init__(pattern)
        rows = np.repeat(np.arange(self.n), np.diff(pattern.indptr))
        self._mask = pattern.indices >= rows
        self.rows = rows[self._mask]
        self.indices = pattern.indices[self._mask]
        self.indptr = np.concatenate([[0], np.cumsum(np.bincount(self.rows, minlength=self.n))])

    def data(self, a: sp.csr_matrix) -> np.ndarray:
        """The upper-triangle values of ``a``."""
        return self.check(a).data[self._mask]


class Latest:
    """Backends that keep one factor per analysis: only the latest may solve."""

    def __init__(self, backend: str):
        self._backend = backend
        self._current: object | None = None

    def claim(self) -> object:
        self._current = token = object()
        return token

    def check(self, token: object) -> None:
        if self._current is not token:
            raise NumericalError(f"this {self._backend} factor was replaced by a later factorization")


def entries_on_pattern(indptr: np.ndarray, indices: np.ndarray, a: sp.spmatrix) -> np.ndarray:
    """The data array of ``a`` on a fixed CSR pattern (``indptr``, sorted ``indices``) that holds every nonzero
    entry of ``a``: each entry at its position, zeros elsewhere (explicit zeros of ``a`` are dropped)."""
    a = sp.csr_matrix(a, copy=True)
    a.sum_duplicates()
    a.eliminate_zeros()
    if np.array_equal(a.indptr, indptr) and np.array_equal(a.indices, indices):
        return a.data.astype(float)
    n = len(indptr) - 1

    def keys(pointers: np.ndarray, columns: np.ndarray) -> np.ndarray:
        return np.repeat(np.arange(n, dtype=np.int64) * a.shape[1], np.diff(pointers)) + columns

    position = np.searchsorted(keys(indptr, indices), keys(a.indptr, a.indices))
    return np.bincount(position, weights=a.data, minlength=len(indices))
