"""The shifted systems ``L + σM`` of the Riesz quadrature and the eigensolvers (Sec. 4.2).

Every ``L + σM`` has the pattern of ``L`` (the lumped ``M`` is diagonal), so
one symbolic analysis (:func:`shift_analysis`) serves every shift.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from .. import linalg
from ..errors import InputError
from ..geometry.surface import Surface
from ..geometry.validation import check_surface
from ..linalg.factor import entries_on_pattern

__all__ = ["shifted_matrix", "shifted_solve", "shift_analysis", "shifted_systems"]


class _ShiftedSystems:
    """``L + σM`` for many ``σ`` on one fixed sparsity pattern (``L``'s plus the diagonal)."""

    def __init__(self, surface: Surface):
        lap = surface.stiffness
        n = lap.shape[0]
        pattern = (abs(lap) + sp.eye(n, format="csr")).tocsr()
        pattern.sum_duplicates()
        pattern.sort_indices()
        # explicit zeros of L may be missing from the pattern: entries_on_pattern drops them
        self.l_data = entries_on_pattern(pattern.indptr, pattern.indices, lap)
        self.m_data = entries_on_pattern(pattern.indptr, pattern.indices, sp.diags(surface.mass_diagonal))
        self.indptr, self.indices, self.n = pattern.indptr, pattern.indices, n

    def matrix(self, sigma: float) -> sp.csr_matrix:
        return sp.csr_matrix(
            (self.l_data + sigma * self.m_data, self.indices.copy(), self.indptr.copy()), shape=(self.n, self.n)
        )


def shifted_systems(surface: Surface) -> _ShiftedSystems:
    """The shifted systems of ``surface`` (cached on it)."""
    key = "riesz:shifted_systems"
    if key not in surface.cache:
        surface.cache[key] = _ShiftedSystems(surface)
    return surface.cache[key]


def shifted_matrix(surface: Surface, sigma: float) -> sp.csr_matrix:
    """``L + σ M`` on the pattern shared by every shift (explicit zeros kept).

    Parameters
    ----------
    surface : Surface
    sigma : float
        Shift; ``L + σM`` is SPD for ``σ > 0``.
    """
    return shifted_systems(check_surface(surface)).matrix(float(sigma))


def shifted_solve(
    surface: Surface,
    sigma: float,
    rhs: np.ndarray,
    *,
    backend: str | None = None,
    symbolic: linalg.SymbolicFactorization | None = None,
) -> np.ndarray:
    """Solve ``(L + σM) x = rhs`` with one factorization for all columns.

    One term of the quadrature of :func:`~hht3d.spectral.riesz_transform.fractional_laplacian`; independent
    of the other shifts, so a scheduler may run each shift as its own task.

    Parameters
    ----------
    surface : Surface
    sigma : float
        Shift ``> 0``.
    rhs : (n,) or (n, k) array_like
        Right-hand sides (for the quadrature: ``M f̃``, one column per signal).
    backend : str, optional
        Sparse solver (:func:`hht3d.linalg.backends.available_backends`).
    symbolic : SymbolicFactorization, optional
        From :func:`shift_analysis`, to analyse the pattern only once.

    Returns
    -------
    ndarray, shape of ``rhs``
    """
    if not sigma > 0:
        raise InputError(f"the shift must be positive (L + σM is then SPD), got {sigma}")
    symbolic = symbolic or shift_analysis(surface, backend)
    return symbolic.factorize(shifted_matrix(surface, sigma)).solve(rhs)


def shift_analysis(
    surface: Surface, backend: str | None = None, tol: float | None = None
) -> linalg.SymbolicFactorization:
    """Symbolic analysis of the pattern of every ``L + σM`` (:func:`shifted_matrix`).

    Pass it as ``symbolic=`` to :func:`shifted_solve` and
    :func:`spectral_bounds` to order and analyse the pattern only once.

    Parameters
    ----------
    surface : Surface
    backend : str, optional
        Sparse solver (:func:`hht3d.linalg.backends.available_backends`).
    tol : float, optional
        The quadrature's relative accuracy, which an iterative backend's solves keep
        (:class:`~hht3d.linalg.symbolic.SymbolicFactorization`).
    """
    return linalg.SymbolicFactorization(shifted_matrix(surface, 1.0), backend, tol, points=surface.vertices)
