"""Analyse a sparsity pattern once, factorize many matrices on it, on any registered backend."""

from __future__ import annotations

import contextlib
from collections.abc import Callable
from typing import Any

import numpy as np
import scipy.sparse as sp

from ..errors import InputError
from . import backends
from .estimate import check_memory, warn_slow_fallback
from .factor import Factor

__all__ = ["SymbolicFactorization", "factorize"]


class SymbolicFactorization:
    """Analyse a sparsity pattern once, then factorize matrices sharing it.

    Before the analysis the whole HHT's memory on this backend is estimated
    for a surface of the matrix's order (:func:`~hht3d.linalg.estimate.check_memory`):
    one line refuses it when it cannot fit, and a slow backend on a large
    mesh is reported once (:func:`~hht3d.linalg.estimate.warn_slow_fallback`).

    Parameters
    ----------
    pattern : sparse matrix
        Symmetric matrix whose stored entries (explicit zeros included)
        define the pattern.
    backend : {"pardiso", "cholmod", "superlu", "cg"}, optional
        Defaults to :func:`~hht3d.linalg.backends.default_backend`.
    tol : float, optional
        The relative accuracy the caller needs, for an iterative backend
        (``cg``: :func:`~hht3d.linalg.cg.rtol_for`); direct ones solve to round-off.
    points : (n, 3) array_like, optional
        The position of each row (a surface's vertices), from which a backend without an
        ordering of its own (``superlu``) orders the pattern by nested dissection.

    Notes
    -----
    With the ``pardiso`` and ``cholmod`` backends only the most recent
    :class:`Factor` of one ``SymbolicFactorization`` is valid (both keep one
    factor per analysis); create one ``SymbolicFactorization`` per factor
    that must stay alive.

    A backend registered with a ``lock`` (:class:`~hht3d.linalg.backends.Backend`:
    ``pardiso``, ``cholmod``) is entered by one thread at a time: the
    analysis, every factorization and every solve of its factors hold that
    lock, so tasks of the threads scheduler may share the process safely.
    """

    def __init__(self, pattern: Any, backend: str | None = None, tol: float | None = None, points: Any = None) -> None:
        pattern = _as_square_csr(pattern)
        self.backend = backends.check_backend(backend)
        check_memory(pattern.shape[0], self.backend)
        warn_slow_fallback(pattern.shape[0], self.backend)
        entry = backends.SOLVER_BACKENDS[self.backend]
        self._lock = entry.lock or contextlib.nullcontext()
        with self._lock:
            accuracy = (tol,) if entry.iterative else ()
            where = {"points": points} if entry.orders_by_points and points is not None else {}
            self._impl = entry.pattern(pattern, entry.module(), *accuracy, **where)
        self.n_factorizations = 0

    def factorize(self, a: Any) -> Factor:
        """Numerically factorize ``a`` (same pattern as analysed)."""
        a = _as_square_csr(a)
        with self._lock:
            factor = self._impl.factorize(a)
        self.n_factorizations += 1
        return Factor(_holding(self._lock, factor._solve), factor.n)


def factorize(a: Any, backend: str | None = None) -> Factor:
    """Factorize one SPD sparse matrix (analysis and numeric phase).

    Parameters
    ----------
    a : sparse matrix
        A symmetric positive definite matrix.
    backend : str, optional
        The backend (default :func:`default_backend`).

    Returns
    -------
    Factor
        The factor, which solves systems in ``a``.

    Examples
    --------
    >>> import numpy as np
    >>> import scipy.sparse as sp
    >>> from hht3d.linalg import factorize
    >>> a = sp.csc_matrix(np.array([[4.0, 1.0], [1.0, 3.0]]))
    >>> factor = factorize(a, "superlu")
    >>> bool(np.allclose(a @ factor.solve(np.array([1.0, 2.0])), [1.0, 2.0]))
    True
    """
    return SymbolicFactorization(a, backend).factorize(a)


def _holding(lock: Any, solve: Callable[[np.ndarray], np.ndarray]) -> Callable[[np.ndarray], np.ndarray]:
    """``solve`` called with ``lock`` held."""

    def locked(b: np.ndarray) -> np.ndarray:
        with lock:
            return solve(b)

    return locked


def _as_square_csr(a: Any) -> sp.csr_matrix:
    a = sp.csr_matrix(a, dtype=np.float64)
    if a.shape[0] != a.shape[1]:
        raise InputError(f"matrix must be square, got shape {a.shape}")
    a.sort_indices()
    return a
