"""Sparse symmetric positive definite (SPD) direct solvers with pattern reuse.

EMD (Sec. 4.1) and the quadrature for ``L^{-1/2}`` (Sec. 4.2) factorize many
matrices that share one sparsity pattern.  A :class:`SymbolicFactorization`
analyses that pattern once (fill-reducing ordering, symbolic factorization)
and then only refactorizes numerically.

Backends
--------
``"pardiso"``
    Intel MKL PARDISO through the ``pypardiso`` package (extra ``fast``):
    real SPD mode (``mtype=2``) on the upper triangle, symbolic phase 11 once,
    numeric phase 22 per matrix, solve phase 33.
``"superlu"``
    SciPy's SuperLU, always available.  SciPy exposes no symbolic reuse, so
    each factorization orders and factorizes from scratch.

The default is the fastest installed backend; every backend gives the same
results to solver round-off.
"""
from __future__ import annotations

import functools
import os
import weakref

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from .errors import InputError, NumericalError

try:  # optional speed-up
    import pypardiso as _pypardiso
except ImportError:  # pragma: no cover - depends on the environment
    _pypardiso = None

__all__ = [
    "available_backends",
    "default_backend",
    "factorize",
    "Factor",
    "SymbolicFactorization",
]


def available_backends() -> list[str]:
    """Names of the installed backends, fastest first."""
    return (["pardiso"] if _pypardiso is not None else []) + ["superlu"]


def default_backend() -> str:
    """The backend used when none is requested: the fastest installed one."""
    return available_backends()[0]


def _check_backend(backend: str | None) -> str:
    backend = default_backend() if backend is None else backend
    if backend not in available_backends():
        raise InputError(
            f"sparse solver backend {backend!r} is not available; installed: "
            f"{available_backends()} (install the 'fast' extra for 'pardiso')"
        )
    return backend


class Factor:
    """A numeric factorization of one SPD matrix; ``solve`` takes (n,) or (n, k)."""

    def __init__(self, solve, n: int):
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


class _SuperLUPattern:
    """SuperLU: no symbolic reuse, a fresh ``splu`` per matrix."""

    def __init__(self, pattern: sp.csr_matrix):
        self.n = pattern.shape[0]

    def factorize(self, a: sp.csr_matrix) -> Factor:
        try:
            lu = spla.splu(a.tocsc(), permc_spec="MMD_AT_PLUS_A",
                           options={"SymmetricMode": True})
        except RuntimeError as exc:  # "Factor is exactly singular"
            raise NumericalError(f"SuperLU factorization failed: {exc}") from exc
        return Factor(lu.solve, self.n)


@functools.lru_cache(maxsize=1)
def _locate_mkl() -> None:
    """Find MKL's runtime once per process and tell pypardiso where it is.

    pypardiso otherwise searches the whole installation tree for ``mkl_rt``
    every time a solver is created (0.3-0.7 s each).
    """
    if "PYPARDISO_MKL_RT" not in os.environ:
        os.environ["PYPARDISO_MKL_RT"] = _pypardiso.PyPardisoSolver().libmkl._name


class _PardisoPattern:
    """MKL PARDISO in SPD mode with the symbolic phase run once."""

    def __init__(self, pattern: sp.csr_matrix):
        self.n = pattern.shape[0]
        self._indptr, self._indices = pattern.indptr.copy(), pattern.indices.copy()
        rows = np.repeat(np.arange(self.n), np.diff(pattern.indptr))
        self._upper_mask = pattern.indices >= rows
        upper_rows = rows[self._upper_mask]
        self._upper_indices = pattern.indices[self._upper_mask]
        self._upper_indptr = np.concatenate([[0], np.cumsum(np.bincount(upper_rows, minlength=self.n))])
        _locate_mkl()
        self._solver = _pypardiso.PyPardisoSolver(mtype=2)  # MKL's SPD defaults
        weakref.finalize(self, self._solver.free_memory, True)
        self._current = None
        self._run(11, self._upper(pattern), np.zeros((self.n, 1)))
        # keep the defaults MKL filled in, minus iterative refinement: SPD
        # solves are accurate to ~1e-13 without it and 5x faster on many columns
        self._solver.iparm[0] = 1
        self._solver.iparm[7] = 0

    def _upper(self, a: sp.csr_matrix) -> sp.csr_matrix:
        """The upper triangle of ``a`` by the index map of the analysed pattern."""
        if not (np.array_equal(a.indptr, self._indptr) and np.array_equal(a.indices, self._indices)):
            raise InputError("matrix sparsity pattern differs from the analysed one")
        return sp.csr_matrix((a.data[self._upper_mask], self._upper_indices, self._upper_indptr),
                             shape=(self.n, self.n))

    def _run(self, phase: int, upper: sp.csr_matrix, b: np.ndarray) -> np.ndarray:
        self._solver.set_phase(phase)
        try:
            return self._solver._call_pardiso(upper, b)
        except _pypardiso.pardiso_wrapper.PyPardisoError as exc:
            raise NumericalError(f"PARDISO phase {phase} failed: {exc}") from exc

    def factorize(self, a: sp.csr_matrix) -> Factor:
        upper = self._upper(a)
        self._run(22, upper, np.zeros((self.n, 1)))
        token = object()
        self._current = token

        def solve(b: np.ndarray) -> np.ndarray:
            if self._current is not token:
                raise NumericalError("this PARDISO factor was replaced by a later factorization")
            return self._run(33, upper, np.asfortranarray(b))

        return Factor(solve, self.n)


class SymbolicFactorization:
    """Analyse a sparsity pattern once, then factorize matrices sharing it.

    Parameters
    ----------
    pattern : sparse matrix
        Symmetric matrix whose stored entries (explicit zeros included)
        define the pattern.
    backend : {"pardiso", "superlu"}, optional
        Defaults to :func:`default_backend`.

    Notes
    -----
    With the ``pardiso`` backend only the most recent :class:`Factor` of one
    ``SymbolicFactorization`` is valid (PARDISO keeps one factor per handle);
    create one ``SymbolicFactorization`` per factor that must stay alive.
    """

    def __init__(self, pattern, backend: str | None = None):
        pattern = _as_square_csr(pattern)
        self.backend = _check_backend(backend)
        impl = _PardisoPattern if self.backend == "pardiso" else _SuperLUPattern
        self._impl = impl(pattern)
        self.n_factorizations = 0

    def factorize(self, a) -> Factor:
        """Numerically factorize ``a`` (same pattern as analysed)."""
        factor = self._impl.factorize(_as_square_csr(a))
        self.n_factorizations += 1
        return factor


def factorize(a, backend: str | None = None) -> Factor:
    """Factorize one SPD sparse matrix (analysis and numeric phase)."""
    return SymbolicFactorization(a, backend).factorize(a)


def _as_square_csr(a) -> sp.csr_matrix:
    a = sp.csr_matrix(a, dtype=np.float64)
    if a.shape[0] != a.shape[1]:
        raise InputError(f"matrix must be square, got shape {a.shape}")
    a.sort_indices()
    return a
