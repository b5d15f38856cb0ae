"""Preconditioned conjugate gradients on many right-hand sides at once.

One loop, vectorized over the columns, serves the iterative backend ``cg`` (smoothed
aggregation, :mod:`hht3d.linalg.cg`) and the Riesz quadrature's large shifts
(:func:`jacobi_cg`).  ``L + σM`` with ``σ`` near the top of the spectrum is close to its
diagonal, and Jacobi-PCG reaches the quadrature's accuracy in a few iterations (on igea, 4 to
54 for the seven largest of its 13 shifts at ``tol=1e-8``), each a product with the matrix,
where a factorization costs as much as tens to hundreds of them; the caller gives a budget of
iterations and factorizes when it is not enough
(:func:`~hht3d.spectral.quadrature.quadrature_part`).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import scipy.sparse as sp

from ..errors import NumericalError

__all__ = ["pcg", "jacobi_cg"]


def pcg(
    a: sp.csr_matrix, b: np.ndarray, precondition: Callable[[np.ndarray], np.ndarray], rtol: float, max_iterations: int
) -> tuple[np.ndarray, float]:
    """CG from ``x = 0`` on each column of ``b`` until ``‖b_i − A x_i‖₂ ≤ rtol ‖b_i‖₂``, or for ``max_iterations``.

    Parameters
    ----------
    a : (n, n) sparse matrix
        Symmetric positive definite.
    b : (n,) or (n, k) ndarray
        Right-hand sides, each solved by its own CG (vectorized over the columns).  Each column is
        scaled to a largest entry of 1 first: squared norms of 1e±200 would vanish or overflow.
    precondition : callable
        ``z = P⁻¹ r`` for an (n, k) block of residuals.
    rtol : float
        Relative residual per column.
    max_iterations : int
        Iterations before giving up.

    Returns
    -------
    x : ndarray of ``b``'s shape
    residual : float
        The largest relative residual of a column; at most ``rtol`` when every column converged.

    Raises
    ------
    NumericalError
        ``pᵀAp ≤ 0`` on a column still iterating: ``a`` is not SPD.
    """
    rhs = np.array(b, dtype=np.float64).reshape(len(b), -1)
    scale = np.max(np.abs(rhs), axis=0)
    scale[scale == 0] = 1.0
    rhs /= scale
    norms = np.einsum("ij,ij->j", rhs, rhs)
    x, r = np.zeros_like(rhs), rhs  # the residual takes over the right-hand side's copy
    z = precondition(r)
    p, scratch = z.copy(), np.empty_like(z)
    rz = _dots(r, z)
    for _ in range(max_iterations + 1):
        left = _dots(r, r) > rtol**2 * norms
        if not left.any():
            break
        q = a @ p
        curvature = _dots(p, q)
        if np.any(curvature[left] <= 0):
            raise NumericalError(f"CG met pᵀAp = {curvature[left].min():.3g} on the {a.shape[0]:,}-row system: not SPD")
        step = np.where(left, rz / np.where(left, curvature, 1.0), 0.0)  # converged columns stay put
        x += np.multiply(p, step, out=scratch)
        r -= np.multiply(q, step, out=scratch)
        z = precondition(r)
        rz, previous = _dots(r, z), rz
        p *= np.divide(rz, previous, out=np.zeros_like(rz), where=previous > 0)
        p += z
    residual = np.sqrt(np.max(_dots(r, r) / np.where(norms > 0, norms, 1.0)))
    return (x * scale).reshape(b.shape), float(residual)


def jacobi_cg(a: sp.csr_matrix, b: np.ndarray, rtol: float, max_iterations: int) -> np.ndarray | None:
    """:func:`pcg` preconditioned by the diagonal of ``a`` (positive); ``None`` when a column needs more than
    ``max_iterations`` iterations."""
    inverse_diagonal = 1.0 / a.diagonal()[:, None]
    x, residual = pcg(a, b, lambda r: inverse_diagonal * r, rtol, max_iterations)
    return x if residual <= rtol else None


def _dots(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Column-wise inner products."""
    return np.einsum("ij,ij->j", u, v)
