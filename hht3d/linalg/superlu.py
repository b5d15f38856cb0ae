"""SciPy's SuperLU used as a Cholesky: one symmetric ordering per pattern, no pivoting.

SuperLU is a general LU with partial pivoting.  With SciPy's default
``diag_pivot_thresh=1.0`` it swaps rows whenever an off-diagonal entry is
larger than the diagonal one, which on SPD systems is never needed and on
EMD's ill-conditioned ones (few constraints, a strong mean-correction
filter) wrecks the symmetric ordering: 5x the fill and 10-40x the time per
factorization, the cause of a 20.8 GB peak on a 50k-vertex mesh.  Here every
matrix is SPD, so the diagonal is always taken (``diag_pivot_thresh=0``,
``SymmetricMode``) and the factor has the fill of ``L + Lᵀ``.

SciPy exposes no symbolic analysis, but it does expose the column ordering.
Given the rows' positions (a surface's vertices), the pattern is ordered by
nested dissection (:mod:`hht3d.linalg.ordering`: on igea 0.7 s per
factorization against 4.3 s with minimum degree); without them the first
factorization orders with multiple minimum degree on ``A + Aᵀ``
(``MMD_AT_PLUS_A``).  Every later one permutes the matrix symmetrically by
that ordering through a fixed index map and factorizes it with ``NATURAL``,
skipping the ordering.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, cast

import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import splu

from ..errors import NumericalError
from .factor import Factor, Pattern
from .ordering import nested_dissection

__all__ = ["SuperLUPattern", "SUPERLU_OPTIONS", "complex_symmetric_solver"]

#: Keyword arguments of ``splu`` for SPD matrices: diagonal pivots, symmetric structure.
SUPERLU_OPTIONS = {"diag_pivot_thresh": 0.0, "options": {"SymmetricMode": True}}


class SuperLUPattern:
    """SuperLU on one pattern: ordered by nested dissection of ``points`` or on the first matrix, then reused."""

    def __init__(self, pattern: sp.csr_matrix, module: Any, points: Any = None) -> None:
        self._pattern = Pattern(pattern)
        self._splu = module.splu
        self._order: np.ndarray | None = None  # new position -> old index
        self._permuted: tuple | None = None  # CSC indptr, indices and data map of P A Pᵀ
        if points is not None:
            self._analyse(pattern, np.argsort(nested_dissection(pattern, points)))

    def _analyse(self, a: sp.csr_matrix, perm_c: np.ndarray) -> None:
        """Keep the ordering ``perm_c`` of a first factorization and the map of ``P A Pᵀ``."""
        self._order = np.argsort(perm_c)
        slots = sp.csr_matrix((np.arange(1, a.nnz + 1), a.indices, a.indptr), shape=a.shape)
        permuted = slots[self._order][:, self._order].tocsc()
        permuted.sort_indices()
        self._permuted = (permuted.indptr, permuted.indices, permuted.data - 1)

    def factorize(self, a: sp.csr_matrix) -> Factor:
        a = self._pattern.check(a)
        n = self._pattern.n
        if self._order is None:
            lu = _factorized(self._splu, a.tocsc(), "MMD_AT_PLUS_A")
            self._analyse(a, lu.perm_c)
            return Factor(lu.solve, n)
        indptr, indices, source = cast(tuple[np.ndarray, np.ndarray, np.ndarray], self._permuted)  # set with _order
        lu = _factorized(self._splu, sp.csc_matrix((a.data[source], indices, indptr), shape=a.shape), "NATURAL")
        return Factor(_permuted_solve(lu, cast(np.ndarray, self._order), np.float64), n)


def complex_symmetric_solver(matrix: sp.spmatrix, points: np.ndarray) -> Callable[[np.ndarray], np.ndarray]:
    """``b ↦ A⁻¹ b`` for a complex symmetric ``A`` whose real part is SPD, factorized as the SPD systems are.

    Its Hermitian part (the real part) is positive definite, so elimination without pivoting exists
    and is stable (Golub & Van Loan, *Matrix Computations*, 4th ed., §4.2): diagonal pivots in
    nested-dissection order of ``points`` (:func:`~hht3d.linalg.ordering.nested_dissection`).
    """
    a = sp.csr_matrix(matrix, dtype=np.complex128)
    a.sort_indices()
    order = nested_dissection(sp.csr_matrix(abs(a)), points)
    return _permuted_solve(_factorized(splu, a[order][:, order].tocsc(), "NATURAL"), order, np.complex128)


def _factorized(splu: Callable, csc: sp.csc_matrix, permc_spec: str) -> Any:
    """``splu`` with :data:`SUPERLU_OPTIONS`; a zero pivot (not positive definite) as a ``NumericalError``."""
    try:
        return splu(csc, permc_spec=permc_spec, **SUPERLU_OPTIONS)
    except RuntimeError as exc:  # "Factor is exactly singular"
        raise NumericalError(f"SuperLU factorization failed: {exc}") from exc


def _permuted_solve(lu: Any, order: np.ndarray, dtype: type) -> Callable[[np.ndarray], np.ndarray]:
    """``b ↦ A⁻¹ b`` from the factor ``lu`` of ``A[order][:, order]`` (``order``: new position -> row)."""

    def solve(b: np.ndarray) -> np.ndarray:
        x: np.ndarray = np.empty(b.shape, dtype=dtype)
        x[order] = lu.solve(np.ascontiguousarray(b[order], dtype=dtype))
        return x

    return solve
