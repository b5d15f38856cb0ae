"""Conjugate gradients preconditioned by the diagonal (Jacobi), all right-hand sides at once.

For the Riesz quadrature's large shifts (:func:`~hht3d.spectral.quadrature.quadrature_part`):
``L + σM`` with ``σ`` near the top of the spectrum is close to its diagonal, and Jacobi-PCG
reaches the quadrature's accuracy in a few iterations (on igea, 4 to 40 for the six largest of
its 13 shifts at ``tol=1e-8``), each a product with the matrix, where a factorization costs
as much as tens to hundreds of them.  The caller gives a budget of iterations and factorizes
when it is not enough.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

__all__ = ["jacobi_cg"]


def jacobi_cg(a: sp.csr_matrix, b: np.ndarray, rtol: float, max_iterations: int) -> np.ndarray | None:
    """``x`` with ``‖b_i − A x_i‖₂ ≤ rtol ‖b_i‖₂`` for every column ``i``, or ``None`` if CG needs more
    than ``max_iterations`` iterations.

    Parameters
    ----------
    a : (n, n) sparse matrix
        Symmetric positive definite, with a positive diagonal.
    b : (n,) or (n, k) ndarray
        Right-hand sides, each solved by its own CG (vectorized over the columns).
    rtol : float
        Relative residual per column.
    max_iterations : int
        Iterations before giving up.

    Returns
    -------
    ndarray of ``b``'s shape, or None
    """
    rhs = np.array(b, dtype=np.float64).reshape(len(b), -1)
    scale = np.max(np.abs(rhs), axis=0)
    scale[scale == 0] = 1.0
    rhs /= scale  # each column's largest entry 1: squared norms neither overflow nor vanish at 1e±200
    inverse_diagonal = 1.0 / a.diagonal()[:, None]
    bound = (rtol * np.linalg.norm(rhs, axis=0)) ** 2
    x, r = np.zeros_like(rhs), rhs  # the residual takes over the right-hand side's copy
    z = inverse_diagonal * r
    p, scratch = z.copy(), np.empty_like(z)
    rz = _dots(r, z)
    for _ in range(max_iterations + 1):
        if np.all(_dots(r, r) <= bound):
            return (x * scale).reshape(b.shape)
        q = a @ p
        step = _ratio(rz, _dots(p, q))
        x += np.multiply(p, step, out=scratch)
        r -= np.multiply(q, step, out=scratch)
        np.multiply(inverse_diagonal, r, out=z)
        rz, previous = _dots(r, z), rz
        p *= _ratio(rz, previous)
        p += z
    return None


def _dots(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Column-wise inner products."""
    return np.einsum("ij,ij->j", u, v)


def _ratio(top: np.ndarray, bottom: np.ndarray) -> np.ndarray:
    """``top / bottom``, 0 where ``bottom`` is not positive (a converged column stays put)."""
    return np.divide(top, bottom, out=np.zeros_like(top), where=bottom > 0)
