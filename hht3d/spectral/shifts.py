"""The shifted systems ``L + σM`` of the Riesz quadrature and the eigensolvers (Sec. 4.2).

Every ``L + σM`` has the pattern of ``L`` (the lumped ``M`` is diagonal), so
one symbolic analysis (:func:`shift_analysis`) serves every shift.

The quadrature's shifts (:func:`solve_shifts`) are solved from the largest down by
Jacobi-preconditioned CG while it converges within the backend's
``factorization_iterations``, and factorized from the first that does not.  On a backend that
may be entered by two threads (SciPy's SuperLU releases the GIL), a second thread factorizes
from the smallest shift up meanwhile: on nefertiti the eight factorizations and seven CG
solves took 1.3 s together against 2.6 s one after the other.  Each shift is still solved by
the method the sequence from the top gives it (a shift the second thread factorized is solved
again by CG when CG reaches it and converges), so the result does not depend on the threads,
to the bit.
"""

from __future__ import annotations

import contextlib
import threading
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import scipy.sparse as sp

from .. import linalg
from ..errors import InputError
from ..geometry.surface import Surface
from ..geometry.validation import check_surface
from ..linalg.cg import rtol_for
from ..linalg.factor import entries_on_pattern
from ..linalg.pcg import jacobi_cg
from ..linalg.threads import usable_cores

__all__ = [
    "shifted_matrix",
    "shifted_solve",
    "shift_analysis",
    "shifted_systems",
    "solve_shifts",
    "CONCURRENT_VERTICES",
]

#: :func:`solve_shifts` factorizes in a second thread on surfaces of up to this many vertices (two factors are
#: held at once then).
CONCURRENT_VERTICES = 250_000


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


def solve_shifts(
    surface: Surface,
    rhs: np.ndarray,
    sigmas: np.ndarray,
    tol: float,
    backend: str | None = None,
    symbolic: linalg.SymbolicFactorization | None = None,
) -> list[np.ndarray]:
    """``(L + σ_j M)⁻¹ rhs`` for decreasing shifts ``σ_j``, by CG and factorizations (module notes).

    Parameters
    ----------
    surface : Surface
    rhs : (n, k) ndarray
        Right-hand sides, one column per signal.
    sigmas : (N,) ndarray
        Positive shifts, largest first.
    tol : float
        The quadrature's accuracy: CG stops at the relative residual :func:`~hht3d.linalg.cg.rtol_for` ``(tol)``.
    backend, symbolic
        As in :func:`shifted_solve`; ``symbolic`` is made on the first factorization when not given.

    Returns
    -------
    list of (n, k) ndarray
        One solution per shift, in the order of ``sigmas``.
    """
    name = symbolic.backend if symbolic else linalg.check_backend(backend)
    entry = linalg.SOLVER_BACKENDS[name]
    budget = entry.factorization_iterations
    analysis = threading.Lock()
    made = [symbolic]

    def factorized(sigma: float) -> np.ndarray:
        with analysis:  # one analysis, whichever thread factorizes first
            made[0] = made[0] or shift_analysis(surface, name, tol)
        return shifted_solve(surface, sigma, rhs, symbolic=made[0])

    shifted_systems(check_surface(surface))  # made here once, not by both threads
    concurrent = (
        entry.lock is None
        and not entry.iterative
        and budget > 0
        and len(sigmas) > 1
        and surface.n_vertices <= CONCURRENT_VERTICES
        and usable_cores() > 1
    )
    claims = threading.Lock()
    ends = {"top": 0, "bottom": len(sigmas) - 1}  # the next shift from each end

    def bottom_up() -> dict[int, np.ndarray]:
        done: dict[int, np.ndarray] = {}
        while True:
            with claims:
                j = ends["bottom"]
                if j < ends["top"]:
                    return done
                ends["bottom"] = j - 1
            done[j] = factorized(float(sigmas[j]))

    out: list[np.ndarray | None] = [None] * len(sigmas)
    with ThreadPoolExecutor(1) if concurrent else contextlib.nullcontext() as pool:
        below = pool.submit(bottom_up) if pool is not None else None
        try:
            for j, sigma in enumerate(sigmas):
                with claims:
                    taken = j > ends["bottom"]  # the other thread factorizes it, and every smaller shift
                    ends["top"] = j + 1
                if budget:
                    out[j] = jacobi_cg(shifted_matrix(surface, sigma), rhs, rtol_for(tol), budget)
                    if out[j] is not None:
                        continue
                    budget = 0  # a smaller shift needs more iterations still: factorize from here on
                if taken:
                    break
                out[j] = factorized(float(sigma))
        finally:
            with claims:
                ends["top"] = len(sigmas)  # the other thread stops at its next claim
        if below is not None:
            for j, x in below.result().items():
                if out[j] is None:
                    out[j] = x
    return out  # type: ignore[return-value]  # every shift is solved by one of the two threads
